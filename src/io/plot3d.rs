//! Plot3D single-block reader: a grid file (`.xyz`) with a solution (`.q`) or function (`.f`)
//! file, as NASA's blunt-fin data set and VTK's `vtkMultiBlockPLOT3DReader` use them.
//!
//! The layout is detected from the file sizes: byte order, Fortran record markers or none,
//! an optional block count of 1, `float` or `double` reals, an optional IBLANK array; the
//! "whole" format (all x, then all y, then all z) and, with record markers, the "planes"
//! format (one record per k plane). The function file must use the grid file's layout. A
//! `.q` file holds the five variables `density`, `momentum_x`, `momentum_y`, `momentum_z`,
//! `energy` (after the four reals Mach, alpha, Re, time); a `.f` file holds `nvars` variables
//! named `f1`, `f2`, …; a function file with another extension (`bluntfinq.bin`) is read as
//! `.q` if it is one, else as `.f`. `field` picks a variable by name or by its 1-based number;
//! default the first.

use std::path::{Path, PathBuf};

use super::read_common::{decode_samples, read_all, Endian, ReadError, SampleType};
use crate::grid::CurvilinearGrid;

/// The names of the variables of a `.q` file.
pub const Q_VARIABLES: [&str; 5] = [
    "density",
    "momentum_x",
    "momentum_y",
    "momentum_z",
    "energy",
];

/// A detected file layout.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Layout {
    endian: Endian,
    records: bool,
    multi: bool,
    real: SampleType,
    iblank: bool,
    planes: bool,
}

/// Reads the `i32` at byte `at`.
fn int_at(b: &[u8], at: usize, endian: Endian) -> Option<i64> {
    let s = b.get(at..at.checked_add(4)?)?;
    Some(decode_samples(s, SampleType::I32, endian)[0] as i64)
}

/// Reads `n` ints of a header record starting at `pos`; returns them and the position after.
fn header_ints(b: &[u8], pos: usize, n: usize, l: &Layout) -> Option<(Vec<i64>, usize)> {
    let mut p = pos;
    if l.records {
        if int_at(b, p, l.endian)? != 4 * n as i64 {
            return None;
        }
        p += 4;
    }
    let v: Option<Vec<i64>> = (0..n).map(|i| int_at(b, p + 4 * i, l.endian)).collect();
    p += 4 * n;
    if l.records {
        if int_at(b, p, l.endian)? != 4 * n as i64 {
            return None;
        }
        p += 4;
    }
    Some((v?, p))
}

/// Block count (must be 1 with `multi`) and `n` dimension ints; the position after.
fn dims_header(b: &[u8], n: usize, l: &Layout) -> Option<(Vec<usize>, usize)> {
    let mut pos = 0;
    if l.multi {
        let (nb, p) = header_ints(b, 0, 1, l)?;
        if nb[0] != 1 {
            return None;
        }
        pos = p;
    }
    let (d, p) = header_ints(b, pos, n, l)?;
    let d: Option<Vec<usize>> = d
        .iter()
        .map(|&x| usize::try_from(x).ok().filter(|v| (1..1 << 24).contains(v)))
        .collect();
    Some((d?, p))
}

/// Byte size of `nvars` arrays of `n` reals (+ IBLANK) in `nk` planes or whole.
fn data_size(l: &Layout, dims: &[usize], nvars: usize, extra_ints: bool) -> Option<usize> {
    let n = dims[0].checked_mul(dims[1])?.checked_mul(dims[2])?;
    let blank = if extra_ints { 4 } else { 0 };
    let per = nvars * l.real.size() + blank;
    let markers = if !l.records {
        0
    } else if l.planes {
        8 * dims[2]
    } else {
        8
    };
    n.checked_mul(per)?.checked_add(markers)
}

/// Every layout under which `bytes` is a grid file; the dims and the data offset of each.
fn grid_layouts(b: &[u8]) -> Vec<(Layout, Vec<usize>, usize)> {
    let mut out = Vec::new();
    for endian in [Endian::Big, Endian::Little] {
        for records in [false, true] {
            for multi in [false, true] {
                for real in [SampleType::F32, SampleType::F64] {
                    for iblank in [false, true] {
                        for planes in [false, true] {
                            let l = Layout {
                                endian,
                                records,
                                multi,
                                real,
                                iblank,
                                planes,
                            };
                            if planes && !records {
                                continue;
                            }
                            let Some((d, pos)) = dims_header(b, 3, &l) else {
                                continue;
                            };
                            if planes && !first_record_is_a_plane(b, pos, &l, &d, 3) {
                                continue;
                            }
                            if data_size(&l, &d, 3, iblank) == Some(b.len() - pos) {
                                out.push((l, d, pos));
                            }
                        }
                    }
                }
            }
        }
    }
    out
}

fn first_record_is_a_plane(b: &[u8], pos: usize, l: &Layout, d: &[usize], nvars: usize) -> bool {
    let blank = if l.iblank && nvars == 3 { 4 } else { 0 };
    let plane = (d[0] * d[1] * (nvars * l.real.size() + blank)) as i64;
    d[2] > 1 && int_at(b, pos, l.endian) == Some(plane)
}

/// `nvars` arrays of `n` reals from `b[pos..]` (whole or planes), as `f64`, variable-major.
fn arrays(b: &[u8], pos: usize, l: &Layout, dims: &[usize], nvars: usize, blank: bool) -> Vec<f64> {
    let plane = dims[0] * dims[1];
    let n = plane * dims[2];
    let rs = l.real.size();
    let mut out = vec![0.0; nvars * n];
    let blank_bytes = if blank { 4 } else { 0 };
    let (chunks, per_chunk) = if l.planes { (dims[2], plane) } else { (1, n) };
    let mut p = pos;
    for c in 0..chunks {
        if l.records {
            p += 4;
        }
        for v in 0..nvars {
            let bytes = &b[p..p + per_chunk * rs];
            let vals = decode_samples(bytes, l.real, l.endian);
            out[v * n + c * per_chunk..v * n + (c + 1) * per_chunk].copy_from_slice(&vals);
            p += per_chunk * rs;
        }
        p += per_chunk * blank_bytes;
        if l.records {
            p += 4;
        }
    }
    out
}

/// Reads a Plot3D grid file and its function file (`function`: default the grid file's
/// path with extension `.q`, else `.f`).
///
/// # Errors
/// [`ReadError`] naming the file when a size matches no layout, the files disagree, the
/// field does not exist (the message lists the names) or the grid is invalid.
pub fn read_plot3d(
    xyz: &Path,
    function: Option<&Path>,
    field: Option<&str>,
) -> Result<CurvilinearGrid, ReadError> {
    let gb = read_all(xyz)?;
    let (l, dims, pos) = grid_layouts(&gb).into_iter().next().ok_or_else(|| {
        ReadError::invalid(
            xyz,
            "not a single-block 3-D Plot3D grid file (no layout matches its size)",
        )
    })?;
    let xyzv = arrays(&gb, pos, &l, &dims, 3, l.iblank);
    let n = dims[0] * dims[1] * dims[2];
    let fpath = function_file(xyz, function)?;
    let ext = fpath
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    let fb = read_all(&fpath)?;
    // `.q` and `.f` by extension; any other name: a solution file if it reads as one
    let (names, vals) = match ext.as_deref() {
        Some("q") => read_q(&fpath, &fb, &l, &dims)?,
        Some("f") => read_f(&fpath, &fb, &l, &dims)?,
        _ => read_q(&fpath, &fb, &l, &dims).or_else(|_| read_f(&fpath, &fb, &l, &dims))?,
    };
    let k = pick(&fpath, &names, field)?;
    let values = vals[k * n..(k + 1) * n].to_vec();
    let points = (0..n)
        .map(|i| [xyzv[i], xyzv[n + i], xyzv[2 * n + i]])
        .collect();
    let dims = [dims[0], dims[1], dims[2]];
    CurvilinearGrid::new(dims, values, points).map_err(|source| ReadError::Grid {
        file: xyz.display().to_string(),
        source,
    })
}

/// The function file [`read_plot3d`] reads with the grid file `xyz`: `function` if given,
/// else the grid file's path with extension `.q`, else `.f` (the first that exists).
///
/// # Errors
/// [`ReadError::Invalid`] naming `xyz` when neither exists.
pub(crate) fn function_file(xyz: &Path, function: Option<&Path>) -> Result<PathBuf, ReadError> {
    match function {
        Some(f) => Ok(f.to_path_buf()),
        None => ["q", "f"]
            .iter()
            .map(|e| xyz.with_extension(e))
            .find(|p| p.exists())
            .ok_or_else(|| {
                ReadError::invalid(xyz, "no function file (.q or .f) next to it; name one")
            }),
    }
}

fn mismatch(path: &Path, what: &str) -> ReadError {
    ReadError::invalid(
        path,
        format!("{what} does not match the grid file's layout and dimensions"),
    )
}

fn read_q(
    path: &Path,
    b: &[u8],
    l: &Layout,
    dims: &[usize],
) -> Result<(Vec<String>, Vec<f64>), ReadError> {
    let (d, pos) = dims_header(b, 3, l).ok_or_else(|| mismatch(path, "header"))?;
    if d != dims {
        return Err(mismatch(path, "dimensions"));
    }
    // Mach, alpha, Re, time
    let consts = 4 * l.real.size() + if l.records { 8 } else { 0 };
    let pos = pos + consts;
    let ql = Layout {
        iblank: false,
        ..*l
    };
    if data_size(&ql, dims, 5, false) != Some(b.len().saturating_sub(pos)) {
        return Err(mismatch(path, "size"));
    }
    let names = Q_VARIABLES.iter().map(|s| s.to_string()).collect();
    Ok((names, arrays(b, pos, &ql, dims, 5, false)))
}

fn read_f(
    path: &Path,
    b: &[u8],
    l: &Layout,
    dims: &[usize],
) -> Result<(Vec<String>, Vec<f64>), ReadError> {
    let (d, pos) = dims_header(b, 4, l).ok_or_else(|| mismatch(path, "header"))?;
    if d[..3] != *dims {
        return Err(mismatch(path, "dimensions"));
    }
    let nvars = d[3];
    let fl = Layout {
        iblank: false,
        ..*l
    };
    if data_size(&fl, dims, nvars, false) != Some(b.len().saturating_sub(pos)) {
        return Err(mismatch(path, "size"));
    }
    let names = (1..=nvars).map(|i| format!("f{i}")).collect();
    Ok((names, arrays(b, pos, &fl, dims, nvars, false)))
}

/// The index of `field` (a name or a 1-based number) among `names`; default 0.
fn pick(path: &Path, names: &[String], field: Option<&str>) -> Result<usize, ReadError> {
    let Some(f) = field else { return Ok(0) };
    if let Some(i) = names.iter().position(|n| n == f) {
        return Ok(i);
    }
    match f.parse::<usize>() {
        Ok(i) if (1..=names.len()).contains(&i) => Ok(i - 1),
        _ => Err(ReadError::invalid(
            path,
            format!(
                "no variable {f:?}; the file has: {} (or 1..{})",
                names.join(", "),
                names.len()
            ),
        )),
    }
}
