//! Whether a mesh bound sits on (or next to) a critical value, and the nearest safe bounds.
//!
//! `{alpha <= f <= beta}` changes topology when `alpha` crosses a critical value of the
//! superlevel sets or `beta` one of the sublevel sets; at such a value the domain pinches and
//! no mesh there is well shaped. A bound is *unsafe* when it lies within `tol` of such a value;
//! the suggested safe bounds are the midpoints of the nearest gaps between consecutive critical
//! values that are at least `2 tol` wide, one below and one above.

use super::CriticalPoint;

/// The critical values near one bound.
#[derive(Clone, Debug, PartialEq)]
pub struct NearCritical {
    /// The critical points within `tol` of the bound (at most a few are needed for a message;
    /// all are kept), nearest first.
    pub hits: Vec<CriticalPoint>,
    /// Nearest safe value below the bound, if any.
    pub safe_below: Option<f64>,
    /// Nearest safe value above the bound, if any.
    pub safe_above: Option<f64>,
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
    let gaps: Vec<f64> = values
        .windows(2)
        .filter(|w| w[1] - w[0] >= 2.0 * tol)
        .map(|w| 0.5 * (w[0] + w[1]))
        .collect();
    let safe_below = gaps.iter().rev().find(|&&m| m < bound).copied();
    let safe_above = gaps.iter().find(|&&m| m > bound).copied();
    Some(NearCritical {
        hits,
        safe_below,
        safe_above,
    })
}
