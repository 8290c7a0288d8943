//! Which saddles a cell uses, per method — the rule that keeps neighbouring cells conforming.
//!
//! Vertex classes: with the open-interval convention (see `docs/ARCHITECTURE.md`), a value
//! `<= alpha` is *below*, `>= beta` is *above*, anything else *inside*.
//!
//! * A cell is **two-level** when it has corners below and corners not below, and corners above
//!   and corners not above (both boundary surfaces may cross it).
//! * `tptd`: every existing face saddle and body saddle is used in every cell.
//! * `std`/`ctd`: a face saddle is used when the face is *ambiguous* for alpha or for beta
//!   (diagonal corners on the same side, the two diagonals on opposite sides), or when a
//!   *full* cell touches the face. A full cell is, for `ctd`, a two-level cell, and for both, a
//!   cell crossing a level that has a body saddle (STD case iii is never used on its own: a
//!   body saddle with masked faces can join what case v keeps apart) or whose corners 0 and 7
//!   are alone on one side of a level (the 6-fold diagonal would join them). Full cells use every
//!   saddle (TPTD); other cells use no body saddle (STD cases i, ii, iv over the used faces).
//!   Both cells of a face evaluate the same rule on the same data, so they agree.

/// Decomposition method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// 5-fold, alternating parity (no saddles; topology not preserved).
    Five,
    /// 6-fold around the main diagonal (no saddles; topology not preserved).
    Six,
    /// Topology-preserving decomposition for all isovalues (§4).
    Tptd,
    /// Simplified decomposition: topology kept for one isovalue per cell (§5.2).
    Std,
    /// STD in cells with at most one boundary surface, TPTD elsewhere (§5.2).
    Ctd,
}

impl Method {
    /// Lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            Method::Five => "five",
            Method::Six => "six",
            Method::Tptd => "tptd",
            Method::Std => "std",
            Method::Ctd => "ctd",
        }
    }
}

/// Class bits of one value: bit 0 = below (`<= alpha`), bit 1 = above (`>= beta`).
#[inline]
pub fn class(v: f64, alpha: f64, beta: f64) -> u8 {
    (v <= alpha) as u8 | (((v >= beta) as u8) << 1)
}

/// Per-cell summary of the corner classes.
#[derive(Clone, Copy, Debug)]
pub struct CellClasses {
    /// Bit c set when corner c is below.
    pub below: u8,
    /// Bit c set when corner c is above.
    pub above: u8,
}

impl CellClasses {
    /// Classes of the eight corner values.
    #[inline]
    pub fn new(v: &[f64; 8], alpha: f64, beta: f64) -> Self {
        let mut below = 0u8;
        let mut above = 0u8;
        for (c, &x) in v.iter().enumerate() {
            let k = class(x, alpha, beta);
            below |= (k & 1) << c;
            above |= (k >> 1) << c;
        }
        CellClasses { below, above }
    }
    /// Whether the alpha surface can cross the cell.
    #[inline]
    pub fn crosses_alpha(self) -> bool {
        self.below != 0 && self.below != 0xff
    }
    /// Whether the beta surface can cross the cell.
    #[inline]
    pub fn crosses_beta(self) -> bool {
        self.above != 0 && self.above != 0xff
    }
    /// Whether the cell lies entirely outside the open interval.
    #[inline]
    pub fn all_outside(self) -> bool {
        self.below == 0xff || self.above == 0xff
    }
    /// Whether every corner is inside.
    #[inline]
    pub fn all_inside(self) -> bool {
        self.below == 0 && self.above == 0
    }
}

/// Whether face `f` is ambiguous for the side mask `m` (bit c set = corner c on one side).
#[inline]
pub fn face_ambiguous(m: u8, f: usize) -> bool {
    let fc = crate::grid::face_corners(f);
    let s = |i: usize| (m >> fc[i]) & 1;
    s(0) == s(2) && s(1) == s(3) && s(0) != s(1)
}

/// Whether corners 0 and 7 are alone on one side of a level (MC configuration 4 along the
/// 6-fold diagonal): the 6-fold split would join them through the 0–7 edge whether or not
/// the trilinear field does (4.1.1 versus 4.1.2), so such cells need TPTD.
#[inline]
pub fn diagonal_pair(cls: CellClasses) -> bool {
    const PAIR: u8 = 0b1000_0001;
    cls.below == PAIR || cls.below == !PAIR || cls.above == PAIR || cls.above == !PAIR
}

/// Whether a cell must use every saddle (TPTD), given its classes and body-saddle count.
#[inline]
pub fn is_full(method: Method, cls: CellClasses, num_body: usize) -> bool {
    let one_level = cls.crosses_alpha() || cls.crosses_beta();
    match method {
        Method::Tptd => true,
        Method::Five | Method::Six => false,
        Method::Ctd => {
            (cls.crosses_alpha() && cls.crosses_beta())
                || (one_level && (num_body > 0 || diagonal_pair(cls)))
        }
        Method::Std => one_level && (num_body > 0 || diagonal_pair(cls)),
    }
}

/// Whether a non-full cell of `method` uses face `f`'s saddle on its own account (ambiguity).
#[inline]
pub fn face_needed(cls: CellClasses, f: usize) -> bool {
    face_ambiguous(cls.below, f) || face_ambiguous(cls.above, f)
}

/// Whether the corners in `mask` form one connected set along cell edges (an empty set counts
/// as connected).
pub fn corners_connected(mask: u8) -> bool {
    if mask == 0 {
        return true;
    }
    let start = mask.trailing_zeros() as u8;
    let mut seen = 1u8 << start;
    let mut stack = [0u8; 8];
    let mut n = 1;
    stack[0] = start;
    while n > 0 {
        n -= 1;
        let c = stack[n];
        for bit in [1u8, 2, 4] {
            let d = c ^ bit;
            if mask & (1 << d) != 0 && seen & (1 << d) == 0 {
                seen |= 1 << d;
                stack[n] = d;
                n += 1;
            }
        }
    }
    seen == mask
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn corner_connectivity() {
        assert!(corners_connected(0));
        assert!(corners_connected(0b0000_0011));
        assert!(!corners_connected(0b1000_0001));
        assert!(!corners_connected(0b0000_0110));
        assert!(corners_connected(0b0000_0111));
        assert!(corners_connected(!0b1000_0001));
        assert!(corners_connected(0xff));
    }
}
