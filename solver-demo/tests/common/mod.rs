//! Meshes for the solver tests: `tptd` meshes of distance fields, written to a file and read
//! back through the library's readers, as `solver-demo` sees them.
#![allow(dead_code)]

use std::path::Path;

use tptd::grid::IDENTITY;
use tptd::io::inp::write_inp;
use tptd::io::msh::{write_msh, MshVersion};
use tptd::io::{read_mesh, MeshFile};
use tptd::{mesh_interval, MeshOptions, Method, ScalarGrid, TetMesh};

/// A grid with `n[k]` vertices along axis `k` spanning `[lo[k], hi[k]]`, sampling `f`.
pub fn grid(n: [usize; 3], lo: [f64; 3], hi: [f64; 3], f: impl Fn([f64; 3]) -> f64) -> ScalarGrid {
    let h: [f64; 3] = std::array::from_fn(|k| (hi[k] - lo[k]) / (n[k] - 1) as f64);
    let mut values = Vec::with_capacity(n[0] * n[1] * n[2]);
    for k in 0..n[2] {
        for j in 0..n[1] {
            for i in 0..n[0] {
                let p = [i, j, k];
                values.push(f(std::array::from_fn(|a| lo[a] + p[a] as f64 * h[a])));
            }
        }
    }
    ScalarGrid::with_geometry(n, h, lo, IDENTITY, values).unwrap()
}

/// Distance to the origin.
pub fn radius(p: [f64; 3]) -> f64 {
    (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt()
}

/// Distance to the circle of radius 1 in the xy-plane (a torus is `<= r`).
pub fn torus_distance(p: [f64; 3]) -> f64 {
    let rho = (p[0] * p[0] + p[1] * p[1]).sqrt() - 1.0;
    (rho * rho + p[2] * p[2]).sqrt()
}

/// Shift of the grids against the shapes, so that no grid vertex lies exactly on a level
/// (see the note in `solver-demo`'s tests: a vertex exactly on the level can leave a node
/// without a tetrahedron).
const SHIFT: f64 = 0.0123;

/// The grid of `cells` cells per axis over `[-1.2, 1.2]^3` (shifted) for the unit ball.
pub fn ball_grid(cells: usize) -> ScalarGrid {
    grid([cells + 1; 3], [-1.2 + SHIFT; 3], [1.2 + SHIFT; 3], radius)
}

/// The torus (tube radius 0.45) meshed on a grid of `cells` cells along x.
pub fn torus_grid(cells: usize) -> ScalarGrid {
    let nz = cells * 5 / 16;
    grid(
        [cells + 1, cells + 1, nz + 1],
        [-1.6 + SHIFT, -1.6 + SHIFT, -0.5 + SHIFT],
        [1.6 + SHIFT, 1.6 + SHIFT, 0.5 + SHIFT],
        torus_distance,
    )
}

/// `{alpha <= f <= beta}` of `grid` (ctd).
pub fn mesh(grid: &ScalarGrid, alpha: f64, beta: f64) -> TetMesh {
    mesh_interval(grid, &MeshOptions::new(alpha, beta, Method::Ctd))
        .unwrap()
        .mesh
}

/// Writes `mesh` to `dir/name` (.msh 4.1 or .inp by extension) and reads it back.
pub fn through_file(mesh: &TetMesh, dir: &Path, name: &str) -> MeshFile {
    let path = dir.join(name);
    let mut buf = Vec::new();
    if name.ends_with(".inp") {
        write_inp(mesh, &mut buf).unwrap();
    } else {
        write_msh(mesh, &mut buf, MshVersion::V41).unwrap();
    }
    std::fs::write(&path, buf).unwrap();
    read_mesh(&path).unwrap()
}

/// Convergence orders `log(e_i / e_i+1) / log(h_i / h_i+1)`.
pub fn orders(h: &[f64], e: &[f64]) -> Vec<f64> {
    (1..e.len())
        .map(|i| (e[i - 1] / e[i]).ln() / (h[i - 1] / h[i]).ln())
        .collect()
}
