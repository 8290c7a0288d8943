//! `tptd.critical_points` and `tptd.critical_points_file`: the library's critical points
//! ([`tptd::pipeline::critical_grid`] for an array, [`tptd::pipeline::critical_file`] for a
//! file, as `tptd-mesh VOLUME --critical --json`), the filters checked as the command line
//! checks them; the points come back as the JSON the command line writes.

use std::path::PathBuf;

use numpy::PyUntypedArray;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use tptd::pipeline::{check_applies, critical_file, critical_grid, values, CriticalRun};
use tptd::pipeline::{CriticalRequest, Given, Mode, NoProgress, Param, PipelineError};

use crate::args::{self, parsed, PY_NAMES};
use crate::{py_error, volume, VOLUME};

/// The keyword arguments of the two functions (`None`: not given; `kind` already joined by
/// commas).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub(crate) struct CriticalArgs {
    spacing: Option<[f64; 3]>,
    origin: [f64; 3],
    affine: Option<[[f64; 4]; 4]>,
    min_value: Option<f64>,
    max_value: Option<f64>,
    kind: Option<String>,
    persistence: bool,
    min_persistence: Option<f64>,
    threads: Option<i64>,
}

impl CriticalArgs {
    /// The request of the arguments for `input` (`None`: an array), each value and then the
    /// whole checked as the command line checks them.
    fn request(&self, input: Option<PathBuf>) -> PyResult<CriticalRequest> {
        let threads = args::threads(self.threads)?;
        let given: Vec<Param> = [
            (Param::Critical, true),
            (Param::Spacing, self.spacing.is_some()),
            (Param::MinValue, self.min_value.is_some()),
            (Param::MaxValue, self.max_value.is_some()),
            (Param::Kind, self.kind.is_some()),
            (Param::Persistence, self.persistence),
            (Param::MinPersistence, self.min_persistence.is_some()),
            (Param::Threads, threads.is_some()),
        ]
        .into_iter()
        .filter_map(|(p, set)| set.then_some(p))
        .collect();
        check_applies(&Given {
            mode: Mode::Critical,
            params: &given,
            input: input.as_deref(),
            output: None,
            transfer: None,
            threads,
        })
        .map_err(|e| PyValueError::new_err(e.render(PY_NAMES)))?;
        let kinds = match &self.kind {
            Some(k) => values::kinds(k).map_err(|e| args::invalid(k, Param::Kind, e))?,
            None => Vec::new(),
        };
        let min_persistence = self
            .min_persistence
            .map(|p| parsed(p, Param::MinPersistence, values::nonnegative))
            .transpose()?;
        let bound = |v, p| args::bound(v, p, PY_NAMES);
        Ok(CriticalRequest {
            input,
            spacing: args::spacing(self.spacing)?,
            min_value: bound(self.min_value, Param::MinValue)?.unwrap_or(f64::NEG_INFINITY),
            max_value: bound(self.max_value, Param::MaxValue)?.unwrap_or(f64::INFINITY),
            kinds,
            min_persistence: min_persistence.unwrap_or(0.0),
            persistence: self.persistence || min_persistence.is_some(),
            threads,
            names: PY_NAMES,
            ..CriticalRequest::default()
        })
    }
}

/// The points of a run as the JSON `tptd-mesh --critical --json` writes.
fn points_json(run: Result<CriticalRun, PipelineError>) -> PyResult<String> {
    let run = run.map_err(py_error)?;
    serde_json::to_string(&run.points).map_err(|e| PyValueError::new_err(e.to_string()))
}

/// The critical points of an array volume (see `tptd.critical_points`), as JSON.
#[pyfunction]
pub(crate) fn critical_volume(
    py: Python<'_>,
    volume: &Bound<'_, PyUntypedArray>,
    options: CriticalArgs,
) -> PyResult<String> {
    let req = options.request(None)?;
    // `lent` (numpy's borrow of an array read in place) outlives the run
    let (grid, lent) = volume::grid_of(volume, options.origin, options.affine)?;
    let out = points_json(py.detach(|| critical_grid(grid, VOLUME, &req, &NoProgress)));
    drop(lent);
    out
}

/// The critical points of the volume file `path` (see `tptd.critical_points_file`), as JSON.
#[pyfunction]
pub(crate) fn critical_path(
    py: Python<'_>,
    path: PathBuf,
    options: CriticalArgs,
) -> PyResult<String> {
    let req = options.request(Some(path))?;
    points_json(py.detach(|| critical_file(&req, &NoProgress)))
}
