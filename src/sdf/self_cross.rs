//! Where a triangle surface crosses itself: pairs of triangles that meet other than along the
//! corners and edges they share, by exact predicates ([`crate::check::triangles_cross`]).
//! The triangles are sorted into cubic buckets about as wide as a typical triangle, and each
//! triangle is tested against the later ones in its buckets, in parallel.

use rayon::prelude::*;
use rustc_hash::FxHashMap;

use crate::check::triangles_cross;

type P = [f64; 3];

/// The number of pairs of triangles that cross or overlap each other; triangles flagged in
/// `skip` (degenerate ones) take no part.
pub fn crossing_pairs(points: &[P], triangles: &[[u32; 3]], skip: &[bool]) -> usize {
    let corners = |t: &[u32; 3]| t.map(|i| points[i as usize]);
    let boxes: Vec<[P; 2]> = triangles.par_iter().map(|t| bounds(&corners(t))).collect();
    let width = bucket_width(&boxes, skip);
    let cell = |x: f64| (x / width).floor().clamp(-1e6, 1e6) as i64;
    let cells = |b: &[P; 2]| {
        let (lo, hi) = (b[0].map(cell), b[1].map(cell));
        (lo[2]..=hi[2]).flat_map(move |z| {
            (lo[1]..=hi[1]).flat_map(move |y| (lo[0]..=hi[0]).map(move |x| [x, y, z]))
        })
    };
    let mut buckets: FxHashMap<[i64; 3], Vec<u32>> = FxHashMap::default();
    for (i, b) in boxes.iter().enumerate() {
        if !skip[i] {
            for c in cells(b) {
                buckets.entry(c).or_default().push(i as u32);
            }
        }
    }
    (0..triangles.len())
        .into_par_iter()
        .filter(|&i| !skip[i])
        .map(|i| {
            let mut later: Vec<u32> = cells(&boxes[i])
                .filter_map(|c| buckets.get(&c))
                .flatten()
                .copied()
                .filter(|&j| j as usize > i && !apart(&boxes[i], &boxes[j as usize]))
                .collect();
            later.sort_unstable();
            later.dedup();
            let (a, pa) = (&triangles[i], corners(&triangles[i]));
            later
                .into_iter()
                .filter(|&j| {
                    let b = &triangles[j as usize];
                    triangles_cross([a, b], [&pa, &corners(b)])
                })
                .count()
        })
        .sum()
}

/// Lower and upper corners of a triangle's box.
fn bounds(p: &[P; 3]) -> [P; 2] {
    let lo = [0, 1, 2].map(|a| p[0][a].min(p[1][a]).min(p[2][a]));
    let hi = [0, 1, 2].map(|a| p[0][a].max(p[1][a]).max(p[2][a]));
    [lo, hi]
}

/// Whether two boxes are disjoint.
fn apart(a: &[P; 2], b: &[P; 2]) -> bool {
    (0..3).any(|k| a[0][k] > b[1][k] || b[0][k] > a[1][k])
}

/// The buckets' width: the mean of the triangles' largest box sides (the surface's box side
/// over a thousand at least, so that tiny triangles do not make the buckets countless).
fn bucket_width(boxes: &[[P; 2]], skip: &[bool]) -> f64 {
    let side = |b: &[P; 2]| (0..3).map(|k| b[1][k] - b[0][k]).fold(0.0, f64::max);
    let used: Vec<&[P; 2]> = boxes
        .iter()
        .zip(skip)
        .filter(|(_, &s)| !s)
        .map(|(b, _)| b)
        .collect();
    let mean = used.iter().map(|b| side(b)).sum::<f64>() / used.len().max(1) as f64;
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for b in &used {
        for k in 0..3 {
            lo[k] = lo[k].min(b[0][k]);
            hi[k] = hi[k].max(b[1][k]);
        }
    }
    let whole = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max);
    mean.max(whole / 1000.0).max(f64::MIN_POSITIVE)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A closed tetrahedron's four faces, its corners shifted by `o`.
    fn tet(o: P, first: u32) -> (Vec<P>, Vec<[u32; 3]>) {
        let p = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ];
        let p = p.map(|q| [q[0] + o[0], q[1] + o[1], q[2] + o[2]]).to_vec();
        let t = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
        (p, t.map(|x| x.map(|i| i + first)).to_vec())
    }

    fn two(o: P) -> usize {
        let (mut p, mut t) = tet([0.0; 3], 0);
        let (q, u) = tet(o, 4);
        p.extend(q);
        t.extend(u);
        crossing_pairs(&p, &t, &vec![false; t.len()])
    }

    #[test]
    fn a_closed_surface_does_not_cross_itself() {
        let (p, t) = tet([0.0; 3], 0);
        assert_eq!(crossing_pairs(&p, &t, &[false; 4]), 0);
    }

    #[test]
    fn overlapping_tetrahedra_cross_and_separate_ones_do_not() {
        assert!(two([0.2, 0.2, 0.2]) > 0);
        assert_eq!(two([1.5, 0.0, 0.0]), 0);
        // touching at a corner counts: the surface meets itself there
        assert!(two([1.0, 0.0, 0.0]) > 0);
    }
}
