//! The number formats of messages ([`crate::text`], re-exported), and the lines that say what
//! the quality pass left: shared by the warnings of a run and by a front end's summary.

use crate::improve::forced::ForcedCounts;
use crate::report::QualitySection;

use super::{Param, ParamNames};

pub use crate::text::{fmt_angle, fmt_bound, fmt_interval};

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
pub fn target_line(q: &QualitySection, names: ParamNames) -> Option<String> {
    let o = &q.outcome;
    if !o.missed() {
        return None;
    }
    let [lo, hi] = q.target_degrees;
    let floor = q.floor_degrees;
    let below_floor = match (&q.forced, o.below_floor) {
        (_, 0) => format!("none below {floor}°"),
        (Some(f), n) => format!("{n} below {floor}°: {}", reasons(&f.counts)),
        (None, n) => format!(
            "{n} below {floor}° (reasons not looked for: {})",
            names.of(Param::NoAnalysis)
        ),
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
pub fn budget_line(q: &QualitySection, seconds: Option<f64>, names: ParamNames) -> Option<String> {
    let k = q.pass.budget.as_ref().filter(|k| k.kept_before)?;
    let (a, b) = (&k.after, &k.before);
    let why = if q.pass.out_of_time {
        format!(
            "{} {} s ran out",
            names.of(Param::QualityTime),
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
