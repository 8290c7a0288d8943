//! Face saddles: saddles of the bilinear interpolant on grid faces that are critical points of the
//! piecewise-trilinear field (Lemma 4 of “Exploring scalar fields using critical isovalues”), on
//! interior faces and on the grid box.
//!
//! Rotate the face so that its corners `A, C` (a diagonal) lie above the saddle value `s` and
//! `B, D` below, and shift all values by `-s`. On the plane at distance `t` into one of the two
//! cells the bilinear slice has corners `A_t = A + t (A' - A)` etc. (primes: the corners one step
//! into that cell), its asymptotic-decider value `A_t C_t - B_t D_t` is 0 at `t = 0` and its
//! derivative there is `d = C (A' - A) + A (C' - C) - D (B' - B) - B (D' - D)`. With `d > 0` the
//! slices just inside that cell connect `A` and `C` (the upper corners), with `d < 0` they connect
//! `B` and `D`. The saddle is a saddle of the whole field iff both cells connect the same pair; on
//! the grid box, where only one cell exists, the pair the cell does *not* connect stays apart,
//! which changes only one of the two filtrations. `d = 0` is degenerate (a curve of critical points
//! crosses the cell, “Detecting critical regions in scalar fields” §5.3): the point is reported as
//! such.

use super::vertex::LinkClass;

/// Link class and degeneracy of a face saddle.
///
/// `q`: the four face values in cyclic order (`face_corners` order); `s`: the saddle value;
/// `sides[0]`, `sides[1]`: the values one step across the face on the lower and the upper
/// side of the face's normal axis, in the same order, `None` on the grid box.
/// Returns `None` when the saddle is regular, `Some((class, degenerate))` otherwise.
pub fn classify_face_saddle(
    q: [f64; 4],
    s: f64,
    sides: [Option<[f64; 4]>; 2],
) -> Option<(LinkClass, bool)> {
    // rotate so that entries 0 and 2 are the upper diagonal
    let r = if q[0] > s { 0 } else { 1 };
    let at = |a: &[f64; 4], i: usize| a[(i + r) % 4];
    let [a, b, c, d] = [0, 1, 2, 3].map(|i| at(&q, i) - s);
    let deriv = |o: &[f64; 4]| {
        let [a1, b1, c1, d1] = [0, 1, 2, 3].map(|i| at(o, i) - s);
        let x = c * (a1 - a) + a * (c1 - c) - d * (b1 - b) - b * (d1 - d);
        // zero up to rounding (integer data hits exact zeros that rounding blurs)
        let scale = (a.abs() + b.abs() + c.abs() + d.abs())
            * ((a1 - a).abs() + (b1 - b).abs() + (c1 - c).abs() + (d1 - d).abs());
        if x.abs() <= 1e-12 * scale {
            0.0
        } else {
            x
        }
    };
    let ds: Vec<f64> = sides.iter().flatten().map(deriv).collect();
    if ds.contains(&0.0) {
        let both = LinkClass {
            upper: [2, 0, 0],
            lower: [2, 0, 0],
        };
        return Some((both, true));
    }
    let upper_joined = ds.iter().filter(|&&x| x > 0.0).count();
    let lower_joined = ds.len() - upper_joined;
    let class = match (upper_joined, lower_joined) {
        // both cells join the upper corners: the upper link is a ring, the lower two pieces
        (2, 0) => LinkClass {
            upper: [1, 1, 0],
            lower: [2, 0, 0],
        },
        (0, 2) => LinkClass {
            upper: [2, 0, 0],
            lower: [1, 1, 0],
        },
        // on the box, one cell: the pair it joins is one disk, the other pair stays apart
        (1, 0) => LinkClass {
            upper: [1, 0, 0],
            lower: [2, 0, 0],
        },
        (0, 1) => LinkClass {
            upper: [2, 0, 0],
            lower: [1, 0, 0],
        },
        _ => return None,
    };
    Some((class, false))
}

/// Every saddle of the bilinear interpolant on a grid face (critical for the field or not) with
/// a value in `[lo, hi]`: `(value, physical position)`, in grid order. Regular ones change no
/// topology, but they are vertices of the TPTD decomposition, so a mesh bound equal to one
/// makes elements with a vertex on the bound (flat or needle-shaped).
pub fn face_saddles_in(grid: &crate::ScalarGrid, lo: f64, hi: f64) -> Vec<(f64, [f64; 3])> {
    use rayon::prelude::*;
    let cd = grid.cell_dims();
    (0..grid.dims[2])
        .into_par_iter()
        .flat_map_iter(|k| {
            let mut out = Vec::new();
            let ck = k.min(cd[2] - 1);
            let rows = super::find::RowRanges::new(grid, ck);
            for j in 0..grid.dims[1] {
                // every face visited from here has its corners in cell row `(j, k)` (clamped),
                // those of `i` in cell `i` (clamped: the last block reaches the box)
                let hit = |a: f64, b: f64| b >= lo && a <= hi;
                for i in rows.live_x(grid, j.min(cd[1] - 1), grid.dims[0], hit) {
                    let c = [i.min(cd[0] - 1), j.min(cd[1] - 1), ck];
                    let v = grid.cell_values(c[0], c[1], c[2]);
                    // the low faces of the cell at (i, j, k) (the high box faces from the last cell)
                    for f in 0..6 {
                        let axis = f / 2;
                        let p = [i, j, k];
                        let fits = (0..3).all(|a| if a == axis { true } else { p[a] < cd[a] });
                        let side_ok = if f % 2 == 0 {
                            p[axis] < cd[axis]
                        } else {
                            p[axis] == cd[axis]
                        };
                        if !fits || !side_ok {
                            continue;
                        }
                        let Some(s) = crate::trilinear::face_saddle(&v, f) else {
                            continue;
                        };
                        if s.value < lo || s.value > hi {
                            continue;
                        }
                        let local = crate::trilinear::face_point(f, s.uv);
                        let idx = [0, 1, 2].map(|a| c[a] as f64 + local[a]);
                        out.push((s.value, grid.to_physical(idx)));
                    }
                }
            }
            out
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lemma4_cases() {
        // checkerboard face 1,0,1,0 (saddle 0.5); above it +1 everywhere, below -1:
        // one cell joins the upper corners, the other the lower: regular
        let q = [1.0, 0.0, 1.0, 0.0];
        assert_eq!(
            classify_face_saddle(q, 0.5, [Some([-1.0; 4]), Some([2.0; 4])]),
            None
        );
        // both sides higher: both join the upper corners, a saddle of both filtrations
        let (c, deg) = classify_face_saddle(q, 0.5, [Some([2.0; 4]), Some([3.0; 4])]).unwrap();
        assert!(!deg && c.superlevel() && c.sublevel());
        assert_eq!(c.upper, [1, 1, 0]);
        // rotated face (upper diagonal at entries 1, 3) gives the same answer
        let q2 = [0.0, 1.0, 0.0, 1.0];
        let (c2, _) = classify_face_saddle(q2, 0.5, [Some([2.0; 4]), Some([3.0; 4])]).unwrap();
        assert_eq!(c, c2);
        // on the box: one cell joining the upper corners changes only the sublevel sets
        let (c, _) = classify_face_saddle(q, 0.5, [None, Some([2.0; 4])]).unwrap();
        assert!(c.sublevel() && !c.superlevel());
        // the across-face checkerboard continuing (mean equal to the saddle value): degenerate
        let (_, deg) =
            classify_face_saddle(q, 0.5, [Some([0.0, 1.0, 0.0, 1.0]), Some([2.0; 4])]).unwrap();
        assert!(deg);
    }
}
