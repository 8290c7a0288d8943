//! NRRD reader (`NRRD0001` to `NRRD0005`), attached (`.nrrd`) or detached (`.nhdr`) data.
//!
//! Supported: `dimension: 3`; types `(u)int8/16/32/64`, `float`, `double` and all their C
//! aliases; encodings `raw`, `gzip`/`gz` and `ascii`/`text`/`txt`; `endian`; `sizes`;
//! `spacings` or `space directions` (+ `space origin`); `data file` (a single file, relative
//! to the header); `line skip` and `byte skip` (including `-1` for raw data). The first axis
//! varies fastest and becomes x.

use std::path::{Path, PathBuf};

use flate2::read::MultiGzDecoder;
use nalgebra::{Matrix3, Vector3};

use super::header::{self, Fields};
use super::read_common::{
    build_grid, checked_decode, data_size, decompress_into, open_raw_range, quote, read_all,
    read_data_file, read_raw_into, split_linear, take_exact, Endian, Geometry, ReadError,
    SampleBuf, SampleType, Skip,
};
use crate::grid::{Samples, ScalarGrid, IDENTITY};

/// Reads an NRRD volume (`.nrrd` with attached or detached data, or a `.nhdr` header).
///
/// # Errors
/// [`ReadError::Io`] if the header or its data file cannot be read; [`ReadError::Invalid`]
/// for a bad magic, a malformed or missing required field, a data size that differs from
/// `sizes` × type size, or a corrupt gzip stream; [`ReadError::Unsupported`] for other
/// dimensions, types, encodings or multi-file data; [`ReadError::Grid`] for a dimension
/// below 2, a non-finite value or degenerate geometry.
pub fn read_nrrd(path: &Path) -> Result<ScalarGrid, ReadError> {
    let bytes = read_all(path)?;
    let header = parse_header(path, &bytes)?;
    let (count, nbytes) = data_size(path, header.sizes, header.ty)?;
    let values = read_samples(path, &header, &bytes, count, nbytes)?;
    drop(bytes);
    build_grid(
        path,
        header.sizes,
        header.spacing,
        header.origin,
        header.direction,
        values,
    )
}

/// The files [`read_nrrd`] reads for `path`: `path` itself, then its detached data file if
/// the header names one. Reads the header only.
///
/// # Errors
/// Those of [`read_nrrd`] about the header.
pub(crate) fn nrrd_files(path: &Path) -> Result<Vec<PathBuf>, ReadError> {
    let bytes = header::read_prefix(path, header::has_blank_line)?;
    let header = parse_header(path, &bytes)?;
    Ok(std::iter::once(path.to_path_buf())
        .chain(header.data_file)
        .collect())
}

/// The `count` samples (`nbytes` data bytes), from the data file or from `bytes` (the whole
/// `.nrrd` file) after the header. Detached raw and gzip data go straight into the samples'
/// storage; attached raw data are copied from `bytes`; ascii data are read as `f64`.
fn read_samples(
    path: &Path,
    h: &Header,
    bytes: &[u8],
    count: usize,
    nbytes: usize,
) -> Result<Samples, ReadError> {
    if let (Some(file), Encoding::Raw, 0) = (&h.data_file, h.encoding, h.line_skip) {
        return read_detached_raw(path, h, file, count, nbytes);
    }
    let all;
    let (block, what) = match &h.data_file {
        Some(file) => {
            all = read_data_file(path, file)?;
            (all.as_slice(), format!("data file {}", file.display()))
        }
        None => {
            let start = h.data_start.ok_or_else(|| {
                ReadError::invalid(
                    path,
                    "header has no blank line ending it and no 'data file' field",
                )
            })?;
            (&bytes[start..], "the file after the header".to_string())
        }
    };
    let block = skip_lines(path, h, block, &what)?;
    decode_block(path, h, block, &what, count, nbytes)
}

/// The `count` samples (`nbytes` bytes) of detached raw data without line skips, read from
/// the data file `file` of the header `path` straight into the samples' storage.
fn read_detached_raw(
    path: &Path,
    h: &Header,
    file: &Path,
    count: usize,
    nbytes: usize,
) -> Result<Samples, ReadError> {
    let f = open_raw_range(
        path,
        file,
        h.byte_skip,
        nbytes,
        h.byte_skip != Skip::FromEnd,
    )?;
    let mut buf = SampleBuf::new(path, h.ty, count)?;
    read_raw_into(path, file, f, buf.bytes_mut())?;
    Ok(buf.finish(h.data_endian()))
}

/// Decodes the `count` samples (`nbytes` bytes) of `block`, the data after the line skips
/// (`what` names it in errors), by the header's encoding and byte skip.
fn decode_block(
    path: &Path,
    h: &Header,
    block: &[u8],
    what: &str,
    count: usize,
    nbytes: usize,
) -> Result<Samples, ReadError> {
    match h.encoding {
        Encoding::Raw => {
            let data = raw_data(path, h, block, nbytes, what)?;
            checked_decode(path, data, h.ty, h.data_endian())
        }
        Encoding::Gzip => {
            // byte skip applies to the decompressed data
            let too_large = || ReadError::invalid(path, "'byte skip' is too large");
            let skip = match h.byte_skip {
                Skip::Bytes(n) => usize::try_from(n).map_err(|_| too_large())?,
                Skip::FromEnd => 0,
            };
            nbytes.checked_add(skip).ok_or_else(too_large)?;
            let mut buf = SampleBuf::new(path, h.ty, count)?;
            let what = format!("gzip data in {what}");
            let gz = MultiGzDecoder::new(block);
            decompress_into(path, gz, skip, buf.bytes_mut(), true, &what)?;
            Ok(buf.finish(h.data_endian()))
        }
        Encoding::Ascii => {
            let byte_skip = match h.byte_skip {
                Skip::Bytes(n) => n,
                Skip::FromEnd => 0,
            };
            let text = skip_bytes(path, block, byte_skip, what)?;
            Ok(parse_ascii(path, text, count)?.into())
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Encoding {
    Raw,
    Gzip,
    Ascii,
}

#[derive(Debug)]
struct Header {
    ty: SampleType,
    sizes: [usize; 3],
    encoding: Encoding,
    endian: Option<Endian>,
    spacing: [f64; 3],
    origin: [f64; 3],
    direction: [[f64; 3]; 3],
    data_file: Option<PathBuf>,
    line_skip: u64,
    /// `byte skip`: [`Skip::FromEnd`] for `-1`, `Skip::Bytes(0)` if absent.
    byte_skip: Skip,
    /// Offset of the attached data, if the header ended with a blank line.
    data_start: Option<usize>,
}

impl Header {
    /// The byte order of the data: the `endian` field, little when there is none (it is
    /// required only for multi-byte types stored in binary).
    fn data_endian(&self) -> Endian {
        self.endian.unwrap_or(Endian::Little)
    }
}

/// `block` after the header's `line skip` lines.
fn skip_lines<'a>(
    path: &Path,
    h: &Header,
    block: &'a [u8],
    what: &str,
) -> Result<&'a [u8], ReadError> {
    let mut block = block;
    for _ in 0..h.line_skip {
        let nl = block.iter().position(|&b| b == b'\n').ok_or_else(|| {
            ReadError::invalid(path, format!("'line skip' goes past the end of {what}"))
        })?;
        block = &block[nl + 1..];
    }
    Ok(block)
}

/// The `nbytes` raw data bytes of an in-memory block (after line skip), by byte skip.
fn raw_data<'a>(
    path: &Path,
    h: &Header,
    block: &'a [u8],
    nbytes: usize,
    what: &str,
) -> Result<&'a [u8], ReadError> {
    match h.byte_skip {
        Skip::FromEnd => {
            let start = block.len().checked_sub(nbytes).ok_or_else(|| {
                ReadError::invalid(
                    path,
                    format!(
                        "header says {nbytes} bytes of data but {what} holds {}",
                        block.len()
                    ),
                )
            })?;
            Ok(&block[start..])
        }
        Skip::Bytes(n) => {
            let block = skip_bytes(path, block, n, what)?;
            take_exact(path, block, nbytes, true, what)
        }
    }
}

fn skip_bytes<'a>(
    path: &Path,
    block: &'a [u8],
    skip: u64,
    what: &str,
) -> Result<&'a [u8], ReadError> {
    usize::try_from(skip)
        .ok()
        .and_then(|s| block.get(s..))
        .ok_or_else(|| {
            ReadError::invalid(
                path,
                format!("'byte skip: {skip}' goes past the end of {what}"),
            )
        })
}

fn parse_ascii(path: &Path, data: &[u8], count: usize) -> Result<Vec<f64>, ReadError> {
    let text = String::from_utf8_lossy(data);
    let mut values = Vec::new();
    for tok in text
        .split(|c: char| c.is_whitespace() || c == ',')
        .filter(|t| !t.is_empty())
    {
        if values.len() == count {
            return Err(ReadError::invalid(
                path,
                format!("ascii data holds more than the {count} values the header says"),
            ));
        }
        let v: f64 = tok.parse().map_err(|_| {
            ReadError::invalid(path, format!("ascii data: {} is not a number", quote(tok)))
        })?;
        values.push(v);
    }
    if values.len() != count {
        return Err(ReadError::invalid(
            path,
            format!(
                "header says {count} values but the ascii data holds {}",
                values.len()
            ),
        ));
    }
    Ok(values)
}

fn parse_type(s: &str) -> Option<SampleType> {
    let norm: Vec<&str> = s.split_whitespace().collect();
    Some(match norm.join(" ").to_ascii_lowercase().as_str() {
        "signed char" | "int8" | "int8_t" => SampleType::I8,
        "uchar" | "unsigned char" | "uint8" | "uint8_t" => SampleType::U8,
        "short" | "short int" | "signed short" | "signed short int" | "int16" | "int16_t" => {
            SampleType::I16
        }
        "ushort" | "unsigned short" | "unsigned short int" | "uint16" | "uint16_t" => {
            SampleType::U16
        }
        "int" | "signed int" | "int32" | "int32_t" => SampleType::I32,
        "uint" | "unsigned int" | "uint32" | "uint32_t" => SampleType::U32,
        "longlong"
        | "long long"
        | "long long int"
        | "signed long long"
        | "signed long long int"
        | "int64"
        | "int64_t" => SampleType::I64,
        "ulonglong" | "unsigned long long" | "unsigned long long int" | "uint64" | "uint64_t" => {
            SampleType::U64
        }
        "float" => SampleType::F32,
        "double" => SampleType::F64,
        _ => return None,
    })
}

/// Parses a vector `(x,y,z)`.
fn vector(path: &Path, field: &str, s: &str) -> Result<[f64; 3], ReadError> {
    let bad = || {
        ReadError::invalid(
            path,
            format!("'{field}' has a malformed vector {}", quote(s)),
        )
    };
    let inner = s
        .trim()
        .strip_prefix('(')
        .and_then(|t| t.strip_suffix(')'))
        .ok_or_else(bad)?;
    let v: Vec<f64> = inner
        .split(',')
        .map(|t| t.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| bad())?;
    v.try_into().map_err(|_| bad())
}

/// Splits `(a,b,c) (d,e,f) ...` into its vectors (or `none` words).
fn vector_list(s: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let mut depth = 0i32;
    for c in s.chars() {
        match c {
            '(' => {
                depth += 1;
                cur.push(c);
            }
            ')' => {
                depth -= 1;
                cur.push(c);
            }
            c if c.is_whitespace() && depth == 0 => {
                if !cur.is_empty() {
                    out.push(std::mem::take(&mut cur));
                }
            }
            c => cur.push(c),
        }
    }
    if !cur.is_empty() {
        out.push(cur);
    }
    out
}

/// Parses the header at the start of `bytes`: magic, fields, then each concern in turn
/// (sample layout, encoding, byte order, geometry, data location).
fn parse_header(path: &Path, bytes: &[u8]) -> Result<Header, ReadError> {
    check_magic(path, bytes)?;
    let fields = Fields::read_colon(path, bytes)?;
    let (ty, sizes) = sample_layout(path, &fields)?;
    let encoding = encoding(path, &fields)?;
    let endian = endian(path, &fields, ty, encoding)?;
    let (spacing, origin, direction) = geometry(path, &fields)?;
    let data_file = data_file(path, &fields)?;
    let (line_skip, byte_skip) = skips(path, &fields, encoding)?;
    if data_file.is_none()
        && path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("nhdr"))
    {
        return Err(ReadError::invalid(
            path,
            "detached header (.nhdr) has no 'data file' field",
        ));
    }
    Ok(Header {
        ty,
        sizes,
        encoding,
        endian,
        spacing,
        origin,
        direction,
        data_file,
        line_skip,
        byte_skip,
        data_start: fields.end(),
    })
}

/// Checks the `NRRD000n` magic and version.
fn check_magic(path: &Path, bytes: &[u8]) -> Result<(), ReadError> {
    if bytes.len() < 8 || &bytes[..4] != b"NRRD" {
        return Err(ReadError::invalid(path, "not an NRRD file (bad magic)"));
    }
    let version = &bytes[4..8];
    if !matches!(version, b"0001" | b"0002" | b"0003" | b"0004" | b"0005") {
        return Err(ReadError::unsupported(
            path,
            format!("NRRD version {}", quote(&String::from_utf8_lossy(version))),
        ));
    }
    Ok(())
}

/// The value of a required field.
fn require<'a>(path: &Path, fields: &'a Fields, name: &str) -> Result<&'a str, ReadError> {
    fields
        .get(name)
        .ok_or_else(|| ReadError::invalid(path, format!("header has no '{name}' field")))
}

/// `dimension` (must be 3), `type` and `sizes`.
fn sample_layout(path: &Path, fields: &Fields) -> Result<(SampleType, [usize; 3]), ReadError> {
    let dimension = require(path, fields, "dimension")?;
    if dimension != "3" {
        return Err(ReadError::unsupported(
            path,
            format!("dimension {} (only 3-D volumes are read)", quote(dimension)),
        ));
    }
    let ty_s = require(path, fields, "type")?;
    let ty = parse_type(ty_s)
        .ok_or_else(|| ReadError::unsupported(path, format!("type {}", quote(ty_s))))?;
    let sizes = header::sizes(path, "'sizes'", require(path, fields, "sizes")?)?;
    Ok((ty, sizes))
}

/// The `encoding` field.
fn encoding(path: &Path, fields: &Fields) -> Result<Encoding, ReadError> {
    let enc_s = require(path, fields, "encoding")?;
    match enc_s.to_ascii_lowercase().as_str() {
        "raw" => Ok(Encoding::Raw),
        "gzip" | "gz" => Ok(Encoding::Gzip),
        "ascii" | "text" | "txt" => Ok(Encoding::Ascii),
        _ => Err(ReadError::unsupported(
            path,
            format!("encoding {} (supported: raw, gzip, ascii)", quote(enc_s)),
        )),
    }
}

/// The `endian` field, required for multi-byte types stored in binary.
fn endian(
    path: &Path,
    fields: &Fields,
    ty: SampleType,
    encoding: Encoding,
) -> Result<Option<Endian>, ReadError> {
    let endian = match fields.get("endian").map(str::to_ascii_lowercase).as_deref() {
        None => None,
        Some("little") => Some(Endian::Little),
        Some("big") => Some(Endian::Big),
        Some(other) => {
            return Err(ReadError::invalid(
                path,
                format!("'endian' must be little or big, got {}", quote(other)),
            ))
        }
    };
    if endian.is_none() && ty.size() > 1 && encoding != Encoding::Ascii {
        return Err(ReadError::invalid(
            path,
            "header has no 'endian' field (needed for multi-byte types)",
        ));
    }
    Ok(endian)
}

/// Spacing, origin and direction from `space directions` (or `spacings`), `space origin`
/// and `space dimension` (must be 3 if present).
fn geometry(path: &Path, fields: &Fields) -> Result<Geometry, ReadError> {
    let (spacing, direction) = if let Some(sd) = fields.get("space directions") {
        space_directions(path, sd)?
    } else if let Some(sp) = fields.get("spacings") {
        (header::numbers::<3>(path, "'spacings'", sp)?, IDENTITY)
    } else {
        ([1.0; 3], IDENTITY)
    };
    let origin = match fields.get("space origin") {
        Some(o) => vector(path, "space origin", o)?,
        None => [0.0; 3],
    };
    if let Some(sdim) = fields.get("space dimension") {
        if sdim.trim() != "3" {
            return Err(ReadError::unsupported(
                path,
                format!("space dimension {} (only 3)", quote(sdim)),
            ));
        }
    }
    Ok((spacing, origin, direction))
}

/// Spacing and direction from the three vectors of `space directions`.
fn space_directions(path: &Path, sd: &str) -> Result<([f64; 3], [[f64; 3]; 3]), ReadError> {
    let vecs = vector_list(sd);
    if vecs.len() != 3 {
        return Err(ReadError::invalid(
            path,
            format!("'space directions' must hold 3 vectors, got {}", quote(sd)),
        ));
    }
    if vecs.iter().any(|v| v.eq_ignore_ascii_case("none")) {
        return Err(ReadError::unsupported(
            path,
            "'space directions' with a non-spatial ('none') axis",
        ));
    }
    let mut cols = [Vector3::zeros(); 3];
    for (col, v) in cols.iter_mut().zip(&vecs) {
        *col = Vector3::from(vector(path, "space directions", v)?);
    }
    split_linear(&Matrix3::from_columns(&cols)).ok_or_else(|| {
        ReadError::invalid(
            path,
            format!(
                "'space directions' has a zero or non-finite vector: {}",
                quote(sd)
            ),
        )
    })
}

/// The `data file` (or `datafile`) field: a single file, relative to the header.
fn data_file(path: &Path, fields: &Fields) -> Result<Option<PathBuf>, ReadError> {
    let Some(f) = fields.get("data file").or_else(|| fields.get("datafile")) else {
        return Ok(None);
    };
    if f.starts_with("LIST") || f.split_whitespace().count() > 1 {
        return Err(ReadError::unsupported(
            path,
            format!("multi-file data {}", quote(f)),
        ));
    }
    Ok(Some(header::data_file_path(path, f)))
}

/// `line skip` and `byte skip` (`-1` only with raw encoding).
fn skips(path: &Path, fields: &Fields, encoding: Encoding) -> Result<(u64, Skip), ReadError> {
    let line_skip = match fields.get("line skip").or_else(|| fields.get("lineskip")) {
        None => 0,
        Some(s) => header::count(path, "'line skip'", s)?,
    };
    let byte_skip = match fields.get("byte skip").or_else(|| fields.get("byteskip")) {
        None => Skip::Bytes(0),
        Some(s) => header::skip(path, "'byte skip'", s)?,
    };
    if byte_skip == Skip::FromEnd && encoding != Encoding::Raw {
        return Err(ReadError::invalid(
            path,
            "'byte skip: -1' is only allowed with raw encoding",
        ));
    }
    Ok((line_skip, byte_skip))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn type_aliases() {
        assert_eq!(parse_type("unsigned  char"), Some(SampleType::U8));
        assert_eq!(parse_type("short"), Some(SampleType::I16));
        assert_eq!(parse_type("ushort"), Some(SampleType::U16));
        assert_eq!(parse_type("signed int"), Some(SampleType::I32));
        assert_eq!(parse_type("uint32_t"), Some(SampleType::U32));
        assert_eq!(parse_type("double"), Some(SampleType::F64));
        assert_eq!(parse_type("block"), None);
    }

    #[test]
    fn vectors() {
        let p = Path::new("x.nrrd");
        assert_eq!(vector_list("(1,0,0) ( 0, 2,0)\t(0,0,3)").len(), 3);
        assert_eq!(vector(p, "v", "( 0, 2.5,-1)").unwrap(), [0.0, 2.5, -1.0]);
        assert!(vector(p, "v", "(0,2)").is_err());
        assert!(vector(p, "v", "0,2,3").is_err());
        assert_eq!(
            vector_list("none (1,0,0)"),
            vec!["none".to_string(), "(1,0,0)".to_string()]
        );
    }

    #[test]
    fn header_needs_endian_for_multibyte() {
        let h = b"NRRD0004\ntype: short\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n\n";
        let e = parse_header(Path::new("a.nrrd"), h).unwrap_err();
        assert!(e.to_string().contains("endian"), "{e}");
        let h = b"NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n\n";
        let hd = parse_header(Path::new("a.nrrd"), h).unwrap();
        assert_eq!(hd.data_start, Some(h.len()));
    }
}
