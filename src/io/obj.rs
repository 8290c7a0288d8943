//! Wavefront `.obj` writer for isosurfaces ([`TriSurface`]).
//!
//! Layout: one `v x y z` line per point (shortest round-trip decimals), then the triangles
//! of each label that occurs as a group `g alpha` / `g beta` / `g box` of `f a b c` lines
//! (1-based indices, counter-clockwise seen from the side the normal points to, i.e. towards
//! increasing f). Vertices are shared (welded) across triangles and groups.

use std::io::{self, Write};

use super::write_common::{check_surface, TextOut};
use crate::mesh::{BoundaryLabel, TriSurface};

/// Writes `s` as Wavefront OBJ to `w`.
///
/// # Errors
/// The first error of `w`; [`io::ErrorKind::InvalidInput`] for an inconsistent surface.
pub fn write_obj(s: &TriSurface, w: &mut dyn Write) -> io::Result<()> {
    check_surface(s)?;
    let mut out = TextOut::new(w);
    out.s("# tptd isosurface: ")
        .int(s.points.len())
        .s(" vertices, ")
        .int(s.triangles.len())
        .s(" triangles, normals towards increasing f");
    out.nl()?;
    for p in &s.points {
        out.s("v ").vec3(*p);
        out.nl()?;
    }
    for label in BoundaryLabel::ALL {
        let mut group = s
            .triangles
            .iter()
            .zip(&s.labels)
            .filter(|(_, &l)| l == label)
            .peekable();
        if group.peek().is_none() {
            continue;
        }
        out.s("g ").s(&label.name_in(s.level_count()));
        out.nl()?;
        for (t, _) in group {
            out.s("f ")
                .int(t[0] + 1)
                .s(" ")
                .int(t[1] + 1)
                .s(" ")
                .int(t[2] + 1);
            out.nl()?;
        }
    }
    out.finish()
}
