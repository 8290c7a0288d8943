//! The part of a mesh the quality pass works on: the stars of the vertices that need work,
//! copied out with their own numbering, tet stars and boundary faces, and spliced back.
//!
//! A vertex of the region is *frozen* when some tet outside the region uses it: its star is
//! incomplete, so it neither moves nor is merged; every vertex that needs work has its whole
//! star in the region and is free.
//!
//! The mesh is cut into regions in `partition`, a region is a [`LocalMesh`] (`local_mesh`),
//! the geometry of one vertex's star is in `star`, and the regions are written back in
//! `splice`.

mod local_mesh;
mod partition;
mod splice;
mod star;

pub use local_mesh::{BoundaryFace, LocalMesh, TetOp};
pub use partition::{extract_regions, longest_axis, Regions, SLAB};
pub use splice::{drop_points, retain_flagged, splice, write_positions};
pub use star::{EdgeTets, StarCorners, StarVec};

/// Sorted copy of a triangle, the key of [`LocalMesh::faces`].
#[inline]
pub fn face_key([a, b, c]: [u32; 3]) -> [u32; 3] {
    // Three compare-exchanges (a sorting network): cheaper than a general sort of three.
    let (a, b) = (a.min(b), a.max(b));
    let (b, c) = (b.min(c), b.max(c));
    [a.min(b), a.max(b), c]
}

/// No region.
const NONE: u32 = u32::MAX;

/// The index of the edge between corners `i < j` of a tet in the order
/// `(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)` (edges from corner `i` follow the
/// `i (7 - i) / 2` edges from the corners before it).
#[inline]
pub fn tet_edge(i: usize, j: usize) -> usize {
    i * (7 - i) / 2 + j - i - 1
}

/// The global id of a vertex added in a region, until it is spliced back.
pub const NEW_POINT: u32 = u32::MAX;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn face_key_sorts_every_order_of_three() {
        for t in [[1, 2, 3], [5, 5, 2], [7, 7, 7], [0, u32::MAX, 9]] {
            let mut sorted = t;
            sorted.sort_unstable();
            for [i, j, k] in [
                [0, 1, 2],
                [0, 2, 1],
                [1, 0, 2],
                [1, 2, 0],
                [2, 0, 1],
                [2, 1, 0],
            ] {
                assert_eq!(face_key([t[i], t[j], t[k]]), sorted, "{t:?} {i}{j}{k}");
            }
        }
    }
}
