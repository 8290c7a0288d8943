//! Which saddles a cell uses, per method — the rule that keeps neighbouring cells conforming.
//!
//! Vertex classes: with the open-interval convention (see `docs/ARCHITECTURE.md`), a value
//! `<= alpha` is *below*, `>= beta` is *above*, anything else *inside*.
//!
//! * A cell is **two-level** when it has corners below and corners not below, and corners above
//!   and corners not above (both boundary surfaces may cross it).
//! * `tptd`: every existing face saddle and body saddle is used in every cell.
//! * `std`/`ctd`: a face saddle is used when the face is *ambiguous* for alpha or for beta
//!   (diagonal corners on the same side, the two diagonals on opposite sides), or when a
//!   *full* cell touches the face. A full cell is, for `ctd`, a two-level cell, and for both, a
//!   cell crossing a level that has a body saddle (STD case iii is never used on its own: a
//!   body saddle with masked faces can join what case v keeps apart) or whose corners 0 and 7
//!   are alone on one side of a level (the 6-fold diagonal would join them). Full cells use every
//!   saddle (TPTD); other cells use no body saddle (STD cases i, ii, iv over the used faces).
//!   Both cells of a face evaluate the same rule on the same data, so they agree.

use super::sag::face_diagonal_split;
use crate::grid::{ScalarGrid, LOW_FACES};
use crate::levels::Levels;
use crate::trilinear::{body_saddles, face_saddle, BodySaddle, FaceSaddle};

/// Decomposition method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// 5-fold, alternating parity (no saddles; topology not preserved).
    Five,
    /// 6-fold around the main diagonal (no saddles; topology not preserved).
    Six,
    /// Topology-preserving decomposition for all isovalues (Sohn, ICCS 2007, §4).
    Tptd,
    /// Simplified decomposition: topology kept for one isovalue per cell (Sohn, ICCS 2007, §5.2).
    Std,
    /// STD in cells with at most one boundary surface, TPTD elsewhere (Sohn, ICCS 2007, §5.2).
    Ctd,
}

impl Method {
    /// Lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            Method::Five => "five",
            Method::Six => "six",
            Method::Tptd => "tptd",
            Method::Std => "std",
            Method::Ctd => "ctd",
        }
    }
}

/// Class bits of one value: bit 0 = below (`<= alpha`), bit 1 = above (`>= beta`).
#[inline]
pub fn class(v: f64, alpha: f64, beta: f64) -> u8 {
    (v <= alpha) as u8 | (((v >= beta) as u8) << 1)
}

/// Per-cell summary of the corner classes.
#[derive(Clone, Copy, Debug)]
pub struct CellClasses {
    /// Bit c set when corner c is below.
    pub below: u8,
    /// Bit c set when corner c is above.
    pub above: u8,
}

impl CellClasses {
    /// Classes of the eight corner values.
    #[inline]
    pub fn new(v: &[f64; 8], alpha: f64, beta: f64) -> Self {
        let mut below = 0u8;
        let mut above = 0u8;
        for (c, &x) in v.iter().enumerate() {
            let k = class(x, alpha, beta);
            below |= (k & 1) << c;
            above |= (k >> 1) << c;
        }
        CellClasses { below, above }
    }
    /// Whether the alpha surface can cross the cell.
    #[inline]
    pub fn crosses_alpha(self) -> bool {
        self.below != 0 && self.below != 0xff
    }
    /// Whether the beta surface can cross the cell.
    #[inline]
    pub fn crosses_beta(self) -> bool {
        self.above != 0 && self.above != 0xff
    }
    /// Whether the cell lies entirely outside the open interval.
    #[inline]
    pub fn all_outside(self) -> bool {
        self.below == 0xff || self.above == 0xff
    }
    /// Whether every corner is inside.
    #[inline]
    pub fn all_inside(self) -> bool {
        self.below == 0 && self.above == 0
    }
}

/// Whether face `f` is ambiguous for the side mask `m` (bit c set = corner c on one side).
#[inline]
pub fn face_ambiguous(m: u8, f: usize) -> bool {
    let fc = crate::grid::face_corners(f);
    let s = |i: usize| (m >> fc[i]) & 1;
    s(0) == s(2) && s(1) == s(3) && s(0) != s(1)
}

/// Whether corners 0 and 7 are alone on one side of a level (MC configuration 4 along the
/// 6-fold diagonal): the 6-fold split would join them through the 0–7 edge whether or not
/// the trilinear field does (4.1.1 versus 4.1.2), so such cells need TPTD.
#[inline]
pub fn diagonal_pair(cls: CellClasses) -> bool {
    const PAIR: u8 = 0b1000_0001;
    cls.below == PAIR || cls.below == !PAIR || cls.above == PAIR || cls.above == !PAIR
}

/// Whether a cell must use every saddle (TPTD), given its classes and body-saddle count.
#[inline]
pub fn is_full(method: Method, cls: CellClasses, num_body: usize) -> bool {
    let one_level = cls.crosses_alpha() || cls.crosses_beta();
    match method {
        Method::Tptd => true,
        Method::Five | Method::Six => false,
        Method::Ctd => {
            (cls.crosses_alpha() && cls.crosses_beta())
                || (one_level && (num_body > 0 || diagonal_pair(cls)))
        }
        Method::Std => one_level && (num_body > 0 || diagonal_pair(cls)),
    }
}

/// Whether a non-full cell of `method` uses face `f`'s saddle on its own account (ambiguity).
#[inline]
pub fn face_needed(cls: CellClasses, f: usize) -> bool {
    face_ambiguous(cls.below, f) || face_ambiguous(cls.above, f)
}

/// Whether the corners in `mask` form one connected set along cell edges (an empty set counts
/// as connected).
pub fn corners_connected(mask: u8) -> bool {
    if mask == 0 {
        return true;
    }
    let start = mask.trailing_zeros() as u8;
    let mut seen = 1u8 << start;
    let mut stack = [0u8; 8];
    let mut n = 1;
    stack[0] = start;
    while n > 0 {
        n -= 1;
        let c = stack[n];
        for bit in [1u8, 2, 4] {
            let d = c ^ bit;
            if mask & (1 << d) != 0 && seen & (1 << d) == 0 {
                seen |= 1 << d;
                stack[n] = d;
                n += 1;
            }
        }
    }
    seen == mask
}

/// How a cell is split (before clipping).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layout {
    /// Entirely below alpha or above beta: nothing to mesh.
    Outside,
    /// The 6-fold split (method `six`).
    Six,
    /// The 5-fold split of the given parity (method `five`).
    Five {
        /// Whether `i + j + k` is odd.
        odd: bool,
    },
    /// TPTD over the plan's used saddles (methods `tptd`, `std`, `ctd`).
    Tptd,
}

/// Which saddles one cell uses, and why.
///
/// The used face saddles are `own | forced`. `apex` are the used faces whose saddle may be the
/// case-(ii) apex of [`crate::decompose::tptd::decompose_tptd`].
#[derive(Clone, Copy, Debug)]
pub struct CellPlan {
    /// How the cell is split.
    pub layout: Layout,
    /// Corner classes.
    pub classes: CellClasses,
    /// Whether the cell uses every saddle it has (TPTD).
    pub full: bool,
    /// Faces whose saddle the cell uses on its own account (the cell is full, or the face is
    /// ambiguous for one of its levels).
    pub own: u8,
    /// Faces whose saddle is used only because the cell across the face is full.
    pub forced: u8,
    /// Faces with no saddle in use whose diagonal sags from the level set: bisected at the
    /// point `saddles[f]` of the diagonal (`uv = [t, t]`) after the decomposition
    /// ([`super::sag`]). Not used faces: the case analysis never sees them.
    pub extra: u8,
    /// The levels, when the cell crosses one: edges inside the cell that sag from the level
    /// set are then bisected after the decomposition ([`super::sag::split_inner_edges`]).
    pub split_levels: Option<[f64; 2]>,
    /// Used faces whose saddle may be the case-(ii) apex: `own`, except for a non-full cell
    /// with only forced saddles on faces of both parities (no corner apex fits), where it is
    /// the forced saddles that join nothing the cell keeps apart.
    pub apex: u8,
    /// The saddles of the used faces (entries of other faces are unspecified).
    pub saddles: [FaceSaddle; 6],
    /// The used body saddles in increasing value order (the first `num_body`).
    pub bodies: [BodySaddle; 2],
    /// Number of used body saddles.
    pub num_body: usize,
}

impl CellPlan {
    /// A plan with no saddle.
    fn bare(layout: Layout, classes: CellClasses) -> Self {
        CellPlan {
            layout,
            classes,
            full: false,
            own: 0,
            forced: 0,
            extra: 0,
            split_levels: None,
            apex: 0,
            saddles: [FaceSaddle {
                uv: [0.0; 2],
                value: 0.0,
            }; 6],
            bodies: [BodySaddle {
                pos: [0.0; 3],
                value: 0.0,
            }; 2],
            num_body: 0,
        }
    }

    /// Faces whose saddle the cell uses.
    #[inline]
    pub fn used(&self) -> u8 {
        self.own | self.forced
    }

    /// The used body saddles, in increasing value order.
    #[inline]
    pub fn bodies(&self) -> &[BodySaddle] {
        &self.bodies[..self.num_body]
    }

    /// Saddle value of each used face (0 for the others).
    #[inline]
    pub fn face_values(&self) -> [f64; 6] {
        let used = self.used();
        std::array::from_fn(|f| {
            if used & (1 << f) != 0 {
                self.saddles[f].value
            } else {
                0.0
            }
        })
    }

    /// Whether the cell is all inside and split 6-fold over its corners alone (no saddle, no
    /// clipping needed away from the grid box).
    #[inline]
    pub fn whole_six(&self) -> bool {
        matches!(self.layout, Layout::Six | Layout::Tptd)
            && self.used() == 0
            && self.num_body == 0
            && self.classes.all_inside()
    }
}

/// The levels and method a plan is made for, and the grid the neighbours are read from.
#[derive(Clone, Copy, Debug)]
pub struct Planner<'a> {
    /// The grid.
    pub grid: &'a ScalarGrid,
    /// Decomposition method.
    pub method: Method,
    /// The run's levels (their values; the ties rule of [`Levels`] decides the classes).
    /// Each cell, and each face diagonal, is planned for the two of them that matter there
    /// ([`Planner::pair`]).
    pub levels: Levels,
    /// Whether edges that sag from the level set are split ([`super::sag`]). Warping decides
    /// its snaps on the split complex (`warp`).
    pub split_sags: bool,
}

impl Planner<'_> {
    /// The two levels, as `(alpha, beta)` for [`class`], that a cell or face with values `v`
    /// is planned for: the interval's two levels; with more levels, the lowest level that
    /// crosses `v` and the next one (the last two when it is the last), or, when none
    /// crosses, the bounds of the region holding `v`. A function of `v` alone, so the cells
    /// on both sides of a face agree on it. A level that is not the run's last is passed as
    /// beta one step above itself, so that a value equal to it counts below it as for alpha
    /// ([`Levels::below`]).
    #[inline]
    pub fn pair(&self, v: &[f64]) -> (f64, f64) {
        let lv = &self.levels;
        let n = lv.len();
        if n == 2 {
            return (lv.get(0), lv.get(1));
        }
        let k = self.pair_index(v);
        let beta = if k + 2 == n {
            lv[k + 1]
        } else {
            lv[k + 1].next_up()
        };
        (lv[k], beta)
    }

    /// Index `k` of the first level of [`Planner::pair`] (levels `k` and `k + 1`): for values
    /// inside the levels that no level crosses, their region.
    #[inline]
    pub fn pair_index(&self, v: &[f64]) -> usize {
        let lv = &self.levels;
        let n = lv.len();
        if n == 2 {
            return 0;
        }
        let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        match (0..n).find(|&i| lv.below(i, lo)) {
            None => n - 2,
            Some(0) => 0,
            Some(i) if lv.below(i, hi) => i - 1,
            Some(i) => i.min(n - 2),
        }
    }

    /// Whether the cell at `c` is full (uses every saddle), computed from its values when
    /// asked: only cells with a face saddle ask about the neighbour across it, which is far
    /// cheaper than a pass over all cells.
    #[inline]
    pub fn cell_full(&self, c: [usize; 3]) -> bool {
        match self.method {
            Method::Tptd => true,
            Method::Ctd | Method::Std => {
                let v = self.grid.cell_values(c[0], c[1], c[2]);
                let (alpha, beta) = self.pair(&v);
                let cls = CellClasses::new(&v, alpha, beta);
                if !(cls.crosses_alpha() || cls.crosses_beta()) {
                    return false;
                }
                is_full(self.method, cls, body_saddles(&v).1)
            }
            Method::Five | Method::Six => false,
        }
    }

    /// Whether the neighbour of cell `c` across face `f` exists and is full.
    #[inline]
    fn neighbour_full(&self, c: [usize; 3], f: usize) -> bool {
        let axis = f / 2;
        let mut n = c;
        if f.is_multiple_of(2) {
            n[axis] = n[axis].wrapping_sub(1);
        } else {
            n[axis] += 1;
        }
        n[axis] < self.grid.cell_dims()[axis] && self.cell_full(n)
    }
}

/// Plans cell `c` (corner values `v`): its layout and, for the TPTD family, which face and
/// body saddles it uses (looking at the neighbours across its saddle faces when needed).
#[inline]
pub fn plan_cell(p: &Planner, c: [usize; 3], v: &[f64; 8]) -> CellPlan {
    let pair = p.pair(v);
    let cls = CellClasses::new(v, pair.0, pair.1);
    if cls.all_outside() {
        return CellPlan::bare(Layout::Outside, cls);
    }
    match p.method {
        Method::Six => CellPlan::bare(Layout::Six, cls),
        Method::Five => CellPlan::bare(
            Layout::Five {
                odd: (c[0] + c[1] + c[2]) % 2 == 1,
            },
            cls,
        ),
        Method::Tptd | Method::Std | Method::Ctd => plan_tptd(p, c, v, cls, pair),
    }
}

/// [`plan_cell`] for the TPTD family.
#[inline]
fn plan_tptd(
    p: &Planner,
    c: [usize; 3],
    v: &[f64; 8],
    cls: CellClasses,
    pair: (f64, f64),
) -> CellPlan {
    let mut plan = CellPlan::bare(Layout::Tptd, cls);
    let crosses = cls.crosses_alpha() || cls.crosses_beta();
    if crosses || p.method == Method::Tptd {
        (plan.bodies, plan.num_body) = body_saddles(v);
    }
    // A cell crossing a level with a body saddle is full (so non-full cells use none).
    plan.full = p.method == Method::Tptd || (crosses && is_full(p.method, cls, plan.num_body));
    for f in 0..6 {
        let Some(s) = face_saddle(v, f) else {
            continue;
        };
        if plan.full || face_needed(cls, f) {
            plan.own |= 1 << f;
        } else if p.neighbour_full(c, f) {
            plan.forced |= 1 << f;
        } else {
            continue;
        }
        plan.saddles[f] = s;
    }
    plan.apex = plan.own;
    let used = plan.used();
    if !plan.full && plan.own == 0 && used & LOW_FACES != 0 && used & !LOW_FACES != 0 {
        // Saddles used only for full neighbours, on faces of both parities: no corner apex
        // fits, so one of them must be the apex. Safe are those on the side of the level
        // whose corners are edge-connected (the apex joins all of them).
        plan.apex = if crosses {
            safe_apexes(pair, cls, used, &plan.face_values())
        } else {
            used
        };
    }
    if crosses && p.split_sags {
        plan_splits(p, v, pair, &mut plan);
    }
    plan
}

/// The sagging diagonals of the faces of a cell crossing a level that use no saddle (each for
/// its own [`Planner::pair`]), and the cell's levels `pair` for the edges inside it (see
/// [`super::sag`]).
#[inline]
fn plan_splits(p: &Planner, v: &[f64; 8], pair: (f64, f64), plan: &mut CellPlan) {
    for f in 0..6 {
        if plan.used() & (1 << f) != 0 {
            continue;
        }
        let q = crate::grid::face_corners(f).map(|c| v[c]);
        let (alpha, beta) = p.pair(&q);
        if let Some(s) = face_diagonal_split(q, alpha, beta) {
            plan.extra |= 1 << f;
            plan.saddles[f] = FaceSaddle {
                uv: [s.t, s.t],
                value: s.value,
            };
        }
    }
    plan.split_levels = Some([pair.0, pair.1]);
}

/// The used faces whose saddle lies on a side of the (single) level crossing the cell whose
/// corners are edge-connected.
fn safe_apexes(pair: (f64, f64), cls: CellClasses, used: u8, fv: &[f64; 6]) -> u8 {
    let (alpha, beta) = pair;
    let mut safe = 0u8;
    for f in 0..6 {
        if used & (1 << f) == 0 {
            continue;
        }
        let m = if cls.crosses_alpha() {
            if fv[f] <= alpha {
                cls.below
            } else {
                !cls.below
            }
        } else if fv[f] >= beta {
            cls.above
        } else {
            !cls.above
        };
        if corners_connected(m) {
            safe |= 1 << f;
        }
    }
    safe
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn corner_connectivity() {
        assert!(corners_connected(0));
        assert!(corners_connected(0b0000_0011));
        assert!(!corners_connected(0b1000_0001));
        assert!(!corners_connected(0b0000_0110));
        assert!(corners_connected(0b0000_0111));
        assert!(corners_connected(!0b1000_0001));
        assert!(corners_connected(0xff));
    }
    fn noise_grid(dims: [usize; 3], seed: u64) -> ScalarGrid {
        let n = dims[0] * dims[1] * dims[2];
        let v: Vec<f64> = (0..n as u64)
            .map(|i| {
                let h = (seed ^ i.wrapping_mul(0x2545_F491_4F6C_DD1D))
                    .wrapping_mul(0x9E37_79B9_7F4A_7C15);
                ((h >> 11) as f64) / ((1u64 << 53) as f64) * 2.0 - 1.0
            })
            .collect();
        ScalarGrid::new(dims, v).unwrap()
    }

    /// The two cells of every interior face agree on whether its saddle is used and on the
    /// split of its diagonal; a forced saddle has a full cell across; `own` and `forced` are
    /// disjoint. One interval, several levels, and levels equal to grid values (ties).
    #[test]
    fn neighbours_agree_on_every_face() {
        let grid = noise_grid([9, 8, 7], 3);
        let cd = grid.cell_dims();
        let mut sorted = grid.values.to_f64_vec();
        sorted.sort_by(f64::total_cmp);
        let q = |x: f64| sorted[(x * (sorted.len() - 1) as f64) as usize];
        let inf = f64::INFINITY;
        let lists: Vec<Vec<f64>> = vec![
            vec![-0.2, 0.3],
            vec![0.1, inf],
            vec![-0.5, 0.6],
            vec![-0.5, -0.1, 0.2, 0.6],
            vec![-inf, -0.3, 0.0, 0.3],
            vec![-0.6, -0.2, 0.1, 0.4, inf],
            vec![q(0.2), q(0.4), q(0.6), q(0.8)],
        ];
        let mut forced = 0;
        for method in [Method::Tptd, Method::Std, Method::Ctd] {
            for list in &lists {
                let p = Planner {
                    grid: &grid,
                    method,
                    levels: Levels::new(list).unwrap(),
                    split_sags: true,
                };
                let plan = |c: [usize; 3]| plan_cell(&p, c, &grid.cell_values(c[0], c[1], c[2]));
                for c in (0..cd[2])
                    .flat_map(|k| (0..cd[1]).flat_map(move |j| (0..cd[0]).map(move |i| [i, j, k])))
                {
                    let a = plan(c);
                    assert_eq!(a.own & a.forced, 0);
                    assert_eq!(a.apex & !a.used(), 0);
                    for axis in 0..3 {
                        if c[axis] + 1 == cd[axis] {
                            continue;
                        }
                        let mut n = c;
                        n[axis] += 1;
                        let b = plan(n);
                        if a.layout == Layout::Outside || b.layout == Layout::Outside {
                            continue;
                        }
                        let (fa, fb) = (2 * axis + 1, 2 * axis);
                        assert_eq!(
                            (a.used() >> fa) & 1,
                            (b.used() >> fb) & 1,
                            "{method:?} {list:?} {c:?} axis {axis}"
                        );
                        let split = |p: &CellPlan, f: usize| {
                            ((p.extra >> f) & 1 == 1).then(|| p.saddles[f].value.to_bits())
                        };
                        assert_eq!(split(&a, fa), split(&b, fb), "{method:?} {list:?} {c:?}");
                        if (a.forced >> fa) & 1 == 1 {
                            assert!(b.full && p.cell_full(n));
                            forced += 1;
                        }
                        assert_eq!(a.full, p.cell_full(c));
                    }
                }
            }
        }
        assert!(forced > 0, "no forced saddle seen");
    }
}
