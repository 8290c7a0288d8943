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
