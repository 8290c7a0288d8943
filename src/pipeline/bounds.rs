//! The warnings about the input before meshing: a bound equal to grid values, a nearly
//! singular direction matrix, and a bound at (or near) a critical value of the trilinear
//! field, where the domain pinches and its elements degenerate.

use crate::critical::face::face_saddles_in;
use crate::critical::find::critical_in_windows;
use crate::critical::{near_critical, CriticalKind, CriticalPoint};
use crate::{Samples, ScalarGrid};

use super::progress::Reporter;
use super::request::Job;
use super::text::fmt_bound;
use super::Param;

/// The warnings about the bounds and the geometry of the input, in order: bounds equal to
/// grid values (not for a closed surface, whose grid vertices on the surface, or on an offset
/// of it, are exactly there), a nearly singular direction matrix (not for a `curvilinear`
/// grid's values), bounds near critical values (unless the request skips that check).
pub(crate) fn warn_input(grid: &ScalarGrid, job: &Job, curvilinear: bool, reporter: &Reporter) {
    if !job.surface() {
        warn_exact_bounds(grid, job, reporter);
    }
    if !curvilinear {
        warn_near_singular(grid, job, reporter);
    }
    if job.req.critical_check {
        let tol = job.req.critical_tol;
        warn_critical_bounds(grid, (&job.input_name, reporter), &checked(job), tol);
    }
}

/// The levels to check against the critical values: each with its name in messages and the
/// sides (`true`: `{f >= w}`, `false`: `{f <= w}`) whose topology it bounds. One interval:
/// alpha (lower) and beta (upper); several regions: every level, the inner ones both ways.
fn checked(job: &Job) -> Vec<(String, f64, Vec<bool>)> {
    let n = job.req.names;
    let levels = &job.opts.levels;
    if levels.is_empty() {
        let (a, b) = (job.opts.alpha, job.opts.beta);
        return vec![
            (n.of(Param::Alpha).to_string(), a, vec![true]),
            (n.of(Param::Beta).to_string(), b, vec![false]),
        ];
    }
    let last = levels.len() - 1;
    (levels.iter().enumerate())
        .map(|(i, &l)| {
            let sides = match i {
                0 => vec![true],
                i if i == last => vec![false],
                _ => vec![true, false],
            };
            (format!("{} L{}", n.of(Param::Levels), i + 1), l, sides)
        })
        .collect()
}

/// Warns when the direction matrix is nearly singular (the mesh comes out nearly flat); an
/// exactly singular one was refused by the reader.
fn warn_near_singular(grid: &ScalarGrid, job: &Job, reporter: &Reporter) {
    let k = crate::grid::condition_number(&grid.direction);
    if k > crate::grid::NEAR_SINGULAR_CONDITION {
        reporter.warn(format_args!(
            "{}: the direction matrix is nearly singular (condition number \
             {k:.2e}): the index axes are almost dependent, so the tetrahedra are nearly flat; \
             check the file's direction/orientation fields",
            job.input_name
        ));
    }
}

/// Warns about each bound of the meshed set (the first and the last level) that equals grid
/// values exactly (a value equal to a level between regions just counts in the region below).
fn warn_exact_bounds(grid: &ScalarGrid, job: &Job, reporter: &Reporter) {
    let (alpha, beta) = (job.opts.alpha, job.opts.beta);
    let all = checked(job);
    let (first, last) = (&all[0].0, &all[all.len() - 1].0);
    for (name, bound, lower) in [(first, alpha, true), (last, beta, false)] {
        if let Some(w) = bound_warning(&grid.values, name, bound, lower) {
            reporter.warn(format_args!("{}: {w}", job.input_name));
        }
    }
}

/// The warning for a bound that equals grid values exactly, if it does.
fn bound_warning(values: &Samples, name: &str, bound: f64, lower: bool) -> Option<String> {
    if !bound.is_finite() {
        return None;
    }
    let hits = values.par_fold(|| 0usize, |n, v| n + usize::from(v == bound), |a, b| a + b);
    if hits == 0 {
        return None;
    }
    let suggestion = match inside_value(values, bound, lower) {
        Some(v) => format!(" (e.g. {name} {} includes them)", fmt_bound(v)),
        None => String::new(),
    };
    Some(format!(
        "{name} {} equals the value of {hits} grid vertices; values equal to a bound count \
         as outside the interval, which can leave hairline gaps or pinch points; use a value \
         between data values to avoid them{suggestion}",
        fmt_bound(bound)
    ))
}

/// A value between `bound` and the next data value on the inside-making side (below a lower
/// bound, above an upper one), so the vertices equal to the bound are included; `None` when
/// there is no such data value.
fn inside_value(values: &Samples, bound: f64, lower: bool) -> Option<f64> {
    let next = if lower {
        let below = |m: f64, v: f64| if v < bound { m.max(v) } else { m };
        values.par_fold(|| f64::NEG_INFINITY, below, f64::max)
    } else {
        let above = |m: f64, v: f64| if v > bound { m.min(v) } else { m };
        values.par_fold(|| f64::INFINITY, above, f64::min)
    };
    next.is_finite().then(|| bound + (next - bound) / 2.0)
}

/// Warns when a level lies within `tol` of a value where `{f >= w}` or `{f <= w}` (the sides
/// it bounds) changes topology, naming the points and the nearest safe values.
fn warn_critical_bounds(
    grid: &ScalarGrid,
    (input, reporter): (&str, &Reporter),
    levels: &[(String, f64, Vec<bool>)],
    tol: Option<f64>,
) {
    let (lo, hi) = grid.value_range();
    let tol = tol.unwrap_or(1e-5 * (hi - lo));
    // look for safe values this far around each bound
    let reach = tol + 0.004 * (hi - lo);
    let windows: Vec<(f64, f64)> = (levels.iter())
        .map(|l| l.1)
        .filter(|b| b.is_finite())
        .map(|b| (b - reach, b + reach))
        .collect();
    if windows.is_empty() || lo == hi {
        return;
    }
    let points = critical_in_windows(grid, &windows);
    for (name, bound, sides) in levels {
        let bound = *bound;
        if !bound.is_finite() {
            continue;
        }
        // grid values equal to the bound have their own warning (`warn_exact_bounds`)
        let grid_value = |p: &CriticalPoint| {
            p.value == bound
                && !matches!(p.kind, CriticalKind::FaceSaddle | CriticalKind::BodySaddle)
        };
        let around: Vec<CriticalPoint> = points
            .iter()
            .filter(|p| (p.value - bound).abs() <= reach && !grid_value(p))
            .cloned()
            .collect();
        let bound = Bound {
            input,
            name,
            value: bound,
            tol,
        };
        warn_face_saddles(grid, &bound, reporter);
        for &lower in sides {
            if warn_near_critical(&bound, &around, (lower, reach), reporter) {
                break;
            }
        }
    }
}

/// A bound being checked: `{name} {value}` of `input` (`name` as the request names it), with the warning tolerance `tol`.
struct Bound<'a> {
    input: &'a str,
    name: &'a str,
    value: f64,
    tol: f64,
}

/// Warns when face saddles of the bilinear interpolant lie within `tol` of the bound.
fn warn_face_saddles(grid: &ScalarGrid, b: &Bound, reporter: &Reporter) {
    let (bound, tol) = (b.value, b.tol);
    let flat = face_saddles_in(grid, bound - tol, bound + tol);
    if let Some((v, p)) = flat.first() {
        reporter.warn(format_args!(
            "{}: {} {} is within {tol:.4} of {} face saddle(s) of \
             the bilinear interpolant (e.g. {} at ({:.3}, {:.3}, {:.3}); a checkerboard face \
             with corners k, k+1 has its saddle at k+0.5): they are vertices of the \
             decomposition, so elements there get a vertex on the bound",
            b.input,
            b.name,
            fmt_bound(bound),
            flat.len(),
            fmt_bound(*v),
            p[0],
            p[1],
            p[2]
        ));
    }
}

/// Warns when critical values among `around` (those within `reach` of the bound) change the
/// filtration of the bound (`lower`: `{f >= w}`, else `{f <= w}`) within `tol`, naming the
/// nearest safer values within `reach`; whether it warned.
fn warn_near_critical(
    b: &Bound,
    around: &[CriticalPoint],
    (lower, reach): (bool, f64),
    reporter: &Reporter,
) -> bool {
    let (bound, tol) = (b.value, b.tol);
    let Some(near) = near_critical(around, bound, lower, tol) else {
        return false;
    };
    let first = &near.hits[0];
    let p = first.position;
    let safe = |v: Option<(f64, f64)>| {
        v.filter(|x| (x.0 - bound).abs() < reach)
            .map_or(format!("none within {}", fmt_bound(reach)), |(x, d)| {
                format!("{x:.4} ({d:.4} from the nearest)")
            })
    };
    reporter.warn(format_args!(
        "{}: {} {} is within {tol:.4} of {} critical value(s) of \
         the trilinear field (e.g. {} {} at ({:.3}, {:.3}, {:.3})): the domain pinches there \
         and its elements degenerate; nearest safer values: {} below, {} above",
        b.input,
        b.name,
        fmt_bound(bound),
        near.hits.len(),
        first.kind.name(),
        fmt_bound(first.value),
        p[0],
        p[1],
        p[2],
        safe(near.safe_below),
        safe(near.safe_above),
    ));
    true
}
