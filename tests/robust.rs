//! Failure paths of the `tptd-mesh` binary a new user hits: empty axes, FIFOs as detached
//! data, a report that names the input or the mesh by another spelling, a huge `-j`, the memory
//! cap, signals during the write. Each gives one line on stderr, a non-zero exit, never a panic,
//! and leaves no file behind.

mod common;

use std::fs;
use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use common::files::{listing, npy_bytes, write_npy};

const BIN: &str = env!("CARGO_BIN_EXE_tptd-mesh");

fn run_in(dir: &Path, args: &[&str]) -> Output {
    run_env(dir, args, &[])
}

fn run_env(dir: &Path, args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut c = Command::new(BIN);
    c.current_dir(dir).args(args).stdin(Stdio::null());
    for (k, v) in env {
        c.env(k, v);
    }
    c.output().expect("the binary runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Distance from an off-centre point: a ball for `--beta r`.
fn ball(i: usize, j: usize, k: usize) -> f64 {
    let (x, y, z) = (i as f64 - 4.3, j as f64 - 3.7, k as f64 - 4.1);
    (x * x + y * y + z * z).sqrt()
}

/// Checks a failed run: exit 1 (not a signal or a panic's 101), one stderr line
/// `tptd-mesh: error: …` naming `names`, and `dir` exactly as `before`.
fn assert_one_line_failure(o: &Output, dir: &Path, before: &[String], names: &str) -> String {
    assert_one_line_exit(o, dir, before, names, 1)
}

/// [`assert_one_line_failure`] with exit status `code`.
fn assert_one_line_exit(
    o: &Output,
    dir: &Path,
    before: &[String],
    names: &str,
    code: i32,
) -> String {
    let err = stderr(o);
    assert_eq!(o.status.code(), Some(code), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.starts_with("tptd-mesh: error: "), "{err}");
    assert!(err.contains(names), "{err} does not name {names}");
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(listing(dir), before, "files left behind");
    err
}

fn fails_cleanly(dir: &Path, args: &[&str], names: &str) -> String {
    let before = listing(dir);
    let o = run_in(dir, args);
    assert_one_line_failure(&o, dir, &before, names)
}

/// A refused run (exit 2) that leaves `dir` as it was.
fn refused_cleanly(dir: &Path, args: &[&str], names: &str) -> String {
    let before = listing(dir);
    let o = run_in(dir, args);
    assert_one_line_exit(&o, dir, &before, names, 2)
}

#[test]
fn empty_axes_are_one_line_errors() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for (n, shape) in ["(0, 5, 5)", "(5, 0, 5)", "(5, 5, 0)", "(0, 0, 0)"]
        .iter()
        .enumerate()
    {
        let name = format!("empty{n}.npy");
        fs::write(d.join(&name), npy_bytes("<f8", shape, &[])).unwrap();
        let e = fails_cleanly(d, &[&name, "-o", "m.vtu", "--alpha", "0"], &name);
        assert!(e.contains("at least 2"), "{shape}: {e}");
    }
    let nrrd =
        "NRRD0004\ntype: double\ndimension: 3\nsizes: 0 3 3\nencoding: raw\nendian: little\n\n";
    fs::write(d.join("empty.nrrd"), nrrd).unwrap();
    let mha = "NDims = 3\nDimSize = 3 0 3\nElementType = MET_DOUBLE\nElementDataFile = LOCAL\n";
    fs::write(d.join("empty.mha"), mha).unwrap();
    for name in ["empty.nrrd", "empty.mha"] {
        let e = fails_cleanly(d, &[name, "-o", "m.vtu", "--alpha", "0"], name);
        assert!(e.contains("at least 2"), "{name}: {e}");
    }
}

/// Writes `vol.nhdr` whose detached data file is `data`.
fn write_nhdr(dir: &Path, data: &str) {
    let text = format!(
        "NRRD0004\ntype: double\ndimension: 3\nsizes: 3 3 3\nencoding: raw\nendian: little\n\
         data file: {data}\n"
    );
    fs::write(dir.join("vol.nhdr"), text).unwrap();
}

#[test]
fn a_fifo_as_detached_data_is_refused_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let ok = Command::new("mkfifo")
        .arg(d.join("pipe.raw"))
        .status()
        .expect("mkfifo runs");
    assert!(ok.success());
    for (header, text) in [
        ("vol.nhdr", None),
        (
            "vol.mhd",
            Some(
                "NDims = 3\nDimSize = 3 3 3\nElementType = MET_DOUBLE\nElementDataFile = pipe.raw\n",
            ),
        ),
    ] {
        match text {
            None => write_nhdr(d, "pipe.raw"),
            Some(t) => fs::write(d.join(header), t).unwrap(),
        }
        let before = listing(d);
        let mut child = Command::new(BIN)
            .current_dir(d)
            .args([header, "-o", "m.vtu", "--alpha", "0"])
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let t = Instant::now();
        while child.try_wait().unwrap().is_none() {
            if t.elapsed() > Duration::from_secs(20) {
                let _ = child.kill();
                panic!("{header}: blocked on the FIFO");
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        let o = child.wait_with_output().unwrap();
        let e = assert_one_line_failure(&o, d, &before, header);
        assert!(e.contains("not a regular file"), "{e}");
    }
}

#[test]
fn a_report_never_replaces_the_input_or_the_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_npy(&d.join("victim.npy"), [9, 8, 9], ball);
    let input = fs::read(d.join("victim.npy")).unwrap();
    fs::create_dir(d.join("out")).unwrap();
    let args = ["victim.npy", "--beta", "3", "-o", "out/m.vtu"];
    let o = run_in(d, &args);
    assert!(o.status.success(), "{}", stderr(&o));
    let mesh = fs::read(d.join("out/m.vtu")).unwrap();
    fs::hard_link(d.join("victim.npy"), d.join("link.json")).unwrap();
    #[cfg(unix)]
    std::os::unix::fs::symlink("out/m.vtu", d.join("sym.json")).unwrap();
    for report in [
        "victim.npy",
        "./victim.npy",
        "out/../victim.npy",
        "link.json",
        "out/../out/m.vtu",
        "./out/m.vtu",
        "sym.json",
    ] {
        let mut a = args.to_vec();
        a.extend(["--report", report]);
        let e = refused_cleanly(d, &a, report);
        assert!(e.contains("same file"), "{report}: {e}");
        assert_eq!(fs::read(d.join("victim.npy")).unwrap(), input, "{report}");
        assert_eq!(fs::read(d.join("out/m.vtu")).unwrap(), mesh, "{report}");
    }
    // The mesh may not replace the input either (a hard link with a mesh extension).
    fs::hard_link(d.join("victim.npy"), d.join("alias.vtu")).unwrap();
    let e = refused_cleanly(
        d,
        &["victim.npy", "--beta", "3", "-o", "alias.vtu"],
        "alias.vtu",
    );
    assert!(e.contains("same file"), "{e}");
    assert_eq!(fs::read(d.join("victim.npy")).unwrap(), input);
}

#[test]
fn a_huge_thread_count_fails_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_npy(&d.join("v.npy"), [9, 8, 9], ball);
    let t = Instant::now();
    let before = listing(d);
    let o = run_in(d, &["v.npy", "--beta", "3", "-o", "m.msh", "-j", "4096"]);
    assert!(t.elapsed() < Duration::from_secs(5), "{:?}", t.elapsed());
    // a usage error: exit 2, one line naming -j, nothing written
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert_eq!(e.lines().count(), 1, "{e}");
    assert!(e.contains("-j 4096") && e.contains("worker threads"), "{e}");
    assert_eq!(listing(d), before);
}

/// Reads each `.vtu` with VTK and (unless raw) meshio and prints one line per reader:
/// `file reader points cells f-sum point-sum connectivity-sum`.
const READ_VTU_PY: &str = r#"
import sys, numpy as np, meshio, vtk
from vtk.util.numpy_support import vtk_to_numpy
for path in sys.argv[1:]:
    r = vtk.vtkXMLUnstructuredGridReader(); r.SetFileName(path); r.Update()
    g = r.GetOutput()
    pts = vtk_to_numpy(g.GetPoints().GetData()); f = vtk_to_numpy(g.GetPointData().GetArray("f"))
    conn = vtk_to_numpy(g.GetCells().GetConnectivityArray())
    rows = [("vtk", pts, f, conn)]
    if "raw" not in path:
        m = meshio.read(path)
        rows.append(("meshio", m.points, m.point_data["f"], m.cells_dict["tetra"].ravel()))
    for name, p, v, c in rows:
        print(path, name, len(p), len(c) // 4, repr(float(np.sum(v))), repr(float(np.sum(p))), int(np.sum(c)))
"#;

/// The MC33 case 3.1 cell (tests/common/mc33_table.rs) as a 2 × 2 × 2 `.npy`.
fn write_mc33_3_1(path: &Path) {
    let v = [
        0.4601, -0.1106, -0.1735, -0.0036, 0.1452, 0.1580, 0.2468, -0.2401,
    ];
    write_npy(path, [2, 2, 2], |i, j, k| v[i + 2 * j + 4 * k]);
}

#[test]
fn every_vtu_encoding_reads_back_in_meshio_and_vtk() {
    if !common::external::require_python_with("meshio")
        || !common::external::require_python_with("vtk")
    {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_mc33_3_1(&d.join("c31.npy"));
    // 24³: every array of the mesh spans several 32 KiB zlib blocks
    write_npy(&d.join("ball.npy"), [24, 24, 24], |i, j, k| {
        ball(i, j, k) + 0.3 * (i as f64).sin()
    });
    let mut files = Vec::new();
    for (input, interval) in [
        ("c31.npy", ["--beta", "-0.1283"]),
        ("ball.npy", ["--beta", "9.5"]),
    ] {
        for enc in ["base64", "zlib", "raw"] {
            let out = format!("{}.{enc}.vtu", &input[..input.len() - 4]);
            let o = run_in(
                d,
                &[
                    input,
                    "-o",
                    &out,
                    interval[0],
                    interval[1],
                    "--vtu-encoding",
                    enc,
                ],
            );
            assert!(o.status.success(), "{}", stderr(&o));
            files.push(out);
        }
    }
    // the raw 3.1 mesh holds a CR byte, which meshio's XML parser rewrites (meshio #1324)
    let raw = fs::read(d.join("c31.raw.vtu")).unwrap();
    let start = raw.iter().position(|&b| b == b'_').unwrap();
    assert!(raw[start..].contains(&b'\r'), "no CR in the raw data");
    let o = Command::new(common::external::python())
        .current_dir(d)
        .arg("-c")
        .arg(READ_VTU_PY)
        .args(&files)
        .output()
        .unwrap();
    let out = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(o.status.success(), "{out}{}", stderr(&o));
    for stem in ["c31", "ball"] {
        let rows: Vec<&str> = out.lines().filter(|l| l.starts_with(stem)).collect();
        assert_eq!(rows.len(), 5, "{out}");
        let summary = |l: &str| l.split_whitespace().skip(2).collect::<Vec<_>>().join(" ");
        for r in &rows {
            assert_eq!(summary(r), summary(rows[0]), "{out}");
        }
        if stem == "c31" {
            // 12 points and 6 tets: the 6-fold split, its sagging diagonals bisected just
            // outside the interval (the nearer side of the level), which clipping removes
            assert!(rows[0].contains(" 12 6 "), "{out}");
        }
    }
}

#[test]
fn sigterm_during_the_write_leaves_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // a ball of radius 45 in 110³: a few million tets, zlib-compressed for a slow write
    write_npy(&d.join("big.npy"), [110, 110, 110], |i, j, k| {
        let (x, y, z) = (i as f64 - 54.7, j as f64 - 55.2, k as f64 - 54.9);
        (x * x + y * y + z * z).sqrt()
    });
    let before = listing(d);
    let mut caught = false;
    for attempt in 0..3 {
        let mut child = Command::new(BIN)
            .current_dir(d)
            .args([
                "big.npy",
                "--beta",
                "45.3",
                "-o",
                "m.vtu",
                "--vtu-encoding",
                "zlib",
            ])
            .args(["--report", "r.json", "--no-analysis", "-j", "1"])
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let t = Instant::now();
        let seen = loop {
            if child.try_wait().unwrap().is_some() || t.elapsed() > Duration::from_secs(120) {
                break false;
            }
            if listing(d).iter().any(|n| n.starts_with(".m.vtu.tmp-")) {
                break true;
            }
            std::thread::sleep(Duration::from_millis(2));
        };
        if !seen {
            let _ = child.kill();
            let _ = child.wait();
            eprintln!("attempt {attempt}: the write ended before the signal");
            for f in ["m.vtu", "r.json"] {
                let _ = fs::remove_file(d.join(f));
            }
            continue;
        }
        let ok = Command::new("kill")
            .args(["-TERM", &child.id().to_string()])
            .status()
            .unwrap();
        assert!(ok.success());
        let o = child.wait_with_output().unwrap();
        let err = stderr(&o);
        if o.status.success() {
            // the rename beat the signal: the outputs are complete, try again
            for f in ["m.vtu", "r.json"] {
                let _ = fs::remove_file(d.join(f));
            }
            continue;
        }
        assert_eq!(o.status.code(), Some(128 + 15), "{err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.contains("interrupted by SIGTERM"), "{err}");
        assert_eq!(listing(d), before, "SIGTERM left files behind");
        caught = true;
        break;
    }
    assert!(caught, "never caught the write in progress");
}

#[cfg(target_os = "linux")]
#[test]
fn a_failed_report_writes_no_mesh_either() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_npy(&d.join("v.npy"), [9, 8, 9], ball);
    // /proc exists, so the early check passes, but no file can be created in it
    let e = fails_cleanly(
        d,
        &[
            "v.npy",
            "--beta",
            "3",
            "-o",
            "m.vtu",
            "--report",
            "/proc/tptd-report.json",
        ],
        "/proc/tptd-report.json",
    );
    assert!(e.contains("cannot write"), "{e}");
    assert!(!d.join("m.vtu").exists());
}

#[test]
fn the_memory_cap_gives_one_line_at_every_stage() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // 40³ f64 (512 kB): reading needs about 512 kB, meshing the ball about 10 MB
    write_npy(&d.join("v.npy"), [40, 40, 40], |i, j, k| {
        let (x, y, z) = (i as f64 - 19.6, j as f64 - 20.2, k as f64 - 19.9);
        (x * x + y * y + z * z).sqrt()
    });
    let args = [
        "v.npy", "--beta", "15.5", "-o", "m.vtu", "--report", "r.json",
    ];
    // an allocation outside any estimate fails (the allocator's line): an ascii NRRD (about
    // 1 MB of text) is read whole before its header is looked at; the .npy reader checks its
    // estimate before it allocates anything proportional to the data
    let text: Vec<String> = (0..40 * 40 * 40)
        .map(|n| format!("{:.15}", n as f64 / 7.0))
        .collect();
    let nrrd = "NRRD0004\ntype: double\ndimension: 3\nsizes: 40 40 40\nencoding: ascii\n\n";
    std::fs::write(d.join("a.nrrd"), format!("{nrrd}{}\n", text.join(" "))).unwrap();
    let before = listing(d);
    let mut a = args.to_vec();
    a[0] = "a.nrrd";
    let o = run_env(d, &a, &[("TPTD_MEMORY_LIMIT", "200K")]);
    let e = assert_one_line_failure(&o, d, &before, "out of memory");
    assert!(e.contains("memory limit of 200.0 KiB"), "{e}");
    let o = run_env(d, &args, &[("TPTD_MEMORY_LIMIT", "200K")]);
    let e = assert_one_line_failure(&o, d, &before, "v.npy");
    assert!(e.contains("reading 64000 samples needs about"), "{e}");
    // the samples do not fit: refused after the header, before the data are decoded
    let mut a = args.to_vec();
    a.extend(["--memory-limit", "400K"]);
    let o = run_in(d, &a);
    let e = assert_one_line_failure(&o, d, &before, "v.npy");
    assert!(e.contains("reading 64000 samples needs about"), "{e}");
    // the mesh does not fit: refused before meshing, naming the estimate
    let o = run_env(d, &args, &[("TPTD_MEMORY_LIMIT", "4M")]);
    let e = assert_one_line_failure(&o, d, &before, "v.npy");
    assert!(
        e.contains("tetrahedra) needs about") && e.contains("memory limit is 4.0 MiB"),
        "{e}"
    );
    // a generous cap changes nothing
    let o = run_env(d, &args, &[("TPTD_MEMORY_LIMIT", "1G")]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = run_in(
        d,
        &[
            "v.npy",
            "--beta",
            "1",
            "-o",
            "x.vtu",
            "--memory-limit",
            "lots",
        ],
    );
    assert_eq!(o.status.code(), Some(2), "a usage error");
    assert_eq!(stderr(&o).lines().count(), 1);
    assert!(stderr(&o).contains("is not a size"), "{}", stderr(&o));
}

/// Writes `name` (a `.nhdr` with `space directions` `dirs`) and its data `name.raw`: a ball
/// in 9³.
fn write_nhdr_with_directions(dir: &Path, name: &str, dirs: &str) {
    let mut data = Vec::new();
    for k in 0..9 {
        for j in 0..9 {
            for i in 0..9 {
                data.extend_from_slice(&ball(i, j, k).to_le_bytes());
            }
        }
    }
    fs::write(dir.join(format!("{name}.raw")), data).unwrap();
    let text = format!(
        "NRRD0004\ntype: double\ndimension: 3\nspace dimension: 3\nsizes: 9 9 9\n\
         space directions: {dirs}\nencoding: raw\nendian: little\ndata file: {name}.raw\n"
    );
    fs::write(dir.join(name), text).unwrap();
}

#[test]
fn near_singular_directions_warn_and_singular_ones_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_nhdr_with_directions(d, "sheared.nhdr", "(1,0,0) (1,0.0001,0) (0,0,1)");
    let o = run_in(d, &["sheared.nhdr", "--beta", "3", "-o", "s.vtu"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.starts_with(
            "tptd-mesh: warning: sheared.nhdr: the direction matrix is nearly singular"
        ),
        "{err}"
    );
    write_nhdr_with_directions(d, "upright.nhdr", "(0,1,0) (-1,0,0) (0,0,2)");
    let o = run_in(d, &["upright.nhdr", "--beta", "3", "-o", "u.vtu"]);
    assert!(
        o.status.success() && stderr(&o).is_empty(),
        "{}",
        stderr(&o)
    );
    for (name, dirs) in [
        ("flat.nhdr", "(1,0,0) (2,0,0) (0,0,1)"),
        ("almost.nhdr", "(1,0,0) (1,1e-17,0) (0,0,1)"),
    ] {
        write_nhdr_with_directions(d, name, dirs);
        let e = fails_cleanly(d, &[name, "--beta", "3", "-o", "f.vtu"], name);
        assert!(e.contains("singular"), "{e}");
    }
}

#[test]
fn every_vtu_encoding_is_identical_for_one_and_two_threads() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // 40³ ball: the arrays span many parallel base64 pieces and zlib blocks
    write_npy(&d.join("v.npy"), [40, 40, 40], |i, j, k| {
        let (x, y, z) = (i as f64 - 19.6, j as f64 - 20.2, k as f64 - 19.9);
        (x * x + y * y + z * z).sqrt() + 0.4 * (0.7 * x).sin()
    });
    for enc in ["base64", "zlib", "raw"] {
        let mut outs = Vec::new();
        for j in ["1", "2"] {
            let out = format!("m{j}.{enc}.vtu");
            let o = run_in(
                d,
                &[
                    "v.npy",
                    "--beta",
                    "16.5",
                    "-o",
                    &out,
                    "-j",
                    j,
                    "-q",
                    "--vtu-encoding",
                    enc,
                ],
            );
            assert!(o.status.success(), "{}", stderr(&o));
            outs.push(fs::read(d.join(&out)).unwrap());
        }
        assert!(outs[0].len() > 1 << 20, "{enc}: {} bytes", outs[0].len());
        assert!(outs[0] == outs[1], "{enc}: -j 1 and -j 2 differ");
    }
}

#[test]
fn pending_files_appear_only_when_committed() {
    use tptd::io::{same_file, write_pending};
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let a = write_pending(&d.join("a.txt"), |w| w.write_all(b"a")).unwrap();
    let b = write_pending(&d.join("b.txt"), |w| w.write_all(b"b")).unwrap();
    assert_eq!(listing(d).len(), 2, "{:?}", listing(d));
    assert!(listing(d)
        .iter()
        .all(|n| n.starts_with('.') && n.contains(".tmp-")));
    drop(b);
    a.commit().unwrap();
    assert_eq!(listing(d), ["a.txt"]);
    assert_eq!(fs::read(d.join("a.txt")).unwrap(), b"a");
    let failed = write_pending(&d.join("c.txt"), |_| Err(std::io::Error::other("no")));
    assert!(failed.is_err());
    assert_eq!(listing(d), ["a.txt"]);
    fs::create_dir(d.join("sub")).unwrap();
    assert!(same_file(&d.join("a.txt"), &d.join("sub/../a.txt")));
    assert!(same_file(&d.join("new.txt"), &d.join("sub/../new.txt")));
    assert!(!same_file(&d.join("a.txt"), &d.join("sub/a.txt")));
}

#[test]
fn sizes_below_a_mebibyte_are_not_printed_as_zero() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_npy(&d.join("v.npy"), [9, 9, 9], ball);
    let before = listing(d);
    let o = run_in(
        d,
        &[
            "v.npy",
            "--beta",
            "3",
            "-o",
            "m.vtu",
            "--memory-limit",
            "1K",
        ],
    );
    let e = assert_one_line_failure(&o, d, &before, "1.0 KiB");
    assert!(!e.contains("0.0 MiB"), "{e}");
}

#[test]
fn out_of_memory_in_critical_mode_gives_a_hint_that_applies() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // an ascii NRRD (about 1 MB of text) is read whole before its header is looked at
    let text: Vec<String> = (0..40 * 40 * 40)
        .map(|n| format!("{:.15}", n as f64 / 7.0))
        .collect();
    let nrrd = "NRRD0004\ntype: double\ndimension: 3\nsizes: 40 40 40\nencoding: ascii\n\n";
    fs::write(d.join("a.nrrd"), format!("{nrrd}{}\n", text.join(" "))).unwrap();
    let before = listing(d);
    let args = ["a.nrrd", "--critical", "--json", "c.json"];
    let o = run_env(d, &args, &[("TPTD_MEMORY_LIMIT", "200K")]);
    let e = assert_one_line_failure(&o, d, &before, "out of memory");
    assert!(!e.contains("interval"), "{e}");
    assert!(e.contains("--memory-limit") && e.contains("crop"), "{e}");
}

/// A 3×3×3 ASCII `.vts` (unit lattice) with `arrays` as point data and the point
/// coordinates `points(i, j, k)`.
fn write_small_vts(path: &Path, arrays: &str, points: impl Fn(usize, usize, usize) -> String) {
    let mut pts = String::new();
    for k in 0..3 {
        for j in 0..3 {
            for i in 0..3 {
                pts += &points(i, j, k);
                pts += " ";
            }
        }
    }
    let text = format!(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"StructuredGrid\" version=\"0.1\">\n\
         <StructuredGrid WholeExtent=\"0 2 0 2 0 2\"><Piece Extent=\"0 2 0 2 0 2\">\n\
         <PointData>{arrays}</PointData>\n\
         <Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">{pts}\
         </DataArray></Points></Piece></StructuredGrid></VTKFile>\n"
    );
    fs::write(path, text).unwrap();
}

fn lattice(i: usize, j: usize, k: usize) -> String {
    format!("{i} {j} {k}")
}

/// 27 values: `f(n)` for point `n`, space-separated.
fn values(f: impl Fn(usize) -> String) -> String {
    (0..27).map(f).collect::<Vec<_>>().join(" ")
}

#[test]
fn a_vts_without_a_scalar_array_lists_the_arrays_it_has() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let v = values(|n| format!("{n} 0 1"));
    let arrays = format!(
        "<DataArray type=\"Float64\" Name=\"velocity\" NumberOfComponents=\"3\" \
         format=\"ascii\">{v}</DataArray>"
    );
    write_small_vts(&d.join("v.vts"), &arrays, lattice);
    let e = fails_cleanly(d, &["v.vts", "--alpha", "1", "-o", "m.vtu"], "v.vts");
    assert!(!e.contains("none"), "{e}");
    assert!(e.contains("velocity") && e.contains("3 components"), "{e}");
}

#[test]
fn a_nan_point_in_a_vts_is_reported_as_such() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let f = values(|n| format!("{}", n as f64 * 0.5));
    let arrays = format!("<DataArray type=\"Float64\" Name=\"f\" format=\"ascii\">{f}</DataArray>");
    let points = |i, j, k| {
        if (i, j, k) == (1, 2, 0) {
            format!("{i} nan {k}")
        } else {
            lattice(i, j, k)
        }
    };
    write_small_vts(&d.join("n.vts"), &arrays, points);
    let e = fails_cleanly(d, &["n.vts", "--alpha", "1", "-o", "m.vtu"], "n.vts");
    assert!(!e.contains("direction"), "{e}");
    assert!(e.contains("(1, 2, 0)") && e.contains("NaN"), "{e}");
}

#[test]
fn a_direction_matrix_of_condition_number_2000_is_warned_about() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // unit axes x and (1, 0.001, 0) / |.|: 2-norm condition number about 2000
    write_nhdr_with_directions(d, "c2000.nhdr", "(1,0,0) (1,0.001,0) (0,0,1)");
    let o = run_in(d, &["c2000.nhdr", "--beta", "3", "-o", "s.vtu", "-q"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("the direction matrix is nearly singular (condition number 2.00e3)"),
        "{}",
        stderr(&o)
    );
    // a condition number of 500 is not
    write_nhdr_with_directions(d, "c500.nhdr", "(1,0,0) (1,0.004,0) (0,0,1)");
    let o = run_in(d, &["c500.nhdr", "--beta", "3", "-o", "t.vtu", "-q"]);
    assert!(
        o.status.success() && stderr(&o).is_empty(),
        "{}",
        stderr(&o)
    );
}

/// A `uint8` volume is estimated at one byte per sample, as the README says, and the bound
/// check before meshing streams through the volume instead of holding the critical-point
/// analysis of all of it: a 192³ `uint8` ball (6.75 MiB of samples, a small mesh) meshes with
/// the default options under a 24 MiB cap (the whole analysis needed more than 40 MiB), and
/// a cap below its samples names 6.8 MiB (three bytes per sample were estimated before).
#[test]
fn a_uint8_volume_costs_one_byte_per_sample_and_the_bound_check_streams() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let n = 192usize;
    let mut data = Vec::with_capacity(n * n * n);
    for i in 0..n {
        for j in 0..n {
            for k in 0..n {
                let (x, y, z) = (i as f64 - 60.3, j as f64 - 64.2, k as f64 - 66.1);
                let r = (x * x + y * y + z * z).sqrt();
                data.push((200.0 - 20.0 * r).clamp(0.0, 200.0) as u8);
            }
        }
    }
    fs::write(d.join("b.npy"), npy_bytes("|u1", "(192, 192, 192)", &data)).unwrap();
    let before = listing(d);
    let args = ["b.npy", "--alpha", "100.3", "-o", "m.vtu", "--memory-limit"];
    let mut a = args.to_vec();
    a.push("5M");
    let e = assert_one_line_failure(&run_in(d, &a), d, &before, "b.npy");
    assert!(
        e.contains("reading 7077888 samples needs about 6.8 MiB"),
        "{e}"
    );
    let mut a = args.to_vec();
    a.push("24M");
    let o = run_in(d, &a);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(d.join("m.vtu").exists());
}
