//! `tptd-mesh --critical` and the bound check before meshing, through the binary.

mod common;

use std::fs;
use std::path::Path;
use std::process::Command;

use common::files::npy_bytes;

const BIN: &str = env!("CARGO_BIN_EXE_tptd-mesh");

/// Writes a C-order `(nx, ny, nz)` float64 `.npy` (x slowest, as tptd reads it).
fn write_npy(path: &Path, dims: [usize; 3], f: impl Fn(usize, usize, usize) -> f64) {
    let [nx, ny, nz] = dims;
    let mut data = Vec::with_capacity(nx * ny * nz * 8);
    for i in 0..nx {
        for j in 0..ny {
            for k in 0..nz {
                data.extend_from_slice(&f(i, j, k).to_le_bytes());
            }
        }
    }
    fs::write(
        path,
        npy_bytes("<f8", &format!("({nx}, {ny}, {nz})"), &data),
    )
    .unwrap();
}

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
