//! What a run is asked to do ([`MeshRequest`]) and the checks of the request before any work:
//! the interval, the thread count, the output format and that every output can be written
//! and is neither an input file nor another output.

use std::path::{Path, PathBuf};
use std::time::Duration;

use crate::cancel::Cancel;
use crate::demo::{DEMO_ALPHA, DEMO_BETA};
use crate::grade::GradeOptions;
use crate::improve::QualityOptions;
use crate::io::{
    check_clashes, check_writable, input_run_files, is_surface, output_run_files, MeshFormat,
    SurfaceFormat, WriteOptions,
};
use crate::sdf::{SurfaceGridOptions, INSIDE_LEVEL};
use crate::{MeshOptions, Method};

use super::text::fmt_bound;
use super::{Param, ParamNames, PipelineError};

/// Output written for the demo volume when no output is given.
pub const DEMO_OUTPUT: &str = "tptd-demo.vtu";

/// One meshing run: the input, the interval and method, the outputs and what to do between.
/// Plain data; [`MeshRequest::default`] meshes the demo volume with the defaults of
/// `tptd-mesh --demo`.
#[derive(Clone, Debug)]
pub struct MeshRequest {
    /// The input volume (a curvilinear grid for `.vts` and Plot3D `.xyz`; a closed surface
    /// for `.obj`, `.stl` and `.ply`, meshed as the solid it bounds); `None`: the demo volume
    /// ([`crate::demo::demo_volume`]).
    pub input: Option<PathBuf>,
    /// The Plot3D function file (`.q` or `.f`) of an `.xyz` input.
    pub function: Option<PathBuf>,
    /// The field of a curvilinear input to mesh (its first one when `None`).
    pub field: Option<String>,
    /// The grid spacing instead of the file's (not with a curvilinear input or a surface).
    pub spacing: Option<[f64; 3]>,
    /// The signed-distance grid of a closed-surface input: its resolution or voxel size and
    /// padding (its margin is set from `beta`, so that an offset surface fits).
    pub surface_grid: SurfaceGridOptions,
    /// Lower bound of the interval (`None`: `-inf`). One bound at least is needed, except
    /// for the demo, whose interval is its own without both. For a closed surface the values
    /// are signed distances in the surface's units, negative inside.
    pub alpha: Option<f64>,
    /// Upper bound of the interval (`None`: `inf`; for a closed surface `0`, the surface
    /// itself: a positive `beta` offsets it outwards, a negative one inwards).
    pub beta: Option<f64>,
    /// Several levels `L1 < … < Ln` (2 to 16; `-inf` and `inf` at the ends): the regions
    /// `[L1, L2]`, …, `[Ln-1, Ln]` meshed in one pass as one conforming mesh, instead of the
    /// one interval of `alpha` and `beta` (which must then not be given).
    pub levels: Option<Vec<f64>>,
    /// The regions' names (as many as regions; default `region1`, `region2`, …).
    pub region_names: Vec<String>,
    /// The cell decomposition.
    pub method: Method,
    /// Worker threads (`None`: all cores).
    pub threads: Option<usize>,
    /// The output: a mesh (`.msh`, `.inp`, `.vtu`) or the level sets (`.obj`, `.ply`,
    /// `.stl`); `None`: the mesh is held in memory ([`super::MeshRun::mesh`]) and not
    /// written, except for the demo volume, which writes [`DEMO_OUTPUT`].
    pub output: Option<PathBuf>,
    /// Where to write the JSON report, if anywhere.
    pub report: Option<PathBuf>,
    /// The writers' options.
    pub write: WriteOptions,
    /// Surface output: the box triangles too.
    pub caps: bool,
    /// The quality pass after meshing, if any.
    pub quality: Option<QualityRequest>,
    /// Graded interior: cubes whose tets' mean edge length is about `max_edge` deep inside the
    /// domain instead of the fine cells (holds the mesh in memory; not with a curvilinear
    /// grid).
    pub grade: Option<GradeOptions>,
    /// Check the mesh before writing it (a failed check is an error and writes nothing).
    pub check: bool,
    /// Compute the Betti numbers, the dihedral angles and the quality summaries.
    pub analysis: bool,
    /// Check the bounds against the critical values of the field before meshing.
    pub critical_check: bool,
    /// The tolerance of that check (`None`: 1e-5 of the data range).
    pub critical_tol: Option<f64>,
    /// The memory limit of the estimates ([`crate::memory::set_limit`]; `None`: the
    /// available memory).
    pub memory_limit: Option<u64>,
    /// How messages name the parameters.
    pub names: ParamNames,
    /// Set by the caller to stop the run: it then fails ([`PipelineError::is_interrupted`])
    /// and leaves no output.
    pub cancel: Cancel,
}

impl Default for MeshRequest {
    fn default() -> Self {
        MeshRequest {
            input: None,
            function: None,
            field: None,
            spacing: None,
            surface_grid: SurfaceGridOptions::default(),
            alpha: None,
            beta: None,
            levels: None,
            region_names: Vec::new(),
            method: Method::Ctd,
            threads: None,
            output: None,
            report: None,
            write: WriteOptions::default(),
            caps: false,
            quality: None,
            grade: None,
            check: false,
            analysis: true,
            critical_check: true,
            critical_tol: None,
            memory_limit: None,
            names: ParamNames::NEUTRAL,
            cancel: Cancel::new(),
        }
    }
}

/// The quality pass of a run.
#[derive(Clone, Debug, PartialEq)]
pub struct QualityRequest {
    /// The pass's options (their `time_budget` is replaced by [`QualityRequest::seconds`]
    /// when that is given).
    pub options: QualityOptions,
    /// The time budget in seconds, as given (it is named so in the warning of a pass it
    /// stopped).
    pub seconds: Option<f64>,
}

impl QualityRequest {
    /// The options of the pass, with the time budget of `seconds`.
    pub(crate) fn pass_options(&self) -> QualityOptions {
        QualityOptions {
            time_budget: self
                .seconds
                .map(Duration::from_secs_f64)
                .or(self.options.time_budget),
            ..self.options.clone()
        }
    }

    /// The time budget in seconds, for messages.
    pub(crate) fn budget_seconds(&self) -> Option<f64> {
        self.seconds
            .or(self.options.time_budget.map(|d| d.as_secs_f64()))
    }
}

/// The checked request of a run.
pub(crate) struct Job<'a> {
    /// The request.
    pub(crate) req: &'a MeshRequest,
    /// The input as named in messages (`demo` for the demo volume).
    pub(crate) input_name: String,
    /// Whether the grid was given in memory (not read from the request's input).
    pub(crate) in_memory: bool,
    /// The output path (`None`: the mesh is held in memory, nothing written).
    pub(crate) output: Option<PathBuf>,
    /// The meshing options.
    pub(crate) opts: MeshOptions,
}

impl Job<'_> {
    /// Whether the input is the demo volume.
    pub(crate) fn demo(&self) -> bool {
        self.req.input.is_none() && !self.in_memory
    }

    /// Whether the input is a closed surface (`.obj`, `.stl`, `.ply`).
    pub(crate) fn surface(&self) -> bool {
        self.req.input.as_deref().is_some_and(is_surface)
    }

    /// The output as named in messages (the input's name when nothing is written).
    pub(crate) fn output_name(&self) -> String {
        match &self.output {
            Some(p) => p.display().to_string(),
            None => self.input_name.clone(),
        }
    }
}

/// Checks the request before any work: the interval, the thread count, the output format
/// and that the outputs can be written. `in_memory` names a grid given in memory (the
/// request's input is then not read).
pub(crate) fn check_request<'a>(
    req: &'a MeshRequest,
    in_memory: Option<&str>,
) -> Result<Job<'a>, PipelineError> {
    let demo = req.input.is_none() && in_memory.is_none();
    let input_name = match (in_memory, &req.input) {
        (Some(name), _) => name.to_string(),
        (None, Some(p)) => p.display().to_string(),
        (None, None) => "demo".to_string(),
    };
    let output = match (&req.output, demo) {
        (Some(p), _) => Some(p.clone()),
        (None, true) => Some(PathBuf::from(DEMO_OUTPUT)),
        (None, false) => None,
    };
    let (alpha, beta) = match &req.levels {
        Some(levels) => run_levels(req, levels, &input_name)?,
        None => interval(req, &input_name, demo)?,
    };
    check_surface_grid(req, &input_name)?;
    check_threads(req.threads, req.names)?;
    check_outputs(req, output.as_deref())?;
    let opts = MeshOptions {
        alpha,
        beta,
        method: req.method,
        threads: req.threads,
        // Warping snaps grid vertices onto the two levels of one interval only.
        warp: if req.quality.is_some() && req.levels.as_ref().is_none_or(|l| l.len() <= 2) {
            crate::improve::DEFAULT_WARP
        } else {
            0.0
        },
        levels: req.levels.clone().unwrap_or_default(),
        ..MeshOptions::default()
    };
    Ok(Job {
        req,
        input_name,
        in_memory: in_memory.is_some(),
        output,
        opts,
    })
}

/// The interval `(alpha, beta)` of the request (the demo's without both bounds; for a
/// closed surface, a bound not given is `-inf` or `0`), which must not be empty.
fn interval(req: &MeshRequest, input_name: &str, demo: bool) -> Result<(f64, f64), PipelineError> {
    let n = req.names;
    let surface = req.input.as_deref().is_some_and(is_surface);
    let (alpha, beta) = match (req.alpha, req.beta) {
        (None, None) if demo => (DEMO_ALPHA, DEMO_BETA),
        (a, b) if surface => (a.unwrap_or(f64::NEG_INFINITY), b.unwrap_or(INSIDE_LEVEL)),
        (None, None) => {
            return Err(PipelineError::file(
                input_name,
                format_args!(
                    "no interval given: use {} A and/or {} B (meshes alpha <= f <= beta)",
                    n.of(Param::Alpha),
                    n.of(Param::Beta)
                ),
            ))
        }
        (a, b) => (a.unwrap_or(f64::NEG_INFINITY), b.unwrap_or(f64::INFINITY)),
    };
    if alpha >= beta {
        return Err(PipelineError::file(
            input_name,
            format_args!(
                "empty interval: {} ({}) must be less than {} ({})",
                n.of(Param::Alpha),
                fmt_bound(alpha),
                n.of(Param::Beta),
                fmt_bound(beta)
            ),
        ));
    }
    Ok((alpha, beta))
}

/// Checks the levels of the request and the region names against them; returns the first
/// and the last level (the bounds of the union). A refusal is a usage error.
fn run_levels(
    req: &MeshRequest,
    levels: &[f64],
    input_name: &str,
) -> Result<(f64, f64), PipelineError> {
    let n = req.names;
    let checked = crate::levels::Levels::new(levels).map_err(|e| {
        PipelineError::usage(
            input_name,
            format_args!("{} {}: {e}", n.of(Param::Levels), list(levels)),
        )
    })?;
    let names = &req.region_names;
    if !names.is_empty() && checked.regions() == 1 {
        return Err(PipelineError::usage(
            input_name,
            format_args!(
                "{} needs three levels or more: two levels are one interval, written as the \
                 volume `domain`",
                n.of(Param::RegionNames)
            ),
        ));
    }
    if !names.is_empty() && names.len() != checked.regions() {
        return Err(PipelineError::usage(
            input_name,
            format_args!(
                "{} gives {} name(s) for {} regions",
                n.of(Param::RegionNames),
                names.len(),
                checked.regions()
            ),
        ));
    }
    let mut seen = std::collections::HashSet::new();
    if let Some(bad) = names
        .iter()
        .find(|s| !valid_name(s) || !seen.insert(s.to_ascii_uppercase()))
    {
        return Err(PipelineError::usage(
            input_name,
            format_args!(
                "{} {bad:?}: names must be distinct, start with a letter and hold only letters, \
                 digits and _ (they become Abaqus set names)",
                n.of(Param::RegionNames)
            ),
        ));
    }
    Ok((levels[0], levels[levels.len() - 1]))
}

/// Whether `s` is a region name every writer takes: a letter, then letters, digits and `_`,
/// at most 64 characters.
fn valid_name(s: &str) -> bool {
    s.len() <= 64
        && s.starts_with(|c: char| c.is_ascii_alphabetic())
        && s.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
}

/// Levels as given, comma-separated.
fn list(levels: &[f64]) -> String {
    let parts: Vec<String> = levels.iter().map(|&l| fmt_bound(l)).collect();
    parts.join(",")
}

/// Checks the signed-distance grid of the request: a resolution or a voxel size only for a
/// closed surface, not both, a resolution of 1 at least, a voxel size positive and finite.
/// A refusal is a usage error.
fn check_surface_grid(req: &MeshRequest, input_name: &str) -> Result<(), PipelineError> {
    let n = req.names;
    let g = &req.surface_grid;
    let (res, voxel) = (n.of(Param::Resolution), n.of(Param::VoxelSize));
    let problem = match (g.resolution, g.voxel_size) {
        (None, None) => return Ok(()),
        (Some(_), _) | (_, Some(_)) if !req.input.as_deref().is_some_and(is_surface) => {
            let p = if g.resolution.is_some() { res } else { voxel };
            format!("{p} applies only to a closed-surface input (.obj, .ply, .stl)")
        }
        (Some(_), Some(_)) => format!("{res} and {voxel} exclude each other: give one"),
        (Some(0), None) => format!("{res} 0: the resolution must be at least 1"),
        (None, Some(h)) if !(h.is_finite() && h > 0.0) => {
            format!("{voxel} {h}: the voxel size must be positive and finite")
        }
        _ => return Ok(()),
    };
    Err(PipelineError::usage(input_name, problem))
}

/// Most worker threads accepted per core: more only adds overhead.
const MAX_THREADS_PER_CORE: usize = 16;

/// Checks a thread count against the machine at once (a huge pool takes long to start and
/// to fail).
///
/// # Errors
/// `{threads} {n}: too many worker threads: …`, the parameter named by `names`.
pub fn check_threads(threads: Option<usize>, names: ParamNames) -> Result<(), PipelineError> {
    match threads.and_then(too_many_threads) {
        Some((n, max, cores)) => Err(PipelineError::file(
            format_args!("{} {n}", names.of(Param::Threads)),
            format_args!("too many worker threads: at most {max} on this machine ({cores} cores)"),
        )),
        None => Ok(()),
    }
}

/// `(n, max, cores)` when `n` worker threads are more than the machine takes (`max`, for its
/// `cores`).
pub(super) fn too_many_threads(n: usize) -> Option<(usize, usize, usize)> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let max = (cores * MAX_THREADS_PER_CORE).max(MAX_THREADS_PER_CORE);
    (n > max).then_some((n, max, cores))
}

/// Checks the output, if any (a known mesh or surface format, writable) and the report output
/// (writable), then that no output is an input file or another output (compared by
/// identity, not spelling).
fn check_outputs(req: &MeshRequest, output: Option<&Path>) -> Result<(), PipelineError> {
    if let Some(output) = output {
        if SurfaceFormat::from_path(output).is_none() {
            MeshFormat::from_path(output)?;
        }
        check_writable(output)?;
    }
    if let Some(r) = &req.report {
        check_writable(r)?;
    }
    check_files(req, output)
}

/// Refuses, before any sample is read, an output (the mesh, the report) that is the same file
/// as a file of the input (the volume and the files read with it) or as the other output. A
/// clash is a usage error.
fn check_files(req: &MeshRequest, output: Option<&Path>) -> Result<(), PipelineError> {
    let inputs = match &req.input {
        Some(input) => {
            input_run_files(input, req.function.as_deref()).map_err(PipelineError::from)?
        }
        None => Vec::new(),
    };
    let n = req.names;
    let outputs = output_run_files(&[
        (n.of(Param::Output), output),
        (n.of(Param::Report), req.report.as_deref()),
    ]);
    check_clashes(&inputs, &outputs)?;
    Ok(())
}
