//! Meshing, either streamed to disk slab by slab or in memory (with the quality pass, the
//! curvilinear map, the analysis and the check), and writing the output under a temporary
//! name.

use std::path::Path;
use std::time::Instant;

use crate::cancel::Cancel;
use crate::check::{check_mesh, CheckOptions, CheckReport};
use crate::curvilinear::map_mesh;
use crate::facts::{FactsSink, MeshFacts, Tee};
use crate::grade::{grade_interior, GradeReport};
use crate::io::{
    check_writable, spill_for_levels, write_mesh_pending, write_spilled_pending,
    write_surface_pending, PendingFile, SurfaceFormat, WriteOptions,
};
use crate::mesh::NoSink;
use crate::quality::summarize;
use crate::report::{QualitySection, QualityTimings};
use crate::surface::analysis::{analyse_surface, SurfaceAnalysis};
use crate::{
    level_surface, mesh_interval, mesh_interval_seen_by, mesh_interval_streamed, CurvilinearGrid,
    MeshChunk, MeshError, MeshOptions, MeshOutput, MeshSink, MeshStats, Method, ScalarGrid,
    SurfaceOptions, TetMesh,
};

use super::progress::{Reporter, StageKind};
use super::quality::improve_mesh;
use super::request::Job;
use super::text::fmt_interval;
use super::{DemoComparison, Param, PipelineError};

/// What meshing, analysing and writing produced (the output file still pending).
pub(crate) struct Written {
    pub(crate) facts: MeshFacts,
    pub(crate) stats: MeshStats,
    pub(crate) quality: Option<QualitySection>,
    pub(crate) surface: Option<SurfaceAnalysis>,
    pub(crate) comparison: Option<DemoComparison>,
    pub(crate) check: Option<CheckReport>,
    /// The graded interior (`--max-edge`).
    pub(crate) grade: Option<GradeReport>,
    /// The output under its temporary name (`None`: nothing written).
    pub(crate) file: Option<PendingFile>,
    /// The mesh (when it was held in memory).
    pub(crate) mesh: Option<MeshOutput>,
    /// Seconds of meshing, analysis (with the demo's comparison), the quality step (by part),
    /// the curvilinear map, the check and writing.
    pub(crate) t_mesh: f64,
    pub(crate) t_analysis: f64,
    pub(crate) t_quality: Option<QualityTimings>,
    pub(crate) t_map: Option<f64>,
    pub(crate) t_check: Option<f64>,
    pub(crate) t_grade: Option<f64>,
    pub(crate) t_write: f64,
    /// The facts were gathered while meshing (`t_mesh` includes them).
    pub(crate) analysed_while_meshing: bool,
}

/// Seconds since `t`.
pub(crate) fn secs(t: Instant) -> f64 {
    t.elapsed().as_secs_f64()
}

/// Runs `f` in a pool of `threads` worker threads (`None`: in the current pool, all cores),
/// so that `--threads` holds for every stage, not only for meshing.
pub(crate) fn in_pool<R: Send>(threads: Option<usize>, f: impl FnOnce() -> R + Send) -> R {
    match threads.and_then(|n| rayon::ThreadPoolBuilder::new().num_threads(n).build().ok()) {
        Some(pool) => pool.install(f),
        None => f(),
    }
}

/// Meshes slab by slab into spill files next to `output`, gathering the facts on the way,
/// then writes `output` from the spill files: memory stays the grid plus a few slabs.
pub(crate) fn stream_to_disk(
    job: &Job,
    output: &Path,
    grid: &ScalarGrid,
    reporter: &Reporter,
) -> Result<Written, PipelineError> {
    let levels = job.opts.levels.len().max(crate::mesh::INTERVAL_LEVELS);
    let mut spill = spill_for_levels(output, levels, job.req.region_names.clone())?;
    let (facts, stats, t_mesh) = mesh_streamed(job, grid, reporter, &mut spill, Some(output))?;
    let t = Instant::now();
    let stage = reporter.stage(&format!("writing {}", output.display()), StageKind::Step);
    let file = in_pool(job.opts.threads, || {
        write_spilled_pending(output, &mut spill, &job.req.write)
    });
    stage.finish();
    let t_write = secs(t);
    let t = Instant::now();
    let comparison = compare_demo(grid, job)?;
    // Only the demo is compared: otherwise nothing is analysed here (the rest is `other`).
    let t_analysis = if comparison.is_some() { secs(t) } else { 0.0 };
    Ok(Written {
        comparison,
        file: Some(file?),
        t_analysis,
        t_write,
        ..Written::streamed(facts, stats, t_mesh)
    })
}

/// Meshes slab by slab into the caller's `sink` (which holds the mesh), gathering the facts
/// on the way; nothing is held here or written ([`super::memory::hands_on`]).
pub(crate) fn mesh_to_sink(
    job: &Job,
    grid: &ScalarGrid,
    reporter: &Reporter,
    sink: &mut (dyn MeshSink + Send),
) -> Result<Written, PipelineError> {
    let (facts, stats, t_mesh) = mesh_streamed(job, grid, reporter, sink, None)?;
    Ok(Written::streamed(facts, stats, t_mesh))
}

/// Meshes slab by slab into `sink` and gathers the facts on the way: the facts, the counters
/// and the seconds. An error of `sink` names `output` (else the input); an empty mesh is an
/// error.
fn mesh_streamed(
    job: &Job,
    grid: &ScalarGrid,
    reporter: &Reporter,
    sink: &mut (dyn MeshSink + Send),
    output: Option<&Path>,
) -> Result<(MeshFacts, MeshStats, f64), PipelineError> {
    let t = Instant::now();
    let mut facts = facts_sink(job);
    let stage = reporter.stage("meshing", meshing(grid));
    let stats = mesh_interval_streamed(
        grid,
        &job.opts,
        &stage.counter(),
        &mut Stop::new(job, &mut Tee(sink, &mut facts)),
    );
    stage.finish();
    let stats = stats.map_err(|e| match (e, output) {
        _ if job.req.cancel.is_cancelled() => PipelineError::interrupted(&job.input_name),
        (MeshError::Output(e), Some(output)) => PipelineError::file(output.display(), e),
        (e, _) => PipelineError::file(&job.input_name, e),
    })?;
    let facts = facts.finish();
    check_not_empty(grid, job, facts.tets)?;
    Ok((facts, stats, secs(t)))
}

impl Written {
    /// A mesh streamed (to disk or to a caller's sink) and analysed while it was made, after
    /// `t_mesh` seconds: nothing else done yet.
    fn streamed(facts: MeshFacts, stats: MeshStats, t_mesh: f64) -> Written {
        Written {
            facts,
            stats,
            quality: None,
            surface: None,
            comparison: None,
            check: None,
            grade: None,
            file: None,
            mesh: None,
            t_mesh,
            t_analysis: 0.0,
            t_quality: None,
            t_map: None,
            t_check: None,
            t_grade: None,
            t_write: 0.0,
            analysed_while_meshing: true,
        }
    }
}

/// The stage kind of meshing `grid`.
fn meshing(grid: &ScalarGrid) -> StageKind {
    StageKind::Meshing {
        cells: grid.num_cells(),
    }
}

/// Meshes into memory, improves (quality pass), maps (curvilinear), analyses, checks and
/// writes (when there is an output).
pub(crate) fn mesh_in_memory(
    job: &Job,
    grid: &ScalarGrid,
    curvilinear: Option<&CurvilinearGrid>,
    reporter: &Reporter,
) -> Result<Written, PipelineError> {
    let t = Instant::now();
    // A mesh that neither the quality pass nor a curvilinear map will change is analysed
    // while it is made, as a streamed one is.
    let analyse_now = job.req.quality.is_none() && job.req.grade.is_none() && curvilinear.is_none();
    let mut sink = analyse_now.then(|| facts_sink(job));
    let mut out = mesh(grid, job, reporter, sink.as_mut())?;
    let t_mesh = secs(t);
    let t = Instant::now();
    let grade = grade_mesh(grid, job, &mut out, reporter);
    let t_grade = grade.is_some().then(|| secs(t));

    let improved = improve_mesh((grid, job), &mut out, curvilinear, reporter);
    if job.req.cancel.is_cancelled() {
        return Err(PipelineError::interrupted(&job.input_name));
    }
    let (quality, t_quality) = improved.unzip();
    // The level-set distance of a curvilinear mesh is checked in parameter space.
    let parameter_points =
        (job.req.check && curvilinear.is_some()).then(|| out.mesh.points.clone());
    let t = Instant::now();
    let t_map = match curvilinear {
        Some(c) => {
            map_mesh(&mut out.mesh, c).map_err(|e| PipelineError::file(&job.input_name, e))?;
            Some(secs(t))
        }
        None => None,
    };

    let t = Instant::now();
    let facts = match sink {
        Some(sink) => sink.finish(),
        None => {
            let stage = reporter.stage("analysing the mesh", StageKind::Step);
            let facts = MeshFacts::of(&out.mesh, job.req.analysis, &job.opts.levels);
            stage.finish();
            facts
        }
    };
    let after = (quality.is_some() && job.req.analysis).then(|| summarize(&out.mesh));
    let quality = quality.map(|q| QualitySection { after, ..q });
    let comparison = compare_demo(grid, job)?;
    let t_analysis = secs(t);
    let parameter_points = parameter_points.as_deref();
    let (check, t_check) = check_output(job, grid, parameter_points, &out.mesh, reporter)?;

    // The output stays under its temporary name until the report is written too.
    let t = Instant::now();
    let (surface, file) = write_output(job, &out, reporter)?;
    let t_write = secs(t);
    Ok(Written {
        facts,
        stats: out.stats.clone(),
        quality,
        surface,
        comparison,
        check,
        grade,
        file,
        mesh: Some(out),
        t_mesh,
        t_analysis,
        t_quality,
        t_map,
        t_check,
        t_grade,
        t_write,
        analysed_while_meshing: analyse_now,
    })
}

/// With a graded interior in the request: the cubes put in place of the fine cells deep
/// inside the domain, before the quality pass.
fn grade_mesh(
    grid: &ScalarGrid,
    job: &Job,
    out: &mut MeshOutput,
    reporter: &Reporter,
) -> Option<GradeReport> {
    let opts = job.req.grade.as_ref()?;
    let stage = reporter.stage("grading the interior", StageKind::Step);
    let levels = job
        .opts
        .run_levels()
        .unwrap_or(crate::Levels::interval(job.opts.alpha, job.opts.beta));
    let pool = job
        .opts
        .threads
        .and_then(|n| rayon::ThreadPoolBuilder::new().num_threads(n).build().ok());
    let report = match pool {
        Some(p) => p.install(|| grade_interior(out, grid, &levels, opts)),
        None => grade_interior(out, grid, &levels, opts),
    };
    stage.finish();
    Some(report)
}

/// With the check: the validity check of the mesh, before anything is written; a mesh that
/// fails it is an error naming the count of each problem. A curvilinear mesh (mapped to
/// physical space) has its level-set distance checked at its points in parameter space
/// (`parameter_points`), where its grid's values are.
fn check_output(
    job: &Job,
    grid: &ScalarGrid,
    parameter_points: Option<&[[f64; 3]]>,
    mesh: &TetMesh,
    reporter: &Reporter,
) -> Result<(Option<CheckReport>, Option<f64>), PipelineError> {
    if !job.req.check {
        return Ok((None, None));
    }
    let t = Instant::now();
    let stage = reporter.stage("checking the mesh", StageKind::Step);
    let mut opts = CheckOptions {
        level_points: parameter_points,
        ..CheckOptions::for_method(grid, job.opts.alpha, job.opts.beta, job.opts.method)
    };
    if let Ok(levels) = crate::levels::Levels::new(&job.opts.levels) {
        opts.levels = levels;
    }
    let report = check_mesh(mesh, &opts);
    stage.finish();
    if !report.valid {
        let how_far = match &report.level {
            Some(l) if l.beyond > 0 => format!(
                "; boundary points up to {:.3} voxel from their level set",
                l.max_beyond
            ),
            _ => String::new(),
        };
        return Err(PipelineError::file(
            job.output_name(),
            format_args!(
                "the mesh fails {} ({}{how_far}); nothing written",
                job.req.names.of(Param::Check),
                report.summary_line()
            ),
        ));
    }
    Ok((Some(report), Some(secs(t))))
}

/// Writes the mesh (or, for a surface extension, the level sets, with their analysis) under
/// a temporary name; without an output, nothing.
fn write_output(
    job: &Job,
    out: &MeshOutput,
    reporter: &Reporter,
) -> Result<(Option<SurfaceAnalysis>, Option<PendingFile>), PipelineError> {
    let Some(output) = job.output.as_deref() else {
        return Ok((None, None));
    };
    let stage = reporter.stage(&format!("writing {}", output.display()), StageKind::Step);
    let surface = SurfaceOptions {
        caps: job.req.caps,
        beta: job.opts.beta,
    };
    let (analysis, file) = in_pool(job.opts.threads, || {
        write_pending(output, &out.mesh, &job.req.write, &surface)
    })?;
    stage.finish();
    Ok((analysis, Some(file)))
}

/// Writes `mesh` to a temporary of `output`: the mesh in the format of its extension, or for
/// a surface extension (`.obj`, `.ply`, `.stl`) its level sets ([`level_surface`] with
/// `surface`), with their analysis.
fn write_pending(
    output: &Path,
    mesh: &TetMesh,
    write: &WriteOptions,
    surface: &SurfaceOptions,
) -> Result<(Option<SurfaceAnalysis>, PendingFile), PipelineError> {
    Ok(match SurfaceFormat::from_path(output) {
        Some(_) => {
            let s = level_surface(mesh, surface);
            let file = write_surface_pending(output, &s, write)?;
            (Some(analyse_surface(&s)), file)
        }
        None => (None, write_mesh_pending(output, mesh, write)?),
    })
}

/// Writes `mesh` to `path` as a run writes its output: the format by the extension (`.msh`,
/// `.inp`, `.vtu` with `write`'s options), or for `.obj`, `.ply` and `.stl` the level sets
/// (with `surface`'s caps). The file is written under a temporary name and renamed onto
/// `path` when complete: a failure leaves no file, and an existing `path` as it was.
///
/// # Errors
/// One line naming `path`: a directory or a missing one, an unknown extension, an
/// inconsistent mesh (an index out of range, lengths that differ, a labelled triangle that
/// is no face of a tet), or the system's refusal ([`PipelineError::is_io`]).
pub fn write_mesh_file(
    path: &Path,
    mesh: &TetMesh,
    write: &WriteOptions,
    surface: &SurfaceOptions,
) -> Result<(), PipelineError> {
    check_writable(path)?;
    let (_, file) = write_pending(path, mesh, write, surface)?;
    file.commit()?;
    Ok(())
}

/// A sink that hands each chunk on until the job's caller asks the run to stop
/// ([`crate::cancel::Cancel`]), then fails, which stops meshing.
struct Stop<'a> {
    cancel: &'a Cancel,
    inner: &'a mut (dyn MeshSink + Send),
}

impl<'a> Stop<'a> {
    fn new(job: &'a Job, inner: &'a mut (dyn MeshSink + Send)) -> Self {
        Stop {
            cancel: &job.req.cancel,
            inner,
        }
    }
}

impl MeshSink for Stop<'_> {
    fn chunk(&mut self, c: &MeshChunk) -> std::io::Result<()> {
        if self.cancel.is_cancelled() {
            return Err(std::io::ErrorKind::Interrupted.into());
        }
        self.inner.chunk(c)
    }
}

/// What gathers the facts of the job's mesh slab by slab.
fn facts_sink(job: &Job) -> FactsSink {
    FactsSink::new(job.req.analysis).with_regions(&job.opts.levels, job.req.region_names.clone())
}

/// Meshes the interval, handing the slabs to `facts` too when given; an empty mesh is an
/// error.
fn mesh(
    grid: &ScalarGrid,
    job: &Job,
    reporter: &Reporter,
    facts: Option<&mut FactsSink>,
) -> Result<MeshOutput, PipelineError> {
    let stage = reporter.stage("meshing", meshing(grid));
    let mut none = NoSink;
    let also: &mut (dyn MeshSink + Send) = match facts {
        Some(f) => f,
        None => &mut none,
    };
    let out = mesh_interval_seen_by(grid, &job.opts, &stage.counter(), &mut Stop::new(job, also));
    stage.finish();
    let mut out = out.map_err(|e| match job.req.cancel.is_cancelled() {
        true => PipelineError::interrupted(&job.input_name),
        false => PipelineError::file(&job.input_name, e),
    })?;
    check_not_empty(grid, job, out.mesh.tets.len())?;
    out.mesh.regions.names = job.req.region_names.clone();
    Ok(out)
}

/// An empty mesh is an error that names the data range.
fn check_not_empty(grid: &ScalarGrid, job: &Job, tets: usize) -> Result<(), PipelineError> {
    if tets > 0 {
        return Ok(());
    }
    let (lo, hi) = grid.value_range();
    Err(PipelineError::file(
        &job.input_name,
        format_args!(
            "the interval {} contains no part of the volume; data range is {}",
            fmt_interval(job.opts.alpha, job.opts.beta),
            fmt_interval(lo, hi)
        ),
    ))
}

/// For the demo (with analysis): the components the same interval has when meshed with a
/// method of the other kind.
fn compare_demo(grid: &ScalarGrid, job: &Job) -> Result<Option<DemoComparison>, PipelineError> {
    if !job.demo() || !job.req.analysis {
        return Ok(None);
    }
    let other = match job.opts.method {
        Method::Six | Method::Five => Method::Ctd,
        _ => Method::Six,
    };
    let o = mesh_interval(
        grid,
        &MeshOptions {
            method: other,
            warp: 0.0,
            ..job.opts.clone()
        },
    )
    .map_err(|e| PipelineError::file(&job.input_name, e))?;
    Ok(Some(DemoComparison {
        other,
        other_b0: crate::topology::betti(&o.mesh)[0],
    }))
}
