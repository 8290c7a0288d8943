//! Moving boundary vertices onto the trilinear level set they belong to.
//!
//! The clipper places cuts on the piecewise-linear level set; only cuts on grid edges are on
//! the trilinear one. Each free level vertex is moved by Newton steps along the gradient
//! (restricted to the axes its box planes leave free) until `|f - level| <= tol`; the move is
//! kept only if every tet around the vertex stays positive. Inside a region, where that move
//! would invert a tet, the vertex tries other points of its level set (projections started
//! halfway to its neighbours on the level) and, if each of them inverts a tet too, max–min
//! steps on the level set from the least bad one until its star is positive again.

use rayon::prelude::*;

use super::constraint::Constraint;
use super::local::{LocalMesh, StarCorners};
use super::smooth::climb;
use super::Ctx;
use crate::mesh::TetMesh;

/// Rounds of reverting the moves that invert a tet, at most (then every move is reverted).
const REVERT_ROUNDS: usize = 8;

/// Projects every level vertex of `mesh` at once (in parallel, independent of the thread
/// count): all moves are computed from the old positions, then the moves of vertices of tets
/// that would not stay positive are reverted until no tet is inverted. Returns, per point,
/// whether it moved.
pub fn project_mesh(mesh: &mut TetMesh, ctx: &Ctx) -> Vec<bool> {
    let labels = mesh.vertex_label_bits();
    let dims = ctx.field.grid().dims;
    // Per point: where a level vertex off its level would go.
    let target: Vec<Option<[f64; 3]>> = (0..mesh.points.len())
        .into_par_iter()
        .map(|v| {
            if labels[v] & 3 == 0 {
                return None; // on no level
            }
            let mut u = ctx.field.to_index(mesh.points[v]);
            let c = Constraint::classify(labels[v], &mut u, dims);
            let level = ctx.levels[c.level? as usize];
            if c.pinned || (ctx.field.value(u) - level).abs() <= ctx.tol {
                return None;
            }
            let p = ctx.field.project(u, level, c.free_axes(), ctx.tol)?;
            Some(ctx.field.to_physical(p))
        })
        .collect();
    let mut moved: Vec<bool> = target.iter().map(Option::is_some).collect();
    // Only tets with a moved corner can invert; after a revert, only those around the
    // reverted vertices changed (an inverted tet has all its moved corners reverted).
    let around_moved: Vec<u32> = (0..mesh.tets.len() as u32)
        .into_par_iter()
        .filter(|&t| mesh.tets[t as usize].iter().any(|&v| moved[v as usize]))
        .collect();
    let mut check = around_moved.clone();
    for round in 0..=REVERT_ROUNDS {
        let bad = inverted_moves(mesh, &target, &moved, &check, ctx);
        if bad.is_empty() {
            break;
        }
        for &v in &bad {
            moved[v as usize] = false;
        }
        if round == REVERT_ROUNDS {
            moved.iter_mut().for_each(|m| *m = false);
        }
        let mut reverted = vec![false; mesh.points.len()];
        for &v in &bad {
            reverted[v as usize] = true;
        }
        check = around_moved
            .par_iter()
            .copied()
            .filter(|&t| mesh.tets[t as usize].iter().any(|&v| reverted[v as usize]))
            .collect();
    }
    for (v, t) in target.iter().enumerate() {
        if moved[v] {
            mesh.points[v] = t.expect("moved vertices have a target");
        }
    }
    moved
}

/// Per point: is it on an `alpha` (`beta`) face but farther than the tolerance from that
/// level set (pinned vertices included)?
pub fn off_level_points(mesh: &TetMesh, ctx: &Ctx) -> Vec<bool> {
    let labels = mesh.vertex_label_bits();
    (0..mesh.points.len())
        .into_par_iter()
        .map(|v| {
            if labels[v] & 3 == 0 {
                return false;
            }
            let f = ctx.field.value(ctx.field.to_index(mesh.points[v]));
            let on = |l: usize| (f - ctx.levels[l]).abs() <= ctx.tol;
            (labels[v] & 1 != 0 && !on(0)) || (labels[v] & 2 != 0 && !on(1))
        })
        .collect()
}

/// The moved vertices of the tets among `check` that the moves would leave non-positive,
/// sorted.
fn inverted_moves(
    mesh: &TetMesh,
    target: &[Option<[f64; 3]>],
    moved: &[bool],
    check: &[u32],
    ctx: &Ctx,
) -> Vec<u32> {
    let mut bad: Vec<u32> = check
        .par_iter()
        .map(|&t| mesh.tets[t as usize])
        .filter(|t| t.iter().any(|&v| moved[v as usize]))
        .filter(|t| {
            let p = t.map(|v| match (moved[v as usize], target[v as usize]) {
                (true, Some(x)) => x,
                _ => mesh.points[v as usize],
            });
            ctx.quality(p) <= 0.0
        })
        .flat_map_iter(|t| t.into_iter().filter(|&v| moved[v as usize]))
        .collect();
    bad.par_sort_unstable();
    bad.dedup();
    bad
}

/// Projects every free level vertex of the region that is not yet within the tolerance of
/// its level, where every tet around it stays positive. Returns how many moved.
pub fn project_levels(lm: &mut LocalMesh, ctx: &Ctx) -> usize {
    (0..lm.u.len() as u32)
        .filter(|&v| project_vertex(lm, ctx, v))
        .count()
}

/// Projects `v` onto its level if it is a free level vertex off its level and the move keeps
/// its star positive. Returns whether it moved.
fn project_vertex(lm: &mut LocalMesh, ctx: &Ctx, v: u32) -> bool {
    let c = lm.con[v as usize];
    let Some(level) = c.level else {
        return false;
    };
    if !lm.is_free(v) || c.pinned {
        return false;
    }
    let target = ctx.levels[level as usize];
    let u = lm.u[v as usize];
    if (ctx.field.value(u) - target).abs() <= ctx.tol {
        return false;
    }
    let free = c.free_axes();
    let direct = ctx.field.project(u, target, free, ctx.tol);
    if let Some(p) = direct.filter(|&p| lm.star_above_at(v, p, ctx, 0.0)) {
        lm.set_position(v, p, ctx);
        return true;
    }
    match detour(lm, ctx, v, target, free, direct) {
        Some(p) => {
            lm.set_position(v, p, ctx);
            true
        }
        None => false,
    }
}

/// A point of the level set near `v` where its star stays positive, when the projection
/// along the gradient (`direct`, if it converged) would invert a tet: the best of several
/// projections ([`best_on_level`]), else max–min steps on the level from it that untangle the
/// star.
fn detour(
    lm: &LocalMesh,
    ctx: &Ctx,
    v: u32,
    level: f64,
    free: u8,
    direct: Option<[f64; 3]>,
) -> Option<[f64; 3]> {
    let star = StarCorners::of(lm, v);
    let mut best = best_on_level(lm, ctx, v, &star, (level, free), direct)?;
    if best.1 <= 0.0 {
        let mut qs = star.qualities(ctx.field.to_physical(best.0), ctx);
        best = climb(lm, ctx, v, &star, best.0, &mut qs, UNTANGLE_STEPS)?;
    }
    (best.1 > 0.0).then_some(best.0)
}

/// Max–min steps tried to untangle a level vertex whose projections all invert a tet.
const UNTANGLE_STEPS: usize = 8;

/// Where the projection along the gradient would invert a tet around `v`: the projections
/// started halfway to each neighbour on the same level set and at their centroid (keeping
/// `v`'s box coordinates), and `direct`, the one from `v` itself. Returns the best of them
/// with the worst quality of the star there (negative when every one inverts a tet).
fn best_on_level(
    lm: &LocalMesh,
    ctx: &Ctx,
    v: u32,
    star: &StarCorners,
    (level, free): (f64, u8),
    direct: Option<[f64; 3]>,
) -> Option<([f64; 3], f64)> {
    let u = lm.u[v as usize];
    let mut on: Vec<u32> = lm.star[v as usize]
        .iter()
        .flat_map(|&t| lm.tets[t as usize])
        .filter(|&w| w != v && (ctx.field.value(lm.u[w as usize]) - level).abs() <= ctx.tol)
        .collect();
    on.sort_unstable();
    on.dedup();
    let mut starts: Vec<[f64; 3]> = on.iter().map(|&w| mid(u, lm.u[w as usize])).collect();
    if !on.is_empty() {
        let n = on.len() as f64;
        starts.push(on.iter().fold([0.0; 3], |a, &w| {
            let x = lm.u[w as usize];
            [a[0] + x[0] / n, a[1] + x[1] / n, a[2] + x[2] / n]
        }));
    }
    starts
        .into_iter()
        .filter_map(|s| {
            ctx.field
                .project(keep_fixed(s, u, free), level, free, ctx.tol)
        })
        .chain(direct)
        .map(|p| {
            let q = star.qualities(ctx.field.to_physical(p), ctx);
            (p, q.into_iter().fold(f64::INFINITY, f64::min))
        })
        .max_by(|a, b| a.1.total_cmp(&b.1))
}

fn mid(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        (a[0] + b[0]) / 2.0,
        (a[1] + b[1]) / 2.0,
        (a[2] + b[2]) / 2.0,
    ]
}

/// `s` with the coordinates of the axes not in `free` taken from `u`.
fn keep_fixed(s: [f64; 3], u: [f64; 3], free: u8) -> [f64; 3] {
    std::array::from_fn(|a| if free & (1 << a) != 0 { s[a] } else { u[a] })
}
