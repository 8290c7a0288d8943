//! `--inspect MESH...`: reads each mesh, has the library inspect it
//! ([`tptd::inspect::inspect`]; with `--volume`, against the trilinear interval) and prints
//! one column per mesh; `--json` writes one object per mesh. An unreadable mesh ends the run
//! with one line naming it (exit 1) before anything is written; an invalid mesh is a result,
//! not an error (exit 0).

use std::io::Write;
use std::path::Path;

use anyhow::Result;
use tptd::check::Problem;
use tptd::inspect::{
    inspect, problem_group, reference, InspectOptions, Inspection, Reference, ReferenceOptions,
    MAX_PERCENTILES, MIN_PERCENTILES, PROBLEM_GROUPS, QUALITY_THRESHOLDS,
};
use tptd::io::{check_writable, read_mesh, read_volume, write_atomically};
use tptd::ScalarGrid;

use crate::cli::{Cli, Spacing};
use crate::error::{file_error, write_error};
use crate::progress::Stage;
use tptd::pipeline::text::fmt_interval;

/// Runs `tptd-mesh --inspect MESH... [--volume VOLUME --alpha A --beta B] [--json FILE]`.
pub(crate) fn run(cli: Cli) -> Result<()> {
    if let Some(n) = cli.threads {
        // the pool is built once, here, before any parallel work
        let _ = rayon::ThreadPoolBuilder::new()
            .num_threads(n as usize)
            .build_global();
    }
    if let Some(j) = &cli.json {
        check_writable(j).map_err(write_error)?;
    }
    crate::files::check_files(&cli, None)?;
    let volume = match &cli.volume {
        Some(path) => Some(read_reference(&cli, path)?),
        None => None,
    };
    let opts = InspectOptions {
        volume: volume.as_ref().map(|(g, r)| (g, r)),
        ..InspectOptions::default()
    };
    let mut all = Vec::with_capacity(cli.inspect.len());
    for path in &cli.inspect {
        let name = path.display().to_string();
        let stage = Stage::start(format!("inspecting {name}"), cli.quiet);
        let file = read_mesh(path)?;
        all.push(inspect(&name, file.mesh, &opts));
        stage.finish();
    }
    if let Some(path) = &cli.json {
        write_atomically(path, |w| {
            serde_json::to_writer_pretty(&mut *w, &all).map_err(std::io::Error::other)?;
            writeln!(w)
        })
        .map_err(write_error)?;
    }
    if !cli.quiet {
        let reference = volume.as_ref().zip(cli.volume.as_deref());
        let text = table(&all, reference.map(|((_, r), p)| (r, p)));
        if let Err(e) = std::io::stdout().write_all(text.as_bytes()) {
            if e.kind() != std::io::ErrorKind::BrokenPipe {
                return Err(file_error("stdout", format_args!("cannot write: {e}")));
            }
        }
    }
    Ok(())
}

/// Reads `--volume` (with `--spacing`) and computes the reference of the interval.
fn read_reference(cli: &Cli, path: &Path) -> Result<(ScalarGrid, Reference)> {
    let name = path.display().to_string();
    let stage = Stage::start(format!("reading {name}"), cli.quiet);
    let mut grid = read_volume(path)?;
    if let Some(Spacing(s)) = cli.spacing {
        grid = ScalarGrid::with_geometry(grid.dims, s, grid.origin, grid.direction, grid.values)
            .map_err(|e| file_error(&name, format_args!("--spacing: {e}")))?;
    }
    stage.finish();
    let alpha = cli.alpha.unwrap_or(f64::NEG_INFINITY);
    let beta = cli.beta.unwrap_or(f64::INFINITY);
    if alpha >= beta {
        return Err(file_error(
            &name,
            format_args!("empty interval: --alpha ({alpha}) must be less than --beta ({beta})"),
        ));
    }
    let stage = Stage::start(
        format!("the trilinear interval {}", fmt_interval(alpha, beta)),
        cli.quiet,
    );
    let r = reference(&grid, alpha, beta, &ReferenceOptions::default())
        .map_err(|e| file_error(&name, e))?;
    stage.finish();
    Ok((grid, r))
}

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
    let dihedral = |f: &dyn Fn(&tptd::inspect::Dihedral) -> String| {
        col(all, &|i| i.dihedral.as_ref().map_or("-".into(), f))
    };
    let q = |f: &dyn Fn(&tptd::inspect::Quality) -> String| col(all, &|i| f(&i.quality));
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
fn level_cell(l: &tptd::check::LevelSummary) -> String {
    if l.beyond == 0 {
        format!("{:.3}", l.max_distance)
    } else {
        format!("{:.3} ({} beyond)", l.max_distance, l.beyond)
    }
}

/// The side-by-side table, the reference, and the examples of every problem.
fn table(all: &[Inspection], reference: Option<(&Reference, &Path)>) -> String {
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
