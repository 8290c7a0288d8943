//! The boundary surface does not meet itself: every pair of boundary triangles whose boxes
//! share a bucket is tested exactly. Triangles without a common corner must not meet at
//! all; ones sharing a corner must meet only there (no crossing through it, no coplanar
//! overlap); ones sharing an edge must not fold onto each other.

use rayon::prelude::*;

use super::buckets::{bbox, Buckets};
use super::predicates::{
    coplanar, fold_over_edge, meet_beyond_vertex, projection_axis, triangles_meet,
};
use super::{ProblemKind, Problems};

type P = [f64; 3];

/// How two boundary triangles meet where they must not.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Contact {
    /// Coplanar, overlapping in area (a fold, or two tets glued without a common face).
    Overlap,
    /// Crossing or touching.
    Crossing,
}

/// Whether two boundary triangles with corner identities `ids` (equal ids: the same point)
/// and corners `pos` meet where they must not (exactly): anywhere, sharing no corner; beyond
/// it, sharing one; folded onto each other, sharing an edge; always, sharing all three.
pub(crate) fn triangles_cross<T: PartialEq>(ids: [&[T; 3]; 2], pos: [&[P; 3]; 2]) -> bool {
    contact(ids, pos).is_some()
}

/// How triangles `i` and `j` meet, if they meet where they must not.
fn contact<T: PartialEq>(ids: [&[T; 3]; 2], pos: [&[P; 3]; 2]) -> Option<Contact> {
    let [a, b] = ids;
    let [s, t] = pos;
    let mut pairs = [(0, 0); 3];
    let mut n = 0;
    for i in 0..3 {
        for j in 0..3 {
            if a[i] == b[j] && n < 3 {
                pairs[n] = (i, j);
                n += 1;
            }
        }
    }
    let shared = &pairs[..n];
    if n == 0 && boxes_apart(s, t) {
        return None;
    }
    let kind = |flat: bool| {
        if flat {
            Contact::Overlap
        } else {
            Contact::Crossing
        }
    };
    match *shared {
        [] => triangles_meet(s, t).then(|| kind(coplanar(s, t))),
        [(i, j)] => {
            let v = s[i];
            let far_s = [s[(i + 1) % 3], s[(i + 2) % 3]];
            let far_t = [t[(j + 1) % 3], t[(j + 2) % 3]];
            meet_beyond_vertex(v, far_s, far_t).then(|| kind(coplanar(s, t)))
        }
        [(i0, j0), (i1, j1)] => {
            let a_far = s[3 - i0 - i1];
            let b_far = t[3 - j0 - j1];
            fold_over_edge(s[i0], s[i1], a_far, b_far).then_some(Contact::Overlap)
        }
        _ => Some(Contact::Overlap),
    }
}

/// Whether the bounding boxes of `s` and `t` are apart along some axis (then the triangles
/// cannot meet).
#[inline]
fn boxes_apart(s: &[P; 3], t: &[P; 3]) -> bool {
    (0..3).any(|k| {
        let lo = |x: &[P; 3]| x[0][k].min(x[1][k]).min(x[2][k]);
        let hi = |x: &[P; 3]| x[0][k].max(x[1][k]).max(x[2][k]);
        hi(s) < lo(t) || hi(t) < lo(s)
    })
}

/// Every pair of triangles of `tris` (corner ids and positions) sharing a bucket that meet
/// where they must not ([`triangles_cross`]), each pair once, `i < j`, sorted; flat triangles
/// take no part.
pub(crate) fn contacts(
    ids: &[[u32; 3]],
    tris: &[[P; 3]],
    buckets: &Buckets,
) -> Vec<(u32, u32, Contact)> {
    let boxes: Vec<[P; 2]> = tris.par_iter().map(bbox).collect();
    let flat: Vec<bool> = tris
        .par_iter()
        .map(|t| projection_axis(t).is_none())
        .collect();
    let overlap = |i: usize, j: usize| {
        let (p, q) = (&boxes[i], &boxes[j]);
        (0..3).all(|k| p[0][k] <= q[1][k] && q[0][k] <= p[1][k])
    };
    let found: Vec<Vec<(u32, u32, Contact)>> = (0..buckets.len())
        .into_par_iter()
        .map(|bk| {
            let items = buckets.items(bk);
            let mut hits = Vec::new();
            for (x, &i) in items.iter().enumerate() {
                let (i, ri) = (i as usize, &buckets.ranges[i as usize]);
                if flat[i] {
                    continue;
                }
                for &j in &items[x + 1..] {
                    let j = j as usize;
                    if flat[j] || !overlap(i, j) {
                        continue;
                    }
                    // Each pair once: in the lowest bucket the two share.
                    let rj = &buckets.ranges[j];
                    let lo = [0, 1, 2].map(|k| ri[0][k].max(rj[0][k]));
                    if buckets.index(lo) != bk {
                        continue;
                    }
                    if let Some(c) = contact([&ids[i], &ids[j]], [&tris[i], &tris[j]]) {
                        hits.push((i as u32, j as u32, c));
                    }
                }
            }
            hits
        })
        .collect();
    let mut hits: Vec<(u32, u32, Contact)> = found.into_iter().flatten().collect();
    hits.sort_unstable_by_key(|h| (h.0, h.1));
    hits
}

/// Tests every pair of triangles of `tris` (corner ids and positions) that share a bucket;
/// `tet[i]` is the tet of triangle `i`, used to name the pair.
pub(crate) fn self_intersections(
    ids: &[[u32; 3]],
    tris: &[[P; 3]],
    tet: &[u32],
    buckets: &Buckets,
    problems: &mut Problems,
) {
    for (i, j, c) in contacts(ids, tris, buckets) {
        let kind = match c {
            Contact::Overlap => ProblemKind::BoundaryOverlap,
            Contact::Crossing => ProblemKind::BoundarySelfIntersection,
        };
        problems.add(
            kind,
            vec![tet[i as usize] as usize, tet[j as usize] as usize],
        );
    }
}
