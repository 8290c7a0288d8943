//! Convergence of the P1 solver on `tptd` meshes of a ball and a torus (distance fields) at
//! three resolutions (h halves each time): the manufactured solution's L2 error falls at
//! order >= 1.8 and its H1 error at order >= 0.9; `-laplace(u) = 1` on the unit ball with
//! `u = 0` on the surface has nodal error against `(1 - r^2)/6` falling at order >= 1.8.

mod common;

use common::*;
use solver_demo::pcg::PcgOptions;
use solver_demo::run::{solve, Options};

fn mms_options() -> Options {
    Options {
        mms: true,
        pcg: PcgOptions {
            tol: 1e-11,
            ..PcgOptions::default()
        },
        ..Options::default()
    }
}

fn check_mms(name: &str, grids: &[tptd::ScalarGrid], level: f64) {
    check_mms_with(name, grids, |g| mesh(g, f64::NEG_INFINITY, level));
}

fn check_mms_with(
    name: &str,
    grids: &[tptd::ScalarGrid],
    make: impl Fn(&tptd::ScalarGrid) -> tptd::TetMesh,
) {
    let dir = tempfile::tempdir().unwrap();
    let (mut h, mut l2, mut h1) = (Vec::new(), Vec::new(), Vec::new());
    for g in grids {
        let file = through_file(&make(g), dir.path(), "m.msh");
        let sol = solve(&file, &mms_options(), &mut |_, _| {}).unwrap();
        assert!(sol.report.converged);
        let e = sol.mms.unwrap();
        println!(
            "{name}: h {:.4} tets {} L2 {:.4e} H1 {:.4e}",
            g.spacing[0],
            file.mesh.tets.len(),
            e.l2,
            e.h1
        );
        h.push(g.spacing[0]);
        l2.push(e.l2);
        h1.push(e.h1);
    }
    let (o2, o1) = (orders(&h, &l2), orders(&h, &h1));
    println!("{name}: L2 orders {o2:.3?}, H1 orders {o1:.3?}");
    assert!(o2.iter().all(|&o| o >= 1.8), "{name}: L2 orders {o2:?}");
    assert!(o1.iter().all(|&o| o >= 0.9), "{name}: H1 orders {o1:?}");
}

#[test]
fn mms_converges_on_a_ball() {
    check_mms("ball", &[ball_grid(12), ball_grid(24), ball_grid(48)], 1.0);
}

#[test]
fn mms_converges_on_a_torus() {
    check_mms(
        "torus",
        &[torus_grid(16), torus_grid(32), torus_grid(64)],
        0.45,
    );
}

#[test]
fn unit_source_on_a_ball_matches_the_exact_solution() {
    let dir = tempfile::tempdir().unwrap();
    let (mut h, mut err) = (Vec::new(), Vec::new());
    for cells in [12, 24, 48] {
        let g = ball_grid(cells);
        let file = through_file(&mesh(&g, f64::NEG_INFINITY, 1.0), dir.path(), "b.inp");
        let opts = Options {
            source: 1.0,
            dirichlet: vec![("beta".into(), 0.0)],
            pcg: PcgOptions {
                tol: 1e-12,
                ..PcgOptions::default()
            },
            ..Options::default()
        };
        let sol = solve(&file, &opts, &mut |_, _| {}).unwrap();
        let e = file
            .mesh
            .points
            .iter()
            .zip(&sol.u)
            .map(|(&p, &u)| (u - (1.0 - radius(p).powi(2)) / 6.0).abs())
            .fold(0.0, f64::max);
        println!(
            "ball -lap u = 1: h {:.4} max nodal error {e:.4e}",
            g.spacing[0]
        );
        h.push(g.spacing[0]);
        err.push(e);
    }
    let o = orders(&h, &err);
    println!("nodal orders {o:.3?}");
    assert!(err[0] < 0.01, "coarse error {}", err[0]);
    assert!(o.iter().all(|&o| o >= 1.8), "nodal orders {o:?}");
}

#[test]
fn mms_converges_on_quality_improved_balls() {
    use tptd::improve::{improve, QualityOptions};
    let grids = [ball_grid(12), ball_grid(24), ball_grid(48)];
    check_mms_with("quality ball", &grids, |g| {
        let mut m = mesh(g, f64::NEG_INFINITY, 1.0);
        let before = m.tets.len();
        improve(
            &mut m,
            g,
            f64::NEG_INFINITY,
            1.0,
            &QualityOptions::default(),
        );
        assert_ne!(m.tets.len(), before, "the quality pass changed nothing");
        m
    });
}
