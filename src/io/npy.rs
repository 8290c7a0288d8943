//! NumPy `.npy` reader (format versions 1.0, 2.0 and 3.0).
//!
//! Only 3-D arrays of plain numbers are accepted: dtypes `b1`, `u1`, `i1`, `u2`, `i2`, `u4`,
//! `i4`, `u8`, `i8`, `f4`, `f8` in either byte order, C or Fortran order. Array element
//! `[i, j, k]` becomes grid vertex `(x = i, y = j, z = k)`; the grid has unit spacing, zero
//! origin and identity direction.

use std::fs::File;
use std::io::{Read, Seek, SeekFrom};
use std::path::Path;

use super::read_common::{
    build_grid, data_size, quote, read_all, Endian, ReadError, SampleBuf, SampleType,
};
use crate::grid::{Samples, ScalarGrid, IDENTITY};

const MAGIC: &[u8] = b"\x93NUMPY";

/// Reads a NumPy `.npy` file holding a 3-D numeric array.
///
/// # Errors
/// [`ReadError::Io`] if the file cannot be read; [`ReadError::Invalid`] for a bad magic,
/// a malformed header, an array that is not 3-D or a data block whose size does not match
/// the shape; [`ReadError::Unsupported`] for other dtypes (structured, complex, half, ...);
/// [`ReadError::Grid`] for a dimension below 2 or a non-finite value.
pub fn read_npy(path: &Path) -> Result<ScalarGrid, ReadError> {
    let cannot = |e| ReadError::io(path, "cannot read file", e);
    let mut file = File::open(path).map_err(cannot)?;
    let size = file.metadata().map_err(cannot)?.len();
    let header = read_header(path, &mut file, size)?;
    let (count, nbytes) = data_size(path, header.shape, header.ty)?;
    let avail = size.saturating_sub(header.data_start as u64);
    if avail != nbytes as u64 {
        return Err(ReadError::invalid(
            path,
            format!("header says {nbytes} bytes of data but the file holds {avail}"),
        ));
    }
    file.seek(SeekFrom::Start(header.data_start as u64))
        .map_err(cannot)?;
    let values = if header.fortran_order {
        let mut buf = SampleBuf::new(path, header.ty, count)?;
        file.read_exact(buf.bytes_mut()).map_err(cannot)?;
        buf.finish(header.endian)
    } else {
        read_c_order(path, &mut file, &header, count)?
    };
    build_grid(path, header.shape, [1.0; 3], [0.0; 3], IDENTITY, values)
}

/// Bytes of a C-order file read at a time by [`read_c_order`].
const C_BLOCK_BYTES: usize = 64 << 20;

/// Reads C-order samples (element `[i, j, k]` at `(i * n1 + j) * n2 + k`) block by block of
/// `i` and scatters each block into x-fastest storage: memory is the grid plus one block.
fn read_c_order(
    path: &Path,
    file: &mut File,
    header: &NpyHeader,
    count: usize,
) -> Result<Samples, ReadError> {
    let [n0, n1, n2] = header.shape;
    let mut out = SampleBuf::new(path, header.ty, count)?.into_zeros();
    let plane = n1 * n2;
    if count == 0 {
        return Ok(out);
    }
    let per_block = (C_BLOCK_BYTES / (plane * header.ty.size()).max(1)).clamp(1, n0);
    for i0 in (0..n0).step_by(per_block) {
        let rows = per_block.min(n0 - i0);
        let mut buf = SampleBuf::new(path, header.ty, rows * plane)?;
        file.read_exact(buf.bytes_mut())
            .map_err(|e| ReadError::io(path, "cannot read file", e))?;
        scatter(&buf.finish(header.endian), &mut out, i0, header.shape);
    }
    Ok(out)
}

/// [`scatter_block`] in the samples' storage type (`out` and `block` share it).
fn scatter(block: &Samples, out: &mut Samples, i0: usize, shape: [usize; 3]) {
    match (block, out) {
        (Samples::U8(b), Samples::U8(o)) => scatter_block(b, o.to_mut(), i0, shape),
        (Samples::I16(b), Samples::I16(o)) => scatter_block(b, o.to_mut(), i0, shape),
        (Samples::U16(b), Samples::U16(o)) => scatter_block(b, o.to_mut(), i0, shape),
        (Samples::F32(b), Samples::F32(o)) => scatter_block(b, o.to_mut(), i0, shape),
        (Samples::F64(b), Samples::F64(o)) => scatter_block(b, o.to_mut(), i0, shape),
        _ => unreachable!("a block is read into the storage type of the grid"),
    }
}

/// Writes the C-order rows `i0..` in `block` to their places in the x-fastest `out`: eight
/// consecutive `k` at a time go to eight output planes, in parallel over the planes.
fn scatter_block<T: Copy + Send + Sync>(
    block: &[T],
    out: &mut [T],
    i0: usize,
    [n0, n1, n2]: [usize; 3],
) {
    use rayon::prelude::*;
    const KB: usize = 8;
    let plane = n0 * n1;
    let rows = block.len() / (n1 * n2);
    out.par_chunks_mut(plane * KB)
        .enumerate()
        .for_each(|(kb, chunk)| {
            let k0 = kb * KB;
            let kn = chunk.len() / plane;
            for di in 0..rows {
                for j in 0..n1 {
                    let src = &block[(di * n1 + j) * n2 + k0..][..kn];
                    for (dk, &x) in src.iter().enumerate() {
                        chunk[dk * plane + i0 + di + n0 * j] = x;
                    }
                }
            }
        });
}

/// Bytes read for the header at first (a header is a few hundred bytes).
const HEAD: u64 = 1 << 16;

/// The parsed header, from the first [`HEAD`] bytes (the whole file if the header is longer).
fn read_header(path: &Path, file: &mut File, size: u64) -> Result<NpyHeader, ReadError> {
    let mut head = Vec::new();
    Read::by_ref(file)
        .take(HEAD)
        .read_to_end(&mut head)
        .map_err(|e| ReadError::io(path, "cannot read file", e))?;
    match parse_npy(path, &head) {
        Err(_) if (head.len() as u64) < size => parse_npy(path, &read_all(path)?),
        r => r,
    }
}

/// The parsed `.npy` header.
#[derive(Debug, PartialEq)]
struct NpyHeader {
    ty: SampleType,
    endian: Endian,
    fortran_order: bool,
    shape: [usize; 3],
    data_start: usize,
}

/// Parses the magic, version and header dictionary at the start of `bytes`.
fn parse_npy(path: &Path, bytes: &[u8]) -> Result<NpyHeader, ReadError> {
    let (text, data_start) = header_text(path, bytes)?;
    let dict = parse_dict(text)
        .map_err(|m| ReadError::invalid(path, format!("malformed .npy header: {m}")))?;
    let (descr, fortran_order, shape) = dict_entries(path, dict)?;
    let (ty, endian) = parse_descr(&descr).ok_or_else(|| {
        ReadError::unsupported(
            path,
            format!(
                "dtype {} (supported: u1 i1 u2 i2 u4 i4 u8 i8 f4 f8 b1)",
                quote(&descr)
            ),
        )
    })?;
    let shape: [usize; 3] = shape.as_slice().try_into().map_err(|_| {
        ReadError::invalid(
            path,
            format!(
                "array is {}-D, a volume must be 3-D (shape {shape:?})",
                shape.len()
            ),
        )
    })?;
    Ok(NpyHeader {
        ty,
        endian,
        fortran_order,
        shape,
        data_start,
    })
}

/// Checks the magic and version and returns the header text with the offset of the data.
fn header_text<'a>(path: &Path, bytes: &'a [u8]) -> Result<(&'a str, usize), ReadError> {
    if bytes.len() < MAGIC.len() || &bytes[..MAGIC.len()] != MAGIC {
        return Err(ReadError::invalid(
            path,
            "not a NumPy .npy file (bad magic)",
        ));
    }
    let too_short = || ReadError::invalid(path, "file ends inside the .npy header");
    let major = *bytes.get(6).ok_or_else(too_short)?;
    let (len, start) = match major {
        1 => {
            let b = bytes.get(8..10).ok_or_else(too_short)?;
            (usize::from(u16::from_le_bytes([b[0], b[1]])), 10usize)
        }
        2 | 3 => {
            let b = bytes.get(8..12).ok_or_else(too_short)?;
            let n = u32::from_le_bytes([b[0], b[1], b[2], b[3]]);
            (usize::try_from(n).map_err(|_| too_short())?, 12usize)
        }
        v => {
            return Err(ReadError::unsupported(
                path,
                format!(".npy format version {v}"),
            ))
        }
    };
    let end = start.checked_add(len).ok_or_else(too_short)?;
    let text = bytes.get(start..end).ok_or_else(too_short)?;
    let text = std::str::from_utf8(text)
        .map_err(|_| ReadError::invalid(path, ".npy header is not text"))?;
    Ok((text, end))
}

/// The `descr`, `fortran_order` and `shape` entries of the header dictionary (all required,
/// nothing else allowed).
fn dict_entries(
    path: &Path,
    dict: Vec<(String, PyValue)>,
) -> Result<(String, bool, Vec<usize>), ReadError> {
    let mut descr = None;
    let mut fortran = None;
    let mut shape = None;
    for (k, v) in dict {
        match (k.as_str(), v) {
            ("descr", PyValue::Str(s)) => descr = Some(s),
            ("descr", PyValue::Other) => {
                return Err(ReadError::unsupported(
                    path,
                    "structured dtype (only plain numbers are read)",
                ))
            }
            ("fortran_order", PyValue::Bool(b)) => fortran = Some(b),
            ("shape", PyValue::Tuple(t)) => shape = Some(t),
            (key, _) => {
                return Err(ReadError::invalid(
                    path,
                    format!("malformed .npy header: bad entry {}", quote(key)),
                ))
            }
        }
    }
    let descr = descr.ok_or_else(|| ReadError::invalid(path, ".npy header has no 'descr'"))?;
    let fortran_order =
        fortran.ok_or_else(|| ReadError::invalid(path, ".npy header has no 'fortran_order'"))?;
    let shape = shape.ok_or_else(|| ReadError::invalid(path, ".npy header has no 'shape'"))?;
    Ok((descr, fortran_order, shape))
}

fn parse_descr(d: &str) -> Option<(SampleType, Endian)> {
    let mut chars = d.chars();
    let first = chars.next()?;
    let (endian, rest) = match first {
        '<' => (Endian::Little, chars.as_str()),
        '>' => (Endian::Big, chars.as_str()),
        '|' | '=' => (Endian::native(), chars.as_str()),
        _ => (Endian::native(), d),
    };
    let ty = match rest {
        "u1" | "b1" => SampleType::U8,
        "i1" => SampleType::I8,
        "u2" => SampleType::U16,
        "i2" => SampleType::I16,
        "u4" => SampleType::U32,
        "i4" => SampleType::I32,
        "u8" => SampleType::U64,
        "i8" => SampleType::I64,
        "f4" => SampleType::F32,
        "f8" => SampleType::F64,
        _ => return None,
    };
    // single-byte types are written with '|'; multi-byte ones must name a byte order
    if ty.size() > 1 && matches!(first, '|') {
        return None;
    }
    Some((ty, endian))
}

/// A value in the header dictionary.
#[derive(Debug, PartialEq)]
enum PyValue {
    Str(String),
    Bool(bool),
    Tuple(Vec<usize>),
    /// Anything else (a list, a nested dict, ...).
    Other,
}

/// Parses the Python dict literal of a `.npy` header: string keys; values that are strings,
/// booleans, tuples of non-negative integers, or (reported as `Other`) lists.
fn parse_dict(text: &str) -> Result<Vec<(String, PyValue)>, String> {
    let mut p = Parser {
        s: text.as_bytes(),
        pos: 0,
    };
    p.expect(b'{')?;
    let mut out = Vec::new();
    loop {
        p.ws();
        if p.eat(b'}') {
            break;
        }
        let key = p.string()?;
        p.ws();
        p.expect(b':')?;
        p.ws();
        let value = p.value()?;
        out.push((key, value));
        p.ws();
        if p.eat(b',') {
            continue;
        }
        p.ws();
        p.expect(b'}')?;
        break;
    }
    p.ws();
    if p.pos != p.s.len() {
        return Err("text after the dictionary".into());
    }
    Ok(out)
}

struct Parser<'a> {
    s: &'a [u8],
    pos: usize,
}

impl Parser<'_> {
    fn ws(&mut self) {
        while self.pos < self.s.len() && self.s[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
    }

    fn eat(&mut self, c: u8) -> bool {
        if self.s.get(self.pos) == Some(&c) {
            self.pos += 1;
            true
        } else {
            false
        }
    }

    fn expect(&mut self, c: u8) -> Result<(), String> {
        self.ws();
        if self.eat(c) {
            Ok(())
        } else {
            Err(format!("expected '{}' at byte {}", c as char, self.pos))
        }
    }

    fn string(&mut self) -> Result<String, String> {
        let q = match self.s.get(self.pos) {
            Some(&q @ (b'\'' | b'"')) => q,
            _ => return Err(format!("expected a quoted string at byte {}", self.pos)),
        };
        let start = self.pos + 1;
        let len = self.s[start..]
            .iter()
            .position(|&c| c == q)
            .ok_or_else(|| "unterminated string".to_string())?;
        self.pos = start + len + 1;
        Ok(String::from_utf8_lossy(&self.s[start..start + len]).into_owned())
    }

    fn value(&mut self) -> Result<PyValue, String> {
        match self.s.get(self.pos) {
            Some(b'\'' | b'"') => Ok(PyValue::Str(self.string()?)),
            Some(b'(') => self.tuple(),
            Some(b'[') => self.skip_list(),
            _ => {
                let rest = &self.s[self.pos..];
                if rest.starts_with(b"True") {
                    self.pos += 4;
                    Ok(PyValue::Bool(true))
                } else if rest.starts_with(b"False") {
                    self.pos += 5;
                    Ok(PyValue::Bool(false))
                } else {
                    Err(format!("unexpected value at byte {}", self.pos))
                }
            }
        }
    }

    /// A tuple of non-negative integers, starting at its `(`.
    fn tuple(&mut self) -> Result<PyValue, String> {
        self.pos += 1;
        let mut items = Vec::new();
        loop {
            self.ws();
            if self.eat(b')') {
                break;
            }
            items.push(self.integer()?);
            self.ws();
            if self.eat(b',') {
                continue;
            }
            self.expect(b')')?;
            break;
        }
        Ok(PyValue::Tuple(items))
    }

    /// Skips a list (a structured dtype), starting at its `[`, to the matching bracket.
    fn skip_list(&mut self) -> Result<PyValue, String> {
        let mut depth = 0usize;
        while let Some(&c) = self.s.get(self.pos) {
            self.pos += 1;
            match c {
                b'[' => depth += 1,
                b']' => {
                    depth -= 1;
                    if depth == 0 {
                        return Ok(PyValue::Other);
                    }
                }
                _ => {}
            }
        }
        Err("unterminated list".into())
    }

    fn integer(&mut self) -> Result<usize, String> {
        let start = self.pos;
        while self.pos < self.s.len() && self.s[self.pos].is_ascii_digit() {
            self.pos += 1;
        }
        let digits =
            std::str::from_utf8(&self.s[start..self.pos]).map_err(|_| "bad integer".to_string())?;
        let n = digits
            .parse::<usize>()
            .map_err(|_| format!("expected a non-negative integer at byte {start}"))?;
        // Python 2 long suffix
        if matches!(self.s.get(self.pos), Some(b'L' | b'l')) {
            self.pos += 1;
        }
        Ok(n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_typical_headers() {
        let d = parse_dict("{'descr': '<f4', 'fortran_order': False, 'shape': (4, 5, 6), }    \n")
            .unwrap();
        assert_eq!(d[0], ("descr".into(), PyValue::Str("<f4".into())));
        assert_eq!(d[1], ("fortran_order".into(), PyValue::Bool(false)));
        assert_eq!(d[2], ("shape".into(), PyValue::Tuple(vec![4, 5, 6])));
        let d = parse_dict("{\"shape\": (3L,), \"descr\": [('a', '<i4')]}").unwrap();
        assert_eq!(d[0].1, PyValue::Tuple(vec![3]));
        assert_eq!(d[1].1, PyValue::Other);
        assert!(parse_dict("{'shape': (-1, 2, 3)}").is_err());
        assert!(parse_dict("{'shape': (1, 2, 3)").is_err());
        assert!(parse_dict("").is_err());
    }

    #[test]
    fn c_order_reorder_matches_index_formula() {
        let dims = [3, 5, 19];
        let raw: Vec<f64> = (0..dims[0] * dims[1] * dims[2]).map(|x| x as f64).collect();
        let plane = dims[1] * dims[2];
        // The whole array as one block, and one row of `i` per block.
        let mut whole = vec![-1.0; raw.len()];
        scatter_block(&raw, &mut whole, 0, dims);
        let mut v = vec![-1.0; raw.len()];
        for i0 in 0..dims[0] {
            scatter_block(&raw[i0 * plane..(i0 + 1) * plane], &mut v, i0, dims);
        }
        assert_eq!(whole, v);
        for k in 0..dims[2] {
            for j in 0..dims[1] {
                for i in 0..dims[0] {
                    assert_eq!(
                        v[i + dims[0] * (j + dims[1] * k)],
                        raw[(i * dims[1] + j) * dims[2] + k]
                    );
                }
            }
        }
    }

    #[test]
    fn descr_table() {
        assert_eq!(parse_descr("<u2"), Some((SampleType::U16, Endian::Little)));
        assert_eq!(parse_descr(">f8"), Some((SampleType::F64, Endian::Big)));
        assert_eq!(parse_descr("|u1").map(|d| d.0), Some(SampleType::U8));
        assert_eq!(parse_descr("<c8"), None);
        assert_eq!(parse_descr("<f2"), None);
        assert_eq!(parse_descr("|f4"), None);
    }
}
