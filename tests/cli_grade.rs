//! `tptd-mesh --max-edge` through the binary: a graded interior with fewer tets and the
//! same topology (against an independent trilinear reference), volume and boundary as the
//! fine mesh, the check passing, with `--quality` and `--levels` too, the same bytes for one
//! and two threads, and the refusals (usage errors that write nothing).

mod common;

use std::fs;

use common::files::{listing, write_npy};
use common::output::{assert_ok, read_json, run_in, stderr};
use common::reference::{sampled_betti, Field};

/// A solid torus (tube radius up to 7.2 around a circle of radius 12) with a wavy surface.
fn torus(i: usize, j: usize, k: usize) -> f64 {
    torus_f(i as f64, j as f64, k as f64)
}

fn torus_f(x: f64, y: f64, z: f64) -> f64 {
    let (x, y, z) = (x - 19.5, y - 20.2, z - 11.3);
    let ring = (x * x + y * y).sqrt() - 12.0;
    (ring * ring + z * z).sqrt() + 0.4 * (0.3 * x).sin()
}

const DIMS: [usize; 3] = [40, 41, 24];

fn report(dir: &std::path::Path, args: &[&str]) -> serde_json::Value {
    let o = run_in(dir, &[args, &["--report", "r.json", "-q"]].concat());
    assert_ok(&o);
    read_json(&dir.join("r.json"))
}

#[test]
fn a_graded_mesh_keeps_the_fine_one_s_topology_volume_and_boundary() {
    let dir = tempfile::tempdir().unwrap();
    write_npy(&dir.path().join("t.npy"), DIMS, torus);
    let fine = report(dir.path(), &["t.npy", "--beta", "7.1", "-o", "f.msh"]);
    let graded = report(
        dir.path(),
        &[
            "t.npy",
            "--beta",
            "7.1",
            "--max-edge",
            "4",
            "--check",
            "-o",
            "g.msh",
        ],
    );
    let g = &graded["grade"];
    assert!(g["tets_after"].as_u64() < g["tets_before"].as_u64(), "{g}");
    assert_eq!(graded["tets"], g["tets_after"]);
    assert_eq!(fine["tets"], g["tets_before"]);
    assert!(g["cubes"][0].as_u64().unwrap() > 0, "{g}");
    // topology: the fine mesh's, and the trilinear interpolant's
    let reference = sampled_betti(&Field::from_fn(DIMS, torus_f), 4, f64::NEG_INFINITY, 7.1);
    assert_eq!(graded["betti"], serde_json::json!(reference));
    assert_eq!(graded["betti"], fine["betti"]);
    let (vf, vg) = (
        fine["volume"].as_f64().unwrap(),
        graded["volume"].as_f64().unwrap(),
    );
    assert!((vf - vg).abs() <= 1e-9 * vf, "{vf} {vg}");
    assert_eq!(graded["boundary_triangles"], fine["boundary_triangles"]);
    assert!(graded["check"]["valid"].as_bool().unwrap());
}

#[test]
fn with_quality_and_levels_on_any_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    write_npy(&dir.path().join("t.npy"), DIMS, torus);
    // nested balls: a core of radius 5.2 in a shell ten cells thick
    write_npy(&dir.path().join("b.npy"), [36, 36, 36], |i, j, k| {
        let d = [i, j, k].map(|x| x as f64 - 17.4);
        (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
    });
    let cases: [(&[&str], &str); 2] = [
        (&["t.npy", "--beta", "7.1", "--quality"], "q"),
        (
            &[
                "b.npy",
                "--levels",
                "-inf,5.2,15.3",
                "--region-names",
                "core,shell",
            ],
            "l",
        ),
    ];
    for (extra, name) in cases {
        let mut outs = Vec::new();
        for j in ["1", "2"] {
            let out = format!("{name}{j}.msh");
            let args = [extra, &["--max-edge", "4", "--check", "-j", j, "-o", &out]].concat();
            let r = report(dir.path(), &args);
            assert!(r["check"]["valid"].as_bool().unwrap(), "{name}");
            let g = &r["grade"];
            assert!(g["tets_added"].as_u64().unwrap() > 0, "{name}: {g}");
            outs.push(fs::read(dir.path().join(&out)).unwrap());
        }
        assert!(outs[0] == outs[1], "{name}: threads differ");
    }
}

#[test]
fn refusals_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    write_npy(&dir.path().join("t.npy"), DIMS, torus);
    let before = listing(dir.path());
    for (args, says) in [
        (&["--max-edge", "1.2"][..], "less than 1.5 cells"),
        (&["--grading", "2"][..], "--max-edge"),
        (&["--max-edge", "0"][..], "--max-edge"),
        (&["--max-edge", "4", "--grading", "1"][..], "--grading"),
    ] {
        let o = run_in(
            dir.path(),
            &[&["t.npy", "--beta", "7.1", "-o", "x.msh"], args].concat(),
        );
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(says), "{args:?}: {}", stderr(&o));
        assert_eq!(stderr(&o).trim().lines().count(), 1, "{}", stderr(&o));
    }
    let o = run_in(
        dir.path(),
        &["t.npy", "--beta", "7.1", "--max-edge", "4", "-o", "x.obj"],
    );
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("volume mesh output"), "{}", stderr(&o));
    assert_eq!(listing(dir.path()), before);
}
