//! Stanford `.ply` surface reader (the twin of the writer in `ply.rs`): ASCII, binary
//! little-endian and binary big-endian.
//!
//! Of the `vertex` element only `x`, `y`, `z` are kept (any scalar type), of the `face`
//! element only the list `vertex_indices` (or `vertex_index`); polygons are fan-triangulated.
//! Every other property and element is read past. Counts in the header are never trusted for
//! allocation: storage grows with what the file actually holds.

use std::path::Path;

use super::read_common::{quote, read_all, ReadError};
use super::surface_read_common::{check_not_empty, fan, finish, TriSoup};

/// A scalar type of a PLY property.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn of(name: &str) -> Option<Scalar> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }
}

/// A property: a scalar, or a list with its count type.
#[derive(Clone, Debug)]
struct Property {
    name: String,
    ty: Scalar,
    list_count: Option<Scalar>,
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: u64,
    props: Vec<Property>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Encoding {
    Ascii,
    Little,
    Big,
}

/// Reads an ASCII or binary `.ply` surface.
///
/// # Errors
/// One line naming the file: unreadable, empty, malformed or truncated header or body, no
/// triangles, an index out of range, a coordinate that is not finite.
pub fn read_ply_surface(path: &Path) -> Result<TriSoup, ReadError> {
    let bytes = read_all(path)?;
    check_not_empty(path, &bytes)?;
    let (encoding, elements, body) = parse_header(path, &bytes)?;
    let mut src = Body {
        bytes: &bytes[body..],
        at: 0,
        encoding,
    };
    let mut points = Vec::new();
    let mut triangles = Vec::new();
    let mut poly = Vec::new();
    for e in &elements {
        let xyz = ["x", "y", "z"].map(|n| e.props.iter().position(|p| p.name == n));
        let faces = e.props.iter().position(|p| {
            p.list_count.is_some() && matches!(p.name.as_str(), "vertex_indices" | "vertex_index")
        });
        if e.name == "vertex" && xyz.contains(&None) {
            return Err(ReadError::invalid(
                path,
                "the vertex element lacks x, y or z",
            ));
        }
        if e.props.is_empty() {
            continue;
        }
        for row in 0..e.count {
            let bad = |m: String| ReadError::invalid(path, format!("{} {}: {m}", e.name, row + 1));
            let mut p = [0.0; 3];
            for (k, prop) in e.props.iter().enumerate() {
                let Some(count_ty) = prop.list_count else {
                    let v = src.scalar(prop.ty).map_err(bad)?;
                    if let Some(a) = xyz.iter().position(|&i| i == Some(k)) {
                        p[a] = v;
                    }
                    continue;
                };
                let n = src.count(count_ty).map_err(bad)?;
                poly.clear();
                for _ in 0..n {
                    let v = src.scalar(prop.ty).map_err(bad)?;
                    if faces == Some(k) {
                        poly.push(to_index(v).map_err(bad)?);
                    }
                }
                if faces == Some(k) {
                    fan(&poly, &mut triangles);
                }
            }
            if e.name == "vertex" {
                points.push(p);
            }
        }
    }
    if elements.iter().any(|e| e.name == "vertex") && points.is_empty() {
        return Err(ReadError::invalid(path, "the file has no vertices"));
    }
    finish(path, &points, &triangles)
}

/// A list entry as a point index.
fn to_index(v: f64) -> Result<u32, String> {
    if v >= 0.0 && v <= f64::from(u32::MAX - 1) && v.fract() == 0.0 {
        Ok(v as u32)
    } else {
        Err(format!("vertex index {v} is not a valid index"))
    }
}

/// The encoding, the elements and the offset of the body.
fn parse_header(path: &Path, bytes: &[u8]) -> Result<(Encoding, Vec<Element>, usize), ReadError> {
    let bad = |m: String| ReadError::invalid(path, format!("header: {m}"));
    if !bytes.starts_with(b"ply") {
        return Err(bad("the file does not start with \"ply\"".into()));
    }
    let end = find(bytes, b"end_header")
        .ok_or_else(|| bad("no end_header line (not a PLY file, or truncated)".into()))?;
    let body = match bytes[end + 10..].iter().position(|&b| b == b'\n') {
        Some(nl) => end + 10 + nl + 1,
        None => bytes.len(),
    };
    let text = String::from_utf8_lossy(&bytes[..end]);
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    for line in text.lines().skip(1) {
        let w: Vec<&str> = line.split_whitespace().collect();
        match w.as_slice() {
            ["format", f, ..] => {
                encoding = Some(match *f {
                    "ascii" => Encoding::Ascii,
                    "binary_little_endian" => Encoding::Little,
                    "binary_big_endian" => Encoding::Big,
                    _ => return Err(bad(format!("unknown format {}", quote(f)))),
                })
            }
            ["element", name, count] => elements.push(Element {
                name: (*name).to_string(),
                count: count
                    .parse()
                    .map_err(|_| bad(format!("bad element count {}", quote(count))))?,
                props: Vec::new(),
            }),
            ["property", rest @ ..] => {
                let e = elements
                    .last_mut()
                    .ok_or_else(|| bad("property before any element".into()))?;
                e.props.push(parse_property(rest).map_err(bad)?);
            }
            [] | ["comment" | "obj_info", ..] => {}
            _ => return Err(bad(format!("unexpected line {}", quote(line)))),
        }
    }
    let encoding = encoding.ok_or_else(|| bad("no format line".into()))?;
    Ok((encoding, elements, body))
}

fn parse_property(w: &[&str]) -> Result<Property, String> {
    let ty = |t: &str| Scalar::of(t).ok_or_else(|| format!("unknown property type {}", quote(t)));
    match w {
        ["list", count, item, name] => Ok(Property {
            name: (*name).to_string(),
            ty: ty(item)?,
            list_count: Some(ty(count)?),
        }),
        [t, name] => Ok(Property {
            name: (*name).to_string(),
            ty: ty(t)?,
            list_count: None,
        }),
        _ => Err(format!("malformed property line {}", quote(&w.join(" ")))),
    }
}

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

/// The body being read: a cursor over bytes, or over whitespace-separated ASCII words.
struct Body<'a> {
    bytes: &'a [u8],
    at: usize,
    encoding: Encoding,
}

impl Body<'_> {
    /// The next value of type `ty`.
    fn scalar(&mut self, ty: Scalar) -> Result<f64, String> {
        if self.encoding == Encoding::Ascii {
            let w = self.word()?;
            return w
                .parse::<f64>()
                .map_err(|_| format!("bad number {}", quote(w)));
        }
        let n = ty.size();
        let raw = self
            .bytes
            .get(self.at..self.at + n)
            .ok_or_else(|| "truncated: the file ends inside the data".to_string())?;
        self.at += n;
        let mut b = [0u8; 8];
        b[..n].copy_from_slice(raw);
        if self.encoding == Encoding::Big {
            b[..n].reverse();
        }
        Ok(match ty {
            Scalar::I8 => f64::from(b[0] as i8),
            Scalar::U8 => f64::from(b[0]),
            Scalar::I16 => f64::from(i16::from_le_bytes([b[0], b[1]])),
            Scalar::U16 => f64::from(u16::from_le_bytes([b[0], b[1]])),
            Scalar::I32 => f64::from(i32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Scalar::U32 => f64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Scalar::F32 => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Scalar::F64 => f64::from_le_bytes(b),
        })
    }

    /// A list length.
    fn count(&mut self, ty: Scalar) -> Result<usize, String> {
        let v = self.scalar(ty)?;
        if v >= 0.0 && v.fract() == 0.0 && v <= 1e9 {
            Ok(v as usize)
        } else {
            Err(format!("bad list length {v}"))
        }
    }

    fn word(&mut self) -> Result<&str, String> {
        let rest = &self.bytes[self.at..];
        let start = rest
            .iter()
            .position(|b| !b.is_ascii_whitespace())
            .ok_or_else(|| "truncated: the file ends inside the data".to_string())?;
        let len = rest[start..]
            .iter()
            .position(u8::is_ascii_whitespace)
            .unwrap_or(rest.len() - start);
        self.at += start + len;
        std::str::from_utf8(&rest[start..start + len])
            .map_err(|_| "bad number (not text)".to_string())
    }
}
