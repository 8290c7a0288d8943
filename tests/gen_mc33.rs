//! The seeded random search that generates `tests/common/mc33_table.rs`, the searched part of
//! the MC33 single-cell configurations of `tests/common/mc33.rs`.
//!
//! Regenerate (deterministic: fixed seed and sample count, single-threaded) and check that
//! the committed table is what the search derives:
//!
//! ```text
//! cargo test --release --test gen_mc33 -- --ignored generate_mc33_table --nocapture
//! git diff --exit-code tests/common/mc33_table.rs
//! ```
//!
//! The search draws a sign class (uniformly among classes 1..=14), a sign pattern of that class
//! and an isovalue in [-0.4, 0.4], then corner values uniform in [-1, 1] on the prescribed
//! side of the isovalue, everything rounded to 4 decimals. Cells are bucketed by
//! [`common::mc33::bucket`] (sign class under rotations and complement, ambiguous faces joined
//! for the minority sign, body saddles and their side) and by the reference Betti numbers of
//! {f > iso} and {f < iso}; the first cell of every (bucket, Betti numbers) that the reference
//! resolves with twice the margin of `tests/topology.rs`, and that [`common::mc33::mc33_label`]
//! names, is kept.
//!
//! Kept cells must also have the same Betti numbers at a finer resolution (`CONFIRM_N`), and
//! so must the two-level intervals derived from them (`two_level_cells`): near a face saddle
//! two components can come closer than a sub-voxel, and the sampled reference then merges
//! them at every resolution of tests/topology.rs. Cells whose Betti numbers fit no MC33
//! subcase are reported as "unlabelled" and left out (the ones checked at a higher
//! resolution were such thin gaps).
//!
//! `print_mc33_buckets` lists the bucket, Betti numbers and derived label of every
//! configuration of `configs()` (searched and transcribed).

mod common;

use common::mc33::{
    bucket, configs, mc33_label, sign_class, two_level_intervals, Bucket, MC33_FAMILY,
};
use common::reference::{reference_betti, sampled_betti, Field, RefBetti};
use common::Rng;
use std::collections::{BTreeMap, HashMap, HashSet};
use std::fmt::Write as _;

const SEED: u64 = 33;
/// Cells drawn.
const SAMPLES: usize = 200_000;
/// Cells of one bucket screened (low-resolution Betti numbers) before the bucket is skipped.
const SCREENS_PER_BUCKET: usize = 400;
/// Reference resolutions and margin (× max |value − iso|): tests/topology.rs uses 0.002.
const NS: [usize; 2] = [40, 64];
const MARGIN: f64 = 0.004;
/// Resolutions of the confirmation of kept cells, and the two-level references of
/// tests/topology.rs.
const CONFIRM_N: usize = 160;
const CONFIRM_N2: usize = 200;
const NS2: [usize; 3] = [40, 64, 96];
/// Resolution of the cheap screening of Betti numbers.
const SCREEN_N: usize = 16;

const TABLE: &str = "tests/common/mc33_table.rs";

type Betti = [usize; 3];

fn round4(x: f64) -> f64 {
    (x * 1e4).round() / 1e4
}

/// Reference Betti numbers of {f > iso} and {f < iso}, if resolved.
fn reference(values: &[f64; 8], iso: f64, margin: f64) -> Option<(Betti, Betti)> {
    let f = Field::cell(*values);
    let scale = values.iter().fold(0.0f64, |m, x| m.max((x - iso).abs()));
    let r = |a, b| match reference_betti(&f, a, b, margin * scale, &NS) {
        RefBetti::Resolved { betti, tie: false } => Some(betti),
        _ => None,
    };
    Some((r(iso, f64::INFINITY)?, r(f64::NEG_INFINITY, iso)?))
}

/// Thin gaps (near face saddles) merge components at every resolution of the reference, so
/// a kept cell must also have the same Betti numbers at `CONFIRM_N`, and so must every
/// two-level interval of `two_level_cells` that the reference of tests/topology.rs resolves.
fn confirmed(values: &[f64; 8], iso: f64, up: Betti, down: Betti) -> bool {
    let f = Field::cell(*values);
    if sampled_betti(&f, CONFIRM_N, iso, f64::INFINITY) != up
        || sampled_betti(&f, CONFIRM_N, f64::NEG_INFINITY, iso) != down
    {
        return false;
    }
    let scale = values.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    two_level_intervals(values).into_iter().all(|(_, a, b)| {
        match reference_betti(&f, a, b, 1e-4 * scale, &NS2) {
            RefBetti::Resolved { betti, tie: false } => {
                sampled_betti(&f, CONFIRM_N2, a, b) == betti
            }
            RefBetti::Resolved { tie: true, .. } => false,
            RefBetti::Unresolved(_) => true,
        }
    })
}

struct Found {
    label: &'static str,
    values: [f64; 8],
    iso: f64,
    sample: usize,
}

fn describe(b: &Bucket, up: Betti, down: Betti) -> String {
    let corner = match b.corner {
        1 => ", around a corner of the joined sign",
        2 => ", around a corner of the other sign",
        3 => ", no common corner",
        _ => "",
    };
    format!(
        "class {}, {} of {} ambiguous faces joined{corner}, body saddles {} in / {} out; \
         Betti up {up:?} down {down:?}",
        b.class, b.joined, b.ambiguous, b.saddles_in, b.saddles_out
    )
}

#[test]
#[ignore = "generator: writes tests/common/mc33_table.rs (about a minute in release)"]
fn generate_mc33_table() {
    let start = std::time::Instant::now();
    // sign patterns by class
    let mut masks: Vec<Vec<u8>> = vec![Vec::new(); 15];
    for m in 0..=255u8 {
        let v: [f64; 8] = std::array::from_fn(|c| if m >> c & 1 == 1 { 1.0 } else { -1.0 });
        let class: usize = sign_class(&v, 0.0).parse().unwrap();
        masks[class].push(m);
    }
    let mut rng = Rng::new(SEED);
    let mut screens: HashMap<Bucket, usize> = HashMap::new();
    let mut done: HashSet<(Bucket, Betti, Betti)> = HashSet::new();
    let mut found: BTreeMap<(Bucket, Betti, Betti), Found> = BTreeMap::new();
    let mut unlabelled: BTreeMap<(Bucket, Betti, Betti), usize> = BTreeMap::new();
    let (mut references, mut unresolved, mut fragile) = (0usize, 0usize, 0usize);
    for sample in 0..SAMPLES {
        let class = rng.usize(1, 14);
        let mask = masks[class][rng.usize(0, masks[class].len() - 1)];
        let iso = round4(rng.range(-0.4, 0.4));
        let values: [f64; 8] = std::array::from_fn(|c| {
            round4(if mask >> c & 1 == 1 {
                rng.range(iso, 1.0)
            } else {
                rng.range(-1.0, iso)
            })
        });
        if values.contains(&iso) {
            continue;
        }
        let b = bucket(&values, iso);
        let n = screens.entry(b).or_insert(0);
        if *n >= SCREENS_PER_BUCKET {
            continue;
        }
        *n += 1;
        let f = Field::cell(values);
        let cheap = (
            sampled_betti(&f, SCREEN_N, iso, f64::INFINITY),
            sampled_betti(&f, SCREEN_N, f64::NEG_INFINITY, iso),
        );
        if done.contains(&(b, cheap.0, cheap.1)) {
            continue;
        }
        references += 1;
        let Some((up, down)) = reference(&values, iso, MARGIN) else {
            unresolved += 1;
            continue;
        };
        // robust cells only: both sides (each has corners) are seen, and already at the
        // screening resolution, so no feature is thinner than a quarter of the reference's
        // sub-voxels
        if up[0] == 0 || down[0] == 0 || (up, down) != cheap {
            fragile += 1;
            continue;
        }
        let key = (b, up, down);
        if found.contains_key(&key) {
            done.insert(key);
            continue;
        }
        let Some(label) = mc33_label(&b, up, down) else {
            done.insert(key);
            *unlabelled.entry(key).or_insert(0) += 1;
            continue;
        };
        if !confirmed(&values, iso, up, down) {
            fragile += 1;
            continue;
        }
        done.insert(key);
        found.insert(
            key,
            Found {
                label,
                values,
                iso,
                sample,
            },
        );
    }

    // order by label (family order), then bucket; name label, label + "b", "c", ...
    let mut entries: Vec<(&(Bucket, Betti, Betti), &Found)> = found.iter().collect();
    let rank = |l: &str| MC33_FAMILY.iter().position(|&f| f == l).unwrap();
    entries.sort_by_key(|(k, f)| (rank(f.label), **k));
    let mut src = String::new();
    writeln!(
        src,
        "//! MC33 single-cell configurations found by the seeded random search of\n\
         //! `tests/gen_mc33.rs` (seed {SEED}, {SAMPLES} cells): one cell per bucket and pair of\n\
         //! reference Betti numbers, labelled with the MC33 subcase they identify.\n\
         //!\n\
         //! Generated by `cargo test --release --test gen_mc33 -- --ignored generate_mc33_table`;\n\
         //! do not edit. The generator is deterministic: after regenerating,\n\
         //! `git diff --exit-code tests/common/mc33_table.rs` checks that this file is up to date.\n\
         \n\
         #![allow(clippy::approx_constant)]\n\
         \n\
         /// (name, MC33 label, corner values, isovalue)\n\
         pub const SEARCHED: [(&str, &str, [f64; 8], f64); {}] = [",
        entries.len()
    )
    .unwrap();
    let mut per_label: BTreeMap<&str, usize> = BTreeMap::new();
    for ((b, up, down), f) in &entries {
        let i = per_label.entry(f.label).or_insert(0);
        let name = if *i == 0 {
            f.label.to_string()
        } else {
            format!("{}{}", f.label, (b'a' + *i as u8) as char)
        };
        *i += 1;
        let vals: Vec<String> = f.values.iter().map(|x| format!("{x:.4}")).collect();
        writeln!(
            src,
            "    // {} (sample {})\n    (\n        \"{name}\",\n        \"{}\",\n        [\n            {},\n        ],\n        {:.4},\n    ),",
            describe(b, *up, *down),
            f.sample,
            f.label,
            vals.join(", "),
            f.iso
        )
        .unwrap();
    }
    src.push_str("];\n");
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(TABLE);
    std::fs::write(&path, src).unwrap();

    println!(
        "{SAMPLES} cells, {references} reference computations ({unresolved} unresolved, \
         {fragile} fragile), {} buckets, {:.1} s",
        screens.len(),
        start.elapsed().as_secs_f64()
    );
    println!("{} configurations written to {TABLE}", entries.len());
    for l in MC33_FAMILY {
        println!("  {l:>7}: {}", per_label.get(l).copied().unwrap_or(0));
    }
    for ((b, up, down), n) in &unlabelled {
        println!("  unlabelled ({n}×): {}", describe(b, *up, *down));
    }
}

#[test]
#[ignore = "diagnostic: prints the bucket and derived label of every configuration"]
fn print_mc33_buckets() {
    let mut keys = BTreeMap::new();
    for cfg in configs() {
        let b = bucket(&cfg.values, cfg.iso);
        let Some((up, down)) = reference(&cfg.values, cfg.iso, 0.002) else {
            println!("{:>22} {:>7}: unresolved", cfg.name, cfg.case);
            continue;
        };
        let derived = mc33_label(&b, up, down).unwrap_or("-");
        let flag = if derived == cfg.case {
            ""
        } else {
            "  MISMATCH"
        };
        println!(
            "{:>22} {:>7} -> {derived:>7}: {}{flag}",
            cfg.name,
            cfg.case,
            describe(&b, up, down)
        );
        keys.entry((b, up, down))
            .or_insert_with(Vec::new)
            .push(cfg.name);
    }
    println!("{} distinct (bucket, Betti) keys", keys.len());
    for (k, names) in &keys {
        println!("KEY {:?} {:?} {:?} {:?}", k.0, k.1, k.2, names);
    }
}
