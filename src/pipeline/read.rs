//! Reading the input: a volume (or the demo volume) with its spacing, a curvilinear grid
//! whose values are meshed in parameter space, or a closed surface whose signed distance is
//! sampled on a grid around it (negative inside, so the solid is `{d <= 0}`).

use std::path::Path;

use crate::demo::demo_volume;
use crate::io::{is_curvilinear, is_surface, read_curvilinear, read_surface, read_volume, TriSoup};
use crate::report::Report;
use crate::sdf::{surface_volume_with_progress, SdfError, SurfaceFacts, SurfaceGridOptions};
use crate::{CurvilinearGrid, ScalarGrid};

use super::progress::{Reporter, StageKind};
use super::request::Job;
use super::{Param, ParamNames, PipelineError};

/// The input as read: the volume, and the curvilinear grid or the closed surface's facts it
/// came from.
pub(crate) struct Input {
    /// The values meshed (a curvilinear grid's in parameter space; a surface's signed
    /// distance).
    pub(crate) grid: ScalarGrid,
    /// The curvilinear grid of a `.vts` or `.xyz` input.
    pub(crate) curvilinear: Option<CurvilinearGrid>,
    /// What the surface check found on a closed-surface input.
    pub(crate) surface: Option<SurfaceFacts>,
}

/// Reads the input volume (a curvilinear grid's values in parameter space, with the grid; a
/// closed surface's signed distance, with the surface's facts).
pub(crate) fn read_input(job: &Job, reporter: &Reporter) -> Result<Input, PipelineError> {
    if job.surface() {
        let (grid, facts) = read_surface_input(job, reporter)?;
        return Ok(Input {
            grid,
            curvilinear: None,
            surface: Some(facts),
        });
    }
    let stage = reporter.stage(&format!("reading {}", job.input_name), StageKind::Step);
    let curvilinear = read_curvilinear_input(job)?;
    let grid = match &curvilinear {
        Some(c) => c.values.clone(),
        None => read_grid(job.req.input.as_deref(), job.req.spacing, job.req.names)?,
    };
    stage.finish();
    Ok(Input {
        grid,
        curvilinear,
        surface: None,
    })
}

/// On a closed-surface input meshed as the solid it bounds (no offset, no shell), the warning
/// when the mesh's components and cavities do not match the surface's pieces
/// ([`SurfaceFacts::sampling_warning`]).
pub(crate) fn warn_sampling(job: &Job, input: &Input, report: &Report, reporter: &Reporter) {
    let (Some(facts), Some(betti)) = (&input.surface, report.betti) else {
        return;
    };
    let solid = job.opts.alpha == f64::NEG_INFINITY && job.opts.beta == 0.0;
    let on_box = report.boundary_triangles.get("box").copied().unwrap_or(0) > 0;
    if let (true, false, Some(w)) = (
        solid,
        on_box,
        facts.sampling_warning(betti, input.grid.spacing[0]),
    ) {
        let n = job.req.names;
        let finer = match job.req.surface_grid.voxel_size {
            Some(_) => format!("a smaller {}", n.of(Param::VoxelSize)),
            None => format!("a larger {}", n.of(Param::Resolution)),
        };
        reporter.warn(format_args!("{}: {w}; {finer} keeps them", job.input_name));
    }
}

/// The signed distance of the closed surface of the input (`.obj`, `.stl`, `.ply`) on the
/// grid of the request, negative inside. What the surface check finds (holes, non-manifold
/// edges, ...) is warned about, naming the file.
fn read_surface_input(
    job: &Job,
    reporter: &Reporter,
) -> Result<(ScalarGrid, SurfaceFacts), PipelineError> {
    let req = job.req;
    let name = &job.input_name;
    let Some(path) = req.input.as_deref() else {
        return Err(PipelineError::file(name, "no surface given"));
    };
    if req.spacing.is_some() {
        let spacing = req.names.of(Param::Spacing);
        return Err(PipelineError::file(
            name,
            format_args!("{spacing} does not apply to a closed surface"),
        ));
    }
    let stage = reporter.stage(&format!("reading {name}"), StageKind::Step);
    let soup = read_surface(path).map_err(PipelineError::from)?;
    stage.finish();
    let (grid, facts) = sample_surface(job, &soup, reporter).map_err(|e| sdf_error(job, e))?;
    for w in facts.warnings() {
        reporter.warn(format_args!("{name}: {w}"));
    }
    Ok((grid, facts))
}

/// Samples the signed distance of `soup` (in a pool of the job's threads) as a stage with its
/// progress; a margin of `beta` (when positive) leaves room for the offset surface.
fn sample_surface(
    job: &Job,
    soup: &TriSoup,
    reporter: &Reporter,
) -> Result<(ScalarGrid, SurfaceFacts), SdfError> {
    let beta = job.opts.beta;
    let opts = SurfaceGridOptions {
        margin: if beta.is_finite() { beta.max(0.0) } else { 0.0 },
        ..job.req.surface_grid
    };
    let pool = job
        .req
        .threads
        .and_then(|n| rayon::ThreadPoolBuilder::new().num_threads(n).build().ok());
    let stage = reporter.stage("signed distance", StageKind::Sampling);
    let counter = stage.counter();
    let sample = || surface_volume_with_progress(&soup.points, &soup.triangles, &opts, &counter);
    match pool {
        Some(pool) => pool.install(sample),
        None => sample(),
    }
}

/// The error of sampling a surface, naming the input and what to change.
fn sdf_error(job: &Job, e: SdfError) -> PipelineError {
    let n = job.req.names;
    let grid = match job.req.surface_grid.voxel_size {
        Some(_) => format!("a larger {}", n.of(Param::VoxelSize)),
        None => format!("a smaller {}", n.of(Param::Resolution)),
    };
    let name = &job.input_name;
    match e {
        SdfError::Surface(m) => PipelineError::file(name, m),
        SdfError::Options(m) => PipelineError::file(name, format_args!("{m}; use {grid}")),
        SdfError::Memory(m) => PipelineError::memory(
            name,
            format_args!("{m}; use {grid} or raise {}", n.of(Param::MemoryLimit)),
        ),
    }
}

/// The curvilinear grid of a `.vts` / `.xyz` input (`None` for other inputs).
fn read_curvilinear_input(job: &Job) -> Result<Option<CurvilinearGrid>, PipelineError> {
    let req = job.req;
    let Some(path) = req.input.as_deref().filter(|p| is_curvilinear(p)) else {
        return Ok(None);
    };
    let grid = read_curvilinear(path, req.function.as_deref(), req.field.as_deref())
        .map_err(PipelineError::from)?;
    Ok(Some(grid))
}

/// Reads the volume `input` (the demo volume for `None`) and gives it `spacing`.
///
/// # Errors
/// The reader's error (a closed surface is refused: it is no volume), or
/// `{input}: {spacing}: …` for a spacing the grid refuses (the parameter named by `names`).
pub fn read_grid(
    input: Option<&Path>,
    spacing: Option<[f64; 3]>,
    names: ParamNames,
) -> Result<ScalarGrid, PipelineError> {
    let grid = match input {
        Some(p) if is_surface(p) => {
            return Err(PipelineError::file(
                p.display(),
                "a closed surface is meshed as a solid, not read as a volume here",
            ))
        }
        Some(p) => read_volume(p).map_err(PipelineError::from)?,
        None => demo_volume(),
    };
    let input_name = input.map_or("demo".to_string(), |p| p.display().to_string());
    with_spacing(grid, spacing, &input_name, names)
}

/// `grid` with `spacing` instead of its own, if given (its origin and direction kept).
///
/// # Errors
/// `{input_name}: {spacing}: …` for a spacing the grid refuses (the parameter named by
/// `names`).
pub(crate) fn with_spacing(
    grid: ScalarGrid,
    spacing: Option<[f64; 3]>,
    input_name: &str,
    names: ParamNames,
) -> Result<ScalarGrid, PipelineError> {
    let Some(s) = spacing else {
        return Ok(grid);
    };
    ScalarGrid::with_geometry(grid.dims, s, grid.origin, grid.direction, grid.values).map_err(|e| {
        PipelineError::file(
            input_name,
            format_args!("{}: {e}", names.of(Param::Spacing)),
        )
    })
}
