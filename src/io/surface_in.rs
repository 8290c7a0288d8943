//! Closed-surface input by file extension: [`read_surface`] chooses among the readers
//! `obj_read` (`.obj`, through `tobj`), `stl_read` (`.stl`, binary or ASCII) and `ply_read`
//! (`.ply`, ASCII or binary). All return a [`TriSoup`]; the readers share
//! [`super::surface_read_common`], never this dispatcher.

use std::path::Path;

use super::read_common::ReadError;
use super::surface_read_common::TriSoup;

/// The surface file extensions [`read_surface`] reads, for messages.
pub const SURFACE_EXTENSIONS: &str = ".obj, .stl or .ply";

/// Whether `path` ends in one of [`SURFACE_EXTENSIONS`] (any case).
pub fn is_surface(path: &Path) -> bool {
    extension(path).is_some_and(|e| matches!(e.as_str(), "obj" | "stl" | "ply"))
}

fn extension(path: &Path) -> Option<String> {
    path.extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
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
    match extension(path).as_deref() {
        Some("obj") => super::obj_read::read_obj_surface(path),
        Some("stl") => super::stl_read::read_stl_surface(path),
        Some("ply") => super::ply_read::read_ply_surface(path),
        _ => Err(ReadError::unsupported(
            path,
            format!("unknown surface format (expected {SURFACE_EXTENSIONS})"),
        )),
    }
}
