//! One run of `tptd-mesh`, step by step: check the arguments, read, mesh, analyse, write the
//! mesh and the report, print the summary.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Result;
use tptd::check::{check_mesh, CheckOptions, CheckReport};
use tptd::demo::{demo_volume, DEMO_ALPHA, DEMO_BETA};
use tptd::facts::{FactsSink, MeshFacts};
use tptd::io::WriteOptions;
use tptd::io::{
    check_writable, read_volume, spill_for, write_mesh_pending, write_pending,
    write_spilled_pending, MeshFormat, PendingFile, SurfaceFormat,
};
use tptd::quality::summarize;
use tptd::report::{build_report, QualitySection, QualityTimings, Report, RunInfo, Timings};
use tptd::{
    mesh_interval, MeshError, MeshOptions, MeshOutput, MeshStats, Method, Samples, ScalarGrid,
};

use crate::cli::{Cli, Spacing};
use crate::error::{file_error, write_error};
use crate::progress::{mesh_streamed_with_progress, mesh_with_progress, Stage};
use crate::quality::improve_mesh;
use crate::summary::{fmt_bound, fmt_interval, summary, DemoComparison};
use crate::surface::{read_curvilinear_input, write_level_surface};
use crate::warnings::warn;
use tptd::curvilinear::map_mesh;
use tptd::surface::analysis::SurfaceAnalysis;
use tptd::CurvilinearGrid;

/// Output written by `--demo` when no `-o` is given.
pub(crate) const DEMO_OUTPUT: &str = "tptd-demo.vtu";

/// The checked arguments of a run.
pub(crate) struct Job {
    /// The input as named in messages (`demo` for the demo volume).
    pub(crate) input_name: String,
    /// The mesh output path.
    pub(crate) output: PathBuf,
    /// The meshing options.
    pub(crate) opts: MeshOptions,
    /// The mesh writer options.
    pub(crate) write: WriteOptions,
}

/// What meshing, analysing and writing produced (the mesh file still pending).
struct Written {
    facts: MeshFacts,
    stats: MeshStats,
    quality: Option<QualitySection>,
    surface: Option<SurfaceAnalysis>,
    comparison: Option<DemoComparison>,
    check: Option<CheckReport>,
    mesh_file: PendingFile,
    /// Seconds of meshing, analysis (with the demo's comparison), the quality step (by part),
    /// the curvilinear map, the check and writing.
    t_mesh: f64,
    t_analysis: f64,
    t_quality: Option<QualityTimings>,
    t_map: Option<f64>,
    t_check: Option<f64>,
    t_write: f64,
}

/// Seconds since `t`.
fn secs(t: Instant) -> f64 {
    t.elapsed().as_secs_f64()
}

/// Runs `tptd-mesh` with the parsed arguments.
pub(crate) fn run(cli: Cli) -> Result<()> {
    let t_total = Instant::now();
    let job = check_args(&cli)?;
    let t_args = secs(t_total);

    let t = Instant::now();
    let (grid, curvilinear) = read_input(&cli, &job)?;
    let t_read = secs(t);
    let t = Instant::now();
    let streaming = streams(&cli, &job, curvilinear.is_some());
    check_input(&cli, &job, &grid, curvilinear.is_some(), streaming)?;
    let t_checks = t_args + secs(t);

    let w = if streaming {
        stream_to_disk(&cli, &job, &grid)?
    } else {
        mesh_in_memory(&cli, &job, &grid, curvilinear.as_ref())?
    };
    let mut timings = Timings {
        streamed: streaming,
        read: t_read,
        checks: t_checks,
        mesh: w.t_mesh,
        analysis: w.t_analysis,
        quality: w.t_quality.as_ref().map(QualityTimings::total),
        quality_stages: w.t_quality,
        map: w.t_map,
        check: w.t_check,
        write: w.t_write,
        other: 0.0,
        total: secs(t_total),
    };
    timings.close();
    let mut report = make_report(&job, &grid, &w.facts, &w.stats, w.quality, timings);
    report.surface = w.surface;
    report.check = w.check;
    report.warnings = crate::warnings::take();
    finish(&cli, &report, w.comparison.as_ref(), w.mesh_file)?;
    // The process ends here: let the OS reclaim the grid at exit instead of freeing hundreds
    // of megabytes page by page first.
    std::mem::forget(grid);
    Ok(())
}

/// Whether the mesh goes straight to disk slab by slab: a volume mesh output without the
/// quality pass (which needs the whole mesh), a curvilinear mapping or the check (which reads
/// the whole mesh).
fn streams(cli: &Cli, job: &Job, curvilinear: bool) -> bool {
    !cli.quality && !cli.check && !curvilinear && SurfaceFormat::from_path(&job.output).is_none()
}

/// Meshes slab by slab into spill files next to the output, gathering the facts on the way,
/// then writes the output from the spill files: memory stays the grid plus a few slabs.
fn stream_to_disk(cli: &Cli, job: &Job, grid: &ScalarGrid) -> Result<Written> {
    let t = Instant::now();
    let mut spill = spill_for(&job.output).map_err(write_error)?;
    let mut facts = FactsSink::new(!cli.no_analysis);
    let stats = mesh_streamed_with_progress(grid, &job.opts, cli.quiet, &mut spill, &mut facts)
        .map_err(|e| match e {
            MeshError::Output(e) => file_error(job.output.display(), e),
            e => file_error(&job.input_name, e),
        })?;
    let facts = facts.finish();
    check_not_empty(grid, job, facts.tets)?;
    let t_mesh = secs(t);
    let t = Instant::now();
    let stage = Stage::start(format!("writing {}", job.output.display()), cli.quiet);
    let mesh_file = write_spilled_pending(&job.output, &mut spill, &job.write);
    stage.finish();
    let t_write = secs(t);
    let t = Instant::now();
    let comparison = compare_demo(cli, grid, job)?;
    // Only the demo is compared: otherwise nothing is analysed here (the rest is `other`).
    let t_analysis = if comparison.is_some() { secs(t) } else { 0.0 };
    Ok(Written {
        facts,
        stats,
        quality: None,
        surface: None,
        comparison,
        check: None,
        mesh_file: mesh_file.map_err(write_error)?,
        t_mesh,
        t_analysis,
        t_quality: None,
        t_map: None,
        t_check: None,
        t_write,
    })
}

/// Meshes into memory, improves (`--quality`), maps (curvilinear), analyses and writes.
fn mesh_in_memory(
    cli: &Cli,
    job: &Job,
    grid: &ScalarGrid,
    curvilinear: Option<&CurvilinearGrid>,
) -> Result<Written> {
    let t = Instant::now();
    let mut out = mesh(grid, job, cli.quiet)?;
    let t_mesh = secs(t);

    let (quality, t_quality) = improve_mesh(cli, (grid, job), &mut out, curvilinear).unzip();
    // The level-set distance of a curvilinear mesh is checked in parameter space.
    let parameter_points = (cli.check && curvilinear.is_some()).then(|| out.mesh.points.clone());
    let t = Instant::now();
    let t_map = match curvilinear {
        Some(c) => {
            map_mesh(&mut out.mesh, c).map_err(|e| file_error(&job.input_name, e))?;
            Some(secs(t))
        }
        None => None,
    };

    let t = Instant::now();
    let stage = Stage::start("analysing the mesh".into(), cli.quiet);
    let facts = MeshFacts::of(&out.mesh, !cli.no_analysis);
    let after = (cli.quality && !cli.no_analysis).then(|| summarize(&out.mesh));
    stage.finish();
    let quality = quality.map(|mut q| {
        q.after = after;
        q
    });
    let comparison = compare_demo(cli, grid, job)?;
    let t_analysis = secs(t);
    let parameter_points = parameter_points.as_deref();
    let (check, t_check) = check_output(cli, job, grid, parameter_points, &out.mesh)?;

    // The mesh stays under its temporary name until the report is written too (`finish`).
    let t = Instant::now();
    let (surface, mesh_file) = write_output(cli, job, &out)?;
    let t_write = secs(t);
    let stats = out.stats.clone();
    // Let the OS reclaim the mesh at exit.
    std::mem::forget(out);
    Ok(Written {
        facts,
        stats,
        quality,
        surface,
        comparison,
        check,
        mesh_file,
        t_mesh,
        t_analysis,
        t_quality,
        t_map,
        t_check,
        t_write,
    })
}

/// With `--check`: the validity check of the mesh, before anything is written; a mesh that
/// fails it is an error naming the count of each problem. A curvilinear mesh (mapped to
/// physical space) has its level-set distance checked at its points in parameter space
/// (`parameter_points`), where its grid's values are.
fn check_output(
    cli: &Cli,
    job: &Job,
    grid: &ScalarGrid,
    parameter_points: Option<&[[f64; 3]]>,
    mesh: &tptd::TetMesh,
) -> Result<(Option<CheckReport>, Option<f64>)> {
    if !cli.check {
        return Ok((None, None));
    }
    let t = Instant::now();
    let stage = Stage::start("checking the mesh".into(), cli.quiet);
    let opts = CheckOptions {
        level_points: parameter_points,
        ..CheckOptions::for_method(grid, job.opts.alpha, job.opts.beta, job.opts.method)
    };
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
        return Err(file_error(
            job.output.display(),
            format_args!(
                "the mesh fails --check ({}{how_far}); nothing written",
                report.summary_line()
            ),
        ));
    }
    Ok((Some(report), Some(secs(t))))
}

/// Reads the input volume (a curvilinear grid's values in parameter space, with the grid).
fn read_input(cli: &Cli, job: &Job) -> Result<(ScalarGrid, Option<CurvilinearGrid>)> {
    let stage = Stage::start(format!("reading {}", job.input_name), cli.quiet);
    let curvilinear = read_curvilinear_input(cli)?;
    let grid = match &curvilinear {
        Some(c) => c.values.clone(),
        None => read_grid(cli, &job.input_name)?,
    };
    stage.finish();
    Ok((grid, curvilinear))
}

/// Warnings about the bounds and the geometry, and the memory check, before meshing.
fn check_input(
    cli: &Cli,
    job: &Job,
    grid: &ScalarGrid,
    curvilinear: bool,
    streaming: bool,
) -> Result<()> {
    warn_exact_bounds(grid, job);
    if !curvilinear {
        warn_near_singular(grid, job);
    }
    if !cli.no_critical_check {
        let (a, b) = (job.opts.alpha, job.opts.beta);
        crate::critical::warn_critical_bounds(grid, &job.input_name, a, b, cli.critical_tol);
    }
    check_memory(grid, job, streaming, cli.quality, cli.check)
}

/// Writes the mesh (or, for a surface extension, the level sets) under a temporary name;
/// `finish` renames it once the report is written too.
fn write_output(
    cli: &Cli,
    job: &Job,
    out: &MeshOutput,
) -> Result<(Option<SurfaceAnalysis>, PendingFile)> {
    let stage = Stage::start(format!("writing {}", job.output.display()), cli.quiet);
    let written = match SurfaceFormat::from_path(&job.output) {
        Some(_) => {
            let (analysis, file) = write_level_surface(cli, job, &out.mesh)?;
            (Some(analysis), file)
        }
        None => {
            let file = write_mesh_pending(&job.output, &out.mesh, &job.write);
            (None, file.map_err(write_error)?)
        }
    };
    stage.finish();
    Ok(written)
}

/// Checks the arguments before any work: the interval, the output format and that the
/// outputs can be written.
fn check_args(cli: &Cli) -> Result<Job> {
    let demo = cli.input.is_none();
    let input_name = match &cli.input {
        Some(p) => p.display().to_string(),
        None => "demo".to_string(),
    };
    let output = match (&cli.output, demo) {
        (Some(p), _) => p.clone(),
        (None, true) => PathBuf::from(DEMO_OUTPUT),
        (None, false) => unreachable!("clap requires -o without --demo"),
    };
    let (alpha, beta) = interval(cli, demo, &input_name)?;
    check_threads(cli.threads)?;
    check_outputs(cli, &output)?;
    let opts = MeshOptions {
        alpha,
        beta,
        method: cli.method.method(),
        threads: cli.threads.map(|n| n as usize),
        warp: if cli.quality {
            tptd::improve::DEFAULT_WARP
        } else {
            0.0
        },
        ..MeshOptions::default()
    };
    let write = WriteOptions::default()
        .with_msh_version(cli.msh_version.version())
        .with_ascii(cli.ascii)
        .with_vtu_encoding(cli.vtu_encoding.encoding());
    Ok(Job {
        input_name,
        output,
        opts,
        write,
    })
}

/// The interval `(alpha, beta)` of `--alpha`/`--beta` (the demo's without both), which must
/// not be empty.
fn interval(cli: &Cli, demo: bool, input_name: &str) -> Result<(f64, f64)> {
    let (alpha, beta) = match (cli.alpha, cli.beta) {
        (None, None) if demo => (DEMO_ALPHA, DEMO_BETA),
        (None, None) => {
            return Err(file_error(
                input_name,
                "no interval given: use --alpha A and/or --beta B (meshes alpha <= f <= beta)",
            ))
        }
        (a, b) => (a.unwrap_or(f64::NEG_INFINITY), b.unwrap_or(f64::INFINITY)),
    };
    if alpha >= beta {
        return Err(file_error(
            input_name,
            format_args!(
                "empty interval: --alpha ({}) must be less than --beta ({})",
                fmt_bound(alpha),
                fmt_bound(beta)
            ),
        ));
    }
    Ok((alpha, beta))
}

/// Checks the output (a known mesh or surface format, writable) and the report output
/// (writable), then that no output is an input file or another output (compared by
/// identity, not spelling; see [`crate::files::check_files`]).
fn check_outputs(cli: &Cli, output: &Path) -> Result<()> {
    if SurfaceFormat::from_path(output).is_none() {
        MeshFormat::from_path(output).map_err(write_error)?;
    }
    check_writable(output).map_err(write_error)?;
    if let Some(r) = &cli.report {
        check_writable(r).map_err(write_error)?;
    }
    crate::files::check_files(cli, Some(output))
}

/// Most worker threads `-j` accepts per core: more only adds overhead.
const MAX_THREADS_PER_CORE: usize = 16;

/// Checks `-j` against the machine at once (a huge pool takes long to start and to fail).
pub(crate) fn check_threads(threads: Option<u32>) -> Result<()> {
    let Some(n) = threads else { return Ok(()) };
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let max = (cores * MAX_THREADS_PER_CORE).max(MAX_THREADS_PER_CORE);
    if n as usize > max {
        return Err(file_error(
            format_args!("-j {n}"),
            format_args!("too many worker threads: at most {max} on this machine ({cores} cores)"),
        ));
    }
    Ok(())
}

/// Reads the input volume (or generates the demo volume) and applies `--spacing`.
pub(crate) fn read_grid(cli: &Cli, input_name: &str) -> Result<ScalarGrid> {
    let mut grid = match &cli.input {
        Some(p) => read_volume(p)?,
        None => demo_volume(),
    };
    if let Some(Spacing(s)) = cli.spacing {
        grid = ScalarGrid::with_geometry(grid.dims, s, grid.origin, grid.direction, grid.values)
            .map_err(|e| file_error(input_name, format_args!("--spacing: {e}")))?;
    }
    Ok(grid)
}

/// Warns ([`warn`]) when the direction matrix is nearly singular (the mesh comes out nearly
/// flat); an exactly singular one was refused by the reader.
fn warn_near_singular(grid: &ScalarGrid, job: &Job) {
    let k = tptd::grid::condition_number(&grid.direction);
    if k > tptd::grid::NEAR_SINGULAR_CONDITION {
        warn(format_args!(
            "{}: the direction matrix is nearly singular (condition number \
             {k:.2e}): the index axes are almost dependent, so the tetrahedra are nearly flat; \
             check the file's direction/orientation fields",
            job.input_name
        ));
    }
}

/// Warns ([`warn`]) about each bound that equals grid values exactly.
fn warn_exact_bounds(grid: &ScalarGrid, job: &Job) {
    let (alpha, beta) = (job.opts.alpha, job.opts.beta);
    for (name, bound, lower) in [("alpha", alpha, true), ("beta", beta, false)] {
        if let Some(w) = bound_warning(&grid.values, name, bound, lower) {
            warn(format_args!("{}: {w}", job.input_name));
        }
    }
}

/// The warning for a bound that equals grid values exactly, if it does.
fn bound_warning(values: &Samples, name: &str, bound: f64, lower: bool) -> Option<String> {
    if !bound.is_finite() {
        return None;
    }
    let hits = values.par_fold(|| 0usize, |n, v| n + usize::from(v == bound), |a, b| a + b);
    if hits == 0 {
        return None;
    }
    let suggestion = match inside_value(values, bound, lower) {
        Some(v) => format!(" (e.g. --{name} {} includes them)", fmt_bound(v)),
        None => String::new(),
    };
    Some(format!(
        "--{name} {} equals the value of {hits} grid vertices; values equal to a bound count \
         as outside the interval, which can leave hairline gaps or pinch points; use a value \
         between data values to avoid them{suggestion}",
        fmt_bound(bound)
    ))
}

/// A value between `bound` and the next data value on the inside-making side (below a lower
/// bound, above an upper one), so the vertices equal to the bound are included; `None` when
/// there is no such data value.
fn inside_value(values: &Samples, bound: f64, lower: bool) -> Option<f64> {
    let next = if lower {
        let below = |m: f64, v: f64| if v < bound { m.max(v) } else { m };
        values.par_fold(|| f64::NEG_INFINITY, below, f64::max)
    } else {
        let above = |m: f64, v: f64| if v > bound { m.min(v) } else { m };
        values.par_fold(|| f64::INFINITY, above, f64::min)
    };
    next.is_finite().then(|| bound + (next - bound) / 2.0)
}

/// Checks the memory estimate of meshing, analysis and the quality pass before the work (see
/// [`tptd::memory`]).
fn check_memory(
    grid: &ScalarGrid,
    job: &Job,
    streaming: bool,
    quality: bool,
    check: bool,
) -> Result<()> {
    use tptd::memory::{estimate_tets, mesh_bytes, stream_bytes};
    let tets = estimate_tets(grid, job.opts.alpha, job.opts.beta);
    let bytes = grid.values.bytes_per_sample() as u64;
    let voxels = grid.num_vertices() as u64;
    let need = if streaming {
        let layers = grid.cell_dims()[2] as u64;
        // Two windows: one meshed while the other is handed on.
        stream_bytes(voxels, bytes, tets, layers, 2 * job.opts.window() as u64)
    } else {
        let pass = if quality {
            tets.saturating_mul(tptd::memory::QUALITY_BYTES_PER_TET)
        } else {
            0
        };
        let checker = if check {
            tets.saturating_mul(tptd::check::CHECK_BYTES_PER_TET)
        } else {
            0
        };
        mesh_bytes(voxels, bytes, tets)
            .saturating_add(pass)
            .saturating_add(checker)
    };
    let what = format!(
        "meshing {} (about {:.1} M tetrahedra)",
        fmt_interval(job.opts.alpha, job.opts.beta),
        tets as f64 / 1e6
    );
    tptd::memory::check(need, what).map_err(|e| {
        file_error(
            &job.input_name,
            format_args!("{e}; narrow the interval, crop the volume or raise --memory-limit"),
        )
    })
}

/// Meshes the interval; an empty mesh is an error.
fn mesh(grid: &ScalarGrid, job: &Job, quiet: bool) -> Result<MeshOutput> {
    let out =
        mesh_with_progress(grid, &job.opts, quiet).map_err(|e| file_error(&job.input_name, e))?;
    check_not_empty(grid, job, out.mesh.tets.len())?;
    Ok(out)
}

/// An empty mesh is an error that names the data range.
fn check_not_empty(grid: &ScalarGrid, job: &Job, tets: usize) -> Result<()> {
    if tets > 0 {
        return Ok(());
    }
    let (lo, hi) = grid.value_range();
    Err(file_error(
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
fn compare_demo(cli: &Cli, grid: &ScalarGrid, job: &Job) -> Result<Option<DemoComparison>> {
    if cli.input.is_some() || cli.no_analysis {
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
    .map_err(|e| file_error(&job.input_name, e))?;
    Ok(Some(DemoComparison {
        other,
        other_b0: tptd::topology::betti(&o.mesh)[0],
    }))
}

/// The report of the run.
fn make_report(
    job: &Job,
    grid: &ScalarGrid,
    facts: &MeshFacts,
    stats: &MeshStats,
    quality: Option<QualitySection>,
    timings: Timings,
) -> Report {
    let threads = job
        .opts
        .threads
        .unwrap_or_else(rayon::current_num_threads)
        .max(1);
    let output_name = job.output.display().to_string();
    build_report(
        &RunInfo {
            input: &job.input_name,
            output: &output_name,
            dims: grid.dims,
            spacing: grid.spacing,
            samples: grid.values.storage(),
            method: job.opts.method,
            alpha: job.opts.alpha,
            beta: job.opts.beta,
            threads,
        },
        facts,
        stats,
        quality,
        timings,
    )
}

/// Writes the JSON report (with `--report`), then renames the mesh and the report onto their
/// names, and prints the summary (unless `--quiet`). When the report cannot be written,
/// neither file is: dropping `mesh_file` removes the mesh's temporary.
fn finish(
    cli: &Cli,
    report: &Report,
    comparison: Option<&DemoComparison>,
    mesh_file: PendingFile,
) -> Result<()> {
    let report_file = match &cli.report {
        Some(path) => {
            let mut json = report.to_json_pretty();
            json.push('\n');
            Some(write_pending(path, |w| w.write_all(json.as_bytes())).map_err(write_error)?)
        }
        None => None,
    };
    mesh_file.commit().map_err(write_error)?;
    if let Some(f) = report_file {
        f.commit().map_err(write_error)?;
    }
    if !cli.quiet {
        let text = summary(report, comparison, cli.report.as_deref());
        // A closed stdout (e.g. `| head`) is not an error of the run.
        let _ = std::io::stdout().lock().write_all(text.as_bytes());
    }
    Ok(())
}
