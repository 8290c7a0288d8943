//! Conformity and orientation: every tet positive (exactly), no duplicate tets, every face in
//! one tet (the boundary) or two (on opposite sides), and the boundary faces the mesh's
//! labelled triangles.

use rayon::prelude::*;

use super::predicates::orient;
use super::{ProblemKind, Problems};
use crate::mesh::TetMesh;

/// The faces of a tet `[a, b, c, d]` as corner slots, each ordered so that its normal by the
/// right-hand rule points away from the fourth corner when the tet is positive.
pub(crate) const FACES: [[usize; 3]; 4] = [[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]];

/// Tets per parallel block (blocks are combined in order: deterministic).
const BLOCK: usize = 1 << 14;

/// A face of the mesh met by one tet only, oriented out of that tet.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct BoundaryFace {
    /// Corner ids, outward.
    pub(crate) tri: [u32; 3],
    /// The tet it bounds.
    pub(crate) tet: u32,
}

/// Checks every tet's orientation with the exact predicate: negative tets are inverted, flat
/// ones (or ones with a repeated corner) degenerate.
pub(crate) fn orientation(mesh: &TetMesh, problems: &mut Problems) {
    let p = &mesh.points;
    let found: Vec<(Vec<usize>, Vec<usize>)> = mesh
        .tets
        .par_chunks(BLOCK)
        .enumerate()
        .map(|(b, c)| {
            let (mut inv, mut flat) = (Vec::new(), Vec::new());
            for (i, t) in c.iter().enumerate() {
                let [a, b2, c2, d] = t.map(|v| p[v as usize]);
                match orient(a, b2, c2, d) {
                    1 => {}
                    -1 => inv.push(b * BLOCK + i),
                    _ => flat.push(b * BLOCK + i),
                }
            }
            (inv, flat)
        })
        .collect();
    for (inv, flat) in found {
        for t in inv {
            problems.add(ProblemKind::InvertedTet, vec![t]);
        }
        for t in flat {
            problems.add(ProblemKind::DegenerateTet, vec![t]);
        }
    }
}

/// Sorted corners of a triangle, packed into the upper 96 bits; the parity of the sort
/// (whether it took an odd permutation).
pub(crate) fn face_key(f: [u32; 3]) -> (u128, bool) {
    let mut s = f;
    let mut odd = false;
    for (i, j) in [(0, 1), (1, 2), (0, 1)] {
        if s[i] > s[j] {
            s.swap(i, j);
            odd = !odd;
        }
    }
    (
        (s[0] as u128) << 96 | (s[1] as u128) << 64 | (s[2] as u128) << 32,
        odd,
    )
}

/// The oriented face `f` of tet `t`.
pub(crate) fn tet_face(t: &[u32; 4], f: usize) -> [u32; 3] {
    FACES[f].map(|k| t[k])
}

/// Groups the tets' faces: reports duplicate tets, faces in three or more tets and faces whose
/// two tets lie on the same side, and returns the faces of one tet (the boundary), in key
/// order. Precondition: fewer than 2^30 tets, every index in range.
pub(crate) fn faces(mesh: &TetMesh, problems: &mut Problems) -> Vec<BoundaryFace> {
    let tets = &mesh.tets;
    let keys = sorted_face_keys(tets);
    let starts = group_starts(&keys);
    let groups: Vec<(Group, Vec<(usize, usize)>)> = starts
        .par_iter()
        .enumerate()
        .map(|(g, &s)| {
            let e = starts.get(g + 1).copied().unwrap_or(keys.len());
            judge_group(tets, &keys[s..e])
        })
        .collect();
    gather_groups(groups, problems)
}

/// Every tet's four faces as one key each, sorted: the face's [`face_key`] with the tet's
/// index and the face's slot in the low 32 bits.
fn sorted_face_keys(tets: &[[u32; 4]]) -> Vec<u128> {
    let mut keys: Vec<u128> = tets
        .par_iter()
        .enumerate()
        .flat_map_iter(|(t, tet)| {
            (0..4).map(move |f| face_key(tet_face(tet, f)).0 | (t as u128) << 2 | f as u128)
        })
        .collect();
    keys.par_sort_unstable();
    keys
}

/// The starts of the groups of equal faces in the sorted `keys`, found in parallel.
fn group_starts(keys: &[u128]) -> Vec<usize> {
    const HIGH: u128 = !0u128 << 32;
    (0..keys.len())
        .into_par_iter()
        .filter(|&i| i == 0 || keys[i] & HIGH != keys[i - 1] & HIGH)
        .collect()
}

/// What one group of equal faces says (after setting aside duplicate tets).
enum Group {
    Boundary(BoundaryFace),
    Pair,
    SameSide(usize, usize),
    Many(Vec<usize>),
}

/// Judges one group of equal faces (`group`: their keys), and lists the duplicate tets met in
/// it as (earlier tet, later tet).
fn judge_group(tets: &[[u32; 4]], group: &[u128]) -> (Group, Vec<(usize, usize)>) {
    let entry = |k: u128| -> (usize, usize) { ((k as u32 >> 2) as usize, (k & 3) as usize) };
    let sorted_tet = |t: usize| {
        let mut s = tets[t];
        s.sort_unstable();
        s
    };
    // Members in tet order; a tet with the corners of an earlier member is a duplicate
    // and set aside, so the face is judged as if it were not there.
    let mut members: Vec<(usize, usize)> = Vec::with_capacity(group.len());
    let mut dups = Vec::new();
    for &k in group {
        let (t, f) = entry(k);
        match members.iter().find(|m| sorted_tet(m.0) == sorted_tet(t)) {
            Some(m) => dups.push((m.0, t)),
            None => members.push((t, f)),
        }
    }
    let group = match members[..] {
        [(t, f)] => Group::Boundary(BoundaryFace {
            tri: tet_face(&tets[t], f),
            tet: t as u32,
        }),
        [(t, f), (u, h)] => {
            let (_, p) = face_key(tet_face(&tets[t], f));
            let (_, q) = face_key(tet_face(&tets[u], h));
            if p != q {
                Group::Pair
            } else {
                Group::SameSide(t, u)
            }
        }
        _ => Group::Many(members.iter().map(|m| m.0).collect()),
    };
    (group, dups)
}

/// Reports the groups' problems in group order, then the duplicate tets (sorted, each pair
/// once); returns the boundary faces.
fn gather_groups(
    groups: Vec<(Group, Vec<(usize, usize)>)>,
    problems: &mut Problems,
) -> Vec<BoundaryFace> {
    let mut boundary = Vec::new();
    let mut dups: Vec<(usize, usize)> = Vec::new();
    for (g, d) in groups {
        dups.extend(d);
        match g {
            Group::Boundary(b) => boundary.push(b),
            Group::Pair => {}
            Group::SameSide(a, b) => problems.add(ProblemKind::TetsOnSameSideOfFace, vec![a, b]),
            Group::Many(ts) => problems.add(ProblemKind::FaceInThreeOrMoreTets, ts),
        }
    }
    dups.sort_unstable();
    dups.dedup();
    for (a, b) in dups {
        problems.add(ProblemKind::DuplicateTet, vec![a, b]);
    }
    boundary
}

/// Compares the faces of one tet with the mesh's labelled boundary triangles as sets, and
/// their orientations. Precondition: `boundary_labels` as long as `boundary`.
pub(crate) fn labelled(mesh: &TetMesh, faces: &[BoundaryFace], problems: &mut Problems) {
    // Faces are in key order already; the labelled ones are sorted here, with their ids.
    let derived: Vec<(u128, bool, usize)> = faces
        .iter()
        .map(|f| {
            let (k, odd) = face_key(f.tri);
            (k, odd, f.tet as usize)
        })
        .collect();
    let mut listed: Vec<(u128, bool, usize)> = mesh
        .boundary
        .par_iter()
        .enumerate()
        .map(|(i, &t)| {
            let (k, odd) = face_key(t);
            (k, odd, i)
        })
        .collect();
    listed.par_sort_unstable();
    let (mut i, mut j) = (0, 0);
    while i < derived.len() || j < listed.len() {
        let d = derived.get(i);
        let l = listed.get(j);
        match (d, l) {
            (Some(d), Some(l)) if d.0 == l.0 => {
                if d.1 != l.1 {
                    problems.add(ProblemKind::BoundaryTriangleInward, vec![l.2]);
                }
                i += 1;
                j += 1;
            }
            (Some(d), l) if l.is_none_or(|l| d.0 < l.0) => {
                problems.add(ProblemKind::BoundaryFaceUnlisted, vec![d.2]);
                i += 1;
            }
            (_, Some(l)) => {
                problems.add(ProblemKind::ListedFaceNotBoundary, vec![l.2]);
                j += 1;
            }
            (_, None) => i += 1,
        }
    }
}
