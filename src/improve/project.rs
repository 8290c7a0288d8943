//! Moving boundary vertices onto the trilinear level set they belong to.
//!
//! The clipper places cuts on the piecewise-linear level set; only cuts on grid edges are on
//! the trilinear one. Each free level vertex is moved by Newton steps along the gradient
//! (restricted to the axes its box planes leave free) until `|f - level| <= tol`; the move is
//! kept only if every tet around the vertex stays positive.

use rayon::prelude::*;

use super::constraint::Constraint;
use super::local::LocalMesh;
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
    match ctx.field.project(u, target, c.free_axes(), ctx.tol) {
        Some(p) if lm.star_above_at(v, p, ctx, 0.0) => {
            lm.set_position(v, p, ctx);
            true
        }
        _ => false,
    }
}
