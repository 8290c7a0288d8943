//! Mesh readers of other tools' formats: TetGen `.node`/`.ele`/`.face`, Medit `.mesh` and
//! `.vtu` (ours in every encoding, and hand-written), on small hand-written files, good and
//! malformed.

use std::path::Path;

use tptd::io::vtu::{write_vtu_with, VtuEncoding};
use tptd::io::{mesh_files, read_mesh, MeshReadError};
use tptd::{mesh_interval, MeshOptions, Method, ScalarGrid};

/// Two tets sharing the face 1 2 3 of the unit tet, in TetGen's files with `base` numbering.
fn tetgen(dir: &Path, base: usize) {
    let b = |i: usize| i + base;
    let node = format!(
        "# a comment\n5 3 1 1\n{} 0 0 0 7.5 1\n{} 1 0 0 7.5 1 # trailing\n\n{} 0 1 0 0 1\n\
         {} 0 0 1 0 1\n{} 1 1 1 0 0\n",
        b(0),
        b(1),
        b(2),
        b(3),
        b(4)
    );
    let ele = format!(
        "2 4 1\n{} {} {} {} {} 1\n{} {} {} {} {} -2\n",
        b(0),
        b(0),
        b(1),
        b(2),
        b(3),
        b(1),
        b(1),
        b(3),
        b(2),
        b(4)
    );
    let face = format!(
        "3 1\n{} {} {} {} 5\n{} {} {} {} 0\n{} {} {} {} 6 {} {}\n",
        b(0),
        b(0),
        b(2),
        b(1),
        b(1),
        b(0),
        b(1),
        b(3),
        b(2),
        b(1),
        b(2),
        b(4),
        b(0),
        b(1)
    );
    std::fs::write(dir.join("m.1.node"), node).unwrap();
    std::fs::write(dir.join("m.1.ele"), ele).unwrap();
    std::fs::write(dir.join("m.1.face"), face).unwrap();
}

#[test]
fn tetgen_pairs_read_with_either_numbering() {
    for base in [0, 1] {
        let dir = tempfile::tempdir().unwrap();
        tetgen(dir.path(), base);
        for name in ["m.1.node", "m.1.ele"] {
            let f = read_mesh(&dir.path().join(name)).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(f.mesh.points.len(), 5);
            assert_eq!(f.mesh.points[4], [1.0, 1.0, 1.0]);
            assert_eq!(f.mesh.tets, vec![[0, 1, 2, 3], [1, 3, 2, 4]]);
            assert!(f.mesh.boundary.is_empty());
            assert_eq!(f.regions, ["1", "-2"]);
            assert_eq!(f.tet_region, [0, 1]);
            let groups: Vec<(&str, &[u32])> = f
                .node_groups
                .iter()
                .map(|g| (g.name.as_str(), g.nodes.as_slice()))
                .collect();
            assert_eq!(groups, [("5", &[0, 1, 2][..]), ("6", &[1, 2, 4][..])]);
        }
        let files = mesh_files(&dir.path().join("m.1.ele"));
        assert_eq!(files.len(), 3, "{files:?}");
    }
}

#[test]
fn tetgen_without_face_file_and_with_quadratic_tets() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(
        d.join("q.node"),
        "4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n",
    )
    .unwrap();
    std::fs::write(d.join("q.ele"), "1 10 0\n1 1 2 3 4 1 1 1 1 1 1\n").unwrap();
    let f = read_mesh(&d.join("q.node")).unwrap();
    assert_eq!(f.mesh.tets, vec![[0, 1, 2, 3]]);
    assert!(f.node_groups.is_empty() && f.regions.is_empty());
    assert_eq!(mesh_files(&d.join("q.node")).len(), 2);
}

/// The error of reading `path`; checks it is one line naming `names` (the file at fault).
fn error_naming(path: &Path, names: &Path) -> String {
    let e = read_mesh(path)
        .map(|_| ())
        .expect_err(&path.display().to_string())
        .to_string();
    assert!(!e.contains('\n'), "multi-line error: {e}");
    assert!(e.starts_with(&names.display().to_string()), "{e}");
    e
}

#[test]
fn bad_tetgen_files_name_the_file_at_fault() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let node = d.join("b.node");
    let ele = d.join("b.ele");
    let good_node = "4 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n";
    let cases: [(&str, &str, &Path, &str); 9] = [
        (
            good_node,
            "1 4 0\n0 0 1 2 9\n",
            &ele,
            "node 9 is not a point",
        ),
        (good_node, "1 4 0\n0 0 1 2\n", &ele, "missing node index"),
        (
            good_node,
            "2 4 0\n0 0 1 2 3\n",
            &ele,
            "unexpected end of file",
        ),
        (good_node, "1 6 0\n0 0 1 2 3 0 0\n", &ele, "6 nodes per"),
        (good_node, "1 4 0\n0 0 1 2 2\n", &ele, "repeats a node"),
        (good_node, "0 4 0\n", &ele, "no tetrahedra"),
        (
            "4 3 0 0\n0 0 0 0\n2 1 0 0\n",
            "",
            &node,
            "point index 2, expected 1",
        ),
        ("4 2 0 0\n", "", &node, "dimension 2"),
        (
            "99999999 3 0 0\n0 0 0 0\n",
            "",
            &node,
            "more than the file holds",
        ),
    ];
    for (n, e, at, want) in cases {
        std::fs::write(&node, n).unwrap();
        std::fs::write(&ele, e).unwrap();
        let msg = error_naming(&ele, at);
        assert!(msg.contains(want), "{msg}");
    }
    std::fs::write(&node, good_node).unwrap();
    std::fs::write(&ele, "1 4 0\n0 0 1 2 3\n").unwrap();
    let face = d.join("b.face");
    std::fs::write(&face, "1 1\n0 0 1 x 1\n").unwrap();
    assert!(error_naming(&node, &face).contains("invalid node index"));
    std::fs::remove_file(&face).unwrap();
    std::fs::remove_file(&node).unwrap();
    let e = error_naming(&ele, &node);
    assert!(
        matches!(read_mesh(&ele), Err(MeshReadError::Io { .. })),
        "{e}"
    );
}

const MEDIT: &str = "MeshVersionFormatted 2\n# comment\nDimension\n3\nVertices\n5\n\
0 0 0 1\n1 0 0 1\n0 1 0 1\n0 0 1 1\n1 1 1 0\n\
Edges 1\n1 2 0\nCorners 2 1 2\n\
Triangles\n2\n1 3 2 4\n2 4 3 0\n\
Tetrahedra\n2\n1 2 3 4 1\n2 4 3 5 1\nEnd\n";

#[test]
fn medit_files_read_with_their_references() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("a.mesh");
    std::fs::write(&path, MEDIT).unwrap();
    let f = read_mesh(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(f.mesh.points.len(), 5);
    assert_eq!(f.mesh.tets, vec![[0, 1, 2, 3], [1, 3, 2, 4]]);
    assert_eq!(f.node_groups.len(), 1);
    assert_eq!(
        (
            f.node_groups[0].name.as_str(),
            f.node_groups[0].nodes.as_slice()
        ),
        ("4", &[0, 1, 2][..])
    );
    assert_eq!(f.regions, ["1"]);
    assert_eq!(f.tet_region, [0, 0]);
}

#[test]
fn bad_medit_files_give_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("b.mesh");
    let cases = [
        ("", "no MeshVersionFormatted"),
        ("Vertices 1 0 0 0 0\n", "before MeshVersionFormatted"),
        ("MeshVersionFormatted 1\nDimension 2\n", "dimension 2"),
        (
            "MeshVersionFormatted 1\nDimension 3\nVertices 1\n0 0 0 0\nTetrahedra 1\n1 1 1 2 0\n",
            "vertex 2 does not exist",
        ),
        (
            "MeshVersionFormatted 1\nVertices 2\n0 0 0 0\n",
            "unexpected end of file",
        ),
        (
            "MeshVersionFormatted 1\nSolAtVertices 1\n",
            "unknown keyword",
        ),
        (
            "MeshVersionFormatted 1\nVertices 1000000\n",
            "more than the file holds",
        ),
        (
            "MeshVersionFormatted 1\nVertices 1\n0 0 nan 0\n",
            "non-finite",
        ),
        ("MeshVersionFormatted 1\nEnd\n", "no tetrahedra"),
    ];
    for (text, want) in cases {
        std::fs::write(&path, text).unwrap();
        let e = error_naming(&path, &path);
        assert!(e.contains(want), "{text:?}: {e}");
    }
}

fn small_mesh() -> tptd::TetMesh {
    let n = 6;
    let v: Vec<f64> = (0..n * n * n)
        .map(|i| {
            let p = [i % n, i / n % n, i / (n * n)].map(|x| x as f64 - 2.5);
            (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt()
        })
        .collect();
    let grid = ScalarGrid::new([n; 3], v).unwrap();
    mesh_interval(
        &grid,
        &MeshOptions::new(f64::NEG_INFINITY, 2.2, Method::Ctd),
    )
    .unwrap()
    .mesh
}

#[test]
fn our_vtu_reads_back_in_every_encoding() {
    let mesh = small_mesh();
    let dir = tempfile::tempdir().unwrap();
    for enc in [VtuEncoding::Base64, VtuEncoding::Zlib, VtuEncoding::Raw] {
        let path = dir.path().join(format!("m-{}.vtu", enc.name()));
        let mut bytes = Vec::new();
        write_vtu_with(&mesh, &mut bytes, enc).unwrap();
        std::fs::write(&path, &bytes).unwrap();
        let f = read_mesh(&path).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(f.mesh.points, mesh.points);
        assert_eq!(f.mesh.tets, mesh.tets);
        assert_eq!(f.mesh.values, mesh.values);
        assert!(f.mesh.boundary.is_empty());
        // Cut short: an error, never a panic.
        for cut in [bytes.len() / 3, bytes.len() * 2 / 3, bytes.len() - 40] {
            std::fs::write(&path, &bytes[..cut]).unwrap();
            if let Err(e) = read_mesh(&path) {
                assert!(!e.to_string().contains('\n'), "{e}");
            }
        }
    }
}

/// An ASCII `.vtu` with the given cells.
fn ascii_vtu(conn: &str, offsets: &str, types: &str, cells: usize) -> String {
    format!(
        r#"<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian">
<UnstructuredGrid><Piece NumberOfPoints="5" NumberOfCells="{cells}">
<Points><DataArray type="Float32" NumberOfComponents="3" format="ascii">
0 0 0 1 0 0 0 1 0 0 0 1 1 1 1</DataArray></Points>
<Cells>
<DataArray type="Int64" Name="connectivity" format="ascii">{conn}</DataArray>
<DataArray type="Int64" Name="offsets" format="ascii">{offsets}</DataArray>
<DataArray type="UInt8" Name="types" format="ascii">{types}</DataArray>
</Cells></Piece></UnstructuredGrid></VTKFile>
"#
    )
}

#[test]
fn hand_written_vtu_skips_lower_cells_and_refuses_others() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("h.vtu");
    std::fs::write(
        &path,
        ascii_vtu("0 1 2 0 1 2 3 1 3 2 4", "3 7 11", "5 10 10", 3),
    )
    .unwrap();
    let f = read_mesh(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(f.mesh.tets, vec![[0, 1, 2, 3], [1, 3, 2, 4]]);
    assert_eq!(f.mesh.values, vec![0.0; 5]);
    let cases = [
        (
            ascii_vtu("0 1 2 3 4 0 1 2", "8", "12", 1),
            "unsupported cell type 12",
        ),
        (ascii_vtu("0 1 2 7", "4", "10", 1), "node 7 is not a point"),
        (ascii_vtu("0 1 2", "3", "10", 1), "has 4 nodes, not 3"),
        (ascii_vtu("0 1 2 3", "4", "10", 2), "expected 2"),
        (ascii_vtu("0 1 2", "3", "5", 1), "no tetrahedra"),
        (
            "<VTKFile type=\"PolyData\">".into(),
            "not a VTK UnstructuredGrid",
        ),
        (
            "<VTKFile type=\"UnstructuredGrid\"><Piece".into(),
            "malformed XML",
        ),
    ];
    for (text, want) in cases {
        std::fs::write(&path, text).unwrap();
        let e = error_naming(&path, &path);
        assert!(e.contains(want), "{e}");
    }
}

/// `mesh` as Medit text, and as TetGen `.node` and `.ele` text (numbered from 1).
fn peer_texts(mesh: &tptd::TetMesh) -> (String, String, String) {
    use std::fmt::Write as _;
    let (mut medit, mut node, mut ele) = (String::new(), String::new(), String::new());
    let n = mesh.points.len();
    write!(
        medit,
        "MeshVersionFormatted 2\nDimension 3\nVertices\n{n}\n"
    )
    .unwrap();
    writeln!(node, "{n} 3 0 0").unwrap();
    for (i, p) in mesh.points.iter().enumerate() {
        writeln!(medit, "{} {} {} 0", p[0], p[1], p[2]).unwrap();
        writeln!(node, "{} {} {} {}", i + 1, p[0], p[1], p[2]).unwrap();
    }
    write!(medit, "Tetrahedra\n{}\n", mesh.tets.len()).unwrap();
    writeln!(ele, "{} 4 0", mesh.tets.len()).unwrap();
    for (i, t) in mesh.tets.iter().enumerate() {
        let [a, b, c, d] = t.map(|v| v + 1);
        writeln!(medit, "{a} {b} {c} {d} 1").unwrap();
        writeln!(ele, "{} {a} {b} {c} {d}", i + 1).unwrap();
    }
    medit.push_str("End\n");
    (medit, node, ele)
}

#[test]
fn peer_files_read_back_and_cut_short_are_errors_not_panics() {
    let mesh = small_mesh();
    let (medit, node, ele) = peer_texts(&mesh);
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (m, nf, ef) = (d.join("a.mesh"), d.join("a.node"), d.join("a.ele"));
    fs_write(&m, &medit);
    fs_write(&nf, &node);
    fs_write(&ef, &ele);
    for path in [&m, &nf] {
        let f = read_mesh(path).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(f.mesh.points, mesh.points);
        assert_eq!(f.mesh.tets, mesh.tets);
    }
    for k in 1..30 {
        for (path, text) in [(&m, &medit), (&nf, &node), (&ef, &ele)] {
            let cut = k * text.len() / 30;
            fs_write(path, &text[..cut]);
            // a cut after the last entry (before Medit's `End`) still reads: only the
            // form of the errors is checked
            if let Err(e) = read_mesh(path) {
                assert!(!e.to_string().contains('\n'), "{e}");
            }
            fs_write(path, text);
        }
    }
}

fn fs_write(path: &Path, text: &str) {
    std::fs::write(path, text).unwrap();
}

const VTK42: &str = "# vtk DataFile Version 4.2\nhand written\nASCII\nDATASET UNSTRUCTURED_GRID\n\
POINTS 5 float\n0 0 0 1 0 0 0 1 0\n0 0 1 1 1 1\n\
CELLS 3 14\n3 0 1 2\n4 0 1 2 3\n4 1 2 3 4\nCELL_TYPES 3\n5\n10\n10\n\
CELL_DATA 3\nSCALARS c int 1\nLOOKUP_TABLE default\n0 1 2\n";

#[test]
fn legacy_vtk_reads_and_bad_ones_give_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("a.vtk");
    fs_write(&path, VTK42);
    let f = read_mesh(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(f.mesh.tets, vec![[0, 1, 2, 3], [1, 2, 3, 4]]);
    assert_eq!(f.mesh.points[4], [1.0, 1.0, 1.0]);
    let with_f = VTK42.replace(
        "CELL_DATA 3\nSCALARS c int 1\nLOOKUP_TABLE default\n0 1 2\n",
        "POINT_DATA 5\nSCALARS f double\nLOOKUP_TABLE default\n0 0.5 1 1.5 2\n",
    );
    fs_write(&path, &with_f);
    assert_eq!(
        read_mesh(&path).unwrap().mesh.values,
        [0.0, 0.5, 1.0, 1.5, 2.0]
    );
    let cases = [
        ("hello\n".to_string(), "not a legacy VTK file"),
        (VTK42.replace("ASCII", "XML"), "ASCII or BINARY"),
        (
            VTK42.replace("UNSTRUCTURED_GRID", "POLYDATA"),
            "UNSTRUCTURED_GRID",
        ),
        (
            VTK42.replace("4 1 2 3 4", "4 1 2 3 9"),
            "node 9 is not a point",
        ),
        (
            VTK42.replace("CELL_TYPES 3\n5", "CELL_TYPES 3\n12"),
            "cell type 12",
        ),
        (VTK42.replace("CELLS 3 14", "CELLS 3 15"), "CELLS"),
        (
            VTK42.replace("POINTS 5 float", "POINTS 5 quaternion"),
            "unknown type",
        ),
        (
            VTK42[..VTK42.find("CELLS").unwrap()].to_string(),
            "no CELLS",
        ),
    ];
    for (text, want) in cases {
        fs_write(&path, &text);
        let e = error_naming(&path, &path);
        assert!(e.contains(want), "{e}");
    }
    for cut in (1..25).map(|k| k * VTK42.len() / 25) {
        fs_write(&path, &VTK42[..cut]);
        if let Err(e) = read_mesh(&path) {
            assert!(!e.to_string().contains('\n'), "{e}");
        }
    }
}
