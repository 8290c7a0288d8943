//! Moving boundary vertices onto the trilinear level set they belong to.
//!
//! The clipper places cuts on the piecewise-linear level set; only cuts on grid edges are on
//! the trilinear one. Each free level vertex is moved by Newton steps along the gradient
//! (restricted to the axes its box planes leave free) until `|f - level| <= tol`; the move is
//! kept only if every tet around the vertex stays positive. Inside a region, where that move
//! would invert a tet, the vertex tries other points of its level set (projections started
//! halfway to its neighbours on the level) and, if each of them inverts a tet too, max–min
//! steps on the level set from the least bad one until its star is positive again. The last
//! resorts, after the sweeps: the vertex goes onto its level and the free corners of the
//! tets it inverts are moved out of the way ([`untangle_around`]); a neighbour is merged into
//! it first ([`absorb_and_project`]); it merges into a neighbour on its level and the tets
//! this inverts are untangled ([`merge_and_untangle`]). Each changes nothing if it fails.

use rayon::prelude::*;

use super::collapse::{apply_collapse, legal_collapse, topological_merge};
use super::constraint::{interface_bits, Constraint};
use super::embed;
use super::region::{LocalMesh, StarCorners};
use super::smooth::{climb, untangle_step};
use super::Ctx;
use crate::geom::{dot, signed_volume, sub};
use crate::mesh::{TetMesh, LEVEL_BITS};

/// Rounds of reverting the moves that invert a tet, at most (then every move is reverted).
const REVERT_ROUNDS: usize = 8;

/// Projects every level vertex of `mesh` at once (in parallel, independent of the thread
/// count): all moves are computed from the old positions, then the moves of vertices of tets
/// that would not stay positive are reverted until no tet is inverted. Adds to each moved
/// vertex's `drift` the volume its move added (over its tets, the others where they were).
/// Returns, per point, whether it moved. With `quality`, fills it with every tet's quality
/// ([`Ctx::quality`]) after the moves, reusing those the first inversion check evaluated at
/// the same corners.
pub fn project_mesh(
    mesh: &mut TetMesh,
    ctx: &Ctx,
    drift: &mut [f64],
    quality: Option<&mut Vec<f64>>,
) -> Vec<bool> {
    let labels = mesh.vertex_label_bits();
    let interfaces = interface_bits(ctx.levels.len());
    let dims = ctx.field.grid().dims;
    // Per point: where a level vertex off its level would go.
    let target: Vec<Option<[f64; 3]>> = (0..mesh.points.len())
        .into_par_iter()
        .map(|v| {
            if labels[v] & LEVEL_BITS == 0 {
                return None; // on no level
            }
            let mut u = ctx.field.to_index(mesh.points[v]);
            let c = Constraint::classify(labels[v], interfaces, &mut u, dims);
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
    // The first check evaluates every tet with every move made (those around no move as
    // they stay), which is each tet's quality after the projection unless a move around it
    // is reverted.
    let all = (0..mesh.tets.len() as u32).into_par_iter();
    let first = qualities_at_targets(mesh, (&target, &moved), all.clone(), ctx);
    let mut bad = inverted_moves(mesh, &moved, all, &first);
    // Moves whose boundary faces would cross another face or leave the level set are taken
    // back too (on a thin interval a node's trilinear level set can lie across the other
    // sheet; on a rough field, across a fold of its own), then the inversion check runs
    // again around them.
    // The first check looks at every move; each later one only around the moves taken back
    // (the other faces are where they were when last checked).
    let mut changed = moved.clone();
    let mut first_check = true;
    loop {
        let before = moved.clone();
        revert_inverting(mesh, ctx, (&target, &mut moved), &around_moved, bad);
        if !first_check {
            changed = before.iter().zip(&moved).map(|(&b, &m)| b && !m).collect();
        }
        first_check = false;
        let position: Vec<[f64; 3]> = (0..mesh.points.len())
            .into_par_iter()
            .map(|v| match target[v] {
                Some(t) if moved[v] => t,
                _ => mesh.points[v],
            })
            .collect();
        let flags = (moved.as_slice(), changed.as_slice());
        bad = super::verify::moves_breaking_embedding(mesh, ctx, &position, flags);
        bad.extend(embed::moves_leaving_level(mesh, ctx, &position, flags));
        bad.sort_unstable();
        bad.dedup();
        if bad.is_empty() {
            break;
        }
    }
    let counted = counted_regions(mesh, &labels, interfaces);
    add_moved_volume(mesh, &around_moved, (&target, &moved), &counted, drift);
    for (v, t) in target.iter().enumerate() {
        if moved[v] {
            mesh.points[v] = t.expect("moved vertices have a target");
        }
    }
    if let Some(quality) = quality {
        *quality = qualities_after(mesh, ctx, first, (&target, &moved));
    }
    moved
}

/// Takes back the moves of the vertices in `bad` and then those of the corners of the tets
/// that stay inverted, [`REVERT_ROUNDS`] times at most (then every move).
fn revert_inverting(
    mesh: &TetMesh,
    ctx: &Ctx,
    (target, moved): (&[Option<[f64; 3]>], &mut [bool]),
    around_moved: &[u32],
    mut bad: Vec<u32>,
) {
    for round in 0..=REVERT_ROUNDS {
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
        let check: Vec<u32> = around_moved
            .par_iter()
            .copied()
            .filter(|&t| mesh.tets[t as usize].iter().any(|&v| reverted[v as usize]))
            .collect();
        let q = qualities_at_targets(mesh, (target, moved), check.par_iter().copied(), ctx);
        bad = inverted_moves(mesh, moved, check.par_iter().copied(), &q);
    }
}

/// Every tet's quality after the projection: `first` (per tet, with every targeted corner at
/// its target) where no corner's move was reverted, else evaluated.
fn qualities_after(
    mesh: &TetMesh,
    ctx: &Ctx,
    mut first: Vec<f64>,
    (target, moved): (&[Option<[f64; 3]>], &[bool]),
) -> Vec<f64> {
    let reverted = |v: u32| target[v as usize].is_some() && !moved[v as usize];
    mesh.tets.par_iter().zip(&mut first).for_each(|(tet, q)| {
        if tet.iter().any(|&v| reverted(v)) {
            *q = ctx.quality(tet.map(|v| mesh.points[v as usize]));
        }
    });
    first
}

/// Per point of a mesh of several regions: the region whose volume its drift counts (for a
/// vertex on an interface, the region below; [`LocalMesh::counted_region`]), `u8::MAX` for
/// all of its star. Empty for one interval.
fn counted_regions(mesh: &TetMesh, labels: &[u32], interfaces: u32) -> Vec<u8> {
    if mesh.regions.is_empty() {
        return Vec::new();
    }
    labels
        .iter()
        .map(|&l| {
            let on = l & LEVEL_BITS;
            match on.count_ones() == 1 && on & interfaces != 0 {
                true => on.trailing_zeros() as u8 - 1,
                false => u8::MAX,
            }
        })
        .collect()
}

/// Adds to the `drift` of each `moved` corner of the tets `around` the volume its move to its
/// `target` adds to them (those of its `counted` region, if any), the other corners where
/// they are.
fn add_moved_volume(
    mesh: &TetMesh,
    around: &[u32],
    (target, moved): (&[Option<[f64; 3]>], &[bool]),
    counted: &[u8],
    drift: &mut [f64],
) {
    // Per tet of `around`: what the move of each moved corner adds (summed below in the
    // order of `around`, then of the corners: the same sums for any thread count).
    let added: Vec<[f64; 4]> = around
        .par_iter()
        .map(|&t| {
            let tet = mesh.tets[t as usize];
            let old = tet.map(|v| mesh.points[v as usize]);
            let v0 = signed_volume(old[0], old[1], old[2], old[3]);
            let mut out = [0.0; 4];
            for (i, o) in out.iter_mut().enumerate() {
                let v = tet[i] as usize;
                let other = counted
                    .get(v)
                    .is_some_and(|&r| r != u8::MAX && r != mesh.regions.tets[t as usize]);
                if other {
                    continue;
                }
                if let (true, Some(x)) = (moved[v], target[v]) {
                    let mut p = old;
                    p[i] = x;
                    *o = signed_volume(p[0], p[1], p[2], p[3]) - v0;
                }
            }
            out
        })
        .collect();
    for (&t, d) in around.iter().zip(&added) {
        for (&v, &d) in mesh.tets[t as usize].iter().zip(d) {
            if moved[v as usize] {
                drift[v as usize] += d;
            }
        }
    }
}

/// Per point: is it on a face of a level but farther than the tolerance from that level set
/// (pinned vertices included)?
pub fn off_level_points(mesh: &TetMesh, ctx: &Ctx) -> Vec<bool> {
    let labels = mesh.vertex_label_bits();
    (0..mesh.points.len())
        .into_par_iter()
        .map(|v| {
            let on_levels = labels[v] & LEVEL_BITS;
            if on_levels == 0 {
                return false;
            }
            let f = ctx.field.value(ctx.field.to_index(mesh.points[v]));
            (0..ctx.levels.len())
                .any(|l| on_levels & (1 << l) != 0 && (f - ctx.levels[l]).abs() > ctx.tol)
        })
        .collect()
}

/// The quality of each tet of `check` with its `moved` corners at their `target`.
fn qualities_at_targets(
    mesh: &TetMesh,
    (target, moved): (&[Option<[f64; 3]>], &[bool]),
    check: impl IndexedParallelIterator<Item = u32>,
    ctx: &Ctx,
) -> Vec<f64> {
    check
        .map(|t| {
            let tet = mesh.tets[t as usize];
            let p = tet.map(|v| match (moved[v as usize], target[v as usize]) {
                (true, Some(x)) => x,
                _ => mesh.points[v as usize],
            });
            ctx.quality(p)
        })
        .collect()
}

/// The moved vertices of the tets among `check` whose qualities with the moves made, `q`
/// ([`qualities_at_targets`]), are not positive, sorted.
fn inverted_moves(
    mesh: &TetMesh,
    moved: &[bool],
    check: impl IndexedParallelIterator<Item = u32>,
    q: &[f64],
) -> Vec<u32> {
    let mut bad: Vec<u32> = check
        .zip(q)
        .filter(|(_, &q)| q <= 0.0)
        .map(|(t, _)| mesh.tets[t as usize])
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
    if lm.known_on_level(v) {
        return false;
    }
    let target = ctx.levels[level as usize];
    let u = lm.u[v as usize];
    if (ctx.field.value(u) - target).abs() <= ctx.tol {
        lm.found_on_level(v);
        return false;
    }
    let free = c.free_axes();
    let direct = ctx.field.project(u, target, free, ctx.tol);
    let keeps = |p: [f64; 3]| embed::projection_keeps_boundary(lm, ctx, v, p);
    if let Some(p) = direct.filter(|&p| lm.star_above_at(v, p, ctx, 0.0) && keeps(p)) {
        lm.set_position(v, p, ctx);
        return true;
    }
    match detour(lm, ctx, v, target, free, direct).filter(|&p| keeps(p)) {
        Some(p) => {
            lm.set_position(v, p, ctx);
            true
        }
        None => false,
    }
}

/// Rounds of moving the neighbours of a level vertex out of the way, at most (only stuck
/// level vertices get here, so more rounds cost little: with 3, and with 6, a node of the
/// T1 at `[101.5, 151.5]` next to a cavity of four nodes stayed 0.17 voxel off its level).
const NEIGHBOUR_ROUNDS: usize = 12;

/// The last resort for a level vertex none of whose level points keeps its star positive:
/// puts `v` at the best of them ([`best_on_level`]) and moves the free corners of the tets
/// it inverts by max–min steps (which raise the worst, here inverted, tet of their stars
/// first). Kept only if every tet around the moved vertices ends positive; else every move
/// is undone. Returns whether `v` moved.
pub fn untangle_around(lm: &mut LocalMesh, ctx: &Ctx, v: u32) -> bool {
    let c = lm.con[v as usize];
    let Some(level) = c.level.map(|l| ctx.levels[l as usize]) else {
        return false;
    };
    let free = c.free_axes();
    let u = lm.u[v as usize];
    let direct = ctx.field.project(u, level, free, ctx.tol);
    let direct = direct.or_else(|| ctx.field.march(u, level, free, ctx.tol));
    let star = StarCorners::of(lm, v);
    let Some((p, _)) = best_on_level(lm, ctx, v, &star, (level, free), direct) else {
        return false;
    };
    let from = lm.u[v as usize];
    lm.set_position(v, p, ctx);
    untangle_corners(lm, ctx, v, vec![(v, from)])
}

/// Moves the free corners (other than `v`) of the tets left non-positive around `v` and the
/// corners moved so far by max–min steps, [`NEIGHBOUR_ROUNDS`] times at most. `undo` holds the
/// moved vertices with their old positions. Keeps the moves if every tet around the moved
/// vertices and `v` ends positive, else undoes them all. Returns whether it kept them.
fn untangle_corners(lm: &mut LocalMesh, ctx: &Ctx, v: u32, mut undo: Vec<(u32, [f64; 3])>) -> bool {
    for _ in 0..NEIGHBOUR_ROUNDS {
        let moved: Vec<u32> = std::iter::once(v)
            .chain(undo.iter().map(|&(w, _)| w))
            .collect();
        let tangled = tangled_corners(lm, &moved);
        if tangled.is_empty() {
            break;
        }
        for w in tangled {
            if let Some(from) = untangle_step(lm, ctx, w, UNTANGLE_STEPS) {
                undo.push((w, from));
            }
        }
    }
    let positive = std::iter::once(v)
        .chain(undo.iter().map(|&(w, _)| w))
        .all(|w| lm.star[w as usize].iter().all(|&t| lm.q[t as usize] > 0.0))
        && std::iter::once(v)
            .chain(undo.iter().map(|&(w, _)| w))
            .all(|w| embed::move_keeps_boundary(lm, ctx, w, lm.u[w as usize]));
    if !positive {
        for &(w, u) in undo.iter().rev() {
            lm.set_position(w, u, ctx);
        }
    }
    positive
}

/// Neighbours tried by [`absorb_and_project`] at most (nearest first).
const ABSORB_TRIES: usize = 8;

/// The last resort after [`untangle_around`]: a free neighbour `w` that may merge into `v`
/// (an interior vertex, or one on every surface `v` lies on) is collapsed into `v` (legal,
/// every tet positive), then `v` is projected, or untangled, onto its level. Tried on a copy
/// of the region, nearest neighbours first, and kept only if `v` reaches its level with every
/// tet positive. A level vertex is blocked where a neighbour stands between it and its level
/// set (the noisy 256³ field at `[-2, 2]` left one such node off before this): removing that
/// neighbour clears the way. The collapse is a move of the complex like any other (link
/// condition, constraints, positive tets), so the topology stays. Returns whether `v` reached
/// its level.
pub fn absorb_and_project(lm: &mut LocalMesh, ctx: &Ctx, v: u32) -> bool {
    let con = lm.con[v as usize];
    for w in nearest(lm, v, |w| lm.con[w as usize].may_merge_into(&con)) {
        if !legal_collapse(lm, ctx, (w, v), false) {
            continue;
        }
        let mut trial = lm.clone();
        apply_collapse(&mut trial, w, v);
        if project_vertex(&mut trial, ctx, v) || untangle_around(&mut trial, ctx, v) {
            *lm = trial;
            return true;
        }
    }
    false
}

/// The last resort after [`absorb_and_project`]: `v` merges into a neighbour `b` on its
/// level where the link condition allows, whatever the signs of the tets it leaves, and the
/// free corners of the non-positive ones are moved out of the way ([`untangle_corners`]).
/// Tried on a copy of the region, nearest neighbours first, and kept only if every tet ends
/// positive. A level vertex is blocked this way where its linear cut is far from the trilinear
/// level set of its own sheet and near another sheet's (the MNI white matter at 63.5: a cut
/// 1/14 along a cell's body diagonal, where the trilinear value is 66.9 and the diagonal
/// crosses 63.5 near its far end; projecting it lands on the sheet across the grid vertex).
/// The merge removes the spike of its sheet, and the link condition keeps the topology.
/// Returns whether `v` was merged.
pub fn merge_and_untangle(lm: &mut LocalMesh, ctx: &Ctx, v: u32) -> bool {
    let level = lm.con[v as usize].level;
    let on_level = |w: u32| lm.con[w as usize].level == level && !lm.off_its_level(w, ctx);
    for b in nearest(lm, v, on_level) {
        if !topological_merge(lm, ctx, v, b) {
            continue;
        }
        let mut trial = lm.clone();
        apply_collapse(&mut trial, v, b);
        if untangle_corners(&mut trial, ctx, b, Vec::new()) {
            *lm = trial;
            return true;
        }
    }
    false
}

/// The neighbours `w` of `v` with `keep(w)`, nearest first (ties by id), [`ABSORB_TRIES`] at
/// most: the candidates of [`absorb_and_project`] and [`merge_and_untangle`].
fn nearest(lm: &LocalMesh, v: u32, keep: impl Fn(u32) -> bool) -> Vec<u32> {
    let mut near: Vec<(f64, u32)> = lm.star[v as usize]
        .iter()
        .flat_map(|&t| lm.tets[t as usize])
        .filter(|&w| w != v && keep(w))
        .map(|w| {
            let d = sub(lm.x[w as usize], lm.x[v as usize]);
            (dot(d, d), w)
        })
        .collect();
    near.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    near.dedup_by_key(|x| x.1);
    near.into_iter()
        .take(ABSORB_TRIES)
        .map(|(_, w)| w)
        .collect()
}

/// The free corners other than `moved[0]` (the level vertex) of the non-positive tets
/// around the `moved` vertices, sorted.
fn tangled_corners(lm: &LocalMesh, moved: &[u32]) -> Vec<u32> {
    let mut out: Vec<u32> = moved
        .iter()
        .flat_map(|&m| &lm.star[m as usize])
        .filter(|&&t| lm.q[t as usize] <= 0.0)
        .flat_map(|&t| lm.tets[t as usize])
        .filter(|&w| w != moved[0] && lm.is_free(w))
        .collect();
    out.sort_unstable();
    out.dedup();
    out
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::{cross, dot, sub};
    use crate::improve::fixtures::{wavy_torus, wavy_torus_regions};

    /// Blocks level vertex `v` (on its level at `p`): moves it inward by a tenth of a voxel,
    /// then an interior neighbour `w` of a tet `vwab` so that the plane through `w`, `a`, `b`
    /// passes between the two positions of `v`: the stars stay positive, but `v` back at `p`
    /// inverts `vwab`. Returns the neighbour moved, or `None` where no such move exists.
    fn block(lm: &mut LocalMesh, ctx: &Ctx, v: u32, p: [f64; 3]) -> Option<u32> {
        let level = lm.con[v as usize].level? as usize;
        let (_, g) = ctx.field.value_gradient(p);
        let inward = if level == 0 { 0.1 } else { -0.1 } / crate::geom::norm(g);
        let inside: [f64; 3] = std::array::from_fn(|a| p[a] + inward * g[a]);
        if !lm.star_above_at(v, inside, ctx, 0.0) {
            return None;
        }
        lm.set_position(v, inside, ctx);
        let mid: [f64; 3] = std::array::from_fn(|a| 0.5 * (p[a] + inside[a]));
        for t in lm.star[v as usize].clone() {
            for w in lm.tets[t as usize] {
                let c = lm.con[w as usize];
                if w == v || !lm.is_free(w) || c.level.is_some() || c.box_planes != 0 {
                    continue;
                }
                let from = lm.u[w as usize];
                let ab: Vec<u32> = lm.tets[t as usize]
                    .into_iter()
                    .filter(|&a| a != v && a != w)
                    .collect();
                let (ua, ub) = (lm.u[ab[0] as usize], lm.u[ab[1] as usize]);
                // Across the plane through a, b and the middle of v's two positions.
                let n = cross(sub(ub, ua), sub(mid, ua));
                let off = dot(sub(from, ua), n) / dot(n, n);
                for s in [1.05, 1.2, 1.5, 2.0] {
                    let to = std::array::from_fn(|i| from[i] - s * off * n[i]);
                    if ctx.inside_interval(to) && lm.star_above_at(w, to, ctx, 0.0) {
                        lm.set_position(w, to, ctx);
                        if !lm.star_above_at(v, p, ctx, 0.0) {
                            return Some(w);
                        }
                        lm.set_position(w, from, ctx);
                    }
                }
            }
        }
        lm.set_position(v, p, ctx);
        None
    }

    #[test]
    fn a_blocked_level_vertex_is_untangled_or_absorbs_a_neighbour_or_is_left_as_it_was() {
        let grid = wavy_torus();
        let (ctx, mut regions) = wavy_torus_regions(&grid, &[0, 1]);
        // Blocked vertices, those no point of their level frees, and of these the untangled.
        let (mut blocked, mut stuck, mut untangled, mut absorbed) = (0, 0, 0, 0);
        for lm in &mut regions {
            project_levels(lm, &ctx);
            for v in 0..lm.u.len() as u32 {
                let c = lm.con[v as usize];
                let Some(l) = c.level else { continue };
                let p = lm.u[v as usize];
                let on = (ctx.field.value(p) - ctx.levels[l as usize]).abs() <= ctx.tol;
                if !lm.is_free(v) || c.pinned || c.freedom() != 2 || !on {
                    continue;
                }
                let Some(w) = block(lm, &ctx, v, p) else {
                    continue;
                };
                blocked += 1;
                let before = (lm.u[v as usize], lm.u[w as usize]);
                let level = ctx.levels[l as usize];
                let direct = ctx.field.project(before.0, level, c.free_axes(), ctx.tol);
                let star = StarCorners::of(lm, v);
                let free = c.free_axes();
                let best = best_on_level(lm, &ctx, v, &star, (level, free), direct);
                let is_stuck = best.is_none_or(|b| b.1 <= 0.0);
                stuck += usize::from(is_stuck);
                // The last resort, on a copy: a neighbour merged into `v` clears its way.
                let mut trial = lm.clone();
                if absorb_and_project(&mut trial, &ctx, v) {
                    absorbed += 1;
                    let f = ctx.field.value(trial.u[v as usize]);
                    assert!((f - level).abs() <= ctx.tol, "{v} absorbed, off its level");
                    let alive = (0..trial.tets.len()).filter(|&t| trial.alive[t]);
                    for t in alive {
                        let q = ctx.quality(trial.corners(trial.tets[t]));
                        assert!(q > 0.0 && q == trial.q[t], "tet {t} after absorbing at {v}");
                    }
                } else {
                    assert_eq!(
                        trial.tets, lm.tets,
                        "{v}: a failed absorption changed the region"
                    );
                    assert_eq!(trial.u, lm.u, "{v}: a failed absorption moved a vertex");
                }
                if untangle_around(lm, &ctx, v) {
                    untangled += usize::from(is_stuck);
                    let f = ctx.field.value(lm.u[v as usize]);
                    assert!(
                        (f - ctx.levels[l as usize]).abs() <= ctx.tol,
                        "{v} off its level"
                    );
                } else {
                    assert_eq!(
                        before,
                        (lm.u[v as usize], lm.u[w as usize]),
                        "{v} not undone"
                    );
                }
                let alive = (0..lm.tets.len()).filter(|&t| lm.alive[t]);
                for t in alive {
                    let q = ctx.quality(lm.corners(lm.tets[t]));
                    assert!(q > 0.0 && q == lm.q[t], "tet {t} after untangling {v}: {q}");
                }
            }
        }
        // 45 blocked, 8 stuck, 8 untangled; all 45 absorb a neighbour on a copy.
        assert!(
            blocked >= 30 && stuck >= 5 && untangled > stuck / 2 && absorbed > blocked / 2,
            "{untangled} of {stuck} stuck of {blocked} blocked, {absorbed} absorbed"
        );
    }

    /// Moves level vertex `v` inward along the gradient by the largest of a few depths that
    /// keeps its star positive (a spike of its sheet, as a linear cut far from its trilinear
    /// level set makes). Returns whether it moved.
    fn push_inward(lm: &mut LocalMesh, ctx: &Ctx, v: u32) -> bool {
        let Some(level) = lm.con[v as usize].level else {
            return false;
        };
        let p = lm.u[v as usize];
        let (_, g) = ctx.field.value_gradient(p);
        let sign = if level as usize == 0 { 1.0 } else { -1.0 };
        for depth in [0.6, 0.45, 0.3] {
            let s = sign * depth / crate::geom::norm(g);
            let to: [f64; 3] = std::array::from_fn(|a| p[a] + s * g[a]);
            if ctx.inside_interval(to) && lm.star_above_at(v, to, ctx, 0.0) {
                lm.set_position(v, to, ctx);
                return true;
            }
        }
        false
    }

    #[test]
    fn a_level_vertex_far_off_its_level_merges_into_its_sheet_or_is_left_as_it_was() {
        let grid = wavy_torus();
        let (ctx, mut regions) = wavy_torus_regions(&grid, &[0, 1]);
        let (mut pushed, mut merged) = (0, 0);
        for lm in &mut regions {
            project_levels(lm, &ctx);
            for v in (0..lm.u.len() as u32).step_by(7) {
                let c = lm.con[v as usize];
                if !lm.is_free(v) || c.pinned || c.freedom() != 2 || !push_inward(lm, &ctx, v) {
                    continue;
                }
                pushed += 1;
                let mut trial = lm.clone();
                if !merge_and_untangle(&mut trial, &ctx, v) {
                    assert_eq!(
                        trial.tets, lm.tets,
                        "{v}: a failed merge changed the region"
                    );
                    assert_eq!(trial.u, lm.u, "{v}: a failed merge moved a vertex");
                    continue;
                }
                merged += 1;
                assert!(trial.removed[v as usize] && trial.star[v as usize].is_empty());
                // One surface edge collapsed: two faces fewer, none at `v` (the Euler
                // characteristic of the level surface kept).
                assert_eq!(
                    trial.faces.len() + 2,
                    lm.faces.len(),
                    "faces after merging {v}"
                );
                assert!(trial.faces.keys().all(|f| !f.contains(&v)));
                for t in (0..trial.tets.len()).filter(|&t| trial.alive[t]) {
                    let q = ctx.quality(trial.corners(trial.tets[t]));
                    assert!(q > 0.0 && q == trial.q[t], "tet {t} after merging {v}: {q}");
                    assert!(!trial.tets[t].contains(&v));
                }
            }
        }
        // The embedding guard refuses the merges whose faces would leave the level set or
        // cross another face; the rest go through.
        assert!(
            pushed >= 30 && merged > pushed / 5,
            "{merged} of {pushed} pushed vertices merged"
        );
    }
}
