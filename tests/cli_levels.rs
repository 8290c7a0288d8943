//! `tptd-mesh --levels` through the binary: several regions in one run, their facts in the
//! summary and the report (names, bounds, tets and volumes adding up to the mesh's, each
//! region's Betti numbers), the check passing, the same bytes for one and two threads in
//! every mesh format, the critical-value check for a level between regions, and the
//! refusals (usage errors that write nothing).

mod common;

use std::fs;

use common::files::{listing, write_npy};
use common::output::{assert_ok, read_json, run_in, stderr, stdout};

/// Distance to the nearer of two centres 9 voxels apart along x: nested balls around each,
/// touching through a saddle between them (of the trilinear field: 4.229657 at a grid vertex,
/// as `tptd-mesh b.npy --critical` lists it).
fn two_balls(dir: &std::path::Path) {
    write_npy(&dir.join("b.npy"), [30, 20, 20], |i, j, k| {
        let d = |cx: f64| {
            ((i as f64 - cx).powi(2) + (j as f64 - 9.6).powi(2) + (k as f64 - 9.3).powi(2)).sqrt()
        };
        d(10.2).min(d(19.2))
    });
}

#[test]
fn regions_are_reported_and_meshed_alike_on_any_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    two_balls(dir.path());
    let levels = "-inf,2.7,6.1,8.45";
    for out in ["m1.msh", "m1.inp", "m1.vtu"] {
        let two = out.replace("m1", "m2");
        let base = [
            "b.npy",
            "--levels",
            levels,
            "--region-names",
            "core,mid,rim",
        ];
        let o = run_in(dir.path(), &[&base[..], &["-o", out, "-j", "1"]].concat());
        assert_ok(&o);
        let o = run_in(
            dir.path(),
            &[&base[..], &["-o", &two, "-j", "2", "-q"]].concat(),
        );
        assert_ok(&o);
        let (a, b) = (dir.path().join(out), dir.path().join(&two));
        assert!(
            fs::read(a).unwrap() == fs::read(b).unwrap(),
            "{out}: threads differ"
        );
    }
    let args = [
        "b.npy",
        "--levels",
        levels,
        "--region-names",
        "core,mid,rim",
        "-o",
        "c.msh",
        "--check",
        "--report",
        "r.json",
    ];
    let o = run_in(dir.path(), &args);
    assert_ok(&o);
    let text = stdout(&o);
    assert!(
        text.contains("levels    -inf, 2.7, 6.1, 8.45 (3 regions)"),
        "{text}"
    );
    assert!(text.contains("region    core [-inf, 2.7]: "), "{text}");
    assert!(text.contains("check     valid"), "{text}");
    let r = read_json(&dir.path().join("r.json"));
    let regions = r["regions"].as_array().unwrap();
    let names: Vec<&str> = regions
        .iter()
        .map(|g| g["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["core", "mid", "rim"]);
    let tets: u64 = regions.iter().map(|g| g["tets"].as_u64().unwrap()).sum();
    assert_eq!(tets, r["tets"].as_u64().unwrap());
    let volume: f64 = regions.iter().map(|g| g["volume"].as_f64().unwrap()).sum();
    let total = r["volume"].as_f64().unwrap();
    assert!((volume - total).abs() < 1e-9 * total, "{volume} vs {total}");
    let betti = |k: usize| -> Vec<u64> {
        let b = regions[k]["betti"].as_array().unwrap();
        b.iter().map(|x| x.as_u64().unwrap()).collect()
    };
    // Two separate balls; two shells around them, one each; the level 6.1 is past the
    // saddle (4.23), so the rim is one shell around both, with the two cavities.
    assert_eq!(betti(0), [2, 0, 0]);
    assert_eq!(betti(1), [1, 0, 2]);
    assert_eq!(betti(2), [1, 0, 1]);
    assert_eq!(r["levels"][0], "-inf");
    assert!(r["boundary_triangles"]["level2"].as_u64().unwrap() > 0);
}

/// Two levels are one interval: the same bytes as `--alpha`/`--beta`, the interval summary.
#[test]
fn two_levels_are_one_interval() {
    let dir = tempfile::tempdir().unwrap();
    two_balls(dir.path());
    let o = run_in(dir.path(), &["b.npy", "--levels", "2.7,6.1", "-o", "l.msh"]);
    assert_ok(&o);
    assert!(
        stdout(&o).contains("interval  [2.7, 6.1]"),
        "{}",
        stdout(&o)
    );
    let o = run_in(
        dir.path(),
        &["b.npy", "--alpha", "2.7", "--beta", "6.1", "-o", "a.msh"],
    );
    assert_ok(&o);
    let read = |n: &str| fs::read(dir.path().join(n)).unwrap();
    assert!(
        read("l.msh") == read("a.msh"),
        "two levels differ from --alpha/--beta"
    );
}

#[test]
fn a_level_between_regions_is_checked_against_the_critical_values() {
    let dir = tempfile::tempdir().unwrap();
    two_balls(dir.path());
    let args = [
        "b.npy",
        "--levels",
        "-inf,4.229657,8.45",
        "-o",
        "m.vtu",
        "-q",
    ];
    let o = run_in(dir.path(), &args);
    assert_ok(&o);
    let err = stderr(&o);
    assert!(
        err.contains("--levels L2 4.229657 is within") && err.contains("critical value"),
        "{err}"
    );
    assert!(!err.contains("L3"), "{err}");
}

#[test]
fn bad_levels_are_usage_errors_that_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    two_balls(dir.path());
    let cases: [(&[&str], &str); 9] = [
        (
            &["--levels", "1,2", "--region-names", "a"],
            "needs three levels or more",
        ),
        (&["--levels", "3,2"], "level 2 is not above level 1"),
        (&["--levels", "3"], "1 level(s) given"),
        (&["--levels", "1,inf,9"], "level 2 is infinite"),
        (&["--levels", "1,2", "--alpha", "1"], "exclude each other"),
        (
            &["--region-names", "a", "--alpha", "1"],
            "--region-names applies only with --levels",
        ),
        (
            &["--levels", "1,2,3", "--region-names", "a"],
            "1 name(s) for 2 regions",
        ),
        (
            &["--levels", "1,2,3", "--region-names", "a,A"],
            "names must be distinct",
        ),
        (
            &["--levels", "1,2,3", "--region-names", "a,2b"],
            "start with a letter",
        ),
    ];
    for (extra, want) in cases {
        let args = [&["b.npy", "-o", "m.msh"][..], extra].concat();
        let o = run_in(dir.path(), &args);
        assert_eq!(o.status.code(), Some(2), "{extra:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(want), "{extra:?}: {}", stderr(&o));
        assert_eq!(listing(dir.path()), ["b.npy"], "{extra:?}");
    }
}

/// `--quality` with several regions: every region keeps its Betti numbers, the checker
/// (`--check`: conformity, embedding, interfaces between their regions and on their levels)
/// passes, and the elements improve.
#[test]
fn quality_keeps_every_region_s_topology() {
    let dir = tempfile::tempdir().unwrap();
    two_balls(dir.path());
    let regions = |o: &std::process::Output| -> Vec<String> {
        stdout(o)
            .lines()
            .filter(|l| l.trim_start().starts_with("region "))
            .map(|l| l.split(", dihedral").next().unwrap().to_string())
            .map(|l| l.split("tets, volume").nth(1).unwrap().to_string())
            .map(|l| l.split_once(", ").unwrap().1.to_string())
            .collect()
    };
    let args = ["b.npy", "--levels", "-inf,2.7,3.9,8.45", "-o", "m.msh"];
    let plain = run_in(dir.path(), &args);
    assert_ok(&plain);
    let o = run_in(dir.path(), &[&args[..], &["--quality", "--check"]].concat());
    assert_ok(&o);
    let (before, after) = (regions(&plain), regions(&o));
    assert_eq!(before.len(), 3, "{}", stdout(&plain));
    assert_eq!(before, after, "{}", stdout(&o));
    assert!(stdout(&o).contains("after: "), "{}", stdout(&o));
}

/// An isosurface output of several levels has every level, each its own group (`.obj`) or
/// vertex label (`.ply`), oriented towards increasing f: two spheres at 2.7, two at 6.1 and
/// one surface around both at 8.45, all closed.
#[test]
fn isosurfaces_of_several_levels_hold_every_level() {
    let dir = tempfile::tempdir().unwrap();
    two_balls(dir.path());
    let args = ["b.npy", "--levels", "-inf,2.7,3.9,8.45", "-o", "s.obj"];
    let o = run_in(dir.path(), &args);
    assert_ok(&o);
    assert!(stdout(&o).contains("Betti [5, 0, 5]"), "{}", stdout(&o));
    let text = fs::read_to_string(dir.path().join("s.obj")).unwrap();
    let groups: Vec<&str> = text.lines().filter_map(|l| l.strip_prefix("g ")).collect();
    assert_eq!(groups, ["level2", "level3", "level4"]);
    let args = [
        "b.npy",
        "--levels",
        "-inf,2.7,3.9,8.45",
        "-o",
        "s.ply",
        "--ascii",
    ];
    assert_ok(&run_in(dir.path(), &args));
    let ply = fs::read_to_string(dir.path().join("s.ply")).unwrap();
    assert!(
        ply.contains(
            "comment vertex label: 0 = level1, 1 = level2, 2 = level3, 3 = level4, 4 = box"
        ),
        "{ply}"
    );
}
