//! The manufactured solution `u = sin(2x) cos(y) exp(z/2)`: `-div(k grad u) = 4.75 k u` for
//! a constant `k`, and the L2 and H1-seminorm errors of a P1 solution against it.

use rayon::prelude::*;
use tptd::TetMesh;

use crate::assemble::{corners, dot3, quad_points, tet_geometry, QUAD_A, QUAD_B};

/// `-laplace(u) = LAPLACE_FACTOR u`.
pub const LAPLACE_FACTOR: f64 = 4.75;

/// The exact solution.
pub fn exact(p: [f64; 3]) -> f64 {
    (2.0 * p[0]).sin() * p[1].cos() * (0.5 * p[2]).exp()
}

/// Its gradient.
pub fn exact_grad(p: [f64; 3]) -> [f64; 3] {
    let (s, c) = (2.0 * p[0]).sin_cos();
    let (sy, cy) = p[1].sin_cos();
    let e = (0.5 * p[2]).exp();
    [2.0 * c * cy * e, -s * sy * e, 0.5 * s * cy * e]
}

/// L2 norm and H1 seminorm of an error.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Errors {
    /// `|u - u_h|_L2`.
    pub l2: f64,
    /// `|grad(u - u_h)|_L2`.
    pub h1: f64,
}

/// The errors of the nodal values `uh` against `u` (gradient `grad`), with 4-point
/// quadrature per tet; summed in fixed blocks, so independent of the thread count.
pub fn errors(
    mesh: &TetMesh,
    uh: &[f64],
    u: &(dyn Fn([f64; 3]) -> f64 + Sync),
    grad: &(dyn Fn([f64; 3]) -> [f64; 3] + Sync),
) -> Errors {
    let per_tet = |t: usize| -> [f64; 2] {
        let p = corners(mesh, t);
        let Some(g) = tet_geometry(p) else {
            return [0.0; 2];
        };
        let nodes = mesh.tets[t].map(|i| uh[i as usize]);
        let gh: [f64; 3] = std::array::from_fn(|k| (0..4).map(|a| nodes[a] * g.grad[a][k]).sum());
        let mut e = [0.0; 2];
        for (q, x) in quad_points(&p).into_iter().enumerate() {
            let vh: f64 = (0..4)
                .map(|a| nodes[a] * if a == q { QUAD_A } else { QUAD_B })
                .sum();
            let d = u(x) - vh;
            let gx = grad(x);
            let dg = [gx[0] - gh[0], gx[1] - gh[1], gx[2] - gh[2]];
            e[0] += g.volume / 4.0 * d * d;
            e[1] += g.volume / 4.0 * dot3(dg, dg);
        }
        e
    };
    let partial: Vec<[f64; 2]> = (0..mesh.tets.len())
        .collect::<Vec<_>>()
        .par_chunks(4096)
        .map(|c| {
            c.iter().fold([0.0; 2], |s, &t| {
                let e = per_tet(t);
                [s[0] + e[0], s[1] + e[1]]
            })
        })
        .collect();
    let s = partial
        .iter()
        .fold([0.0; 2], |s, e| [s[0] + e[0], s[1] + e[1]]);
    Errors {
        l2: s[0].sqrt(),
        h1: s[1].sqrt(),
    }
}
