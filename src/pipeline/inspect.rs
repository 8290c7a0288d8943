//! Meshes inspected side by side as a library call: [`inspect_files`] takes an
//! [`InspectRequest`] (the meshes, the volume they model with its interval, the JSON output)
//! and does what `tptd-mesh --inspect` does between parsing its arguments and printing its
//! table ([`InspectRun::table`]): it checks that the JSON output can be written and is no
//! file read, reads the reference volume and computes the trilinear interval's reference,
//! reads and inspects each mesh ([`crate::inspect::inspect`]) and writes the JSON. An
//! unreadable mesh ends the run before anything is written; an invalid mesh is a result,
//! not an error. [`inspect_given`] is the same run with meshes and the volume in memory
//! (a binding's).

use std::path::{Path, PathBuf};

use crate::inspect::ReferenceOptions;
use crate::inspect::{inspect, reference, table, InspectOptions, Inspection, Reference};
use crate::io::{check_clashes, check_writable, input_run_files, mesh_files, output_run_files};
use crate::io::{read_mesh, read_volume, write_atomically, RunFile};
use crate::{ScalarGrid, TetMesh};

use super::progress::{Progress, Reporter, StageKind};
use super::text::fmt_interval;
use super::{Param, ParamNames, PipelineError};

/// One inspection: the meshes, the volume they model and the outputs. Plain data.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct InspectRequest {
    /// The meshes, in order.
    pub meshes: Vec<PathBuf>,
    /// The volume the meshes model, if any (then with the interval).
    pub volume: Option<PathBuf>,
    /// The volume's grid spacing instead of the file's.
    pub spacing: Option<[f64; 3]>,
    /// Lower bound of the interval (`None`: `-inf`).
    pub alpha: Option<f64>,
    /// Upper bound of the interval (`None`: `inf`).
    pub beta: Option<f64>,
    /// Where to write one JSON object per mesh, if anywhere.
    pub json: Option<PathBuf>,
    /// Worker threads (`None`: all cores); the global pool is built with them.
    pub threads: Option<usize>,
    /// The memory limit of the estimates ([`crate::memory::set_limit`]).
    pub memory_limit: Option<u64>,
    /// How messages name the parameters.
    pub names: ParamNames,
}

/// The result of [`inspect_files`].
#[derive(Clone, Debug)]
pub struct InspectRun {
    /// One inspection per mesh, in order.
    pub meshes: Vec<Inspection>,
    /// The reference of the interval, with the volume's path, when a volume was given.
    pub reference: Option<(Reference, PathBuf)>,
}

impl InspectRun {
    /// The side-by-side text: one column per mesh.
    pub fn table(&self) -> String {
        table(
            &self.meshes,
            self.reference.as_ref().map(|(r, p)| (r, p.as_path())),
        )
    }
}

/// Meshes and a reference volume given in memory instead of files (a binding's), for
/// [`inspect_given`].
#[derive(Clone, Debug, Default)]
pub struct InspectInputs {
    /// The meshes, each with its name in the results, inspected after the request's files.
    pub meshes: Vec<(String, TetMesh)>,
    /// The volume the meshes model, with its name in messages, instead of the request's.
    pub volume: Option<(String, ScalarGrid)>,
}

/// Runs `req`: checks the JSON output, reads the volume and its reference, reads and
/// inspects each mesh, writes the JSON. Stages go to `progress`.
///
/// # Errors
/// The first failure, as one line naming the file; an output that is an input file is a
/// usage error ([`PipelineError::is_usage`]).
pub fn inspect_files(
    req: &InspectRequest,
    progress: &dyn Progress,
) -> Result<InspectRun, PipelineError> {
    inspect_given(req, InspectInputs::default(), progress)
}

/// [`inspect_files`] with meshes and a volume in memory too (`given`): the request's mesh
/// files are inspected first, then the given meshes, as if read from files (a mesh's
/// `boundary` holds the triangles it labels, possibly none); a given volume replaces the
/// request's (the request's spacing applies to it as to a file).
///
/// # Errors
/// As [`inspect_files`].
pub fn inspect_given(
    req: &InspectRequest,
    given: InspectInputs,
    progress: &dyn Progress,
) -> Result<InspectRun, PipelineError> {
    crate::memory::set_limit(req.memory_limit);
    if let Some(n) = req.threads {
        // the pool is built once, here, before any parallel work
        let _ = rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global();
    }
    if let Some(j) = &req.json {
        check_writable(j)?;
    }
    check_files(req)?;
    let reporter = Reporter::new(progress);
    let volume = match (given.volume, &req.volume) {
        (Some((name, grid)), _) => Some(reference_of(req, grid, &name, &reporter)?),
        (None, Some(path)) => Some(read_reference(req, path, &reporter)?),
        (None, None) => None,
    };
    let opts = InspectOptions {
        volume: volume.as_ref().map(|(g, r, _)| (g, r)),
        ..InspectOptions::default()
    };
    let mut meshes = Vec::with_capacity(req.meshes.len() + given.meshes.len());
    for path in &req.meshes {
        let name = path.display().to_string();
        let stage = reporter.stage(&format!("inspecting {name}"), StageKind::Step);
        let file = read_mesh(path).map_err(PipelineError::from)?;
        meshes.push(inspect(&name, file.mesh, &opts));
        stage.finish();
    }
    for (name, mesh) in given.meshes {
        let stage = reporter.stage(&format!("inspecting {name}"), StageKind::Step);
        meshes.push(inspect(&name, mesh, &opts));
        stage.finish();
    }
    if let Some(path) = &req.json {
        write_atomically(path, |w| {
            serde_json::to_writer_pretty(&mut *w, &meshes).map_err(std::io::Error::other)?;
            writeln!(w)
        })?;
    }
    let reference = volume.map(|(_, r, p)| (r, p));
    Ok(InspectRun { meshes, reference })
}

/// Refuses, before any sample is read, the JSON output when it is the same file as a file
/// of the input (the volume with its detached data files, every file of every mesh). A clash
/// is a usage error.
fn check_files(req: &InspectRequest) -> Result<(), PipelineError> {
    let mut inputs = match &req.volume {
        Some(volume) => input_run_files(volume, None).map_err(PipelineError::from)?,
        None => Vec::new(),
    };
    for mesh in &req.meshes {
        let role = format!("the mesh {}", mesh.display());
        inputs.extend(mesh_files(mesh).into_iter().map(|f| RunFile::new(&role, f)));
    }
    let outputs = output_run_files(&[(req.names.of(Param::Json), req.json.as_deref())]);
    check_clashes(&inputs, &outputs)?;
    Ok(())
}

/// Reads the volume and computes the reference of the interval (see [`reference_of`]).
fn read_reference(
    req: &InspectRequest,
    path: &Path,
    reporter: &Reporter,
) -> Result<(ScalarGrid, Reference, PathBuf), PipelineError> {
    let name = path.display().to_string();
    let stage = reporter.stage(&format!("reading {name}"), StageKind::Step);
    let grid = read_volume(path).map_err(PipelineError::from)?;
    stage.finish();
    reference_of(req, grid, &name, reporter)
}

/// The volume `grid` named `name` with the request's spacing, the reference of the
/// request's interval, and the name as a path (for the table).
fn reference_of(
    req: &InspectRequest,
    mut grid: ScalarGrid,
    name: &str,
    reporter: &Reporter,
) -> Result<(ScalarGrid, Reference, PathBuf), PipelineError> {
    let n = req.names;
    if let Some(s) = req.spacing {
        grid = ScalarGrid::with_geometry(grid.dims, s, grid.origin, grid.direction, grid.values)
            .map_err(|e| {
                PipelineError::file(name, format_args!("{}: {e}", n.of(Param::Spacing)))
            })?;
    }
    let alpha = req.alpha.unwrap_or(f64::NEG_INFINITY);
    let beta = req.beta.unwrap_or(f64::INFINITY);
    if alpha >= beta {
        return Err(PipelineError::file(
            name,
            format_args!(
                "empty interval: {} ({alpha}) must be less than {} ({beta})",
                n.of(Param::Alpha),
                n.of(Param::Beta)
            ),
        ));
    }
    let what = format!("the trilinear interval {}", fmt_interval(alpha, beta));
    let stage = reporter.stage(&what, StageKind::Step);
    let r = reference(&grid, alpha, beta, &ReferenceOptions::default())
        .map_err(|e| PipelineError::file(name, e))?;
    stage.finish();
    Ok((grid, r, PathBuf::from(name)))
}
