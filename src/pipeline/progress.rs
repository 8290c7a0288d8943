//! What a run tells its caller while it works: the stage it is in, how far meshing has got,
//! and each warning as it occurs ([`Progress`]); and the collector that keeps the warnings
//! for the report.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Mutex, PoisonError};

/// How a stage measures its progress, so that a front end can choose how to show it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StageKind {
    /// A step without a measure (reading, analysing, checking, writing): usually short.
    Step,
    /// Meshing `cells` cells: [`Progress::fraction`] reports the cells done.
    Meshing {
        /// The cells of the grid.
        cells: usize,
    },
    /// The quality pass: no measure, its message may change ([`Progress::message`]).
    Pass,
    /// Sampling the signed distance of a closed surface on a grid: [`Progress::fraction`]
    /// reports the grid points done.
    Sampling,
}

/// The receiver of a run's progress and warnings. Stages do not nest: each
/// [`Progress::stage`] is followed by [`Progress::finish`] (also when the stage fails) before
/// the next one starts. Calls may come from worker threads.
pub trait Progress: Sync {
    /// A stage starts, e.g. `reading in.npy`, `meshing`, `writing out.vtu`.
    fn stage(&self, name: &str, kind: StageKind);
    /// Of the current stage, `done` of `total` units are done (never decreasing).
    fn fraction(&self, done: u64, total: u64);
    /// The current stage now does `message`.
    fn message(&self, message: &str);
    /// The current stage ends.
    fn finish(&self);
    /// A warning (one line, without a prefix); the run keeps it for its report too.
    fn warn(&self, message: &str);
}

/// A [`Progress`] that ignores everything (the warnings are still in the run's result).
#[derive(Clone, Copy, Debug, Default)]
pub struct NoProgress;

impl Progress for NoProgress {
    fn stage(&self, _name: &str, _kind: StageKind) {}
    fn fraction(&self, _done: u64, _total: u64) {}
    fn message(&self, _message: &str) {}
    fn finish(&self) {}
    fn warn(&self, _message: &str) {}
}

/// The [`Progress`] of a run and the warnings it has given so far.
pub(crate) struct Reporter<'a> {
    progress: &'a dyn Progress,
    warnings: Mutex<Vec<String>>,
}

impl<'a> Reporter<'a> {
    /// Reports to `progress`.
    pub(crate) fn new(progress: &'a dyn Progress) -> Self {
        Reporter {
            progress,
            warnings: Mutex::new(Vec::new()),
        }
    }

    /// Gives `message` as a warning (made one line) and keeps it.
    pub(crate) fn warn(&self, message: impl std::fmt::Display) {
        let message = message.to_string().replace(['\n', '\r'], " ");
        self.progress.warn(&message);
        self.warnings
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .push(message);
    }

    /// The warnings given so far, in order (and forgets them).
    pub(crate) fn take_warnings(&self) -> Vec<String> {
        std::mem::take(&mut *self.warnings.lock().unwrap_or_else(PoisonError::into_inner))
    }

    /// Starts the stage `name`; it ends when the guard is dropped (also on an error).
    pub(crate) fn stage(&self, name: &str, kind: StageKind) -> Stage<'a> {
        self.progress.stage(name, kind);
        Stage {
            progress: self.progress,
        }
    }
}

/// A started stage; dropping it ends the stage.
pub(crate) struct Stage<'a> {
    progress: &'a dyn Progress,
}

impl Stage<'_> {
    /// The stage now does `message`.
    pub(crate) fn message(&self, message: &str) {
        self.progress.message(message);
    }

    /// The progress callback of meshing (sampling): the most cells (points) reported done so
    /// far, of the total.
    pub(crate) fn counter(&self) -> impl Fn(usize, usize) + Sync + '_ {
        let high = AtomicU64::new(0);
        move |done, total| {
            let d = high
                .fetch_max(done as u64, Ordering::Relaxed)
                .max(done as u64);
            self.progress.fraction(d, total as u64);
        }
    }

    /// Ends the stage (as dropping it does).
    pub(crate) fn finish(self) {}
}

impl Drop for Stage<'_> {
    fn drop(&mut self) {
        self.progress.finish();
    }
}
