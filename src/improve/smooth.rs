//! Optimisation-based smoothing: moves one vertex to raise the worst quality of its star
//! (Freitag and Ollivier-Gooch's non-smooth max–min, as in Klingner and Shewchuk's Stellar).
//!
//! The search runs in index space over the axes the vertex's box planes leave free; a level
//! vertex moves in the tangent plane of its level set and is projected back onto it before
//! every evaluation. Moving a vertex with every tet of its star positive is a homeomorphism of
//! the mesh, so smoothing never changes the topology.

use super::constraint::Constraint;
use super::embed;
use super::region::{LocalMesh, StarCorners, StarVec};
use super::Ctx;
use crate::geom::{dot, norm, sub};

/// Gradient steps per call. One: a vertex still at a bad tet is smoothed again in the next
/// sweep, after its neighbours moved, and the steps are spent where the tets still need them
/// (one step instead of four made the local stage 19–24 % shorter on the full-size volumes,
/// with fewer tets left below 15° on the T1: docs/QUALITY-LOG.md).
const ITERATIONS: usize = 1;
/// Halvings of the step in the line search.
const HALVINGS: usize = 10;
/// Tets whose quality is within this fraction of the worst count as active.
const ACTIVE_BAND: f64 = 0.02;

/// Tries to raise the smallest quality around `v`. Returns whether `v` moved.
pub fn smooth_vertex(lm: &mut LocalMesh, ctx: &Ctx, v: u32) -> bool {
    move_vertex(lm, ctx, v, ITERATIONS).is_some()
}

/// Up to `iterations` max–min steps of `v` from where it is (which raise the worst tet of its
/// star, an inverted one first), if it may move. Returns its old position if it moved.
pub fn move_vertex(lm: &mut LocalMesh, ctx: &Ctx, v: u32, iterations: usize) -> Option<[f64; 3]> {
    climb_by(lm, ctx, v, iterations, true)
}

/// [`move_vertex`] for a vertex moved out of the way of a tangled tet: a vertex between two
/// regions moves without the regions' volume budgets ([`embed::move_keeps_volume`]), as
/// the last resorts that untangle need.
pub fn untangle_step(lm: &mut LocalMesh, ctx: &Ctx, v: u32, iterations: usize) -> Option<[f64; 3]> {
    climb_by(lm, ctx, v, iterations, false)
}

/// [`move_vertex`], with `budget` passed to [`embed::move_keeps_volume`].
fn climb_by(
    lm: &mut LocalMesh,
    ctx: &Ctx,
    v: u32,
    iterations: usize,
    budget: bool,
) -> Option<[f64; 3]> {
    move_by(lm, ctx, v, budget, |lm, star, qs| {
        let from = lm.u[v as usize];
        let (u, _) = climb(lm, ctx, v, star, from, qs, iterations)
            .or_else(|| centroid_step(lm, ctx, v, star, qs))?;
        Some(u)
    })
}

/// Moves `v`, if it may move, to where `search` finds a better place for it: `search` gets the
/// region, `v`'s star (the other corners stay where they are while `v` moves) and the star's
/// qualities, and returns the index point, with the qualities there left in them. A level
/// vertex's move adds the volume it sweeps to its drift. Returns `v`'s old position if it
/// moved.
pub(crate) fn move_by(
    lm: &mut LocalMesh,
    ctx: &Ctx,
    v: u32,
    budget: bool,
    search: impl FnOnce(&LocalMesh, &StarCorners, &mut StarVec<f64>) -> Option<[f64; 3]>,
) -> Option<[f64; 3]> {
    let c = lm.con[v as usize];
    if !lm.is_free(v) || c.pinned || c.freedom() == 0 {
        return None;
    }
    let star = StarCorners::of(lm, v);
    let mut qs: StarVec<f64> = lm.star[v as usize]
        .iter()
        .map(|&t| lm.q[t as usize])
        .collect();
    let from = lm.u[v as usize];
    let u = search(lm, &star, &mut qs)?;
    if !embed::move_keeps_volume(lm, ctx, v, u, budget)
        || !embed::move_keeps_boundary(lm, ctx, v, u)
    {
        return None;
    }
    if c.level.is_some() {
        let (x0, x1) = (lm.x[v as usize], ctx.field.to_physical(u));
        let (v0, v1) = match c.interface {
            true => StarCorners::counted(lm, v).volumes(x0, x1),
            false => star.volumes(x0, x1),
        };
        lm.drift[v as usize] += v1 - v0;
        lm.book_volume(lm.budget_region(v), v1 - v0);
    }
    lm.set_position_with(v, u, ctx, &qs);
    Some(from)
}

/// Where the max–min steps find no way up (a kink of the worst qualities whose gradients
/// oppose each other), the centroid of `v`'s neighbours (on the axes it may move along, put
/// on its level set) may still lie higher: `v` goes there if that raises its star's worst
/// quality, with the qualities there left in `qs`.
fn centroid_step(
    lm: &LocalMesh,
    ctx: &Ctx,
    v: u32,
    star: &StarCorners,
    qs: &mut StarVec<f64>,
) -> Option<([f64; 3], f64)> {
    if !ctx.round.centroid {
        return None;
    }
    let c = lm.con[v as usize];
    let free = c.free_axes();
    let u = lm.u[v as usize];
    let (mut sum, mut n) = ([0.0; 3], 0.0);
    for w in star_others(lm, v) {
        for a in 0..3 {
            sum[a] += lm.u[w as usize][a];
        }
        n += 1.0;
    }
    if n == 0.0 {
        return None;
    }
    let mut p = u;
    for a in 0..3 {
        if free & (1 << a) != 0 {
            p[a] = sum[a] / n;
        }
    }
    let p = place(ctx, c, p)?;
    let floor = rise_over(worst_of(qs));
    let mut next = StarVec::new();
    let mut hint = 0;
    if !star.qualities_above(ctx.field.to_physical(p), ctx, floor, &mut next, &mut hint) {
        return None;
    }
    *qs = next;
    Some((p, worst_of(qs)))
}

/// Where a vertex with constraint `c` tried at index point `p` goes: a level vertex onto
/// its level set (along the axes it may move), an interior one stays at `p` if that is inside
/// its region's interval; `None` if neither works.
pub(crate) fn place(ctx: &Ctx, c: Constraint, p: [f64; 3]) -> Option<[f64; 3]> {
    match c.level {
        Some(l) => ctx
            .field
            .project(p, ctx.levels[l as usize], c.free_axes(), ctx.tol),
        None => Some(p).filter(|&p| ctx.inside_region(p, c.region)),
    }
}

/// Index point `u` moved by `step` along `d`, kept inside the grid.
pub(crate) fn stepped(ctx: &Ctx, u: [f64; 3], d: [f64; 3], step: f64) -> [f64; 3] {
    let dims = ctx.field.grid().dims;
    let mut p = [0.0; 3];
    for a in 0..3 {
        p[a] = (u[a] + step * d[a]).clamp(0.0, (dims[a] - 1) as f64);
    }
    p
}

/// The smallest of the qualities `qs`.
pub(crate) fn worst_of(qs: &[f64]) -> f64 {
    qs.iter().copied().fold(f64::INFINITY, f64::min)
}

/// The worst quality a move must beat to count as raising `q0` (above rounding).
pub(crate) fn rise_over(q0: f64) -> f64 {
    q0 * (1.0 + 1e-9) + 1e-12
}

/// Up to `iterations` max–min steps of `v` (whose star is `star`) from index point `u`, where
/// the star's qualities are `qs` (star order; `v`'s own position in `lm` is not read). Returns
/// where it ended and its worst quality if it moved, with the qualities there left in `qs`.
/// The start may invert tets: then the steps untangle.
pub fn climb(
    lm: &LocalMesh,
    ctx: &Ctx,
    v: u32,
    star: &StarCorners,
    mut u: [f64; 3],
    qs: &mut StarVec<f64>,
    iterations: usize,
) -> Option<([f64; 3], f64)> {
    let mut q0 = worst_of(qs);
    let mut moved = false;
    let mut next = StarVec::new();
    for _ in 0..iterations {
        let scale = local_scale(lm, v, u);
        let dirs = ascent_directions(lm, ctx, v, star, (u, qs, q0), scale);
        let found = dirs
            .into_iter()
            .flatten()
            .find_map(|d| line_search(lm, ctx, v, star, (u, d, q0, scale), &mut next));
        match found {
            Some((p, q)) => {
                (u, q0, moved) = (p, q, true);
                std::mem::swap(qs, &mut next);
            }
            None => break,
        }
    }
    moved.then_some((u, q0))
}

/// Directions (index space, over the free axes, tangent to the level set) along which the
/// worst tets of the star improve, to be tried in order. By default one: the normalised sum
/// of their normalised gradients. With [`Ctx::steepest`], first the steepest ascent of the
/// worst quality, the point of smallest norm in the convex hull of their gradients (Freitag
/// and Ollivier-Gooch; along it every one of them improves at first), then the normalised
/// sum where it points elsewhere.
/// `star` is the star of `v`, with `v` at `u` and qualities `qs` (worst `q0`); `scale` is
/// [`local_scale`] there.
fn ascent_directions(
    lm: &LocalMesh,
    ctx: &Ctx,
    v: u32,
    star: &StarCorners,
    (u, qs, q0): ([f64; 3], &[f64], f64),
    scale: f64,
) -> [Option<[f64; 3]>; 2] {
    let free = lm.con[v as usize].free_axes();
    let h = 1e-7 * scale.max(1e-12);
    let level = lm.con[v as usize].level.is_some();
    // Kept only for the steepest ascent.
    let mut grads: StarVec<[f64; 3]> = StarVec::new();
    let mut sum = [0.0; 3];
    for (i, &q) in qs.iter().enumerate() {
        if q > q0 + ACTIVE_BAND * q0.abs().max(1e-3) {
            continue;
        }
        let mut g = [0.0; 3];
        for a in 0..3 {
            if free & (1 << a) != 0 {
                let mut p = u;
                p[a] += h;
                g[a] = (star.quality(i, ctx.field.to_physical(p), ctx) - q) / h;
            }
        }
        let n = norm(g);
        if n > 0.0 {
            for a in 0..3 {
                sum[a] += g[a] / n;
            }
        }
        if ctx.round.steepest {
            grads.push(g);
        }
    }
    if level {
        sum = ctx.field.tangent(u, free, sum);
    }
    let n = norm(sum);
    let mean = (n > 0.0 && n.is_finite()).then(|| sum.map(|x| x / n));
    if !ctx.round.steepest {
        return [mean, None];
    }
    if level {
        let normal = ctx.field.value_gradient_on(u, free).1;
        grads.iter_mut().for_each(|g| *g = tangential(*g, normal));
    }
    grads.retain(|g| g.iter().all(|x| x.is_finite()));
    let steepest = min_norm_in_hull(&grads).and_then(|d| {
        let n = norm(d);
        (n > 1e-12 && n.is_finite()).then(|| d.map(|x| x / n))
    });
    [
        steepest,
        mean.filter(|m| steepest.is_none_or(|s| dot(*m, s) < 0.999)),
    ]
}

/// `g` without its component along `n`.
fn tangential(g: [f64; 3], n: [f64; 3]) -> [f64; 3] {
    let n2 = dot(n, n);
    if n2 == 0.0 {
        return g;
    }
    let s = dot(g, n) / n2;
    [g[0] - s * n[0], g[1] - s * n[1], g[2] - s * n[2]]
}

/// Iterations of [`min_norm_in_hull`].
const HULL_ITERATIONS: usize = 64;

/// The point of (nearly) smallest norm in the convex hull of `points` (Gilbert's algorithm:
/// step from the current point towards the vertex least along it, exactly as far as
/// shortens it most). `None` if `points` is empty.
fn min_norm_in_hull(points: &[[f64; 3]]) -> Option<[f64; 3]> {
    let mut p = *points
        .iter()
        .min_by(|a, b| dot(**a, **a).total_cmp(&dot(**b, **b)))?;
    for _ in 0..HULL_ITERATIONS {
        let pp = dot(p, p);
        let (s, ps) = points
            .iter()
            .map(|&g| (g, dot(g, p)))
            .min_by(|a, b| a.1.total_cmp(&b.1))?;
        // `p` is the nearest point when no vertex lies below the plane through it.
        if pp - ps <= 1e-12 * pp {
            break;
        }
        let e = sub(s, p);
        let t = ((pp - ps) / dot(e, e)).clamp(0.0, 1.0);
        p = [p[0] + t * e[0], p[1] + t * e[1], p[2] + t * e[2]];
    }
    Some(p)
}

/// Backtracking search along `d` from `u`: the first step (longest first)
/// that raises the star's worst quality above `q0`, with that quality; the star's qualities
/// there are left in `qs`. The first step is a quarter of `scale` ([`local_scale`]).
fn line_search(
    lm: &LocalMesh,
    ctx: &Ctx,
    v: u32,
    star: &StarCorners,
    (u, d, q0, scale): ([f64; 3], [f64; 3], f64, f64),
    qs: &mut StarVec<f64>,
) -> Option<([f64; 3], f64)> {
    let c = lm.con[v as usize];
    let mut step = 0.25 * scale;
    let mut hint = 0;
    for _ in 0..HALVINGS {
        if let Some(p) = place(ctx, c, stepped(ctx, u, d, step)) {
            if star.qualities_above(ctx.field.to_physical(p), ctx, rise_over(q0), qs, &mut hint) {
                return Some((p, worst_of(qs)));
            }
        }
        step *= 0.5;
    }
    None
}

/// Mean index-space length of the edges at `v`, placed at `u` (each counted once per tet).
pub(crate) fn local_scale(lm: &LocalMesh, v: u32, u: [f64; 3]) -> f64 {
    let (mut sum, mut n) = (0.0, 0usize);
    for w in star_others(lm, v) {
        sum += norm(sub(lm.u[w as usize], u));
        n += 1;
    }
    if n == 0 {
        0.0
    } else {
        sum / n as f64
    }
}

/// The corners other than `v` of the tets around `v` (each once per tet).
fn star_others(lm: &LocalMesh, v: u32) -> impl Iterator<Item = u32> + '_ {
    lm.star[v as usize]
        .iter()
        .flat_map(move |&t| lm.tets[t as usize])
        .filter(move |&w| w != v)
}
