//! Labels for the boundary of a mesh whose file has none: where each face of one tet lies.

use rayon::prelude::*;

use crate::field::Field;
use crate::grid::ScalarGrid;
use crate::mesh::{BoundaryLabel, TetMesh};

/// Distance (voxels) within which a corner counts as on a face of the grid box.
const ON_BOX: f64 = 1e-6;

/// Sets `mesh.boundary` to the faces of one tet (outward from positive tets) and labels
/// each: `box` when its three corners lie within 10⁻⁶ voxel of one face of the grid box, else
/// the level of `levels` (alpha, beta) nearer in value to the trilinear field at its centroid;
/// an infinite level is never nearer. The mesh's points are in `grid`'s physical coordinates.
pub fn label_boundary(mesh: &mut TetMesh, grid: &ScalarGrid, levels: (f64, f64)) {
    let faces = crate::check::boundary_faces(mesh);
    let field = Field::new(grid);
    let hi = grid.dims.map(|d| (d - 1) as f64);
    let labels = faces
        .par_iter()
        .map(|t| {
            let u = t.map(|v| field.to_index(mesh.points[v as usize]));
            let on_plane = |k: usize, x: f64| u.iter().all(|p| (p[k] - x).abs() <= ON_BOX);
            if (0..3).any(|k| on_plane(k, 0.0) || on_plane(k, hi[k])) {
                return BoundaryLabel::Box;
            }
            let c = [0, 1, 2].map(|k| (u[0][k] + u[1][k] + u[2][k]) / 3.0);
            let f = field.value(c);
            let gap = |level: f64| {
                if level.is_finite() {
                    (f - level).abs()
                } else {
                    f64::INFINITY
                }
            };
            if gap(levels.1) < gap(levels.0) {
                BoundaryLabel::Level(1)
            } else {
                BoundaryLabel::Level(0)
            }
        })
        .collect();
    mesh.boundary = faces;
    mesh.boundary_labels = labels;
}
