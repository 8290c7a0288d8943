//! What `tptd-mesh` tells about a run, through the binary: every warning printed is in the
//! `--report`, a missed quality target is said in one line (regular and curvilinear grids),
//! a time budget never leaves the mesh worse than before the pass, the stage times add up,
//! and bad arguments are usage errors before any work.

mod common;

use std::fs;
use std::path::Path;
use std::process::{Command, Output};

use common::files::write_npy;
use serde_json::Value;

const BIN: &str = env!("CARGO_BIN_EXE_tptd-mesh");

fn run_in(dir: &Path, args: &[&str]) -> Output {
    Command::new(BIN)
        .current_dir(dir)
        .args(args)
        .output()
        .expect("the binary runs")
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn assert_ok(o: &Output) {
    assert!(
        o.status.success(),
        "exit {:?}\nstdout:\n{}\nstderr:\n{}",
        o.status,
        stdout(o),
        stderr(o)
    );
}

/// The JSON document in the file at `path`.
fn read_json(path: &Path) -> Value {
    serde_json::from_str(&fs::read_to_string(path).unwrap()).unwrap()
}

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
