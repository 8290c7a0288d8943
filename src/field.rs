//! The trilinear field of a grid, evaluated anywhere in index space, and Newton projection of
//! a point onto one of its level sets along a subset of the axes.

use nalgebra::{Matrix3, Point3};

use crate::algebra::{array3, rows};
use crate::geom::norm;
use crate::grid::ScalarGrid;
use crate::trilinear;

/// How far (index units, voxels) a boundary triangle may leave its level set, as the guard
/// measures it: below the half voxel that the checker allows, so that the checker's own
/// search, which tries more directions, always finds the level set within its bound.
pub const GUARD_DISTANCE: f64 = 0.4;

/// The piecewise-trilinear interpolant of a [`ScalarGrid`], in index coordinates
/// (grid vertex `(i, j, k)` at `(i, j, k)`).
#[derive(Clone, Copy)]
pub struct Field<'a> {
    grid: &'a ScalarGrid,
    /// Inverse of [`ScalarGrid::linear_map`]: physical offset → index offset.
    inverse: Matrix3<f64>,
    /// `inverse` as row-major arrays (what [`Field::inverse`] lends).
    inverse_rows: [[f64; 3]; 3],
}

/// `g` with the components of the axes whose bit is not set in `free_axes` zeroed.
fn on_axes(mut g: [f64; 3], free_axes: u8) -> [f64; 3] {
    for (a, ga) in g.iter_mut().enumerate() {
        if free_axes & (1 << a) == 0 {
            *ga = 0.0;
        }
    }
    g
}

/// Newton steps tried by [`Field::project`] before giving up.
const NEWTON_STEPS: usize = 30;

impl<'a> Field<'a> {
    /// The interpolant of `grid`.
    pub fn new(grid: &'a ScalarGrid) -> Self {
        // A grid that passed `ScalarGrid::with_geometry` has an invertible map; one built
        // field by field with a singular map gets NaN (as dividing by its zero determinant did).
        let inverse = grid
            .linear_matrix()
            .try_inverse()
            .unwrap_or_else(|| Matrix3::from_element(f64::NAN));
        Field {
            grid,
            inverse,
            inverse_rows: rows(&inverse),
        }
    }

    /// Inverse of [`ScalarGrid::linear_map`] (physical offset → index offset); row `a` is the
    /// physical gradient of index coordinate `a`.
    pub fn inverse(&self) -> &[[f64; 3]; 3] {
        &self.inverse_rows
    }

    /// [`Field::inverse`] as a `nalgebra` matrix.
    pub fn inverse_matrix(&self) -> &Matrix3<f64> {
        &self.inverse
    }

    /// The grid.
    pub fn grid(&self) -> &ScalarGrid {
        self.grid
    }

    /// Index coordinates of physical point `x`.
    pub fn to_index(&self, x: [f64; 3]) -> [f64; 3] {
        array3(&(self.inverse * (Point3::from(x) - self.grid.origin_point())))
    }

    /// Physical position of index point `u`.
    pub fn to_physical(&self, u: [f64; 3]) -> [f64; 3] {
        self.grid.to_physical(u)
    }

    /// The cell holding `u` (clamped to the grid) and `u`'s cell-local coordinates.
    #[inline]
    fn locate(&self, u: [f64; 3]) -> ([usize; 3], [f64; 3]) {
        let mut cell = [0usize; 3];
        let mut t = [0.0; 3];
        for a in 0..3 {
            let hi = self.grid.dims[a] - 2;
            // Truncation is the floor once negatives are clamped to 0 (and `floor` is a call
            // into libm on baseline x86-64).
            let c = (u[a].max(0.0) as usize).min(hi);
            cell[a] = c;
            t[a] = u[a] - c as f64;
        }
        (cell, t)
    }

    /// Value of the interpolant at index point `u` (extrapolated linearly outside the box).
    pub fn value(&self, u: [f64; 3]) -> f64 {
        let (c, t) = self.locate(u);
        trilinear::eval(&self.grid.cell_values(c[0], c[1], c[2]), t)
    }

    /// Value and index-space gradient of the interpolant at `u`.
    pub fn value_gradient(&self, u: [f64; 3]) -> (f64, [f64; 3]) {
        let (c, t) = self.locate(u);
        Self::value_gradient_in(&self.grid.cell_values(c[0], c[1], c[2]), t)
    }

    /// Value and gradient in a cell with corner values `v` at cell-local point `[x, y, z]`.
    #[inline]
    fn value_gradient_in(v: &[f64; 8], [x, y, z]: [f64; 3]) -> (f64, [f64; 3]) {
        let lerp = |a: f64, b: f64, s: f64| a + (b - a) * s;
        // Along x on the four x-edges, then the rest.
        let e = [0, 2, 4, 6].map(|i| (lerp(v[i], v[i + 1], x), v[i + 1] - v[i]));
        let fy0 = lerp(e[0].0, e[1].0, y);
        let fy1 = lerp(e[2].0, e[3].0, y);
        let value = lerp(fy0, fy1, z);
        let gx = lerp(lerp(e[0].1, e[1].1, y), lerp(e[2].1, e[3].1, y), z);
        let gy = lerp(e[1].0 - e[0].0, e[3].0 - e[2].0, z);
        let gz = fy1 - fy0;
        (value, [gx, gy, gz])
    }

    /// Value and index-space gradient at `u`, the gradient restricted to the axes whose bit is
    /// set in `free_axes` (the others zeroed).
    pub fn value_gradient_on(&self, u: [f64; 3], free_axes: u8) -> (f64, [f64; 3]) {
        let (f, g) = self.value_gradient(u);
        (f, on_axes(g, free_axes))
    }

    /// `d` without its component along the gradient at `u` (over `free_axes`): the part of
    /// `d` tangent to the level set through `u` (`d` itself where the gradient vanishes).
    pub fn tangent(&self, u: [f64; 3], free_axes: u8, mut d: [f64; 3]) -> [f64; 3] {
        let (_, n) = self.value_gradient_on(u, free_axes);
        let n2 = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
        if n2 > 0.0 {
            let s = (d[0] * n[0] + d[1] * n[1] + d[2] * n[2]) / n2;
            for a in 0..3 {
                d[a] -= s * n[a];
            }
        }
        d
    }

    /// Moves `u` onto the level set `f = level` by Newton steps along the gradient restricted
    /// to the axes whose bit is set in `free_axes`, staying inside the grid box. Returns the
    /// projected point when `|f - level| <= tol` was reached, `None` otherwise.
    pub fn project(&self, u: [f64; 3], level: f64, free_axes: u8, tol: f64) -> Option<[f64; 3]> {
        let mut p = u;
        // The corner values of the cell the last step ended in: most steps stay in it.
        let mut cell: Option<([usize; 3], [f64; 8])> = None;
        for _ in 0..NEWTON_STEPS {
            let (c, t) = self.locate(p);
            let v = match cell {
                Some((at, v)) if at == c => v,
                _ => {
                    let v = self.grid.cell_values(c[0], c[1], c[2]);
                    cell = Some((c, v));
                    v
                }
            };
            let (f, g) = Self::value_gradient_in(&v, t);
            let g = on_axes(g, free_axes);
            let r = f - level;
            if r.abs() <= tol {
                return Some(p);
            }
            let g2 = g[0] * g[0] + g[1] * g[1] + g[2] * g[2];
            if g2 == 0.0 || !g2.is_finite() {
                return None;
            }
            // Newton step, at most a quarter voxel at a time.
            let mut s = -r / g2;
            let len = s.abs() * g2.sqrt();
            if len > 0.25 {
                s *= 0.25 / len;
            }
            for a in 0..3 {
                let hi = (self.grid.dims[a] - 1) as f64;
                p[a] = (p[a] + s * g[a]).clamp(0.0, hi);
            }
        }
        let f = self.value(p);
        ((f - level).abs() <= tol).then_some(p)
    }

    /// A point of the level set near `u` where Newton steps ([`Field::project`]) do not
    /// settle (the gradient jumps across cell faces, or vanishes): walks from `u` towards
    /// `level` along the gradient at `u` and along each lattice direction (axes, face and
    /// body diagonals, both ways) that keeps the fixed axes, in steps of
    /// `MARCH_STEP` (0.05) up to `MARCH_REACH` (1) voxel, bisects the first step of each walk
    /// that crosses the level (the trilinear field is continuous, so that step holds a point
    /// of the level) and returns the nearest point found.
    pub fn march(&self, u: [f64; 3], level: f64, free_axes: u8, tol: f64) -> Option<[f64; 3]> {
        let (f0, g) = self.value_gradient_on(u, free_axes);
        let side = (f0 - level).signum();
        let n = norm(g);
        let mut dirs: Vec<[f64; 3]> = Vec::with_capacity(27);
        if n > 0.0 && n.is_finite() {
            dirs.push(g.map(|x| -side * x / n));
        }
        // The 26 lattice directions that keep the fixed axes: the gradient at `u` can point
        // out of its cell towards a rise, while the level lies across a diagonal.
        for code in 0..27usize {
            let d = [code % 3, code / 3 % 3, code / 9].map(|k| k as f64 - 1.0);
            let keeps = (0..3).all(|a| d[a] == 0.0 || free_axes & (1 << a) != 0);
            if code != 13 && keeps {
                let n = norm(d);
                dirs.push(d.map(|x| x / n));
            }
        }
        dirs.into_iter()
            .filter_map(|d| self.walk(u, d, (level, side), tol))
            .min_by(|x, y| x.0.total_cmp(&y.0))
            .map(|(_, p)| p)
    }

    /// One walk of [`Field::march`] along the unit direction `d`: `(distance, point)` of the
    /// first crossing of `level`, from the side `side` (the sign of `f(u) - level`).
    fn walk(
        &self,
        u: [f64; 3],
        d: [f64; 3],
        (level, side): (f64, f64),
        tol: f64,
    ) -> Option<(f64, [f64; 3])> {
        let at = |t: f64| -> [f64; 3] { std::array::from_fn(|a| u[a] + t * d[a]) };
        let crossed = |t: f64| (self.value(at(t)) - level) * side <= 0.0;
        let (mut a, mut b) = self.first_step_across(u, d, (MARCH_STEP, MARCH_REACH), crossed)?;
        for _ in 0..BISECTIONS {
            let m = 0.5 * (a + b);
            let r = self.value(at(m)) - level;
            if r.abs() <= tol {
                return Some((m, at(m)));
            }
            if r * side > 0.0 {
                a = m;
            } else {
                b = m;
            }
        }
        None
    }
}

impl Field<'_> {
    /// Whether the level set `f = level` passes within `bound` (index units) of index point
    /// `u`: `|f(u) - level| <= tol`, or `f - level` changes sign along a segment of length
    /// `bound` from `u` (down the gradient towards the level first, then along the 26 lattice
    /// directions). A sign change is a witness: the answer `true` is never wrong; `false` may
    /// be, where the level set is near but found along none of these segments.
    pub fn near_level(&self, u: [f64; 3], level: f64, bound: f64, tol: f64) -> bool {
        let (f, g) = self.value_gradient(u);
        let d = f - level;
        if d.abs() <= tol {
            return true;
        }
        let crosses = |dir: [f64; 3]| {
            let norm = (dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]).sqrt();
            if norm == 0.0 || !norm.is_finite() {
                return false;
            }
            (1..=4).any(|k| {
                let s = bound * k as f64 / 4.0 / norm;
                let p = [0, 1, 2].map(|a| u[a] + s * dir[a]);
                (self.value(p) - level) * d.signum() <= 0.0
            })
        };
        let down = g.map(|c| -c * d.signum());
        if crosses(down) {
            return true;
        }
        (0..27).filter(|&i| i != 13).any(|i| {
            let dir = [i % 3, (i / 3) % 3, i / 9].map(|c| c as f64 - 1.0);
            crosses(dir)
        })
    }

    /// Walks from `c` along unit direction `d` in steps of `step` up to `reach` (index units)
    /// and returns the first step `(t - step, t)` with `crossed(t)`; `None` when the walk leaves
    /// the grid box or reaches `reach` first. Callers bisect the step.
    pub fn first_step_across(
        &self,
        c: [f64; 3],
        d: [f64; 3],
        (step, reach): (f64, f64),
        crossed: impl Fn(f64) -> bool,
    ) -> Option<(f64, f64)> {
        let dims = self.grid.dims;
        let inside = |t: f64| {
            (0..3).all(|a| {
                let x = c[a] + t * d[a];
                x >= 0.0 && x <= (dims[a] - 1) as f64
            })
        };
        let mut t = 0.0;
        while t < reach {
            let next = t + step;
            if !inside(next) {
                return None;
            }
            if crossed(next) {
                return Some((t, next));
            }
            t = next;
        }
        None
    }
}

/// Step (index units) of [`Field::march`].
const MARCH_STEP: f64 = 0.05;
/// How far [`Field::march`] walks (index units).
const MARCH_REACH: f64 = 1.0;
/// Bisections of the step across the level in [`Field::march`] (enough for any `f64`).
const BISECTIONS: usize = 80;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::ScalarGrid;

    fn sphere_grid(n: usize) -> ScalarGrid {
        let c = (n - 1) as f64 / 2.0;
        let mut v = Vec::with_capacity(n * n * n);
        for k in 0..n {
            for j in 0..n {
                for i in 0..n {
                    let d = [i, j, k].map(|x| x as f64 - c);
                    v.push((d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt());
                }
            }
        }
        let dir = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]];
        ScalarGrid::with_geometry([n; 3], [0.5, 1.5, 2.0], [3.0, -1.0, 7.0], dir, v).unwrap()
    }

    #[test]
    fn index_and_physical_round_trip() {
        let g = sphere_grid(6);
        let f = Field::new(&g);
        let u = [1.25, 3.5, 0.75];
        let back = f.to_index(f.to_physical(u));
        for a in 0..3 {
            assert!((back[a] - u[a]).abs() < 1e-12);
        }
    }

    #[test]
    fn gradient_matches_differences_and_values_match_grid() {
        let g = sphere_grid(7);
        let f = Field::new(&g);
        assert_eq!(f.value([2.0, 3.0, 4.0]), g.value(2, 3, 4));
        assert_eq!(f.value([6.0, 6.0, 6.0]), g.value(6, 6, 6));
        let u = [2.3, 1.7, 4.4];
        let (v, gr) = f.value_gradient(u);
        assert!((v - f.value(u)).abs() < 1e-12);
        for a in 0..3 {
            let mut p = u;
            p[a] += 1e-6;
            let num = (f.value(p) - v) / 1e-6;
            assert!((num - gr[a]).abs() < 1e-5, "{a}: {num} vs {}", gr[a]);
        }
    }

    #[test]
    fn projection_reaches_the_level_on_free_axes_only() {
        let g = sphere_grid(9);
        let f = Field::new(&g);
        let u = [5.9, 4.2, 4.0];
        let p = f.project(u, 2.0, 0b111, 1e-12).unwrap();
        assert!((f.value(p) - 2.0).abs() <= 1e-12);
        let q = f.project(u, 2.0, 0b001, 1e-12).unwrap();
        assert!((f.value(q) - 2.0).abs() <= 1e-12);
        assert_eq!((q[1], q[2]), (u[1], u[2]));
        // No solution along y from a point whose level is out of reach inside the box.
        assert!(f.project([4.0, 4.0, 4.0], 9.0, 0b010, 1e-9).is_none());
    }

    /// A plateau `f = 0` for `i <= 1`, then `f = i - 1`.
    fn plateau_grid() -> ScalarGrid {
        let v: Vec<f64> = (0..4 * 3 * 3)
            .map(|n| ((n % 4) as f64 - 1.0).max(0.0))
            .collect();
        ScalarGrid::with_geometry([4, 3, 3], [1.0; 3], [0.0; 3], IDENTITY, v).unwrap()
    }

    const IDENTITY: [[f64; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

    #[test]
    fn march_finds_the_level_where_newton_has_no_gradient() {
        let g = plateau_grid();
        let f = Field::new(&g);
        let u = [0.5, 1.0, 1.0];
        assert!(
            f.project(u, 0.3, 0b111, 1e-12).is_none(),
            "no gradient on the plateau"
        );
        let p = f
            .march(u, 0.3, 0b111, 1e-12)
            .expect("the level is 0.8 away along +x");
        assert!((f.value(p) - 0.3).abs() <= 1e-12);
        for (a, want) in [1.3, 1.0, 1.0].into_iter().enumerate() {
            assert!((p[a] - want).abs() < 1e-9, "{p:?}");
        }
        // Along the fixed axes only, or farther than the reach, there is nothing to find.
        assert!(f.march(u, 0.3, 0b110, 1e-12).is_none());
        assert!(f.march(u, 1.5, 0b111, 1e-12).is_none());
    }

    #[test]
    fn march_finds_the_level_across_a_diagonal_when_the_gradient_leads_to_a_rise() {
        // MNI152 T1 voxels [44, 48) × [101, 105) × [127, 131): the level vertex of the
        // interval [101.5, 151.5] at u (f = 104.85) that the pass could not settle. Newton
        // fails, the gradient at u points out of its cell towards a rise, and no axis reaches
        // 101.5 within a voxel; two diagonals do.
        let v = [
            163, 142, 121, 106, 144, 121, 106, 110, 121, 105, 108, 138, 102, 105, 134, 171, 139,
            123, 108, 104, 116, 103, 102, 125, 99, 98, 122, 161, 95, 115, 158, 184, 111, 103, 98,
            112, 98, 96, 109, 147, 93, 103, 139, 178, 98, 127, 171, 187, 99, 94, 98, 124, 95, 96,
            119, 161, 95, 110, 150, 184, 100, 134, 176, 189,
        ];
        let v: Vec<f64> = v.iter().map(|&x| x as f64).collect();
        let g = ScalarGrid::with_geometry([4; 3], [1.0; 3], [0.0; 3], IDENTITY, v).unwrap();
        let f = Field::new(&g);
        let u = [
            1.739_130_434_782_61,
            1.152_173_913_043_47,
            1.108_695_652_173_9,
        ];
        let (level, tol) = (101.5, 1e-9);
        assert!((f.value(u) - 104.85).abs() < 0.01);
        assert!(f.project(u, level, 0b111, tol).is_none());
        let side = (f.value(u) - level).signum();
        for a in 0..3 {
            for s in [-1.0, 1.0] {
                let mut d = [0.0; 3];
                d[a] = s;
                assert!(f.walk(u, d, (level, side), tol).is_none(), "axis {a} {s}");
            }
        }
        let p = f.march(u, level, 0b111, tol).expect("a diagonal crosses");
        assert!((f.value(p) - level).abs() <= tol);
        assert!(crate::geom::distance(p, u) <= 1.0, "{p:?}");
        // With x fixed, the diagonals that move x are not walked.
        assert!(f
            .march(u, level, 0b110, tol)
            .is_none_or(|q| (q[0] - u[0]).abs() < 1e-12));
    }
}
