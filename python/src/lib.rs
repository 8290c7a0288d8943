//! `tptd._tptd`, the native module of the Python package `tptd`: arguments in, the library's
//! runs out. Each function converts its arguments ([`args`], [`volume`], [`mesh_in`]), calls
//! the library's entry point with the GIL released ([`tptd::pipeline::mesh_grid_into`] for
//! an array, [`tptd::pipeline::mesh_file_into`] for a file, the mesh converted as it is made
//! when the run does not hold it; [`tptd::pipeline::read_grid`], and with
//! [`tptd::level_surface`] for an isosurface; [`critical`], [`inspect`] and [`write`] for
//! the other runs) and converts the result to numpy arrays ([`result`]) or the JSON of
//! `tptd-mesh`; the package's `__init__.py` builds the `meshio.Mesh` and the dicts. The
//! checks, messages and work are the library's, as for `tptd-mesh`.

mod args;
mod critical;
mod inspect;
mod interrupt;
mod mesh_in;
mod progress;
mod result;
mod volume;
mod write;

use std::path::PathBuf;

use numpy::PyUntypedArray;
use pyo3::exceptions::{PyMemoryError, PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use tptd::pipeline::{
    mesh_file_into, mesh_grid, mesh_grid_into, read_grid, MeshRun, NoProgress, PipelineError,
};
use tptd::{level_surface, SurfaceOptions};

use args::{Options, ISO_NAMES, PY_NAMES};
use interrupt::interruptible;
use progress::PyProgress;
use result::Collect;

/// The name of an array volume in messages (the parameter's).
pub(crate) const VOLUME: &str = "volume";

/// A library error as a Python exception: `OSError` when the system refused a file,
/// `MemoryError` when the run would not fit in memory, `ValueError` otherwise, with the
/// library's one-line message.
pub(crate) fn py_error(e: PipelineError) -> PyErr {
    let message = e.message().replace(['\n', '\r'], " ");
    if e.is_io() {
        PyOSError::new_err(message)
    } else if e.is_memory() {
        PyMemoryError::new_err(message)
    } else {
        PyValueError::new_err(message)
    }
}

/// Meshes an array volume (see `tptd.mesh`); returns the arrays of the mesh as a dict.
#[pyfunction]
#[pyo3(signature = (volume, options, progress=None))]
fn mesh_volume<'py>(
    py: Python<'py>,
    volume: &Bound<'py, PyUntypedArray>,
    options: Options,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let req = options.request(None)?;
    // `grid` may read the array in place: `lent` (numpy's read-only borrow of it) outlives
    // the grid, which the run drops (or `finish` does, attached) before this returns.
    let (grid, lent) = volume::grid_of(volume, options.origin, options.affine)?;
    let progress = PyProgress::new(progress);
    let mut collect = Collect::new(&req);
    let run = interruptible(py, &req.cancel, || {
        mesh_grid_into(grid, VOLUME, &req, &progress, &mut collect)
    })?;
    let out = finish(py, run, progress, collect);
    drop(lent);
    out
}

/// Meshes the volume file `path` (see `tptd.mesh_file`); returns the arrays of the mesh as a
/// dict.
#[pyfunction]
#[pyo3(signature = (path, options, progress=None))]
fn mesh_path<'py>(
    py: Python<'py>,
    path: PathBuf,
    options: Options,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let req = options.request(Some(path))?;
    let progress = PyProgress::new(progress);
    let mut collect = Collect::new(&req);
    let run = interruptible(py, &req.cancel, || {
        mesh_file_into(&req, &progress, &mut collect)
    })?;
    finish(py, run, progress, collect)
}

/// The result of a run as a dict of arrays (the mesh the run held, else the one `collect`
/// gathered while it was made), or its error; an exception raised by the progress callback
/// is raised after the run.
fn finish<'py>(
    py: Python<'py>,
    run: Result<MeshRun, PipelineError>,
    progress: PyProgress,
    collect: Collect,
) -> PyResult<Bound<'py, PyDict>> {
    let run = run.map_err(py_error)?;
    progress.raise()?;
    result::mesh_dict(py, run, collect)
}

/// The level set `{f = level}` of an array volume (see `tptd.isosurface`): the interval
/// `[level, inf)` meshed in memory as `options` say (`alpha` is the level), then its level
/// surface, as `tptd-mesh VOLUME --alpha LEVEL -o OUT.obj` writes it; returns its arrays as a
/// dict.
#[pyfunction]
#[pyo3(signature = (volume, options, caps=false))]
fn isosurface_volume<'py>(
    py: Python<'py>,
    volume: &Bound<'py, PyUntypedArray>,
    options: Options,
    caps: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let req = options.request_named(None, ISO_NAMES)?;
    // `lent` (numpy's borrow of an array read in place) outlives the run
    let (grid, lent) = volume::grid_of(volume, options.origin, options.affine)?;
    let surface = interruptible(py, &req.cancel, || {
        let run = mesh_grid(grid, VOLUME, &req, &NoProgress)?;
        let opts = SurfaceOptions {
            caps,
            beta: f64::INFINITY,
        };
        let s = run.mesh.as_ref().map(|out| level_surface(&out.mesh, &opts));
        Ok((s, run.report.warnings))
    });
    drop(lent);
    let (s, warnings) = surface?.map_err(py_error)?;
    let s = s.ok_or_else(|| PyValueError::new_err("the run held no mesh"))?;
    result::surface_dict(py, s, warnings)
}

/// Reads a volume file: `(array, affine)`, the array indexed `[i, j, k]` in the file's sample
/// type (Fortran order, no copy of the samples) and the 4×4 affine from index to physical
/// coordinates.
#[pyfunction]
fn read_volume(py: Python<'_>, path: PathBuf) -> PyResult<(Py<PyAny>, Py<PyAny>)> {
    let grid = py
        .detach(|| read_grid(Some(&path), None, PY_NAMES))
        .map_err(py_error)?;
    volume::to_numpy(py, grid)
}

/// The native module.
#[pymodule]
fn _tptd(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(mesh_volume, m)?)?;
    m.add_function(wrap_pyfunction!(mesh_path, m)?)?;
    m.add_function(wrap_pyfunction!(read_volume, m)?)?;
    m.add_function(wrap_pyfunction!(isosurface_volume, m)?)?;
    m.add_function(wrap_pyfunction!(critical::critical_volume, m)?)?;
    m.add_function(wrap_pyfunction!(critical::critical_path, m)?)?;
    m.add_function(wrap_pyfunction!(inspect::inspect_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(write::write_mesh, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
