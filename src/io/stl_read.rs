//! STL surface reader, binary or ASCII (the twin of the writer in `stl.rs`).
//!
//! A file is binary when its size is exactly `84 + 50 n` bytes for the triangle count `n`
//! stored at byte 80; otherwise it is ASCII when it starts with `solid`, and a truncated or
//! padded binary file when it does not. Normals are ignored; corners are welded by their
//! exact coordinates ([`super::surface_read_common::finish`]).

use std::path::Path;

use super::read_common::{quote, read_all, ReadError};
use super::surface_read_common::{check_not_empty, fan, finish, TriSoup};

/// Reads a binary or ASCII STL file.
///
/// # Errors
/// One line naming the file: unreadable, empty, truncated, malformed numbers, no triangles,
/// a coordinate that is not finite.
pub fn read_stl_surface(path: &Path) -> Result<TriSoup, ReadError> {
    let bytes = read_all(path)?;
    check_not_empty(path, &bytes)?;
    if let Some(n) = binary_count(&bytes) {
        return parse_binary(path, &bytes, n);
    }
    let start = bytes.iter().position(|b| !b.is_ascii_whitespace());
    if start.is_some_and(|s| bytes[s..].starts_with(b"solid")) {
        return parse_ascii(path, &String::from_utf8_lossy(&bytes));
    }
    if bytes.len() < 84 {
        return Err(ReadError::invalid(
            path,
            format!(
                "not an STL file: {} bytes, shorter than a binary header and not ASCII STL",
                bytes.len()
            ),
        ));
    }
    let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]);
    let want = 84 + 50 * u64::from(n);
    Err(ReadError::invalid(
        path,
        format!(
            "binary STL of {n} triangles needs {want} bytes but the file holds {}{}",
            bytes.len(),
            if (bytes.len() as u64) < want {
                " (truncated)"
            } else {
                ""
            }
        ),
    ))
}

/// The triangle count of a binary STL whose size matches it exactly.
fn binary_count(bytes: &[u8]) -> Option<u32> {
    let head = bytes.get(80..84)?;
    let n = u32::from_le_bytes([head[0], head[1], head[2], head[3]]);
    (84 + 50 * u64::from(n) == bytes.len() as u64).then_some(n)
}

fn parse_binary(path: &Path, bytes: &[u8], n: u32) -> Result<TriSoup, ReadError> {
    let mut points = Vec::with_capacity(3 * n as usize);
    let mut triangles = Vec::with_capacity(n as usize);
    for rec in bytes[84..].chunks_exact(50) {
        let first = points.len() as u32;
        for c in 0..3 {
            let at = 12 + 12 * c;
            let coord = |a: usize| {
                let o = at + 4 * a;
                f64::from(f32::from_le_bytes([
                    rec[o],
                    rec[o + 1],
                    rec[o + 2],
                    rec[o + 3],
                ]))
            };
            points.push([coord(0), coord(1), coord(2)]);
        }
        triangles.push([first, first + 1, first + 2]);
    }
    finish(path, &points, &triangles)
}

fn parse_ascii(path: &Path, text: &str) -> Result<TriSoup, ReadError> {
    let mut points: Vec<[f64; 3]> = Vec::new();
    let mut triangles = Vec::new();
    let mut facet: Vec<u32> = Vec::new();
    let mut in_facet = false;
    for (n, line) in text.lines().enumerate() {
        let at = |msg: String| ReadError::invalid(path, format!("line {}: {msg}", n + 1));
        let mut words = line.split_whitespace();
        match words.next() {
            Some("facet") => {
                in_facet = true;
                facet.clear();
            }
            Some("vertex") => {
                if !in_facet {
                    return Err(at("vertex outside a facet".into()));
                }
                let mut p = [0.0; 3];
                for c in &mut p {
                    let w = words.next().unwrap_or("");
                    *c = w
                        .parse()
                        .map_err(|_| at(format!("bad coordinate {}", quote(w))))?;
                }
                facet.push(points.len() as u32);
                points.push(p);
            }
            Some("endfacet") => {
                if facet.len() < 3 {
                    return Err(at(format!("facet with {} vertices", facet.len())));
                }
                fan(&facet, &mut triangles);
                in_facet = false;
            }
            _ => {}
        }
    }
    if in_facet {
        return Err(ReadError::invalid(
            path,
            "truncated: the last facet has no endfacet",
        ));
    }
    finish(path, &points, &triangles)
}
