//! What every volume reader shares: the [`ReadError`] every reader returns, sample types and
//! byte order, decoding into the grid's storage ([`SampleBuf`], [`checked_decode`]), bounded
//! file and stream reads, and the geometry helpers that build the [`ScalarGrid`].
//!
//! Readers never trust a header: sizes are computed with checked arithmetic, the amount of
//! data actually present is checked before anything proportional to the header's claim is
//! allocated, and decompression stops one byte after the expected length.

use std::fmt::Write as _;
use std::fs::File;
use std::io::{Read, Seek, SeekFrom};
use std::path::Path;

use nalgebra::Matrix3;

use super::formats::supported_extensions;
use crate::algebra::rows;
use crate::grid::{GridError, SampleStorage, Samples, ScalarGrid};

/// Why a volume file could not be read.
///
/// Every variant's `Display` is a single line that starts with the file's path.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    /// The file (or a data file it refers to) could not be opened or read.
    #[error("{file}: {what}: {source}")]
    Io {
        /// The file being read (for detached data: the header).
        file: String,
        /// What was being done, e.g. `cannot open data file vol.raw`.
        what: String,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// The content is malformed, truncated or inconsistent.
    #[error("{file}: {message}")]
    Invalid {
        /// The file being read.
        file: String,
        /// What is wrong.
        message: String,
    },
    /// The file is well formed but uses a feature these readers do not support.
    #[error("{file}: unsupported: {message}")]
    Unsupported {
        /// The file being read.
        file: String,
        /// The unsupported feature.
        message: String,
    },
    /// The decoded samples and geometry do not form a valid [`ScalarGrid`]
    /// (too small, non-finite value, degenerate spacing or direction).
    #[error("{file}: {source}")]
    Grid {
        /// The file being read.
        file: String,
        /// The grid validation error.
        #[source]
        source: GridError,
    },
    /// Holding the samples would exceed the memory limit (or the memory available).
    #[error("{file}: {message}")]
    Memory {
        /// The file being read.
        file: String,
        /// What would not fit, and what helps.
        message: String,
    },
    /// The file extension is not one of the supported volume formats.
    #[error(
        "{file}: unknown volume format; supported extensions are {}",
        supported_extensions()
    )]
    UnknownFormat {
        /// The file being read.
        file: String,
    },
}

/// Replaces control characters (newlines included) by their escapes so a message stays on
/// one line, and shortens very long text.
fn one_line(s: &str) -> String {
    const MAX: usize = 300;
    let mut out = String::with_capacity(s.len().min(MAX + 3));
    for (n, c) in s.chars().enumerate() {
        if n >= MAX {
            out.push_str("...");
            break;
        }
        if c.is_control() {
            let _ = write!(out, "{}", c.escape_default());
        } else {
            out.push(c);
        }
    }
    out
}

/// Quotes a piece of file content for an error message (escaped, at most 40 characters).
pub(crate) fn quote(s: &str) -> String {
    let mut q: String = s.chars().take(40).collect();
    if q.len() < s.len() {
        q.push_str("...");
    }
    format!("{q:?}")
}

fn file_name(path: &Path) -> String {
    one_line(&path.display().to_string())
}

impl ReadError {
    /// An error of `path` whose samples would not fit in memory.
    pub(crate) fn memory(path: &Path, message: impl AsRef<str>) -> Self {
        ReadError::Memory {
            file: file_name(path),
            message: one_line(message.as_ref()),
        }
    }

    /// A malformed-content error for `path`.
    pub(crate) fn invalid(path: &Path, message: impl AsRef<str>) -> Self {
        ReadError::Invalid {
            file: file_name(path),
            message: one_line(message.as_ref()),
        }
    }

    /// An unsupported-feature error for `path`.
    pub(crate) fn unsupported(path: &Path, message: impl AsRef<str>) -> Self {
        ReadError::Unsupported {
            file: file_name(path),
            message: one_line(message.as_ref()),
        }
    }

    /// An unknown-format error for `path`.
    pub(crate) fn unknown_format(path: &Path) -> Self {
        ReadError::UnknownFormat {
            file: file_name(path),
        }
    }

    /// An I/O error for `path`.
    pub(crate) fn io(path: &Path, what: impl AsRef<str>, source: std::io::Error) -> Self {
        ReadError::Io {
            file: file_name(path),
            what: one_line(what.as_ref()),
            source,
        }
    }

    /// The file the error is about, as shown in the message.
    pub fn file(&self) -> &str {
        match self {
            ReadError::Io { file, .. }
            | ReadError::Invalid { file, .. }
            | ReadError::Memory { file, .. }
            | ReadError::Unsupported { file, .. }
            | ReadError::Grid { file, .. }
            | ReadError::UnknownFormat { file } => file,
        }
    }
}

/// Sample type of a stored volume.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum SampleType {
    U8,
    I8,
    U16,
    I16,
    U32,
    I32,
    U64,
    I64,
    F32,
    F64,
}

impl SampleType {
    /// Size of one sample in bytes.
    pub(crate) fn size(self) -> usize {
        match self {
            SampleType::U8 | SampleType::I8 => 1,
            SampleType::U16 | SampleType::I16 => 2,
            SampleType::U32 | SampleType::I32 | SampleType::F32 => 4,
            SampleType::U64 | SampleType::I64 | SampleType::F64 => 8,
        }
    }
}

/// Byte order of stored samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Endian {
    Little,
    Big,
}

impl Endian {
    /// The byte order of the machine running this code.
    pub(crate) fn native() -> Self {
        if cfg!(target_endian = "big") {
            Endian::Big
        } else {
            Endian::Little
        }
    }
}

fn array<const N: usize>(c: &[u8], endian: Endian) -> [u8; N] {
    let mut a = [0u8; N];
    a.copy_from_slice(&c[..N]);
    if endian == Endian::Big {
        a.reverse();
    }
    a
}

/// Decodes `bytes` (a whole number of samples; any trailing partial sample is ignored) into
/// `f64` values. 64-bit integers beyond 2^53 are rounded.
pub(crate) fn decode_samples(bytes: &[u8], ty: SampleType, endian: Endian) -> Vec<f64> {
    use rayon::prelude::*;
    const BLOCK: usize = 1 << 16;
    let size = ty.size();
    let mut out = vec![0.0; bytes.len() / size];
    out.par_chunks_mut(BLOCK)
        .zip(bytes.par_chunks(BLOCK * size))
        .for_each(|(o, b)| decode_into(b, ty, endian, o));
    out
}

/// The storage type that holds samples of file type `ty` exactly (see [`Samples`]): the same
/// type for u8, i16, u16, f32, f64; `i16` for i8; `f64` for 32- and 64-bit integers.
pub(crate) fn storage_of(ty: SampleType) -> SampleStorage {
    match ty {
        SampleType::U8 => SampleStorage::U8,
        SampleType::I8 | SampleType::I16 => SampleStorage::I16,
        SampleType::U16 => SampleStorage::U16,
        SampleType::F32 => SampleStorage::F32,
        SampleType::F64 | SampleType::U32 | SampleType::I32 | SampleType::U64 | SampleType::I64 => {
            SampleStorage::F64
        }
    }
}

/// Samples being read: storage of the final type whose first `count * ty.size()` bytes
/// receive the file's bytes ([`SampleBuf::bytes_mut`]), then are put in native byte order and
/// widened in place ([`SampleBuf::finish`]). The file's bytes are never held beside a decoded
/// copy.
pub(crate) struct SampleBuf {
    samples: Samples,
    ty: SampleType,
    count: usize,
}

impl SampleBuf {
    /// Room for `count` samples of file type `ty`, after checking the memory estimate
    /// ([`crate::memory::read_bytes`]): a volume that cannot fit is an error naming `path`.
    pub(crate) fn new(path: &Path, ty: SampleType, count: usize) -> Result<Self, ReadError> {
        Self::beside(path, ty, count, 0)
    }

    /// [`SampleBuf::new`] while `held` bytes of the file are in memory.
    fn beside(path: &Path, ty: SampleType, count: usize, held: usize) -> Result<Self, ReadError> {
        let storage = storage_of(ty);
        let need = crate::memory::read_bytes(count as u64, storage.bytes() as u64, held as u64);
        crate::memory::check(need, format!("reading {count} samples"))
            .map_err(|e| ReadError::memory(path, format!("{e}; crop or downsample the volume")))?;
        let cannot = |e| ReadError::memory(path, format!("cannot hold {count} samples: {e}"));
        let samples = match storage {
            SampleStorage::U8 => Samples::U8(zeroed(count).map_err(cannot)?.into()),
            SampleStorage::I16 => Samples::I16(zeroed(count).map_err(cannot)?.into()),
            SampleStorage::U16 => Samples::U16(zeroed(count).map_err(cannot)?.into()),
            SampleStorage::F32 => Samples::F32(zeroed(count).map_err(cannot)?.into()),
            SampleStorage::F64 => Samples::F64(zeroed(count).map_err(cannot)?.into()),
        };
        Ok(SampleBuf { samples, ty, count })
    }

    /// The bytes the file's samples go to (`count * ty.size()` of them).
    pub(crate) fn bytes_mut(&mut self) -> &mut [u8] {
        let n = self.count * self.ty.size();
        &mut self.samples.as_bytes_mut()[..n]
    }

    /// The (zero) samples, for filling in another order than the file's.
    pub(crate) fn into_zeros(self) -> Samples {
        self.samples
    }

    /// The samples, from file byte order `endian`, in their storage type.
    pub(crate) fn finish(mut self, endian: Endian) -> Samples {
        use rayon::prelude::*;
        let (ty, count) = (self.ty, self.count);
        let (s, d) = (ty.size(), self.samples.bytes_per_sample());
        let buf = self.samples.as_bytes_mut();
        match ty {
            SampleType::U8 => {}
            SampleType::U16 | SampleType::I16 | SampleType::F32 | SampleType::F64 => {
                if endian != Endian::native() {
                    buf.par_chunks_mut(s).for_each(<[u8]>::reverse);
                }
            }
            SampleType::I8 => widen_in_place(buf, count, s, d, |c, o| {
                o.copy_from_slice(&i16::from(c[0] as i8).to_ne_bytes())
            }),
            _ => widen_in_place(buf, count, s, d, |c, o| {
                let mut one = [0.0];
                decode_into(c, ty, endian, &mut one);
                o.copy_from_slice(&one[0].to_ne_bytes());
            }),
        }
        self.samples
    }
}

/// A zero-filled vector of `n` elements, allocated in a fallible section.
fn zeroed<T: bytemuck::Pod>(n: usize) -> Result<Vec<T>, std::collections::TryReserveError> {
    let mut v = Vec::new();
    crate::memory::try_reserve(&mut v, n)?;
    v.resize(n, T::zeroed());
    Ok(v)
}

/// Widens the `count` samples of `s` bytes at the start of `buf` to `d` bytes each in place
/// (`d` is `s` or `2 s`), `conv` writing the wide value of one sample. With `d = 2 s` the
/// upper half of the samples is converted first (its wide values lie beyond every unread
/// sample), then the upper half of the rest, and so on: log₂(count) parallel passes.
fn widen_in_place(
    buf: &mut [u8],
    count: usize,
    s: usize,
    d: usize,
    conv: impl Fn(&[u8], &mut [u8]) + Sync,
) {
    use rayon::prelude::*;
    let mut tmp = [0u8; 8];
    if d == s {
        buf[..count * s].par_chunks_mut(s).for_each(|c| {
            let mut t = [0u8; 8];
            conv(c, &mut t[..d]);
            c.copy_from_slice(&t[..d]);
        });
        return;
    }
    debug_assert_eq!(d, 2 * s);
    let mut m = count;
    while m > 1 {
        let h = m.div_ceil(2);
        let (lo, hi) = buf.split_at_mut(d * h);
        let src = &lo[s * h..s * m];
        hi[..d * (m - h)]
            .par_chunks_mut(d)
            .zip(src.par_chunks(s))
            .for_each(|(o, c)| conv(c, o));
        m = h;
    }
    if count > 0 {
        conv(&buf[..s], &mut tmp[..d]);
        buf[..d].copy_from_slice(&tmp[..d]);
    }
}

/// The samples of `bytes` (a whole number of samples of `ty`) in their storage type, after
/// the memory check of [`SampleBuf::new`]. For data a reader already holds in memory.
pub(crate) fn checked_decode(
    path: &Path,
    bytes: &[u8],
    ty: SampleType,
    endian: Endian,
) -> Result<Samples, ReadError> {
    let count = bytes.len() / ty.size();
    let mut buf = SampleBuf::beside(path, ty, count, bytes.len())?;
    buf.bytes_mut().copy_from_slice(&bytes[..count * ty.size()]);
    Ok(buf.finish(endian))
}

/// Decodes `out.len()` samples from the start of `bytes` into `out`.
fn decode_into(bytes: &[u8], ty: SampleType, endian: Endian, out: &mut [f64]) {
    fn each(bytes: &[u8], size: usize, out: &mut [f64], f: impl Fn(&[u8]) -> f64) {
        for (o, c) in out.iter_mut().zip(bytes.chunks_exact(size)) {
            *o = f(c);
        }
    }
    let size = ty.size();
    match ty {
        SampleType::U8 => each(bytes, size, out, |c| f64::from(c[0])),
        SampleType::I8 => each(bytes, size, out, |c| f64::from(c[0] as i8)),
        SampleType::U16 => each(bytes, size, out, |c| {
            f64::from(u16::from_le_bytes(array(c, endian)))
        }),
        SampleType::I16 => each(bytes, size, out, |c| {
            f64::from(i16::from_le_bytes(array(c, endian)))
        }),
        SampleType::U32 => each(bytes, size, out, |c| {
            f64::from(u32::from_le_bytes(array(c, endian)))
        }),
        SampleType::I32 => each(bytes, size, out, |c| {
            f64::from(i32::from_le_bytes(array(c, endian)))
        }),
        SampleType::U64 => each(bytes, size, out, |c| {
            u64::from_le_bytes(array(c, endian)) as f64
        }),
        SampleType::I64 => each(bytes, size, out, |c| {
            i64::from_le_bytes(array(c, endian)) as f64
        }),
        SampleType::F32 => each(bytes, size, out, |c| {
            f64::from(f32::from_le_bytes(array(c, endian)))
        }),
        SampleType::F64 => each(bytes, size, out, |c| f64::from_le_bytes(array(c, endian))),
    }
}

/// Number of samples and of data bytes for `dims` samples of type `ty`, or an error naming
/// `path` if the product overflows.
pub(crate) fn data_size(
    path: &Path,
    dims: [usize; 3],
    ty: SampleType,
) -> Result<(usize, usize), ReadError> {
    let (n, bytes) = dims[0]
        .checked_mul(dims[1])
        .and_then(|n| n.checked_mul(dims[2]))
        .and_then(|n| n.checked_mul(ty.size()).map(|b| (n, b)))
        .ok_or_else(|| ReadError::invalid(path, format!("dimensions {dims:?} are too large")))?;
    Ok((n, bytes))
}

/// Reads a whole file.
pub(crate) fn read_all(path: &Path) -> Result<Vec<u8>, ReadError> {
    std::fs::read(path).map_err(|e| ReadError::io(path, "cannot read file", e))
}

/// Refuses a detached data file that is not a regular file: opening a FIFO would block
/// forever, and devices or directories hold no volume.
pub(crate) fn check_data_file(header: &Path, data_path: &Path) -> Result<(), ReadError> {
    let shown = data_path.display();
    let meta = std::fs::metadata(data_path)
        .map_err(|e| ReadError::io(header, format!("cannot open data file {shown}"), e))?;
    if meta.is_file() {
        Ok(())
    } else {
        Err(ReadError::invalid(
            header,
            format!("data file {shown} is not a regular file (a FIFO, device or directory)"),
        ))
    }
}

/// Reads a whole detached data file (a regular file, see [`check_data_file`]).
pub(crate) fn read_data_file(header: &Path, data_path: &Path) -> Result<Vec<u8>, ReadError> {
    check_data_file(header, data_path)?;
    let shown = data_path.display();
    std::fs::read(data_path)
        .map_err(|e| ReadError::io(header, format!("cannot read data file {shown}"), e))
}

/// Where the data of a separate raw data file start.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Skip {
    /// Skip this many bytes from the start of the file.
    Bytes(u64),
    /// The data are the last bytes of the file.
    FromEnd,
}

/// Opens the raw data file `data_path` (referenced by the header `header`) for reading
/// `len` data bytes after `skip`, positioned at the data; fill the samples with
/// [`read_raw_into`]. The file's size is checked before anything is allocated; unless the
/// skip is [`Skip::FromEnd`] the file must end right after the data (`exact`) or may hold
/// more.
pub(crate) fn open_raw_range(
    header: &Path,
    data_path: &Path,
    skip: Skip,
    len: usize,
    exact: bool,
) -> Result<File, ReadError> {
    check_data_file(header, data_path)?;
    let shown = data_path.display();
    let mut file = File::open(data_path)
        .map_err(|e| ReadError::io(header, format!("cannot open data file {shown}"), e))?;
    let size = file
        .metadata()
        .map_err(|e| ReadError::io(header, format!("cannot read data file {shown}"), e))?
        .len();
    let want = len as u64;
    let start = match skip {
        Skip::Bytes(s) => s,
        Skip::FromEnd => size.checked_sub(want).ok_or_else(|| {
            ReadError::invalid(
                header,
                format!("header says {want} bytes of data but data file {shown} holds {size}"),
            )
        })?,
    };
    let avail = size.saturating_sub(start);
    if avail < want || (exact && avail != want) {
        let skipped = if start > 0 {
            format!(" after skipping {start}")
        } else {
            String::new()
        };
        return Err(ReadError::invalid(
            header,
            format!(
                "header says {want} bytes of data but data file {shown} holds {avail}{skipped}"
            ),
        ));
    }
    file.seek(SeekFrom::Start(start))
        .map_err(|e| ReadError::io(header, format!("cannot read data file {shown}"), e))?;
    Ok(file)
}

/// Reads `out.len()` bytes of the data file `data_path` opened by [`open_raw_range`].
pub(crate) fn read_raw_into(
    header: &Path,
    data_path: &Path,
    mut file: File,
    out: &mut [u8],
) -> Result<(), ReadError> {
    let shown = data_path.display();
    file.read_exact(out)
        .map_err(|e| ReadError::io(header, format!("cannot read data file {shown}"), e))
}

/// Checks that an in-memory data block holds exactly (or, if `!exact`, at least) `want`
/// bytes and returns the first `want`. `what` names the block in the message.
pub(crate) fn take_exact<'a>(
    path: &Path,
    data: &'a [u8],
    want: usize,
    exact: bool,
    what: &str,
) -> Result<&'a [u8], ReadError> {
    if data.len() < want || (exact && data.len() != want) {
        return Err(ReadError::invalid(
            path,
            format!(
                "header says {want} bytes of data but {what} holds {}",
                data.len()
            ),
        ));
    }
    Ok(&data[..want])
}

/// Decompresses `reader` expecting exactly `want` bytes (at least `want` if `!exact`).
/// Only `want` bytes are kept in memory; the rest of the stream is decoded into a sink so
/// its checksum is still verified. `what` names the stream in messages.
pub(crate) fn decompress_exact(
    path: &Path,
    reader: impl Read,
    want: usize,
    exact: bool,
    what: &str,
) -> Result<Vec<u8>, ReadError> {
    let mut out = Vec::new();
    crate::memory::try_reserve(&mut out, want)
        .map_err(|e| ReadError::memory(path, format!("cannot hold {want} bytes of data: {e}")))?;
    out.resize(want, 0);
    decompress_into(path, reader, 0, &mut out, exact, what)?;
    Ok(out)
}

/// Decompresses `reader`, drops its first `skip` bytes and fills `out` with the next ones:
/// the stream must hold exactly `skip + out.len()` bytes (at least that many if `!exact`).
/// The rest of the stream is decoded into a sink so its checksum is still verified. `what`
/// names the stream in messages.
pub(crate) fn decompress_into(
    path: &Path,
    mut reader: impl Read,
    skip: usize,
    out: &mut [u8],
    exact: bool,
    what: &str,
) -> Result<(), ReadError> {
    let corrupt = |e: std::io::Error| ReadError::invalid(path, format!("{what} is corrupt: {e}"));
    let want = skip as u64 + out.len() as u64;
    let skipped = std::io::copy(&mut (&mut reader).take(skip as u64), &mut std::io::sink())
        .map_err(corrupt)?;
    let mut got = skipped;
    if skipped == skip as u64 {
        got += read_full(&mut reader, out).map_err(corrupt)? as u64;
    }
    if got < want {
        return Err(ReadError::invalid(
            path,
            format!("header says {want} bytes of data but {what} decompresses to {got}"),
        ));
    }
    let extra = std::io::copy(&mut reader, &mut std::io::sink()).map_err(corrupt)?;
    if exact && extra > 0 {
        return Err(ReadError::invalid(
            path,
            format!(
                "header says {want} bytes of data but {what} decompresses to {}",
                want.saturating_add(extra)
            ),
        ));
    }
    Ok(())
}

/// Reads until `out` is full or the stream ends; the number of bytes read.
fn read_full(mut reader: impl Read, out: &mut [u8]) -> std::io::Result<usize> {
    let mut n = 0;
    while n < out.len() {
        match reader.read(&mut out[n..]) {
            Ok(0) => break,
            Ok(k) => n += k,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(n)
}

/// Spacing, origin and direction of a grid, in the order [`build_grid`] takes them.
pub(crate) type Geometry = ([f64; 3], [f64; 3], [[f64; 3]; 3]);

/// Splits a 3×3 linear map (columns = index-axis vectors) into spacing (column norms) and
/// direction (normalised columns, as row-major arrays). `None` if a column is zero or not
/// finite.
pub(crate) fn split_linear(m: &Matrix3<f64>) -> Option<([f64; 3], [[f64; 3]; 3])> {
    let mut dir = *m;
    let mut spacing = [0.0; 3];
    for (c, s) in spacing.iter_mut().enumerate() {
        let n = m.column(c).norm();
        if !n.is_finite() || n == 0.0 {
            return None;
        }
        *s = n;
        dir.column_mut(c).unscale_mut(n);
    }
    Some((spacing, rows(&dir)))
}

/// Builds the grid, attaching `path` to any validation error.
pub(crate) fn build_grid(
    path: &Path,
    dims: [usize; 3],
    spacing: [f64; 3],
    origin: [f64; 3],
    direction: [[f64; 3]; 3],
    values: impl Into<crate::grid::Samples>,
) -> Result<ScalarGrid, ReadError> {
    ScalarGrid::with_geometry(dims, spacing, origin, direction, values).map_err(|source| {
        ReadError::Grid {
            file: file_name(path),
            source,
        }
    })
}

/// Converts a header integer to a grid dimension.
pub(crate) fn to_dim(path: &Path, v: i64, what: &str) -> Result<usize, ReadError> {
    usize::try_from(v)
        .map_err(|_| ReadError::invalid(path, format!("{what} {v} is not a valid size")))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::algebra::matrix3;

    #[test]
    fn decodes_all_types_both_endians() {
        let le = [0x01u8, 0x02, 0x03, 0x04, 0x05, 0x06, 0x07, 0x88];
        assert_eq!(decode_samples(&le, SampleType::U8, Endian::Big)[7], 136.0);
        assert_eq!(decode_samples(&le, SampleType::I8, Endian::Big)[7], -120.0);
        assert_eq!(
            decode_samples(&le, SampleType::U16, Endian::Little)[0],
            513.0
        );
        assert_eq!(decode_samples(&le, SampleType::U16, Endian::Big)[0], 258.0);
        assert_eq!(
            decode_samples(&le, SampleType::I16, Endian::Little)[3],
            f64::from(i16::from_le_bytes([7, 0x88]))
        );
        assert_eq!(
            decode_samples(&le, SampleType::I32, Endian::Big)[1],
            f64::from(i32::from_be_bytes([5, 6, 7, 0x88]))
        );
        assert_eq!(
            decode_samples(&le, SampleType::I64, Endian::Little)[0],
            i64::from_le_bytes(le) as f64
        );
        let f = 1.5f32.to_be_bytes();
        assert_eq!(decode_samples(&f, SampleType::F32, Endian::Big), vec![1.5]);
        let d = (-2.25f64).to_le_bytes();
        assert_eq!(
            decode_samples(&d, SampleType::F64, Endian::Little),
            vec![-2.25]
        );
        // partial trailing sample ignored
        assert_eq!(
            decode_samples(&le[..3], SampleType::U16, Endian::Little).len(),
            1
        );
    }

    #[test]
    fn messages_are_one_line() {
        let e = ReadError::invalid(Path::new("a\nb.nrrd"), "bad\r\nthing");
        let s = e.to_string();
        assert!(!s.contains('\n') && !s.contains('\r'), "{s}");
        assert!(s.starts_with("a\\nb.nrrd: "));
        assert_eq!(quote("x\ny"), "\"x\\ny\"");
    }

    #[test]
    fn split_linear_rejects_zero_column() {
        let m = [[1.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 2.0]];
        assert!(split_linear(&matrix3(&m)).is_none());
        let m = [[0.0, -2.0, 0.0], [3.0, 0.0, 0.0], [0.0, 0.0, 4.0]];
        let (s, d) = split_linear(&matrix3(&m)).unwrap();
        assert_eq!(s, [3.0, 2.0, 4.0]);
        assert_eq!(d, [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]);
    }

    /// Column norms and quotients as the readers always computed them: every coordinate of
    /// every output depends on them.
    #[test]
    fn split_linear_keeps_the_bits_of_the_plain_formulas() {
        let mut seed = 0x9e37_79b9_7f4a_7c15_u64;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 10.0 - 5.0
        };
        for _ in 0..1000 {
            let m: [[f64; 3]; 3] = std::array::from_fn(|_| std::array::from_fn(|_| next()));
            let (s, d) = split_linear(&matrix3(&m)).unwrap();
            for c in 0..3 {
                let n = (m[0][c] * m[0][c] + m[1][c] * m[1][c] + m[2][c] * m[2][c]).sqrt();
                assert_eq!(s[c].to_bits(), n.to_bits());
                for r in 0..3 {
                    assert_eq!(d[r][c].to_bits(), (m[r][c] / n).to_bits());
                }
            }
        }
    }

    #[test]
    fn data_size_overflow_is_an_error() {
        assert!(data_size(Path::new("x"), [usize::MAX, 2, 2], SampleType::U8).is_err());
        assert_eq!(
            data_size(Path::new("x"), [2, 3, 4], SampleType::F32).unwrap(),
            (24, 96)
        );
    }
}
