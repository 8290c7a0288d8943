//! Small file helpers: directory listings and hand-written `.npy` files.

use std::fs;
use std::path::Path;

/// Names of the entries of `dir`, sorted.
pub fn listing(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// The bytes of a `.npy` file (format 1.0) with the header fields `descr` and `shape` (a
/// Python tuple, as text), not Fortran-ordered, followed by `data`.
pub fn npy_bytes(descr: &str, shape: &str, data: &[u8]) -> Vec<u8> {
    let mut dict = format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}");
    // magic (6) + version (2) + length (2) + header + '\n' must be a multiple of 64.
    while (10 + dict.len() + 1) % 64 != 0 {
        dict.push(' ');
    }
    dict.push('\n');
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    out.extend_from_slice(&(dict.len() as u16).to_le_bytes());
    out.extend_from_slice(dict.as_bytes());
    out.extend_from_slice(data);
    out
}

/// Writes a C-order `<f8` `.npy` of shape `(nx, ny, nz)`; element `[i, j, k]` (grid vertex
/// x = i, y = j, z = k, as tptd reads it) is `f(i, j, k)`.
pub fn write_npy(path: &Path, dims: [usize; 3], f: impl Fn(usize, usize, usize) -> f64) {
    let [nx, ny, nz] = dims;
    let mut data = Vec::with_capacity(nx * ny * nz * 8);
    for i in 0..nx {
        for j in 0..ny {
            for k in 0..nz {
                data.extend_from_slice(&f(i, j, k).to_le_bytes());
            }
        }
    }
    let shape = format!("({nx}, {ny}, {nz})");
    fs::write(path, npy_bytes("<f8", &shape, &data)).unwrap();
}
