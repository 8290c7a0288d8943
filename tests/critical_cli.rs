//! `tptd-mesh --critical` and the bound check before meshing, through the binary.

mod common;

use std::fs;
use std::process::Command;

use common::files::write_npy;

const BIN: &str = env!("CARGO_BIN_EXE_tptd-mesh");

fn gaussians(i: usize, j: usize, k: usize) -> f64 {
    let g = |c: f64| {
        (-((i as f64 - c).powi(2) + (j as f64 - 4.0).powi(2) + (k as f64 - 4.0).powi(2)) / 4.0)
            .exp()
    };
    g(3.0) + g(9.0)
}

fn run(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(BIN).args(args).output().unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn critical_table_and_json() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("g.npy");
    write_npy(&input, [13, 9, 9], gaussians);
    let json = dir.path().join("c.json");
    let inp = input.to_str().unwrap();
    let (ok, stdout, stderr) = run(&[
        inp,
        "--critical",
        "--json",
        json.to_str().unwrap(),
        "--persistence",
    ]);
    assert!(ok, "{stderr}");
    assert!(
        stdout.contains("maximum") && stdout.contains("saddle"),
        "{stdout}"
    );
    let v: serde_json::Value = serde_json::from_str(&fs::read_to_string(&json).unwrap()).unwrap();
    let arr = v.as_array().unwrap();
    let interior: Vec<&serde_json::Value> = arr
        .iter()
        .filter(|p| !p["on_box"].as_bool().unwrap())
        .collect();
    assert_eq!(interior.len(), 3);
    let saddle = interior.iter().find(|p| p["kind"] == "saddle").unwrap();
    assert_eq!(saddle["position"], serde_json::json!([6.0, 4.0, 4.0]));
    assert!((saddle["value"].as_f64().unwrap() - 2.0 * (-2.25f64).exp()).abs() < 1e-12);
    assert!(saddle["persistence"].as_f64().unwrap() > 0.0);
    // filters: kind and value range
    let (ok, stdout, _) = run(&[inp, "--critical", "--kind", "maximum", "--min-value", "0.5"]);
    assert!(ok);
    let rows: Vec<&str> = stdout.lines().skip(2).collect();
    assert_eq!(rows.len(), 2, "{stdout}");
    assert!(rows.iter().all(|r| r.contains("maximum")));
    // --min-persistence 0.9 keeps the two features spanning the whole range: the global
    // minimum (sublevel) and the elder maximum (superlevel); the other maximum and the saddle
    // that kills it span 0.79
    let (ok, stdout, _) = run(&[inp, "--critical", "--min-persistence", "0.9"]);
    assert!(ok);
    let rows: Vec<&str> = stdout.lines().skip(2).collect();
    assert_eq!(rows.len(), 2, "{stdout}");
    assert!(
        rows[0].contains("minimum") && rows[1].contains("maximum"),
        "{stdout}"
    );
}

#[test]
fn bound_on_a_checkerboard_face_saddle_warns() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("c.npy");
    // 200 everywhere, with one face checkerboarded 200/201 inside: its saddle is 200.5
    write_npy(&input, [6, 6, 6], |i, j, k| {
        let r2 = (i as f64 - 2.5).powi(2) + (j as f64 - 2.5).powi(2) + (k as f64 - 2.5).powi(2);
        let base = if r2 < 3.0 { 210.0 } else { 190.0 };
        if (2..=3).contains(&i) && (2..=3).contains(&j) && k == 1 {
            200.0 + ((i + j) % 2) as f64
        } else {
            base
        }
    });
    let out = dir.path().join("m.vtu");
    let inp = input.to_str().unwrap();
    let (ok, _, stderr) = run(&[inp, "--alpha", "200.5", "-o", out.to_str().unwrap(), "-q"]);
    assert!(ok, "{stderr}");
    // the face saddle is regular here (Lemma 4: the cell above joins one diagonal, the cell
    // below the other), but it is a vertex of the decomposition on the bound
    assert!(stderr.contains("--alpha 200.5 is within"), "{stderr}");
    assert!(stderr.contains("1 face saddle(s)"), "{stderr}");
    assert!(!stderr.contains("critical value"), "{stderr}");
    // a bound away from every saddle and critical value gets no warning
    let (ok, _, stderr) = run(&[inp, "--alpha", "200.25", "-o", out.to_str().unwrap(), "-q"]);
    assert!(ok && !stderr.contains("is within"), "{stderr}");
    // a bound next to a critical value: 1e-4 above the blob's maximum plateau at 210 (within
    // the default tolerance, 1e-5 of the range 20); exactly 210 has the grid-value warning
    let (ok, _, stderr) = run(&[inp, "--beta", "209.9999", "-o", out.to_str().unwrap(), "-q"]);
    assert!(
        ok && stderr.contains("critical value(s)") && stderr.contains("region_maximum 210"),
        "{stderr}"
    );
    assert!(stderr.contains("nearest safer values"), "{stderr}");
    // and the check can be skipped
    let (ok, _, stderr) = run(&[
        inp,
        "--alpha",
        "200.5",
        "-o",
        out.to_str().unwrap(),
        "-q",
        "--no-critical-check",
    ]);
    assert!(ok && !stderr.contains("is within"), "{stderr}");
}

#[test]
fn bad_input_gets_one_line_errors() {
    let dir = tempfile::tempdir().unwrap();
    let constant = dir.path().join("k.npy");
    write_npy(&constant, [3, 3, 3], |_, _, _| 7.0);
    let (ok, _, stderr) = run(&[constant.to_str().unwrap(), "--critical"]);
    assert!(
        !ok && stderr.contains("constant") && stderr.lines().count() == 1,
        "{stderr}"
    );
    let input = dir.path().join("g.npy");
    write_npy(&input, [5, 5, 5], gaussians);
    let inp = input.to_str().unwrap();
    let (ok, _, stderr) = run(&[inp, "--critical", "--min-value", "5", "--max-value", "6"]);
    assert!(!ok && stderr.contains("contains no data"), "{stderr}");
    let (ok, _, stderr) = run(&[inp, "--critical", "--kind", "bump"]);
    assert!(!ok && stderr.contains("unknown kind 'bump'"), "{stderr}");
    let json = dir.path().join("none/c.json");
    let (ok, _, stderr) = run(&[inp, "--critical", "--json", json.to_str().unwrap()]);
    assert!(!ok && stderr.contains("does not exist"), "{stderr}");
    assert!(!json.exists());
}

/// The numbers of `v[key]` (a JSON array) in groups of `n`.
fn groups(v: &serde_json::Value, key: &str, n: usize) -> Vec<Vec<f64>> {
    let flat: Vec<f64> = v[key]
        .as_array()
        .unwrap_or_else(|| panic!("no array {key}"))
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    assert_eq!(flat.len() % n, 0, "{key} has {} numbers", flat.len());
    flat.chunks(n).map(|c| c.to_vec()).collect()
}

#[test]
fn transfer_functions_as_paraview_preset_and_csv() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("g.npy");
    let dims = [13, 9, 9];
    write_npy(&input, dims, gaussians);
    let all = (0..dims[0]).flat_map(|i| {
        (0..dims[1]).flat_map(move |j| (0..dims[2]).map(move |k| gaussians(i, j, k)))
    });
    let (lo, hi) = all.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    });
    let saddle = 2.0 * (-2.25f64).exp();
    let inp = input.to_str().unwrap();
    let (json, preset, csv) = (
        dir.path().join("c.json"),
        dir.path().join("t.json"),
        dir.path().join("t.csv"),
    );
    let path = |p: &std::path::PathBuf| p.to_str().unwrap().to_string();
    let (ok, stdout, stderr) = run(&[
        inp,
        "--critical",
        "--json",
        &path(&json),
        "--transfer",
        &path(&preset),
        "-q",
    ]);
    assert!(ok && stdout.is_empty(), "{stderr}");
    let critical: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(&json).unwrap()).unwrap();
    let values: Vec<f64> = critical
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["value"].as_f64().unwrap())
        .collect();
    // the ParaView preset: one object, control points sorted over the data range
    let v: serde_json::Value = serde_json::from_str(&fs::read_to_string(&preset).unwrap()).unwrap();
    let p = &v.as_array().unwrap()[0];
    assert_eq!(v.as_array().unwrap().len(), 1);
    assert!(p["Name"].as_str().unwrap().contains("intervals"));
    assert_eq!(p["ColorSpace"], "RGB");
    for (key, n) in [("RGBPoints", 4), ("Points", 4)] {
        let pts = groups(p, key, n);
        assert_eq!((pts[0][0], pts[pts.len() - 1][0]), (lo, hi), "{key}");
        assert!(
            pts.windows(2).all(|w| w[0][0] < w[1][0]),
            "{key} not increasing"
        );
        assert!(
            pts.iter()
                .all(|q| q[1..].iter().all(|c| (0.0..=1.0).contains(c))),
            "{key}"
        );
    }
    let opacity = groups(p, "Points", 4);
    assert!(opacity.iter().all(|q| q[2] == 0.5 && q[3] == 0.0));
    let top = opacity.iter().fold(0.0f64, |m, q| m.max(q[1]));
    let peaks: Vec<f64> = opacity
        .iter()
        .filter(|q| q[1] == top)
        .map(|q| q[0])
        .collect();
    assert!(
        peaks.iter().all(|x| values.contains(x)),
        "{peaks:?} not in {values:?}"
    );
    assert!(
        peaks.iter().any(|&x| (x - saddle).abs() < 1e-12),
        "{peaks:?}"
    );
    // hue bands: the colour just below and just above the saddle differ
    let colors = groups(p, "RGBPoints", 4);
    let near = |x: f64| {
        colors
            .iter()
            .min_by(|a, b| (a[0] - x).abs().total_cmp(&(b[0] - x).abs()))
            .unwrap()
            .clone()
    };
    assert_ne!(near(saddle - 1e-3)[1..], near(saddle + 1e-3)[1..]);

    // CSV, the other design, filtered: only the saddle is left inside the range
    let (ok, stdout, stderr) = run(&[
        inp,
        "--critical",
        "--transfer",
        &path(&csv),
        "--transfer-design",
        "details",
        "--min-value",
        "0.15",
    ]);
    assert!(
        ok && stdout.contains("transfer function (details, 1 critical values from"),
        "{stdout}{stderr}"
    );
    let text = fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("value,r,g,b,opacity"));
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    assert!(rows.iter().all(|r| r.len() == 5));
    assert_eq!((rows[0][0], rows[rows.len() - 1][0]), (lo, hi));
    assert!(rows.windows(2).all(|w| w[0][0] < w[1][0]));
    let raised: Vec<&Vec<f64>> = rows.iter().filter(|r| r[4] > 0.05).collect();
    assert!(
        raised
            .iter()
            .all(|r| (r[0] - saddle).abs() <= 0.01 * (hi - lo) && r[4] == 0.65),
        "{raised:?}"
    );
    assert!(raised.iter().any(|r| r[0] == saddle));
    assert_eq!((rows[0][4], rows[rows.len() - 1][4]), (0.05, 0.05));
}

#[test]
fn transfer_bad_paths_are_one_line_errors_without_output() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("g.npy");
    write_npy(&input, [5, 5, 5], gaussians);
    let inp = input.to_str().unwrap();
    let xml = dir.path().join("t.xml");
    let (ok, _, stderr) = run(&[inp, "--critical", "--transfer", xml.to_str().unwrap()]);
    assert!(
        !ok && stderr.contains("unknown transfer-function format") && stderr.lines().count() == 1,
        "{stderr}"
    );
    assert!(!xml.exists());
    let missing = dir.path().join("none/t.csv");
    let (ok, _, stderr) = run(&[inp, "--critical", "--transfer", missing.to_str().unwrap()]);
    assert!(
        !ok && stderr.contains("does not exist") && stderr.lines().count() == 1,
        "{stderr}"
    );
    let (ok, _, stderr) = run(&[
        inp,
        "--critical",
        "--transfer",
        dir.path().to_str().unwrap(),
    ]);
    assert!(!ok && stderr.contains("is a directory"), "{stderr}");
    // a width as large as the data range
    let csv = dir.path().join("t.csv");
    let json = dir.path().join("c.json");
    let (ok, _, stderr) = run(&[
        inp,
        "--critical",
        "--json",
        json.to_str().unwrap(),
        "--transfer",
        csv.to_str().unwrap(),
        "--transfer-width",
        "5",
    ]);
    assert!(
        !ok && stderr.contains("widths must be") && stderr.lines().count() == 1,
        "{stderr}"
    );
    assert!(
        !csv.exists() && !json.exists(),
        "no output after a bad parameter"
    );
    let (ok, _, _) = run(&[
        inp,
        "--transfer-design",
        "details",
        "-o",
        csv.to_str().unwrap(),
    ]);
    assert!(!ok);
    assert_eq!(
        fs::read_dir(dir.path()).unwrap().count(),
        1,
        "only the input is left"
    );
}

#[test]
fn a_ring_region_is_placed_on_the_ring_with_its_centroid_apart() {
    // integer data: 0 on a ring of radius 6 around (10, 10, 3), rising away from it; the
    // ring's centroid is in its hole, where f = 12
    let ring = |i: usize, j: usize, k: usize| {
        let (x, y, z) = (i as f64, j as f64, k as f64);
        let r = ((x - 10.0).powi(2) + (y - 10.0).powi(2)).sqrt();
        (((r - 6.0).powi(2) + (z - 3.0).powi(2)) / 0.6)
            .floor()
            .min(12.0)
    };
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("ring.npy");
    write_npy(&input, [21, 21, 7], ring);
    let json = dir.path().join("c.json");
    let (ok, stdout, stderr) = run(&[
        input.to_str().unwrap(),
        "--critical",
        "--kind",
        "region_minimum",
        "--json",
        json.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    let v: serde_json::Value = serde_json::from_str(&fs::read_to_string(&json).unwrap()).unwrap();
    let arr = v.as_array().unwrap();
    assert_eq!(arr.len(), 1, "{v}");
    let p = &arr[0];
    let pos: Vec<f64> = (0..3).map(|a| p["position"][a].as_f64().unwrap()).collect();
    // a grid vertex of the region (spacing 1, origin 0: physical = index)
    assert!(pos.iter().all(|x| x.fract() == 0.0), "{p}");
    assert_eq!(
        ring(pos[0] as usize, pos[1] as usize, pos[2] as usize),
        0.0,
        "{p}"
    );
    assert_eq!(p["index"], p["position"], "{p}");
    let c = &p["region"]["centroid"];
    for (a, want) in [10.0, 10.0, 3.0].into_iter().enumerate() {
        assert!((c[a].as_f64().unwrap() - want).abs() < 0.3, "{p}");
    }
    // the table shows the position too
    let at = format!("{:.3}, {:.3}, {:.3}", pos[0], pos[1], pos[2]);
    assert!(stdout.contains(&at), "{stdout}");
}

#[test]
fn critical_memory_is_estimated_before_the_work() {
    // 40³ float64: about 6 MB plain, 26 MB with persistence, 160 MB with the spectrum
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("g.npy");
    write_npy(&input, [40, 40, 40], |i, j, k| {
        (i as f64 * 0.3).sin() + (j as f64 * 0.25).cos() + (k as f64 * 0.2).sin()
    });
    let inp = input.to_str().unwrap();
    let spectrum = dir.path().join("s.csv");
    let (ok, _, stderr) = run(&[inp, "--critical", "--memory-limit", "20M"]);
    assert!(ok, "{stderr}");
    for (extra, what) in [
        ("--persistence", "with persistence"),
        ("--spectrum", "and the contour spectrum"),
    ] {
        let mut args = vec![inp, "--critical", "--memory-limit", "20M", extra];
        if extra == "--spectrum" {
            args.push(spectrum.to_str().unwrap());
        }
        let out = Command::new(BIN).args(&args).output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{stderr}");
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
        assert!(
            stderr.contains(&format!("finding the critical points {what} needs about"))
                && stderr.contains("the memory limit is 20.0 MiB"),
            "{stderr}"
        );
        assert!(out.stdout.is_empty());
    }
    assert!(!spectrum.exists());
}
