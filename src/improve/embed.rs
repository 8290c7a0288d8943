//! The embedding guard: an operation of the quality pass may change the boundary surface only
//! where the new boundary triangles stay near the trilinear level set they are labelled with.
//!
//! Positive tets and the link condition keep the complex right, but not its embedding: on a
//! thin interval nearly every vertex is a level vertex, every tet is a sliver between the two
//! sheets, and collapses and moves that keep every tet positive can turn the boundary into
//! long chords across the folds of the layer, so that the mesh covers other parts of the
//! domain, and space outside it, a second time. The guard refuses a move or a collapse whose
//! new boundary triangles leave their level set by more than [`GUARD_DISTANCE`] index units at
//! any of their sample points ([`sample_points`]); the check after each phase
//! ([`super::verify`]) also refuses boundary triangles that cross one another.

use super::collapse::{boundary_faces_at, VertexFaces};
use super::region::{BoundaryFace, LocalMesh};
use super::Ctx;
use crate::check::triangles_cross;
use crate::field::GUARD_DISTANCE;
use crate::geom::sample_points_spaced;
use crate::levels::Levels;
use crate::mesh::{BoundaryLabel, TetMesh};

/// Spacing (index units) of the sample points of a triangle.
const SAMPLE_SPACING: f64 = 0.25;

/// The level a boundary label lies on (`None` for the grid box).
pub fn label_level(label: BoundaryLabel, levels: &Levels) -> Option<f64> {
    label.level().map(|i| levels.get(i))
}

/// The points of triangle `t` (index space) at which its distance to the level set is
/// measured: a barycentric lattice with `n` steps along each edge, `n` such that neighbouring
/// points are at most [`SAMPLE_SPACING`] apart (at least 2: corners, edge midpoints and three
/// inner points). `None` if the triangle is too long to sample
/// ([`sample_points_spaced`]).
pub fn sample_points(t: [[f64; 3]; 3]) -> Option<impl Iterator<Item = [f64; 3]>> {
    sample_points_spaced(t, SAMPLE_SPACING)
}

/// Whether the level set `f = level` passes within `bound` of index point `u`
/// ([`crate::field::Field::near_level`]).
pub fn near_level(ctx: &Ctx, u: [f64; 3], level: f64, bound: f64) -> bool {
    ctx.field.near_level(u, level, bound, ctx.tol)
}

/// Whether every sample point of triangle `t` (index space) with label `label` lies within
/// [`GUARD_DISTANCE`] of its level set (box triangles: always).
pub fn triangle_near_level(ctx: &Ctx, t: [[f64; 3]; 3], label: BoundaryLabel) -> bool {
    triangle_within(ctx, t, label, GUARD_DISTANCE)
}

/// Whether every sample point of triangle `t` (index space) with label `label` lies within
/// `bound` of its level set (box triangles: always).
fn triangle_within(ctx: &Ctx, t: [[f64; 3]; 3], label: BoundaryLabel, bound: f64) -> bool {
    let Some(level) = label_level(label, &ctx.levels) else {
        return true;
    };
    match sample_points(t) {
        Some(mut points) => points.all(|p| near_level(ctx, p, level, bound)),
        None => false,
    }
}

/// How far (index units) a face that was already beyond [`GUARD_DISTANCE`] may be from its
/// level set after a projection of its corners ([`projected_face_keeps_level`]): still
/// inside the half voxel the checker allows.
pub const SLACK_DISTANCE: f64 = 0.45;

/// Whether a change that takes boundary face `before` to `after` (corners in index space,
/// label `label`) and brings corners onto their level set (a projection, a split, a move
/// along the level set) leaves the face near its level set. A face near it before
/// ([`triangle_near_level`]) must stay near it. A face already beyond it may stay so while a
/// corner is still off the level set (the other corners' projections come later, and such a
/// face would otherwise hold every corner back), but once all three corners are on it the
/// face must lie within [`SLACK_DISTANCE`]. Nothing a later operation does brings such a
/// face back: the moves and collapses keep only faces near their levels.
pub fn projected_face_keeps_level(
    ctx: &Ctx,
    label: BoundaryLabel,
    before: [[f64; 3]; 3],
    after: [[f64; 3]; 3],
) -> bool {
    let Some(level) = label_level(label, &ctx.levels) else {
        return true;
    };
    if triangle_near_level(ctx, after, label) {
        return true;
    }
    if triangle_near_level(ctx, before, label) {
        return false;
    }
    let settled = after
        .iter()
        .all(|&u| (ctx.field.value(u) - level).abs() <= ctx.tol);
    !settled || triangle_within(ctx, after, label, SLACK_DISTANCE)
}

/// Whether the boundary faces `faces` of region `lm`, with vertex `v` at index point `u`, all
/// stay near their level sets ([`triangle_near_level`]).
pub fn faces_near_level_with(
    lm: &LocalMesh,
    ctx: &Ctx,
    faces: &[BoundaryFace],
    v: u32,
    u: [f64; 3],
) -> bool {
    faces
        .iter()
        .all(|f| triangle_near_level(ctx, corners_with(lm, f, v, u), f.label))
}

/// The corners (index space) of face `f` of region `lm` with vertex `v` at `u`.
fn corners_with(lm: &LocalMesh, f: &BoundaryFace, v: u32, u: [f64; 3]) -> [[f64; 3]; 3] {
    f.tri.map(|w| if w == v { u } else { lm.u[w as usize] })
}

/// Whether moving vertex `v` of region `lm` to index point `u` keeps the boundary faces at `v`
/// near their level sets and clear of the boundary faces around them (always, for a vertex
/// off the boundary). Smoothing moves also ask [`move_keeps_volume`]; projections onto the
/// level set do not (they correct the geometry).
pub fn move_keeps_boundary(lm: &LocalMesh, ctx: &Ctx, v: u32, u: [f64; 3]) -> bool {
    if !lm.on_boundary(v) {
        return true;
    }
    let faces = boundary_faces_at(lm, v);
    faces_near_level_with(lm, ctx, &faces, v, u) && !crosses_nearby(lm, &faces, (v, v), u)
}

/// Whether projecting level vertex `v` onto its level set at index point `u` keeps the
/// boundary faces at `v` near their level sets as [`projected_face_keeps_level`] asks (a
/// detour to a point of the level set away from `v` can put a face across a fold of the
/// level set) and clear of the boundary faces around them.
pub fn projection_keeps_boundary(lm: &LocalMesh, ctx: &Ctx, v: u32, u: [f64; 3]) -> bool {
    if !lm.on_boundary(v) {
        return true;
    }
    let faces = boundary_faces_at(lm, v);
    faces_keep_level(lm, ctx, &faces, v, u) && !crosses_nearby(lm, &faces, (v, v), u)
}

/// Whether moving vertex `v` of region `lm` to index point `u` along its level set keeps the
/// boundary faces at `v` near their level sets as [`projected_face_keeps_level`] asks.
/// Crossings are left to the check after the phase ([`super::verify`]): the volume
/// restoration's many small steps along the level set cross nothing on their own.
pub fn level_move_keeps_level(lm: &LocalMesh, ctx: &Ctx, v: u32, u: [f64; 3]) -> bool {
    !lm.on_boundary(v) || faces_keep_level(lm, ctx, &boundary_faces_at(lm, v), v, u)
}

/// Whether each of `faces` (at `v`) keeps near its level set with `v` at `u`
/// ([`projected_face_keeps_level`]).
fn faces_keep_level(
    lm: &LocalMesh,
    ctx: &Ctx,
    faces: &[BoundaryFace],
    v: u32,
    u: [f64; 3],
) -> bool {
    faces.iter().all(|f| {
        let before = f.tri.map(|w| lm.u[w as usize]);
        projected_face_keeps_level(ctx, f.label, before, corners_with(lm, f, v, u))
    })
}

/// The moved corners (flagged in `moved`) of the boundary faces of `mesh` that, with every
/// point at `position` (physical), leave their level set as [`projected_face_keeps_level`]
/// refuses, among the faces with a corner flagged in `changed` (the others are as they were
/// when last asked): moves of the whole-mesh projection to take back.
pub fn moves_leaving_level(
    mesh: &TetMesh,
    ctx: &Ctx,
    position: &[[f64; 3]],
    (moved, changed): (&[bool], &[bool]),
) -> Vec<u32> {
    use rayon::prelude::*;
    let index = |p: &[[f64; 3]], tri: &[u32; 3]| tri.map(|v| ctx.field.to_index(p[v as usize]));
    let mut back: Vec<u32> = mesh
        .boundary
        .par_iter()
        .zip(&mesh.boundary_labels)
        .filter(|(tri, &label)| {
            tri.iter().any(|&v| changed[v as usize])
                && tri.iter().any(|&v| moved[v as usize])
                && !projected_face_keeps_level(
                    ctx,
                    label,
                    index(&mesh.points, tri),
                    index(position, tri),
                )
        })
        .flat_map_iter(|(tri, _)| *tri)
        .filter(|&v| moved[v as usize])
        .collect();
    back.sort_unstable();
    back.dedup();
    back
}

/// Whether merging `a` into `b` keeps the boundary faces that `a` leaves to `b` near their
/// level sets and clear of the boundary faces around them (always, for `a` off the
/// boundary), and its star's volume as [`collapse_keeps_volume`] asks (with `budget`).
pub fn collapse_keeps_boundary(
    lm: &LocalMesh,
    ctx: &Ctx,
    (a, b): (u32, u32),
    budget: bool,
) -> bool {
    if !lm.on_boundary(a) {
        return true;
    }
    let faces = boundary_faces_at(lm, a);
    let kept: VertexFaces = faces.into_iter().filter(|f| !f.tri.contains(&b)).collect();
    let ub = lm.u[b as usize];
    collapse_keeps_volume(lm, a, b, budget)
        && faces_near_level_with(lm, ctx, &kept, a, ub)
        && !crosses_nearby(lm, &kept, (a, b), ub)
}

/// The share of a level vertex's star volume that one move or collapse of it may add or take
/// away. On a thin interval the star is a thin slice between the two level sets, and a move
/// that keeps every sample of its faces within [`GUARD_DISTANCE`] of the level set can still
/// make the slice several times thicker; elsewhere a move along the level set changes the
/// star's volume by a small share of it.
pub const VOLUME_SHARE: f64 = 0.2;

/// Whether moving level vertex `v` to index point `u` changes its star's volume by at most
/// [`VOLUME_SHARE`] of it (always, for other vertices), and with `budget` keeps the
/// regions around a vertex between two regions within their budgets ([`star_keeps_volume`]).
pub fn move_keeps_volume(lm: &LocalMesh, ctx: &Ctx, v: u32, u: [f64; 3], budget: bool) -> bool {
    if lm.con[v as usize].level.is_none() {
        return true;
    }
    let x = ctx.field.to_physical(u);
    star_keeps_volume(lm, v, budget, |t| {
        let p = lm.corners_with(t, v, x);
        crate::geom::signed_volume(p[0], p[1], p[2], p[3])
    })
}

/// Whether merging level vertex `a` into `b` changes the volume of `a`'s star by at most
/// [`VOLUME_SHARE`] of it (always, for other vertices), and with `budget` keeps the
/// regions around a vertex between two regions within their budgets ([`star_keeps_volume`]).
pub fn collapse_keeps_volume(lm: &LocalMesh, a: u32, b: u32, budget: bool) -> bool {
    if lm.con[a as usize].level.is_none() {
        return true;
    }
    let xb = lm.x[b as usize];
    star_keeps_volume(lm, a, budget, |t| {
        if lm.tets[t as usize].contains(&b) {
            return 0.0;
        }
        let p = lm.corners_with(t, a, xb);
        crate::geom::signed_volume(p[0], p[1], p[2], p[3])
    })
}

/// Whether the tets of `v`'s star, each of volume `after(t)` after a change, keep the
/// star's volume within [`VOLUME_SHARE`] of it; with `budget`, for a vertex between two
/// regions, also whether each region keeps within its budget in the copy
/// ([`LocalMesh::within_budget`]). There the star's whole volume does not change (what one
/// region gains the other loses), and a thin region between two interfaces would otherwise
/// thicken merge by merge: the quality asks for fatter tets across it, and every boundary
/// face can stay near its level set while the layer doubles.
fn star_keeps_volume(lm: &LocalMesh, v: u32, budget: bool, after: impl Fn(u32) -> f64) -> bool {
    let below = lm.budget_region(v).filter(|_| budget);
    let (mut before, mut now) = (0.0, 0.0);
    let (mut sides_before, mut sides_now) = ([0.0; 2], [0.0; 2]);
    for &t in &lm.star[v as usize] {
        let (b, a) = (lm.volume_of(t), after(t));
        before += b;
        now += a;
        if let Some((r, _)) = below {
            let side = usize::from(lm.region[t as usize] != r);
            sides_before[side] += b;
            sides_now[side] += a;
        }
    }
    if (now - before).abs() > VOLUME_SHARE * before.abs() {
        return false;
    }
    below.is_none_or(|(r, interface)| {
        let r = r as usize;
        lm.within_budget(r, sides_now[0] - sides_before[0], REGION_BUDGET)
            && (!interface
                || lm.within_budget(r + 1, sides_now[1] - sides_before[1], REGION_BUDGET))
    })
}

/// The share of a region's volume in a copy that the merges and moves of interface vertices
/// may add to it or take from it, all together ([`LocalMesh::within_budget`]): what
/// [`super::verify`] asks of one interval's copy as a whole.
const REGION_BUDGET: f64 = super::verify::REGION_VOLUME_SHARE;

/// Whether a face of `new` (faces at `from`, with `from` becoming `to` at index point `u`: a
/// move when `from == to`, a collapse otherwise) crosses another of them, or another boundary
/// face of the region that the change keeps ([`LocalMesh::face_grid`]).
fn crosses_nearby(
    lm: &LocalMesh,
    new: &[BoundaryFace],
    (from, to): (u32, u32),
    u: [f64; 3],
) -> bool {
    let rename = |w: u32| if w == from { to } else { w };
    let at = |w: u32| if w == to { u } else { lm.u[w as usize] };
    let tri = |t: [u32; 3]| {
        let t = t.map(rename);
        (t.map(at), t.map(|w| w as u64))
    };
    new.iter().enumerate().any(|(i, f)| {
        let (p, ids) = tri(f.tri);
        if new[i + 1..].iter().any(|g| {
            let (q, jds) = tri(g.tri);
            triangles_cross([&ids, &jds], [&p, &q])
        }) {
            return true;
        }
        lm.face_grid.near(&p).into_iter().any(|key| {
            // The faces at `from` are the new ones (or go, in a collapse).
            if key.contains(&from) {
                return false;
            }
            let (q, jds) = tri(key);
            triangles_cross([&ids, &jds], [&p, &q])
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Instant;

    use crate::grid::ScalarGrid;
    use crate::improve::ctx::context;
    use crate::improve::QualityOptions;

    fn ctx_of(grid: &ScalarGrid) -> Ctx<'_> {
        context(
            grid,
            &Levels::interval(2.0, 3.0),
            &QualityOptions::default(),
            Instant::now(),
        )
    }

    /// f = x on a 5³ grid: the level set f = 2 is the plane x = 2.
    fn linear_x() -> ScalarGrid {
        let n = 5;
        let values: Vec<f64> = (0..n * n * n).map(|i| (i % n) as f64).collect();
        ScalarGrid::new([n, n, n], values).unwrap()
    }

    #[test]
    fn a_point_is_near_its_level_exactly_within_the_bound() {
        let grid = linear_x();
        let ctx = ctx_of(&grid);
        assert!(near_level(&ctx, [2.0, 1.0, 1.0], 2.0, 0.4));
        assert!(near_level(&ctx, [2.39, 1.0, 1.0], 2.0, 0.4));
        assert!(near_level(&ctx, [1.61, 1.0, 1.0], 2.0, 0.4));
        assert!(!near_level(&ctx, [2.45, 1.0, 1.0], 2.0, 0.4));
        assert!(!near_level(&ctx, [1.5, 1.0, 1.0], 2.0, 0.4));
    }

    #[test]
    fn a_triangle_is_near_its_level_only_if_every_sample_is() {
        let grid = linear_x();
        let ctx = ctx_of(&grid);
        let on = [[2.0, 0.5, 0.5], [2.0, 3.5, 0.5], [2.0, 0.5, 3.5]];
        assert!(triangle_near_level(&ctx, on, BoundaryLabel::ALPHA));
        // Corners on the level, the triangle bent away from it: a corner at x = 3 would put
        // the midpoints of its edges half a voxel off.
        let off = [[2.0, 0.5, 0.5], [2.0, 3.5, 0.5], [3.0, 2.0, 2.0]];
        assert!(!triangle_near_level(&ctx, off, BoundaryLabel::ALPHA));
        // The same triangle on the beta level (x = 3) is off at two corners.
        assert!(!triangle_near_level(&ctx, on, BoundaryLabel::BETA));
        // Box triangles are not measured.
        assert!(triangle_near_level(&ctx, off, BoundaryLabel::Box));
    }

    #[test]
    fn sample_points_cover_corners_and_refuse_huge_triangles() {
        let t = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let points: Vec<[f64; 3]> = sample_points(t).unwrap().collect();
        for c in t {
            assert!(points.contains(&c));
        }
        // n = 6 steps along the longest edge (sqrt 2 / 0.25 = 5.7): 28 points.
        assert_eq!(points.len(), 28);
        assert!(sample_points([[0.0; 3], [100.0, 0.0, 0.0], [0.0, 1.0, 0.0]]).is_none());
    }
}
