//! The three runs of `tptd-mesh`: the arguments as the library's request
//! ([`tptd::pipeline::mesh_file`], [`critical_file`], [`inspect_files`]) with the progress and
//! warnings on stderr, and the summary or table on stdout.

use std::io::Write;

use tptd::grade::GradeOptions;
use tptd::improve::QualityOptions;
use tptd::io::WriteOptions;
use tptd::pipeline::{critical_file, critical_table, inspect_files, mesh_file, summary};
use tptd::pipeline::{transfer_line, CriticalRequest, InspectRequest, MeshRequest, NoProgress};
use tptd::pipeline::{PipelineError, QualityRequest};
use tptd::sdf::SurfaceGridOptions;

use crate::cli::{Cli, Spacing, FLAGS};
use crate::progress::TermProgress;

type Result = std::result::Result<(), PipelineError>;

/// Meshes: `tptd-mesh INPUT -o OUT ...`.
pub(crate) fn mesh(cli: Cli) -> Result {
    let progress = TermProgress::new(cli.quiet);
    let run = mesh_file(&mesh_request(&cli), &progress)?;
    if !cli.quiet {
        let text = summary(
            &run.report,
            run.comparison.as_ref(),
            cli.report.as_deref(),
            FLAGS,
        );
        // A closed stdout (e.g. `| head`) is not an error of the run.
        let _ = std::io::stdout().lock().write_all(text.as_bytes());
    }
    // The process ends here: let the OS reclaim the grid and the mesh at exit instead of
    // freeing hundreds of megabytes page by page first.
    std::mem::forget(run);
    Ok(())
}

/// The meshing request of the arguments.
fn mesh_request(cli: &Cli) -> MeshRequest {
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
        surface_grid: SurfaceGridOptions {
            resolution: cli.resolution.map(|n| n as usize),
            voxel_size: cli.voxel_size,
            ..SurfaceGridOptions::default()
        },
        alpha: cli.alpha,
        beta: cli.beta,
        levels: cli.levels.clone().map(|l| l.0),
        region_names: cli.region_names.clone().map(|n| n.0).unwrap_or_default(),
        method: cli.method.get(),
        threads: cli.threads.map(|n| n as usize),
        output: cli.output.clone(),
        report: cli.report.clone(),
        write: WriteOptions::default()
            .with_msh_version(cli.msh_version.get())
            .with_ascii(cli.ascii)
            .with_vtu_encoding(cli.vtu_encoding.get()),
        caps: cli.caps,
        quality,
        grade: cli.max_edge.map(|max_edge| GradeOptions {
            max_edge,
            grading: cli.grading,
        }),
        check: cli.check,
        analysis: !cli.no_analysis,
        critical_check: !cli.no_critical_check,
        critical_tol: cli.critical_tol,
        memory_limit: cli.memory_limit,
        names: FLAGS,
        cancel: tptd::cancel::Cancel::new(),
    }
}

/// Lists the critical points: `tptd-mesh INPUT --critical ...`.
pub(crate) fn critical(cli: Cli) -> Result {
    let req = CriticalRequest {
        input: cli.input.clone(),
        spacing: cli.spacing.map(|Spacing(s)| s),
        min_value: cli.min_value.unwrap_or(f64::NEG_INFINITY),
        max_value: cli.max_value.unwrap_or(f64::INFINITY),
        kinds: cli.kind.clone().map(|k| k.0).unwrap_or_default(),
        min_persistence: cli.min_persistence.unwrap_or(0.0),
        persistence: cli.persistence || cli.min_persistence.is_some(),
        json: cli.json.clone(),
        spectrum: cli.spectrum.clone(),
        transfer: cli.transfer.clone(),
        transfer_design: cli.transfer_design.get(),
        transfer_width: cli.transfer_width,
        threads: cli.threads.map(|n| n as usize),
        memory_limit: cli.memory_limit,
        names: FLAGS,
    };
    let run = critical_file(&req, &NoProgress)?;
    if !cli.quiet {
        if let (Some(path), Some(tf)) = (&req.transfer, &run.transfer) {
            print(&transfer_line(tf, run.points.len(), path))?;
        }
        print(&critical_table(&req.input_name(), &run.points, run.secs))?;
    }
    Ok(())
}

/// Inspects meshes: `tptd-mesh --inspect MESH... [--volume VOLUME --alpha A --beta B]`.
pub(crate) fn inspect(cli: Cli) -> Result {
    let req = InspectRequest {
        meshes: cli.inspect.clone(),
        volume: cli.volume.clone(),
        spacing: cli.spacing.map(|Spacing(s)| s),
        alpha: cli.alpha,
        beta: cli.beta,
        json: cli.json.clone(),
        threads: cli.threads.map(|n| n as usize),
        memory_limit: cli.memory_limit,
        names: FLAGS,
    };
    let run = inspect_files(&req, &TermProgress::new(cli.quiet))?;
    if !cli.quiet {
        print(&run.table())?;
    }
    Ok(())
}

/// Writes `text` on stdout. A closed pipe (e.g. `| head`) is not an error of the run, whose
/// files are written by then: it ends quietly with status 0.
fn print(text: &str) -> Result {
    match std::io::stdout().lock().write_all(text.as_bytes()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(PipelineError::file(
            "stdout",
            format_args!("cannot write: {e}"),
        )),
        _ => Ok(()),
    }
}
