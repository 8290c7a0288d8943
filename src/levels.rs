//! The levels a run meshes between ([`Levels`]): their values, sorted, how values tied with
//! a level are handled, and the preparation of the data that keeps near ties out of the mesh.
//!
//! Levels pair up into intervals: level 0 is the lower bound of the first interval, level 1
//! its upper bound. The meshed set is the closure of the open intervals, so a value equal to
//! a lower bound (an even level) counts as below it and one equal to an upper bound (an odd
//! level) as above it. One interval `{alpha <= f <= beta}` is the case of two levels
//! ([`Levels::interval`]), with `-inf` or `+inf` standing for a missing bound.

use crate::grid::ScalarGrid;
use crate::samples::Samples;

/// Number of levels a [`Levels`] holds: the two bounds of one interval. Point keys reserve
/// enough bits for a level index to name this many (`keys::LEVEL_BITS`).
pub const MAX_LEVELS: usize = 2;

/// Fraction of the smallest gap between a level and the data values by which tied values are
/// moved outward when cuts are placed.
pub const TIE_FRACTION: f64 = 1e-3;

/// Values within this fraction of the data range of a level, but not equal to it, are set
/// onto the level before meshing.
pub const NEAR_TIE: f64 = 1e-9;

/// Which side of a level a value lies on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    /// Below the level, or equal to it when the level is a lower bound.
    Below,
    /// Above the level, or equal to it when the level is an upper bound.
    Above,
}

/// The sorted levels of a run (finite or infinite) and the values that data tied with each
/// level is moved to when cuts are placed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Levels {
    /// The levels, sorted (`-inf` / `+inf` for a missing bound).
    values: [f64; MAX_LEVELS],
    /// Per level, the value used for cut placement at vertices whose value equals the level:
    /// moved outward of the interval it bounds (the level itself until [`Levels::with_ties`]).
    ties: [f64; MAX_LEVELS],
}

impl Levels {
    /// The two levels of the interval `(alpha, beta)` (`alpha < beta`; `-inf` / `+inf` for a
    /// missing bound), ties not moved yet ([`Levels::with_ties`]).
    pub fn interval(alpha: f64, beta: f64) -> Self {
        Levels {
            values: [alpha, beta],
            ties: [alpha, beta],
        }
    }

    /// Number of levels.
    #[inline]
    pub const fn len(&self) -> usize {
        MAX_LEVELS
    }

    /// Whether there are no levels (never: an interval has two, possibly infinite).
    #[inline]
    pub const fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Level `i` (`i < len()`).
    #[inline]
    pub fn get(&self, i: usize) -> f64 {
        self.values[i]
    }

    /// The levels, in increasing order.
    #[inline]
    pub fn iter(&self) -> std::iter::Copied<std::slice::Iter<'_, f64>> {
        self.values.iter().copied()
    }

    /// The levels as an array, in increasing order.
    #[inline]
    pub fn values(&self) -> [f64; MAX_LEVELS] {
        self.values
    }

    /// The value that data equal to level `i` takes when cuts are placed.
    #[inline]
    pub fn tie(&self, i: usize) -> f64 {
        self.ties[i]
    }

    /// Whether level `i` is a lower bound (a value equal to it counts as below).
    #[inline]
    pub const fn is_lower(i: usize) -> bool {
        i.is_multiple_of(2)
    }

    /// Whether `v` lies below level `i` (equal counts as below for a lower bound). False for
    /// NaN.
    #[inline]
    pub fn below(&self, i: usize, v: f64) -> bool {
        if Self::is_lower(i) {
            v <= self.values[i]
        } else {
            v < self.values[i]
        }
    }

    /// Whether `v` lies above level `i` (equal counts as above for an upper bound). False for
    /// NaN.
    #[inline]
    pub fn above(&self, i: usize, v: f64) -> bool {
        if Self::is_lower(i) {
            v > self.values[i]
        } else {
            v >= self.values[i]
        }
    }

    /// Which side of level `i` the value `v` lies on (NaN counts as above).
    #[inline]
    pub fn side(&self, i: usize, v: f64) -> Side {
        if self.below(i, v) {
            Side::Below
        } else {
            Side::Above
        }
    }

    /// Whether `v` lies strictly between the first two levels (inside the interval).
    #[inline]
    pub fn inside(&self, v: f64) -> bool {
        v > self.values[0] && v < self.values[1]
    }

    /// Value of a (not snapped) vertex for cut placement: a value tied with a level moved to
    /// [`Levels::tie`].
    #[inline]
    pub fn effective(&self, v: f64) -> f64 {
        for i in 0..MAX_LEVELS {
            if v == self.values[i] {
                return self.ties[i];
            }
        }
        v
    }

    /// `v` set onto the first finite level within `tol` of it, else `v` itself.
    #[inline]
    pub fn onto_near(&self, v: f64, tol: f64) -> f64 {
        self.iter()
            .find(|&l| l.is_finite() && (v - l).abs() <= tol)
            .unwrap_or(v)
    }

    /// Distance from level `i` to its nearest level when both are finite, else `+inf`.
    fn width(&self, i: usize) -> f64 {
        let l = self.values[i];
        let gap = |j: usize| -> f64 {
            let m = self.values[j];
            if l.is_finite() && m.is_finite() {
                (l - m).abs()
            } else {
                f64::INFINITY
            }
        };
        let below = if i > 0 { gap(i - 1) } else { f64::INFINITY };
        let above = if i + 1 < MAX_LEVELS {
            gap(i + 1)
        } else {
            f64::INFINITY
        };
        below.min(above)
    }

    /// These levels with their tie values for data `values`: a tied value is moved outward
    /// (below a lower bound, above an upper one) by [`TIE_FRACTION`] of the smallest non-zero
    /// distance between the level and a data value (so, with integer data, by 10⁻³), at most
    /// a quarter of the distance to the next level.
    pub fn with_ties(self, values: &Samples) -> Self {
        let gap = |level: f64| -> f64 {
            if !level.is_finite() {
                return 0.0;
            }
            let g = values.par_fold(
                || f64::INFINITY,
                |m, v| {
                    let d = (v - level).abs();
                    if d > 0.0 {
                        m.min(d)
                    } else {
                        m
                    }
                },
                f64::min,
            );
            if g.is_finite() {
                g
            } else {
                1.0
            }
        };
        let mut ties = self.values;
        for (i, tie) in ties.iter_mut().enumerate() {
            let l = self.values[i];
            let d = (TIE_FRACTION * gap(l))
                .min(0.25 * self.width(i))
                .max(l.abs() * 4.0 * f64::EPSILON);
            *tie = if Self::is_lower(i) { l - d } else { l + d };
        }
        Levels { ties, ..self }
    }

    /// Removes the values of `grid` within [`NEAR_TIE`] × (data range) of a level but not
    /// equal to it. Such values (e.g. 0.9999999999999999 for a distance sampled on a sphere
    /// of radius 1) would put cuts within rounding of a grid vertex: the cut point and the
    /// vertex coincide in floating point, and tets between them vanish. As exact ties they
    /// follow the ties rule (`clip`), which keeps every tet non-degenerate. Returns the grid
    /// to mesh (`None`: `grid` itself) and the levels to mesh:
    /// * integer storage: a level moves onto the integer next to it (the tolerance is far
    ///   below 0.5, so no other value lies between them: the same interval of the data), no
    ///   copy;
    /// * float storage: a copy of the grid with those values set onto the level, in the same
    ///   storage type when it holds the levels exactly, else in `f64`.
    pub fn without_near_ties(self, grid: &ScalarGrid) -> (Option<ScalarGrid>, Levels) {
        let (lo, hi) = grid.value_range();
        let tol = NEAR_TIE * (hi - lo);
        let near = |v: f64, l: f64| l.is_finite() && v != l && (v - l).abs() <= tol;
        let near_any = |v: f64| self.iter().find(|&l| near(v, l));
        if !grid.values.par_any(|v| near_any(v).is_some()) {
            return (None, self);
        }
        if grid.values.storage().is_integer() && tol < 0.5 {
            let moved = self
                .values
                .map(|l| match grid.values.par_any(|v| near(v, l)) {
                    true => l.round(),
                    false => l,
                });
            if moved.windows(2).all(|w| w[0] < w[1]) {
                return (None, Levels::interval(moved[0], moved[1]));
            }
        }
        let written = self.iter().filter(|l| l.is_finite());
        let mut values = match written.clone().all(|l| grid.values.holds(l)) {
            true => grid.values.clone(),
            false => Samples::F64(grid.values.to_f64_vec()),
        };
        values.par_map_in_place(|v| near_any(v).unwrap_or(v));
        let g = ScalarGrid {
            dims: grid.dims,
            spacing: grid.spacing,
            origin: grid.origin,
            direction: grid.direction,
            values,
        };
        (Some(g), self)
    }
}

impl std::ops::Index<usize> for Levels {
    type Output = f64;

    /// Level `i` ([`Levels::get`]).
    #[inline]
    fn index(&self, i: usize) -> &f64 {
        &self.values[i]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sides_and_ties_follow_the_bounds() {
        let lv = Levels::interval(1.0, 3.0).with_ties(&Samples::from(vec![0.0, 1.0, 2.0, 3.0]));
        assert_eq!(lv.len(), 2);
        assert_eq!(lv.iter().collect::<Vec<_>>(), vec![1.0, 3.0]);
        assert!(lv.below(0, 1.0) && !lv.above(0, 1.0));
        assert!(lv.above(1, 3.0) && !lv.below(1, 3.0));
        assert_eq!(lv.side(0, 2.0), Side::Above);
        assert_eq!(lv.side(1, 2.0), Side::Below);
        assert!(lv.tie(0) < 1.0 && lv.tie(1) > 3.0);
        assert_eq!(lv.effective(1.0), lv.tie(0));
        assert_eq!(lv.effective(2.0), 2.0);
        assert!(lv.inside(2.0) && !lv.inside(3.0));
    }

    #[test]
    fn infinite_bounds() {
        let lv = Levels::interval(f64::NEG_INFINITY, 0.5).with_ties(&Samples::from(vec![0.0]));
        assert!(lv.below(0, f64::NEG_INFINITY));
        assert_eq!(lv.tie(0), f64::NEG_INFINITY);
        assert_eq!(lv.onto_near(0.5 + 1e-12, 1e-9), 0.5);
        assert_eq!(lv.onto_near(-1e300, 1e-9), -1e300);
    }
}
