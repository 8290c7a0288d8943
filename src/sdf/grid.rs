//! The signed distance of a surface sampled on a regular grid around it.
//!
//! The grid has cubic voxels: the surface's box spans [`SurfaceGridOptions::resolution`]
//! voxels along its longest side (or the voxels are [`SurfaceGridOptions::voxel_size`]
//! wide) and is centred in the grid with its sides midway between grid planes;
//! [`SurfaceGridOptions::margin`] (a distance) and [`SurfaceGridOptions::padding`] voxels are
//! added on every side so the level set meshed (zero, or an offset up to the margin) closes
//! inside the grid.
//!
//! Each grid point gets its distance to the nearest triangle ([`Bvh::closest`]), negative
//! where the generalised winding number exceeds one half ([`WindingTree`]). Rows along x are
//! computed in parallel, each from its first point on: a point's search starts from the
//! previous point's nearest triangle, and on a closed surface (its winding number constant
//! between triangles, [`SurfaceFacts::closed`]) a point within the empty ball of the previous
//! one (`|d| >` one voxel) takes its sign without a winding-number query. Every value depends
//! on its row alone, so the output is the same for any number of threads.

use std::sync::atomic::{AtomicUsize, Ordering};

use rayon::prelude::*;

use super::bvh::{Bvh, Tri};
use super::surface_check::{check_surface, SurfaceFacts};
use super::winding::WindingTree;
use super::SdfError;

/// How the grid around a surface is laid out.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceGridOptions {
    /// Voxels along the longest side of the surface's box (`None`: 64, unless `voxel_size`
    /// is given).
    pub resolution: Option<usize>,
    /// Width of a voxel in the surface's units (exclusive with `resolution`).
    pub voxel_size: Option<f64>,
    /// Voxels added beyond the surface's box (and the margin) on every side.
    pub padding: usize,
    /// Distance in the surface's units added beyond the surface's box on every side, before
    /// the padding: room for an offset surface `{d = margin}` (0 by default).
    pub margin: f64,
}

/// The resolution used when neither a resolution nor a voxel size is given.
pub const DEFAULT_RESOLUTION: usize = 64;

/// The padding of [`SurfaceGridOptions::default`].
pub const DEFAULT_PADDING: usize = 3;

impl Default for SurfaceGridOptions {
    fn default() -> Self {
        SurfaceGridOptions {
            resolution: None,
            voxel_size: None,
            padding: DEFAULT_PADDING,
            margin: 0.0,
        }
    }
}

/// Where the grid lies: vertex `(i, j, k)` is at `origin + spacing · (i, j, k)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridGeometry {
    /// Grid vertices along x, y, z.
    pub dims: [usize; 3],
    /// Position of vertex `(0, 0, 0)`.
    pub origin: [f64; 3],
    /// Width of a voxel (the same along every axis).
    pub spacing: f64,
}

impl GridGeometry {
    /// The grid laid out by `opts` around the box `bounds` (lower and upper corners).
    ///
    /// # Errors
    /// [`SdfError::Options`] for both a resolution and a voxel size, a zero resolution, a
    /// voxel size that is not positive and finite, a margin that is negative or not finite, or
    /// a grid too large to address.
    pub fn around(bounds: [[f64; 3]; 2], opts: &SurfaceGridOptions) -> Result<Self, SdfError> {
        let extent = [0, 1, 2].map(|a| (bounds[1][a] - bounds[0][a]).max(0.0));
        let longest = extent.iter().copied().fold(0.0, f64::max);
        let spacing = spacing(longest, opts)?;
        if !(opts.margin.is_finite() && opts.margin >= 0.0) {
            return Err(SdfError::Options(format!(
                "margin {} must be finite and not negative",
                opts.margin
            )));
        }
        let mut dims = [0usize; 3];
        let mut origin = [0.0; 3];
        for a in 0..3 {
            let extent = extent[a] + 2.0 * opts.margin;
            // a hair of slack so a box of exactly n voxels is not rounded up to n + 1
            let cells = (extent / spacing * (1.0 - 1e-12)).ceil();
            if cells > 1e7 {
                return Err(SdfError::Options(format!(
                    "voxel size {spacing} makes {cells} voxels along an axis; choose a coarser one"
                )));
            }
            // one vertex more than the cells: the box ends half a voxel between grid planes,
            // so that flat faces on it (a machined part's) are no planes of zeros and saddles
            dims[a] = cells as usize + 2 + 2 * opts.padding;
            let centre = 0.5 * (bounds[0][a] + bounds[1][a]);
            origin[a] = centre - 0.5 * (dims[a] - 1) as f64 * spacing;
        }
        let geometry = GridGeometry {
            dims,
            origin,
            spacing,
        };
        geometry.points()?;
        Ok(geometry)
    }

    /// Number of grid vertices.
    ///
    /// # Errors
    /// [`SdfError::Options`] when the count overflows.
    pub fn points(&self) -> Result<usize, SdfError> {
        let [x, y, z] = self.dims;
        x.checked_mul(y)
            .and_then(|n| n.checked_mul(z))
            .ok_or_else(|| {
                SdfError::Options(format!("a grid of {:?} points is too large", self.dims))
            })
    }

    /// Position of grid vertex `(i, j, k)`.
    pub fn point(&self, i: usize, j: usize, k: usize) -> [f64; 3] {
        let h = self.spacing;
        [
            self.origin[0] + h * i as f64,
            self.origin[1] + h * j as f64,
            self.origin[2] + h * k as f64,
        ]
    }
}

/// The voxel size `opts` gives a box whose longest side is `longest`.
fn spacing(longest: f64, opts: &SurfaceGridOptions) -> Result<f64, SdfError> {
    let spacing = match (opts.resolution, opts.voxel_size) {
        (Some(_), Some(_)) => {
            return Err(SdfError::Options(
                "give a resolution or a voxel size, not both".into(),
            ))
        }
        (_, Some(h)) if !(h.is_finite() && h > 0.0) => {
            return Err(SdfError::Options(format!(
                "voxel size {h} must be positive"
            )))
        }
        (_, Some(h)) => h,
        (Some(0), None) => return Err(SdfError::Options("resolution 0 must be at least 1".into())),
        (r, None) => longest / r.unwrap_or(DEFAULT_RESOLUTION) as f64,
    };
    if !(spacing.is_finite() && spacing > 0.0) {
        return Err(SdfError::Surface("the surface's box has no extent".into()));
    }
    Ok(spacing)
}

/// The signed distance of a surface on a grid, with what the surface check found.
#[derive(Clone, Debug, PartialEq)]
pub struct SignedDistance {
    /// Distance to the surface at each grid vertex, negative inside, x fastest
    /// (`i + nx (j + ny k)`).
    pub values: Vec<f64>,
    /// The grid.
    pub geometry: GridGeometry,
    /// The surface check ([`check_surface`]).
    pub facts: SurfaceFacts,
}

/// Samples the signed distance to the surface `(points, triangles)` on the grid `opts`
/// lays out. Inside is where the generalised winding number exceeds 0.5 (for a surface whose
/// enclosed volume is negative, its triangles facing inwards, where it is below −0.5).
///
/// # Errors
/// [`SdfError::Surface`] for a surface [`check_surface`] refuses, [`SdfError::Options`] for
/// bad options, [`SdfError::Memory`] when the grid does not fit the memory limit.
pub fn signed_distance_grid(
    points: &[[f64; 3]],
    triangles: &[[u32; 3]],
    opts: &SurfaceGridOptions,
) -> Result<SignedDistance, SdfError> {
    signed_distance_grid_with_progress(points, triangles, opts, &|_, _| {})
}

/// [`signed_distance_grid`], calling `progress(done, total)` with the grid points sampled so
/// far of all of them after each row (from the worker threads, `done` not always increasing).
///
/// # Errors
/// As [`signed_distance_grid`].
pub fn signed_distance_grid_with_progress(
    points: &[[f64; 3]],
    triangles: &[[u32; 3]],
    opts: &SurfaceGridOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<SignedDistance, SdfError> {
    let facts = check_surface(points, triangles)?;
    let geometry = GridGeometry::around(facts.bounds, opts)?;
    let n = geometry.points()?;
    let need = (n as u64).saturating_mul(16);
    crate::memory::check(need, format!("a signed-distance grid of {n} points"))
        .map_err(|e| SdfError::Memory(e.to_string()))?;
    let tris: Vec<Tri> = triangles
        .iter()
        .map(|t| t.map(|i| points[i as usize]))
        .collect();
    let bvh = Bvh::new(&tris);
    let tree = WindingTree::new(&bvh);
    let rows = Rows {
        bvh: &bvh,
        tree: &tree,
        geometry,
        closed: facts.closed,
        orientation: if facts.volume < 0.0 { -1.0 } else { 1.0 },
    };
    let mut values = Vec::new();
    crate::memory::try_reserve(&mut values, n).map_err(|e| SdfError::Memory(e.to_string()))?;
    values.resize(n, 0.0);
    let [nx, ny, _] = geometry.dims;
    let done = AtomicUsize::new(0);
    values
        .par_chunks_mut(nx)
        .enumerate()
        .for_each(|(row, out)| {
            rows.fill(row % ny, row / ny, out);
            progress(done.fetch_add(nx, Ordering::Relaxed) + nx, n);
        });
    Ok(SignedDistance {
        values,
        geometry,
        facts,
    })
}

/// What every row reads.
struct Rows<'a> {
    bvh: &'a Bvh,
    tree: &'a WindingTree<'a>,
    geometry: GridGeometry,
    closed: bool,
    /// 1, or −1 for an inward-facing surface.
    orientation: f64,
}

impl Rows<'_> {
    /// The values of row `(j, k)`.
    fn fill(&self, j: usize, k: usize, out: &mut [f64]) {
        let h = self.geometry.spacing;
        let mut hint = None;
        let mut previous: Option<(f64, bool)> = None;
        for (i, v) in out.iter_mut().enumerate() {
            let q = self.geometry.point(i, j, k);
            let c = self.bvh.closest(q, hint);
            hint = Some(c.slot);
            let d = c.distance2.sqrt();
            if d == 0.0 {
                let w = self.orientation * self.tree.winding_number(q);
                previous = Some((0.0, w > 0.5));
                *v = on_surface(w, h);
                continue;
            }
            let inside = match previous {
                Some((dp, inside)) if self.closed && dp > h * (1.0 + 1e-9) => inside,
                _ => self.orientation * self.tree.winding_number(q) > 0.5,
            };
            previous = Some((d, inside));
            *v = if inside { -d } else { d };
        }
    }
}

/// The value at a point on a triangle, from its winding number `w` there (the mean of the
/// two sides') and the voxel size `h`: 0 on the solid's boundary (one side inside, one
/// outside); on a wall with the solid (the outside) on both sides, where the surface overlaps
/// itself, `-WALL h` (`+WALL h`), so that the wall is no boundary of `{d <= 0}` and no grid
/// value is a tie with the level 0 that the mesher would move off by a vanishing amount.
fn on_surface(w: f64, h: f64) -> f64 {
    const WALL: f64 = 1e-3;
    if w > 1.0 {
        -WALL * h
    } else if w < 0.0 {
        WALL * h
    } else {
        0.0
    }
}
