//! The `solver-demo` binary: the report it prints, the `.vtu` it writes (read back by VTK),
//! identical output for any thread count, and one-line errors with a non-zero exit and no
//! output file for bad input.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use common::*;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_solver-demo"))
}

fn run(args: &[&str]) -> Output {
    bin().args(args).output().unwrap()
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// A shell mesh (groups alpha and beta) written as `.msh` into `dir`.
fn shell_file(dir: &Path) -> PathBuf {
    let m = mesh(&ball_grid(14), 0.5, 1.0);
    through_file(&m, dir, "shell.msh");
    dir.join("shell.msh")
}

#[test]
fn solves_reports_and_writes_a_vtu_that_vtk_reads() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = shell_file(dir.path());
    let out = dir.path().join("u.vtu");
    let o = run(&[
        mesh.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--k",
        "2",
        "--dirichlet",
        "alpha=0",
        "--dirichlet",
        "beta=1",
    ]);
    let stdout = text(&o.stdout);
    assert!(o.status.success(), "{stdout}{}", text(&o.stderr));
    for key in [
        "unknowns: ",
        "iterations: ",
        "final relative residual: ",
        "times (s): read",
    ] {
        assert!(stdout.contains(key), "{key:?} missing in:\n{stdout}");
    }
    // Without a source, u is harmonic: between its boundary values 0 and 1, and the flux is
    // -k grad u. VTK reads the file independently.
    let script = r#"
import sys, vtk
from vtk.util.numpy_support import vtk_to_numpy as a
r = vtk.vtkXMLUnstructuredGridReader(); r.SetFileName(sys.argv[1]); r.Update()
g = r.GetOutput()
u = a(g.GetPointData().GetArray("u")); gu = a(g.GetCellData().GetArray("grad_u")); fl = a(g.GetCellData().GetArray("flux"))
assert len(u) == g.GetNumberOfPoints() and gu.shape == (g.GetNumberOfCells(), 3)
assert u.min() >= -1e-12 and u.max() <= 1 + 1e-12, (u.min(), u.max())
assert abs(u.min()) < 1e-12 and abs(u.max() - 1) < 1e-12
assert abs(fl + 2 * gu).max() <= 1e-12 * abs(gu).max()
print("ok", g.GetNumberOfPoints(), g.GetNumberOfCells())
"#;
    let py = Command::new("python3")
        .args(["-c", script, out.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(
        py.status.success(),
        "VTK check failed: {}{}",
        text(&py.stdout),
        text(&py.stderr)
    );
}

#[test]
fn output_is_identical_for_one_and_two_threads() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = shell_file(dir.path());
    let mut files = Vec::new();
    for j in ["1", "2"] {
        let out = dir.path().join(format!("u{j}.vtu"));
        let o = run(&[
            mesh.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "-j",
            j,
            "--source",
            "1.5",
            "--dirichlet",
            "beta=0",
        ]);
        assert!(o.status.success(), "{}", text(&o.stderr));
        files.push(std::fs::read(out).unwrap());
    }
    assert!(files[0] == files[1], "-j 1 and -j 2 differ");
}

#[test]
fn mms_mode_prints_relative_errors_and_the_problem() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = shell_file(dir.path());
    let o = run(&[mesh.to_str().unwrap(), "--mms"]);
    let stdout = text(&o.stdout);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(
        stdout.contains("u = sin(2x) cos(y) exp(z/2)") && stdout.contains("-div(k grad u)"),
        "{stdout}"
    );
    let line = stdout
        .lines()
        .find(|l| l.starts_with("mms relative errors: L2 "))
        .expect(&stdout);
    let l2: f64 = line.split_whitespace().nth(4).unwrap().parse().unwrap();
    let h1: f64 = line.split_whitespace().nth(6).unwrap().parse().unwrap();
    assert!(l2 > 0.0 && l2 < 0.05, "{line}");
    assert!(h1 > l2 && h1 < 0.5, "{line}");
}

/// Runs with `args` (output `x.vtu` in `dir`), expects failure with one line on stderr
/// containing `expect`, and no output file.
fn fails(dir: &Path, mesh: &Path, args: &[&str], expect: &str) {
    let out = dir.join("x.vtu");
    let mut all = vec![mesh.to_str().unwrap(), "-o", out.to_str().unwrap()];
    all.extend_from_slice(args);
    let o = run(&all);
    let err = text(&o.stderr);
    assert!(!o.status.success(), "{args:?} succeeded");
    assert_eq!(err.trim_end().lines().count(), 1, "not one line: {err}");
    assert!(
        err.starts_with("solver-demo: error: ") && err.contains(expect),
        "{args:?}: {err}"
    );
    assert!(!out.exists(), "{args:?} left an output file");
}

#[test]
fn bad_input_gives_one_line_errors() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mesh = shell_file(d);
    fails(
        d,
        &mesh,
        &["--dirichlet", "gamma=1"],
        "no node group named \"gamma\"",
    );
    fails(d, &mesh, &[], "singular system: no Dirichlet node");
    fails(d, &mesh, &["--dirichlet", "alpha"], "expected NAME=VALUE");
    fails(
        d,
        &mesh,
        &["--dirichlet", "alpha=0", "--k", "-1"],
        "not positive",
    );
    fails(
        d,
        &mesh,
        &["--dirichlet", "alpha=0", "--k", "rock=3"],
        "no region named \"rock\"",
    );
    // One tet, an empty node set, and a second tet with no Dirichlet node.
    let inp = d.join("small.inp");
    std::fs::write(
        &inp,
        "*NODE\n1, 0, 0, 0\n2, 1, 0, 0\n3, 0, 1, 0\n4, 0, 0, 1\n\
         5, 5, 0, 0\n6, 6, 0, 0\n7, 5, 1, 0\n8, 5, 0, 1\n\
         *ELEMENT, TYPE=C3D4, ELSET=DOMAIN\n1, 1, 2, 3, 4\n2, 5, 6, 7, 8\n\
         *NSET, NSET=EMPTY\n*NSET, NSET=FIRST\n1, 2\n",
    )
    .unwrap();
    fails(
        d,
        &inp,
        &["--dirichlet", "empty=1"],
        "\"empty\" has no nodes",
    );
    fails(
        d,
        &inp,
        &["--dirichlet", "first=1"],
        "containing node 5 has no Dirichlet node",
    );
    let flat = d.join("flat.inp");
    std::fs::write(
        &flat,
        "*NODE\n1, 0, 0, 0\n2, 1, 0, 0\n3, 0, 1, 0\n4, 2, 0, 0\n\
         *ELEMENT, TYPE=C3D4, ELSET=DOMAIN\n1, 1, 2, 3, 4\n*NSET, NSET=A\n1\n",
    )
    .unwrap();
    fails(
        d,
        &flat,
        &["--dirichlet", "a=1"],
        "tetrahedron 1 is degenerate",
    );
    let bad = d.join("bad.msh");
    std::fs::write(
        &bad,
        "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 2 1 2\n",
    )
    .unwrap();
    fails(d, &bad, &["--dirichlet", "alpha=0"], "bad.msh: line");
    fails(
        d,
        &d.join("none.msh"),
        &["--dirichlet", "alpha=0"],
        "none.msh: cannot read",
    );
}
