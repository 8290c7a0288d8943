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

/// The manufactured problem, for messages.
pub const PROBLEM: &str = "-div(k grad u) = 4.75 k g with g = sin(2x) cos(y) exp(z/2) and \
                           u = g on the whole boundary (exact solution: u = sin(2x) cos(y) exp(z/2))";

/// L2 norm and H1 seminorm of an error, and the same norms of the exact solution (its scale:
/// `exp(z/2)` grows fast with the coordinates, so absolute errors say little by themselves).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Errors {
    /// `|u - u_h|_L2`.
    pub l2: f64,
    /// `|grad(u - u_h)|_L2`.
    pub h1: f64,
    /// `|u|_L2`.
    pub exact_l2: f64,
    /// `|grad u|_L2`.
    pub exact_h1: f64,
}

impl Errors {
    /// `|u - u_h|_L2 / |u|_L2`.
    pub fn relative_l2(&self) -> f64 {
        self.l2 / self.exact_l2
    }

    /// `|grad(u - u_h)|_L2 / |grad u|_L2`.
    pub fn relative_h1(&self) -> f64 {
        self.h1 / self.exact_h1
    }
}

/// The errors of the nodal values `uh` against `u` (gradient `grad`), and the norms of `u`,
/// with 4-point quadrature per tet; summed in fixed blocks, so independent of the thread
/// count.
pub fn errors(
    mesh: &TetMesh,
    uh: &[f64],
    u: &(dyn Fn([f64; 3]) -> f64 + Sync),
    grad: &(dyn Fn([f64; 3]) -> [f64; 3] + Sync),
) -> Errors {
    let per_tet = |t: usize| -> [f64; 4] {
        let p = corners(mesh, t);
        let Some(g) = tet_geometry(p) else {
            return [0.0; 4];
        };
        let nodes = mesh.tets[t].map(|i| uh[i as usize]);
        let gh: [f64; 3] = std::array::from_fn(|k| (0..4).map(|a| nodes[a] * g.grad[a][k]).sum());
        let mut e = [0.0; 4];
        for (q, x) in quad_points(&p).into_iter().enumerate() {
            let vh: f64 = (0..4)
                .map(|a| nodes[a] * if a == q { QUAD_A } else { QUAD_B })
                .sum();
            let ux = u(x);
            let d = ux - vh;
            let gx = grad(x);
            let dg = [gx[0] - gh[0], gx[1] - gh[1], gx[2] - gh[2]];
            let w = g.volume / 4.0;
            e[0] += w * d * d;
            e[1] += w * dot3(dg, dg);
            e[2] += w * ux * ux;
            e[3] += w * dot3(gx, gx);
        }
        e
    };
    let add = |s: [f64; 4], e: [f64; 4]| std::array::from_fn(|i| s[i] + e[i]);
    let partial: Vec<[f64; 4]> = (0..mesh.tets.len())
        .collect::<Vec<_>>()
        .par_chunks(4096)
        .map(|c| c.iter().fold([0.0; 4], |s, &t| add(s, per_tet(t))))
        .collect();
    let s = partial.iter().fold([0.0; 4], |s, &e| add(s, e));
    Errors {
        l2: s[0].sqrt(),
        h1: s[1].sqrt(),
        exact_l2: s[2].sqrt(),
        exact_h1: s[3].sqrt(),
    }
}
