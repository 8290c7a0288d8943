//! The graded blocks: which cells of the interior are merged into cubes of 2, 4, 8, … cells,
//! as the leaves of an octree aligned to the grid.
//!
//! A cell is *interior* when its eight corners lie strictly inside one region (no level
//! passes through it, and none passes within it: a trilinear cell's values lie between its
//! corners' smallest and largest). A block of side `s` is placed where every cell within
//! [`clearance`]`(s)` cells of it (L∞ distance) is interior, so sizes grow by at most the
//! grading per cell away from the surfaces; then blocks are split until every block's
//! neighbours (across a face, an edge or a corner) are at least half its side (2:1 balance),
//! which the block triangulation ([`super::blocks`]) relies on.

use crate::grid::ScalarGrid;
use crate::levels::Levels;

/// The leaves: per cell, the level of the block holding it (`0`: a fine cell; `l`: a block
/// of side `2^l`, aligned to multiples of its side).
pub struct Leaves {
    /// Cells along x, y, z.
    pub dims: [usize; 3],
    /// Per cell (x fastest), the level of its leaf.
    level: Vec<u8>,
}

/// A block: its lowest cell and its level (side `2^level` cells).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Block {
    /// The block's lowest cell.
    pub origin: [usize; 3],
    /// The block's level (its side is `1 << level` cells).
    pub level: u8,
}

impl Block {
    /// The block's side in cells.
    pub fn side(&self) -> usize {
        1 << self.level
    }
}

/// The distance (in cells, L∞) to the nearest cell that is not interior that a block of side
/// `s` needs: sizes grow from one cell at the surfaces by at most `grading − 1` cells per
/// cell of distance (`s <= 1 + (grading − 1) d`), and at least one cell, so that no corner
/// of a block is a corner of a cell a level passes through.
pub fn clearance(s: usize, grading: f64) -> usize {
    let need = (s as f64 - 1.0) / (grading - 1.0);
    (need.ceil() as usize).max(1)
}

impl Leaves {
    /// The leaves of `grid` for `levels`: blocks up to `2^top` cells a side, graded by
    /// `grading` (> 1), balanced.
    pub fn build(grid: &ScalarGrid, levels: &Levels, top: u8, grading: f64) -> Leaves {
        let dims = grid.cell_dims();
        let counts = OutsideCounts::new(grid, levels);
        let mut leaves = Leaves {
            dims,
            level: vec![0; dims[0] * dims[1] * dims[2]],
        };
        let s = 1usize << top;
        for z in (0..dims[2]).step_by(s) {
            for y in (0..dims[1]).step_by(s) {
                for x in (0..dims[0]).step_by(s) {
                    leaves.place([x, y, z], top, &counts, grading);
                }
            }
        }
        leaves.balance();
        leaves
    }

    /// Places the block at `origin` of level `l` if it fits in the grid and is clear of
    /// non-interior cells, else its eight children.
    fn place(&mut self, origin: [usize; 3], l: u8, counts: &OutsideCounts, grading: f64) {
        if l == 0 {
            return;
        }
        let s = 1usize << l;
        let fits = (0..3).all(|a| origin[a] + s <= self.dims[a]);
        if fits && counts.clear(origin, s, clearance(s, grading)) {
            self.set(Block { origin, level: l }, l);
            return;
        }
        let h = s / 2;
        for c in 0..8 {
            let o = [
                origin[0] + h * (c & 1),
                origin[1] + h * ((c >> 1) & 1),
                origin[2] + h * (c >> 2),
            ];
            if (0..3).all(|a| o[a] < self.dims[a]) {
                self.place(o, l - 1, counts, grading);
            }
        }
    }

    fn index(&self, c: [usize; 3]) -> usize {
        c[0] + self.dims[0] * (c[1] + self.dims[1] * c[2])
    }

    /// The level of the leaf holding cell `c`.
    pub fn level_at(&self, c: [usize; 3]) -> u8 {
        self.level[self.index(c)]
    }

    /// The level of the leaf holding the cell at signed position `c`; `None` outside the
    /// grid.
    pub fn level_at_signed(&self, c: [i64; 3]) -> Option<u8> {
        let inside = (0..3).all(|a| c[a] >= 0 && (c[a] as usize) < self.dims[a]);
        inside.then(|| self.level_at([c[0] as usize, c[1] as usize, c[2] as usize]))
    }

    /// Sets every cell of `b` to level `l`.
    fn set(&mut self, b: Block, l: u8) {
        let s = b.side();
        for z in b.origin[2]..b.origin[2] + s {
            for y in b.origin[1]..b.origin[1] + s {
                let i = self.index([b.origin[0], y, z]);
                self.level[i..i + s].fill(l);
            }
        }
    }

    /// Every block, in z, y, x order of its origin.
    pub fn blocks(&self) -> Vec<Block> {
        let mut out = Vec::new();
        for z in 0..self.dims[2] {
            for y in 0..self.dims[1] {
                for x in 0..self.dims[0] {
                    let l = self.level_at([x, y, z]);
                    let m = (1usize << l) - 1;
                    if l > 0 && x & m == 0 && y & m == 0 && z & m == 0 {
                        out.push(Block {
                            origin: [x, y, z],
                            level: l,
                        });
                    }
                }
            }
        }
        out
    }

    /// The lowest level of the leaves touching block `b` (across a face, an edge or a
    /// corner), inside the grid.
    fn lowest_neighbour(&self, b: Block) -> u8 {
        let s = b.side() as i64;
        let o = b.origin.map(|x| x as i64);
        let mut lowest = u8::MAX;
        for z in -1..=s {
            for y in -1..=s {
                let shell_row = z == -1 || z == s || y == -1 || y == s;
                let xs: Vec<i64> = if shell_row {
                    (-1..=s).collect()
                } else {
                    vec![-1, s]
                };
                for x in xs {
                    if let Some(l) = self.level_at_signed([o[0] + x, o[1] + y, o[2] + z]) {
                        lowest = lowest.min(l);
                    }
                }
            }
        }
        lowest
    }

    /// Splits blocks until each one's neighbours are at least half its side.
    fn balance(&mut self) {
        loop {
            let mut changed = false;
            for b in self.blocks() {
                if b.level >= 2 && self.lowest_neighbour(b) + 1 < b.level {
                    self.set(b, b.level - 1);
                    changed = true;
                }
            }
            if !changed {
                return;
            }
        }
    }

    /// Whether the lattice point `m` (grid vertex indices) is a corner of some leaf.
    pub fn is_leaf_corner(&self, m: [usize; 3]) -> bool {
        (0..8).any(|k| {
            let c = [
                m[0] as i64 - 1 + (k & 1) as i64,
                m[1] as i64 - 1 + ((k >> 1) & 1) as i64,
                m[2] as i64 - 1 + (k >> 2) as i64,
            ];
            let Some(l) = self.level_at_signed(c) else {
                return false;
            };
            let s = 1usize << l;
            (0..3).all(|a| {
                let origin = (c[a] as usize) & !(s - 1);
                m[a] == origin || m[a] == origin + s
            })
        })
    }
}

/// Values within this fraction of the data range of a level count as on it: a thousand times
/// the mesher's own tolerance ([`crate::levels::NEAR_TIE`]).
const NEAR_LEVEL: f64 = 1e3 * crate::levels::NEAR_TIE;

/// Prefix counts of the cells that are not interior, for the count in any box of cells.
struct OutsideCounts {
    dims: [usize; 3],
    /// `(dims + 1)` per axis, x fastest: the count in `[0, x) × [0, y) × [0, z)`.
    sum: Vec<u32>,
}

impl OutsideCounts {
    fn new(grid: &ScalarGrid, levels: &Levels) -> Self {
        let dims = grid.cell_dims();
        let (lo, hi) = grid.value_range();
        let tol = NEAR_LEVEL * (hi - lo);
        let [nx, ny, nz] = dims.map(|d| d + 1);
        let mut sum = vec![0u32; nx * ny * nz];
        let at = |x: usize, y: usize, z: usize| x + nx * (y + ny * z);
        for z in 0..dims[2] {
            for y in 0..dims[1] {
                for x in 0..dims[0] {
                    let out = !interior(&grid.cell_values(x, y, z), levels, tol) as u32;
                    sum[at(x + 1, y + 1, z + 1)] = out
                        + sum[at(x, y + 1, z + 1)]
                        + sum[at(x + 1, y, z + 1)]
                        + sum[at(x + 1, y + 1, z)]
                        - sum[at(x, y, z + 1)]
                        - sum[at(x, y + 1, z)]
                        - sum[at(x + 1, y, z)]
                        + sum[at(x, y, z)];
                }
            }
        }
        OutsideCounts { dims, sum }
    }

    /// Whether every cell within `d` cells of the block at `origin` of side `s` is interior
    /// and inside the grid.
    fn clear(&self, origin: [usize; 3], s: usize, d: usize) -> bool {
        if (0..3).any(|a| origin[a] < d || origin[a] + s + d > self.dims[a]) {
            return false;
        }
        let lo = origin.map(|x| x - d);
        let hi = [0, 1, 2].map(|a| origin[a] + s + d);
        let [nx, ny, _] = self.dims.map(|x| x + 1);
        let at = |x: usize, y: usize, z: usize| self.sum[x + nx * (y + ny * z)] as i64;
        let count = at(hi[0], hi[1], hi[2])
            - at(lo[0], hi[1], hi[2])
            - at(hi[0], lo[1], hi[2])
            - at(hi[0], hi[1], lo[2])
            + at(lo[0], lo[1], hi[2])
            + at(lo[0], hi[1], lo[2])
            + at(hi[0], lo[1], lo[2])
            - at(lo[0], lo[1], lo[2]);
        count == 0
    }
}

/// Whether a cell with corner values `v` is interior: every corner finite, strictly inside
/// the meshed set, farther than `tol` from every level (the mesher sets values within
/// rounding of a level onto it), and all in one region.
pub fn interior(v: &[f64; 8], levels: &Levels, tol: f64) -> bool {
    let strictly =
        |x: f64| x.is_finite() && levels.inside(x) && levels.iter().all(|l| (x - l).abs() > tol);
    let region = levels.region_of(v[0]);
    v.iter()
        .all(|&x| strictly(x) && levels.region_of(x) == region)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Euclidean (`cube` false) or L∞ (`cube` true) distance from the grid's centre.
    fn distance(n: usize, cube: bool) -> ScalarGrid {
        let c = (n - 1) as f64 / 2.0;
        let mut v = Vec::with_capacity(n * n * n);
        for k in 0..n {
            for j in 0..n {
                for i in 0..n {
                    let d = [i, j, k].map(|x| x as f64 - c);
                    v.push(match cube {
                        true => d.iter().fold(0.0f64, |m, x| m.max(x.abs())),
                        false => (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt(),
                    });
                }
            }
        }
        ScalarGrid::new([n; 3], v).unwrap()
    }

    #[test]
    fn blocks_keep_their_clearance_and_balance() {
        let grid = distance(40, true);
        let levels = Levels::interval(f64::NEG_INFINITY, 18.3);
        let leaves = Leaves::build(&grid, &levels, 3, 2.0);
        let blocks = leaves.blocks();
        assert!(blocks.iter().any(|b| b.level == 3), "no block of 8 cells");
        let counts = OutsideCounts::new(&grid, &levels);
        for b in &blocks {
            let s = b.side();
            assert!(counts.clear(b.origin, s, clearance(s, 2.0)), "{b:?}");
            assert!(
                leaves.lowest_neighbour(*b) + 1 >= b.level,
                "{b:?} unbalanced"
            );
        }
        // every cell of a block has the block's level, and the cells tile the blocks
        let covered: usize = blocks.iter().map(|b| b.side().pow(3)).sum();
        let marked = leaves.level.iter().filter(|&&l| l > 0).count();
        assert_eq!(covered, marked);
    }

    #[test]
    fn no_block_touches_a_level_or_the_box() {
        let grid = distance(24, false);
        let levels = Levels::new(&[f64::NEG_INFINITY, 5.1, 10.7]).unwrap();
        let leaves = Leaves::build(&grid, &levels, 2, 2.0);
        for b in leaves.blocks() {
            let s = b.side();
            for a in 0..3 {
                assert!(b.origin[a] >= 1 && b.origin[a] + s < leaves.dims[a]);
            }
            for z in b.origin[2] - 1..=b.origin[2] + s {
                for y in b.origin[1] - 1..=b.origin[1] + s {
                    for x in b.origin[0] - 1..=b.origin[0] + s {
                        assert!(interior(&grid.cell_values(x, y, z), &levels, 0.0));
                    }
                }
            }
        }
    }

    #[test]
    fn clearance_follows_the_grading() {
        assert_eq!(clearance(2, 1.5), 2);
        assert_eq!(clearance(4, 1.5), 6);
        assert_eq!(clearance(8, 1.5), 14);
        assert_eq!(clearance(2, 3.0), 1);
    }
}
