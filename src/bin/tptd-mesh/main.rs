//! `tptd-mesh`: command-line front end. Meshes the interval volume `{alpha <= f <= beta}` of
//! a scalar volume (or of the demo volume, or of a closed surface's signed distance) into
//! tetrahedra, writes it as `.msh`, `.inp` or `.vtu` (or its level sets as `.obj`, `.ply` or
//! `.stl`) with an optional JSON report; or lists critical points (`--critical`), or inspects
//! meshes (`--inspect`).
//!
//! The runs are the library's ([`tptd::pipeline`]). This program parses the arguments
//! ([`cli`]), builds the requests and prints the results ([`run`]) and the progress
//! ([`progress`]). Every failure is one line `tptd-mesh: error: {file}: {problem}` on stderr,
//! exit status 1 (2 for malformed arguments and for an output that is an input or another
//! output); a failed run leaves no output. A closed stdout is not an error.

mod cli;
mod progress;
mod run;

use std::io::Write;

use tptd::allocator::{set_out_of_memory_message, CappedAlloc, OutOfMemory};
use tptd::pipeline::{out_of_memory_line, Mode};

#[global_allocator]
static ALLOC: CappedAlloc = CappedAlloc;

fn main() {
    let cli = cli::parse_or_exit();
    tptd::memory::set_limit(cli.memory_limit);
    set_out_of_memory_message(if cli.critical {
        |w, m| out_of_memory(w, m, Mode::Critical)
    } else {
        |w, m| out_of_memory(w, m, Mode::Mesh)
    });
    clean_up_on_signals();
    let result = if !cli.inspect.is_empty() {
        run::inspect(cli)
    } else if cli.critical {
        run::critical(cli)
    } else {
        run::mesh(cli)
    };
    if let Err(e) = result {
        let msg = e.to_string().replace(['\n', '\r'], " ");
        eprintln!("tptd-mesh: error: {msg}");
        // An output that would replace an input or another output is a usage error.
        std::process::exit(if e.is_usage() { 2 } else { 1 });
    }
}

/// The out-of-memory line of a run in `mode`.
fn out_of_memory(w: &mut dyn Write, m: OutOfMemory, mode: Mode) -> std::io::Result<()> {
    write!(w, "tptd-mesh: error: ")?;
    out_of_memory_line(w, m, mode, cli::FLAGS)
}

/// On SIGINT or SIGTERM: remove the temporaries of unfinished outputs, print one line and
/// exit with status 128 + the signal number.
fn clean_up_on_signals() {
    use signal_hook::consts::{SIGINT, SIGTERM};
    let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM]) else {
        return;
    };
    std::thread::spawn(move || {
        if let Some(sig) = signals.forever().next() {
            tptd::io::remove_pending_temporaries();
            let name = if sig == SIGINT { "SIGINT" } else { "SIGTERM" };
            eprintln!("tptd-mesh: error: interrupted by {name}; unfinished outputs removed");
            std::process::exit(128 + sig);
        }
    });
}
