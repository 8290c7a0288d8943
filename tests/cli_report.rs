//! What `tptd-mesh` tells about a run, through the binary: every warning printed is in the
//! `--report`, a missed quality target is said in one line (regular and curvilinear grids),
//! a time budget never leaves the mesh worse than before the pass, the stage times add up,
//! and bad arguments are usage errors before any work.

mod common;

use std::fs;
use std::path::Path;
use std::process::Output;

use common::files::{npy_bytes, write_npy};
use common::output::{assert_ok, read_json, run_in, stderr, stdout};
use serde_json::Value;

/// The warnings on stderr, without their prefix.
fn stderr_warnings(o: &Output) -> Vec<String> {
    stderr(o)
        .lines()
        .filter_map(|l| l.strip_prefix("tptd-mesh: warning: "))
        .map(str::to_string)
        .collect()
}

/// The report's `warnings` array.
fn report_warnings(r: &Value) -> Vec<String> {
    let w = r["warnings"].as_array().expect("a warnings array");
    w.iter().map(|s| s.as_str().unwrap().to_string()).collect()
}

#[test]
fn the_report_carries_every_warning_printed() {
    let dir = tempfile::tempdir().unwrap();
    // 190 outside a blob of 210, with one face checkerboarded 200/201: its saddle is 200.5.
    write_npy(&dir.path().join("c.npy"), [6, 6, 6], |i, j, k| {
        let r2 = (i as f64 - 2.5).powi(2) + (j as f64 - 2.5).powi(2) + (k as f64 - 2.5).powi(2);
        if (2..=3).contains(&i) && (2..=3).contains(&j) && k == 1 {
            200.0 + ((i + j) % 2) as f64
        } else if r2 < 3.0 {
            210.0
        } else {
            190.0
        }
    });
    // alpha on the face saddle (the critical-value check), beta on grid values (the exact
    // bound check)
    let args = [
        "c.npy", "--alpha", "200.5", "--beta", "210", "-o", "m.vtu", "-q", "--report", "r.json",
    ];
    let o = run_in(dir.path(), &args);
    assert_ok(&o);
    let printed = stderr_warnings(&o);
    assert!(
        printed.iter().any(|w| w.contains("face saddle")),
        "{printed:?}"
    );
    assert!(
        printed.iter().any(|w| w.contains("--beta 210 equals")),
        "{printed:?}"
    );
    assert_eq!(stderr(&o).lines().count(), printed.len(), "{}", stderr(&o));
    assert_eq!(
        report_warnings(&read_json(&dir.path().join("r.json"))),
        printed
    );
    // no warning: an empty array
    let args = [
        "c.npy", "--alpha", "200.25", "-o", "m.vtu", "-q", "--report", "r.json",
    ];
    let o = run_in(dir.path(), &args);
    assert_ok(&o);
    assert!(stderr(&o).is_empty(), "{}", stderr(&o));
    let r = read_json(&dir.path().join("r.json"));
    assert_eq!(r["warnings"], serde_json::json!([]));
}

#[test]
fn an_unknown_transfer_extension_is_a_usage_error_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    // The input does not exist: the argument is refused before anything is read.
    let o = run_in(
        dir.path(),
        &["missing.npy", "--critical", "--transfer", "x.foo"],
    );
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let err = stderr(&o);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.starts_with("tptd-mesh: error: "), "{err}");
    assert!(err.contains("x.foo") && err.contains(".csv"), "{err}");
    assert!(!err.contains("missing.npy"), "{err}");
    assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 0);
}

/// A `.vts` of 12 × 10 × 8 points, sheared (x + y) and squashed (z × 0.1), with field `a`:
/// two Gaussian blobs. The pass works in the grid's parameter space, where its tets are fine;
/// the map flattens some, before the pass and after it.
fn write_sheared_vts(path: &Path) {
    let dims = [12usize, 10, 8];
    let (mut pts, mut a) = (String::new(), String::new());
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                let (x, y, z) = (i as f64, j as f64, k as f64);
                pts += &format!("{} {} {} ", x + y, y + 0.1 * (x * 0.8).sin(), 0.1 * z);
                let blob = |cx: f64| {
                    let d = (x - cx).powi(2) + (y - 5.0).powi(2) + (z - 4.0).powi(2);
                    (-d / 4.0).exp()
                };
                a += &format!("{} ", blob(3.6) + blob(8.4));
            }
        }
    }
    let text = format!(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"StructuredGrid\" version=\"0.1\">\n\
         <StructuredGrid WholeExtent=\"0 11 0 9 0 7\"><Piece Extent=\"0 11 0 9 0 7\">\n\
         <PointData><DataArray type=\"Float64\" Name=\"a\" format=\"ascii\">{a}</DataArray>\
         </PointData>\n<Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" \
         format=\"ascii\">{pts}</DataArray></Points></Piece></StructuredGrid></VTKFile>\n"
    );
    fs::write(path, text).unwrap();
}

/// A gently curved layer 0.18 voxels thick: the pass cannot reach its target there.
fn write_thin_layer(path: &Path) {
    write_npy(path, [16, 16, 16], |i, j, k| {
        let (x, y) = (i as f64, j as f64);
        k as f64 + 0.8 * (x / 3.0).sin() * (y / 2.5).cos()
    });
}

/// The one summary line that says the target was missed.
fn missed_line(o: &Output) -> String {
    let out = stdout(o);
    let lines: Vec<&str> = out
        .lines()
        .filter(|l| l.contains("quality target missed"))
        .collect();
    assert_eq!(lines.len(), 1, "{out}");
    lines[0].trim_start().to_string()
}

/// `u64` at `v`.
fn count(v: &Value) -> u64 {
    v.as_u64().unwrap_or_else(|| panic!("not a count: {v}"))
}

#[test]
fn a_missed_target_is_said_in_one_line_for_regular_and_curvilinear_grids() {
    let dir = tempfile::tempdir().unwrap();
    write_sheared_vts(&dir.path().join("g.vts"));
    write_thin_layer(&dir.path().join("thin.npy"));
    for (input, alpha, beta) in [("g.vts", "0.5", "2"), ("thin.npy", "7.03", "7.21")] {
        let args = [
            input,
            "--alpha",
            alpha,
            "--beta",
            beta,
            "--quality",
            "-o",
            "m.vtu",
            "--report",
            "r.json",
        ];
        let o = run_in(dir.path(), &args);
        assert_ok(&o);
        let line = missed_line(&o);
        assert!(
            line.starts_with("warning   quality target missed: ") && line.contains("below 5°: "),
            "{input}: {line}"
        );
        let r = read_json(&dir.path().join("r.json"));
        let q = &r["quality"];
        // the line is the warning printed and reported
        let message = format!("{input}: {}", line.trim_start_matches("warning").trim());
        assert!(stderr_warnings(&o).contains(&message), "{}", stderr(&o));
        assert!(report_warnings(&r).contains(&message), "{input}: {r}");
        // the counts are those of the mesh written, and every tet below 5° has a reason
        let (outcome, after) = (&q["outcome"], &q["after"]);
        assert_eq!(q["target_missed"], Value::Bool(true));
        assert_eq!(count(&outcome["below_min"]), count(&after["below"][2]));
        assert_eq!(count(&outcome["above_max"]), count(&after["above"][1]));
        let below_floor = count(&outcome["below_floor"]);
        assert!(below_floor > 0, "{input}: {q}");
        assert_eq!(below_floor, count(&after["below"][0]), "{input}");
        let c = &q["forced"]["counts"];
        let reasons = ["near_critical", "thin_layer", "box_angle", "grid_mapping"];
        let sum = reasons.iter().map(|k| count(&c[k])).sum::<u64>() + count(&c["unexplained"]);
        assert_eq!(sum, below_floor, "{input}: {c}");
        let listed = q["forced"]["elements"].as_array().unwrap().len() as u64;
        assert_eq!(listed, below_floor.min(1000), "{input}");
        assert!(line.contains(&format!("{below_floor} below 5°")), "{line}");
        if input == "g.vts" {
            // fine in parameter space, flattened by the map
            assert!(count(&c["grid_mapping"]) > 0, "{c}");
            assert!(line.contains("flattened by the grid mapping"), "{line}");
            // the pass's result is compared with its start through the map, the better kept
            let b = &q["pass"]["budget"];
            for side in ["before", "after"] {
                assert!(below_floor <= count(&b[side]["below_floor"]), "{b}");
            }
        }
    }
    // a target met: no such line, no warning
    let o = run_in(dir.path(), &["--demo", "--quality", "-o", "d.vtu"]);
    assert_ok(&o);
    assert!(!stdout(&o).contains("target missed"), "{}", stdout(&o));
    assert!(stderr(&o).is_empty(), "{}", stderr(&o));
}

/// Asserts that the stage times of report `r` add up to its total (the rest, `other`, is
/// small) and the quality step's parts to the step.
fn assert_times_add_up(r: &Value) {
    let t = &r["timings_seconds"];
    let secs = |v: &Value| v.as_f64().unwrap_or(0.0);
    let stages = [
        "read", "checks", "mesh", "quality", "map", "analysis", "check", "write", "other",
    ];
    let sum: f64 = stages.iter().map(|k| secs(&t[k])).sum();
    let total = secs(&t["total"]);
    assert!((sum - total).abs() <= 1e-6 * total.max(1.0), "{t}");
    assert!(secs(&t["other"]) <= 0.05 * total + 0.05, "{t}");
    let Some(parts) = t["quality_stages"].as_object() else {
        return;
    };
    let step: f64 = parts.values().map(secs).sum();
    assert!((step - secs(&t["quality"])).abs() <= 1e-6, "{t}");
    // the pass's own seconds: within its part, broken down by stage
    let pass = &r["quality"]["pass"];
    let seconds = secs(&pass["seconds"]);
    assert!(seconds <= secs(&parts["pass"]) + 1e-6, "{t} {pass}");
    assert!(
        secs(&parts["pass"]) - seconds <= 0.1 * seconds + 0.05,
        "{t} {pass}"
    );
    let by_stage: f64 = pass["stage_seconds"]
        .as_object()
        .unwrap()
        .values()
        .map(secs)
        .sum();
    assert!(
        (by_stage - seconds).abs() <= 1e-6 * seconds.max(1.0),
        "{pass}"
    );
    assert!(
        secs(&pass["stage_seconds"]["other"]) <= 0.25 * seconds + 0.05,
        "{pass}"
    );
}

#[test]
fn a_time_budget_never_leaves_the_mesh_worse_and_the_times_add_up() {
    let dir = tempfile::tempdir().unwrap();
    // A z-map: a 64³ height field (float32) whose bounds equal grid values (slivers to
    // improve).
    let mut data = Vec::new();
    for i in 0..64 {
        for j in 0..64 {
            for k in 0..64 {
                let (x, y) = (f64::from(i), f64::from(j));
                let f = f64::from(k) - 20.0 * (x / 9.0).sin() * (y / 7.0).cos();
                data.extend_from_slice(&(f as f32).to_le_bytes());
            }
        }
    }
    let npy = npy_bytes("<f4", "(64, 64, 64)", &data);
    fs::write(dir.path().join("z.npy"), npy).unwrap();
    let args = [
        "z.npy",
        "--alpha",
        "0",
        "--beta",
        "10",
        "--quality",
        "--quality-time",
        "0.05",
        "-o",
        "m.vtu",
        "--report",
        "r.json",
    ];
    let o = run_in(dir.path(), &args);
    assert_ok(&o);
    let r = read_json(&dir.path().join("r.json"));
    let q = &r["quality"];
    let (before, after) = (&q["before"], &q["after"]);
    // not worse: no more tets below 5°, and no more below 15° when those are as many
    let key = |s: &Value| (count(&s["below"][0]), count(&s["below"][2]));
    assert!(key(after) <= key(before), "before {before}\nafter {after}");
    let pass = &q["pass"];
    if pass["out_of_time"] == Value::Bool(true) {
        let budget = &pass["budget"];
        let kept_before = budget["kept_before"] == Value::Bool(true);
        let kept = if kept_before { "before" } else { "after" };
        assert_eq!(
            budget[kept]["below_floor"], q["outcome"]["below_floor"],
            "{budget}"
        );
        assert_eq!(
            stdout(&o).contains("the mesh from before the pass kept"),
            kept_before
        );
        let said = report_warnings(&r)
            .iter()
            .any(|w| w.contains("--quality-time 0.05 s ran out"));
        assert_eq!(said, kept_before, "{:?}", report_warnings(&r));
    }
    assert_times_add_up(&r);
    // and on a curvilinear grid, with the map
    write_sheared_vts(&dir.path().join("g.vts"));
    let args = [
        "g.vts",
        "--alpha",
        "0.5",
        "--quality",
        "--check",
        "-o",
        "g.vtu",
        "--report",
        "g.json",
    ];
    assert_ok(&run_in(dir.path(), &args));
    let r = read_json(&dir.path().join("g.json"));
    assert!(r["timings_seconds"]["map"].as_f64().is_some(), "{r}");
    assert_times_add_up(&r);
}
