//! Mesh readers: writer → reader round trips (`.msh` 4.1, 2.2 and binary 4.1, `.inp`) and bad
//! files.

use std::path::Path;

use tptd::io::inp::write_inp;
use tptd::io::msh::{write_msh, MshVersion};
use tptd::io::{read_mesh, MeshFile, MeshReadError};
use tptd::{mesh_interval, BoundaryLabel, MeshOptions, Method, ScalarGrid, TetMesh};

/// A spherical shell cut by the grid box: boundary groups alpha, beta and box all occur.
fn shell() -> TetMesh {
    let n = 10;
    let c = 4.5;
    let mut values = Vec::new();
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let d = [i, j, k].map(|x| x as f64 - c);
                values.push((d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt() + 0.01 * i as f64);
            }
        }
    }
    let grid = ScalarGrid::new([n; 3], values).unwrap();
    let mesh = mesh_interval(&grid, &MeshOptions::new(2.0, 5.0, Method::Ctd))
        .unwrap()
        .mesh;
    for l in BoundaryLabel::of_levels(2) {
        assert!(mesh.boundary_labels.contains(&l), "{l:?} missing");
    }
    mesh
}

/// Triangle rotated so that its smallest index comes first (keeps the orientation).
fn canonical(t: [u32; 3]) -> [u32; 3] {
    let k = (0..3).min_by_key(|&k| t[k]).unwrap();
    [t[k], t[(k + 1) % 3], t[(k + 2) % 3]]
}

fn labelled(mesh: &TetMesh, label: BoundaryLabel) -> Vec<[u32; 3]> {
    let mut v: Vec<[u32; 3]> = mesh
        .boundary
        .iter()
        .zip(&mesh.boundary_labels)
        .filter(|&(_, &l)| l == label)
        .map(|(&t, _)| canonical(t))
        .collect();
    v.sort_unstable();
    v
}

fn write(path: &Path, mesh: &TetMesh, version: Option<MshVersion>) {
    let mut buf = Vec::new();
    match version {
        Some(v) => write_msh(mesh, &mut buf, v).unwrap(),
        None => write_inp(mesh, &mut buf).unwrap(),
    }
    std::fs::write(path, buf).unwrap();
}

fn check_round_trip(mesh: &TetMesh, back: &MeshFile, exact_values: bool) {
    assert_eq!(back.mesh.points.len(), mesh.points.len());
    for (p, q) in mesh.points.iter().zip(&back.mesh.points) {
        for k in 0..3 {
            assert!(
                (p[k] - q[k]).abs() <= 1e-12 * p[k].abs().max(1.0),
                "{p:?} vs {q:?}"
            );
        }
    }
    assert_eq!(back.mesh.tets, mesh.tets);
    if exact_values {
        assert_eq!(back.mesh.values, mesh.values);
    }
    for label in BoundaryLabel::of_levels(2) {
        let tris = labelled(mesh, label);
        assert_eq!(labelled(&back.mesh, label), tris, "{label:?} triangles");
        let mut nodes: Vec<u32> = tris.iter().flatten().copied().collect();
        nodes.sort_unstable();
        nodes.dedup();
        let group = back.group(label.name()).expect("group present");
        assert_eq!(group.nodes, nodes, "{label:?} node group");
    }
    assert_eq!(back.regions, vec!["domain".to_string()]);
    assert_eq!(back.tet_region, vec![0; mesh.tets.len()]);
}

#[test]
fn msh_and_inp_round_trip_through_the_readers() {
    let mesh = shell();
    let dir = tempfile::tempdir().unwrap();
    for (name, version) in [
        ("a.msh", Some(MshVersion::V41)),
        ("b.msh", Some(MshVersion::V22)),
        ("d.msh", Some(MshVersion::V41Binary)),
        ("c.inp", None),
    ] {
        let path = dir.path().join(name);
        write(&path, &mesh, version);
        let back = read_mesh(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        check_round_trip(&mesh, &back, version.is_some());
    }
}

#[test]
fn binary_msh_reads_as_its_ascii_twin_and_bad_ones_give_one_line() {
    let mesh = shell();
    let dir = tempfile::tempdir().unwrap();
    let (mut ascii, mut bytes) = (Vec::new(), Vec::new());
    write_msh(&mesh, &mut ascii, MshVersion::V41).unwrap();
    write_msh(&mesh, &mut bytes, MshVersion::V41Binary).unwrap();
    let (a, b) = (dir.path().join("a.msh"), dir.path().join("b.msh"));
    std::fs::write(&a, &ascii).unwrap();
    std::fs::write(&b, &bytes).unwrap();
    assert_eq!(read_mesh(&a).unwrap(), read_mesh(&b).unwrap());
    // A version other than 4.1, a data size other than 8 and a bad int 1 are one line each.
    for (head, want) in [
        ("$MeshFormat\n2.2 1 8\n", "version 2.2"),
        ("$MeshFormat\n4.1 1 4\n", "data size"),
        ("$MeshFormat\n4.1 1 8\nxxxx\n", "not 1"),
    ] {
        let e = error_of(dir.path(), "h.msh", head.as_bytes());
        assert!(e.contains(want), "{e}");
    }
    // Cut anywhere: an error, never a panic.
    for cut in (1..40).map(|k| k * bytes.len() / 41) {
        std::fs::write(&b, &bytes[..cut]).unwrap();
        if let Err(e) = read_mesh(&b) {
            assert!(!e.to_string().contains('\n'), "{e}");
        }
    }
}

/// The error of reading `text` as `name`; checks it is one line naming the file.
fn error_of(dir: &Path, name: &str, text: &[u8]) -> String {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    let e = read_mesh(&path).expect_err(name).to_string();
    assert!(!e.contains('\n'), "multi-line error: {e}");
    assert!(e.starts_with(&path.display().to_string()), "{e}");
    e
}

#[test]
fn bad_files_give_one_line_errors() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let v2 = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n1\n1 0 0 0\n$EndNodes\n";
    let cases: [(&str, String, &str); 8] = [
        ("e.msh", String::new(), "no tetrahedra"),
        ("g.msh", "hello\n".into(), "no $MeshFormat"),
        (
            "b.msh",
            "$MeshFormat\n4.1 1 8\n$EndMeshFormat\n".into(),
            "not 1",
        ),
        (
            "v.msh",
            "$MeshFormat\n3.0 0 8\n$EndMeshFormat\n".into(),
            "version",
        ),
        (
            "u.msh",
            format!("{v2}$Elements\n1\n1 4 0 1 2 3 4\n$EndElements\n"),
            "undefined node",
        ),
        (
            "t.msh",
            format!("{v2}$Elements\n1\n1 11 0 1 1 1 1\n$EndElements\n"),
            "element type",
        ),
        ("x.inp", "*NODE\n1, 0, 0\n".into(), "three coordinates"),
        ("y.inp", "*ELEMENT, TYPE=C3D10\n".into(), "C3D10"),
    ];
    for (name, text, expect) in cases {
        let e = error_of(d, name, text.as_bytes());
        assert!(e.contains(expect), "{name}: {e}");
    }
    let missing = read_mesh(&d.join("none.msh")).unwrap_err();
    assert!(matches!(missing, MeshReadError::Io { .. }), "{missing}");
    let ext = read_mesh(&d.join("a.stl")).unwrap_err();
    assert!(matches!(ext, MeshReadError::UnknownFormat { .. }), "{ext}");
}

#[test]
fn truncated_files_are_errors_not_panics() {
    let mesh = shell();
    let dir = tempfile::tempdir().unwrap();
    for (name, version) in [
        ("a.msh", Some(MshVersion::V41)),
        ("b.msh", Some(MshVersion::V22)),
        ("c.inp", None),
    ] {
        let mut full = Vec::new();
        match version {
            Some(v) => write_msh(&mesh, &mut full, v).unwrap(),
            None => write_inp(&mesh, &mut full).unwrap(),
        }
        // Cut inside the node and element sections (not after the last tet, where a
        // truncated file may still be a valid, smaller mesh).
        let step = full.len() / 23;
        for cut in (1..20).map(|k| k * step / 2) {
            let path = dir.path().join(name);
            std::fs::write(&path, &full[..cut]).unwrap();
            match read_mesh(&path) {
                Err(e) => assert!(!e.to_string().contains('\n'), "{e}"),
                // A .msh cut anywhere lacks its closing `$End` line.
                Ok(_) => assert!(version.is_none(), "{name} cut at {cut} was accepted"),
            }
        }
    }
}

/// `*ELSET` cards after the elements move their elements to their region (listed ids and
/// `GENERATE` ranges); an undefined element is an error naming it.
#[test]
fn inp_element_sets_name_the_regions() {
    let dir = tempfile::tempdir().unwrap();
    let nodes = "*NODE\n1, 0, 0, 0\n2, 1, 0, 0\n3, 0, 1, 0\n4, 0, 0, 1\n5, 1, 1, 1\n";
    let elements =
        "*ELEMENT, TYPE=C3D4, ELSET=DOMAIN\n1, 1, 2, 3, 4\n2, 2, 3, 4, 5\n3, 1, 2, 3, 4\n";
    let sets = "*ELSET, ELSET=CORE\n2\n*ELSET, ELSET=RIM, GENERATE\n3, 3, 1\n";
    let path = dir.path().join("r.inp");
    std::fs::write(&path, format!("{nodes}{elements}{sets}")).unwrap();
    let f = read_mesh(&path).unwrap();
    assert_eq!(f.regions, ["domain", "core", "rim"]);
    assert_eq!(f.tet_region, [0, 1, 2]);
    let bad = format!("{nodes}{elements}*ELSET, ELSET=CORE\n9\n");
    let e = error_of(dir.path(), "b.inp", bad.as_bytes());
    assert!(e.contains("undefined element 9"), "{e}");
}
