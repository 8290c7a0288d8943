//! Math on one cell's eight corner values: evaluation, face saddles, body saddles.
//!
//! Corner and face numbering are those of [`crate::grid`]. Coordinates are cell-local,
//! in `[0, 1]^3`.

use nalgebra::{Matrix3, Vector3};

use crate::grid::face_corners;

/// Trilinear interpolation of the corner values `v` at cell-local point `p`.
#[inline]
pub fn eval(v: &[f64; 8], p: [f64; 3]) -> f64 {
    let [x, y, z] = p;
    let c00 = v[0] * (1.0 - x) + v[1] * x;
    let c10 = v[2] * (1.0 - x) + v[3] * x;
    let c01 = v[4] * (1.0 - x) + v[5] * x;
    let c11 = v[6] * (1.0 - x) + v[7] * x;
    let c0 = c00 * (1.0 - y) + c10 * y;
    let c1 = c01 * (1.0 - y) + c11 * y;
    c0 * (1.0 - z) + c1 * z
}

/// How far (in cell units) a saddle must lie from the cell's or face's boundary to count as
/// inside. Saddles closer than this are degenerate (on an edge or a face up to rounding, e.g.
/// at 3e-17 with integer data) and belong to the boundary, where they change no topology.
pub const INSIDE_EPS: f64 = 1e-9;

/// A saddle of the bilinear interpolant on one cell face.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FaceSaddle {
    /// Position in the face's own coordinates `(u, v)` along its two in-plane axes
    /// (lower-numbered axis first), at least [`INSIDE_EPS`] inside `(0, 1)^2`.
    pub uv: [f64; 2],
    /// Value of the bilinear interpolant at the saddle.
    pub value: f64,
}

/// The saddle of the bilinear interpolant with corner values `q` given in
/// [`face_corners`] cyclic order `(f00, f10, f11, f01)`, if it lies inside the face by at least
/// [`INSIDE_EPS`].
///
/// Degenerate faces (parallel asymptotes, i.e. `f00 + f11 == f10 + f01`, including
/// constant faces) and saddles on, next to or outside the face's edges give `None`.
#[inline]
pub fn face_saddle_of(q: [f64; 4]) -> Option<FaceSaddle> {
    let [f00, f10, f11, f01] = q;
    let d = f00 - f10 - f01 + f11;
    if d == 0.0 {
        return None;
    }
    let u = (f00 - f01) / d;
    let v = (f00 - f10) / d;
    if !(u > INSIDE_EPS && u < 1.0 - INSIDE_EPS && v > INSIDE_EPS && v < 1.0 - INSIDE_EPS) {
        return None;
    }
    Some(FaceSaddle {
        uv: [u, v],
        value: (f00 * f11 - f10 * f01) / d,
    })
}

/// The face saddle of face `f` of a cell with corner values `v`.
#[inline]
pub fn face_saddle(v: &[f64; 8], f: usize) -> Option<FaceSaddle> {
    let fc = face_corners(f);
    face_saddle_of([v[fc[0]], v[fc[1]], v[fc[2]], v[fc[3]]])
}

/// Face saddles are placed at their true face coordinates clamped into
/// `[FACE_SADDLE_CLAMP.0, FACE_SADDLE_CLAMP.1]²`, which keeps every tet around them positive.
pub const FACE_SADDLE_CLAMP: (f64, f64) = (0.3, 0.7);

/// Cell-local 3D position at which a face saddle with face coordinates `uv` is placed on
/// face `f` (its true position clamped by [`FACE_SADDLE_CLAMP`]).
#[inline]
pub fn face_saddle_point(f: usize, uv: [f64; 2]) -> [f64; 3] {
    let (lo, hi) = FACE_SADDLE_CLAMP;
    face_point(f, uv.map(|x| x.clamp(lo, hi)))
}

/// Cell-local 3D position of a point with face coordinates `uv` on face `f`.
#[inline]
pub fn face_point(f: usize, uv: [f64; 2]) -> [f64; 3] {
    let axis = f / 2;
    let (a, b) = match axis {
        0 => (1, 2),
        1 => (0, 2),
        _ => (0, 1),
    };
    let mut p = [0.0; 3];
    p[axis] = (f % 2) as f64;
    p[a] = uv[0];
    p[b] = uv[1];
    p
}

/// A saddle of the trilinear interpolant strictly inside the cell.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodySaddle {
    /// Cell-local position, at least [`INSIDE_EPS`] inside `(0, 1)^3`.
    pub pos: [f64; 3],
    /// Value of the trilinear interpolant there.
    pub value: f64,
}

/// Coefficients `[a, b, c, d, e, f, g, h]` of
/// `F = a + b x + c y + d z + e xy + f yz + g xz + h xyz` for corner values `v`.
#[inline]
pub fn coefficients(v: &[f64; 8]) -> [f64; 8] {
    [
        v[0],
        v[1] - v[0],
        v[2] - v[0],
        v[4] - v[0],
        v[0] - v[1] - v[2] + v[3],
        v[0] - v[2] - v[4] + v[6],
        v[0] - v[1] - v[4] + v[5],
        -v[0] + v[1] + v[2] - v[3] + v[4] - v[5] - v[6] + v[7],
    ]
}

/// Hessian of `F` (coefficients `k`, see [`coefficients`]) at cell-local point `p`: zero
/// diagonal, `F_xy = e + h z`, `F_yz = f + h x`, `F_xz = g + h y` off it.
#[inline]
pub fn hessian(k: &[f64; 8], p: [f64; 3]) -> Matrix3<f64> {
    let [_, _, _, _, e, f, g, h] = *k;
    let (fxy, fyz, fxz) = (e + h * p[2], f + h * p[0], g + h * p[1]);
    Matrix3::new(0.0, fxy, fxz, fxy, 0.0, fyz, fxz, fyz, 0.0)
}

/// The body saddles (0, 1 or 2) inside the cell (by at least [`INSIDE_EPS`]), sorted by increasing value.
///
/// The gradient of a trilinear function vanishes where (with `h != 0` and the shift
/// `x = X - f/h`, `y = Y - g/h`, `z = Z - e/h`) `YZ = p`, `XZ = q`, `XY = r`, so
/// `X = ±sqrt(qr/p)`; with `h == 0` the system is linear. Trilinear functions are harmonic,
/// so every interior critical point is a saddle. Degenerate cells (lines of critical points,
/// a singular linear system) report no body saddle.
pub fn body_saddles(v: &[f64; 8]) -> ([BodySaddle; 2], usize) {
    let [_, b, c, d, e, f, g, h] = coefficients(v);
    let mut out = [BodySaddle {
        pos: [0.0; 3],
        value: 0.0,
    }; 2];
    let mut n = 0;
    let mut push = |p: [f64; 3]| {
        if p.iter().all(|&x| x > INSIDE_EPS && x < 1.0 - INSIDE_EPS) {
            out[n] = BodySaddle {
                pos: p,
                value: eval(v, p),
            };
            n += 1;
        }
    };
    if h != 0.0 {
        let h2 = h * h;
        let p = (e * g - b * h) / h2;
        let q = (e * f - c * h) / h2;
        let r = (f * g - d * h) / h2;
        if p != 0.0 && q != 0.0 && r != 0.0 {
            let x2 = q * r / p;
            if x2 > 0.0 {
                let xs = x2.sqrt();
                for sx in [xs, -xs] {
                    let (yy, zz) = (r / sx, q / sx);
                    push([sx - f / h, yy - g / h, zz - e / h]);
                }
            }
        }
    } else {
        // [0 e g; e 0 f; g f 0] (x y z)^T = -(b c d)^T, the (constant) Hessian system, by
        // Cramer's rule with the closed-form determinant `2efg`
        let det = 2.0 * e * f * g;
        if det != 0.0 {
            let m = hessian(&[0.0, b, c, d, e, f, g, 0.0], [0.0; 3]);
            let rhs = Vector3::new(-b, -c, -d);
            let sol = std::array::from_fn(|col| {
                let mut mm = m;
                mm.set_column(col, &rhs);
                mm.determinant() / det
            });
            push(sol);
        }
    }
    if n == 2 && out[1].value < out[0].value {
        out.swap(0, 1);
    }
    (out, n)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grad(v: &[f64; 8], p: [f64; 3]) -> [f64; 3] {
        let hstep = 1e-6;
        let mut g = [0.0; 3];
        for a in 0..3 {
            let mut p1 = p;
            let mut p0 = p;
            p1[a] += hstep;
            p0[a] -= hstep;
            g[a] = (eval(v, p1) - eval(v, p0)) / (2.0 * hstep);
        }
        g
    }

    fn rng(seed: &mut u64) -> f64 {
        *seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((*seed >> 11) as f64) / ((1u64 << 53) as f64)
    }

    #[test]
    fn eval_interpolates_corners() {
        let v = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.5];
        for (c, &val) in v.iter().enumerate() {
            let p = [(c & 1) as f64, ((c >> 1) & 1) as f64, ((c >> 2) & 1) as f64];
            assert_eq!(eval(&v, p), val);
        }
    }

    #[test]
    fn face_saddle_has_zero_gradient_and_matches_value() {
        // f = (u - 0.3)(v - 0.6) -> saddle at (0.3, 0.6), value 0
        let f = |u: f64, v: f64| (u - 0.3) * (v - 0.6) + 2.0;
        let q = [f(0.0, 0.0), f(1.0, 0.0), f(1.0, 1.0), f(0.0, 1.0)];
        let s = face_saddle_of(q).unwrap();
        assert!((s.uv[0] - 0.3).abs() < 1e-12 && (s.uv[1] - 0.6).abs() < 1e-12);
        assert!((s.value - 2.0).abs() < 1e-12);
        // parallel asymptotes / linear faces have no saddle
        assert!(face_saddle_of([0.0, 1.0, 2.0, 1.0]).is_none());
        // saddle outside the face
        let g = |u: f64, v: f64| (u - 1.5) * (v - 0.5);
        assert!(face_saddle_of([g(0.0, 0.0), g(1.0, 0.0), g(1.0, 1.0), g(0.0, 1.0)]).is_none());
    }

    #[test]
    fn body_saddles_are_critical_points_inside() {
        let mut seed = 7u64;
        let mut found = [0usize; 3];
        for _ in 0..20000 {
            let v: [f64; 8] = std::array::from_fn(|_| rng(&mut seed) * 2.0 - 1.0);
            let (bs, n) = body_saddles(&v);
            found[n] += 1;
            for s in &bs[..n] {
                let g = grad(&v, s.pos);
                assert!(
                    g.iter().all(|x| x.abs() < 1e-6),
                    "gradient {g:?} at {:?} for {v:?}",
                    s.pos
                );
                assert!((eval(&v, s.pos) - s.value).abs() < 1e-12);
            }
            if n == 2 {
                assert!(bs[0].value <= bs[1].value);
            }
        }
        assert!(found[1] > 0 && found[2] > 0, "{found:?}");
    }

    #[test]
    fn body_saddle_of_h_zero_cell() {
        // f = (x-0.5)(y-0.5) + (y-0.5)(z-0.5) + (x-0.5)(z-0.5): h = 0, critical point at centre
        let f = |x: f64, y: f64, z: f64| {
            (x - 0.5) * (y - 0.5) + (y - 0.5) * (z - 0.5) + (x - 0.5) * (z - 0.5)
        };
        let v: [f64; 8] = std::array::from_fn(|c| {
            f((c & 1) as f64, ((c >> 1) & 1) as f64, ((c >> 2) & 1) as f64)
        });
        let (bs, n) = body_saddles(&v);
        assert_eq!(n, 1);
        assert!(bs[0].pos.iter().all(|x| (x - 0.5).abs() < 1e-12));
    }
}
