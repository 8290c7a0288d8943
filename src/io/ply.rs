//! Stanford `.ply` writer for isosurfaces ([`TriSurface`]), binary little-endian (default)
//! or ASCII.
//!
//! Elements: `vertex` with `double x, y, z, value` (the field) and `uchar label`, `face` with
//! `list uchar int vertex_indices` (counter-clockwise seen from the side of increasing f).
//!
//! The label is a vertex property (0 alpha, 1 beta, 2 box, as
//! [`crate::mesh::BoundaryLabel::code`]; for several levels 0 to n - 1 the levels and n the
//! box, as the header's comment says): the smallest label of the vertex's triangles. A face lies on
//! level alpha (beta) exactly when its three vertices have label 0 (1); every other face is a
//! cap on the grid box. (A clipped box face always keeps a vertex inside the interval, and no
//! point lies on both levels, so no cap has three vertices of one level.) The label is not a
//! face property because meshio's binary PLY reader cannot read scalar face properties.

use std::io::{self, Write};

use super::write_common::{check_surface, invalid, TextOut};
use crate::mesh::TriSurface;

/// What the vertex labels mean: `0 = alpha, 1 = beta, 2 = box`, or for several levels
/// `0 = level1, ..., n = box`.
fn label_legend(s: &TriSurface) -> String {
    let n = s.level_count();
    let parts: Vec<String> = crate::mesh::BoundaryLabel::of_levels(n)
        .map(|l| format!("{} = {}", l.code(n), l.name_in(n)))
        .collect();
    parts.join(", ")
}

fn header(s: &TriSurface, ascii: bool) -> String {
    let format = if ascii {
        "ascii"
    } else {
        "binary_little_endian"
    };
    format!(
        "ply\nformat {format} 1.0\ncomment tptd isosurface, normals towards increasing f\n\
         comment vertex label: {}; a face is on a level iff its 3 vertices are\n\
         element vertex {}\nproperty double x\nproperty double y\nproperty double z\n\
         property double value\nproperty uchar label\nelement face {}\n\
         property list uchar int vertex_indices\nend_header\n",
        label_legend(s),
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
    let labels = vertex_labels(s);
    if ascii {
        write_ascii(s, &labels, w)
    } else {
        write_binary(s, &labels, w)
    }
}

/// Per vertex, the smallest label of its triangles.
fn vertex_labels(s: &TriSurface) -> Vec<u8> {
    let mut l = vec![u8::MAX; s.points.len()];
    for (t, &label) in s.triangles.iter().zip(&s.labels) {
        for &i in t {
            l[i as usize] = l[i as usize].min(label.code(s.level_count()) as u8);
        }
    }
    l
}

fn write_ascii(s: &TriSurface, labels: &[u8], w: &mut dyn Write) -> io::Result<()> {
    let mut out = TextOut::new(w);
    for ((p, &v), &l) in s.points.iter().zip(&s.values).zip(labels) {
        out.vec3(*p);
        out.s(" ").float(v).s(" ").int(l);
        out.nl()?;
    }
    for t in &s.triangles {
        out.s("3 ").int(t[0]).s(" ").int(t[1]).s(" ").int(t[2]);
        out.nl()?;
    }
    out.finish()
}

fn write_binary(s: &TriSurface, labels: &[u8], w: &mut dyn Write) -> io::Result<()> {
    const CHUNK: usize = 1 << 16;
    let mut buf = Vec::with_capacity(CHUNK + 64);
    for ((p, &v), &l) in s.points.iter().zip(&s.values).zip(labels) {
        for x in [p[0], p[1], p[2], v] {
            buf.extend_from_slice(&x.to_le_bytes());
        }
        buf.push(l);
        if buf.len() >= CHUNK {
            w.write_all(&buf)?;
            buf.clear();
        }
    }
    for t in &s.triangles {
        buf.push(3);
        for i in t {
            buf.extend_from_slice(&(*i as i32).to_le_bytes());
        }
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
            labels: vec![BoundaryLabel::BETA],
            levels: 0,
        };
        let mut b = Vec::new();
        write_ply(&s, &mut b, false).unwrap();
        let h = header(&s, false).len();
        assert_eq!(b.len(), h + 3 * 33 + 1 + 12);
        assert_eq!(&b[h + 33..h + 41], &1.0f64.to_le_bytes());
        assert_eq!(b[h + 32], 1, "label of vertex 0: beta");
        assert_eq!(&b[b.len() - 4..], &2i32.to_le_bytes());
        let mut a = Vec::new();
        write_ply(&s, &mut a, true).unwrap();
        assert!(String::from_utf8(a)
            .unwrap()
            .ends_with("0.0 0.0 0.0 0.5 1\n1.0 0.0 0.0 0.5 1\n0.0 1.0 0.0 0.5 1\n3 0 1 2\n"));
    }
}
