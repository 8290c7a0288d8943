//! Wavefront `.obj` surface reader through the `tobj` crate (the twin of the writer in
//! `obj.rs`).
//!
//! Only `v` positions and `f` faces count: polygons are fan-triangulated by `tobj`, points
//! and lines are ignored, material libraries are not opened. Every object and group of the
//! file goes into one surface, whose points are welded by their exact coordinates
//! ([`super::surface_read_common::finish`]), so a closed surface split into groups stays
//! closed.

use std::path::Path;

use super::read_common::{read_all, ReadError};
use super::surface_read_common::{check_not_empty, finish, TriSoup};

/// Reads a Wavefront `.obj` surface.
///
/// # Errors
/// One line naming the file: unreadable, empty, malformed, a face index out of range, no
/// triangles, a coordinate that is not finite.
pub fn read_obj_surface(path: &Path) -> Result<TriSoup, ReadError> {
    let bytes = read_all(path)?;
    check_not_empty(path, &bytes)?;
    let opts = tobj::LoadOptions {
        single_index: false,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let no_materials = |_: &Path| Ok(Default::default());
    let (models, _) = tobj::load_obj_buf(&mut bytes.as_slice(), &opts, no_materials)
        .map_err(|e| ReadError::invalid(path, e.to_string()))?;
    let mut points = Vec::new();
    let mut triangles = Vec::new();
    for m in &models {
        let first = points.len();
        let count = m.mesh.positions.len() / 3;
        if first + count > u32::MAX as usize {
            return Err(ReadError::invalid(path, "more than 2^32 points"));
        }
        points.extend(m.mesh.positions.chunks_exact(3).map(|c| [c[0], c[1], c[2]]));
        let base = first as u32;
        for t in m.mesh.indices.chunks_exact(3) {
            triangles.push([t[0], t[1], t[2]].map(|i| base.saturating_add(i)));
        }
    }
    finish(path, &points, &triangles)
}
