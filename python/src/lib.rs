//! `tptd._tptd`, the native module of the Python package `tptd`: arguments in, the library's
//! runs out. Each function converts its arguments ([`args`], [`volume`]), calls the library's
//! entry point with the GIL released ([`tptd::pipeline::mesh_grid`] for an array,
//! [`tptd::pipeline::mesh_file`] for a file, [`tptd::pipeline::read_grid`]) and converts the
//! result to numpy arrays ([`result`]); the package's `__init__.py` builds the
//! `meshio.Mesh`. The checks, messages and meshing are the library's, as for `tptd-mesh`.

mod args;
mod progress;
mod result;
mod volume;

use std::path::PathBuf;

use numpy::PyUntypedArray;
use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use tptd::pipeline::{mesh_file, mesh_grid, read_grid, MeshRun, PipelineError};

use args::{Options, PY_NAMES};
use progress::PyProgress;

/// The name of an array volume in messages (the parameter's).
const VOLUME: &str = "volume";

/// A library error as a Python exception: `OSError` when the system refused a file,
/// `ValueError` otherwise, with the library's one-line message.
fn py_error(e: PipelineError) -> PyErr {
    let message = e.message().replace(['\n', '\r'], " ");
    if e.is_io() {
        PyOSError::new_err(message)
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
    let run = py.detach(|| mesh_grid(grid, VOLUME, &req, &progress));
    let out = finish(py, run, progress);
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
    let run = py.detach(|| mesh_file(&req, &progress));
    finish(py, run, progress)
}

/// The result of a run as a dict of arrays, or its error; an exception raised by the
/// progress callback is raised after the run.
fn finish<'py>(
    py: Python<'py>,
    run: Result<MeshRun, PipelineError>,
    progress: PyProgress,
) -> PyResult<Bound<'py, PyDict>> {
    let run = run.map_err(py_error)?;
    progress.raise()?;
    result::mesh_dict(py, run)
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
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
