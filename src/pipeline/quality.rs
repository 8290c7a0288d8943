//! The quality pass of a run: the quality before it, the pass in its own thread pool (in a
//! curvilinear grid's parameter space, measured through the grid's map), and what it left:
//! the tets off the targets and the reasons of those below the floor. A missed target and a
//! pass stopped by its time budget are said in one warning each.

use std::time::Instant;

use crate::curvilinear::map_point;
use crate::improve::forced::{classify_forced_mapped, ForcedReport};
use crate::improve::outcome::{improve_meshed_mapped, target_counts, PointMap, TargetCounts};
use crate::improve::{ImproveReport, QualityOptions};
use crate::quality::{summarize, QualitySummary};
use crate::report::{QualitySection, QualityTimings};
use crate::{CurvilinearGrid, MeshOutput, ScalarGrid, TetMesh};

use super::progress::{Reporter, StageKind};
use super::request::Job;
use super::text::{budget_line, target_line};

/// With a quality pass in the request: the pass (and the quality before it, with analysis),
/// and the time of each part. On a `curvilinear` grid the mesh is in its parameter space,
/// and every quality is measured through the grid's map (as the mesh is written).
pub(crate) fn improve_mesh(
    (grid, job): (&ScalarGrid, &Job),
    out: &mut MeshOutput,
    curvilinear: Option<&CurvilinearGrid>,
    reporter: &Reporter,
) -> Option<(QualitySection, QualityTimings)> {
    let request = job.req.quality.as_ref()?;
    let analysis = job.req.analysis;
    let mapping = |p: [f64; 3]| curvilinear.map_or(p, |c| map_point(c, p));
    let map = curvilinear.is_some().then_some(&mapping as PointMap);
    let t = Instant::now();
    let before = analysis.then(|| summarize_mapped(&out.mesh, curvilinear));
    let before_seconds = t.elapsed().as_secs_f64();
    let opts = QualityOptions {
        cancel: job.req.cancel.clone(),
        ..request.pass_options()
    };
    let done = improve_in_pool(out, (grid, job), &opts, map, reporter);
    let section = QualitySection {
        target_degrees: [opts.min_angle, opts.max_angle],
        boundary_collapse_ratio: Some(opts.boundary_collapse_ratio).filter(|r| r.is_finite()),
        split_sag: Some(opts.split_sag).filter(|s| s.is_finite()),
        before,
        after: None,
        pass: done.report,
        forced: done.forced,
        floor_degrees: opts.forced_floor,
        outcome: done.outcome,
        target_missed: done.outcome.missed(),
    };
    if let Some(line) = budget_line(&section, request.budget_seconds(), job.req.names) {
        reporter.warn(format_args!("{}: {line}", job.input_name));
    }
    if let Some(line) = target_line(&section, job.req.names) {
        reporter.warn(format_args!("{}: {line}", job.input_name));
    }
    let seconds = QualityTimings {
        before: before_seconds,
        pass: done.pass_seconds,
        outcome: done.outcome_seconds,
    };
    Some((section, seconds))
}

/// The quality summary of `mesh`, through the `curvilinear` grid's map when there is one.
pub(crate) fn summarize_mapped(
    mesh: &TetMesh,
    curvilinear: Option<&CurvilinearGrid>,
) -> QualitySummary {
    use rayon::prelude::*;
    let Some(c) = curvilinear else {
        return summarize(mesh);
    };
    let mapped = TetMesh {
        points: mesh.points.par_iter().map(|&p| map_point(c, p)).collect(),
        tets: mesh.tets.clone(),
        ..TetMesh::default()
    };
    summarize(&mapped)
}

/// What [`improve_in_pool`] did and found, and the seconds of each part.
struct Improved {
    /// The pass.
    report: ImproveReport,
    /// The tets left below the floor with their reasons (with analysis).
    forced: Option<ForcedReport>,
    /// The tets left off the targets.
    outcome: TargetCounts,
    /// Seconds of the pass.
    pass_seconds: f64,
    /// Seconds of `forced` and `outcome`.
    outcome_seconds: f64,
}

/// Runs the quality pass on `out`'s mesh (in a pool of the job's threads), as the stage
/// `improving elements`; then counts the tets left off the targets and, with analysis, lists
/// those below the floor with their reasons. Quality is measured through `map` (a
/// curvilinear grid's geometry map; `None`: as the mesh is).
fn improve_in_pool(
    out: &mut MeshOutput,
    (grid, job): (&ScalarGrid, &Job),
    opts: &QualityOptions,
    map: Option<PointMap>,
    reporter: &Reporter,
) -> Improved {
    let stage = reporter.stage("improving elements", StageKind::Pass);
    let levels = job
        .opts
        .run_levels()
        .unwrap_or(crate::Levels::interval(job.opts.alpha, job.opts.beta));
    let classify = job.req.analysis;
    let pool = job
        .opts
        .threads
        .and_then(|n| rayon::ThreadPoolBuilder::new().num_threads(n).build().ok());
    let work = |out: &mut MeshOutput| {
        let t = Instant::now();
        let report = improve_meshed_mapped(out, grid, &levels, opts, map);
        let pass_seconds = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let mesh = &out.mesh;
        stage.message(&format!(
            "giving a reason for each element below {}°",
            opts.forced_floor
        ));
        let forced = classify.then(|| classify_forced_mapped(mesh, grid, &levels, opts, map));
        let outcome = target_counts(mesh, opts, map);
        Improved {
            report,
            forced,
            outcome,
            pass_seconds,
            outcome_seconds: t.elapsed().as_secs_f64(),
        }
    };
    let improved = match pool {
        Some(pool) => pool.install(|| work(out)),
        None => work(out),
    };
    stage.finish();
    improved
}
