//! Closed surfaces as volumes: the signed distance to a triangle surface sampled on a
//! regular grid, negative inside, so that the solid the surface bounds is the interval
//! volume `{d <= 0}` (`alpha = -inf`, `beta = 0`) the mesher already handles.
//!
//! One algorithm per file: `bvh.rs` (bounding-volume hierarchy, closest points),
//! `winding.rs` (generalised winding number with the far-field expansion), `surface_check.rs`
//! (holes, non-manifold edges, degenerate triangles, pieces, crossing triangles by the
//! checker's search), `grid.rs` (the grid and the parallel
//! sampling). The surface comes as plain points and triangles; reading it from a file is
//! `io::read_surface`, and both together are [`crate::surface_volume::volume_from_surface`].

pub mod bvh;
pub mod grid;
pub mod surface_check;
pub mod winding;

pub use grid::{
    signed_distance_grid, signed_distance_grid_with_progress, GridGeometry, SignedDistance,
    SurfaceGridOptions, DEFAULT_PADDING, DEFAULT_RESOLUTION,
};
pub use surface_check::{check_surface, SurfaceFacts};

use crate::grid::{ScalarGrid, IDENTITY};

/// The level whose sublevel set `{d <= INSIDE_LEVEL}` is the solid: mesh the grid of
/// [`surface_volume`] with `alpha = -inf`, `beta = INSIDE_LEVEL`.
pub const INSIDE_LEVEL: f64 = 0.0;

/// Why a surface could not be turned into a grid. `Display` is one line (without a file
/// name: the caller that read the file adds it).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SdfError {
    /// The surface is empty, fully degenerate, or names missing or non-finite points.
    #[error("{0}")]
    Surface(String),
    /// The grid options are inconsistent or ask for a grid too large to address.
    #[error("{0}")]
    Options(String),
    /// The grid does not fit the memory limit.
    #[error("{0}")]
    Memory(String),
}

/// The signed distance to `(points, triangles)` as a [`ScalarGrid`] (cubic voxels, identity
/// direction, `f64` samples), with what the surface check found.
///
/// # Errors
/// See [`signed_distance_grid`].
pub fn surface_volume(
    points: &[[f64; 3]],
    triangles: &[[u32; 3]],
    opts: &SurfaceGridOptions,
) -> Result<(ScalarGrid, SurfaceFacts), SdfError> {
    surface_volume_with_progress(points, triangles, opts, &|_, _| {})
}

/// [`surface_volume`], calling `progress(done, total)` with the grid points sampled so far
/// ([`signed_distance_grid_with_progress`]).
///
/// # Errors
/// See [`signed_distance_grid`].
pub fn surface_volume_with_progress(
    points: &[[f64; 3]],
    triangles: &[[u32; 3]],
    opts: &SurfaceGridOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<(ScalarGrid, SurfaceFacts), SdfError> {
    let sd = signed_distance_grid_with_progress(points, triangles, opts, progress)?;
    let g = sd.geometry;
    let grid = ScalarGrid::with_geometry(g.dims, [g.spacing; 3], g.origin, IDENTITY, sd.values)
        .map_err(|e| SdfError::Options(e.to_string()))?;
    Ok((grid, sd.facts))
}
