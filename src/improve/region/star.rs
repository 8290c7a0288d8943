//! The star of one vertex with the other corners fixed ([`StarCorners`]): what a search for a
//! better position of that vertex evaluates again and again, and the inline lists it uses.

use smallvec::SmallVec;

use super::LocalMesh;
use crate::improve::Ctx;

/// Tets of a star that a [`StarVec`] holds inline (on the stack); a larger star's list
/// spills to the heap. 94 % of the vertices of the improved 48³ shell (`shell_48.npy`) have
/// at most 32 tets.
pub const STAR_INLINE: usize = 32;

/// One item per tet of a star, in star order (inline up to [`STAR_INLINE`] tets).
pub type StarVec<T> = SmallVec<[T; STAR_INLINE]>;

/// The tets around an edge ([`LocalMesh::edge_tets`]; inline up to 8).
pub type EdgeTets = SmallVec<[u32; 8]>;

/// The tets around one vertex with the positions of their other corners: what a search
/// for a better position of that vertex evaluates again and again while only it moves.
pub struct StarCorners {
    /// Per tet of the star (in star order): its corners.
    corners: StarVec<[[f64; 3]; 4]>,
    /// Per tet: which corner is the vertex.
    slot: StarVec<usize>,
}

impl StarCorners {
    /// The star of `v` in `lm`.
    pub fn of(lm: &LocalMesh, v: u32) -> Self {
        Self::of_tets(lm, v, None)
    }

    /// The part of the star of `v` whose volume its drift counts ([`LocalMesh::drift`]): all
    /// of it, or for a vertex on an interface, its tets in the region below
    /// ([`LocalMesh::counted_region`]).
    pub fn counted(lm: &LocalMesh, v: u32) -> Self {
        Self::of_tets(lm, v, lm.counted_region(v))
    }

    /// The tets of the star of `v` (of region `region` only, if given).
    fn of_tets(lm: &LocalMesh, v: u32, region: Option<u8>) -> Self {
        let mut star = StarCorners {
            corners: StarVec::new(),
            slot: StarVec::new(),
        };
        for &t in &lm.star[v as usize] {
            if region.is_some_and(|r| lm.region[t as usize] != r) {
                continue;
            }
            let tet = lm.tets[t as usize];
            let slot = tet.iter().position(|&w| w == v).unwrap_or(0);
            star.corners.push(lm.corners(tet));
            star.slot.push(slot);
        }
        star
    }

    /// [`StarCorners::volume`] at `x0` and at `x1`, in one pass over the tets (each sum in
    /// the same order as `volume`'s, so the same numbers).
    pub fn volumes(&self, x0: [f64; 3], x1: [f64; 3]) -> (f64, f64) {
        (0..self.corners.len()).fold((0.0, 0.0), |(s0, s1), i| {
            (s0 + self.tet_volume(i, x0), s1 + self.tet_volume(i, x1))
        })
    }

    /// Summed signed volume of the tets with the vertex at physical point `x` (affine in `x`).
    pub fn volume(&self, x: [f64; 3]) -> f64 {
        (0..self.corners.len()).fold(0.0, |sum, i| sum + self.tet_volume(i, x))
    }

    /// Signed volume of the `i`-th tet with the vertex at physical point `x`.
    #[inline]
    fn tet_volume(&self, i: usize, x: [f64; 3]) -> f64 {
        let mut p = self.corners[i];
        p[self.slot[i]] = x;
        crate::geom::signed_volume(p[0], p[1], p[2], p[3])
    }

    /// Quality of the `i`-th tet with the vertex at physical point `x`.
    #[inline]
    pub fn quality(&self, i: usize, x: [f64; 3], ctx: &Ctx) -> f64 {
        let mut p = self.corners[i];
        p[self.slot[i]] = x;
        ctx.quality(p)
    }

    /// The qualities of the tets (in star order) with the vertex at physical point `x`.
    pub fn qualities(&self, x: [f64; 3], ctx: &Ctx) -> StarVec<f64> {
        (0..self.corners.len())
            .map(|i| self.quality(i, x, ctx))
            .collect()
    }

    /// Whether every tet would have quality above `floor` with the vertex at physical point
    /// `x`, keeping the qualities (in star order) in `out`. `hint` is a tet to test first
    /// (the one that failed last time: in a line search it usually fails again); it is set
    /// to the failing one.
    pub fn qualities_above(
        &self,
        x: [f64; 3],
        ctx: &Ctx,
        floor: f64,
        out: &mut StarVec<f64>,
        hint: &mut usize,
    ) -> bool {
        out.clear();
        let above = |i: usize| Some(self.quality(i, x, ctx)).filter(|&q| q > floor);
        // The hint's quality, once it passed (not evaluated twice).
        let mut at_hint = None;
        if *hint < self.corners.len() {
            at_hint = above(*hint);
            if at_hint.is_none() {
                return false;
            }
        }
        for i in 0..self.corners.len() {
            let q = if i == *hint { at_hint } else { above(i) };
            match q {
                Some(q) => out.push(q),
                None => {
                    *hint = i;
                    return false;
                }
            }
        }
        true
    }
}
