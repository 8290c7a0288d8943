//! Triangulation of one convex clipped piece: coned from its first point in a global order
//! over the faces not containing it, each face fanned from its own first point.

use super::piece::Poly;
use super::{ClipPoint, ClipSink};
use crate::geom::signed_volume;
use crate::keys::{split, PointKey};
use crate::levels::Bounds;

/// Cones the piece from its first point in [`rank`] order over the faces not containing it,
/// each face fanned from its own first point; boundary faces also go out as triangles (those
/// the sink keeps).
#[inline]
pub(super) fn cone_and_fan(
    pts: &[ClipPoint],
    faces: &[Poly],
    lv: &Bounds,
    sink: &mut impl ClipSink,
) {
    // Each point is ranked once (a piece has at most 12).
    let mut ranks = [(0, 0); 12];
    for (r, p) in ranks.iter_mut().zip(pts) {
        *r = rank(p, lv);
    }
    let v0 = (0..pts.len()).min_by_key(|&i| ranks[i]).unwrap_or(0);
    for poly in faces {
        let verts = &poly.v[..poly.n];
        let r = (0..poly.n)
            .min_by_key(|&i| ranks[usize::from(verts[i])])
            .unwrap_or(0);
        let has_v0 = verts.contains(&(v0 as u8));
        let label = poly.label.filter(|&l| sink.keeps(l));
        let inside_sign = label.map(|_| inside_side(pts, verts));
        // Index `r + s` around the polygon (`s < n`; no division).
        let at = |s: usize| {
            usize::from(
                verts[if r + s < poly.n {
                    r + s
                } else {
                    r + s - poly.n
                }],
            )
        };
        for s in 1..poly.n - 1 {
            let (a, b, c) = (at(0), at(s), at(s + 1));
            if !has_v0 {
                let vol = signed_volume(pts[v0].pos, pts[a].pos, pts[b].pos, pts[c].pos);
                if vol > 0.0 {
                    sink.tet(pts, [v0, a, b, c]);
                } else if vol < 0.0 {
                    sink.tet(pts, [v0, a, c, b]);
                }
            }
            if let (Some(label), Some(sign)) = (label, inside_sign) {
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

/// Depth bits above every depth: [`rank`] stores `DEEPEST - depth` to put deeper first.
const DEEPEST: u64 = i64::MAX as u64;

/// The order in which a piece's points become cone apexes and fan points: vertices before
/// cuts, vertices farther from the nearer level first, then by key. A function of the point
/// alone (its identity and value), so every cell and thread agrees on it and both sides of a
/// shared face fan it the same way. Coning from the vertex deepest inside the interval, and
/// fanning from it, keeps the tets away from the flat ones whose four corners lie near the
/// level surface; it leaves about a quarter fewer tets below 15° than coning by key (noisy
/// 256³ field, T1 band: docs/QUALITY-LOG.md, *Where the bad tets come from*).
///
/// Packed for cheap comparison: the top bit says cut, the other 63 hold `DEEPEST - depth`
/// (a non-negative depth's bits order as its value and stay below `DEEPEST`), then the key.
#[inline]
fn rank(p: &ClipPoint, lv: &Bounds) -> (u64, PointKey) {
    let is_cut = split(p.key).1.is_some();
    let mut depth = (p.val - lv.get(0)).abs();
    for i in 1..lv.len() {
        depth = depth.min((p.val - lv.get(i)).abs());
    }
    // Non-negative (or infinite, for a one-sided interval), so the bits order as the values.
    let depth = if depth.is_nan() { 0 } else { depth.to_bits() };
    ((u64::from(is_cut) << 63) | (DEEPEST - depth), p.key)
}

/// For a boundary face: the signed volume over the face's first three points of the piece's
/// point farthest from the face's plane, whose sign says which side is inside (robust even
/// for very thin pieces).
#[inline]
fn inside_side(pts: &[ClipPoint], verts: &[u8]) -> f64 {
    let [a, b, c] = [0, 1, 2].map(|i| pts[usize::from(verts[i])].pos);
    let mut best = 0.0f64;
    for p in pts {
        let v = signed_volume(a, b, c, p.pos);
        if v.abs() > best.abs() {
            best = v;
        }
    }
    best
}
