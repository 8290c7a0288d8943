//! Topological flips inside the domain: 2-3 (two tets sharing an interior face become three
//! around the edge joining their apexes) and 3-2 (the inverse). Both replace a triangulation
//! of a small convex region by another one with the same outer faces, so the underlying space,
//! the boundary and the labels are unchanged; a flip is applied only when every new tet is
//! positive and the worst new tet is better than the worst old one.

use super::region::{face_key, tet_edge, EdgeTets, LocalMesh};
use super::Ctx;

/// Tries the 2-3 flip of the face of tet `t` opposite its corner `i`; `around` holds the tets
/// around each edge of `t` ([`LocalMesh::tet_edge_tets`]). Returns whether it flipped.
pub fn try_flip23(
    lm: &mut LocalMesh,
    ctx: &Ctx,
    (t, i): (u32, usize),
    around: &[EdgeTets; 6],
) -> bool {
    let tet = lm.tets[t as usize];
    let p = tet[i];
    // [p, b, c, d] is an even permutation of `tet`.
    let [b, c, d] = opposite_face(tet, i);
    if ![b, c, d].iter().any(|&v| lm.is_free(v)) || is_boundary_face(lm, [b, c, d]) {
        return false;
    }
    let Some(s) = neighbour_across(lm, (t, i), around) else {
        return false;
    };
    let q = lm.tets[s as usize]
        .into_iter()
        .find(|v| ![b, c, d].contains(v))
        .expect("a tet has a fourth vertex");
    let new = [[p, b, c, q], [p, q, c, d], [p, b, q, d]];
    let old = [t, s];
    // Not when the edge pq exists already.
    let legal = |lm: &LocalMesh| {
        !lm.star[p as usize]
            .iter()
            .any(|&u| lm.tets[u as usize].contains(&q))
    };
    replace_if_better(lm, ctx, &old, &new, legal)
}

/// The other alive tet with the face of `t` opposite its corner `i`, among the tets around an
/// edge of that face (`around`, as [`try_flip23`] takes it). A face with a free corner has all
/// its tets in the region.
fn neighbour_across(lm: &LocalMesh, (t, i): (u32, usize), around: &[EdgeTets; 6]) -> Option<u32> {
    let tet = lm.tets[t as usize];
    let [j, k, l] = FACES[i];
    around[tet_edge(j.min(k), j.max(k))]
        .iter()
        .copied()
        .find(|&u| u != t && lm.tets[u as usize].contains(&tet[l]))
}

/// Tries the 3-2 flip of the edge `(p, q)` of tet `t`, whose tets are `edge_tets`
/// ([`LocalMesh::edge_tets`]). Returns whether it flipped.
pub fn try_flip32(
    lm: &mut LocalMesh,
    ctx: &Ctx,
    (t, p, q): (u32, u32, u32),
    edge_tets: &[u32],
) -> bool {
    if !lm.is_free(p) && !lm.is_free(q) {
        return false;
    }
    // The tets around the edge, and the vertices of its ring: three each, or no 3-2 flip.
    let &[u0, u1, u2] = edge_tets else {
        return false;
    };
    let around = [u0, u1, u2];
    let (mut ring, mut m) = ([0u32; 3], 0);
    for w in around.iter().flat_map(|&u| lm.tets[u as usize]) {
        if w != p && w != q && !ring[..m].contains(&w) {
            if m == 3 {
                return false;
            }
            ring[m] = w;
            m += 1;
        }
    }
    if m != 3 || ring.iter().any(|&w| is_boundary_face(lm, [p, q, w])) {
        // An open ring: the edge is on the boundary; or it is an edge of an interface.
        return false;
    }
    // Orient from tet t: [p, b, c, q] even permutation of it; d is the third ring vertex.
    let (b, c) = even_completion(lm.tets[t as usize], p, q);
    let d = ring.into_iter().find(|&v| v != b && v != c).unwrap_or(b);
    let new = [[p, b, c, d], [q, b, d, c]];
    // A face with no free corner may be a face of a tet outside the region, which the region
    // cannot see: the flip would make it a face of three tets (or more).
    if ![b, c, d].iter().any(|&v| lm.is_free(v)) {
        return false;
    }
    replace_if_better(lm, ctx, &around, &new, |lm| !face_exists(lm, [b, c, d]))
}

/// Replaces the tets `old` by `new` when every new tet is positive, the worst of them is
/// better than the worst old one and `legal` holds (asked after the qualities: nearly every
/// attempt fails on them, and the order does not change the answer).
fn replace_if_better(
    lm: &mut LocalMesh,
    ctx: &Ctx,
    old: &[u32],
    new: &[[u32; 4]],
    legal: impl FnOnce(&LocalMesh) -> bool,
) -> bool {
    // The old tets' qualities are kept up to date in `lm.q`; the first new tet that is not
    // better decides.
    let q_old = old
        .iter()
        .map(|&t| lm.q[t as usize])
        .fold(f64::INFINITY, f64::min);
    let floor = q_old.max(0.0);
    let mut q_new = [0.0; 3];
    for (q, &t) in q_new.iter_mut().zip(new) {
        *q = ctx.quality(lm.corners(t));
        if *q <= floor {
            return false;
        }
    }
    if !legal(lm) {
        return false;
    }
    // No face between two regions is removed, so the old tets are of one region.
    let region = lm.region[old[0] as usize];
    for &t in old {
        lm.kill_tet(t);
    }
    for (&t, &q) in new.iter().zip(&q_new) {
        lm.push_tet(t, q, region);
    }
    true
}

/// The face of `tet` opposite corner `i`, ordered so that `[tet[i], f0, f1, f2]` is an even
/// permutation of `tet`.
fn opposite_face(tet: [u32; 4], i: usize) -> [u32; 3] {
    FACES[i].map(|k| tet[k])
}

/// The corners of the face opposite each corner, ordered as [`opposite_face`] gives them.
const FACES: [[usize; 3]; 4] = [[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]];

/// Whether `f` is a domain-boundary face (its corners are checked first: that is cheaper
/// than the lookup, and most faces have a corner off the boundary).
fn is_boundary_face(lm: &LocalMesh, f: [u32; 3]) -> bool {
    f.iter().all(|&v| lm.on_boundary(v)) && lm.faces.contains_key(&face_key(f))
}

/// Whether some alive tet has the face `f`.
fn face_exists(lm: &LocalMesh, f: [u32; 3]) -> bool {
    lm.star[f[0] as usize]
        .iter()
        .any(|&u| f.iter().all(|v| lm.tets[u as usize].contains(v)))
}

/// The two vertices `(x, y)` of `tet` besides `p` and `q` such that `[p, x, y, q]` is an even
/// permutation of `tet`.
pub(super) fn even_completion(tet: [u32; 4], p: u32, q: u32) -> (u32, u32) {
    let (mut rest, mut n) = ([0u32; 2], 0);
    for v in tet {
        if v != p && v != q && n < 2 {
            rest[n] = v;
            n += 1;
        }
    }
    let cand = [p, rest[0], rest[1], q];
    if is_even_permutation(tet, cand) {
        (rest[0], rest[1])
    } else {
        (rest[1], rest[0])
    }
}

/// Whether `b` is an even permutation of `a` (same four distinct entries).
fn is_even_permutation(a: [u32; 4], b: [u32; 4]) -> bool {
    let pos = b.map(|x| a.iter().position(|&y| y == x).unwrap_or(0));
    let mut inversions = 0;
    for i in 0..4 {
        for j in i + 1..4 {
            if pos[i] > pos[j] {
                inversions += 1;
            }
        }
    }
    inversions % 2 == 0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::improve::fixtures::{wavy_torus, wavy_torus_regions};

    #[test]
    fn the_neighbour_across_a_face_is_the_other_tet_with_it() {
        let grid = wavy_torus();
        let (_, regions) = wavy_torus_regions(&grid, &[0]);
        let (mut inner, mut outer) = (0, 0);
        for lm in &regions {
            for t in 0..lm.tets.len() as u32 {
                let around = lm.tet_edge_tets(lm.tets[t as usize]);
                for i in 0..4 {
                    let f = opposite_face(lm.tets[t as usize], i);
                    if !f.iter().any(|&v| lm.is_free(v)) {
                        continue;
                    }
                    let all: Vec<u32> = (0..lm.tets.len() as u32)
                        .filter(|&u| u != t && f.iter().all(|v| lm.tets[u as usize].contains(v)))
                        .collect();
                    assert!(all.len() <= 1);
                    assert_eq!(neighbour_across(lm, (t, i), &around), all.first().copied());
                    if all.is_empty() {
                        outer += 1;
                    } else {
                        inner += 1;
                    }
                }
            }
        }
        assert!(inner > 1000 && outer > 100, "{inner} {outer}");
    }

    /// A 3-2 flip never makes a face whose corners are all frozen: a tet outside the region may
    /// have it already, unseen (a 3-2 flip made a face of three tets that way on the whole
    /// MNI152 T1 at 127.0135). Every 3-2 flip of the fixture's regions is tried on a copy; some
    /// must meet a ring of frozen corners.
    #[test]
    fn flip32_makes_no_face_of_frozen_corners_only() {
        let grid = wavy_torus();
        let (ctx, regions) = wavy_torus_regions(&grid, &[0, 1]);
        let mut frozen_rings = 0;
        for lm in &regions {
            for t in 0..lm.tets.len() as u32 {
                let tet = lm.tets[t as usize];
                let around = lm.tet_edge_tets(tet);
                for (i, j) in [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)] {
                    let (p, q) = (tet[i], tet[j]);
                    let edge = &around[tet_edge(i, j)];
                    if edge.len() != 3 || !(lm.is_free(p) || lm.is_free(q)) {
                        continue;
                    }
                    let ring: Vec<u32> = edge
                        .iter()
                        .flat_map(|&u| lm.tets[u as usize])
                        .filter(|&w| w != p && w != q)
                        .collect();
                    let all_frozen = ring.iter().all(|&w| !lm.is_free(w));
                    frozen_rings += usize::from(all_frozen);
                    let mut copy = lm.clone();
                    if try_flip32(&mut copy, &ctx, (t, p, q), edge) {
                        assert!(!all_frozen, "a 3-2 flip made a face of frozen corners");
                    }
                }
            }
        }
        assert!(frozen_rings > 0, "no 3-2 flip met a ring of frozen corners");
    }

    #[test]
    fn opposite_faces_are_even_completions() {
        let tet = [10, 11, 12, 13];
        for i in 0..4 {
            let f = opposite_face(tet, i);
            assert!(is_even_permutation(tet, [tet[i], f[0], f[1], f[2]]), "{i}");
        }
        let (x, y) = even_completion(tet, 12, 10);
        assert!(is_even_permutation(tet, [12, x, y, 10]));
    }
}
