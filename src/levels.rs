//! The levels a run meshes between ([`Levels`]): their values, sorted, how values tied with
//! a level are handled, and the preparation of the data that keeps near ties out of the mesh.
//!
//! `n` sorted levels bound `n - 1` regions: region `k` is the interval between levels `k`
//! and `k + 1`. One interval `{alpha <= f <= beta}` is the case of two levels
//! ([`Levels::interval`]), with `-inf` or `+inf` standing for a missing bound. The meshed set
//! of a region is the closure of its open interval; a value equal to a level is given to one
//! side of it, the same for every region: equal to the last level counts as above it, equal
//! to any other level as below it. So a value equal to the lower bound of the meshed set
//! counts as outside, and one equal to the upper bound too, and a value equal to a level
//! between two regions belongs to the region below it.
//!
//! A region's clipper sees its two levels as a [`Levels`] of its own ([`Levels::region`]),
//! which keeps their indices in the run ([`Levels::global`]): cut points and boundary labels
//! name a level by its index in the run.

use crate::grid::ScalarGrid;
use crate::samples::Samples;

/// Most levels a run may have (so at most `MAX_LEVELS - 1` regions). Point keys reserve
/// enough bits for a level index to name this many (`keys::LEVEL_BITS`).
pub const MAX_LEVELS: usize = 16;

/// Fraction of the smallest gap between a level and the data values by which tied values are
/// moved outward when cuts are placed.
pub const TIE_FRACTION: f64 = 1e-3;

/// Values within this fraction of the data range of a level, but not equal to it, are set
/// onto the level before meshing.
pub const NEAR_TIE: f64 = 1e-9;

/// Whether `v` lies below `level`, a value equal to it counting as below when `ties_below`.
/// False for NaN. (Above is the same question with the two swapped and ties the other way.)
#[inline]
fn below(v: f64, level: f64, ties_below: bool) -> bool {
    if ties_below {
        v <= level
    } else {
        v < level
    }
}

/// Which side of a level a value lies on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    /// Below the level, or equal to it when ties count as below.
    Below,
    /// Above the level, or equal to it when ties count as above.
    Above,
}

/// Why a list of levels is refused ([`Levels::new`]).
#[derive(Clone, Debug, PartialEq)]
pub enum LevelsError {
    /// Fewer than two levels, or more than [`MAX_LEVELS`].
    Count(usize),
    /// A level is NaN.
    NotANumber(usize),
    /// Level `i` is not above level `i - 1`.
    NotIncreasing(usize),
    /// An infinite level other than `-inf` first or `+inf` last.
    Infinite(usize),
}

impl std::fmt::Display for LevelsError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LevelsError::Count(n) => {
                write!(
                    f,
                    "{n} level(s) given; between 2 and {MAX_LEVELS} are needed"
                )
            }
            LevelsError::NotANumber(i) => write!(f, "level {} is not a number", i + 1),
            LevelsError::NotIncreasing(i) => {
                write!(
                    f,
                    "level {} is not above level {}: levels must increase",
                    i + 1,
                    i
                )
            }
            LevelsError::Infinite(i) => write!(
                f,
                "level {} is infinite: only the first may be -inf and the last +inf",
                i + 1
            ),
        }
    }
}

impl std::error::Error for LevelsError {}

/// The sorted levels of a run (finite or infinite) and the values that data tied with each
/// level is moved to when cuts are placed; or one region's two levels, with their indices in
/// the run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Levels {
    /// The levels, sorted (`-inf` / `+inf` for a missing bound); the first `len` are used,
    /// the rest are 0.
    values: [f64; MAX_LEVELS],
    /// Per level, the value used for cut placement at vertices whose value equals the level:
    /// moved to the side ties count on (the level itself until [`Levels::with_ties`]).
    ties: [f64; MAX_LEVELS],
    /// Number of levels.
    len: u8,
    /// Bit `i` set: a value equal to level `i` counts as above it (the run's last level).
    ties_above: u16,
}
impl Levels {
    /// The two levels of the interval `(alpha, beta)` (`alpha < beta`; `-inf` / `+inf` for a
    /// missing bound), ties not moved yet ([`Levels::with_ties`]).
    pub fn interval(alpha: f64, beta: f64) -> Self {
        Self::sorted(&[alpha, beta])
    }

    /// The levels `values` (2 to [`MAX_LEVELS`], strictly increasing, `-inf` only first and
    /// `+inf` only last), ties not moved yet ([`Levels::with_ties`]).
    pub fn new(values: &[f64]) -> Result<Self, LevelsError> {
        let n = values.len();
        if !(2..=MAX_LEVELS).contains(&n) {
            return Err(LevelsError::Count(n));
        }
        for (i, &v) in values.iter().enumerate() {
            if v.is_nan() {
                return Err(LevelsError::NotANumber(i));
            }
            let end_ok = (i == 0 && v == f64::NEG_INFINITY) || (i + 1 == n && v == f64::INFINITY);
            if v.is_infinite() && !end_ok {
                return Err(LevelsError::Infinite(i));
            }
            if i > 0 && v <= values[i - 1] {
                return Err(LevelsError::NotIncreasing(i));
            }
        }
        Ok(Self::sorted(values))
    }

    /// Levels from a list already checked ([`Levels::new`]).
    fn sorted(list: &[f64]) -> Self {
        let mut values = [0.0; MAX_LEVELS];
        values[..list.len()].copy_from_slice(list);
        Levels {
            values,
            ties: values,
            len: list.len() as u8,
            ties_above: 1 << (list.len() - 1),
        }
    }

    /// Number of levels.
    #[inline]
    pub const fn len(&self) -> usize {
        self.len as usize
    }

    /// Whether there are no levels (never: there are at least two, possibly infinite).
    #[inline]
    pub const fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Number of regions (`len() - 1`).
    #[inline]
    pub const fn regions(&self) -> usize {
        self.len() - 1
    }

    /// Region `k`'s two levels (`k < regions()`), with their ties, as the clipper sees
    /// them; [`Bounds::global`] gives their indices in the run.
    pub fn region(&self, k: usize) -> Bounds {
        Bounds {
            values: [self.values[k], self.values[k + 1]],
            ties: [self.ties[k], self.ties[k + 1]],
            first: k as u8,
            ties_above: ((self.ties_above >> k) & 0b11) as u8,
        }
    }

    /// Level `i` (`i < len()`).
    #[inline]
    pub fn get(&self, i: usize) -> f64 {
        self.values[i]
    }

    /// The levels, in increasing order.
    #[inline]
    pub fn iter(&self) -> std::iter::Copied<std::slice::Iter<'_, f64>> {
        self.values().iter().copied()
    }

    /// The levels, in increasing order.
    #[inline]
    pub fn values(&self) -> &[f64] {
        &self.values[..self.len()]
    }

    /// The value that data equal to level `i` takes when cuts are placed.
    #[inline]
    pub fn tie(&self, i: usize) -> f64 {
        self.ties[i]
    }

    /// Whether a value equal to level `i` counts as below it (every level but the run's
    /// last).
    #[inline]
    pub const fn ties_below(&self, i: usize) -> bool {
        self.ties_above & (1 << i) == 0
    }

    /// Whether `v` lies below level `i` (equal counts as below unless `i` is the run's last
    /// level). False for NaN.
    #[inline]
    pub fn below(&self, i: usize, v: f64) -> bool {
        below(v, self.values[i], self.ties_below(i))
    }

    /// Whether `v` lies above level `i` (equal counts as above only for the run's last
    /// level). False for NaN.
    #[inline]
    pub fn above(&self, i: usize, v: f64) -> bool {
        below(self.values[i], v, !self.ties_below(i))
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

    /// Whether `v` lies strictly between the first and the last level (inside the meshed
    /// set, away from its bounds).
    #[inline]
    pub fn inside(&self, v: f64) -> bool {
        v > self.values[0] && v < self.values[self.len() - 1]
    }

    /// The region whose interval holds `v`: the number of levels between regions (not the
    /// first or the last) below it; a value equal to one counts as below it. Always 0 for
    /// one interval.
    #[inline]
    pub fn region_of(&self, v: f64) -> usize {
        (1..self.len() - 1).filter(|&i| v > self.values[i]).count()
    }

    /// Value of a (not snapped) vertex for cut placement: a value tied with a level moved to
    /// [`Levels::tie`].
    #[inline]
    pub fn effective(&self, v: f64) -> f64 {
        for i in 0..self.len() {
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
        let above = if i + 1 < self.len() {
            gap(i + 1)
        } else {
            f64::INFINITY
        };
        below.min(above)
    }

    /// These levels with their tie values for data `values`: a tied value is moved to the
    /// side ties count on (below every level but the last, above the last) by [`TIE_FRACTION`] of the smallest non-zero
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
        for (i, tie) in ties.iter_mut().enumerate().take(self.len()) {
            let l = self.values[i];
            let d = (TIE_FRACTION * gap(l))
                .min(0.25 * self.width(i))
                .max(l.abs() * 4.0 * f64::EPSILON);
            *tie = if self.ties_below(i) { l - d } else { l + d };
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
            let moved: Vec<f64> = self
                .iter()
                .map(|l| match grid.values.par_any(|v| near(v, l)) {
                    true => l.round(),
                    false => l,
                })
                .collect();
            if moved.windows(2).all(|w| w[0] < w[1]) {
                return (None, Levels::sorted(&moved));
            }
        }
        let written = self.iter().filter(|l| l.is_finite());
        let mut values = match written.clone().all(|l| grid.values.holds(l)) {
            true => grid.values.clone(),
            false => Samples::from(grid.values.to_f64_vec()),
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

/// One region's two levels as the clipper sees them ([`Levels::region`]): their values,
/// their tie values and their indices in the run. Small, with the two levels fixed, because
/// the clipper asks it for every vertex and cut.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    values: [f64; 2],
    ties: [f64; 2],
    /// Index in the run of level 0.
    first: u8,
    /// Bit `i` set: a value equal to level `i` counts as above it.
    ties_above: u8,
}

impl Bounds {
    /// Number of levels: two.
    #[inline]
    pub const fn len(&self) -> usize {
        2
    }

    /// Never empty.
    #[inline]
    pub const fn is_empty(&self) -> bool {
        false
    }

    /// Level `i` (`i < 2`).
    #[inline]
    pub fn get(&self, i: usize) -> f64 {
        self.values[i]
    }

    /// The value that data equal to level `i` takes when cuts are placed.
    #[inline]
    pub fn tie(&self, i: usize) -> f64 {
        self.ties[i]
    }

    /// Index in the run of level `i`.
    #[inline]
    pub const fn global(&self, i: usize) -> u8 {
        self.first + i as u8
    }

    /// Whether a value equal to level `i` counts as below it ([`Levels::ties_below`]).
    #[inline]
    pub const fn ties_below(&self, i: usize) -> bool {
        self.ties_above & (1 << i) == 0
    }

    /// Whether `v` lies below level `i` ([`Levels::below`]).
    #[inline]
    pub fn below(&self, i: usize, v: f64) -> bool {
        below(v, self.values[i], self.ties_below(i))
    }

    /// Whether `v` lies above level `i` ([`Levels::above`]).
    #[inline]
    pub fn above(&self, i: usize, v: f64) -> bool {
        below(self.values[i], v, !self.ties_below(i))
    }

    /// The region whose interval holds `v`: the number of levels between regions (not the
    /// first or the last) below it; a value equal to one counts as below it. Always 0 for
    /// one interval.
    #[inline]
    pub fn region_of(&self, v: f64) -> usize {
        (1..self.len() - 1).filter(|&i| v > self.values[i]).count()
    }

    /// Value of a (not snapped) vertex for cut placement ([`Levels::effective`]).
    #[inline]
    pub fn effective(&self, v: f64) -> f64 {
        if v == self.values[0] {
            self.ties[0]
        } else if v == self.values[1] {
            self.ties[1]
        } else {
            v
        }
    }
}

impl std::ops::Index<usize> for Levels {
    type Output = f64;

    /// Level `i` ([`Levels::get`]).
    #[inline]
    fn index(&self, i: usize) -> &f64 {
        debug_assert!(i < self.len());
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

    #[test]
    fn several_levels_give_ties_to_the_region_below_but_the_last() {
        let data = Samples::from(vec![0.0, 1.0, 2.0, 3.0, 4.0]);
        let lv = Levels::new(&[1.0, 2.0, 3.0]).unwrap().with_ties(&data);
        assert_eq!((lv.len(), lv.regions()), (3, 2));
        // A value equal to 2 counts below it: inside region 0, outside region 1.
        assert!(lv.below(1, 2.0) && !lv.above(1, 2.0) && lv.tie(1) < 2.0);
        assert!(lv.above(2, 3.0) && lv.tie(2) > 3.0);
        assert!(lv.inside(2.5) && !lv.inside(3.0));
        let r1 = lv.region(1);
        assert_eq!((r1.len(), r1.get(0), r1.get(1)), (2, 2.0, 3.0));
        assert_eq!((r1.global(0), r1.global(1)), (1, 2));
        assert!(r1.below(0, 2.0) && r1.above(1, 3.0) && r1.tie(0) == lv.tie(1));
        let r0 = lv.region(0);
        assert!(!r0.above(1, 2.0) && r0.ties_below(1) && r0.effective(2.0) == lv.tie(1));
        assert_eq!(
            Levels::new(&[1.0, 3.0]).unwrap(),
            Levels::interval(1.0, 3.0)
        );
    }

    #[test]
    fn bad_level_lists_are_refused() {
        let (inf, nan) = (f64::INFINITY, f64::NAN);
        assert_eq!(Levels::new(&[1.0]), Err(LevelsError::Count(1)));
        assert_eq!(Levels::new(&[0.0; 17]), Err(LevelsError::Count(17)));
        assert_eq!(Levels::new(&[1.0, nan]), Err(LevelsError::NotANumber(1)));
        assert_eq!(Levels::new(&[1.0, 1.0]), Err(LevelsError::NotIncreasing(1)));
        assert_eq!(Levels::new(&[inf, 2.0]), Err(LevelsError::Infinite(0)));
        assert_eq!(
            Levels::new(&[0.0, -inf, 1.0]),
            Err(LevelsError::Infinite(1))
        );
        assert!(Levels::new(&[-inf, 0.0, inf]).is_ok());
        let e = Levels::new(&[2.0, 1.0]).unwrap_err().to_string();
        assert!(e.contains("level 2 is not above level 1"), "{e}");
    }
}
