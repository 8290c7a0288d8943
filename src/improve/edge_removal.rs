//! Edge removal (Shewchuk, "Two discrete optimization algorithms for the topological
//! improvement of tetrahedral meshes"; used by Klingner and Shewchuk's Stellar): the `k` tets
//! around an interior edge `ab`, whose other corners form a closed ring `r_0 … r_{k-1}`, are
//! replaced by the `2(k − 2)` tets coning `a` and `b` over a triangulation of the ring. The
//! triangulation is chosen by dynamic programming over the ring polygon so that its worst tet
//! is as good as possible; the removal is applied only when every new tet is positive and
//! better than the worst old one. `k = 3` is the 3-2 flip (`flip.rs`), `k = 4` the 4-4 flip.
//!
//! Why it keeps everything: the faces `a r_i r_{i+1}` and `b r_i r_{i+1}` bounding the old tets
//! are the outer faces of the new ones too, and every inner face of the new tets is shared by
//! two of them with opposite orientations; positive tets whose boundary is a polyhedron's tile
//! exactly that polyhedron. So the underlying space, the boundary and its labels (no face
//! around an interior edge is a boundary face) and every vertex stay.

use smallvec::{smallvec, SmallVec};

use super::flip::even_completion;
use super::region::{face_key, LocalMesh};
use super::Ctx;

/// Largest ring tried (Stellar's limit): the triangulations of a ring of `k` vertices have
/// `C(k, 3)` candidate triangles, two tets each.
pub const MAX_RING: usize = 7;

/// Up to [`MAX_RING`] items (ring vertices or tets around an edge), inline.
type RingVec<T> = SmallVec<[T; MAX_RING]>;

/// Tries to remove the edge `(a, b)` of tet `t`, whose tets are `edge_tets`
/// ([`LocalMesh::edge_tets`]), when 4 to [`MAX_RING`] tets surround it. Returns whether it
/// did.
pub fn try_remove_edge(
    lm: &mut LocalMesh,
    ctx: &Ctx,
    (t, a, b): (u32, u32, u32),
    edge_tets: &[u32],
) -> bool {
    if !lm.is_free(a) && !lm.is_free(b) {
        return false; // then the tets around the edge may reach out of the region
    }
    let Some((ring, around)) = ring_around(lm, (t, a, b), edge_tets) else {
        return false;
    };
    let k = ring.len();
    if k < 4 {
        return false;
    }
    let floor = around
        .iter()
        .map(|&u| lm.q[u as usize])
        .fold(f64::INFINITY, f64::min)
        .max(0.0);
    let Some(tris) = best_triangulation(lm, ctx, [a, b], &ring, floor) else {
        return false;
    };
    // A diagonal of the ring that is an edge already would be doubled. Tested after the
    // triangulation, which fails far more often (the same result, less work).
    if diagonal_is_edge(lm, &ring) {
        return false;
    }
    // No face around the edge is an interface's ([`ring_around`]): one region.
    let region = lm.region[around[0] as usize];
    for &u in &around {
        lm.kill_tet(u);
    }
    for tet in tris.into_iter().flat_map(|tri| cone(a, b, &ring, tri)) {
        lm.add_tet(tet, region);
    }
    true
}

/// The two new tets over the ring triangle `i < j < l`: `[a, r_i, r_j, r_l]` and
/// `[b, r_i, r_l, r_j]`, positive when the ring runs so that `[a, b, r_i, r_{i+1}]` is (as
/// vertex ids, or as their positions).
fn cone<T: Copy>(a: T, b: T, ring: &[T], [i, j, l]: [usize; 3]) -> [[T; 4]; 2] {
    [
        [a, ring[i], ring[j], ring[l]],
        [b, ring[i], ring[l], ring[j]],
    ]
}

/// The ring of edge `(a, b)` (whose tets are `edge_tets`) around from tet `t`, ordered so
/// that `[a, b, r_i, r_{i+1}]` is positive, and the tets around the edge
/// (`[a, b, r_i, r_{i+1}]` at `i`); `None` when the ring is open (the edge is on the boundary
/// or leaves the region), the edge is on an interface between regions, or the ring is longer
/// than [`MAX_RING`].
fn ring_around(
    lm: &LocalMesh,
    (t, a, b): (u32, u32, u32),
    edge_tets: &[u32],
) -> Option<(RingVec<u32>, RingVec<u32>)> {
    if edge_tets.len() > MAX_RING {
        return None;
    }
    // [a, x, y, b] even, so [a, b, x, y] is too.
    let (x, y) = even_completion(lm.tets[t as usize], a, b);
    let mut ring: RingVec<u32> = smallvec![x, y];
    let mut around: RingVec<u32> = smallvec![t];
    while around.len() < edge_tets.len() {
        let (prev, last) = (ring[ring.len() - 2], ring[ring.len() - 1]);
        let next = edge_tets.iter().copied().find(|&u| {
            let tet = lm.tets[u as usize];
            tet.contains(&last) && !tet.contains(&prev)
        })?;
        let z = lm.tets[next as usize]
            .into_iter()
            .find(|&w| w != a && w != b && w != last)?;
        around.push(next);
        if z == ring[0] {
            break;
        }
        ring.push(z);
    }
    // Closed: as many ring vertices as tets, and the last tet closes onto the first vertex.
    let closes =
        ring.len() == around.len() && lm.tets[around[around.len() - 1] as usize].contains(&ring[0]);
    (closes && !on_interface(lm, [a, b], &ring)).then_some((ring, around))
}

/// Whether the closed ring's edge `(a, b)` is an edge of an interface between regions: one
/// of the faces around it is a face of the boundary's map.
fn on_interface(lm: &LocalMesh, [a, b]: [u32; 2], ring: &[u32]) -> bool {
    lm.on_boundary(a)
        && lm.on_boundary(b)
        && ring
            .iter()
            .any(|&w| lm.on_boundary(w) && lm.faces.contains_key(&face_key([a, b, w])))
}

/// Whether some diagonal of the polygon `ring` is an edge of the region.
fn diagonal_is_edge(lm: &LocalMesh, ring: &[u32]) -> bool {
    let k = ring.len();
    (0..k).any(|i| (i + 2..k).any(|j| (i, j) != (0, k - 1) && has_edge(lm, ring[i], ring[j])))
}

/// Whether some tet of the region has the edge `(v, w)`.
fn has_edge(lm: &LocalMesh, v: u32, w: u32) -> bool {
    lm.star[v as usize]
        .iter()
        .any(|&u| lm.tets[u as usize].contains(&w))
}

/// The triangulation of `ring` whose cones from `a` and `b` ([`cone`]) have the best worst
/// quality, if that is above `floor`: Klincsek's dynamic programme over the polygon's
/// sub-chains, each candidate triangle evaluated once (and only as far as its first tet at or
/// below `floor`). Ties go to the first middle vertex.
fn best_triangulation(
    lm: &LocalMesh,
    ctx: &Ctx,
    [a, b]: [u32; 2],
    ring: &[u32],
    floor: f64,
) -> Option<RingVec<[usize; 3]>> {
    let k = ring.len();
    // The corners' positions, gathered once: the programme evaluates up to 2 C(k, 3) tets.
    let (xa, xb) = (lm.x[a as usize], lm.x[b as usize]);
    let xr: RingVec<[f64; 3]> = ring.iter().map(|&v| lm.x[v as usize]).collect();
    let tri_quality = |i: usize, j: usize, l: usize| -> f64 {
        let mut worst = f64::INFINITY;
        for p in cone(xa, xb, &xr, [i, j, l]) {
            let q = ctx.quality(p);
            if q <= floor {
                return f64::NEG_INFINITY;
            }
            worst = worst.min(q);
        }
        worst
    };
    // best[i][l]: the best worst quality over the triangulations of the chain r_i … r_l
    // (closed by the chord r_i r_l); split[i][l]: the apex of the triangle on that chord.
    let mut best = [[f64::INFINITY; MAX_RING]; MAX_RING];
    let mut split = [[0usize; MAX_RING]; MAX_RING];
    for len in 2..k {
        for i in 0..k - len {
            let l = i + len;
            let mut top = (f64::NEG_INFINITY, i + 1);
            for j in i + 1..l {
                let lower = best[i][j].min(best[j][l]);
                if lower <= top.0 || lower <= floor {
                    continue;
                }
                let q = lower.min(tri_quality(i, j, l));
                if q > top.0 {
                    top = (q, j);
                }
            }
            (best[i][l], split[i][l]) = top;
        }
    }
    if best[0][k - 1] <= floor {
        return None;
    }
    let mut tris = RingVec::new();
    let mut chords: RingVec<(usize, usize)> = smallvec![(0, k - 1)];
    while let Some((i, l)) = chords.pop() {
        if l - i < 2 {
            continue;
        }
        let j = split[i][l];
        tris.push([i, j, l]);
        chords.push((j, l));
        chords.push((i, j));
    }
    Some(tris)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::improve::fixtures::{wavy_torus, wavy_torus_regions};
    use crate::improve::region::face_key;
    use std::collections::{BTreeSet, HashMap};

    /// The faces of the alive tets of `lm` that only one of them has (the region's outside),
    /// after checking that no face has more than two.
    fn outer_faces(lm: &LocalMesh) -> BTreeSet<[u32; 3]> {
        let mut count: HashMap<[u32; 3], usize> = HashMap::new();
        for (t, tet) in lm.tets.iter().enumerate() {
            if lm.alive[t] {
                for skip in 0..4 {
                    let f: Vec<u32> = (0..4).filter(|&i| i != skip).map(|i| tet[i]).collect();
                    *count.entry(face_key([f[0], f[1], f[2]])).or_default() += 1;
                }
            }
        }
        assert!(
            count.values().all(|&c| c <= 2),
            "a face in more than two tets"
        );
        count
            .into_iter()
            .filter(|&(_, c)| c == 1)
            .map(|(f, _)| f)
            .collect()
    }

    fn alive_volume(lm: &LocalMesh) -> (usize, f64) {
        let alive = (0..lm.tets.len()).filter(|&t| lm.alive[t]);
        (
            alive.clone().count(),
            alive.map(|t| lm.volume_of(t as u32)).sum(),
        )
    }

    #[test]
    fn a_removed_edge_leaves_better_positive_tets_tiling_the_same_ring() {
        let grid = wavy_torus();
        let (ctx, mut regions) = wavy_torus_regions(&grid, &[0, 1]);
        let mut by_ring = [0usize; MAX_RING + 1];
        for lm in &mut regions {
            for t in 0..lm.tets.len() as u32 {
                for (i, j) in [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)] {
                    if !lm.alive[t as usize] {
                        break;
                    }
                    let tet = lm.tets[t as usize];
                    let (a, b) = (tet[i], tet[j]);
                    let edge_tets = lm.edge_tets(a, b);
                    let Some((ring, around)) = ring_around(lm, (t, a, b), &edge_tets) else {
                        continue;
                    };
                    let worst = around.iter().map(|&u| lm.q[u as usize]).fold(1.0, f64::min);
                    let (outer, (n, volume)) = (outer_faces(lm), alive_volume(lm));
                    let first_new = lm.tets.len();
                    if !try_remove_edge(lm, &ctx, (t, a, b), &edge_tets) {
                        continue;
                    }
                    let k = ring.len();
                    by_ring[k] += 1;
                    assert!((4..=MAX_RING).contains(&k));
                    assert_eq!(lm.tets.len() - first_new, 2 * (k - 2));
                    for u in first_new..lm.tets.len() {
                        let q = ctx.quality(lm.corners(lm.tets[u]));
                        assert!(
                            lm.volume_of(u as u32) > 0.0 && q > worst.max(0.0),
                            "{q} {worst}"
                        );
                        assert_eq!(q, lm.q[u]);
                    }
                    let (n_after, volume_after) = alive_volume(lm);
                    assert_eq!(n_after, n - k + 2 * (k - 2));
                    assert!(
                        (volume_after - volume).abs() <= 1e-9 * volume,
                        "volume changed"
                    );
                    assert_eq!(outer_faces(lm), outer, "the region's outside changed");
                    assert!(!has_edge(lm, a, b), "the edge is still there");
                }
            }
        }
        assert!(
            by_ring[4] > 10 && by_ring[5] > 10,
            "removals by ring size: {by_ring:?}"
        );
    }
}
