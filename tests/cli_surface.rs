//! End-to-end tests of `tptd-mesh` with isosurface output (`-o OUT.obj|.ply|.stl`): the
//! report's surface section, `--caps`, `--ascii`, thread independence, and the errors.

use std::fs;
use std::path::Path;
use std::process::{Command, Output};

use serde_json::Value;

const BIN: &str = env!("CARGO_BIN_EXE_tptd-mesh");

fn run_in(dir: &Path, args: &[&str]) -> Output {
    let o = Command::new(BIN)
        .current_dir(dir)
        .args(args)
        .output()
        .expect("the binary runs");
    o
}

fn ok(o: &Output) {
    assert!(
        o.status.success(),
        "stdout:\n{}\nstderr:\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
}

fn surface_report(dir: &Path, out: &str, extra: &[&str]) -> Value {
    let mut args = vec!["--demo", "-q", "-o", out, "--report", "r.json"];
    args.extend_from_slice(extra);
    ok(&run_in(dir, &args));
    let r: Value = serde_json::from_str(&fs::read_to_string(dir.join("r.json")).unwrap()).unwrap();
    r["surface"].clone()
}

#[test]
fn demo_isosurface_keeps_the_vessels_apart_and_six_merges_them() {
    let dir = tempfile::tempdir().unwrap();
    let s = surface_report(dir.path(), "ctd.obj", &[]);
    // two closed tubes (capped inside the box): two spheres
    assert_eq!(s["betti"], serde_json::json!([2, 0, 2]), "{s}");
    assert_eq!(s["closed_manifold"], true);
    assert_eq!(s["oriented"], true);
    assert!(s["area"].as_f64().unwrap() > 0.0);
    let six = surface_report(dir.path(), "six.obj", &["--method", "six"]);
    assert_eq!(six["betti"][0], 1, "{six}");
    let text = fs::read_to_string(dir.path().join("ctd.obj")).unwrap();
    let v = text.lines().filter(|l| l.starts_with("v ")).count();
    let f = text.lines().filter(|l| l.starts_with("f ")).count();
    assert_eq!(
        (v as u64, f as u64),
        (
            s["vertices"].as_u64().unwrap(),
            s["triangles"].as_u64().unwrap()
        )
    );
}

#[test]
fn caps_close_the_surface_and_ascii_is_text() {
    let dir = tempfile::tempdir().unwrap();
    // at 0.05 the level set meets the grid box
    let open = surface_report(dir.path(), "o.ply", &["--alpha", "0.05"]);
    let closed = surface_report(dir.path(), "c.ply", &["--alpha", "0.05", "--caps"]);
    assert_eq!(open["closed_manifold"], false, "{open}");
    assert!(open["border_edges"].as_u64().unwrap() > 0);
    assert_eq!(closed["closed_manifold"], true, "{closed}");
    assert_eq!(closed["oriented"], true, "{closed}");
    ok(&run_in(
        dir.path(),
        &["--demo", "-q", "-o", "a.stl", "--ascii"],
    ));
    ok(&run_in(dir.path(), &["--demo", "-q", "-o", "b.stl"]));
    let a = fs::read_to_string(dir.path().join("a.stl")).unwrap();
    assert!(a.starts_with("solid tptd\n") && a.trim_end().ends_with("endsolid tptd"));
    let b = fs::read(dir.path().join("b.stl")).unwrap();
    let n = u32::from_le_bytes(b[80..84].try_into().unwrap()) as usize;
    assert_eq!(b.len(), 84 + 50 * n);
    assert_eq!(n, a.matches("facet normal").count());
}

#[test]
fn surface_output_is_identical_for_one_and_two_threads() {
    let dir = tempfile::tempdir().unwrap();
    for ext in ["obj", "ply", "stl"] {
        let one = format!("one.{ext}");
        let two = format!("two.{ext}");
        ok(&run_in(
            dir.path(),
            &["--demo", "-q", "-j", "1", "-o", &one, "--method", "tptd"],
        ));
        ok(&run_in(
            dir.path(),
            &["--demo", "-q", "-j", "2", "-o", &two, "--method", "tptd"],
        ));
        assert!(
            fs::read(dir.path().join(&one)).unwrap() == fs::read(dir.path().join(&two)).unwrap(),
            "{ext}"
        );
    }
}

#[test]
fn unknown_extension_names_the_surface_formats_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let o = run_in(dir.path(), &["--demo", "-o", "x.off"]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("x.off") && err.contains(".obj, .ply or .stl"),
        "{err}"
    );
    assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 0);
}

/// A small ASCII `.vts`: a sheared, bent 6×5×4 grid with fields `a` (two blobs) and `b`.
fn write_vts(path: &Path) {
    let dims = [6usize, 5, 4];
    let (mut pts, mut a, mut b) = (String::new(), String::new(), String::new());
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                let (x, y, z) = (i as f64, j as f64, k as f64);
                pts += &format!("{} {} {} ", x + 0.2 * y, y + 0.1 * (x * 0.8).sin(), 0.5 * z);
                let d1 = (x - 1.2).powi(2) + (y - 2.0).powi(2) + (z - 1.5).powi(2);
                let d2 = (x - 3.8).powi(2) + (y - 2.0).powi(2) + (z - 1.5).powi(2);
                a += &format!("{} ", (-d1).exp() + (-d2).exp());
                b += &format!("{} ", x + y);
            }
        }
    }
    let text = format!(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"StructuredGrid\" version=\"0.1\">\n\
         <StructuredGrid WholeExtent=\"0 5 0 4 0 3\"><Piece Extent=\"0 5 0 4 0 3\">\n\
         <PointData><DataArray type=\"Float64\" Name=\"a\" format=\"ascii\">{a}</DataArray>\n\
         <DataArray type=\"Float64\" Name=\"b\" format=\"ascii\">{b}</DataArray></PointData>\n\
         <Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">{pts}\
         </DataArray></Points></Piece></StructuredGrid></VTKFile>\n"
    );
    fs::write(path, text).unwrap();
}

#[test]
fn curvilinear_vts_meshes_to_every_output_format() {
    let dir = tempfile::tempdir().unwrap();
    write_vts(&dir.path().join("g.vts"));
    for out in ["m.msh", "m.inp", "m.vtu", "s.obj", "s.ply", "s.stl"] {
        let o = run_in(
            dir.path(),
            &[
                "g.vts", "--alpha", "0.5", "-q", "-o", out, "--report", "r.json",
            ],
        );
        ok(&o);
        let r: Value =
            serde_json::from_str(&fs::read_to_string(dir.path().join("r.json")).unwrap()).unwrap();
        // the two blobs stay apart
        assert_eq!(r["betti"], serde_json::json!([2, 0, 0]), "{out}: {r}");
        if out.starts_with('s') {
            assert_eq!(r["surface"]["betti"], serde_json::json!([2, 0, 2]), "{out}");
        }
    }
    ok(&run_in(
        dir.path(),
        &[
            "g.vts", "--field", "b", "--alpha", "4.5", "-q", "-o", "b.vtu",
        ],
    ));
    let o = run_in(
        dir.path(),
        &["g.vts", "--field", "c", "--alpha", "1", "-o", "c.vtu"],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        err.contains("g.vts") && err.contains("the file has: a, b"),
        "{err}"
    );
    let o = run_in(
        dir.path(),
        &["g.vts", "--spacing", "1,1,1", "--alpha", "1", "-o", "c.vtu"],
    );
    assert_eq!(o.status.code(), Some(2));
    assert!(!dir.path().join("c.vtu").exists());
    // --field on a volume that has no fields
    let o = run_in(dir.path(), &["--demo", "--field", "a", "-o", "e.vtu"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("curvilinear grid"));
    assert!(!dir.path().join("e.vtu").exists());
    // mapped output is identical for one and two threads
    for (j, out) in [("1", "j1.msh"), ("2", "j2.msh")] {
        ok(&run_in(
            dir.path(),
            &["g.vts", "--alpha", "0.5", "-q", "-j", j, "-o", out],
        ));
    }
    let (a, b) = (dir.path().join("j1.msh"), dir.path().join("j2.msh"));
    assert!(fs::read(a).unwrap() == fs::read(b).unwrap());
}
