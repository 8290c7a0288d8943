//! MetaImage reader: `.mhd` header with a separate data file (`.raw`, or zlib-compressed
//! `.zraw` with `CompressedData = True`), or `.mha` with the data after the header
//! (`ElementDataFile = LOCAL`).
//!
//! Supported fields: `NDims = 3`, `DimSize`, `ElementType` (`MET_UCHAR`, `MET_CHAR`,
//! `MET_USHORT`, `MET_SHORT`, `MET_UINT`, `MET_INT`, `MET_LONG_LONG`, `MET_ULONG_LONG`,
//! `MET_FLOAT`, `MET_DOUBLE`), `ElementSpacing` (or `ElementSize`), `Offset` / `Position` /
//! `Origin`, `TransformMatrix` / `Rotation` / `Orientation`, `BinaryDataByteOrderMSB` /
//! `ElementByteOrderMSB`, `CompressedData`, `HeaderSize` (raw data only, `-1` = data at the
//! end of the file) and `ElementNumberOfChannels = 1`.
//!
//! The 9 numbers of `TransformMatrix` are the direction matrix in column-major order, as
//! ITK/SimpleITK write it: the first three are the direction of the first index axis.

use std::path::{Path, PathBuf};

use flate2::read::ZlibDecoder;
use nalgebra::Matrix3;

use super::header::{self, Fields};
use super::read_common::{
    build_grid, checked_decode, data_size, decompress_into, open_raw_range, quote, read_all,
    read_data_file, read_raw_into, take_exact, Endian, Geometry, ReadError, SampleBuf, SampleType,
    Skip,
};
use crate::algebra::rows;
use crate::grid::{Samples, ScalarGrid, IDENTITY};

/// Reads a MetaImage volume (`.mhd` + data file, or `.mha`).
///
/// # Errors
/// [`ReadError::Io`] if the header or data file cannot be read; [`ReadError::Invalid`] for
/// malformed or missing required fields, a data size that differs from `DimSize` × type
/// size, or a corrupt zlib stream; [`ReadError::Unsupported`] for other `NDims`, element
/// types, multi-channel or ASCII data, or file lists; [`ReadError::Grid`] for a dimension
/// below 2, a non-finite value or degenerate geometry.
pub fn read_mhd(path: &Path) -> Result<ScalarGrid, ReadError> {
    let bytes = read_all(path)?;
    let h = parse_header(path, &bytes)?;
    let (count, nbytes) = data_size(path, h.dims, h.ty)?;
    let values = match (&h.data, h.compressed) {
        (DataLocation::Local(start), false) => {
            let data = read_local_raw(path, &h, &bytes[*start..], nbytes)?;
            checked_decode(path, data, h.ty, h.endian)?
        }
        (DataLocation::Local(start), true) => {
            let block = &bytes[*start..];
            check_compressed_size(
                path,
                h.compressed_size,
                block.len(),
                "the file after the header",
            )?;
            let mut buf = SampleBuf::new(path, h.ty, count)?;
            let z = ZlibDecoder::new(block);
            decompress_into(path, z, 0, buf.bytes_mut(), true, "the zlib data")?;
            buf.finish(h.endian)
        }
        (DataLocation::File(file), false) => {
            let skip = h.header_size.unwrap_or(Skip::Bytes(0));
            let f = open_raw_range(path, file, skip, nbytes, skip != Skip::FromEnd)?;
            let mut buf = SampleBuf::new(path, h.ty, count)?;
            read_raw_into(path, file, f, buf.bytes_mut())?;
            buf.finish(h.endian)
        }
        (DataLocation::File(file), true) => read_zlib_file(path, &h, file, count)?,
    };
    drop(bytes);
    build_grid(path, h.dims, h.spacing, h.origin, h.direction, values)
}

/// The files [`read_mhd`] reads for `path`: `path` itself, then its `ElementDataFile` unless
/// that is `LOCAL`. Reads the header only.
///
/// # Errors
/// Those of [`read_mhd`] about the header.
pub(crate) fn mhd_files(path: &Path) -> Result<Vec<PathBuf>, ReadError> {
    let ended = |b: &[u8]| {
        Fields::read_equals(path, b, "ElementDataFile").map_or(true, |f| f.end().is_some())
    };
    let bytes = header::read_prefix(path, ended)?;
    let mut files = vec![path.to_path_buf()];
    if let DataLocation::File(data) = parse_header(path, &bytes)?.data {
        files.push(data);
    }
    Ok(files)
}

/// The `nbytes` uncompressed data bytes of a `.mha` file, from `block` (the file after the
/// header) and `HeaderSize`.
fn read_local_raw<'a>(
    path: &Path,
    h: &Header,
    block: &'a [u8],
    nbytes: usize,
) -> Result<&'a [u8], ReadError> {
    let block = match h.header_size {
        Some(Skip::FromEnd) => {
            let from = block.len().checked_sub(nbytes).ok_or_else(|| {
                ReadError::invalid(
                    path,
                    format!(
                        "header says {nbytes} bytes of data but the file holds {}",
                        block.len()
                    ),
                )
            })?;
            return Ok(&block[from..]);
        }
        Some(Skip::Bytes(s)) => usize::try_from(s)
            .ok()
            .and_then(|s| block.get(s..))
            .ok_or_else(|| {
                ReadError::invalid(
                    path,
                    format!("HeaderSize {s} goes past the end of the file"),
                )
            })?,
        None => block,
    };
    take_exact(path, block, nbytes, true, "the file after the header")
}

/// Decompresses the `count` samples of the zlib data file `file`.
fn read_zlib_file(
    path: &Path,
    h: &Header,
    file: &Path,
    count: usize,
) -> Result<Samples, ReadError> {
    let shown = file.display().to_string();
    let all = read_data_file(path, file)?;
    check_compressed_size(
        path,
        h.compressed_size,
        all.len(),
        &format!("data file {shown}"),
    )?;
    let what = format!("zlib data file {shown}");
    let mut buf = SampleBuf::new(path, h.ty, count)?;
    let z = ZlibDecoder::new(all.as_slice());
    decompress_into(path, z, 0, buf.bytes_mut(), true, &what)?;
    Ok(buf.finish(h.endian))
}

/// Checks `CompressedDataSize`, if the header gives it, against the bytes present.
fn check_compressed_size(
    path: &Path,
    declared: Option<u64>,
    present: usize,
    what: &str,
) -> Result<(), ReadError> {
    match declared {
        Some(d) if d != present as u64 => Err(ReadError::invalid(
            path,
            format!("CompressedDataSize is {d} but {what} holds {present} bytes"),
        )),
        _ => Ok(()),
    }
}

#[derive(Debug)]
enum DataLocation {
    /// Data follow the header in the same file, from this byte.
    Local(usize),
    /// Data in this file.
    File(std::path::PathBuf),
}

#[derive(Debug)]
struct Header {
    dims: [usize; 3],
    ty: SampleType,
    endian: Endian,
    compressed: bool,
    compressed_size: Option<u64>,
    header_size: Option<Skip>,
    spacing: [f64; 3],
    origin: [f64; 3],
    direction: [[f64; 3]; 3],
    data: DataLocation,
}

/// How the data are stored: `CompressedData`, `CompressedDataSize` and `HeaderSize`.
struct Storage {
    compressed: bool,
    compressed_size: Option<u64>,
    header_size: Option<Skip>,
}

fn element_type(s: &str) -> Option<SampleType> {
    Some(match s {
        "MET_UCHAR" => SampleType::U8,
        "MET_CHAR" => SampleType::I8,
        "MET_USHORT" => SampleType::U16,
        "MET_SHORT" => SampleType::I16,
        "MET_UINT" => SampleType::U32,
        "MET_INT" => SampleType::I32,
        "MET_ULONG_LONG" => SampleType::U64,
        "MET_LONG_LONG" => SampleType::I64,
        "MET_FLOAT" => SampleType::F32,
        "MET_DOUBLE" => SampleType::F64,
        _ => return None,
    })
}

fn boolean(path: &Path, key: &str, v: &str) -> Result<bool, ReadError> {
    match v.to_ascii_lowercase().as_str() {
        "true" | "1" => Ok(true),
        "false" | "0" => Ok(false),
        _ => Err(ReadError::invalid(
            path,
            format!("{key} must be True or False, got {}", quote(v)),
        )),
    }
}

/// Parses the header at the start of `bytes` (up to and including `ElementDataFile`), one
/// concern at a time: object kind, sizes, sample type, byte order, storage, geometry and
/// data location.
fn parse_header(path: &Path, bytes: &[u8]) -> Result<Header, ReadError> {
    let fields = Fields::read_equals(path, bytes, "ElementDataFile")?;
    if fields.is_empty() {
        return Err(ReadError::invalid(path, "empty MetaImage header"));
    }
    check_image(path, &fields)?;
    let dims = header::sizes(path, "DimSize", require(path, &fields, "DimSize")?)?;
    let ty = sample_type(path, &fields)?;
    let endian = endian(path, &fields)?;
    let storage = storage(path, &fields)?;
    let (spacing, origin, direction) = geometry(path, &fields)?;
    let data = data_location(path, &fields, bytes.len())?;
    if storage.compressed && storage.header_size.is_some_and(|s| s != Skip::Bytes(0)) {
        return Err(ReadError::unsupported(
            path,
            "HeaderSize with CompressedData = True",
        ));
    }
    Ok(Header {
        dims,
        ty,
        endian,
        compressed: storage.compressed,
        compressed_size: storage.compressed_size,
        header_size: storage.header_size,
        spacing,
        origin,
        direction,
        data,
    })
}

/// The value of a required field.
fn require<'a>(path: &Path, fields: &'a Fields, name: &str) -> Result<&'a str, ReadError> {
    fields
        .get(name)
        .ok_or_else(|| ReadError::invalid(path, format!("header has no {name} field")))
}

/// `ObjectType` (must be `Image` if present) and `NDims` (must be 3).
fn check_image(path: &Path, fields: &Fields) -> Result<(), ReadError> {
    if let Some(t) = fields.get("ObjectType") {
        if !t.eq_ignore_ascii_case("Image") {
            return Err(ReadError::unsupported(
                path,
                format!("ObjectType {}", quote(t)),
            ));
        }
    }
    let ndims = require(path, fields, "NDims")?;
    if ndims != "3" {
        return Err(ReadError::unsupported(
            path,
            format!("NDims = {} (only 3-D volumes are read)", quote(ndims)),
        ));
    }
    Ok(())
}

/// `ElementType`, with `ElementNumberOfChannels` (must be 1) and `BinaryData` (must be
/// true) if present.
fn sample_type(path: &Path, fields: &Fields) -> Result<SampleType, ReadError> {
    let et = require(path, fields, "ElementType")?;
    let ty = element_type(et)
        .ok_or_else(|| ReadError::unsupported(path, format!("ElementType {}", quote(et))))?;
    if let Some(ch) = fields.get("ElementNumberOfChannels") {
        if ch != "1" {
            return Err(ReadError::unsupported(
                path,
                format!(
                    "ElementNumberOfChannels = {} (only scalar volumes)",
                    quote(ch)
                ),
            ));
        }
    }
    if let Some(b) = fields.get("BinaryData") {
        if !boolean(path, "BinaryData", b)? {
            return Err(ReadError::unsupported(
                path,
                "ASCII data (BinaryData = False)",
            ));
        }
    }
    Ok(ty)
}

/// `BinaryDataByteOrderMSB` / `ElementByteOrderMSB` (little-endian if absent).
fn endian(path: &Path, fields: &Fields) -> Result<Endian, ReadError> {
    let msb = match fields.get_any(&["BinaryDataByteOrderMSB", "ElementByteOrderMSB"]) {
        Some((k, v)) => boolean(path, k, v)?,
        None => false,
    };
    Ok(if msb { Endian::Big } else { Endian::Little })
}

/// `CompressedData`, `CompressedDataSize` and `HeaderSize` (`-1` only without compression).
fn storage(path: &Path, fields: &Fields) -> Result<Storage, ReadError> {
    let compressed = match fields.get("CompressedData") {
        Some(v) => boolean(path, "CompressedData", v)?,
        None => false,
    };
    let compressed_size = match fields.get("CompressedDataSize") {
        None => None,
        Some(v) => Some(header::count(path, "CompressedDataSize", v)?),
    };
    let header_size = match fields.get("HeaderSize") {
        None => None,
        Some(v) => Some(header::skip(path, "HeaderSize", v)?),
    };
    if compressed && header_size == Some(Skip::FromEnd) {
        return Err(ReadError::invalid(
            path,
            "HeaderSize = -1 cannot be used with CompressedData = True",
        ));
    }
    Ok(Storage {
        compressed,
        compressed_size,
        header_size,
    })
}

/// Spacing, origin and direction; the 9 numbers of the direction are column-major.
fn geometry(path: &Path, fields: &Fields) -> Result<Geometry, ReadError> {
    let spacing = match fields.get_any(&["ElementSpacing", "ElementSize"]) {
        Some((k, v)) => header::numbers::<3>(path, k, v)?,
        None => [1.0; 3],
    };
    let origin = match fields.get_any(&["Offset", "Position", "Origin"]) {
        Some((k, v)) => header::numbers::<3>(path, k, v)?,
        None => [0.0; 3],
    };
    let direction = match fields.get_any(&["TransformMatrix", "Rotation", "Orientation"]) {
        Some((k, v)) => {
            let m = header::numbers::<9>(path, k, v)?;
            rows(&Matrix3::from_column_slice(&m))
        }
        None => IDENTITY,
    };
    Ok((spacing, origin, direction))
}

/// `ElementDataFile`: `LOCAL` (the data follow the header, whose end is `fields.end()`, or
/// `len` if unknown) or a single file relative to the header.
fn data_location(path: &Path, fields: &Fields, len: usize) -> Result<DataLocation, ReadError> {
    let df = require(path, fields, "ElementDataFile")?;
    if df.eq_ignore_ascii_case("LOCAL") {
        Ok(DataLocation::Local(fields.end().unwrap_or(len)))
    } else if df.starts_with("LIST") || df.contains('%') || df.split_whitespace().count() > 1 {
        Err(ReadError::unsupported(
            path,
            format!("multi-file data {}", quote(df)),
        ))
    } else {
        Ok(DataLocation::File(header::data_file_path(path, df)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transform_matrix_is_column_major() {
        let h = b"ObjectType = Image\nNDims = 3\nDimSize = 2 2 2\nElementType = MET_UCHAR\n\
TransformMatrix = 0 1 0 -1 0 0 0 0 1\nElementDataFile = LOCAL\n\x00\x01\x02\x03\x04\x05\x06\x07";
        let hd = parse_header(Path::new("a.mha"), h).unwrap();
        // first index axis points along +y
        assert_eq!(
            hd.direction,
            [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
        );
        assert!(matches!(hd.data, DataLocation::Local(n) if n == h.len() - 8));
    }

    #[test]
    fn bad_headers() {
        let p = Path::new("a.mhd");
        assert!(parse_header(p, b"").is_err());
        assert!(parse_header(
            p,
            b"NDims = 2\nDimSize = 2 2\nElementType = MET_UCHAR\nElementDataFile = x.raw\n"
        )
        .is_err());
        assert!(parse_header(
            p,
            b"NDims = 3\nDimSize = 2 2 2\nElementType = MET_FOO\nElementDataFile = x.raw\n"
        )
        .is_err());
        assert!(parse_header(p, b"\x89PNG\r\n\x1a\n\x00\x00").is_err());
    }
}
