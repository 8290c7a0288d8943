//! Exact geometric predicates on `f64` points (Shewchuk's adaptive arithmetic through the
//! `robust` crate) and the triangle tests built on them: no constructed point is ever rounded,
//! so every answer is the one of the real numbers the coordinates stand for.

use robust::Coord3D;

type P = [f64; 3];

fn c3(p: P) -> Coord3D<f64> {
    Coord3D {
        x: p[0],
        y: p[1],
        z: p[2],
    }
}

/// Sign of the volume of tet `(a, b, c, d)`: `1` when `d` lies on the side of plane `abc`
/// that `(b - a) × (c - a)` points to (a positive tet of [`crate::TetMesh`]), `-1` on the
/// other side, `0` when the four points are coplanar. Exact.
#[inline]
pub(crate) fn orient(a: P, b: P, c: P, d: P) -> i8 {
    // `robust::orient3d` is positive when `d` lies below the plane, the opposite convention.
    sign(-robust::orient3d(c3(a), c3(b), c3(c), c3(d)))
}

#[inline]
fn sign(x: f64) -> i8 {
    if x > 0.0 {
        1
    } else if x < 0.0 {
        -1
    } else {
        0
    }
}

/// Exact sign of the 2-D orientation of `(a, b, c)` after dropping coordinate `drop`.
#[inline]
fn orient2(a: P, b: P, c: P, drop: usize) -> i8 {
    let (i, j) = match drop {
        0 => (1, 2),
        1 => (2, 0),
        _ => (0, 1),
    };
    let q = |p: P| robust::Coord { x: p[i], y: p[j] };
    sign(robust::orient2d(q(a), q(b), q(c)))
}

/// A coordinate to drop so that triangle `t` projects to a non-degenerate triangle (exactly);
/// `None` for a degenerate (collinear) triangle.
pub(crate) fn projection_axis(t: &[P; 3]) -> Option<usize> {
    (0..3).rev().find(|&d| orient2(t[0], t[1], t[2], d) != 0)
}

/// Whether closed segments `ab` and `cd`, coplanar and projected by dropping `drop`, meet.
fn segments_meet_2d(a: P, b: P, c: P, d: P, drop: usize) -> bool {
    let (o1, o2) = (orient2(a, b, c, drop), orient2(a, b, d, drop));
    let (o3, o4) = (orient2(c, d, a, drop), orient2(c, d, b, drop));
    if o1 * o2 < 0 && o3 * o4 < 0 {
        return true;
    }
    let on = |p: P, q: P, r: P, o: i8| o == 0 && within_box(p, q, r);
    on(a, b, c, o1) || on(a, b, d, o2) || on(c, d, a, o3) || on(c, d, b, o4)
}

/// Whether `r` lies in the bounding box of `p` and `q` (for a point collinear with them: on
/// the closed segment).
fn within_box(p: P, q: P, r: P) -> bool {
    (0..3).all(|k| r[k] >= p[k].min(q[k]) && r[k] <= p[k].max(q[k]))
}

/// Whether point `p`, coplanar with triangle `t`, lies in the closed triangle (projected by
/// dropping `drop`, along which `t` is not degenerate).
fn point_in_triangle_2d(p: P, t: &[P; 3], drop: usize) -> bool {
    let o = orient2(t[0], t[1], t[2], drop);
    (0..3).all(|k| orient2(t[k], t[(k + 1) % 3], p, drop) * o >= 0)
}

/// Whether the closed segment `ab` meets the closed triangle `t` (not degenerate).
pub(crate) fn segment_meets_triangle(a: P, b: P, t: &[P; 3]) -> bool {
    let (sa, sb) = (orient(t[0], t[1], t[2], a), orient(t[0], t[1], t[2], b));
    if sa * sb > 0 {
        return false;
    }
    if sa == 0 && sb == 0 {
        let Some(drop) = projection_axis(t) else {
            return false;
        };
        return point_in_triangle_2d(a, t, drop)
            || point_in_triangle_2d(b, t, drop)
            || (0..3).any(|k| segments_meet_2d(a, b, t[k], t[(k + 1) % 3], drop));
    }
    // The segment crosses (or touches) the plane once: inside the triangle iff the three
    // edges see the segment's line turn the same way (or touch it).
    let e = [0, 1, 2].map(|k| orient(a, b, t[k], t[(k + 1) % 3]));
    e.iter().all(|&x| x >= 0) || e.iter().all(|&x| x <= 0)
}

/// Whether the closed triangles `s` and `t` (neither degenerate) meet. Two triangles meet
/// iff an edge of one meets the other (the intersection is convex: its extreme points lie on
/// edges), and coplanar ones also when one holds the other.
pub(crate) fn triangles_meet(s: &[P; 3], t: &[P; 3]) -> bool {
    let side = |t: &[P; 3], p: P| orient(t[0], t[1], t[2], p);
    let st = s.map(|p| side(t, p));
    if st.iter().all(|&x| x > 0) || st.iter().all(|&x| x < 0) {
        return false;
    }
    let ts = t.map(|p| side(s, p));
    if ts.iter().all(|&x| x > 0) || ts.iter().all(|&x| x < 0) {
        return false;
    }
    (0..3).any(|k| segment_meets_triangle(s[k], s[(k + 1) % 3], t))
        || (0..3).any(|k| segment_meets_triangle(t[k], t[(k + 1) % 3], s))
}

/// Whether all points of `s` lie in the plane of `t`.
pub(crate) fn coplanar(s: &[P; 3], t: &[P; 3]) -> bool {
    s.iter().all(|&p| orient(t[0], t[1], t[2], p) == 0)
}

/// Whether segment `v → a`, lying in the plane of triangle `t = (v, c, d)`, leaves `v` into
/// the closed wedge of `t` at `v` (so it runs along or into `t` beyond `v`).
fn ray_in_wedge(v: P, a: P, c: P, d: P, drop: usize) -> bool {
    let o = orient2(v, c, d, drop);
    orient2(v, c, a, drop) * o >= 0 && orient2(v, a, d, drop) * o >= 0
}

/// Whether triangles `(v, a, b)` and `(v, c, d)`, sharing exactly vertex `v` (neither
/// degenerate), meet anywhere but at `v`: a far edge meets the other triangle, or an edge at
/// `v` lies in the other's plane and runs into its wedge at `v`.
pub(crate) fn meet_beyond_vertex(v: P, [a, b]: [P; 2], [c, d]: [P; 2]) -> bool {
    let s = [v, a, b];
    let t = [v, c, d];
    if segment_meets_triangle(a, b, &t) || segment_meets_triangle(c, d, &s) {
        return true;
    }
    let into = |p: P, tri: &[P; 3], q: P, r: P| -> bool {
        if orient(tri[0], tri[1], tri[2], p) != 0 {
            return false;
        }
        projection_axis(tri).is_some_and(|drop| ray_in_wedge(v, p, q, r, drop))
    };
    into(a, &t, c, d) || into(b, &t, c, d) || into(c, &s, a, b) || into(d, &s, a, b)
}

/// Whether triangles `(u, w, a)` and `(u, w, b)`, sharing exactly edge `uw`, overlap beyond
/// it: coplanar with `a` and `b` on the same side of the edge (a fold).
pub(crate) fn fold_over_edge(u: P, w: P, a: P, b: P) -> bool {
    if orient(u, w, a, b) != 0 {
        return false;
    }
    let Some(drop) = projection_axis(&[u, w, a]) else {
        return false;
    };
    orient2(u, w, a, drop) * orient2(u, w, b, drop) > 0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn orient_is_positive_for_a_positive_tet() {
        let (o, x, y, z) = ([0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]);
        assert_eq!(orient(o, x, y, z), 1);
        assert_eq!(orient(o, y, x, z), -1);
        assert_eq!(orient(o, x, y, [0.3, 0.3, 0.0]), 0);
        // Exact where rounding would decide: a point off the plane by one ulp.
        let e = f64::EPSILON;
        assert_eq!(orient(o, x, y, [0.5, 0.5, e * e]), 1);
    }

    #[test]
    fn triangle_pairs_meet_cross_and_touch() {
        let t = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]];
        let crossing = [[0.5, 0.5, -1.0], [0.5, 0.5, 1.0], [3.0, 3.0, 0.5]];
        let apart = [[0.5, 0.5, 0.1], [0.5, 0.5, 1.0], [3.0, 3.0, 0.5]];
        let touching = [[0.5, 0.5, 0.0], [0.5, 0.5, 1.0], [3.0, 3.0, 0.5]];
        let flat_inside = [[0.2, 0.2, 0.0], [0.6, 0.2, 0.0], [0.2, 0.6, 0.0]];
        let flat_outside = [[3.0, 3.0, 0.0], [4.0, 3.0, 0.0], [3.0, 4.0, 0.0]];
        assert!(triangles_meet(&t, &crossing));
        assert!(!triangles_meet(&t, &apart));
        assert!(triangles_meet(&t, &touching));
        assert!(triangles_meet(&t, &flat_inside));
        assert!(triangles_meet(&flat_inside, &t));
        assert!(!triangles_meet(&t, &flat_outside));
        assert!(coplanar(&flat_inside, &t));
    }

    #[test]
    fn pairs_sharing_a_vertex_or_an_edge() {
        let v = [0.0; 3];
        let (a, b) = ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
        // Apart but for v: the other triangle rises out of the plane.
        assert!(!meet_beyond_vertex(
            v,
            [a, b],
            [[-1.0, 0.0, 1.0], [0.0, -1.0, 1.0]]
        ));
        // Coplanar, the other one's wedge inside this one's.
        assert!(meet_beyond_vertex(
            v,
            [a, b],
            [[1.0, 0.5, 0.0], [0.5, 1.0, 0.0]]
        ));
        // Crossing through v: the other triangle pierces this one along a segment from v.
        assert!(meet_beyond_vertex(
            v,
            [a, b],
            [[0.3, 0.3, 1.0], [0.3, 0.3, -1.0]]
        ));
        // Coplanar, opposite quadrant.
        assert!(!meet_beyond_vertex(
            v,
            [a, b],
            [[-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]]
        ));
        let (u, w) = ([0.0; 3], [1.0, 0.0, 0.0]);
        assert!(fold_over_edge(u, w, [0.5, 1.0, 0.0], [0.2, 0.3, 0.0]));
        assert!(!fold_over_edge(u, w, [0.5, 1.0, 0.0], [0.2, -0.3, 0.0]));
        assert!(!fold_over_edge(u, w, [0.5, 1.0, 0.0], [0.2, 0.3, 0.1]));
    }
}
