//! Tests of the mesh writers (`.msh` 4.1/2.2, `.inp`, `.vtu`) and of atomic file output.
//!
//! * Golden files (`tests/fixtures/golden/`) pin the exact bytes of small meshes; regenerate
//!   them with `TPTD_BLESS=1 cargo test --test write_formats`.
//! * Round trips through real readers: meshio and VTK (via `tests/py/check_mesh.py`),
//!   `gmsh -check` and a CalculiX (`ccx`) heat-transfer run on the `.inp`. A missing tool
//!   makes the test fail, unless `TPTD_SKIP_EXTERNAL=1`, which turns those tests into no-ops.

mod common;

use std::collections::HashMap;
use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;

use common::external::{
    check_mesh_py, dat_temperatures, gmsh_check, gmsh_reads_binary_as_ascii, require_ccx,
    require_gmsh, require_python_with, run, run_ccx_job, write_file, Format, DECK_HEAD, DECK_TAIL,
};
use common::files::listing;
use tptd::io::atomic::{write_atomically, WriteError};
use tptd::io::inp::write_inp;
use tptd::io::msh::{write_msh, MshVersion};
use tptd::io::vtu::write_vtu;
use tptd::{BoundaryLabel, TetMesh};

// ---------------------------------------------------------------------------------------
// Test meshes
// ---------------------------------------------------------------------------------------

/// Box of `n[0]×n[1]×n[2]` cells of size `h` at `origin`, each cell split into the 6 Kuhn
/// tets around its main diagonal (conforming), reoriented positively; the boundary faces
/// are found by counting, oriented outward and labelled by `label(centroid)`.
fn box_mesh(
    n: [usize; 3],
    origin: [f64; 3],
    h: [f64; 3],
    label: impl Fn([f64; 3]) -> BoundaryLabel,
    value: impl Fn(usize, [f64; 3]) -> f64,
) -> TetMesh {
    let id = |i: usize, j: usize, k: usize| (i + (n[0] + 1) * (j + (n[1] + 1) * k)) as u32;
    let mut points = Vec::new();
    for k in 0..=n[2] {
        for j in 0..=n[1] {
            for i in 0..=n[0] {
                points.push([
                    origin[0] + i as f64 * h[0],
                    origin[1] + j as f64 * h[1],
                    origin[2] + k as f64 * h[2],
                ]);
            }
        }
    }
    let values = points
        .iter()
        .enumerate()
        .map(|(i, &p)| value(i, p))
        .collect();
    let perms = [
        [0, 1, 2],
        [0, 2, 1],
        [1, 0, 2],
        [1, 2, 0],
        [2, 0, 1],
        [2, 1, 0],
    ];
    let mut mesh = TetMesh {
        points,
        values,
        ..TetMesh::default()
    };
    for k in 0..n[2] {
        for j in 0..n[1] {
            for i in 0..n[0] {
                for perm in perms {
                    let mut c = [i, j, k];
                    let mut tet = [id(c[0], c[1], c[2]); 4];
                    for (s, &axis) in perm.iter().enumerate() {
                        c[axis] += 1;
                        tet[s + 1] = id(c[0], c[1], c[2]);
                    }
                    mesh.tets.push(tet);
                    let t = mesh.tets.len() - 1;
                    if mesh.tet_volume(t) < 0.0 {
                        mesh.tets[t].swap(2, 3);
                    }
                    assert!(mesh.tet_volume(t) > 0.0);
                }
            }
        }
    }
    let mut count: HashMap<[u32; 3], usize> = HashMap::new();
    let mut faces = Vec::new();
    for &[a, b, c, d] in &mesh.tets {
        for f in [[a, c, b], [a, b, d], [a, d, c], [b, c, d]] {
            let mut key = f;
            key.sort_unstable();
            *count.entry(key).or_default() += 1;
            faces.push((key, f));
        }
    }
    for (key, f) in faces {
        if count[&key] == 1 {
            let p = f.map(|v| mesh.points[v as usize]);
            let centroid = [0, 1, 2].map(|k| (p[0][k] + p[1][k] + p[2][k]) / 3.0);
            mesh.boundary.push(f);
            mesh.boundary_labels.push(label(centroid));
        }
    }
    mesh
}

/// Unit cube in 6 tets, 12 boundary triangles: x = 0 alpha, x = 1 beta, the rest box.
fn cube6() -> TetMesh {
    let m = box_mesh(
        [1, 1, 1],
        [0.0; 3],
        [1.0; 3],
        |c| match c[0] {
            x if x < 1e-9 => BoundaryLabel::ALPHA,
            x if x > 1.0 - 1e-9 => BoundaryLabel::BETA,
            _ => BoundaryLabel::Box,
        },
        |i, _| i as f64 * 0.1 - 1.0 / 3.0,
    );
    assert_eq!((m.points.len(), m.tets.len(), m.boundary.len()), (8, 6, 12));
    m
}

/// Two shifted, stretched cells (12 tets) with awkward coordinates; only alpha (top) and box.
fn slab12() -> TetMesh {
    let top = 2.5 + 0.3;
    let m = box_mesh(
        [2, 1, 1],
        [-0.3, 0.1, 2.5],
        [0.7, 0.45, 0.3],
        |c| {
            if (c[2] - top).abs() < 1e-9 {
                BoundaryLabel::ALPHA
            } else {
                BoundaryLabel::Box
            }
        },
        |_, p| (p[0] * 3.7).sin() * 1e-5 + p[1] * std::f64::consts::PI - p[2].exp(),
    );
    assert_eq!(
        (m.points.len(), m.tets.len(), m.boundary.len()),
        (12, 12, 20)
    );
    m
}

/// Bar `[0, 1.5] × [0, 0.5] × [0, 0.5]` in 6×2×2 cells: x = 0 alpha, x = 1.5 beta, rest box.
fn bar() -> TetMesh {
    box_mesh(
        [6, 2, 2],
        [0.0; 3],
        [0.25; 3],
        |c| {
            if c[0] < 1e-9 {
                BoundaryLabel::ALPHA
            } else if c[0] > 1.5 - 1e-9 {
                BoundaryLabel::BETA
            } else {
                BoundaryLabel::Box
            }
        },
        |_, p| p[0] * p[0] + 0.1 * p[1],
    )
}

// ---------------------------------------------------------------------------------------
// Helpers
// ---------------------------------------------------------------------------------------

fn render(mesh: &TetMesh, format: Format) -> Vec<u8> {
    let mut out = Vec::new();
    format
        .write(mesh, &mut out)
        .expect("writing to a Vec cannot fail");
    out
}

// ---------------------------------------------------------------------------------------
// Golden files and determinism
// ---------------------------------------------------------------------------------------

fn golden_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/golden")
}

#[test]
fn golden_files_match() {
    let bless = std::env::var("TPTD_BLESS").is_ok_and(|v| v == "1");
    let mut mismatches = Vec::new();
    for (stem, mesh) in [("cube6", cube6()), ("slab12", slab12())] {
        for format in Format::ALL.into_iter().chain(Format::OTHER_VTU) {
            let bytes = render(&mesh, format);
            assert_eq!(
                bytes,
                render(&mesh, format),
                "{stem} {format:?} is not deterministic"
            );
            let path = golden_dir().join(format.file_name(stem));
            if bless {
                fs::create_dir_all(golden_dir()).unwrap();
                fs::write(&path, &bytes).unwrap();
                continue;
            }
            match fs::read(&path) {
                Ok(golden) if golden == bytes => {}
                Ok(_) => mismatches.push(format!("{} differs", path.display())),
                Err(e) => mismatches.push(format!("{}: {e}", path.display())),
            }
        }
    }
    assert!(
        mismatches.is_empty(),
        "golden mismatch (TPTD_BLESS=1 regenerates): {mismatches:#?}"
    );
}

#[test]
fn msh_structure() {
    let m = slab12();
    let v41 = String::from_utf8(render(&m, Format::Msh41)).unwrap();
    assert!(v41.starts_with("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"));
    assert!(v41.contains(
        "$PhysicalNames\n3\n2 1 \"alpha\"\n2 3 \"box\"\n3 4 \"domain\"\n$EndPhysicalNames\n"
    ));
    assert!(!v41.contains("beta"));
    assert!(v41.contains("$Entities\n0 0 2 1\n"));
    // two surface blocks (alpha: 4 triangles, box: 16) and one tet block
    assert!(v41.contains("$Elements\n3 32 1 32\n3 1 4 12\n"));
    assert!(v41.contains("\n2 1 2 4\n") && v41.contains("\n2 3 2 16\n"));
    assert!(v41.ends_with("$EndNodeData\n"));

    let v22 = String::from_utf8(render(&m, Format::Msh22)).unwrap();
    assert!(v22.starts_with("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n"));
    assert!(v22.contains("$Elements\n32\n1 4 2 4 1 "));
    assert_eq!(
        v22.lines()
            .filter(|l| l.split(' ').nth(1) == Some("2"))
            .count(),
        20
    );
    assert!(v22.contains("$NodeData\n1\n\"f\"\n1\n0\n3\n0\n1\n12\n"));
}

/// The byte offset just after the first occurrence of `pat` in `bytes`.
fn after(bytes: &[u8], pat: &[u8]) -> usize {
    bytes
        .windows(pat.len())
        .position(|w| w == pat)
        .unwrap_or_else(|| panic!("no {:?}", String::from_utf8_lossy(pat)))
        + pat.len()
}

/// `n` little-endian 8-byte numbers at `at`.
fn sizes(bytes: &[u8], at: usize, n: usize) -> Vec<u64> {
    (0..n)
        .map(|k| u64::from_le_bytes(bytes[at + 8 * k..at + 8 * k + 8].try_into().unwrap()))
        .collect()
}

#[test]
fn binary_msh_structure() {
    let m = slab12();
    let ascii = String::from_utf8(render(&m, Format::Msh41)).unwrap();
    let b = render(&m, Format::Msh41Binary);
    assert!(b.starts_with(b"$MeshFormat\n4.1 1 8\n\x01\0\0\0\n$EndMeshFormat\n"));
    // the text sections are those of the ASCII file
    let names = &ascii[ascii.find("$PhysicalNames").unwrap()..ascii.find("$Entities").unwrap()];
    assert_eq!(
        &b[after(&b, b"$EndMeshFormat\n")..][..names.len()],
        names.as_bytes()
    );
    let head = "$NodeData\n1\n\"f\"\n1\n0\n3\n0\n1\n12\n";
    assert!(ascii.contains(head));
    // entities: 0 points, 0 curves, 2 surfaces (alpha, box), 1 volume
    assert_eq!(sizes(&b, after(&b, b"$Entities\n"), 4), [0, 0, 2, 1]);
    // nodes: one block of 12 tagged 1..=12 on volume 1, then the coordinates
    let n = after(&b, b"$Nodes\n");
    assert_eq!(sizes(&b, n, 4), [1, 12, 1, 12]);
    assert_eq!(b[n + 32..n + 44], [3, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0]);
    assert_eq!(
        sizes(&b, n + 44, 13),
        [12, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12]
    );
    let x0 = f64::from_le_bytes(b[n + 148..n + 156].try_into().unwrap());
    assert_eq!(x0, m.points[0][0]);
    // elements: 3 blocks, 32 elements tagged 1..=32; the first tet is tag 1 with its nodes
    let e = after(&b, b"$Elements\n");
    assert_eq!(sizes(&b, e, 4), [3, 32, 1, 32]);
    assert_eq!(b[e + 32..e + 44], [3, 0, 0, 0, 1, 0, 0, 0, 4, 0, 0, 0]);
    let first: Vec<u64> = m.tets[0].iter().map(|&v| v as u64 + 1).collect();
    assert_eq!(sizes(&b, e + 44, 6), [[12, 1].as_slice(), &first].concat());
    // node data: the ASCII head, then (int tag, f64 value) per node
    let d = after(&b, head.as_bytes());
    assert_eq!(b[d..d + 4], 1i32.to_le_bytes());
    assert_eq!(b[d + 4..d + 12], m.values[0].to_le_bytes());
    assert_eq!(d + 12 * 12, b.len() - "\n$EndNodeData\n".len());
    assert!(b.ends_with(b"\n$EndNodeData\n"));
}

/// Parses the `.inp` text: node sets and surfaces by name, element connectivity (1-based).
struct Inp {
    elements: Vec<[u32; 4]>,
    nsets: HashMap<String, Vec<u32>>,
    surfaces: HashMap<String, Vec<(usize, usize)>>,
}

fn parse_inp(text: &str) -> Inp {
    let mut inp = Inp {
        elements: Vec::new(),
        nsets: HashMap::new(),
        surfaces: HashMap::new(),
    };
    let mut section = String::new();
    for line in text.lines() {
        if let Some(kw) = line.strip_prefix('*') {
            section = kw.to_string();
            continue;
        }
        if section == "HEADING" {
            continue;
        }
        for field in line.split(',') {
            assert!(
                field.trim().len() <= 20,
                "field wider than 20 characters: {line:?}"
            );
        }
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        if section.starts_with("ELEMENT") {
            assert_eq!(fields.len(), 5);
            assert_eq!(fields[0].parse::<usize>().unwrap(), inp.elements.len() + 1);
            inp.elements
                .push([1, 2, 3, 4].map(|k| fields[k].parse().unwrap()));
        } else if let Some(name) = section.strip_prefix("NSET, NSET=") {
            assert!(fields.len() <= 16);
            inp.nsets
                .entry(name.to_string())
                .or_default()
                .extend(fields.iter().map(|f| f.parse::<u32>().unwrap()));
        } else if let Some(rest) = section.strip_prefix("SURFACE, NAME=") {
            let name = rest.strip_suffix(", TYPE=ELEMENT").unwrap();
            let face = fields[1].strip_prefix('S').unwrap().parse().unwrap();
            inp.surfaces
                .entry(name.to_string())
                .or_default()
                .push((fields[0].parse().unwrap(), face));
        }
    }
    inp
}

#[test]
fn inp_sets_and_surfaces_match_the_boundary() {
    for mesh in [cube6(), slab12(), bar()] {
        let text = String::from_utf8(render(&mesh, Format::Inp)).unwrap();
        assert!(text.starts_with("*HEADING\n"));
        let inp = parse_inp(&text);
        assert_eq!(inp.elements.len(), mesh.tets.len());
        for (t, e) in inp.elements.iter().enumerate() {
            assert_eq!(e.map(|v| v - 1), mesh.tets[t]);
        }
        for label in BoundaryLabel::of_levels(2) {
            let name = label.name().to_ascii_uppercase();
            let mut want: Vec<[u32; 3]> = mesh
                .boundary
                .iter()
                .zip(&mesh.boundary_labels)
                .filter(|&(_, &l)| l == label)
                .map(|(t, _)| *t)
                .collect();
            if want.is_empty() {
                assert!(!inp.nsets.contains_key(&name) && !inp.surfaces.contains_key(&name));
                continue;
            }
            let mut nodes: Vec<u32> = want.iter().flatten().map(|v| v + 1).collect();
            nodes.sort_unstable();
            nodes.dedup();
            assert_eq!(inp.nsets[&name], nodes, "NSET {name}");
            // C3D4 faces S1 = 1-2-3, S2 = 1-4-2, S3 = 2-4-3, S4 = 3-4-1 (1-based local nodes);
            // the face seen from outside must be the outward boundary triangle up to rotation
            // with reversed orientation (C3D4 faces are numbered with normals pointing inward).
            let local = [[0, 1, 2], [0, 3, 1], [1, 3, 2], [2, 3, 0]];
            let mut got: Vec<[u32; 3]> = inp.surfaces[&name]
                .iter()
                .map(|&(e, s)| {
                    let tet = inp.elements[e - 1];
                    let f = local[s - 1].map(|k| tet[k] - 1);
                    [f[0], f[2], f[1]] // reverse: inward → outward
                })
                .collect();
            let canon = |t: &mut [u32; 3]| {
                let r = t.iter().enumerate().min_by_key(|&(_, v)| v).unwrap().0;
                t.rotate_left(r);
            };
            got.iter_mut().for_each(canon);
            want.iter_mut().for_each(canon);
            assert_eq!(got, want, "SURFACE {name}");
        }
    }
}

#[test]
fn inp_fields_stay_within_20_characters() {
    let mut m = cube6();
    m.points[0] = [
        -1.234_567_890_123_456_7e-300,
        1.0 / 3.0,
        -std::f64::consts::PI * 1e200,
    ];
    let text = String::from_utf8(render(&m, Format::Inp)).unwrap();
    let line = text.lines().find(|l| l.starts_with("1, ")).unwrap();
    for f in line.split(", ") {
        assert!(f.len() <= 20, "{f:?}");
    }
    let x: Vec<f64> = line
        .split(", ")
        .skip(1)
        .map(|f| f.parse().unwrap())
        .collect();
    assert_eq!(x[1], 1.0 / 3.0); // shortest form fits: exact
    assert!((x[0] / m.points[0][0] - 1.0).abs() < 1e-12);
    assert!((x[2] / m.points[0][2] - 1.0).abs() < 1e-12);
}

#[test]
fn vtu_header_and_sizes() {
    let m = cube6();
    let bytes = render(&m, Format::VtuRaw);
    let text = String::from_utf8_lossy(&bytes);
    assert!(text.contains("header_type=\"UInt64\"") && text.contains("format=\"appended\""));
    assert!(text.contains("NumberOfPoints=\"8\" NumberOfCells=\"6\""));
    // header + 5 arrays (each with an 8-byte length): f 64, points 192, conn 96, offsets 24,
    // types 6 bytes, then the closing tags
    let start = bytes.windows(5).position(|w| w == b"   _\x40").unwrap() + 4;
    let tail = b"\n  </AppendedData>\n</VTKFile>\n";
    assert!(bytes.ends_with(tail));
    assert_eq!(
        bytes.len() - start - tail.len(),
        5 * 8 + 64 + 192 + 96 + 24 + 6
    );
}

#[test]
fn invalid_meshes_are_rejected() {
    let mut m = cube6();
    m.values.pop();
    for format in Format::ALL {
        let mut out = Vec::new();
        let r = match format {
            Format::Msh41 => write_msh(&m, &mut out, MshVersion::V41),
            Format::Msh22 => write_msh(&m, &mut out, MshVersion::V22),
            Format::Msh41Binary => write_msh(&m, &mut out, MshVersion::V41Binary),
            Format::Inp => write_inp(&m, &mut out),
            Format::Vtu | Format::VtuZlib | Format::VtuRaw => write_vtu(&m, &mut out),
        };
        assert_eq!(r.unwrap_err().kind(), std::io::ErrorKind::InvalidInput);
    }
    let mut m = cube6();
    // (0,0,0), (1,0,0), (0,1,0): the bottom face is split along 0-3, so this is no tet face
    m.boundary[0] = [0, 1, 2];
    let err = write_inp(&m, &mut Vec::new()).unwrap_err();
    assert!(err.to_string().contains("not a face"), "{err}");
}

#[test]
fn empty_mesh_writes() {
    let m = TetMesh::default();
    for format in Format::ALL {
        assert!(!render(&m, format).is_empty());
    }
}

// ---------------------------------------------------------------------------------------
// Atomic output
// ---------------------------------------------------------------------------------------

#[test]
fn atomic_failing_writer_leaves_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.msh");
    let err = write_atomically(&path, |w| {
        w.write_all(&[b'x'; 3_000_000])?; // more than the buffer: really reaches the temp file
        Err(std::io::Error::other("boom"))
    })
    .unwrap_err();
    let msg = err.to_string();
    assert!(
        msg.contains("out.msh") && msg.contains("boom") && !msg.contains('\n'),
        "{msg}"
    );
    assert!(matches!(err, WriteError::Io { .. }));
    assert!(listing(dir.path()).is_empty(), "{:?}", listing(dir.path()));

    // an existing file survives a failed rewrite untouched
    fs::write(&path, "old").unwrap();
    assert!(write_atomically(&path, |_| Err(std::io::Error::other("boom"))).is_err());
    assert_eq!(fs::read_to_string(&path).unwrap(), "old");
    assert_eq!(listing(dir.path()), ["out.msh"]);
}

#[test]
fn atomic_success_replaces_existing_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("mesh.vtu");
    fs::write(&path, "a much longer old content that must disappear").unwrap();
    write_atomically(&path, |w| w.write_all(b"new")).unwrap();
    assert_eq!(fs::read_to_string(&path).unwrap(), "new");
    assert_eq!(listing(dir.path()), ["mesh.vtu"]);

    // a relative path with no directory part works too (written into the current dir)
    let name = format!("tptd-atomic-test-{}.txt", std::process::id());
    write_atomically(Path::new(&name), |w| w.write_all(b"x")).unwrap();
    assert_eq!(fs::read_to_string(&name).unwrap(), "x");
    fs::remove_file(&name).unwrap();
}

#[test]
fn atomic_refuses_directories_and_special_files() {
    let dir = tempfile::tempdir().unwrap();
    let sub = dir.path().join("sub");
    fs::create_dir(&sub).unwrap();
    let err = write_atomically(&sub, |w| w.write_all(b"x")).unwrap_err();
    assert!(matches!(err, WriteError::IsDirectory { .. }), "{err}");
    assert!(err.to_string().contains("sub") && !err.to_string().contains('\n'));
    assert!(sub.is_dir());
    assert_eq!(listing(dir.path()), ["sub"]);

    // missing parent directory: an I/O error naming the path, nothing created
    let missing = dir.path().join("nope/out.inp");
    let err = write_atomically(&missing, |w| w.write_all(b"x")).unwrap_err();
    assert!(err.to_string().contains("nope/out.inp"), "{err}");

    #[cfg(unix)]
    {
        let fifo = dir.path().join("fifo");
        let ok = Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .map(|s| s.success())
            .unwrap_or(false);
        if ok {
            let err = write_atomically(&fifo, |w| w.write_all(b"x")).unwrap_err();
            assert!(matches!(err, WriteError::NotRegularFile { .. }), "{err}");
            assert_eq!(listing(dir.path()), ["fifo", "sub"]);
        }
    }
}

// ---------------------------------------------------------------------------------------
// Round trips through real readers
// ---------------------------------------------------------------------------------------

fn python_check(reader: &str, format: Format) {
    if !require_python_with(reader) {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    for (stem, mesh) in [("cube6", cube6()), ("slab12", slab12()), ("bar", bar())] {
        let out = check_mesh_py(reader, format, &mesh, dir.path(), stem, &[]);
        eprint!("{out}");
    }
}

#[test]
fn meshio_reads_msh41() {
    python_check("meshio", Format::Msh41);
}

#[test]
fn meshio_reads_binary_msh41() {
    python_check("meshio", Format::Msh41Binary);
}

#[test]
fn meshio_reads_msh22() {
    python_check("meshio", Format::Msh22);
}

#[test]
fn meshio_reads_inp() {
    python_check("meshio", Format::Inp);
}

#[test]
fn meshio_reads_vtu() {
    python_check("meshio", Format::Vtu);
}

#[test]
fn vtk_reads_vtu() {
    python_check("vtk", Format::Vtu);
}

#[test]
fn meshio_reads_zlib_vtu() {
    python_check("meshio", Format::VtuZlib);
}

#[test]
fn vtk_reads_zlib_and_raw_vtu() {
    python_check("vtk", Format::VtuZlib);
    python_check("vtk", Format::VtuRaw);
}

#[test]
fn gmsh_checks_msh() {
    if !require_gmsh() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    for (stem, mesh) in [("cube6", cube6()), ("slab12", slab12()), ("bar", bar())] {
        for format in [Format::Msh41, Format::Msh22, Format::Msh41Binary] {
            let path = write_file(&mesh, format, dir.path(), stem);
            gmsh_check(&path, &mesh);
            // gmsh re-exports the mesh: converting to 2.2 must keep every element
            let copy = dir
                .path()
                .join(format!("{stem}.{}.gmsh-copy.msh", format.key()));
            let (ok, out) = run(Command::new("gmsh")
                .arg(&path)
                .args(["-0", "-format", "msh22", "-save_all", "-o"])
                .arg(&copy)
                .arg("-nopopup"));
            assert!(
                ok && !out.contains("Error"),
                "gmsh -0 {}:\n{out}",
                path.display()
            );
            let text = fs::read_to_string(&copy).unwrap();
            let n_elem: usize = text
                .split("$Elements\n")
                .nth(1)
                .unwrap()
                .lines()
                .next()
                .unwrap()
                .parse()
                .unwrap();
            assert_eq!(n_elem, mesh.tets.len() + mesh.boundary.len());
        }
    }
}

#[test]
fn gmsh_reads_binary_msh_as_ascii() {
    if !require_gmsh() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    for (stem, mesh) in [("cube6", cube6()), ("slab12", slab12()), ("bar", bar())] {
        gmsh_reads_binary_as_ascii(&mesh, dir.path(), stem);
    }
}

/// Runs `ccx` on `deck` (stem `job`) in `dir`; returns the `.dat` text.
fn run_ccx(dir: &Path, job: &str, deck: &str) -> String {
    run_ccx_job(
        dir,
        job,
        deck,
        &["negative jacobian", "nonpositive jacobian"],
    );
    let frd = dir.join(format!("{job}.frd"));
    assert!(
        fs::metadata(&frd).map(|m| m.len() > 0).unwrap_or(false),
        "no .frd written for {job}"
    );
    fs::read_to_string(dir.join(format!("{job}.dat"))).unwrap()
}

#[test]
fn calculix_solves_heat_transfer_on_inp() {
    if !require_ccx() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let mesh = bar();
    write_atomically(&dir.path().join("mesh.inp"), |w| write_inp(&mesh, w)).unwrap();
    let inp = parse_inp(&fs::read_to_string(dir.path().join("mesh.inp")).unwrap());
    let head = format!("{DECK_HEAD}ALPHA, 11, 11, 0.\n");
    let tail = DECK_TAIL;

    // 1) body flux on DOMAIN, T = 0 on ALPHA: runs, temperatures positive away from ALPHA
    let deck = format!("{head}*DFLUX\nDOMAIN, BF, 1.\n{tail}");
    let temps = dat_temperatures(&run_ccx(dir.path(), "body", &deck));
    assert_eq!(temps.len(), mesh.points.len());
    for (&id, &t) in &temps {
        let x = mesh.points[id - 1][0];
        assert!(
            t.is_finite() && (x == 0.0 || t > 0.0),
            "node {id} at x = {x}: T = {t}"
        );
    }

    // 2) uniform flux q into the BETA faces (from the *SURFACE, so the face numbering is
    //    exercised), T = 0 on ALPHA, box insulated: the exact solution T = q x is linear, so
    //    the linear tets reproduce it at every node.
    let q = 2.0;
    let mut deck = format!("{head}*DFLUX\n");
    for &(e, s) in &inp.surfaces["BETA"] {
        deck.push_str(&format!("{e}, S{s}, {q}\n"));
    }
    deck.push_str(tail);
    let temps = dat_temperatures(&run_ccx(dir.path(), "surface", &deck));
    assert_eq!(temps.len(), mesh.points.len());
    for (&id, &t) in &temps {
        let x = mesh.points[id - 1][0];
        assert!(
            (t - q * x).abs() < 1e-6,
            "node {id} at x = {x}: T = {t}, expected {}",
            q * x
        );
    }
}

/// Throughput of the writers on a 750k-tet mesh (run with `--ignored --nocapture`).
#[test]
#[ignore = "timing only"]
fn large_mesh_write_speed() {
    let mesh = box_mesh(
        [50, 50, 50],
        [0.0; 3],
        [0.02; 3],
        |_| BoundaryLabel::Box,
        |_, p| p[0] + p[1] * p[2],
    );
    let dir = tempfile::tempdir().unwrap();
    for format in Format::ALL {
        let start = std::time::Instant::now();
        let path = write_file(&mesh, format, dir.path(), "large");
        let secs = start.elapsed().as_secs_f64();
        let mb = fs::metadata(&path).unwrap().len() as f64 / 1e6;
        eprintln!(
            "{format:?}: {} tets, {mb:.1} MB in {secs:.3} s ({:.0} MB/s)",
            mesh.tets.len(),
            mb / secs
        );
    }
}
