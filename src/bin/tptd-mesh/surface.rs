//! Isosurface output (`-o OUT.obj|.ply|.stl`): the level sets of the meshed interval; and
//! curvilinear input (`.vts`, Plot3D), whose mesh is made in parameter space and mapped.

use anyhow::Result;
use tptd::io::{is_curvilinear, read_curvilinear, write_surface_pending, PendingFile};
use tptd::surface::analysis::{analyse_surface, SurfaceAnalysis};
use tptd::CurvilinearGrid;
use tptd::{level_surface, SurfaceOptions, TetMesh};

use crate::cli::Cli;
use crate::error::write_error;
use crate::run::Job;

/// Writes the level sets of `mesh` (with `--caps` the box triangles too) to a temporary of
/// the job's output (renamed by the caller once the report is written too) and returns their
/// analysis for the report.
pub(crate) fn write_level_surface(
    cli: &Cli,
    job: &Job,
    mesh: &TetMesh,
) -> Result<(SurfaceAnalysis, PendingFile)> {
    let opts = SurfaceOptions {
        caps: cli.caps,
        beta: job.opts.beta,
    };
    let s = level_surface(mesh, &opts);
    let file = write_surface_pending(&job.output, &s, &job.write).map_err(write_error)?;
    Ok((analyse_surface(&s), file))
}

/// The curvilinear grid of a `.vts` / `.xyz` input (`None` for other inputs).
pub(crate) fn read_curvilinear_input(cli: &Cli) -> Result<Option<CurvilinearGrid>> {
    // --field, --function and --spacing were checked against the input by `crate::applies`
    let Some(path) = cli.input.as_deref().filter(|p| is_curvilinear(p)) else {
        return Ok(None);
    };
    Ok(Some(read_curvilinear(
        path,
        cli.function.as_deref(),
        cli.field.as_deref(),
    )?))
}
