//! Global identities of mesh points. Points are welded by these keys, never by distance.
//!
//! * A [`VertexKey`] names a decomposition vertex: `(grid_index << KIND_BITS) | kind` where
//!   `kind` is [`CORNER`] (the grid vertex itself), [`FACE`]` + axis` (the saddle, or the split
//!   point of the diagonal, of the cell face normal to `axis` whose smallest corner is the grid
//!   vertex), or [`BODY`]` + n` (point `n` inside the cell whose smallest corner is the grid
//!   vertex: its body saddles, then the points that split its edges).
//! * A [`PointKey`] names an output point: a decomposition vertex, or the cut of a
//!   decomposition edge by a level, named by its index in the run's
//!   [`Levels`](crate::levels::Levels) (for one interval: alpha 0, beta 1) in the low
//!   [`LEVEL_BITS`] bits. Its order (the clipper's last
//!   tie-break when it picks cone and fan apexes) is a function of the identity only, so every
//!   cell and thread agrees on it.

/// Identity of a decomposition vertex.
pub type VertexKey = u64;
/// Identity of an output point.
pub type PointKey = u128;

/// Kind tag of a grid vertex.
pub const CORNER: u64 = 0;
/// Kind tag of a face saddle (add the face normal axis 0..3).
pub const FACE: u64 = 1;
/// Kind tag of a point inside a cell (add its number: body saddles 0 and 1, then split points).
pub const BODY: u64 = 4;
/// Bits of a vertex key that hold the kind.
pub const KIND_BITS: u32 = 5;

/// Key of a decomposition vertex.
#[inline]
pub const fn vertex_key(grid_index: usize, kind: u64) -> VertexKey {
    ((grid_index as u64) << KIND_BITS) | kind
}

/// The kind of a vertex key.
#[inline]
pub const fn key_kind(k: VertexKey) -> u64 {
    k & ((1 << KIND_BITS) - 1)
}

/// The grid index a vertex key is attached to.
#[inline]
pub const fn key_index(k: VertexKey) -> usize {
    (k >> KIND_BITS) as usize
}

/// Output-point key of a decomposition vertex.
#[inline]
pub const fn vertex_point(k: VertexKey) -> PointKey {
    (k as u128) << 64
}

/// Bits of a cut's point key that hold the index of its level.
pub const LEVEL_BITS: u32 = 4;

/// Mask of the level bits of a point key.
const LEVEL_MASK: u64 = (1 << LEVEL_BITS) - 1;

const _: () = assert!(crate::levels::MAX_LEVELS <= 1 << LEVEL_BITS);

/// Output-point key of the cut of edge `{a, b}` by level `level` (its index in the run's
/// [`Levels`](crate::levels::Levels): for one interval, 0 = alpha, 1 = beta).
#[inline]
pub fn cut_point(a: VertexKey, b: VertexKey, level: u8) -> PointKey {
    debug_assert!(u64::from(level) <= LEVEL_MASK);
    let (lo, hi) = if a < b { (a, b) } else { (b, a) };
    ((lo as u128) << 64) | (((hi as u128) + 1) << LEVEL_BITS) | level as u128
}

/// The decomposition vertices a point key is made of: `(a, None)` for a vertex,
/// `(a, Some((b, level)))` for a cut of edge `{a, b}` by level index `level`.
#[inline]
pub fn split(p: PointKey) -> (VertexKey, Option<(VertexKey, u8)>) {
    let a = (p >> 64) as u64;
    let low = p as u64;
    if low == 0 {
        (a, None)
    } else {
        (a, Some(((low >> LEVEL_BITS) - 1, (low & LEVEL_MASK) as u8)))
    }
}

/// Grid index of output point `p` if it is a grid vertex (not a saddle, not a cut).
#[inline]
pub fn grid_vertex(p: PointKey) -> Option<usize> {
    let (vk, rest) = split(p);
    (rest.is_none() && key_kind(vk) == CORNER).then_some(key_index(vk))
}

/// Key of cell-local id `id` (`0..8` corners, `8 + f` face points, `14 + n` inner points, as
/// in [`crate::decompose`]) of the cell whose smallest corner is grid vertex `base`;
/// `stride` is the grid-index step along each axis (`[1, nx, nx·ny]`).
#[inline]
pub fn local_key(base: usize, stride: [usize; 3], id: usize) -> VertexKey {
    match id {
        0..=7 => {
            let o = crate::grid::corner_offset(id);
            vertex_key(
                base + o[0] * stride[0] + o[1] * stride[1] + o[2] * stride[2],
                CORNER,
            )
        }
        8..=13 => {
            let f = id - 8;
            let axis = f / 2;
            vertex_key(base + (f % 2) * stride[axis], FACE + axis as u64)
        }
        _ => vertex_key(base, BODY + (id as u64 - crate::decompose::BODY0 as u64)),
    }
}

/// z index of the grid vertex a vertex key is attached to, and whether the vertex lies
/// in the plane z = that index (grid vertices and saddles of faces normal to z do).
#[inline]
fn vertex_plane(k: VertexKey, plane_stride: usize) -> (usize, bool) {
    let kind = key_kind(k);
    let z = key_index(k) / plane_stride;
    (z, kind == CORNER || kind == FACE + 2)
}

/// Whether output point `p` lies in the grid plane z = `z` (`plane_stride` = nx·ny).
#[inline]
pub fn on_z_plane(p: PointKey, z: usize, plane_stride: usize) -> bool {
    let (a, rest) = split(p);
    let in_plane = |k: VertexKey| {
        let (kz, flat) = vertex_plane(k, plane_stride);
        flat && kz == z
    };
    match rest {
        None => in_plane(a),
        Some((b, _)) => in_plane(a) && in_plane(b),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_round_trip_and_order() {
        let a = vertex_key(12345, FACE + 1);
        let b = vertex_key(99, BODY + 1);
        assert_eq!(split(vertex_point(a)), (a, None));
        assert_eq!(split(cut_point(a, b, 1)), (b, Some((a, 1))));
        assert_eq!(cut_point(a, b, 0), cut_point(b, a, 0));
        assert_ne!(cut_point(a, b, 0), cut_point(a, b, 1));
        assert!(vertex_point(b) < cut_point(a, b, 0));
    }

    #[test]
    fn plane_membership() {
        let stride = 10 * 10;
        let v = |i: usize, j: usize, k: usize| i + 10 * (j + 10 * k);
        let c0 = vertex_key(v(1, 2, 3), CORNER);
        let c1 = vertex_key(v(2, 2, 3), CORNER);
        let c2 = vertex_key(v(2, 2, 4), CORNER);
        let fz = vertex_key(v(1, 2, 3), FACE + 2);
        let fx = vertex_key(v(1, 2, 3), FACE);
        assert!(on_z_plane(vertex_point(c0), 3, stride));
        assert!(on_z_plane(vertex_point(fz), 3, stride));
        assert!(!on_z_plane(vertex_point(fx), 3, stride));
        assert!(on_z_plane(cut_point(c0, c1, 0), 3, stride));
        assert!(!on_z_plane(cut_point(c0, c2, 0), 3, stride));
        assert!(!on_z_plane(cut_point(c0, fx, 0), 3, stride));
    }
    #[test]
    fn local_keys_and_grid_vertices() {
        let (nx, ny) = (5, 4);
        let stride = [1, nx, nx * ny];
        let base = 1 + nx * (2 + ny * 3);
        assert_eq!(local_key(base, stride, 0), vertex_key(base, CORNER));
        assert_eq!(
            local_key(base, stride, 7),
            vertex_key(base + 1 + nx + nx * ny, CORNER)
        );
        // +y face (3) of this cell is the -y face (2) of the cell above in y
        assert_eq!(
            local_key(base, stride, 11),
            local_key(base + nx, stride, 10)
        );
        assert_eq!(local_key(base, stride, 11), vertex_key(base + nx, FACE + 1));
        assert_eq!(local_key(base, stride, 15), vertex_key(base, BODY + 1));
        assert_eq!(
            grid_vertex(vertex_point(local_key(base, stride, 6))),
            Some(base + nx + nx * ny)
        );
        assert_eq!(grid_vertex(vertex_point(local_key(base, stride, 8))), None);
        let c = cut_point(vertex_key(base, CORNER), vertex_key(base + 1, CORNER), 0);
        assert_eq!(grid_vertex(c), None);
    }
}
