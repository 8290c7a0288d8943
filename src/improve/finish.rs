//! The last stage after the rounds: the splits of the boundary edges that sag from the level
//! set and the restoration of the volume the operations moved, region by region, and once
//! more over the whole boundary where the mesh's volume is still off.

use std::time::Instant;

use rayon::prelude::*;

use super::constraint::interface_bits;
use super::ctx::Ctx;
use super::mark::grow;
use super::pass::PassState;
use super::region::{self, LocalMesh};
use super::report::lap;
use super::volumes::Volumes;
use super::{restore, split, verify, ImproveReport, QualityOptions};
use crate::levels::MAX_LEVELS;
use crate::mesh::{TetMesh, LEVEL_BITS};

/// The last stage after the rounds (of each target stage), region by region: splits the
/// boundary edges whose chord sags from the level set ([`split::split_sagging_edges`]), then,
/// around the points that carry volume drift, gives it back by moving level vertices along
/// their level sets ([`restore::restore_volume`]). Neither lets a tet fall below the target
/// (or below where it was), so nothing they do needs improving again. New points are appended
/// to the mesh, so point ids stay valid.
pub(super) fn finish_stage(
    mesh: &mut TetMesh,
    ctx: &Ctx,
    opts: &QualityOptions,
    drift: &[f64],
    quality: &mut Vec<f64>,
    report: &mut ImproveReport,
) {
    let mut clock = Instant::now();
    let split = opts.split_sag.is_finite();
    let sagging = if split {
        split::sagging_points(mesh, ctx, opts.split_sag)
    } else {
        vec![false; mesh.points.len()]
    };
    let owed = if opts.restore_volume {
        let labels = mesh.vertex_label_bits();
        restore::largest_drift_by_group(drift, |v| {
            let on = labels[v] & LEVEL_BITS;
            (on.count_ones() == 1).then(|| restore::group_of(ctx, on.trailing_zeros() as u8))
        })
    } else {
        Vec::new()
    };
    // The points that owe drift and their neighbours, which share the moves that give it
    // back (without them the T1 at [51.5, 101.5] was still 0.43 % off, and the whole
    // boundary was restored again by `restore_residual`).
    let mut work: Vec<bool> = owed.iter().map(|&d| d != 0.0).collect();
    work.resize(mesh.points.len(), false);
    if work.contains(&true) {
        grow(mesh, &mut work);
    }
    for (w, &s) in work.iter_mut().zip(&sagging) {
        *w |= s;
    }
    for phase in 0..2 {
        // The points the first phase added need nothing.
        work.resize(mesh.points.len(), false);
        let (mut regions, bookkeeping) =
            region::extract_regions(mesh, (&work, None), quality, ctx, phase);
        let starts = regions.clone();
        let (splits, moves) = regions
            .par_iter_mut()
            .map(|lm| finish_region(lm, ctx, opts, (&owed, &sagging)))
            .reduce(|| (0, 0), |x, y| (x.0 + y.0, x.1 + y.1));
        report.regions_undone +=
            verify::keep_embedded(mesh, ctx, &mut regions, starts, &bookkeeping, false);
        report.splits += splits;
        report.restored += moves;
        if splits > 0 {
            region::splice(mesh, regions, bookkeeping, quality);
        } else {
            region::write_positions(mesh, &regions, &bookkeeping, quality);
        }
    }
    lap(&mut report.stage_seconds.finish, &mut clock);
}

/// The share of the plain volume that the mesh may be off by without the restoration
/// (before the last stage), or after it without [`restore_residual`] (half of what the quality goal
/// allows, 0.5 %).
pub(super) const RESIDUAL: f64 = 2.5e-3;

/// The rungs of [`restore_residual`], as multiples of [`QualityOptions::split_sag`]: first no
/// splits, then (after the last stage only) splits of the chords that sag by a third and by
/// a tenth of it. A moved node only shifts volume along the level set: where a small convex
/// part lost boundary nodes (the benchmark's two balls 0.3 voxel apart, radius 4.4 voxels at
/// 20³: −0.70 % after the first rung), only more nodes on the level set give it back (−0.39 %
/// after the third).
const RESIDUAL_RUNGS: [f64; 3] = [f64::INFINITY, 1.0 / 3.0, 0.1];

/// Where the last stage left the mesh's volume off `plain` by more than [`RESIDUAL`] of it
/// (the regions around the drift could not give it all back where it arose: their tets
/// were at the target), books the rest evenly on every level vertex and restores once more
/// around all of them, rung by rung of [`RESIDUAL_RUNGS`] while it stays off (the splits
/// only after the `last` stage: splits in an earlier one change where the next starts). The
/// full-size volumes of the benchmarks never get here; small analytic domains (a boundary
/// of a few thousand nodes) do.
pub(super) fn restore_residual(
    mesh: &mut TetMesh,
    ctx: &Ctx,
    opts: &QualityOptions,
    (plain, last): (&Volumes, bool),
    state: &mut PassState,
    report: &mut ImproveReport,
) {
    let rungs = if last && opts.split_sag.is_finite() {
        &RESIDUAL_RUNGS[..]
    } else {
        &RESIDUAL_RUNGS[..1]
    };
    for &rung in rungs {
        let split_sag = rung * opts.split_sag;
        let residual = mesh.volume() - plain.whole;
        if plain.off(mesh) <= RESIDUAL || ctx.out_of_time() {
            return;
        }
        if mesh.regions.is_empty() {
            spread_residual(mesh, residual, &mut state.drift);
        } else {
            spread_region_residuals(mesh, plain, &mut state.drift);
        }
        let rung_opts = QualityOptions {
            split_sag,
            ..opts.clone()
        };
        let PassState { quality, drift, .. } = &mut *state;
        finish_stage(mesh, ctx, &rung_opts, drift, quality, report);
        // The next rung (or stage) starts from no drift, and from the points splits added.
        drift.iter_mut().for_each(|d| *d = 0.0);
        drift.resize(mesh.points.len(), 0.0);
    }
}

/// Books `residual` evenly on every vertex of `mesh` on the first or the last level (`drift`,
/// per point; left as it is when there is none): moves on the levels between regions do not
/// change the volume of the whole.
fn spread_residual(mesh: &TetMesh, residual: f64, drift: &mut [f64]) {
    let labels = mesh.vertex_label_bits();
    let outer = LEVEL_BITS & !interface_bits(mesh.level_count());
    let level = |v: usize| labels[v] & outer != 0;
    let n = (0..mesh.points.len()).filter(|&v| level(v)).count();
    if n == 0 {
        return;
    }
    for (v, d) in drift.iter_mut().enumerate() {
        *d = if level(v) { residual / n as f64 } else { 0.0 };
    }
}

/// [`spread_residual`] for a mesh of several regions: what each region is off its `plain`
/// volume is booked on the vertices of its levels, evenly on each level, so that giving back
/// every level's drift ([`restore::group_of`]) gives every region its volume back. A level's
/// drift counts for the region below it (for the first level, above), so region `k`'s
/// residual goes to its upper level, after what the levels below passed up to it; the sum
/// ends on the last level (the whole mesh's residual). Where the last level has no vertices
/// (`+inf`) the chain runs from the top down and ends on the first.
fn spread_region_residuals(mesh: &TetMesh, plain: &Volumes, drift: &mut [f64]) {
    let residual: Vec<f64> = Volumes::of_regions(mesh)
        .iter()
        .zip(&plain.regions)
        .map(|(now, was)| now - was)
        .collect();
    let labels = mesh.vertex_label_bits();
    let level_of = |v: usize| {
        let on = labels[v] & LEVEL_BITS;
        (on.count_ones() == 1).then(|| on.trailing_zeros() as usize)
    };
    let n = residual.len() + 1;
    let mut count = vec![0usize; n];
    for v in 0..mesh.points.len() {
        if let Some(l) = level_of(v) {
            count[l] += 1;
        }
    }
    // The drift booked on each level (a level's counts for the region below it; the first
    // level's for the region above it).
    let mut booked = vec![0.0; n];
    if count[n - 1] > 0 || count[0] == 0 {
        for k in 0..n - 1 {
            booked[k + 1] = residual[k] + if k > 0 { booked[k] } else { 0.0 };
        }
    } else {
        for k in (1..n - 1).rev() {
            booked[k] = if k + 1 < n - 1 { booked[k + 1] } else { 0.0 } - residual[k];
        }
        booked[0] = residual[0] - booked.get(1).copied().unwrap_or(0.0);
    }
    for (v, d) in drift.iter_mut().enumerate() {
        *d = match level_of(v) {
            Some(l) if count[l] > 0 => booked[l] / count[l] as f64,
            _ => 0.0,
        };
    }
}

/// [`finish_stage`] in one region (`drift` and the [`split::sagging_points`] per point of the
/// mesh): returns its splits and its restoring moves.
fn finish_region(
    lm: &mut LocalMesh,
    ctx: &Ctx,
    opts: &QualityOptions,
    (drift, sagging): (&[f64], &[bool]),
) -> (usize, usize) {
    let (splits, added) = if opts.split_sag.is_finite() {
        split::split_sagging_edges(lm, ctx, opts.split_sag, Some(sagging))
    } else {
        (0, [0.0; MAX_LEVELS])
    };
    if !opts.restore_volume {
        return (splits, 0);
    }
    // Points added by splits (here, or in the first phase) carry no drift. Each volume group
    // gives back its own ([`restore::group_of`]; one for one interval).
    let mut drifted = [0.0; MAX_LEVELS];
    for v in (0..lm.u.len()).filter(|&v| lm.is_free(v as u32)) {
        if let Some(d) = drift.get(lm.global[v] as usize) {
            let group = lm.con[v].level.map_or(0, |l| restore::group_of(ctx, l));
            drifted[group] += d;
        }
    }
    let mut moves = 0;
    for (group, (&drifted, &added)) in drifted.iter().zip(&added).enumerate() {
        if group > 0 && drifted == 0.0 {
            continue;
        }
        // Volume the splits added pays back volume the region lost, and volume they took
        // pays back volume it gained; beyond that (or the other way) they are a correction
        // towards the level set, which is kept.
        let mut owed = if drifted * added >= 0.0 {
            drifted
        } else if drifted < 0.0 {
            (drifted + added).min(0.0)
        } else {
            (drifted + added).max(0.0)
        };
        moves += restore::restore_volume(lm, ctx, &mut owed, group);
    }
    (splits, moves)
}
