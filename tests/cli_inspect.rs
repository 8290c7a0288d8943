//! `tptd-mesh --inspect`: our meshes in every format, TetGen and Medit files of the same
//! mesh, broken meshes, the JSON, bad files and options, an independent computation (numpy
//! through meshio) and, when it is installed, a real TetGen mesh of our boundary surface.

mod common;

use std::fmt::Write as _;
use std::fs;
use std::path::Path;
use std::process::Command;

use common::external::{python, require_gmsh, require_python_with, run};
use common::files::{listing, write_npy};
use common::output::{assert_ok, read_json, run_in, stderr, stdout};
use serde_json::Value;
use tptd::io::read_mesh;
use tptd::TetMesh;

/// A torus (tube radius about 2.6 around a circle of radius 5) off the grid's centre, so
/// that no grid value equals the level.
fn torus(i: usize, j: usize, k: usize) -> f64 {
    let (x, y, z) = (i as f64 - 7.3, j as f64 - 6.9, k as f64 - 6.1);
    let r = (x * x + y * y).sqrt();
    ((r - 5.0).powi(2) + z * z).sqrt()
}

const BETA: &str = "2.6";

/// A temp dir with `vol.npy` and our mesh of `f <= 2.6` as `m.msh` (4.1), `m22.msh` (2.2),
/// `m.vtu` and `m.inp`, with the report `r.json` of the `.msh` run.
fn meshed() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_npy(&d.join("vol.npy"), [16, 15, 13], torus);
    let mesh = |out: &str, extra: &[&str]| {
        let args = [&["vol.npy", "--beta", BETA, "-o", out, "-q"][..], extra].concat();
        assert_ok(&run_in(d, &args));
    };
    mesh("m.msh", &["--report", "r.json"]);
    mesh("m22.msh", &["--msh-version", "2.2"]);
    mesh("m.vtu", &[]);
    mesh("m.inp", &[]);
    dir
}

/// Runs `--inspect` on `meshes` with `extra`, writing `i.json`; returns its array and stdout.
fn inspect(d: &Path, meshes: &[&str], extra: &[&str]) -> (Vec<Value>, String) {
    let args = [&["--inspect"][..], meshes, &["--json", "i.json"], extra].concat();
    let o = run_in(d, &args);
    assert_ok(&o);
    let json = read_json(&d.join("i.json"));
    (json.as_array().unwrap().clone(), stdout(&o))
}

fn with_volume() -> Vec<&'static str> {
    vec!["--volume", "vol.npy", "--beta", BETA]
}

#[test]
fn our_meshes_in_every_format_give_the_report_s_numbers() {
    let dir = meshed();
    let d = dir.path();
    let report = read_json(&d.join("r.json"));
    let names = ["m.msh", "m22.msh", "m.vtu", "m.inp"];
    let (all, out) = inspect(d, &names, &with_volume());
    assert_eq!(all.len(), 4);
    for (i, name) in all.iter().zip(names) {
        assert_eq!(i["file"], name);
        assert_eq!(i["nodes"], report["nodes"], "{name}");
        assert_eq!(i["tets"], report["tets"], "{name}");
        let v = i["volume"].as_f64().unwrap();
        let want = report["volume"].as_f64().unwrap();
        assert!((v - want).abs() <= 1e-12 * want, "{name}: {v} vs {want}");
        assert_eq!(i["betti"], report["betti"], "{name}");
        assert_eq!(i["reference_betti"], report["betti"], "{name}");
        assert_eq!(i["matches_reference"], true, "{name}");
        assert_eq!(i["valid"], true, "{name}: {}", i["problems"]);
        assert_eq!(i["problems"], Value::Array(vec![]));
        let e = i["volume_error"].as_f64().unwrap();
        assert!(
            e.abs() < 0.02,
            "{name}: volume off the trilinear truth by {e}"
        );
        let source = if name.ends_with(".vtu") {
            "nearest_level"
        } else {
            "file"
        };
        assert_eq!(i["labels"]["source"], source, "{name}");
        assert!(i["level"]["max_distance"].as_f64().unwrap() < 0.5, "{name}");
        for key in ["min", "max"] {
            let a = i["dihedral"][key].as_f64().unwrap();
            assert!(a > 0.0 && a < 180.0, "{name}: {key} {a}");
        }
    }
    assert_eq!(report["betti"], serde_json::json!([1, 1, 0]));
    // Side by side: one column per mesh, and the reference line.
    let head = out.lines().next().unwrap();
    for name in names {
        assert!(head.contains(name), "{head}");
    }
    assert!(
        out.contains("matching it: m.msh, m22.msh, m.vtu, m.inp"),
        "{out}"
    );
    // Without --volume: no reference fields.
    let (all, out) = inspect(d, &["m.msh"], &[]);
    for key in ["reference_betti", "matches_reference", "level", "labels"] {
        assert!(all[0].get(key).is_none(), "{key}");
    }
    assert!(!out.contains("reference"), "{out}");
}

/// `mesh` as TetGen files `stem.node`/`.ele`/`.face`, numbered from `base`.
fn write_tetgen(dir: &Path, stem: &str, mesh: &TetMesh, base: usize) {
    let mut node = format!("# written by the test\n{} 3 0 0\n", mesh.points.len());
    for (i, p) in mesh.points.iter().enumerate() {
        writeln!(node, "{} {} {} {}", i + base, p[0], p[1], p[2]).unwrap();
    }
    let mut ele = format!("{} 4 1\n", mesh.tets.len());
    for (i, t) in mesh.tets.iter().enumerate() {
        let [a, b, c, e] = t.map(|v| v as usize + base);
        writeln!(ele, "{} {a} {b} {c} {e} 1", i + base).unwrap();
    }
    let mut face = format!("{} 1\n", mesh.boundary.len());
    for (i, (t, l)) in mesh.boundary.iter().zip(&mesh.boundary_labels).enumerate() {
        let [a, b, c] = t.map(|v| v as usize + base);
        writeln!(face, "{} {a} {b} {c} {}", i + base, l.index() + 1).unwrap();
    }
    fs::write(dir.join(format!("{stem}.node")), node).unwrap();
    fs::write(dir.join(format!("{stem}.ele")), ele).unwrap();
    fs::write(dir.join(format!("{stem}.face")), face).unwrap();
}

/// `mesh` as a Medit `.mesh` file.
fn write_medit(path: &Path, mesh: &TetMesh) {
    let mut s = format!(
        "MeshVersionFormatted 2\nDimension 3\nVertices\n{}\n",
        mesh.points.len()
    );
    for p in &mesh.points {
        writeln!(s, "{} {} {} 0", p[0], p[1], p[2]).unwrap();
    }
    writeln!(s, "Triangles\n{}", mesh.boundary.len()).unwrap();
    for t in &mesh.boundary {
        writeln!(s, "{} {} {} 1", t[0] + 1, t[1] + 1, t[2] + 1).unwrap();
    }
    writeln!(s, "Tetrahedra\n{}", mesh.tets.len()).unwrap();
    for t in &mesh.tets {
        writeln!(s, "{} {} {} {} 1", t[0] + 1, t[1] + 1, t[2] + 1, t[3] + 1).unwrap();
    }
    s.push_str("End\n");
    fs::write(path, s).unwrap();
}

/// `a` and `b` equal, numbers to 1e-7 relative (the angles of a tet of 0.02° from other
/// corners differ by 1.5e-9 relative).
fn close(a: &Value, b: &Value) -> bool {
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => {
            let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            (x - y).abs() <= 1e-7 * x.abs().max(y.abs())
        }
        (Value::Array(x), Value::Array(y)) => {
            x.len() == y.len() && x.iter().zip(y).all(|(x, y)| close(x, y))
        }
        (Value::Object(x), Value::Object(y)) => {
            x.len() == y.len() && x.iter().all(|(k, v)| y.get(k).is_some_and(|w| close(v, w)))
        }
        _ => a == b,
    }
}

/// The fields that must agree between two files of the same mesh (numbers as [`close`]: a
/// file in the other orientation convention gives the angles from other corners).
fn same_numbers(a: &Value, b: &Value) {
    for key in [
        "nodes",
        "tets",
        "boundary_faces",
        "volume",
        "dihedral",
        "quality",
        "betti",
        "valid",
        "matches_reference",
        "volume_error",
    ] {
        assert!(
            close(&a[key], &b[key]),
            "{key}: {} vs {}: {} vs {}",
            a["file"],
            b["file"],
            a[key],
            b[key]
        );
    }
}

#[test]
fn tetgen_and_medit_files_of_our_mesh_give_the_same_numbers() {
    let dir = meshed();
    let d = dir.path();
    let mesh = read_mesh(&d.join("m.msh")).unwrap().mesh;
    write_tetgen(d, "t0", &mesh, 0);
    write_tetgen(d, "t1.1", &mesh, 1);
    write_medit(&d.join("w.mesh"), &mesh);
    let names = ["m.msh", "t0.ele", "t1.1.node", "w.mesh"];
    let (all, out) = inspect(d, &names, &with_volume());
    for i in &all[1..] {
        same_numbers(&all[0], i);
        assert_eq!(i["labels"]["source"], "nearest_level");
        assert_eq!(i["valid"], true, "{}: {}", i["file"], i["problems"]);
    }
    // The nearest level labels every triangle as the file's groups do (all beta here).
    assert_eq!(all[0]["labels"]["counts"], all[3]["labels"]["counts"]);
    assert!(
        out.contains("matching it: m.msh, t0.ele, t1.1.node, w.mesh"),
        "{out}"
    );
    // A file in the opposite orientation convention is read flipped, with the same numbers.
    let mut flipped = mesh.clone();
    for t in &mut flipped.tets {
        t.swap(0, 1);
    }
    write_medit(&d.join("f.mesh"), &flipped);
    let (mut all, out) = inspect(d, &["w.mesh", "f.mesh"], &with_volume());
    assert_eq!(all[1]["flipped"], true);
    assert_eq!(all[0]["flipped"], false);
    // angles of exactly 45°, 60° or 90° may fall in the bin on either side
    for i in &mut all {
        i["quality"]["histogram"] = Value::Null;
    }
    same_numbers(&all[0], &all[1]);
    assert!(out.contains("ok (flipped)"), "{out}");
}

fn kinds(i: &Value) -> Vec<String> {
    i["problems"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["kind"].as_str().unwrap().to_string())
        .collect()
}

#[test]
fn an_inverted_tet_a_cavity_and_a_missing_boundary_triangle_are_reported() {
    let dir = meshed();
    let d = dir.path();
    let mesh = read_mesh(&d.join("m.msh")).unwrap().mesh;
    let mut inverted = mesh.clone();
    inverted.tets[10].swap(0, 1);
    write_medit(&d.join("inv.mesh"), &inverted);
    // A cavity: an interior tet (no boundary node) removed.
    let on_boundary = mesh.vertex_label_bits();
    let inner = mesh
        .tets
        .iter()
        .position(|t| t.iter().all(|&v| on_boundary[v as usize] == 0))
        .expect("an interior tet");
    let mut cavity = mesh.clone();
    cavity.tets.remove(inner);
    write_medit(&d.join("cav.mesh"), &cavity);
    // The file's labelled boundary lacks a triangle.
    let mut open = mesh.clone();
    open.boundary.pop();
    open.boundary_labels.pop();
    let mut bytes = Vec::new();
    tptd::io::msh::write_msh(&open, &mut bytes, tptd::io::msh::MshVersion::V41).unwrap();
    fs::write(d.join("open.msh"), bytes).unwrap();
    let (all, out) = inspect(d, &["inv.mesh", "cav.mesh", "open.msh"], &with_volume());
    assert_eq!(all[0]["valid"], false);
    assert!(
        kinds(&all[0]).contains(&"inverted_tet".into()),
        "{:?}",
        kinds(&all[0])
    );
    assert_eq!(all[1]["valid"], false);
    assert_eq!(all[1]["betti"], serde_json::json!([1, 1, 1]));
    assert_eq!(all[1]["matches_reference"], false);
    assert!(
        kinds(&all[1]).contains(&"off_level".into()),
        "{:?}",
        kinds(&all[1])
    );
    assert_eq!(all[2]["valid"], false);
    assert!(kinds(&all[2]).contains(&"boundary_face_unlisted".into()));
    assert!(
        out.lines()
            .any(|l| l.starts_with("valid") && l.contains("NO")),
        "{out}"
    );
    assert!(out.contains("inv.mesh: 1 inverted_tet (e.g. 10)"), "{out}");
}

#[test]
fn bad_files_exit_non_zero_with_one_line_naming_them() {
    let dir = meshed();
    let d = dir.path();
    fs::write(
        d.join("bad.mesh"),
        "MeshVersionFormatted 2\nVertices\n3\n0 0\n",
    )
    .unwrap();
    fs::write(
        d.join("t.node"),
        "4 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n",
    )
    .unwrap();
    fs::write(d.join("t.ele"), "1 4 0\n0 0 1 2 7\n").unwrap();
    for (file, args) in [
        ("bad.mesh", vec!["m.msh", "bad.mesh"]),
        ("t.ele", vec!["t.node"]),
        ("none.vtu", vec!["none.vtu"]),
        ("m.stl", vec!["m.stl"]),
    ] {
        let before = listing(d);
        let all = [&["--inspect"][..], &args, &["--json", "x.json"]].concat();
        let o = run_in(d, &all);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(
            err.starts_with(&format!("tptd-mesh: error: {file}")),
            "{err}"
        );
        assert_eq!(listing(d), before, "no JSON after a failed run");
    }
}

#[test]
fn options_that_do_not_apply_are_refused() {
    let dir = meshed();
    let d = dir.path();
    for (args, needle) in [
        (vec!["--inspect", "m.msh", "-o", "x.vtu"], "--output"),
        (vec!["--inspect", "m.msh", "--quality"], "--quality"),
        (vec!["--inspect", "m.msh", "--method", "six"], "--method"),
        (
            vec!["--inspect", "m.msh", "--report", "r2.json"],
            "--report",
        ),
        (vec!["--inspect", "m.msh", "--beta", "1"], "--volume"),
        (vec!["--inspect", "m.msh", "--volume", "vol.npy"], "--alpha"),
        (vec!["vol.npy", "--inspect", "m.msh"], "--volume"),
        (vec!["--inspect", "m.msh", "--json", "m.msh"], "m.msh"),
        (
            vec![
                "--inspect",
                "m.msh",
                "--json",
                "vol.npy",
                "--volume",
                "vol.npy",
                "--beta",
                "1",
            ],
            "vol.npy",
        ),
        (
            vec![
                "vol.npy", "-o", "x.vtu", "--beta", "1", "--volume", "vol.npy",
            ],
            "--inspect",
        ),
    ] {
        let o = run_in(d, &args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.contains(needle), "{args:?}: {err}");
    }
}

/// Gmsh's own binary `.msh` 4.1 (converted from ours by `gmsh -bin`) and ours in binary give
/// the numbers of our ASCII file.
#[test]
fn binary_msh_from_gmsh_and_from_us_give_the_same_numbers() {
    if !require_gmsh() {
        return;
    }
    let dir = meshed();
    let d = dir.path();
    let args = ["vol.npy", "--beta", BETA, "-q", "-o", "b.msh"];
    assert_ok(&run_in(
        d,
        &[&args[..], &["--msh-version", "4.1-binary"]].concat(),
    ));
    let (ok, out) = run(Command::new("gmsh")
        .current_dir(d)
        .args(["m.msh", "-0", "-bin", "-format", "msh41", "-o", "g.msh"]));
    assert!(ok, "{out}");
    let (all, _) = inspect(d, &["m.msh", "b.msh", "g.msh"], &with_volume());
    for i in &all[1..] {
        same_numbers(&all[0], i);
        assert_eq!(all[0]["labels"], i["labels"]);
    }
}

/// nodes, tets, volume and dihedral extremes of a mesh file computed by numpy from what
/// meshio reads.
const NUMPY: &str = r#"
import json, sys
import numpy as np
import meshio
m = meshio.read(sys.argv[1])
p = m.points.astype(float)
t = np.concatenate([c.data for c in m.cells if c.type == "tetra"]).astype(np.int64)
a, b, c, d = (p[t[:, k]] for k in range(4))
vol = np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a)) / 6.0
faces = [(1, 2, 3, 0), (0, 3, 2, 1), (0, 1, 3, 2), (0, 2, 1, 3)]
corner = [a, b, c, d]
normals = []
for f in faces:
    x, y, z, w = (corner[k] for k in f)
    n = np.cross(y - x, z - x)
    n /= np.linalg.norm(n, axis=1)[:, None]
    normals.append(n)
cosines = []
for i in range(4):
    for j in range(i + 1, 4):
        cosines.append(-np.einsum("ij,ij->i", normals[i], normals[j]))
cos = np.stack(cosines, axis=1)
print(json.dumps({"nodes": len(p), "tets": len(t), "volume": float(vol.sum()),
                  "min": float(np.degrees(np.arccos(np.clip(cos.max(), -1, 1)))),
                  "max": float(np.degrees(np.arccos(np.clip(cos.min(), -1, 1))))}))
"#;

#[test]
fn the_json_matches_numpy_through_meshio() {
    if !require_python_with("meshio") {
        return;
    }
    let dir = meshed();
    let d = dir.path();
    let (all, _) = inspect(d, &["m.vtu", "m.msh"], &[]);
    for i in &all {
        let file = d.join(i["file"].as_str().unwrap());
        let (ok, out) = run(Command::new(python()).args(["-c", NUMPY]).arg(&file));
        assert!(ok, "{out}");
        let np: Value = serde_json::from_str(out.trim()).unwrap();
        assert_eq!(i["nodes"], np["nodes"]);
        assert_eq!(i["tets"], np["tets"]);
        let close = |a: &Value, b: &Value| {
            let (a, b) = (a.as_f64().unwrap(), b.as_f64().unwrap());
            assert!((a - b).abs() <= 1e-9 * a.abs().max(b.abs()), "{a} vs {b}");
        };
        close(&i["volume"], &np["volume"]);
        close(&i["dihedral"]["min"], &np["min"]);
        close(&i["dihedral"]["max"], &np["max"]);
    }
}

/// Meshes the closed surface `s.off` with the PyPI `tetgen` package (TetGen 1.6 inside;
/// `-pq1.2`) and writes what it returns as `py.1.node`/`py.1.ele` (numbered from 1).
const PY_TETGEN: &str = r#"
import sys
import numpy as np
import tetgen
lines = [l.split() for l in open(sys.argv[1]) if l.strip()]
nv, nf = int(lines[1][0]), int(lines[1][1])
v = np.array([[float(x) for x in l] for l in lines[2:2 + nv]])
f = np.array([[int(x) for x in l[1:4]] for l in lines[2 + nv:2 + nv + nf]], dtype=np.int32)
nodes, elems, *_ = tetgen.TetGen(v, f).tetrahedralize(switches="pq1.2Q")
with open("py.1.node", "w") as out:
    out.write(f"{len(nodes)} 3 0 0\n")
    for i, p in enumerate(nodes):
        out.write(f"{i + 1} {float(p[0])!r} {float(p[1])!r} {float(p[2])!r}\n")
with open("py.1.ele", "w") as out:
    out.write(f"{len(elems)} 4 0\n")
    for i, t in enumerate(elems):
        out.write(f"{i + 1} {t[0] + 1} {t[1] + 1} {t[2] + 1} {t[3] + 1}\n")
"#;

/// Real TetGen on our boundary surface (`-pq1.2`): the PyPI `tetgen` package from Python,
/// and Debian's `tetgen` program (which writes its own `.node`/`.ele`/`.face`), each when
/// installed (a note otherwise). Its mesh has our volume (the same boundary, up to the
/// facets TetGen merges), the reference Betti numbers, and is a valid embedding within the
/// level-set bound.
#[test]
fn real_tetgen_on_our_boundary_surface() {
    let dir = meshed();
    let d = dir.path();
    let mesh = read_mesh(&d.join("m.msh")).unwrap().mesh;
    // the torus reaches the box at x = 0: the caps close the surface
    let closed = tptd::SurfaceOptions {
        caps: true,
        beta: BETA.parse().unwrap(),
    };
    let s = tptd::level_surface(&mesh, &closed);
    let mut off = format!("OFF\n{} {} 0\n", s.points.len(), s.triangles.len());
    for p in &s.points {
        writeln!(off, "{} {} {}", p[0], p[1], p[2]).unwrap();
    }
    for t in &s.triangles {
        writeln!(off, "3 {} {} {}", t[0], t[1], t[2]).unwrap();
    }
    fs::write(d.join("s.off"), off).unwrap();
    let mut peers = Vec::new();
    let py = Command::new(python())
        .current_dir(d)
        .args(["-c", PY_TETGEN, "s.off"])
        .output();
    match py {
        Ok(o) if o.status.success() => peers.push("py.1.ele"),
        Ok(o) => eprintln!(
            "note: TetGen from Python (PyPI tetgen) not run: {}",
            String::from_utf8_lossy(&o.stderr)
                .lines()
                .last()
                .unwrap_or("")
        ),
        Err(e) => eprintln!("note: no python3 for TetGen: {e}"),
    }
    match Command::new("tetgen")
        .current_dir(d)
        .args(["-pq1.2Q", "s.off"])
        .output()
    {
        Ok(o) if o.status.success() => peers.push("s.1.ele"),
        Ok(o) => panic!("tetgen failed: {}", String::from_utf8_lossy(&o.stderr)),
        Err(_) => eprintln!("note: Debian's tetgen is not installed (apt-get install tetgen)"),
    }
    if peers.is_empty() {
        eprintln!("note: neither TetGen is installed; skipping the TetGen comparison");
        return;
    }
    let names = [&["m.msh"][..], &peers].concat();
    let (all, out) = inspect(d, &names, &with_volume());
    let ours = all[0]["volume"].as_f64().unwrap();
    for i in &all[1..] {
        let name = &i["file"];
        assert_eq!(i["valid"], true, "{name}: {}\n{out}", i["problems"]);
        assert_eq!(i["matches_reference"], true, "{name}\n{out}");
        assert_eq!(i["betti"], serde_json::json!([1, 1, 0]));
        let v = i["volume"].as_f64().unwrap();
        // TetGen merges facets within 0.1° of coplanar and may triangulate them anew
        assert!(
            (v - ours).abs() <= 1e-4 * ours,
            "{name}: volume {v} vs ours {ours}"
        );
        assert!(i["nodes"].as_u64().unwrap() >= s.points.len() as u64);
    }
    eprintln!("{out}");
}

/// Legacy `.vtk` files written by meshio (ASCII and binary, file versions 4.2 and 5.1) of our
/// `.vtu` read back to the same points, tets and values, and inspect alike.
#[test]
fn legacy_vtk_from_meshio_reads_as_our_vtu() {
    if !require_python_with("meshio") {
        return;
    }
    let dir = meshed();
    let d = dir.path();
    let script = "import meshio\nm = meshio.read('m.vtu')\n\
        for b in (False, True):\n    for v in ('4.2', '5.1'):\n        \
        meshio.vtk.write(f'l{int(b)}{v[0]}.vtk', m, binary=b, fmt_version=v)\n";
    let (ok, out) = run(Command::new(python()).current_dir(d).args(["-c", script]));
    assert!(ok, "{out}");
    let ours = read_mesh(&d.join("m.vtu")).unwrap().mesh;
    let names = ["l04.vtk", "l05.vtk", "l14.vtk", "l15.vtk"];
    for name in names {
        let back = read_mesh(&d.join(name)).unwrap_or_else(|e| panic!("{e}"));
        // (not assert_eq!: the vectors are long)
        assert!(back.mesh.points == ours.points, "{name}: points differ");
        assert!(back.mesh.tets == ours.tets, "{name}: tets differ");
        assert!(back.mesh.values == ours.values, "{name}: values differ");
    }
    let (all, _) = inspect(d, &[&["m.vtu"][..], &names].concat(), &[]);
    for i in &all[1..] {
        same_numbers(&all[0], i);
    }
}
