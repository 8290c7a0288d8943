//! The 5-fold decomposition with alternating ("zig-zag") parity.
//!
//! A cell with even `i + j + k` keeps the central tet (0, 3, 5, 6) and cuts off corners
//! 1, 2, 4, 7; an odd cell is its mirror image (central tet (1, 2, 4, 7)). Neighbours have
//! opposite parity, so both sides of a shared face use the same diagonal. The face diagonals
//! are not the smallest–largest ones of the other decompositions, so `five` never mixes with
//! them; it uses no saddles.

/// Even-parity cells (positively oriented).
pub const FIVE_EVEN: [[u8; 4]; 5] = [
    [0, 3, 6, 5],
    [1, 0, 5, 3],
    [2, 0, 3, 6],
    [4, 0, 6, 5],
    [7, 3, 5, 6],
];
/// Odd-parity cells (positively oriented).
pub const FIVE_ODD: [[u8; 4]; 5] = [
    [1, 2, 4, 7],
    [0, 1, 2, 4],
    [3, 1, 7, 2],
    [5, 1, 4, 7],
    [6, 2, 7, 4],
];

/// Appends the 5-fold decomposition for a cell of the given parity (`(i + j + k) % 2`).
#[inline]
pub fn decompose_five(odd: bool, out: &mut Vec<[u8; 4]>) {
    out.extend_from_slice(if odd { &FIVE_ODD } else { &FIVE_EVEN });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::decompose::{orient_tiling, CellPoints};
    use crate::geom::signed_volume;

    #[test]
    fn five_is_positive_and_tiles() {
        let pts = CellPoints::from_corners(&[0.0; 8]);
        for tets in [FIVE_EVEN, FIVE_ODD] {
            let mut t2 = tets;
            assert!(orient_tiling(&mut t2, &pts, 1.0));
            assert_eq!(t2, tets, "tables are already positively oriented: {t2:?}");
            let vol: f64 = tets
                .iter()
                .map(|t| {
                    signed_volume(
                        pts.pos[t[0] as usize],
                        pts.pos[t[1] as usize],
                        pts.pos[t[2] as usize],
                        pts.pos[t[3] as usize],
                    )
                })
                .sum();
            assert!((vol - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn neighbours_share_face_diagonals() {
        // The +x face of an even cell (corners 1,3,5,7) is the -x face of an odd cell
        // (corners 0,2,4,6); corner c on +x maps to c - 1 on -x. Same for y (c-2) and z (c-4).
        let diag = |tets: &[[u8; 4]; 5], face: &[u8; 4]| -> Vec<[u8; 2]> {
            let mut d = Vec::new();
            for t in tets {
                let on: Vec<u8> = t.iter().copied().filter(|c| face.contains(c)).collect();
                if on.len() == 3 {
                    for a in 0..3 {
                        for b in a + 1..3 {
                            let (x, y) = (on[a].min(on[b]), on[a].max(on[b]));
                            if (x ^ y).count_ones() == 2 {
                                d.push([x, y]);
                            }
                        }
                    }
                }
            }
            d.sort();
            d.dedup();
            d
        };
        for (axis, bit) in [(0, 1u8), (1, 2), (2, 4)] {
            let _ = axis;
            let hi: [u8; 4] = {
                let v: Vec<u8> = (0..8u8).filter(|c| c & bit != 0).collect();
                [v[0], v[1], v[2], v[3]]
            };
            let lo = hi.map(|c| c - bit);
            for (a, b) in [(&FIVE_EVEN, &FIVE_ODD), (&FIVE_ODD, &FIVE_EVEN)] {
                let da = diag(a, &hi);
                let db: Vec<[u8; 2]> = diag(b, &lo)
                    .into_iter()
                    .map(|[x, y]| [x + bit, y + bit])
                    .collect();
                assert_eq!(da.len(), 1);
                assert_eq!(da, db);
            }
        }
    }
}
