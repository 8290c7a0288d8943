//! The output mesh: plain data shared by the mesher, the writers and the analyses, whole
//! ([`TetMesh`]) or one slab at a time ([`MeshChunk`] to a [`MeshSink`]).

use std::io;

use serde::Serialize;

use crate::geom::signed_volume;

/// Which surface a boundary triangle lies on: the level set of one of the run's levels
/// ([`crate::levels::Levels`]), or the grid box.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum BoundaryLabel {
    /// On the level set of level `i` (for one interval, 0: f = alpha, the lower bound; 1:
    /// f = beta, the upper bound).
    Level(u8),
    /// On the outer boundary of the grid box.
    Box,
}

/// Number of levels a boundary label can name: the two bounds of one interval.
pub const LABEL_LEVELS: usize = 2;

/// Number of boundary labels: one per level, then the box.
pub const NUM_LABELS: usize = LABEL_LEVELS + 1;

impl BoundaryLabel {
    /// The level set f = alpha (level 0, the lower bound of an interval).
    pub const ALPHA: BoundaryLabel = BoundaryLabel::Level(0);
    /// The level set f = beta (level 1, the upper bound of an interval).
    pub const BETA: BoundaryLabel = BoundaryLabel::Level(1);

    /// All labels, in tag order ([`BoundaryLabel::index`]).
    pub const ALL: [BoundaryLabel; NUM_LABELS] = [
        BoundaryLabel::Level(0),
        BoundaryLabel::Level(1),
        BoundaryLabel::Box,
    ];

    /// The label's number: the level index, or [`LABEL_LEVELS`] for the box. Writers emit it
    /// (as is or plus one) as the label's tag; per-label tables are indexed by it.
    #[inline]
    pub const fn index(self) -> usize {
        match self {
            BoundaryLabel::Level(i) => i as usize,
            BoundaryLabel::Box => LABEL_LEVELS,
        }
    }

    /// The label numbered `i` ([`BoundaryLabel::index`]); `i <= LABEL_LEVELS`.
    #[inline]
    pub const fn from_index(i: usize) -> BoundaryLabel {
        if i < LABEL_LEVELS {
            BoundaryLabel::Level(i as u8)
        } else {
            BoundaryLabel::Box
        }
    }

    /// The level index of a level label, `None` for the box.
    #[inline]
    pub const fn level(self) -> Option<usize> {
        match self {
            BoundaryLabel::Level(i) => Some(i as usize),
            BoundaryLabel::Box => None,
        }
    }

    /// Bit `1 << index` of the label, for per-vertex label sets.
    #[inline]
    pub const fn bit(self) -> u8 {
        1 << self.index()
    }

    /// Lower-case name used by every writer (`alpha`, `beta`, `box`).
    pub fn name(self) -> &'static str {
        match self {
            BoundaryLabel::Level(0) => "alpha",
            BoundaryLabel::Level(1) => "beta",
            BoundaryLabel::Level(_) => "level",
            BoundaryLabel::Box => "box",
        }
    }
}

impl Serialize for BoundaryLabel {
    /// As a unit variant: `Alpha`, `Beta` or `Box`.
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let variant = match self {
            BoundaryLabel::Level(0) => "Alpha",
            BoundaryLabel::Level(1) => "Beta",
            BoundaryLabel::Level(_) => "Level",
            BoundaryLabel::Box => "Box",
        };
        s.serialize_unit_variant("BoundaryLabel", self.index() as u32, variant)
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
                bits[v as usize] |= label.bit();
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

/// One slab of the mesh in global numbering, as handed to a [`MeshSink`].
///
/// Chunks arrive in slab order. `points` are the points numbered first in this slab (global
/// numbers `first_point..first_point + points.len()`); the elements may also use points of
/// earlier chunks (those on the plane shared with the slab below).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshChunk {
    /// Global number of `points[0]`.
    pub first_point: usize,
    /// New points, physical coordinates.
    pub points: Vec<[f64; 3]>,
    /// Field value at each new point.
    pub values: Vec<f64>,
    /// Global number of `tets[0]`.
    pub first_tet: usize,
    /// Tets, global point numbers, positively oriented.
    pub tets: Vec<[u32; 4]>,
    /// Boundary triangles, global point numbers, outward normals. Each is a face of a tet of
    /// the same chunk.
    pub boundary: Vec<[u32; 3]>,
    /// Label of each boundary triangle.
    pub boundary_labels: Vec<BoundaryLabel>,
    /// Per label (in [`BoundaryLabel::ALL`] order) the bounding box `[min xyz, max xyz]` of the
    /// vertices of this chunk's triangles with that label (`±inf` when there are none).
    pub label_boxes: [[f64; 6]; NUM_LABELS],
    /// With several regions, the region of each tet (empty for one interval).
    pub regions: Vec<u8>,
}

/// Where [`crate::mesh_interval_streamed`] delivers the mesh, one slab at a time.
pub trait MeshSink {
    /// Takes the next chunk (in slab order).
    ///
    /// # Errors
    /// Any I/O error: it stops the meshing run and is returned from it.
    fn chunk(&mut self, chunk: &MeshChunk) -> io::Result<()>;
}

/// A sink that gathers the chunks into one [`TetMesh`].
#[derive(Default)]
pub(crate) struct Gather {
    pub(crate) mesh: TetMesh,
    /// The chunks' regions, in tet order (empty for one interval).
    pub(crate) regions: Vec<u8>,
}

impl MeshSink for Gather {
    fn chunk(&mut self, c: &MeshChunk) -> io::Result<()> {
        let m = &mut self.mesh;
        m.points.extend_from_slice(&c.points);
        m.values.extend_from_slice(&c.values);
        m.tets.extend_from_slice(&c.tets);
        m.boundary.extend_from_slice(&c.boundary);
        m.boundary_labels.extend_from_slice(&c.boundary_labels);
        self.regions.extend_from_slice(&c.regions);
        Ok(())
    }
}

/// An empty bounding box (`min = +inf`, `max = -inf`).
pub const EMPTY_BOX: [f64; 6] = [
    f64::INFINITY,
    f64::INFINITY,
    f64::INFINITY,
    f64::NEG_INFINITY,
    f64::NEG_INFINITY,
    f64::NEG_INFINITY,
];

/// Grows box `b` by point `p`.
#[inline]
pub fn grow_box(b: &mut [f64; 6], p: [f64; 3]) {
    for k in 0..3 {
        b[k] = b[k].min(p[k]);
        b[k + 3] = b[k + 3].max(p[k]);
    }
}
