//! The problem an operation works on ([`Ctx`]): the trilinear field, the levels, the target
//! quality; and apart from it the state of the round it runs in ([`RoundFlags`]).

use std::time::Instant;

use super::QualityOptions;
use crate::field::Field;
use crate::grid::ScalarGrid;
use crate::levels::Levels;
use crate::quality::biased_min_sine;

/// Everything an operation needs besides the local mesh: the problem (field, levels,
/// targets, time budget) and the state of the round ([`Ctx::round`]).
pub struct Ctx<'a> {
    /// The trilinear field.
    pub field: Field<'a>,
    /// The levels (for one interval: alpha, beta).
    pub levels: Levels,
    /// Absolute tolerance on `|f - level|` for boundary vertices.
    pub tol: f64,
    /// Weight of obtuse angles in [`biased_min_sine`].
    pub obtuse_weight: f64,
    /// Biased-sine quality of the target angles: tets below it need work.
    pub target: f64,
    /// [`QualityOptions::boundary_collapse_ratio`].
    pub boundary_collapse_ratio: f64,
    /// When the time budget runs out.
    pub deadline: Option<Instant>,
    /// The caller's stop flag ([`QualityOptions::cancel`](super::QualityOptions::cancel)).
    pub cancel: crate::cancel::Cancel,
    /// The state of the round the operation runs in.
    pub round: RoundFlags<'a>,
}

/// The state of one round of the pass: where its slabs start, how its regions are smoothed,
/// retried and polished, and on a copy what is pinned. All off in a pass's first rounds.
#[derive(Clone, Copy, Default)]
pub struct RoundFlags<'a> {
    /// Where the slabs that split the work into regions start along the grid's longest axis
    /// (index units; [`region::SLAB`](super::region::SLAB)).
    pub slab_offset: f64,
    /// Smoothing tries the steepest ascent direction first ([`smooth`](super::smooth)).
    pub steepest: bool,
    /// Smoothing tries the centroid of the neighbours where its line searches fail
    /// ([`smooth`](super::smooth)).
    pub centroid: bool,
    /// Per point: pinned (frozen in every region), as the rim of a [`submesh::SubMesh`](super::submesh::SubMesh) is.
    pub pinned: Option<&'a [bool]>,
    /// On a copy: per point, what the whole mesh said of it when the copy was cut
    /// ([`thin::rim_marks`](super::thin::rim_marks); the rim's faces and tets outside the copy are missing from it).
    pub rim_marks: Option<&'a [crate::mesh::LabelBits]>,
    /// A region that ends with a few tets below the target is improved again from its start
    /// with other smoothing ([`RoundFlags::steepest`], [`RoundFlags::centroid`]), and the best end is kept
    /// ([`schedule::improve_local`](super::schedule::improve_local)). Set for the last round of a single pass and of the
    /// first stage of a ladder ([`stages`](super::stages)).
    pub retry_stuck: bool,
    /// A region that ends with tets below the target gets a compass search over their
    /// corners ([`search`](super::search), [`schedule::improve_local`](super::schedule::improve_local)). Set for the last round of every
    /// stage.
    pub polish: bool,
}

impl Ctx<'_> {
    /// Whether the time budget has run out, or the caller asked the pass to stop.
    pub fn out_of_time(&self) -> bool {
        self.cancel.is_cancelled() || self.deadline.is_some_and(|d| Instant::now() >= d)
    }

    /// The quality the pass maximises (biased minimum sine).
    #[inline]
    pub fn quality(&self, p: [[f64; 3]; 4]) -> f64 {
        biased_min_sine(p, self.obtuse_weight)
    }

    /// Whether index point `u` lies strictly inside the interval (where interior vertices
    /// must stay).
    pub fn inside_interval(&self, u: [f64; 3]) -> bool {
        let f = self.field.value(u);
        self.levels.inside(f)
    }

    /// Whether index point `u` lies strictly inside region `r`'s interval (where its interior
    /// vertices must stay; for one interval, [`Ctx::inside_interval`]).
    pub fn inside_region(&self, u: [f64; 3], r: u8) -> bool {
        let f = self.field.value(u);
        let r = r as usize;
        f > self.levels[r] && f < self.levels[r + 1]
    }
}

/// The context of a pass over `grid`'s field at `opts`' targets and tolerance, its time
/// budget counted from `start`; the round's state is off ([`RoundFlags::default`]).
pub(super) fn context<'a>(
    grid: &'a ScalarGrid,
    levels: &Levels,
    opts: &QualityOptions,
    start: Instant,
) -> Ctx<'a> {
    let (lo, hi) = grid.value_range();
    let range = (hi - lo).max(f64::MIN_POSITIVE);
    let lo_s = opts.min_angle.to_radians().sin();
    let hi_s = (180.0 - opts.max_angle).to_radians().sin();
    let obtuse_weight = (lo_s / hi_s).min(1.0);
    Ctx {
        field: Field::new(grid),
        levels: *levels,
        tol: opts.level_tolerance * range,
        obtuse_weight,
        target: lo_s.min(obtuse_weight * hi_s),
        boundary_collapse_ratio: opts.boundary_collapse_ratio,
        deadline: opts.time_budget.map(|b| start + b),
        cancel: opts.cancel.clone(),
        round: RoundFlags::default(),
    }
}
