//! The output mesh: plain data shared by the mesher, the writers and the analyses.

use serde::Serialize;

use crate::geom::signed_volume;

/// Which surface a boundary triangle lies on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[repr(u8)]
pub enum BoundaryLabel {
    /// On the level set f = alpha (the lower bound).
    Alpha = 0,
    /// On the level set f = beta (the upper bound).
    Beta = 1,
    /// On the outer boundary of the grid box.
    Box = 2,
}

impl BoundaryLabel {
    /// All labels, in tag order.
    pub const ALL: [BoundaryLabel; 3] = [
        BoundaryLabel::Alpha,
        BoundaryLabel::Beta,
        BoundaryLabel::Box,
    ];

    /// Lower-case name used by every writer (`alpha`, `beta`, `box`).
    pub fn name(self) -> &'static str {
        match self {
            BoundaryLabel::Alpha => "alpha",
            BoundaryLabel::Beta => "beta",
            BoundaryLabel::Box => "box",
        }
    }
}

/// A conforming tetrahedral mesh with labelled boundary.
///
/// Invariants (established by the mesher, relied on by writers and analyses):
/// * every tet `[a, b, c, d]` is positively oriented: `(b-a)·((c-a)×(d-a)) > 0`;
/// * `boundary` lists exactly the triangles that belong to one tet only, each oriented with
///   its normal pointing out of the domain, and `boundary_labels[t]` labels `boundary[t]`;
/// * every point is used by at least one tet; `values[p]` is the field at `points[p]`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TetMesh {
    /// #P physical positions.
    pub points: Vec<[f64; 3]>,
    /// #P field values (the piecewise-linear interpolant at each node).
    pub values: Vec<f64>,
    /// #T tetrahedra, as indices into `points`.
    pub tets: Vec<[u32; 4]>,
    /// #B boundary triangles, outward-oriented.
    pub boundary: Vec<[u32; 3]>,
    /// #B labels, one per boundary triangle.
    pub boundary_labels: Vec<BoundaryLabel>,
}

/// Tets per block of [`TetMesh::volume`]'s sum (blocks are summed in order, so the volume
/// does not depend on the thread count; `facts` sums a streamed mesh in the same blocks).
pub(crate) const VOLUME_BLOCK: usize = 1 << 14;

impl TetMesh {
    /// Per point: bit `1 << label` for each [`BoundaryLabel`] of the boundary triangles around
    /// it (0 for interior points).
    pub fn vertex_label_bits(&self) -> Vec<u8> {
        let mut bits = vec![0u8; self.points.len()];
        for (tri, &label) in self.boundary.iter().zip(&self.boundary_labels) {
            for &v in tri {
                bits[v as usize] |= 1 << (label as u8);
            }
        }
        bits
    }

    /// Signed volume of tet `t` (positive for the mesher's output).
    pub fn tet_volume(&self, t: usize) -> f64 {
        let [a, b, c, d] = self.tets[t].map(|i| self.points[i as usize]);
        signed_volume(a, b, c, d)
    }

    /// Sum of the tet volumes. Summed in fixed-size blocks (in parallel) whose partial sums are
    /// added in order, so the result does not depend on the thread count.
    pub fn volume(&self) -> f64 {
        use rayon::prelude::*;
        let partial: Vec<f64> = self
            .tets
            .par_chunks(VOLUME_BLOCK)
            .map(|c| {
                c.iter()
                    .map(|t| {
                        let [a, b, c, d] = t.map(|i| self.points[i as usize]);
                        signed_volume(a, b, c, d)
                    })
                    .sum()
            })
            .collect();
        partial.iter().sum()
    }
}

/// A triangle surface with labelled triangles: the isosurface output of
/// [`crate::surface::level_surface`], written by the `obj`, `ply` and `stl` writers.
///
/// Invariants: every point is used by a triangle; `values[p]` is the field at `points[p]`;
/// `labels[t]` labels `triangles[t]`; triangles are listed grouped by label in
/// [`BoundaryLabel::ALL`] order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriSurface {
    /// #P physical positions.
    pub points: Vec<[f64; 3]>,
    /// #P field values.
    pub values: Vec<f64>,
    /// #F triangles, as indices into `points`.
    pub triangles: Vec<[u32; 3]>,
    /// #F labels, one per triangle.
    pub labels: Vec<BoundaryLabel>,
}
