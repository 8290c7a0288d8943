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
/// that would not stay positive are reverted until no tet is inverted. Returns the number of
/// moved vertices and of level vertices left off their level.
pub fn project_mesh(mesh: &mut TetMesh, ctx: &Ctx) -> (usize, usize) {
    let labels = vertex_labels(mesh);
    let dims = ctx.field.grid().dims;
    // Per point: is it a level vertex off its level, and where it would go.
    let (off_level, target): (Vec<bool>, Vec<Option<[f64; 3]>>) = (0..mesh.points.len())
        .into_par_iter()
        .map(|v| {
            let bits = labels[v];
            if bits & 3 == 0 {
                return (false, None);
            }
            let mut u = ctx.field.to_index(mesh.points[v]);
            let c = Constraint::classify(bits, &mut u, dims);
            let Some(level) = c.level.map(|l| ctx.levels[l as usize]) else {
                return (false, None);
            };
            if (ctx.field.value(u) - level).abs() <= ctx.tol {
                return (false, None);
            }
            if c.pinned {
                return (true, None);
            }
            let p = ctx.field.project(u, level, c.free_axes(), ctx.tol);
            (true, p.map(|p| ctx.field.to_physical(p)))
        })
        .unzip();
    let mut moved: Vec<bool> = target.iter().map(Option::is_some).collect();
    for round in 0..=REVERT_ROUNDS {
        let bad = inverted_moves(mesh, &target, &moved, ctx);
        if bad.is_empty() {
            break;
        }
        for v in bad {
            moved[v as usize] = false;
        }
        if round == REVERT_ROUNDS {
            moved.iter_mut().for_each(|m| *m = false);
        }
    }
    let count = moved.iter().filter(|&&m| m).count();
    for (v, t) in target.iter().enumerate() {
        if moved[v] {
            mesh.points[v] = t.expect("moved vertices have a target");
        }
    }
    let off = off_level
        .iter()
        .zip(&moved)
        .filter(|(&o, &m)| o && !m)
        .count();
    (count, off)
}

/// Level vertices of `mesh` farther than the tolerance from their level (pinned ones, on both
/// levels or on a level and a box edge, included).
pub fn count_off_level(mesh: &TetMesh, ctx: &Ctx) -> usize {
    let labels = vertex_labels(mesh);
    (0..mesh.points.len())
        .into_par_iter()
        .filter(|&v| {
            let u = ctx.field.to_index(mesh.points[v]);
            let f = ctx.field.value(u);
            let on = |l: usize| (f - ctx.levels[l]).abs() <= ctx.tol;
            (labels[v] & 1 != 0 && !on(0)) || (labels[v] & 2 != 0 && !on(1))
        })
        .count()
}

/// Per point: bits `1 << label` of the boundary triangles around it.
fn vertex_labels(mesh: &TetMesh) -> Vec<u8> {
    let mut bits = vec![0u8; mesh.points.len()];
    for (tri, &label) in mesh.boundary.iter().zip(&mesh.boundary_labels) {
        for &v in tri {
            bits[v as usize] |= 1 << (label as u8);
        }
    }
    bits
}

/// The moved vertices of the tets that the moves would leave non-positive, sorted.
fn inverted_moves(
    mesh: &TetMesh,
    target: &[Option<[f64; 3]>],
    moved: &[bool],
    ctx: &Ctx,
) -> Vec<u32> {
    let mut bad: Vec<u32> = mesh
        .tets
        .par_iter()
        .filter(|t| t.iter().any(|&v| moved[v as usize]))
        .filter(|t| {
            let p = t.map(|v| match (moved[v as usize], target[v as usize]) {
                (true, Some(x)) => x,
                _ => mesh.points[v as usize],
            });
            ctx.quality(p) <= 0.0
        })
        .flat_map_iter(|t| t.iter().copied().filter(|&v| moved[v as usize]))
        .collect();
    bad.par_sort_unstable();
    bad.dedup();
    bad
}

/// Projects every free level vertex that is not yet within the tolerance of its level.
/// Returns (moved, still off the level).
pub fn project_levels(lm: &mut LocalMesh, ctx: &Ctx) -> (usize, usize) {
    let (mut moved, mut failed) = (0, 0);
    for v in 0..lm.u.len() as u32 {
        match project_vertex(lm, ctx, v) {
            Some(true) => moved += 1,
            Some(false) => failed += 1,
            None => {}
        }
    }
    (moved, failed)
}

/// Projects `v` onto its level if it is a free level vertex off its level. `None` when there
/// is nothing to do, `Some(moved)` otherwise.
pub fn project_vertex(lm: &mut LocalMesh, ctx: &Ctx, v: u32) -> Option<bool> {
    let c = lm.con[v as usize];
    let level = c.level?;
    if !lm.is_free(v) || c.pinned {
        return None;
    }
    let target = ctx.levels[level as usize];
    let u = lm.u[v as usize];
    if (ctx.field.value(u) - target).abs() <= ctx.tol {
        return None;
    }
    let Some(p) = ctx.field.project(u, target, c.free_axes(), ctx.tol) else {
        return Some(false);
    };
    Some(lm.try_move(v, p, ctx, f64::MIN_POSITIVE))
}

impl LocalMesh {
    /// Smallest quality over the star of `v` if `v` stood at index point `u`.
    pub fn star_quality_at(&self, v: u32, u: [f64; 3], ctx: &Ctx) -> f64 {
        let x = ctx.field.to_physical(u);
        let mut q = f64::INFINITY;
        for &t in &self.star[v as usize] {
            let mut p = self.corners(self.tets[t as usize]);
            for (i, &w) in self.tets[t as usize].iter().enumerate() {
                if w == v {
                    p[i] = x;
                }
            }
            q = q.min(ctx.quality(p));
        }
        q
    }

    /// Whether every tet of the star of `v` would have quality above `floor` with `v` at
    /// index point `u` (stops at the first that does not).
    pub fn star_above_at(&self, v: u32, u: [f64; 3], ctx: &Ctx, floor: f64) -> bool {
        let x = ctx.field.to_physical(u);
        self.star[v as usize].iter().all(|&t| {
            let mut p = self.corners(self.tets[t as usize]);
            for (i, &w) in self.tets[t as usize].iter().enumerate() {
                if w == v {
                    p[i] = x;
                }
            }
            ctx.quality(p) > floor
        })
    }

    /// Moves `v` to index point `u` if the smallest quality of its star is then at least
    /// `floor`. Returns whether it moved.
    pub fn try_move(&mut self, v: u32, u: [f64; 3], ctx: &Ctx, floor: f64) -> bool {
        if self.star_quality_at(v, u, ctx) < floor {
            return false;
        }
        self.set_position(v, u, ctx);
        true
    }

    /// Puts `v` at index point `u` and updates its physical position and value (a level
    /// vertex carries its level exactly, other vertices the trilinear value).
    pub fn set_position(&mut self, v: u32, u: [f64; 3], ctx: &Ctx) {
        let i = v as usize;
        self.u[i] = u;
        self.x[i] = ctx.field.to_physical(u);
        self.value[i] = match self.con[i].level {
            Some(l) => ctx.levels[l as usize],
            None => ctx.field.value(u),
        };
        self.update_star_quality(v);
    }
}
