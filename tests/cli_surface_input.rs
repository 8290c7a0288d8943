//! End-to-end tests of `tptd-mesh` with a closed-surface input (`SURFACE.obj|.stl|.ply`):
//! the solid `{d <= 0}` of the signed distance meshed with the right topology and judged by
//! the checker (`--check`), an open surface meshed with a warning naming its hole, and the
//! refusals: an empty or garbage file, a surface option with a volume, an output that is the
//! input.

mod common;

use std::fs;
use std::path::Path;

use common::files::{listing, write_npy};
use common::output::{assert_ok, read_json, run_in, stderr};
use common::soup::{sphere, torus, write_obj, write_stl};
use serde_json::Value;

/// Meshes `input` in `dir` with `--check` and a report, and gives the report and stderr.
fn mesh_checked(dir: &Path, input: &str, extra: &[&str]) -> (Value, String) {
    let mut args = vec![input, "-o", "m.vtu", "--check", "--report", "r.json"];
    args.extend_from_slice(extra);
    let o = run_in(dir, &args);
    assert_ok(&o);
    let r = read_json(&dir.join("r.json"));
    assert_eq!(r["check"]["valid"], Value::Bool(true), "{}", r["check"]);
    (r, stderr(&o))
}

/// The error line of a refused run, which must leave `dir` as it was.
fn refused(dir: &Path, args: &[&str]) -> (Option<i32>, String) {
    let before = listing(dir);
    let o = run_in(dir, args);
    assert!(!o.status.success(), "{args:?} ran");
    let err = stderr(&o);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert_eq!(listing(dir), before, "{args:?} left files");
    (o.status.code(), err)
}

/// The warning line of `err` that contains `needle`.
fn warning_line<'a>(err: &'a str, needle: &str) -> &'a str {
    err.lines()
        .find(|l| l.contains(needle))
        .unwrap_or_else(|| panic!("no warning with {needle:?}: {err}"))
}

#[test]
fn a_torus_is_a_solid_ring() {
    let dir = tempfile::tempdir().unwrap();
    write_obj(&dir.path().join("torus.obj"), &torus(1.0, 0.4, 48, 24));
    let (r, err) = mesh_checked(dir.path(), "torus.obj", &["--resolution", "64"]);
    assert_eq!(r["betti"], serde_json::json!([1, 1, 0]), "{r}");
    assert!(!err.contains("warning"), "{err}");
    // the surface's units: the solid torus has volume 2 pi^2 R r^2
    let exact = 2.0 * std::f64::consts::PI.powi(2) * 1.0 * 0.4 * 0.4;
    let v = r["volume"].as_f64().unwrap();
    assert!((v - exact).abs() < 0.03 * exact, "{v} vs {exact}");
    // the grid: 64 voxels along the longest side (2.8), 3.5 more on each side
    assert_eq!(r["dims"][0], 64 + 2 + 6, "{}", r["dims"]);
}

/// Two unit spheres `gap` apart along x (overlapping when negative), as one soup.
fn two_spheres(gap: f64) -> common::soup::Soup {
    let c = 1.0 + 0.5 * gap;
    let (mut p, mut t) = sphere([-c, 0.0, 0.0], 1.0, 4);
    let (q, u) = sphere([c, 0.0, 0.0], 1.0, 4);
    let off = p.len() as u32;
    p.extend(q);
    t.extend(u.iter().map(|x| x.map(|i| i + off)));
    (p, t)
}

#[test]
fn two_spheres_a_few_voxels_apart_stay_two() {
    let dir = tempfile::tempdir().unwrap();
    write_stl(&dir.path().join("pair.stl"), &two_spheres(0.2));
    // 4.2 long in 64 voxels: the gap of 0.2 is three voxels
    let (r, err) = mesh_checked(dir.path(), "pair.stl", &["--resolution", "64"]);
    assert_eq!(r["betti"], serde_json::json!([2, 0, 0]), "{r}");
    assert!(!err.contains("warning"), "{err}");
}

#[test]
fn spheres_closer_than_a_voxel_merge_with_a_warning_that_says_why() {
    let dir = tempfile::tempdir().unwrap();
    write_stl(&dir.path().join("pair.stl"), &two_spheres(0.2));
    // 4.2 long in 12 voxels of 0.35: the gap of 0.2 is less than one
    let (r, err) = mesh_checked(dir.path(), "pair.stl", &["--resolution", "12"]);
    assert_eq!(r["betti"], serde_json::json!([1, 0, 0]), "{r}");
    let line = warning_line(&err, "closed piece");
    assert!(
        line.starts_with("tptd-mesh: warning: pair.stl: the surface has 2 closed pieces but the mesh has 1 component and 0 cavities"),
        "{line}"
    );
    assert!(
        line.contains("closer together than about a voxel merged"),
        "{line}"
    );
    assert!(line.contains("on this grid of voxels 0.35 wide"), "{line}");
    assert!(line.ends_with("a larger --resolution keeps them"), "{line}");
    assert!(r["warnings"].to_string().contains("closed pieces"), "{r}");
    // an offset that joins them is what was asked for: no warning
    let o = run_in(
        dir.path(),
        &[
            "pair.stl",
            "--beta",
            "0.3",
            "--resolution",
            "12",
            "-o",
            "b.vtu",
        ],
    );
    assert_ok(&o);
    assert!(!stderr(&o).contains("closed piece"), "{}", stderr(&o));
}

#[test]
fn a_self_intersecting_surface_is_meshed_as_the_union_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    // two unit spheres overlapping by half their diameter: their surfaces cross
    write_obj(&dir.path().join("overlap.obj"), &two_spheres(-1.0));
    let (r, err) = mesh_checked(dir.path(), "overlap.obj", &["--resolution", "32"]);
    assert_eq!(r["betti"], serde_json::json!([1, 0, 0]), "{r}");
    let line = warning_line(&err, "intersects itself");
    assert!(
        line.starts_with("tptd-mesh: warning: overlap.obj: the surface intersects itself ("),
        "{line}"
    );
    assert!(!err.contains("closed piece"), "{err}");
    // the union of two unit balls whose centres are 1 apart: 2 (4/3 pi) - (5/12 pi)
    let exact = std::f64::consts::PI * (8.0 / 3.0 - 5.0 / 12.0);
    let v = r["volume"].as_f64().unwrap();
    assert!((v - exact).abs() < 0.03 * exact, "{v} vs {exact}");
}

#[test]
fn beta_offsets_the_surface_in_its_units() {
    let dir = tempfile::tempdir().unwrap();
    write_obj(&dir.path().join("ball.obj"), &sphere([0.0; 3], 1.0, 3));
    let args = ["--voxel-size", "0.1", "--beta", "0.5"];
    let (r, _) = mesh_checked(dir.path(), "ball.obj", &args);
    assert_eq!(r["betti"], serde_json::json!([1, 0, 0]), "{r}");
    // the offset ball of radius 1.5 fits in the grid: no box boundary
    let exact = 4.0 / 3.0 * std::f64::consts::PI * 1.5f64.powi(3);
    let v = r["volume"].as_f64().unwrap();
    assert!((v - exact).abs() < 0.03 * exact, "{v} vs {exact}");
    assert_eq!(r["boundary_triangles"]["box"], 0, "{r}");
}

#[test]
fn an_open_surface_is_meshed_with_a_warning_naming_the_hole() {
    let dir = tempfile::tempdir().unwrap();
    let (p, t) = sphere([0.0; 3], 1.0, 3);
    // remove the cap above z = 0.9: one hole, its rim about 2 pi 0.44 long
    let t: Vec<[u32; 3]> = t
        .into_iter()
        .filter(|f| f.iter().any(|&i| p[i as usize][2] < 0.9))
        .collect();
    write_obj(&dir.path().join("cup.obj"), &(p, t));
    let (r, err) = mesh_checked(dir.path(), "cup.obj", &["--resolution", "32"]);
    let warning = warning_line(&err, "open");
    assert!(
        warning.starts_with("tptd-mesh: warning: cup.obj: the surface is open: 1 hole"),
        "{warning}"
    );
    assert!(warning.contains("the longest boundary"), "{warning}");
    assert_eq!(r["betti"], serde_json::json!([1, 0, 0]), "{r}");
    assert!(r["warnings"][0].as_str().unwrap().contains("1 hole"), "{r}");
}

#[test]
fn empty_and_garbage_surfaces_are_one_line_errors_that_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    fs::write(d.join("empty.obj"), b"").unwrap();
    fs::write(d.join("junk.stl"), b"this is not an stl file at all").unwrap();
    fs::write(d.join("junk.ply"), b"\x00\x01garbage\xff").unwrap();
    // every triangle flat: read, but no solid
    fs::write(d.join("flat.obj"), "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n").unwrap();
    for name in ["empty.obj", "junk.stl", "junk.ply", "flat.obj"] {
        let (code, err) = refused(d, &[name, "-o", "m.vtu", "--report", "r.json"]);
        assert_eq!(code, Some(1), "{err}");
        assert!(
            err.starts_with(&format!("tptd-mesh: error: {name}: ")),
            "{err}"
        );
    }
}

#[test]
fn surface_options_are_refused_where_they_do_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_npy(&d.join("v.npy"), [4, 4, 4], |i, j, k| (i + j + k) as f64);
    write_obj(&d.join("ball.obj"), &sphere([0.0; 3], 1.0, 1));
    let cases: [(&[&str], &str); 5] = [
        (
            &["v.npy", "--alpha", "1", "--resolution", "32", "-o", "m.vtu"],
            "--resolution applies only to a closed-surface input",
        ),
        (
            &["--demo", "--voxel-size", "0.1"],
            "--voxel-size applies only to a closed-surface input",
        ),
        (
            &[
                "ball.obj",
                "--resolution",
                "8",
                "--voxel-size",
                "0.1",
                "-o",
                "m.vtu",
            ],
            "--resolution and --voxel-size exclude each other",
        ),
        (
            &["ball.obj", "--spacing", "1,1,1", "-o", "m.vtu"],
            "--spacing does not apply to a closed surface",
        ),
        (
            &["ball.obj", "--critical"],
            "--critical applies only to a volume input",
        ),
    ];
    for (args, expected) in cases {
        let (code, err) = refused(d, args);
        assert_eq!(code, Some(2), "{err}");
        assert!(err.contains(expected), "{args:?}: {err}");
    }
    let (code, err) = refused(d, &["ball.obj", "--resolution", "0", "-o", "m.vtu"]);
    assert_eq!(code, Some(2), "{err}");
}

#[test]
fn the_output_never_overwrites_the_input_surface() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_obj(&d.join("ball.obj"), &sphere([0.0; 3], 1.0, 1));
    let before = fs::read(d.join("ball.obj")).unwrap();
    for out in ["ball.obj", "./ball.obj"] {
        let (code, err) = refused(d, &["ball.obj", "-o", out]);
        assert_eq!(code, Some(2), "{err}");
        assert!(err.contains("refusing to overwrite"), "{err}");
    }
    let (code, _) = refused(d, &["ball.obj", "-o", "m.vtu", "--report", "ball.obj"]);
    assert_eq!(code, Some(2));
    assert_eq!(fs::read(d.join("ball.obj")).unwrap(), before);
}
