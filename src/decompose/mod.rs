//! Decompositions of one trilinear cell into tetrahedra over cell-local vertex ids.
//!
//! Local ids: `0..8` the corners (numbering of [`crate::grid`]), `8 + f` the saddle of face
//! `f` (or the point splitting its diagonal), [`BODY0`] and [`BODY1`] the body saddles in
//! increasing value order, and from [`SPLIT0`] on the points that split edges inside the cell.
//!
//! Conformity between cells rests on one rule: a cell face is split into four triangles around
//! its saddle when the face's saddle is *used* (a decision that depends only on the face and
//! its two cells, see [`plan`]), otherwise into two triangles along the diagonal from its
//! smallest to its largest corner ([`crate::grid::face_corners`] entries 0 and 2). Every
//! decomposition here builds the tets touching a face from that rule.

pub mod five;
pub mod plan;
pub mod sag;
pub mod six;
pub mod tptd;

use crate::geom::signed_volume;
use crate::grid::{corner_faces, corner_offset, face_corners};
use crate::trilinear::face_saddle_point;
use plan::{CellPlan, Layout};

/// Local id of the lower-valued body saddle.
pub const BODY0: u8 = 14;
/// Local id of the higher-valued body saddle.
pub const BODY1: u8 = 15;
/// Local id of the first point splitting an edge inside the cell ([`sag`]).
pub const SPLIT0: u8 = 16;
/// Number of local ids.
pub const NUM_LOCAL: usize = 40;

/// Local id of the saddle of face `f`.
#[inline]
pub const fn face_id(f: usize) -> u8 {
    8 + f as u8
}

/// Which TPTD case (Table 2 of Sohn, ICCS 2007) a cell was decomposed with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[repr(u8)]
pub enum CellCase {
    /// No saddle used: 6-fold (or 5-fold) split.
    I = 0,
    /// Face saddles only (1–5 used): five pyramids around one face saddle.
    II = 1,
    /// One body saddle: six pyramids around it.
    III = 2,
    /// Six face saddles, no body saddle: the diamond, 24 tets.
    IV = 3,
    /// Six face saddles and one or two body saddles: two pyramids and four prisms.
    V = 4,
    /// A configuration with no valid layout of its case; decomposed with body-saddle pyramids.
    Fallback = 5,
}

impl CellCase {
    /// All cases in order.
    pub const ALL: [CellCase; 6] = [
        CellCase::I,
        CellCase::II,
        CellCase::III,
        CellCase::IV,
        CellCase::V,
        CellCase::Fallback,
    ];

    /// Short name used in reports.
    pub fn name(self) -> &'static str {
        match self {
            CellCase::I => "i",
            CellCase::II => "ii",
            CellCase::III => "iii",
            CellCase::IV => "iv",
            CellCase::V => "v",
            CellCase::Fallback => "fallback",
        }
    }
}

/// Positions (cell-local) and values of the 16 local ids of one cell.
/// Entries of ids a decomposition does not use are unspecified.
#[derive(Clone, Copy, Debug)]
pub struct CellPoints {
    /// Cell-local positions.
    pub pos: [[f64; 3]; NUM_LOCAL],
    /// Field values.
    pub val: [f64; NUM_LOCAL],
}

impl CellPoints {
    /// Corners filled in from the corner values; saddles zeroed.
    pub fn from_corners(v: &[f64; 8]) -> Self {
        let mut pos = [[0.0; 3]; NUM_LOCAL];
        let mut val = [0.0; NUM_LOCAL];
        for c in 0..8 {
            let o = corner_offset(c);
            pos[c] = [o[0] as f64, o[1] as f64, o[2] as f64];
            val[c] = v[c];
        }
        CellPoints { pos, val }
    }
}

/// Box-plane mask of every local id: a corner lies on its three faces, a face saddle on its
/// face, body points on none (bit `f` = cell face `f`).
pub const LOCAL_BOX: [u8; NUM_LOCAL] = local_box();

const fn local_box() -> [u8; NUM_LOCAL] {
    let mut m = [0u8; NUM_LOCAL];
    let mut c = 0;
    while c < 8 {
        let f = corner_faces(c);
        m[c] = (1 << f[0]) | (1 << f[1]) | (1 << f[2]);
        c += 1;
    }
    let mut f = 0;
    while f < 6 {
        m[8 + f] = 1 << f;
        f += 1;
    }
    m
}

/// Decomposes one cell (corner values `v`) as `plan` says: appends tets over local ids to
/// `out` (which the caller clears) and returns the case and the local ids' points.
/// `plan.layout` must not be [`plan::Layout::Outside`].
#[inline]
pub fn decompose_cell(
    plan: &CellPlan,
    v: &[f64; 8],
    out: &mut Vec<[u8; 4]>,
) -> (CellCase, CellPoints) {
    let mut pts = CellPoints::from_corners(v);
    let case = match plan.layout {
        Layout::Outside | Layout::Six => {
            six::decompose_six(out);
            CellCase::I
        }
        Layout::Five { odd } => {
            five::decompose_five(odd, out);
            CellCase::I
        }
        Layout::Tptd => {
            let used = plan.used();
            for f in 0..6 {
                if used & (1 << f) != 0 {
                    let s = plan.saddles[f];
                    pts.pos[8 + f] = face_saddle_point(f, s.uv);
                    pts.val[8 + f] = s.value;
                }
            }
            let fv = plan.face_values();
            let case = tptd::decompose_tptd(used, plan.apex, &fv, plan.bodies(), &mut pts, out);
            split_sagging_edges(plan, &mut pts, out);
            case
        }
    };
    (case, pts)
}

/// Splits the main diagonal where it dips through a level, then bisects the sagging face
/// diagonals the plan names, then the sagging edges inside the cell (see [`sag`]). The
/// diagonal goes first: whether its split keeps the topology is read off the corners around
/// it, and a face diagonal's split point, a tenth of the band from a level, would stand among
/// them on the wrong side of it.
#[inline]
fn split_sagging_edges(plan: &CellPlan, pts: &mut CellPoints, out: &mut Vec<[u8; 4]>) {
    let first = match plan.split_levels {
        Some(levels) => sag::split_dipping_diagonal(levels, pts, out),
        None => SPLIT0 as usize,
    };
    for f in 0..6 {
        if plan.extra & (1 << f) == 0 {
            continue;
        }
        let s = plan.saddles[f];
        pts.pos[8 + f] = crate::trilinear::face_point(f, s.uv);
        pts.val[8 + f] = s.value;
        let fc = face_corners(f);
        sag::bisect(out, fc[0] as u8, fc[2] as u8, face_id(f));
    }
    if let Some(levels) = plan.split_levels {
        sag::split_inner_edges(levels, pts, out, first);
    }
}

/// Appends the tets of the pyramid with apex `apex` over cell face `f`: four tets around the
/// face saddle when bit `f` of `used_faces` is set, otherwise two along the face's
/// smallest–largest diagonal.
///
/// The tets are positively oriented whenever the apex lies strictly on the inner side of face
/// `f` (inside the cell, or on another face): the base triangles run counter-clockwise in the
/// face's (lower axis, higher axis) frame, whose normal is `+x`, `-y`, `+z` for the three axes,
/// so they are reversed where that normal points into the cell.
#[inline]
pub fn push_pyramid(out: &mut Vec<[u8; 4]>, apex: u8, f: usize, used_faces: u8) {
    let fc = face_corners(f).map(|c| c as u8);
    let normal_positive = f / 2 != 1;
    let outward_positive = f % 2 == 1;
    let flip = normal_positive != outward_positive;
    let mut push = |a: u8, b: u8, c: u8| {
        if flip {
            out.push([apex, a, c, b]);
        } else {
            out.push([apex, a, b, c]);
        }
    };
    if used_faces & (1 << f) != 0 {
        let s = face_id(f);
        for t in 0..4 {
            push(fc[t], fc[(t + 1) % 4], s);
        }
    } else {
        push(fc[0], fc[1], fc[2]);
        push(fc[0], fc[2], fc[3]);
    }
}

/// Makes every tet in `tets` positively oriented with respect to `pts` and checks that the
/// tets do not overlap: their absolute volumes must add up to `volume` (the region they are
/// meant to tile). Returns false for a flat tet or an overlap, which callers treat as an
/// invalid layout.
pub fn orient_tiling(tets: &mut [[u8; 4]], pts: &CellPoints, volume: f64) -> bool {
    let mut sum = 0.0;
    for t in tets.iter_mut() {
        let v = signed_volume(
            pts.pos[t[0] as usize],
            pts.pos[t[1] as usize],
            pts.pos[t[2] as usize],
            pts.pos[t[3] as usize],
        );
        if v < 0.0 {
            t.swap(2, 3);
        }
        if v.is_nan() || v.abs() <= 1e-12 {
            return false;
        }
        sum += v.abs();
    }
    (sum - volume).abs() <= 1e-9
}

#[cfg(test)]
pub(crate) mod test_util {
    use super::*;
    use std::collections::HashMap;

    /// Asserts the tets tile the unit cube: positive volumes summing to 1, every interior
    /// triangle shared by two tets, and each cell face triangulated as `used_faces` says.
    pub fn assert_tiles_cube(tets: &[[u8; 4]], pts: &CellPoints, used_faces: u8) {
        let mut vol = 0.0;
        let mut faces: HashMap<[u8; 3], usize> = HashMap::new();
        for t in tets {
            let v = signed_volume(
                pts.pos[t[0] as usize],
                pts.pos[t[1] as usize],
                pts.pos[t[2] as usize],
                pts.pos[t[3] as usize],
            );
            assert!(v > 0.0, "tet {t:?} has volume {v}");
            vol += v;
            for skip in 0..4 {
                let mut f: Vec<u8> = (0..4).filter(|&i| i != skip).map(|i| t[i]).collect();
                f.sort();
                *faces.entry([f[0], f[1], f[2]]).or_default() += 1;
            }
        }
        assert!((vol - 1.0).abs() < 1e-9, "volume {vol}");
        let on_face = |id: u8, f: usize| -> bool {
            let p = pts.pos[id as usize];
            p[f / 2] == (f % 2) as f64
        };
        let mut per_face = [0usize; 6];
        for (tri, n) in faces {
            let face = (0..6).find(|&f| tri.iter().all(|&id| on_face(id, f)));
            match face {
                Some(f) => {
                    assert_eq!(n, 1, "boundary triangle {tri:?} used {n} times");
                    per_face[f] += 1;
                    if used_faces & (1 << f) == 0 {
                        let fc = face_corners(f);
                        // the two-triangle split uses the smallest-largest diagonal
                        assert!(
                            tri.contains(&(fc[0] as u8)) && tri.contains(&(fc[2] as u8)),
                            "face {f} triangle {tri:?}"
                        );
                    } else {
                        assert!(tri.contains(&face_id(f)));
                    }
                }
                None => assert_eq!(n, 2, "interior triangle {tri:?} used {n} times"),
            }
        }
        for (f, &n) in per_face.iter().enumerate() {
            let want = if used_faces & (1 << f) != 0 { 4 } else { 2 };
            assert_eq!(n, want, "face {f}");
        }
    }
}
