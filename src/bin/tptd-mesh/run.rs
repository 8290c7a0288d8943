//! One meshing run of `tptd-mesh`: the arguments as a [`MeshRequest`], the run
//! ([`tptd::pipeline::mesh_file`]) with the progress and warnings on stderr, and the summary
//! on stdout.

use std::io::Write;

use anyhow::Result;
use tptd::improve::QualityOptions;
use tptd::io::WriteOptions;
use tptd::pipeline::{mesh_file, summary, MeshRequest, QualityRequest};

use crate::cli::{Cli, Spacing};
use crate::progress::TermProgress;

pub(crate) use tptd::pipeline::DEMO_OUTPUT;

/// Runs `tptd-mesh` with the parsed arguments.
pub(crate) fn run(cli: Cli) -> Result<()> {
    let progress = TermProgress::new(cli.quiet);
    let run = mesh_file(&request(&cli), &progress)?;
    if !cli.quiet {
        let text = summary(&run.report, run.comparison.as_ref(), cli.report.as_deref());
        // A closed stdout (e.g. `| head`) is not an error of the run.
        let _ = std::io::stdout().lock().write_all(text.as_bytes());
    }
    // The process ends here: let the OS reclaim the grid and the mesh at exit instead of
    // freeing hundreds of megabytes page by page first.
    std::mem::forget(run);
    Ok(())
}

/// The request of the arguments.
fn request(cli: &Cli) -> MeshRequest {
    let quality = cli.quality.then(|| QualityRequest {
        options: QualityOptions {
            min_angle: cli.min_angle,
            max_angle: cli.max_angle,
            time_budget: None,
            boundary_collapse_ratio: cli.boundary_collapse_ratio,
            split_sag: cli.split_sag,
            ..QualityOptions::default()
        },
        seconds: cli.quality_time,
    });
    MeshRequest {
        input: cli.input.clone(),
        function: cli.function.clone(),
        field: cli.field.clone(),
        spacing: cli.spacing.map(|Spacing(s)| s),
        alpha: cli.alpha,
        beta: cli.beta,
        method: cli.method.method(),
        threads: cli.threads.map(|n| n as usize),
        output: cli.output.clone(),
        report: cli.report.clone(),
        write: WriteOptions::default()
            .with_msh_version(cli.msh_version.version())
            .with_ascii(cli.ascii)
            .with_vtu_encoding(cli.vtu_encoding.encoding()),
        caps: cli.caps,
        quality,
        check: cli.check,
        analysis: !cli.no_analysis,
        critical_check: !cli.no_critical_check,
        critical_tol: cli.critical_tol,
        memory_limit: cli.memory_limit,
    }
}

/// Checks `-j` against the machine at once (a huge pool takes long to start and to fail).
pub(crate) fn check_threads(threads: Option<u32>) -> Result<()> {
    Ok(tptd::pipeline::check_threads(threads.map(|n| n as usize))?)
}
