//! Volume restoration, the last stage of the pass: moves level vertices along their level
//! set to give back the volume that the collapses and moves of the pass added or took around
//! them ([`LocalMesh::drift`], summed over a region), without letting any tet fall below the
//! target quality, or below where it is if it is below already. So it changes no element
//! that the pass left below the target for the worse, and makes none of the others bad.
//!
//! Collapses and max–min moves on a curved boundary change the volume one way on average:
//! the boundary nodes lie on the level set, so a convex part's surface is inscribed in it and
//! shrinks when its nodes thin out or bunch. The volume of a vertex's star is affine in the
//! vertex's position, so its gradient is exact: each step follows the part of that gradient
//! tangent to the level set, sized to cancel the drift (at most a fifth of the vertex's mean
//! edge), and is projected back onto the level set.
//!
//! Only the drift of the points that carry most of the net sum is owed
//! ([`largest_drift`]): the rest cancels.

use rayon::prelude::*;

use super::embed;
use super::region::{LocalMesh, StarCorners, StarVec};
use super::smooth::local_scale;
use super::Ctx;
use crate::geom::dot;
use crate::levels::MAX_LEVELS;

/// Passes over the region's vertices at most (each stops once the drift is given back).
const PASSES: usize = 5;
/// Longest step, as a fraction of the mean edge length at the vertex.
const MAX_STEP: f64 = 0.2;
/// Halvings of a step.
const HALVINGS: usize = 5;
/// Drift left, relative to the region's volume, that is not worth a move.
const SETTLED: f64 = 1e-7;

/// The drift the last stage gives back: that of the points whose drift has the sign of the
/// sum and is largest (ties by index), as few as cover the sum (the last one only what is
/// left, so that the owed drift sums to the drift); zero elsewhere. A pass
/// leaves drift on nearly every level point, of both signs and mostly cancelling: on the T1
/// at `[51.5, 101.5]` 603 k points carry −0.95 % of the volume in all, and the 2 543 largest
/// of that sign cover it (the noisy 256³ field: 840 k points, +0.23 %, and 1 424). Giving
/// back only theirs keeps the last stage's work proportional to where the volume went,
/// instead of copying out the whole boundary.
pub fn largest_drift(drift: &[f64]) -> Vec<f64> {
    let total: f64 = drift.iter().sum();
    let sign = total.signum();
    let mut order: Vec<u32> = (0..drift.len() as u32)
        .filter(|&v| drift[v as usize] * sign > 0.0)
        .collect();
    order.par_sort_unstable_by(|&a, &b| {
        let (da, db) = (drift[a as usize].abs(), drift[b as usize].abs());
        db.total_cmp(&da).then(a.cmp(&b))
    });
    let mut owed = vec![0.0; drift.len()];
    let mut left = total;
    for v in order {
        if left * sign <= 0.0 {
            break;
        }
        // The last one gives back only what is left.
        owed[v as usize] = sign * (drift[v as usize] * sign).min(left * sign);
        left -= owed[v as usize];
    }
    owed
}

/// The volume group of level `level` ([`largest_drift_by_group`]): 0 for every level of one
/// interval (the domain's volume), the level itself with several regions (the volume its
/// drift counts: the region below an interface, the region on a first or last level).
#[inline]
pub fn group_of(ctx: &Ctx, level: u8) -> usize {
    match ctx.levels.len() {
        0..=2 => 0,
        _ => level as usize,
    }
}

/// Volumes per group ([`group_of`]).
pub type GroupVolumes = [f64; MAX_LEVELS];

/// [`largest_drift`] of each group of points apart (`group`, per point: its
/// [`group_of`], `None` for a point on no level): with several regions each level gives back
/// its own drift, which is what keeps every region's volume.
pub fn largest_drift_by_group(drift: &[f64], group: impl Fn(usize) -> Option<usize>) -> Vec<f64> {
    let groups: Vec<Option<usize>> = (0..drift.len()).map(&group).collect();
    let used = groups.iter().flatten().fold(0u32, |b, &g| b | 1 << g);
    if used.count_ones() <= 1 {
        return largest_drift(drift);
    }
    let mut owed = vec![0.0; drift.len()];
    for g in (0..MAX_LEVELS).filter(|&g| used & (1 << g) != 0) {
        let part: Vec<f64> = drift
            .iter()
            .zip(&groups)
            .map(|(&d, &h)| if h == Some(g) { d } else { 0.0 })
            .collect();
        for (o, p) in owed.iter_mut().zip(largest_drift(&part)) {
            *o += p;
        }
    }
    owed
}

/// Gives back `owed`, the volume the operations added in the region to volume group `group`
/// ([`group_of`]), where the group's level vertices can move; `owed` is left with what could
/// not be given back. Returns the moves.
pub fn restore_volume(lm: &mut LocalMesh, ctx: &Ctx, owed: &mut f64, group: usize) -> usize {
    let mut moves = 0;
    for _ in 0..PASSES {
        let before = moves;
        for v in 0..lm.u.len() as u32 {
            let late = v % 64 == 63 && ctx.out_of_time();
            if owed.abs() <= SETTLED * lm.volume.abs() || late {
                return moves;
            }
            let in_group = lm.con[v as usize]
                .level
                .is_some_and(|l| group_of(ctx, l) == group);
            moves += usize::from(in_group && restore_at(lm, ctx, v, owed));
        }
        if moves == before {
            break;
        }
    }
    moves
}

/// One step of `v` that brings the drift closer to zero, if `v` is a free level vertex on
/// its level and such a step keeps its star above the floors.
fn restore_at(lm: &mut LocalMesh, ctx: &Ctx, v: u32, owed: &mut f64) -> bool {
    let c = lm.con[v as usize];
    let Some(level) = c.level else {
        return false;
    };
    if !lm.is_free(v) || c.pinned || c.freedom() == 0 || lm.off_its_level(v, ctx) {
        return false;
    }
    let star = StarCorners::of(lm, v);
    // The volume the drift counts: on an interface, the region below's.
    let counted = c.interface.then(|| StarCorners::counted(lm, v));
    let volume_star = counted.as_ref().unwrap_or(&star);
    let u = lm.u[v as usize];
    let free = c.free_axes();
    let v0 = volume_star.volume(lm.x[v as usize]);
    let Some(g) = tangent_volume_gradient(ctx, volume_star, u, free, v0) else {
        return false;
    };
    let g2 = dot(g, g);
    let floors: StarVec<f64> = lm.star[v as usize]
        .iter()
        .map(|&t| lm.q[t as usize].min(ctx.target))
        .collect();
    let floor = floors.iter().copied().fold(f64::INFINITY, f64::min);
    // The step that would cancel the drift to first order, at most MAX_STEP of an edge.
    let mut t = -*owed / g2;
    let longest = MAX_STEP * local_scale(lm, v, u);
    if t.abs() * g2.sqrt() > longest {
        t = longest / g2.sqrt() * t.signum();
    }
    let dims = ctx.field.grid().dims;
    let (mut qs, mut hint) = (StarVec::new(), 0);
    for _ in 0..HALVINGS {
        let p = [0, 1, 2].map(|a| (u[a] + t * g[a]).clamp(0.0, (dims[a] - 1) as f64));
        if let Some(p) = ctx
            .field
            .project(p, ctx.levels[level as usize], free, ctx.tol)
        {
            let x = ctx.field.to_physical(p);
            let dv = volume_star.volume(x) - v0;
            if (*owed + dv).abs() < owed.abs()
                && star.qualities_above(x, ctx, floor * (1.0 - 1e-12), &mut qs, &mut hint)
                && qs.iter().zip(&floors).all(|(q, f)| q >= f)
                && embed::level_move_keeps_level(lm, ctx, v, p)
            {
                *owed += dv;
                lm.set_position_with(v, p, ctx, &qs);
                return true;
            }
        }
        t *= 0.5;
    }
    false
}

/// The index-space gradient of the star's volume at `u` (where it is `v0`), over the `free`
/// axes and tangent to the level set there; `None` where it vanishes.
fn tangent_volume_gradient(
    ctx: &Ctx,
    star: &StarCorners,
    u: [f64; 3],
    free: u8,
    v0: f64,
) -> Option<[f64; 3]> {
    // The volume is affine in the position: a difference quotient is its gradient.
    const H: f64 = 1e-3;
    let mut g = [0.0; 3];
    for a in 0..3 {
        if free & (1 << a) != 0 {
            let mut p = u;
            p[a] += H;
            g[a] = (star.volume(ctx.field.to_physical(p)) - v0) / H;
        }
    }
    let g = ctx.field.tangent(u, free, g);
    let g2 = dot(g, g);
    (g2 > 0.0 && g2.is_finite()).then_some(g)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::improve::fixtures::{wavy_torus, wavy_torus_regions};
    use crate::improve::project::project_levels;

    #[test]
    fn the_largest_drift_of_the_sign_of_the_sum_covers_it() {
        let close = |a: &[f64], b: &[f64]| {
            a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-12)
        };
        // Net +0.35: the largest positive drifts (equal ones by index), the last one only
        // what is left.
        let owed = largest_drift(&[0.3, -0.2, 0.1, 0.3, -0.4, 0.05, 0.2, 0.0]);
        assert!(
            close(&owed, &[0.3, 0.0, 0.0, 0.05, 0.0, 0.0, 0.0, 0.0]),
            "{owed:?}"
        );
        // Net −0.5: the two largest negative ones.
        let owed = largest_drift(&[0.1, -0.3, 0.2, -0.35, -0.15]);
        assert!(close(&owed, &[0.0, -0.15, 0.0, -0.35, 0.0]), "{owed:?}");
        // Nothing owed where the drift cancels.
        assert!(largest_drift(&[0.25, -0.25, 0.0]).iter().all(|&x| x == 0.0));
    }

    fn region_volume(lm: &LocalMesh) -> f64 {
        (0..lm.tets.len() as u32)
            .filter(|&t| lm.alive[t as usize])
            .map(|t| lm.volume_of(t))
            .sum()
    }

    #[test]
    fn restoring_gives_the_volume_back_and_keeps_every_tet_above_its_floor() {
        let grid = wavy_torus();
        let (ctx, mut regions) = wavy_torus_regions(&grid, &[0, 1]);
        let (mut owed_before, mut owed_after, mut moves) = (0.0, 0.0, 0);
        for (i, lm) in regions.iter_mut().enumerate() {
            project_levels(lm, &ctx);
            let on_level: Vec<bool> = (0..lm.u.len() as u32)
                .map(|v| lm.con[v as usize].level.is_some() && !lm.off_its_level(v, &ctx))
                .collect();
            let floors: Vec<f64> = lm.q.iter().map(|&q| q.min(ctx.target)).collect();
            let before = region_volume(lm);
            // As if the operations had taken (even regions) or added (odd ones) 0.2 %.
            let sign = if i % 2 == 0 { -1.0 } else { 1.0 };
            let mut owed = sign * 2e-3 * lm.volume;
            owed_before += owed.abs();
            let start = owed;
            moves += restore_volume(lm, &ctx, &mut owed, 0);
            owed_after += owed.abs();
            // What is left owed is exactly what the moves did not give back.
            let gained = region_volume(lm) - before;
            assert!(
                (start + gained - owed).abs() <= 1e-9 * lm.volume,
                "region {i}: owed {start} -> {owed}, volume changed by {gained}"
            );
            for t in (0..lm.tets.len()).filter(|&t| lm.alive[t]) {
                let q = ctx.quality(lm.corners(lm.tets[t]));
                assert!(
                    q >= floors[t] * (1.0 - 1e-9),
                    "region {i} tet {t}: {q} < {}",
                    floors[t]
                );
            }
            for v in (0..lm.u.len() as u32).filter(|&v| on_level[v as usize]) {
                assert!(
                    !lm.off_its_level(v, &ctx),
                    "region {i}: vertex {v} left its level"
                );
            }
        }
        assert!(moves > 50, "{moves} moves");
        assert!(
            owed_after < 0.1 * owed_before,
            "owed {owed_before} -> {owed_after} after {moves} moves"
        );
    }
}
