//! End-to-end tests of the `tptd-mesh` binary: the demo, meshing a small `.npy` to every
//! output format, the JSON report, determinism across thread counts, and the one-line errors
//! that leave no output behind.

mod common;

use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use common::external::{gmsh_reading, require_gmsh};
use common::files::{listing, write_npy};
use common::output::{assert_ok, read_json, run_in, stderr, stdout};
use serde_json::Value;

const BIN: &str = env!("CARGO_BIN_EXE_tptd-mesh");

/// A smooth blob: distance from an off-centre point plus a wobble, so generic values (no grid
/// value equals the bounds used below) and some ambiguous faces.
fn blob(i: usize, j: usize, k: usize) -> f64 {
    let (x, y, z) = (i as f64, j as f64, k as f64);
    let r = ((x - 4.3).powi(2) + (y - 3.7).powi(2) + (z - 3.1).powi(2)).sqrt();
    r + 0.7 * (1.3 * x).sin() * (0.9 * y).cos() + 0.4 * (1.7 * z).sin()
}

/// A temp dir holding `vol.npy` (9 × 8 × 7 blob).
fn dir_with_volume() -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("vol.npy");
    write_npy(&p, [9, 8, 7], blob);
    (dir, p)
}

#[test]
fn demo_keeps_the_two_vessels_apart() {
    let dir = tempfile::tempdir().unwrap();
    let o = run_in(dir.path(), &["--demo"]);
    assert_ok(&o);
    let out = stdout(&o);
    assert!(out.contains("b0 = 2"), "{out}");
    assert!(out.contains("six would give b0 = 1"), "{out}");
    assert!(stderr(&o).is_empty(), "{}", stderr(&o));
    assert_eq!(listing(dir.path()), ["tptd-demo.vtu"]);
    let vtu = fs::read(dir.path().join("tptd-demo.vtu")).unwrap();
    assert!(vtu.starts_with(b"<?xml") || vtu.starts_with(b"<VTKFile"));
}

/// `--msh-version 4.1-binary`: gmsh reads the demo's binary `.msh` (groups alpha and
/// domain, node data `f`) exactly as its ASCII 4.1 file.
#[test]
fn demo_binary_msh_reads_as_ascii_in_gmsh() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    assert_ok(&run_in(d, &["--demo", "-o", "a.msh", "-q"]));
    let binary = ["--demo", "-o", "b.msh", "--msh-version", "4.1-binary", "-q"];
    assert_ok(&run_in(d, &binary));
    let bytes = fs::read(d.join("b.msh")).unwrap();
    assert!(bytes.starts_with(b"$MeshFormat\n4.1 1 8\n\x01\0\0\0\n$EndMeshFormat\n"));
    if !require_gmsh() {
        return;
    }
    let (a_mesh, a_view) = gmsh_reading(&d.join("a.msh"), d, "a");
    let (b_mesh, b_view) = gmsh_reading(&d.join("b.msh"), d, "b");
    assert!(a_mesh.contains("2 1 \"alpha\"") && a_mesh.contains("3 4 \"domain\""));
    assert!(a_view.lines().filter(|l| l.starts_with("SS(")).count() > 1000);
    assert!(
        a_mesh == b_mesh,
        "gmsh re-exports the binary demo differently"
    );
    assert!(a_view == b_view, "gmsh reads different node data 'f'");
}

#[test]
fn demo_with_six_reports_the_merge() {
    let dir = tempfile::tempdir().unwrap();
    let o = run_in(
        dir.path(),
        &["--demo", "--method", "six", "-o", "six.msh", "-q"],
    );
    assert_ok(&o);
    assert!(stdout(&o).is_empty());
    assert_eq!(listing(dir.path()), ["six.msh"]);
    let o = run_in(dir.path(), &["--demo", "--method", "six", "-o", "six.msh"]);
    assert_ok(&o);
    assert!(stdout(&o).contains("b0 = 1"), "{}", stdout(&o));
    assert!(
        stdout(&o).contains("ctd would give b0 = 2"),
        "{}",
        stdout(&o)
    );
}

#[test]
fn meshes_npy_to_every_format_with_a_consistent_report() {
    let (dir, vol) = dir_with_volume();
    let vol = vol.to_str().unwrap();
    for (out, extra) in [
        ("m.msh", &[][..]),
        ("m22.msh", &["--msh-version", "2.2"][..]),
        ("mb.msh", &["--msh-version", "4.1-binary"][..]),
        ("m.inp", &[][..]),
        ("m.vtu", &[][..]),
    ] {
        let report = format!("{out}.json");
        let mut args = vec![
            vol, "-o", out, "--alpha", "2.05", "--beta", "4.45", "--report", &report,
        ];
        args.extend_from_slice(extra);
        let o = run_in(dir.path(), &args);
        assert_ok(&o);
        assert!(stderr(&o).is_empty(), "{}", stderr(&o));
        let s = stdout(&o);
        assert!(s.contains("b0 = "), "{s}");
        assert!(s.contains(out), "{s}");
        let text = fs::read_to_string(dir.path().join(out)).unwrap_or_else(|_| {
            // .vtu may hold binary data; only check it exists and is non-empty.
            assert!(fs::metadata(dir.path().join(out)).unwrap().len() > 0);
            String::new()
        });
        match out {
            "m.msh" => assert!(text.contains("$MeshFormat\n4.1"), "{}", &text[..50]),
            "m22.msh" => assert!(text.contains("$MeshFormat\n2.2"), "{}", &text[..50]),
            "mb.msh" => {
                let bytes = fs::read(dir.path().join(out)).unwrap();
                assert!(bytes.starts_with(b"$MeshFormat\n4.1 1 8\n\x01\0\0\0\n"));
            }
            "m.inp" => assert!(text.to_ascii_lowercase().contains("*node")),
            _ => {}
        }

        let r: Value = read_json(&dir.path().join(&report));
        assert_eq!(r["input"], vol);
        assert_eq!(r["output"], out);
        assert_eq!(r["method"], "ctd");
        assert_eq!(r["alpha"], 2.05);
        assert_eq!(r["beta"], 4.45);
        assert_eq!(r["dims"], serde_json::json!([9, 8, 7]));
        assert_eq!(r["spacing"], serde_json::json!([1.0, 1.0, 1.0]));
        assert_eq!(r["cells_total"], 8 * 7 * 6);
        let nodes = r["nodes"].as_u64().unwrap();
        let tets = r["tets"].as_u64().unwrap();
        assert!(nodes >= 4 && tets >= 1);
        assert!(s.contains(&format!("{nodes} nodes, {tets} tets")), "{s}");
        let bt = &r["boundary_triangles"];
        let (a, b, x) = (
            bt["alpha"].as_u64().unwrap(),
            bt["beta"].as_u64().unwrap(),
            bt["box"].as_u64().unwrap(),
        );
        assert!(a > 0 && b > 0, "{bt}");
        // A closed surface: every boundary edge is shared by two triangles, so 3B is even.
        assert_eq!((3 * (a + b + x)) % 2, 0);
        let meshed = r["cells_meshed"].as_u64().unwrap();
        assert!(meshed > 0 && meshed <= 8 * 7 * 6);
        let cases = r["cells_by_case"].as_object().unwrap();
        assert_eq!(cases.len(), 6);
        let sum: u64 = cases.values().map(|c| c["count"].as_u64().unwrap()).sum();
        assert_eq!(sum, meshed);
        let ratio: f64 = cases.values().map(|c| c["ratio"].as_f64().unwrap()).sum();
        assert!((ratio - 1.0).abs() < 1e-9);
        assert!(r["volume"].as_f64().unwrap() > 0.0);
        let betti = r["betti"].as_array().unwrap();
        assert_eq!(betti.len(), 3);
        assert!(betti[0].as_u64().unwrap() >= 1);
        let d = &r["dihedral_degrees"];
        let (lo, hi) = (d["min"].as_f64().unwrap(), d["max"].as_f64().unwrap());
        assert!(0.0 < lo && lo <= hi && hi < 180.0);
        assert!(r["threads"].as_u64().unwrap() >= 1);
        let t = &r["timings_seconds"];
        for k in ["read", "mesh", "analysis", "write", "total"] {
            assert!(t[k].as_f64().unwrap() >= 0.0, "{k}");
        }
        // Without --quality the mesh streams to disk, and the analysis happens on the way.
        assert_eq!(t["streamed"], Value::Bool(true));
        assert_eq!(t["analysis"].as_f64(), Some(0.0));
    }
}

#[test]
fn report_spells_infinite_bounds_and_skipped_analysis() {
    let (dir, vol) = dir_with_volume();
    let o = run_in(
        dir.path(),
        &[
            vol.to_str().unwrap(),
            "-o",
            "m.vtu",
            "--beta",
            "3.05",
            "--no-analysis",
            "--spacing",
            "0.5,1,2",
            "--method",
            "tptd",
            "-j",
            "1",
            "--report",
            "r.json",
        ],
    );
    assert_ok(&o);
    let r: Value = read_json(&dir.path().join("r.json"));
    assert_eq!(r["alpha"], "-inf");
    assert_eq!(r["beta"], 3.05);
    assert_eq!(r["method"], "tptd");
    assert_eq!(r["threads"], 1);
    assert_eq!(r["spacing"], serde_json::json!([0.5, 1.0, 2.0]));
    assert!(r["betti"].is_null());
    assert!(r["dihedral_degrees"].is_null());
    assert!(stdout(&o).contains("skipped"));
}

#[test]
fn output_is_identical_for_one_and_two_threads() {
    let dir = tempfile::tempdir().unwrap();
    let vol = dir.path().join("big.npy");
    write_npy(&vol, [17, 15, 13], |i, j, k| blob(i, j, k) * 0.6);
    let vol = vol.to_str().unwrap();
    for ext in ["msh", "inp", "vtu"] {
        for method in ["ctd", "six"] {
            let mut outs = Vec::new();
            for j in ["1", "2"] {
                let out = format!("o{j}.{ext}");
                let o = run_in(
                    dir.path(),
                    &[
                        vol, "-o", &out, "--alpha", "1.55", "--beta", "3.9", "-j", j, "-q",
                        "--method", method,
                    ],
                );
                assert_ok(&o);
                outs.push(fs::read(dir.path().join(&out)).unwrap());
            }
            assert!(!outs[0].is_empty());
            assert!(outs[0] == outs[1], "{ext}/{method}: -j 1 and -j 2 differ");
        }
    }
}

#[test]
fn warns_when_a_bound_equals_a_data_value() {
    let dir = tempfile::tempdir().unwrap();
    let vol = dir.path().join("labels.npy");
    write_npy(&vol, [6, 6, 6], |i, j, k| {
        if (1..5).contains(&i) && (1..5).contains(&j) && (1..4).contains(&k) {
            1.0
        } else {
            0.0
        }
    });
    let o = run_in(
        dir.path(),
        &[vol.to_str().unwrap(), "-o", "m.inp", "--alpha", "0", "-q"],
    );
    assert_ok(&o);
    let err = stderr(&o);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.starts_with("tptd-mesh: warning: "), "{err}");
    assert!(
        err.contains("labels.npy") && err.contains("--alpha 0"),
        "{err}"
    );
    assert!(err.contains("count as outside"), "{err}");
}

/// Runs a failing command in `dir` and checks: non-zero exit, exactly one stderr line of the
/// form `tptd-mesh: error: ...` that mentions `names`, nothing on stdout, and `dir` unchanged.
fn assert_clean_failure(dir: &Path, args: &[&str], names: &str) -> String {
    let before = listing(dir);
    let o = run_in(dir, args);
    assert_eq!(o.status.code(), Some(1), "{args:?}: {}", stderr(&o));
    let err = stderr(&o);
    assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
    assert!(err.starts_with("tptd-mesh: error: "), "{err}");
    assert!(err.contains(names), "{args:?}: {err} does not name {names}");
    assert!(stdout(&o).is_empty(), "{}", stdout(&o));
    assert_eq!(listing(dir), before, "{args:?} left files behind");
    err
}

#[test]
fn errors_are_one_line_and_leave_nothing_behind() {
    let (dir, vol) = dir_with_volume();
    let d = dir.path();
    let vol = vol.to_str().unwrap();

    assert_clean_failure(
        d,
        &["missing.npy", "-o", "m.vtu", "--alpha", "1"],
        "missing.npy",
    );
    let e = assert_clean_failure(
        d,
        &[vol, "-o", "m.vtu", "--alpha", "3", "--beta", "2"],
        "vol.npy",
    );
    assert!(e.contains("less than"), "{e}");
    assert_clean_failure(
        d,
        &[vol, "-o", "m.vtu", "--alpha", "2", "--beta", "2"],
        "vol.npy",
    );
    let e = assert_clean_failure(d, &[vol, "-o", "m.msh", "--alpha", "1000"], "vol.npy");
    assert!(e.contains("contains no part of the volume"), "{e}");
    assert!(e.contains("data range is ["), "{e}");
    assert_clean_failure(d, &[vol, "-o", "m.msh", "--beta", "-1000"], "vol.npy");
    assert_clean_failure(d, &[vol, "-o", "m.msh"], "vol.npy");

    fs::create_dir(d.join("outdir.vtu")).unwrap();
    let e = assert_clean_failure(d, &[vol, "-o", "outdir.vtu", "--alpha", "2"], "outdir.vtu");
    assert!(e.contains("directory"), "{e}");
    assert!(listing(&d.join("outdir.vtu")).is_empty());
    assert_clean_failure(
        d,
        &[vol, "-o", "m.vtu", "--alpha", "2", "--report", "outdir.vtu"],
        "outdir.vtu",
    );
    let e = assert_clean_failure(
        d,
        &[vol, "-o", "no/such/dir/m.vtu", "--alpha", "2"],
        "no/such/dir/m.vtu",
    );
    assert!(e.contains("does not exist"), "{e}");
    // The report naming the mesh: exit 2 (see tests/data_safety.rs).

    let bytes = fs::read(vol).unwrap();
    let cut = d.join("cut.npy");
    fs::write(&cut, &bytes[..bytes.len() - 13]).unwrap();
    assert_clean_failure(
        d,
        &[cut.to_str().unwrap(), "-o", "m.vtu", "--alpha", "2"],
        "cut.npy",
    );
    fs::write(&cut, &bytes[..40]).unwrap();
    assert_clean_failure(
        d,
        &[cut.to_str().unwrap(), "-o", "m.vtu", "--alpha", "2"],
        "cut.npy",
    );
}

#[test]
fn rejects_nan_and_bad_arguments_without_output() {
    let (dir, vol) = dir_with_volume();
    let d = dir.path();
    let vol = vol.to_str().unwrap();
    for args in [
        &[vol, "-o", "m.vtu", "--alpha", "nan"][..],
        &[vol, "-o", "m.vtu", "--beta", "NaN"][..],
        &[vol, "-o", "m.vtu", "--alpha", "x"][..],
        &[vol, "-o", "m.vtu", "--alpha", "1", "--spacing", "1,0,1"][..],
        &[vol, "-o", "m.vtu", "--alpha", "1", "-j", "0"][..],
        &[vol, "--alpha", "1"][..],
        &[vol, "-o", "m.vtu", "--alpha", "1", "--demo"][..],
    ] {
        let before = listing(d);
        let o = run_in(d, args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        let err = stderr(&o);
        assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
        assert!(err.starts_with("tptd-mesh: error: "), "{err}");
        assert_eq!(listing(d), before, "{args:?} left files behind");
    }
    // Infinite bounds are accepted.
    let o = run_in(
        d,
        &[vol, "-o", "m.vtu", "--alpha", "-inf", "--beta", "2.5", "-q"],
    );
    assert_ok(&o);
}

#[test]
fn quality_improves_the_demo_and_reports_before_and_after() {
    let dir = tempfile::tempdir().unwrap();
    let o = run_in(
        dir.path(),
        &["--demo", "-o", "q.msh", "--quality", "--report", "q.json"],
    );
    assert_ok(&o);
    let out = stdout(&o);
    assert!(out.contains("quality   target [15, 155] deg"), "{out}");
    assert!(out.contains("b0 = 2"), "the vessels stay apart: {out}");
    let r: Value = read_json(&dir.path().join("q.json"));
    let q = &r["quality"];
    let (before, after) = (&q["before"], &q["after"]);
    let min = |s: &Value| s["min_dihedral"].as_f64().unwrap();
    let max = |s: &Value| s["max_dihedral"].as_f64().unwrap();
    assert!(min(after) > min(before) && max(after) < max(before), "{q}");
    assert!(min(after) >= 10.0 && max(after) <= 165.0, "{q}");
    assert_eq!(after["tets"].as_u64(), r["tets"].as_u64());
    assert_eq!(after["histogram"].as_array().unwrap().len(), 180);
    assert!(r["timings_seconds"]["quality"].as_f64().unwrap() > 0.0);
    assert_eq!(r["timings_seconds"]["streamed"], Value::Bool(false));
    assert_eq!(r["betti"], serde_json::json!([2, 0, 0]));
    // every tet left below 5° is listed with a reason
    let c = &q["forced"]["counts"];
    let listed: u64 = ["near_critical", "thin_layer", "box_angle", "unexplained"]
        .iter()
        .map(|k| c[k].as_u64().unwrap())
        .sum();
    assert_eq!(Some(listed), after["below"][0].as_u64(), "{q}");
    assert!(out.contains("below 5 deg after:"), "{out}");
    assert_eq!(q["boundary_collapse_ratio"].as_f64(), Some(3.0));
    // Another limit on boundary collapses, or none, is used and recorded.
    let o = run_in(
        dir.path(),
        &[
            "--demo",
            "-o",
            "r.msh",
            "--quality",
            "--boundary-collapse-ratio",
            "1.5",
            "--report",
            "r.json",
        ],
    );
    assert_ok(&o);
    let r: Value = read_json(&dir.path().join("r.json"));
    assert_eq!(r["quality"]["boundary_collapse_ratio"].as_f64(), Some(1.5));
    assert_eq!(r["betti"], serde_json::json!([2, 0, 0]));
    let args = ["--demo", "-o", "r.msh", "--quality", "--report", "r.json"];
    let o = run_in(
        dir.path(),
        &[&args[..], &["--boundary-collapse-ratio", "inf"]].concat(),
    );
    assert_ok(&o);
    let r: Value = read_json(&dir.path().join("r.json"));
    assert_eq!(r["quality"]["boundary_collapse_ratio"], Value::Null);
    assert_eq!(r["betti"], serde_json::json!([2, 0, 0]));
}

#[test]
fn quality_output_is_identical_for_one_and_two_threads() {
    let dir = tempfile::tempdir().unwrap();
    let vol = dir.path().join("big.npy");
    write_npy(&vol, [17, 15, 13], |i, j, k| blob(i, j, k) * 0.6);
    let vol = vol.to_str().unwrap();
    let mut outs = Vec::new();
    for j in ["1", "2"] {
        let out = format!("q{j}.msh");
        let args = [
            vol,
            "-o",
            &out,
            "--alpha",
            "1.55",
            "--beta",
            "3.9",
            "-j",
            j,
            "-q",
            "--quality",
        ];
        assert_ok(&run_in(dir.path(), &args));
        outs.push(fs::read(dir.path().join(&out)).unwrap());
    }
    assert!(outs[0] == outs[1], "--quality: -j 1 and -j 2 differ");
}

#[test]
fn quality_knobs_without_quality_are_refused() {
    // A knob of the quality pass without --quality would be silently ignored: refused instead,
    // naming the flag it needs, before anything is written.
    let dir = tempfile::tempdir().unwrap();
    for args in [
        ["--min-angle", "20"],
        ["--max-angle", "150"],
        ["--quality-time", "5"],
        ["--boundary-collapse-ratio", "2"],
        ["--split-sag", "0.05"],
    ] {
        let all = [&["--demo", "-o", "x.vtu"][..], &args[..]].concat();
        assert_refused(dir.path(), &all, "--quality");
    }
}

#[test]
fn quality_rejects_impossible_angles() {
    let dir = tempfile::tempdir().unwrap();
    for args in [
        ["--min-angle", "75"],
        ["--max-angle", "60"],
        ["--quality-time", "0"],
        ["--boundary-collapse-ratio", "0"],
        ["--boundary-collapse-ratio", "nan"],
    ] {
        let all = [&["--demo", "-o", "x.vtu", "--quality"][..], &args[..]].concat();
        assert_refused(dir.path(), &all, args[0]);
    }
}

/// `args` exit with status 2, an error naming `needle`, and nothing written in `dir`.
fn assert_refused(dir: &Path, args: &[&str], needle: &str) {
    let o = run_in(dir, args);
    assert_eq!(o.status.code(), Some(2), "{args:?}");
    assert!(stderr(&o).contains(needle), "{}", stderr(&o));
    assert!(listing(dir).is_empty());
}

/// `args` (run in `dir`) exit with status 2 and one line naming `needle`; `dir` is unchanged.
fn assert_usage_error(dir: &Path, args: &[&str], needle: &str) -> String {
    let before = listing(dir);
    let o = run_in(dir, args);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
    assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
    assert!(err.starts_with("tptd-mesh: error: "), "{err}");
    assert!(
        err.contains(needle),
        "{args:?}: {err} does not name {needle}"
    );
    assert!(stdout(&o).is_empty(), "{}", stdout(&o));
    assert_eq!(listing(dir), before, "{args:?} left files behind");
    err
}

#[test]
fn options_that_do_nothing_in_the_mode_are_refused() {
    let (dir, vol) = dir_with_volume();
    let d = dir.path();
    let vol = vol.to_str().unwrap();
    let mesh = |out: &'static str| vec![vol, "-o", out, "--alpha", "2"];
    // options of --critical while meshing
    for extra in [
        &["--json", "c.json"][..],
        &["--spectrum", "s.csv"],
        &["--transfer", "t.json"],
        &["--persistence"],
        &["--min-persistence", "1"],
        &["--min-value", "1"],
        &["--max-value", "2"],
        &["--kind", "maximum"],
    ] {
        let args = [&mesh("m.vtu")[..], extra].concat();
        let e = assert_usage_error(d, &args, extra[0]);
        assert!(e.contains("--critical"), "{e}");
    }
    // options of other outputs
    for (out, extra) in [
        ("m.vtu", &["--caps"][..]),
        ("m.msh", &["--ascii"]),
        ("m.obj", &["--ascii"]),
        ("m.vtu", &["--msh-version", "2.2"]),
        ("m.inp", &["--msh-version", "4.1"]),
        ("m.msh", &["--vtu-encoding", "raw"]),
        ("m.stl", &["--vtu-encoding", "zlib"]),
    ] {
        let args = [&mesh(out)[..], extra].concat();
        let e = assert_usage_error(d, &args, extra[0]);
        assert!(e.contains(out), "{e}");
    }
    // options of other inputs
    for extra in [&["--field", "a"][..], &["--function", "f.q"]] {
        let args = [&mesh("m.vtu")[..], extra].concat();
        assert_usage_error(d, &args, extra[0]);
        let args = [&["--demo"][..], extra].concat();
        assert_usage_error(d, &args, extra[0]);
    }
    // the bound check's tolerance without the check
    let args = [
        &mesh("m.vtu")[..],
        &["--no-critical-check", "--critical-tol", "1"],
    ]
    .concat();
    assert_usage_error(d, &args, "--critical-tol");
    // meshing options with --critical
    for extra in [
        &["--alpha", "1"][..],
        &["--beta", "1"],
        &["--method", "six"],
        &["--report", "r.json"],
        &["--msh-version", "2.2"],
        &["--vtu-encoding", "raw"],
        &["--caps"],
        &["--ascii"],
        &["--no-analysis"],
        &["--critical-tol", "0.1"],
        &["--no-critical-check"],
        &["--field", "a"],
        &["--function", "f.q"],
    ] {
        let args = [&[vol, "--critical"][..], extra].concat();
        let e = assert_usage_error(d, &args, extra[0]);
        assert!(e.contains("--critical"), "{e}");
    }
    // what applies is still accepted
    for (out, extra) in [
        ("a.msh", &["--msh-version", "2.2"][..]),
        ("b.vtu", &["--vtu-encoding", "raw"]),
        ("c.ply", &["--caps", "--ascii"]),
        ("d.obj", &["--caps"]),
        ("e.vtu", &["--critical-tol", "0.1"]),
    ] {
        assert_ok(&run_in(d, &[&mesh(out)[..], extra, &["-q"]].concat()));
    }
    assert_ok(&run_in(
        d,
        &[vol, "--critical", "--kind", "minimum", "-j", "1", "-q"],
    ));
}

#[test]
fn negative_numbers_reach_the_value_checks() {
    let (dir, vol) = dir_with_volume();
    let d = dir.path();
    let vol = vol.to_str().unwrap();
    let mesh = [vol, "-o", "m.vtu", "--alpha", "2"];
    for (extra, needle) in [
        (&["--spacing", "-1,1,1"][..], "must be finite and positive"),
        (&["--quality", "--min-angle", "-5"], "expected an angle"),
        (&["--quality", "--max-angle", "-5"], "expected an angle"),
        (
            &["--quality", "--quality-time", "-1"],
            "positive number of seconds",
        ),
        (
            &["--quality", "--boundary-collapse-ratio", "-1"],
            "positive ratio",
        ),
        (&["--quality", "--split-sag", "-0.5"], "positive ratio"),
        (&["--critical-tol", "-1e-3"], "finite number >= 0"),
        (&["-j", "-2"], "-2"),
        (&["--memory-limit", "-1G"], "is not a size"),
    ] {
        let e = assert_usage_error(d, &[&mesh[..], extra].concat(), needle);
        assert!(!e.contains("unexpected argument"), "{e}");
    }
    for (extra, needle) in [
        (&["--min-persistence", "-1"][..], "finite number >= 0"),
        (
            &["--transfer", "t.csv", "--transfer-width", "-2"],
            "finite number >= 0",
        ),
    ] {
        let args = [&[vol, "--critical"][..], extra].concat();
        let e = assert_usage_error(d, &args, needle);
        assert!(!e.contains("unexpected argument"), "{e}");
    }
    // negative values that are valid work
    let o = run_in(
        d,
        &[vol, "-o", "n.vtu", "--alpha", "-2.3", "--beta", "2.5", "-q"],
    );
    assert_ok(&o);
    let o = run_in(
        d,
        &[
            vol,
            "--critical",
            "--min-value",
            "-1",
            "--max-value",
            "9",
            "-q",
        ],
    );
    assert_ok(&o);
}

#[test]
fn an_unknown_extension_and_too_many_threads_are_usage_errors() {
    let (dir, vol) = dir_with_volume();
    let d = dir.path();
    let vol = vol.to_str().unwrap();
    let e = assert_usage_error(d, &[vol, "-o", "m.off", "--alpha", "1"], "m.off");
    assert!(e.contains(".msh, .inp or .vtu"), "{e}");
    assert_usage_error(d, &[vol, "-o", "m", "--alpha", "1"], "m");
    // -j is at most 16 per core: 4096 is beyond it on any machine of fewer than 256 cores
    let e = assert_usage_error(d, &[vol, "-o", "m.vtu", "--alpha", "1", "-j", "4096"], "-j");
    assert!(e.contains("too many worker threads"), "{e}");
    assert_usage_error(d, &[vol, "--critical", "-j", "4096"], "-j");
}

/// Runs `args` in `dir` with a stdout that is closed before the binary writes to it.
fn run_with_closed_stdout(dir: &Path, args: &[&str]) -> Output {
    let mut child = Command::new(BIN)
        .current_dir(dir)
        .args(args)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("the binary runs");
    drop(child.stdout.take());
    child.wait_with_output().unwrap()
}

#[test]
fn a_closed_stdout_is_not_an_error() {
    let (dir, vol) = dir_with_volume();
    let d = dir.path();
    let vol = vol.to_str().unwrap();
    for args in [
        &[vol, "-o", "m.vtu", "--alpha", "2"][..],
        &[vol, "--critical"],
        &[vol, "--critical", "--transfer", "t.csv"],
    ] {
        let o = run_with_closed_stdout(d, args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(0), "{args:?}: {err}");
        assert!(err.is_empty(), "{args:?}: {err}");
    }
    assert!(d.join("m.vtu").exists() && d.join("t.csv").exists());
}

#[test]
fn check_validates_the_mesh_before_writing_it() {
    // --check holds the mesh in memory and checks it; the file is the streamed one, byte for
    // byte, and the report carries the check.
    let (dir, _) = dir_with_volume();
    let d = dir.path();
    assert_ok(&run_in(
        d,
        &["vol.npy", "--alpha", "3", "--beta", "6", "-o", "plain.vtu"],
    ));
    let o = run_in(
        d,
        &[
            "vol.npy",
            "--alpha",
            "3",
            "--beta",
            "6",
            "-o",
            "checked.vtu",
            "--check",
            "--report",
            "r.json",
        ],
    );
    assert_ok(&o);
    assert!(
        stdout(&o).contains("check     valid: winding number 1"),
        "{}",
        stdout(&o)
    );
    assert_eq!(
        fs::read(d.join("plain.vtu")).unwrap(),
        fs::read(d.join("checked.vtu")).unwrap()
    );
    let r = read_json(&d.join("r.json"));
    assert_eq!(r["check"]["valid"], Value::Bool(true));
    assert_eq!(r["check"]["problems"], Value::Array(Vec::new()));
    assert!(r["check"]["level"]["max_distance"].as_f64().unwrap() <= 0.5);
    assert!(r["timings_seconds"]["check"].as_f64().unwrap() >= 0.0);
    assert_eq!(r["check"]["betti"], r["betti"]);
    // With --quality too.
    let o = run_in(
        d,
        &[
            "vol.npy",
            "--alpha",
            "3",
            "--beta",
            "6",
            "-o",
            "q.msh",
            "--check",
            "--quality",
        ],
    );
    assert_ok(&o);
    assert!(stdout(&o).contains("check     valid"), "{}", stdout(&o));
    // The level-set bound is the method's: half a voxel for ctd, a cell's diagonal for the
    // methods that interpolate linearly across a cell.
    assert!(stdout(&o).contains("bound 0.500)"), "{}", stdout(&o));
    let o = run_in(
        d,
        &[
            "vol.npy", "--alpha", "3", "--beta", "6", "--method", "six", "-o", "six.vtu", "--check",
        ],
    );
    assert_ok(&o);
    assert!(stdout(&o).contains("bound 1.732)"), "{}", stdout(&o));
    // Nothing to check in --critical mode.
    let empty = tempfile::tempdir().unwrap();
    assert_refused(
        empty.path(),
        &["vol.npy", "--critical", "--check"],
        "--check",
    );
}

/// Writes a quarter of a thick ring as Plot3D `duct.xyz` and `duct.f` (single block, float),
/// with the field of the README's curvilinear example.
fn write_duct(d: &Path) {
    let n = [21usize, 48, 12];
    let mut xyz = Vec::new();
    let mut f = Vec::new();
    for &i in &n {
        xyz.extend((i as i32).to_le_bytes());
        f.extend((i as i32).to_le_bytes());
    }
    f.extend(1i32.to_le_bytes());
    let at = |a: usize, i: usize, j: usize, k: usize| {
        let (r, t, z) = (10.0 + i as f64 / 2.0, j as f64 / 30.0, k as f64 / 2.0);
        match a {
            0 => r * t.cos(),
            1 => r * t.sin(),
            2 => z,
            _ => (r / 2.0).sin() * (3.0 * t).cos() + z / 7.0,
        }
    };
    for a in 0..4 {
        for k in 0..n[2] {
            for j in 0..n[1] {
                for i in 0..n[0] {
                    let out = if a < 3 { &mut xyz } else { &mut f };
                    out.extend((at(a, i, j, k) as f32).to_le_bytes());
                }
            }
        }
    }
    fs::write(d.join("duct.xyz"), xyz).unwrap();
    fs::write(d.join("duct.f"), f).unwrap();
}

#[test]
fn check_measures_a_curvilinear_mesh_against_its_level_sets_in_parameter_space() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_duct(d);
    for (beta, quality) in [("0.7", false), ("0.32", false), ("0.32", true)] {
        let mut args = vec!["duct.xyz", "--alpha", "0.3", "--beta", beta, "--check"];
        args.extend(["--report", "r.json", "-o", "duct.vtu"]);
        if quality {
            args.push("--quality");
        }
        let o = run_in(d, &args);
        assert_ok(&o);
        assert!(stdout(&o).contains("check     valid"), "{}", stdout(&o));
        let r = read_json(&d.join("r.json"));
        let level = &r["check"]["level"];
        assert!(
            level["points"].as_u64().unwrap() > 1000,
            "{args:?}: {level}"
        );
        assert!(
            level["max_distance"].as_f64().unwrap() <= 0.5,
            "{args:?}: {level}"
        );
    }
}
