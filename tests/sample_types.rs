//! Samples keep their storage type: every reader returns uint8, int16, uint16 and float32
//! volumes in that type with exact values (either byte order, compressed or not), i8 and
//! 32-bit integers are widened exactly, and a grid's samples mesh the same in any type.

use std::io::Write;
use std::path::Path;

use tptd::io::read_volume;
use tptd::{mesh_interval, MeshOptions, Method, SampleStorage, Samples, ScalarGrid};

/// 45 samples (odd, so in-place widening meets its last odd half).
const DIMS: [usize; 3] = [5, 3, 3];
const N: usize = 45;

/// A file sample type: its names in each format, size, and the values written.
struct Ty {
    npy: &'static str,
    nrrd: &'static str,
    nifti: i16,
    mhd: &'static str,
    size: usize,
    storage: SampleStorage,
    values: Vec<f64>,
}

fn types() -> Vec<Ty> {
    let v = |f: fn(usize) -> f64| (0..N).map(f).collect::<Vec<f64>>();
    vec![
        Ty {
            npy: "u1",
            nrrd: "uint8",
            nifti: 2,
            mhd: "MET_UCHAR",
            size: 1,
            storage: SampleStorage::U8,
            values: v(|n| ((n * 37) % 256) as f64),
        },
        Ty {
            npy: "i2",
            nrrd: "int16",
            nifti: 4,
            mhd: "MET_SHORT",
            size: 2,
            storage: SampleStorage::I16,
            values: v(|n| (n as f64 * 1403.0) - 31000.0),
        },
        Ty {
            npy: "u2",
            nrrd: "uint16",
            nifti: 512,
            mhd: "MET_USHORT",
            size: 2,
            storage: SampleStorage::U16,
            values: v(|n| ((n * 1499) % 65536) as f64),
        },
        Ty {
            npy: "f4",
            nrrd: "float",
            nifti: 16,
            mhd: "MET_FLOAT",
            size: 4,
            storage: SampleStorage::F32,
            values: v(|n| f64::from(n as f32 * 0.37 - 5.0)),
        },
        Ty {
            npy: "i1",
            nrrd: "int8",
            nifti: 256,
            mhd: "MET_CHAR",
            size: 1,
            storage: SampleStorage::I16,
            values: v(|n| (n as f64 * 5.0) - 128.0),
        },
        Ty {
            npy: "i4",
            nrrd: "int32",
            nifti: 8,
            mhd: "MET_INT",
            size: 4,
            storage: SampleStorage::F64,
            values: v(|n| n as f64 * 40_000_001.0 - 2e9),
        },
    ]
}

/// The samples of `t` as stored bytes, x fastest.
fn bytes(t: &Ty, big: bool) -> Vec<u8> {
    let mut out = Vec::new();
    for &x in &t.values {
        let mut b: Vec<u8> = match t.npy {
            "u1" => vec![x as u8],
            "i1" => vec![x as i8 as u8],
            "i2" => (x as i16).to_le_bytes().to_vec(),
            "u2" => (x as u16).to_le_bytes().to_vec(),
            "i4" => (x as i32).to_le_bytes().to_vec(),
            _ => (x as f32).to_le_bytes().to_vec(),
        };
        if big {
            b.reverse();
        }
        out.extend(b);
    }
    out
}

fn write_npy(path: &Path, t: &Ty, big: bool) {
    let order = if t.size == 1 {
        '|'
    } else if big {
        '>'
    } else {
        '<'
    };
    let mut h = format!(
        "{{'descr': '{order}{}', 'fortran_order': True, 'shape': ({}, {}, {}), }}",
        t.npy, DIMS[0], DIMS[1], DIMS[2]
    );
    while (10 + h.len() + 1) % 64 != 0 {
        h.push(' ');
    }
    h.push('\n');
    let mut f = b"\x93NUMPY\x01\x00".to_vec();
    f.extend((h.len() as u16).to_le_bytes());
    f.extend(h.as_bytes());
    f.extend(bytes(t, big));
    std::fs::write(path, f).unwrap();
}

fn write_nrrd(path: &Path, t: &Ty, big: bool, gzip: bool) {
    let endian = if big { "big" } else { "little" };
    let enc = if gzip { "gzip" } else { "raw" };
    let head = format!(
        "NRRD0004\ntype: {}\ndimension: 3\nsizes: {} {} {}\nencoding: {enc}\nendian: {endian}\n\n",
        t.nrrd, DIMS[0], DIMS[1], DIMS[2]
    );
    let mut f = head.into_bytes();
    let data = bytes(t, big);
    f.extend(if gzip { gz(&data) } else { data });
    std::fs::write(path, f).unwrap();
}

fn gz(data: &[u8]) -> Vec<u8> {
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    e.write_all(data).unwrap();
    e.finish().unwrap()
}

/// NIfTI-1, little-endian, 352-byte offset; `scale` = (scl_slope, scl_inter).
fn nifti(t: &Ty, scale: (f32, f32)) -> Vec<u8> {
    let mut h = vec![0u8; 352];
    let put = |h: &mut Vec<u8>, at: usize, b: &[u8]| h[at..at + b.len()].copy_from_slice(b);
    put(&mut h, 0, &348i32.to_le_bytes());
    for (i, d) in [3, DIMS[0], DIMS[1], DIMS[2], 1, 1, 1, 1]
        .iter()
        .enumerate()
    {
        put(&mut h, 40 + 2 * i, &(*d as i16).to_le_bytes());
    }
    put(&mut h, 70, &t.nifti.to_le_bytes());
    put(&mut h, 72, &(8 * t.size as i16).to_le_bytes());
    for i in 0..8 {
        put(&mut h, 76 + 4 * i, &1f32.to_le_bytes());
    }
    put(&mut h, 108, &352f32.to_le_bytes());
    put(&mut h, 112, &scale.0.to_le_bytes());
    put(&mut h, 116, &scale.1.to_le_bytes());
    put(&mut h, 344, b"n+1\0");
    h.extend(bytes(t, false));
    h
}

fn write_mha(path: &Path, t: &Ty, big: bool) {
    let msb = if big { "True" } else { "False" };
    let head = format!(
        "ObjectType = Image\nNDims = 3\nDimSize = {} {} {}\nElementType = {}\n\
         ElementByteOrderMSB = {msb}\nElementDataFile = LOCAL\n",
        DIMS[0], DIMS[1], DIMS[2], t.mhd
    );
    let mut f = head.into_bytes();
    f.extend(bytes(t, big));
    std::fs::write(path, f).unwrap();
}

fn check(path: &Path, t: &Ty, want: SampleStorage) {
    let g = read_volume(path).unwrap_or_else(|e| panic!("{e}"));
    let name = path.file_name().unwrap().to_string_lossy();
    assert_eq!(g.values.storage(), want, "{name}");
    assert_eq!(g.values.bytes_per_sample(), want.bytes(), "{name}");
    assert_eq!(g.values.as_bytes().len(), N * want.bytes(), "{name}");
    assert_eq!(g.values.to_f64_vec(), t.values, "{name}");
}

#[test]
fn every_reader_keeps_the_sample_type_and_the_values() {
    let dir = tempfile::tempdir().unwrap();
    for t in types() {
        for big in [false, true] {
            let tag = format!("{}_{}", t.npy, if big { "be" } else { "le" });
            let p = dir.path().join(format!("{tag}.npy"));
            write_npy(&p, &t, big);
            check(&p, &t, t.storage);
            for gzip in [false, true] {
                let p = dir.path().join(format!("{tag}_{gzip}.nrrd"));
                write_nrrd(&p, &t, big, gzip);
                check(&p, &t, t.storage);
            }
            let p = dir.path().join(format!("{tag}.mha"));
            write_mha(&p, &t, big);
            check(&p, &t, t.storage);
        }
        let p = dir.path().join(format!("{}.nii", t.npy));
        std::fs::write(&p, nifti(&t, (0.0, 0.0))).unwrap();
        check(&p, &t, t.storage);
        let p = dir.path().join(format!("{}.nii.gz", t.npy));
        std::fs::write(&p, gz(&nifti(&t, (1.0, 0.0)))).unwrap();
        check(&p, &t, t.storage);
    }
}

#[test]
fn nifti_scaling_is_exact_in_float32_or_float64() {
    let dir = tempfile::tempdir().unwrap();
    let t = &types()[0];
    // 0.5 x + 3: every value is exactly a float32
    let p = dir.path().join("half.nii");
    std::fs::write(&p, nifti(t, (0.5, 3.0))).unwrap();
    let g = read_volume(&p).unwrap();
    assert_eq!(g.values.storage(), SampleStorage::F32);
    let want: Vec<f64> = t.values.iter().map(|x| x * 0.5 + 3.0).collect();
    assert_eq!(g.values.to_f64_vec(), want);
    // 0.1 x (0.1 as a float32, times x, in f64): not float32 values in general
    let p = dir.path().join("tenth.nii");
    std::fs::write(&p, nifti(t, (0.1, 0.0))).unwrap();
    let g = read_volume(&p).unwrap();
    assert_eq!(g.values.storage(), SampleStorage::F64);
    let want: Vec<f64> = t.values.iter().map(|x| x * f64::from(0.1f32)).collect();
    assert_eq!(g.values.to_f64_vec(), want);
}

/// The same values meshed from uint8, int16, uint16, float32 and float64 storage give the
/// same mesh, byte for byte, for every method and both one- and two-sided intervals.
#[test]
fn meshing_does_not_depend_on_the_storage_type() {
    let dims = [14, 13, 12];
    let vals: Vec<u8> = (0..dims[0] * dims[1] * dims[2])
        .map(|n| {
            let p = [n % 14, n / 14 % 13, n / 182].map(|x| x as f64);
            let r = ((p[0] - 6.3).powi(2) + (p[1] - 6.1).powi(2) + (p[2] - 5.7).powi(2)).sqrt();
            let ripple = 20.0 * (p[0] * 1.3).sin() * (p[1] * 0.7).cos();
            (200.0 - 30.0 * r + ripple).clamp(0.0, 255.0) as u8
        })
        .collect();
    let f64s: Vec<f64> = vals.iter().map(|&v| f64::from(v)).collect();
    let grids: Vec<ScalarGrid> = [
        Samples::from(vals.clone()),
        Samples::from(vals.iter().map(|&v| i16::from(v)).collect::<Vec<_>>()),
        Samples::from(vals.iter().map(|&v| u16::from(v)).collect::<Vec<_>>()),
        Samples::from(vals.iter().map(|&v| f32::from(v)).collect::<Vec<_>>()),
        Samples::from(f64s),
    ]
    .into_iter()
    .map(|s| ScalarGrid::new(dims, s).unwrap())
    .collect();
    assert_eq!(
        grids[0].values.as_bytes().len(),
        vals.len(),
        "1 byte per voxel"
    );
    for method in [
        Method::Ctd,
        Method::Tptd,
        Method::Std,
        Method::Six,
        Method::Five,
    ] {
        for (a, b) in [
            (100.5, f64::INFINITY),
            (80.5, 150.0),
            (f64::NEG_INFINITY, 120.0),
        ] {
            let opts = MeshOptions::new(a, b, method);
            let want = mesh_interval(&grids[4], &opts).unwrap();
            assert!(!want.mesh.tets.is_empty());
            for g in &grids[..4] {
                let got = mesh_interval(g, &opts).unwrap();
                let s = g.values.storage();
                assert_eq!(got.mesh, want.mesh, "{s} {method:?} ({a}, {b})");
                assert_eq!(got.stats, want.stats, "{s} {method:?} ({a}, {b})");
            }
        }
    }
}
