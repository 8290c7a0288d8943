//! STL writer for isosurfaces ([`TriSurface`]), binary (default) or ASCII.
//!
//! STL has no shared vertices and no labels: every triangle is written with its unit normal
//! (towards increasing f) and its three corners (counter-clockwise seen from the normal), in
//! single precision for binary STL (the format's only type), shortest round-trip decimals in
//! ASCII. Binary: 80-byte header, `u32` triangle count, 50 bytes per triangle.

use std::io::{self, Write};

use super::write_common::{check_surface, invalid, unit_normal, TextOut};
use crate::mesh::TriSurface;

/// Writes `s` as STL to `w`: binary, or ASCII when `ascii`.
///
/// # Errors
/// The first error of `w`; [`io::ErrorKind::InvalidInput`] for an inconsistent surface or
/// more than `u32::MAX` triangles.
pub fn write_stl(s: &TriSurface, w: &mut dyn Write, ascii: bool) -> io::Result<()> {
    check_surface(s)?;
    if ascii {
        write_ascii(s, w)
    } else {
        write_binary(s, w)
    }
}

fn write_ascii(s: &TriSurface, w: &mut dyn Write) -> io::Result<()> {
    let mut out = TextOut::new(w);
    out.s("solid tptd");
    out.nl()?;
    for &t in &s.triangles {
        let n = unit_normal(s, t);
        out.s("facet normal ").vec3(n);
        out.nl()?;
        out.s(" outer loop");
        out.nl()?;
        for i in t {
            let p = s.points[i as usize];
            out.s("  vertex ").vec3(p);
            out.nl()?;
        }
        out.s(" endloop");
        out.nl()?;
        out.s("endfacet");
        out.nl()?;
    }
    out.s("endsolid tptd");
    out.nl()?;
    out.finish()
}

fn write_binary(s: &TriSurface, w: &mut dyn Write) -> io::Result<()> {
    const CHUNK: usize = 1 << 16;
    let count = u32::try_from(s.triangles.len())
        .map_err(|_| invalid(format!("{} triangles exceed STL's u32", s.triangles.len())))?;
    let mut head = [b' '; 80];
    let text = b"tptd isosurface, binary STL, normals towards increasing f";
    head[..text.len()].copy_from_slice(text);
    w.write_all(&head)?;
    w.write_all(&count.to_le_bytes())?;
    let mut buf = Vec::with_capacity(CHUNK + 64);
    for &t in &s.triangles {
        let n = unit_normal(s, t);
        let corners = t.map(|i| s.points[i as usize]);
        for x in n.iter().chain(corners.iter().flatten()) {
            buf.extend_from_slice(&(*x as f32).to_le_bytes());
        }
        buf.extend_from_slice(&0u16.to_le_bytes());
        if buf.len() >= CHUNK {
            w.write_all(&buf)?;
            buf.clear();
        }
    }
    w.write_all(&buf)?;
    w.flush()
}
