//! What a mesh of the interval volume `{alpha < f < beta}` of a grid should have: the Betti
//! numbers of the trilinear interval, and its volume.
//!
//! * **Betti numbers**: those of the interval meshed by [`Method::Tptd`] (every face and body
//!   saddle of every cell, so the topology of the trilinear interpolant; the tests check it
//!   against an independent sampled reference, `tests/common/reference.rs`). The mesh
//!   streams into a [`FactsSink`]: memory is the grid plus a few slabs.
//! * **Volume**: cell by cell. A trilinear function on a box takes its extremes at the
//!   corners, and is trilinear again on every sub-box, so a box whose corners all lie strictly
//!   inside the interval is inside, one whose corners all lie on one side of it (or on a
//!   level) is outside, and the others are split in eight, down to
//!   [`ReferenceOptions::depth`] splits of a cell. A box still mixed there counts by the value
//!   at its centre: the estimate; the boxes known to be inside give the lower bound and with
//!   the mixed ones the upper bound. Values equal to a level count as outside, as in the
//!   mesh.

use rayon::prelude::*;
use serde::Serialize;

use crate::facts::FactsSink;
use crate::grid::ScalarGrid;
use crate::trilinear::eval;
use crate::{mesh_interval_streamed, MeshError, MeshOptions, Method};

/// How the reference is computed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReferenceOptions {
    /// Times a cell crossed by a level is split in eight for the volume (0: the cell's
    /// centre decides). Each split halves the gap between the bounds.
    pub depth: u32,
}

impl Default for ReferenceOptions {
    fn default() -> Self {
        ReferenceOptions { depth: 5 }
    }
}

/// The volume of the trilinear interval, in the grid's physical units.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct TrilinearVolume {
    /// The estimate (mixed boxes at the finest split counted by their centre).
    pub estimate: f64,
    /// The volume of the boxes known to be inside: the true volume is at least this.
    pub low: f64,
    /// `low` plus the boxes still mixed at the finest split: the true volume is at most this.
    pub high: f64,
}

/// What a mesh of the interval should have.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Reference {
    /// The interval `(alpha, beta)`.
    pub levels: (f64, f64),
    /// Betti numbers `[b0, b1, b2]` of the trilinear interval.
    pub betti: [usize; 3],
    /// Its volume.
    pub volume: TrilinearVolume,
}

/// The reference of the interval `(alpha, beta)` of `grid`.
///
/// # Errors
/// [`MeshError`] of meshing the interval (an invalid interval, too large a mesh).
pub fn reference(
    grid: &ScalarGrid,
    alpha: f64,
    beta: f64,
    opts: &ReferenceOptions,
) -> Result<Reference, MeshError> {
    let mut facts = FactsSink::new(true);
    let mesh_opts = MeshOptions::new(alpha, beta, Method::Tptd);
    mesh_interval_streamed(grid, &mesh_opts, &|_, _| {}, &mut facts)?;
    let betti = facts.finish().betti.unwrap_or([0; 3]);
    Ok(Reference {
        levels: (alpha, beta),
        betti,
        volume: trilinear_volume(grid, alpha, beta, opts.depth),
    })
}

/// The volume of `{alpha < f < beta}` of the trilinear interpolant of `grid` (see the module
/// documentation), summed per layer of cells and the layers in order (deterministic).
pub fn trilinear_volume(grid: &ScalarGrid, alpha: f64, beta: f64, depth: u32) -> TrilinearVolume {
    let [cx, cy, cz] = grid.cell_dims();
    let layers: Vec<[f64; 3]> = (0..cz)
        .into_par_iter()
        .map(|k| {
            let mut sum = [0.0; 3];
            for j in 0..cy {
                for i in 0..cx {
                    let v = grid.cell_values(i, j, k);
                    let c = cell_volume(&v, alpha, beta, depth);
                    for (s, x) in sum.iter_mut().zip(c) {
                        *s += x;
                    }
                }
            }
            sum
        })
        .collect();
    let mut total = [0.0; 3];
    for l in layers {
        for (t, x) in total.iter_mut().zip(l) {
            *t += x;
        }
    }
    let voxel = grid.affine_determinant().abs();
    TrilinearVolume {
        estimate: total[0] * voxel,
        low: total[1] * voxel,
        high: total[2] * voxel,
    }
}

/// Where a box's corner values put it.
fn classify(c: &[f64; 8], alpha: f64, beta: f64) -> Option<bool> {
    let lo = c.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = c.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if lo > alpha && hi < beta {
        Some(true)
    } else if hi <= alpha || lo >= beta {
        Some(false)
    } else {
        None
    }
}

/// `[estimate, low, high]` of one cell (unit volume) with corner values `v`.
fn cell_volume(v: &[f64; 8], alpha: f64, beta: f64, depth: u32) -> [f64; 3] {
    match classify(v, alpha, beta) {
        Some(true) => return [1.0; 3],
        Some(false) => return [0.0; 3],
        None => {}
    }
    let inside = |p: [f64; 3]| {
        let f = eval(v, p);
        f > alpha && f < beta
    };
    let mut out = [0.0; 3];
    // boxes as (lower corner, size, corner values), split depth first
    let mut stack = vec![([0.0; 3], 1.0, *v, 0u32)];
    while let Some((o, s, c, d)) = stack.pop() {
        let vol = s * s * s;
        match classify(&c, alpha, beta) {
            Some(true) => {
                out[0] += vol;
                out[1] += vol;
                out[2] += vol;
                continue;
            }
            Some(false) => continue,
            None if d == depth => {
                if inside([0, 1, 2].map(|k| o[k] + 0.5 * s)) {
                    out[0] += vol;
                }
                out[2] += vol;
                continue;
            }
            None => {}
        }
        let h = 0.5 * s;
        for child in 0..8 {
            let co = [0, 1, 2].map(|k| o[k] + if child >> k & 1 == 1 { h } else { 0.0 });
            let cv: [f64; 8] = std::array::from_fn(|corner| {
                let p = [0, 1, 2].map(|k| co[k] + if corner >> k & 1 == 1 { h } else { 0.0 });
                eval(v, p)
            });
            stack.push((co, h, cv, d + 1));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_linear_field_gives_its_slab_within_the_bounds() {
        // f = x + 0.3 y on a 5 x 3 x 2 grid: {1.2 < f < 2.9} is a slab of volume
        // (2.9 - 1.2) * 2 * 1 = 3.4 when it stays inside the box in x (x in 0..4).
        let dims = [5, 3, 2];
        let values: Vec<f64> = (0..30)
            .map(|n| (n % 5) as f64 + 0.3 * ((n / 5) % 3) as f64)
            .collect();
        let grid = ScalarGrid::new(dims, values).unwrap();
        let v = trilinear_volume(&grid, 1.2, 2.9, 6);
        assert!(v.low <= 3.4 && 3.4 <= v.high, "{v:?}");
        assert!((v.estimate - 3.4).abs() < 0.01, "{v:?}");
        assert!(v.high - v.low < 0.2, "{v:?}");
        let all = trilinear_volume(&grid, -1.0, 10.0, 3);
        assert_eq!((all.low, all.estimate, all.high), (8.0, 8.0, 8.0));
    }
}
