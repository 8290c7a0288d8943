//! The one place a run's warnings go through: [`warn`] prints each as one line
//! `tptd-mesh: warning: {message}` on stderr and keeps it, and [`take`] hands them all to the
//! report (`--report`: its `warnings` array), so the report carries every warning printed.

use std::fmt::Display;
use std::sync::{Mutex, PoisonError};

/// The warnings printed so far, in order, without the `tptd-mesh: warning: ` prefix.
static WARNINGS: Mutex<Vec<String>> = Mutex::new(Vec::new());

/// Prints `message` on stderr as a warning (one line) and keeps it for the report.
pub(crate) fn warn(message: impl Display) {
    let message = message.to_string().replace(['\n', '\r'], " ");
    eprintln!("tptd-mesh: warning: {message}");
    WARNINGS
        .lock()
        .unwrap_or_else(PoisonError::into_inner)
        .push(message);
}

/// The warnings printed so far (and forgets them).
pub(crate) fn take() -> Vec<String> {
    std::mem::take(&mut *WARNINGS.lock().unwrap_or_else(PoisonError::into_inner))
}
