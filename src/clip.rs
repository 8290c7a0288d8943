//! One linear tetrahedron clipped to the open interval `alpha < f < beta`.
//!
//! The clipped piece is a convex polytope whose vertices are the tet's inside vertices and the
//! cuts of its edges by the two levels. It is split into tets by coning from its smallest-key
//! vertex over the faces that do not contain it, each face fanned from *its* smallest-key
//! vertex. A face shared with a neighbouring tet is the same polygon with the same keys on
//! both sides, so both sides triangulate it the same way: the mesh conforms.
//!
//! **Ties.** A value equal to alpha counts as below and one equal to beta as above (the mesh
//! is the closure of the open interval). For placing cuts, a tied vertex's value is moved
//! outward by a per-run constant ([`Interval`]): the field stays linear on every tet, so each
//! clipped piece stays convex, no output point coincides with another and no tet is flat.

use crate::geom::signed_volume;
use crate::keys::{cut_point, vertex_point, PointKey, VertexKey};
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
    pub fn new(alpha: f64, beta: f64, values: &[f64]) -> Self {
        let gap = |level: f64| -> f64 {
            if !level.is_finite() {
                return 0.0;
            }
            use rayon::prelude::*;
            let g = values
                .par_iter()
                .map(|&v| (v - level).abs())
                .filter(|&d| d > 0.0)
                .reduce(|| f64::INFINITY, f64::min);
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
}

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

/// Value of a vertex for cut placement (moves tied values outward).
#[inline]
fn effective(v: f64, iv: &Interval) -> f64 {
    if v == iv.alpha {
        iv.alpha_tie
    } else if v == iv.beta {
        iv.beta_tie
    } else {
        v
    }
}

/// Cut of edge (a, b) by `level`, computed from the key-ordered ends so that every tet
/// sharing the edge gets the bit-identical point.
#[inline]
fn cut(a: &ClipVertex, b: &ClipVertex, level: f64, which: u8, iv: &Interval) -> ClipPoint {
    let (p, q) = if a.key < b.key { (a, b) } else { (b, a) };
    let fp = effective(p.val, iv);
    let fq = effective(q.val, iv);
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

const EDGES: [(usize, usize); 6] = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)];

#[inline]
fn edge_index(i: usize, j: usize) -> usize {
    let (a, b) = if i < j { (i, j) } else { (j, i) };
    match (a, b) {
        (0, 1) => 0,
        (0, 2) => 1,
        (0, 3) => 2,
        (1, 2) => 3,
        (1, 3) => 4,
        _ => 5,
    }
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
    fn push(&mut self, x: usize) {
        self.v[self.n] = x;
        self.n += 1;
    }
}

/// Clips tet `tv` (positively oriented) to `alpha < f < beta` and sends the pieces to `sink`.
/// `box_planes` selects which bits of [`ClipVertex::box_mask`] are grid-box planes.
/// `iv.alpha` may be `-inf` and `iv.beta` `+inf`; `alpha < beta`.
pub fn clip_tet(tv: &[ClipVertex; 4], iv: &Interval, box_planes: u8, sink: &mut impl ClipSink) {
    let (alpha, beta) = (iv.alpha, iv.beta);
    let cls: [u8; 4] = std::array::from_fn(|i| classify(tv[i].val, alpha, beta));
    if cls.iter().all(|&c| c == BELOW) || cls.iter().all(|&c| c == ABOVE) {
        return;
    }
    // Face planes on the grid box.
    let box_face: [bool; 4] = std::array::from_fn(|f| {
        let [a, b, c] = TET_FACES[f];
        tv[a].box_mask & tv[b].box_mask & tv[c].box_mask & box_planes != 0
    });
    let as_point = |v: &ClipVertex| ClipPoint {
        key: vertex_point(v.key),
        pos: v.pos,
        val: v.val,
    };
    if cls == [INSIDE; 4] {
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
        return;
    }
    // At most 4 vertices + 8 cuts (two levels on the four edges of a 2–2 split).
    let mut pts: [ClipPoint; 12] = [ClipPoint {
        key: 0,
        pos: [0.0; 3],
        val: 0.0,
    }; 12];
    let mut np = 0;
    let mut vid = [usize::MAX; 4];
    for i in 0..4 {
        if cls[i] == INSIDE {
            pts[np] = as_point(&tv[i]);
            vid[i] = np;
            np += 1;
        }
    }
    // cut ids per edge: [alpha, beta]
    let mut cid = [[usize::MAX; 2]; 6];
    for (e, &(i, j)) in EDGES.iter().enumerate() {
        let (ci, cj) = (cls[i], cls[j]);
        if ci == cj {
            continue;
        }
        if ci == BELOW || cj == BELOW {
            pts[np] = cut(&tv[i], &tv[j], alpha, 0, iv);
            cid[e][0] = np;
            np += 1;
        }
        if ci == ABOVE || cj == ABOVE {
            pts[np] = cut(&tv[i], &tv[j], beta, 1, iv);
            cid[e][1] = np;
            np += 1;
        }
    }
    let pts = &pts[..np];
    let mut faces: [Poly; 6] = [Poly::new(None); 6];
    let mut nfaces = 0;
    for (f, tri) in TET_FACES.iter().enumerate() {
        let mut poly = Poly::new(if box_face[f] {
            Some(BoundaryLabel::Box)
        } else {
            None
        });
        for s in 0..3 {
            let (p, q) = (tri[s], tri[(s + 1) % 3]);
            if cls[p] == INSIDE {
                poly.push(vid[p]);
            }
            let e = edge_index(p, q);
            match (cls[p], cls[q]) {
                (BELOW, INSIDE) | (INSIDE, BELOW) => poly.push(cid[e][0]),
                (ABOVE, INSIDE) | (INSIDE, ABOVE) => poly.push(cid[e][1]),
                (BELOW, ABOVE) => {
                    poly.push(cid[e][0]);
                    poly.push(cid[e][1]);
                }
                (ABOVE, BELOW) => {
                    poly.push(cid[e][1]);
                    poly.push(cid[e][0]);
                }
                _ => {}
            }
        }
        if poly.n >= 3 {
            faces[nfaces] = poly;
            nfaces += 1;
        }
    }
    // Level faces: alpha separates BELOW from the rest, beta ABOVE from the rest.
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
        if ni == 2 {
            let (b1, b2, r1, r2) = (ins[0], ins[1], outs[0], outs[1]);
            for (x, y) in [(b1, r1), (b1, r2), (b2, r2), (b2, r1)] {
                poly.push(cid[edge_index(x, y)][which]);
            }
        } else {
            for &x in &ins[..ni] {
                for &y in &outs[..no] {
                    poly.push(cid[edge_index(x, y)][which]);
                }
            }
        }
        faces[nfaces] = poly;
        nfaces += 1;
    }
    // Cone from the smallest-key vertex.
    let v0 = (0..np).min_by_key(|&i| pts[i].key).unwrap_or(0);
    for poly in &faces[..nfaces] {
        let verts = &poly.v[..poly.n];
        let r = (0..poly.n).min_by_key(|&i| pts[verts[i]].key).unwrap_or(0);
        let has_v0 = verts.contains(&v0);
        // For a boundary face: the polytope vertex farthest from the face's plane says which
        // side is inside (robust even for very thin pieces).
        let inside_sign = poly.label.map(|_| {
            let (a, b, c) = (pts[verts[0]].pos, pts[verts[1]].pos, pts[verts[2]].pos);
            let mut best = 0.0f64;
            for p in pts {
                let v = signed_volume(a, b, c, p.pos);
                if v.abs() > best.abs() {
                    best = v;
                }
            }
            best
        });
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
            },
            ClipVertex {
                key: 2 << 3,
                pos: [1.0, 0.0, 0.0],
                val: 1.0,
                box_mask: 0,
            },
            ClipVertex {
                key: 3 << 3,
                pos: [0.0, 1.0, 0.0],
                val: 1.0,
                box_mask: 0,
            },
            ClipVertex {
                key: 4 << 3,
                pos: [0.0, 0.0, 1.0],
                val: 1.0,
                box_mask: 0,
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
            clip_tet(&tv, &Interval::new(a, b, &[0.0, 1.0]), 0, &mut c);
            let cube = |s: f64| s.clamp(0.0, 1.0).powi(3) / 6.0;
            let want = cube(b) - cube(a);
            assert!((c.vol - want).abs() < 1e-14, "{a} {b}: {} vs {want}", c.vol);
        }
    }
}
