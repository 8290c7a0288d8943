//! Progress on stderr: the bar of the meshing stage, the spinner of the quality pass, the bar
//! of sampling a surface's signed distance and a spinner for every other stage (read,
//! analysis, write), both once they take more than a second; and the warnings of a run, one
//! line each.

use std::io::IsTerminal;
use std::sync::{Arc, Mutex, PoisonError};
use std::time::Duration;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use tptd::pipeline::{Progress, StageKind};

/// Grids with more cells than this get a progress bar (when stderr is a terminal).
const PROGRESS_MIN_CELLS: usize = 2_000_000;

/// The [`Progress`] of a run on stderr: bars and spinners (none with `quiet`), and each
/// warning as one line `tptd-mesh: warning: {message}`.
pub(crate) struct TermProgress {
    quiet: bool,
    current: Mutex<Option<Stage>>,
}

impl TermProgress {
    /// Progress on stderr, without bars and spinners when `quiet`.
    pub(crate) fn new(quiet: bool) -> Self {
        TermProgress {
            quiet,
            current: Mutex::new(None),
        }
    }

    /// The current stage's display.
    fn current(&self) -> std::sync::MutexGuard<'_, Option<Stage>> {
        self.current.lock().unwrap_or_else(PoisonError::into_inner)
    }
}

impl Progress for TermProgress {
    fn stage(&self, name: &str, kind: StageKind) {
        let (template, show_after) = match kind {
            StageKind::Step => (SPINNER, Some(SHOW_AFTER)),
            StageKind::Sampling => (BAR, Some(SHOW_AFTER)),
            StageKind::Meshing { cells } => (BAR, (cells > PROGRESS_MIN_CELLS).then_some(NOW)),
            StageKind::Pass => (SPINNER, Some(NOW)),
        };
        let show_after = show_after.filter(|_| !self.quiet && std::io::stderr().is_terminal());
        *self.current() = Some(Stage::start(name.to_string(), template, show_after));
    }

    fn fraction(&self, done: u64, total: u64) {
        if let Some(s) = &*self.current() {
            s.pb.set_length(total);
            s.pb.set_position(done);
        }
    }

    fn message(&self, message: &str) {
        if let Some(s) = &*self.current() {
            s.pb.set_message(message.to_string());
        }
    }

    fn finish(&self) {
        self.current().take();
    }

    fn warn(&self, message: &str) {
        eprintln!("tptd-mesh: warning: {message}");
    }
}

/// How long a stage runs before its spinner appears.
const SHOW_AFTER: Duration = Duration::from_secs(1);

/// At once.
const NOW: Duration = Duration::ZERO;

/// The display of a stage without a measure.
const SPINNER: &str = "{spinner} {msg} {elapsed}";

/// The display of a stage whose fraction done is known.
const BAR: &str = "{msg} {bar:40} {percent:>3}% {elapsed_precise} eta {eta}";

/// A spinner or a bar (`template`) on stderr for one stage, shown once the stage has run for
/// `show_after` (never when `None`); dropping it clears it.
struct Stage {
    pb: ProgressBar,
    done: Arc<Mutex<bool>>,
}

impl Stage {
    /// Starts the stage `msg` (e.g. `writing m.vtu`).
    fn start(msg: String, template: &str, show_after: Option<Duration>) -> Stage {
        let pb = ProgressBar::with_draw_target(None, ProgressDrawTarget::hidden());
        pb.set_style(
            ProgressStyle::with_template(template)
                .unwrap_or_else(|_| ProgressStyle::default_spinner()),
        );
        pb.set_message(msg);
        let done = Arc::new(Mutex::new(false));
        if let Some(after) = show_after {
            let (pb, done) = (pb.clone(), Arc::clone(&done));
            std::thread::spawn(move || {
                std::thread::sleep(after);
                let done = done.lock().unwrap_or_else(PoisonError::into_inner);
                if !*done {
                    pb.set_draw_target(ProgressDrawTarget::stderr());
                    pb.enable_steady_tick(Duration::from_millis(200));
                }
            });
        }
        Stage { pb, done }
    }
}

impl Drop for Stage {
    fn drop(&mut self) {
        let mut done = self.done.lock().unwrap_or_else(PoisonError::into_inner);
        *done = true;
        self.pb.finish_and_clear();
    }
}
