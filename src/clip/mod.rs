//! One linear tetrahedron clipped to the open interval `alpha < f < beta` between two levels
//! (one interval, or one region of several: the levels' indices in the run name the cuts and
//! the boundary labels).
//!
//! The clipped piece is a convex polytope whose vertices are the tet's inside vertices and the
//! cuts of its edges by the two levels. It is split into tets by coning from its first point
//! in a global order over the faces that do not contain it, each face fanned from *its* first
//! point. The order ranks vertices before cuts, vertices deeper inside the interval first,
//! then keys (`rank`): a function of the point alone, so a face shared with a neighbouring tet
//! is the same polygon with the same order on both sides, and both sides triangulate it the
//! same way: the mesh conforms.
//!
//! **Ties.** A value equal to alpha counts as below and one equal to beta as above (the mesh
//! is the closure of the open interval). For placing cuts, a tied vertex's value is moved
//! outward by a per-run constant ([`Bounds::tie`]): the field stays linear on every tet, so each
//! clipped piece stays convex, no output point coincides with another and no tet is flat.

mod cone;
mod piece;

use crate::geom::{cross, dot, sub};
use crate::keys::{vertex_point, PointKey, VertexKey};
use crate::levels::Bounds;
use crate::mesh::BoundaryLabel;
use cone::cone_and_fan;
use piece::{cut_points, level_faces, tet_faces, CutPoints, Faces, Poly};

/// A tet vertex handed to the clipper.
#[derive(Clone, Copy, Debug)]
pub struct ClipVertex {
    /// Global identity.
    pub key: VertexKey,
    /// Position (any affine frame; the output uses the same frame).
    pub pos: [f64; 3],
    /// Field value.
    pub val: f64,
    /// Bit mask of the grid-box planes the vertex lies on (used to label box faces).
    pub box_mask: u8,
    /// [`SNAP_NONE`], or the level the vertex was moved onto before clipping
    /// ([`SNAP_ALPHA`], [`SNAP_BETA`]; see `crate::warp`). A snapped vertex has `val` equal
    /// to its level and counts as inside: it is a point of the piece, and the cuts of its
    /// edges by its own level are the vertex itself.
    pub snap: u8,
}

/// [`ClipVertex::snap`]: not moved onto a level.
pub const SNAP_NONE: u8 = 0;
/// [`ClipVertex::snap`]: moved onto alpha.
pub const SNAP_ALPHA: u8 = 1;
/// [`ClipVertex::snap`]: moved onto beta.
pub const SNAP_BETA: u8 = 2;

/// An output point of the clipper.
#[derive(Clone, Copy, Debug)]
pub struct ClipPoint {
    /// Global identity.
    pub key: PointKey,
    /// Position.
    pub pos: [f64; 3],
    /// Field value (exactly alpha or beta for cuts).
    pub val: f64,
}

/// Receives the clipper's output. Point arguments are indices into the `points` slice
/// passed alongside.
pub trait ClipSink {
    /// A positively oriented tet.
    fn tet(&mut self, points: &[ClipPoint], t: [usize; 4]);
    /// An outward-oriented boundary triangle.
    fn triangle(&mut self, points: &[ClipPoint], t: [usize; 3], label: BoundaryLabel);
    /// Whether the sink keeps triangles labelled `label` (when not, the clipper may skip
    /// orienting them; [`ClipSink::triangle`] may still be called and must drop them).
    #[inline]
    fn keeps(&self, _label: BoundaryLabel) -> bool {
        true
    }
}

const BELOW: u8 = 1;
const ABOVE: u8 = 2;
const INSIDE: u8 = 0;

#[inline]
fn classify(v: f64, lv: &Bounds) -> u8 {
    if lv.below(0, v) {
        BELOW
    } else if lv.above(1, v) {
        ABOVE
    } else {
        INSIDE
    }
}

/// Value of a tet vertex for cut placement: a snapped vertex is exactly on its level, a tied
/// one is moved outward.
#[inline]
fn placed(v: &ClipVertex, lv: &Bounds) -> f64 {
    if v.snap == SNAP_NONE {
        lv.effective(v.val)
    } else {
        v.val
    }
}

/// The six edges of a tet as vertex pairs `(i, j)`, `i < j`.
const EDGES: [(usize, usize); 6] = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)];

/// `EDGE_INDEX[i][j]`: the index in [`EDGES`] of edge `{i, j}` (`usize::MAX` on the diagonal).
const EDGE_INDEX: [[usize; 4]; 4] = edge_index_table();

/// Inverts [`EDGES`] into a symmetric vertex-pair table.
const fn edge_index_table() -> [[usize; 4]; 4] {
    let mut t = [[usize::MAX; 4]; 4];
    let mut e = 0;
    while e < EDGES.len() {
        let (a, b) = EDGES[e];
        t[a][b] = e;
        t[b][a] = e;
        e += 1;
    }
    t
}

/// Index in [`EDGES`] of the edge `{i, j}` (`i != j`).
#[inline]
fn edge_index(i: usize, j: usize) -> usize {
    EDGE_INDEX[i][j]
}

/// Faces of a tet as (opposite vertex, cyclic vertex order).
const TET_FACES: [[usize; 3]; 4] = [[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]];

/// A tet vertex as an output point.
#[inline]
fn as_point(v: &ClipVertex) -> ClipPoint {
    ClipPoint {
        key: vertex_point(v.key),
        pos: v.pos,
        val: v.val,
    }
}

/// Clips tet `tv` (positively oriented) to the interval between levels 0 and 1 of `lv`
/// (`alpha < f < beta`) and sends the pieces to `sink`. `box_planes` selects which bits of
/// [`ClipVertex::box_mask`] are grid-box planes. Level 0 may be `-inf` and level 1 `+inf`.
pub fn clip_tet(tv: &[ClipVertex; 4], lv: &Bounds, box_planes: u8, sink: &mut impl ClipSink) {
    let cls: [u8; 4] = std::array::from_fn(|i| match tv[i].snap {
        SNAP_NONE => classify(tv[i].val, lv),
        _ => INSIDE,
    });
    if cls.iter().all(|&c| c == BELOW) || cls.iter().all(|&c| c == ABOVE) {
        return;
    }
    // Face planes on the grid box.
    let box_face: [bool; 4] = std::array::from_fn(|f| {
        let [a, b, c] = TET_FACES[f];
        tv[a].box_mask & tv[b].box_mask & tv[c].box_mask & box_planes != 0
    });
    if cls == [INSIDE; 4] {
        emit_whole(tv, box_face, sink);
        return;
    }
    let cuts = cut_points(tv, &cls, lv);
    // Only snapped vertices make a piece with every point on one level.
    if tv.iter().any(|v| v.snap != SNAP_NONE) && flat(&cuts.pts[..cuts.np], lv) {
        snapped_face(tv, &cls, &cuts, lv, sink);
        return;
    }
    let mut faces = Faces {
        n: 0,
        polys: [Poly::new(None); 6],
    };
    tet_faces(&cls, box_face, &cuts, &mut faces);
    level_faces(&cls, &cuts, lv, &mut faces);
    cone_and_fan(&cuts.pts[..cuts.np], &faces.polys[..faces.n], lv, sink);
}

/// A flat piece of three corners snapped to one level and a fourth outside (beyond that
/// level): their face is a boundary face of the domain, emitted here facing the outside
/// corner. Warping lets three snapped corners share a face only where the tet across it has
/// its fourth corner on the domain side (`crate::warp`, `Link::on_edge_ok`): that tet keeps
/// the face as an inner face of its piece, which is whole, or cut only by the other level
/// away from the face. Any other flat piece (fewer points) emits nothing.
#[inline]
fn snapped_face(
    tv: &[ClipVertex; 4],
    cls: &[u8; 4],
    cuts: &CutPoints,
    lv: &Bounds,
    sink: &mut impl ClipSink,
) {
    let Some(out) = (0..4).find(|&i| cls[i] != INSIDE) else {
        return;
    };
    if cuts.np != 3 {
        return;
    }
    let label = BoundaryLabel::Level(lv.global(usize::from(cls[out] != BELOW)));
    let p = &cuts.pts[..3];
    let normal = cross(sub(p[1].pos, p[0].pos), sub(p[2].pos, p[0].pos));
    // Outward: the domain (the tet across) on the side away from the outside corner.
    if dot(normal, sub(tv[out].pos, p[0].pos)) > 0.0 {
        sink.triangle(p, [0, 1, 2], label);
    } else {
        sink.triangle(p, [0, 2, 1], label);
    }
}

/// A tet entirely inside: itself, plus its box faces.
#[inline]
fn emit_whole(tv: &[ClipVertex; 4], box_face: [bool; 4], sink: &mut impl ClipSink) {
    let pts = [
        as_point(&tv[0]),
        as_point(&tv[1]),
        as_point(&tv[2]),
        as_point(&tv[3]),
    ];
    sink.tet(&pts, [0, 1, 2, 3]);
    for f in 0..4 {
        if box_face[f] {
            let [a, b, c] = TET_FACES[f];
            sink.triangle(&pts, [a, b, c], BoundaryLabel::Box);
        }
    }
}

/// Whether every point of a piece lies on one level (a piece reduced to snapped vertices and
/// their level's cuts: it has no volume and emits nothing).
#[inline]
fn flat(pts: &[ClipPoint], lv: &Bounds) -> bool {
    let on = |level: f64| pts.iter().all(|p| p.val == level);
    on(lv.get(0)) || on(lv.get(1))
}

#[cfg(test)]
mod tests;
