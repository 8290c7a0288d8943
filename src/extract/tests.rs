//! Tests of the cell loop: welding, thread-count independence, exact volumes, near ties.

use super::*;
use crate::decompose::CellCase;
use crate::geom::signed_volume;
use crate::mesh::BoundaryLabel;
use rustc_hash::FxHashMap;

const ALL: [Method; 5] = [
    Method::Five,
    Method::Six,
    Method::Tptd,
    Method::Std,
    Method::Ctd,
];

fn grid(dims: [usize; 3], f: impl Fn(usize, usize, usize) -> f64) -> ScalarGrid {
    let mut v = Vec::with_capacity(dims[0] * dims[1] * dims[2]);
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                v.push(f(i, j, k));
            }
        }
    }
    ScalarGrid::new(dims, v).unwrap()
}

fn noise(dims: [usize; 3], seed: u64) -> ScalarGrid {
    grid(dims, |i, j, k| {
        let h = (seed ^ (i + 97 * j + 9973 * k) as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        ((h >> 11) as f64) / ((1u64 << 53) as f64) * 2.0 - 1.0
    })
}

fn volume(m: &TetMesh) -> f64 {
    m.tets
        .iter()
        .map(|t| {
            let p = t.map(|i| m.points[i as usize]);
            let v = signed_volume(p[0], p[1], p[2], p[3]);
            assert!(v > 0.0, "tet volume {v}");
            v
        })
        .sum()
}

/// A 2×2×2-cell grid entirely inside: whole cells, corners welded, box boundary only.
#[test]
fn all_inside_grid() {
    let g = grid([3, 3, 3], |i, j, k| (i + j + k) as f64);
    for m in ALL {
        let out = mesh_interval(&g, &MeshOptions::new(-1.0, 7.0, m)).unwrap();
        let per_cell = if m == Method::Five { 5 } else { 6 };
        assert_eq!(out.mesh.tets.len(), 8 * per_cell, "{m:?}");
        assert_eq!(
            out.mesh.points.len(),
            27,
            "{m:?}: corners welded across cells"
        );
        assert_eq!(out.mesh.boundary.len(), 6 * 4 * 2, "{m:?}");
        assert!(out
            .mesh
            .boundary_labels
            .iter()
            .all(|&l| l == BoundaryLabel::Box));
        assert!((volume(&out.mesh) - 8.0).abs() < 1e-12);
        assert_eq!(out.stats.cells_by_case[CellCase::I as usize], 8);
        assert_eq!(out.stats.cells_total, 8);
    }
}

/// Every point appears once (no two points at the same place, every point in a tet), and
/// every tet face is shared by two tets or is a boundary triangle.
#[test]
fn welding_shares_points_between_cells() {
    let g = noise([5, 4, 6], 3);
    for m in ALL {
        let mesh = mesh_interval(&g, &MeshOptions::new(-0.3, 0.4, m))
            .unwrap()
            .mesh;
        let mut pos: Vec<[u64; 3]> = mesh.points.iter().map(|p| p.map(f64::to_bits)).collect();
        pos.sort();
        pos.dedup();
        assert_eq!(pos.len(), mesh.points.len(), "{m:?}: duplicate points");
        let mut used = vec![false; mesh.points.len()];
        let mut faces: FxHashMap<[u32; 3], usize> = FxHashMap::default();
        for t in &mesh.tets {
            for skip in 0..4 {
                let mut f = [t[(skip + 1) % 4], t[(skip + 2) % 4], t[(skip + 3) % 4]];
                f.sort();
                *faces.entry(f).or_default() += 1;
            }
            t.iter().for_each(|&i| used[i as usize] = true);
        }
        assert!(used.iter().all(|&u| u), "{m:?}: unused point");
        let once = faces.values().filter(|&&n| n == 1).count();
        assert!(faces.values().all(|&n| n <= 2), "{m:?}");
        assert_eq!(once, mesh.boundary.len(), "{m:?}: open faces");
    }
}

/// The same mesh for one and several worker threads (rayon pools).
#[test]
fn same_mesh_for_any_thread_count() {
    let g = noise([13, 11, 17], 5);
    for m in ALL {
        let opts = MeshOptions::new(-0.2, 0.5, m);
        let run = |n: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .unwrap();
            pool.install(|| mesh_interval(&g, &opts).unwrap())
        };
        let (a, b) = (run(1), run(3));
        assert_eq!(a.mesh.points, b.mesh.points, "{m:?}");
        assert_eq!(a.mesh.values, b.mesh.values, "{m:?}");
        assert_eq!(a.mesh.tets, b.mesh.tets, "{m:?}");
        assert_eq!(a.mesh.boundary, b.mesh.boundary, "{m:?}");
        assert_eq!(a.mesh.boundary_labels, b.mesh.boundary_labels, "{m:?}");
        assert_eq!(a.stats, b.stats, "{m:?}");
        let c = mesh_interval(&g, &opts.clone().threads(Some(2))).unwrap();
        assert_eq!(a.mesh.tets, c.mesh.tets, "{m:?}");
    }
}

/// A linear field is its own trilinear interpolant: the mesh volume is exact.
#[test]
fn values_within_rounding_of_a_level_give_a_closed_mesh() {
    // |p| sampled at multiples of 0.2: some vertices are 1.0, others 1 ± 1 ulp.
    let g = grid([13, 13, 13], |i, j, k| {
        let c = |n: usize| -1.2 + n as f64 * 0.2;
        (c(i) * c(i) + c(j) * c(j) + c(k) * c(k)).sqrt()
    });
    assert!(g.values.iter().any(|v| v != 1.0 && (v - 1.0).abs() < 1e-15));
    for method in ALL {
        let m = mesh_interval(&g, &MeshOptions::new(f64::NEG_INFINITY, 1.0, method))
            .unwrap()
            .mesh;
        let mut faces = std::collections::HashMap::new();
        for (t, tet) in m.tets.iter().enumerate() {
            assert!(m.tet_volume(t) > 0.0, "{method:?}: tet {t} not positive");
            for skip in 0..4 {
                let mut f: Vec<u32> = (0..4).filter(|&i| i != skip).map(|i| tet[i]).collect();
                f.sort_unstable();
                *faces.entry(f).or_insert(0usize) += 1;
            }
        }
        for b in &m.boundary {
            let mut f = b.to_vec();
            f.sort_unstable();
            assert_eq!(faces.get(&f), Some(&1), "{method:?}: boundary {b:?}");
        }
        let open = faces.values().filter(|&&n| n == 1).count();
        assert_eq!(open, m.boundary.len(), "{method:?}: unlabelled open faces");
    }
}

#[test]
fn integer_samples_near_a_level_move_the_level_not_the_grid() {
    // u8 ball; alpha 1e-8 above a data value (tolerance 1e-9 * 255), beta 1e-8 below one
    let vals: Vec<u8> = (0..9 * 9 * 9)
        .map(|n| {
            let d = [n % 9, n / 9 % 9, n / 81].map(|x| x as f64 - 4.0);
            (250.0 - 30.0 * (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()) as u8
        })
        .collect();
    let g = ScalarGrid::new([9, 9, 9], vals).unwrap();
    let (a, b) = (100.0 + 1e-8, 190.0 - 1e-8);
    assert!(g.values.iter().any(|v| v == 100.0) && g.values.iter().any(|v| v == 190.0));
    let without_near_ties = |g: &ScalarGrid, a: f64, b: f64| {
        let (copy, lv) = Levels::interval(a, b).without_near_ties(g);
        (copy, lv.get(0), lv.get(1))
    };
    let (copy, a2, b2) = without_near_ties(&g, a, b);
    assert!(copy.is_none());
    assert_eq!((a2, b2), (100.0, 190.0));
    // a level near no value stays; float storage gets a copy with the value on the level
    assert_eq!(without_near_ties(&g, 100.5, 190.0 - 1e-8).1, 100.5);
    let gf = ScalarGrid::new([9, 9, 9], g.values.to_f64_vec()).unwrap();
    let (copy, a3, _) = without_near_ties(&gf, a, b);
    let copy = copy.expect("a copy for float storage");
    assert_eq!(a3, a);
    assert!(copy.values.iter().any(|v| v == a));
    for method in ALL {
        let exact = mesh_interval(&g, &MeshOptions::new(100.0, 190.0, method)).unwrap();
        let near = mesh_interval(&g, &MeshOptions::new(a, b, method)).unwrap();
        assert_eq!(exact.mesh, near.mesh, "{method:?}");
        assert!(!near.mesh.tets.is_empty());
        for t in 0..near.mesh.tets.len() {
            assert!(near.mesh.tet_volume(t) > 0.0, "{method:?}: tet {t}");
        }
    }
}

#[test]
fn volume_of_a_linear_field() {
    let c = [1.0, 2.0, 0.5];
    let g = grid([6, 5, 4], |i, j, k| {
        c[0] * i as f64 + c[1] * j as f64 + c[2] * k as f64
    });
    let len = [5.0, 4.0, 3.0];
    // volume of {c·x < s} in the box, by inclusion–exclusion over the box's corners (bounds
    // avoid the data values, which are multiples of 0.5, so no tie moves a cut)
    let below = |s: f64| -> f64 {
        let mut v = 0.0;
        for corner in 0..8 {
            let shift: f64 = (0..3)
                .filter(|a| corner >> a & 1 == 1)
                .map(|a| c[a] * len[a])
                .sum();
            let sign = if (corner as u32).count_ones().is_multiple_of(2) {
                1.0
            } else {
                -1.0
            };
            v += sign * (s - shift).max(0.0).powi(3);
        }
        v / (6.0 * c[0] * c[1] * c[2])
    };
    for (a, b) in [
        (2.7, 9.3),
        (f64::NEG_INFINITY, 3.1),
        (4.2, f64::INFINITY),
        (3.3, 6.1),
    ] {
        let want = below(b.min(100.0)) - below(a.max(-100.0));
        for m in ALL {
            let got = volume(&mesh_interval(&g, &MeshOptions::new(a, b, m)).unwrap().mesh);
            assert!(
                (got - want).abs() < 1e-9,
                "{m:?} ({a}, {b}): {got} vs {want}"
            );
        }
    }
}

#[test]
fn options_default_and_builder() {
    let d = MeshOptions::default();
    assert_eq!((d.alpha, d.beta), (f64::NEG_INFINITY, f64::INFINITY));
    assert_eq!((d.method, d.threads), (Method::Ctd, None));
    let o = MeshOptions::default()
        .alpha(1.0)
        .beta(2.0)
        .method(Method::Tptd)
        .threads(Some(3));
    assert_eq!(
        o,
        MeshOptions {
            threads: Some(3),
            ..MeshOptions::new(1.0, 2.0, Method::Tptd)
        }
    );
    let g = noise([3, 3, 3], 1);
    for (a, b) in [(1.0, 1.0), (2.0, 1.0), (f64::NAN, 1.0)] {
        let e = mesh_interval(&g, &MeshOptions::default().alpha(a).beta(b));
        assert!(matches!(e, Err(MeshError::InvalidInterval { .. })));
    }
}
