//! Text header fields shared by the NRRD (`key: value`) and MetaImage (`Key = Value`)
//! readers: a line splitter, the [`Fields`] reader for both syntaxes, and parsers for the
//! value kinds both formats use (number lists, sizes, counts, skips, data file names).
//!
//! Field names are matched case-insensitively; when a field appears more than once the
//! last occurrence wins. Error messages name a field as the caller shows it (`'sizes'` for
//! NRRD, `DimSize` for MetaImage).

use std::fs::File;
use std::io::{self, Read};
use std::path::{Path, PathBuf};

use super::read_common::{quote, ReadError, Skip};

/// The lines of `bytes`, split at `\n` with a trailing `\r` removed, each with the offset of
/// its first byte and the offset just past its line break. A final line break does not start
/// an empty line.
fn lines(bytes: &[u8]) -> impl Iterator<Item = (usize, &[u8], usize)> {
    let mut pos = 0usize;
    std::iter::from_fn(move || {
        if pos >= bytes.len() {
            return None;
        }
        let start = pos;
        let (line, next) = match bytes[pos..].iter().position(|&b| b == b'\n') {
            Some(n) => (&bytes[pos..pos + n], pos + n + 1),
            None => (&bytes[pos..], bytes.len()),
        };
        pos = next;
        Some((start, line.strip_suffix(b"\r").unwrap_or(line), next))
    })
}

/// The fields of a text header, in file order.
#[derive(Debug, Default)]
pub(crate) struct Fields {
    /// `(key, value)` pairs, both trimmed.
    list: Vec<(String, String)>,
    /// Offset of the first byte after the header, if the header's end was found.
    end: Option<usize>,
}

impl Fields {
    /// Reads a `key: value` header (NRRD). The first line (the magic) is skipped; `#` lines
    /// are comments; `key:=value` lines are key/value pairs, not fields, and are skipped;
    /// `key:` is a field with an empty value; the first empty line ends the header (and
    /// [`Fields::end`] is the offset after it).
    ///
    /// # Errors
    /// [`ReadError::Invalid`] for any other line without `": "`.
    pub(crate) fn read_colon(path: &Path, bytes: &[u8]) -> Result<Fields, ReadError> {
        let mut fields = Fields::default();
        for (_, line, next) in lines(bytes).skip(1) {
            if line.is_empty() {
                fields.end = Some(next);
                break;
            }
            if let Some((k, v)) = colon_field(line).map_err(|text| {
                ReadError::invalid(path, format!("malformed header line {}", quote(&text)))
            })? {
                fields.list.push((k, v));
            }
        }
        Ok(fields)
    }

    /// Reads a `Key = Value` header (MetaImage). Blank lines are skipped; the header ends
    /// after the field named `last` (case-insensitive; [`Fields::end`] is the offset after
    /// its line) or at the end of `bytes`.
    ///
    /// # Errors
    /// [`ReadError::Invalid`] for a line that is not UTF-8 text or has no `=`.
    pub(crate) fn read_equals(path: &Path, bytes: &[u8], last: &str) -> Result<Fields, ReadError> {
        let mut fields = Fields::default();
        for (start, line, next) in lines(bytes) {
            if line.iter().all(u8::is_ascii_whitespace) {
                continue;
            }
            let (k, v) = equals_field(path, start, line)?;
            let is_last = k.eq_ignore_ascii_case(last);
            fields.list.push((k, v));
            if is_last {
                fields.end = Some(next);
                break;
            }
        }
        Ok(fields)
    }

    /// The value of the last field named `name` (case-insensitive).
    pub(crate) fn get(&self, name: &str) -> Option<&str> {
        self.list
            .iter()
            .rev()
            .find(|(k, _)| k.eq_ignore_ascii_case(name))
            .map(|(_, v)| v.as_str())
    }

    /// The first of `names` that is present, with its value.
    pub(crate) fn get_any(&self, names: &[&'static str]) -> Option<(&'static str, &str)> {
        names.iter().find_map(|&n| self.get(n).map(|v| (n, v)))
    }

    /// Whether the header holds no field at all.
    pub(crate) fn is_empty(&self) -> bool {
        self.list.is_empty()
    }

    /// Offset of the first byte after the header, if its end marker was found.
    pub(crate) fn end(&self) -> Option<usize> {
        self.end
    }
}

/// Splits a non-empty `key: value` line: `Ok(None)` for comments and `key:=value` pairs,
/// `Err(line)` (as text) if the line is malformed.
fn colon_field(line: &[u8]) -> Result<Option<(String, String)>, String> {
    if line.starts_with(b"#") {
        return Ok(None);
    }
    let line = String::from_utf8_lossy(line);
    if line.contains(":=") && !line.contains(": ") {
        return Ok(None);
    }
    if let Some((k, v)) = line.split_once(": ") {
        Ok(Some((k.trim().to_string(), v.trim().to_string())))
    } else if let Some(k) = line.strip_suffix(':') {
        Ok(Some((k.trim().to_string(), String::new())))
    } else {
        Err(line.into_owned())
    }
}

/// Splits a `Key = Value` line that starts at byte `start` of the header.
fn equals_field(path: &Path, start: usize, line: &[u8]) -> Result<(String, String), ReadError> {
    let text = std::str::from_utf8(line).map_err(|_| {
        ReadError::invalid(
            path,
            format!("header line at byte {start} is not text (not a MetaImage header?)"),
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
    Ok((k.trim().to_string(), v.trim().to_string()))
}

/// Parses exactly `N` numbers separated by whitespace; `shown` names the field in the
/// message.
pub(crate) fn numbers<const N: usize>(
    path: &Path,
    shown: &str,
    value: &str,
) -> Result<[f64; N], ReadError> {
    let bad = || {
        ReadError::invalid(
            path,
            format!("{shown} must be {N} numbers, got {}", quote(value)),
        )
    };
    let v: Vec<f64> = value
        .split_whitespace()
        .map(str::parse::<f64>)
        .collect::<Result<_, _>>()
        .map_err(|_| bad())?;
    v.try_into().map_err(|_| bad())
}

/// Parses the three sizes of a 3-D volume (non-negative integers separated by whitespace).
pub(crate) fn sizes(path: &Path, shown: &str, value: &str) -> Result<[usize; 3], ReadError> {
    let v: Vec<usize> = value
        .split_whitespace()
        .map(str::parse::<usize>)
        .collect::<Result<_, _>>()
        .map_err(|_| {
            ReadError::invalid(
                path,
                format!(
                    "{shown} must be 3 non-negative integers, got {}",
                    quote(value)
                ),
            )
        })?;
    v.try_into().map_err(|_| {
        ReadError::invalid(
            path,
            format!("{shown} must be 3 integers, got {}", quote(value)),
        )
    })
}

/// Parses a non-negative integer.
pub(crate) fn count(path: &Path, shown: &str, value: &str) -> Result<u64, ReadError> {
    value.parse::<u64>().map_err(|_| {
        ReadError::invalid(
            path,
            format!(
                "{shown} must be a non-negative integer, got {}",
                quote(value)
            ),
        )
    })
}

/// Parses a byte skip: `-1` (the data are the last bytes) or a non-negative integer.
pub(crate) fn skip(path: &Path, shown: &str, value: &str) -> Result<Skip, ReadError> {
    if value == "-1" {
        return Ok(Skip::FromEnd);
    }
    let n = value.parse::<u64>().map_err(|_| {
        ReadError::invalid(
            path,
            format!(
                "{shown} must be -1 or a non-negative integer, got {}",
                quote(value)
            ),
        )
    })?;
    Ok(Skip::Bytes(n))
}

/// The start of the file `path`: its complete lines up to those for which `ended` holds
/// (called with every complete line read so far), or the whole file. Reads 64 KiB at a time,
/// so a header is read without the data after it.
///
/// # Errors
/// [`ReadError::Io`] if the file cannot be opened or read.
pub(crate) fn read_prefix(
    path: &Path,
    ended: impl Fn(&[u8]) -> bool,
) -> Result<Vec<u8>, ReadError> {
    let err = |e| ReadError::io(path, "cannot read file", e);
    let mut file = File::open(path).map_err(err)?;
    let mut buf = Vec::new();
    let mut chunk = vec![0u8; 1 << 16];
    loop {
        let n = match file.read(&mut chunk) {
            Ok(0) => return Ok(buf),
            Ok(n) => n,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(err(e)),
        };
        buf.extend_from_slice(&chunk[..n]);
        if let Some(last) = buf.iter().rposition(|&b| b == b'\n') {
            if ended(&buf[..=last]) {
                buf.truncate(last + 1);
                return Ok(buf);
            }
        }
    }
}

/// Whether `bytes` hold an empty line after the first (the end of a NRRD header).
pub(crate) fn has_blank_line(bytes: &[u8]) -> bool {
    lines(bytes).skip(1).any(|(_, line, _)| line.is_empty())
}

/// The path of a data file named in the header `header`: absolute as given, relative to the
/// header's folder otherwise.
pub(crate) fn data_file_path(header: &Path, name: &str) -> PathBuf {
    let p = Path::new(name);
    if p.is_absolute() {
        p.to_path_buf()
    } else {
        header.parent().unwrap_or_else(|| Path::new("")).join(p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p() -> &'static Path {
        Path::new("h.txt")
    }

    #[test]
    fn lines_strip_cr_and_report_offsets() {
        let l: Vec<_> = lines(b"ab\r\n\ncd").collect();
        assert_eq!(
            l,
            vec![(0, &b"ab"[..], 4), (4, &b""[..], 5), (5, &b"cd"[..], 7)]
        );
        assert_eq!(lines(b"x\n").count(), 1);
        assert_eq!(lines(b"").count(), 0);
    }

    #[test]
    fn colon_fields_comments_pairs_and_end() {
        let h = b"NRRD0004\n# a: comment\nType: uchar\nk:=v\nsizes:  2 3 4 \nempty:\n\nDATA";
        let f = Fields::read_colon(p(), h).unwrap();
        assert_eq!(f.get("type"), Some("uchar"));
        assert_eq!(f.get("SIZES"), Some("2 3 4"));
        assert_eq!(f.get("empty"), Some(""));
        assert_eq!(f.get("k"), None);
        assert_eq!(f.get("# a"), None);
        assert_eq!(f.end(), Some(h.len() - 4));
        // a line with both ":=" and ": " is a field
        let f = Fields::read_colon(p(), b"NRRD0004\nk:=a: b\n").unwrap();
        assert_eq!(f.get("k:=a"), Some("b"));
        assert_eq!(f.end(), None);
    }

    #[test]
    fn colon_duplicates_last_wins_and_malformed_lines() {
        let f = Fields::read_colon(p(), b"NRRD0004\ntype: short\nTYPE: float\n").unwrap();
        assert_eq!(f.get("type"), Some("float"));
        let e = Fields::read_colon(p(), b"NRRD0004\ntype=short\n").unwrap_err();
        assert_eq!(e.to_string(), "h.txt: malformed header line \"type=short\"");
        // "key:value" (no space) is malformed too
        assert!(Fields::read_colon(p(), b"NRRD0004\ntype:short\n").is_err());
        // the first line is never read as a field
        assert!(Fields::read_colon(p(), b"garbage\n").unwrap().is_empty());
    }

    #[test]
    fn equals_fields_blank_lines_and_last_key() {
        let h = b"NDims = 3\r\n\n  \nDimSize=2 2 2\nElementDataFile = LOCAL\nrest = 1\n";
        let f = Fields::read_equals(p(), h, "ElementDataFile").unwrap();
        assert_eq!(f.get("ndims"), Some("3"));
        assert_eq!(f.get("DimSize"), Some("2 2 2"));
        assert_eq!(f.get("elementdatafile"), Some("LOCAL"));
        assert_eq!(f.get("rest"), None);
        assert_eq!(f.end(), Some(h.len() - 9));
        assert_eq!(
            f.get_any(&["Offset", "DIMSIZE", "NDims"]),
            Some(("DIMSIZE", "2 2 2"))
        );
        let f = Fields::read_equals(p(), b"a = 1\nA = 2\nb = x = y\n", "z").unwrap();
        assert_eq!(f.get("a"), Some("2"));
        assert_eq!(f.get("b"), Some("x = y"));
        assert_eq!(f.end(), None);
        assert!(Fields::read_equals(p(), b"\n \n", "z").unwrap().is_empty());
    }

    #[test]
    fn equals_malformed_and_binary_lines() {
        let e = Fields::read_equals(p(), b"a = 1\nno separator\n", "z").unwrap_err();
        assert_eq!(
            e.to_string(),
            "h.txt: malformed header line \"no separator\" (expected Key = Value)"
        );
        let e = Fields::read_equals(p(), b"a = 1\n\xff = 2\n", "z").unwrap_err();
        assert_eq!(
            e.to_string(),
            "h.txt: header line at byte 6 is not text (not a MetaImage header?)"
        );
    }

    #[test]
    fn value_parsers() {
        assert_eq!(numbers::<2>(p(), "x", "1 -2.5").unwrap(), [1.0, -2.5]);
        let e = numbers::<3>(p(), "'spacings'", "1 2").unwrap_err();
        assert_eq!(
            e.to_string(),
            "h.txt: 'spacings' must be 3 numbers, got \"1 2\""
        );
        assert_eq!(sizes(p(), "s", "2 3  4").unwrap(), [2, 3, 4]);
        assert!(sizes(p(), "s", "2 -3 4")
            .unwrap_err()
            .to_string()
            .contains("non-negative"));
        assert!(sizes(p(), "s", "2 3").is_err());
        assert_eq!(count(p(), "c", "7").unwrap(), 7);
        assert!(count(p(), "c", "-1").is_err());
        assert_eq!(skip(p(), "s", "-1").unwrap(), Skip::FromEnd);
        assert_eq!(skip(p(), "s", "12").unwrap(), Skip::Bytes(12));
        assert!(skip(p(), "s", "-2").is_err());
    }

    #[test]
    fn data_files_are_relative_to_the_header() {
        let h = Path::new("/a/b/vol.nhdr");
        assert_eq!(data_file_path(h, "v.raw"), Path::new("/a/b/v.raw"));
        assert_eq!(data_file_path(h, "/c/v.raw"), Path::new("/c/v.raw"));
        assert_eq!(
            data_file_path(Path::new("vol.mhd"), "v.raw"),
            Path::new("v.raw")
        );
    }
}
