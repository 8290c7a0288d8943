//! `--quality`: the quality before the pass, the pass (in a curvilinear grid's parameter
//! space, measured through the grid's map), and what it left: the tets off the targets and
//! the reasons of those below the floor. A missed target and a pass stopped by its time
//! budget are said in one warning each.

use std::time::{Duration, Instant};

use tptd::curvilinear::map_point;
use tptd::improve::QualityOptions;
use tptd::quality::{summarize, QualitySummary};
use tptd::report::{QualitySection, QualityTimings};
use tptd::{CurvilinearGrid, MeshOutput, ScalarGrid, TetMesh};

use crate::cli::Cli;
use crate::progress::improve_with_progress;
use crate::run::Job;
use crate::summary::{budget_line, target_line};
use crate::warnings::warn;

/// With `--quality`: the quality pass (and the quality before it, unless `--no-analysis`), and
/// the time of each part. On a `curvilinear` grid the mesh is in its parameter space, and every
/// quality is measured through the grid's map (as the mesh is written).
pub(crate) fn improve_mesh(
    cli: &Cli,
    (grid, job): (&ScalarGrid, &Job),
    out: &mut MeshOutput,
    curvilinear: Option<&CurvilinearGrid>,
) -> Option<(QualitySection, QualityTimings)> {
    if !cli.quality {
        return None;
    }
    let mapping = |p: [f64; 3]| curvilinear.map_or(p, |c| map_point(c, p));
    let map = curvilinear
        .is_some()
        .then_some(&mapping as tptd::improve::outcome::PointMap);
    let t = Instant::now();
    let before = (!cli.no_analysis).then(|| summarize_mapped(&out.mesh, curvilinear));
    let before_seconds = t.elapsed().as_secs_f64();
    let opts = QualityOptions {
        min_angle: cli.min_angle,
        max_angle: cli.max_angle,
        time_budget: cli.quality_time.map(Duration::from_secs_f64),
        boundary_collapse_ratio: cli.boundary_collapse_ratio,
        split_sag: cli.split_sag,
        ..QualityOptions::default()
    };
    let flags = (cli.quiet, !cli.no_analysis);
    let done = improve_with_progress(out, (grid, job), &opts, flags, map);
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
    warn_outcome(cli, job, &section);
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

/// Warns when the pass stopped on its time budget and kept the mesh from before it, and when
/// the mesh misses the targets.
fn warn_outcome(cli: &Cli, job: &Job, q: &QualitySection) {
    if let Some(line) = budget_line(q, cli.quality_time) {
        warn(format_args!("{}: {line}", job.input_name));
    }
    if let Some(line) = target_line(q) {
        warn(format_args!("{}: {line}", job.input_name));
    }
}
