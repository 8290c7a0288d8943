//! No `tptd-mesh` command destroys a file it did not create: every output (`-o`, `--report`,
//! `--json`, `--spectrum`, `--transfer`) that names a file of the input — the volume, a
//! detached NRRD or MetaImage data file, a Plot3D grid or function file, a `.vts` — or
//! another output, under any spelling (`./x`, `dir/../x`, a symbolic or hard link), is refused
//! before any work: exit 2, one line on stderr, every file byte for byte as before.
#![cfg(unix)]

mod common;

use std::fs;
use std::io::Write as _;
use std::os::unix::fs::symlink;
use std::path::Path;
use std::process::{Command, Output};

use common::files::{listing, write_npy};

const BIN: &str = env!("CARGO_BIN_EXE_tptd-mesh");

fn run_in(dir: &Path, args: &[String]) -> Output {
    Command::new(BIN)
        .current_dir(dir)
        .args(args)
        .output()
        .expect("the binary runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn strings(args: &[&str]) -> Vec<String> {
    args.iter().map(|s| s.to_string()).collect()
}

/// Distance from an off-centre point: a ball for `--beta 3`.
fn ball(x: f64, y: f64, z: f64) -> f64 {
    ((x - 3.3).powi(2) + (y - 2.7).powi(2) + (z - 2.6).powi(2)).sqrt()
}

/// Dimensions of the generated volumes.
const DIMS: [usize; 3] = [7, 6, 6];

/// The ball's samples as little-endian `f64`, x fastest.
fn ball_bytes() -> Vec<u8> {
    let mut out = Vec::new();
    for k in 0..DIMS[2] {
        for j in 0..DIMS[1] {
            for i in 0..DIMS[0] {
                out.extend(ball(i as f64, j as f64, k as f64).to_le_bytes());
            }
        }
    }
    out
}

/// An input: the arguments that name it, the interval that meshes it, and its files (the
/// ones that must survive every run), relative to the test's directory.
struct Input {
    args: Vec<String>,
    interval: [&'static str; 2],
    files: Vec<&'static str>,
}

impl Input {
    fn new(args: &[&str], interval: [&'static str; 2], files: &[&'static str]) -> Self {
        Input {
            args: strings(args),
            interval,
            files: files.to_vec(),
        }
    }
}

/// The bytes of each file of `files` in `dir`.
fn snapshot(dir: &Path, files: &[&str]) -> Vec<Vec<u8>> {
    files
        .iter()
        .map(|f| fs::read(dir.join(f)).unwrap())
        .collect()
}

/// Runs `args` in `dir` and checks the refusal: exit 2, one stderr line
/// `tptd-mesh: error: … same file …`, every file of `keep` unchanged and no file created.
fn assert_refused(dir: &Path, args: &[String], keep: &[&str]) {
    let before = snapshot(dir, keep);
    let names = listing(dir);
    let o = run_in(dir, args);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
    assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
    assert!(
        err.starts_with("tptd-mesh: error: ") && err.contains("same file"),
        "{args:?}: {err}"
    );
    assert_eq!(snapshot(dir, keep), before, "{args:?} changed a file");
    assert_eq!(listing(dir), names, "{args:?} left files behind");
}

/// The output options, each with an extension it accepts.
const FLAGS: [(&str, &str); 5] = [
    ("-o", "vtu"),
    ("--report", "json"),
    ("--json", "json"),
    ("--spectrum", "csv"),
    ("--transfer", "json"),
];

/// The arguments of a run of `input` whose output `flag` is `target`.
fn args_with(input: &Input, flag: &str, target: &str) -> Vec<String> {
    let mut a = input.args.clone();
    match flag {
        "-o" | "--report" => {
            a.extend(strings(&["--alpha", input.interval[0]]));
            a.extend(strings(&["--beta", input.interval[1]]));
            if flag == "--report" {
                a.extend(strings(&["-o", "m.vtu"]));
            }
        }
        _ => a.push("--critical".into()),
    }
    a.extend([flag.to_string(), target.to_string()]);
    a
}

/// Checks `input` (its files already in `dir`): it meshes, and every output option naming
/// each of its files is refused, both under another spelling of the file's name and through
/// a symbolic link with the option's extension.
fn every_output_spares(dir: &Path, input: &Input) {
    fs::create_dir_all(dir.join("sub")).unwrap();
    let mut ok = input.args.clone();
    ok.extend(strings(&[
        "--alpha",
        input.interval[0],
        "--beta",
        input.interval[1],
    ]));
    ok.extend(strings(&["-o", "ok.vtu", "-q"]));
    let o = run_in(dir, &ok);
    assert!(o.status.success(), "{ok:?}: {}", stderr(&o));
    fs::remove_file(dir.join("ok.vtu")).unwrap();
    let mut n = 0;
    for file in &input.files {
        for (flag, ext) in FLAGS {
            n += 1;
            let spelling = match n % 3 {
                0 => file.to_string(),
                1 => format!("./{file}"),
                _ => format!("sub/../{file}"),
            };
            let link = format!("to-{}-{n}.{ext}", file.replace('.', "_"));
            symlink(file, dir.join(&link)).unwrap();
            // `--critical` meshes nothing and refuses `--function` before any file is
            // compared (exit 2, `options_that_do_nothing_in_the_mode_are_refused`).
            let critical = !matches!(flag, "-o" | "--report");
            if critical && input.args.iter().any(|a| a == "--function") {
                continue;
            }
            let accepts = |name: &str| flag != "-o" && flag != "--transfer" || name.ends_with(ext);
            for target in [spelling, link] {
                if accepts(&target) {
                    assert_refused(dir, &args_with(input, flag, &target), &input.files);
                }
            }
        }
    }
}

#[test]
fn no_output_replaces_a_npy_input() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_npy(&d.join("v.npy"), DIMS, |i, j, k| {
        ball(i as f64, j as f64, k as f64)
    });
    every_output_spares(d, &Input::new(&["v.npy"], ["-inf", "3"], &["v.npy"]));
}

/// The 4³ NIfTI-1 fixture (values 0 to 333).
fn nifti_fixture() -> Vec<u8> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    fs::read(root.join("tests/fixtures/volumes/nii_cube_i2_sform.nii")).unwrap()
}

#[test]
fn no_output_replaces_a_nifti_input() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    fs::write(d.join("v.nii"), nifti_fixture()).unwrap();
    every_output_spares(d, &Input::new(&["v.nii"], ["150.5", "inf"], &["v.nii"]));
}

#[test]
fn no_output_replaces_a_gzipped_nifti_input() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let file = fs::File::create(d.join("v.nii.gz")).unwrap();
    let mut gz = flate2::write::GzEncoder::new(file, flate2::Compression::fast());
    gz.write_all(&nifti_fixture()).unwrap();
    gz.finish().unwrap();
    let input = Input::new(&["v.nii.gz"], ["150.5", "inf"], &["v.nii.gz"]);
    every_output_spares(d, &input);
}

#[test]
fn no_output_replaces_a_detached_nrrd_header_or_its_data_file() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let [nx, ny, nz] = DIMS;
    let header = format!(
        "NRRD0004\ntype: double\ndimension: 3\nsizes: {nx} {ny} {nz}\nencoding: raw\n\
         endian: little\ndata file: data.msh\n"
    );
    fs::write(d.join("det.nhdr"), header).unwrap();
    fs::write(d.join("data.msh"), ball_bytes()).unwrap();
    let input = Input::new(&["det.nhdr"], ["-inf", "3"], &["det.nhdr", "data.msh"]);
    every_output_spares(d, &input);
    // The data file under its own name as the mesh, as a user would type it.
    let args = args_with(&input, "-o", "data.msh");
    assert_refused(d, &args, &input.files);
}

#[test]
fn no_output_replaces_a_metaimage_header_or_its_data_file() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let [nx, ny, nz] = DIMS;
    let header = format!(
        "NDims = 3\nDimSize = {nx} {ny} {nz}\nElementType = MET_DOUBLE\n\
         ElementDataFile = data.vtu\n"
    );
    fs::write(d.join("v.mhd"), header).unwrap();
    fs::write(d.join("data.vtu"), ball_bytes()).unwrap();
    let input = Input::new(&["v.mhd"], ["-inf", "3"], &["v.mhd", "data.vtu"]);
    every_output_spares(d, &input);
    assert_refused(d, &args_with(&input, "-o", "data.vtu"), &input.files);
}

/// Points of the curvilinear grids: the index lattice, sheared.
fn point(i: usize, j: usize, k: usize) -> [f64; 3] {
    let (x, y, z) = (i as f64, j as f64, k as f64);
    [x + 0.2 * y, y, z + 0.1 * x]
}

/// Every grid vertex `(i, j, k)`, i fastest.
fn lattice() -> impl Iterator<Item = [usize; 3]> {
    let [nx, ny, nz] = DIMS;
    (0..nz).flat_map(move |k| (0..ny).flat_map(move |j| (0..nx).map(move |i| [i, j, k])))
}

/// A Plot3D grid file (little-endian `int32` dims, `float64` x, y and z arrays, no records).
fn plot3d_grid() -> Vec<u8> {
    let mut out: Vec<u8> = DIMS
        .iter()
        .flat_map(|&n| (n as i32).to_le_bytes())
        .collect();
    for c in 0..3 {
        for [i, j, k] in lattice() {
            out.extend(point(i, j, k)[c].to_le_bytes());
        }
    }
    out
}

/// The field on the lattice as `float64` bytes.
fn field_bytes() -> Vec<u8> {
    lattice()
        .flat_map(|[i, j, k]| ball(i as f64, j as f64, k as f64).to_le_bytes())
        .collect()
}

/// A Plot3D function file (`.f`) with one variable, the ball.
fn plot3d_f() -> Vec<u8> {
    let mut out: Vec<u8> = DIMS
        .iter()
        .flat_map(|&n| (n as i32).to_le_bytes())
        .collect();
    out.extend(1i32.to_le_bytes());
    out.extend(field_bytes());
    out
}

/// A Plot3D solution file (`.q`): the four constants, then the ball as density and four more
/// variables.
fn plot3d_q() -> Vec<u8> {
    let mut out: Vec<u8> = DIMS
        .iter()
        .flat_map(|&n| (n as i32).to_le_bytes())
        .collect();
    for c in [0.5f64, 0.0, 1e6, 0.0] {
        out.extend(c.to_le_bytes());
    }
    for _ in 0..5 {
        out.extend(field_bytes());
    }
    out
}

#[test]
fn no_output_replaces_a_plot3d_grid_or_its_function_file() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    fs::write(d.join("g.xyz"), plot3d_grid()).unwrap();
    fs::write(d.join("g.q"), plot3d_q()).unwrap();
    fs::write(d.join("h.xyz"), plot3d_grid()).unwrap();
    fs::write(d.join("fun.f"), plot3d_f()).unwrap();
    // The .q next to the grid, found without --function.
    let q = Input::new(&["g.xyz"], ["-inf", "2.5"], &["g.xyz", "g.q"]);
    every_output_spares(d, &q);
    let f = Input::new(
        &["h.xyz", "--function", "fun.f"],
        ["-inf", "2.5"],
        &["h.xyz", "fun.f"],
    );
    every_output_spares(d, &f);
}

/// An ASCII `.vts` of the sheared lattice with the ball as its field.
fn vts_text() -> String {
    let [nx, ny, nz] = DIMS;
    let extent = format!("0 {} 0 {} 0 {}", nx - 1, ny - 1, nz - 1);
    let values: Vec<String> = lattice()
        .map(|[i, j, k]| ball(i as f64, j as f64, k as f64).to_string())
        .collect();
    let points: Vec<String> = lattice()
        .map(|[i, j, k]| {
            let p = point(i, j, k);
            format!("{} {} {}", p[0], p[1], p[2])
        })
        .collect();
    format!(
        "<?xml version=\"1.0\"?>\n\
         <VTKFile type=\"StructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n\
         <StructuredGrid WholeExtent=\"{extent}\">\n<Piece Extent=\"{extent}\">\n\
         <PointData Scalars=\"f\">\n\
         <DataArray type=\"Float64\" Name=\"f\" format=\"ascii\">{}</DataArray>\n\
         </PointData>\n<Points>\n\
         <DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">{}</DataArray>\n\
         </Points>\n</Piece>\n</StructuredGrid>\n</VTKFile>\n",
        values.join(" "),
        points.join(" ")
    )
}

#[test]
fn no_output_replaces_a_vts_input() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    fs::write(d.join("c.vts"), vts_text()).unwrap();
    every_output_spares(d, &Input::new(&["c.vts"], ["-inf", "2.5"], &["c.vts"]));
}

#[test]
fn two_outputs_never_name_one_file() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    fs::create_dir(d.join("sub")).unwrap();
    write_npy(&d.join("v.npy"), DIMS, |i, j, k| {
        ball(i as f64, j as f64, k as f64)
    });
    let mesh = |extra: &[&str]| {
        let mut a = strings(&["v.npy", "--beta", "3"]);
        a.extend(strings(extra));
        a
    };
    let critical = |extra: &[&str]| {
        let mut a = strings(&["v.npy", "--critical"]);
        a.extend(strings(extra));
        a
    };
    // Files that do not exist yet.
    let keep = ["v.npy"];
    assert_refused(d, &mesh(&["-o", "m.vtu", "--report", "m.vtu"]), &keep);
    assert_refused(d, &mesh(&["-o", "m.vtu", "--report", "./m.vtu"]), &keep);
    assert_refused(
        d,
        &critical(&["--json", "a.json", "--spectrum", "a.json"]),
        &keep,
    );
    assert_refused(
        d,
        &critical(&["--json", "a.json", "--spectrum", "sub/../a.json"]),
        &keep,
    );
    assert_refused(
        d,
        &critical(&["--json", "./t.json", "--transfer", "t.json"]),
        &keep,
    );
    assert_refused(
        d,
        &critical(&["--spectrum", "t.csv", "--transfer", "sub/../t.csv"]),
        &keep,
    );
    // Files that exist, through links.
    fs::write(d.join("m.vtu"), "an earlier mesh").unwrap();
    fs::write(d.join("a.json"), "[]").unwrap();
    symlink("m.vtu", d.join("r.json")).unwrap();
    fs::hard_link(d.join("a.json"), d.join("s.csv")).unwrap();
    let keep = ["v.npy", "m.vtu", "a.json"];
    assert_refused(d, &mesh(&["-o", "m.vtu", "--report", "r.json"]), &keep);
    assert_refused(
        d,
        &mesh(&["-o", "sub/../m.vtu", "--report", "m.vtu"]),
        &keep,
    );
    assert_refused(
        d,
        &critical(&["--json", "a.json", "--spectrum", "s.csv"]),
        &keep,
    );
    assert_refused(
        d,
        &critical(&[
            "--json",
            "a.json",
            "--spectrum",
            "./a.json",
            "--transfer",
            "x.json",
        ]),
        &keep,
    );
}
