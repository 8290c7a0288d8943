//! The cells of a layer entirely below the first level or entirely above the last, found 64 at a time from
//! bit rows of the grid's vertex classes, so that the cell loop passes over them.

use crate::grid::ScalarGrid;
use crate::levels::Levels;

/// Bit rows of the cells of layer `k` entirely below alpha or entirely above beta: bit `i`
/// of word `j * words + i / 64` for cell `(i, j)` (`words` = `ceil(nx / 64)`).
///
/// Bit i of a vertex-row word is set when vertex i of that grid row is below (resp. above);
/// a cell is outside when its eight corners are, i.e. when the AND of its four rows has bits
/// i and i + 1 set. Skips such cells 64 at a time.
pub(super) fn outside_cells(grid: &ScalarGrid, lv: &Levels, k: usize) -> Vec<u64> {
    let cy = grid.dims[1] - 1;
    let words = grid.dims[0].div_ceil(64);
    let planes = [plane_bits(grid, lv, k), plane_bits(grid, lv, k + 1)];
    let mut outside = vec![0u64; words * cy];
    for j in 0..cy {
        let out = &mut outside[j * words..(j + 1) * words];
        for side in 0..2 {
            let row = |p: usize, jj: usize, w: usize| planes[p][side][jj * words + w];
            let all = |w: usize| row(0, j, w) & row(0, j + 1, w) & row(1, j, w) & row(1, j + 1, w);
            for (w, o) in out.iter_mut().enumerate() {
                let here = all(w);
                let next = if w + 1 < words { all(w + 1) } else { 0 };
                *o |= here & ((here >> 1) | (next << 63));
            }
        }
    }
    outside
}

/// Class bits of grid plane `z`: `[below, above][j * words + i / 64]` bit `i % 64` for vertex
/// `(i, j)`.
fn plane_bits(grid: &ScalarGrid, lv: &Levels, z: usize) -> [Vec<u64>; 2] {
    let [nx, ny, _] = grid.dims;
    let words = nx.div_ceil(64);
    let mut bits = [vec![0u64; ny * words], vec![0u64; ny * words]];
    let base = grid.index(0, 0, z);
    // Level 0 counts ties below it, the last level above it (`Levels::below`, `above`).
    let (lo, hi) = (lv.get(0), lv.get(lv.len() - 1));
    for jj in 0..ny {
        let [below, above] = &mut bits;
        let (below, above) = (&mut below[jj * words..], &mut above[jj * words..]);
        let row = base + jj * nx..base + (jj + 1) * nx;
        grid.values.for_each_in(row, |i, v| {
            below[i / 64] |= ((v <= lo) as u64) << (i % 64);
            above[i / 64] |= ((v >= hi) as u64) << (i % 64);
        });
    }
    bits
}
