//! `solver-demo` never destroys a file it did not create: an output that is the input mesh
//! (under any spelling or through a link) or that is not `.vtu` is refused before any work
//! with exit 2, and a solve that fails leaves no output file.

mod common;

use std::fs;
use std::path::Path;
use std::process::{Command, Output};

use common::*;

fn run_in(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_solver-demo"))
        .current_dir(dir)
        .args(args)
        .output()
        .unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The entries of `dir`, sorted.
fn listing(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// A shell mesh (groups alpha and beta) written as `dir/name` (`.msh` or `.inp`).
fn shell(dir: &Path, name: &str) {
    through_file(&mesh(&ball_grid(10), 0.5, 1.0), dir, name);
}

/// Runs `args` in `dir`: exit `code`, one stderr line containing `needle`, `dir` holds the
/// same files as before and `keep` the same bytes.
fn assert_fails(dir: &Path, args: &[&str], code: i32, needle: &str, keep: &str) {
    let before = fs::read(dir.join(keep)).unwrap();
    let names = listing(dir);
    let o = run_in(dir, args);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(code), "{args:?}: {err}");
    assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
    assert!(
        err.starts_with("solver-demo: error: ") && err.contains(needle),
        "{args:?}: {err}"
    );
    assert_eq!(
        fs::read(dir.join(keep)).unwrap(),
        before,
        "{args:?} changed {keep}"
    );
    assert_eq!(listing(dir), names, "{args:?} left files behind");
}

#[test]
fn the_output_never_replaces_the_input_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    fs::create_dir(d.join("sub")).unwrap();
    shell(d, "m.msh");
    shell(d, "m.inp");
    #[cfg(unix)]
    std::os::unix::fs::symlink("m.msh", d.join("u.vtu")).unwrap();
    fs::hard_link(d.join("m.inp"), d.join("w.vtu")).unwrap();
    let bc = ["--dirichlet", "alpha=0", "--dirichlet", "beta=1"];
    let cases = [
        ("m.msh", "m.msh"),
        ("m.msh", "./m.msh"),
        ("m.inp", "sub/../m.inp"),
        ("m.msh", "u.vtu"),
        ("m.inp", "w.vtu"),
    ];
    for (input, out) in cases {
        if out == "u.vtu" && cfg!(not(unix)) {
            continue;
        }
        let mut args = vec![input, "-o", out];
        args.extend(bc);
        assert_fails(d, &args, 2, "same file", input);
    }
}

#[test]
fn an_output_that_is_not_vtu_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    shell(d, "m.msh");
    for out in ["u.txt", "u", "u.msh"] {
        let args = ["m.msh", "-o", out, "--dirichlet", "alpha=0"];
        assert_fails(d, &args, 2, ".vtu", "m.msh");
    }
    // Any case of the extension is accepted.
    let o = run_in(d, &["m.msh", "-o", "u.VTU", "--dirichlet", "alpha=0"]);
    assert!(o.status.success(), "{}", stderr(&o));
}

#[test]
fn a_failed_solve_leaves_no_output_file() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    shell(d, "m.msh");
    let args = [
        "m.msh",
        "-o",
        "u.vtu",
        "--dirichlet",
        "alpha=0",
        "--dirichlet",
        "beta=1",
        "--max-iter",
        "3",
    ];
    assert_fails(d, &args, 1, "did not reach --tol", "m.msh");
    // An earlier result is left as it was.
    fs::write(d.join("u.vtu"), "an earlier result").unwrap();
    assert_fails(d, &args, 1, "did not reach --tol", "u.vtu");
}
