//! The quality pass (`tptd::improve`) on analytic distance fields and seeded random fields:
//! every invariant of the mesher still holds afterwards (positive conforming tets, closed
//! outward boundary, labels), the Betti numbers equal the independent reference, boundary
//! nodes lie on the trilinear level set, the volume stays, and the angles reach the targets.

mod common;

use common::invariants::{check_labels, check_mesh, mesh_betti, total_volume};
use common::reference::{self, Field};
use common::{extent, Rng};
use tptd::improve::{improve_meshed, QualityOptions, DEFAULT_WARP};
use tptd::quality::summarize;
use tptd::{mesh_interval, MeshOptions, MeshOutput, Method, ScalarGrid, TetMesh};

/// A field sampled from `f(x, y, z)` on an `n`³ grid.
fn sampled(n: usize, f: impl Fn(f64, f64, f64) -> f64) -> Field {
    let mut values = Vec::with_capacity(n * n * n);
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                values.push(f(i as f64, j as f64, k as f64));
            }
        }
    }
    Field {
        dims: [n, n, n],
        values,
    }
}

fn sphere(n: usize, r: f64) -> Field {
    sphere_at(n, (n - 1) as f64 / 2.0, r)
}

/// The distance to a sphere of radius `r` centred at `(c, c, c)`.
fn sphere_at(n: usize, c: f64, r: f64) -> Field {
    sampled(n, |x, y, z| {
        ((x - c).powi(2) + (y - c).powi(2) + (z - c).powi(2)).sqrt() - r
    })
}

fn torus(n: usize, big: f64, small: f64) -> Field {
    let c = (n - 1) as f64 / 2.0;
    sampled(n, |x, y, z| {
        let q = ((x - c).powi(2) + (y - c).powi(2)).sqrt() - big;
        (q * q + (z - c).powi(2)).sqrt() - small
    })
}

/// The genus-3 solid of the benchmarks (`quality.py`): three coplanar solid tori in a row
/// (ring radius 0.12 N, tube 0.06 N), tangent rings, their smooth union (blend 0.04 N).
fn genus3(n: usize) -> Field {
    let c = (n / 2) as f64;
    let (big, small, k) = (0.12 * n as f64, 0.06 * n as f64, 0.04 * n as f64);
    let ring = |x: f64, y: f64, z: f64, cx: f64| {
        let q = ((x - cx).powi(2) + y * y).sqrt() - big;
        (q * q + z * z).sqrt() - small
    };
    let smooth_min = |a: f64, b: f64| {
        let h = (0.5 + 0.5 * (b - a) / k).clamp(0.0, 1.0);
        b + (a - b) * h - k * h * (1.0 - h)
    };
    sampled(n, |x, y, z| {
        let (x, y, z) = (x - c, y - c, z - c);
        let d = smooth_min(ring(x, y, z, -2.0 * big), ring(x, y, z, 0.0));
        smooth_min(d, ring(x, y, z, 2.0 * big))
    })
}

/// Two balls of radius `r` whose surfaces are `gap` apart along x, the gap centred on the grid
/// plane through the middle (`n` odd), so that the trilinear interpolant keeps them apart.
fn two_balls(n: usize, r: f64, gap: f64) -> Field {
    assert!(n % 2 == 1);
    let c = (n - 1) as f64 / 2.0;
    let off = r + gap / 2.0;
    sampled(n, |x, y, z| {
        let d = |cx: f64| ((x - cx).powi(2) + (y - c).powi(2) + (z - c).powi(2)).sqrt() - r;
        d(c - off).min(d(c + off))
    })
}

/// Smooth random field: a few random plane waves.
fn random_smooth(n: usize, seed: u64) -> Field {
    let mut rng = Rng::new(seed);
    let waves: Vec<([f64; 3], f64, f64)> = (0..6)
        .map(|_| {
            let k = [0, 1, 2].map(|_| rng.range(-0.6, 0.6));
            (k, rng.range(0.0, 6.3), rng.range(0.5, 1.0))
        })
        .collect();
    sampled(n, |x, y, z| {
        waves
            .iter()
            .map(|(k, ph, a)| a * (k[0] * x + k[1] * y + k[2] * z + ph).sin())
            .sum()
    })
}

/// Integer-valued blobs (a quantised distance field), meshed at a bound equal to data values:
/// the tie rule's thin elements.
fn quantised(n: usize) -> Field {
    let c = (n - 1) as f64 / 2.0;
    sampled(n, |x, y, z| {
        let d = ((x - c).powi(2) + (y - c).powi(2) + (z - c).powi(2)).sqrt();
        (d * 2.0).round()
    })
}

struct Outcome {
    before: TetMesh,
    after: TetMesh,
    min_angle: f64,
    max_angle: f64,
}

fn improve_with_threads(
    grid: &ScalarGrid,
    out: &mut MeshOutput,
    (a, b): (f64, f64),
    q: &QualityOptions,
    threads: usize,
) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| improve_meshed(out, grid, a, b, q));
}

/// The volume of `after` relative to that of `before`, less one.
fn volume_change(before: &TetMesh, after: &TetMesh) -> f64 {
    total_volume(after) / total_volume(before) - 1.0
}

fn mesh_and_improve(field: &Field, alpha: f64, beta: f64) -> Outcome {
    mesh_and_improve_with(field, alpha, beta, &QualityOptions::default())
}

fn mesh_and_improve_with(field: &Field, alpha: f64, beta: f64, q: &QualityOptions) -> Outcome {
    let grid = ScalarGrid::new(field.dims, field.values.clone()).unwrap();
    let opts = MeshOptions::new(alpha, beta, Method::Ctd);
    let before = mesh_interval(&grid, &opts).unwrap().mesh;
    // As `tptd-mesh --quality` does: warped clipping, then the quality pass.
    let mut warped = mesh_interval(&grid, &opts.warp(DEFAULT_WARP)).unwrap();
    let r = improve_meshed(&mut warped, &grid, alpha, beta, q);
    let after = warped.mesh;
    let (b, a) = (summarize(&before), summarize(&after));
    eprintln!(
        "  {} tets: [{:.3}°, {:.2}°] -> {} tets: [{:.3}°, {:.2}°]; {} off level, {} collapses, \
         {} flips, {} moves in {:.2} s; volume {:+.2} %",
        b.tets,
        b.min_dihedral,
        b.max_dihedral,
        a.tets,
        a.min_dihedral,
        a.max_dihedral,
        r.unprojected,
        r.collapses,
        r.flips,
        r.smoothed,
        r.seconds,
        100.0 * volume_change(&before, &after)
    );
    Outcome {
        before,
        after,
        min_angle: a.min_dihedral,
        max_angle: a.max_dihedral,
    }
}

/// The reference Betti numbers when two sampling resolutions agree on them (finer for small
/// fields, whose features are thinner in voxels).
fn resolved_reference(field: &Field, alpha: f64, beta: f64) -> Option<[usize; 3]> {
    let n = if field.dims[0] <= 16 { 12 } else { 6 };
    let coarse = reference::sampled_betti(field, n, alpha, beta);
    let fine = reference::sampled_betti(field, 2 * n, alpha, beta);
    (coarse == fine).then_some(fine)
}

/// Every invariant that must survive the pass, and the topology against the reference.
fn check_invariants(name: &str, field: &Field, alpha: f64, beta: f64, o: &Outcome) {
    check_invariants_with(name, field, alpha, beta, o, VOLUME_FLOOR);
}

fn check_invariants_with(
    name: &str,
    field: &Field,
    alpha: f64,
    beta: f64,
    o: &Outcome,
    volume_floor: f64,
) {
    check_mesh(&o.after);
    check_labels(&o.after, alpha, beta, extent(field));
    let (b0, b1) = (mesh_betti(&o.before), mesh_betti(&o.after));
    assert_eq!(b1, b0, "{name}: Betti numbers changed by the quality pass");
    if let Some(r) = resolved_reference(field, alpha, beta) {
        assert_eq!(b1, r, "{name}: improved mesh vs reference");
    }
    check_on_level(name, field, alpha, beta, &o.after);
    let (v0, v1) = (total_volume(&o.before), total_volume(&o.after));
    let truth = reference::sample(field, 12, alpha, beta).volume();
    assert!(
        ((v1 - v0) / v0).abs() <= volume_floor || (v1 - truth).abs() < (v0 - truth).abs(),
        "{name}: volume {v0} -> {v1} (sampled trilinear volume {truth})"
    );
}

/// The smallest and largest sample of `field`.
fn value_range(field: &Field) -> (f64, f64) {
    field
        .values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        })
}

/// Nodes of alpha/beta triangles lie on the trilinear level set within 1e-6 of the data range.
fn check_on_level(name: &str, field: &Field, alpha: f64, beta: f64, mesh: &TetMesh) {
    let (lo, hi) = value_range(field);
    let tol = 1e-6 * (hi - lo);
    for (tri, &label) in mesh.boundary.iter().zip(&mesh.boundary_labels) {
        let level = match label {
            tptd::BoundaryLabel::Level(0) => alpha,
            tptd::BoundaryLabel::Level(_) => beta,
            tptd::BoundaryLabel::Box => continue,
        };
        for &v in tri {
            let p = mesh.points[v as usize];
            let f = field.eval(p);
            assert!(
                (f - level).abs() <= tol,
                "{name}: node {v} at {p:?} has f = {f}, level {level}"
            );
        }
    }
}

/// The relative volume change allowed when the improved mesh is not closer to the sampled
/// trilinear volume than the plain one (the quality goal: 0.5 %).
const VOLUME_FLOOR: f64 = 5e-3;

/// The angles the default pass must reach on the smooth closed domains: its targets, 15° and
/// 155° (the quality goal), up to rounding.
const FLOOR: (f64, f64) = (15.0 - 1e-6, 155.0 + 1e-6);

/// The relative volume change allowed at targets above the default, which coarsen more (and
/// whose splits and volume restoration may not take a tet below the target).
const VOLUME_AT_HIGHER_TARGETS: f64 = 1.5e-2;

/// Meshes `field` on `[alpha, beta]`, improves it at the targets `[lo°, hi°]` and checks the
/// invariants (volume within [`VOLUME_AT_HIGHER_TARGETS`]).
fn improve_at_targets(
    name: &str,
    field: &Field,
    (alpha, beta): (f64, f64),
    (lo, hi): (f64, f64),
) -> Outcome {
    let opts = QualityOptions {
        min_angle: lo,
        max_angle: hi,
        ..QualityOptions::default()
    };
    let o = mesh_and_improve_with(field, alpha, beta, &opts);
    check_invariants_with(name, field, alpha, beta, &o, VOLUME_AT_HIGHER_TARGETS);
    o
}

fn check_angles(name: &str, o: &Outcome, floor: (f64, f64)) {
    assert!(
        o.min_angle >= floor.0 && o.max_angle <= floor.1,
        "{name}: dihedral angles [{}, {}] outside [{}, {}]",
        o.min_angle,
        o.max_angle,
        floor.0,
        floor.1
    );
}

#[test]
fn sphere_and_torus() {
    for (name, f) in [("sphere", sphere(30, 9.3)), ("torus", torus(36, 10.0, 4.2))] {
        let o = mesh_and_improve(&f, f64::NEG_INFINITY, 0.0);
        check_invariants(name, &f, f64::NEG_INFINITY, 0.0, &o);
        check_angles(name, &o, FLOOR);
    }
}

#[test]
fn thin_shell_and_close_balls_keep_their_topology() {
    let f = sphere(26, 8.3);
    let o = mesh_and_improve(&f, -0.6, 0.6);
    check_invariants("shell", &f, -0.6, 0.6, &o);
    check_angles("shell", &o, FLOOR);
    let f = two_balls(31, 7.0, 0.3);
    let o = mesh_and_improve(&f, f64::NEG_INFINITY, 0.0);
    check_invariants("two balls", &f, f64::NEG_INFINITY, 0.0, &o);
    assert_eq!(mesh_betti(&o.after)[0], 2, "the two balls stay apart");
    check_angles("two balls", &o, FLOOR);
}

#[test]
fn higher_targets_climb_in_stages_and_never_end_below_a_lower_one() {
    // Aimed straight at 20° (one pass), the thin shell collapses across its 1.2-voxel layer
    // and ends below what the default target gives (measured on the benchmark's 32³ shell:
    // 12.5° against 15.0°). In stages (15°, then 2.5° higher at a time), each higher target
    // ends at least where the lower one did. Higher targets coarsen more, and the splits and
    // the volume restoration may not take a tet below the target, so the volume may move by
    // more than the default's 0.5 % (measured here: the shell -0.52 % at 20°; docs/QUALITY-LOG.md).
    for (name, f, alpha, beta) in [
        ("shell", sphere(26, 8.3), -0.6, 0.6),
        ("torus", torus(36, 10.0, 4.2), f64::NEG_INFINITY, 0.0),
    ] {
        let mut last = mesh_and_improve(&f, alpha, beta);
        for (lo, hi) in [(20.0, 150.0), (25.0, 145.0)] {
            let what = format!("{name} at {lo}°/{hi}°");
            let o = improve_at_targets(&what, &f, (alpha, beta), (lo, hi));
            assert!(
                o.min_angle >= last.min_angle - 1e-9,
                "{what}: {}° after {}° at the lower target",
                o.min_angle,
                last.min_angle
            );
            last = o;
        }
    }
}

#[test]
fn a_boundary_collapse_limit_keeps_the_invariants_and_the_shell_at_its_target() {
    // Boundary collapses limited to three times the mean edge at the removed node (the
    // default) keep the invariants on a 1.2-voxel layer, end at the targets, and their
    // smallest angle is no worse than unlimited ones'. The limit used to raise this shell's smallest angle (27.32° -> 28.08° at
    // 30°/140°); since warping snaps vertices whose link the other level crosses and the
    // smoothing takes one step a call, both end at the target
    // here, and on no benchmark shell at 24³-40³ does the limit change the angles
    // (docs/QUALITY-LOG.md, 2026-12-05). Without the edge splits, which change the shell's
    // last elements either way.
    let f = benchmark_shell(36);
    let unlimited = QualityOptions {
        min_angle: 30.0,
        max_angle: 140.0,
        boundary_collapse_ratio: f64::INFINITY,
        split_sag: f64::INFINITY,
        ..QualityOptions::default()
    };
    let free = mesh_and_improve_with(&f, -0.6, 0.6, &unlimited);
    let opts = QualityOptions {
        boundary_collapse_ratio: 3.0,
        ..unlimited.clone()
    };
    let limited = mesh_and_improve_with(&f, -0.6, 0.6, &opts);
    check_invariants("shell, limited collapses", &f, -0.6, 0.6, &limited);
    assert!(
        limited.min_angle >= free.min_angle - 1e-6
            && limited.min_angle >= 30.0 - 1e-6
            && limited.max_angle <= 140.0 + 1e-6,
        "limited [{}, {}] vs unlimited [{}, {}]",
        limited.min_angle,
        limited.max_angle,
        free.min_angle,
        free.max_angle
    );
}

#[test]
fn volume_restoration_moves_only_level_nodes_and_lowers_no_element() {
    // Restoration is the pass's last stage: the same pass without it is the mesh it starts
    // from. It must give volume back (torus: -0.36 % -> -0.14 %, shell: -0.51 % -> -0.07 %,
    // measured with the link-snapping warping), keep every tet and every interior node, and take no element below the
    // target that was not below it (nor lower one that was).
    for (name, f, a, b) in [
        ("torus", torus(36, 10.0, 4.2), f64::NEG_INFINITY, 0.0),
        ("shell", sphere(24, 7.5), -0.6, 0.6),
    ] {
        // Without the edge splits, which add tets where the restoration's regions are.
        let on = QualityOptions {
            split_sag: f64::INFINITY,
            ..QualityOptions::default()
        };
        let off = QualityOptions {
            restore_volume: false,
            ..on.clone()
        };
        let (without, with) = (
            mesh_and_improve_with(&f, a, b, &off),
            mesh_and_improve_with(&f, a, b, &on),
        );
        let change = |m: &TetMesh| volume_change(&with.before, m).abs();
        assert!(
            change(&with.after) < 0.6 * change(&without.after),
            "{name}: volume change {} with restoration, {} without",
            change(&with.after),
            change(&without.after)
        );
        assert!(
            with.after.tets == without.after.tets && with.after.boundary == without.after.boundary,
            "{name}: the tets or the boundary faces changed"
        );
        let level = level_nodes(&with.after);
        for (v, (p, q)) in with
            .after
            .points
            .iter()
            .zip(&without.after.points)
            .enumerate()
        {
            assert!(p == q || level[v], "{name}: interior node {v} moved");
        }
        assert_no_angle_lost(&format!("{name}, restoration"), &with, &without);
    }
}

#[test]
fn boundary_splits_give_a_thin_tube_its_volume_back() {
    // A torus whose tube is 1.9 voxels in radius: its boundary nodes on the level set inscribe
    // the surface in it, and without splits the pass leaves it 1.13 % below the plain mesh,
    // which is within 0.1 % of the trilinear volume; with them 0.55 % below (measured). That
    // is still more than the quality goal allows (0.5 %): splits that would make poor tets are not
    // made. The benchmark's genus-3 solid (tubes of the same radius) goes from -1.08 % to
    // -0.32 % (docs/QUALITY-LOG.md).
    let f = torus(28, 8.0, 1.9);
    let truth = reference::sample(&f, 12, f64::NEG_INFINITY, 0.0).volume();
    let no_splits = QualityOptions {
        split_sag: f64::INFINITY,
        ..QualityOptions::default()
    };
    let without = mesh_and_improve_with(&f, f64::NEG_INFINITY, 0.0, &no_splits);
    let with = mesh_and_improve(&f, f64::NEG_INFINITY, 0.0);
    check_invariants_with("thin torus", &f, f64::NEG_INFINITY, 0.0, &with, 1e-2);
    let error = |m: &TetMesh| (total_volume(m) / truth - 1.0).abs();
    assert!(
        error(&with.after) < 0.6 * error(&without.after),
        "thin torus: volume error {} with splits, {} without",
        error(&with.after),
        error(&without.after)
    );
    assert!(
        with.after.points.len() > without.after.points.len(),
        "thin torus: no node was added"
    );
    assert_no_angle_lost("thin torus, splits", &with, &without);
}

/// A last stage (`with` it, against the same pass `without` it) takes no element below the
/// target that was not below it, nor lowers the smallest angle where it was below.
fn assert_no_angle_lost(what: &str, with: &Outcome, without: &Outcome) {
    let target = QualityOptions::default().min_angle;
    assert!(
        with.min_angle >= without.min_angle.min(target) - 1e-9,
        "{what}: smallest angle {} with, {} without",
        with.min_angle,
        without.min_angle
    );
}

/// Per point: is it a corner of an alpha or beta face?
fn level_nodes(mesh: &TetMesh) -> Vec<bool> {
    let mut on = vec![false; mesh.points.len()];
    for (tri, label) in mesh.boundary.iter().zip(&mesh.boundary_labels) {
        if *label != tptd::BoundaryLabel::Box {
            for &v in tri {
                on[v as usize] = true;
            }
        }
    }
    on
}

#[test]
fn random_fields_and_box_cuts_keep_their_invariants() {
    for seed in 0..3 {
        let f = random_smooth(16, seed);
        let o = mesh_and_improve(&f, -0.4, 0.5);
        // Coarse wavy fields bend their level sets within a voxel: seed 1 moves by 1.4 %,
        // towards the trilinear volume (its plain mesh is 1.0 % short of it).
        check_invariants(&format!("random {seed}"), &f, -0.4, 0.5, &o);
    }
}

/// [`random_smooth`] scaled to `0..=255` and rounded, as 8-bit imaging data is.
fn quantised_random(n: usize, seed: u64) -> Field {
    let mut f = random_smooth(n, seed);
    let (lo, hi) = value_range(&f);
    for v in &mut f.values {
        *v = ((*v - lo) / (hi - lo) * 255.0).round();
    }
    f
}

#[test]
fn quantised_random_fields_end_on_their_levels() {
    // Half-integer bounds on 8-bit data: the trilinear level set bends away from the
    // piecewise-linear one along the decomposition's diagonals, so some level vertices cannot
    // be projected along the gradient without inverting a tet (before the detour and untangling
    // steps, these left 1, 3 and 1 vertices off their level).
    for (seed, a, b) in [(1, 60.5, 200.5), (6, 127.5, 167.5)] {
        let f = quantised_random(24, seed);
        let o = mesh_and_improve(&f, a, b);
        check_invariants(&format!("quantised random {seed} [{a}, {b}]"), &f, a, b, &o);
    }
}

/// Seed 4 of [`quantised_random_fields_end_on_their_levels`]: one level vertex whose
/// projection onto its level set would make its boundary faces cross another part of the
/// boundary stays 1.4 grey levels off it (the embedding guard keeps it where it is). Open:
/// moving it needs its neighbours moved first.
#[test]
#[ignore = "the embedding guard leaves one node off its level here"]
fn quantised_random_field_4_ends_on_its_levels() {
    let f = quantised_random(24, 4);
    let o = mesh_and_improve(&f, 100.5, 140.5);
    check_invariants("quantised random 4 [100.5, 140.5]", &f, 100.5, 140.5, &o);
}

#[test]
fn ties_with_integer_data() {
    let f = quantised(18);
    for (a, b) in [(6.0, 12.0), (5.5, 11.5)] {
        let o = mesh_and_improve(&f, a, b);
        // Bounds equal to data values: the tie rule's slivers are merged away and the
        // boundary moves onto the level set through the tied vertices.
        check_invariants(&format!("quantised [{a}, {b}]"), &f, a, b, &o);
    }
}

#[test]
fn output_does_not_depend_on_the_thread_count() {
    let f = random_smooth(14, 7);
    let grid = ScalarGrid::new(f.dims, f.values.clone()).unwrap();
    let opts = MeshOptions::new(-0.3, 0.6, Method::Ctd).warp(DEFAULT_WARP);
    let out = mesh_interval(&grid, &opts.clone().threads(Some(1))).unwrap();
    let out2 = mesh_interval(&grid, &opts.threads(Some(2))).unwrap();
    assert!(
        out.mesh == out2.mesh && out.snapped == out2.snapped,
        "warped meshes differ between 1 and 2 threads"
    );
    // The default pass, and one in stages (a higher target).
    let higher = QualityOptions {
        min_angle: 22.0,
        max_angle: 148.0,
        ..QualityOptions::default()
    };
    for q in [QualityOptions::default(), higher] {
        let (mut one, mut two) = (out.clone(), out.clone());
        improve_with_threads(&grid, &mut one, (-0.3, 0.6), &q, 1);
        improve_with_threads(&grid, &mut two, (-0.3, 0.6), &q, 2);
        assert!(
            one.mesh == two.mesh,
            "1 and 2 threads give different meshes at {}°/{}°",
            q.min_angle,
            q.max_angle
        );
    }
}

#[test]
fn thin_shells_reach_the_default_target() {
    // The benchmark's thin shell (1.2 voxels) at sizes where, before warping snapped vertices
    // whose link the other level crosses, the default pass needed one of three
    // mechanisms to reach 15° (measured then): the last round's slab boundaries shifted by
    // half a slab (48³: 11.1° with every round cut alike), stuck regions retried with other
    // smoothing (36³: 14.19° without; 24³: 14.84° without, 15.00° after the second variant)
    // and the compass search (20³: 13.82° without). With that warping the shell starts with
    // a third of the slivers and every size from 20³ to 48³ reaches 15° with any one of the
    // three turned off (measured), so this test now checks the outcome only: no small
    // benchmark domain shows those mechanisms at the default target today, the full-size
    // volumes do (the T1 band ends at 9.44° without the compass search, 9.65° without the
    // shift, 11.51° with both; docs/QUALITY-LOG.md, 2026-12-04).
    for n in [48, 36, 24, 20] {
        let (name, o) = default_shell(n);
        check_angles(&name, &o, FLOOR);
    }
}

#[test]
fn every_target_stage_polishes_its_stuck_regions() {
    // Stages above the default do not retry stuck regions (that made them worse), but each
    // stage's last round polishes them with the compass search. The benchmark's 24³ shell at
    // 25°/145° ends at 21.82° without it, 25.00° with it (measured on build 879126a's
    // warping, which joins snapped nodes; on the link-snapping warping the 36³ shell at 20°/150° showed it,
    // 16.93° -> 20.00°, and no longer does).
    let (name, o) = shell_at_targets(24, (25.0, 145.0));
    check_angles(&name, &o, (25.0 - 1e-9, 145.0 + 1e-9));
}

#[test]
fn a_collapse_judged_after_its_moves_frees_stuck_caps() {
    // Some tets left below the target need two steps: a collapse that alone leaves a poor
    // tet, then moves that lift it. The polish of a stuck region tries such collapses on a
    // copy and keeps one when the region's worst tet ends higher (src/improve/composite.rs).
    // Measured on the link-snapping warping: the benchmark's genus-3 solid at 35³ ends at 13.68°
    // without it, 15.00° with it; the 34³ shell at 25°/145° at 21.87° without, 25.00° with.
    // On build 879126a's warping the genus-3 solid reaches 15° without it too, and the shell
    // ends at 22.13° without it (measured): the shell is what this test can fail on.
    // (Before that warping the 30³ and 40³ shells and the 28³ shell at 25°/145° showed it;
    // they reach their targets without it now.)
    let f = genus3(35);
    let o = mesh_and_improve(&f, f64::NEG_INFINITY, 0.0);
    check_invariants("genus 3, 35³", &f, f64::NEG_INFINITY, 0.0, &o);
    check_angles("genus 3, 35³", &o, FLOOR);
    let (name, o) = shell_at_targets(34, (25.0, 145.0));
    assert!(o.min_angle >= 24.0, "{name}: {}°", o.min_angle);
}

#[test]
fn stages_above_the_default_polish_twice() {
    // The polishing round shifts the slab boundaries by half a slab; a bad tet whose corners
    // straddle a shifted boundary is never whole in one region there. In the stages above the
    // default a second polishing round follows with the boundaries back in place. The
    // benchmark's 30³ shell at 30°/140° ends at 28.49° with one polishing round, 30.00° with
    // two (measured with one smoothing step a call; over the shells at 24³–40³
    // the second round raised 10 of 17 and none fell. Before, the 36³ shell showed it with
    // the one-division sine, 29.21° -> 30.00°, the 29³ one with the sine edge by edge,
    // 27.83° -> 30.00°, and on the link-snapping warping the genus-3 solid at 36³ and 25°/145°,
    // 24.81° -> 25.00°).
    let (name, o) = shell_at_targets(30, (30.0, 140.0));
    check_angles(&name, &o, (30.0 - 1e-9, 140.0 + 1e-9));
}

/// [`benchmark_shell`] at `n`³ through a pass at `targets` (degrees), its invariants checked
/// ([`improve_at_targets`]); with its name.
fn shell_at_targets(n: usize, (lo, hi): (f64, f64)) -> (String, Outcome) {
    let name = format!("{n}³ shell at {lo}°/{hi}°");
    let o = improve_at_targets(&name, &benchmark_shell(n), (-0.6, 0.6), (lo, hi));
    (name, o)
}

/// [`benchmark_shell`] at `n`³ through the default pass, its invariants checked; with its
/// name.
fn default_shell(n: usize) -> (String, Outcome) {
    let f = benchmark_shell(n);
    let o = mesh_and_improve(&f, -0.6, 0.6);
    let name = format!("{n}³ shell");
    check_invariants(&name, &f, -0.6, 0.6, &o);
    (name, o)
}

/// The thin shell of the benchmarks (`benchmarks/data/quality/shell_N.npy`): a sphere of
/// radius 0.35 N around the centre grid point, samples rounded to `f32`, meshed at
/// `[-0.6, 0.6]`.
fn benchmark_shell(n: usize) -> Field {
    let c = (n / 2) as f64;
    in_f32(sphere_at(n, c, 0.35 * n as f64))
}

/// `f` with its samples rounded to `f32`, as the benchmarks' `.npy` files hold them.
fn in_f32(mut f: Field) -> Field {
    f.values.iter_mut().for_each(|v| *v = *v as f32 as f64);
    f
}

#[test]
fn a_higher_target_ends_at_least_where_the_default_pass_does() {
    // The first stage of a ladder is the default pass, stuck regions retried as in the
    // single pass. Without the retries there, the benchmark's 24³ shell ended at 14.84° at
    // 20°/150° against 15.00° by default (measured before the link-snapping warping; 20.00° with them; since
    // that build's warping it starts better and ends at 20.02° either way).
    let f = benchmark_shell(24);
    let default = mesh_and_improve(&f, -0.6, 0.6);
    let higher = improve_at_targets("24³ shell at 20°/150°", &f, (-0.6, 0.6), (20.0, 150.0));
    assert!(
        higher.min_angle >= default.min_angle - 1e-9,
        "24³ shell: {}° at 20°/150°, {}° by default",
        higher.min_angle,
        default.min_angle
    );
}

#[test]
fn the_volume_warping_moved_is_given_back() {
    // Warping merges the cuts at a snapped grid vertex into it, so a thin tube's boundary has
    // fewer nodes and it shrinks. `improve_meshed` owes that volume like the operations';
    // `improve` on the same warped mesh does not know it. Measured on this torus (tube 1.9
    // voxels in radius): -0.55 % of the plain mesh's volume (measured), and more than three
    // times that without.
    let f = torus(28, 8.0, 1.9);
    let with = mesh_and_improve(&f, f64::NEG_INFINITY, 0.0);
    let grid = ScalarGrid::new(f.dims, f.values.clone()).unwrap();
    let opts = MeshOptions::new(f64::NEG_INFINITY, 0.0, Method::Ctd).warp(DEFAULT_WARP);
    let mut out = mesh_interval(&grid, &opts).unwrap();
    assert!(!out.snapped.is_empty(), "nothing was snapped");
    let q = QualityOptions::default();
    tptd::improve::improve(&mut out.mesh, &grid, f64::NEG_INFINITY, 0.0, &q);
    let change = |m: &TetMesh| volume_change(&with.before, m).abs();
    assert!(
        change(&with.after) < 0.3 * change(&out.mesh),
        "volume change {} with the warping's volume owed, {} without",
        change(&with.after),
        change(&out.mesh)
    );
    check_invariants_with("thin torus", &f, f64::NEG_INFINITY, 0.0, &with, 1e-2);
}

/// The benchmark's two balls (`quality.py`): radius 0.22 N, 0.3 voxel apart across the grid
/// plane through the centre `N / 2`, `f32` samples.
fn benchmark_two_balls(n: usize) -> Field {
    let c = (n / 2) as f64;
    let r = 0.22 * n as f64;
    let off = r + 0.15;
    sampled(n, |x, y, z| {
        let d = |cx: f64| ((x - cx).powi(2) + (y - c).powi(2) + (z - c).powi(2)).sqrt() - r;
        d(c - off).min(d(c + off)) as f32 as f64
    })
}

#[test]
fn a_small_convex_part_gets_its_volume_back_by_splits() {
    // The benchmark's two balls at 20³ (radius 4.4 voxels): the restoration's node moves
    // along the level set left the mesh 0.70 % short of its plain volume (`tptd-mesh`); the
    // residual's splits of the chords that sag by a third and a tenth of the default bring
    // it within 0.4 %.
    check_sublevel_volume("two balls, 20³", &benchmark_two_balls(20), 4e-3);
}

#[test]
fn volume_left_after_the_last_stage_is_spread_over_the_boundary() {
    // The benchmark's genus-3 solid at 23³ (tubes 1.4 voxels in radius): the regions around
    // where the volume was lost gave back all they could with their tets at the target and
    // left the mesh 0.58 % short of its plain volume; spread over every boundary node and
    // restored once more, -0.17 % (both measured). At 20³ (tubes 1.2 voxels) the mesh still
    // ends 0.41 % short (docs/QUALITY-LOG.md, *The clipper's point order*).
    check_sublevel_volume("genus 3, 23³", &genus3(23), 2.5e-3);
}

/// Improves the mesh of `{f <= 0}` and checks that its volume moved by less than `limit`
/// (relative), with the invariants and the angle floor.
fn check_sublevel_volume(name: &str, f: &Field, limit: f64) {
    let o = mesh_and_improve(f, f64::NEG_INFINITY, 0.0);
    let change = volume_change(&o.before, &o.after);
    assert!(
        change.abs() < limit,
        "{name}: volume {:+.3} %",
        100.0 * change
    );
    check_invariants(name, f, f64::NEG_INFINITY, 0.0, &o);
    check_angles(name, &o, FLOOR);
}

#[test]
fn a_pass_that_leaves_a_small_solid_off_its_volume_runs_again() {
    // Small solids with parts a voxel or two thick: boundary collapses along long edges take
    // volume the restoration cannot give back. Measured with one smoothing step a call, with the run again
    // turned off: a torus of tube radius 1.76 voxels at 22³ -0.80 %, the genus-3 solid at
    // 20³ without the edge splits -1.04 %. Run again with boundary collapses limited to
    // shorter edges, they end at -0.34 % and +0.03 %. (Since the smoothing takes one step a
    // call, the genus-3 solid at 19³ and 20³ with the splits no longer needs it: -0.16 % and
    // -0.35 % either way.) With the sagging edges split, the torus's plain mesh is 0.16 %
    // larger (382.07 against 381.46, the trilinear volume by quadrature 381.46) and the pass
    // ends at -0.52 % of it with two runs again, -0.44 % with a third at an eighth.
    ends_near_its_volume(
        "thin torus, 22³",
        &torus(22, 6.6, 1.76),
        &QualityOptions::default(),
    );
}

/// The genus-3 solid of [`a_pass_that_leaves_a_small_solid_off_its_volume_runs_again`]
/// without the edge splits: since the embedding guard it ends at -1.6 % (the guard refuses
/// some of the collapses and moves that the restoration relied on). Open.
#[test]
#[ignore = "the embedding guard leaves this solid 1.6 % off its volume"]
fn the_genus_3_solid_without_splits_ends_near_its_volume() {
    let no_splits = QualityOptions {
        split_sag: f64::INFINITY,
        ..QualityOptions::default()
    };
    ends_near_its_volume("genus 3, 20³, no splits", &genus3(20), &no_splits);
}

/// Meshes `{f <= 0}` with `opts`, checks the invariants and the angles, and that the volume
/// changed by less than 0.5 % (the quality pass's volume rule).
fn ends_near_its_volume(name: &str, f: &Field, opts: &QualityOptions) {
    let o = mesh_and_improve_with(f, f64::NEG_INFINITY, 0.0, opts);
    check_invariants(name, f, f64::NEG_INFINITY, 0.0, &o);
    check_angles(name, &o, FLOOR);
    let change = volume_change(&o.before, &o.after).abs();
    assert!(change < VOLUME_FLOOR, "{name}: volume change {change}");
}

#[test]
fn a_pass_of_no_rounds_leaves_the_warped_mesh_valid() {
    // `max_rounds: 0` once ran the off-level round anyway, on no tet qualities, and panicked.
    let field = sphere(12, 4.3);
    let q = QualityOptions {
        max_rounds: 0,
        ..QualityOptions::default()
    };
    let o = mesh_and_improve_with(&field, -1.0, 0.0, &q);
    // No projection either: the snapped nodes stay at their grid vertices.
    check_mesh(&o.after);
    check_labels(&o.after, -1.0, 0.0, extent(&field));
    assert_eq!(mesh_betti(&o.after), mesh_betti(&o.before));
}

/// The whole MNI152 2009a T1 template (nilearn's copy, as a `.npy`: unit spacing, zero
/// origin) at 127.0135, near 8 critical values: the quality pass once made a face of three
/// tets there (a 3-2 flip in a region made the face of three frozen corners that a tet outside
/// the region already had). Whole volume only (crops of it around the place passed); about 4
/// minutes on one thread, so ignored. Needs python3 with numpy, nibabel and nilearn; skipped
/// with a note otherwise.
#[test]
#[ignore = "whole MNI152 T1 volume, about 4 minutes on one thread"]
fn quality_keeps_the_mni_t1_conforming_near_critical_values() {
    let dir = std::env::temp_dir().join(format!("tptd-mni-t1-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let npy = dir.join("t1.npy");
    let script = "import sys, os, numpy as np, nibabel, nilearn\n\
        d = os.path.join(os.path.dirname(nilearn.__file__), 'datasets', 'data')\n\
        img = nibabel.load(os.path.join(d, 'mni_icbm152_t1_tal_nlin_sym_09a_converted.nii.gz'))\n\
        np.save(sys.argv[1], np.ascontiguousarray(np.asarray(img.dataobj)))\n";
    let made = std::process::Command::new("python3")
        .args(["-c", script])
        .arg(&npy)
        .output();
    if !made.is_ok_and(|o| o.status.success()) {
        eprintln!("note: skipped: needs python3 with numpy, nibabel and nilearn (its MNI152 T1)");
        return;
    }
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_tptd-mesh"))
        .arg(&npy)
        .args(["--alpha", "127.0135", "-j", "1", "--quality", "-o"])
        .arg(dir.join("t1.msh"))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let mesh = tptd::io::read_mesh(&dir.join("t1.msh")).unwrap().mesh;
    std::fs::remove_dir_all(&dir).ok();
    // Without the grid: the level distance is off at this level already in the plain mesh.
    let report = tptd::check::check_mesh(&mesh, &tptd::check::CheckOptions::default());
    assert!(report.valid, "{}", report.summary_line());
}
