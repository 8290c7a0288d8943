//! One meshing run as a library call: [`mesh_file`] takes a [`MeshRequest`] (input,
//! interval, method, outputs, quality pass, check, threads, memory limit) and a
//! [`Progress`] receiver, and does what `tptd-mesh` does between parsing its arguments and
//! printing its summary:
//!
//! 1. checks the request (`request.rs`): the interval, the thread count, the output format,
//!    that the outputs can be written and that none is an input file or another output;
//! 2. reads the input (`read.rs`): a volume, the demo volume, a curvilinear grid, or a closed
//!    surface whose signed distance it samples (the interval then defaults to `(-inf, 0]`);
//! 3. warns about the bounds (`bounds.rs`): bounds equal to grid values, a nearly singular
//!    direction matrix, bounds near critical values;
//! 4. chooses between streaming the mesh to disk and holding it in memory, and checks the
//!    memory estimate (`memory.rs`);
//! 5. meshes (`run.rs`), with the quality pass in its own thread pool and the reasons of the
//!    tets it left below the floor (`quality.rs`), the curvilinear map, the analysis and the
//!    check, and writes the output under a temporary name;
//! 6. builds the report (`report.rs`), writes it and renames both files onto their names.
//!
//! Without an output the mesh is held in memory and only returned. [`mesh_grid`] is the same
//! run on a volume given in memory (a binding's array) instead of an input file: steps 1 and
//! 3 to 6.
//!
//! The result ([`MeshRun`]) holds the report, with every warning given on the way; the
//! warnings also go to [`Progress::warn`] as they occur. Nothing here prints. Every failure
//! is a [`PipelineError`]: one line naming the file and the problem, and whether the run was
//! refused for how it was asked ([`PipelineError::is_usage`]). A failed run leaves no output.
//!
//! The critical points of a volume (`tptd-mesh --critical`) are a run of their own
//! (`critical.rs`): [`critical_file`] takes a [`CriticalRequest`] and gives a
//! [`CriticalRun`], whose table is [`critical_table`]; [`critical_grid`] is the same run on a
//! volume in memory. [`write_mesh_file`] writes a mesh as a run writes its output.

mod applies;
mod bounds;
mod critical;
mod error;
mod inspect;
mod memory;
mod param;
mod progress;
mod quality;
mod read;
mod report;
mod request;
mod run;
mod summary;
pub mod text;
pub mod values;

use std::time::Instant;

use crate::report::{QualityTimings, Report, Timings};
use crate::{MeshOutput, MeshSink, Method, ScalarGrid};

pub use applies::{check_applies, Given, Inapplicable, Mode};
pub use critical::{
    critical_file, critical_grid, critical_table, transfer_line, CriticalRequest, CriticalRun,
};
pub use error::PipelineError;
pub use inspect::{inspect_files, inspect_given, InspectInputs, InspectRequest, InspectRun};
pub use memory::out_of_memory_line;
pub use param::{Param, ParamNames};
pub use progress::{NoProgress, Progress, StageKind};
pub use read::read_grid;
pub use request::{check_threads, MeshRequest, QualityRequest, DEMO_OUTPUT};
pub use run::write_mesh_file;
pub use summary::summary;

use progress::Reporter;
use run::secs;

/// What the demo shows: the same interval meshed with a method of the other kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DemoComparison {
    /// The method of the other kind.
    pub other: Method,
    /// The number of components `other` gives.
    pub other_b0: usize,
}

/// The result of a run: its report (with its warnings), the demo's comparison, and the grid
/// and the mesh it made.
pub struct MeshRun {
    /// The report, as written to the request's report path.
    pub report: Report,
    /// For the demo volume (with analysis): the components with a method of the other kind.
    pub comparison: Option<DemoComparison>,
    /// The input grid (a curvilinear grid's values in parameter space).
    pub grid: ScalarGrid,
    /// The mesh, when it was held in memory (not when it was streamed to disk).
    pub mesh: Option<MeshOutput>,
}

impl MeshRun {
    /// The warnings of the run, in the order they were given.
    pub fn warnings(&self) -> &[String] {
        &self.report.warnings
    }
}

/// Runs `req`: checks it, reads the input, warns about the bounds, checks the memory
/// estimate, meshes (streamed or in memory), improves, analyses, checks and writes the output
/// and the report. Stages, meshing progress and warnings go to `progress` as they happen.
/// Without an output (and not on the demo volume) the mesh is held in memory, returned in
/// [`MeshRun::mesh`] and not written.
///
/// # Errors
/// The first failure, as one line naming the file; no output is left behind.
pub fn mesh_file(req: &MeshRequest, progress: &dyn Progress) -> Result<MeshRun, PipelineError> {
    file_run(req, progress, None)
}

/// [`mesh_file`] handing the mesh to `sink` slab by slab as it is made (chunks in slab order,
/// as [`crate::mesh_interval_streamed`] gives them), in place of holding it, when nothing
/// after meshing needs the whole mesh: no output, quality pass, curvilinear mapping or check.
/// [`MeshRun::mesh`] is then `None`. Otherwise the run is [`mesh_file`]'s (the mesh held and
/// returned) and `sink` gets nothing. For a binding that converts the mesh as it comes.
///
/// # Errors
/// As [`mesh_file`].
pub fn mesh_file_into(
    req: &MeshRequest,
    progress: &dyn Progress,
    sink: &mut (dyn MeshSink + Send),
) -> Result<MeshRun, PipelineError> {
    file_run(req, progress, Some(sink))
}

/// [`mesh_file`], with the sink of [`mesh_file_into`] if any.
fn file_run(
    req: &MeshRequest,
    progress: &dyn Progress,
    sink: Option<&mut (dyn MeshSink + Send)>,
) -> Result<MeshRun, PipelineError> {
    let t_total = Instant::now();
    crate::memory::set_limit(req.memory_limit);
    let reporter = Reporter::new(progress);
    let job = request::check_request(req, None)?;
    let t_args = secs(t_total);
    let t = Instant::now();
    let input = read::read_input(&job, &reporter)?;
    let t_read = secs(t);
    run_job(&job, input, &reporter, (t_total, t_args, t_read), sink)
}

/// Runs `req` on `grid`, a volume given in memory and named `name` in messages, as
/// [`mesh_file`] runs it on its input file: the same checks, warnings, meshing, quality
/// pass, analysis, check and output. The request's input (and its function, field and
/// surface grid) is not read; its spacing, if given, replaces the grid's.
///
/// # Errors
/// The first failure, as one line naming `name` (or the file written).
pub fn mesh_grid(
    grid: ScalarGrid,
    name: &str,
    req: &MeshRequest,
    progress: &dyn Progress,
) -> Result<MeshRun, PipelineError> {
    grid_run(grid, name, req, progress, None)
}

/// [`mesh_grid`] handing the mesh to `sink` slab by slab as it is made, in place of holding
/// it, when nothing after meshing needs the whole mesh, as [`mesh_file_into`] does.
///
/// # Errors
/// As [`mesh_grid`].
pub fn mesh_grid_into(
    grid: ScalarGrid,
    name: &str,
    req: &MeshRequest,
    progress: &dyn Progress,
    sink: &mut (dyn MeshSink + Send),
) -> Result<MeshRun, PipelineError> {
    grid_run(grid, name, req, progress, Some(sink))
}

/// [`mesh_grid`], with the sink of [`mesh_grid_into`] if any.
fn grid_run(
    grid: ScalarGrid,
    name: &str,
    req: &MeshRequest,
    progress: &dyn Progress,
    sink: Option<&mut (dyn MeshSink + Send)>,
) -> Result<MeshRun, PipelineError> {
    let t_total = Instant::now();
    crate::memory::set_limit(req.memory_limit);
    let reporter = Reporter::new(progress);
    let req = MeshRequest {
        input: None,
        function: None,
        field: None,
        surface_grid: Default::default(),
        ..req.clone()
    };
    let job = request::check_request(&req, Some(name))?;
    let grid = read::with_spacing(grid, req.spacing, name, req.names)?;
    let t_args = secs(t_total);
    let input = read::Input {
        grid,
        curvilinear: None,
        surface: None,
    };
    run_job(&job, input, &reporter, (t_total, t_args, 0.0), sink)
}

/// A graded interior needs cubes of two cells at least: `max_edge` of 1.5 times the grid's
/// widest spacing (the nearest power of two is then 2), and a grading above 1.
fn check_grade(grid: &ScalarGrid, job: &request::Job) -> Result<(), PipelineError> {
    let Some(g) = &job.req.grade else {
        return Ok(());
    };
    let names = job.req.names;
    let widest = grid.spacing.iter().fold(0.0f64, |m, &s| m.max(s.abs()));
    if !(g.grading > 1.0 && g.grading.is_finite()) {
        return Err(PipelineError::usage(
            &job.input_name,
            format_args!(
                "{} must be a finite number above 1, got {}",
                names.of(Param::Grading),
                g.grading
            ),
        ));
    }
    if crate::grade::max_side(grid, g.max_edge) < 2 {
        return Err(PipelineError::usage(
            &job.input_name,
            format_args!(
                "{} {} is less than 1.5 cells (the grid's widest spacing is {widest}): the \
                 nearest cube is one cell; give at least {}",
                names.of(Param::MaxEdge),
                g.max_edge,
                1.5 * widest
            ),
        ));
    }
    Ok(())
}

/// The run of a checked request on its input, read (`mesh_file`) or given (`mesh_grid`),
/// after the seconds `(start, checking the arguments, reading)`; the mesh goes to `sink` if
/// given and nothing after meshing needs it whole.
fn run_job(
    job: &request::Job,
    input: read::Input,
    reporter: &Reporter,
    (t_total, t_args, t_read): (Instant, f64, f64),
    sink: Option<&mut (dyn MeshSink + Send)>,
) -> Result<MeshRun, PipelineError> {
    let (grid, curvilinear) = (&input.grid, input.curvilinear.as_ref());
    let t = Instant::now();
    let stream_to = memory::streams(job, curvilinear.is_some());
    run::in_pool(job.opts.threads, || {
        bounds::warn_input(grid, job, curvilinear.is_some(), reporter);
    });
    check_grade(grid, job)?;
    memory::check_memory(grid, job, stream_to.is_some())?;
    let t_checks = t_args + secs(t);

    let sink = sink.filter(|_| memory::hands_on(job, curvilinear.is_some()));
    let mut w = match (stream_to, sink) {
        (Some(output), _) => run::stream_to_disk(job, output, grid, reporter)?,
        (None, Some(sink)) => run::mesh_to_sink(job, grid, reporter, sink)?,
        (None, None) => run::mesh_in_memory(job, grid, curvilinear, reporter)?,
    };
    let t_quality = w.t_quality.take();
    let mut timings = Timings {
        streamed: stream_to.is_some(),
        analysed_while_meshing: w.analysed_while_meshing,
        read: t_read,
        checks: t_checks,
        mesh: w.t_mesh,
        analysis: w.t_analysis,
        quality: t_quality.as_ref().map(QualityTimings::total),
        quality_stages: t_quality,
        map: w.t_map,
        check: w.t_check,
        grade: w.t_grade,
        write: w.t_write,
        other: 0.0,
        total: secs(t_total),
    };
    timings.close();
    let mut report = report::make_report(job, grid, &mut w, timings);
    read::warn_sampling(job, &input, &report, reporter);
    report.warnings = reporter.take_warnings();
    report::commit(&report, job.req.report.as_deref(), w.file)?;
    Ok(MeshRun {
        report,
        comparison: w.comparison,
        grid: input.grid,
        mesh: w.mesh,
    })
}
