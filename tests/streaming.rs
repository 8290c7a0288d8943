//! Streamed meshing and writing (`mesh_interval_streamed` → `SpilledMesh` →
//! `write_spilled_pending`) against the in-memory path (`mesh_interval` → `write_mesh`):
//! the same bytes in every format and encoding, for any number of threads and of slabs in
//! flight; the facts gathered while streaming equal those of the mesh in memory; no spill
//! file is left behind.

mod common;

use std::fs;
use std::path::Path;

use common::Rng;
use tptd::facts::{FactsSink, MeshFacts, Tee};
use tptd::io::{spill_for, write_mesh, write_spilled_pending, WriteOptions};
use tptd::{
    mesh_interval, mesh_interval_streamed, BoundaryLabel, MeshOptions, Method, ScalarGrid, TetMesh,
};

/// A smooth random field with plenty of saddles, in a left- or right-handed frame.
fn field(dims: [usize; 3], seed: u64, left_handed: bool) -> ScalarGrid {
    let mut rng = Rng::new(seed);
    let waves: Vec<[f64; 4]> = (0..6)
        .map(|_| [0.0, 1.0, 2.0, 3.0].map(|_| rng.range(-1.2, 1.2)))
        .collect();
    let mut v = Vec::with_capacity(dims.iter().product());
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                let p = [i as f64, j as f64, k as f64];
                v.push(
                    waves
                        .iter()
                        .map(|w| (w[0] * p[0] + w[1] * p[1] + w[2] * p[2] + 3.0 * w[3]).sin())
                        .sum::<f64>(),
                );
            }
        }
    }
    let mut dir = tptd::grid::IDENTITY;
    if left_handed {
        dir[2][2] = -1.0;
    }
    ScalarGrid::with_geometry(dims, [0.5, 0.7, 0.9], [1.0, -2.0, 3.0], dir, v).unwrap()
}

/// Streams `grid` with `opts` into `dir/name` and returns the bytes and the facts.
fn streamed(
    grid: &ScalarGrid,
    opts: &MeshOptions,
    dir: &Path,
    name: &str,
    w: &WriteOptions,
) -> (Vec<u8>, MeshFacts) {
    let path = dir.join(name);
    let mut spill = spill_for(&path).unwrap();
    let mut facts = FactsSink::new(true);
    mesh_interval_streamed(grid, opts, &|_, _| {}, &mut Tee(&mut spill, &mut facts)).unwrap();
    write_spilled_pending(&path, &mut spill, w)
        .unwrap()
        .commit()
        .unwrap();
    (fs::read(&path).unwrap(), facts.finish())
}

fn in_memory(mesh: &TetMesh, dir: &Path, name: &str, w: &WriteOptions) -> Vec<u8> {
    let path = dir.join(format!("mem-{name}"));
    write_mesh(&path, mesh, w).unwrap();
    fs::read(&path).unwrap()
}

#[test]
fn streamed_output_equals_the_in_memory_output() {
    let dir = tempfile::tempdir().unwrap();
    for (seed, left) in [(1, false), (2, true)] {
        let grid = field([9, 8, 11], seed, left);
        let base = MeshOptions::new(-0.8, 1.1, Method::Ctd);
        let mesh = mesh_interval(&grid, &base).unwrap().mesh;
        let labels: Vec<_> = BoundaryLabel::of_levels(2)
            .map(|l| mesh.boundary_labels.iter().filter(|&&m| m == l).count())
            .collect();
        assert!(
            labels.iter().all(|&n| n > 0),
            "every label occurs: {labels:?}"
        );
        let expect = MeshFacts::of(&mesh, true, &[]);
        for (name, w) in common::output::mesh_outputs() {
            let want = in_memory(&mesh, dir.path(), name, &w);
            for (threads, slabs) in [(1, 1), (2, 3), (2, 0)] {
                let opts = MeshOptions {
                    threads: Some(threads),
                    slabs_in_flight: slabs,
                    ..base.clone()
                };
                let (got, facts) = streamed(&grid, &opts, dir.path(), name, &w);
                let what = format!("{name}, seed {seed}, -j {threads}, {slabs} slabs in flight");
                assert!(got == want, "{what}: streamed bytes differ");
                // Bit for bit, the volume included.
                assert_eq!(facts, expect, "{what}");
            }
        }
    }
    let left: Vec<_> = fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.'))
        .collect();
    assert!(left.is_empty(), "spill or temporary files left: {left:?}");
}

#[test]
fn streamed_facts_match_on_every_method_and_an_empty_mesh() {
    let grid = field([7, 9, 6], 3, false);
    for method in common::ALL_METHODS {
        let opts = MeshOptions::new(-0.5, 0.6, method).threads(Some(2));
        let mesh = mesh_interval(&grid, &opts).unwrap().mesh;
        let mut facts = FactsSink::new(true);
        mesh_interval_streamed(&grid, &opts, &|_, _| {}, &mut facts).unwrap();
        assert_eq!(
            facts.finish(),
            MeshFacts::of(&mesh, true, &[]),
            "{method:?}"
        );
    }
    let opts = MeshOptions::new(100.0, 200.0, Method::Ctd);
    let mut facts = FactsSink::new(true);
    mesh_interval_streamed(&grid, &opts, &|_, _| {}, &mut facts).unwrap();
    let f = facts.finish();
    assert_eq!(
        (f.tets, f.nodes, f.betti, f.dihedral),
        (0, 0, Some([0, 0, 0]), None)
    );
}

#[test]
fn a_failing_sink_stops_meshing_with_its_error() {
    struct Full(usize);
    impl tptd::MeshSink for Full {
        fn chunk(&mut self, _: &tptd::MeshChunk) -> std::io::Result<()> {
            self.0 += 1;
            if self.0 == 3 {
                return Err(std::io::Error::other("disk full"));
            }
            Ok(())
        }
    }
    let grid = field([6, 6, 12], 4, false);
    let opts = MeshOptions::new(-1.0, 1.0, Method::Ctd).threads(Some(2));
    let mut sink = Full(0);
    let e = mesh_interval_streamed(&grid, &opts, &|_, _| {}, &mut sink).unwrap_err();
    assert_eq!(e.to_string(), "disk full");
    assert_eq!(sink.0, 3, "no chunk after the error");
}

/// With several regions, the facts streamed (each region's included) equal those of the mesh
/// in memory, and each region's Betti numbers and volume equal those of its tets meshed as
/// one interval's run would count them (the region's own mesh from the library's checker).
#[test]
fn streamed_region_facts_match_the_mesh_in_memory() {
    let grid = field([12, 11, 10], 5, false);
    let levels = [f64::NEG_INFINITY, -0.4, 0.1, 0.7];
    for method in [Method::Ctd, Method::Tptd] {
        let opts = MeshOptions::default().method(method).levels(&levels);
        let mesh = mesh_interval(&grid, &opts).unwrap().mesh;
        let names = vec!["low".to_string()];
        let mut facts = FactsSink::new(true).with_regions(&levels, names.clone());
        mesh_interval_streamed(&grid, &opts, &|_, _| {}, &mut facts).unwrap();
        let mut named = mesh.clone();
        named.regions.names = names;
        let want = MeshFacts::of(&named, true, &levels);
        let got = facts.finish();
        assert_eq!(got, want, "{method:?}");
        assert_eq!(got.regions.len(), 3);
        let names: Vec<&str> = got.regions.iter().map(|r| r.name.as_str()).collect();
        assert_eq!(names, ["low", "region2", "region3"]);
        let tets: usize = got.regions.iter().map(|r| r.tets).sum();
        assert_eq!(tets, got.tets);
        let volume: f64 = got.regions.iter().map(|r| r.volume).sum();
        assert!((volume - got.volume).abs() < 1e-9 * got.volume);
        for (k, r) in got.regions.iter().enumerate() {
            let sub = common::invariants::region_submesh(&mesh, k as u8);
            assert_eq!(
                r.betti,
                Some(common::invariants::mesh_betti(&sub)),
                "{method:?} {k}"
            );
        }
    }
}

/// A mesh large enough that the writers encode it in several parallel batches (base64
/// batches of megabytes, binary `.msh` windows, spill slices): written by pools of one and
/// of two threads, streamed and from memory, the formats encoded in parallel pieces give
/// the same bytes.
#[test]
fn the_writers_bytes_do_not_depend_on_the_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    let grid = field([44, 42, 40], 6, false);
    let opts = MeshOptions::new(-0.8, 1.1, Method::Ctd).threads(Some(2));
    let mesh = mesh_interval(&grid, &opts).unwrap().mesh;
    // connectivity of more than one base64 batch, tets of more than one binary window
    assert!(mesh.tets.len() > 1 << 19, "{} tets", mesh.tets.len());
    let pool = |n| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .unwrap()
    };
    let touched = ["m41b.msh", "b64.vtu", "raw.vtu"];
    let outputs = common::output::mesh_outputs().into_iter();
    for (name, w) in outputs.filter(|(n, _)| touched.contains(n)) {
        let want = pool(1).install(|| in_memory(&mesh, dir.path(), name, &w));
        let got = pool(2).install(|| in_memory(&mesh, dir.path(), name, &w));
        assert!(got == want, "{name}: in memory, 2 threads");
        for threads in [1, 2] {
            let (got, _) = pool(threads).install(|| streamed(&grid, &opts, dir.path(), name, &w));
            assert!(got == want, "{name}: streamed, {threads} threads");
        }
    }
}
