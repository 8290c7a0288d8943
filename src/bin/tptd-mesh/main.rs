//! `tptd-mesh`: command-line front end. Reads a scalar volume (or generates the demo volume),
//! meshes the interval volume `{alpha <= f <= beta}` into tetrahedra, analyses the mesh and
//! writes it as `.msh`, `.inp` or `.vtu` (or its level sets as `.obj`, `.ply` or `.stl`), plus
//! an optional JSON report.
//!
//! This is the only part of the crate that prints. Every failure is reported as one line
//! `tptd-mesh: error: {file}: {problem}` on stderr with exit status 1 (2 for malformed
//! arguments and for an output that is the same file as an input file or another output,
//! found before any work); outputs are written atomically, so a failed run leaves no
//! (partial) output file behind. A closed stdout is not an error.
//!
//! Modules: [`alloc`] (the memory-capped allocator), [`cli`] (arguments), [`applies`] (options
//! that do nothing are refused), [`inspect`] (`--inspect`: meshes side by side), [`run`] (the run,
//! step by step), [`quality`] (`--quality` and what it left), [`critical`] (`--critical` and the check of the bounds against the critical
//! values), [`summary`] (stdout), [`progress`] (the progress bar), [`error`]
//! (`{file}: {problem}` errors), [`files`] (the check that no output is an input or another
//! output), [`surface`] (isosurface output), [`warnings`] (every warning, printed and kept for
//! the report).

mod alloc;
mod applies;
mod cli;
mod critical;
mod error;
mod files;
mod inspect;
mod progress;
mod quality;
mod run;
mod summary;
mod surface;
mod warnings;

#[global_allocator]
static ALLOC: alloc::CappedAlloc = alloc::CappedAlloc;

fn main() {
    let cli = cli::parse_or_exit();
    tptd::memory::set_limit(cli.memory_limit);
    clean_up_on_signals();
    let result = if !cli.inspect.is_empty() {
        inspect::run(cli)
    } else if cli.critical {
        alloc::set_critical_mode();
        critical::run(cli)
    } else {
        run::run(cli)
    };
    if let Err(e) = result {
        let msg = e.to_string().replace(['\n', '\r'], " ");
        eprintln!("tptd-mesh: error: {msg}");
        // An output that would replace an input or another output is a usage error.
        let usage = e.is::<tptd::io::FileClash>();
        std::process::exit(if usage { 2 } else { 1 });
    }
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
