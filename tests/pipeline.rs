//! The meshing run as a library call ([`tptd::pipeline::mesh_file`]), without the binary:
//! the stages reach the progress receiver in order and each one ends, the warnings reach it
//! as they occur and come back in the report, errors are one line with their kind, and a
//! failed run leaves no output. The same run on a grid in memory ([`mesh_grid`]) gives the
//! same mesh and writes nothing, or hands it to a caller's sink as it is made
//! ([`mesh_grid_into`]).

mod common;

use std::path::Path;
use std::sync::Mutex;

use common::files::write_npy;
use tptd::pipeline::{
    mesh_file, mesh_grid, mesh_grid_into, MeshRequest, NoProgress, PipelineError, Progress,
    QualityRequest, StageKind,
};
use tptd::sdf::SurfaceGridOptions;
use tptd::{MeshChunk, MeshSink, ScalarGrid};

/// A [`Progress`] that records every call, one line each.
#[derive(Default)]
struct Record(Mutex<Vec<String>>);

impl Record {
    fn push(&self, line: String) {
        self.0.lock().unwrap().push(line);
    }

    fn lines(&self) -> Vec<String> {
        self.0.lock().unwrap().clone()
    }
}

impl Progress for Record {
    fn stage(&self, name: &str, kind: StageKind) {
        let kind = match kind {
            StageKind::Step => "step",
            StageKind::Meshing { .. } => "meshing",
            StageKind::Pass => "pass",
            StageKind::Sampling => "sampling",
        };
        self.push(format!("stage {kind} {name}"));
    }
    fn fraction(&self, _done: u64, _total: u64) {}
    fn message(&self, message: &str) {
        self.push(format!("message {message}"));
    }
    fn finish(&self) {
        self.push("finish".into());
    }
    fn warn(&self, message: &str) {
        self.push(format!("warn {message}"));
    }
}

/// The stage lines of `lines`, each checked to be followed by its `finish` before the next.
fn stages(lines: &[String]) -> Vec<String> {
    let mut open = false;
    let mut out = Vec::new();
    for l in lines {
        if let Some(s) = l.strip_prefix("stage ") {
            assert!(!open, "stages nest: {lines:?}");
            open = true;
            out.push(s.to_string());
        } else if l == "finish" {
            assert!(open, "a finish without a stage: {lines:?}");
            open = false;
        }
    }
    assert!(!open, "a stage never finished: {lines:?}");
    out
}

#[test]
fn the_demo_streams_to_disk_with_its_comparison_and_report() {
    let dir = tempfile::tempdir().unwrap();
    let req = MeshRequest {
        output: Some(dir.path().join("demo.vtu")),
        report: Some(dir.path().join("demo.json")),
        ..MeshRequest::default()
    };
    let record = Record::default();
    let run = mesh_file(&req, &record).unwrap();
    assert!(run.report.tets > 0);
    assert_eq!(run.report.betti.map(|b| b[0]), Some(2));
    assert_eq!(run.comparison.map(|c| c.other_b0), Some(1));
    assert!(run.report.timings_seconds.streamed && run.mesh.is_none());
    assert!(dir.path().join("demo.vtu").is_file() && dir.path().join("demo.json").is_file());
    let out = dir.path().join("demo.vtu").display().to_string();
    let expected = [
        "step reading demo",
        "meshing meshing",
        &format!("step writing {out}"),
    ];
    assert_eq!(stages(&record.lines()), expected);
}

#[test]
fn the_quality_pass_holds_the_mesh_and_names_its_stages() {
    let dir = tempfile::tempdir().unwrap();
    let req = MeshRequest {
        output: Some(dir.path().join("q.msh")),
        quality: Some(QualityRequest {
            options: Default::default(),
            seconds: None,
        }),
        check: true,
        ..MeshRequest::default()
    };
    let record = Record::default();
    let run = mesh_file(&req, &record).unwrap();
    assert!(run.mesh.is_some() && run.report.quality.is_some() && run.report.check.is_some());
    let stages = stages(&record.lines());
    let names: Vec<&str> = stages
        .iter()
        .map(|s| s.split(' ').next().unwrap())
        .collect();
    assert_eq!(names, ["step", "meshing", "pass", "step", "step", "step"]);
    assert_eq!(stages[2], "pass improving elements");
    assert!(record
        .lines()
        .iter()
        .any(|l| l.starts_with("message giving a reason")));
}

#[test]
fn warnings_reach_the_progress_as_they_occur_and_the_report() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("steps.npy");
    write_npy(&input, [12, 12, 12], |i, j, k| ((i + j + k) % 5) as f64);
    let req = MeshRequest {
        input: Some(input.clone()),
        alpha: Some(2.0),
        beta: Some(3.5),
        output: Some(dir.path().join("steps.inp")),
        ..MeshRequest::default()
    };
    let record = Record::default();
    let run = mesh_file(&req, &record).unwrap();
    let given: Vec<String> = record
        .lines()
        .iter()
        .filter_map(|l| l.strip_prefix("warn ").map(str::to_string))
        .collect();
    assert!(!given.is_empty());
    assert_eq!(run.warnings(), given.as_slice());
    let name = input.display().to_string();
    assert!(given[0].starts_with(&format!("{name}: alpha 2 equals the value of")));
}

/// Runs `req` and expects an error; no file of `dir` but `keep` is left.
fn fails(req: &MeshRequest, dir: &Path, keep: &[&str]) -> PipelineError {
    let e = match mesh_file(req, &NoProgress) {
        Ok(_) => panic!("the run succeeded"),
        Err(e) => e,
    };
    for f in std::fs::read_dir(dir).unwrap() {
        let name = f.unwrap().file_name().to_string_lossy().to_string();
        assert!(keep.contains(&name.as_str()), "{name} left behind");
    }
    e
}

#[test]
fn errors_are_one_line_with_their_kind_and_leave_no_output() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("m.vtu");
    let empty = MeshRequest {
        alpha: Some(2.0),
        beta: Some(1.0),
        output: Some(out.clone()),
        ..MeshRequest::default()
    };
    let e = fails(&empty, dir.path(), &[]);
    assert_eq!(
        e.to_string(),
        "demo: empty interval: alpha (2) must be less than beta (1)"
    );
    assert!(!e.is_usage());

    let clash = MeshRequest {
        output: Some(out.clone()),
        report: Some(out.clone()),
        ..MeshRequest::default()
    };
    assert!(fails(&clash, dir.path(), &[]).is_usage());

    let nothing = MeshRequest {
        alpha: Some(1e9),
        output: Some(out),
        ..MeshRequest::default()
    };
    let e = fails(&nothing, dir.path(), &[]);
    assert!(
        e.message().contains("contains no part of the volume"),
        "{e}"
    );
}

/// A unit cube as an OBJ, outward.
fn write_cube(path: &Path) {
    let mut s = String::new();
    for k in 0..8 {
        s += &format!("v {} {} {}\n", k & 1, (k >> 1) & 1, (k >> 2) & 1);
    }
    for f in [
        [1, 3, 4, 2],
        [5, 6, 8, 7],
        [1, 2, 6, 5],
        [3, 7, 8, 4],
        [1, 5, 7, 3],
        [2, 4, 8, 6],
    ] {
        s += &format!("f {} {} {} {}\n", f[0], f[1], f[2], f[3]);
    }
    std::fs::write(path, s).unwrap();
}

#[test]
fn a_closed_surface_is_sampled_as_a_stage_of_its_own() {
    let dir = tempfile::tempdir().unwrap();
    let cube = dir.path().join("cube.obj");
    write_cube(&cube);
    let out = dir.path().join("cube.vtu");
    let req = MeshRequest {
        input: Some(cube.clone()),
        output: Some(out.clone()),
        surface_grid: SurfaceGridOptions {
            resolution: Some(8),
            ..SurfaceGridOptions::default()
        },
        ..MeshRequest::default()
    };
    let record = Record::default();
    let run = mesh_file(&req, &record).unwrap();
    assert_eq!(run.report.betti, Some([1, 0, 0]));
    assert!(
        (run.report.volume - 1.0).abs() < 0.03,
        "{}",
        run.report.volume
    );
    // 8 voxels, half a voxel and 3 more on each side
    assert_eq!(run.grid.dims, [16, 16, 16]);
    assert!(run.warnings().is_empty(), "{:?}", run.warnings());
    let expected = [
        format!("step reading {}", cube.display()),
        "sampling signed distance".to_string(),
        "meshing meshing".to_string(),
        format!("step writing {}", out.display()),
    ];
    assert_eq!(stages(&record.lines()), expected);
    // a grid for a surface, asked of a volume: a usage error before any work
    let demo = MeshRequest {
        output: Some(dir.path().join("demo.vtu")),
        ..req
    };
    let volume = MeshRequest {
        input: None,
        ..demo
    };
    let e = fails(&volume, dir.path(), &["cube.obj", "cube.vtu"]);
    assert!(
        e.is_usage() && e.message().contains("resolution applies only"),
        "{e}"
    );
}

#[test]
fn a_grid_in_memory_meshes_as_its_file_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("steps.npy");
    let f = |i: usize, j: usize, k: usize| ((i * 7 + j * 3 + k * 5) % 11) as f64 + 0.25;
    write_npy(&input, [9, 8, 7], f);
    let req = MeshRequest {
        input: Some(input.clone()),
        levels: Some(vec![2.0, 5.5, 9.0]),
        spacing: Some([0.5, 1.0, 2.0]),
        check: true,
        output: Some(dir.path().join("steps.msh")),
        ..MeshRequest::default()
    };
    let from_file = mesh_file(&req, &NoProgress).unwrap();
    let mut values = Vec::new();
    for k in 0..7 {
        for j in 0..8 {
            for i in 0..9 {
                values.push(f(i, j, k));
            }
        }
    }
    let grid = ScalarGrid::new([9, 8, 7], values).unwrap();
    let memory = MeshRequest {
        output: None,
        ..req.clone()
    };
    std::fs::remove_file(dir.path().join("steps.msh")).unwrap();
    let in_memory = mesh_grid(grid, "volume", &memory, &NoProgress).unwrap();
    let (a, b) = (from_file.mesh.unwrap(), in_memory.mesh.unwrap());
    assert_eq!(a.mesh, b.mesh);
    assert_eq!(from_file.report.tets, in_memory.report.tets);
    assert!(in_memory.report.check.is_some_and(|c| c.valid));
    assert!(
        !dir.path().join("steps.msh").exists(),
        "an in-memory run wrote"
    );

    let bad = MeshRequest {
        alpha: Some(3.0),
        ..memory
    };
    let grid = ScalarGrid::new([2, 2, 2], vec![0.0; 8]).unwrap();
    let e = mesh_grid(grid, "volume", &bad, &NoProgress).err().unwrap();
    assert!(e.message().starts_with("volume: "), "{e}");
    assert!(!e.is_io());
}

#[test]
fn a_missing_input_is_an_error_of_the_system() {
    let dir = tempfile::tempdir().unwrap();
    let req = MeshRequest {
        input: Some(dir.path().join("missing.npy")),
        alpha: Some(1.0),
        output: Some(dir.path().join("m.vtu")),
        ..MeshRequest::default()
    };
    let e = fails(&req, dir.path(), &[]);
    assert!(e.is_io() && !e.is_usage(), "{e}");
    assert!(e.message().contains("missing.npy"), "{e}");
}

/// A run in memory that nothing changes after meshing analyses the mesh while it is made:
/// its report's facts are those of the mesh analysed after the run, with one interval and
/// with several regions, and it says so in its timings.
#[test]
fn a_mesh_in_memory_is_analysed_while_it_is_made() {
    use tptd::facts::MeshFacts;
    let f = |i: usize, j: usize, k: usize| {
        let (x, y, z) = (i as f64 - 6.3, j as f64 - 5.8, k as f64 - 6.1);
        (x * x + y * y + z * z).sqrt() + 0.7 * ((i * 5 + j * 3 + k) % 4) as f64
    };
    let dims = [13, 12, 14];
    let values: Vec<f64> = (0..dims[2])
        .flat_map(|k| (0..dims[1]).flat_map(move |j| (0..dims[0]).map(move |i| f(i, j, k))))
        .collect();
    let cases = [
        (None, Some(3.3), Some(6.6)),
        (Some(vec![f64::NEG_INFINITY, 2.3, 4.6, 6.9]), None, None),
    ];
    for (levels, alpha, beta) in cases {
        let req = MeshRequest {
            levels: levels.clone(),
            alpha,
            beta,
            ..MeshRequest::default()
        };
        let grid = ScalarGrid::new(dims, values.clone()).unwrap();
        let run = mesh_grid(grid, "volume", &req, &NoProgress).unwrap();
        assert!(run.report.timings_seconds.analysed_while_meshing);
        let mesh = run.mesh.unwrap().mesh;
        let after = MeshFacts::of(&mesh, true, levels.as_deref().unwrap_or(&[]));
        let r = &run.report;
        assert_eq!((r.nodes, r.tets), (after.nodes, after.tets));
        assert!(
            (r.volume - after.volume).abs() <= 1e-9 * after.volume,
            "{levels:?}"
        );
        assert_eq!(r.betti, after.betti, "{levels:?}");
        let d = r.dihedral_degrees.as_ref().unwrap();
        assert_eq!(Some((d.min, d.max)), after.dihedral, "{levels:?}");
        assert_eq!(r.regions.len(), after.regions.len());
        for (a, b) in r.regions.iter().zip(&after.regions) {
            assert_eq!((a.tets, a.betti), (b.tets, b.betti), "{}", a.name);
            assert!((a.volume - b.volume).abs() <= 1e-9 * b.volume, "{}", a.name);
        }
    }
}

/// The chunks a sink is handed, concatenated, and how many there were.
#[derive(Default)]
struct Chunks {
    points: Vec<[f64; 3]>,
    tets: Vec<[u32; 4]>,
    regions: Vec<u8>,
    triangles: usize,
    count: usize,
}

impl MeshSink for Chunks {
    fn chunk(&mut self, c: &MeshChunk) -> std::io::Result<()> {
        assert_eq!(
            (c.first_point, c.first_tet),
            (self.points.len(), self.tets.len())
        );
        self.points.extend_from_slice(&c.points);
        self.tets.extend_from_slice(&c.tets);
        self.regions.extend_from_slice(&c.regions);
        self.triangles += c.boundary.len();
        self.count += 1;
        Ok(())
    }
}

/// A run in memory that nothing needs whole after meshing hands the mesh to the caller's
/// sink slab by slab (the chunks make the mesh `mesh_grid` holds, with one interval and with
/// several regions) and holds none; with the check it holds the mesh and the sink gets
/// nothing.
#[test]
fn a_sink_takes_the_mesh_as_it_is_made_when_nothing_needs_it_whole() {
    let dims = [11, 10, 12];
    let values: Vec<f64> = (0..dims[0] * dims[1] * dims[2])
        .map(|n| ((n * 7) % 13) as f64 * 0.5 + (n % 5) as f64 * 0.1)
        .collect();
    let cases = [
        (None, Some(1.3), Some(4.4)),
        (Some(vec![0.6, 2.3, 4.1, 5.7]), None, None),
    ];
    for (levels, alpha, beta) in cases {
        let req = MeshRequest {
            levels: levels.clone(),
            alpha,
            beta,
            ..MeshRequest::default()
        };
        let grid = || ScalarGrid::new(dims, values.clone()).unwrap();
        let held = mesh_grid(grid(), "volume", &req, &NoProgress).unwrap();
        let held_mesh = held.mesh.unwrap().mesh;
        let mut sink = Chunks::default();
        let run = mesh_grid_into(grid(), "volume", &req, &NoProgress, &mut sink).unwrap();
        assert!(run.mesh.is_none(), "{levels:?}");
        assert!(sink.count > 1, "{levels:?}: {} chunks", sink.count);
        assert_eq!(sink.points, held_mesh.points);
        assert_eq!(sink.tets, held_mesh.tets);
        assert_eq!(sink.regions, held_mesh.regions.tets);
        let triangles = held_mesh.boundary.len() + held_mesh.regions.interfaces.len();
        assert_eq!(sink.triangles, triangles);
        assert_eq!(run.report.tets, held.report.tets);
        assert_eq!(run.report.betti, held.report.betti);

        let checked = MeshRequest {
            check: true,
            ..req.clone()
        };
        let mut sink = Chunks::default();
        let run = mesh_grid_into(grid(), "volume", &checked, &NoProgress, &mut sink).unwrap();
        assert_eq!(sink.count, 0);
        assert_eq!(run.mesh.unwrap().mesh, held_mesh);
    }
}

/// A [`Progress`] that sets the run's stop flag when the stage `at` starts.
struct CancelAt(&'static str, tptd::cancel::Cancel);

impl Progress for CancelAt {
    fn stage(&self, name: &str, _kind: StageKind) {
        if name == self.0 {
            self.1.cancel();
        }
    }
    fn fraction(&self, _done: u64, _total: u64) {}
    fn message(&self, _message: &str) {}
    fn finish(&self) {}
    fn warn(&self, _message: &str) {}
}

/// A run whose caller sets its stop flag while it meshes (streamed to disk or held in
/// memory) or while the quality pass works stops with an interrupted error and leaves no
/// file; the same request with a fresh flag runs to its end.
#[test]
fn a_cancelled_run_stops_and_leaves_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("waves.npy");
    let f = |i: usize, j: usize, k: usize| {
        let (x, y, z) = (i as f64 * 0.35, j as f64 * 0.35, k as f64 * 0.35);
        x.sin() * y.cos() + y.sin() * z.cos() + z.sin() * x.cos()
    };
    write_npy(&input, [24, 24, 24], f);
    let quality = Some(QualityRequest {
        options: Default::default(),
        seconds: None,
    });
    let cases = [
        ("meshing", None, Some("w.vtu")),
        ("meshing", None, None),
        ("improving elements", quality.clone(), Some("w.msh")),
    ];
    for (at, quality, output) in cases {
        let req = MeshRequest {
            input: Some(input.clone()),
            alpha: Some(-0.3013),
            beta: Some(0.2987),
            quality: quality.clone(),
            output: output.map(|o| dir.path().join(o)),
            ..MeshRequest::default()
        };
        let e = mesh_file(&req, &CancelAt(at, req.cancel.clone()))
            .err()
            .unwrap();
        assert!(e.is_interrupted() && !e.is_usage(), "{at}: {e}");
        assert!(e.message().contains("interrupted"), "{e}");
        let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(left.len(), 1, "{at}: the run left files");
        let fresh = MeshRequest {
            cancel: Default::default(),
            ..req
        };
        let run = mesh_file(&fresh, &NoProgress).unwrap();
        assert!(run.report.tets > 0);
        if let Some(o) = output {
            std::fs::remove_file(dir.path().join(o)).unwrap();
        }
    }
}
