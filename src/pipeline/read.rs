//! Reading the input: a volume (or the demo volume) with its spacing, or a curvilinear grid
//! whose values are meshed in parameter space.

use std::path::Path;

use crate::demo::demo_volume;
use crate::io::{is_curvilinear, read_curvilinear, read_volume};
use crate::{CurvilinearGrid, ScalarGrid};

use super::progress::{Reporter, StageKind};
use super::request::Job;
use super::{Param, ParamNames, PipelineError};

/// Reads the input volume (a curvilinear grid's values in parameter space, with the grid).
pub(crate) fn read_input(
    job: &Job,
    reporter: &Reporter,
) -> Result<(ScalarGrid, Option<CurvilinearGrid>), PipelineError> {
    let stage = reporter.stage(&format!("reading {}", job.input_name), StageKind::Step);
    let curvilinear = read_curvilinear_input(job)?;
    let grid = match &curvilinear {
        Some(c) => c.values.clone(),
        None => read_grid(job.req.input.as_deref(), job.req.spacing, job.req.names)?,
    };
    stage.finish();
    Ok((grid, curvilinear))
}

/// The curvilinear grid of a `.vts` / `.xyz` input (`None` for other inputs).
fn read_curvilinear_input(job: &Job) -> Result<Option<CurvilinearGrid>, PipelineError> {
    let req = job.req;
    let Some(path) = req.input.as_deref().filter(|p| is_curvilinear(p)) else {
        return Ok(None);
    };
    let grid = read_curvilinear(path, req.function.as_deref(), req.field.as_deref())
        .map_err(PipelineError::other)?;
    Ok(Some(grid))
}

/// Reads the volume `input` (the demo volume for `None`) and gives it `spacing`.
///
/// # Errors
/// The reader's error, or `{input}: {spacing}: …` for a spacing the grid refuses (the
/// parameter named by `names`).
pub fn read_grid(
    input: Option<&Path>,
    spacing: Option<[f64; 3]>,
    names: ParamNames,
) -> Result<ScalarGrid, PipelineError> {
    let mut grid = match input {
        Some(p) => read_volume(p).map_err(PipelineError::other)?,
        None => demo_volume(),
    };
    if let Some(s) = spacing {
        let input_name = input.map_or("demo".to_string(), |p| p.display().to_string());
        grid = ScalarGrid::with_geometry(grid.dims, s, grid.origin, grid.direction, grid.values)
            .map_err(|e| {
                PipelineError::file(
                    input_name,
                    format_args!("{}: {e}", names.of(Param::Spacing)),
                )
            })?;
    }
    Ok(grid)
}
