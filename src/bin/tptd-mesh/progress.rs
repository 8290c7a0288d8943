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

/// A progress bar on stderr for the meshing stage, hidden unless stderr is a terminal and the
/// grid (of `cells` cells) is large.
fn progress_bar(cells: usize, quiet: bool) -> ProgressBar {
    if quiet || !std::io::stderr().is_terminal() || cells <= PROGRESS_MIN_CELLS {
        return ProgressBar::hidden();
    }
    let pb = ProgressBar::with_draw_target(Some(0), ProgressDrawTarget::stderr());
    pb.set_style(
        ProgressStyle::with_template("meshing {bar:40} {percent:>3}% {elapsed_precise} eta {eta}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    pb
}

/// The spinner `{msg}` of the quality pass, shown at once unless `quiet` or stderr is not a
/// terminal.
fn pass_spinner(msg: &str, quiet: bool) -> ProgressBar {
    if quiet || !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let pb = ProgressBar::new_spinner();
    pb.set_message(msg.to_string());
    pb.enable_steady_tick(Duration::from_millis(200));
    pb
}

/// What shows the current stage.
enum Shown {
    /// The meshing bar or the spinner of the quality pass.
    Bar(ProgressBar),
    /// The spinner of another stage.
    Stage(Stage),
}

/// The [`Progress`] of a run on stderr: bars and spinners (none with `quiet`), and each
/// warning as one line `tptd-mesh: warning: {message}`.
pub(crate) struct TermProgress {
    quiet: bool,
    current: Mutex<Option<Shown>>,
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
    fn current(&self) -> std::sync::MutexGuard<'_, Option<Shown>> {
        self.current.lock().unwrap_or_else(PoisonError::into_inner)
    }
}

impl Progress for TermProgress {
    fn stage(&self, name: &str, kind: StageKind) {
        let shown = match kind {
            StageKind::Step => Shown::Stage(Stage::start(name.to_string(), SPINNER, self.quiet)),
            StageKind::Sampling => Shown::Stage(Stage::start(name.to_string(), BAR, self.quiet)),
            StageKind::Meshing { cells } => Shown::Bar(progress_bar(cells, self.quiet)),
            StageKind::Pass => Shown::Bar(pass_spinner(name, self.quiet)),
        };
        *self.current() = Some(shown);
    }

    fn fraction(&self, done: u64, total: u64) {
        let current = self.current();
        let pb = match &*current {
            Some(Shown::Bar(pb)) => pb,
            Some(Shown::Stage(s)) => &s.pb,
            None => return,
        };
        pb.set_length(total);
        pb.set_position(done);
    }

    fn message(&self, message: &str) {
        match &*self.current() {
            Some(Shown::Bar(pb)) => pb.set_message(message.to_string()),
            Some(Shown::Stage(s)) => s.pb.set_message(message.to_string()),
            None => {}
        }
    }

    fn finish(&self) {
        let shown = self.current().take();
        if let Some(Shown::Bar(pb)) = shown {
            pb.finish_and_clear();
        }
    }

    fn warn(&self, message: &str) {
        eprintln!("tptd-mesh: warning: {message}");
    }
}

/// How long a stage runs before its spinner appears.
const SHOW_AFTER: Duration = Duration::from_secs(1);

/// The display of a stage without a measure.
const SPINNER: &str = "{spinner} {msg} {elapsed}";

/// The display of a stage whose fraction done is known.
const BAR: &str = "{msg} {bar:40} {percent:>3}% {elapsed_precise} eta {eta}";

/// A spinner or a bar (`template`) on stderr for one stage, shown once the stage has run for
/// [`SHOW_AFTER`] (never with `quiet` or when stderr is not a terminal); dropping it clears it.
struct Stage {
    pb: ProgressBar,
    done: Arc<Mutex<bool>>,
}

impl Stage {
    /// Starts the stage `msg` (e.g. `writing m.vtu`).
    fn start(msg: String, template: &str, quiet: bool) -> Stage {
        let pb = ProgressBar::with_draw_target(None, ProgressDrawTarget::hidden());
        pb.set_style(
            ProgressStyle::with_template(template)
                .unwrap_or_else(|_| ProgressStyle::default_spinner()),
        );
        pb.set_message(msg);
        let done = Arc::new(Mutex::new(false));
        if !quiet && std::io::stderr().is_terminal() {
            let (pb, done) = (pb.clone(), Arc::clone(&done));
            std::thread::spawn(move || {
                std::thread::sleep(SHOW_AFTER);
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
