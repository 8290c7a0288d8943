//! Volume readers against fixtures written and read back by the reference Python libraries
//! (numpy, pynrrd, nibabel, SimpleITK; see `tests/fixtures/make_volume_fixtures.py`), plus
//! broken inputs derived from those fixtures in a temporary directory.

mod common;

use std::fs;
use std::path::{Path, PathBuf};

use common::files::npy_bytes;
use serde_json::Value;
use tptd::io::read_volume;
use tptd::ScalarGrid;

fn fixture_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/volumes")
}

fn fixture(name: &str) -> PathBuf {
    fixture_dir().join(name)
}

fn expected() -> Value {
    let text = fs::read_to_string(fixture("expected.json")).expect("expected.json");
    serde_json::from_str(&text).expect("valid expected.json")
}

fn f64s(v: &Value) -> Vec<f64> {
    v.as_array()
        .expect("array")
        .iter()
        .map(|x| x.as_f64().expect("number"))
        .collect()
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * (1.0 + a.abs().max(b.abs()))
}

fn assert_close(what: &str, file: &str, got: &[f64], want: &[f64], tol: f64) {
    assert_eq!(got.len(), want.len(), "{file}: {what} length");
    for (n, (g, w)) in got.iter().zip(want).enumerate() {
        assert!(
            close(*g, *w, tol),
            "{file}: {what}[{n}] is {g}, the library says {w}"
        );
    }
}

fn is_volume_file(name: &str) -> bool {
    [".npy", ".nrrd", ".nhdr", ".nii", ".nii.gz", ".mhd", ".mha"]
        .iter()
        .any(|e| name.ends_with(e))
}

#[test]
fn every_fixture_matches_its_library() {
    let doc = expected();
    let fixtures = doc["fixtures"].as_array().expect("fixtures");
    assert!(fixtures.len() >= 25);
    for fx in fixtures {
        let file = fx["file"].as_str().expect("file");
        let g = read_volume(&fixture(file)).unwrap_or_else(|e| panic!("{file}: {e}"));
        let dims: Vec<usize> = f64s(&fx["dims"]).iter().map(|&d| d as usize).collect();
        assert_eq!(g.dims.to_vec(), dims, "{file}: dims");
        assert_close("spacing", file, &g.spacing, &f64s(&fx["spacing"]), 1e-6);
        assert_close("origin", file, &g.origin, &f64s(&fx["origin"]), 1e-6);
        let want_dir: Vec<f64> = fx["direction"]
            .as_array()
            .expect("direction")
            .iter()
            .flat_map(f64s)
            .collect();
        let got_dir: Vec<f64> = g.direction.iter().flatten().copied().collect();
        assert_close("direction", file, &got_dir, &want_dir, 1e-6);
        assert_close(
            "values",
            file,
            &g.values.to_f64_vec(),
            &f64s(&fx["values"]),
            1e-12,
        );
        let sum: f64 = g.values.iter().sum();
        assert!(
            close(sum, fx["sum"].as_f64().expect("sum"), 1e-12),
            "{file}: sum {sum}"
        );
    }
}

#[test]
fn every_fixture_file_is_listed() {
    let doc = expected();
    let listed: Vec<&str> = doc["fixtures"]
        .as_array()
        .expect("fixtures")
        .iter()
        .map(|f| f["file"].as_str().expect("file"))
        .collect();
    for entry in fs::read_dir(fixture_dir()).expect("fixture dir") {
        let name = entry
            .expect("entry")
            .file_name()
            .to_string_lossy()
            .into_owned();
        if is_volume_file(&name) {
            assert!(
                listed.contains(&name.as_str()),
                "{name} is not in expected.json"
            );
        }
    }
}

#[test]
fn all_formats_give_the_same_cube() {
    let doc = expected();
    let cube = f64s(&doc["cube_values"]);
    assert_eq!(cube.len(), 64);
    let mut formats = Vec::new();
    let mut grids: Vec<(String, ScalarGrid)> = Vec::new();
    for fx in doc["fixtures"].as_array().expect("fixtures") {
        if fx["cube"].as_bool() != Some(true) {
            continue;
        }
        let file = fx["file"].as_str().expect("file");
        let g = read_volume(&fixture(file)).unwrap_or_else(|e| panic!("{file}: {e}"));
        assert_eq!(g.dims, [4, 4, 4], "{file}");
        for k in 0..4 {
            for j in 0..4 {
                for i in 0..4 {
                    assert_eq!(
                        g.value(i, j, k),
                        (i + 10 * j + 100 * k) as f64,
                        "{file} at ({i},{j},{k})"
                    );
                }
            }
        }
        formats.push(fx["format"].as_str().expect("format").to_string());
        grids.push((file.to_string(), g));
    }
    for f in ["npy", "nrrd", "nifti", "mhd"] {
        assert!(formats.iter().any(|x| x == f), "no cube fixture for {f}");
    }
    for (file, g) in &grids[1..] {
        let (a, b) = (g.values.to_f64_vec(), grids[0].1.values.to_f64_vec());
        assert_eq!(a, b, "{file} vs {}", grids[0].0);
        assert_eq!(g.values.to_f64_vec(), cube, "{file}");
    }
}

#[test]
fn geometry_maps_vertices_like_the_libraries() {
    // SimpleITK: physical point of index (1, 2, 1) of the oblique float image
    let g = read_volume(&fixture("mhd_aniso_f4.mhd")).unwrap();
    let p = g.to_physical([1.0, 2.0, 1.0]);
    let m = g.linear_map();
    for r in 0..3 {
        let want = g.origin[r] + m[r][0] + 2.0 * m[r][1] + m[r][2];
        assert!((p[r] - want).abs() < 1e-12);
    }
    // nibabel sform: affine applied to (i, j, k) equals to_physical
    let doc = expected();
    let fx = doc["fixtures"]
        .as_array()
        .unwrap()
        .iter()
        .find(|f| f["file"] == "nii_aniso_f4_sform.nii.gz")
        .unwrap();
    let g = read_volume(&fixture("nii_aniso_f4_sform.nii.gz")).unwrap();
    assert!(g.affine_determinant() > 0.0);
    let sp = f64s(&fx["spacing"]);
    assert!((sp[0] - 0.8).abs() < 1e-6 && (sp[1] - 1.1).abs() < 1e-6 && (sp[2] - 2.5).abs() < 1e-6);
    // the qform fixture is left-handed (qfac = -1)
    let g = read_volume(&fixture("nii_aniso_f8_qform.nii")).unwrap();
    assert!(g.affine_determinant() < 0.0);
}

// ------------------------------------------------------------------------ broken inputs

/// Reads `path`, which must fail with a one-line message naming the file; returns it.
fn expect_err(path: &Path) -> String {
    let name = path.file_name().unwrap().to_string_lossy().into_owned();
    match read_volume(path) {
        Ok(g) => panic!("{name}: expected an error, got a {:?} grid", g.dims),
        Err(e) => {
            let msg = e.to_string();
            eprintln!("{msg}");
            assert!(
                !msg.contains('\n') && !msg.contains('\r'),
                "{name}: multi-line message {msg:?}"
            );
            assert!(
                msg.contains(&name),
                "{name}: message does not name the file: {msg}"
            );
            msg
        }
    }
}

fn expect_err_containing(path: &Path, words: &[&str]) -> String {
    let msg = expect_err(path);
    for w in words {
        assert!(
            msg.to_lowercase().contains(&w.to_lowercase()),
            "{:?}: message lacks {w:?}: {msg}",
            path.file_name()
        );
    }
    msg
}

fn replace(data: &[u8], from: &[u8], to: &[u8]) -> Vec<u8> {
    let pos = data
        .windows(from.len())
        .position(|w| w == from)
        .unwrap_or_else(|| panic!("{:?} not found", String::from_utf8_lossy(from)));
    let mut out = data[..pos].to_vec();
    out.extend_from_slice(to);
    out.extend_from_slice(&data[pos + from.len()..]);
    out
}

struct Scratch {
    dir: tempfile::TempDir,
}

impl Scratch {
    fn new() -> Self {
        Scratch {
            dir: tempfile::tempdir().expect("tempdir"),
        }
    }
    fn write(&self, name: &str, bytes: &[u8]) -> PathBuf {
        let p = self.dir.path().join(name);
        fs::write(&p, bytes).expect("write");
        p
    }
    /// Copies a fixture, transformed by `f`.
    fn derive(
        &self,
        fixture_name: &str,
        new_name: &str,
        f: impl FnOnce(Vec<u8>) -> Vec<u8>,
    ) -> PathBuf {
        let bytes = fs::read(fixture(fixture_name)).expect("fixture");
        self.write(new_name, &f(bytes))
    }
}

fn garbage(n: usize, seed: u32) -> Vec<u8> {
    let mut x = seed.wrapping_mul(2_654_435_761).max(1);
    (0..n)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            (x >> 7) as u8
        })
        .collect()
}

const EXTS: [&str; 7] = ["npy", "nrrd", "nhdr", "nii", "nii.gz", "mhd", "mha"];

#[test]
fn empty_and_garbage_files_are_errors() {
    let s = Scratch::new();
    for (n, ext) in EXTS.iter().enumerate() {
        expect_err(&s.write(&format!("empty.{ext}"), b""));
        for (m, len) in [1usize, 3, 7, 100, 348, 600, 5000].into_iter().enumerate() {
            expect_err(&s.write(
                &format!("garbage{m}.{ext}"),
                &garbage(len, (n * 31 + m) as u32 + 1),
            ));
        }
        // text lines that look almost right
        expect_err(&s.write(
            &format!("text.{ext}"),
            b"NRRD0004\nhello: world\nNDims = 3\n\n",
        ));
    }
    expect_err_containing(&s.write("volume.tiff", b"II*\0"), &["supported", ".nii.gz"]);
    expect_err_containing(&s.write("noextension", b""), &["supported"]);
    expect_err(&s.dir.path().join("does_not_exist.nii"));
}

#[test]
fn every_truncation_of_every_fixture_is_an_error() {
    let s = Scratch::new();
    let doc = expected();
    for fx in doc["fixtures"].as_array().unwrap() {
        let file = fx["file"].as_str().unwrap();
        let bytes = fs::read(fixture(file)).unwrap();
        // detached headers: truncating the header alone can still describe valid data
        if file.ends_with(".nhdr") || file.ends_with(".mhd") {
            continue;
        }
        let cuts: Vec<usize> = (0..bytes.len())
            .step_by(7)
            .chain([bytes.len() - 1])
            .collect();
        for cut in cuts {
            if file.contains("skipm1") && cut + 8 >= bytes.len() {
                // 'byte skip: -1': the data are the last bytes, whatever precedes them
                continue;
            }
            let name = format!("cut{cut}_{file}");
            let p = s.write(&name, &bytes[..cut]);
            expect_err(&p);
        }
    }
}

#[test]
fn truncated_or_oversized_detached_data_are_errors() {
    let s = Scratch::new();
    for (hdr, data) in [
        ("nrrd_aniso_u2_detached.nhdr", "nrrd_aniso_u2_detached.raw"),
        (
            "nrrd_aniso_u1_gz_detached.nhdr",
            "nrrd_aniso_u1_gz_detached.raw.gz",
        ),
        ("nrrd_aniso_i4_skip.nhdr", "nrrd_aniso_i4_skip.raw"),
        ("mhd_aniso_f4.mhd", "mhd_aniso_f4.raw"),
        ("mhd_aniso_u2_z.mhd", "mhd_aniso_u2_z.zraw"),
    ] {
        let d = fs::read(fixture(data)).unwrap();
        let h = fs::read(fixture(hdr)).unwrap();
        for (n, content) in [
            d[..d.len() - 1].to_vec(),
            d[..d.len() / 2].to_vec(),
            Vec::new(),
            [d.clone(), vec![0; 4]].concat(),
        ]
        .into_iter()
        .enumerate()
        {
            let sub = s.dir.path().join(format!("case{n}"));
            fs::create_dir_all(&sub).unwrap();
            fs::write(sub.join(data), &content).unwrap();
            fs::write(sub.join(hdr), &h).unwrap();
            // the gzip member is self-delimiting: appended zeros are a garbage trailer
            expect_err(&sub.join(hdr));
        }
    }
}

#[test]
fn missing_detached_data_file_is_an_error() {
    let s = Scratch::new();
    for hdr in [
        "nrrd_aniso_u2_detached.nhdr",
        "nrrd_aniso_u1_gz_detached.nhdr",
        "mhd_cube_i2.mhd",
        "mhd_aniso_u2_z.mhd",
    ] {
        let p = s.derive(hdr, hdr, |b| b);
        let msg = expect_err_containing(&p, &["data file"]);
        assert!(msg.contains(".raw") || msg.contains(".zraw"), "{msg}");
    }
    // .nhdr without a data file field
    let p = s.derive("nrrd_aniso_u2_detached.nhdr", "nofield.nhdr", |b| {
        replace(&b, b"data file: nrrd_aniso_u2_detached.raw", b"")
    });
    expect_err_containing(&p, &["data file"]);
}

#[test]
fn header_dims_that_do_not_match_the_data_are_errors() {
    let s = Scratch::new();
    // npy: shape larger and smaller than the data
    for (n, to) in [b"(5, 4, 4)", b"(5, 4, 2)"].iter().enumerate() {
        let p = s.derive("npy_aniso_i2_c.npy", &format!("shape{n}.npy"), |b| {
            replace(&b, b"(5, 4, 3)", *to)
        });
        expect_err_containing(&p, &["bytes"]);
    }
    // a lying header asking for terabytes must fail fast, without allocating them
    let p = s.derive("npy_aniso_i2_c.npy", "huge.npy", |b| {
        replace(&b, b"(5, 4, 3),", b"(99999, 99999, 99999),")
    });
    expect_err_containing(&p, &["bytes"]);
    let p = s.derive("npy_aniso_i2_c.npy", "overflow.npy", |b| {
        replace(&b, b"(5, 4, 3),", b"(18446744073709551615, 4, 3),")
    });
    expect_err(&p);
    // nrrd attached raw / gzip / detached
    for (fx, from, to) in [
        (
            "nrrd_cube_i2_raw.nrrd",
            &b"sizes: 4 4 4"[..],
            &b"sizes: 4 4 5"[..],
        ),
        ("nrrd_cube_i2_raw.nrrd", b"sizes: 4 4 4", b"sizes: 4 4 3"),
        (
            "nrrd_cube_i2_raw.nrrd",
            b"sizes: 4 4 4",
            b"sizes: 100000 100000 100000",
        ),
        ("nrrd_cube_i2_raw.nrrd", b"sizes: 4 4 4", b"sizes: 4 4"),
        ("nrrd_cube_i2_raw.nrrd", b"sizes: 4 4 4", b"sizes: 4 -4 4"),
        ("nrrd_aniso_f4_gzip.nrrd", b"sizes: 5 4 3", b"sizes: 5 4 4"),
        ("nrrd_aniso_f4_gzip.nrrd", b"sizes: 5 4 3", b"sizes: 5 4 2"),
        (
            "nrrd_aniso_f4_gzip.nrrd",
            b"sizes: 5 4 3",
            b"sizes: 4294967296 4294967296 4294967296",
        ),
        (
            "nrrd_aniso_u1_skipm1.nrrd",
            b"sizes: 5 4 3",
            b"sizes: 50 40 30",
        ),
    ] {
        let name = format!(
            "dims_{}_{}",
            String::from_utf8_lossy(to).replace([' ', ':'], ""),
            fx
        );
        let p = s.derive(fx, &name, |b| replace(&b, from, to));
        expect_err(&p);
    }
    let sub = s.dir.path().join("detached");
    fs::create_dir_all(&sub).unwrap();
    fs::copy(
        fixture("nrrd_aniso_u2_detached.raw"),
        sub.join("nrrd_aniso_u2_detached.raw"),
    )
    .unwrap();
    let h = fs::read(fixture("nrrd_aniso_u2_detached.nhdr")).unwrap();
    fs::write(
        sub.join("big.nhdr"),
        replace(&h, b"sizes: 5 4 3", b"sizes: 5 4 30"),
    )
    .unwrap();
    expect_err_containing(
        &sub.join("big.nhdr"),
        &["bytes", "nrrd_aniso_u2_detached.raw"],
    );
    // nifti: dim[3] (int16 at byte 46) larger / smaller
    for (n, d3) in [4i16, 2, 30000].into_iter().enumerate() {
        for fx in ["nii_aniso_f8_qform.nii", "nii_aniso_f4_sform.nii.gz"] {
            if fx.ends_with(".gz") {
                continue; // header is compressed; handled in the gzip test
            }
            let p = s.derive(fx, &format!("dim{n}_{fx}"), |mut b| {
                b[46..48].copy_from_slice(&d3.to_le_bytes());
                b
            });
            if d3 == 2 {
                // fewer voxels than stored: NIfTI allows trailing bytes, the read succeeds
                assert_eq!(read_volume(&p).unwrap().dims, [5, 4, 2]);
            } else {
                expect_err_containing(&p, &["bytes"]);
            }
        }
    }
    // negative dim
    let p = s.derive("nii_aniso_f8_qform.nii", "negdim.nii", |mut b| {
        b[42..44].copy_from_slice(&(-4i16).to_le_bytes());
        b
    });
    expect_err(&p);
    // mhd: DimSize larger / smaller than the raw file, and LOCAL data
    for (n, to) in [
        &b"DimSize = 5 4 4"[..],
        b"DimSize = 5 4 2",
        b"DimSize = 5 4",
        b"DimSize = 5 4 x",
    ]
    .into_iter()
    .enumerate()
    {
        let sub = s.dir.path().join(format!("mhd{n}"));
        fs::create_dir_all(&sub).unwrap();
        fs::copy(fixture("mhd_aniso_f4.raw"), sub.join("mhd_aniso_f4.raw")).unwrap();
        let h = fs::read(fixture("mhd_aniso_f4.mhd")).unwrap();
        fs::write(
            sub.join("mhd_aniso_f4.mhd"),
            replace(&h, b"DimSize = 5 4 3", to),
        )
        .unwrap();
        expect_err(&sub.join("mhd_aniso_f4.mhd"));
        let p = s.derive("mhd_aniso_f8_local.mha", &format!("dims{n}.mha"), |b| {
            replace(&b, b"DimSize = 5 4 3", to)
        });
        expect_err(&p);
    }
}

#[test]
fn unsupported_types_and_encodings_are_errors() {
    let s = Scratch::new();
    let cases: [(&str, &[u8], &[u8], &str); 12] = [
        ("npy_cube_f4_c.npy", b"'<f4'", b"'<c8'", "dtype"),
        ("npy_cube_f4_c.npy", b"'<f4'", b"'<f2'", "dtype"),
        ("npy_cube_f4_c.npy", b"'<f4'", b"'|O8'", "dtype"),
        (
            "npy_cube_f4_c.npy",
            b"'descr': '<f4'",
            b"'descr': [('a', '<f4')]",
            "structured",
        ),
        (
            "nrrd_cube_i2_raw.nrrd",
            b"encoding: raw",
            b"encoding: bzip2",
            "encoding",
        ),
        (
            "nrrd_cube_i2_raw.nrrd",
            b"encoding: raw",
            b"encoding: hex",
            "encoding",
        ),
        (
            "nrrd_cube_i2_raw.nrrd",
            b"type: int16",
            b"type: block",
            "type",
        ),
        ("nrrd_cube_i2_raw.nrrd", b"NRRD0005", b"NRRD0009", "version"),
        (
            "mhd_aniso_f8_local.mha",
            b"MET_DOUBLE",
            b"MET_STRING",
            "ElementType",
        ),
        (
            "mhd_aniso_f8_local.mha",
            b"NDims = 3",
            b"NDims = 4",
            "NDims",
        ),
        (
            "mhd_aniso_f8_local.mha",
            b"BinaryData = True",
            b"BinaryData = False",
            "ASCII",
        ),
        (
            "mhd_aniso_f8_local.mha",
            b"ObjectType = Image",
            b"ObjectType = Mesh",
            "ObjectType",
        ),
    ];
    for (n, (fx, from, to, word)) in cases.into_iter().enumerate() {
        let ext = if fx.ends_with(".npy") {
            "npy"
        } else if fx.ends_with(".nrrd") {
            "nrrd"
        } else {
            "mha"
        };
        let p = s.derive(fx, &format!("unsup{n}.{ext}"), |b| replace(&b, from, to));
        let msg = expect_err_containing(&p, &[word]);
        assert!(msg.contains("unsupported") || n == 3, "{msg}");
    }
    // nifti datatype 32 (complex64) and 128 (rgb24)
    for code in [32i16, 128, 0, -5] {
        let p = s.derive(
            "nii_cube_i2_sform.nii",
            &format!("dt{code}.nii"),
            |mut b| {
                b[70..72].copy_from_slice(&code.to_le_bytes());
                b
            },
        );
        expect_err_containing(&p, &["datatype"]);
    }
    // nifti header/image pair magic
    let p = s.derive("nii_cube_i2_sform.nii", "pair.nii", |mut b| {
        b[344..348].copy_from_slice(b"ni1\0");
        b
    });
    expect_err_containing(&p, &["unsupported"]);
}

#[test]
fn wrong_magic_is_an_error() {
    let s = Scratch::new();
    let p = s.derive("npy_cube_f4_c.npy", "magic.npy", |mut b| {
        b[1] = b'X';
        b
    });
    expect_err_containing(&p, &["magic"]);
    let p = s.derive("npy_cube_f4_c.npy", "version9.npy", |mut b| {
        b[6] = 9;
        b
    });
    expect_err_containing(&p, &["version"]);
    let p = s.derive("nrrd_cube_i2_raw.nrrd", "magic.nrrd", |b| {
        replace(&b, b"NRRD0005", b"NRRX0005")
    });
    expect_err_containing(&p, &["magic"]);
    let p = s.derive("nii_cube_i2_sform.nii", "magic.nii", |mut b| {
        b[344..348].copy_from_slice(b"n+9\0");
        b
    });
    expect_err_containing(&p, &["magic"]);
    let p = s.derive("nii_cube_i2_sform.nii", "sizeof.nii", |mut b| {
        b[0..4].copy_from_slice(&349i32.to_le_bytes());
        b
    });
    expect_err_containing(&p, &["sizeof_hdr"]);
    // a NIfTI file named .npy and an NRRD named .nii are rejected by the reader for the name
    let p = s.derive("nii_cube_i2_sform.nii", "nifti.npy", |b| b);
    expect_err_containing(&p, &["magic"]);
    let p = s.derive("nrrd_cube_i2_raw.nrrd", "nrrd.nii", |b| b);
    expect_err_containing(&p, &["sizeof_hdr"]);
    let p = s.derive("npy_cube_f4_c.npy", "npy.mha", |b| b);
    expect_err(&p);
}

#[test]
fn non_3d_arrays_are_errors() {
    let s = Scratch::new();
    let p = s.write("flat2d.npy", &npy_bytes("<f8", "(4, 4)", &[0u8; 128]));
    expect_err_containing(&p, &["2-D"]);
    let p = s.write("flat4d.npy", &npy_bytes("<f8", "(2, 2, 2, 2)", &[0u8; 128]));
    expect_err_containing(&p, &["4-D"]);
    let p = s.write("scalar.npy", &npy_bytes("<f8", "()", &[0u8; 8]));
    expect_err(&p);
    // a 3-D array with a dimension of 1 is not a volume either
    let p = s.write("thin.npy", &npy_bytes("<f8", "(4, 1, 4)", &[0u8; 128]));
    expect_err_containing(&p, &["at least 2"]);
    // sanity: the hand writer produces readable files
    let p = s.write("ok.npy", &npy_bytes("<f8", "(2, 2, 2)", &[0u8; 64]));
    assert_eq!(read_volume(&p).unwrap().dims, [2, 2, 2]);

    let p = s.derive("nrrd_cube_i2_raw.nrrd", "dim2.nrrd", |b| {
        replace(&b, b"dimension: 3", b"dimension: 2")
    });
    expect_err_containing(&p, &["dimension"]);
    let p = s.derive("nii_cube_i2_sform.nii", "dim2.nii", |mut b| {
        b[40..42].copy_from_slice(&2i16.to_le_bytes());
        b
    });
    expect_err(&p);
    let p = s.derive("nii_cube_i2_sform.nii", "dim4.nii", |mut b| {
        b[40..42].copy_from_slice(&4i16.to_le_bytes());
        b[48..50].copy_from_slice(&2i16.to_le_bytes());
        b
    });
    expect_err_containing(&p, &["3-D"]);
    let p = s.derive("nii_cube_i2_sform.nii", "dim9.nii", |mut b| {
        b[40..42].copy_from_slice(&9i16.to_le_bytes());
        b
    });
    expect_err(&p);
}

#[test]
fn nan_and_inf_in_float_volumes_are_errors() {
    let s = Scratch::new();
    // npy f8 Fortran order: sample 7 is vertex (2, 1, 0)
    let p = s.derive("npy_aniso_f8_f.npy", "nan.npy", |mut b| {
        let off = b.len() - 60 * 8 + 7 * 8;
        b[off..off + 8].copy_from_slice(&f64::NAN.to_le_bytes());
        b
    });
    expect_err_containing(&p, &["not finite", "(2, 1, 0)"]);
    // big-endian f4 npy with +inf as the last sample
    let p = s.derive("npy_aniso_f4_be_f.npy", "inf.npy", |mut b| {
        let n = b.len();
        b[n - 4..].copy_from_slice(&f32::INFINITY.to_be_bytes());
        b
    });
    expect_err_containing(&p, &["not finite", "(4, 3, 2)"]);
    // nifti float64 (vox_offset 352)
    let p = s.derive("nii_aniso_f8_qform.nii", "nan.nii", |mut b| {
        b[352..360].copy_from_slice(&f64::NAN.to_le_bytes());
        b
    });
    expect_err_containing(&p, &["not finite"]);
    // nrrd big-endian double, raw
    let p = s.derive("nrrd_aniso_f8_be_raw.nrrd", "nan.nrrd", |mut b| {
        let n = b.len();
        b[n - 16..n - 8].copy_from_slice(&f64::NAN.to_be_bytes());
        b
    });
    expect_err_containing(&p, &["not finite"]);
    // mhd float raw
    let sub = s.dir.path().join("mhdnan");
    fs::create_dir_all(&sub).unwrap();
    fs::copy(fixture("mhd_aniso_f4.mhd"), sub.join("mhd_aniso_f4.mhd")).unwrap();
    let mut raw = fs::read(fixture("mhd_aniso_f4.raw")).unwrap();
    raw[0..4].copy_from_slice(&f32::NEG_INFINITY.to_le_bytes());
    fs::write(sub.join("mhd_aniso_f4.raw"), raw).unwrap();
    expect_err_containing(&sub.join("mhd_aniso_f4.mhd"), &["not finite", "(0, 0, 0)"]);
}

#[test]
fn corrupt_compressed_streams_are_errors() {
    let s = Scratch::new();
    // overwrite the middle of the compressed payload with 0xff / flip bits
    fn damage(mut b: Vec<u8>, from: usize, mode: u8) -> Vec<u8> {
        let n = b.len();
        let range = from.min(n)..((from + 24).min(n));
        for x in &mut b[range] {
            *x = if mode == 0 { 0xff } else { *x ^ 0x55 };
        }
        b
    }
    for mode in 0..2 {
        let nrrd = fs::read(fixture("nrrd_aniso_f4_gzip.nrrd")).unwrap();
        let start = nrrd.windows(2).position(|w| w == b"\n\n").unwrap() + 2;
        let p = s.derive(
            "nrrd_aniso_f4_gzip.nrrd",
            &format!("corrupt{mode}.nrrd"),
            |b| damage(b, start + 20, mode),
        );
        expect_err(&p);
        let p = s.derive(
            "nii_aniso_f4_sform.nii.gz",
            &format!("corrupt{mode}.nii.gz"),
            |b| damage(b, 40, mode),
        );
        expect_err(&p);
        let p = s.derive(
            "nii2_aniso_i4.nii.gz",
            &format!("corrupt2_{mode}.nii.gz"),
            |b| damage(b, 200, mode),
        );
        expect_err(&p);
        let sub = s.dir.path().join(format!("zraw{mode}"));
        fs::create_dir_all(&sub).unwrap();
        fs::copy(
            fixture("mhd_aniso_u2_z.mhd"),
            sub.join("mhd_aniso_u2_z.mhd"),
        )
        .unwrap();
        let z = fs::read(fixture("mhd_aniso_u2_z.zraw")).unwrap();
        fs::write(sub.join("mhd_aniso_u2_z.zraw"), damage(z, 10, mode)).unwrap();
        expect_err(&sub.join("mhd_aniso_u2_z.mhd"));
        let sub = s.dir.path().join(format!("rawgz{mode}"));
        fs::create_dir_all(&sub).unwrap();
        fs::copy(
            fixture("nrrd_aniso_u1_gz_detached.nhdr"),
            sub.join("nrrd_aniso_u1_gz_detached.nhdr"),
        )
        .unwrap();
        let z = fs::read(fixture("nrrd_aniso_u1_gz_detached.raw.gz")).unwrap();
        fs::write(
            sub.join("nrrd_aniso_u1_gz_detached.raw.gz"),
            damage(z, 12, mode),
        )
        .unwrap();
        expect_err(&sub.join("nrrd_aniso_u1_gz_detached.nhdr"));
    }
    // plain (uncompressed) data declared as gzip
    let p = s.derive("nrrd_cube_i2_raw.nrrd", "notgz.nrrd", |b| {
        replace(&b, b"encoding: raw", b"encoding: gzip")
    });
    expect_err_containing(&p, &["gzip"]);
}

#[test]
fn malformed_header_fields_are_errors() {
    let s = Scratch::new();
    let nrrd_cases: [(&[u8], &[u8]); 9] = [
        (b"endian: little\n", b""),
        (b"endian: little", b"endian: middle"),
        (
            b"space directions: (1,0,0) (0,2,0) (0,0,3)",
            b"space directions: (1,0,0) (0,2,0)",
        ),
        (
            b"space directions: (1,0,0) (0,2,0) (0,0,3)",
            b"space directions: (1,0,0) (0,0,0) (0,0,3)",
        ),
        (
            b"space directions: (1,0,0) (0,2,0) (0,0,3)",
            b"space directions: (1,0,0) (0,2,0) none",
        ),
        (
            b"space directions: (1,0,0) (0,2,0) (0,0,3)",
            b"space directions: (1,0,0) (0,2,0) (0,0,nan)",
        ),
        (b"space origin: (-1,2.5,10)", b"space origin: (-1,2.5)"),
        (b"type: int16\n", b""),
        (b"encoding: raw", b"encoding: raw\nbyte skip: 99999"),
    ];
    for (n, (from, to)) in nrrd_cases.into_iter().enumerate() {
        let p = s.derive("nrrd_cube_i2_raw.nrrd", &format!("field{n}.nrrd"), |b| {
            replace(&b, from, to)
        });
        expect_err(&p);
    }
    let mhd_cases: [(&[u8], &[u8]); 5] = [
        (
            b"ElementSpacing = 0.29999999999999999 0.29999999999999999 0.59999999999999998",
            b"ElementSpacing = 1 1",
        ),
        (
            b"ElementSpacing = 0.29999999999999999 0.29999999999999999 0.59999999999999998",
            b"ElementSpacing = 1 0 1",
        ),
        (b"Offset = 0 1 2", b"Offset = 0 one 2"),
        (
            b"BinaryDataByteOrderMSB = False",
            b"BinaryDataByteOrderMSB = Maybe",
        ),
        (b"ElementType = MET_DOUBLE\n", b""),
    ];
    for (n, (from, to)) in mhd_cases.into_iter().enumerate() {
        let p = s.derive("mhd_aniso_f8_local.mha", &format!("field{n}.mha"), |b| {
            replace(&b, from, to)
        });
        expect_err(&p);
    }
    // NIfTI: a singular sform, an invalid vox_offset, a NaN intercept with a valid slope
    let p = s.derive("nii_cube_i2_sform.nii", "sform0.nii", |mut b| {
        b[280..296].copy_from_slice(&[0u8; 16]);
        b
    });
    expect_err_containing(&p, &["sform"]);
    let p = s.derive("nii_cube_i2_sform.nii", "voxoff.nii", |mut b| {
        b[108..112].copy_from_slice(&352.5f32.to_le_bytes());
        b
    });
    expect_err_containing(&p, &["vox_offset"]);
    let p = s.derive("nii_aniso_i2_scaled.nii", "inter.nii", |mut b| {
        b[116..120].copy_from_slice(&f32::NAN.to_le_bytes());
        b
    });
    expect_err_containing(&p, &["scl_inter"]);
}

#[test]
fn nifti_scaling_and_endianness() {
    // slope 0.5, intercept -3 applied by nibabel and by us
    let g = read_volume(&fixture("nii_aniso_i2_scaled.nii")).unwrap();
    assert_eq!(g.value(0, 0, 0), -30.0 * 0.5 - 3.0);
    // slope 0 means "no scaling"
    let s = Scratch::new();
    let p = s.derive("nii_aniso_i2_scaled.nii", "slope0.nii", |mut b| {
        b[112..116].copy_from_slice(&0f32.to_le_bytes());
        b
    });
    assert_eq!(read_volume(&p).unwrap().value(0, 0, 0), -30.0);
    // big-endian header and data (4-D with dim[4] = 1)
    let g = read_volume(&fixture("nii_aniso_u2_be_4d.nii")).unwrap();
    assert_eq!(g.dims, [5, 4, 3]);
    assert_eq!(g.value(1, 0, 0), 800.0);
}

#[test]
fn random_byte_mutations_never_panic() {
    let s = Scratch::new();
    let doc = expected();
    let mut rng = 0x9e37_79b9u32;
    let mut next = move || {
        rng ^= rng << 13;
        rng ^= rng >> 17;
        rng ^= rng << 5;
        rng as usize
    };
    let mut errors = 0usize;
    for fx in doc["fixtures"].as_array().unwrap() {
        let file = fx["file"].as_str().unwrap();
        let bytes = fs::read(fixture(file)).unwrap();
        let sub = s.dir.path().join(file.replace('.', "_"));
        fs::create_dir_all(&sub).unwrap();
        // detached data files next to the (mutated) header
        for entry in fs::read_dir(fixture_dir()).unwrap() {
            let name = entry.unwrap().file_name().to_string_lossy().into_owned();
            if !is_volume_file(&name) && !name.ends_with(".json") {
                fs::copy(fixture(&name), sub.join(&name)).unwrap();
            }
        }
        for round in 0..150 {
            let mut b = bytes.clone();
            for _ in 0..1 + round % 3 {
                let at = next() % b.len();
                b[at] = match next() % 4 {
                    0 => b[at] ^ (1 << (next() % 8)),
                    1 => b'0' + (next() % 10) as u8,
                    2 => 0xff,
                    _ => next() as u8,
                };
            }
            let p = sub.join(file);
            fs::write(&p, &b).unwrap();
            if let Err(e) = read_volume(&p) {
                let msg = e.to_string();
                assert!(!msg.contains('\n') && msg.contains(file), "{msg}");
                errors += 1;
            }
        }
    }
    assert!(errors > 0);
}
