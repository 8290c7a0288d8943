//! Isosurface output (`-o OUT.obj|.ply|.stl`): the level sets of the meshed interval.

use anyhow::Result;
use tptd::io::write_surface;
use tptd::surface::analysis::{analyse_surface, SurfaceAnalysis};
use tptd::{level_surface, SurfaceOptions, TetMesh};

use crate::cli::Cli;
use crate::error::write_error;
use crate::run::Job;

/// Writes the level sets of `mesh` (with `--caps` the box triangles too) to the job's output
/// and returns their analysis for the report.
pub(crate) fn write_level_surface(cli: &Cli, job: &Job, mesh: &TetMesh) -> Result<SurfaceAnalysis> {
    let opts = SurfaceOptions {
        caps: cli.caps,
        beta: job.opts.beta,
    };
    let s = level_surface(mesh, &opts);
    write_surface(&job.output, &s, &job.write).map_err(write_error)?;
    Ok(analyse_surface(&s))
}
