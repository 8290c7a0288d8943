//! Graded meshes against their fine ones: the checker's verdict, the topology of every
//! region, the volume, the boundary, the cubes' angles and the thread count.

use super::*;
use crate::check::{check_mesh, CheckOptions};
use crate::facts::MeshFacts;
use crate::quality::dihedral_angles;
use crate::{mesh_interval, MeshOptions, Method, TetMesh};

pub(super) fn field(n: usize, f: impl Fn([f64; 3]) -> f64) -> ScalarGrid {
    let mut v = Vec::with_capacity(n * n * n);
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                v.push(f([i, j, k].map(|x| x as f64)));
            }
        }
    }
    ScalarGrid::new([n; 3], v).unwrap()
}

pub(super) fn radius(c: f64) -> impl Fn([f64; 3]) -> f64 {
    move |p| p.iter().map(|x| (x - c) * (x - c)).sum::<f64>().sqrt()
}

/// A torus of tube radius `r` around the circle of radius `big` in the plane z = c.
fn torus(c: f64, big: f64) -> impl Fn([f64; 3]) -> f64 {
    move |p| {
        let ring = ((p[0] - c).powi(2) + (p[1] - c).powi(2)).sqrt() - big;
        (ring * ring + (p[2] - c).powi(2)).sqrt()
    }
}

fn mesh(grid: &ScalarGrid, levels: &[f64], method: Method) -> MeshOutput {
    let opts = MeshOptions {
        levels: if levels.len() > 2 {
            levels.to_vec()
        } else {
            Vec::new()
        },
        ..MeshOptions::new(levels[0], levels[levels.len() - 1], method)
    };
    mesh_interval(grid, &opts).unwrap()
}

fn sorted_boundary(m: &TetMesh) -> Vec<[[u64; 3]; 3]> {
    let mut out: Vec<_> = m
        .boundary
        .iter()
        .map(|t| {
            let mut k = t.map(|v| m.points[v as usize].map(f64::to_bits));
            k.sort();
            k
        })
        .collect();
    out.sort();
    out
}

/// Grades `grid`'s mesh of `levels` and checks everything the fine mesh guarantees; returns
/// the report.
fn graded_as_fine(grid: &ScalarGrid, levels: &[f64], opts: &GradeOptions) -> GradeReport {
    graded_mesh_as_fine(grid, levels, opts).0
}

/// [`graded_as_fine`], returning the graded mesh too.
pub(super) fn graded_mesh_as_fine(
    grid: &ScalarGrid,
    levels: &[f64],
    opts: &GradeOptions,
) -> (GradeReport, TetMesh) {
    let lv = Levels::new(levels).unwrap();
    let mut out = mesh(grid, levels, Method::Ctd);
    let fine = out.mesh.clone();
    let report = grade_interior(&mut out, grid, &lv, opts);
    let graded = &out.mesh;
    let check = check_mesh(graded, &CheckOptions::with_levels(grid, lv));
    assert!(check.valid, "{}", check.summary_line());
    let before = MeshFacts::of(&fine, true, levels);
    let after = MeshFacts::of(graded, true, levels);
    assert_eq!(before.betti, after.betti);
    for (b, a) in before.regions.iter().zip(&after.regions) {
        assert_eq!(b.betti, a.betti, "region {}", b.name);
        assert!(
            (b.volume - a.volume).abs() <= 1e-9 * b.volume,
            "{} {}",
            b.volume,
            a.volume
        );
    }
    assert!((before.volume - after.volume).abs() <= 1e-9 * before.volume);
    assert_eq!(before.boundary_triangles, after.boundary_triangles);
    assert_eq!(sorted_boundary(&fine), sorted_boundary(graded));
    assert_eq!(report.tets_after, graded.tets.len());
    assert!(
        (report.volume_replaced - report.volume_replacing).abs() <= 1e-9 * before.volume,
        "{report:?}"
    );
    // the cones (after the kept tets) have the angles of the construction
    let kept = report.tets_before - report.tets_replaced;
    assert_eq!(kept + report.tets_added, report.tets_after);
    for t in &graded.tets[kept..] {
        let a = dihedral_angles(t.map(|v| graded.points[v as usize]));
        for x in a {
            assert!((35.26 - 1e-6..=125.27).contains(&x), "{x}");
        }
    }
    (report, out.mesh)
}

#[test]
fn a_ball_keeps_everything_and_loses_most_of_its_tets() {
    let grid = field(48, radius(23.5));
    let r = graded_as_fine(&grid, &[f64::NEG_INFINITY, 21.3], &GradeOptions::default());
    assert!(r.cubes.len() == 2 && r.cubes[1] > 0, "{r:?}");
    // the cubes replace their cells' tets by fewer than half as many
    assert!(r.tets_added * 2 < r.tets_replaced, "{r:?}");
    assert!(r.tets_after * 5 < r.tets_before * 4, "{r:?}");
}

#[test]
fn larger_cubes_deeper_inside() {
    let grid = field(64, radius(31.5));
    let opts = GradeOptions {
        max_edge: 16.0,
        grading: 2.0,
    };
    let r = graded_as_fine(&grid, &[f64::NEG_INFINITY, 29.2], &opts);
    assert_eq!(r.max_side_cells, 16);
    assert!(r.cubes[..3].iter().all(|&c| c > 0), "{r:?}");
    let fine = graded_as_fine(&grid, &[f64::NEG_INFINITY, 29.2], &GradeOptions::default());
    assert!(r.tets_after < fine.tets_after, "{r:?} {fine:?}");
}

#[test]
fn nested_regions_and_a_torus_keep_their_topology() {
    let grid = field(44, radius(21.5));
    graded_as_fine(
        &grid,
        &[f64::NEG_INFINITY, 8.3, 19.6],
        &GradeOptions::default(),
    );
    let grid = field(48, torus(23.5, 13.0));
    let r = graded_as_fine(&grid, &[f64::NEG_INFINITY, 8.2], &GradeOptions::default());
    assert!(r.cubes[0] > 0, "{r:?}");
}

#[test]
fn thin_layers_and_near_critical_levels_get_no_cubes_where_they_are_thin() {
    // a shell two cells thick: nothing is deep enough inside
    let grid = field(40, radius(19.5));
    let r = graded_as_fine(&grid, &[14.1, 16.0], &GradeOptions::default());
    assert_eq!(r.tets_after, r.tets_before, "{r:?}");
    // a level a hair above the centre's value (a minimum): a critical level
    let r = graded_as_fine(&grid, &[1e-9, 18.0], &GradeOptions::default());
    assert!(r.tets_after < r.tets_before);
    // a torus whose hole is about to close (the saddle value at the centre is 11.0)
    let grid = field(44, torus(21.5, 11.0));
    graded_as_fine(&grid, &[f64::NEG_INFINITY, 10.98], &GradeOptions::default());
}

#[test]
fn the_same_mesh_for_any_thread_count() {
    let grid = field(40, torus(19.5, 11.0));
    let lv = Levels::interval(f64::NEG_INFINITY, 7.7);
    let run = |threads| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut out = mesh(&grid, &[f64::NEG_INFINITY, 7.7], Method::Ctd);
            grade_interior(&mut out, &grid, &lv, &GradeOptions::default());
            out.mesh
        })
    };
    assert_eq!(run(1), run(2));
}

#[test]
fn every_method_and_a_placed_grid() {
    for method in [Method::Tptd, Method::Six, Method::Five] {
        let grid = field(36, radius(17.5));
        let lv = Levels::interval(f64::NEG_INFINITY, 15.2);
        let mut out = mesh(&grid, &[f64::NEG_INFINITY, 15.2], method);
        let before = MeshFacts::of(&out.mesh, true, &[]);
        let r = grade_interior(&mut out, &grid, &lv, &GradeOptions::default());
        assert!(r.tets_after < r.tets_before, "{method:?}");
        let check = check_mesh(&out.mesh, &CheckOptions::with_levels(&grid, lv));
        assert!(check.valid, "{method:?}: {}", check.summary_line());
        let after = MeshFacts::of(&out.mesh, true, &[]);
        assert_eq!(before.betti, after.betti);
    }
    // spacing, origin and a rotation: the cubes are found in index space
    let mut grid = field(36, radius(17.5));
    grid.spacing = [0.5, 0.5, 0.5];
    grid.origin = [3.0, -2.0, 1.0];
    grid.direction = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]];
    let r = graded_as_fine(
        &grid,
        &[f64::NEG_INFINITY, 15.2],
        &GradeOptions {
            max_edge: 2.0,
            grading: 1.5,
        },
    );
    assert_eq!(r.max_side_cells, 4);
    assert!(r.tets_after < r.tets_before);
}
