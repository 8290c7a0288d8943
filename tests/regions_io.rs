//! Writing meshes of several regions (`MeshOptions::levels`): every format gives the same
//! bytes from memory and streamed through a `SpilledMesh` (also when the interfaces lie on
//! the planes between slabs); the crate's readers find the regions of the `.msh` files
//! (volume groups `region1`, … per tet) and read the `.inp`; meshio finds the region of every
//! tet (`gmsh:physical` = region + 1 in the `.msh` files, cell data `region` in the `.vtu`);
//! gmsh checks the `.msh` files; CalculiX runs a deck with one material per region on the
//! `.inp`, fixing temperatures on an interface's node set and loading an interface surface.

mod common;

use std::fs;
use std::path::Path;
use std::process::Command;

use common::external::{python, require_ccx, require_gmsh, require_python_with, run, run_ccx_job};
use tptd::io::{
    read_mesh, spill_for_levels, write_mesh, write_spilled_pending, MeshFile, WriteOptions,
};
use tptd::{mesh_interval, mesh_interval_streamed, MeshOptions, ScalarGrid, TetMesh};

/// Distance from a point near the centre of an `n³` grid.
fn sphere_distance(n: usize) -> ScalarGrid {
    let c = [7.3, 7.6, 7.45];
    let mut v = Vec::with_capacity(n * n * n);
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let p = [i as f64, j as f64, k as f64];
                v.push((0..3).map(|a| (p[a] - c[a]).powi(2)).sum::<f64>().sqrt());
            }
        }
    }
    ScalarGrid::new([n; 3], v).unwrap()
}

/// A ball, a shell around it and the rest of the box: three regions, interfaces on the
/// levels 2.7 and 5.2, the box around the outer one.
const LEVELS: [f64; 4] = [f64::NEG_INFINITY, 2.7, 5.2, f64::INFINITY];

fn mesh_of(grid: &ScalarGrid, levels: &[f64]) -> TetMesh {
    let mesh = mesh_interval(grid, &MeshOptions::default().levels(levels))
        .unwrap()
        .mesh;
    assert_eq!(mesh.regions.levels, levels.len());
    assert!(!mesh.regions.interfaces.is_empty());
    mesh
}

/// Streams the mesh of `levels` into `dir/name` through a spilled mesh; returns the bytes.
fn streamed(grid: &ScalarGrid, opts: &MeshOptions, n: usize, path: &Path, w: &WriteOptions) {
    let mut spill = spill_for_levels(path, n, Vec::new()).unwrap();
    mesh_interval_streamed(grid, opts, &|_, _| {}, &mut spill).unwrap();
    write_spilled_pending(path, &mut spill, w)
        .unwrap()
        .commit()
        .unwrap();
}

/// Asserts that every format streamed equals the in-memory bytes for `grid` and `levels`.
fn streamed_equals_in_memory(grid: &ScalarGrid, levels: &[f64]) {
    let dir = tempfile::tempdir().unwrap();
    let mesh = mesh_of(grid, levels);
    for (name, w) in common::output::mesh_outputs() {
        let mem = dir.path().join(format!("mem-{name}"));
        write_mesh(&mem, &mesh, &w).unwrap();
        let want = fs::read(&mem).unwrap();
        for (threads, slabs) in [(1, 1), (2, 3), (2, 0)] {
            let opts = MeshOptions::default().levels(levels).threads(Some(threads));
            let opts = MeshOptions {
                slabs_in_flight: slabs,
                ..opts
            };
            let path = dir.path().join(name);
            streamed(grid, &opts, levels.len(), &path, &w);
            let got = fs::read(&path).unwrap();
            assert!(got == want, "{name}, {threads} threads, {slabs} slabs");
        }
    }
    let left: Vec<_> = fs::read_dir(dir.path()).unwrap().collect();
    assert_eq!(
        left.len(),
        2 * common::output::mesh_outputs().len(),
        "spill files left behind"
    );
}

#[test]
fn streamed_output_equals_the_in_memory_output() {
    streamed_equals_in_memory(&sphere_distance(16), &LEVELS);
    streamed_equals_in_memory(&sphere_distance(16), &LEVELS[..3]);
}

/// f = z: the interfaces lie on grid planes, between two slabs, where the tets above an
/// interface are in another chunk than the triangle.
#[test]
fn interfaces_between_slabs_have_their_faces_above() {
    let n = [6, 5, 12];
    let v = (0..n[0] * n[1] * n[2])
        .map(|i| (i / (n[0] * n[1])) as f64)
        .collect::<Vec<_>>();
    let grid = ScalarGrid::new(n, v).unwrap();
    streamed_equals_in_memory(&grid, &[f64::NEG_INFINITY, 3.0, 6.0, 8.5]);
}

/// The written files and the mesh they hold, in `dir`.
fn write_all(dir: &Path) -> TetMesh {
    let mesh = mesh_of(&sphere_distance(16), &LEVELS);
    for (name, w) in common::output::mesh_outputs() {
        write_mesh(&dir.join(name), &mesh, &w).unwrap();
    }
    mesh
}

#[test]
fn the_readers_find_the_regions() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = write_all(dir.path());
    let names: Vec<String> = (mesh.regions.tets.iter())
        .map(|&r| format!("region{}", r + 1))
        .collect();
    let by_tet = |f: &MeshFile| -> Vec<(Vec<u32>, String)> {
        let mut x: Vec<_> = (f.mesh.tets.iter().zip(&f.tet_region))
            .map(|(t, &r)| (t.to_vec(), f.regions[r as usize].clone()))
            .collect();
        x.sort_unstable();
        x
    };
    let mut want: Vec<_> = (mesh.tets.iter().zip(&names))
        .map(|(t, n)| (t.to_vec(), n.clone()))
        .collect();
    want.sort_unstable();
    for name in ["m41.msh", "m22.msh", "m41b.msh"] {
        let f = read_mesh(&dir.path().join(name)).unwrap();
        assert_eq!(f.mesh.tets.len(), mesh.tets.len(), "{name}");
        let mut regions = f.regions.clone();
        regions.sort();
        assert_eq!(regions, ["region1", "region2", "region3"], "{name}");
        assert!(by_tet(&f) == want, "{name}: the region of each tet");
        let groups: Vec<&str> = f.node_groups.iter().map(|g| g.name.as_str()).collect();
        assert_eq!(groups, ["level2", "level3", "box"], "{name}");
    }
    let f = read_mesh(&dir.path().join("m.inp")).unwrap();
    assert_eq!(f.mesh.tets, mesh.tets);
    let inp = fs::read_to_string(dir.path().join("m.inp")).unwrap();
    for key in [
        "*ELSET, ELSET=REGION1\n",
        "*ELSET, ELSET=REGION3\n",
        "*NSET, NSET=LEVEL2\n",
        "*SURFACE, NAME=LEVEL2_BELOW, TYPE=ELEMENT\n",
        "*SURFACE, NAME=LEVEL3_ABOVE, TYPE=ELEMENT\n",
        "*SURFACE, NAME=BOX, TYPE=ELEMENT\n",
    ] {
        assert!(inp.contains(key), "no {key:?} in the .inp");
    }
}

const MESHIO_SCRIPT: &str = r#"
import json, sys
import meshio
want = json.load(open(sys.argv[1]))
tets = [tuple(t) for t in want["tets"]]
regions = want["regions"]
expect = {t: r + 1 for t, r in zip(tets, regions)}
for name in ["m41.msh", "m22.msh", "m41b.msh"]:
    m = meshio.read(sys.argv[2] + "/" + name)
    got = {}
    for block, phys in zip(m.cells, m.cell_data["gmsh:physical"]):
        if block.type == "tetra":
            for cell, p in zip(block.data.tolist(), phys.tolist()):
                got[tuple(cell)] = p
    assert got == expect, name
m = meshio.read(sys.argv[2] + "/b64.vtu")
assert m.cell_data["region"][0].tolist() == regions, "vtu"
print("ok")
"#;

#[test]
fn meshio_reads_the_regions() {
    if !require_python_with("meshio") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let mesh = write_all(dir.path());
    let want = serde_json::json!({"tets": mesh.tets, "regions": mesh.regions.tets});
    let exp = dir.path().join("want.json");
    fs::write(&exp, want.to_string()).unwrap();
    let (ok, out) = run(Command::new(python())
        .arg("-c")
        .arg(MESHIO_SCRIPT)
        .arg(&exp)
        .arg(dir.path()));
    assert!(ok && out.contains("ok"), "meshio:\n{out}");
}

#[test]
fn gmsh_checks_the_msh_files() {
    if !require_gmsh() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let mesh = write_all(dir.path());
    let elements = mesh.tets.len() + mesh.boundary.len() + mesh.regions.interfaces.len();
    for name in ["m41.msh", "m22.msh", "m41b.msh"] {
        let path = dir.path().join(name);
        let (ok, out) = run(Command::new("gmsh").arg(&path).args(["-check", "-nopopup"]));
        assert!(ok && !out.contains("Error"), "gmsh -check {name}:\n{out}");
        for want in [
            format!("{} nodes", mesh.points.len()),
            format!("{elements} elements"),
        ] {
            assert!(
                out.contains(&want),
                "gmsh -check {name}: no {want:?} in\n{out}"
            );
        }
        let copy = dir.path().join(format!("gmsh-{name}"));
        let (ok, out) = run(Command::new("gmsh")
            .arg(&path)
            .arg("-0")
            .arg("-o")
            .arg(&copy)
            .arg("-nopopup"));
        assert!(ok && !out.contains("Error"), "gmsh -0 {name}:\n{out}");
    }
}

/// Three materials, one per region; the interface at level 2 held at 0, the box at 1, a
/// flux on the faces below the interface at level 3.
const DECK: &str = "*INCLUDE, INPUT=mesh.inp\n\
    *MATERIAL, NAME=A\n*CONDUCTIVITY\n1.\n\
    *MATERIAL, NAME=B\n*CONDUCTIVITY\n5.\n\
    *MATERIAL, NAME=C\n*CONDUCTIVITY\n2.\n\
    *SOLID SECTION, ELSET=REGION1, MATERIAL=A\n\
    *SOLID SECTION, ELSET=REGION2, MATERIAL=B\n\
    *SOLID SECTION, ELSET=REGION3, MATERIAL=C\n\
    *STEP\n*HEAT TRANSFER, STEADY STATE\n\
    *BOUNDARY\nLEVEL2, 11, 11, 0.\nBOX, 11, 11, 1.\n\
    *DFLUX\nLEVEL3_BELOW, S, 0.5\n\
    *NODE PRINT, NSET=NALL\nNT\n*END STEP\n";

#[test]
fn calculix_runs_a_deck_with_a_material_per_region() {
    if !require_ccx() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let mesh = mesh_of(&sphere_distance(16), &LEVELS);
    write_mesh(
        &dir.path().join("mesh.inp"),
        &mesh,
        &WriteOptions::default(),
    )
    .unwrap();
    run_ccx_job(dir.path(), "regions", DECK, &["jacobian"]);
    let dat = fs::read_to_string(dir.path().join("regions.dat")).unwrap();
    assert!(dat.contains("temperatures"), "no temperatures in the .dat");
}
