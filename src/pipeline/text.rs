//! The number formats of messages, and the lines that say what the quality pass left: shared
//! by the warnings of a run and by a front end's summary.

use crate::improve::forced::ForcedCounts;
use crate::report::QualitySection;

/// Formats a bound for messages (`inf`, `-inf` or the shortest round-trip form).
pub fn fmt_bound(v: f64) -> String {
    if v == f64::INFINITY {
        "inf".into()
    } else if v == f64::NEG_INFINITY {
        "-inf".into()
    } else {
        format!("{v}")
    }
}

/// `[a, b]` for messages, with an open bracket at an infinite end: `(-inf, b]`, `[a, inf)`.
pub fn fmt_interval(alpha: f64, beta: f64) -> String {
    let open = if alpha.is_infinite() { '(' } else { '[' };
    let close = if beta.is_infinite() { ')' } else { ']' };
    format!("{open}{}, {}{close}", fmt_bound(alpha), fmt_bound(beta))
}

/// An angle in degrees with three decimals, or three significant digits when tiny.
pub fn fmt_angle(a: f64) -> String {
    if a != 0.0 && a.abs() < 0.01 {
        format!("{a:.2e}")
    } else {
        format!("{a:.3}")
    }
}

/// The reasons of the tets below the floor, counted.
pub fn reasons(c: &ForcedCounts) -> String {
    let mapping = if c.grid_mapping > 0 {
        format!(", {} flattened by the grid mapping", c.grid_mapping)
    } else {
        String::new()
    };
    format!(
        "{} near a critical value, {} in a thin layer, {} at a sharp box angle{mapping}, {} \
         unexplained",
        c.near_critical, c.thin_layer, c.box_angle, c.unexplained
    )
}

/// The one line that says the quality target was missed, with the counts and the reasons of
/// the tets below the floor; `None` when it was met.
pub fn target_line(q: &QualitySection) -> Option<String> {
    let o = &q.outcome;
    if !o.missed() {
        return None;
    }
    let [lo, hi] = q.target_degrees;
    let floor = q.floor_degrees;
    let below_floor = match (&q.forced, o.below_floor) {
        (_, 0) => format!("none below {floor}°"),
        (Some(f), n) => format!("{n} below {floor}°: {}", reasons(&f.counts)),
        (None, n) => format!("{n} below {floor}° (reasons not looked for: --no-analysis)"),
    };
    Some(format!(
        "quality target missed: {} tets below {lo}°, {} above {hi}° (smallest angle {}°); {below_floor}",
        o.below_min,
        o.above_max,
        fmt_angle(o.min_dihedral)
    ))
}

/// The line that says a pass stopped by its time budget (`seconds`, as given) had left the
/// mesh worse than before it, so the mesh from before it was kept; `None` otherwise.
pub fn budget_line(q: &QualitySection, seconds: Option<f64>) -> Option<String> {
    let k = q.pass.budget.as_ref().filter(|k| k.kept_before)?;
    let (a, b) = (&k.after, &k.before);
    let why = if q.pass.out_of_time {
        format!(
            "--quality-time {} s ran out",
            seconds.map_or_else(|| "?".into(), |t| t.to_string())
        )
    } else {
        "on the curvilinear grid the pass ended".to_string()
    };
    Some(format!(
        "{why} with the mesh worse than before the pass ({} tets below {}° \
         and {} off target, against {} and {} before; smallest angle {}° against {}°): the mesh \
         from before the pass is kept",
        a.below_floor,
        q.floor_degrees,
        a.off_target,
        b.below_floor,
        b.off_target,
        fmt_angle(a.min_dihedral),
        fmt_angle(b.min_dihedral)
    ))
}
