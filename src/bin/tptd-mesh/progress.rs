//! Progress on stderr: the bar of the meshing stage, the spinner of the quality pass, and a
//! spinner for every other stage (read, analysis, write) that takes more than a second.

use std::io::IsTerminal;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, PoisonError};
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use tptd::facts::{FactsSink, Tee};
use tptd::improve::forced::{classify_forced_mapped, ForcedReport};
use tptd::improve::outcome::{improve_meshed_mapped, target_counts, PointMap, TargetCounts};
use tptd::improve::{ImproveReport, QualityOptions};
use tptd::io::SpilledMesh;
use tptd::{
    mesh_interval_streamed, mesh_interval_with_progress, MeshError, MeshOptions, MeshOutput,
    MeshStats, ScalarGrid,
};

use crate::run::Job;

/// Grids with more cells than this get a progress bar (when stderr is a terminal).
const PROGRESS_MIN_CELLS: usize = 2_000_000;

/// A progress bar on stderr for the meshing stage, hidden unless stderr is a terminal and the
/// grid is large.
fn progress_bar(grid: &ScalarGrid, quiet: bool) -> ProgressBar {
    if quiet || !std::io::stderr().is_terminal() || grid.num_cells() <= PROGRESS_MIN_CELLS {
        return ProgressBar::hidden();
    }
    let pb = ProgressBar::with_draw_target(Some(0), ProgressDrawTarget::stderr());
    pb.set_style(
        ProgressStyle::with_template("meshing {bar:40} {percent:>3}% {elapsed_precise} eta {eta}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    pb
}

/// Meshes `grid` with `opts`, showing a progress bar unless `quiet` (see [`progress_bar`]).
pub(crate) fn mesh_with_progress(
    grid: &ScalarGrid,
    opts: &MeshOptions,
    quiet: bool,
) -> Result<MeshOutput, MeshError> {
    let pb = progress_bar(grid, quiet);
    let high = AtomicU64::new(0);
    let result = mesh_interval_with_progress(grid, opts, &|done, total| {
        pb.set_length(total as u64);
        let d = high
            .fetch_max(done as u64, Ordering::Relaxed)
            .max(done as u64);
        pb.set_position(d);
    });
    pb.finish_and_clear();
    result
}

/// Meshes like [`mesh_with_progress`], streaming the chunks to `spill` and `facts`.
pub(crate) fn mesh_streamed_with_progress(
    grid: &ScalarGrid,
    opts: &MeshOptions,
    quiet: bool,
    spill: &mut SpilledMesh,
    facts: &mut FactsSink,
) -> Result<MeshStats, MeshError> {
    let pb = progress_bar(grid, quiet);
    let high = AtomicU64::new(0);
    let mut tee = Tee(spill, facts);
    let result = mesh_interval_streamed(
        grid,
        opts,
        &|done, total| {
            pb.set_length(total as u64);
            let d = high
                .fetch_max(done as u64, Ordering::Relaxed)
                .max(done as u64);
            pb.set_position(d);
        },
        &mut tee,
    );
    pb.finish_and_clear();
    result
}

/// What [`improve_with_progress`] did and found, and the seconds of each part.
pub(crate) struct Improved {
    /// The pass.
    pub(crate) report: ImproveReport,
    /// The tets left below the floor with their reasons (when asked for).
    pub(crate) forced: Option<ForcedReport>,
    /// The tets left off the targets.
    pub(crate) outcome: TargetCounts,
    /// Seconds of the pass.
    pub(crate) pass_seconds: f64,
    /// Seconds of `forced` and `outcome`.
    pub(crate) outcome_seconds: f64,
}

/// Runs the quality pass on `out`'s mesh (in `job`'s thread pool), with a spinner on stderr
/// unless `quiet` or stderr is not a terminal; then counts the tets left off the targets and,
/// if `classify`, lists those below the floor with their reasons. Quality is measured
/// through `map` (a curvilinear grid's geometry map; `None`: as the mesh is).
pub(crate) fn improve_with_progress(
    out: &mut MeshOutput,
    (grid, job): (&ScalarGrid, &Job),
    opts: &QualityOptions,
    (quiet, classify): (bool, bool),
    map: Option<PointMap>,
) -> Improved {
    let pb = if quiet || !std::io::stderr().is_terminal() {
        ProgressBar::hidden()
    } else {
        let pb = ProgressBar::new_spinner();
        pb.set_message("improving elements");
        pb.enable_steady_tick(std::time::Duration::from_millis(200));
        pb
    };
    let (alpha, beta) = (job.opts.alpha, job.opts.beta);
    let pool = job
        .opts
        .threads
        .and_then(|n| rayon::ThreadPoolBuilder::new().num_threads(n).build().ok());
    let work = |out: &mut MeshOutput| {
        let t = Instant::now();
        let report = improve_meshed_mapped(out, grid, alpha, beta, opts, map);
        let pass_seconds = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let mesh = &out.mesh;
        pb.set_message(format!(
            "giving a reason for each element below {}°",
            opts.forced_floor
        ));
        let forced = classify.then(|| classify_forced_mapped(mesh, grid, alpha, beta, opts, map));
        let outcome = target_counts(mesh, opts, map);
        Improved {
            report,
            forced,
            outcome,
            pass_seconds,
            outcome_seconds: t.elapsed().as_secs_f64(),
        }
    };
    let report = match pool {
        Some(pool) => pool.install(|| work(out)),
        None => work(out),
    };
    pb.finish_and_clear();
    report
}

/// How long a stage runs before its spinner appears.
const SHOW_AFTER: Duration = Duration::from_secs(1);

/// A spinner `{msg} {elapsed}` on stderr for one stage, shown once the stage has run for
/// [`SHOW_AFTER`] (never with `quiet` or when stderr is not a terminal).
pub(crate) struct Stage {
    pb: ProgressBar,
    done: Arc<Mutex<bool>>,
}

impl Stage {
    /// Starts the stage `msg` (e.g. `writing m.vtu`).
    pub(crate) fn start(msg: String, quiet: bool) -> Stage {
        let pb = ProgressBar::with_draw_target(None, ProgressDrawTarget::hidden());
        pb.set_style(
            ProgressStyle::with_template("{spinner} {msg} {elapsed}")
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

    /// Ends the stage and clears its spinner (as dropping it does, e.g. on an error).
    pub(crate) fn finish(self) {}
}

impl Drop for Stage {
    fn drop(&mut self) {
        let mut done = self.done.lock().unwrap_or_else(PoisonError::into_inner);
        *done = true;
        self.pb.finish_and_clear();
    }
}
