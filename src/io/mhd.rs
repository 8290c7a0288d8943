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

use std::path::Path;

use flate2::read::ZlibDecoder;

use super::volume::{
    build_grid, data_size, decode_samples, decompress_exact, quote, read_all, read_raw_range,
    take_exact, Endian, ReadError, SampleType, Skip,
};
use crate::grid::{ScalarGrid, IDENTITY};

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
    let (_, nbytes) = data_size(path, h.dims, h.ty)?;
    let data: Vec<u8> = match (&h.data, h.compressed) {
        (DataLocation::Local(start), false) => {
            let block = &bytes[*start..];
            match h.header_size {
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
                    block[from..].to_vec()
                }
                Some(Skip::Bytes(s)) => {
                    let block = usize::try_from(s)
                        .ok()
                        .and_then(|s| block.get(s..))
                        .ok_or_else(|| {
                            ReadError::invalid(
                                path,
                                format!("HeaderSize {s} goes past the end of the file"),
                            )
                        })?;
                    take_exact(path, block, nbytes, true, "the file after the header")?.to_vec()
                }
                None => {
                    take_exact(path, block, nbytes, true, "the file after the header")?.to_vec()
                }
            }
        }
        (DataLocation::Local(start), true) => {
            let block = &bytes[*start..];
            check_compressed_size(
                path,
                h.compressed_size,
                block.len(),
                "the file after the header",
            )?;
            decompress_exact(path, ZlibDecoder::new(block), nbytes, true, "the zlib data")?
        }
        (DataLocation::File(file), false) => {
            let skip = h.header_size.unwrap_or(Skip::Bytes(0));
            read_raw_range(path, file, skip, nbytes, skip != Skip::FromEnd)?
        }
        (DataLocation::File(file), true) => {
            let shown = file.display().to_string();
            let all = std::fs::read(file)
                .map_err(|e| ReadError::io(path, format!("cannot read data file {shown}"), e))?;
            check_compressed_size(
                path,
                h.compressed_size,
                all.len(),
                &format!("data file {shown}"),
            )?;
            let what = format!("zlib data file {shown}");
            decompress_exact(path, ZlibDecoder::new(all.as_slice()), nbytes, true, &what)?
        }
    };
    let values = decode_samples(&data, h.ty, h.endian);
    build_grid(path, h.dims, h.spacing, h.origin, h.direction, values)
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

fn numbers<const N: usize>(path: &Path, key: &str, v: &str) -> Result<[f64; N], ReadError> {
    let bad = || ReadError::invalid(path, format!("{key} must be {N} numbers, got {}", quote(v)));
    let list: Vec<f64> = v
        .split_whitespace()
        .map(str::parse::<f64>)
        .collect::<Result<_, _>>()
        .map_err(|_| bad())?;
    list.try_into().map_err(|_| bad())
}

fn parse_header(path: &Path, bytes: &[u8]) -> Result<Header, ReadError> {
    let mut fields: Vec<(String, String)> = Vec::new();
    let mut data_start = None;
    let mut pos = 0usize;
    while pos < bytes.len() {
        let (line, next) = match bytes[pos..].iter().position(|&b| b == b'\n') {
            Some(n) => (&bytes[pos..pos + n], pos + n + 1),
            None => (&bytes[pos..], bytes.len()),
        };
        let line_start = pos;
        pos = next;
        let line = line.strip_suffix(b"\r").unwrap_or(line);
        if line.iter().all(u8::is_ascii_whitespace) {
            continue;
        }
        let text = std::str::from_utf8(line).map_err(|_| {
            ReadError::invalid(
                path,
                format!("header line at byte {line_start} is not text (not a MetaImage header?)"),
            )
        })?;
        let (k, v) = text.split_once('=').ok_or_else(|| {
            ReadError::invalid(
                path,
                format!(
                    "malformed header line {} (expected Key = Value)",
                    quote(text)
                ),
            )
        })?;
        let (k, v) = (k.trim().to_string(), v.trim().to_string());
        let is_data_file = k.eq_ignore_ascii_case("ElementDataFile");
        fields.push((k, v));
        if is_data_file {
            // ElementDataFile is always the last field
            data_start = Some(pos);
            break;
        }
    }
    let get = |name: &str| {
        fields
            .iter()
            .rev()
            .find(|(k, _)| k.eq_ignore_ascii_case(name))
            .map(|(_, v)| v.as_str())
    };
    let get_any = |names: &[&'static str]| names.iter().find_map(|&n| get(n).map(|v| (n, v)));
    let require = |name: &str| {
        get(name).ok_or_else(|| ReadError::invalid(path, format!("header has no {name} field")))
    };

    if fields.is_empty() {
        return Err(ReadError::invalid(path, "empty MetaImage header"));
    }
    if let Some(t) = get("ObjectType") {
        if !t.eq_ignore_ascii_case("Image") {
            return Err(ReadError::unsupported(
                path,
                format!("ObjectType {}", quote(t)),
            ));
        }
    }
    let ndims = require("NDims")?;
    if ndims != "3" {
        return Err(ReadError::unsupported(
            path,
            format!("NDims = {} (only 3-D volumes are read)", quote(ndims)),
        ));
    }
    let ds = require("DimSize")?;
    let dims_v: Vec<usize> = ds
        .split_whitespace()
        .map(str::parse::<usize>)
        .collect::<Result<_, _>>()
        .map_err(|_| {
            ReadError::invalid(
                path,
                format!("DimSize must be 3 non-negative integers, got {}", quote(ds)),
            )
        })?;
    let dims: [usize; 3] = dims_v.try_into().map_err(|_| {
        ReadError::invalid(
            path,
            format!("DimSize must be 3 integers, got {}", quote(ds)),
        )
    })?;
    let et = require("ElementType")?;
    let ty = element_type(et)
        .ok_or_else(|| ReadError::unsupported(path, format!("ElementType {}", quote(et))))?;
    if let Some(ch) = get("ElementNumberOfChannels") {
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
    if let Some(b) = get("BinaryData") {
        if !boolean(path, "BinaryData", b)? {
            return Err(ReadError::unsupported(
                path,
                "ASCII data (BinaryData = False)",
            ));
        }
    }
    let msb = match get_any(&["BinaryDataByteOrderMSB", "ElementByteOrderMSB"]) {
        Some((k, v)) => boolean(path, k, v)?,
        None => false,
    };
    let endian = if msb { Endian::Big } else { Endian::Little };
    let compressed = match get("CompressedData") {
        Some(v) => boolean(path, "CompressedData", v)?,
        None => false,
    };
    let compressed_size = match get("CompressedDataSize") {
        None => None,
        Some(v) => Some(v.parse::<u64>().map_err(|_| {
            ReadError::invalid(
                path,
                format!(
                    "CompressedDataSize must be a non-negative integer, got {}",
                    quote(v)
                ),
            )
        })?),
    };
    let header_size = match get("HeaderSize") {
        None => None,
        Some("-1") => Some(Skip::FromEnd),
        Some(v) => Some(Skip::Bytes(v.parse::<u64>().map_err(|_| {
            ReadError::invalid(
                path,
                format!(
                    "HeaderSize must be -1 or a non-negative integer, got {}",
                    quote(v)
                ),
            )
        })?)),
    };
    if compressed && header_size == Some(Skip::FromEnd) {
        return Err(ReadError::invalid(
            path,
            "HeaderSize = -1 cannot be used with CompressedData = True",
        ));
    }

    let spacing = match get_any(&["ElementSpacing", "ElementSize"]) {
        Some((k, v)) => numbers::<3>(path, k, v)?,
        None => [1.0; 3],
    };
    let origin = match get_any(&["Offset", "Position", "Origin"]) {
        Some((k, v)) => numbers::<3>(path, k, v)?,
        None => [0.0; 3],
    };
    let direction = match get_any(&["TransformMatrix", "Rotation", "Orientation"]) {
        Some((k, v)) => {
            let m = numbers::<9>(path, k, v)?;
            let mut d = [[0.0; 3]; 3];
            for (r, row) in d.iter_mut().enumerate() {
                for (c, x) in row.iter_mut().enumerate() {
                    *x = m[c * 3 + r]; // column-major
                }
            }
            d
        }
        None => IDENTITY,
    };

    let df = require("ElementDataFile")?;
    let data = if df.eq_ignore_ascii_case("LOCAL") {
        DataLocation::Local(data_start.unwrap_or(bytes.len()))
    } else if df.starts_with("LIST") || df.contains('%') || df.split_whitespace().count() > 1 {
        return Err(ReadError::unsupported(
            path,
            format!("multi-file data {}", quote(df)),
        ));
    } else {
        let p = Path::new(df);
        DataLocation::File(if p.is_absolute() {
            p.to_path_buf()
        } else {
            path.parent().unwrap_or_else(|| Path::new("")).join(p)
        })
    };
    if compressed && header_size.is_some_and(|s| s != Skip::Bytes(0)) {
        return Err(ReadError::unsupported(
            path,
            "HeaderSize with CompressedData = True",
        ));
    }
    Ok(Header {
        dims,
        ty,
        endian,
        compressed,
        compressed_size,
        header_size,
        spacing,
        origin,
        direction,
        data,
    })
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
