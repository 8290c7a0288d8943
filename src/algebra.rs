//! The small dense algebra of the crate, on `nalgebra`'s fixed-size (stack) types, and the
//! conversions between them and the plain row-major arrays of the public API.
//!
//! `nalgebra`'s `Matrix3::from([[f64; 3]; 3])` reads the array as *columns*; the arrays of this
//! crate (a grid's `direction`, [`crate::ScalarGrid::linear_map`]) are *rows*. [`matrix3`] and
//! [`rows`] convert without that trap.
//!
//! Bit-for-bit notes, relied on to keep every output byte: `nalgebra`'s 3×3
//! [`determinant`](nalgebra::Matrix3::determinant) is the first-row cofactor expansion that the
//! hand-written `det3` computed, its 3×3 `try_inverse` computes each entry as the same cofactor
//! over that determinant, and a `Matrix3 * Vector3` product sums each row left to right
//! (`m[r][0] x + m[r][1] y + m[r][2] z`).

use nalgebra::{Matrix3, Vector3};

/// The `nalgebra` matrix of a row-major 3×3 array (`m[r][c]` is row `r`, column `c`).
#[inline]
pub fn matrix3(m: &[[f64; 3]; 3]) -> Matrix3<f64> {
    Matrix3::from_fn(|r, c| m[r][c])
}

/// The row-major array of a `nalgebra` matrix (the inverse of [`matrix3`]).
#[inline]
pub fn rows(m: &Matrix3<f64>) -> [[f64; 3]; 3] {
    std::array::from_fn(|r| std::array::from_fn(|c| m[(r, c)]))
}

/// The `nalgebra` vector of an array.
#[inline]
pub fn vector3(v: [f64; 3]) -> Vector3<f64> {
    Vector3::from(v)
}

/// The array of a `nalgebra` vector.
#[inline]
pub fn array3(v: &Vector3<f64>) -> [f64; 3] {
    [v.x, v.y, v.z]
}

/// Determinant of a row-major 3×3 matrix.
#[inline]
pub fn det3(m: &[[f64; 3]; 3]) -> f64 {
    matrix3(m).determinant()
}

/// Condition number of a 3×3 matrix in the 2-norm: its largest singular value over its
/// smallest (1 for a rotation, 2000 for `diag(1, 1, 0.0005)`); infinite when singular.
pub fn condition_number(m: &[[f64; 3]; 3]) -> f64 {
    // scaled to entries of at most 1, so that nothing below overflows
    let scale = m.iter().flatten().fold(0.0f64, |s, x| s.max(x.abs()));
    if scale == 0.0 || !scale.is_finite() {
        return f64::INFINITY;
    }
    let a = matrix3(m) / scale;
    let det = a.determinant();
    if det == 0.0 || !det.is_finite() {
        return f64::INFINITY;
    }
    let sv = a.svd(false, false).singular_values;
    let (hi, lo) = (sv.max(), sv.min());
    if lo > 0.0 {
        hi / lo
    } else {
        f64::INFINITY
    }
}

#[cfg(test)]
pub(crate) mod tests {
    /// A seeded xorshift stream uniform in [-1, 1): the random cases of the bit-for-bit tests.
    pub(crate) fn uniform_signed() -> impl FnMut() -> f64 {
        let mut seed = 0x2545_f491_4f6c_dd1d_u64;
        move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        }
    }

    use super::*;

    #[test]
    fn conversions_keep_rows_and_columns() {
        let m = [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0], [7.0, 8.0, 10.0]];
        let a = matrix3(&m);
        assert_eq!(a[(0, 1)], 2.0);
        assert_eq!(a[(1, 0)], 4.0);
        assert_eq!(rows(&a), m);
        assert_eq!(array3(&vector3([1.0, -2.0, 3.5])), [1.0, -2.0, 3.5]);
    }

    /// The cofactor expansion `nalgebra` computes is the one this crate always computed: the
    /// outputs keep their bytes.
    #[test]
    fn determinant_and_inverse_match_the_cofactor_formulas_bit_for_bit() {
        let mut next = uniform_signed();
        for _ in 0..1000 {
            let m: [[f64; 3]; 3] = std::array::from_fn(|_| std::array::from_fn(|_| next()));
            let det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
                - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
                + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
            assert_eq!(det3(&m).to_bits(), det.to_bits());
            let inv = rows(&matrix3(&m).try_inverse().unwrap());
            for (r, row) in inv.iter().enumerate() {
                for (c, x) in row.iter().enumerate() {
                    let (c1, c2) = ((c + 1) % 3, (c + 2) % 3);
                    let (r1, r2) = ((r + 1) % 3, (r + 2) % 3);
                    let want = (m[c1][r1] * m[c2][r2] - m[c1][r2] * m[c2][r1]) / det;
                    assert_eq!(*x, want, "entry ({r}, {c})");
                }
            }
            let v = [next(), next(), next()];
            let p = array3(&(matrix3(&m) * vector3(v)));
            for r in 0..3 {
                assert_eq!(p[r], m[r][0] * v[0] + m[r][1] * v[1] + m[r][2] * v[2]);
            }
        }
    }
}
