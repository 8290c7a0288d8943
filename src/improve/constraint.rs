//! Where a vertex may move: the level set it must stay on and the grid-box planes it must
//! stay in.

pub use crate::mesh::LabelBits;
use crate::mesh::{BOX_BIT, LEVEL_BITS};

/// Which level set a boundary vertex lies on: the level's index in the run (for one
/// interval, 0 alpha and 1 beta).
pub type Level = u8;

/// The motion a vertex is allowed.
///
/// `box_planes` has bit `2 a + s` set when the vertex lies on the grid-box plane of axis `a`
/// at side `s` (index coordinate `0` or `n_a - 1`); those coordinates never change.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Constraint {
    /// The level set the vertex must stay on, if any.
    pub level: Option<Level>,
    /// Grid-box planes the vertex lies on.
    pub box_planes: u8,
    /// The vertex may not move at all (it lies on two levels, or on a level and a box edge,
    /// or at a box corner, or its class could not be established).
    pub pinned: bool,
    /// Its level lies between two regions: a collapse from it must keep the topology of the
    /// regions on both sides too ([`crate::improve::interfaces`]).
    pub interface: bool,
    /// The region a vertex on no level lies in, which it must stay inside (0 for one
    /// interval).
    pub region: u8,
}

/// Index-space distance under which a vertex counts as lying on a grid-box plane.
pub const BOX_TOL: f64 = 1e-7;

/// The bits of the levels between regions in a run of `levels` levels (none for one
/// interval).
pub fn interface_bits(levels: usize) -> LabelBits {
    match levels {
        0..=2 => 0,
        n => ((1 << (n - 1)) - 1) & !1,
    }
}

impl Constraint {
    /// The constraint of a vertex at index point `u` (snapped exactly onto the box planes it
    /// lies on) whose boundary faces (interfaces included) carry the labels `labels`, in a
    /// grid of `dims` vertices; `interfaces` are the bits of the levels between regions
    /// ([`interface_bits`]).
    pub fn classify(
        labels: LabelBits,
        interfaces: LabelBits,
        u: &mut [f64; 3],
        dims: [usize; 3],
    ) -> Constraint {
        let mut c = Constraint::default();
        for a in 0..3 {
            let hi = (dims[a] - 1) as f64;
            if u[a].abs() < BOX_TOL {
                c.box_planes |= 1 << (2 * a);
                u[a] = 0.0;
            } else if (u[a] - hi).abs() < BOX_TOL {
                c.box_planes |= 2 << (2 * a);
                u[a] = hi;
            }
        }
        let levels = labels & LEVEL_BITS;
        c.level = match levels.count_ones() {
            0 => None,
            1 => Some(levels.trailing_zeros() as Level),
            _ => {
                c.pinned = true;
                None
            }
        };
        c.interface = levels & interfaces != 0;
        let on_box = labels & BOX_BIT != 0;
        if (on_box && c.box_planes == 0) || (c.level.is_some() && c.freedom() == 0) {
            c.pinned = true;
        }
        c
    }

    /// Bit mask of the index axes along which the vertex may move (none when pinned).
    pub fn free_axes(&self) -> u8 {
        if self.pinned {
            return 0;
        }
        let mut fixed = 0u8;
        for a in 0..3 {
            if self.box_planes & (0b11 << (2 * a)) != 0 {
                fixed |= 1 << a;
            }
        }
        !fixed & 0b111
    }

    /// Number of degrees of freedom: free axes, minus one for a level set.
    pub fn freedom(&self) -> u32 {
        let free = self.free_axes().count_ones();
        match self.level {
            Some(_) => free.saturating_sub(1),
            None => free,
        }
    }

    /// Whether a vertex under `self` may be merged into a vertex under `target`: `target` lies
    /// on every surface `self` lies on.
    pub fn may_merge_into(&self, target: &Constraint) -> bool {
        if self.pinned {
            return false;
        }
        let level_ok = self.level.is_none() || self.level == target.level;
        level_ok && self.box_planes & !target.box_planes == 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn freedom_and_merging() {
        let free = Constraint::default();
        let on_alpha = Constraint {
            level: Some(0),
            ..free
        };
        let on_xlow = Constraint {
            box_planes: 0b01,
            ..free
        };
        let curve = Constraint {
            level: Some(0),
            box_planes: 0b01,
            pinned: false,
            interface: false,
            region: 0,
        };
        assert_eq!((free.freedom(), on_alpha.freedom()), (3, 2));
        assert_eq!((on_xlow.free_axes(), curve.freedom()), (0b110, 1));
        assert!(free.may_merge_into(&curve));
        assert!(on_alpha.may_merge_into(&curve) && !curve.may_merge_into(&on_alpha));
        assert!(on_xlow.may_merge_into(&curve) && !on_xlow.may_merge_into(&on_alpha));
        let beta = Constraint {
            level: Some(1),
            ..free
        };
        assert!(!on_alpha.may_merge_into(&beta));
    }
}
