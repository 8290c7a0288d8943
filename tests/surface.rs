//! Isosurfaces (`level_surface`, the obj/ply/stl writers) against independent references.
//!
//! * Topology: each MC33 configuration (tests/common/mc33.rs) is placed in the middle cell of
//!   a 4×4×4 grid whose outer vertices lie on the other side of the level, and seeded random
//!   fields are padded the same way, so V = {f > w} (or {f < w}) stays away from the box.
//!   The sampled reference (tests/common/reference.rs, no tptd code) gives the Betti numbers
//!   of V; its boundary surface S then has b0(S) = b2(S) = b0(V) + b2(V), b1(S) = 2·b1(V).
//!   A mismatch counts only when finer sampling confirms it.
//!   `tptd` and `ctd` must match on every resolved case, with a closed, oriented 2-manifold
//!   (checked here by counting directed edges, independently of the crate's analysis); `six`
//!   and `five` must each get at least one case wrong.
//! * Orientation: every triangle's normal points into the tet it bounds on the side of
//!   increasing f (found back in the tet mesh by position).
//! * Writers: OBJ read back with the `tobj` crate; OBJ, PLY (binary and ASCII) and STL (binary
//!   and ASCII) read back with meshio (tests/py/check_surface.py); the bytes are identical for
//!   one and two threads.

mod common;

use std::collections::HashMap;
use std::path::Path;
use std::process::Command;

use common::external::{python, require_python_with, run};
use common::mc33::configs;
use common::reference::{reference_betti, Field, RefBetti};
use common::Rng;
use tptd::io::{SurfaceFormat, WriteOptions};
use tptd::{
    analyse_surface, level_surface, mesh_interval, BoundaryLabel, MeshOptions, Method, ScalarGrid,
    SurfaceOptions, TetMesh, TriSurface,
};

/// Sampling resolutions of the padded fields; all must agree.
const NS: [usize; 2] = [20, 32];
/// Finer resolutions that confirm a mismatch (the coarse ones can agree on a wrong answer
/// when a feature is thinner than a sample).
const FINE: [usize; 2] = [48, 72];

/// `inner` (dims `d`) surrounded by one layer of `pad`.
fn padded(d: [usize; 3], inner: &[f64], pad: f64) -> Field {
    let dims = d.map(|n| n + 2);
    Field::from_fn(dims, |x, y, z| {
        let (i, j, k) = (x as usize, y as usize, z as usize);
        let inside = |c: usize, n: usize| c >= 1 && c <= n;
        if inside(i, d[0]) && inside(j, d[1]) && inside(k, d[2]) {
            inner[(i - 1) + d[0] * ((j - 1) + d[1] * (k - 1))]
        } else {
            pad
        }
    })
}

/// One case: a field and a one-sided interval whose set stays inside the box.
struct Case {
    name: String,
    field: Field,
    alpha: f64,
    beta: f64,
    /// Reference Betti numbers of the surface, if the sampler resolved it.
    expected: Option<[usize; 3]>,
    /// Margin of the reference around critical values.
    margin: f64,
}

impl Case {
    /// Whether the finer reference confirms that `betti` is wrong.
    fn confirmed_wrong(&self, betti: [usize; 3]) -> bool {
        match reference_betti(&self.field, self.alpha, self.beta, self.margin, &FINE) {
            RefBetti::Resolved { betti: v, .. } => boundary_betti(v) != betti,
            RefBetti::Unresolved(_) => false,
        }
    }
}

/// The surface Betti numbers of the boundary of a domain V in the open box.
fn boundary_betti(v: [usize; 3]) -> [usize; 3] {
    [v[0] + v[2], 2 * v[1], v[0] + v[2]]
}

fn case(name: String, field: Field, iso: f64, up: bool, scale: f64) -> Case {
    let (alpha, beta) = if up {
        (iso, f64::INFINITY)
    } else {
        (f64::NEG_INFINITY, iso)
    };
    let margin = 0.002 * scale;
    let expected = match reference_betti(&field, alpha, beta, margin, &NS) {
        RefBetti::Resolved { betti, .. } => Some(boundary_betti(betti)),
        RefBetti::Unresolved(_) => None,
    };
    Case {
        name,
        field,
        alpha,
        beta,
        expected,
        margin,
    }
}

/// Every MC33 configuration, both sides, padded.
fn mc33_cases() -> Vec<Case> {
    let mut out = Vec::new();
    for cfg in configs() {
        let scale = cfg
            .values
            .iter()
            .fold(0.0f64, |m, x| m.max((x - cfg.iso).abs()));
        for up in [true, false] {
            let pad = if up { cfg.iso - scale } else { cfg.iso + scale };
            let f = padded([2, 2, 2], &cfg.values, pad);
            let tag = if up { "up" } else { "down" };
            out.push(case(format!("{} {tag}", cfg.name), f, cfg.iso, up, scale));
        }
    }
    out
}

/// Seeded random 3³ fields in [-1, 1], padded, at a random level near 0.
fn random_cases(n: usize) -> Vec<Case> {
    let mut rng = Rng::new(1017);
    (0..n)
        .map(|i| {
            let inner: Vec<f64> = (0..27).map(|_| rng.range(-1.0, 1.0)).collect();
            let iso = rng.range(-0.3, 0.3);
            let up = i % 2 == 0;
            let pad = if up { iso - 1.5 } else { iso + 1.5 };
            let f = padded([3, 3, 3], &inner, pad);
            case(format!("random {i}"), f, iso, up, 1.0)
        })
        .collect()
}

fn mesh(field: &Field, alpha: f64, beta: f64, method: Method, threads: usize) -> TetMesh {
    let grid = ScalarGrid::new(field.dims, field.values.clone()).unwrap();
    let opts = MeshOptions::new(alpha, beta, method).threads(Some(threads));
    mesh_interval(&grid, &opts).unwrap().mesh
}

/// Independent check of a closed oriented 2-manifold: every directed edge occurs once and
/// its reverse once; every vertex's triangles form one fan (its link is one cycle).
fn closed_oriented_errors(s: &TriSurface) -> Vec<String> {
    let mut errs = Vec::new();
    let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
    for t in &s.triangles {
        for i in 0..3 {
            *directed.entry((t[i], t[(i + 1) % 3])).or_default() += 1;
        }
    }
    for (&(a, b), &n) in &directed {
        if n != 1 || directed.get(&(b, a)) != Some(&1) {
            errs.push(format!(
                "edge {a}-{b}: {n} times, reverse {:?}",
                directed.get(&(b, a))
            ));
        }
    }
    // link of v: next vertex after v -> the one after that; one cycle through all of them
    let mut link: HashMap<u32, HashMap<u32, u32>> = HashMap::new();
    for t in &s.triangles {
        for i in 0..3 {
            link.entry(t[i])
                .or_default()
                .insert(t[(i + 1) % 3], t[(i + 2) % 3]);
        }
    }
    for (v, next) in &link {
        let start = *next.keys().min().unwrap();
        let (mut cur, mut steps) = (start, 0);
        while let Some(&n) = next.get(&cur) {
            steps += 1;
            cur = n;
            if cur == start || steps > next.len() {
                break;
            }
        }
        if cur != start || steps != next.len() {
            errs.push(format!("vertex {v}: link is not one cycle"));
        }
    }
    errs.truncate(4);
    errs
}

/// Problems of the `method` isosurface of case `c` against its reference `expected`: the
/// Betti numbers (only if not confirmed right by `confirm`), closed, oriented, no caps.
fn surface_errors(c: &Case, expected: [usize; 3], method: Method) -> Vec<String> {
    let m = mesh(&c.field, c.alpha, c.beta, method, 1);
    let s = level_surface(&m, &SurfaceOptions::default());
    let a = analyse_surface(&s);
    let mut errs = closed_oriented_errors(&s);
    if a.betti != expected && c.confirmed_wrong(a.betti) {
        errs.push(format!("Betti {:?}, reference {expected:?}", a.betti));
    }
    if !(a.closed_manifold && a.oriented) {
        errs.push("analysis: not a closed oriented manifold".into());
    }
    if s.labels.contains(&BoundaryLabel::Box) {
        errs.push("box triangles without caps".into());
    }
    errs
}

/// Runs `method` on the resolved cases until `max_failures` failed; returns the failures and
/// the number compared.
fn failures(cases: &[Case], method: Method, max_failures: usize) -> (Vec<String>, usize) {
    let mut fails = Vec::new();
    let mut compared = 0;
    for c in cases {
        let Some(expected) = c.expected else { continue };
        compared += 1;
        let errs = surface_errors(c, expected, method);
        if !errs.is_empty() {
            fails.push(format!("{}: {}", c.name, errs.join("; ")));
            if fails.len() == max_failures {
                break;
            }
        }
    }
    (fails, compared)
}

#[test]
fn mc33_and_random_isosurfaces_have_the_trilinear_topology() {
    let mut cases = mc33_cases();
    let n_mc33 = cases.len();
    cases.extend(random_cases(40));
    let resolved = cases.iter().filter(|c| c.expected.is_some()).count();
    let resolved_mc33 = cases[..n_mc33]
        .iter()
        .filter(|c| c.expected.is_some())
        .count();
    println!(
        "{resolved} of {} cases resolved ({resolved_mc33} of {n_mc33} MC33)",
        cases.len()
    );
    assert!(resolved_mc33 >= 150 && resolved >= resolved_mc33 + 25);
    for method in [Method::Tptd, Method::Ctd] {
        let (fails, compared) = failures(&cases, method, usize::MAX);
        println!("{method:?}: {compared} compared, {} wrong", fails.len());
        assert!(
            fails.is_empty(),
            "{method:?}: {} of {compared} wrong:\n{}",
            fails.len(),
            fails.join("\n")
        );
    }
    for method in [Method::Six, Method::Five] {
        // TPTD_SURFACE_ALL=1 counts every (confirmed) failure: slower, each one is resampled
        let all = std::env::var("TPTD_SURFACE_ALL").is_ok_and(|v| v == "1");
        let (fails, compared) = failures(&cases, method, if all { usize::MAX } else { 3 });
        let first = if all { "" } else { "the first " };
        println!(
            "{method:?}: {first}{} wrong of {compared} compared, e.g.:",
            fails.len()
        );
        for f in fails.iter().take(3) {
            println!("  {f}");
        }
        assert!(!fails.is_empty(), "{method:?} should get some case wrong");
    }
}

/// The isosurface of a random padded field, two-sided, from `mesh`.
fn random_two_sided(threads: usize, method: Method) -> (Field, TetMesh, TriSurface) {
    let mut rng = Rng::new(7);
    let inner: Vec<f64> = (0..6 * 5 * 4).map(|_| rng.range(-1.0, 1.0)).collect();
    let f = padded([6, 5, 4], &inner, -2.0);
    let m = mesh(&f, -0.1, 0.35, method, threads);
    let s = level_surface(&m, &SurfaceOptions::default());
    (f, m, s)
}

#[test]
fn normals_point_towards_increasing_f_and_labels_follow_the_levels() {
    let (_, m, s) = random_two_sided(2, Method::Ctd);
    let by_pos: HashMap<[u64; 3], u32> = m
        .points
        .iter()
        .enumerate()
        .map(|(i, p)| (p.map(f64::to_bits), i as u32))
        .collect();
    let mut tet_of_face: HashMap<[u32; 3], usize> = HashMap::new();
    for (t, tet) in m.tets.iter().enumerate() {
        for skip in 0..4 {
            let mut f: Vec<u32> = (0..4).filter(|&i| i != skip).map(|i| tet[i]).collect();
            f.sort_unstable();
            tet_of_face.insert([f[0], f[1], f[2]], t);
        }
    }
    let (mut n_alpha, mut n_beta) = (0, 0);
    for (tri, &label) in s.triangles.iter().zip(&s.labels) {
        let ids = tri.map(|i| by_pos[&s.points[i as usize].map(f64::to_bits)]);
        let level = if label == BoundaryLabel::ALPHA {
            -0.1
        } else {
            0.35
        };
        for i in ids {
            assert!(
                (m.values[i as usize] - level).abs() < 1e-9,
                "{label:?} vertex off its level"
            );
        }
        let mut key = ids;
        key.sort_unstable();
        let tet = m.tets[tet_of_face[&key]];
        let apex = *tet.iter().find(|v| !ids.contains(v)).unwrap();
        let [a, b, c] = ids.map(|i| m.points[i as usize]);
        let d = m.points[apex as usize];
        let side = common::invariants::tet_volume(
            &TetMesh {
                points: vec![a, b, c, d],
                ..Default::default()
            },
            [0, 1, 2, 3],
        );
        // the tet lies on the normal side for alpha (f grows into the interval) and on the
        // other side for beta; its apex value says the same
        let (into, apex_up) = (side > 0.0, m.values[apex as usize] > level);
        match label {
            BoundaryLabel::ALPHA => {
                n_alpha += 1;
                assert!(into && apex_up);
            }
            BoundaryLabel::BETA => {
                n_beta += 1;
                assert!(!into && !apex_up);
            }
            _ => panic!("no caps asked for"),
        }
    }
    assert!(
        n_alpha > 100 && n_beta > 100,
        "{n_alpha} alpha, {n_beta} beta"
    );
    // both levels stay inside the box: closed, oriented, and the two surfaces nest
    assert!(closed_oriented_errors(&s).is_empty());
}

fn write_to_vec(s: &TriSurface, format: SurfaceFormat, ascii: bool) -> Vec<u8> {
    let mut b = Vec::new();
    format
        .write(s, &mut b, &WriteOptions::default().with_ascii(ascii))
        .unwrap();
    b
}

#[test]
fn output_is_identical_for_one_and_two_threads() {
    for method in [Method::Ctd, Method::Tptd, Method::Five] {
        let (_, _, s1) = random_two_sided(1, method);
        let (_, _, s2) = random_two_sided(2, method);
        for f in [SurfaceFormat::Obj, SurfaceFormat::Ply, SurfaceFormat::Stl] {
            for ascii in [false, true] {
                assert!(
                    write_to_vec(&s1, f, ascii) == write_to_vec(&s2, f, ascii),
                    "{f:?}"
                );
            }
        }
    }
}

#[test]
fn obj_round_trips_through_tobj() {
    let (_, _, s) = random_two_sided(2, Method::Ctd);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s.obj");
    tptd::io::write_surface(&path, &s, &WriteOptions::default()).unwrap();
    let (models, _) = tobj::load_obj(&path, &tobj::LoadOptions::default()).unwrap();
    let names: Vec<&str> = models.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["alpha", "beta"]);
    for m in &models {
        let label = if m.name == "alpha" {
            BoundaryLabel::ALPHA
        } else {
            BoundaryLabel::BETA
        };
        let ours: Vec<[f64; 3]> = s
            .triangles
            .iter()
            .zip(&s.labels)
            .filter(|(_, &l)| l == label)
            .flat_map(|(t, _)| t.map(|i| s.points[i as usize]))
            .collect();
        let mesh = &m.mesh;
        assert_eq!(mesh.indices.len(), ours.len(), "{}", m.name);
        for (k, &i) in mesh.indices.iter().enumerate() {
            let p = &mesh.positions[3 * i as usize..3 * i as usize + 3];
            for a in 0..3 {
                // tobj reads f64 (its `use_f64` feature, for `io::read_surface`)
                let tol = 1e-6 * ours[k][a].abs().max(1.0);
                assert!((p[a] - ours[k][a]).abs() < tol);
            }
        }
    }
    // welded: tobj's single-index load keeps one vertex per OBJ vertex
    let (all, _) = tobj::load_obj(
        &path,
        &tobj::LoadOptions {
            single_index: true,
            ..Default::default()
        },
    )
    .unwrap();
    let vertices: usize = all.iter().map(|m| m.mesh.positions.len() / 3).sum();
    assert_eq!(vertices, s.points.len(), "alpha and beta share no vertex");
}

#[test]
fn obj_ply_stl_round_trip_through_meshio() {
    if !require_python_with("meshio") {
        return;
    }
    // unpadded: both levels and the caps occur
    let mut rng = Rng::new(8);
    let f = Field::new([6, 5, 4], (0..120).map(|_| rng.range(-1.0, 1.0)).collect());
    let m = mesh(&f, -0.1, 0.35, Method::Ctd, 2);
    let s = level_surface(
        &m,
        &SurfaceOptions {
            caps: true,
            beta: 0.35,
        },
    );
    for l in BoundaryLabel::of_levels(2) {
        assert!(s.labels.contains(&l), "{l:?}");
    }
    let dir = tempfile::tempdir().unwrap();
    let expected = dir.path().join("expected.json");
    let labels: Vec<u8> = s.labels.iter().map(|&l| l.code(2) as u8).collect();
    let json = serde_json::json!({
        "points": s.points, "triangles": s.triangles, "labels": labels,
        "area": analyse_surface(&s).area,
    });
    std::fs::write(&expected, json.to_string()).unwrap();
    for (name, ascii) in [
        ("s.obj", false),
        ("s.ply", false),
        ("a.ply", true),
        ("s.stl", false),
        ("a.stl", true),
    ] {
        let path = dir.path().join(name);
        tptd::io::write_surface(&path, &s, &WriteOptions::default().with_ascii(ascii)).unwrap();
        check_py(&path, &expected);
    }
}

fn check_py(path: &Path, expected: &Path) {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/py/check_surface.py");
    let (ok, out) = run(Command::new(python()).arg(script).arg(path).arg(expected));
    assert!(ok, "meshio failed on {}:\n{out}", path.display());
    println!("{}", out.trim());
}
