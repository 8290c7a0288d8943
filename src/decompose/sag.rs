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

use super::{CellPoints, LOCAL_BOX, NUM_LOCAL, SPLIT0};
use crate::trilinear::eval;

/// Largest distance (voxels along the edge) between the linear and the trilinear crossing of
/// a level that is left unsplit, on a face diagonal: the cut ends boundary triangles that
/// span the face, whose middles sag further than their corners.
pub const FACE_SAG_LIMIT: f64 = 0.25;
/// The same inside a cell.
pub const INNER_SAG_LIMIT: f64 = 0.4;

/// Split points stay this far (fraction of the edge) from the edge's ends.
const END_MARGIN: f64 = 0.002;

/// Bisection steps of a crossing.
const STEPS: usize = 36;

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

/// Whether a level crosses an edge (values `a`, `b` at its ends) more than `limit` away
/// from the linear crossing, for an edge of length `len` (voxels) along which the field is
/// `g`; and which levels cross it. Classes as in [`super::plan::class`].
fn sags(
    g: &impl Fn(f64) -> f64,
    len: f64,
    limit: f64,
    alpha: f64,
    beta: f64,
) -> Option<(bool, bool)> {
    let (a, b) = (g(0.0), g(1.0));
    let crosses_alpha = (a <= alpha) != (b <= alpha);
    let crosses_beta = (a >= beta) != (b >= beta);
    let within = limit / len;
    let sag = |level: f64| {
        let linear = (level - a) / (b - a);
        let (lo, hi) = ((linear - within).max(0.0), (linear + within).min(1.0));
        // A crossing within the limit of the linear one (the common case, two evaluations).
        if (g(lo) - level) * (g(hi) - level) <= 0.0 {
            return false;
        }
        (crossing(g, level) - linear).abs() > within
    };
    ((crosses_alpha && sag(alpha)) || (crosses_beta && sag(beta)))
        .then_some((crosses_alpha, crosses_beta))
}

/// The point where `g` takes `target`, if it lies strictly inside the edge with a value
/// strictly between the ends' and equal to no level.
fn split_at(g: &impl Fn(f64) -> f64, target: f64, alpha: f64, beta: f64) -> Option<EdgeSplit> {
    let (a, b) = (g(0.0), g(1.0));
    let t = crossing(g, target);
    let value = g(t);
    let between = value > a.min(b) && value < a.max(b) && value != alpha && value != beta;
    ((END_MARGIN..=1.0 - END_MARGIN).contains(&t) && between).then_some(EdgeSplit { t, value })
}

/// How far from the level (fraction of the way to the nearer bracketing value) a split point
/// for one level is placed: its value is never a level, and the cuts of that level on the
/// edges around it stay a fair distance from it.
const NUDGE: f64 = 0.1;

/// The value of a split point for `level`, [`NUDGE`] of the way toward `toward`.
fn nudged(level: f64, toward: f64) -> f64 {
    level + NUDGE * (toward - level)
}

/// The split of an edge with end values `a` and `b` for the one level `level` that crosses
/// it (`alpha` or `beta`): the point where the field takes a value [`NUDGE`] of the way from
/// the level toward the nearer of the values that bracket it along the edge — the end beyond
/// the level, or on the interval's side the end or the other level if that comes first.
/// The cut of the level then falls on the half of the edge toward the farther value, within
/// about a tenth of that half of the point, whatever the field does beyond the crossing (on
/// the T1 a face diagonal from 178 to 181 rises to 186.5: a point just inside beta = 180.7
/// left the cut halfway to the 181 corner, 0.6 voxel from the level set). The other side
/// is tried when the nearer one gives no point.
fn one_level_split(
    g: &impl Fn(f64) -> f64,
    level: f64,
    (alpha, beta): (f64, f64),
) -> Option<EdgeSplit> {
    let (a, b) = (g(0.0), g(1.0));
    let (lo, hi) = (a.min(b), a.max(b));
    let (inside, outside) = if level == alpha {
        (hi.min(beta), lo)
    } else {
        (lo.max(alpha), hi)
    };
    let (near, far) = match (inside - level).abs() <= (outside - level).abs() {
        true => (inside, outside),
        false => (outside, inside),
    };
    split_at(g, nudged(level, near), alpha, beta)
        .or_else(|| split_at(g, nudged(level, far), alpha, beta))
}

/// The split of an edge (see [`sags`]) at one point: where the field takes the middle of the
/// band when both levels cross the edge, else near the crossing level ([`one_level_split`]).
pub fn edge_split(
    g: impl Fn(f64) -> f64,
    len: f64,
    limit: f64,
    alpha: f64,
    beta: f64,
) -> Option<EdgeSplit> {
    match sags(&g, len, limit, alpha, beta)? {
        (true, true) => split_at(&g, 0.5 * (alpha + beta), alpha, beta),
        (true, false) => one_level_split(&g, alpha, (alpha, beta)),
        _ => one_level_split(&g, beta, (alpha, beta)),
    }
}

/// The split of an edge (see [`sags`]) at up to two points: with both levels crossing it, one
/// a tenth inside the band from each; with one, near it ([`one_level_split`]); in order along
/// the edge.
pub fn edge_splits(
    g: impl Fn(f64) -> f64,
    len: f64,
    limit: f64,
    alpha: f64,
    beta: f64,
) -> [Option<EdgeSplit>; 2] {
    let Some((ca, cb)) = sags(&g, len, limit, alpha, beta) else {
        return [None, None];
    };
    let at = |level: f64, toward: f64| split_at(&g, nudged(level, toward), alpha, beta);
    let mut s = match (ca, cb) {
        (true, true) => [at(alpha, beta), at(beta, alpha)],
        (true, false) => [one_level_split(&g, alpha, (alpha, beta)), None],
        _ => [one_level_split(&g, beta, (alpha, beta)), None],
    };
    if let [Some(x), Some(y)] = s {
        if y.t < x.t {
            s = [Some(y), Some(x)];
        }
    }
    match s {
        [None, y] => [y, None],
        s => s,
    }
}

/// The split of the diagonal (entry 0 to entry 2) of a face with values `q` in
/// [`crate::grid::face_corners`] order, along which the bilinear field is quadratic.
pub fn face_diagonal_split(q: [f64; 4], alpha: f64, beta: f64) -> Option<EdgeSplit> {
    let g = |t: f64| {
        let s = 1.0 - t;
        q[0] * s * s + (q[1] + q[3]) * s * t + q[2] * t * t
    };
    edge_split(g, std::f64::consts::SQRT_2, FACE_SAG_LIMIT, alpha, beta)
}

/// Rounds of [`split_inner_edges`] (the second looks at the edges the first made).
const PASSES: usize = 2;

/// Bisects the edges inside a cell (not on one of its faces) that sag from the level set of
/// `levels`, each at up to two points, in a fixed order, with local ids from `first` on
/// while there are some. Along an edge the field is the trilinear interpolant of the corner
/// values, corrected linearly so that it takes the vertex values at the ends (a face saddle
/// sits at a clamped position with its own value).
pub fn split_inner_edges(
    levels: [f64; 2],
    pts: &mut CellPoints,
    tets: &mut Vec<[u8; 4]>,
    first: usize,
) {
    let [alpha, beta] = levels;
    let corners: [f64; 8] = std::array::from_fn(|c| pts.val[c]);
    let mut next = first;
    let mut edges: Vec<(u8, u8)> = Vec::with_capacity(6 * tets.len());
    for _ in 0..PASSES {
        edges.clear();
        for t in tets.iter() {
            for (i, j) in [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)] {
                let (a, b) = (t[i].min(t[j]), t[i].max(t[j]));
                let (va, vb) = (pts.val[a as usize], pts.val[b as usize]);
                let crosses = (va <= alpha) != (vb <= alpha) || (va >= beta) != (vb >= beta);
                if crosses && LOCAL_BOX[a as usize] & LOCAL_BOX[b as usize] == 0 {
                    edges.push((a, b));
                }
            }
        }
        edges.sort_unstable();
        edges.dedup();
        let mut split = false;
        for &(a, b) in &edges {
            let (pa, pb) = (pts.pos[a as usize], pts.pos[b as usize]);
            let (va, vb) = (pts.val[a as usize], pts.val[b as usize]);
            let at = |t: f64| std::array::from_fn(|k| pa[k] + t * (pb[k] - pa[k]));
            let (ea, eb) = (va - eval(&corners, pa), vb - eval(&corners, pb));
            let g = |t: f64| eval(&corners, at(t)) + (1.0 - t) * ea + t * eb;
            let len = (0..3).map(|k| (pb[k] - pa[k]).powi(2)).sum::<f64>().sqrt();
            let splits = edge_splits(g, len, INNER_SAG_LIMIT, alpha, beta);
            let need = splits.iter().flatten().count();
            if need == 0 {
                continue;
            }
            if next + need > NUM_LOCAL {
                return;
            }
            let mut from = a;
            for s in splits.iter().flatten() {
                pts.pos[next] = at(s.t);
                pts.val[next] = s.value;
                bisect(tets, from, b, next as u8);
                from = next as u8;
                next += 1;
            }
            split = true;
        }
        if !split {
            break;
        }
    }
}

/// Samples of the main diagonal searched for a dip.
const DIP_SAMPLES: usize = 16;

/// Bisects the main diagonal `0–7` where both its ends lie on one side of the levels but the
/// trilinear field along it dips through one (the 6-fold split then joins the ends across a
/// layer the field has between them), at the deepest sample, with the trilinear value there.
/// That value lies outside the ends' range, so the point keeps the topology only where it is
/// a regular vertex at every level it passes: the diagonal's ring (the other corners of its
/// tets) must split into one arc below the level and one above. Or where it mends it: a ring
/// of the six other corners all on the point's side is a cell whose corners 0 and 7 are
/// alone on their side, which the 6-fold split joins and the trilinear field parts
/// ([`parts_a_lone_pair`]). Runs before the face diagonals are split, whose points would
/// stand in the ring. Returns the next free local id.
pub fn split_dipping_diagonal(
    levels: [f64; 2],
    pts: &mut CellPoints,
    tets: &mut Vec<[u8; 4]>,
) -> usize {
    let next = SPLIT0 as usize;
    let [alpha, beta] = levels;
    let class = |v: f64| super::plan::class(v, alpha, beta);
    let (v0, v7) = (pts.val[0], pts.val[7]);
    if class(v0) != class(v7) || !tets.iter().any(|t| t.contains(&0) && t.contains(&7)) {
        return next;
    }
    let corners: [f64; 8] = std::array::from_fn(|c| pts.val[c]);
    let Some((t, value)) = dip(|t| eval(&corners, [t; 3]), v0, alpha, beta) else {
        return next;
    };
    // The levels the value passes from the ends' side, each with its lower side as the
    // classes have it (at or below alpha; below beta).
    let lower_alpha = |x: f64| x <= alpha;
    let lower_beta = |x: f64| x < beta;
    let passed: [(bool, &dyn Fn(f64) -> bool); 2] = [
        (lower_alpha(v0) != lower_alpha(value), &lower_alpha),
        (lower_beta(v0) != lower_beta(value), &lower_beta),
    ];
    let ring: Vec<[u8; 2]> = tets
        .iter()
        .filter(|t| t.contains(&0) && t.contains(&7))
        .map(|t| {
            let mut o = t.iter().copied().filter(|&x| x != 0 && x != 7);
            [o.next().unwrap(), o.next().unwrap()]
        })
        .collect();
    for (_, lower) in passed.iter().filter(|p| p.0) {
        let below = |x: u8| lower(pts.val[x as usize]);
        if !splits_into_two_arcs(&ring, below) && !parts_a_lone_pair(&ring, below, lower(value)) {
            return next;
        }
    }
    pts.pos[next] = [t; 3];
    pts.val[next] = value;
    bisect(tets, 0, 7, next as u8);
    next + 1
}

/// The sample of the main diagonal (field `g`, ends in the class of `v0`) farthest beyond a
/// level from the ends' side, if one lies in another class and on no level: the highest
/// sample when the ends are below, the lowest when above, and from ends inside the band
/// whichever of the two leaves it by more (a diagonal between two corners just under beta
/// that rises through it in the middle of the cell dips as much as one that sinks).
fn dip(g: impl Fn(f64) -> f64, v0: f64, alpha: f64, beta: f64) -> Option<(f64, f64)> {
    let class = |v: f64| super::plan::class(v, alpha, beta);
    let samples = (1..DIP_SAMPLES).map(|k| k as f64 / DIP_SAMPLES as f64);
    let (mut low, mut high) = ((0.0, f64::INFINITY), (0.0, f64::NEG_INFINITY));
    for t in samples {
        let v = g(t);
        if v < low.1 {
            low = (t, v);
        }
        if v > high.1 {
            high = (t, v);
        }
    }
    let beyond = |(_, v): (f64, f64)| {
        let passes = class(v) != class(v0) && v != alpha && v != beta;
        passes.then_some((alpha - v).max(v - beta))
    };
    let candidates = match class(v0) {
        1 => [None, beyond(high).map(|d| (d, high))],
        2 => [beyond(low).map(|d| (d, low)), None],
        _ => [
            beyond(low).map(|d| (d, low)),
            beyond(high).map(|d| (d, high)),
        ],
    };
    candidates
        .into_iter()
        .flatten()
        .max_by(|x, y| x.0.total_cmp(&y.0))
        .map(|(_, s)| s)
}

/// Whether the diagonal's ring is the six other corners of the cell (the 6-fold split, which
/// a cell whose corners 0 and 7 are alone on one side of a level gets only with no saddle at
/// all) and every one of them lies on the side of the split point (`below(x) == side`). The
/// point is then no regular vertex: it parts the ends, where the 6-fold split joins them
/// through a tube along the diagonal. The trilinear field parts them too: two components of
/// one side of a level meet in a cell only at a critical point of the cell, corners, face
/// saddles and body saddles, of a value between theirs and the level; here every other
/// corner is beyond the level, a face holds one of the two ends and three corners beyond
/// the level, so its saddle is beyond them, and a body saddle would have made the cell's
/// split another (4.1.1 of the case table of Sohn, ICCS 2007, against 4.1.2).
fn parts_a_lone_pair(ring: &[[u8; 2]], below: impl Fn(u8) -> bool, side: bool) -> bool {
    let mut seen = 0u8;
    for &[x, y] in ring {
        for v in [x, y] {
            if !(1..7).contains(&v) || below(v) != side {
                return false;
            }
            seen |= 1 << v;
        }
    }
    seen == 0b0111_1110
}

/// Whether the cycle given by its edges `ring` splits into one non-empty arc of vertices
/// where `below` holds and one where it does not.
fn splits_into_two_arcs(ring: &[[u8; 2]], below: impl Fn(u8) -> bool) -> bool {
    // In a cycle, each side is one non-empty arc exactly when two edges change side.
    let changes = ring.iter().filter(|e| below(e[0]) != below(e[1])).count();
    changes == 2
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
        assert!(s.value > 149.84 && s.value < 149.85, "{s:?}");
        // the same face seen through the upper level: the 150 end is nearer to it than the
        // 146 one, so the point goes a tenth of the way toward 150, just outside the interval
        let s = face_diagonal_split(TIED, f64::NEG_INFINITY, 149.83).expect("split");
        assert!(s.value > 149.84 && s.value < 149.85, "{s:?}");
        assert!((s.t - 0.835).abs() < 0.01, "{s:?}");
        // a thin band: the middle of the band
        let s = face_diagonal_split(TIED, 149.5, 149.83).expect("split");
        assert!((s.value - 149.665).abs() < 1e-9, "{s:?}");
    }

    #[test]
    fn a_split_goes_to_the_nearer_side_of_its_level() {
        // A face of the MNI T1: its diagonal runs from 178 to 181 and rises to 186.5 between,
        // crossing 180.7 at 0.095. A point a tenth inside (180.43) would leave the cut of the
        // piece toward 181 halfway along it; just outside (180.73), the cut falls on the piece
        // toward 178, next to the point.
        let q = [178.0, 192.0, 181.0, 195.0];
        let s = face_diagonal_split(q, 120.3, 180.7).expect("split");
        assert!(s.value > 180.7 && s.value < 180.75, "{s:?}");
        assert!((s.t - 0.095).abs() < 0.01, "{s:?}");
        let g = |t: f64| 178.0 * (1.0 - t) * (1.0 - t) + 387.0 * (1.0 - t) * t + 181.0 * t * t;
        let cut = s.t * (180.7 - 178.0) / (s.value - 178.0);
        assert!(
            (cut - crossing(g, 180.7)).abs() * std::f64::consts::SQRT_2 < 0.01,
            "{cut}"
        );
    }

    #[test]
    fn edges_that_are_nearly_linear_or_uncut_stay_whole() {
        assert!(face_diagonal_split([0.0, 1.0, 2.0, 1.0], 0.7, 1.5).is_none());
        assert!(face_diagonal_split(TIED, 140.0, 145.0).is_none());
        let linear = |t: f64| 1.0 + 2.0 * t;
        assert_eq!(edge_splits(linear, 1.7, 0.25, 1.2, 2.5), [None, None]);
    }

    /// The 6-fold split of a cell whose main diagonal dips (corner 0 at 174, corner 7 at 135,
    /// 132 on the way): the diagonal is split just inside the band from each level, and every
    /// tet stays positive.
    #[test]
    fn the_main_diagonal_of_a_dipping_cell_is_split() {
        use crate::geom::signed_volume;
        let v = [174.0, 120.0, 123.0, 115.0, 158.0, 130.0, 138.0, 135.0];
        let mut pts = CellPoints::from_corners(&v);
        let mut tets = Vec::new();
        super::super::six::decompose_six(&mut tets);
        split_inner_edges([150.23, 150.77], &mut pts, &mut tets, SPLIT0 as usize);
        let on_diagonal: Vec<usize> = (SPLIT0 as usize..NUM_LOCAL)
            .filter(|&i| tets.iter().any(|t| t.contains(&(i as u8))))
            .filter(|&i| {
                pts.pos[i]
                    .iter()
                    .all(|&x| (x - pts.pos[i][0]).abs() < 1e-15)
            })
            .collect();
        assert_eq!(on_diagonal.len(), 2, "{on_diagonal:?}");
        let (x, y) = (on_diagonal[0], on_diagonal[1]);
        // the upper level first from corner 0, each a tenth of the band inside, both within 0.3
        assert!(pts.pos[x][0] < pts.pos[y][0] && pts.pos[y][0] < 0.3);
        assert!(pts.val[x] < 150.72 && pts.val[x] > 150.71, "{}", pts.val[x]);
        assert!(pts.val[y] > 150.28 && pts.val[y] < 150.29, "{}", pts.val[y]);
        let vol = |t: &[u8; 4]| {
            let p = t.map(|i| pts.pos[i as usize]);
            signed_volume(p[0], p[1], p[2], p[3])
        };
        assert!(tets.iter().all(|t| vol(t) > 0.0));
        assert!((tets.iter().map(vol).sum::<f64>() - 1.0).abs() < 1e-12);
    }

    /// The cell of the T1 crop whose main diagonal runs from 151 to 151 and dips to 146 in
    /// between, through the band [150.23, 150.77]: split at the dip (its ring, corners 1, 3,
    /// 2, 6, 4, 5 around 0–7, is 152, 151 above and 143, 137, 139, 146 below: two arcs).
    /// With the lower corners alternating around the ring the point would be a saddle: no
    /// split.
    #[test]
    fn a_dipping_main_diagonal_is_split_only_where_the_point_is_regular() {
        let run = |v: [f64; 8]| {
            let mut pts = CellPoints::from_corners(&v);
            let mut tets = Vec::new();
            super::super::six::decompose_six(&mut tets);
            let next = split_dipping_diagonal([150.23, 150.77], &mut pts, &mut tets);
            (next, pts, tets)
        };
        let (next, pts, tets) = run([151.0, 152.0, 143.0, 151.0, 139.0, 146.0, 137.0, 151.0]);
        assert_eq!(next, SPLIT0 as usize + 1);
        let p = SPLIT0 as usize;
        assert!(
            (pts.pos[p][0] - 0.5).abs() < 1e-12 && pts.val[p] < 146.3,
            "{:?}",
            pts.val[p]
        );
        assert_eq!(tets.len(), 12);
        assert!(!tets.iter().any(|t| t.contains(&0) && t.contains(&7)));
        let (next, _, tets) = run([151.0, 155.0, 155.0, 140.0, 155.0, 140.0, 140.0, 151.0]);
        assert_eq!((next, tets.len()), (SPLIT0 as usize, 6));
    }

    /// The 6-fold split of `v` with [`split_dipping_diagonal`] applied.
    fn dipped(v: [f64; 8], levels: [f64; 2]) -> (usize, CellPoints, Vec<[u8; 4]>) {
        let mut pts = CellPoints::from_corners(&v);
        let mut tets = Vec::new();
        super::super::six::decompose_six(&mut tets);
        let next = split_dipping_diagonal(levels, &mut pts, &mut tets);
        (next, pts, tets)
    }

    /// A cell of a field rough at the voxel scale: corners 0 and 7 just under beta = 0 (inside
    /// the band) and the main diagonal rising to 0.82 between them. The 6-fold split joined
    /// the two corners under the level along the diagonal, with triangles whose edge midpoints
    /// lay up to 0.55 voxel from the level set; the diagonal is split at its peak, above the
    /// level, whose ring (1, 3, 2 above, 6, 4 below, 5 above) makes it a regular vertex.
    #[test]
    fn a_diagonal_rising_through_beta_from_inside_the_band_is_split() {
        let v = [-0.291, 3.076, 0.754, 1.579, -0.202, 2.121, -0.335, -0.106];
        let (next, pts, tets) = dipped(v, [f64::NEG_INFINITY, 0.0]);
        assert_eq!(next, SPLIT0 as usize + 1);
        let p = SPLIT0 as usize;
        assert!(
            (pts.pos[p][0] - 0.5).abs() < 0.1 && pts.val[p] > 0.8,
            "{:?}",
            pts.val[p]
        );
        assert!(!tets.iter().any(|t| t.contains(&0) && t.contains(&7)));
        // the same cell seen through alpha from above: the diagonal sinks through it
        let w = v.map(|x| -x);
        let (next, pts, _) = dipped(w, [0.0, f64::INFINITY]);
        assert_eq!(next, SPLIT0 as usize + 1);
        assert!(pts.val[SPLIT0 as usize] < -0.8);
    }

    /// A cell of the MNI T1: corners 0 and 7 at 201, just under beta = 201.0135, the other six
    /// at 202 to 206, no saddle. The trilinear field keeps two caps around the corners (the
    /// diagonal peaks at 203.1), the 6-fold split joined them by a tube along the diagonal,
    /// 0.86 voxel from the level set. Split at the peak, the caps part.
    #[test]
    fn a_lone_diagonal_pair_with_no_saddle_is_parted() {
        use crate::geom::signed_volume;
        let v = [201.0, 206.0, 204.0, 205.0, 202.0, 204.0, 202.0, 201.0];
        assert_eq!(crate::trilinear::body_saddles(&v).1, 0);
        let (next, pts, tets) = dipped(v, [151.0135, 201.0135]);
        assert_eq!(next, SPLIT0 as usize + 1);
        let p = SPLIT0 as usize;
        assert!((pts.pos[p][0] - 0.5).abs() < 1e-12 && pts.val[p] > 203.0);
        // no tet holds both corners: nothing under beta joins them
        assert!(!tets.iter().any(|t| t.contains(&0) && t.contains(&7)));
        let vol = |t: &[u8; 4]| {
            let q = t.map(|i| pts.pos[i as usize]);
            signed_volume(q[0], q[1], q[2], q[3])
        };
        assert!(tets.iter().all(|t| vol(t) > 0.0));
        // with one of the six on the pair's side, the ring has two arcs and the point is
        // regular; with two apart (1 and 6 under beta), it would be a saddle: no split
        let mut w = v;
        w[1] = 200.0;
        w[6] = 200.0;
        let (next, _, tets) = dipped(w, [151.0135, 201.0135]);
        assert_eq!((next, tets.len()), (SPLIT0 as usize, 6));
    }

    /// A cell of a noisy field: corners 0 and 7 above alpha = 0, the diagonal sinking to
    /// -0.23 between them, and the diagonal of face 5 sagging. Its split point, a tenth of the
    /// way above alpha, took corner 4's place in the main diagonal's ring (1, 3 above, 2, 6
    /// below, 4 below, 5 below) and broke its two arcs: the dip stayed, with triangles 0.43
    /// voxel from the level set. The main diagonal is split first.
    #[test]
    fn the_main_diagonal_is_split_before_the_face_diagonals() {
        use super::super::plan::{plan_cell, Method, Planner};
        let v = [0.391, 0.112, -1.557, 0.581, -0.479, -0.375, -0.807, 0.306];
        let grid = crate::grid::ScalarGrid::new([2; 3], v.to_vec()).unwrap();
        let planner = Planner {
            grid: &grid,
            method: Method::Ctd,
            levels: crate::levels::Levels::interval(0.0, f64::INFINITY),
            split_sags: true,
        };
        let plan = plan_cell(&planner, [0; 3], &v);
        assert_eq!((plan.used(), plan.extra), (0, 1 << 5));
        let mut tets = Vec::new();
        let (_, pts) = super::super::decompose_cell(&plan, &v, &mut tets);
        assert!(!tets.iter().any(|t| t.contains(&0) && t.contains(&7)));
        super::super::test_util::assert_tiles_cube(&tets, &pts, plan.extra);
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
