//! The knobs of the quality pass ([`QualityOptions`]) and their defaults.

use std::time::Duration;

/// The default of [`QualityOptions::split_sag`].
pub const DEFAULT_SPLIT_SAG: f64 = 0.03;

/// The default [`QualityOptions::boundary_collapse_ratio`].
pub(super) const DEFAULT_COLLAPSE_RATIO: f64 = 3.0;

/// Knobs of the quality pass.
#[derive(Clone, Debug, PartialEq)]
pub struct QualityOptions {
    /// Target smallest dihedral angle (degrees).
    pub min_angle: f64,
    /// Target largest dihedral angle (degrees).
    pub max_angle: f64,
    /// Improvement rounds at most (each re-marks what still needs work).
    pub max_rounds: usize,
    /// Stop improving after this much time (checked between sweeps over a region and between
    /// rounds; the mesh is valid whenever it stops).
    pub time_budget: Option<Duration>,
    /// Boundary vertices are projected until `|f - level| <= level_tolerance · (data range)`.
    pub level_tolerance: f64,
    /// Two boundary vertices are merged only along an edge shorter than this times the mean
    /// length of the edges at the removed vertex (`f64::INFINITY`: no limit). Long merges
    /// coarsen the boundary: a thin layer is left with long, flat elements, and a convex
    /// boundary shrinks (the surface is inscribed in the level set). The default, 3, brings
    /// the thin shell of the benchmarks from 14.2° to 15.0° and leaves no `unexplained`
    /// element on the noisy 256³ field (docs/QUALITY-LOG.md).
    pub boundary_collapse_ratio: f64,
    /// Give back the volume that a region's collapses and moves added or took, by moving its
    /// level vertices along their level sets where no tet falls below the target
    /// (`improve/restore.rs`). Without it, the small analytic domains of `tests/quality.rs`
    /// shrink or grow by up to 0.6 % (docs/QUALITY-LOG.md).
    pub restore_volume: bool,
    /// A boundary edge on a level set whose chord sags from the level set by more than this
    /// fraction of its length is split at the end, with the new node on the level set, where
    /// no tet gets worse than the target (`improve/split.rs`; `f64::INFINITY`: never). Nodes
    /// on a curved level set inscribe the surface in it, so thin tubes lose volume: the 32³
    /// genus-3 solid of the benchmark (tubes 1.9 voxels in radius) lost 1.08 % without it,
    /// and loses 0.32 % with it.
    pub split_sag: f64,
    /// Tets whose smallest dihedral angle stays below this (degrees) after the pass are listed
    /// with a reason ([`forced::classify_forced`](super::forced::classify_forced)).
    pub forced_floor: f64,
    /// A critical value within this of alpha or beta (relative to the data range) explains a
    /// bad tet in a cell with that critical point (`near_critical`).
    pub forced_critical_tol: f64,
    /// At most this many of the listed tets are given one by one (worst first); the counts
    /// per reason cover all.
    pub forced_list_cap: usize,
    /// Set by the caller to stop the pass early: it then stops as when its time budget runs
    /// out (the mesh is valid whenever it stops).
    pub cancel: crate::cancel::Cancel,
}

impl Default for QualityOptions {
    fn default() -> Self {
        QualityOptions {
            min_angle: 15.0,
            max_angle: 155.0,
            max_rounds: 4,
            time_budget: None,
            level_tolerance: 1e-9,
            boundary_collapse_ratio: DEFAULT_COLLAPSE_RATIO,
            restore_volume: true,
            split_sag: DEFAULT_SPLIT_SAG,
            forced_floor: 5.0,
            forced_critical_tol: 1e-5,
            forced_list_cap: 1000,
            cancel: crate::cancel::Cancel::new(),
        }
    }
}
