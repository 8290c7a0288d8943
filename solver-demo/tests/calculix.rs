//! `solver-demo` against CalculiX: the same `tptd` mesh exported as `.inp`, solved as steady
//! heat transfer by `ccx` (same conductivity, volumetric source and Dirichlet node sets) and
//! by `solver-demo` reading that `.inp`, agrees to 1e-5 relative in max norm at every node
//! (the `.frd` holds about six significant digits). Also on a mesh improved by the quality
//! pass (`tptd-mesh --quality`), and on a mesh of two regions (`--levels`) with a material
//! per region.
//!
//! A missing `ccx` makes the test fail unless `TPTD_SKIP_EXTERNAL=1`.

mod common;

use std::path::Path;
use std::process::Command;

use common::*;
use solver_demo::pcg::PcgOptions;
use solver_demo::run::{solve, Options};
use tptd::improve::{improve, QualityOptions};

const K: f64 = 2.5;
const SOURCE: f64 = 3.0;
const U_ALPHA: f64 = 0.0;
const U_BETA: f64 = 1.0;

fn have_ccx() -> bool {
    let ok = Command::new("sh")
        .args(["-c", "command -v ccx"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !ok && std::env::var("TPTD_SKIP_EXTERNAL").is_ok_and(|v| v == "1") {
        eprintln!("note: ccx missing, skipped (TPTD_SKIP_EXTERNAL=1)");
        return false;
    }
    assert!(
        ok,
        "CalculiX (ccx) is not installed (apt-get install calculix-ccx)"
    );
    true
}

/// The steady heat-transfer deck around the exported mesh `mesh.inp`.
fn deck() -> String {
    format!(
        "*INCLUDE, INPUT=mesh.inp\n\
         *MATERIAL, NAME=M\n*CONDUCTIVITY\n{K}\n\
         *SOLID SECTION, ELSET=DOMAIN, MATERIAL=M\n\
         *STEP\n*HEAT TRANSFER, STEADY STATE\n\
         *BOUNDARY\nALPHA, 11, 11, {U_ALPHA}\nBETA, 11, 11, {U_BETA}\n\
         *DFLUX\nDOMAIN, BF, {SOURCE}\n\
         *NODE FILE\nNT\n*END STEP\n"
    )
}

/// Node temperatures (by 1-based node id) from the `NDTEMP` block of a `.frd` file.
fn frd_temperatures(path: &Path) -> Vec<(usize, f64)> {
    let text = std::fs::read_to_string(path).unwrap();
    let start = text.find("NDTEMP").expect("no NDTEMP block in the .frd");
    let mut out = Vec::new();
    for line in text[start..].lines().skip(1) {
        if line.starts_with(" -3") {
            break;
        }
        // Fixed columns: " -1", node id (10 wide), value (12 wide).
        if line.starts_with(" -1") && line.len() >= 25 {
            let id = line[3..13].trim().parse().unwrap();
            let v = line[13..25].trim().parse().unwrap();
            out.push((id, v));
        }
    }
    out
}

/// Runs ccx and solver-demo on `mesh`; returns the max-norm difference relative to max |u|.
fn compare(mesh: &tptd::TetMesh, name: &str) -> f64 {
    let opts = Options {
        k: K,
        source: SOURCE,
        dirichlet: vec![("alpha".into(), U_ALPHA), ("beta".into(), U_BETA)],
        ..Options::default()
    };
    compare_with(mesh, name, &deck(), opts)
}

/// Runs ccx with `deck` and solver-demo with `opts` (reading the same `.inp`) on `mesh`;
/// returns the max-norm difference relative to max |u|.
fn compare_with(mesh: &tptd::TetMesh, name: &str, deck: &str, opts: Options) -> f64 {
    let dir = tempfile::tempdir().unwrap();
    let file = through_file(mesh, dir.path(), "mesh.inp");
    std::fs::write(dir.path().join("job.inp"), deck).unwrap();
    let out = Command::new("ccx")
        .args(["-i", "job"])
        .current_dir(dir.path())
        .env("OMP_NUM_THREADS", "1")
        .output()
        .unwrap();
    let log = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success() && log.contains("Job finished"),
        "ccx failed:\n{log}"
    );
    let ccx = frd_temperatures(&dir.path().join("job.frd"));
    assert_eq!(
        ccx.len(),
        file.mesh.points.len(),
        "ccx temperatures for every node"
    );
    let opts = Options {
        pcg: PcgOptions {
            tol: 1e-13,
            ..PcgOptions::default()
        },
        ..opts
    };
    let sol = solve(&file, &opts, &mut |_, _| {}).unwrap();
    let max_u = ccx.iter().map(|&(_, v)| v.abs()).fold(0.0, f64::max);
    let diff = ccx
        .iter()
        .map(|&(id, v)| (sol.u[id - 1] - v).abs())
        .fold(0.0, f64::max);
    let rel = diff / max_u;
    println!(
        "{name}: {} nodes, {} tets, max |u| {max_u:.6}, max |u - u_ccx| / max |u| = {rel:.3e}",
        ccx.len(),
        mesh.tets.len()
    );
    rel
}

#[test]
fn agrees_with_calculix_on_a_spherical_shell() {
    if !have_ccx() {
        return;
    }
    let g = ball_grid(20);
    let rel = compare(&mesh(&g, 0.5, 1.0), "shell");
    assert!(rel <= 1e-5, "relative max difference {rel:e}");
}

#[test]
fn agrees_with_calculix_on_a_quality_improved_shell() {
    if !have_ccx() {
        return;
    }
    let g = ball_grid(20);
    let mut m = mesh(&g, 0.5, 1.0);
    let report = improve(&mut m, &g, 0.5, 1.0, &QualityOptions::default());
    assert!(
        report.collapses + report.flips + report.smoothed > 0,
        "the quality pass changed nothing"
    );
    let rel = compare(&m, "quality shell");
    assert!(rel <= 1e-5, "relative max difference {rel:e}");
}

/// Two materials: a ball (conductivity 1) inside a shell (conductivity 6) meshed in one run
/// with `--levels`, the outer level held at 0, a unit source; CalculiX takes a material per
/// region `*ELSET` of the `.inp`, solver-demo `--k NAME=K` per region read from the same sets.
#[test]
fn agrees_with_calculix_on_two_materials() {
    if !have_ccx() {
        return;
    }
    let g = ball_grid(20);
    let opts = tptd::MeshOptions::default().levels(&[f64::NEG_INFINITY, 0.55, 1.0]);
    let mut m = tptd::mesh_interval(&g, &opts).unwrap().mesh;
    m.regions.names = vec!["core".into(), "shell".into()];
    let deck = "*INCLUDE, INPUT=mesh.inp\n\
                *MATERIAL, NAME=SOFT\n*CONDUCTIVITY\n1\n\
                *MATERIAL, NAME=HARD\n*CONDUCTIVITY\n6\n\
                *SOLID SECTION, ELSET=CORE, MATERIAL=SOFT\n\
                *SOLID SECTION, ELSET=SHELL, MATERIAL=HARD\n\
                *STEP\n*HEAT TRANSFER, STEADY STATE\n\
                *BOUNDARY\nLEVEL3, 11, 11, 0\n\
                *DFLUX\nDOMAIN, BF, 1\n\
                *NODE FILE\nNT\n*END STEP\n";
    let opts = Options {
        k: 1.0,
        k_regions: vec![("core".into(), 1.0), ("shell".into(), 6.0)],
        source: 1.0,
        dirichlet: vec![("level3".into(), 0.0)],
        ..Options::default()
    };
    let rel = compare_with(&m, "two materials", deck, opts);
    assert!(rel <= 1e-5, "relative max difference {rel:e}");
}
