//! Ctrl-C during a run: the run works in a thread of its own while the calling thread waits
//! with the GIL released and, every [`POLL`], lets Python check its signals. A signal's
//! exception (`KeyboardInterrupt` for Ctrl-C) sets the run's stop flag; the run stops at its
//! next check (between slabs of meshing, inside the quality pass) and leaves nothing, and
//! the exception is raised.

use std::sync::mpsc::{channel, RecvTimeoutError};
use std::time::Duration;

use pyo3::prelude::*;
use tptd::cancel::Cancel;

/// How often the waiting thread checks the signals.
const POLL: Duration = Duration::from_millis(50);

/// Stack of the run's thread: the library's recursion depth is the main thread's.
const STACK_BYTES: usize = 64 << 20;

/// `work` run in a thread of its own with the GIL released; a signal that arrives meanwhile
/// sets `cancel` and its exception is returned once `work` has ended.
pub(crate) fn interruptible<T: Send>(
    py: Python<'_>,
    cancel: &Cancel,
    work: impl FnOnce() -> T + Send,
) -> PyResult<T> {
    let (result, signal) = py.detach(|| {
        std::thread::scope(|s| {
            let (done, ended) = channel();
            let worker = std::thread::Builder::new()
                .name("tptd-run".into())
                .stack_size(STACK_BYTES)
                .spawn_scoped(s, move || {
                    let r = work();
                    let _ = done.send(());
                    r
                })
                .expect("the run's thread starts");
            let mut signal = None;
            while let Err(RecvTimeoutError::Timeout) = ended.recv_timeout(POLL) {
                if signal.is_none() {
                    if let Err(e) = Python::attach(|py| py.check_signals()) {
                        cancel.cancel();
                        signal = Some(e);
                    }
                }
            }
            let result = worker
                .join()
                .unwrap_or_else(|p| std::panic::resume_unwind(p));
            (result, signal)
        })
    });
    signal.map_or(Ok(result), Err)
}
