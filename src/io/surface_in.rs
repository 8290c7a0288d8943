//! Closed-surface input by file extension (the table in [`super::formats`]): [`read_surface`]
//! chooses among the readers `obj_read` (`.obj`, through `tobj`), `stl_read` (`.stl`, binary
//! or ASCII) and `ply_read` (`.ply`, ASCII or binary). All return a [`TriSoup`]; the readers share
//! [`super::surface_read_common`], never this dispatcher.

use std::path::Path;

use super::formats::{surface_extensions, SurfaceFormat};
use super::read_common::ReadError;
use super::surface_read_common::TriSoup;

/// Whether `path` names a closed-surface input ([`read_surface`]): its extension is `.obj`,
/// `.stl` or `.ply` (any case; the table in [`super::formats`]).
pub fn is_surface(path: &Path) -> bool {
    SurfaceFormat::from_path(path).is_some()
}

/// Reads a triangle surface by file extension (case-insensitive): `.obj`
/// ([`super::obj_read::read_obj_surface`]), `.stl` ([`super::stl_read::read_stl_surface`]),
/// `.ply` ([`super::ply_read::read_ply_surface`]). Points with identical coordinates are
/// welded; nothing is checked about the surface's shape (see `tptd::sdf::check_surface`).
///
/// # Errors
/// [`ReadError::Unsupported`] for another extension, otherwise the reader's one-line error
/// naming the file (unreadable, empty, truncated, no triangles, an index out of range, a
/// coordinate that is not finite). Never panics, whatever the file holds.
pub fn read_surface(path: &Path) -> Result<TriSoup, ReadError> {
    match SurfaceFormat::from_path(path) {
        Some(SurfaceFormat::Obj) => super::obj_read::read_obj_surface(path),
        Some(SurfaceFormat::Stl) => super::stl_read::read_stl_surface(path),
        Some(SurfaceFormat::Ply) => super::ply_read::read_ply_surface(path),
        None => Err(ReadError::unsupported(
            path,
            format!("unknown surface format (expected {})", surface_extensions()),
        )),
    }
}
