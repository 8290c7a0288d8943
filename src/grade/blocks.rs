//! The tets of one block: a cone from its centre over a triangulation of its six faces.
//!
//! Each face of a block is tiled by *leaf faces*, the faces of the smaller of the two leaves
//! on its sides: the whole face, or (next to blocks of half its side) four quarters. A leaf
//! face of fine cells keeps the triangles the fine mesh has there (given by the caller). A
//! larger one is triangulated from what lies on it alone, so that the blocks on both sides
//! agree: two triangles along the diagonal from its lowest corner when no leaf has a corner
//! at the middle of one of its edges, else a fan from its centre over its corners and those
//! midpoints. With the 2:1 balance ([`super::octree`]) no other point lies on a leaf face, so
//! the blocks and the fine cells around them form a conforming mesh. Every vertex is a grid
//! vertex; the cone's tets have dihedral angles between 35.26° and 125.26° on a grid of equal
//! spacing.

use super::octree::{Block, Leaves};

/// A triangle of grid vertices (indices `[x, y, z]`).
pub type GridTriangle = [[usize; 3]; 3];

/// The triangles of the faces of block `b` that border other blocks, as grid vertices (the
/// faces bordering fine cells are not included: their triangles are the fine mesh's).
pub fn block_face_triangles(leaves: &Leaves, b: Block) -> Vec<GridTriangle> {
    let s = b.side();
    let mut out = Vec::new();
    for axis in 0..3 {
        for high in [false, true] {
            let across = neighbour_cell(b, axis, high);
            let Some(l) = leaves.level_at_signed(across) else {
                continue;
            };
            if l == 0 {
                continue;
            }
            let plane = b.origin[axis] + if high { s } else { 0 };
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let h = if l >= b.level { s } else { s / 2 };
            for du in (0..s).step_by(h) {
                for dv in (0..s).step_by(h) {
                    let mut corner = [0usize; 3];
                    corner[axis] = plane;
                    corner[u] = b.origin[u] + du;
                    corner[v] = b.origin[v] + dv;
                    leaf_face(leaves, corner, (u, v), h, &mut out);
                }
            }
        }
    }
    out
}

/// The cell just across face (`axis`, `high`) of `b`, at the face's lowest corner.
fn neighbour_cell(b: Block, axis: usize, high: bool) -> [i64; 3] {
    let mut c = b.origin.map(|x| x as i64);
    c[axis] += if high { b.side() as i64 } else { -1 };
    c
}

/// Triangulates the leaf face of side `h` with lowest corner `c`, spanning axes `u` and `v`.
fn leaf_face(
    leaves: &Leaves,
    c: [usize; 3],
    (u, v): (usize, usize),
    h: usize,
    out: &mut Vec<GridTriangle>,
) {
    let at = |du: usize, dv: usize| {
        let mut p = c;
        p[u] += du;
        p[v] += dv;
        p
    };
    let half = h / 2;
    // The boundary walked around: corners, and the edge midpoints that are leaf corners.
    let ring = [
        (at(0, 0), true),
        (at(half, 0), false),
        (at(h, 0), true),
        (at(h, half), false),
        (at(h, h), true),
        (at(half, h), false),
        (at(0, h), true),
        (at(0, half), false),
    ];
    let polygon: Vec<[usize; 3]> = ring
        .iter()
        .filter(|&&(p, corner)| corner || leaves.is_leaf_corner(p))
        .map(|&(p, _)| p)
        .collect();
    if polygon.len() == 4 {
        out.push([at(0, 0), at(h, 0), at(h, h)]);
        out.push([at(0, 0), at(h, h), at(0, h)]);
        return;
    }
    let centre = at(half, half);
    for i in 0..polygon.len() {
        out.push([centre, polygon[i], polygon[(i + 1) % polygon.len()]]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::ScalarGrid;
    use crate::levels::Levels;
    use std::collections::HashMap;

    /// A field whose interior (f < 100) holds a graded set of blocks.
    fn leaves() -> Leaves {
        let n = 44;
        let mut v = Vec::new();
        for k in 0..n {
            for j in 0..n {
                for i in 0..n {
                    let x = [i, j, k].map(|t| t as f64 - 21.5);
                    v.push(x[0].abs().max(x[1].abs()).max(x[2].abs()) + 0.3 * (i as f64));
                }
            }
        }
        let grid = ScalarGrid::new([n; 3], v).unwrap();
        Leaves::build(&grid, &Levels::interval(f64::NEG_INFINITY, 19.9), 3, 1.5)
    }

    /// Every triangle of a face between two blocks is made alike by both.
    #[test]
    fn faces_between_blocks_agree() {
        let leaves = leaves();
        let blocks = leaves.blocks();
        assert!(blocks.iter().map(|b| b.level).max() >= Some(2));
        let mut seen: HashMap<[[usize; 3]; 3], usize> = HashMap::new();
        for b in &blocks {
            for mut t in block_face_triangles(&leaves, *b) {
                t.sort();
                *seen.entry(t).or_default() += 1;
            }
        }
        // A triangle on a face between two blocks appears twice; the triangles that appear
        // once lie on the faces bordering fine cells' neighbours... which are not emitted, so
        // every triangle appears exactly twice.
        let once: Vec<_> = seen.iter().filter(|(_, &n)| n != 2).collect();
        assert!(
            once.is_empty(),
            "{} unmatched, e.g. {:?}",
            once.len(),
            once.first()
        );
    }
}
