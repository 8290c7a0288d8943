//! Meshes made by Gmsh itself (a unit ball, `.msh` 4.1 and 2.2, physical groups `alpha` and
//! `domain`) read by the library's reader and solved: the reader handles a real peer's files
//! (several entities, point and line elements, nodes on lower-dimensional entities).
//!
//! A missing `gmsh` makes the test fail unless `TPTD_SKIP_EXTERNAL=1`.

use std::process::Command;

use solver_demo::pcg::PcgOptions;
use solver_demo::run::{solve, Options};
use tptd::io::read_mesh;

const GEO: &str = "SetFactory(\"OpenCASCADE\");\nSphere(1) = {0, 0, 0, 1};\n\
Physical Volume(\"domain\") = {1};\nPhysical Surface(\"alpha\") = {1};\n\
Mesh.CharacteristicLengthMax = 0.2;\n";

#[test]
fn gmsh_balls_are_read_and_solved() {
    let have = Command::new("sh")
        .args(["-c", "command -v gmsh"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !have && std::env::var("TPTD_SKIP_EXTERNAL").is_ok_and(|v| v == "1") {
        return;
    }
    assert!(have, "gmsh is not installed (apt-get install gmsh)");
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("ball.geo"), GEO).unwrap();
    let mut meshes = Vec::new();
    for format in ["msh41", "msh22"] {
        let out = dir.path().join(format!("{format}.msh"));
        let o = Command::new("gmsh")
            .args(["-3", "ball.geo", "-format", format, "-o"])
            .arg(&out)
            .current_dir(dir.path())
            .output()
            .unwrap();
        let log = String::from_utf8_lossy(&o.stdout);
        assert!(
            o.status.success() && !log.contains("Error"),
            "gmsh failed:\n{log}"
        );
        let file = read_mesh(&out).unwrap_or_else(|e| panic!("{e}"));
        let volume: f64 = (0..file.mesh.tets.len())
            .map(|t| file.mesh.tet_volume(t).abs())
            .sum();
        let ball = 4.0 / 3.0 * std::f64::consts::PI;
        assert!(
            (volume - ball).abs() < 0.03 * ball,
            "{format}: volume {volume}"
        );
        assert_eq!(file.regions, vec!["domain".to_string()]);
        let alpha = file.group("alpha").expect("alpha group");
        for &v in &alpha.nodes {
            let p = file.mesh.points[v as usize];
            let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
            assert!((r - 1.0).abs() < 1e-6, "{format}: alpha node at r = {r}");
        }
        assert!(file.mesh.boundary.len() > 100);
        let opts = Options {
            source: 1.0,
            dirichlet: vec![("alpha".into(), 0.0)],
            pcg: PcgOptions {
                tol: 1e-12,
                ..PcgOptions::default()
            },
            ..Options::default()
        };
        let sol = solve(&file, &opts, &mut |_, _| {}).unwrap();
        let err = file
            .mesh
            .points
            .iter()
            .zip(&sol.u)
            .map(|(p, u)| (u - (1.0 - (p[0] * p[0] + p[1] * p[1] + p[2] * p[2])) / 6.0).abs())
            .fold(0.0, f64::max);
        assert!(err < 0.005, "{format}: max nodal error {err}");
        meshes.push(file.mesh);
    }
    assert_eq!(
        meshes[0].tets, meshes[1].tets,
        "4.1 and 2.2 give the same tets"
    );
    assert_eq!(meshes[0].points, meshes[1].points);
}
