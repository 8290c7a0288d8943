//! Plateaus: the maximal edge-connected sets of at least two grid vertices of equal value
//! (the vertices whose link [`super::find::vertex_class`] cannot classify), found by a flood
//! fill from the vertices with an equal neighbour. Labels are kept for those vertices only,
//! chunk by chunk, so memory follows the plateaus, not the grid; a value filter (windows)
//! skips rows by their minimum and maximum and reads neighbours only of vertices it keeps.

use rayon::prelude::*;

use super::find::meets;
use crate::grid::ScalarGrid;

/// Label of grid vertices that belong to no plateau.
pub const NO_REGION: u32 = u32::MAX;

/// A plateau vertex whose plateau is not numbered yet (only while the labels are made).
const UNCLAIMED: u32 = u32::MAX - 1;

/// Grid vertices per chunk of [`Plateaus`]' sparse labels (`1 << CHUNK_BITS`).
const CHUNK_BITS: u32 = 20;

/// Labels are kept for every grid vertex (4 bytes each, constant-time lookups) when at least
/// one vertex in `DENSE_FRACTION` is on a plateau, else for the plateau vertices only (8
/// bytes each, lookups by binary search).
const DENSE_FRACTION: usize = 8;

/// The plateaus of a grid (or those with a value in some windows). Memory follows the
/// plateau vertices, not the grid, unless they are a large part of it.
///
/// Invariants: `regions` lists every maximal edge-connected set of at least two vertices of
/// equal value (vertex indices ascending), ordered by their smallest vertex; a vertex is on a
/// plateau iff it has an edge-neighbour of its value, and [`Plateaus::label`] is its position
/// in `regions`.
pub struct Plateaus {
    /// The plateaus' vertices (ascending grid indices), ordered by their smallest vertex.
    pub regions: Vec<Vec<usize>>,
    /// Per chunk of `1 << chunk_bits` grid vertices: the in-chunk offsets of its plateau
    /// vertices, ascending (empty with dense labels).
    offsets: Vec<Vec<u32>>,
    labels: Labels,
    /// Chunks hold `1 << chunk_bits` grid vertices ([`CHUNK_BITS`]; smaller in tests).
    chunk_bits: u32,
    /// Number of plateau vertices.
    flat: usize,
}

/// The plateau numbers: of every grid vertex, or per chunk of the vertices in `offsets`.
enum Labels {
    Dense(Vec<u32>),
    Sparse(Vec<Vec<u32>>),
}

impl Plateaus {
    /// The plateau number of grid vertex `idx`, [`NO_REGION`] when it is on none.
    #[inline]
    pub fn label(&self, idx: usize) -> u32 {
        let l = match &self.labels {
            Labels::Dense(l) => l[idx],
            Labels::Sparse(ids) => self.slot(idx).map_or(NO_REGION, |(c, s)| ids[c][s]),
        };
        // only while the labels are being made
        if l == UNCLAIMED {
            NO_REGION
        } else {
            l
        }
    }

    /// Number of grid vertices on plateaus.
    pub fn num_flat(&self) -> usize {
        self.flat
    }

    /// Whether labels are held for every grid vertex (many plateau vertices).
    pub fn is_dense(&self) -> bool {
        matches!(self.labels, Labels::Dense(_))
    }

    /// Labels `idx` with `id` if it is a plateau vertex without a label yet; whether it was.
    #[inline]
    fn claim(&mut self, idx: usize, id: u32) -> bool {
        let slot = match &mut self.labels {
            Labels::Dense(l) => &mut l[idx],
            Labels::Sparse(_) => {
                let Some((c, s)) = self.slot(idx) else {
                    return false;
                };
                let Labels::Sparse(ids) = &mut self.labels else {
                    unreachable!()
                };
                &mut ids[c][s]
            }
        };
        let fresh = *slot == UNCLAIMED;
        if fresh {
            *slot = id;
        }
        fresh
    }

    /// The chunk and position of plateau vertex `idx` in `offsets`.
    #[inline]
    fn slot(&self, idx: usize) -> Option<(usize, usize)> {
        let c = idx >> self.chunk_bits;
        let off = (idx & ((1 << self.chunk_bits) - 1)) as u32;
        let s = self.offsets.get(c)?.binary_search(&off).ok()?;
        Some((c, s))
    }
}

/// The plateaus of the grid (see [`Plateaus`]).
pub fn plateaus(grid: &ScalarGrid) -> Plateaus {
    plateaus_in(grid, &[(f64::NEG_INFINITY, f64::INFINITY)])
}

/// [`plateaus`] of the values in one of the closed `windows` `[lo, hi]` (vertices of other
/// values are on none). Rows (along x) whose values miss every window are passed over after
/// their minimum and maximum, and the neighbours of a vertex are read only when its value is
/// in a window: narrow windows cost about one pass over the samples, and memory is that of
/// their plateaus.
pub fn plateaus_in(grid: &ScalarGrid, windows: &[(f64, f64)]) -> Plateaus {
    plateaus_chunked(grid, windows, CHUNK_BITS)
}

/// [`plateaus_in`] with chunks of `1 << chunk_bits` grid vertices.
fn plateaus_chunked(grid: &ScalarGrid, windows: &[(f64, f64)], chunk_bits: u32) -> Plateaus {
    let offsets = plateau_offsets(grid, windows, chunk_bits);
    let mut p = Plateaus::unnumbered(offsets, grid.num_vertices(), chunk_bits);
    p.number(grid);
    p
}

/// The edge-neighbours of grid vertex `idx`.
fn neighbours(grid: &ScalarGrid, idx: usize) -> impl Iterator<Item = usize> + '_ {
    let nx = grid.dims[0];
    let stride = [1, nx, nx * grid.dims[1]];
    let p = grid.vertex_ijk(idx);
    (0..6).filter_map(move |d| {
        let (a, side) = (d / 2, d % 2);
        if side == 0 {
            (p[a] > 0).then(|| idx - stride[a])
        } else {
            (p[a] + 1 < grid.dims[a]).then(|| idx + stride[a])
        }
    })
}

/// Per chunk of `1 << chunk_bits` grid vertices, the in-chunk offsets (ascending) of the
/// vertices with a value in a window and an edge-neighbour of that value.
fn plateau_offsets(grid: &ScalarGrid, windows: &[(f64, f64)], chunk_bits: u32) -> Vec<Vec<u32>> {
    let n = grid.num_vertices();
    let nx = grid.dims[0];
    let chunk = 1usize << chunk_bits;
    (0..n.div_ceil(chunk))
        .into_par_iter()
        .map(|c| {
            let (start, end) = (c * chunk, n.min((c + 1) * chunk));
            let mut out = Vec::new();
            // the chunk row by row (its first and last rows may be partial)
            let mut a = start;
            while a < end {
                let b = end.min((a / nx + 1) * nx);
                let (lo, hi) = grid.values.min_max_in(a..b);
                if meets(windows, lo, hi) {
                    grid.values.for_each_in(a..b, |o, v| {
                        if !meets(windows, v, v) {
                            return;
                        }
                        // the vertex and its six neighbours (itself where there is none)
                        let i = a + o;
                        let mut idx = [i; 7];
                        let mut count = 1;
                        for m in neighbours(grid, i) {
                            idx[count] = m;
                            count += 1;
                        }
                        let w = grid.values.gather(idx);
                        if w[1..count].contains(&v) {
                            out.push((i - start) as u32);
                        }
                    });
                }
                a = b;
            }
            out.shrink_to_fit();
            out
        })
        .collect()
}

impl Plateaus {
    /// The plateau vertices of a grid of `n` vertices (`offsets`, per chunk of
    /// `1 << chunk_bits`) marked unclaimed, with no plateau numbered yet: in dense labels
    /// (the offsets then dropped) when they are at least one vertex in [`DENSE_FRACTION`],
    /// else in sparse ones.
    fn unnumbered(offsets: Vec<Vec<u32>>, n: usize, chunk_bits: u32) -> Plateaus {
        let flat: usize = offsets.iter().map(Vec::len).sum();
        let mut p = Plateaus {
            regions: Vec::new(),
            offsets,
            labels: Labels::Sparse(Vec::new()),
            chunk_bits,
            flat,
        };
        if flat >= n / DENSE_FRACTION {
            // the plateau vertices marked in the dense labels, then their list dropped
            let mut l = vec![NO_REGION; n];
            for (c, o) in p.offsets.iter().enumerate() {
                for &off in o {
                    l[(c << chunk_bits) + off as usize] = UNCLAIMED;
                }
            }
            p.offsets = Vec::new();
            p.labels = Labels::Dense(l);
        } else {
            p.labels = Labels::Sparse(p.offsets.iter().map(|o| vec![UNCLAIMED; o.len()]).collect());
        }
        p
    }

    /// Numbers the plateaus in the order of their smallest vertex, as the vertices are
    /// visited, and lists their vertices.
    fn number(&mut self, grid: &ScalarGrid) {
        let mut stack = Vec::new();
        if self.is_dense() {
            for i in 0..grid.num_vertices() {
                self.grow(grid, i, &mut stack);
            }
        } else {
            for c in 0..self.offsets.len() {
                for s in 0..self.offsets[c].len() {
                    let start = (c << self.chunk_bits) + self.offsets[c][s] as usize;
                    self.grow(grid, start, &mut stack);
                }
            }
        }
    }

    /// The plateau of `start` by a flood fill (`stack`: empty scratch), numbered next, unless
    /// `start` is on no plateau or on one already numbered.
    fn grow(&mut self, grid: &ScalarGrid, start: usize, stack: &mut Vec<usize>) {
        let id = self.regions.len() as u32;
        if !self.claim(start, id) {
            return;
        }
        let v = grid.values.get(start);
        let mut region = vec![start];
        stack.push(start);
        while let Some(i) = stack.pop() {
            for m in neighbours(grid, i) {
                // an equal neighbour of a kept value is a plateau vertex
                if grid.values.get(m) == v && self.claim(m, id) {
                    region.push(m);
                    stack.push(m);
                }
            }
        }
        region.sort_unstable();
        self.regions.push(region);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every plateau of `values` by brute force: vertex lists of the edge-connected classes of
    /// equal values with at least two vertices whose value is in `[lo, hi]`.
    fn brute_force(grid: &ScalarGrid, lo: f64, hi: f64) -> Vec<Vec<usize>> {
        let n = grid.num_vertices();
        let stride = [1, grid.dims[0], grid.dims[0] * grid.dims[1]];
        let mut seen = vec![false; n];
        let mut out = Vec::new();
        for s in 0..n {
            let v = grid.values.get(s);
            if seen[s] || v < lo || v > hi {
                continue;
            }
            let (mut region, mut stack) = (vec![s], vec![s]);
            seen[s] = true;
            while let Some(i) = stack.pop() {
                let p = grid.vertex_ijk(i);
                for a in 0..3 {
                    for (ok, m) in [
                        (p[a] > 0, i.wrapping_sub(stride[a])),
                        (p[a] + 1 < grid.dims[a], i + stride[a]),
                    ] {
                        if ok && !seen[m] && grid.values.get(m) == v {
                            seen[m] = true;
                            region.push(m);
                            stack.push(m);
                        }
                    }
                }
            }
            if region.len() > 1 {
                region.sort_unstable();
                out.push(region);
            }
        }
        out
    }

    #[test]
    fn sparse_labels_match_a_flood_fill_for_any_chunk_size() {
        let dims = [13, 9, 7];
        let values: Vec<u8> = (0..dims[0] * dims[1] * dims[2])
            .map(|i| {
                let (x, y, z) = (i % 13, i / 13 % 9, i / 117);
                ((x / 3 + y / 2 + z) % 4 + (x * y + z) % 3 / 2) as u8
            })
            .collect();
        let grid = ScalarGrid::new(dims, values).unwrap();
        let mut modes = [false; 2];
        for (lo, hi) in [
            (f64::NEG_INFINITY, f64::INFINITY),
            (1.0, 2.0),
            (4.0, 4.0),
            (3.5, 3.6),
        ] {
            let expected = brute_force(&grid, lo, hi);
            for bits in [2, 5, 7, CHUNK_BITS] {
                let p = plateaus_chunked(&grid, &[(lo, hi)], bits);
                let many = 8 * p.num_flat() >= grid.num_vertices();
                assert_eq!(p.is_dense(), many);
                modes[p.is_dense() as usize] |= p.num_flat() > 0;
                assert_eq!(p.regions, expected, "[{lo}, {hi}] chunks of 2^{bits}");
                let flat: usize = expected.iter().map(Vec::len).sum();
                assert_eq!(p.num_flat(), flat);
                for i in 0..grid.num_vertices() {
                    let want = expected
                        .iter()
                        .position(|r| r.binary_search(&i).is_ok())
                        .map_or(NO_REGION, |r| r as u32);
                    assert_eq!(p.label(i), want, "vertex {i}, chunks of 2^{bits}");
                }
            }
        }
        assert_eq!(modes, [true, true], "sparse and dense labels both tested");
    }
}
