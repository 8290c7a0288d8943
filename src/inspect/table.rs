//! The side-by-side table `tptd-mesh --inspect` prints: one column per inspected mesh (counts,
//! quality, validity, the embedding, and against a reference interval its topology, level
//! distance and volume), then the reference and every problem with examples.

use std::path::Path;

use super::{
    problem_group, Inspection, Reference, MAX_PERCENTILES, MIN_PERCENTILES, PROBLEM_GROUPS,
    QUALITY_THRESHOLDS,
};
use crate::check::Problem;
use crate::text::fmt_interval;

/// A number with six significant digits (scientific when very large or small).
fn num(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let mag = v.abs().log10().floor() as i32;
    if !(-3..6).contains(&mag) {
        return format!("{v:.5e}");
    }
    format!("{v:.*}", (5 - mag).max(0) as usize)
}

fn joined<T: std::fmt::Display>(v: &[T]) -> String {
    v.iter()
        .map(ToString::to_string)
        .collect::<Vec<_>>()
        .join(" ")
}

fn angles(v: &[f64]) -> String {
    v.iter()
        .map(|a| format!("{a:.2}"))
        .collect::<Vec<_>>()
        .join(" ")
}

/// The problems of one group, `ok` when none.
fn group_cell(i: &Inspection, group: &str) -> String {
    let found: Vec<String> = i
        .problems
        .iter()
        .filter(|p| problem_group(p.kind) == group)
        .map(|p| format!("{} {}", p.count, p.kind.name()))
        .collect();
    let mut cell = if found.is_empty() {
        "ok".to_string()
    } else {
        found.join(", ")
    };
    if group == PROBLEM_GROUPS[1] && i.flipped {
        cell.push_str(" (flipped)");
    }
    cell
}

/// A row: its name and one cell per mesh.
type Row = (String, Vec<String>);

/// The cells of one row, one per mesh.
fn col(all: &[Inspection], f: &dyn Fn(&Inspection) -> String) -> Vec<String> {
    all.iter().map(f).collect()
}

/// The rows of the table: counts and quality, the checker's verdict, the reference.
fn rows(all: &[Inspection], with_volume: bool) -> Vec<Row> {
    let mut r = quality_rows(all);
    let groups = if with_volume { 5 } else { 4 };
    for g in &PROBLEM_GROUPS[..groups] {
        r.push((g.to_string(), col(all, &|i| group_cell(i, g))));
    }
    r.push((
        "Betti numbers".into(),
        col(all, &|i| {
            i.betti.map_or("- (boundary open)".into(), |b| joined(&b))
        }),
    ));
    if with_volume {
        r.extend(reference_rows(all));
    }
    r.push(("valid".into(), col(all, &|i| yes_no(i.valid))));
    r
}

/// Counts, volume, dihedral angles and the other quality measures.
fn quality_rows(all: &[Inspection]) -> Vec<Row> {
    let (below, above) = QUALITY_THRESHOLDS;
    let pct = |p: &[f64]| joined(&p.iter().map(|x| format!("p{x}")).collect::<Vec<_>>());
    let dihedral = |f: &dyn Fn(&super::Dihedral) -> String| {
        col(all, &|i| i.dihedral.as_ref().map_or("-".into(), f))
    };
    let q = |f: &dyn Fn(&super::Quality) -> String| col(all, &|i| f(&i.quality));
    vec![
        ("nodes".into(), col(all, &|i| i.nodes.to_string())),
        ("tets".into(), col(all, &|i| i.tets.to_string())),
        (
            "boundary faces".into(),
            col(all, &|i| i.boundary_faces.to_string()),
        ),
        ("volume".into(), col(all, &|i| num(i.volume))),
        (
            "dihedral min max".into(),
            dihedral(&|d| angles(&[d.min, d.max])),
        ),
        (
            format!("tet min angle {}", pct(&MIN_PERCENTILES)),
            dihedral(&|d| angles(&d.min_percentiles)),
        ),
        (
            format!("tet max angle {}", pct(&MAX_PERCENTILES)),
            dihedral(&|d| angles(&d.max_percentiles)),
        ),
        (
            format!("tets min angle < {}", joined(&below)),
            q(&|q| joined(&q.below)),
        ),
        (
            format!("tets max angle > {}", joined(&above)),
            q(&|q| joined(&q.above)),
        ),
        (
            "radius ratio min".into(),
            q(&|q| format!("{:.4}", q.min_radius_ratio)),
        ),
        ("SICN min".into(), q(&|q| format!("{:.4}", q.min_sicn))),
        ("gamma min".into(), q(&|q| format!("{:.4}", q.min_gamma))),
    ]
}

/// Against the trilinear interval: topology, labels, level distance, volume.
fn reference_rows(all: &[Inspection]) -> Vec<Row> {
    vec![
        (
            "matches reference".into(),
            col(all, &|i| yes_no(i.matches_reference == Some(true))),
        ),
        (
            "boundary labels".into(),
            col(all, &|i| {
                i.labels
                    .as_ref()
                    .map_or("-".into(), |l| l.source.replace('_', " "))
            }),
        ),
        (
            "level distance max (vox)".into(),
            col(all, &|i| i.level.as_ref().map_or("-".into(), level_cell)),
        ),
        (
            "volume vs trilinear".into(),
            col(all, &|i| {
                i.volume_error
                    .map_or("-".into(), |e| format!("{:+.3} %", 100.0 * e))
            }),
        ),
    ]
}

fn yes_no(b: bool) -> String {
    if b { "yes" } else { "NO" }.into()
}

/// The largest level-set distance, and the points beyond the bound.
fn level_cell(l: &crate::check::LevelSummary) -> String {
    if l.beyond == 0 {
        format!("{:.3}", l.max_distance)
    } else {
        format!("{:.3} ({} beyond)", l.max_distance, l.beyond)
    }
}

/// The side-by-side table, the reference, and the examples of every problem.
pub fn table(all: &[Inspection], reference: Option<(&Reference, &Path)>) -> String {
    let rows = rows(all, reference.is_some());
    let heads: Vec<String> = all.iter().map(|i| i.file.clone()).collect();
    let w0 = rows.iter().map(|(n, _)| n.len()).max().unwrap_or(0);
    let widths: Vec<usize> = (0..all.len())
        .map(|c| {
            rows.iter()
                .map(|(_, cells)| cells[c].len())
                .chain([heads[c].len()])
                .max()
                .unwrap_or(0)
        })
        .collect();
    let mut out = String::new();
    let mut line = |name: &str, cells: &[String]| {
        let mut l = format!("{name:<w0$}");
        for (c, w) in cells.iter().zip(&widths) {
            l.push_str(&format!("  {c:<w$}"));
        }
        out.push_str(l.trim_end());
        out.push('\n');
    };
    line("", &heads);
    for (name, cells) in &rows {
        line(name, cells);
    }
    if let Some((r, path)) = reference {
        out.push_str(&reference_line(r, path, all));
    }
    for i in all {
        for p in &i.problems {
            out.push_str(&format!("{}: {}\n", i.file, problem_line(p)));
        }
    }
    out
}

/// The reference and which meshes match it.
fn reference_line(r: &Reference, path: &Path, all: &[Inspection]) -> String {
    let v = r.volume;
    let matching: Vec<&str> = all
        .iter()
        .filter(|i| i.matches_reference == Some(true))
        .map(|i| i.file.as_str())
        .collect();
    format!(
        "reference: the trilinear interval {} of {}: Betti numbers {}, volume {} (between {} \
         and {}); matching it: {}\n",
        fmt_interval(r.levels.0, r.levels.1),
        path.display(),
        joined(&r.betti),
        num(v.estimate),
        num(v.low),
        num(v.high),
        if matching.is_empty() {
            "none".to_string()
        } else {
            matching.join(", ")
        }
    )
}

/// `N kind (e.g. ids; ids)`.
fn problem_line(p: &Problem) -> String {
    let ex: Vec<String> = p
        .examples
        .iter()
        .filter(|e| !e.is_empty())
        .map(|e| joined(e))
        .collect();
    if ex.is_empty() {
        format!("{} {}", p.count, p.kind.name())
    } else {
        format!("{} {} (e.g. {})", p.count, p.kind.name(), ex.join("; "))
    }
}
