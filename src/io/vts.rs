//! VTK XML StructuredGrid (`.vts`) reader: a curvilinear grid with point-data scalars.
//!
//! Supported as VTK and ParaView write them: `format="ascii"`, `"binary"` (base64, inline)
//! and `"appended"` data (`encoding="raw"` or `"base64"`), uncompressed or compressed with
//! `compressor="vtkZLibDataCompressor"`, `header_type` `UInt32` or `UInt64`, either
//! `byte_order`, every numeric `type`. One piece. The points (`<Points>`, 3 components) give
//! the geometry; the field is the point-data array named by `field` (default: the first
//! single-component point-data array).

use std::path::Path;

use base64::Engine as _;
use quick_xml::events::{BytesStart, Event};

use super::volume::{decode_samples, decompress_exact, read_all, Endian, ReadError, SampleType};
use crate::grid::CurvilinearGrid;

/// How the file's binary arrays are stored.
#[derive(Clone, Copy)]
struct Encoding {
    endian: Endian,
    /// `UInt32` (4) or `UInt64` (8) headers.
    header: SampleType,
    compressed: bool,
}

/// One `<DataArray>`.
#[derive(Default)]
struct ArrayDesc {
    name: String,
    ty: Option<SampleType>,
    components: usize,
    format: String,
    offset: usize,
    text: String,
    /// Inside `<PointData>` (else inside `<Points>` or elsewhere).
    point_data: bool,
    points: bool,
}

/// The parsed XML part.
#[derive(Default)]
struct Parsed {
    encoding: Option<Encoding>,
    dims: Option<[usize; 3]>,
    arrays: Vec<ArrayDesc>,
    /// `(raw, start)`: the appended data's encoding and its first byte (after `_`).
    appended: Option<(bool, usize)>,
    pieces: usize,
}

fn attr(e: &BytesStart, key: &str) -> Option<String> {
    e.attributes()
        .flatten()
        .find(|a| a.key.as_ref() == key.as_bytes())
        .map(|a| String::from_utf8_lossy(&a.value).into_owned())
}

fn sample_type(path: &Path, t: &str) -> Result<SampleType, ReadError> {
    Ok(match t {
        "Int8" | "Char" => SampleType::I8,
        "UInt8" | "UnsignedChar" => SampleType::U8,
        "Int16" | "Short" => SampleType::I16,
        "UInt16" | "UnsignedShort" => SampleType::U16,
        "Int32" | "Int" => SampleType::I32,
        "UInt32" | "UnsignedInt" => SampleType::U32,
        "Int64" | "Long" | "LongLong" | "IdType" => SampleType::I64,
        "UInt64" | "UnsignedLong" | "UnsignedLongLong" => SampleType::U64,
        "Float32" | "Float" => SampleType::F32,
        "Float64" | "Double" => SampleType::F64,
        _ => {
            return Err(ReadError::unsupported(
                path,
                format!("DataArray type {t:?}"),
            ))
        }
    })
}

fn file_encoding(path: &Path, e: &BytesStart) -> Result<Encoding, ReadError> {
    if attr(e, "type").as_deref() != Some("StructuredGrid") {
        return Err(ReadError::invalid(path, "not a VTK StructuredGrid file"));
    }
    let endian = match attr(e, "byte_order").as_deref() {
        Some("BigEndian") => Endian::Big,
        _ => Endian::Little,
    };
    let header = match attr(e, "header_type").as_deref() {
        Some("UInt64") => SampleType::U64,
        None | Some("UInt32") => SampleType::U32,
        Some(t) => return Err(ReadError::unsupported(path, format!("header_type {t:?}"))),
    };
    let compressed = match attr(e, "compressor").as_deref() {
        None | Some("") => false,
        Some("vtkZLibDataCompressor") => true,
        Some(c) => return Err(ReadError::unsupported(path, format!("compressor {c:?}"))),
    };
    Ok(Encoding {
        endian,
        header,
        compressed,
    })
}

fn extent_dims(path: &Path, s: &str) -> Result<[usize; 3], ReadError> {
    let v: Vec<i64> = s
        .split_whitespace()
        .map(str::parse)
        .collect::<Result<_, _>>()
        .map_err(|_| ReadError::invalid(path, format!("bad WholeExtent {s:?}")))?;
    if v.len() != 6 {
        return Err(ReadError::invalid(path, format!("bad WholeExtent {s:?}")));
    }
    let d = |a: usize| {
        usize::try_from(v[2 * a + 1] - v[2 * a] + 1)
            .ok()
            .filter(|&n| n > 0)
    };
    match (d(0), d(1), d(2)) {
        (Some(x), Some(y), Some(z)) => Ok([x, y, z]),
        _ => Err(ReadError::invalid(path, format!("bad WholeExtent {s:?}"))),
    }
}

/// Handles a start (or empty) tag; `ctx` is (inside PointData, inside Points).
fn start_tag(
    path: &Path,
    e: &BytesStart,
    p: &mut Parsed,
    ctx: (bool, bool),
) -> Result<(), ReadError> {
    match e.name().as_ref() {
        b"VTKFile" => p.encoding = Some(file_encoding(path, e)?),
        b"StructuredGrid" => {
            let ext = attr(e, "WholeExtent")
                .ok_or_else(|| ReadError::invalid(path, "StructuredGrid has no WholeExtent"))?;
            p.dims = Some(extent_dims(path, &ext)?);
        }
        b"Piece" => p.pieces += 1,
        b"DataArray" => {
            let ty = attr(e, "type").unwrap_or_default();
            let offset = attr(e, "offset").unwrap_or_default();
            p.arrays.push(ArrayDesc {
                name: attr(e, "Name").unwrap_or_default(),
                ty: Some(sample_type(path, &ty)?),
                components: attr(e, "NumberOfComponents")
                    .map_or(Ok(1), |s| s.trim().parse())
                    .map_err(|_| ReadError::invalid(path, "bad NumberOfComponents"))?,
                format: attr(e, "format").unwrap_or_else(|| "ascii".into()),
                offset: if offset.is_empty() {
                    0
                } else {
                    offset
                        .trim()
                        .parse()
                        .map_err(|_| ReadError::invalid(path, "bad DataArray offset"))?
                },
                text: String::new(),
                point_data: ctx.0,
                points: ctx.1,
            });
        }
        _ => {}
    }
    Ok(())
}

/// Parses the XML up to (and including the position of) the appended data.
fn parse(path: &Path, bytes: &[u8]) -> Result<Parsed, ReadError> {
    let mut reader = quick_xml::Reader::from_reader(bytes);
    let mut p = Parsed::default();
    let (mut in_pd, mut in_points, mut in_array) = (false, false, false);
    // elements nested in a DataArray (VTK's <InformationKey>): their text is not data
    let mut nested = 0usize;
    let bad = |e: quick_xml::Error| ReadError::invalid(path, format!("malformed XML: {e}"));
    loop {
        match reader.read_event().map_err(bad)? {
            Event::Start(e) if in_array => {
                nested += 1;
                let _ = e;
            }
            Event::End(_) if in_array && nested > 0 => nested -= 1,
            Event::Start(e) => {
                match e.name().as_ref() {
                    b"PointData" => in_pd = true,
                    b"Points" => in_points = true,
                    b"DataArray" => in_array = true,
                    b"AppendedData" => {
                        let raw = attr(&e, "encoding").as_deref() == Some("raw");
                        let pos = reader.buffer_position() as usize;
                        let us = bytes[pos..]
                            .iter()
                            .position(|&b| b == b'_')
                            .ok_or_else(|| {
                                ReadError::invalid(path, "AppendedData has no '_' marker")
                            })?;
                        p.appended = Some((raw, pos + us + 1));
                        break;
                    }
                    _ => {}
                }
                start_tag(path, &e, &mut p, (in_pd, in_points))?;
            }
            Event::Empty(e) => start_tag(path, &e, &mut p, (in_pd, in_points))?,
            Event::Text(t) if in_array && nested == 0 => {
                if let Some(a) = p.arrays.last_mut() {
                    a.text.push_str(&String::from_utf8_lossy(&t));
                }
            }
            Event::End(e) => match e.name().as_ref() {
                b"PointData" => in_pd = false,
                b"Points" => in_points = false,
                b"DataArray" => in_array = false,
                _ => {}
            },
            Event::Eof => break,
            _ => {}
        }
    }
    Ok(p)
}

/// Reads a `.vts` file; `field` names the point-data array (default: the first scalar one).
///
/// # Errors
/// [`ReadError`] naming the file for malformed, truncated, inconsistent or unsupported
/// content, a missing field (the message lists the ones there are) or an invalid grid.
pub fn read_vts(path: &Path, field: Option<&str>) -> Result<CurvilinearGrid, ReadError> {
    let bytes = read_all(path)?;
    let p = parse(path, &bytes)?;
    let enc = p
        .encoding
        .ok_or_else(|| ReadError::invalid(path, "not a VTK XML file (no <VTKFile>)"))?;
    let dims = p
        .dims
        .ok_or_else(|| ReadError::invalid(path, "no <StructuredGrid WholeExtent=...>"))?;
    if p.pieces > 1 {
        return Err(ReadError::unsupported(path, "more than one Piece"));
    }
    let n = dims[0]
        .checked_mul(dims[1])
        .and_then(|v| v.checked_mul(dims[2]))
        .filter(|&v| v < (1 << 40))
        .ok_or_else(|| ReadError::invalid(path, format!("dimensions {dims:?} too large")))?;
    let src = Source {
        path,
        bytes: &bytes,
        enc,
        appended: p.appended,
        limit: std::cell::Cell::new(0),
    };
    let pts_desc = p
        .arrays
        .iter()
        .find(|a| a.points)
        .ok_or_else(|| ReadError::invalid(path, "no <Points> array"))?;
    let pts = src.values(pts_desc, 3 * n)?;
    let scalars: Vec<&ArrayDesc> = p
        .arrays
        .iter()
        .filter(|a| a.point_data && a.components == 1)
        .collect();
    let chosen = match field {
        Some(f) => scalars.iter().find(|a| a.name == f),
        None => scalars.first(),
    }
    .ok_or_else(|| ReadError::invalid(path, missing_field(&p.arrays, field)))?;
    let values = src.values(chosen, n)?;
    let points = pts.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    CurvilinearGrid::new(dims, values, points).map_err(|source| ReadError::Grid {
        file: path.display().to_string(),
        source,
    })
}

/// Why no point-data scalar (named `field`) was found: the scalars there are, or, when there
/// is none, the point-data arrays there are and that none is a scalar.
fn missing_field(arrays: &[ArrayDesc], field: Option<&str>) -> String {
    let what = field.map_or("no point-data scalar".to_string(), |f| {
        format!("no point-data scalar {f:?}")
    });
    let scalars: Vec<&str> = arrays
        .iter()
        .filter(|a| a.point_data && a.components == 1)
        .map(|a| a.name.as_str())
        .collect();
    if !scalars.is_empty() {
        return format!("{what}; the file has: {}", scalars.join(", "));
    }
    let others: Vec<String> = arrays
        .iter()
        .filter(|a| a.point_data)
        .map(|a| format!("{:?} ({} components)", a.name, a.components))
        .collect();
    if others.is_empty() {
        format!("{what}; the file has no point-data arrays")
    } else {
        format!(
            "{what}; the file's point-data arrays are not scalar: {}",
            others.join(", ")
        )
    }
}

/// Where the arrays' data come from.
struct Source<'a> {
    path: &'a Path,
    bytes: &'a [u8],
    enc: Encoding,
    appended: Option<(bool, usize)>,
    /// Bytes the array being decoded needs.
    limit: std::cell::Cell<usize>,
}

impl Source<'_> {
    /// The `count` values of array `a`.
    fn values(&self, a: &ArrayDesc, count: usize) -> Result<Vec<f64>, ReadError> {
        let ty = a.ty.expect("set when parsed");
        let what = format!("DataArray {:?}", a.name);
        self.limit.set(count.saturating_mul(ty.size()));
        let data = match a.format.as_str() {
            "ascii" => return self.ascii(a, count, &what),
            "binary" => self.base64_block(a.text.trim().as_bytes(), &what)?,
            "appended" => self.appended(a.offset, &what)?,
            f => {
                return Err(ReadError::unsupported(
                    self.path,
                    format!("{what}: format {f:?}"),
                ))
            }
        };
        let want = count * ty.size();
        if data.len() != want {
            return Err(ReadError::invalid(
                self.path,
                format!(
                    "{what} holds {} bytes, {count} values need {want}",
                    data.len()
                ),
            ));
        }
        Ok(decode_samples(&data, ty, self.enc.endian))
    }

    fn ascii(&self, a: &ArrayDesc, count: usize, what: &str) -> Result<Vec<f64>, ReadError> {
        let v: Vec<f64> = a
            .text
            .split_ascii_whitespace()
            .map(str::parse)
            .collect::<Result<_, _>>()
            .map_err(|_| ReadError::invalid(self.path, format!("{what}: not a number")))?;
        if v.len() != count {
            return Err(ReadError::invalid(
                self.path,
                format!("{what} has {} values, expected {count}", v.len()),
            ));
        }
        Ok(v)
    }

    fn appended(&self, offset: usize, what: &str) -> Result<Vec<u8>, ReadError> {
        let (raw, start) = self
            .appended
            .ok_or_else(|| ReadError::invalid(self.path, format!("{what}: no AppendedData")))?;
        let at = start.checked_add(offset).filter(|&s| s <= self.bytes.len());
        let rest = &self.bytes[at.ok_or_else(|| {
            ReadError::invalid(
                self.path,
                format!("{what}: offset past the end of the file"),
            )
        })?..];
        if raw {
            self.raw_block(rest, what)
        } else {
            let end = rest.iter().position(|&b| b == b'<').unwrap_or(rest.len());
            self.base64_block(&rest[..end], what)
        }
    }

    /// Header integer `i` of `b` (`usize::MAX` when `b` is too short: callers then report
    /// truncation through their checked arithmetic).
    fn header_int(&self, b: &[u8], i: usize) -> usize {
        let s = self.enc.header.size();
        if b.len() < (i + 1) * s {
            return usize::MAX;
        }
        decode_samples(&b[i * s..(i + 1) * s], self.enc.header, self.enc.endian)[0] as usize
    }

    fn truncated(&self, what: &str) -> ReadError {
        ReadError::invalid(self.path, format!("{what} is truncated"))
    }

    /// One raw appended array: header (byte count, or the compression header) and data.
    fn raw_block(&self, b: &[u8], what: &str) -> Result<Vec<u8>, ReadError> {
        let hs = self.enc.header.size();
        if !self.enc.compressed {
            let len = b
                .get(..hs)
                .map(|h| self.header_int(h, 0))
                .ok_or_else(|| self.truncated(what))?;
            return Ok(b
                .get(hs..hs.saturating_add(len))
                .ok_or_else(|| self.truncated(what))?
                .to_vec());
        }
        let nb = b
            .get(..hs)
            .map(|h| self.header_int(h, 0))
            .ok_or_else(|| self.truncated(what))?;
        let hlen = nb
            .checked_add(3)
            .and_then(|x| x.checked_mul(hs))
            .ok_or_else(|| self.truncated(what))?;
        let header = b.get(..hlen).ok_or_else(|| self.truncated(what))?;
        self.inflate(header, &b[hlen..], what)
    }

    /// One base64 array: the header is encoded on its own (compressed data, and VTK's
    /// appended base64 data) or together with the data (inline uncompressed binary).
    fn base64_block(&self, text: &[u8], what: &str) -> Result<Vec<u8>, ReadError> {
        let text: Vec<u8> = text
            .iter()
            .copied()
            .filter(|c| !c.is_ascii_whitespace())
            .collect();
        let hs = self.enc.header.size();
        let chars = |bytes: usize| bytes.div_ceil(3).saturating_mul(4);
        let dec = |t: &[u8]| {
            base64::engine::general_purpose::STANDARD
                .decode(t)
                .map_err(|e| ReadError::invalid(self.path, format!("{what}: bad base64: {e}")))
        };
        if !self.enc.compressed {
            let hc = chars(hs).min(text.len());
            if text[..hc].contains(&b'=') {
                let len = self.header_int(&dec(&text[..hc])?, 0);
                let end = hc.saturating_add(chars(len)).min(text.len());
                let data = dec(&text[hc..end])?;
                return data
                    .get(..len)
                    .map(<[u8]>::to_vec)
                    .ok_or_else(|| self.truncated(what));
            }
            // header and data in one stream
            let len = self.header_int(&dec(&text[..hc])?, 0);
            let end = len
                .checked_add(hs)
                .map(chars)
                .ok_or_else(|| self.truncated(what))?
                .min(text.len());
            return self.raw_block(&dec(&text[..end])?, what);
        }
        let first = dec(text
            .get(..chars(3 * hs))
            .ok_or_else(|| self.truncated(what))?)?;
        let nb = self.header_int(&first, 0);
        let hlen = nb
            .checked_add(3)
            .and_then(|x| x.checked_mul(hs))
            .ok_or_else(|| self.truncated(what))?;
        let hc = chars(hlen);
        let header = dec(text.get(..hc).ok_or_else(|| self.truncated(what))?)?;
        let header = &header[..hlen.min(header.len())];
        let total = (0..nb).try_fold(0usize, |s, i| {
            header
                .get((3 + i) * hs..(4 + i) * hs)
                .and_then(|b| s.checked_add(self.header_int(b, 0)))
        });
        let end = total
            .and_then(|t| hc.checked_add(chars(t)))
            .ok_or_else(|| self.truncated(what))?
            .min(text.len());
        self.inflate(header, &dec(&text[hc..end])?, what)
    }

    /// Decompresses zlib blocks described by a VTK compression header.
    fn inflate(&self, header: &[u8], data: &[u8], what: &str) -> Result<Vec<u8>, ReadError> {
        let hs = self.enc.header.size();
        if header.len() < 3 * hs {
            return Err(self.truncated(what));
        }
        let nb = self.header_int(header, 0);
        let block = self.header_int(header, 1);
        let last = self.header_int(header, 2);
        if nb.checked_add(3).and_then(|x| x.checked_mul(hs)) > Some(header.len()) {
            return Err(self.truncated(what));
        }
        // never inflate more than the array needs (a corrupt or hostile header)
        if nb.saturating_mul(block) > self.limit.get().saturating_add(block) {
            return Err(ReadError::invalid(
                self.path,
                format!("{what}: compression header declares more data than the array holds"),
            ));
        }
        let mut out = Vec::new();
        let mut pos = 0usize;
        for i in 0..nb {
            let clen = self.header_int(header, 3 + i);
            let chunk = pos
                .checked_add(clen)
                .and_then(|end| data.get(pos..end))
                .ok_or_else(|| self.truncated(what))?;
            pos += clen;
            let want = if i + 1 == nb && last != 0 {
                last
            } else {
                block
            };
            let r = flate2::read::ZlibDecoder::new(chunk);
            out.extend(decompress_exact(self.path, r, want, true, what)?);
        }
        Ok(out)
    }
}
