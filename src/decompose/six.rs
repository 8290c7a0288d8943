//! The 6-fold decomposition around the main diagonal 0–7.
//!
//! Every tet contains the diagonal 0–7, so every face is split along the diagonal from its
//! smallest to its largest corner: neighbouring cells conform without any bookkeeping.

/// The six tets (0, a, b, 7) along the monotone paths 0 → a → b → 7 (positively oriented).
pub const SIX: [[u8; 4]; 6] = [
    [0, 1, 3, 7],
    [0, 3, 2, 7],
    [0, 2, 6, 7],
    [0, 6, 4, 7],
    [0, 4, 5, 7],
    [0, 5, 1, 7],
];

/// Appends the 6-fold decomposition.
#[inline]
pub fn decompose_six(out: &mut Vec<[u8; 4]>) {
    out.extend_from_slice(&SIX);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::decompose::{test_util::assert_tiles_cube, CellPoints};

    #[test]
    fn six_tiles_the_cube_positively() {
        let pts = CellPoints::from_corners(&[0.0; 8]);
        assert_tiles_cube(&SIX, &pts, 0);
    }
}
