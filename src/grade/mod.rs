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
    /// The element size the interior grows to, in the grid's physical units: the mean edge
    /// length deep inside. Cubes are the power of two cells nearest it ([`max_side`], along
    /// the grid's widest spacing); their tets' edges run from 0.87 to 1.41 times the side,
    /// 1.002 times it on average.
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

/// The side (in cells, a power of two from 1 to 64) of the cubes deep inside `grid` for
/// `max_edge`: the power of two nearest `max_edge` in cells of the widest spacing, going up
/// from 1.5 times a power of two. A cube's cone tets have edges of 0.87 to 1.41 times its
/// side and a mean edge length of 1.002 times it, so the deep interior's mean edge length is
/// within a third of `max_edge` (within 25 % unless `max_edge` is 1.25 to 1.6 times a power
/// of two cells), and exactly the side at a power of two.
pub fn max_side(grid: &ScalarGrid, max_edge: f64) -> usize {
    let widest = grid.spacing.iter().fold(0.0f64, |m, &s| m.max(s.abs()));
    let cells = max_edge / widest;
    let mut side = 1usize;
    while side < (1 << TOP_LEVEL) && cells >= 1.5 * side as f64 {
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
mod size_tests;
#[cfg(test)]
mod tests;
