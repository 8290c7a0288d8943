//! Tests of the classification of the tets the quality pass leaves below the floor.

use super::*;
use crate::improve::{improve_meshed, DEFAULT_WARP};
use crate::quality::summarize;
use crate::{mesh_interval, MeshOptions, Method};

/// `f` sampled at the integer points of an `n[0] × n[1] × n[2]` grid.
fn grid(n: [usize; 3], f: impl Fn(f64, f64, f64) -> f64) -> ScalarGrid {
    let mut values = Vec::with_capacity(n[0] * n[1] * n[2]);
    for k in 0..n[2] {
        for j in 0..n[1] {
            for i in 0..n[0] {
                values.push(f(i as f64, j as f64, k as f64));
            }
        }
    }
    ScalarGrid::new(n, values).unwrap()
}

/// As `tptd-mesh --quality` does: warped clipping, the pass, then the classification.
fn run(g: &ScalarGrid, alpha: f64, beta: f64, opts: &QualityOptions) -> (TetMesh, ForcedReport) {
    let mo = MeshOptions::new(alpha, beta, Method::Ctd).warp(DEFAULT_WARP);
    let mut out = mesh_interval(g, &mo).unwrap();
    improve_meshed(&mut out, g, alpha, beta, opts);
    let r = classify_forced(&out.mesh, g, alpha, beta, opts);
    (out.mesh, r)
}

#[test]
fn a_pinch_at_a_saddle_value_is_near_critical_there() {
    // f = x² + y² − z² around (5, 5, 5): the grid vertex there is a saddle of value 0 =
    // alpha, where {f >= 0} pinches to a point (the tip of a double cone).
    let c = 5.0;
    let g = grid([11, 11, 11], |x, y, z| {
        (x - c).powi(2) + (y - c).powi(2) - (z - c).powi(2)
    });
    // A floor above the target angle, so that the pass surely leaves tets below it near
    // the pinch (with edge removal, none stays below the 15° target there).
    let opts = QualityOptions {
        forced_floor: 20.0,
        ..QualityOptions::default()
    };
    let (mesh, r) = run(&g, 0.0, f64::INFINITY, &opts);
    let below = (0..mesh.tets.len())
        .filter(|&t| tet_dihedral_range(tet_points(&mesh, t)).0 < 20.0)
        .count();
    assert_eq!(r.total(), below);
    assert!(r.counts.near_critical > 0, "{:?}", r.counts);
    // Tets within a voxel of the pinch are near it; a `near_critical` tet touches a cell
    // around it, so its centroid is at most a few voxels away (the pass lengthens edges:
    // measured up to 3.02 voxels).
    for e in &r.elements {
        let d = distance(e.point, [c; 3]);
        let near = e.reason == ForcedReason::NearCritical;
        assert!(near || d >= 1.0, "{e:?}");
        assert!(!near || d < 4.0, "{e:?}");
    }
}

#[test]
fn a_level_set_meeting_the_box_at_a_shallow_angle_is_box_angle() {
    // {z <= 0.05 x − 0.33}: a wedge of 2.9° between the plane and the box face z = 0.
    let s: f64 = 0.05;
    let g = grid([17, 4, 6], |x, _, z| s * x - z);
    let (_, r) = run(&g, 0.33, f64::INFINITY, &QualityOptions::default());
    assert!(r.counts.box_angle > 0, "{:?}", r.counts);
    assert_eq!(r.counts.near_critical, 0);
    let wedge = s.atan().to_degrees();
    for e in r
        .elements
        .iter()
        .filter(|e| e.reason == ForcedReason::BoxAngle)
    {
        let a = e.box_angle.unwrap();
        assert!((a - wedge).abs() < 1e-6, "{a} vs {wedge}");
        assert!(e.point[2] < s * e.point[0] - 0.33 + 1e-9 && e.point[0] > 6.6);
    }
}

#[test]
fn a_smooth_sphere_lists_nothing() {
    let c = 9.5;
    let g = grid([20, 20, 20], |x, y, z| {
        ((x - c).powi(2) + (y - c).powi(2) + (z - c).powi(2)).sqrt() - 6.3
    });
    let (mesh, r) = run(&g, f64::NEG_INFINITY, 0.0, &QualityOptions::default());
    assert_eq!(summarize(&mesh).below[0], 0);
    assert_eq!(r.total(), 0);
    assert!(r.elements.is_empty());
}

#[test]
fn the_list_is_capped_worst_first_but_counts_cover_all() {
    let s: f64 = 0.05;
    let g = grid([17, 4, 6], |x, _, z| s * x - z);
    let opts = QualityOptions {
        forced_floor: 30.0,
        forced_list_cap: 3,
        ..QualityOptions::default()
    };
    let (_, r) = run(&g, 0.33, f64::INFINITY, &opts);
    assert!(r.total() > 3);
    assert_eq!(r.elements.len(), 3);
    assert!(r
        .elements
        .windows(2)
        .all(|w| w[0].min_dihedral <= w[1].min_dihedral));
}

/// A classifier of an empty mesh of `[alpha, beta]` on `g` (its field measures only).
fn measurer<'a>(g: &'a ScalarGrid, alpha: f64, beta: f64, mesh: &'a TetMesh) -> Classifier<'a> {
    Classifier {
        mesh,
        field: Field::new(g),
        levels: Levels::interval(alpha, beta),
        range: 1.0,
        floor: 5f64.to_radians(),
        target_sine: 15f64.to_radians().sin(),
        tol: 1e-5,
        labels: &[],
        first: 0,
    }
}

#[test]
fn the_layer_is_measured_across_it() {
    // A flat layer off the lattice directions: {3.2 <= 0.6 x + 0.8 y <= 3.5}, 0.3 thick.
    let g = grid([12, 12, 4], |x, y, _| 0.6 * x + 0.8 * y);
    let empty = TetMesh::default();
    let c = measurer(&g, 3.2, 3.5, &empty);
    // On the plane 0.6 x + 0.8 y = 3.3: 0.1 from alpha and 0.2 from beta across the layer.
    let p = [3.0, 1.875, 1.5];
    let (_, grad) = c.field.value_gradient(p);
    let h = c.shortest_chord(p, grad, 2.0).unwrap();
    assert!((h - 0.3).abs() < 1e-5, "{h}");
    // Chords with an end beyond the reach do not count.
    assert!(c.shortest_chord(p, grad, 0.15).is_none());
    assert!((c.shortest_chord(p, grad, 0.25).unwrap() - 0.3).abs() < 1e-5);
    // A spherical shell {6 <= |x − m| <= 6.2}: measured across, within a tenth of 0.2
    // (the trilinear interpolant of the distance is not quite it between samples: 0.201 on
    // an axis, 0.214 on a body diagonal).
    let m = 9.3;
    let g = grid([20, 20, 20], |x, y, z| {
        ((x - m).powi(2) + (y - m).powi(2) + (z - m).powi(2)).sqrt()
    });
    let c = measurer(&g, 6.0, 6.2, &empty);
    for p in [[m + 6.1, m, m], [m, m - 6.1, m], [m + 6.1 / 3f64.sqrt(); 3]] {
        let (f, grad) = c.field.value_gradient(p);
        assert!((6.0..=6.2).contains(&f), "{f}");
        let h = c.shortest_chord(p, grad, 2.0).unwrap();
        assert!((0.18..=0.22).contains(&h), "{p:?}: {h}");
    }
}

#[test]
fn a_layer_thinner_than_the_floor_allows_is_thin_layer() {
    // {6 <= |x − c| <= 6.01}: a spherical shell 0.01 voxel thick, spanned by tets with a
    // corner on each sphere and edges along it about a voxel long. (A tenth of a voxel
    // thick, the pass reaches 5.5°; 0.04 voxel thick, 5.1° since the compass search, and
    // 3.8° before it, with 10 thin-layer tets; measured.)
    let c = 9.3;
    let g = grid([20, 20, 20], |x, y, z| {
        ((x - c).powi(2) + (y - c).powi(2) + (z - c).powi(2)).sqrt()
    });
    let (mesh, r) = run(&g, 6.0, 6.01, &QualityOptions::default());
    let below = (0..mesh.tets.len())
        .filter(|&t| tet_dihedral_range(tet_points(&mesh, t)).0 < 5.0)
        .count();
    assert_eq!(r.total(), below);
    assert!(r.counts.thin_layer > 0, "{:?}", r.counts);
    assert_eq!(r.counts.unexplained, 0, "{:?}", r.counts);
    for e in r
        .elements
        .iter()
        .filter(|e| e.reason == ForcedReason::ThinLayer)
    {
        let h = e.layer_thickness.unwrap();
        // The trilinear gradient of |x − c| is a little steeper than 1 between samples.
        assert!((0.0085..0.05).contains(&h), "{e:?}");
    }
    // The same shell two hundred times thicker lists no thin layer.
    let (_, r) = run(&g, 6.0, 8.0, &QualityOptions::default());
    assert_eq!(r.counts.thin_layer, 0, "{:?}", r.counts);
}

#[test]
fn the_quick_reasons_are_those_of_the_full_measures() {
    // 8-bit-like noise at a half-integer bound: critical values everywhere, some within
    // the tolerance of the bound, many necks. No pass, so thousands of tets are below a
    // 15° floor; each reason must equal the one the full measures give.
    let g = grid([9, 8, 8], |x, y, z| {
        if z == 3.0 && (4.0..=5.0).contains(&x) && (4.0..=5.0).contains(&y) {
            // A checkerboard face: its saddle value is 3.5, the bound.
            return if x == y { 3.0 } else { 4.0 };
        }
        let s = (x + 9.0 * (y + 8.0 * z)) as u64 + 12345;
        let s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s.wrapping_mul(2862933555777941757) >> 33) % 8) as f64
    });
    let mo = MeshOptions::new(3.5, 5.5, Method::Ctd);
    let mesh = mesh_interval(&g, &mo).unwrap().mesh;
    let opts = QualityOptions {
        forced_floor: 15.0,
        forced_list_cap: usize::MAX,
        ..QualityOptions::default()
    };
    let r = classify_forced(&mesh, &g, 3.5, 5.5, &opts);
    let c = Classifier {
        mesh: &mesh,
        field: Field::new(&g),
        levels: Levels::interval(3.5, 5.5),
        range: 7.0,
        floor: 15f64.to_radians(),
        target_sine: opts.min_angle.to_radians().sin(),
        tol: opts.forced_critical_tol,
        labels: &mesh.vertex_label_bits(),
        first: 0,
    };
    let (mut by_tol, mut by_neck) = (0, 0);
    for e in &r.elements {
        let index = tet_points(&mesh, e.tet).map(|q| c.field.to_index(q));
        let limit = longest_edge(&index) * c.floor;
        let tol = e.critical_distance.is_some_and(|d| d <= c.tol);
        let neck = e.neck_width.is_some_and(|w| w < limit);
        let thin = (longest_edge(&index) * c.target_sine)
            .min(GUARD_DISTANCE)
            .max(limit);
        let full = c.decide(tol || neck, thin, || e.layer_thickness, || e.box_angle);
        assert_eq!(e.reason, full, "{e:?}");
        by_tol += tol as usize;
        by_neck += (neck && !tol) as usize;
    }
    assert_eq!(r.elements.len(), r.total());
    assert!(r.total() > 300, "{:?} {by_tol} {by_neck}", r.counts);
    assert!(by_tol > 0 && by_neck > 0, "{by_tol} {by_neck}");
    assert!(r.counts.unexplained > 0, "{:?}", r.counts);
}

#[test]
fn the_neck_width_is_measured_across_the_saddle() {
    // f = (x − 5.5)(y − 5.5): bilinear, so the interpolant is f itself, with a face saddle
    // of value 0 at x = y = 5.5. The level 0.01 makes a gap between the hyperbola's
    // branches of 2·sqrt(2 · 0.01) along the diagonal (1, 1).
    let g = grid([12, 12, 6], |x, y, _| (x - 5.5) * (y - 5.5));
    let mesh = TetMesh::default();
    let c = Classifier {
        mesh: &mesh,
        field: Field::new(&g),
        levels: Levels::interval(0.01, f64::INFINITY),
        range: 1.0,
        floor: 5f64.to_radians(),
        target_sine: 15f64.to_radians().sin(),
        tol: 1e-5,
        labels: &[],
        first: 0,
    };
    let w = c.measured_width([5.5, 5.5, 2.5], 0.01).unwrap();
    assert!((w - 2.0 * 0.02f64.sqrt()).abs() < 1e-5, "{w}");
    // The quadratic estimate 2·sqrt(δ / k) (k = 1 here) says 0.2; the cell's own saddle
    // is found and measured.
    let (dist, neck) = c.nearest_critical(&[
        [5.2, 5.2, 2.2],
        [5.8, 5.2, 2.2],
        [5.2, 5.8, 2.2],
        [5.2, 5.2, 2.8],
    ]);
    assert!((dist.unwrap() - 0.01).abs() < 1e-12);
    assert!((neck.unwrap() - w).abs() < 1e-9, "{neck:?}");
}
