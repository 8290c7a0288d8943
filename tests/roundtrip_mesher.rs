//! Round trips of REAL mesher output through the writers and real readers.
//!
//! `tests/write_formats.rs` checks the writers on hand-built meshes; here the meshes come from
//! [`tptd::mesh_interval`] (method `ctd`):
//! * a spherical shell `{r1 <= |x - c| <= r2}` on an anisotropic, offset and rotated grid, the
//!   outer sphere cutting the box, so the boundary has all three labels alpha, beta and box;
//! * a slab `{alpha <= x <= beta}` of the linear field `f = x` on an axis-aligned grid, where
//!   linear (C3D4) heat conduction must reproduce `T = x` exactly.
//!
//! Readers: meshio and VTK (via `tests/py/check_mesh.py`), `gmsh -check` and CalculiX
//! (`ccx`). A missing tool makes the test fail, unless `TPTD_SKIP_EXTERNAL=1`, which turns
//! those tests into no-ops (the same convention as `tests/write_formats.rs`).

mod common;

use std::collections::{BTreeSet, HashMap};
use std::fs;
use std::path::Path;

use common::external::{
    check_mesh_py, dat_temperatures, gmsh_check, gmsh_reads_binary_as_ascii, heat_deck,
    require_ccx, require_gmsh, require_python_with, run_ccx_job, write_file, Format, DECK_TAIL,
};
use tptd::io::atomic::write_atomically;
use tptd::io::inp::write_inp;
use tptd::{mesh_interval, BoundaryLabel, MeshOptions, Method, ScalarGrid, TetMesh};

// ---------------------------------------------------------------------------------------
// Meshes from the mesher
// ---------------------------------------------------------------------------------------

/// Inner and outer radius of the shell.
const R1: f64 = 1.7;
const R2: f64 = 3.8;

/// Bounds of the slab of `f = x` (neither is a grid value `-1.1 + 0.4 i`).
const SLAB_ALPHA: f64 = -0.55;
const SLAB_BETA: f64 = 1.23;

/// Rotation by `angle` about the unit axis `k` (Rodrigues), row-major.
fn rotation(k: [f64; 3], angle: f64) -> [[f64; 3]; 3] {
    let (s, c) = angle.sin_cos();
    let cross = [[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]];
    let mut r = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            let id = if i == j { 1.0 } else { 0.0 };
            r[i][j] = c * id + s * cross[i][j] + (1.0 - c) * k[i] * k[j];
        }
    }
    r
}

/// 12×10×9 grid, spacing (0.7, 1.1, 0.9), offset origin, rotated by 0.7 rad about
/// (1, 2, 2)/3; field = distance from a point slightly off the box centre.
fn shell_grid() -> ScalarGrid {
    let dims = [12, 10, 9];
    let direction = rotation([1.0 / 3.0, 2.0 / 3.0, 2.0 / 3.0], 0.7);
    let mut grid = ScalarGrid::with_geometry(
        dims,
        [0.7, 1.1, 0.9],
        [-2.3, 1.45, 0.6],
        direction,
        vec![0.0; dims[0] * dims[1] * dims[2]],
    )
    .unwrap();
    let mid = grid.to_physical([5.5, 4.5, 4.0]);
    let centre = [mid[0] + 0.31, mid[1] - 0.22, mid[2] + 0.17];
    let values: Vec<f64> = (0..grid.num_vertices())
        .map(|idx| {
            let p = grid.to_physical(grid.vertex_ijk(idx).map(|i| i as f64));
            (0..3)
                .map(|k| (p[k] - centre[k]).powi(2))
                .sum::<f64>()
                .sqrt()
        })
        .collect();
    grid.values = values.into();
    grid
}

fn shell_mesh() -> TetMesh {
    let out = mesh_interval(&shell_grid(), &MeshOptions::new(R1, R2, Method::Ctd)).unwrap();
    check_mesher_output(&out.mesh);
    out.mesh
}

/// 9×6×5 axis-aligned grid at an offset origin with anisotropic spacing, `f = x`.
fn slab_grid() -> ScalarGrid {
    let dims = [9, 6, 5];
    let mut grid = ScalarGrid::with_geometry(
        dims,
        [0.4, 0.3, 0.35],
        [-1.1, 0.2, -0.5],
        tptd::grid::IDENTITY,
        vec![0.0; dims[0] * dims[1] * dims[2]],
    )
    .unwrap();
    let values: Vec<f64> = (0..grid.num_vertices())
        .map(|idx| grid.to_physical(grid.vertex_ijk(idx).map(|i| i as f64))[0])
        .collect();
    grid.values = values.into();
    grid
}

fn slab_mesh() -> TetMesh {
    let opts = MeshOptions::new(SLAB_ALPHA, SLAB_BETA, Method::Ctd);
    let out = mesh_interval(&slab_grid(), &opts).unwrap();
    check_mesher_output(&out.mesh);
    out.mesh
}

/// The invariants the writers rely on, and all three labels present.
fn check_mesher_output(mesh: &TetMesh) {
    assert!(mesh.tets.len() > 100, "{} tets", mesh.tets.len());
    assert_eq!(mesh.values.len(), mesh.points.len());
    assert_eq!(mesh.boundary_labels.len(), mesh.boundary.len());
    for t in 0..mesh.tets.len() {
        assert!(mesh.tet_volume(t) > 0.0, "tet {t}: {}", mesh.tet_volume(t));
    }
    for label in BoundaryLabel::of_levels(2) {
        assert!(
            mesh.boundary_labels.contains(&label),
            "no {} triangles",
            label.name()
        );
    }
}

/// Node ids (0-based) of the triangles labelled `label`.
fn label_nodes(mesh: &TetMesh, label: BoundaryLabel) -> BTreeSet<usize> {
    mesh.boundary
        .iter()
        .zip(&mesh.boundary_labels)
        .filter(|&(_, &l)| l == label)
        .flat_map(|(t, _)| t.map(|v| v as usize))
        .collect()
}

// ---------------------------------------------------------------------------------------
// meshio and VTK
// ---------------------------------------------------------------------------------------

/// Writes the shell mesh in `format` and runs `check_mesh.py reader format` on it: point and
/// tet counts, coordinates, connectivity, `f`, physical groups / node and element sets, and
/// (meshio) positive volumes computed by numpy from what was read.
fn python_check(reader: &str, format: Format) {
    if !require_python_with(reader) {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let mesh = shell_mesh();
    // ask for `.inp` coordinates to 1e-12 (relative) and for a positive numpy volume of every
    // tet as read
    let extra = [
        ("coord_rtol", serde_json::json!(1e-12)),
        ("positive_volumes", serde_json::json!(true)),
    ];
    let out = check_mesh_py(reader, format, &mesh, dir.path(), "shell", &extra);
    let want = format!("{} points", mesh.points.len());
    assert!(out.contains(&want), "{out}");
    eprint!("{out}");
}

#[test]
fn meshio_reads_mesher_msh41() {
    python_check("meshio", Format::Msh41);
}

#[test]
fn meshio_reads_mesher_binary_msh41() {
    python_check("meshio", Format::Msh41Binary);
}

#[test]
fn meshio_reads_mesher_msh22() {
    python_check("meshio", Format::Msh22);
}

#[test]
fn meshio_reads_mesher_inp() {
    python_check("meshio", Format::Inp);
}

#[test]
fn meshio_reads_mesher_vtu() {
    python_check("meshio", Format::Vtu);
}

#[test]
fn vtk_reads_mesher_vtu() {
    python_check("vtk", Format::Vtu);
}

// ---------------------------------------------------------------------------------------
// gmsh
// ---------------------------------------------------------------------------------------

#[test]
fn gmsh_checks_mesher_msh() {
    if !require_gmsh() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let mesh = shell_mesh();
    for format in [Format::Msh41, Format::Msh22] {
        let path = write_file(&mesh, format, dir.path(), "shell");
        gmsh_check(&path, &mesh);
    }
}

/// The shell (groups alpha, beta and box) in binary `.msh` 4.1: gmsh reads the mesh, the
/// groups and `f` exactly as from the ASCII file.
#[test]
fn gmsh_reads_mesher_binary_msh_as_ascii() {
    if !require_gmsh() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    gmsh_reads_binary_as_ascii(&shell_mesh(), dir.path(), "shell");
}

// ---------------------------------------------------------------------------------------
// CalculiX
// ---------------------------------------------------------------------------------------

/// Runs `ccx` on `deck` (stem `job`) in `dir`; returns the temperatures of the `.dat`, one
/// per node of `mesh`.
fn run_ccx(dir: &Path, job: &str, deck: &str, mesh: &TetMesh) -> HashMap<usize, f64> {
    run_ccx_job(dir, job, deck, &["jacobian"]);
    let temps = dat_temperatures(&fs::read_to_string(dir.join(format!("{job}.dat"))).unwrap());
    assert_eq!(temps.len(), mesh.points.len(), "{job}: temperatures");
    for id in 1..=mesh.points.len() {
        assert!(
            temps.get(&id).is_some_and(|t| t.is_finite()),
            "{job}: node {id} has no finite temperature"
        );
    }
    temps
}

/// Shell, T = 0 on ALPHA and T = 1 on BETA, no source: the fixed values are kept and every
/// node lies in [0, 1] (maximum principle).
#[test]
fn calculix_heat_on_shell_obeys_maximum_principle() {
    if !require_ccx() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let mesh = shell_mesh();
    write_atomically(&dir.path().join("mesh.inp"), |w| write_inp(&mesh, w)).unwrap();
    let deck = heat_deck(&[("ALPHA", 0.0), ("BETA", 1.0)]) + DECK_TAIL;
    let temps = run_ccx(dir.path(), "shell", &deck, &mesh);
    let alpha = label_nodes(&mesh, BoundaryLabel::ALPHA);
    let beta = label_nodes(&mesh, BoundaryLabel::BETA);
    assert!(alpha.is_disjoint(&beta));
    let mut intermediate = 0;
    for (&id, &t) in &temps {
        // (the .dat holds 7 significant digits: the bounds are checked to that precision)
        assert!(
            (0.0..=1.0).contains(&t),
            "node {id}: T = {t} outside [0, 1]"
        );
        if alpha.contains(&(id - 1)) {
            assert_eq!(t, 0.0, "ALPHA node {id}");
        } else if beta.contains(&(id - 1)) {
            assert_eq!(t, 1.0, "BETA node {id}");
        } else if 0.1 < t && t < 0.9 {
            intermediate += 1;
        }
    }
    // the free nodes really take intermediate values (the solve did something)
    assert!(intermediate > 10, "{intermediate} nodes with 0.1 < T < 0.9");
}

/// Slab of `f = x`, T = alpha on ALPHA and T = beta on BETA, box insulated: the exact
/// solution T = x is linear, so linear tets reproduce it at every node.
#[test]
fn calculix_heat_on_linear_slab_is_exact() {
    if !require_ccx() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let mesh = slab_mesh();
    write_atomically(&dir.path().join("mesh.inp"), |w| write_inp(&mesh, w)).unwrap();
    let deck = heat_deck(&[("ALPHA", SLAB_ALPHA), ("BETA", SLAB_BETA)]) + DECK_TAIL;
    let temps = run_ccx(dir.path(), "slab", &deck, &mesh);
    for (&id, &t) in &temps {
        let x = mesh.points[id - 1][0];
        assert!(
            (t - x).abs() < 1e-6,
            "node {id} at x = {x}: T = {t}, expected {x}"
        );
    }
}

/// Slab of `f = x`, T = alpha on ALPHA and a uniform flux q into the faces of the `*SURFACE`
/// BETA (exercising the element-face numbering on mesher output): exact T = alpha +
/// q (x - alpha).
#[test]
fn calculix_surface_flux_on_linear_slab_is_exact() {
    if !require_ccx() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let mesh = slab_mesh();
    let path = dir.path().join("mesh.inp");
    write_atomically(&path, |w| write_inp(&mesh, w)).unwrap();
    let text = fs::read_to_string(&path).unwrap();
    let faces: Vec<&str> = text
        .split("*SURFACE, NAME=BETA, TYPE=ELEMENT\n")
        .nth(1)
        .expect("no *SURFACE BETA")
        .lines()
        .take_while(|l| !l.starts_with('*'))
        .collect();
    assert_eq!(
        faces.len(),
        mesh.boundary_labels
            .iter()
            .filter(|&&l| l == BoundaryLabel::BETA)
            .count()
    );
    let q = 0.75;
    let mut deck = heat_deck(&[("ALPHA", SLAB_ALPHA)]) + "*DFLUX\n";
    for face in faces {
        deck.push_str(&format!("{face}, {q}\n"));
    }
    deck.push_str(DECK_TAIL);
    let temps = run_ccx(dir.path(), "flux", &deck, &mesh);
    for (&id, &t) in &temps {
        let x = mesh.points[id - 1][0];
        let want = SLAB_ALPHA + q * (x - SLAB_ALPHA);
        assert!(
            (t - want).abs() < 1e-6,
            "node {id} at x = {x}: T = {t}, expected {want}"
        );
    }
}
