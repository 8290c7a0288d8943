//! Graded interiors: the fine tets deep inside the domain replaced by larger ones, so that
//! elements grow away from the surfaces up to a given edge length.
//!
//! Pipeline position: `extract` → **grade** → improve → write. The cells whose corners all
//! lie strictly inside one region are merged into cubes of 2, 4, 8, … cells, the leaves of
//! an octree aligned to the grid, graded by distance to the nearest cell a level passes
//! through and balanced 2:1 ([`octree`]); each cube is meshed as a cone from its centre over
//! its faces, whose triangles match the neighbours on each side ([`blocks`]); the fine tets
//! inside the cubes are replaced ([`splice`]). The cubes cover exactly the cells they
//! replace, away from every level and from the box, so the boundary, the levels, the regions
//! and the topology do not change, and neither does the volume.

pub mod blocks;
pub mod octree;
pub mod splice;

use std::time::Instant;

use serde::Serialize;

use crate::extract::MeshOutput;
use crate::grid::ScalarGrid;
use crate::levels::Levels;
use octree::Leaves;
use splice::{splice, IndexSpace};

/// Options of [`grade_interior`].
#[derive(Clone, Debug, PartialEq)]
pub struct GradeOptions {
    /// The longest cube side the interior may grow to, in the grid's physical units: cubes
    /// are the largest power of two cells whose side (along the grid's widest spacing) is at
    /// most this; their tets' edges run from 0.87 to 1.41 times the side.
    pub max_edge: f64,
    /// How fast sizes may grow away from the surfaces: a cube of side `s` cells lies at
    /// least `(s − 1) / (grading − 1)` cells from every cell a level passes through (and from
    /// the box). Greater than 1.
    pub grading: f64,
}

/// The default growth per cell of distance from the surfaces ([`GradeOptions::grading`]).
pub const DEFAULT_GRADING: f64 = 1.5;

/// The largest cube: 2^6 = 64 cells a side.
const TOP_LEVEL: u8 = 6;

impl Default for GradeOptions {
    /// Cubes of up to 4 cells of unit spacing, grading 1.5.
    fn default() -> Self {
        GradeOptions {
            max_edge: 4.0,
            grading: DEFAULT_GRADING,
        }
    }
}

/// What [`grade_interior`] did.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct GradeReport {
    /// The side of the largest cube allowed, in cells.
    pub max_side_cells: usize,
    /// Cubes placed, by side: `cubes[l]` of side `2^(l+1)` cells.
    pub cubes: Vec<usize>,
    /// Tets before.
    pub tets_before: usize,
    /// Tets after.
    pub tets_after: usize,
    /// Points before.
    pub points_before: usize,
    /// Points after.
    pub points_after: usize,
    /// Fine tets replaced.
    pub tets_replaced: usize,
    /// The cubes' tets replacing them (after the kept tets).
    pub tets_added: usize,
    /// Volume of the tets replaced.
    pub volume_replaced: f64,
    /// Volume of the cubes' tets (equal to the replaced one up to rounding).
    pub volume_replacing: f64,
    /// Seconds.
    pub seconds: f64,
}

/// The side (in cells, a power of two, at least 1) of the largest cube of `grid` whose
/// edges are at most `max_edge` along its widest spacing.
pub fn max_side(grid: &ScalarGrid, max_edge: f64) -> usize {
    let widest = grid.spacing.iter().fold(0.0f64, |m, &s| m.max(s.abs()));
    let cells = (max_edge / widest).floor();
    let mut side = 1usize;
    while side < (1 << TOP_LEVEL) && (2 * side) as f64 <= cells {
        side *= 2;
    }
    side
}

/// Grades the interior of `out`'s mesh, a mesh of `levels` on `grid` made by
/// [`crate::mesh_interval`] (before any other change): the fine tets of the cells deep inside
/// one region are replaced by cubes as [`GradeOptions`] allows. The boundary, the interfaces,
/// the regions and the volume stay as they are; only interior points go.
pub fn grade_interior(
    out: &mut MeshOutput,
    grid: &ScalarGrid,
    levels: &Levels,
    opts: &GradeOptions,
) -> GradeReport {
    let start = Instant::now();
    let mesh = &mut out.mesh;
    let mut report = GradeReport {
        max_side_cells: max_side(grid, opts.max_edge),
        tets_before: mesh.tets.len(),
        points_before: mesh.points.len(),
        ..GradeReport::default()
    };
    let top = report.max_side_cells.trailing_zeros() as u8;
    let index = IndexSpace::new(grid);
    if let (true, Some(index)) = (top > 0 && opts.grading > 1.0, index) {
        let leaves = Leaves::build(grid, levels, top, opts.grading);
        let blocks = leaves.blocks();
        report.cubes = (1..=top)
            .map(|l| blocks.iter().filter(|b| b.level == l).count())
            .collect();
        match splice(mesh, &leaves, &blocks, &index) {
            Some(s) => {
                (report.volume_replaced, report.volume_replacing) = s.volumes;
                (report.tets_replaced, report.tets_added) = (s.removed, s.added);
            }
            // not a mesh of this grid's interior cells: left as it is
            None => report.cubes.clear(),
        }
    }
    report.tets_after = mesh.tets.len();
    report.points_after = mesh.points.len();
    report.seconds = start.elapsed().as_secs_f64();
    report
}

#[cfg(test)]
mod tests;
