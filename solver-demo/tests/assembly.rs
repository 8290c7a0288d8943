//! The two assemblies (row-parallel and `sprs` triplets) give the same system, and the
//! assembled matrix has the properties of a P1 stiffness matrix.

mod common;

use common::*;
use solver_demo::assemble::{assemble, assemble_triplets, Problem, Source};
use solver_demo::setup::boundary_nodes;

#[test]
fn row_and_triplet_assembly_agree() {
    let m = mesh(&torus_grid(24), f64::NEG_INFINITY, 0.45);
    let k: Vec<f64> = (0..m.tets.len()).map(|t| 1.0 + (t % 7) as f64).collect();
    let mut g = vec![f64::NAN; m.points.len()];
    for v in boundary_nodes(&m) {
        g[v as usize] = m.points[v as usize][0];
    }
    let f = |p: [f64; 3]| p[1] * p[1] + 1.0;
    for source in [Source::Constant(2.0), Source::Function(&f)] {
        let pb = Problem {
            mesh: &m,
            k: &k,
            source,
            dirichlet: &g,
        };
        let (s1, s2) = (assemble(&pb).unwrap(), assemble_triplets(&pb).unwrap());
        assert_eq!(s1.dof, s2.dof);
        assert_eq!(s1.a.indptr().raw_storage(), s2.a.indptr().raw_storage());
        assert_eq!(s1.a.indices(), s2.a.indices());
        let scale = s1.a.data().iter().fold(0.0f64, |m, x| m.max(x.abs()));
        for (x, y) in s1.a.data().iter().zip(s2.a.data()) {
            assert!((x - y).abs() <= 1e-13 * scale, "{x} vs {y}");
        }
        for (x, y) in s1.b.iter().zip(&s2.b) {
            assert!((x - y).abs() <= 1e-12 * (1.0 + x.abs()), "{x} vs {y}");
        }
        // Symmetric with a positive diagonal.
        let a = &s1.a;
        for r in 0..a.rows() {
            assert!(*a.get(r, r).unwrap() > 0.0);
            for (c, &x) in a.outer_view(r).unwrap().iter() {
                let y = *a.get(c, r).expect("symmetric pattern");
                assert!((x - y).abs() <= 1e-14 * scale, "asymmetric at {r},{c}");
            }
        }
    }
}

#[test]
fn stiffness_rows_sum_to_zero_and_reproduce_linear_functions() {
    // With no Dirichlet node except one, every other row of K sums to zero (constants are in
    // the kernel of the full Laplacian); K applied to a linear function vanishes at interior
    // nodes.
    let m = mesh(&ball_grid(10), f64::NEG_INFINITY, 1.0);
    let k = vec![1.0; m.tets.len()];
    let mut g = vec![f64::NAN; m.points.len()];
    g[0] = 0.0;
    let pb = Problem {
        mesh: &m,
        k: &k,
        source: Source::Constant(0.0),
        dirichlet: &g,
    };
    let s = assemble(&pb).unwrap();
    let on_boundary = boundary_nodes(&m);
    let mut interior = vec![true; m.points.len()];
    for v in on_boundary {
        interior[v as usize] = false;
    }
    let lin: Vec<f64> = m
        .points
        .iter()
        .map(|p| 1.0 + 2.0 * p[0] - p[1] + 0.5 * p[2])
        .collect();
    let x: Vec<f64> = (0..m.points.len())
        .filter(|&v| s.dof[v] != u32::MAX)
        .map(|v| lin[v])
        .collect();
    let mut y = vec![0.0; x.len()];
    solver_demo::pcg::spmv(&s.a, &x, &mut y);
    // The scale of each row's sum: the sum of the magnitudes of its terms.
    let abs_a = s.a.map(|a: &f64| a.abs());
    let abs_x: Vec<f64> = x.iter().map(|v| v.abs()).collect();
    let mut scale = vec![0.0; x.len()];
    solver_demo::pcg::spmv(&abs_a, &abs_x, &mut scale);
    let node_of: Vec<usize> = (0..m.points.len())
        .filter(|&v| s.dof[v] != u32::MAX)
        .collect();
    for (r, &v) in node_of.iter().enumerate() {
        let touches_fixed = m
            .tets
            .iter()
            .any(|t| t.contains(&(v as u32)) && t.contains(&0));
        if interior[v] && !touches_fixed {
            assert!(
                y[r].abs() < 1e-12 * scale[r],
                "K * linear at interior node {v}: {} (row terms {})",
                y[r],
                scale[r]
            );
        }
    }
}

#[test]
fn conductivity_per_region_gives_the_exact_two_layer_solution() {
    // The slab [0, 2] x [0, 1]^2, k = 1 for x < 1 and k = 3 for x > 1, u = 0 at x = 0 and
    // u = 1 at x = 2: flux continuity gives the piecewise-linear u with u(1) = 3/4, which P1
    // reproduces exactly on a mesh that conforms to x = 1.
    use solver_demo::run::{solve, Options};
    use tptd::io::{MeshFile, NodeGroup};
    let g = grid([9, 5, 5], [0.0; 3], [2.0, 1.0, 1.0], |p| p[0]);
    let m = mesh(&g, f64::NEG_INFINITY, f64::INFINITY);
    let side = |x: f64| NodeGroup {
        name: if x == 0.0 {
            "left".into()
        } else {
            "right".into()
        },
        nodes: (0..m.points.len() as u32)
            .filter(|&v| m.points[v as usize][0] == x)
            .collect(),
    };
    let tet_region = m
        .tets
        .iter()
        .map(|t| u32::from(t.iter().map(|&v| m.points[v as usize][0]).sum::<f64>() > 4.0))
        .collect();
    let file = MeshFile {
        node_groups: vec![side(0.0), side(2.0)],
        regions: vec!["soft".into(), "hard".into()],
        tet_region,
        mesh: m,
    };
    let opts = Options {
        k_regions: vec![("hard".into(), 3.0)],
        dirichlet: vec![("left".into(), 0.0), ("right".into(), 1.0)],
        pcg: solver_demo::pcg::PcgOptions {
            tol: 1e-13,
            ..Default::default()
        },
        ..Options::default()
    };
    let sol = solve(&file, &opts, &mut |_, _| {}).unwrap();
    for (p, u) in file.mesh.points.iter().zip(&sol.u) {
        let exact = if p[0] <= 1.0 {
            0.75 * p[0]
        } else {
            0.75 + 0.25 * (p[0] - 1.0)
        };
        assert!((u - exact).abs() < 1e-10, "u({p:?}) = {u}, exact {exact}");
    }
    // Ignoring the regions gives a different (linear) solution: the test can fail.
    let uniform = solve(
        &file,
        &Options {
            k_regions: vec![],
            ..opts
        },
        &mut |_, _| {},
    )
    .unwrap();
    assert!(uniform
        .u
        .iter()
        .zip(&sol.u)
        .any(|(a, b)| (a - b).abs() > 0.1));
}
