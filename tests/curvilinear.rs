//! Curvilinear grids: `.vts` in every encoding VTK writes (written by VTK's own writer in
//! tests/py/write_curvilinear.py) and Plot3D twins read to the same grid; a smoothly warped
//! and an exactly affine grid mesh to valid (positive, conforming, outward) tets with the
//! Betti numbers of the same values on the uniform grid; on the affine grid the mesh is the
//! uniform mesh mapped by the affine map; folded or left-handed grids are handled.

mod common;

use std::path::Path;
use std::process::Command;

use common::external::{python, require_python_with, run};
use common::invariants::mesh_errors;
use tptd::curvilinear::{map_point, mesh_curvilinear};
use tptd::io::plot3d::read_plot3d;
use tptd::io::vts::read_vts;
use tptd::io::{read_curvilinear, SurfaceFormat, WriteOptions};
use tptd::topology::betti;
use tptd::{
    level_surface, mesh_interval, CurvilinearError, CurvilinearGrid, MeshOptions, Method,
    ScalarGrid, SurfaceOptions,
};

const DIMS: [usize; 3] = [9, 8, 7];
const NAMES: [&str; 5] = [
    "density",
    "momentum_x",
    "momentum_y",
    "momentum_z",
    "energy",
];
const ALPHA: f64 = 0.1;
const BETA: f64 = 0.8;

fn lattice() -> impl Iterator<Item = [f64; 3]> {
    let [nx, ny, nz] = DIMS;
    (0..nz).flat_map(move |k| {
        (0..ny).flat_map(move |j| (0..nx).map(move |i| [i as f64, j as f64, k as f64]))
    })
}

/// A field with tunnels and several components on the lattice, and four more.
fn fields() -> Vec<Vec<f64>> {
    let f = |p: [f64; 3], s: f64| {
        (0.9 * p[0] + s).sin() * (0.8 * p[1]).cos() + 0.5 * (0.7 * p[2] + 0.3 * p[0]).sin()
    };
    (0..5)
        .map(|s| lattice().map(|p| f(p, s as f64)).collect())
        .collect()
}

fn warped(p: [f64; 3]) -> [f64; 3] {
    [
        0.5 * p[0] + 0.06 * (0.7 * p[1] + 0.3 * p[2]).sin(),
        0.4 * p[1] + 0.05 * (0.5 * p[0] + 0.4 * p[2]).sin() + 0.02 * p[0],
        0.6 * p[2] + 0.05 * (0.6 * p[0] + 0.5 * p[1]).sin(),
    ]
}

const A: [[f64; 3]; 3] = [[0.7, 0.2, -0.1], [0.1, 1.3, 0.2], [-0.2, 0.1, 0.9]];
const B: [f64; 3] = [10.0, -3.0, 2.5];

fn affine(p: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|r| B[r] + A[r][0] * p[0] + A[r][1] * p[1] + A[r][2] * p[2])
}

fn grid(map: fn([f64; 3]) -> [f64; 3]) -> CurvilinearGrid {
    CurvilinearGrid::new(DIMS, fields().remove(0), lattice().map(map).collect()).unwrap()
}

/// Writes the grid `map` gives with VTK and as Plot3D into `dir`.
fn write_files(dir: &Path, map: fn([f64; 3]) -> [f64; 3]) {
    let fs = fields();
    let spec = serde_json::json!({
        "dims": DIMS,
        "points": lattice().map(map).collect::<Vec<_>>(),
        "order": NAMES,
        "fields": NAMES.iter().zip(&fs).map(|(n, v)| (n.to_string(), serde_json::json!(v)))
            .collect::<serde_json::Map<_, _>>(),
    });
    let json = dir.join("spec.json");
    std::fs::write(&json, spec.to_string()).unwrap();
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/py/write_curvilinear.py");
    let (ok, out) = run(Command::new(python()).arg(script).arg(&json).arg(dir));
    assert!(ok, "write_curvilinear.py failed:\n{out}");
}

const MODES: [&str; 9] = [
    "ascii",
    "binary",
    "binary_zlib",
    "binary_zlib64",
    "appended_raw",
    "appended_raw_zlib",
    "appended_raw64_be",
    "appended_b64",
    "appended_b64_zlib",
];

#[test]
fn vts_in_every_encoding_and_plot3d_twins_read_the_same_grid() {
    if !require_python_with("vtk") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    write_files(dir.path(), warped);
    let want = grid(warped);
    let fs = fields();
    for mode in MODES {
        let path = dir.path().join(format!("{mode}.vts"));
        let g = read_vts(&path, None).unwrap_or_else(|e| panic!("{mode}: {e}"));
        assert_eq!(g, want, "{mode}: default field");
        let g = read_vts(&path, Some("energy")).unwrap();
        assert_eq!(
            g.values.values.to_f64_vec(),
            fs[4],
            "{mode}: --field energy"
        );
    }
    let e = read_vts(&dir.path().join("binary.vts"), Some("pressure")).unwrap_err();
    assert!(e.to_string().contains("density, momentum_x"), "{e}");
    // the Float32 twins: .vts, blunt-fin style .xyz/.q, and records + planes + IBLANK .xyz/.f
    for (k, name) in NAMES.iter().enumerate() {
        let vts = read_vts(&dir.path().join("twin.vts"), Some(name)).unwrap();
        let q = read_plot3d(&dir.path().join("twin.xyz"), None, Some(name)).unwrap();
        assert_eq!(q, vts, "{name}: twin.xyz + twin.q");
        let by_number = read_curvilinear(
            &dir.path().join("twin.xyz"),
            None,
            Some(&(k + 1).to_string()),
        );
        assert_eq!(by_number.unwrap(), vts);
        if k < 2 {
            let f = dir.path().join("rec.f");
            let r = read_plot3d(
                &dir.path().join("rec.xyz"),
                Some(&f),
                Some(&format!("f{}", k + 1)),
            );
            assert_eq!(r.unwrap(), vts, "{name}: rec.xyz + rec.f");
        }
        let single = vts.values.values.iter().zip(&fs[k]);
        assert!(single.into_iter().all(|(a, b)| a == f64::from(*b as f32)));
    }
    // blunt-fin naming: the solution file as `bluntfinq.bin`, read as a .q by its content
    let bin = dir.path().join("bluntfinq.bin");
    std::fs::copy(dir.path().join("twin.q"), &bin).unwrap();
    let fin = read_plot3d(&dir.path().join("twin.xyz"), Some(&bin), Some("energy")).unwrap();
    assert_eq!(
        fin,
        read_vts(&dir.path().join("twin.vts"), Some("energy")).unwrap()
    );
    damaged_files_give_errors(dir.path());
}

/// Truncated and corrupted copies of every file: an error naming the file, never a panic.
fn damaged_files_give_errors(dir: &Path) {
    let bad = dir.join("bad");
    std::fs::create_dir(&bad).unwrap();
    let mut rng = common::Rng::new(5);
    let names: Vec<String> = MODES
        .iter()
        .map(|m| format!("{m}.vts"))
        .chain([
            "twin.xyz".into(),
            "rec.xyz".into(),
            "twin.q".into(),
            "rec.f".into(),
        ])
        .collect();
    for name in &names {
        let orig = std::fs::read(dir.join(name)).unwrap();
        for round in 0..12 {
            let mut b = orig.clone();
            if round % 2 == 0 {
                b.truncate(rng.usize(0, orig.len() - 1));
            } else {
                for _ in 0..4 {
                    let i = rng.usize(0, b.len() - 1);
                    b[i] = rng.usize(0, 255) as u8;
                }
            }
            for f in ["twin.xyz", "twin.q", "rec.xyz", "rec.f"] {
                std::fs::copy(dir.join(f), bad.join(f)).unwrap();
            }
            let target = bad.join(name);
            std::fs::write(&target, &b).unwrap();
            let input = if name.ends_with(".vts") || name.ends_with(".xyz") {
                target.clone()
            } else {
                bad.join(if name.starts_with("twin") {
                    "twin.xyz"
                } else {
                    "rec.xyz"
                })
            };
            let function = bad.join(if name.starts_with("rec") {
                "rec.f"
            } else {
                "twin.q"
            });
            let f = input
                .to_string_lossy()
                .ends_with(".xyz")
                .then_some(function.as_path());
            if let Err(e) = read_curvilinear(&input, f, None) {
                let msg = e.to_string();
                assert!(msg.contains("bad/") && !msg.contains('\n'), "{msg}");
            }
        }
    }
}

#[test]
fn warped_and_affine_vts_mesh_like_the_uniform_grid() {
    if !require_python_with("vtk") {
        return;
    }
    let uniform = ScalarGrid::new(DIMS, fields().remove(0)).unwrap();
    for method in [Method::Ctd, Method::Tptd] {
        let opts = MeshOptions::new(ALPHA, BETA, method);
        let flat = mesh_interval(&uniform, &opts).unwrap().mesh;
        let b = betti(&flat);
        assert!(b[1] >= 1, "the test field should have a tunnel: {b:?}");
        for (name, map) in [("warped", warped as fn(_) -> _), ("affine", affine)] {
            let dir = tempfile::tempdir().unwrap();
            write_files(dir.path(), map);
            let g = read_vts(&dir.path().join("appended_raw_zlib.vts"), None).unwrap();
            let m = mesh_curvilinear(&g, &opts).unwrap().mesh;
            let errs = mesh_errors(&m);
            assert!(errs.is_empty(), "{name} {method:?}: {errs:?}");
            assert_eq!(betti(&m), b, "{name} {method:?}");
            assert_eq!(
                (m.tets.len(), m.boundary.len()),
                (flat.tets.len(), flat.boundary.len())
            );
            if name == "affine" {
                let scale = m
                    .points
                    .iter()
                    .flatten()
                    .fold(0.0f64, |s, x| s.max(x.abs()));
                for (p, q) in m.points.iter().zip(&flat.points) {
                    let want = affine(*q);
                    for a in 0..3 {
                        assert!((p[a] - want[a]).abs() <= 1e-12 * scale, "{p:?} vs {want:?}");
                    }
                }
                assert_eq!(m.tets, flat.tets);
            }
            // every output works: the surface writers on a mapped mesh
            let s = level_surface(&m, &SurfaceOptions::default());
            let mut buf = Vec::new();
            SurfaceFormat::Ply
                .write(&s, &mut buf, &WriteOptions::default())
                .unwrap();
        }
    }
}

#[test]
fn mirrored_grid_keeps_tets_positive_and_folded_cells_are_named() {
    let mirror = |p: [f64; 3]| [-p[0], p[1], p[2]];
    let g =
        CurvilinearGrid::new(DIMS, fields().remove(0), lattice().map(mirror).collect()).unwrap();
    let m = mesh_curvilinear(&g, &MeshOptions::new(ALPHA, BETA, Method::Ctd))
        .unwrap()
        .mesh;
    assert!(mesh_errors(&m).is_empty());
    // fold cell (3, 2, 1): pull vertex (4, 3, 2) back past its cell's opposite corner
    let mut pts: Vec<[f64; 3]> = lattice().collect();
    let v = 4 + DIMS[0] * (3 + DIMS[1] * 2);
    pts[v] = [2.5, 1.5, 0.5];
    let g = CurvilinearGrid::new(DIMS, fields().remove(0), pts).unwrap();
    let e = mesh_curvilinear(&g, &MeshOptions::new(ALPHA, BETA, Method::Ctd)).unwrap_err();
    assert!(
        matches!(
            e,
            CurvilinearError::FoldedCell {
                cell: [3, 2, 1],
                ..
            }
        ),
        "{e}"
    );
    assert!(e.to_string().contains("cell (3, 2, 1)"), "{e}");
}

/// One cell whose bottom face is bent into a saddle of height `h` (corners 1 and 2 raised).
fn bent_cell(h: f64, values: [f64; 8]) -> CurvilinearGrid {
    let pts: Vec<[f64; 3]> = (0..8)
        .map(|c| {
            let (x, y, z) = ((c & 1) as f64, ((c >> 1) & 1) as f64, (c >> 2) as f64);
            let lift = if z == 0.0 && x != y { h } else { 0.0 };
            [x, y, z + lift]
        })
        .collect();
    CurvilinearGrid::new([2, 2, 2], values.to_vec(), pts).unwrap()
}

#[test]
fn strongly_curved_cells_are_refused_never_inverted() {
    // every corner Jacobian is positive (h < 1), but for large h the straight tets through
    // the bent face's saddle cannot follow it
    let values = [0.0, 1.0, 1.0, 0.0, 1.0, 0.0, 0.0, 1.0];
    let mut refused = Vec::new();
    for h in [0.3, 0.6, 0.8, 0.9, 0.97] {
        for method in [Method::Tptd, Method::Six] {
            let g = bent_cell(h, values);
            assert!(
                !tptd::curvilinear::left_handed(&g).unwrap(),
                "h = {h}: corners are fine"
            );
            match mesh_curvilinear(&g, &MeshOptions::new(0.3, f64::INFINITY, method)) {
                Ok(out) => assert!(mesh_errors(&out.mesh).is_empty(), "h = {h} {method:?}"),
                Err(e) => {
                    assert!(
                        matches!(
                            e,
                            CurvilinearError::InvertedTet {
                                cell: [0, 0, 0],
                                ..
                            }
                        ),
                        "{e}"
                    );
                    assert!(
                        e.to_string()
                            .contains("cell (0, 0, 0) is too strongly curved"),
                        "{e}"
                    );
                    refused.push((h, method));
                }
            }
        }
    }
    println!("refused: {refused:?}");
    assert!(!refused.is_empty() && refused[0].0 > 0.3, "{refused:?}");
    // the map itself: exactly the corners at the corners
    let g = grid(warped);
    assert_eq!(map_point(&g, [3.0, 2.0, 1.0]), warped([3.0, 2.0, 1.0]));
}
