//! The human-readable summary of a run, as `tptd-mesh` prints it on stdout: input, mesh,
//! analysis, quality, cells, outputs (number formats from [`super::text`]).

use std::fmt::Write as _;
use std::path::Path;

use super::text::{fmt_angle, fmt_bound, reasons, target_line};
use super::{DemoComparison, Param, ParamNames};
use crate::improve::ImproveReport;
use crate::quality::BELOW_ANGLES;
use crate::report::Report;
use crate::CellCase;

/// The check's findings on a valid mesh.
fn check_line(c: &crate::check::CheckReport) -> String {
    let mut line = c.summary_line();
    if let Some(w) = &c.winding {
        line += &format!(
            ": winding number 1 at {} sampled tets",
            w.exact + w.generalised
        );
    }
    if let Some(l) = &c.level {
        line += &format!(
            ", boundary within {:.3} voxel of its levels ({} points, bound {:.3})",
            l.max_distance, l.points, l.bound
        );
    }
    line
}

/// The human-readable summary of a run's report `r` (with the demo's comparison `cmp`, and
/// the report file's path when one was written), one line per fact, each ending in a newline;
/// parameters are named by `names`.
pub fn summary(
    r: &Report,
    cmp: Option<&DemoComparison>,
    report_path: Option<&Path>,
    names: ParamNames,
) -> String {
    let mut s = String::new();
    input_lines(&mut s, r);
    mesh_lines(&mut s, r);
    analysis_lines(&mut s, r, names);
    region_lines(&mut s, r);
    grade_line(&mut s, r);
    quality_lines(&mut s, r, names);
    cells_line(&mut s, r);
    output_lines(&mut s, r, report_path);
    if let (Some(c), Some([b0, ..])) = (cmp, r.betti) {
        demo_lines(&mut s, r, c, b0);
    }
    s
}

/// The first lines: input and output, grid, interval and method.
fn input_lines(s: &mut String, r: &Report) {
    let [nx, ny, nz] = r.dims;
    let alpha = match r.alpha.0 {
        v if v == f64::NEG_INFINITY => "(-inf".to_string(),
        v => format!("[{}", fmt_bound(v)),
    };
    let beta = match r.beta.0 {
        v if v == f64::INFINITY => "inf)".to_string(),
        v => format!("{}]", fmt_bound(v)),
    };
    let _ = writeln!(s, "tptd-mesh: {} -> {}", r.input, r.output);
    let _ = writeln!(
        s,
        "  grid      {nx} x {ny} x {nz} vertices, spacing {} x {} x {} (file units), {} cells, \
         samples {}",
        r.spacing[0], r.spacing[1], r.spacing[2], r.cells_total, r.samples
    );
    if r.levels.is_empty() {
        let _ = writeln!(
            s,
            "  interval  {alpha}, {beta}   method {}   threads {}",
            r.method, r.threads
        );
        return;
    }
    let levels: Vec<String> = r.levels.iter().map(|l| fmt_bound(l.0)).collect();
    let _ = writeln!(
        s,
        "  levels    {} ({} regions)   method {}   threads {}",
        levels.join(", "),
        r.levels.len() - 1,
        r.method,
        r.threads
    );
}

/// The size of the mesh and of its boundary.
fn mesh_lines(s: &mut String, r: &Report) {
    let _ = writeln!(
        s,
        "  mesh      {} nodes, {} tets, volume {:.6} (file units^3)",
        r.nodes, r.tets, r.volume
    );
    let bt = |k: &str| r.boundary_triangles.get(k).copied().unwrap_or(0);
    if r.levels.is_empty() {
        let _ = writeln!(
            s,
            "  boundary  {} triangles: alpha {}, beta {}, box {}",
            bt("alpha") + bt("beta") + bt("box"),
            bt("alpha"),
            bt("beta"),
            bt("box")
        );
        return;
    }
    let n = r.levels.len();
    let (first, last) = ("level1".to_string(), format!("level{n}"));
    let outer = bt(&first) + bt(&last) + bt("box");
    let inner: Vec<String> = (2..n)
        .map(|i| format!("level{i} {}", bt(&format!("level{i}"))))
        .collect();
    let _ = writeln!(
        s,
        "  boundary  {outer} triangles: {first} {}, {last} {}, box {}; interfaces: {}",
        bt(&first),
        bt(&last),
        bt("box"),
        inner.join(", ")
    );
}

/// The graded interior: the cubes by side and the tets they saved.
fn grade_line(s: &mut String, r: &Report) {
    let Some(g) = &r.grade else {
        return;
    };
    let cubes: Vec<String> = (g.cubes.iter().enumerate())
        .map(|(l, n)| format!("{n} of {} cells", 2usize << l))
        .collect();
    let saved = 1.0 - g.tets_after as f64 / g.tets_before.max(1) as f64;
    let _ = writeln!(
        s,
        "  graded    cubes up to {} cells a side: {}; tets {} -> {} ({:.1} % fewer)",
        g.max_side_cells,
        if cubes.is_empty() {
            "none".to_string()
        } else {
            cubes.join(", ")
        },
        g.tets_before,
        g.tets_after,
        100.0 * saved
    );
}

/// Each region of a run of several levels: its interval, tets, volume, and with the analysis
/// its Betti numbers and dihedral range.
fn region_lines(s: &mut String, r: &Report) {
    for g in &r.regions {
        let mut line = format!(
            "  region    {} [{}, {}]: {} tets, volume {:.6}",
            g.name,
            fmt_bound(g.levels[0].0),
            fmt_bound(g.levels[1].0),
            g.tets,
            g.volume
        );
        if let Some([b0, b1, b2]) = g.betti {
            line += &format!(", b0 = {b0}, b1 = {b1}, b2 = {b2}");
        }
        if let Some(d) = g.dihedral_degrees {
            line += &format!(", dihedral {}..{} deg", fmt_angle(d.min), fmt_angle(d.max));
        }
        let _ = writeln!(s, "{line}");
    }
}

/// Betti numbers and dihedral angles (or that they were skipped).
fn analysis_lines(s: &mut String, r: &Report, names: ParamNames) {
    match r.betti {
        Some([b0, b1, b2]) => {
            let _ = writeln!(s, "  topology  b0 = {b0}, b1 = {b1}, b2 = {b2}");
        }
        None => {
            let _ = writeln!(s, "  topology  (skipped: {})", names.of(Param::NoAnalysis));
        }
    }
    if let Some(d) = r.dihedral_degrees {
        let _ = writeln!(
            s,
            "  dihedral  min {} deg, max {} deg",
            fmt_angle(d.min),
            fmt_angle(d.max)
        );
    }
}

/// The quality pass: what it did and the angles before and after.
fn quality_lines(s: &mut String, r: &Report, names: ParamNames) {
    let Some(q) = &r.quality else {
        return;
    };
    let p = &q.pass;
    let _ = writeln!(
        s,
        "  quality   target [{}, {}] deg: {} collapses, {} flips, {} edge removals, {} edge \
         splits, {} moves ({} giving volume back), {} nodes onto the level sets ({} left off) in \
         {} rounds{}",
        q.target_degrees[0],
        q.target_degrees[1],
        p.collapses,
        p.flips,
        p.edge_removals,
        p.splits,
        p.smoothed + p.restored,
        p.restored,
        p.projected,
        p.unprojected,
        p.rounds,
        stopped(p, names)
    );
    if !p.stages.is_empty() {
        let stages: Vec<String> = p
            .stages
            .iter()
            .map(|st| {
                let [lo, hi] = st.target_degrees;
                let what = if st.kept { "kept" } else { "undone" };
                let deg = |x: f64| (x * 100.0).round() / 100.0;
                format!("{}°/{}° {what}", deg(lo), deg(hi))
            })
            .collect();
        let _ = writeln!(s, "            in stages: {}", stages.join(", "));
    }
    if p.volume_retries > 0 {
        let _ = writeln!(
            s,
            "            ran again from the start {}× with shorter boundary collapses, \
             to keep the volume",
            p.volume_retries
        );
    }
    if let (Some(b), Some(a)) = (&q.before, &q.after) {
        for (label, summary) in [("before:", b), ("after: ", a)] {
            let _ = writeln!(
                s,
                "            {label} {} tets, dihedral [{}, {}] deg, {} tets below {} deg, {} below {} \
                 deg",
                summary.tets,
                fmt_angle(summary.min_dihedral),
                fmt_angle(summary.max_dihedral),
                summary.below[2],
                BELOW_ANGLES[2],
                summary.below[0],
                BELOW_ANGLES[0]
            );
        }
    }
    if let Some(f) = &q.forced {
        let _ = writeln!(
            s,
            "            below {} deg after: {}",
            f.floor_degrees,
            reasons(&f.counts)
        );
    }
    if let Some(line) = target_line(q, names) {
        let _ = writeln!(s, "  warning   {line}");
    }
}

/// How the pass ended, when its time budget stopped it (empty otherwise).
fn stopped(p: &ImproveReport, names: ParamNames) -> String {
    if !p.out_of_time {
        return String::new();
    }
    match &p.budget {
        Some(k) if k.kept_before => {
            format!(
                " (stopped by {}; the mesh from before the pass kept, it was better)",
                names.of(Param::QualityTime)
            )
        }
        _ => format!(" (stopped by {})", names.of(Param::QualityTime)),
    }
}

/// The meshed cells by case.
fn cells_line(s: &mut String, r: &Report) {
    let cases: Vec<String> = CellCase::ALL
        .iter()
        .filter_map(|c| {
            let e = r.cells_by_case.get(c.name())?;
            (e.count > 0).then(|| format!("{} {} ({:.1}%)", c.name(), e.count, 100.0 * e.ratio))
        })
        .collect();
    let _ = writeln!(
        s,
        "  cells     {} meshed of {}: {}",
        r.cells_meshed,
        r.cells_total,
        cases.join(", ")
    );
}

/// The seconds of meshing and of what followed it, in order.
fn stage_times(t: &crate::report::Timings) -> Vec<String> {
    let mut parts = Vec::new();
    parts.push(match (t.streamed, t.analysed_while_meshing) {
        (true, _) => format!("mesh and analysis (streamed to disk) {:.3} s", t.mesh),
        (false, true) => format!("mesh and analysis {:.3} s", t.mesh),
        (false, false) => format!("mesh {:.3} s", t.mesh),
    });
    if let (Some(q), Some(p)) = (t.quality, &t.quality_stages) {
        parts.push(format!(
            "quality {q:.3} s (before {:.3} s, pass {:.3} s, outcome {:.3} s)",
            p.before, p.pass, p.outcome
        ));
    }
    if let Some(m) = t.map {
        parts.push(format!("map {m:.3} s"));
    }
    match (t.analysed_while_meshing, t.analysis > 0.0) {
        (true, true) => parts.push(format!("demo comparison {:.3} s", t.analysis)),
        (true, false) => {}
        (false, _) => parts.push(format!("analysis {:.3} s", t.analysis)),
    }
    if let Some(g) = t.grade {
        parts.push(format!("grading {g:.3} s"));
    }
    if let Some(c) = t.check {
        parts.push(format!("check {c:.3} s"));
    }
    parts
}

/// Timings and the files written.
fn output_lines(s: &mut String, r: &Report, report_path: Option<&Path>) {
    let t = &r.timings_seconds;
    let middle = stage_times(t).join(", ");
    let _ = writeln!(
        s,
        "  time      read {:.3} s, checks {:.3} s, {middle}, write {:.3} s, other {:.3} s, total \
         {:.3} s",
        t.read, t.checks, t.write, t.other, t.total
    );
    if let Some(sf) = &r.surface {
        let _ = writeln!(
            s,
            "  surface   {} vertices, {} triangles, area {:.6}, Betti {:?}, closed 2-manifold {}, oriented {}",
            sf.vertices,
            sf.triangles,
            sf.area,
            sf.betti,
            if sf.closed_manifold { "yes" } else { "no" },
            if sf.oriented { "yes" } else { "no" }
        );
    }
    if let Some(c) = &r.check {
        let _ = writeln!(s, "  check     {}", check_line(c));
    }
    let _ = writeln!(s, "  wrote     {}", r.output);
    if let Some(p) = report_path {
        let _ = writeln!(s, "  report    {}", p.display());
    }
}

/// What the demo shows: the components of this method and of the other kind.
fn demo_lines(s: &mut String, r: &Report, c: &DemoComparison, b0: usize) {
    let _ = writeln!(s);
    let _ = writeln!(
        s,
        "demo: two parallel vessels whose walls are about a third of a voxel apart."
    );
    let _ = writeln!(
        s,
        "  {}: {b0} component{} (b0 = {b0}); {} would give b0 = {}{}",
        r.method,
        if b0 == 1 { "" } else { "s" },
        c.other.name(),
        c.other_b0,
        match (b0, c.other_b0) {
            (2, 1) => ": the 6-fold decomposition merges the vessels".to_string(),
            (1, 2) => ": the topology-preserving decomposition keeps them apart".to_string(),
            _ => String::new(),
        }
    );
}
