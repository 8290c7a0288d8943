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
//! The meshing run itself is the library's ([`tptd::pipeline::mesh_file`]): this program
//! turns the arguments into its request, shows its progress and warnings on stderr, prints
//! its summary and maps its errors to exit statuses.
//!
//! Modules: [`alloc`] (the memory-capped allocator), [`cli`] (arguments), [`applies`] (options
//! that do nothing are refused), [`inspect`] (`--inspect`: meshes side by side), [`run`] (the
//! meshing run: request, progress, the library's summary on stdout), [`critical`]
//! (`--critical`: request, the library's run and table), [`progress`] (the progress bar and
//! the warnings on stderr), [`error`] (`{file}: {problem}` errors), [`files`] (the check of
//! `--inspect` that no output is an input or another output).

mod alloc;
mod applies;
mod cli;
mod critical;
mod error;
mod files;
mod inspect;
mod progress;
mod run;

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
        let usage = e.is::<tptd::io::FileClash>()
            || e.downcast_ref::<tptd::pipeline::PipelineError>()
                .is_some_and(|p| p.is_usage());
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
