//! Several levels in one mesh (`MeshOptions::levels`): the regions between consecutive levels
//! meshed in one pass. Each region's tets, taken alone, are a valid mesh with the Betti
//! numbers of its interval and its sampled volume; the union passes the library checker as
//! the mesh of `[L1, Ln]` (so it conforms across the levels between regions: no face there
//! is open) and has the union's Betti numbers; the faces shared by tets of two regions lie on
//! the level between them; one and two threads give identical meshes. Fields: nested
//! spheres (one with a region 0.15 voxel thin), a torus inside a shell, two balls touching the
//! level between them at a saddle (against the dense-sampling reference), a linear field
//! (volumes), seeded smooth random fields with 2–4 regions (against the same interval meshed
//! alone), and integer data tied with inner levels (conformity only).
//!
//! Every case runs again with the quality pass (`tptd::improve::improve_levels`): the same
//! checks, and besides them every interface node on its trilinear level set (to 1e-6 of the
//! data range; not with integer ties, where the level set is degenerate), each region's volume
//! within [`REGION_VOLUME`] of its plain mesh's or closer to the sampled trilinear volume, and
//! one and two threads giving identical meshes.

mod common;

use std::collections::HashMap;

use common::invariants::{mesh_betti, mesh_errors, region_submesh, total_volume};
use common::reference::{sample, sampled_betti, Field};
use common::Rng;
use tptd::check::{check_mesh, CheckOptions};
use tptd::improve::{improve_levels, QualityOptions};
use tptd::levels::Levels;
use tptd::{mesh_interval, MeshOptions, Method, ScalarGrid, TetMesh};

/// Outward faces of a positive tet `[a, b, c, d]`.
fn tet_faces(t: [u32; 4]) -> [[u32; 3]; 4] {
    [
        [t[1], t[2], t[3]],
        [t[0], t[3], t[2]],
        [t[0], t[1], t[3]],
        [t[0], t[2], t[1]],
    ]
}

fn sorted(mut f: [u32; 3]) -> [u32; 3] {
    f.sort_unstable();
    f
}

/// What a region's (and the union's) Betti numbers are compared with.
#[derive(Clone, Copy, PartialEq)]
enum Truth {
    /// The dense-sampling reference of the trilinear interval (when it agrees at two
    /// resolutions).
    Sampled,
    /// The single-interval mesh of the same interval, by TPTD: for random fields, whose
    /// levels may fall near critical values that the sampler does not resolve (the single
    /// interval is checked against the sampled reference in `tests/properties.rs`).
    SingleInterval,
    /// None: integer data with levels equal to data values (ties), where a region's set
    /// depends on which side of a level the tied values are given.
    Nothing,
}

/// A field, its levels and what its Betti numbers are compared with.
struct Case {
    name: String,
    field: Field,
    levels: Vec<f64>,
    truth: Truth,
}

/// The Betti numbers `(a, b)` must have, if known (see [`Truth`]).
fn expected(case: &Case, a: f64, b: f64) -> Option<[usize; 3]> {
    match case.truth {
        Truth::Sampled => reference(&case.field, a, b),
        Truth::SingleInterval => {
            let f = &case.field;
            let grid = ScalarGrid::new(f.dims, f.values.clone()).unwrap();
            let opts = MeshOptions::new(a, b, Method::Tptd);
            Some(mesh_betti(&mesh_interval(&grid, &opts).unwrap().mesh))
        }
        Truth::Nothing => None,
    }
}

/// Betti numbers of `(a, b)` sampled at 4 and 6 sub-voxels per cell when they agree.
fn reference(field: &Field, a: f64, b: f64) -> Option<[usize; 3]> {
    let r = sampled_betti(field, 4, a, b);
    (sampled_betti(field, 6, a, b) == r).then_some(r)
}

/// The mesh of `case` by `method`, with the quality pass when `quality`, in a pool of
/// `threads` threads.
fn mesh_case(case: &Case, method: Method, quality: bool, threads: usize) -> TetMesh {
    let grid = ScalarGrid::new(case.field.dims, case.field.values.clone()).unwrap();
    let opts = MeshOptions::default()
        .method(method)
        .levels(&case.levels)
        .threads(Some(threads));
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let mut mesh = mesh_interval(&grid, &opts).unwrap().mesh;
        if quality {
            let levels = Levels::new(&case.levels).unwrap();
            improve_levels(&mut mesh, &grid, &levels, &QualityOptions::default());
        }
        mesh
    })
}

/// Meshes `case` and checks everything the module documentation lists (with the quality
/// pass when `quality`); returns the number of regions (and the union) whose reference could
/// not be resolved.
fn check_case(case: &Case, method: Method, quality: bool) -> usize {
    let Case {
        name,
        field,
        levels,
        ..
    } = case;
    let grid = ScalarGrid::new(field.dims, field.values.clone()).unwrap();
    let one = mesh_case(case, method, quality, 1);
    let two = mesh_case(case, method, quality, 2);
    assert!(
        one == two,
        "{name} {method:?} quality {quality}: threads differ"
    );
    let plain = quality.then(|| mesh_case(case, method, false, 2));
    let name = &format!("{name}{}", if quality { " (quality)" } else { "" });
    let (mesh, regions) = (&one, &one.regions.tets);
    assert_eq!(regions.len(), mesh.tets.len(), "{name}");
    let (first, last) = (levels[0], levels[levels.len() - 1]);
    let errs = mesh_errors(mesh);
    assert!(errs.is_empty(), "{name} {method:?}: {errs:?}");
    let all = Levels::new(levels).unwrap();
    let report = check_mesh(mesh, &CheckOptions::with_levels(&grid, all));
    assert!(report.valid, "{name} {method:?}: {}", report.summary_line());
    let mut unresolved = 0;
    match expected(case, first, last) {
        Some(b) => assert_eq!(mesh_betti(mesh), b, "{name} {method:?}: union"),
        None => unresolved += 1,
    }
    interfaces_lie_on_their_levels(mesh, regions, levels, name);
    if quality && case.truth != Truth::Nothing {
        interface_nodes_on_their_level_sets(mesh, field, levels, name);
    }
    for k in 0..levels.len() - 1 {
        let sub = region_submesh(mesh, k as u8);
        let errs = mesh_errors(&sub);
        assert!(errs.is_empty(), "{name} {method:?} region {k}: {errs:?}");
        let (a, b) = (levels[k], levels[k + 1]);
        match expected(case, a, b) {
            Some(r) => assert_eq!(mesh_betti(&sub), r, "{name} {method:?} region {k}"),
            None => unresolved += 1,
        }
        if case.truth != Truth::Nothing {
            let want = sample(field, 8, a, b).volume();
            let got = total_volume(&sub);
            // The mesh is linear inside tets: it differs from the trilinear volume only in
            // cells a level crosses, by well under a tenth of a cell each (as in
            // tests/properties.rs), plus 2 %.
            let tol = 0.1 * crossed_cells(field, a, b) as f64 + 0.02 * want;
            assert!(
                (got - want).abs() <= tol,
                "{name} region {k}: volume {got} vs {want}"
            );
            if let Some(plain) = &plain {
                let before = total_volume(&region_submesh(plain, k as u8));
                assert!(
                    (got - before).abs() <= REGION_VOLUME * before
                        || (got - want).abs() < (before - want).abs(),
                    "{name} region {k}: volume {before} -> {got} (sampled {want})"
                );
            }
        }
    }
    unresolved
}

/// How far the quality pass may move a region's volume from its plain mesh's when it does not
/// bring it nearer the sampled trilinear volume. The goal is the single interval's 0.5 %; small
/// regions bounded by interfaces are not there yet (measured: the top region of random field 2,
/// two blobs of 29 voxels³ in all, −3.6 %, against −0.4 % meshed alone; a ball of radius 2.7
/// voxels inside three shells −1.5 %; docs/QUALITY-LOG.md, *The quality pass with several
/// regions*).
const REGION_VOLUME: f64 = 0.04;

/// Every node of an interface lies on its level set of the trilinear field, to 1e-6 of the
/// data range.
fn interface_nodes_on_their_level_sets(mesh: &TetMesh, field: &Field, levels: &[f64], name: &str) {
    let (lo, hi) = field
        .values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    for (tri, label) in mesh
        .regions
        .interfaces
        .iter()
        .zip(&mesh.regions.interface_labels)
    {
        let level = levels[label.level().unwrap()];
        for &p in tri {
            let f = field.eval(mesh.points[p as usize]);
            assert!(
                (f - level).abs() <= 1e-6 * (hi - lo),
                "{name}: interface node {p} at f = {f}, level {level}"
            );
        }
    }
}

/// Cells whose corner values straddle `a` or `b`.
fn crossed_cells(field: &Field, a: f64, b: f64) -> usize {
    let [cx, cy, cz] = field.cell_dims();
    let cells = (0..cz).flat_map(|k| (0..cy).flat_map(move |j| (0..cx).map(move |i| [i, j, k])));
    cells
        .filter(|c| {
            let v = field.corners(c[0], c[1], c[2]);
            let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            (lo <= a && a < hi) || (lo < b && b <= hi)
        })
        .count()
}

/// Every face shared by tets of two regions joins consecutive regions and lies on the level
/// between them; some such face exists wherever two regions have tets.
fn interfaces_lie_on_their_levels(mesh: &TetMesh, regions: &[u8], levels: &[f64], name: &str) {
    let mut owner: HashMap<[u32; 3], u8> = HashMap::new();
    let mut shared = 0;
    for (t, &r) in mesh.tets.iter().zip(regions) {
        for f in tet_faces(*t) {
            let Some(o) = owner.insert(sorted(f), r) else {
                continue;
            };
            if o == r {
                continue;
            }
            shared += 1;
            assert_eq!(o.abs_diff(r), 1, "{name}: regions {o} and {r} share a face");
            let level = levels[o.max(r) as usize];
            for p in f {
                assert_eq!(
                    mesh.values[p as usize], level,
                    "{name}: interface off its level"
                );
            }
        }
    }
    let used: std::collections::BTreeSet<u8> = regions.iter().copied().collect();
    let adjacent = used
        .iter()
        .zip(used.iter().skip(1))
        .any(|(a, b)| b - a == 1);
    assert!(!adjacent || shared > 0, "{name}: no interface face");
    assert_eq!(
        shared,
        mesh.regions.interfaces.len(),
        "{name}: interfaces listed"
    );
}

/// The checker finds a mesh's regions broken: an interface dropped, one turned over, and a
/// tet moved to another region.
#[test]
fn the_checker_finds_broken_regions() {
    use tptd::check::ProblemKind::*;
    let field = sphere_distance(16, 7.3);
    let grid = ScalarGrid::new(field.dims, field.values.clone()).unwrap();
    let levels = [f64::NEG_INFINITY, 2.7, 5.2];
    let out = mesh_interval(&grid, &MeshOptions::default().levels(&levels)).unwrap();
    let check = |m: &TetMesh| {
        let opts = CheckOptions::with_levels(&grid, Levels::new(&levels).unwrap());
        check_mesh(m, &opts)
    };
    assert!(
        check(&out.mesh).valid,
        "{}",
        check(&out.mesh).summary_line()
    );
    let mut dropped = out.mesh.clone();
    dropped.regions.interfaces.pop();
    dropped.regions.interface_labels.pop();
    assert_eq!(check(&dropped).kinds(), [UnlistedInterface]);
    let mut turned = out.mesh.clone();
    turned.regions.interfaces[0].swap(1, 2);
    assert_eq!(
        check(&turned).kinds(),
        [UnlistedInterface, InterfaceNotBetweenRegions]
    );
    let mut moved = out.mesh.clone();
    let t = moved.regions.tets.iter().position(|&r| r == 1).unwrap();
    moved.regions.tets[t] = 0;
    assert!(check(&moved).has(UnlistedInterface) || check(&moved).has(InterfaceNotBetweenRegions));
    moved.regions.tets[t] = 2;
    assert_eq!(check(&moved).kinds(), [RegionCount]);
}

fn sphere_distance(n: usize, c: f64) -> Field {
    Field::from_fn([n; 3], |x, y, z| {
        ((x - c).powi(2) + (y - c).powi(2) + (z - c).powi(2)).sqrt()
    })
}

fn analytic_cases() -> Vec<Case> {
    let torus_in_shell = Field::from_fn([28; 3], |x, y, z| {
        let (x, y, z) = (x - 13.7, y - 13.4, z - 13.6);
        let ring = (((x * x + y * y).sqrt() - 5.1).powi(2) + z * z).sqrt();
        let shell = ((x * x + y * y + z * z).sqrt() - 11.3).abs();
        ring.min(shell)
    });
    // Two balls whose {f <= 4.3} parts touch through a saddle of f at about 4.0 between them.
    let balls = Field::from_fn([24, 16, 16], |x, y, z| {
        let d = |cx: f64| ((x - cx).powi(2) + (y - 7.6).powi(2) + (z - 7.3).powi(2)).sqrt();
        d(7.2).min(d(15.1))
    });
    vec![
        Case {
            name: "nested spheres".into(),
            field: sphere_distance(24, 11.3),
            levels: vec![3.3, 6.1, 9.2],
            truth: Truth::Sampled,
        },
        Case {
            // A layer 0.15 voxel thin between two regions of normal thickness.
            name: "thin shell between shells".into(),
            field: sphere_distance(24, 11.3),
            levels: vec![3.3, 3.45, 6.1],
            truth: Truth::SingleInterval,
        },
        Case {
            name: "ball in shells".into(),
            field: sphere_distance(24, 11.7),
            levels: vec![f64::NEG_INFINITY, 2.7, 5.3, 7.9, 10.2],
            truth: Truth::Sampled,
        },
        Case {
            name: "torus inside a shell".into(),
            field: torus_in_shell,
            levels: vec![f64::NEG_INFINITY, 1.3, 2.6],
            truth: Truth::Sampled,
        },
        Case {
            name: "two balls touching at a saddle".into(),
            field: balls,
            levels: vec![f64::NEG_INFINITY, 3.1, 4.3, 5.7],
            truth: Truth::Sampled,
        },
    ]
}

#[test]
fn analytic_fields_have_each_region_s_topology() {
    for case in analytic_cases() {
        for method in [Method::Ctd, Method::Tptd] {
            for quality in [false, true] {
                assert_eq!(
                    check_case(&case, method, quality),
                    0,
                    "{}: unresolved",
                    case.name
                );
            }
        }
    }
}

/// A region 0.15 voxel thin between two shells keeps its plain volume through the quality
/// pass to the single interval's 0.5 %: the merges that coarsen either of its sides cut
/// chords into the convex side of its spheres, and each region's volume budget in a copy
/// counts them on the domain's boundary as on the interface (without the budget on the
/// boundary's vertices it grew 13.5 %, without any budget 1.3 %).
#[test]
fn a_thin_shell_between_shells_keeps_its_volume() {
    let case = analytic_cases()
        .into_iter()
        .find(|c| c.name == "thin shell between shells")
        .unwrap();
    for method in [Method::Ctd, Method::Tptd] {
        let plain = total_volume(&region_submesh(&mesh_case(&case, method, false, 2), 0));
        let got = total_volume(&region_submesh(&mesh_case(&case, method, true, 2), 0));
        assert!(
            (got - plain).abs() <= 0.005 * plain,
            "{method:?}: thin region {plain} -> {got}"
        );
    }
}

/// A linear field is meshed exactly: each region's volume is that of its slab of the box.
#[test]
fn linear_field_regions_have_exact_volumes() {
    let n = 9;
    let field = Field::from_fn([n; 3], |x, y, z| x + 0.37 * y + 0.11 * z);
    let levels = [1.3, 2.9, 4.45, 6.2];
    let grid = ScalarGrid::new(field.dims, field.values.clone()).unwrap();
    let out = mesh_interval(&grid, &MeshOptions::default().levels(&levels)).unwrap();
    let fine = sample(&field, 40, levels[0], levels[3]).volume();
    let mut sum = 0.0;
    for k in 0..3u8 {
        let sub = region_submesh(&out.mesh, k);
        let got = total_volume(&sub);
        let want = sample(&field, 40, levels[k as usize], levels[k as usize + 1]).volume();
        assert!(
            (got - want).abs() < 2e-2,
            "region {k}: {got} vs sampled {want}"
        );
        sum += got;
    }
    assert!((sum - total_volume(&out.mesh)).abs() < 1e-9);
    // The exact volume of {a < x + 0.37 y + 0.11 z < b} in the box, by fine sampling: the
    // two agree to the sampling error only, the regions' sum to rounding.
    assert!((sum - fine).abs() < 2e-2, "{sum} vs {fine}");
}

/// Smooth random fields (sums of a few Gaussian bumps) with 2–4 regions between random
/// levels spread over the value range; each region has the topology of the same interval
/// meshed alone.
#[test]
fn random_smooth_fields_have_each_region_s_topology() {
    let mut rng = Rng::new(0x5eed_1e7e15);
    let (mut unresolved, mut total) = (0, 0);
    for case in 0..12 {
        let dims = [rng.usize(8, 14), rng.usize(8, 14), rng.usize(8, 14)];
        let bumps: Vec<([f64; 3], f64, f64)> = (0..5)
            .map(|_| {
                let c = dims.map(|d| rng.range(0.0, d as f64 - 1.0));
                (c, rng.range(-1.0, 1.0), rng.range(2.0, 4.0))
            })
            .collect();
        let field = Field::from_fn(dims, |x, y, z| {
            bumps
                .iter()
                .map(|(c, h, w)| {
                    let r2 = (x - c[0]).powi(2) + (y - c[1]).powi(2) + (z - c[2]).powi(2);
                    h * (-r2 / (w * w)).exp()
                })
                .sum()
        });
        let (lo, hi) = field
            .values
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        let count = 3 + case % 3;
        let mut levels: Vec<f64> = (0..count)
            .map(|i| lo + (hi - lo) * (i as f64 + rng.range(0.2, 0.8)) / count as f64)
            .collect();
        levels.sort_by(f64::total_cmp);
        let c = Case {
            name: format!("random {case}"),
            field,
            levels,
            truth: Truth::SingleInterval,
        };
        for method in [Method::Ctd, Method::Tptd] {
            for quality in [false, true] {
                unresolved += check_case(&c, method, quality);
                total += c.levels.len();
            }
        }
    }
    assert_eq!(unresolved, 0, "of {total}");
}

/// Integer data (smooth bumps rounded) with integer levels: many vertices equal an inner
/// level. They belong to the region below it on both sides, so the mesh still conforms,
/// passes the checker and has its interfaces on the levels (topology is not compared: at
/// such levels it depends on which side the tied values are given).
#[test]
fn integer_data_tied_with_inner_levels_still_conforms() {
    let field = Field::from_fn([13, 11, 12], |x, y, z| {
        let b = |cx: f64, cy: f64, cz: f64, w: f64| {
            (-((x - cx).powi(2) + (y - cy).powi(2) + (z - cz).powi(2)) / (w * w)).exp()
        };
        (9.0 * b(4.0, 5.0, 6.0, 3.5) + 7.0 * b(9.0, 5.5, 5.0, 3.0)).round()
    });
    assert!(
        field
            .values
            .iter()
            .filter(|&&v| v == 3.0 || v == 5.0)
            .count()
            > 20
    );
    let c = Case {
        name: "integer ties".into(),
        field,
        levels: vec![1.0, 3.0, 5.0, 8.0],
        truth: Truth::Nothing,
    };
    for method in [Method::Ctd, Method::Tptd] {
        for quality in [false, true] {
            check_case(&c, method, quality);
        }
    }
}
