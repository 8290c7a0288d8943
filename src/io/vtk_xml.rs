//! The VTK XML file machinery shared by the `.vts` reader ([`super::vts`]) and the `.vtu`
//! reader ([`super::vtu_read`]): the `<DataArray>` descriptions of one `<Piece>`, and their
//! data in every encoding VTK and ParaView write — `format="ascii"`, `"binary"` (base64,
//! inline) and `"appended"` (`encoding="raw"` or `"base64"`), uncompressed or compressed
//! with `compressor="vtkZLibDataCompressor"`, `header_type` `UInt32` or `UInt64`, either
//! `byte_order`, every numeric `type`.

use std::path::Path;

use base64::Engine as _;
use quick_xml::events::{BytesStart, Event};

use super::read_common::{decode_samples, decompress_exact, Endian, ReadError, SampleType};

/// How the file's binary arrays are stored.
#[derive(Clone, Copy)]
pub(crate) struct Encoding {
    endian: Endian,
    /// `UInt32` (4) or `UInt64` (8) headers.
    header: SampleType,
    compressed: bool,
}

/// The element a `<DataArray>` is in.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) enum Section {
    /// `<PointData>`.
    PointData,
    /// `<CellData>`.
    CellData,
    /// `<Points>`.
    Points,
    /// `<Cells>` (connectivity, offsets, types).
    Cells,
    /// Anywhere else (`<FieldData>`, ...).
    #[default]
    Other,
}

/// One `<DataArray>`.
#[derive(Default)]
pub(crate) struct ArrayDesc {
    pub(crate) name: String,
    ty: Option<SampleType>,
    pub(crate) components: usize,
    format: String,
    offset: usize,
    text: String,
    /// Where it is.
    pub(crate) section: Section,
}

/// The parsed XML part.
#[derive(Default)]
pub(crate) struct Parsed {
    pub(crate) encoding: Option<Encoding>,
    /// `WholeExtent` of a `StructuredGrid`, as vertex counts.
    pub(crate) dims: Option<[usize; 3]>,
    /// `NumberOfPoints` and `NumberOfCells` of the (last) `<Piece>`.
    pub(crate) piece_counts: (Option<usize>, Option<usize>),
    pub(crate) arrays: Vec<ArrayDesc>,
    /// `(raw, start)`: the appended data's encoding and its first byte (after `_`).
    pub(crate) appended: Option<(bool, usize)>,
    pub(crate) pieces: usize,
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

fn file_encoding(path: &Path, e: &BytesStart, kind: &str) -> Result<Encoding, ReadError> {
    if attr(e, "type").as_deref() != Some(kind) {
        return Err(ReadError::invalid(path, format!("not a VTK {kind} file")));
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

/// A `NumberOfPoints` or `NumberOfCells` attribute of a `<Piece>`.
fn piece_count(path: &Path, e: &BytesStart, key: &str) -> Result<Option<usize>, ReadError> {
    attr(e, key)
        .map(|s| {
            s.trim()
                .parse()
                .map_err(|_| ReadError::invalid(path, format!("bad {key} {s:?}")))
        })
        .transpose()
}

/// Handles a start (or empty) tag of a file of type `kind`; `section`: where it is.
fn start_tag(
    path: &Path,
    e: &BytesStart,
    p: &mut Parsed,
    kind: &str,
    section: Section,
) -> Result<(), ReadError> {
    match e.name().as_ref() {
        b"VTKFile" => p.encoding = Some(file_encoding(path, e, kind)?),
        b"StructuredGrid" => {
            let ext = attr(e, "WholeExtent")
                .ok_or_else(|| ReadError::invalid(path, "StructuredGrid has no WholeExtent"))?;
            p.dims = Some(extent_dims(path, &ext)?);
        }
        b"Piece" => {
            p.pieces += 1;
            p.piece_counts = (
                piece_count(path, e, "NumberOfPoints")?,
                piece_count(path, e, "NumberOfCells")?,
            );
        }
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
                section,
            });
        }
        _ => {}
    }
    Ok(())
}

/// Parses the XML of a VTK file of type `kind` (`StructuredGrid`, `UnstructuredGrid`) up to
/// (and including the position of) the appended data.
pub(crate) fn parse(path: &Path, bytes: &[u8], kind: &str) -> Result<Parsed, ReadError> {
    let mut reader = quick_xml::Reader::from_reader(bytes);
    let mut p = Parsed::default();
    let mut section = Section::Other;
    let mut in_array = false;
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
                    b"PointData" => section = Section::PointData,
                    b"CellData" => section = Section::CellData,
                    b"Points" => section = Section::Points,
                    b"Cells" => section = Section::Cells,
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
                start_tag(path, &e, &mut p, kind, section)?;
            }
            Event::Empty(e) => start_tag(path, &e, &mut p, kind, section)?,
            Event::Text(t) if in_array && nested == 0 => {
                if let Some(a) = p.arrays.last_mut() {
                    a.text.push_str(&String::from_utf8_lossy(&t));
                }
            }
            Event::End(e) => match e.name().as_ref() {
                b"PointData" | b"CellData" | b"Points" | b"Cells" => section = Section::Other,
                b"DataArray" => in_array = false,
                _ => {}
            },
            Event::Eof => break,
            _ => {}
        }
    }
    Ok(p)
}

/// Where the arrays' data come from.
pub(crate) struct Source<'a> {
    path: &'a Path,
    bytes: &'a [u8],
    enc: Encoding,
    appended: Option<(bool, usize)>,
    /// Bytes the array being decoded needs.
    limit: std::cell::Cell<usize>,
}

impl<'a> Source<'a> {
    /// The arrays of the file `bytes` (read from `path`) as `p` describes them.
    ///
    /// # Errors
    /// Not a VTK XML file (no `<VTKFile>`).
    pub(crate) fn new(path: &'a Path, bytes: &'a [u8], p: &Parsed) -> Result<Self, ReadError> {
        let enc = p
            .encoding
            .ok_or_else(|| ReadError::invalid(path, "not a VTK XML file (no <VTKFile>)"))?;
        Ok(Source {
            path,
            bytes,
            enc,
            appended: p.appended,
            limit: std::cell::Cell::new(0),
        })
    }

    /// The `count` values of array `a`.
    pub(crate) fn values(&self, a: &ArrayDesc, count: usize) -> Result<Vec<f64>, ReadError> {
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
