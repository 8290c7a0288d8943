//! A closed-surface file as the volume the mesher takes: [`volume_from_surface`] reads the
//! surface (`io::read_surface`) and samples its signed distance (`sdf::surface_volume`).
//! Like `pipeline`, this joins `io` and an algorithm; neither imports the other.

use std::path::Path;

use crate::grid::ScalarGrid;
use crate::io::{read_surface, ReadError};
use crate::sdf::{surface_volume, SdfError, SurfaceFacts, SurfaceGridOptions};

/// Why a surface file could not be turned into a volume. `Display` is one line starting with
/// the file's path.
#[derive(Debug, thiserror::Error)]
pub enum SurfaceVolumeError {
    /// The file could not be read or parsed.
    #[error(transparent)]
    Read(#[from] ReadError),
    /// The surface or the grid options were refused.
    #[error("{file}: {source}")]
    Sdf {
        /// The file.
        file: String,
        /// What was refused.
        #[source]
        source: SdfError,
    },
}

/// Reads the surface `path` (`.obj`, `.stl`, `.ply`) and returns its signed distance on the
/// grid `opts` lays out, negative inside, with what the surface check found (holes,
/// non-manifold edges, ... : [`SurfaceFacts::warnings`]). Mesh the solid as the interval
/// `alpha = -inf`, `beta = `[`crate::sdf::INSIDE_LEVEL`] of the grid.
///
/// # Errors
/// [`SurfaceVolumeError`]: one line naming the file.
pub fn volume_from_surface(
    path: &Path,
    opts: &SurfaceGridOptions,
) -> Result<(ScalarGrid, SurfaceFacts), SurfaceVolumeError> {
    let soup = read_surface(path)?;
    surface_volume(&soup.points, &soup.triangles, opts).map_err(|source| SurfaceVolumeError::Sdf {
        file: path.display().to_string(),
        source,
    })
}
