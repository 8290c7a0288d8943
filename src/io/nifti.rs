//! NIfTI-1 and NIfTI-2 reader (single-file `.nii`, or gzip-compressed `.nii.gz`).
//!
//! The byte order is detected from `sizeof_hdr` (348 for NIfTI-1, 540 for NIfTI-2).
//! Supported datatypes: uint8, int8, int16, uint16, int32, uint32, int64, uint64, float32,
//! float64. Values are scaled by `scl_slope`/`scl_inter` when the slope is finite and
//! non-zero. Only 3-D images are read (`dim[0] == 3`, or more with every extra dimension 1).
//!
//! Geometry follows the NIfTI specification (world coordinates are NIfTI's RAS+ space):
//! the sform affine when `sform_code > 0` (spacing = column norms, direction = normalised
//! columns, origin = translation), else the qform quaternion when `qform_code > 0` (with
//! `qfac` from the sign of `pixdim[0]`), else "method 1": spacing `pixdim[1..=3]`, zero
//! origin, identity direction. As in `nifti1_io`, zero or non-finite `pixdim` entries read
//! as 1.

use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::Path;

use flate2::read::MultiGzDecoder;
use nalgebra::Matrix3;

use super::read_common::{
    build_grid, data_size, decompress_into, split_linear, to_dim, Endian, Geometry, ReadError,
    SampleBuf, SampleType,
};
use crate::algebra::rows;
use crate::grid::{Samples, ScalarGrid, IDENTITY};

const NIFTI1_HDR: usize = 348;
const NIFTI2_HDR: usize = 540;

/// Reads a NIfTI-1 or NIfTI-2 volume from a `.nii` or `.nii.gz` file (gzip is detected from
/// the content, not the name).
///
/// # Errors
/// [`ReadError::Io`] if the file cannot be read; [`ReadError::Invalid`] for a bad
/// `sizeof_hdr` or magic, inconsistent `dim`, `vox_offset` or scaling, truncated data or a
/// corrupt gzip stream; [`ReadError::Unsupported`] for a separate `.img` file (`ni1`/`ni2`),
/// other datatypes or images that are not 3-D; [`ReadError::Grid`] for a dimension below 2,
/// a non-finite value or a degenerate affine.
pub fn read_nifti(path: &Path) -> Result<ScalarGrid, ReadError> {
    let cannot = |e| ReadError::io(path, "cannot read file", e);
    let mut file = File::open(path).map_err(cannot)?;
    let size = file.metadata().map_err(cannot)?.len();
    let head = read_head(&mut file).map_err(cannot)?;
    let gz = head.starts_with(&[0x1f, 0x8b]);
    if !gz {
        let h = parse_header(path, &head)?;
        let (count, nbytes) = data_size(path, h.dims, h.ty)?;
        h.vox_offset
            .checked_add(nbytes)
            .ok_or_else(|| ReadError::invalid(path, "vox_offset + data size overflows"))?;
        let body = size.saturating_sub(h.vox_offset as u64);
        if body < nbytes as u64 {
            return Err(ReadError::invalid(
                path,
                format!(
                    "header says {nbytes} bytes of data but the file (after vox_offset {}) holds {body}",
                    h.vox_offset
                ),
            ));
        }
        let mut buf = SampleBuf::new(path, h.ty, count)?;
        file.seek(SeekFrom::Start(h.vox_offset as u64))
            .and_then(|_| file.read_exact(buf.bytes_mut()))
            .map_err(cannot)?;
        return finish(path, h, buf);
    }
    file.seek(SeekFrom::Start(0)).map_err(cannot)?;
    let mut gz = MultiGzDecoder::new(BufReader::new(file));
    let head = read_head(&mut gz)
        .map_err(|e| ReadError::invalid(path, format!("gzip stream is corrupt: {e}")))?;
    let h = parse_header(path, &head)?;
    let (count, nbytes) = data_size(path, h.dims, h.ty)?;
    h.vox_offset
        .checked_add(nbytes)
        .ok_or_else(|| ReadError::invalid(path, "vox_offset + data size overflows"))?;
    let mut buf = SampleBuf::new(path, h.ty, count)?;
    let stream = head.as_slice().chain(gz);
    decompress_into(
        path,
        stream,
        h.vox_offset,
        buf.bytes_mut(),
        false,
        "the gzip stream",
    )?;
    finish(path, h, buf)
}

/// The first bytes of a stream, enough for the largest header (NIfTI-2's 540 bytes + 4).
fn read_head(r: &mut impl Read) -> std::io::Result<Vec<u8>> {
    let mut head = Vec::new();
    r.take((NIFTI2_HDR + 4) as u64).read_to_end(&mut head)?;
    Ok(head)
}

/// The grid from the samples read: scaled by `scl_slope`/`scl_inter` unless they are the
/// identity ([`scaled`]).
fn finish(path: &Path, h: Header, buf: SampleBuf) -> Result<ScalarGrid, ReadError> {
    let mut values = buf.finish(h.endian);
    if let Some((slope, inter)) = h.scale {
        values = scaled(values, slope, inter);
    }
    build_grid(path, h.dims, h.spacing, h.origin, h.direction, values)
}

/// `x * slope + inter` for every sample, computed in `f64` as before scaling was typed:
/// the identity keeps the samples (and their type); otherwise the values are held as
/// `float32` when every one is exactly a `float32`, else as `float64`.
fn scaled(raw: Samples, slope: f64, inter: f64) -> Samples {
    use rayon::prelude::*;
    const BLOCK: usize = 1 << 14;
    if slope == 1.0 && inter == 0.0 {
        return raw;
    }
    let f = |x: f64| x * slope + inter;
    if raw.par_any(|x| f64::from(f(x) as f32) != f(x)) {
        let mut out = raw.to_f64_vec();
        drop(raw);
        out.par_iter_mut().for_each(|v| *v = f(*v));
        return Samples::from(out);
    }
    let mut out = vec![0f32; raw.len()];
    out.par_chunks_mut(BLOCK).enumerate().for_each(|(c, o)| {
        let mut tmp = [0.0; BLOCK];
        let tmp = &mut tmp[..o.len()];
        raw.read_into(c * BLOCK, tmp);
        for (y, &x) in o.iter_mut().zip(tmp.iter()) {
            *y = f(x) as f32;
        }
    });
    Samples::from(out)
}

#[derive(Debug)]
struct Header {
    endian: Endian,
    ty: SampleType,
    dims: [usize; 3],
    vox_offset: usize,
    scale: Option<(f64, f64)>,
    spacing: [f64; 3],
    origin: [f64; 3],
    direction: [[f64; 3]; 3],
}

/// Field reader for a header of known byte order. Offsets are always within the header
/// (checked by the caller), so reads cannot fail.
struct Fields<'a> {
    b: &'a [u8],
    endian: Endian,
}

impl Fields<'_> {
    fn bytes<const N: usize>(&self, off: usize) -> [u8; N] {
        let mut a = [0u8; N];
        a.copy_from_slice(&self.b[off..off + N]);
        if self.endian == Endian::Big {
            a.reverse();
        }
        a
    }
    fn i16(&self, off: usize) -> i64 {
        i64::from(i16::from_le_bytes(self.bytes(off)))
    }
    fn i32(&self, off: usize) -> i64 {
        i64::from(i32::from_le_bytes(self.bytes(off)))
    }
    fn i64(&self, off: usize) -> i64 {
        i64::from_le_bytes(self.bytes(off))
    }
    fn f32(&self, off: usize) -> f64 {
        f64::from(f32::from_le_bytes(self.bytes(off)))
    }
    fn f64(&self, off: usize) -> f64 {
        f64::from_le_bytes(self.bytes(off))
    }
}

/// Offsets of the fields a reader needs, per NIfTI version.
struct Layout {
    version: u8,
    hdr_size: usize,
    magic: (usize, &'static [u8], &'static [u8]),
    dim: usize,
    datatype: usize,
    pixdim: usize,
    vox_offset: usize,
    scl_slope: usize,
    scl_inter: usize,
    qform_code: usize,
    sform_code: usize,
    quatern_b: usize,
    srow_x: usize,
}

const V1: Layout = Layout {
    version: 1,
    hdr_size: NIFTI1_HDR,
    magic: (344, b"n+1\0", b"ni1\0"),
    dim: 40,
    datatype: 70,
    pixdim: 76,
    vox_offset: 108,
    scl_slope: 112,
    scl_inter: 116,
    qform_code: 252,
    sform_code: 254,
    quatern_b: 256,
    srow_x: 280,
};

const V2: Layout = Layout {
    version: 2,
    hdr_size: NIFTI2_HDR,
    magic: (4, b"n+2\0", b"ni2\0"),
    dim: 16,
    datatype: 12,
    pixdim: 104,
    vox_offset: 168,
    scl_slope: 176,
    scl_inter: 184,
    qform_code: 344,
    sform_code: 348,
    quatern_b: 352,
    srow_x: 400,
};

impl Layout {
    /// A v1 int16 / v2 int32 field (`qform_code`, `sform_code`).
    fn code(&self, f: &Fields, off: usize) -> i64 {
        if self.version == 1 {
            f.i16(off)
        } else {
            f.i32(off)
        }
    }
    /// A v1 float32 / v2 float64 field.
    fn float(&self, f: &Fields, off: usize) -> f64 {
        if self.version == 1 {
            f.f32(off)
        } else {
            f.f64(off)
        }
    }
    fn float_at(&self, f: &Fields, base: usize, i: usize) -> f64 {
        let w = if self.version == 1 { 4 } else { 8 };
        self.float(f, base + w * i)
    }
    fn dim(&self, f: &Fields, i: usize) -> i64 {
        if self.version == 1 {
            f.i16(self.dim + 2 * i)
        } else {
            f.i64(self.dim + 8 * i)
        }
    }
}

fn datatype(code: i64) -> Option<SampleType> {
    Some(match code {
        2 => SampleType::U8,
        4 => SampleType::I16,
        8 => SampleType::I32,
        16 => SampleType::F32,
        64 => SampleType::F64,
        256 => SampleType::I8,
        512 => SampleType::U16,
        768 => SampleType::U32,
        1024 => SampleType::I64,
        1280 => SampleType::U64,
        _ => return None,
    })
}

/// Parses the header at the start of `head`, one concern at a time: version and byte order,
/// magic, dimensions, datatype, data offset, scaling and geometry.
fn parse_header(path: &Path, head: &[u8]) -> Result<Header, ReadError> {
    let (layout, endian) = detect(path, head)?;
    check_magic(path, head, layout)?;
    let f = Fields { b: head, endian };
    let dims = dims(path, layout, &f)?;
    let ty = sample_type(path, layout, &f)?;
    let vox_offset = vox_offset(path, layout, &f)?;
    let scale = scaling(path, layout, &f)?;
    let (spacing, origin, direction) = geometry(path, layout, &f)?;
    Ok(Header {
        endian,
        ty,
        dims,
        vox_offset,
        scale,
        spacing,
        origin,
        direction,
    })
}

/// The NIfTI version and byte order, from `sizeof_hdr`; checks the whole header is present.
fn detect(path: &Path, head: &[u8]) -> Result<(&'static Layout, Endian), ReadError> {
    let Some(first) = head.get(..4) else {
        return Err(ReadError::invalid(
            path,
            format!(
                "file holds {} bytes, too short for a NIfTI header",
                head.len()
            ),
        ));
    };
    let first = [first[0], first[1], first[2], first[3]];
    let (layout, endian) = match (i32::from_le_bytes(first), i32::from_be_bytes(first)) {
        (348, _) => (&V1, Endian::Little),
        (540, _) => (&V2, Endian::Little),
        (_, 348) => (&V1, Endian::Big),
        (_, 540) => (&V2, Endian::Big),
        (n, _) => {
            return Err(ReadError::invalid(
                path,
                format!("not a NIfTI file (sizeof_hdr is {n}, expected 348 or 540)"),
            ))
        }
    };
    if head.len() < layout.hdr_size {
        return Err(ReadError::invalid(
            path,
            format!(
                "file ends inside the NIfTI-{} header ({} of {} bytes)",
                layout.version,
                head.len(),
                layout.hdr_size
            ),
        ));
    }
    Ok((layout, endian))
}

/// Checks the magic: single-file `n+1`/`n+2`; the `ni1`/`ni2` pair form is unsupported.
fn check_magic(path: &Path, head: &[u8], layout: &Layout) -> Result<(), ReadError> {
    let (moff, single, pair) = layout.magic;
    let magic = &head[moff..moff + 4];
    if magic == pair {
        return Err(ReadError::unsupported(
            path,
            "header/image pair (.hdr/.img); only single-file .nii is read",
        ));
    }
    if magic != single {
        return Err(ReadError::invalid(
            path,
            format!(
                "bad NIfTI-{} magic {:?}",
                layout.version,
                String::from_utf8_lossy(magic)
            ),
        ));
    }
    Ok(())
}

/// The three sizes from `dim` (3-D, or more with every extra dimension 1).
fn dims(path: &Path, layout: &Layout, f: &Fields) -> Result<[usize; 3], ReadError> {
    let ndim = layout.dim(f, 0);
    if !(1..=7).contains(&ndim) {
        return Err(ReadError::invalid(
            path,
            format!("dim[0] is {ndim}, must be 1 to 7"),
        ));
    }
    let dim_list: Vec<i64> = (1..=ndim as usize).map(|i| layout.dim(f, i)).collect();
    if ndim < 3 || dim_list[3..].iter().any(|&d| d != 1) {
        return Err(ReadError::unsupported(
            path,
            format!("image of dimensions {dim_list:?}; only 3-D volumes are read"),
        ));
    }
    Ok([
        to_dim(path, dim_list[0], "dim[1]")?,
        to_dim(path, dim_list[1], "dim[2]")?,
        to_dim(path, dim_list[2], "dim[3]")?,
    ])
}

/// The sample type from `datatype`.
fn sample_type(path: &Path, layout: &Layout, f: &Fields) -> Result<SampleType, ReadError> {
    let code = f.i16(layout.datatype); // int16 in both versions
    datatype(code).ok_or_else(|| {
        ReadError::unsupported(
            path,
            format!(
                "NIfTI datatype {code} (supported: uint8, int8, (u)int16/32/64, float32, float64)"
            ),
        )
    })
}

/// The byte offset of the data from `vox_offset`.
fn vox_offset(path: &Path, layout: &Layout, f: &Fields) -> Result<usize, ReadError> {
    let vox = if layout.version == 1 {
        f.f32(layout.vox_offset)
    } else {
        f.i64(layout.vox_offset) as f64
    };
    if !vox.is_finite() || vox < 0.0 || vox.fract() != 0.0 || vox > 1e15 {
        return Err(ReadError::invalid(
            path,
            format!("vox_offset {vox} is not a valid byte offset"),
        ));
    }
    // 0 (or anything inside the header) is taken as "right after the header + extension flag"
    Ok((vox as usize).max(layout.hdr_size + 4))
}

/// `(scl_slope, scl_inter)` if the slope is finite and non-zero.
fn scaling(path: &Path, layout: &Layout, f: &Fields) -> Result<Option<(f64, f64)>, ReadError> {
    let slope = layout.float(f, layout.scl_slope);
    let inter = layout.float(f, layout.scl_inter);
    if !(slope.is_finite() && slope != 0.0) {
        return Ok(None);
    }
    if !inter.is_finite() {
        return Err(ReadError::invalid(
            path,
            format!("scl_slope is {slope} but scl_inter is {inter}"),
        ));
    }
    Ok(Some((slope, inter)))
}

/// Spacing, origin and direction: from the sform if `sform_code > 0`, else from the qform if
/// `qform_code > 0`, else from `pixdim` alone.
fn geometry(path: &Path, layout: &Layout, f: &Fields) -> Result<Geometry, ReadError> {
    let mut pixdim = [0.0; 4];
    for (i, p) in pixdim.iter_mut().enumerate() {
        *p = layout.float_at(f, layout.pixdim, i);
    }
    if layout.code(f, layout.sform_code) > 0 {
        sform_geometry(path, layout, f)
    } else if layout.code(f, layout.qform_code) > 0 {
        Ok(qform_geometry(layout, f, pixdim))
    } else {
        Ok(pixdim_geometry(pixdim))
    }
}

/// Geometry from the sform rows `srow_x`, `srow_y`, `srow_z`.
fn sform_geometry(path: &Path, layout: &Layout, f: &Fields) -> Result<Geometry, ReadError> {
    let row = |r: usize| layout.srow_x + r * 4 * if layout.version == 1 { 4 } else { 8 };
    let m = Matrix3::from_fn(|r, c| layout.float_at(f, row(r), c));
    let t = [0, 1, 2].map(|r| layout.float_at(f, row(r), 3));
    let (s, d) = split_linear(&m).ok_or_else(|| {
        ReadError::invalid(
            path,
            format!("sform {:?} has a zero or non-finite column", rows(&m)),
        )
    })?;
    Ok((s, t, d))
}

/// Geometry from the qform quaternion and offsets, `qfac` from the sign of `pixdim[0]`.
fn qform_geometry(layout: &Layout, f: &Fields, pixdim: [f64; 4]) -> Geometry {
    let q = [0, 1, 2].map(|i| layout.float_at(f, layout.quatern_b, i));
    let offset = [3, 4, 5].map(|i| layout.float_at(f, layout.quatern_b, i));
    let qfac = if pixdim[0] < 0.0 { -1.0 } else { 1.0 };
    let mut d = quaternion_matrix(q[0], q[1], q[2]);
    for row in &mut d {
        row[2] *= qfac;
    }
    // nifti1_io: non-positive pixdim reads as 1 for the qform
    let s = [1, 2, 3].map(|i| {
        if pixdim[i] > 0.0 && pixdim[i].is_finite() {
            pixdim[i]
        } else {
            1.0
        }
    });
    (s, offset, d)
}

/// "Method 1" geometry: spacing `|pixdim[1..=3]|` (zero or non-finite reads as 1), axis
/// signs from `pixdim`, zero origin.
fn pixdim_geometry(pixdim: [f64; 4]) -> Geometry {
    let step = |p: f64| if p.is_finite() && p != 0.0 { p } else { 1.0 };
    let mut d = IDENTITY;
    let mut s = [0.0; 3];
    for i in 0..3 {
        let p = step(pixdim[i + 1]);
        s[i] = p.abs();
        d[i][i] = p.signum();
    }
    (s, [0.0; 3], d)
}

/// Rotation matrix of the unit quaternion `(a, b, c, d)` with `a` derived from `b, c, d`
/// as in `nifti1_io`'s `quatern_to_mat44`.
fn quaternion_matrix(b: f64, c: f64, d: f64) -> [[f64; 3]; 3] {
    let (mut a, mut b, mut c, mut d) = (1.0 - (b * b + c * c + d * d), b, c, d);
    if a < 1e-7 {
        let n = 1.0 / (b * b + c * c + d * d).sqrt();
        b *= n;
        c *= n;
        d *= n;
        a = 0.0;
    } else {
        a = a.sqrt();
    }
    [
        [
            a * a + b * b - c * c - d * d,
            2.0 * (b * c - a * d),
            2.0 * (b * d + a * c),
        ],
        [
            2.0 * (b * c + a * d),
            a * a + c * c - b * b - d * d,
            2.0 * (c * d - a * b),
        ],
        [
            2.0 * (b * d - a * c),
            2.0 * (c * d + a * b),
            a * a + d * d - c * c - b * b,
        ],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quaternion_identity_and_half_turn() {
        assert_eq!(quaternion_matrix(0.0, 0.0, 0.0), IDENTITY);
        // 180 degrees about z: b = c = 0, d = 1
        let m = quaternion_matrix(0.0, 0.0, 1.0);
        assert_eq!(m, [[-1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]]);
    }

    #[test]
    fn datatype_table() {
        assert_eq!(datatype(4), Some(SampleType::I16));
        assert_eq!(datatype(512), Some(SampleType::U16));
        assert_eq!(datatype(32), None); // complex64
        assert_eq!(datatype(128), None); // rgb24
    }

    #[test]
    fn short_and_foreign_headers_are_errors() {
        let p = Path::new("x.nii");
        assert!(parse_header(p, &[]).is_err());
        assert!(parse_header(p, &[1, 2, 3, 4, 5]).is_err());
        let mut h = vec![0u8; 400];
        h[..4].copy_from_slice(&348i32.to_le_bytes());
        let e = parse_header(p, &h).unwrap_err().to_string();
        assert!(e.contains("magic"), "{e}");
    }
}
