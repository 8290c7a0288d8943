//! A flag the caller of a run sets to stop it early (a binding's Ctrl-C). Meshing polls it
//! between slabs and the quality pass where it checks its time budget; a run that sees it
//! fails with an interrupted error and leaves no output.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// A shared stop flag: clones see the same flag. Two flags compare equal when both are set
/// or both are not (the flag is not part of what a run is asked to do).
#[derive(Clone, Debug, Default)]
pub struct Cancel(Arc<AtomicBool>);

impl Cancel {
    /// A flag not set.
    pub fn new() -> Self {
        Self::default()
    }

    /// Asks every run holding this flag (or a clone) to stop.
    pub fn cancel(&self) {
        self.0.store(true, Ordering::Relaxed);
    }

    /// Whether the flag is set.
    #[inline]
    pub fn is_cancelled(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }
}

impl PartialEq for Cancel {
    fn eq(&self, other: &Self) -> bool {
        self.is_cancelled() == other.is_cancelled()
    }
}

#[cfg(test)]
mod tests {
    use super::Cancel;

    #[test]
    fn clones_share_the_flag() {
        let a = Cancel::new();
        let b = a.clone();
        assert!(!b.is_cancelled() && a == Cancel::new());
        a.cancel();
        assert!(b.is_cancelled() && a != Cancel::new());
    }
}
