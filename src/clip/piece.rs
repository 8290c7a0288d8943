//! The convex piece of one clipped tet: its points (the inside tet vertices and the cuts of
//! its edges by the two levels) and its faces (the parts of the tet's faces inside the
//! interval, and the level faces).

use super::{
    as_point, edge_index, placed, ClipPoint, ClipVertex, ABOVE, BELOW, EDGES, INSIDE, SNAP_ALPHA,
    SNAP_BETA, TET_FACES,
};
use crate::keys::cut_point;
use crate::levels::Bounds;
use crate::mesh::BoundaryLabel;

/// Cut of edge (a, b) by `level` (index `which` in the run), computed from the key-ordered
/// ends so that every tet sharing the edge gets the bit-identical point.
#[inline]
fn cut(a: &ClipVertex, b: &ClipVertex, level: f64, which: u8, lv: &Bounds) -> ClipPoint {
    let (p, q) = if a.key < b.key { (a, b) } else { (b, a) };
    let fp = placed(p, lv);
    let fq = placed(q, lv);
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

/// Small fixed-capacity polygon (point indices as bytes: a piece has at most 12 points, and
/// the faces are copied around).
#[derive(Clone, Copy)]
pub(super) struct Poly {
    pub(super) n: usize,
    pub(super) v: [u8; 8],
    pub(super) label: Option<BoundaryLabel>,
}

impl Poly {
    pub(super) fn new(label: Option<BoundaryLabel>) -> Self {
        Poly {
            n: 0,
            v: [0; 8],
            label,
        }
    }
    /// Appends `x` unless it repeats the previous point (a cut that is a snapped vertex).
    fn push(&mut self, x: u8) {
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
pub(super) struct Faces {
    pub(super) n: usize,
    pub(super) polys: [Poly; 6],
}

impl Faces {
    /// A new empty face labelled `label`, built in place (after the faces kept so far).
    fn start(&mut self, label: Option<BoundaryLabel>) -> &mut Poly {
        let poly = &mut self.polys[self.n];
        *poly = Poly::new(label);
        poly
    }

    /// Closes the face begun by [`Faces::start`] and keeps it if it has three points or more.
    fn finish(&mut self) {
        let poly = &mut self.polys[self.n];
        poly.close();
        if poly.n >= 3 {
            self.n += 1;
        }
    }
}

/// The points of one clipped piece: its inside tet vertices, then the cuts of its edges.
pub(super) struct CutPoints {
    /// At most 4 vertices + 8 cuts (two levels on the four edges of a 2–2 split).
    pub(super) pts: [ClipPoint; 12],
    pub(super) np: usize,
    /// Point index of each inside tet vertex.
    pub(super) vid: [u8; 4],
    /// Point indices of the cuts of each edge by `[alpha, beta]`.
    pub(super) cid: [[u8; 2]; 6],
}

/// The piece's points: inside vertices in vertex order, then per edge (in [`EDGES`] order)
/// its alpha cut and its beta cut.
#[inline]
pub(super) fn cut_points(tv: &[ClipVertex; 4], cls: &[u8; 4], lv: &Bounds) -> CutPoints {
    let mut c = CutPoints {
        pts: [ClipPoint {
            key: 0,
            pos: [0.0; 3],
            val: 0.0,
        }; 12],
        np: 0,
        vid: [u8::MAX; 4],
        cid: [[u8::MAX; 2]; 6],
    };
    for i in 0..4 {
        if cls[i] == INSIDE {
            c.pts[c.np] = as_point(&tv[i]);
            c.vid[i] = c.np as u8;
            c.np += 1;
        }
    }
    for (e, &(i, j)) in EDGES.iter().enumerate() {
        let (ci, cj) = (cls[i], cls[j]);
        if ci == cj {
            continue;
        }
        for (which, side, level, snap) in [
            (0, BELOW, lv.get(0), SNAP_ALPHA),
            (1, ABOVE, lv.get(1), SNAP_BETA),
        ] {
            if ci != side && cj != side {
                continue;
            }
            c.cid[e][which] = if tv[i].snap == snap {
                c.vid[i]
            } else if tv[j].snap == snap {
                c.vid[j]
            } else {
                c.pts[c.np] = cut(&tv[i], &tv[j], level, lv.global(which), lv);
                c.np += 1;
                (c.np - 1) as u8
            };
        }
    }
    c
}

/// The parts of the tet's four faces inside the interval (boundary faces when on the box).
#[inline]
pub(super) fn tet_faces(cls: &[u8; 4], box_face: [bool; 4], cuts: &CutPoints, faces: &mut Faces) {
    for (f, tri) in TET_FACES.iter().enumerate() {
        let poly = faces.start(box_face[f].then_some(BoundaryLabel::Box));
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
        faces.finish();
    }
}

/// The level faces: level 0 separates BELOW from the rest, level 1 ABOVE from the rest
/// (labelled by their indices in the run).
#[inline]
pub(super) fn level_faces(cls: &[u8; 4], cuts: &CutPoints, lv: &Bounds, faces: &mut Faces) {
    for (which, side) in [(0usize, BELOW), (1, ABOVE)] {
        let label = BoundaryLabel::Level(lv.global(which));
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
        let poly = faces.start(Some(label));
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
        faces.finish();
    }
}
