//! NRRD reader (`NRRD0001` to `NRRD0005`), attached (`.nrrd`) or detached (`.nhdr`) data.
//!
//! Supported: `dimension: 3`; types `(u)int8/16/32/64`, `float`, `double` and all their C
//! aliases; encodings `raw`, `gzip`/`gz` and `ascii`/`text`/`txt`; `endian`; `sizes`;
//! `spacings` or `space directions` (+ `space origin`); `data file` (a single file, relative
//! to the header); `line skip` and `byte skip` (including `-1` for raw data). The first axis
//! varies fastest and becomes x.

use std::path::{Path, PathBuf};

use flate2::read::MultiGzDecoder;

use super::volume::{
    build_grid, data_size, decode_samples, decompress_exact, quote, read_all, read_raw_range,
    split_linear, take_exact, Endian, ReadError, SampleType, Skip,
};
use crate::grid::{ScalarGrid, IDENTITY};

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

    let data: Vec<u8> = match (&header.data_file, header.encoding) {
        (Some(file), Encoding::Raw) if header.line_skip == 0 => {
            let (skip, exact) = if header.byte_skip_from_end {
                (Skip::FromEnd, false)
            } else {
                (Skip::Bytes(header.byte_skip.unwrap_or(0)), true)
            };
            read_raw_range(path, file, skip, nbytes, exact)?
        }
        (Some(file), _) => {
            let shown = file.display().to_string();
            let all = std::fs::read(file)
                .map_err(|e| ReadError::io(path, format!("cannot read data file {shown}"), e))?;
            extract(path, &header, &all, nbytes, &format!("data file {shown}"))?
        }
        (None, _) => {
            let start = header.data_start.ok_or_else(|| {
                ReadError::invalid(
                    path,
                    "header has no blank line ending it and no 'data file' field",
                )
            })?;
            extract(
                path,
                &header,
                &bytes[start..],
                nbytes,
                "the file after the header",
            )?
        }
    };

    let values = match header.encoding {
        Encoding::Ascii => parse_ascii(path, &data, count)?,
        _ => decode_samples(&data, header.ty, header.endian.unwrap_or(Endian::Little)),
    };
    build_grid(
        path,
        header.sizes,
        header.spacing,
        header.origin,
        header.direction,
        values,
    )
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
    byte_skip: Option<u64>,
    byte_skip_from_end: bool,
    /// Offset of the attached data, if the header ended with a blank line.
    data_start: Option<usize>,
}

/// Applies line skip, byte skip and decoding to a data block held in memory.
fn extract(
    path: &Path,
    h: &Header,
    block: &[u8],
    nbytes: usize,
    what: &str,
) -> Result<Vec<u8>, ReadError> {
    let mut block = block;
    for _ in 0..h.line_skip {
        let nl = block.iter().position(|&b| b == b'\n').ok_or_else(|| {
            ReadError::invalid(path, format!("'line skip' goes past the end of {what}"))
        })?;
        block = &block[nl + 1..];
    }
    match h.encoding {
        Encoding::Raw => {
            if h.byte_skip_from_end {
                let start = block.len().checked_sub(nbytes).ok_or_else(|| {
                    ReadError::invalid(
                        path,
                        format!(
                            "header says {nbytes} bytes of data but {what} holds {}",
                            block.len()
                        ),
                    )
                })?;
                return Ok(block[start..].to_vec());
            }
            let block = skip_bytes(path, block, h.byte_skip.unwrap_or(0), what)?;
            Ok(take_exact(path, block, nbytes, true, what)?.to_vec())
        }
        Encoding::Gzip => {
            // byte skip applies to the decompressed data
            let skip = usize::try_from(h.byte_skip.unwrap_or(0))
                .map_err(|_| ReadError::invalid(path, "'byte skip' is too large"))?;
            let want = nbytes
                .checked_add(skip)
                .ok_or_else(|| ReadError::invalid(path, "'byte skip' is too large"))?;
            let what = format!("gzip data in {what}");
            let data = decompress_exact(path, MultiGzDecoder::new(block), want, true, &what)?;
            Ok(data[skip..].to_vec())
        }
        Encoding::Ascii => Ok(skip_bytes(path, block, h.byte_skip.unwrap_or(0), what)?.to_vec()),
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

/// Parses numbers separated by whitespace.
fn numbers<const N: usize>(path: &Path, field: &str, value: &str) -> Result<[f64; N], ReadError> {
    let bad = || {
        ReadError::invalid(
            path,
            format!("'{field}' must be {N} numbers, got {}", quote(value)),
        )
    };
    let v: Vec<f64> = value
        .split_whitespace()
        .map(|t| t.parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| bad())?;
    v.try_into().map_err(|_| bad())
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

fn parse_header(path: &Path, bytes: &[u8]) -> Result<Header, ReadError> {
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

    let mut fields: Vec<(String, String)> = Vec::new();
    let mut pos = 0usize;
    let mut first = true;
    let mut data_start = None;
    while pos < bytes.len() {
        let (line, next) = match bytes[pos..].iter().position(|&b| b == b'\n') {
            Some(n) => (&bytes[pos..pos + n], pos + n + 1),
            None => (&bytes[pos..], bytes.len()),
        };
        pos = next;
        let line = line.strip_suffix(b"\r").unwrap_or(line);
        if first {
            first = false;
            continue; // magic line
        }
        if line.is_empty() {
            data_start = Some(pos);
            break;
        }
        if line.starts_with(b"#") {
            continue;
        }
        let line = String::from_utf8_lossy(line);
        if line.contains(":=") && !line.contains(": ") {
            continue; // key/value pair, not a field
        }
        if let Some((k, v)) = line.split_once(": ") {
            fields.push((k.trim().to_ascii_lowercase(), v.trim().to_string()));
        } else if let Some(k) = line.strip_suffix(':') {
            fields.push((k.trim().to_ascii_lowercase(), String::new()));
        } else {
            return Err(ReadError::invalid(
                path,
                format!("malformed header line {}", quote(&line)),
            ));
        }
    }
    let get = |name: &str| {
        fields
            .iter()
            .rev()
            .find(|(k, _)| k == name)
            .map(|(_, v)| v.as_str())
    };
    let require = |name: &str| {
        get(name).ok_or_else(|| ReadError::invalid(path, format!("header has no '{name}' field")))
    };

    let dimension = require("dimension")?;
    if dimension != "3" {
        return Err(ReadError::unsupported(
            path,
            format!("dimension {} (only 3-D volumes are read)", quote(dimension)),
        ));
    }
    let ty_s = require("type")?;
    let ty = parse_type(ty_s)
        .ok_or_else(|| ReadError::unsupported(path, format!("type {}", quote(ty_s))))?;
    let sizes_s = require("sizes")?;
    let sizes_v: Vec<usize> = sizes_s
        .split_whitespace()
        .map(|t| t.parse::<usize>())
        .collect::<Result<_, _>>()
        .map_err(|_| {
            ReadError::invalid(
                path,
                format!(
                    "'sizes' must be 3 non-negative integers, got {}",
                    quote(sizes_s)
                ),
            )
        })?;
    let sizes: [usize; 3] = sizes_v.try_into().map_err(|_| {
        ReadError::invalid(
            path,
            format!("'sizes' must be 3 integers, got {}", quote(sizes_s)),
        )
    })?;

    let enc_s = require("encoding")?;
    let encoding = match enc_s.to_ascii_lowercase().as_str() {
        "raw" => Encoding::Raw,
        "gzip" | "gz" => Encoding::Gzip,
        "ascii" | "text" | "txt" => Encoding::Ascii,
        _ => {
            return Err(ReadError::unsupported(
                path,
                format!("encoding {} (supported: raw, gzip, ascii)", quote(enc_s)),
            ))
        }
    };
    let endian = match get("endian").map(str::to_ascii_lowercase).as_deref() {
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

    // geometry
    let mut spacing = [1.0; 3];
    let mut direction = IDENTITY;
    let mut origin = [0.0; 3];
    if let Some(sd) = get("space directions") {
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
        let mut m = [[0.0; 3]; 3];
        for (c, v) in vecs.iter().enumerate() {
            let col = vector(path, "space directions", v)?;
            for r in 0..3 {
                m[r][c] = col[r];
            }
        }
        let (s, d) = split_linear(m).ok_or_else(|| {
            ReadError::invalid(
                path,
                format!(
                    "'space directions' has a zero or non-finite vector: {}",
                    quote(sd)
                ),
            )
        })?;
        spacing = s;
        direction = d;
    } else if let Some(sp) = get("spacings") {
        spacing = numbers::<3>(path, "spacings", sp)?;
    }
    if let Some(o) = get("space origin") {
        origin = vector(path, "space origin", o)?;
    }
    if let Some(sdim) = get("space dimension") {
        if sdim.trim() != "3" {
            return Err(ReadError::unsupported(
                path,
                format!("space dimension {} (only 3)", quote(sdim)),
            ));
        }
    }

    // data location
    let data_file_s = get("data file").or_else(|| get("datafile"));
    let data_file = match data_file_s {
        None => None,
        Some(f) => {
            if f.starts_with("LIST") || f.split_whitespace().count() > 1 {
                return Err(ReadError::unsupported(
                    path,
                    format!("multi-file data {}", quote(f)),
                ));
            }
            let p = Path::new(f);
            Some(if p.is_absolute() {
                p.to_path_buf()
            } else {
                path.parent().unwrap_or_else(|| Path::new("")).join(p)
            })
        }
    };
    let line_skip = match get("line skip").or_else(|| get("lineskip")) {
        None => 0,
        Some(s) => s.parse::<u64>().map_err(|_| {
            ReadError::invalid(
                path,
                format!(
                    "'line skip' must be a non-negative integer, got {}",
                    quote(s)
                ),
            )
        })?,
    };
    let (byte_skip, byte_skip_from_end) = match get("byte skip").or_else(|| get("byteskip")) {
        None => (None, false),
        Some("-1") => {
            if encoding != Encoding::Raw {
                return Err(ReadError::invalid(
                    path,
                    "'byte skip: -1' is only allowed with raw encoding",
                ));
            }
            (None, true)
        }
        Some(s) => (
            Some(s.parse::<u64>().map_err(|_| {
                ReadError::invalid(
                    path,
                    format!(
                        "'byte skip' must be -1 or a non-negative integer, got {}",
                        quote(s)
                    ),
                )
            })?),
            false,
        ),
    };
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
        byte_skip_from_end,
        data_start,
    })
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
