//! Round trips of written meshes through external tools: meshio and VTK (via
//! `tests/py/check_mesh.py`), `gmsh -check` and CalculiX (`ccx`), shared by
//! `tests/write_formats.rs` and `tests/roundtrip_mesher.rs`.
//!
//! A missing tool makes a test fail, unless `TPTD_SKIP_EXTERNAL=1`, in which case
//! [`require_tool`] returns false and the test returns early (a no-op).

use std::collections::HashMap;
use std::fs;
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::process::Command;

use tptd::io::atomic::write_atomically;
use tptd::io::inp::write_inp;
use tptd::io::msh::{write_msh, MshVersion};
use tptd::io::vtu::{write_vtu, write_vtu_with, VtuEncoding};
use tptd::{BoundaryLabel, TetMesh};

// ---------------------------------------------------------------------------------------
// Output formats
// ---------------------------------------------------------------------------------------

#[derive(Clone, Copy, Debug)]
pub enum Format {
    Msh41,
    Msh22,
    /// `.msh` 4.1 binary.
    Msh41Binary,
    Inp,
    /// `.vtu` in the default encoding (base64).
    Vtu,
    /// `.vtu` with zlib-compressed data.
    VtuZlib,
    /// `.vtu` with raw appended data.
    VtuRaw,
}

impl Format {
    pub const ALL: [Format; 5] = [
        Format::Msh41,
        Format::Msh22,
        Format::Msh41Binary,
        Format::Inp,
        Format::Vtu,
    ];
    /// The `.vtu` encodings other than the default.
    pub const OTHER_VTU: [Format; 2] = [Format::VtuZlib, Format::VtuRaw];

    /// The format argument of `check_mesh.py`.
    pub fn key(self) -> &'static str {
        match self {
            Format::Msh41 | Format::Msh41Binary => "msh41",
            Format::Msh22 => "msh22",
            Format::Inp => "inp",
            Format::Vtu | Format::VtuZlib | Format::VtuRaw => "vtu",
        }
    }

    pub fn file_name(self, stem: &str) -> String {
        match self {
            Format::Msh41 => format!("{stem}.v41.msh"),
            Format::Msh22 => format!("{stem}.v22.msh"),
            Format::Msh41Binary => format!("{stem}.v41b.msh"),
            Format::Inp => format!("{stem}.inp"),
            Format::Vtu => format!("{stem}.vtu"),
            Format::VtuZlib => format!("{stem}.zlib.vtu"),
            Format::VtuRaw => format!("{stem}.raw.vtu"),
        }
    }

    /// Writes `mesh` in this format to `w` with the crate's writer.
    pub fn write(self, mesh: &TetMesh, w: &mut dyn Write) -> io::Result<()> {
        match self {
            Format::Msh41 => write_msh(mesh, w, MshVersion::V41),
            Format::Msh22 => write_msh(mesh, w, MshVersion::V22),
            Format::Msh41Binary => write_msh(mesh, w, MshVersion::V41Binary),
            Format::Inp => write_inp(mesh, w),
            Format::Vtu => write_vtu(mesh, w),
            Format::VtuZlib => write_vtu_with(mesh, w, VtuEncoding::Zlib),
            Format::VtuRaw => write_vtu_with(mesh, w, VtuEncoding::Raw),
        }
    }
}

/// Writes `mesh` in `format` into `dir` through [`write_atomically`]; returns the path.
pub fn write_file(mesh: &TetMesh, format: Format, dir: &Path, stem: &str) -> PathBuf {
    let path = dir.join(format.file_name(stem));
    write_atomically(&path, |w| format.write(mesh, w)).unwrap();
    path
}

// ---------------------------------------------------------------------------------------
// Running tools
// ---------------------------------------------------------------------------------------

pub fn skip_external() -> bool {
    std::env::var("TPTD_SKIP_EXTERNAL").is_ok_and(|v| v == "1")
}

/// Returns false (after a note) when external tools are to be skipped; panics with a clear
/// message when `cmd args` cannot be run successfully.
pub fn require_tool(what: &str, cmd: &str, args: &[&str]) -> bool {
    if skip_external() {
        eprintln!("note: TPTD_SKIP_EXTERNAL=1, skipping the {what} round trip");
        return false;
    }
    match Command::new(cmd).args(args).output() {
        Ok(o) if o.status.success() => true,
        Ok(o) => panic!(
            "{what} is required for this test but `{cmd} {}` failed ({}): {}{}\n\
             install it (see the repo's test script) or set TPTD_SKIP_EXTERNAL=1",
            args.join(" "),
            o.status,
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        ),
        Err(e) => panic!(
            "{what} is required for this test but `{cmd}` could not be run: {e}\n\
             install it (see the repo's test script) or set TPTD_SKIP_EXTERNAL=1"
        ),
    }
}

/// [`require_tool`] for python3 with numpy and `reader` (`"vtk"` or `"meshio"`).
pub fn require_python_with(reader: &str) -> bool {
    let imports = if reader == "vtk" {
        "import numpy, vtk"
    } else {
        "import numpy, meshio"
    };
    require_tool(
        &format!("python3 with {reader}"),
        &python(),
        &["-c", imports],
    )
}

pub fn require_gmsh() -> bool {
    require_tool("gmsh", "gmsh", &["--version"])
}

pub fn require_ccx() -> bool {
    require_tool("CalculiX (ccx)", "sh", &["-c", "command -v ccx"])
}

pub fn python() -> String {
    std::env::var("PYTHON").unwrap_or_else(|_| "python3".to_string())
}

/// Runs `cmd`; returns whether it succeeded and its stdout followed by its stderr.
pub fn run(cmd: &mut Command) -> (bool, String) {
    let o = cmd
        .output()
        .unwrap_or_else(|e| panic!("cannot run {cmd:?}: {e}"));
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    (o.status.success(), text)
}

// ---------------------------------------------------------------------------------------
// meshio and VTK
// ---------------------------------------------------------------------------------------

/// The expectation file of `check_mesh.py`: points, values, tets and the boundary triangles
/// by label name, plus the `extra` top-level keys (options of the check).
pub fn expected_json(mesh: &TetMesh, extra: &[(&str, serde_json::Value)]) -> String {
    let mut boundary = serde_json::Map::new();
    for label in BoundaryLabel::ALL {
        let tris: Vec<_> = mesh
            .boundary
            .iter()
            .zip(&mesh.boundary_labels)
            .filter(|&(_, &l)| l == label)
            .map(|(t, _)| t.to_vec())
            .collect();
        if !tris.is_empty() {
            boundary.insert(label.name().to_string(), serde_json::json!(tris));
        }
    }
    let mut json = serde_json::json!({
        "points": mesh.points,
        "values": mesh.values,
        "tets": mesh.tets,
        "boundary": boundary,
    });
    let object = json.as_object_mut().unwrap();
    for (key, value) in extra {
        object.insert(key.to_string(), value.clone());
    }
    json.to_string()
}

pub fn check_script() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/py/check_mesh.py")
}

/// Writes `mesh` in `format` (`dir/stem.*`) and its expectation file (`dir/stem.json`, with
/// the `extra` keys), then runs `check_mesh.py reader format` on them and asserts that it
/// passes; returns what it printed.
pub fn check_mesh_py(
    reader: &str,
    format: Format,
    mesh: &TetMesh,
    dir: &Path,
    stem: &str,
    extra: &[(&str, serde_json::Value)],
) -> String {
    let path = write_file(mesh, format, dir, stem);
    let exp = dir.join(format!("{stem}.json"));
    fs::write(&exp, expected_json(mesh, extra)).unwrap();
    let (ok, out) = run(Command::new(python())
        .arg(check_script())
        .args([reader, format.key()])
        .arg(&path)
        .arg(&exp));
    assert!(ok, "{reader} failed on {}:\n{out}", path.display());
    out
}

// ---------------------------------------------------------------------------------------
// gmsh
// ---------------------------------------------------------------------------------------

/// Runs `gmsh -check` on the `.msh` file `path` written from `mesh`: no error, and the node
/// and element (tets + boundary triangles) counts of `mesh`.
pub fn gmsh_check(path: &Path, mesh: &TetMesh) {
    let (ok, out) = run(Command::new("gmsh").arg(path).arg("-check").arg("-nopopup"));
    assert!(
        ok && !out.contains("Error"),
        "gmsh -check {}:\n{out}",
        path.display()
    );
    for want in [
        format!("{} nodes", mesh.points.len()),
        format!("{} elements", mesh.tets.len() + mesh.boundary.len()),
    ] {
        assert!(
            out.contains(&want),
            "gmsh -check {}: no {want:?} in\n{out}",
            path.display()
        );
    }
}

/// Runs gmsh with `args`; asserts it succeeded without an error.
fn run_gmsh(args: &[&std::ffi::OsStr]) {
    let (ok, out) = run(Command::new("gmsh").args(args).arg("-nopopup"));
    assert!(ok && !out.contains("Error"), "gmsh {args:?}:\n{out}");
}

/// What gmsh reads from the `.msh` file `path`: the mesh as gmsh re-exports it (ASCII 4.1)
/// and the node data `f` as a `.pos` view (written into `dir` as `stem.*`).
pub fn gmsh_reading(path: &Path, dir: &Path, stem: &str) -> (String, String) {
    let mesh = dir.join(format!("{stem}.gmsh41.msh"));
    run_gmsh(&[
        path.as_os_str(),
        "-0".as_ref(),
        "-format".as_ref(),
        "msh41".as_ref(),
        "-save_all".as_ref(),
        "-o".as_ref(),
        mesh.as_os_str(),
    ]);
    let view = dir.join(format!("{stem}.view.pos"));
    let script = dir.join(format!("{stem}.geo"));
    let geo = format!(
        "Merge {:?};\nSave View[0] {:?};\n",
        path.display().to_string(),
        view.display().to_string()
    );
    fs::write(&script, geo).unwrap();
    run_gmsh(&[script.as_os_str(), "-0".as_ref()]);
    let text = |p: &Path| fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    (text(&mesh), text(&view))
}

/// Writes `mesh` as ASCII and as binary `.msh` 4.1 into `dir` and asserts that gmsh reads
/// the same from both: the same re-exported mesh (nodes, coordinates, elements, entities,
/// physical groups) and the same node data `f`, with the node and element counts of `mesh`.
pub fn gmsh_reads_binary_as_ascii(mesh: &TetMesh, dir: &Path, stem: &str) {
    let ascii = write_file(mesh, Format::Msh41, dir, stem);
    let binary = write_file(mesh, Format::Msh41Binary, dir, stem);
    gmsh_check(&binary, mesh);
    let (a_mesh, a_view) = gmsh_reading(&ascii, dir, &format!("{stem}.ascii"));
    let (b_mesh, b_view) = gmsh_reading(&binary, dir, &format!("{stem}.binary"));
    let (n, e) = (mesh.points.len(), mesh.tets.len() + mesh.boundary.len());
    for (section, count) in [("$Nodes\n", n), ("$Elements\n", e)] {
        let line = a_mesh.split(section).nth(1).and_then(|r| r.lines().next());
        let want = format!(" {count} 1 {count}");
        assert!(
            line.is_some_and(|l| l.ends_with(&want)),
            "{stem}: gmsh's copy has {section:?} {line:?}, expected ...{want:?}"
        );
    }
    let lines = |prefix: &str| a_view.lines().filter(|l| l.starts_with(prefix)).count();
    assert_eq!(lines("SS("), mesh.tets.len(), "{stem}: tets in gmsh's view");
    assert_eq!(
        lines("ST("),
        mesh.boundary.len(),
        "{stem}: triangles in gmsh's view"
    );
    assert!(
        a_mesh == b_mesh,
        "{stem}: gmsh re-exports binary and ASCII differently"
    );
    assert!(
        a_view == b_view,
        "{stem}: gmsh reads different node data 'f'"
    );
}

// ---------------------------------------------------------------------------------------
// CalculiX
// ---------------------------------------------------------------------------------------

/// Deck head up to `*BOUNDARY`: the mesh (`mesh.inp`), a unit-conductivity material on
/// `DOMAIN` and a steady heat-transfer step.
pub const DECK_HEAD: &str = "*INCLUDE, INPUT=mesh.inp\n*MATERIAL, NAME=M\n*CONDUCTIVITY\n1.\n\
                             *SOLID SECTION, ELSET=DOMAIN, MATERIAL=M\n*STEP\n\
                             *HEAT TRANSFER, STEADY STATE\n*BOUNDARY\n";

/// Deck tail: print and store the nodal temperatures, end the step.
pub const DECK_TAIL: &str = "*NODE PRINT, NSET=NALL\nNT\n*NODE FILE\nNT\n*END STEP\n";

/// [`DECK_HEAD`] with the fixed temperatures `(set, value)`.
pub fn heat_deck(fixed: &[(&str, f64)]) -> String {
    let mut deck = String::from(DECK_HEAD);
    for (set, t) in fixed {
        deck.push_str(&format!("{set}, 11, 11, {t:?}\n"));
    }
    deck
}

/// Temperatures by node id (1-based) from a CalculiX `.dat` `temperatures` block.
pub fn dat_temperatures(dat: &str) -> HashMap<usize, f64> {
    let block = dat
        .split("temperatures")
        .nth(1)
        .expect("no temperatures in the .dat");
    block
        .lines()
        .skip(1)
        .map(str::split_whitespace)
        .filter_map(|mut f| Some((f.next()?.parse().ok()?, f.next()?.parse().ok()?)))
        .collect()
}

/// Writes `deck` to `dir/job.inp` and runs `ccx -i job` in `dir` (one OpenMP thread);
/// asserts that it succeeded and finished, and that its output (in lower case) contains
/// neither `*error` nor any of `bad`.
pub fn run_ccx_job(dir: &Path, job: &str, deck: &str, bad: &[&str]) {
    fs::write(dir.join(format!("{job}.inp")), deck).unwrap();
    let (ok, out) = run(Command::new("ccx")
        .arg("-i")
        .arg(job)
        .current_dir(dir)
        .env("OMP_NUM_THREADS", "1"));
    let lower = out.to_lowercase();
    assert!(
        ok && !lower.contains("*error") && !bad.iter().any(|b| lower.contains(b)),
        "ccx failed on {job}:\n{out}"
    );
    assert!(
        out.contains("Job finished"),
        "ccx did not finish {job}:\n{out}"
    );
}
