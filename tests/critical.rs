//! Critical points and regions: analytic fields, the TPTD-complex route against the seeds'
//! local method, and Betti numbers of `{f >= w}` from the independent sampled reference.

mod common;

use common::reference::{reference_betti, Field, RefBetti};
use common::Rng;
use tptd::critical::complex::build_complex;
use tptd::critical::{find_critical, CriticalKind, CriticalPoint};
use tptd::ScalarGrid;

fn grid_of(f: &Field) -> ScalarGrid {
    ScalarGrid::new(f.dims, f.values.clone()).unwrap()
}

fn random_field(dims: [usize; 3], seed: u64, integer: Option<i64>) -> Field {
    let mut rng = Rng::new(seed);
    let n = dims[0] * dims[1] * dims[2];
    let values = (0..n)
        .map(|_| match integer {
            Some(m) => rng.int(0, m) as f64,
            None => rng.f64(),
        })
        .collect();
    Field::new(dims, values)
}

/// Sorted distinct values of the points changing `{f >= w}` (`superlevel`) or `{f <= w}`.
fn values(points: &[CriticalPoint], superlevel: bool) -> Vec<f64> {
    let mut v: Vec<f64> = points
        .iter()
        .filter(|p| if superlevel { p.superlevel } else { p.sublevel })
        .map(|p| p.value)
        .collect();
    v.sort_by(f64::total_cmp);
    v.dedup();
    v
}

/// Values equal up to rounding (mirror-image cells of integer data give saddle values that
/// differ in the last bit).
fn same(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * (1.0 + a.abs())
}

fn diff(a: &[f64], b: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let only_a = a
        .iter()
        .filter(|&&x| !b.iter().any(|&y| same(x, y)))
        .copied()
        .collect();
    let only_b = b
        .iter()
        .filter(|&&x| !a.iter().any(|&y| same(x, y)))
        .copied()
        .collect();
    (only_a, only_b)
}

/// Betti numbers of `{f > w}` (`superlevel`) or `{f < w}` from the sampled reference just below
/// and just above `c`, `None` when the sampler cannot decide.
fn reference_change(f: &Field, c: f64, superlevel: bool) -> Option<bool> {
    let crit = common::reference::critical_values(f);
    let gap = crit
        .iter()
        .filter(|&&x| !same(x, c))
        .map(|&x| (x - c).abs())
        .fold(f64::INFINITY, f64::min)
        .min(1.0);
    let at = |w: f64| {
        let (a, b) = if superlevel {
            (w, f64::INFINITY)
        } else {
            (f64::NEG_INFINITY, w)
        };
        match reference_betti(f, a, b, 0.2 * gap, &[10, 14]) {
            RefBetti::Resolved { betti, .. } => Some(betti),
            RefBetti::Unresolved(_) => None,
        }
    };
    Some(at(c - 0.5 * gap)? != at(c + 0.5 * gap)?)
}

/// The local method and the TPTD complex give the same critical values of both filtrations;
/// where they differ (ties in integer data) the sampled reference must side with the local
/// method. Plateaus on the grid box whose neighbourhood component counts cannot decide are
/// flagged for both filtrations on purpose (a warning too many, never one too few): those may
/// be reported without a change. Returns the number of values the reference decided.
fn check_routes_agree(f: &Field, what: &str) -> usize {
    let grid = grid_of(f);
    let pts = find_critical(&grid).unwrap();
    let cx = build_complex(&grid);
    let mut arbitrated = 0;
    for superlevel in [true, false] {
        let local = values(&pts, superlevel);
        let global = cx.critical_values(superlevel);
        let (only_local, only_cx) = diff(&local, &global);
        // a value reported by one point alone must change some Betti number (several points at
        // one value may cancel, e.g. a merge and a split at the same integer)
        let relevant = |p: &&CriticalPoint| if superlevel { p.superlevel } else { p.sublevel };
        let alone = |v: f64| {
            pts.iter()
                .filter(relevant)
                .filter(|p| same(p.value, v))
                .count()
                == 1
        };
        let bad_local: Vec<&CriticalPoint> = pts
            .iter()
            .filter(relevant)
            .filter(|p| only_local.contains(&p.value) && !p.degenerate && alone(p.value))
            .collect();
        for p in &bad_local {
            let change = reference_change(f, p.value, superlevel);
            if change == Some(true) {
                arbitrated += 1;
                continue;
            }
            assert!(
                p.kind.is_region() && p.on_box,
                "{what} superlevel={superlevel}: reported, no change on the complex nor the \
                 reference ({change:?}): {p:#?}"
            );
            println!(
                "conservative: {what}: {:?} {} at {:?}",
                p.kind, p.value, p.index
            );
        }
        for &c in &only_cx {
            let change = reference_change(f, c, superlevel);
            assert_eq!(
                change,
                Some(false),
                "{what} superlevel={superlevel}: Betti numbers change at {c} on the complex, no \
                 point reported; points there: {:#?}",
                pts.iter().filter(|p| same(p.value, c)).collect::<Vec<_>>()
            );
            arbitrated += 1;
        }
    }
    arbitrated
}

#[test]
fn routes_agree_on_random_fields() {
    for seed in 0..150 {
        let dims = [4 + seed as usize % 3, 4, 5 + seed as usize % 2];
        let n = check_routes_agree(&random_field(dims, seed, None), &format!("seed {seed}"));
        assert_eq!(n, 0, "generic data: the two routes must agree exactly");
    }
}

#[test]
fn routes_agree_on_integer_fields() {
    let mut arbitrated = 0;
    for seed in 0..150 {
        let top = [2, 3, 8][seed as usize % 3];
        arbitrated += check_routes_agree(
            &random_field([5, 5, 4], 100 + seed, Some(top)),
            &format!("integer seed {seed} (0..={top})"),
        );
    }
    println!("values decided by the sampled reference: {arbitrated}");
}

/// Two levels strictly inside `(lo, hi)`, away from every critical value of the reference's own
/// list (vertex values and saddles, critical or not): the midpoints of the gaps of that list
/// holding the points at 1/3 and 2/3 of the interval (a feature born at `lo` has grown there
/// to a size the sampler sees), with a margin a quarter of the narrower gap.
fn levels_between(crit: &[f64], lo: f64, hi: f64, min_width: f64) -> Option<(f64, f64, f64)> {
    let mut inner: Vec<f64> = crit.iter().copied().filter(|&x| x > lo && x < hi).collect();
    inner.insert(0, lo);
    inner.push(hi);
    let gap_at = |t: f64| {
        let x = lo + t * (hi - lo);
        let i = inner.partition_point(|&c| c <= x).clamp(1, inner.len() - 1);
        (inner[i - 1], inner[i])
    };
    let (first, last) = (gap_at(1.0 / 3.0), gap_at(2.0 / 3.0));
    let width = (first.1 - first.0).min(last.1 - last.0);
    // the sampler resolves necks and blobs only some way from the values where they form
    let far = |g: (f64, f64)| (g.0 - lo).max(hi - g.1) >= 0.0 && g.0 - lo >= 0.0;
    if width < min_width
        || !far(first)
        || (first.0 + first.1) * 0.5 - lo < 2.0 * min_width
        || hi - (last.0 + last.1) * 0.5 < 2.0 * min_width
    {
        return None;
    }
    Some((
        0.5 * (first.0 + first.1),
        0.5 * (last.0 + last.1),
        0.25 * width,
    ))
}

/// Reference Betti numbers, `None` when undecided.
type Betti = Option<[usize; 3]>;

fn superlevel_betti(f: &Field, w: f64, margin: f64) -> Option<[usize; 3]> {
    match reference_betti(f, w, f64::INFINITY, margin, &[12, 20]) {
        RefBetti::Resolved { betti, .. } => Some(betti),
        RefBetti::Unresolved(_) => None,
    }
}

/// Between consecutive reported critical values of `{f >= w}` the reference Betti numbers are
/// constant; across a value reported by one point (not a conservatively flagged box plateau)
/// they change. Returns (intervals checked, crossings checked, undecided).
fn check_spectrum_against_reference(f: &Field, what: &str) -> (usize, usize, usize) {
    let grid = grid_of(f);
    let pts = find_critical(&grid).unwrap();
    let mut crit = common::reference::critical_values(f);
    crit.dedup();
    let (min, max) = grid.value_range();
    let mut cuts = values(&pts, true);
    cuts.insert(0, min - 1.0);
    cuts.push(max + 1.0);
    let (mut intervals, mut crossings, mut undecided) = (0, 0, 0);
    // per interval: reference Betti numbers at its two levels (None: not sampled)
    let mut inside: Vec<Option<(Betti, Betti)>> = Vec::new();
    for w in cuts.windows(2) {
        let Some((a, b, margin)) = levels_between(&crit, w[0], w[1], 0.003 * (max - min)) else {
            inside.push(None);
            undecided += 1;
            continue;
        };
        let (ba, bb) = (
            superlevel_betti(f, a, margin),
            superlevel_betti(f, b, margin),
        );
        if let (Some(x), Some(y)) = (ba, bb) {
            assert_eq!(
                x, y,
                "{what}: Betti numbers change inside ({}, {}) at no reported value",
                w[0], w[1]
            );
            intervals += 1;
        } else {
            undecided += 1;
        }
        inside.push(Some((ba, bb)));
    }
    for (i, &c) in cuts.iter().enumerate().skip(1).take(cuts.len() - 2) {
        let at_c: Vec<&CriticalPoint> = pts
            .iter()
            .filter(|p| p.superlevel && same(p.value, c))
            .collect();
        if at_c.len() != 1 || (at_c[0].kind.is_region() && at_c[0].on_box) || at_c[0].degenerate {
            continue;
        }
        let below = inside[i - 1].and_then(|x| x.1);
        let above = inside[i].and_then(|x| x.0);
        match (below, above) {
            (Some(x), Some(y)) => {
                assert_ne!(x, y, "{what}: no Betti number changes across {:?}", at_c[0]);
                crossings += 1;
            }
            _ => undecided += 1,
        }
    }
    (intervals, crossings, undecided)
}

/// A smooth random field: three Gaussian bumps (positive or negative) plus a little noise, so
/// critical values are few and far enough apart for the sampler.
fn bumpy_field(dims: [usize; 3], seed: u64, noise: f64) -> Field {
    let mut rng = Rng::new(seed);
    let bumps: Vec<([f64; 3], f64, f64)> = (0..3)
        .map(|_| {
            let c = [0, 1, 2].map(|a| rng.range(0.0, (dims[a] - 1) as f64));
            (c, rng.range(-1.0, 1.0), rng.range(1.0, 2.5))
        })
        .collect();
    let mut f = Field::from_fn(dims, |x, y, z| {
        bumps
            .iter()
            .map(|(c, a, s)| {
                let d2 = (x - c[0]).powi(2) + (y - c[1]).powi(2) + (z - c[2]).powi(2);
                a * (-d2 / (s * s)).exp()
            })
            .sum()
    });
    for v in f.values.iter_mut() {
        *v += noise * rng.range(-1.0, 1.0);
    }
    f
}

#[test]
fn betti_numbers_change_exactly_at_reported_values() {
    let mut totals = (0, 0, 0);
    for seed in 0..12u64 {
        let f = bumpy_field([6, 5, 6], 500 + seed, 0.002);
        let (a, b, c) = check_spectrum_against_reference(&f, &format!("seed {seed}"));
        totals = (totals.0 + a, totals.1 + b, totals.2 + c);
    }
    println!(
        "generic: intervals {} crossings {} undecided {}",
        totals.0, totals.1, totals.2
    );
    assert!(totals.0 >= 40 && totals.1 >= 20, "{totals:?}");
}

#[test]
fn betti_numbers_change_exactly_at_reported_values_with_plateaus() {
    let mut totals = (0, 0, 0);
    for seed in 0..8u64 {
        // integer data: a smooth field quantized to 12 levels (plateaus everywhere)
        let mut f = bumpy_field([6, 5, 6], 700 + seed, 0.0);
        let (lo, hi) = f
            .values
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        for v in f.values.iter_mut() {
            *v = (11.0 * (*v - lo) / (hi - lo)).round();
        }
        let (a, b, c) = check_spectrum_against_reference(&f, &format!("integer seed {seed}"));
        totals = (totals.0 + a, totals.1 + b, totals.2 + c);
    }
    println!(
        "plateaus: intervals {} crossings {} undecided {}",
        totals.0, totals.1, totals.2
    );
    assert!(totals.0 >= 20 && totals.1 >= 5, "{totals:?}");
}

fn interior(points: &[CriticalPoint]) -> Vec<&CriticalPoint> {
    points.iter().filter(|p| !p.on_box).collect()
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

#[test]
fn two_gaussians_have_two_maxima_and_one_saddle() {
    let g = |x: f64, y: f64, z: f64, c: f64| {
        (-((x - c).powi(2) + (y - 4.0).powi(2) + (z - 4.0).powi(2)) / 4.0).exp()
    };
    let f = Field::from_fn([13, 9, 9], |x, y, z| g(x, y, z, 3.0) + g(x, y, z, 9.0));
    let grid = grid_of(&f);
    let pts = find_critical(&grid).unwrap();
    let inner = interior(&pts);
    let kinds: Vec<(CriticalKind, [f64; 3])> = inner.iter().map(|p| (p.kind, p.index)).collect();
    assert_eq!(
        kinds,
        vec![
            (CriticalKind::Saddle, [6.0, 4.0, 4.0]),
            (CriticalKind::Maximum, [3.0, 4.0, 4.0]),
            (CriticalKind::Maximum, [9.0, 4.0, 4.0]),
        ],
        "{inner:#?}"
    );
    assert_eq!(inner[0].value, 2.0 * (-9.0f64 / 4.0).exp());
    assert_eq!(inner[1].value, 1.0 + (-9.0f64).exp());
    // the elder maximum lives over the whole range; the other dies at the saddle
    let spans: Vec<f64> = inner.iter().map(|p| p.persistence.unwrap()).collect();
    let (lo, hi) = grid.value_range();
    assert!((spans[0] - (inner[1].value - inner[0].value)).abs() < 1e-12);
    assert!(spans[1..].contains(&(hi - lo)) && spans[1..].contains(&spans[0]));
    check_routes_agree(&f, "two gaussians");
}

#[test]
fn drip_field_of_seed_002() {
    // F = x^2 + y^2 - 0.5 (0.995 z^2 + 0.005 - z^3) on [-1.5, 1.5]^3, 40^3 samples (§6)
    let h = 3.0 / 39.0;
    let f = Field::from_fn([40, 40, 40], |i, j, k| {
        let (x, y, z) = (-1.5 + h * i, -1.5 + h * j, -1.5 + h * k);
        x * x + y * y - 0.5 * (0.995 * z * z + 0.005 - z * z * z)
    });
    let grid = ScalarGrid::with_geometry(
        [40, 40, 40],
        [h; 3],
        [-1.5; 3],
        tptd::grid::IDENTITY,
        f.values.clone(),
    )
    .unwrap();
    let pts = find_critical(&grid).unwrap();
    let inner = interior(&pts);
    assert_eq!(inner.len(), 2, "{inner:#?}");
    let min = inner
        .iter()
        .find(|p| matches!(p.kind, CriticalKind::Minimum | CriticalKind::RegionMinimum))
        .expect("interior minimum");
    let saddle = inner
        .iter()
        .find(|p| p.superlevel && p.kind != min.kind)
        .unwrap();
    // published: minimum -0.0754 at (0, 0, 0.663), saddle -0.0025 at the origin; the trilinear
    // field of the samples is within the sampling error (h^2 ~ 0.006) of them
    assert!((min.value + 0.0754).abs() < 0.004, "{min:#?}");
    assert!(dist(min.position, [0.0, 0.0, 0.663]) < h, "{min:#?}");
    assert!((saddle.value + 0.0025).abs() < 0.004, "{saddle:#?}");
    assert!(dist(saddle.position, [0.0, 0.0, 0.0]) < h, "{saddle:#?}");
    assert!(matches!(
        saddle.kind,
        CriticalKind::Saddle | CriticalKind::FaceSaddle | CriticalKind::BodySaddle
    ));
    check_routes_agree(&f, "drip");
    println!(
        "drip: minimum {} at {:?}, saddle {} ({:?}) at {:?}",
        min.value, min.position, saddle.value, saddle.kind, saddle.position
    );
}

#[test]
fn torus_minimum_is_a_ring_region() {
    // integer data: 0 on a ring of radius 6 around (10, 10, 3), rising away from it
    let f = Field::from_fn([21, 21, 7], |x, y, z| {
        let r = ((x - 10.0).powi(2) + (y - 10.0).powi(2)).sqrt();
        (((r - 6.0).powi(2) + (z - 3.0).powi(2)) / 0.6)
            .floor()
            .min(12.0)
    });
    let grid = grid_of(&f);
    let pts = find_critical(&grid).unwrap();
    let ring: Vec<&CriticalPoint> = pts.iter().filter(|p| p.value == 0.0).collect();
    assert_eq!(ring.len(), 1, "{ring:#?}");
    let r = ring[0];
    assert_eq!(r.kind, CriticalKind::RegionMinimum);
    assert!(!r.on_box && r.superlevel && r.sublevel);
    let info = r.region.as_ref().unwrap();
    let zeros = f.values.iter().filter(|&&v| v == 0.0).count();
    assert_eq!(info.vertices, zeros);
    // the position is a vertex of the ring; the centroid, in its hole, is apart
    assert!(dist(info.centroid, [10.0, 10.0, 3.0]) < 0.3, "{r:#?}");
    assert_eq!(r.position, r.index, "{r:#?}");
    let v = r.index.map(|x| x as usize);
    assert_eq!(grid.values.get(grid.index(v[0], v[1], v[2])), 0.0, "{r:#?}");
    assert_eq!(info.bbox_min[2], 3.0);
    assert!((info.bbox_min[0] - 4.0).abs() <= 1.0 && (info.bbox_max[0] - 16.0).abs() <= 1.0);
    // just above the minimum the sublevel set is a solid torus
    let cx = build_complex(&grid);
    assert_eq!(cx.betti(0.5, false), [1, 1, 0]);
    check_routes_agree(&f, "torus");
}

#[test]
fn integer_plateaus_two_maxima_and_a_bridge() {
    // zeros; two 2x2x2 blocks of 5 joined by a 4x2x2 bridge of 3
    let f = Field::from_fn([12, 6, 6], |x, y, z| {
        let core = (2.0..=3.0).contains(&y) && (2.0..=3.0).contains(&z);
        if core && ((2.0..=3.0).contains(&x) || (8.0..=9.0).contains(&x)) {
            5.0
        } else if core && (4.0..=7.0).contains(&x) {
            3.0
        } else {
            0.0
        }
    });
    let grid = grid_of(&f);
    let pts = find_critical(&grid).unwrap();
    let got: Vec<(CriticalKind, f64, [f64; 3], usize)> = pts
        .iter()
        .map(|p| {
            (
                p.kind,
                p.value,
                p.position,
                p.region.as_ref().map_or(1, |r| r.vertices),
            )
        })
        .collect();
    let background = 12 * 6 * 6 - 32;
    assert_eq!(
        got,
        vec![
            (CriticalKind::RegionMinimum, 0.0, got[0].2, background),
            (CriticalKind::RegionSaddle, 3.0, [5.0, 2.0, 2.0], 16),
            (CriticalKind::RegionMaximum, 5.0, [2.0, 2.0, 2.0], 8),
            (CriticalKind::RegionMaximum, 5.0, [8.0, 2.0, 2.0], 8),
        ]
    );
    // a region's position is its first vertex nearest to its centroid
    let centroids: Vec<[f64; 3]> = pts[1..]
        .iter()
        .map(|p| p.region.as_ref().unwrap().centroid)
        .collect();
    assert_eq!(
        centroids,
        [[5.5, 2.5, 2.5], [2.5, 2.5, 2.5], [8.5, 2.5, 2.5]]
    );
    check_routes_agree(&f, "plateaus");
}

#[test]
fn output_is_the_same_for_any_thread_count() {
    let mut f = bumpy_field([9, 8, 7], 9, 0.05);
    for v in f.values.iter_mut().step_by(3) {
        *v = (*v * 4.0).round() / 4.0; // some plateaus
    }
    let grid = grid_of(&f);
    let run = |threads| {
        let opts = tptd::critical::CriticalOptions {
            threads: Some(threads),
            ..Default::default()
        };
        tptd::critical::find_critical_with_options(&grid, &opts).unwrap()
    };
    let one = run(1);
    assert!(one.len() > 20);
    assert_eq!(one, run(2));
    assert_eq!(one, run(3));
}

#[test]
fn windowed_search_equals_the_filtered_full_search() {
    use tptd::critical::face::face_saddles_in;
    use tptd::critical::find::{all_critical, critical_in_windows};
    // a smooth field quantised to integers (plateaus of every size, some reaching the box),
    // long along x so that the skipped blocks of rows and their last partial block are used,
    // in uint8 and float64 storage (the row ranges are computed per storage type)
    let f = Field::from_fn([75, 23, 19], |x, y, z| {
        let s = (x * 0.21).sin() * 6.0 + (y * 0.37).cos() * 4.0 + (z * 0.29 + x * 0.05).sin() * 5.0;
        (s + 15.0).round()
    });
    // and a zero background with sparse spikes 1..=8 (most blocks of a row are skipped, and
    // a block reaches a window through one corner in one of its rows or planes)
    let mut rng = Rng::new(77);
    let spikes: Vec<f64> = (0..f.values.len())
        .map(|_| {
            let v = rng.int(0, 160);
            if v <= 8 {
                v as f64
            } else {
                0.0
            }
        })
        .collect();
    let u8_of = |v: &[f64]| v.iter().map(|&x| x as u8).collect::<Vec<u8>>();
    let grids = [
        grid_of(&f),
        ScalarGrid::new(f.dims, u8_of(&f.values)).unwrap(),
        ScalarGrid::new(f.dims, spikes.clone()).unwrap(),
        ScalarGrid::new(f.dims, u8_of(&spikes)).unwrap(),
    ];
    for grid in &grids {
        let all = all_critical(grid);
        assert!(all.iter().filter(|p| p.kind.is_region()).count() > 0);
        let in_windows = |v: f64, w: &[(f64, f64)]| w.iter().any(|&(a, b)| a <= v && v <= b);
        for windows in [
            vec![(15.0, 15.0)],
            vec![(3.2, 7.5), (20.0, 21.0)],
            vec![(14.4, 14.6), (25.5, 40.0)],
            vec![(-1.0, 0.5)],
            vec![(5.0, 5.0)],
            vec![(7.5, 8.0), (1.2, 1.8)],
        ] {
            let expected: Vec<CriticalPoint> = all
                .iter()
                .filter(|p| in_windows(p.value, &windows))
                .cloned()
                .collect();
            assert_eq!(critical_in_windows(grid, &windows), expected, "{windows:?}");
            for &(lo, hi) in &windows {
                let every = face_saddles_in(grid, f64::NEG_INFINITY, f64::INFINITY);
                let kept: Vec<_> = every
                    .into_iter()
                    .filter(|s| lo <= s.0 && s.0 <= hi)
                    .collect();
                assert_eq!(face_saddles_in(grid, lo, hi), kept, "[{lo}, {hi}]");
            }
        }
    }
}
