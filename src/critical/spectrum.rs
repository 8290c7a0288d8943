//! The contour spectrum: Betti numbers `(b0, b1, b2)` of `{f >= w}` on each interval between
//! consecutive critical values of the superlevel sets, computed on the TPTD complex
//! ([`super::complex`]) in one sweep.

use serde::Serialize;

use super::complex::build_complex;
use super::CriticalPoint;
use crate::grid::ScalarGrid;

/// One interval of the spectrum.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SpectrumStep {
    /// Lower end (a critical value, or the smallest data value).
    pub lo: f64,
    /// Upper end (a critical value, or the largest data value).
    pub hi: f64,
    /// Betti numbers of `{f >= w}` for every `w` strictly inside `(lo, hi)`.
    pub betti: [usize; 3],
}

/// The spectrum over `[lo, hi]` from the critical points `points` (those changing `{f >= w}`
/// are used). Builds the TPTD complex of the whole grid: meant for volumes up to about a
/// million cells (crop larger ones).
pub fn contour_spectrum(
    grid: &ScalarGrid,
    points: &[CriticalPoint],
    lo: f64,
    hi: f64,
) -> Vec<SpectrumStep> {
    let (min, max) = grid.value_range();
    let (lo, hi) = (lo.max(min), hi.min(max));
    let mut cuts: Vec<f64> = points
        .iter()
        .filter(|p| p.superlevel && p.value > lo && p.value < hi)
        .map(|p| p.value)
        .collect();
    cuts.push(lo);
    cuts.push(hi);
    cuts.sort_by(f64::total_cmp);
    cuts.dedup();
    let complex = build_complex(grid);
    // a level strictly inside each interval and off every vertex value of the complex
    let levels = complex.levels();
    let mids: Vec<f64> = cuts
        .windows(2)
        .map(|w| {
            let a = levels.partition_point(|&x| x <= w[0]);
            let next = levels.get(a).copied().unwrap_or(w[1]).min(w[1]);
            0.5 * (w[0] + next)
        })
        .collect();
    let betti = complex.spectrum(&mids, true);
    cuts.windows(2)
        .zip(betti)
        .map(|(w, b)| SpectrumStep {
            lo: w[0],
            hi: w[1],
            betti: b,
        })
        .collect()
}
