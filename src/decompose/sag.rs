//! Edges that sag from the level set, and the points that split them.
//!
//! The clipper cuts an edge where the *linear* interpolant along it crosses a level. Along a
//! face diagonal the trilinear field is quadratic, along the cell's main diagonal cubic, and
//! where the edge's ends lie close to a level while the rest of the cell lies far from it
//! (tied grid values on integer data are the common case) the trilinear crossing can be most
//! of the edge away: the boundary vertex lies up to a voxel from the level set. Such an edge is
//! bisected at a point near its trilinear crossing, with the trilinear value there, and the
//! clipper then cuts the two halves.
//!
//! Bisecting an edge `a–b` at a point `p` whose value lies strictly between the values at `a`
//! and `b` keeps the topology of every level set and interval: with `p` at its linearly
//! interpolated value the field is unchanged, and while its value moves to the new one, `p`
//! stays a regular vertex whenever it passes a level (its link is the suspension of the edge's
//! link with poles `a` and `b`, exactly one of which is below the level, so its lower link is
//! a cone). Each tet on the edge becomes two positive tets.
//!
//! A face diagonal is split by both cells of the face, from the face's four values alone, so
//! they agree; the main diagonal `0–7` is inside its cell.

use crate::trilinear::eval;

/// Largest distance (voxels along the edge) between the linear and the trilinear crossing of
/// a level that is left unsplit.
pub const SAG_LIMIT: f64 = 0.25;

/// Split points stay this far (fraction of the edge) from the edge's ends.
const END_MARGIN: f64 = 0.02;

/// Bisection steps of a crossing.
const STEPS: usize = 44;

/// A point splitting an edge: `t` along it from its first end, and the field value there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EdgeSplit {
    /// Fraction of the edge from its first end.
    pub t: f64,
    /// The trilinear value at the point.
    pub value: f64,
}

/// Where `g` (continuous on `[0, 1]`, `g(0)` and `g(1)` on opposite sides of `level`) crosses
/// `level`: bisection.
fn crossing(g: impl Fn(f64) -> f64, level: f64) -> f64 {
    let rising = g(1.0) > g(0.0);
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    for _ in 0..STEPS {
        let mid = 0.5 * (lo + hi);
        if (g(mid) > level) == rising {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    0.5 * (lo + hi)
}

/// The split of an edge of length `len` (voxels) along which the field is `g` (`g(0)`, `g(1)`
/// its ends' values) when a level crosses it more than [`SAG_LIMIT`] away from the linear
/// crossing; classes as in [`super::plan::class`]. The point is placed where the field takes
/// the middle of the band when both levels cross the edge, else just inside the interval from
/// the crossing level, so that its value is never a level.
pub fn edge_split(g: impl Fn(f64) -> f64, len: f64, alpha: f64, beta: f64) -> Option<EdgeSplit> {
    let (a, b) = (g(0.0), g(1.0));
    let crosses_alpha = (a <= alpha) != (b <= alpha);
    let crosses_beta = (a >= beta) != (b >= beta);
    if !crosses_alpha && !crosses_beta {
        return None;
    }
    let sag = |level: f64| {
        let linear = (level - a) / (b - a);
        (crossing(&g, level) - linear).abs() * len
    };
    let sags = (crosses_alpha && sag(alpha) > SAG_LIMIT) || (crosses_beta && sag(beta) > SAG_LIMIT);
    if !sags {
        return None;
    }
    let (lo, hi) = (a.min(b), a.max(b));
    let target = match (crosses_alpha, crosses_beta) {
        (true, true) => 0.5 * (alpha + beta),
        (true, false) => alpha + 1e-3 * (hi - alpha),
        _ => beta - 1e-3 * (beta - lo),
    };
    let t = crossing(&g, target);
    let value = g(t);
    let strictly_between = value > lo && value < hi && value != alpha && value != beta;
    ((END_MARGIN..=1.0 - END_MARGIN).contains(&t) && strictly_between)
        .then_some(EdgeSplit { t, value })
}

/// The split of the diagonal (entry 0 to entry 2) of a face with values `q` in
/// [`crate::grid::face_corners`] order, along which the bilinear field is quadratic.
pub fn face_diagonal_split(q: [f64; 4], alpha: f64, beta: f64) -> Option<EdgeSplit> {
    let g = |t: f64| {
        let s = 1.0 - t;
        q[0] * s * s + (q[1] + q[3]) * s * t + q[2] * t * t
    };
    edge_split(g, std::f64::consts::SQRT_2, alpha, beta)
}

/// The split of the main diagonal (corner 0 to corner 7) of a cell with corner values `v`.
pub fn main_diagonal_split(v: &[f64; 8], alpha: f64, beta: f64) -> Option<EdgeSplit> {
    edge_split(|t| eval(v, [t; 3]), 3f64.sqrt(), alpha, beta)
}

/// Bisects every tet of `tets` that has the edge `{a, b}` at local id `p`.
pub fn bisect(tets: &mut Vec<[u8; 4]>, a: u8, b: u8, p: u8) {
    let n = tets.len();
    for i in 0..n {
        let t = tets[i];
        let (Some(ia), Some(ib)) = (
            t.iter().position(|&x| x == a),
            t.iter().position(|&x| x == b),
        ) else {
            continue;
        };
        // Replacing one end by the point keeps the orientation.
        let mut first = t;
        first[ib] = p;
        let mut second = t;
        second[ia] = p;
        tets[i] = first;
        tets.push(second);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Face values of a tie on integer data: the diagonal runs from 150 to 146 with 150 and
    /// 169 across, so the bilinear crossing of 149.83 is at 0.835 along the diagonal and the
    /// linear one at 0.04.
    const TIED: [f64; 4] = [150.0, 150.0, 146.0, 169.0];

    #[test]
    fn a_tied_face_is_split_near_its_bilinear_crossing() {
        let s = face_diagonal_split(TIED, 149.83, f64::INFINITY).expect("split");
        assert!((s.t - 0.835).abs() < 0.01, "{s:?}");
        assert!(s.value > 149.83 && s.value < 149.84, "{s:?}");
        // the same face seen through the upper level
        let s = face_diagonal_split(TIED, f64::NEG_INFINITY, 149.83).expect("split");
        assert!(s.value < 149.83 && s.value > 149.82, "{s:?}");
        // a thin band: the middle of the band
        let s = face_diagonal_split(TIED, 149.5, 149.83).expect("split");
        assert!((s.value - 149.665).abs() < 1e-9, "{s:?}");
    }

    #[test]
    fn edges_that_are_nearly_linear_or_uncut_stay_whole() {
        assert!(face_diagonal_split([0.0, 1.0, 2.0, 1.0], 0.7, 1.5).is_none());
        assert!(face_diagonal_split(TIED, 140.0, 145.0).is_none());
        let v = [0.0, 1.0, 1.0, 2.0, 1.0, 2.0, 2.0, 3.0];
        assert!(main_diagonal_split(&v, 1.2, 2.5).is_none());
    }

    #[test]
    fn the_main_diagonal_of_a_dipping_cell_is_split() {
        // corner 0 at 174, corner 7 at 135, the diagonal dips to 132 on its way
        let v = [174.0, 120.0, 123.0, 115.0, 158.0, 130.0, 138.0, 135.0];
        let s = main_diagonal_split(&v, 150.23, 150.77).expect("split");
        assert!((s.value - 150.5).abs() < 1e-9 && s.t < 0.3, "{s:?}");
    }

    #[test]
    fn bisection_keeps_orientation_and_volume() {
        use crate::geom::signed_volume;
        let pos = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.3, 0.0, 0.7],
        ];
        let mut tets = vec![[0u8, 1, 2, 3]];
        bisect(&mut tets, 3, 1, 4);
        assert_eq!(tets.len(), 2);
        let vol = |t: &[u8; 4]| {
            signed_volume(
                pos[t[0] as usize],
                pos[t[1] as usize],
                pos[t[2] as usize],
                pos[t[3] as usize],
            )
        };
        let total: f64 = tets.iter().map(vol).sum();
        assert!(tets.iter().all(|t| vol(t) > 0.0));
        assert!((total - 1.0 / 6.0).abs() < 1e-12);
    }
}
