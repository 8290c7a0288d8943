//! Whether a mesh bound sits on (or next to) a critical value, and the nearest safe bounds.
//!
//! `{alpha <= f <= beta}` changes topology when `alpha` crosses a critical value of the
//! superlevel sets or `beta` one of the sublevel sets; at such a value the domain pinches and
//! no mesh there is well shaped (near it, necks are about `sqrt(distance)` thin). A bound is
//! *unsafe* when it lies within `tol` of such a value. The suggested bounds are the midpoints of
//! the nearest gaps between consecutive critical values at least `2 tol` wide, one below and one
//! above; where critical values are denser than that (integer MRI data: face saddles at many
//! simple fractions), the midpoint of the widest gap on each side among those given.

use super::CriticalPoint;

/// The critical values near one bound.
#[derive(Clone, Debug, PartialEq)]
pub struct NearCritical {
    /// The critical points within `tol` of the bound (at most a few are needed for a message;
    /// all are kept), nearest first.
    pub hits: Vec<CriticalPoint>,
    /// Suggested value below the bound and its distance to the nearest critical value.
    pub safe_below: Option<(f64, f64)>,
    /// Suggested value above the bound and its distance to the nearest critical value.
    pub safe_above: Option<(f64, f64)>,
}

/// The critical points of `points` that matter for a lower bound (`lower`: they change
/// `{f >= w}`) or an upper bound (they change `{f <= w}`) and lie within `tol` of `bound`, with
/// the nearest safe bounds; `None` when the bound is safe.
pub fn near_critical(
    points: &[CriticalPoint],
    bound: f64,
    lower: bool,
    tol: f64,
) -> Option<NearCritical> {
    let relevant = |p: &&CriticalPoint| if lower { p.superlevel } else { p.sublevel };
    let mut hits: Vec<CriticalPoint> = points
        .iter()
        .filter(relevant)
        .filter(|p| (p.value - bound).abs() <= tol)
        .cloned()
        .collect();
    if hits.is_empty() {
        return None;
    }
    hits.sort_by(|a, b| (a.value - bound).abs().total_cmp(&(b.value - bound).abs()));
    let mut values: Vec<f64> = points.iter().filter(relevant).map(|p| p.value).collect();
    values.sort_by(f64::total_cmp);
    values.dedup();
    // (midpoint, half width) of each gap
    let gaps: Vec<(f64, f64)> = values
        .windows(2)
        .map(|w| (0.5 * (w[0] + w[1]), 0.5 * (w[1] - w[0])))
        .collect();
    let pick = |side: &mut dyn Iterator<Item = (f64, f64)>| {
        let side: Vec<(f64, f64)> = side.collect();
        side.iter()
            .copied()
            .find(|g| g.1 >= tol)
            .or_else(|| side.iter().copied().max_by(|a, b| a.1.total_cmp(&b.1)))
    };
    let safe_below = pick(&mut gaps.iter().rev().copied().filter(|g| g.0 < bound));
    let safe_above = pick(&mut gaps.iter().copied().filter(|g| g.0 > bound));
    Some(NearCritical {
        hits,
        safe_below,
        safe_above,
    })
}
