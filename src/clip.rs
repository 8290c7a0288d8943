//! One linear tetrahedron clipped to the open interval `alpha < f < beta`.
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
//! outward by a per-run constant ([`Interval`]): the field stays linear on every tet, so each
//! clipped piece stays convex, no output point coincides with another and no tet is flat.

use std::cmp::Reverse;

use crate::geom::{cross, dot, signed_volume, sub};
use crate::keys::{cut_point, split, vertex_point, PointKey, VertexKey};
use crate::mesh::BoundaryLabel;

/// Fraction of the smallest gap between a level and the data values by which tied values are
/// moved outward when cuts are placed.
pub const TIE_FRACTION: f64 = 1e-3;

/// The clipping interval and the values tied vertices are moved to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interval {
    /// Lower bound (may be `-inf`).
    pub alpha: f64,
    /// Upper bound (may be `+inf`).
    pub beta: f64,
    /// Value used for cut placement at vertices whose value equals alpha (below alpha).
    pub alpha_tie: f64,
    /// Value used for cut placement at vertices whose value equals beta (above beta).
    pub beta_tie: f64,
}

impl Interval {
    /// The interval `(alpha, beta)` for data `values`: a tied value is moved outward by
    /// [`TIE_FRACTION`] of the smallest non-zero distance between the level and a data value
    /// (so, with integer data, by 10⁻³).
    pub fn new(alpha: f64, beta: f64, values: &crate::samples::Samples) -> Self {
        let gap = |level: f64| -> f64 {
            if !level.is_finite() {
                return 0.0;
            }
            let g = values.par_fold(
                || f64::INFINITY,
                |m, v| {
                    let d = (v - level).abs();
                    if d > 0.0 {
                        m.min(d)
                    } else {
                        m
                    }
                },
                f64::min,
            );
            if g.is_finite() {
                g
            } else {
                1.0
            }
        };
        let (ga, gb) = (gap(alpha), gap(beta));
        let width = if alpha.is_finite() && beta.is_finite() {
            beta - alpha
        } else {
            f64::INFINITY
        };
        let da = (TIE_FRACTION * ga)
            .min(0.25 * width)
            .max(alpha.abs() * 4.0 * f64::EPSILON);
        let db = (TIE_FRACTION * gb)
            .min(0.25 * width)
            .max(beta.abs() * 4.0 * f64::EPSILON);
        Interval {
            alpha,
            beta,
            alpha_tie: alpha - da,
            beta_tie: beta + db,
        }
    }
}

impl Interval {
    /// Value of a (not snapped) vertex for cut placement: tied values moved outward.
    #[inline]
    pub fn effective(&self, v: f64) -> f64 {
        if v == self.alpha {
            self.alpha_tie
        } else if v == self.beta {
            self.beta_tie
        } else {
            v
        }
    }
}

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
}

const BELOW: u8 = 1;
const ABOVE: u8 = 2;
const INSIDE: u8 = 0;

#[inline]
fn classify(v: f64, alpha: f64, beta: f64) -> u8 {
    if v <= alpha {
        BELOW
    } else if v >= beta {
        ABOVE
    } else {
        INSIDE
    }
}

/// Value of a tet vertex for cut placement: a snapped vertex is exactly on its level, a tied
/// one is moved outward.
#[inline]
fn placed(v: &ClipVertex, iv: &Interval) -> f64 {
    if v.snap == SNAP_NONE {
        iv.effective(v.val)
    } else {
        v.val
    }
}

/// Cut of edge (a, b) by `level`, computed from the key-ordered ends so that every tet
/// sharing the edge gets the bit-identical point.
#[inline]
fn cut(a: &ClipVertex, b: &ClipVertex, level: f64, which: u8, iv: &Interval) -> ClipPoint {
    let (p, q) = if a.key < b.key { (a, b) } else { (b, a) };
    let fp = placed(p, iv);
    let fq = placed(q, iv);
    let t = (level - fp) / (fq - fp);
    ClipPoint {
        key: cut_point(p.key, q.key, which),
        pos: [
            p.pos[0] + t * (q.pos[0] - p.pos[0]),
            p.pos[1] + t * (q.pos[1] - p.pos[1]),
            p.pos[2] + t * (q.pos[2] - p.pos[2]),
        ],
        val: level,
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

/// Small fixed-capacity polygon.
#[derive(Clone, Copy)]
struct Poly {
    n: usize,
    v: [usize; 8],
    label: Option<BoundaryLabel>,
}

impl Poly {
    fn new(label: Option<BoundaryLabel>) -> Self {
        Poly {
            n: 0,
            v: [0; 8],
            label,
        }
    }
    /// Appends `x` unless it repeats the previous point (a cut that is a snapped vertex).
    fn push(&mut self, x: usize) {
        if self.n > 0 && self.v[self.n - 1] == x {
            return;
        }
        self.v[self.n] = x;
        self.n += 1;
    }

    /// Drops a last point that repeats the first (closing the cycle).
    fn close(&mut self) {
        if self.n > 1 && self.v[self.n - 1] == self.v[0] {
            self.n -= 1;
        }
    }
}

/// The faces of one clipped piece: at most the four tet faces and the two level faces.
struct Faces {
    n: usize,
    polys: [Poly; 6],
}

impl Faces {
    fn push(&mut self, poly: Poly) {
        self.polys[self.n] = poly;
        self.n += 1;
    }
}

/// The points of one clipped piece: its inside tet vertices, then the cuts of its edges.
struct CutPoints {
    /// At most 4 vertices + 8 cuts (two levels on the four edges of a 2–2 split).
    pts: [ClipPoint; 12],
    np: usize,
    /// Point index of each inside tet vertex.
    vid: [usize; 4],
    /// Point indices of the cuts of each edge by `[alpha, beta]`.
    cid: [[usize; 2]; 6],
}

/// A tet vertex as an output point.
#[inline]
fn as_point(v: &ClipVertex) -> ClipPoint {
    ClipPoint {
        key: vertex_point(v.key),
        pos: v.pos,
        val: v.val,
    }
}

/// Clips tet `tv` (positively oriented) to `alpha < f < beta` and sends the pieces to `sink`.
/// `box_planes` selects which bits of [`ClipVertex::box_mask`] are grid-box planes.
/// `iv.alpha` may be `-inf` and `iv.beta` `+inf`; `alpha < beta`.
pub fn clip_tet(tv: &[ClipVertex; 4], iv: &Interval, box_planes: u8, sink: &mut impl ClipSink) {
    let cls: [u8; 4] = std::array::from_fn(|i| match tv[i].snap {
        SNAP_NONE => classify(tv[i].val, iv.alpha, iv.beta),
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
    let cuts = cut_points(tv, &cls, iv);
    // Only snapped vertices make a piece with every point on one level.
    if tv.iter().any(|v| v.snap != SNAP_NONE) && flat(&cuts.pts[..cuts.np], iv) {
        snapped_face(tv, &cls, &cuts, sink);
        return;
    }
    let mut faces = Faces {
        n: 0,
        polys: [Poly::new(None); 6],
    };
    tet_faces(&cls, box_face, &cuts, &mut faces);
    level_faces(&cls, &cuts, &mut faces);
    cone_and_fan(&cuts.pts[..cuts.np], &faces.polys[..faces.n], iv, sink);
}

/// A flat piece of three corners snapped to one level and a fourth outside (beyond that
/// level): their face is a boundary face of the domain, emitted here facing the outside
/// corner. Warping lets three snapped corners share a face only where the tet across it has
/// its fourth corner on the domain side (`crate::warp`, `Link::on_edge_ok`): that tet keeps
/// the face as an inner face of its piece, which is whole, or cut only by the other level
/// away from the face. Any other flat piece (fewer points) emits nothing.
#[inline]
fn snapped_face(tv: &[ClipVertex; 4], cls: &[u8; 4], cuts: &CutPoints, sink: &mut impl ClipSink) {
    let Some(out) = (0..4).find(|&i| cls[i] != INSIDE) else {
        return;
    };
    if cuts.np != 3 {
        return;
    }
    let label = if cls[out] == BELOW {
        BoundaryLabel::Alpha
    } else {
        BoundaryLabel::Beta
    };
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

/// The piece's points: inside vertices in vertex order, then per edge (in [`EDGES`] order)
/// its alpha cut and its beta cut.
#[inline]
fn cut_points(tv: &[ClipVertex; 4], cls: &[u8; 4], iv: &Interval) -> CutPoints {
    let mut c = CutPoints {
        pts: [ClipPoint {
            key: 0,
            pos: [0.0; 3],
            val: 0.0,
        }; 12],
        np: 0,
        vid: [usize::MAX; 4],
        cid: [[usize::MAX; 2]; 6],
    };
    for i in 0..4 {
        if cls[i] == INSIDE {
            c.pts[c.np] = as_point(&tv[i]);
            c.vid[i] = c.np;
            c.np += 1;
        }
    }
    for (e, &(i, j)) in EDGES.iter().enumerate() {
        let (ci, cj) = (cls[i], cls[j]);
        if ci == cj {
            continue;
        }
        for (which, side, level, snap) in [
            (0, BELOW, iv.alpha, SNAP_ALPHA),
            (1, ABOVE, iv.beta, SNAP_BETA),
        ] {
            if ci != side && cj != side {
                continue;
            }
            c.cid[e][which] = if tv[i].snap == snap {
                c.vid[i]
            } else if tv[j].snap == snap {
                c.vid[j]
            } else {
                c.pts[c.np] = cut(&tv[i], &tv[j], level, which as u8, iv);
                c.np += 1;
                c.np - 1
            };
        }
    }
    c
}

/// The parts of the tet's four faces inside the interval (boundary faces when on the box).
#[inline]
fn tet_faces(cls: &[u8; 4], box_face: [bool; 4], cuts: &CutPoints, faces: &mut Faces) {
    for (f, tri) in TET_FACES.iter().enumerate() {
        let mut poly = Poly::new(box_face[f].then_some(BoundaryLabel::Box));
        for s in 0..3 {
            let (p, q) = (tri[s], tri[(s + 1) % 3]);
            if cls[p] == INSIDE {
                poly.push(cuts.vid[p]);
            }
            let cid = cuts.cid[edge_index(p, q)];
            match (cls[p], cls[q]) {
                (BELOW, INSIDE) | (INSIDE, BELOW) => poly.push(cid[0]),
                (ABOVE, INSIDE) | (INSIDE, ABOVE) => poly.push(cid[1]),
                (BELOW, ABOVE) => {
                    poly.push(cid[0]);
                    poly.push(cid[1]);
                }
                (ABOVE, BELOW) => {
                    poly.push(cid[1]);
                    poly.push(cid[0]);
                }
                _ => {}
            }
        }
        poly.close();
        if poly.n >= 3 {
            faces.push(poly);
        }
    }
}

/// The level faces: alpha separates BELOW from the rest, beta ABOVE from the rest.
#[inline]
fn level_faces(cls: &[u8; 4], cuts: &CutPoints, faces: &mut Faces) {
    for (which, side, label) in [
        (0usize, BELOW, BoundaryLabel::Alpha),
        (1, ABOVE, BoundaryLabel::Beta),
    ] {
        let mut ins = [0usize; 4];
        let mut outs = [0usize; 4];
        let (mut ni, mut no) = (0, 0);
        for i in 0..4 {
            if cls[i] == side {
                ins[ni] = i;
                ni += 1;
            } else {
                outs[no] = i;
                no += 1;
            }
        }
        if ni == 0 || ni == 4 {
            continue;
        }
        let mut poly = Poly::new(Some(label));
        let mut push = |x: usize, y: usize| poly.push(cuts.cid[edge_index(x, y)][which]);
        if ni == 2 {
            let (b1, b2, r1, r2) = (ins[0], ins[1], outs[0], outs[1]);
            for (x, y) in [(b1, r1), (b1, r2), (b2, r2), (b2, r1)] {
                push(x, y);
            }
        } else {
            for &x in &ins[..ni] {
                for &y in &outs[..no] {
                    push(x, y);
                }
            }
        }
        poly.close();
        if poly.n >= 3 {
            faces.push(poly);
        }
    }
}

/// Whether every point of a piece lies on one level (a piece reduced to snapped vertices and
/// their level's cuts: it has no volume and emits nothing).
#[inline]
fn flat(pts: &[ClipPoint], iv: &Interval) -> bool {
    let on = |level: f64| pts.iter().all(|p| p.val == level);
    on(iv.alpha) || on(iv.beta)
}

/// Cones the piece from its first point in [`rank`] order over the faces not containing it,
/// each face fanned from its own first point; boundary faces also go out as triangles.
#[inline]
fn cone_and_fan(pts: &[ClipPoint], faces: &[Poly], iv: &Interval, sink: &mut impl ClipSink) {
    // Each point is ranked once (a piece has at most 12).
    let mut ranks = [(false, Reverse(0), 0); 12];
    for (r, p) in ranks.iter_mut().zip(pts) {
        *r = rank(p, iv);
    }
    let v0 = (0..pts.len()).min_by_key(|&i| ranks[i]).unwrap_or(0);
    for poly in faces {
        let verts = &poly.v[..poly.n];
        let r = (0..poly.n).min_by_key(|&i| ranks[verts[i]]).unwrap_or(0);
        let has_v0 = verts.contains(&v0);
        let inside_sign = poly.label.map(|_| inside_side(pts, verts));
        for s in 1..poly.n - 1 {
            let a = verts[r];
            let b = verts[(r + s) % poly.n];
            let c = verts[(r + s + 1) % poly.n];
            if !has_v0 {
                let vol = signed_volume(pts[v0].pos, pts[a].pos, pts[b].pos, pts[c].pos);
                if vol > 0.0 {
                    sink.tet(pts, [v0, a, b, c]);
                } else if vol < 0.0 {
                    sink.tet(pts, [v0, a, c, b]);
                }
            }
            if let (Some(label), Some(sign)) = (poly.label, inside_sign) {
                // The fan triangles keep the polygon's winding; outward means the inside is
                // on the negative side.
                if sign > 0.0 {
                    sink.triangle(pts, [a, c, b], label);
                } else {
                    sink.triangle(pts, [a, b, c], label);
                }
            }
        }
    }
}

/// The order in which a piece's points become cone apexes and fan points: vertices before
/// cuts, vertices farther from the nearer level first, then by key. A function of the point
/// alone (its identity and value), so every cell and thread agrees on it and both sides of a
/// shared face fan it the same way. Coning from the vertex deepest inside the interval, and
/// fanning from it, keeps the tets away from the flat ones whose four corners lie near the
/// level surface; it leaves about a quarter fewer tets below 15° than coning by key (noisy
/// 256³ field, T1 band: docs/QUALITY-LOG.md, *Where the bad tets come from*).
#[inline]
fn rank(p: &ClipPoint, iv: &Interval) -> (bool, Reverse<u64>, PointKey) {
    let is_cut = split(p.key).1.is_some();
    let depth = (p.val - iv.alpha).abs().min((p.val - iv.beta).abs());
    // Non-negative (or infinite, for a one-sided interval), so the bits order as the values.
    let depth = if depth.is_nan() { 0 } else { depth.to_bits() };
    (is_cut, Reverse(depth), p.key)
}

/// For a boundary face: the signed volume over the face's first three points of the piece's
/// point farthest from the face's plane, whose sign says which side is inside (robust even
/// for very thin pieces).
#[inline]
fn inside_side(pts: &[ClipPoint], verts: &[usize]) -> f64 {
    let (a, b, c) = (pts[verts[0]].pos, pts[verts[1]].pos, pts[verts[2]].pos);
    let mut best = 0.0f64;
    for p in pts {
        let v = signed_volume(a, b, c, p.pos);
        if v.abs() > best.abs() {
            best = v;
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Collect {
        vol: f64,
        tets: usize,
        area_alpha: f64,
    }
    impl ClipSink for Collect {
        fn tet(&mut self, p: &[ClipPoint], t: [usize; 4]) {
            let v = signed_volume(p[t[0]].pos, p[t[1]].pos, p[t[2]].pos, p[t[3]].pos);
            assert!(v > 0.0);
            self.vol += v;
            self.tets += 1;
        }
        fn triangle(&mut self, p: &[ClipPoint], t: [usize; 3], label: BoundaryLabel) {
            if label == BoundaryLabel::Alpha {
                for &i in &t {
                    assert_eq!(p[i].val, 0.25);
                }
                self.area_alpha += 1.0;
            }
        }
    }

    /// Volume of {alpha < x+y+z < beta} in the unit simplex-corner tet, checked against the
    /// closed form for the linear field f = x + y + z on tet (0, e1, e2, e3).
    #[test]
    fn clip_of_linear_tet_has_exact_volume() {
        let tv = [
            ClipVertex {
                key: 1 << 3,
                pos: [0.0, 0.0, 0.0],
                val: 0.0,
                box_mask: 0,
                snap: SNAP_NONE,
            },
            ClipVertex {
                key: 2 << 3,
                pos: [1.0, 0.0, 0.0],
                val: 1.0,
                box_mask: 0,
                snap: SNAP_NONE,
            },
            ClipVertex {
                key: 3 << 3,
                pos: [0.0, 1.0, 0.0],
                val: 1.0,
                box_mask: 0,
                snap: SNAP_NONE,
            },
            ClipVertex {
                key: 4 << 3,
                pos: [0.0, 0.0, 1.0],
                val: 1.0,
                box_mask: 0,
                snap: SNAP_NONE,
            },
        ];
        // volume of {x+y+z <= s} in the corner is s^3/6
        for (a, b) in [
            (0.25, 0.75),
            (f64::NEG_INFINITY, 0.5),
            (0.25, f64::INFINITY),
            (-1.0, 2.0),
        ] {
            let mut c = Collect {
                vol: 0.0,
                tets: 0,
                area_alpha: 0.0,
            };
            clip_tet(&tv, &Interval::new(a, b, &vec![0.0, 1.0].into()), 0, &mut c);
            let cube = |s: f64| s.clamp(0.0, 1.0).powi(3) / 6.0;
            let want = cube(b) - cube(a);
            assert!((c.vol - want).abs() < 1e-14, "{a} {b}: {} vs {want}", c.vol);
        }
    }
    /// Collects the emitted tets' point keys.
    struct Keys(Vec<[PointKey; 4]>);
    impl ClipSink for Keys {
        fn tet(&mut self, p: &[ClipPoint], t: [usize; 4]) {
            self.0.push(t.map(|i| p[i].key));
        }
        fn triangle(&mut self, _: &[ClipPoint], _: [usize; 3], _: BoundaryLabel) {}
    }

    /// A prism piece (two vertices inside, two below) is coned from the vertex deeper inside
    /// the interval, whichever key is smaller: every tet has it as a corner.
    #[test]
    fn pieces_are_coned_from_their_deepest_vertex() {
        let iv = Interval::new(0.0, 1.0, &vec![-1.0, 1.0].into());
        let pos = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ];
        for (shallow, deep) in [(0.1, 0.5), (0.95, 0.6)] {
            for deep_first in [false, true] {
                // Corners 0 and 1 are inside; the deep one has the larger key unless
                // `deep_first`.
                let vals = [shallow, deep, -1.0, -1.0];
                let mut keys = [1u64 << 3, 2 << 3, 3 << 3, 4 << 3];
                if deep_first {
                    keys.swap(0, 1);
                }
                let tv: [ClipVertex; 4] = std::array::from_fn(|i| ClipVertex {
                    key: keys[i],
                    pos: pos[i],
                    val: vals[i],
                    box_mask: 0,
                    snap: SNAP_NONE,
                });
                let mut out = Keys(Vec::new());
                clip_tet(&tv, &iv, 0, &mut out);
                let apex = vertex_point(keys[1]);
                assert_eq!(out.0.len(), 3, "a prism makes three tets");
                assert!(
                    out.0.iter().all(|t| t.contains(&apex)),
                    "{shallow} {deep} {deep_first}: not coned from the deepest vertex"
                );
            }
        }
    }

    #[test]
    fn edge_index_inverts_edges() {
        let hand = [[9, 0, 1, 2], [0, 9, 3, 4], [1, 3, 9, 5], [2, 4, 5, 9]];
        for i in 0..4 {
            for j in 0..4 {
                if i != j {
                    assert_eq!(edge_index(i, j), hand[i][j]);
                    assert_eq!(EDGES[edge_index(i, j)], (i.min(j), i.max(j)));
                }
            }
        }
    }

    /// Every output tet and boundary triangle of one clip, as point keys.
    #[derive(Default)]
    struct Record {
        tets: Vec<[ClipPoint; 4]>,
        tris: Vec<([ClipPoint; 3], BoundaryLabel)>,
    }
    impl ClipSink for Record {
        fn tet(&mut self, p: &[ClipPoint], t: [usize; 4]) {
            self.tets.push(t.map(|i| p[i]));
        }
        fn triangle(&mut self, p: &[ClipPoint], t: [usize; 3], label: BoundaryLabel) {
            self.tris.push((t.map(|i| p[i]), label));
        }
    }

    /// Volume of `{f < s}` in the tet `pos` with linear `f` given by its vertex values,
    /// computed without the clipper: the cubic closed forms when one or three vertices are
    /// below `s`, an explicit three-tet split of the wedge when two are.
    fn sublevel_volume(pos: &[[f64; 3]; 4], val: &[f64; 4], s: f64) -> f64 {
        let vol = signed_volume(pos[0], pos[1], pos[2], pos[3]);
        let mut o = [0usize, 1, 2, 3];
        o.sort_by(|&a, &b| val[a].total_cmp(&val[b]));
        let f = o.map(|i| val[i]);
        let p = o.map(|i| pos[i]);
        let below = f.iter().filter(|&&x| x < s).count();
        let at = |i: usize, j: usize| {
            let t = (s - f[i]) / (f[j] - f[i]);
            [0, 1, 2].map(|r| p[i][r] + t * (p[j][r] - p[i][r]))
        };
        match below {
            0 => 0.0,
            1 => vol * (s - f[0]).powi(3) / ((f[1] - f[0]) * (f[2] - f[0]) * (f[3] - f[0])),
            2 => {
                // prism (p0, c02, c03) – (p1, c12, c13), lateral edges p0p1, c02c12, c03c13
                let (a, b) = ([p[0], at(0, 2), at(0, 3)], [p[1], at(1, 2), at(1, 3)]);
                [
                    [a[0], a[1], a[2], b[2]],
                    [a[0], a[1], b[1], b[2]],
                    [a[0], b[0], b[1], b[2]],
                ]
                .iter()
                .map(|t| signed_volume(t[0], t[1], t[2], t[3]).abs())
                .sum()
            }
            3 => vol * (1.0 - (f[3] - s).powi(3) / ((f[3] - f[0]) * (f[3] - f[1]) * (f[3] - f[2]))),
            _ => vol,
        }
    }

    /// Sorted key triple of a triangle.
    fn tri_key(t: [PointKey; 3]) -> [PointKey; 3] {
        let mut k = t;
        k.sort();
        k
    }

    /// Checks one clip: positive pieces, the closed-form volume, and a closed boundary (each
    /// tet face shared by two pieces or emitted as a boundary triangle lying on its level or
    /// on its tet face, and every boundary edge used twice).
    fn check_clip(tv: &[ClipVertex; 4], iv: &Interval, case: &str) {
        let mut rec = Record::default();
        // each tet face f is on box plane f, so every boundary triangle is emitted
        clip_tet(tv, iv, 0b1111, &mut rec);
        if let Some(out) = snapped_face_corner(tv, iv) {
            check_snapped_face(tv, out, &rec, case);
            return;
        }
        let pos = tv.map(|v| v.pos);
        let eff = tv.map(|v| placed(&v, iv));
        let want = sublevel_volume(&pos, &eff, iv.beta) - sublevel_volume(&pos, &eff, iv.alpha);
        let (got, faces) = pieces(&rec, case);
        let scale = signed_volume(pos[0], pos[1], pos[2], pos[3]);
        assert!(
            (got - want).abs() <= 1e-9 * scale,
            "{case}: volume {got} vs {want}"
        );
        let mut boundary: std::collections::HashMap<[PointKey; 3], BoundaryLabel> =
            Default::default();
        let mut edges: std::collections::HashMap<[PointKey; 2], usize> = Default::default();
        for (t, label) in &rec.tris {
            check_on_boundary(tv, iv, t, *label, case);
            let k = t.map(|p| p.key);
            assert!(
                boundary.insert(tri_key(k), *label).is_none(),
                "{case}: twice"
            );
            for e in 0..3 {
                let (a, b) = (k[e], k[(e + 1) % 3]);
                *edges.entry([a.min(b), a.max(b)]).or_default() += 1;
            }
        }
        for (tri, n) in &faces {
            match n {
                1 => assert!(boundary.contains_key(tri), "{case}: open face {tri:?}"),
                2 => assert!(
                    !boundary.contains_key(tri),
                    "{case}: inner face on boundary"
                ),
                _ => panic!("{case}: face used {n} times"),
            }
        }
        let once = faces.values().filter(|&&n| n == 1).count();
        assert_eq!(
            once,
            boundary.len(),
            "{case}: boundary triangle without a tet"
        );
        assert!(
            edges.values().all(|&n| n == 2),
            "{case}: boundary not closed"
        );
    }

    /// If three corners are snapped to one level and the fourth lies beyond it (the piece
    /// is their face, with no volume): the fourth.
    fn snapped_face_corner(tv: &[ClipVertex; 4], iv: &Interval) -> Option<usize> {
        [(SNAP_ALPHA, BELOW), (SNAP_BETA, ABOVE)]
            .into_iter()
            .find_map(|(snap, side)| {
                let snapped = tv.iter().filter(|v| v.snap == snap).count();
                let out = (0..4).find(|&i| tv[i].snap != snap)?;
                let beyond = classify(tv[out].val, iv.alpha, iv.beta) == side;
                (snapped == 3 && tv[out].snap == SNAP_NONE && beyond).then_some(out)
            })
    }

    /// The flat piece of three snapped corners: no tet, and their face as one boundary
    /// triangle of their level whose normal points at the outside corner `out` (the domain
    /// is the tet across the face).
    fn check_snapped_face(tv: &[ClipVertex; 4], out: usize, rec: &Record, case: &str) {
        assert!(rec.tets.is_empty(), "{case}: a flat piece made tets");
        let [(t, label)] = rec.tris.as_slice() else {
            panic!("{case}: {} triangles instead of one", rec.tris.len());
        };
        let want = match tv[(out + 1) % 4].snap {
            SNAP_ALPHA => BoundaryLabel::Alpha,
            _ => BoundaryLabel::Beta,
        };
        assert_eq!(*label, want, "{case}");
        let corners = (0..4)
            .filter(|&i| i != out)
            .map(|i| vertex_point(tv[i].key));
        let mut keys: Vec<PointKey> = corners.collect();
        keys.sort_unstable();
        assert_eq!(tri_key(t.map(|p| p.key)).to_vec(), keys, "{case}");
        let normal = cross(sub(t[1].pos, t[0].pos), sub(t[2].pos, t[0].pos));
        assert!(
            dot(normal, sub(tv[out].pos, t[0].pos)) > 0.0,
            "{case}: the face points away from the outside corner"
        );
    }

    /// Total volume of the pieces (each checked positive) and how often each face occurs.
    fn pieces(rec: &Record, case: &str) -> (f64, std::collections::HashMap<[PointKey; 3], usize>) {
        let mut got = 0.0;
        let mut faces: std::collections::HashMap<[PointKey; 3], usize> = Default::default();
        for t in &rec.tets {
            let v = signed_volume(t[0].pos, t[1].pos, t[2].pos, t[3].pos);
            assert!(v > 0.0, "{case}: piece volume {v}");
            got += v;
            for skip in 0..4 {
                let k = [0, 1, 2, 3].map(|i| t[i].key);
                let tri = [k[(skip + 1) % 4], k[(skip + 2) % 4], k[(skip + 3) % 4]];
                *faces.entry(tri_key(tri)).or_default() += 1;
            }
        }
        (got, faces)
    }

    /// A boundary triangle lies on its level, or (box) within one face of the tet.
    fn check_on_boundary(
        tv: &[ClipVertex; 4],
        iv: &Interval,
        t: &[ClipPoint; 3],
        label: BoundaryLabel,
        case: &str,
    ) {
        match label {
            BoundaryLabel::Alpha => assert!(t.iter().all(|p| p.val == iv.alpha), "{case}"),
            BoundaryLabel::Beta => assert!(t.iter().all(|p| p.val == iv.beta), "{case}"),
            _ => {
                let on = |f: usize| {
                    let [a, b, c] = TET_FACES[f].map(|i| tv[i].key);
                    t.iter().all(|p| {
                        let (x, rest) = crate::keys::split(p.key);
                        let y = rest.map_or(x, |r| r.0);
                        [x, y].iter().all(|k| [a, b, c].contains(k))
                    })
                };
                assert!((0..4).any(on), "{case}: box triangle off the tet faces");
            }
        }
    }

    fn rng(seed: &mut u64) -> f64 {
        *seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((*seed >> 11) as f64) / ((1u64 << 53) as f64)
    }

    /// Every class pattern of the four vertices (below, equal to alpha, inside, equal to
    /// beta, above), for a two-sided interval and both one-sided ones, on random tets with
    /// random key orders.
    #[test]
    fn clip_every_class_pattern() {
        let mut seed = 7u64;
        let (inf, alpha, beta) = (f64::INFINITY, -0.5, 1.5);
        for (a, b) in [(alpha, beta), (alpha, inf), (-inf, beta)] {
            // 0 below, 1 = alpha, 2 inside, 3 = beta, 4 above, 5 snapped to alpha, 6 snapped
            // to beta; skip classes a bound rules out
            let classes: Vec<usize> = (0..7)
                .filter(|&c| a.is_finite() || !matches!(c, 0 | 1 | 5))
                .filter(|&c| b.is_finite() || !matches!(c, 3 | 4 | 6))
                .collect();
            let n = classes.len();
            for pattern in 0..n.pow(4) {
                let cls: [usize; 4] =
                    std::array::from_fn(|i| classes[pattern / n.pow(i as u32) % n]);
                if !snaps_possible(&cls) {
                    continue;
                }
                for _ in 0..4 {
                    let tv = random_tet(&mut seed, cls, alpha, beta);
                    let vals: Vec<f64> = tv.iter().map(|v| v.val).collect();
                    let iv = Interval::new(a, b, &vals.into());
                    check_clip(&tv, &iv, &format!("({a}, {b}) classes {cls:?}"));
                }
            }
        }
    }

    /// A positively oriented random tet with vertex values of the given classes and shuffled
    /// keys.
    /// Whether `warp` can make these classes: at most three corners snapped to one level
    /// (`warp`'s `Link::on_edge_ok`: a fourth would be a tet with four corners on it).
    fn snaps_possible(cls: &[usize; 4]) -> bool {
        let count = |c: usize| cls.iter().filter(|&&x| x == c).count();
        count(5) <= 3 && count(6) <= 3
    }

    fn random_tet(seed: &mut u64, cls: [usize; 4], alpha: f64, beta: f64) -> [ClipVertex; 4] {
        let mut pos: [[f64; 3]; 4] = std::array::from_fn(|_| [0; 3].map(|_| rng(seed) * 2.0));
        while signed_volume(pos[0], pos[1], pos[2], pos[3]).abs() < 0.05 {
            pos = std::array::from_fn(|_| [0; 3].map(|_| rng(seed) * 2.0));
        }
        if signed_volume(pos[0], pos[1], pos[2], pos[3]) < 0.0 {
            pos.swap(2, 3);
        }
        let mut keys = [1u64, 2, 3, 4].map(|k| (k << 3) | (rng(seed) * 8.0) as u64);
        for i in (1..4).rev() {
            keys.swap(i, (rng(seed) * (i + 1) as f64) as usize);
        }
        std::array::from_fn(|i| ClipVertex {
            key: keys[i] + ((i as u64) << 8),
            pos: pos[i],
            val: match cls[i] {
                0 => alpha - 0.1 - rng(seed),
                1 => alpha,
                2 => alpha + (0.05 + 0.9 * rng(seed)) * (beta - alpha),
                3 | 6 => beta,
                5 => alpha,
                _ => beta + 0.1 + rng(seed),
            },
            box_mask: 0b1111 & !(1 << i),
            snap: match cls[i] {
                5 => SNAP_ALPHA,
                6 => SNAP_BETA,
                _ => SNAP_NONE,
            },
        })
    }
}
