//! Saddles of the trilinear interpolant inside cells (“Exploring scalar fields using critical
//! isovalues” §3.4): always critical points of the whole field. Their index comes from the Hessian,
//! whose diagonal is zero: `det H = 2 f_xy f_yz f_xz`. With `det H > 0` two eigenvalues are
//! negative (index 2: the lower link is a ring, the upper link two pieces), with `det H < 0` one is
//! (index 1).

use super::vertex::LinkClass;
use crate::trilinear::{body_saddles, coefficients, hessian, BodySaddle};

/// The body saddles of a cell with corner values `v`, with their link classes. A saddle with
/// a singular Hessian (degenerate) gets `None` as class.
pub fn classify_body_saddles(v: &[f64; 8]) -> Vec<(BodySaddle, Option<LinkClass>)> {
    let (bs, n) = body_saddles(v);
    let k = coefficients(v);
    bs[..n]
        .iter()
        .map(|s| {
            let hess = hessian(&k, s.pos);
            let det = hess.determinant();
            // zero up to rounding: a curve of critical points (degenerate); the sum of the
            // absolute entries is twice `|f_xy| + |f_yz| + |f_xz|`, and `det H` twice their
            // product
            let scale = (hess.abs().sum() / 2.0).powi(3);
            let class = if det.abs() <= 2e-12 * scale {
                None
            } else if det > 0.0 {
                Some(LinkClass {
                    upper: [2, 0, 0],
                    lower: [1, 1, 0],
                })
            } else {
                Some(LinkClass {
                    upper: [1, 1, 0],
                    lower: [2, 0, 0],
                })
            };
            (*s, class)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trilinear::eval;

    /// Counts the sign components of `f - f(p)` on a small sphere around `p`, sampled.
    fn sphere_components(v: &[f64; 8], p: [f64; 3], r: f64) -> (usize, usize) {
        let n = 60;
        let s = eval(v, p);
        let pt = |i: usize, j: usize| {
            let th = std::f64::consts::PI * (i as f64 + 0.5) / n as f64;
            let ph = 2.0 * std::f64::consts::PI * j as f64 / n as f64;
            [
                p[0] + r * th.sin() * ph.cos(),
                p[1] + r * th.sin() * ph.sin(),
                p[2] + r * th.cos(),
            ]
        };
        let sign: Vec<bool> = (0..n * n).map(|k| eval(v, pt(k / n, k % n)) > s).collect();
        let mut seen = vec![false; n * n];
        let mut counts = (0, 0);
        for start in 0..n * n {
            if seen[start] {
                continue;
            }
            if sign[start] {
                counts.0 += 1
            } else {
                counts.1 += 1
            }
            let mut stack = vec![start];
            seen[start] = true;
            while let Some(k) = stack.pop() {
                let (i, j) = (k / n, k % n);
                let mut nb = vec![i * n + (j + 1) % n, i * n + (j + n - 1) % n];
                if i > 0 {
                    nb.push((i - 1) * n + j);
                } else {
                    nb.extend(0..n); // the pole row is one neighbourhood
                }
                if i + 1 < n {
                    nb.push((i + 1) * n + j);
                } else {
                    nb.extend((0..n).map(|jj| (n - 1) * n + jj));
                }
                for q in nb {
                    if !seen[q] && sign[q] == sign[k] {
                        seen[q] = true;
                        stack.push(q);
                    }
                }
            }
        }
        counts
    }

    #[test]
    fn index_from_the_hessian_matches_the_sampled_neighbourhood() {
        let mut seed = 11u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 11) as f64) / ((1u64 << 53) as f64) * 2.0 - 1.0
        };
        let mut checked = 0;
        for _ in 0..4000 {
            let v: [f64; 8] = std::array::from_fn(|_| rnd());
            for (s, class) in classify_body_saddles(&v) {
                let Some(c) = class else { continue };
                if s.pos.iter().any(|&x| !(0.05..=0.95).contains(&x)) {
                    continue;
                }
                let (np, nn) = sphere_components(&v, s.pos, 0.01);
                assert_eq!(np, c.upper[0] as usize, "{v:?} {s:?}");
                assert_eq!(nn, c.lower[0] as usize, "{v:?} {s:?}");
                checked += 1;
            }
        }
        assert!(checked > 50, "{checked}");
    }
}
