//! Boundary edge splits: where the level set curves within a boundary edge, the edge's chord
//! lies well inside (or outside) the level set, and a surface whose nodes all lie on the level
//! set is inscribed in it: a thin tube loses volume that no vertex move along the level set
//! gives back. Such an edge gets a node at its midpoint, put on the level set; every tet around
//! the edge is cut in two through the new node, and so are the two boundary faces on it.
//!
//! A split refines the complex (the same underlying space), and the move of the new node onto
//! the level set is a vertex move: it is kept only where every new tet is positive and of at
//! least the target quality (or of the worst quality around the edge before, where that was
//! below the target), so the topology holds and no element gets worse than what was there.

use super::constraint::Constraint;
use super::embed;
use super::region::{face_key, BoundaryFace, EdgeTets, LocalMesh};
use super::restore::{group_of, GroupVolumes};
use super::Ctx;
use crate::geom::{norm, signed_volume, sub};
use crate::levels::MAX_LEVELS;
use crate::mesh::{BoundaryLabel, TetMesh};

/// How far the new node may lie from the chord's midpoint, as a fraction of the edge.
const REACH: f64 = 0.5;

/// The sag of the chord from `ua` to `ub` (index space) from the level set `ctx.levels[l]`,
/// relative to its length: the first-order distance from the midpoint to the level set over
/// the edge's length, positive where the midpoint lies inside the domain (the boundary bulges
/// out there) and negative outside.
pub fn sag(ctx: &Ctx, ua: [f64; 3], ub: [f64; 3], l: usize) -> f64 {
    let len = norm(sub(ub, ua));
    let (f, g) = ctx.field.value_gradient(midpoint(ua, ub));
    let g = norm(g);
    if len <= 0.0 || g <= 0.0 || !g.is_finite() {
        return 0.0;
    }
    // The domain lies above alpha and below beta.
    let inward = if l == 0 { 1.0 } else { -1.0 };
    inward * (f - ctx.levels[l]) / g / len
}

/// The midpoint of `a` and `b`.
fn midpoint(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|i| 0.5 * (a[i] + b[i]))
}

/// Per point: an end of a boundary edge that may be split ([`candidates`] decides): one on
/// a level set whose chord sags by more than `min_sag` of its length ([`sag`]), where the
/// boundary bends one way ([`bends`]), in a slab of the grid (along its longest axis) whose
/// sagging edges bend mostly one way, and on that side ([`dominant_side`]). Elsewhere the
/// chords' errors cancel, and the splits would cost time for nothing. With several regions
/// each level votes apart ([`group_of`]): the chords of one level do not cancel those of
/// another, since each moves the volume of other regions.
pub fn sagging_points(mesh: &TetMesh, ctx: &Ctx, min_sag: f64) -> Vec<bool> {
    use rayon::prelude::*;
    let edges: Vec<([u32; 2], f64, usize)> = mesh
        .boundary
        .par_iter()
        .zip(&mesh.boundary_labels)
        .flat_map_iter(|(tri, &label)| {
            let level = label.level();
            let u = |v: u32| ctx.field.to_index(mesh.points[v as usize]);
            (0..3).filter_map(move |i| {
                let (a, b) = (tri[i], tri[(i + 1) % 3]);
                // Each edge is on two faces: take it from the one where it runs a < b.
                (a < b)
                    .then_some(level)
                    .flatten()
                    .map(|l| ([a, b], sag(ctx, u(a), u(b), l), group_of(ctx, l as u8)))
            })
        })
        .collect();
    let groups = edges.iter().map(|&(_, _, g)| g + 1).max().unwrap_or(1);
    let bend = bends(
        mesh.points.len(),
        edges.iter().map(|&(e, s, _)| (e, s)),
        min_sag,
    );
    let (sagging, group): (Vec<([u32; 2], f64)>, Vec<usize>) = edges
        .into_iter()
        .filter(|&(e, s, _)| one_way(&bend, e, s, min_sag))
        .map(|(e, s, g)| ((e, s), g))
        .unzip();
    let axis = super::region::longest_axis(&ctx.field);
    // The vote of each slab, and with several regions of each level in it.
    let slab: Vec<usize> = sagging
        .iter()
        .zip(&group)
        .map(|(&(e, _), &g)| {
            let u = ctx.field.to_index(mesh.points[e[0] as usize])[axis];
            (u / SLAB).floor().max(0.0) as usize * groups + g
        })
        .collect();
    let side = dominant_side(mesh, &sagging, &slab);
    let mut work = vec![false; mesh.points.len()];
    for ((e, s), k) in sagging.into_iter().zip(slab) {
        if s * side[k] > 0.0 {
            for v in e {
                work[v as usize] = true;
            }
        }
    }
    work
}

/// Thickness of the slabs of [`dominant_side`] (voxels, along the grid's longest axis).
const SLAB: f64 = 16.0;

/// Per slab (`slab`: that of each sagging edge): +1 where the sagging edges bulge out (chords
/// inside) by more than twice what they bulge in, weighted by the volume their chords miss
/// (sag times the cube of length), -1 the other way round, 0 where neither side dominates.
fn dominant_side(mesh: &TetMesh, sagging: &[([u32; 2], f64)], slab: &[usize]) -> Vec<f64> {
    let n = slab.iter().max().map_or(0, |&k| k + 1);
    let mut weight = vec![[0.0f64; 2]; n];
    for (&(e, s), &k) in sagging.iter().zip(slab) {
        let [a, b] = e.map(|v| mesh.points[v as usize]);
        let len = norm(sub(b, a));
        weight[k][usize::from(s < 0.0)] += s.abs() * len * len * len;
    }
    weight
        .iter()
        .map(|&[out, inn]| {
            if out > 2.0 * inn {
                1.0
            } else if inn > 2.0 * out {
                -1.0
            } else {
                0.0
            }
        })
        .collect()
}

/// Whether edge `e` with sag `s` is split-worthy: it sags by more than `min_sag`, and the
/// boundary at both its ends bends one way ([`bends`]).
fn one_way(bend: &[u8], e: [u32; 2], s: f64, min_sag: f64) -> bool {
    s.abs() > min_sag && e.iter().all(|&v| bend[v as usize] != BOTH_WAYS)
}

/// [`bends`] of a vertex with edges sagging both ways.
const BOTH_WAYS: u8 = 3;

/// Per vertex of `n`: bit 0 if a boundary edge at it (of `edges`, with their [`sag`]) sags
/// inwards by more than `min_sag`, bit 1 if one sags outwards.
fn bends(n: usize, edges: impl IntoIterator<Item = ([u32; 2], f64)>, min_sag: f64) -> Vec<u8> {
    let mut bend = vec![0u8; n];
    for (e, s) in edges {
        if s.abs() > min_sag {
            let bit = if s > 0.0 { 1 } else { 2 };
            for v in e {
                bend[v as usize] |= bit;
            }
        }
    }
    bend
}

/// An edge to split: its ends and its sag.
struct Candidate {
    a: u32,
    b: u32,
    sag: f64,
}

/// Splits the boundary edges of the region whose chord sags by more than `min_sag` of their
/// length, most sagging first, where that keeps every new tet above its floor, and only as far
/// as the region's volume needs. Returns the splits and the volume they added, per volume
/// group ([`group_of`]).
///
/// Which volume: had every such edge been split, the region would have gained the sum of
/// their gains (a convex part gains, a concave one loses). Where a split's new tets would be
/// poor, it is not made, and that happens more on one side (a concave part's new tets are
/// flatter), so splitting all the others would overshoot wherever the two sides balance (the
/// noisy 256³ field gained 0.5 %, which its plain mesh did not lack). So only edges that add
/// volume on the side of the sum are split, while each brings the region closer to it. The
/// edges are those of the region as it was: the halves of a split edge are not split again.
pub fn split_sagging_edges(
    lm: &mut LocalMesh,
    ctx: &Ctx,
    min_sag: f64,
    sagging: Option<&[bool]>,
) -> (usize, GroupVolumes) {
    let planned: Vec<Split> = candidates(lm, ctx, min_sag, sagging)
        .into_iter()
        .filter_map(|c| plan(lm, ctx, c.a, c.b))
        .collect();
    // Each volume group splits only as far as its own volume needs.
    let mut owed: GroupVolumes = [0.0; MAX_LEVELS];
    for s in &planned {
        owed[s.group(ctx)] += s.gain;
    }
    let (mut n, mut added) = (0, [0.0; MAX_LEVELS]);
    for (i, first) in planned.into_iter().enumerate() {
        if i % 64 == 63 && ctx.out_of_time() {
            break;
        }
        let group = first.group(ctx);
        let (owed, added) = (&mut owed[group], &mut added[group]);
        if first.gain * *owed <= 0.0 {
            continue;
        }
        // Earlier splits may have cut the tets around this edge.
        let Some(s) = plan(lm, ctx, first.a, first.b) else {
            continue;
        };
        if (*owed - s.gain).abs() < owed.abs() && s.fits(lm, ctx) {
            *owed -= s.gain;
            *added += s.gain;
            apply(lm, ctx, s);
            n += 1;
        }
    }
    (n, added)
}

/// The boundary edges of the region on a level set with both ends movable on it and one end
/// free (so that every tet around the edge is in the region), sagging by more than
/// `min_sag`, with both ends marked in `sagging` (per point of the mesh, from
/// [`sagging_points`]; `None`: every edge); most sagging first (ties by ids). The region may
/// reach beyond the sagging points (the volume restoration's work is every point with drift),
/// and its other edges lie where the chords' errors cancel.
///
/// Only where the boundary bends one way: an edge is a candidate when no boundary edge at
/// either end sags by more than `min_sag` the other way. Where it bends both ways (a saddle,
/// or noise), the faces' errors cancel, and splitting the edges that sag most would not (the
/// noisy 256³ field lost 0.4 % that way; with this rule it stays within 0.1 %).
fn candidates(lm: &LocalMesh, ctx: &Ctx, min_sag: f64, sagging: Option<&[bool]>) -> Vec<Candidate> {
    let marked =
        |v: u32| sagging.is_none_or(|s| s.get(lm.global[v as usize] as usize) == Some(&true));
    let mut edges: Vec<(u32, u32, usize)> = lm
        .faces
        .values()
        .filter(|f| f.label != BoundaryLabel::Box)
        .flat_map(|f| (0..3).map(move |i| (f.tri[i], f.tri[(i + 1) % 3], f.label.index())))
        .map(|(a, b, l)| (a.min(b), a.max(b), l))
        .filter(|&(a, b, _)| marked(a) && marked(b))
        .collect();
    edges.sort_unstable();
    edges.dedup();
    let sags: Vec<([u32; 2], f64)> = edges
        .iter()
        .map(|&(a, b, l)| ([a, b], sag(ctx, lm.u[a as usize], lm.u[b as usize], l)))
        .collect();
    let bend = bends(lm.u.len(), sags.iter().copied(), min_sag);
    let mut out: Vec<Candidate> = sags
        .into_iter()
        .filter(|&(e, s)| one_way(&bend, e, s, min_sag))
        .filter(|&([a, b], _)| splittable(lm, a, b))
        .map(|([a, b], s)| Candidate { a, b, sag: s.abs() })
        .collect();
    out.sort_by(|x, y| y.sag.total_cmp(&x.sag).then((x.a, x.b).cmp(&(y.a, y.b))));
    out
}

/// Whether both ends lie on the same level set only (no box plane), may move, and one of them
/// is free.
fn splittable(lm: &LocalMesh, a: u32, b: u32) -> bool {
    let (ca, cb) = (lm.con[a as usize], lm.con[b as usize]);
    let plain = |c: Constraint| c.level.is_some() && c.box_planes == 0 && !c.pinned;
    plain(ca)
        && plain(cb)
        && ca.level == cb.level
        && (lm.is_free(a) || lm.is_free(b))
        && !lm.removed[a as usize]
        && !lm.removed[b as usize]
}

/// A split of edge `ab`: the new node (index-space and physical position on the level set,
/// its level's value and constraint), the tets and boundary faces around the edge, and the
/// volume it adds.
struct Split {
    a: u32,
    b: u32,
    p: [f64; 3],
    x: [f64; 3],
    value: f64,
    con: Constraint,
    around: EdgeTets,
    faces: Vec<BoundaryFace>,
    gain: f64,
}

impl Split {
    /// The volume group of the split's level ([`group_of`]).
    fn group(&self, ctx: &Ctx) -> usize {
        self.con.level.map_or(0, |l| group_of(ctx, l))
    }

    /// The corners of the two halves of tet `t` (around the edge), the new node at `x`.
    fn halves_at(&self, lm: &LocalMesh, t: u32) -> [[[f64; 3]; 4]; 2] {
        halves(lm.tets[t as usize], self.a, self.b, NEW)
            .map(|h| h.map(|v| if v == NEW { self.x } else { lm.x[v as usize] }))
    }

    /// Whether every new tet is at or above the target quality, or at or above the worst tet
    /// around the edge where that is below the target.
    fn fits(&self, lm: &LocalMesh, ctx: &Ctx) -> bool {
        let floor = self
            .around
            .iter()
            .map(|&t| lm.q[t as usize])
            .fold(ctx.target, f64::min)
            .max(0.0);
        self.around.iter().all(|&t| {
            self.halves_at(lm, t)
                .iter()
                .all(|&c| ctx.quality(c) >= floor)
        })
    }
}

/// The split of edge `ab` at its midpoint projected onto the level set, if the two boundary
/// faces on it carry that level and the projection stays near the midpoint.
fn plan(lm: &LocalMesh, ctx: &Ctx, a: u32, b: u32) -> Option<Split> {
    let (free, other) = if lm.is_free(a) { (a, b) } else { (b, a) };
    let around = lm.edge_tets(free, other);
    let level = lm.con[a as usize].level?;
    let faces = faces_on_edge(lm, &around, a, b);
    if faces.len() != 2 {
        return None;
    }
    let (ua, ub) = (lm.u[a as usize], lm.u[b as usize]);
    let mid = midpoint(ua, ub);
    let value = ctx.levels[level as usize];
    let p = ctx.field.project(mid, value, 0b111, ctx.tol)?;
    if norm(sub(p, mid)) > REACH * norm(sub(ub, ua)) {
        return None;
    }
    // The halves of the two faces must stay near the level set (the midpoint's projection
    // can land across a fold of it).
    let halves_near = faces.iter().all(|f| {
        let before = f.tri.map(|v| lm.u[v as usize]);
        [a, b].into_iter().all(|from| {
            let after = f.tri.map(|v| if v == from { p } else { lm.u[v as usize] });
            embed::projected_face_keeps_level(ctx, f.label, before, after)
        })
    });
    if !halves_near {
        return None;
    }
    let con = Constraint {
        level: Some(level),
        interface: lm.con[a as usize].interface,
        ..Constraint::default()
    };
    let x = ctx.field.to_physical(p);
    let mut split = Split {
        a,
        b,
        p,
        x,
        value,
        con,
        around,
        faces,
        gain: 0.0,
    };
    // On an interface, the volume of the region below ([`LocalMesh::counted_region`]).
    let counted = lm.counted_region(a);
    for &t in &split.around {
        if counted.is_some_and(|r| lm.region[t as usize] != r) {
            continue;
        }
        split.gain -= lm.volume_of(t);
        for c in split.halves_at(lm, t) {
            split.gain += signed_volume(c[0], c[1], c[2], c[3]);
        }
    }
    Some(split)
}

/// Stands for the new node in [`halves`] before it has an id.
const NEW: u32 = u32::MAX;

/// The two halves of `tet` (around edge `ab`) cut through node `m`: `b` and then `a` replaced
/// by `m` (each keeps the orientation).
fn halves(tet: [u32; 4], a: u32, b: u32, m: u32) -> [[u32; 4]; 2] {
    let with = |from: u32| tet.map(|v| if v == from { m } else { v });
    [with(b), with(a)]
}

/// Makes split `s`.
fn apply(lm: &mut LocalMesh, ctx: &Ctx, s: Split) {
    let m = lm.add_vertex(s.p, s.value, s.con, ctx);
    for t in s.around {
        let (tet, region) = (lm.tets[t as usize], lm.region[t as usize]);
        lm.kill_tet(t);
        for h in halves(tet, s.a, s.b, m) {
            lm.add_tet(h, region);
        }
    }
    for f in s.faces {
        lm.remove_face(f.tri);
        for from in [s.b, s.a] {
            let tri = f.tri.map(|v| if v == from { m } else { v });
            lm.insert_face(BoundaryFace { tri, ..f });
        }
    }
}

/// The boundary faces on edge `ab` (`around`: the tets around it).
fn faces_on_edge(lm: &LocalMesh, around: &[u32], a: u32, b: u32) -> Vec<BoundaryFace> {
    let mut out: Vec<BoundaryFace> = Vec::new();
    for &t in around {
        for &c in &lm.tets[t as usize] {
            if c == a || c == b {
                continue;
            }
            if let Some(f) = lm.faces.get(&face_key([a, b, c])) {
                if !out.contains(f) {
                    out.push(*f);
                }
            }
        }
    }
    let label = lm.con[a as usize].level;
    if out.iter().any(|f| Some(f.label.index() as u8) != label) {
        out.clear();
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::improve::fixtures::{wavy_torus, wavy_torus_regions};
    use crate::improve::project::project_levels;
    use crate::improve::region::NEW_POINT;

    #[test]
    fn splits_keep_the_region_conforming_positive_and_on_its_levels() {
        let grid = wavy_torus();
        let (ctx, mut regions) = wavy_torus_regions(&grid, &[0, 1]);
        let mut splits = 0;
        for (r, lm) in regions.iter_mut().enumerate() {
            project_levels(lm, &ctx);
            let worst = (0..lm.tets.len())
                .filter(|&t| lm.alive[t])
                .map(|t| lm.q[t])
                .fold(ctx.target, f64::min);
            splits += split_sagging_edges(lm, &ctx, 0.03, None).0;
            let alive: Vec<usize> = (0..lm.tets.len()).filter(|&t| lm.alive[t]).collect();
            for &t in &alive {
                let q = ctx.quality(lm.corners(lm.tets[t]));
                assert!(
                    q > 0.0 && q >= worst,
                    "region {r} tet {t}: {q} (worst before {worst})"
                );
            }
            for v in (0..lm.u.len()).filter(|&v| lm.global[v] == NEW_POINT) {
                assert!(
                    !lm.off_its_level(v as u32, &ctx),
                    "region {r}: new node {v} off level"
                );
                assert!(
                    !lm.star[v].is_empty(),
                    "region {r}: new node {v} has no tets"
                );
            }
            // Each boundary face bounds exactly one alive tet, and all on the same side.
            let mut sides = Vec::new();
            for f in lm.faces.values() {
                let holders: Vec<usize> = alive
                    .iter()
                    .copied()
                    .filter(|&t| f.tri.iter().all(|v| lm.tets[t].contains(v)))
                    .collect();
                assert_eq!(
                    holders.len(),
                    1,
                    "region {r}: face {:?} in {holders:?}",
                    f.tri
                );
                let tet = lm.tets[holders[0]];
                let d = tet.iter().copied().find(|v| !f.tri.contains(v)).unwrap();
                let [a, b, c] = f.tri.map(|v| lm.x[v as usize]);
                sides.push(signed_volume(a, b, c, lm.x[d as usize]).signum());
            }
            assert!(
                sides.windows(2).all(|w| w[0] == w[1] && w[0] != 0.0),
                "region {r}: boundary faces oriented both ways"
            );
        }
        assert!(splits > 10, "{splits} splits");
    }

    #[test]
    fn only_edges_with_both_ends_marked_sagging_are_split() {
        let grid = wavy_torus();
        let (ctx, mut regions) = wavy_torus_regions(&grid, &[0, 1]);
        let points = regions
            .iter()
            .flat_map(|lm| lm.global.iter())
            .filter(|&&g| g != NEW_POINT)
            .max()
            .map_or(0, |&g| g as usize + 1);
        // Every other point of the mesh marked.
        let marks: Vec<bool> = (0..points).map(|g| g % 2 == 0).collect();
        let marked = |lm: &LocalMesh, v: u32| {
            lm.global[v as usize] != NEW_POINT && marks[lm.global[v as usize] as usize]
        };
        let (mut unrestricted, mut restricted) = (0, 0);
        for lm in regions.iter_mut() {
            project_levels(lm, &ctx);
            unrestricted += split_sagging_edges(&mut lm.clone(), &ctx, 0.03, None).0;
            let before = lm.u.len();
            restricted += split_sagging_edges(lm, &ctx, 0.03, Some(&marks)).0;
            for m in before..lm.u.len() {
                // The new node lies near the midpoint of two marked neighbours: the ends of
                // the edge it split.
                let mut nbrs: Vec<u32> = lm.star[m]
                    .iter()
                    .flat_map(|&t| lm.tets[t as usize])
                    .filter(|&w| w as usize != m && marked(lm, w))
                    .collect();
                nbrs.sort_unstable();
                nbrs.dedup();
                let um = lm.u[m];
                let split_of = |a: u32, b: u32| {
                    let (ua, ub) = (lm.u[a as usize], lm.u[b as usize]);
                    norm(sub(um, midpoint(ua, ub))) <= REACH * norm(sub(ub, ua))
                };
                let found = nbrs
                    .iter()
                    .enumerate()
                    .any(|(i, &a)| nbrs[i + 1..].iter().any(|&b| split_of(a, b)));
                assert!(found, "new node {m} splits no edge between marked points");
            }
        }
        assert!(
            restricted > 0 && restricted < unrestricted,
            "{restricted} splits with half the points marked, {unrestricted} with all"
        );
    }
}
