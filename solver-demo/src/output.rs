//! Output: the element gradient and flux, and the `.vtu` with `u`, `grad_u` and `flux`
//! written through the library's writer ([`tptd::io::vtu::write_vtu_fields`]).

use std::path::Path;

use rayon::prelude::*;
use tptd::io::vtu::{write_vtu_fields, VtuField};
use tptd::io::{write_atomically, WriteError};
use tptd::TetMesh;

use crate::assemble::{corners, tet_geometry};

/// `grad(u_h)` on every tet (zero on a degenerate tet), x, y, z interleaved.
pub fn gradients(mesh: &TetMesh, u: &[f64]) -> Vec<f64> {
    (0..mesh.tets.len())
        .into_par_iter()
        .flat_map_iter(|t| {
            let g = tet_geometry(corners(mesh, t));
            let vals = mesh.tets[t].map(|i| u[i as usize]);
            let grad: [f64; 3] = match g {
                Some(g) => std::array::from_fn(|k| (0..4).map(|a| vals[a] * g.grad[a][k]).sum()),
                None => [0.0; 3],
            };
            grad
        })
        .collect()
}

/// Writes `mesh` with the point field `u` and the cell fields `grad_u` and
/// `flux = -k grad_u` to `path` (atomically).
///
/// # Errors
/// Whatever [`write_atomically`] returns.
pub fn write_solution(path: &Path, mesh: &TetMesh, u: &[f64], k: &[f64]) -> Result<(), WriteError> {
    let grad = gradients(mesh, u);
    let flux: Vec<f64> = grad
        .par_chunks(3)
        .zip(k.par_iter())
        .flat_map_iter(|(g, &k)| [-k * g[0], -k * g[1], -k * g[2]])
        .collect();
    let point = [VtuField {
        name: "u",
        components: 1,
        data: u,
    }];
    let cell = [
        VtuField {
            name: "grad_u",
            components: 3,
            data: &grad,
        },
        VtuField {
            name: "flux",
            components: 3,
            data: &flux,
        },
    ];
    write_atomically(path, |w| write_vtu_fields(mesh, &point, &cell, w))
}
