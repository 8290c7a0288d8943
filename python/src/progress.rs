//! The `progress` callable of a run as the library's [`Progress`]: `progress(stage,
//! fraction)` at the start of each stage (0.0), as meshing goes (every 1 % at most) and at its
//! end (1.0). It is called with the GIL taken for the call only, from whichever thread
//! reports, one call at a time and with the fractions of a stage in increasing order. An exception it raises stops further calls and is raised when the run ends (the
//! run itself is not interrupted).

use std::sync::{Mutex, PoisonError};

use pyo3::prelude::*;
use tptd::pipeline::{Progress, StageKind};

/// Steps of the fraction between two calls.
const STEP: f64 = 0.01;

/// The current stage and what was last reported of it.
#[derive(Default)]
struct State {
    stage: String,
    last: f64,
    error: Option<PyErr>,
}

/// A Python callable receiving `(stage, fraction)`, or nothing.
pub(crate) struct PyProgress {
    callback: Option<Py<PyAny>>,
    state: Mutex<State>,
}

impl PyProgress {
    /// Reports to `callback`, if any.
    pub(crate) fn new(callback: Option<Py<PyAny>>) -> Self {
        PyProgress {
            callback,
            state: Mutex::new(State::default()),
        }
    }

    fn state(&self) -> std::sync::MutexGuard<'_, State> {
        self.state.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Calls the callable with `(stage, fraction)` of the current stage when `due` says so
    /// (given the fraction last reported); the first exception is kept and ends the calls.
    /// The state stays locked through the call, so that calls from several threads reach
    /// the callable one at a time and in the order of their fractions (no thread that
    /// reports holds the GIL while it waits for the lock: the run releases it).
    fn report(&self, fraction: f64, due: impl Fn(f64) -> bool) {
        let Some(callback) = &self.callback else {
            return;
        };
        let mut s = self.state();
        if s.error.is_some() || !due(s.last) {
            return;
        }
        s.last = fraction;
        let stage = s.stage.clone();
        let result = Python::attach(|py| callback.call1(py, (stage, fraction)).map(|_| ()));
        if let Err(e) = result {
            s.error.get_or_insert(e);
        }
    }

    /// Raises the exception the callable raised, if any.
    pub(crate) fn raise(self) -> PyResult<()> {
        let state = self
            .state
            .into_inner()
            .unwrap_or_else(PoisonError::into_inner);
        state.error.map_or(Ok(()), Err)
    }
}

impl Progress for PyProgress {
    fn stage(&self, name: &str, _kind: StageKind) {
        self.state().stage = name.to_string();
        self.report(0.0, |_| true);
    }

    fn fraction(&self, done: u64, total: u64) {
        if total == 0 {
            return;
        }
        let f = (done as f64 / total as f64).min(1.0);
        self.report(f, |last| f >= last + STEP && f < 1.0);
    }

    fn message(&self, _message: &str) {}

    fn finish(&self) {
        self.report(1.0, |_| true);
    }

    fn warn(&self, _message: &str) {}
}
