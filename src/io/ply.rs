//! Stanford `.ply` writer for isosurfaces ([`TriSurface`]), binary little-endian (default)
//! or ASCII.
//!
//! Elements: `vertex` with `double x, y, z, value` (the field), `face` with
//! `list uchar int vertex_indices` (counter-clockwise seen from the side of increasing f) and
//! `uchar label` (0 alpha, 1 beta, 2 box, as [`crate::mesh::BoundaryLabel`]).

use std::io::{self, Write};

use super::write_common::{check_surface, invalid, TextOut};
use crate::mesh::TriSurface;

fn header(s: &TriSurface, ascii: bool) -> String {
    let format = if ascii {
        "ascii"
    } else {
        "binary_little_endian"
    };
    format!(
        "ply\nformat {format} 1.0\ncomment tptd isosurface, normals towards increasing f\n\
         comment face label: 0 = alpha, 1 = beta, 2 = box\n\
         element vertex {}\nproperty double x\nproperty double y\nproperty double z\n\
         property double value\nelement face {}\nproperty list uchar int vertex_indices\n\
         property uchar label\nend_header\n",
        s.points.len(),
        s.triangles.len()
    )
}

/// Writes `s` as PLY to `w`: binary little-endian, or ASCII when `ascii`.
///
/// # Errors
/// The first error of `w`; [`io::ErrorKind::InvalidInput`] for an inconsistent surface or
/// more than `i32::MAX` points.
pub fn write_ply(s: &TriSurface, w: &mut dyn Write, ascii: bool) -> io::Result<()> {
    check_surface(s)?;
    if s.points.len() > i32::MAX as usize {
        return Err(invalid(format!(
            "{} points exceed PLY's int",
            s.points.len()
        )));
    }
    w.write_all(header(s, ascii).as_bytes())?;
    if ascii {
        write_ascii(s, w)
    } else {
        write_binary(s, w)
    }
}

fn write_ascii(s: &TriSurface, w: &mut dyn Write) -> io::Result<()> {
    let mut out = TextOut::new(w);
    for (p, &v) in s.points.iter().zip(&s.values) {
        out.float(p[0]).s(" ").float(p[1]).s(" ").float(p[2]);
        out.s(" ").float(v);
        out.nl()?;
    }
    for (t, &l) in s.triangles.iter().zip(&s.labels) {
        out.s("3 ").int(t[0]).s(" ").int(t[1]).s(" ").int(t[2]);
        out.s(" ").int(l as u8);
        out.nl()?;
    }
    out.finish()
}

fn write_binary(s: &TriSurface, w: &mut dyn Write) -> io::Result<()> {
    const CHUNK: usize = 1 << 16;
    let mut buf = Vec::with_capacity(CHUNK + 64);
    for (p, &v) in s.points.iter().zip(&s.values) {
        for x in [p[0], p[1], p[2], v] {
            buf.extend_from_slice(&x.to_le_bytes());
        }
        if buf.len() >= CHUNK {
            w.write_all(&buf)?;
            buf.clear();
        }
    }
    for (t, &l) in s.triangles.iter().zip(&s.labels) {
        buf.push(3);
        for i in t {
            buf.extend_from_slice(&(*i as i32).to_le_bytes());
        }
        buf.push(l as u8);
        if buf.len() >= CHUNK {
            w.write_all(&buf)?;
            buf.clear();
        }
    }
    w.write_all(&buf)?;
    w.flush()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::BoundaryLabel;

    #[test]
    fn binary_layout() {
        let s = TriSurface {
            points: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            values: vec![0.5; 3],
            triangles: vec![[0, 1, 2]],
            labels: vec![BoundaryLabel::Beta],
        };
        let mut b = Vec::new();
        write_ply(&s, &mut b, false).unwrap();
        let h = header(&s, false).len();
        assert_eq!(b.len(), h + 3 * 32 + 1 + 12 + 1);
        assert_eq!(&b[h + 32..h + 40], &1.0f64.to_le_bytes());
        assert_eq!(b[b.len() - 1], 1);
        let mut a = Vec::new();
        write_ply(&s, &mut a, true).unwrap();
        assert!(String::from_utf8(a)
            .unwrap()
            .ends_with("0 0 0 0.5\n1 0 0 0.5\n0 1 0 0.5\n3 0 1 2 1\n"));
    }
}
