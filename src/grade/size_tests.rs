//! The size field measured on balls. The field is the distance to the centre, so the depth of
//! a point below the boundary (the sphere of the level's radius) is known. A tet's *size* is
//! its mean edge length (a cube's cone tets have 1.002 times the cube's side). Deep inside,
//! the mean size is `max_edge` within 25 %; away from the boundary, sizes grow by no more
//! than the grading per layer of elements. Every mesh also passes what the graded meshes of
//! `tests.rs` pass: the checker, the Betti numbers, the volume, the boundary.

use super::octree::clearance;
use super::tests::{field, graded_mesh_as_fine, radius};
use super::*;

/// Bins of the size profile with fewer tets are left out (their mean is a handful of cubes).
const MIN_TETS: usize = 30;

/// A ball of radius `r` centred on an `n`³ grid, graded with `max_edge` `h` and grading `g`:
/// the report and, per tet, the depth of its centroid and its size.
fn graded_ball(n: usize, r: f64, h: f64, g: f64) -> (GradeReport, Vec<(f64, f64)>) {
    let c = (n - 1) as f64 / 2.0;
    let grid = field(n, radius(c));
    let opts = GradeOptions {
        max_edge: h,
        grading: g,
    };
    let (report, m) = graded_mesh_as_fine(&grid, &[f64::NEG_INFINITY, r], &opts);
    let sizes = m
        .tets
        .iter()
        .map(|t| {
            let p = t.map(|v| m.points[v as usize]);
            let centroid = [0, 1, 2].map(|a| p.iter().map(|q| q[a]).sum::<f64>() / 4.0);
            let depth = r - centroid
                .iter()
                .map(|x| (x - c) * (x - c))
                .sum::<f64>()
                .sqrt();
            (depth, mean_edge(&p))
        })
        .collect();
    (report, sizes)
}

fn mean_edge(p: &[[f64; 3]; 4]) -> f64 {
    let mut sum = 0.0;
    for a in 0..4 {
        for b in a + 1..4 {
            sum += (0..3)
                .map(|k| (p[a][k] - p[b][k]).powi(2))
                .sum::<f64>()
                .sqrt();
        }
    }
    sum / 6.0
}

/// Where the deep interior for cubes of side `s` cells and grading `g` begins: the depth
/// √3 (2s + clearance). A point deeper lies in a cube of side `s`: the aligned cube holding
/// it and every cell within its clearance lie at most `s + clearance` cells from it along
/// each axis, so inside the ball, and the cells next to the cube, which the 2:1 balance
/// looks at, are at most one side farther.
fn deep_depth(s: usize, g: f64) -> f64 {
    3f64.sqrt() * (2 * s + clearance(s, g)) as f64
}

/// The mean size of the tets deeper than `depth`, and their number.
fn mean_deeper(sizes: &[(f64, f64)], depth: f64) -> (f64, usize) {
    let deep: Vec<f64> = sizes
        .iter()
        .filter(|(d, _)| *d > depth)
        .map(|x| x.1)
        .collect();
    (deep.iter().sum::<f64>() / deep.len() as f64, deep.len())
}

/// The size profile h(d): per bin of depth `[i, i + 1)` (from 0), the bin's centre and the
/// mean size of the tets whose centroid lies in it, for bins of [`MIN_TETS`] tets or more.
fn profile(sizes: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let mut bins: Vec<(f64, usize)> = Vec::new();
    for &(d, h) in sizes.iter().filter(|(d, _)| *d >= 0.0) {
        let i = d as usize;
        if bins.len() <= i {
            bins.resize(i + 1, (0.0, 0));
        }
        bins[i].0 += h;
        bins[i].1 += 1;
    }
    let bins = bins.iter().enumerate();
    bins.filter(|(_, b)| b.1 >= MIN_TETS)
        .map(|(i, b)| (i as f64 + 0.5, b.0 / b.1 as f64))
        .collect()
}

/// The fastest growth over one layer of elements: the largest `h(d + h(d)) / h(d)` over the
/// profile's bins, `h` interpolated linearly between bin centres (bins whose layer ends
/// beyond the profile are left out).
fn layer_growth(profile: &[(f64, f64)]) -> f64 {
    let at = |x: f64| {
        let k = profile.iter().position(|p| p.0 >= x)?;
        let (a, b) = (profile[k.max(1) - 1], profile[k]);
        let t = if b.0 > a.0 {
            (x - a.0) / (b.0 - a.0)
        } else {
            1.0
        };
        Some(a.1 + t.clamp(0.0, 1.0) * (b.1 - a.1))
    };
    let ratios = profile.iter().filter_map(|&(d, h)| Some(at(d + h)? / h));
    ratios.fold(0.0, f64::max)
}

#[test]
fn the_deep_interior_has_the_requested_mean_edge() {
    // (grid, radius, max_edge, grading, cube side)
    let cases = [
        (64, 29.2, 4.0, 1.5, 4),
        (100, 47.3, 7.0, 2.0, 8),
        (100, 47.3, 10.0, 3.0, 8),
    ];
    for (n, r, h, g, side) in cases {
        let (report, sizes) = graded_ball(n, r, h, g);
        assert_eq!(report.max_side_cells, side, "H {h}");
        let deep = deep_depth(side, g);
        let (mean, count) = mean_deeper(&sizes, deep);
        let growth = layer_growth(&profile(&sizes));
        let cubes = &report.cubes;
        eprintln!("H {h} G {g}: mean edge {mean:.4} over {count} tets deeper than {deep:.2}");
        eprintln!("  growth {growth:.4} per layer; cubes {cubes:?}");
        assert!(count >= MIN_TETS, "H {h} G {g}: {count} deep tets");
        assert!(
            (mean - h).abs() <= 0.25 * h,
            "H {h} G {g}: mean edge {mean:.3} over {count} deep tets"
        );
        assert!(growth <= g, "H {h} G {g}: growth {growth:.3} per layer");
    }
}

#[test]
fn sizes_grow_no_faster_than_the_grading_per_layer() {
    for (h, g) in [(8.0, 1.5), (16.0, 2.0)] {
        let (_, sizes) = graded_ball(64, 29.2, h, g);
        let p = profile(&sizes);
        let growth = layer_growth(&p);
        eprintln!("H {h} G {g}: growth {growth:.4} per layer, profile {p:.3?}");
        assert!(
            growth <= g,
            "H {h} G {g}: growth {growth:.3} per layer, {p:?}"
        );
        // sizes do grow, from the fine cells at the boundary to cubes of 4 inside, and the
        // measure sees it: the changes of cube size grow by more than 1.3 per layer
        assert!(p.iter().any(|x| x.1 > 4.0), "{p:?}");
        assert!(
            growth > 1.3,
            "H {h} G {g}: growth {growth:.3} per layer, {p:?}"
        );
    }
}
