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

/// Number of levels a boundary label can name: every level of a run.
pub const LABEL_LEVELS: usize = crate::levels::MAX_LEVELS;

/// Number of boundary labels: one per level, then the box.
pub const NUM_LABELS: usize = LABEL_LEVELS + 1;

/// The levels of one interval (alpha and beta): what a mesh without regions has.
pub const INTERVAL_LEVELS: usize = 2;

/// A set of boundary labels ([`BoundaryLabel::bit`]): bit `i` for level `i`, [`BOX_BIT`] for
/// the box.
pub type LabelBits = u32;

/// The box's bit in a [`LabelBits`] (above every level's).
pub const BOX_BIT: LabelBits = 1 << LABEL_LEVELS;

/// The levels' bits in a [`LabelBits`].
pub const LEVEL_BITS: LabelBits = BOX_BIT - 1;

impl BoundaryLabel {
    /// The level set f = alpha (level 0, the lower bound of an interval).
    pub const ALPHA: BoundaryLabel = BoundaryLabel::Level(0);
    /// The level set f = beta (level 1, the upper bound of an interval).
    pub const BETA: BoundaryLabel = BoundaryLabel::Level(1);

    /// All labels, in tag order ([`BoundaryLabel::index`]): the levels, then the box.
    pub const ALL: [BoundaryLabel; NUM_LABELS] = {
        let mut all = [BoundaryLabel::Box; NUM_LABELS];
        let mut i = 0;
        while i < LABEL_LEVELS {
            all[i] = BoundaryLabel::Level(i as u8);
            i += 1;
        }
        all
    };

    /// The labels of a run of `levels` levels, in tag order: its levels, then the box.
    pub fn of_levels(levels: usize) -> impl Iterator<Item = BoundaryLabel> {
        (0..levels.min(LABEL_LEVELS))
            .map(|i| BoundaryLabel::Level(i as u8))
            .chain(std::iter::once(BoundaryLabel::Box))
    }

    /// The label's slot in per-label tables: the level index, or [`LABEL_LEVELS`] for the
    /// box.
    #[inline]
    pub const fn index(self) -> usize {
        match self {
            BoundaryLabel::Level(i) => i as usize,
            BoundaryLabel::Box => LABEL_LEVELS,
        }
    }

    /// The label's number in a run of `levels` levels: the level index, or `levels` for the
    /// box (so 0, 1, 2 for alpha, beta and the box of one interval). Writers emit it (as is
    /// or plus one) as the label's tag.
    #[inline]
    pub const fn code(self, levels: usize) -> usize {
        match self {
            BoundaryLabel::Level(i) => i as usize,
            BoundaryLabel::Box => levels,
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

    /// The label numbered `code` in a run of `levels` levels ([`BoundaryLabel::code`]).
    #[inline]
    pub const fn from_code(code: usize, levels: usize) -> BoundaryLabel {
        if code < levels {
            BoundaryLabel::Level(code as u8)
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

    /// Whether the label names a level between two regions in a run of `levels` levels (not
    /// the first or the last): its triangles are interfaces, not boundary.
    #[inline]
    pub fn is_interface(self, levels: usize) -> bool {
        matches!(self.level(), Some(i) if i != 0 && i + 1 < levels)
    }

    /// Bit of the label in a per-vertex label set (the quality pass's): `1 << i` for level
    /// `i`, [`BOX_BIT`] for the box.
    #[inline]
    pub const fn bit(self) -> LabelBits {
        match self {
            BoundaryLabel::Level(i) => 1 << i,
            BoundaryLabel::Box => BOX_BIT,
        }
    }

    /// Lower-case name of a one-interval label used by every writer (`alpha`, `beta`,
    /// `box`; `level` for the levels of several regions, named by [`BoundaryLabel::name_in`]).
    pub fn name(self) -> &'static str {
        match self {
            BoundaryLabel::Level(0) => "alpha",
            BoundaryLabel::Level(1) => "beta",
            BoundaryLabel::Level(_) => "level",
            BoundaryLabel::Box => "box",
        }
    }

    /// The label's name in a run of `levels` levels: as [`BoundaryLabel::name`] for one
    /// interval; `level1`, `level2`, … (counting from 1, as the levels are given) and `box`
    /// for several regions.
    pub fn name_in(self, levels: usize) -> String {
        match self {
            BoundaryLabel::Level(i) if levels > INTERVAL_LEVELS => format!("level{}", i + 1),
            l => l.name().to_string(),
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
    /// The regions of a mesh of several intervals; empty for one interval.
    pub regions: Regions,
}

/// The regions of a mesh of several intervals (`--levels`): region `k` lies between levels
/// `k` and `k + 1`. Empty ([`Regions::is_empty`]) for a mesh of one interval.
///
/// Invariants: `tets[t]` is the region of tet `t`; `boundary[b]` the region of the tet the
/// boundary triangle `b` is a face of; each interface triangle is a face of two tets, one in
/// the region below its level and one in the region above, oriented with its normal pointing
/// out of the region below (towards increasing f), and is not a boundary triangle.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Regions {
    /// Number of levels of the run (0 when empty).
    pub levels: usize,
    /// #T regions, one per tet.
    pub tets: Vec<u8>,
    /// #B regions, one per boundary triangle.
    pub boundary: Vec<u8>,
    /// Triangles on the levels between regions.
    pub interfaces: Vec<[u32; 3]>,
    /// Level label ([`BoundaryLabel::Level`]) of each interface triangle.
    pub interface_labels: Vec<BoundaryLabel>,
    /// The regions' names as the writers give them (missing ones: [`Regions::name`]).
    pub names: Vec<String>,
}

impl Regions {
    /// Whether the mesh has no regions (one interval).
    pub fn is_empty(&self) -> bool {
        self.levels == 0
    }

    /// Number of regions (0 for one interval).
    pub fn count(&self) -> usize {
        self.levels.saturating_sub(1)
    }

    /// The name of region `k`: the given one, else `region1`, `region2`, … (counting from 1).
    pub fn name(&self, k: usize) -> String {
        region_name(&self.names, k)
    }
}

/// Tets per block of [`TetMesh::volume`]'s sum (blocks are summed in order, so the volume
/// does not depend on the thread count; `facts` sums a streamed mesh in the same blocks).
pub(crate) const VOLUME_BLOCK: usize = 1 << 14;

impl TetMesh {
    /// Number of levels the mesh's labels name: 2 for one interval, the run's for several
    /// regions.
    pub fn level_count(&self) -> usize {
        if self.regions.is_empty() {
            INTERVAL_LEVELS
        } else {
            self.regions.levels
        }
    }

    /// Per point: bit `1 << label` for each [`BoundaryLabel`] of the boundary triangles around
    /// it (0 for interior points).
    pub fn vertex_label_bits(&self) -> Vec<LabelBits> {
        let mut bits = vec![0; self.points.len()];
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
    /// Number of levels the labels name when the surface comes from several regions; 0 for
    /// one interval (alpha, beta).
    pub levels: usize,
}

impl TriSurface {
    /// Number of levels the labels name: 2 for one interval.
    pub fn level_count(&self) -> usize {
        self.levels.max(INTERVAL_LEVELS)
    }
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
    /// the same chunk. With several regions the interface triangles (labelled with a level
    /// between regions) are listed here too, with normals out of the region below.
    pub boundary: Vec<[u32; 3]>,
    /// Label of each boundary triangle.
    pub boundary_labels: Vec<BoundaryLabel>,
    /// Per label (in [`BoundaryLabel::ALL`] order) the bounding box `[min xyz, max xyz]` of the
    /// vertices of this chunk's triangles with that label (`±inf` when there are none).
    pub label_boxes: [[f64; 6]; NUM_LABELS],
    /// With several regions, the region of each tet (empty for one interval).
    pub regions: Vec<u8>,
    /// With several regions, the region of the tet of each triangle of `boundary` (for an
    /// interface, the region below it); empty for one interval.
    pub boundary_regions: Vec<u8>,
}

/// Where [`crate::mesh_interval_streamed`] delivers the mesh, one slab at a time.
pub trait MeshSink {
    /// Takes the next chunk (in slab order).
    ///
    /// # Errors
    /// Any I/O error: it stops the meshing run and is returned from it.
    fn chunk(&mut self, chunk: &MeshChunk) -> io::Result<()>;
}

/// A sink that takes every chunk and keeps nothing.
pub struct NoSink;

impl MeshSink for NoSink {
    fn chunk(&mut self, _: &MeshChunk) -> io::Result<()> {
        Ok(())
    }
}

/// Hands each chunk to two sinks at once (in parallel: they are independent); the first
/// sink's error comes first.
pub struct Tee<'a>(
    pub &'a mut (dyn MeshSink + Send),
    pub &'a mut (dyn MeshSink + Send),
);

impl MeshSink for Tee<'_> {
    fn chunk(&mut self, c: &MeshChunk) -> io::Result<()> {
        let (a, b) = rayon::join(|| self.0.chunk(c), || self.1.chunk(c));
        a.and(b)
    }
}

/// The name of region `k` among `names`: the given one, else `region1`, `region2`, …
/// (counting from 1).
pub fn region_name(names: &[String], k: usize) -> String {
    names
        .get(k)
        .cloned()
        .unwrap_or_else(|| format!("region{}", k + 1))
}

/// A sink that gathers the chunks into one [`TetMesh`] (the interface triangles of several
/// regions into [`Regions::interfaces`]).
#[derive(Default)]
pub(crate) struct Gather {
    pub(crate) mesh: TetMesh,
}

impl Gather {
    /// A gatherer for a run of `levels` levels.
    pub(crate) fn new(levels: usize) -> Self {
        let mut g = Gather::default();
        if levels > INTERVAL_LEVELS {
            g.mesh.regions.levels = levels;
        }
        g
    }
}

impl MeshSink for Gather {
    fn chunk(&mut self, c: &MeshChunk) -> io::Result<()> {
        let m = &mut self.mesh;
        m.points.extend_from_slice(&c.points);
        m.values.extend_from_slice(&c.values);
        m.tets.extend_from_slice(&c.tets);
        if c.boundary_regions.is_empty() {
            m.boundary.extend_from_slice(&c.boundary);
            m.boundary_labels.extend_from_slice(&c.boundary_labels);
            return Ok(());
        }
        let r = &mut m.regions;
        r.tets.extend_from_slice(&c.regions);
        for ((&t, &l), &region) in c
            .boundary
            .iter()
            .zip(&c.boundary_labels)
            .zip(&c.boundary_regions)
        {
            match l.is_interface(r.levels) {
                true => {
                    r.interfaces.push(t);
                    r.interface_labels.push(l);
                }
                false => {
                    m.boundary.push(t);
                    m.boundary_labels.push(l);
                    r.boundary.push(region);
                }
            }
        }
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
