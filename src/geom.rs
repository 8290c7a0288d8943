//! Small 3-vector helpers shared by the decompositions, the clipper and the analyses.

/// Signed volume of the tetrahedron (a, b, c, d): positive when (b-a, c-a, d-a) is right-handed.
#[inline]
pub fn signed_volume(a: [f64; 3], b: [f64; 3], c: [f64; 3], d: [f64; 3]) -> f64 {
    let u = sub(b, a);
    let v = sub(c, a);
    let w = sub(d, a);
    dot(u, cross(v, w)) / 6.0
}

/// `a - b`.
#[inline]
pub fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// Dot product.
#[inline]
pub fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Euclidean length.
#[inline]
pub fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

/// Euclidean distance between `a` and `b`.
#[inline]
pub fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    norm(sub(a, b))
}

/// Cross product `a × b`.
#[inline]
pub fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Volume of `{x in tet p : lo <= f(x) <= hi}` for the linear interpolant of the corner values
/// `f` (either bound may be infinite).
pub fn interval_volume(p: [[f64; 3]; 4], f: [f64; 4], lo: f64, hi: f64) -> f64 {
    sublevel_volume(p, f, hi) - sublevel_volume(p, f, lo)
}

/// The polygon where the linear interpolant of the corner values `f` on tet `p` equals `c`,
/// in cyclic order: the corners on `c` and the points where edges from a corner below `c` to
/// one above cross it. Returns the points and how many there are (0 to 4; 4 only when two
/// corners lie on each side).
pub fn level_polygon(p: [[f64; 3]; 4], f: [f64; 4], c: f64) -> ([[f64; 3]; 4], usize) {
    let mut out = [[0.0; 3]; 4];
    let at = |i: usize, j: usize| {
        let s = (c - f[i]) / (f[j] - f[i]);
        [0, 1, 2].map(|a| p[i][a] + s * (p[j][a] - p[i][a]))
    };
    let (mut below, mut above) = ([0usize; 4], [0usize; 4]);
    let (mut nb, mut na, mut n) = (0, 0, 0);
    for i in 0..4 {
        if f[i] < c {
            below[nb] = i;
            nb += 1;
        } else if f[i] > c {
            above[na] = i;
            na += 1;
        } else {
            out[n] = p[i];
            n += 1;
        }
    }
    if nb == 2 && na == 2 {
        let ([a, b], [x, y]) = ([below[0], below[1]], [above[0], above[1]]);
        return ([at(a, x), at(a, y), at(b, y), at(b, x)], 4);
    }
    for &i in &below[..nb] {
        for &j in &above[..na] {
            out[n] = at(i, j);
            n += 1;
        }
    }
    (out, n)
}

/// Volume of `{x in tet p : f(x) < c}` for the linear interpolant of the corner values `f`:
/// the corner tet at a lone corner below `c` (or the tet less the one at a lone corner above
/// it), or, with two on each side, the wedge between them as three tets.
pub fn sublevel_volume(p: [[f64; 3]; 4], f: [f64; 4], c: f64) -> f64 {
    let whole = signed_volume(p[0], p[1], p[2], p[3]).abs();
    // The corners below `c`, then those above (a stable partition).
    let mut sides = [0, 1, 2, 3];
    sides.sort_by_key(|&i| f[i] >= c);
    let n_below = f.iter().filter(|&&x| x < c).count();
    let (below, above) = sides.split_at(n_below);
    // The point where the edge from corner `i` to corner `j` crosses `c`, and its fraction.
    let t = |i: usize, j: usize| (c - f[i]) / (f[j] - f[i]);
    let at = |i: usize, j: usize| {
        let s = t(i, j);
        [0, 1, 2].map(|a| p[i][a] + s * (p[j][a] - p[i][a]))
    };
    match (below, above) {
        ([], _) => 0.0,
        (_, []) => whole,
        (&[i], others) => whole * others.iter().map(|&j| t(i, j)).product::<f64>(),
        (others, &[j]) => whole * (1.0 - others.iter().map(|&i| t(j, i)).product::<f64>()),
        (&[a, b], &[c0, d]) => {
            // The prism (a, a-c0, a-d) over (b, b-c0, b-d): its side quads lie in the tet's
            // faces and on the plane f = c, so it is convex and any staircase of it tiles it.
            let (a0, a1, a2) = (p[a], at(a, c0), at(a, d));
            let (b0, b1, b2) = (p[b], at(b, c0), at(b, d));
            signed_volume(a0, a1, a2, b2).abs()
                + signed_volume(a0, a1, b1, b2).abs()
                + signed_volume(a0, b0, b1, b2).abs()
        }
        _ => unreachable!("four corners split into below and above"),
    }
}

/// At most this many subdivisions of a triangle's edges: a longer triangle is refused (its
/// edge is more than `MAX_SUBDIVISIONS` spacings long).
const MAX_SUBDIVISIONS: usize = 64;

/// The points of triangle `t` at which the quality pass and warping measure its distance to
/// a level set: a barycentric lattice with `n` steps along each edge, `n` such that
/// neighbouring points are at most `spacing` apart (at least 2: corners, edge midpoints and
/// three inner points). `None` if the triangle is too long to sample ([`MAX_SUBDIVISIONS`]).
pub(crate) fn sample_points_spaced(
    t: [[f64; 3]; 3],
    spacing: f64,
) -> Option<impl Iterator<Item = [f64; 3]>> {
    let len = |a: [f64; 3], b: [f64; 3]| {
        ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
    };
    let longest = len(t[0], t[1]).max(len(t[1], t[2])).max(len(t[2], t[0]));
    let n = (longest / spacing).ceil().max(2.0);
    if n.is_nan() || n > MAX_SUBDIVISIONS as f64 {
        return None;
    }
    let n = n as usize;
    Some((0..=n).flat_map(move |i| {
        (0..=n - i).map(move |j| {
            let (a, b) = (i as f64 / n as f64, j as f64 / n as f64);
            let c = 1.0 - a - b;
            [0, 1, 2].map(|k| a * t[0][k] + b * t[1][k] + c * t[2][k])
        })
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn level_polygons_lie_on_the_level_in_cyclic_order() {
        let p = [
            [0.1, 0.0, 0.2],
            [1.3, 0.1, 0.0],
            [0.2, 1.1, 0.1],
            [0.0, 0.3, 1.4],
        ];
        // The linear interpolant at a point, from its barycentric coordinates on `p`.
        let value = |f: [f64; 4], u: [f64; 3]| {
            let whole = signed_volume(p[0], p[1], p[2], p[3]);
            (0..4)
                .map(|i| {
                    let mut q = p;
                    q[i] = u;
                    f[i] * signed_volume(q[0], q[1], q[2], q[3]) / whole
                })
                .sum::<f64>()
        };
        for (f, c, n) in [
            ([0.0, 1.0, 2.0, 3.0], 0.5, 3),
            ([0.0, 1.0, 2.0, 3.0], 1.5, 4),
            ([0.0, 1.0, 2.0, 3.0], 2.5, 3),
            ([0.0, 1.0, 2.0, 3.0], 1.0, 3),
            ([1.0, 1.0, 0.0, 3.0], 1.0, 3),
            ([1.0, 1.0, 1.0, 3.0], 1.0, 3),
            ([1.0, 1.0, 0.0, 0.0], 1.0, 2),
            ([1.0, 0.0, 0.0, 0.0], 1.0, 1),
            ([0.0, 0.0, 0.0, 0.5], 1.0, 0),
        ] {
            let (q, m) = level_polygon(p, f, c);
            assert_eq!(m, n, "{f:?} at {c}");
            for u in &q[..m] {
                assert!((value(f, *u) - c).abs() < 1e-12, "{f:?} at {c}: {u:?}");
            }
            if m == 4 {
                // A convex quad in cyclic order: every turn has the same sense.
                let normal = cross(sub(q[1], q[0]), sub(q[3], q[0]));
                for k in 0..4 {
                    let (a, b, c2) = (q[k], q[(k + 1) % 4], q[(k + 2) % 4]);
                    assert!(dot(cross(sub(b, a), sub(c2, b)), normal) > 0.0, "{q:?}");
                }
            }
        }
    }

    /// The divided-difference formula for distinct values: the volume fraction of
    /// `{f < c}` is the sum over the corners below `c` of `(c - f_i)^3 / prod (f_j - f_i)`.
    fn fraction_by_formula(f: [f64; 4], c: f64) -> f64 {
        (0..4)
            .filter(|&i| f[i] < c)
            .map(|i| {
                let den: f64 = (0..4).filter(|&j| j != i).map(|j| f[j] - f[i]).product();
                (c - f[i]).powi(3) / den
            })
            .sum()
    }

    #[test]
    fn sublevel_volumes_match_the_divided_difference_formula() {
        let p = [
            [0.1, 0.0, 0.2],
            [1.3, 0.1, 0.0],
            [0.2, 0.9, 0.1],
            [0.3, 0.2, 1.1],
        ];
        let whole = signed_volume(p[0], p[1], p[2], p[3]).abs();
        let mut seed = 7u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut cases = [0usize; 5];
        for _ in 0..2000 {
            let f = [rnd(), rnd(), rnd(), rnd()].map(|x| 4.0 * x - 2.0);
            let c = 3.0 * rnd() - 1.5;
            cases[f.iter().filter(|&&x| x < c).count()] += 1;
            let got = sublevel_volume(p, f, c);
            let want = whole * fraction_by_formula(f, c);
            assert!(
                (got - want).abs() <= 1e-9 * whole,
                "f {f:?} c {c}: {got} vs {want}"
            );
            let rest = sublevel_volume(p, f.map(|x| -x), -c);
            assert!((got + rest - whole).abs() <= 1e-12 * whole.max(1.0));
        }
        assert!(cases.iter().all(|&n| n > 50), "every case met: {cases:?}");
    }

    #[test]
    fn interval_volume_of_a_linear_field_is_exact() {
        // f = x on the unit corner tet: {x <= s} has volume (1 - (1 - s)^3) / 6.
        let p = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ];
        let f = [0.0, 1.0, 0.0, 0.0];
        let below = |s: f64| (1.0 - (1.0 - s).powi(3)) / 6.0;
        let v = interval_volume(p, f, 0.25, 0.75);
        assert!((v - (below(0.75) - below(0.25))).abs() < 1e-15, "{v}");
        assert_eq!(
            interval_volume(p, f, f64::NEG_INFINITY, f64::INFINITY),
            1.0 / 6.0
        );
        assert_eq!(interval_volume(p, f, 2.0, 3.0), 0.0);
    }
}
