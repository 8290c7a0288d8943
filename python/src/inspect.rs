//! `tptd.inspect`: the library's inspection ([`tptd::pipeline::inspect_given`], as
//! `tptd-mesh --inspect MESH [--volume VOLUME] --json`) of a mesh file or a mesh from Python,
//! against a volume file or array, with the arguments checked as the command line checks
//! them.

use std::path::PathBuf;

use numpy::PyUntypedArray;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use tptd::pipeline::{check_applies, inspect_given, Given, Mode, Param};
use tptd::pipeline::{InspectInputs, InspectRequest, NoProgress};

use crate::args::{self, PY_NAMES};
use crate::mesh_in::MeshArrays;
use crate::{py_error, volume, VOLUME};

/// The name of a mesh given as arrays, in the result (`file`).
const MESH: &str = "mesh";

/// A mesh: its file or its arrays.
#[derive(FromPyObject)]
pub(crate) enum MeshArg<'py> {
    Path(PathBuf),
    Arrays(MeshArrays<'py>),
}

/// A volume: its file or an array.
#[derive(FromPyObject)]
pub(crate) enum VolumeArg<'py> {
    Path(PathBuf),
    Array(Bound<'py, PyUntypedArray>),
}

/// The keyword arguments of `tptd.inspect` (`None`: not given).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub(crate) struct InspectArgs {
    alpha: Option<f64>,
    beta: Option<f64>,
    spacing: Option<[f64; 3]>,
    origin: [f64; 3],
    affine: Option<[[f64; 4]; 4]>,
    threads: Option<i64>,
}

impl InspectArgs {
    /// The request (without the mesh and the volume), checked as the command line checks
    /// an inspection's options.
    fn request(&self, volume: bool) -> PyResult<InspectRequest> {
        let threads = args::threads(self.threads)?;
        let given: Vec<Param> = [
            (Param::Inspect, true),
            (Param::Volume, volume),
            (Param::Alpha, self.alpha.is_some()),
            (Param::Beta, self.beta.is_some()),
            (Param::Spacing, self.spacing.is_some()),
            (Param::Threads, threads.is_some()),
        ]
        .into_iter()
        .filter_map(|(p, set)| set.then_some(p))
        .collect();
        check_applies(&Given {
            mode: Mode::Inspect,
            params: &given,
            input: None,
            output: None,
            transfer: None,
            threads,
        })
        .map_err(|e| PyValueError::new_err(e.render(PY_NAMES)))?;
        Ok(InspectRequest {
            alpha: args::bound(self.alpha, Param::Alpha, PY_NAMES)?,
            beta: args::bound(self.beta, Param::Beta, PY_NAMES)?,
            spacing: args::spacing(self.spacing)?,
            threads,
            names: PY_NAMES,
            ..InspectRequest::default()
        })
    }
}

/// Inspects a mesh (a file or arrays) against a volume (a file, an array or none); returns
/// the inspection as JSON (see `tptd.inspect`).
#[pyfunction]
#[pyo3(signature = (mesh, volume, options))]
pub(crate) fn inspect_mesh(
    py: Python<'_>,
    mesh: MeshArg<'_>,
    volume: Option<VolumeArg<'_>>,
    options: InspectArgs,
) -> PyResult<String> {
    let mut req = options.request(volume.is_some())?;
    let mut given = InspectInputs::default();
    match mesh {
        MeshArg::Path(p) => req.meshes.push(p),
        MeshArg::Arrays(a) => given.meshes.push((MESH.to_string(), a.into_mesh()?)),
    }
    // `lent` (numpy's borrow of an array read in place) outlives the run
    let mut lent = None;
    match &volume {
        Some(VolumeArg::Path(p)) => req.volume = Some(p.clone()),
        Some(VolumeArg::Array(a)) => {
            let (grid, borrow) = volume::grid_of(a, options.origin, options.affine)?;
            given.volume = Some((VOLUME.to_string(), grid));
            lent = Some(borrow);
        }
        None => {}
    }
    let threads = req.threads.take();
    let run = py.detach(|| {
        let pool =
            threads.and_then(|n| rayon::ThreadPoolBuilder::new().num_threads(n).build().ok());
        let work = || inspect_given(&req, given, &NoProgress);
        match pool {
            Some(pool) => pool.install(work),
            None => work(),
        }
    });
    let run = run.map_err(py_error);
    drop(lent);
    serde_json::to_string(&run?.meshes[0]).map_err(|e| PyValueError::new_err(e.to_string()))
}
