//! TPTD: the topology-preserving decomposition of §4 of B.-S. Sohn, “Topology preserving
//! tetrahedral decomposition of trilinear cell” (ICCS 2007), cases (i)–(v).
//!
//! The decomposition is written for a *mask* of used face saddles (see
//! [`crate::decompose::plan`]): pure TPTD uses every face saddle that exists, STD/CTD cells use
//! only the ones their level needs plus the ones a TPTD neighbour forces. With every saddle
//! used it is exactly the paper's rule:
//! * (i) no saddle: 6-fold;
//! * (ii) face saddles only: five pyramids around one face saddle — the *second biggest* one
//!   when three or more are used (the paper's Appendix), pyramid bases split per face rule;
//! * (iii) one body saddle: six pyramids around it;
//! * (iv) six face saddles, no body saddle: the diamond (8 corner tets, 12 edge tets, 4 tets
//!   inside the octahedron of face saddles);
//! * (v) six face saddles and body saddles: two pyramids on the parallel faces holding a small
//!   and a big face saddle, apexes the small and big body saddle, and four prisms split so the
//!   small corner never meets the big body saddle nor the big corner the small one. With one
//!   body saddle the pyramid on the side of the third-smallest face saddle collapses onto that
//!   face saddle (never the smallest nor the biggest).
//!
//! Inserted points: face saddles sit at their true position clamped into the middle of the
//! face (done by the caller), body saddles at their true position (case iii) or on the cell's
//! centre line (case v). Topology depends on the values only; the placement keeps every tet
//! positively oriented.

use super::{face_id, orient_tiling, push_pyramid, CellCase, CellPoints, BODY0, BODY1};
use crate::grid::{corner_faces, corner_offset, HIGH_FACES, LOW_FACES};
use crate::trilinear::BodySaddle;

/// Decomposes one cell. `face_value[f]` is the saddle value of face `f` (read for used faces
/// only); `pts` holds the corners and the used face saddles and receives the body points.
/// `bodies` are the used body saddles sorted by value (0, 1 or 2). `apex_faces` are the used
/// faces whose saddle may be the case-(ii) apex: all used faces for TPTD, only the faces a
/// STD cell needs for its own level otherwise (a saddle used only because a TPTD neighbour
/// needs it may sit on either side of the level and would join what the cell keeps apart).
/// Appends positively oriented tets to `out` and returns the case used.
pub fn decompose_tptd(
    used_faces: u8,
    apex_faces: u8,
    face_value: &[f64; 6],
    bodies: &[BodySaddle],
    pts: &mut CellPoints,
    out: &mut Vec<[u8; 4]>,
) -> CellCase {
    let start = out.len();
    let nf = used_faces.count_ones();
    let case = match (bodies.len(), nf) {
        (0, 0) => {
            super::six::decompose_six(out);
            return CellCase::I;
        }
        (0, 6) => {
            if diamond(pts, out) {
                return CellCase::IV;
            }
            CellCase::Fallback
        }
        (0, _) => return face_pyramids(used_faces, apex_faces, face_value, out),
        (1, 6) | (2, 6) => {
            if prisms(face_value, bodies, pts, out) {
                return CellCase::V;
            }
            CellCase::Fallback
        }
        (1, _) => CellCase::III,
        _ => CellCase::Fallback,
    };
    out.truncate(start);
    // Case (iii), and the fallback for layouts that failed: six pyramids around a body point.
    body_pyramids(bodies.first(), used_faces, pts, out);
    case
}

/// Case (ii) and its STD variants (face saddles only, not all six or none): pyramids from a
/// corner or around a face saddle (see [`decompose_tptd`] for `apex_faces`).
fn face_pyramids(
    used_faces: u8,
    apex_faces: u8,
    face_value: &[f64; 6],
    out: &mut Vec<[u8; 4]>,
) -> CellCase {
    let eligible = apex_faces & used_faces;
    if eligible == 0 && used_faces & LOW_FACES == 0 {
        // Only faces away from corner 0 are split: the 6-fold split seen as three
        // pyramids from corner 0, with the split faces in four.
        for f in [1, 3, 5] {
            push_pyramid(out, 0, f, used_faces);
        }
        return CellCase::I;
    }
    if eligible == 0 && used_faces & HIGH_FACES == 0 {
        for f in [0, 2, 4] {
            push_pyramid(out, 7, f, used_faces);
        }
        return CellCase::I;
    }
    let from = if eligible != 0 { eligible } else { used_faces };
    let apex = face_id(second_biggest(from, face_value));
    for f in 0..6 {
        if face_id(f) != apex {
            push_pyramid(out, apex, f, used_faces);
        }
    }
    // push_pyramid orients every tet (apex on another face); tests check it
    if eligible != 0 {
        CellCase::II
    } else {
        CellCase::Fallback
    }
}

/// Six pyramids around body saddle `body` (clamped into the cell), or around the cell centre
/// when there is none: valid and positively oriented by construction.
fn body_pyramids(
    body: Option<&BodySaddle>,
    used_faces: u8,
    pts: &mut CellPoints,
    out: &mut Vec<[u8; 4]>,
) {
    let b = match body {
        Some(b) => *b,
        None => {
            let p = [0.5; 3];
            BodySaddle {
                pos: p,
                value: crate::trilinear::eval(&corner_values(pts), p),
            }
        }
    };
    pts.pos[BODY0 as usize] = b.pos.map(|x| x.clamp(0.05, 0.95));
    pts.val[BODY0 as usize] = b.value;
    for f in 0..6 {
        push_pyramid(out, BODY0, f, used_faces);
    }
}

fn corner_values(pts: &CellPoints) -> [f64; 8] {
    std::array::from_fn(|c| pts.val[c])
}

/// The used face whose saddle is the second biggest (the only one when one is used).
/// Ties are broken by face number so the choice is a function of the values only.
fn second_biggest(used_faces: u8, face_value: &[f64; 6]) -> usize {
    let mut faces = [0usize; 6];
    let mut n = 0;
    for f in 0..6 {
        if used_faces & (1 << f) != 0 {
            faces[n] = f;
            n += 1;
        }
    }
    let faces = &mut faces[..n];
    faces.sort_unstable_by(|&a, &b| face_value[a].total_cmp(&face_value[b]).then(a.cmp(&b)));
    faces[n.saturating_sub(2)]
}

/// Case (iv): 24 tets. Returns false if no octahedron split is positive.
fn diamond(pts: &CellPoints, out: &mut Vec<[u8; 4]>) -> bool {
    let start = out.len();
    for c in 0..8 {
        let [fx, fy, fz] = corner_faces(c);
        out.push([c as u8, face_id(fx), face_id(fy), face_id(fz)]);
    }
    for c1 in 0..8usize {
        for a in 0..3 {
            if c1 & (1 << a) != 0 {
                continue;
            }
            let c2 = c1 | (1 << a);
            let o = corner_offset(c1);
            let fs: Vec<u8> = (0..3)
                .filter(|&b| b != a)
                .map(|b| face_id(2 * b + o[b]))
                .collect();
            out.push([c1 as u8, c2 as u8, fs[0], fs[1]]);
        }
    }
    let outer = out.len();
    for axis in [2usize, 0, 1] {
        let others: Vec<usize> = (0..3).filter(|&b| b != axis).collect();
        let ring = [
            face_id(2 * others[0]),
            face_id(2 * others[1]),
            face_id(2 * others[0] + 1),
            face_id(2 * others[1] + 1),
        ];
        for t in 0..4 {
            out.push([
                face_id(2 * axis),
                face_id(2 * axis + 1),
                ring[t],
                ring[(t + 1) % 4],
            ]);
        }
        if orient_tiling(&mut out[start..], pts, 1.0) {
            return true;
        }
        out.truncate(outer);
    }
    out.truncate(start);
    false
}

/// Case (v). Returns false (and appends nothing) if the small face saddles do not meet at a
/// corner or a tet would be flat.
fn prisms(
    face_value: &[f64; 6],
    bodies: &[BodySaddle],
    pts: &mut CellPoints,
    out: &mut Vec<[u8; 4]>,
) -> bool {
    let start = out.len();
    let mut order: [usize; 6] = [0, 1, 2, 3, 4, 5];
    order.sort_by(|&a, &b| face_value[a].total_cmp(&face_value[b]).then(a.cmp(&b)));
    let Some(side) = small_sides(&order) else {
        return false;
    };
    let (axis, b_small, b_big) = prism_apexes(face_value, &order, bodies, pts);
    let small_face = 2 * axis + side[axis];
    let big_face = 2 * axis + 1 - side[axis];
    // Case-(v) apexes sit on the cell's centre line, 0.3 of the way in from their own face.
    let small_coord = if side[axis] == 0 { 0.3 } else { 0.7 };
    let all = 0b11_1111u8;
    for (apex, face, coord) in [
        (b_small, small_face, small_coord),
        (b_big, big_face, 1.0 - small_coord),
    ] {
        if apex != face_id(face) {
            let mut centre = [0.5; 3];
            centre[axis] = coord;
            pts.pos[apex as usize] = centre;
            push_pyramid(out, apex, face, all);
        }
    }
    let c_small = side[0] | (side[1] << 1) | (side[2] << 2);
    for f in 0..6 {
        if f / 2 != axis {
            side_region(f, axis, side[axis], (b_small, b_big), 7 ^ c_small, out);
        }
    }
    if !orient_tiling(&mut out[start..], pts, 1.0) {
        out.truncate(start);
        return false;
    }
    true
}

/// The side (0 low, 1 high) per axis of the faces of the three smallest face saddles, when
/// they lie on faces meeting at one corner (one per axis); `order` sorts faces by value.
fn small_sides(order: &[usize; 6]) -> Option<[usize; 3]> {
    let mut side = [usize::MAX; 3];
    for &f in &order[..3] {
        if side[f / 2] != usize::MAX {
            return None;
        }
        side[f / 2] = f % 2;
    }
    Some(side)
}

/// Axis of the two case-(v) pyramids and their small and big apexes (local ids); sets the
/// body saddles' values in `pts`.
fn prism_apexes(
    face_value: &[f64; 6],
    order: &[usize; 6],
    bodies: &[BodySaddle],
    pts: &mut CellPoints,
) -> (usize, u8, u8) {
    if bodies.len() == 2 {
        for (id, b) in [(BODY0, &bodies[0]), (BODY1, &bodies[1])] {
            pts.val[id as usize] = b.value;
        }
        return (2, BODY0, BODY1);
    }
    // One body saddle: it plays the small role when its value is nearer the small face
    // saddles, the big one otherwise; the other pyramid collapses onto the face saddle
    // nearest in rank (the third-smallest or third-biggest: never the smallest nor the
    // biggest).
    pts.val[BODY0 as usize] = bodies[0].value;
    let mid = 0.5 * (face_value[order[2]] + face_value[order[3]]);
    if bodies[0].value < mid {
        let fc = order[3];
        (fc / 2, BODY0, face_id(fc))
    } else {
        let fc = order[2];
        (fc / 2, face_id(fc), BODY0)
    }
}

/// The tets of the prism between side face `f` (not normal to `axis`) and the two apexes
/// `(b_small, b_big)`; `low_side` is the side along `axis` of the small pyramid's face and
/// `c_big` the corner of the three big face saddles.
///
/// The four edges parallel to `axis` run from c_lo on the small face to c_hi on the big face.
/// Each is shared by two side regions, which must split the quad (b_small, c_lo, c_hi, b_big)
/// the same way.
fn side_region(
    f: usize,
    axis: usize,
    low_side: usize,
    (b_small, b_big): (u8, u8),
    c_big: usize,
    out: &mut Vec<[u8; 4]>,
) {
    let interface = |c_lo: u8| -> [[u8; 3]; 2] {
        let c_hi = c_lo ^ (1 << axis);
        if c_hi as usize == c_big {
            [[b_small, c_lo, b_big], [b_big, c_lo, c_hi]]
        } else {
            // also the rule for c_lo == c_small: never connect it to b_big
            [[b_small, c_lo, c_hi], [b_small, c_hi, b_big]]
        }
    };
    let s = face_id(f);
    let fa = f / 2;
    let on_face: Vec<u8> = (0..8u8)
        .filter(|&c| ((c as usize >> fa) & 1) == f % 2)
        .collect();
    let lo: Vec<u8> = on_face
        .iter()
        .copied()
        .filter(|&c| ((c as usize >> axis) & 1) == low_side)
        .collect();
    let hi: Vec<u8> = lo.iter().map(|&c| c ^ (1 << axis)).collect();
    out.push([s, b_small, lo[0], lo[1]]);
    out.push([s, b_big, hi[0], hi[1]]);
    for &c_lo in &lo {
        for tri in interface(c_lo) {
            out.push([s, tri[0], tri[1], tri[2]]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::decompose::test_util::assert_tiles_cube;
    use crate::trilinear::{body_saddles, face_saddle, face_saddle_point};

    fn rng(seed: &mut u64) -> f64 {
        *seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((*seed >> 11) as f64) / ((1u64 << 53) as f64)
    }

    /// Every random cell, with every mask of its existing face saddles, tiles the cube.
    #[test]
    fn tptd_tiles_the_cube_for_all_masks() {
        let mut seed = 11u64;
        let mut seen = [0usize; 6];
        let mut fb = std::collections::BTreeMap::new();
        let mut out = Vec::new();
        for _ in 0..20000 {
            let v: [f64; 8] = std::array::from_fn(|_| rng(&mut seed) * 2.0 - 1.0);
            let mut pts = CellPoints::from_corners(&v);
            let mut exists = 0u8;
            let mut fv = [0.0; 6];
            for f in 0..6 {
                if let Some(s) = face_saddle(&v, f) {
                    exists |= 1 << f;
                    fv[f] = s.value;
                    pts.pos[8 + f] = face_saddle_point(f, s.uv);
                    pts.val[8 + f] = s.value;
                }
            }
            let (bs, nb) = body_saddles(&v);
            // which used faces may be the apex (all, for full cells; some or none for STD)
            let apex_mask = if rng(&mut seed) < 0.5 {
                0
            } else {
                (rng(&mut seed) * 64.0) as u8
            };
            let mut mask = exists;
            loop {
                for nbu in 0..=nb {
                    out.clear();
                    let case = decompose_tptd(
                        mask,
                        if nbu == 0 { mask & apex_mask } else { mask },
                        &fv,
                        &bs[..nbu],
                        &mut pts,
                        &mut out,
                    );
                    seen[case as usize] += 1;
                    if case == CellCase::Fallback {
                        *fb.entry((nbu, mask.count_ones())).or_insert(0usize) += 1;
                    }
                    assert_tiles_cube(&out, &pts, mask);
                }
                if mask == 0 {
                    break;
                }
                mask = (mask - 1) & exists;
            }
        }
        eprintln!("cases seen {seen:?} fallbacks by (bodies, faces) {fb:?}");
        assert!(seen.iter().take(5).all(|&n| n > 0), "cases seen {seen:?}");
    }
}
