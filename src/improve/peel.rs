//! Peeling a boundary tet: a tet `abcd` whose faces `abc` and `abd` are boundary faces of one
//! level set (its other two faces inside) is removed, and `acd` and `bcd` become boundary faces
//! of that level. On a curved level set four boundary vertices can make a flat tet that no move,
//! flip or collapse raises: every corner already lies on the level set, and the tet spans the
//! surface's curvature. Peeling it flips the surface edge `ab` to `cd`.
//!
//! Why it keeps everything:
//! * Topology: the tet meets the rest of the mesh exactly in the disc `acd ∪ bcd` when no
//!   other tet has the edge `ab` and `cd` is not a boundary edge (else the rest would pinch
//!   at `cd`); removing a ball glued along a disc of its boundary is a homeomorphism.
//! * Boundary: every corner of the new faces is a corner of `abc` or `abd`, so on the level
//!   set already; no vertex moves, and no box face is touched.
//! * Elements: the other tets are unchanged, so none gets worse.
//!
//! The domain loses the tet's volume; it is booked as drift of `a` and `b` (the vertices
//! whose surface moved), which the last stage gives back ([`super::restore`]).

use super::collapse::{boundary_faces_at, face_without};
use super::flip::opposite_face;
use super::local::{face_key, BoundaryFace, LocalMesh};
use crate::mesh::BoundaryLabel;

/// Peels tet `t` if it is a boundary tet that may be peeled (see the module). Returns whether
/// it did.
pub fn try_peel(lm: &mut LocalMesh, t: u32) -> bool {
    let tet = lm.tets[t as usize];
    if !tet.iter().all(|&v| lm.is_free(v) && lm.on_boundary(v)) {
        return false;
    }
    let Some((label, [ia, ib])) = two_level_faces(lm, tet) else {
        return false;
    };
    let (a, b) = (tet[ia], tet[ib]);
    let mut others = tet.into_iter().filter(|&v| v != a && v != b);
    let (Some(c), Some(d)) = (others.next(), others.next()) else {
        return false;
    };
    if lm.edge_tets(a, b).len() != 1 || boundary_faces_at(lm, c).iter().any(|f| f.tri.contains(&d))
    {
        return false;
    }
    let volume = lm.volume_of(t);
    for i in 0..4 {
        if i != ia && i != ib {
            lm.remove_face(face_without(tet, i));
        }
    }
    // The faces opposite `a` and `b` become boundary faces, outward from the rest of the mesh:
    // turned to face into the removed tet.
    for i in [ia, ib] {
        let [f0, f1, f2] = opposite_face(tet, i);
        lm.insert_face(BoundaryFace {
            tri: [f0, f2, f1],
            label,
        });
    }
    lm.kill_tet(t);
    lm.drift[a as usize] -= 0.5 * volume;
    lm.drift[b as usize] -= 0.5 * volume;
    true
}

/// If exactly two faces of `tet` are boundary faces, both of one level set: that level and the
/// two corners they share (as positions in `tet`).
fn two_level_faces(lm: &LocalMesh, tet: [u32; 4]) -> Option<(BoundaryLabel, [usize; 2])> {
    let mut found: [Option<(usize, BoundaryLabel)>; 2] = [None; 2];
    let mut n = 0;
    for skip in 0..4 {
        if let Some(f) = lm.faces.get(&face_key(face_without(tet, skip))) {
            if n == 2 {
                return None;
            }
            found[n] = Some((skip, f.label));
            n += 1;
        }
    }
    let (Some((s0, l0)), Some((s1, l1))) = (found[0], found[1]) else {
        return None;
    };
    if l0 != l1 || l0 == BoundaryLabel::Box {
        return None;
    }
    // The faces skip corners s0 and s1; they share the other two.
    let mut shared = (0..4).filter(|&i| i != s0 && i != s1);
    Some((l0, [shared.next()?, shared.next()?]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::signed_volume;
    use crate::improve::fixtures::{improved_wavy_torus_regions, wavy_torus};
    use std::collections::BTreeMap;

    /// `f` rotated to start at its smallest vertex (the same oriented triangle).
    fn rotated(f: [u32; 3]) -> [u32; 3] {
        let i = (0..3).min_by_key(|&i| f[i]).unwrap_or(0);
        [f[i], f[(i + 1) % 3], f[(i + 2) % 3]]
    }

    /// The faces of the alive tets that no other alive tet has (oriented outward), by key.
    fn outer_faces(lm: &LocalMesh) -> BTreeMap<[u32; 3], [u32; 3]> {
        let mut count: BTreeMap<[u32; 3], ([u32; 3], usize)> = BTreeMap::new();
        for t in (0..lm.tets.len()).filter(|&t| lm.alive[t]) {
            for i in 0..4 {
                let f = opposite_face(lm.tets[t], i);
                count.entry(face_key(f)).or_insert((f, 0)).1 += 1;
            }
        }
        count
            .into_iter()
            .filter(|(_, (_, n))| *n == 1)
            .map(|(k, (f, _))| (k, rotated(f)))
            .collect()
    }

    fn boundary_edge_faces(lm: &LocalMesh, a: u32, b: u32) -> usize {
        lm.faces
            .keys()
            .filter(|k| k.contains(&a) && k.contains(&b))
            .count()
    }

    #[test]
    fn a_peeled_tet_leaves_the_rest_with_the_surface_flipped_across_it() {
        let grid = wavy_torus();
        let mut regions = improved_wavy_torus_regions(&grid, &[0, 1]);
        let (mut peeled, mut refused) = (0, 0);
        for lm in &mut regions {
            for t in 0..lm.tets.len() as u32 {
                let tet = lm.tets[t as usize];
                let candidate = lm.alive[t as usize]
                    && tet.iter().all(|&v| lm.is_free(v))
                    && two_level_faces(lm, tet).is_some();
                let (outer, faces) = (outer_faces(lm), lm.faces.clone());
                let (volume, drift) = (lm.volume_of(t), lm.drift.iter().sum::<f64>());
                if !try_peel(lm, t) {
                    if candidate {
                        // Refused only where the rest would pinch.
                        let (_, [ia, ib]) = two_level_faces(lm, tet).unwrap();
                        let (a, b) = (tet[ia], tet[ib]);
                        let [c, d] = [0, 1, 2, 3]
                            .into_iter()
                            .filter(|&i| i != ia && i != ib)
                            .map(|i| tet[i])
                            .collect::<Vec<_>>()[..]
                        else {
                            unreachable!()
                        };
                        assert!(
                            lm.edge_tets(a, b).len() > 1 || boundary_edge_faces(lm, c, d) > 0,
                            "refused a tet that may be peeled"
                        );
                        refused += 1;
                    }
                    continue;
                }
                assert!(candidate, "peeled a tet without two faces on one level");
                peeled += 1;
                assert!(!lm.alive[t as usize]);
                let after = outer_faces(lm);
                // The region's outside lost the two boundary faces and gained the two inner
                // ones, turned round; nothing else changed.
                let (_, [ia, ib]) = {
                    let mut shared =
                        (0..4).filter(|&i| faces.contains_key(&face_key(face_without(tet, i))));
                    let s: Vec<usize> = (&mut shared).collect();
                    assert_eq!(s.len(), 2);
                    let rest: Vec<usize> = (0..4).filter(|i| !s.contains(i)).collect();
                    ((), [rest[0], rest[1]])
                };
                let mut expected = outer.clone();
                for i in 0..4 {
                    let f = opposite_face(tet, i);
                    if i == ia || i == ib {
                        expected.insert(face_key(f), rotated([f[0], f[2], f[1]]));
                    } else {
                        expected.remove(&face_key(f));
                    }
                }
                assert!(
                    after == expected,
                    "the region's outside is not the flipped one"
                );
                for i in [ia, ib] {
                    let key = face_key(opposite_face(tet, i));
                    let f = lm.faces[&key];
                    assert_eq!(rotated(f.tri), expected[&key]);
                    // Outward: the rest of the mesh lies on its negative side.
                    let x = |v: u32| lm.x[v as usize];
                    assert!(signed_volume(x(f.tri[0]), x(f.tri[1]), x(f.tri[2]), x(tet[i])) > 0.0);
                }
                assert_eq!(lm.faces.len(), faces.len());
                // Every boundary edge of the tet's corners still has two boundary faces.
                for (i, j) in [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)] {
                    let n = boundary_edge_faces(lm, tet[i], tet[j]);
                    assert!(n == 0 || n == 2, "edge in {n} boundary faces");
                }
                let drift_after: f64 = lm.drift.iter().sum();
                assert!((drift_after - (drift - volume)).abs() <= 1e-12 * (1.0 + volume));
            }
        }
        assert!(
            peeled > 0 && refused > 0,
            "peeled {peeled}, refused {refused}"
        );
    }
}
