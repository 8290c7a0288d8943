//! The mesh against the pass's targets: how many tets miss them ([`TargetCounts`]), and the
//! last step of a pass stopped by its time budget, which keeps the better of the mesh before
//! the pass and the one it stopped at ([`keep_better`]).

use std::time::Instant;

use rayon::prelude::*;

pub use crate::pass_report::{KeptBetter, TargetCounts};

use super::interfaces;
use super::pass::{improve_keeping_volume, runs_again_for_volume};
use super::{ImproveReport, QualityOptions, StageSeconds};
use crate::extract::MeshOutput;
use crate::grid::ScalarGrid;
use crate::levels::Levels;
use crate::mesh::TetMesh;
use crate::quality::tet_dihedral_range;
use crate::warp::Snapped;

/// A map of the mesh's points to the space its quality is measured in (a curvilinear grid's
/// geometry map: the pass works in the grid's parameter space, the mesh is written mapped).
pub type PointMap<'a> = &'a (dyn Fn([f64; 3]) -> [f64; 3] + Sync);

impl TargetCounts {
    fn empty() -> Self {
        TargetCounts {
            min_dihedral: 180.0,
            ..TargetCounts::default()
        }
    }

    fn add(mut self, (lo, hi): (f64, f64), opts: &QualityOptions) -> Self {
        let (below, above) = (lo < opts.min_angle, hi > opts.max_angle);
        self.tets += 1;
        self.below_floor += usize::from(lo < opts.forced_floor);
        self.below_min += usize::from(below);
        self.above_max += usize::from(above);
        self.off_target += usize::from(below || above);
        self.min_dihedral = self.min_dihedral.min(lo);
        self.max_dihedral = self.max_dihedral.max(hi);
        self
    }

    fn merge(self, o: Self) -> Self {
        TargetCounts {
            tets: self.tets + o.tets,
            below_floor: self.below_floor + o.below_floor,
            below_min: self.below_min + o.below_min,
            above_max: self.above_max + o.above_max,
            off_target: self.off_target + o.off_target,
            min_dihedral: self.min_dihedral.min(o.min_dihedral),
            max_dihedral: self.max_dihedral.max(o.max_dihedral),
        }
    }
}

/// The [`TargetCounts`] of `mesh` at `opts`' targets, its points taken through `map` (`None`:
/// as they are). Independent of the thread count.
pub fn target_counts(mesh: &TetMesh, opts: &QualityOptions, map: Option<PointMap>) -> TargetCounts {
    mesh.tets
        .par_iter()
        .fold(TargetCounts::empty, |c, t| {
            let p = t.map(|i| mesh.points[i as usize]);
            let p = match map {
                Some(m) => p.map(m),
                None => p,
            };
            c.add(tet_dihedral_range(p), opts)
        })
        .reduce(TargetCounts::empty, TargetCounts::merge)
}

/// Keeps the better of `mesh` (where a pass stopped) and `before` (the mesh before it), by
/// [`TargetCounts::better_than`] with the points through `map`: `mesh` becomes `before` only
/// when that is strictly better.
pub fn keep_better(
    mesh: &mut TetMesh,
    before: TetMesh,
    opts: &QualityOptions,
    map: Option<PointMap>,
) -> KeptBetter {
    let b = target_counts(&before, opts, map);
    let a = target_counts(mesh, opts, map);
    let kept_before = b.better_than(&a);
    if kept_before {
        *mesh = before;
    }
    KeptBetter {
        before: b,
        after: a,
        kept_before,
    }
}

/// [`super::improve_meshed`] for a mesh whose quality is measured through `map` (a
/// curvilinear grid's geometry map, [`crate::curvilinear::map_point`]; `None`: as it is):
/// when the time budget runs out, and always with a map, the better of the mesh before the
/// pass and the one it stopped at is kept by their quality through `map` ([`keep_better`]).
///
/// `levels` are the run's: with several regions the pass keeps every interface on its level
/// and every tet in its region ([`super::interfaces`]).
pub fn improve_meshed_mapped(
    out: &mut MeshOutput,
    grid: &ScalarGrid,
    levels: &Levels,
    opts: &QualityOptions,
    map: Option<PointMap>,
) -> ImproveReport {
    let (mesh, snapped) = (&mut out.mesh, &out.snapped);
    improve_keeping_better(mesh, grid, levels, opts, snapped, map)
}

/// The pass ([`improve_keeping_volume`]); with a time budget, a copy of the mesh before it is
/// kept, and if the budget runs out (the pass ends after its deadline, whether or not a
/// round was cut short) the better of the two is kept ([`keep_better`]). Sets
/// [`super::StageSeconds::other`] so that the stage seconds add up to the pass's.
pub(super) fn improve_keeping_better(
    mesh: &mut TetMesh,
    grid: &ScalarGrid,
    levels: &Levels,
    opts: &QualityOptions,
    snapped: &[Snapped],
    map: Option<PointMap>,
) -> ImproveReport {
    let start = Instant::now();
    let regions = !mesh.regions.is_empty();
    if regions {
        interfaces::into_boundary(mesh);
    }
    let volume = runs_again_for_volume(mesh, opts);
    let copy = (volume || opts.time_budget.is_some() || map.is_some()).then(|| mesh.clone());
    // Copying is part of comparing (the copy is what the result is compared with).
    let copied = start.elapsed().as_secs_f64();
    let again = copy.as_ref().filter(|_| volume);
    let mut report = improve_keeping_volume(mesh, grid, levels, opts, (snapped, again));
    report.stage_seconds.compare += copied;
    // A deadline met inside the last round's sweeps cuts them short without the flag.
    report.out_of_time |= opts.time_budget.is_some_and(|b| start.elapsed() >= b);
    // The pass measures quality in the grid's parameter space; through a curvilinear map its
    // result can be worse than its start, so it is compared there always.
    if let (Some(before), true) = (copy, report.out_of_time || map.is_some()) {
        let t = Instant::now();
        report.budget = Some(keep_better(mesh, before, opts, map));
        report.stage_seconds.compare += t.elapsed().as_secs_f64();
    }
    if regions {
        interfaces::out_of_boundary(mesh);
    }
    report.seconds = start.elapsed().as_secs_f64();
    report.stage_seconds.other = (report.seconds - report.stage_seconds.named()).max(0.0);
    report
}

impl StageSeconds {
    /// Adds `o`'s seconds to these.
    pub(super) fn add(&mut self, o: &StageSeconds) {
        self.project += o.project;
        self.mark += o.mark;
        self.extract += o.extract;
        self.local += o.local;
        self.splice += o.splice;
        self.finish += o.finish;
        self.compare += o.compare;
    }

    /// The named stages' sum (all but [`StageSeconds::other`]).
    pub(super) fn named(&self) -> f64 {
        self.project
            + self.mark
            + self.extract
            + self.local
            + self.splice
            + self.finish
            + self.compare
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One tet: a regular-ish corner tet, or a sliver when `flat`.
    fn tet(flat: bool) -> TetMesh {
        let top = if flat { 0.01 } else { 1.0 };
        TetMesh {
            points: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.3, 0.3, top],
            ],
            values: vec![0.0; 4],
            tets: vec![[0, 1, 2, 3]],
            ..Default::default()
        }
    }

    #[test]
    fn counts_and_order() {
        let opts = QualityOptions::default();
        let good = target_counts(&tet(false), &opts, None);
        let bad = target_counts(&tet(true), &opts, None);
        assert_eq!((good.tets, good.below_floor, good.off_target), (1, 0, 0));
        assert_eq!((bad.below_floor, bad.below_min, bad.off_target), (1, 1, 1));
        assert!(!good.missed() && bad.missed());
        assert!(good.better_than(&bad) && !bad.better_than(&good));
        assert!(!good.better_than(&good));
        // Through a map that flattens z, the good tet is a sliver too.
        let flatten = |p: [f64; 3]| [p[0], p[1], 0.01 * p[2]];
        let mapped = target_counts(&tet(false), &opts, Some(&flatten));
        assert_eq!(mapped.below_floor, 1);
    }

    #[test]
    fn keeps_the_mesh_before_only_when_it_is_better() {
        let opts = QualityOptions::default();
        let mut mesh = tet(true);
        let k = keep_better(&mut mesh, tet(false), &opts, None);
        assert!(k.kept_before && mesh == tet(false));
        let k = keep_better(&mut mesh, tet(true), &opts, None);
        assert!(!k.kept_before && mesh == tet(false));
    }
}
