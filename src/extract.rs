//! The parallel cell loop: plan → decompose → clip, slab by slab.
//!
//! Cells are processed in z-slabs (one slab = one layer of cells), a window of slabs at a
//! time in parallel. Each slab welds its points by key into slab-local numbering; the
//! [`Welder`] then numbers them globally in slab order and hands each slab on as a chunk
//! (see `weld`). Output is therefore identical for every thread count and window size.

use std::sync::atomic::{AtomicUsize, Ordering};

use rayon::prelude::*;

use crate::clip::{clip_tet, ClipVertex, Interval, SNAP_ALPHA, SNAP_BETA, SNAP_NONE};
use crate::decompose::plan::{plan_cell, Layout, Planner};
use crate::decompose::{decompose_cell, six, CellCase, CellPoints, LOCAL_BOX, NUM_LOCAL};
use crate::grid::{cell_box_planes, corner_offset, Samples, ScalarGrid};
use crate::keys::{key_index, local_key};
use crate::mesh::TetMesh;
use crate::mesh::{Gather, MeshSink};
use crate::warp::{snap_vertices, Snapped};
use crate::weld::{Slab, Welder};

pub use crate::decompose::plan::Method;

/// Options of [`mesh_interval`].
#[derive(Clone, Debug, PartialEq)]
pub struct MeshOptions {
    /// Lower bound (may be `-inf`).
    pub alpha: f64,
    /// Upper bound (may be `+inf`); must exceed `alpha`.
    pub beta: f64,
    /// Cell decomposition.
    pub method: Method,
    /// Worker threads; `None` uses rayon's global pool (all cores).
    pub threads: Option<usize>,
    /// Warping threshold (`0`: off): a grid vertex that a level cuts one of its edges within
    /// this fraction of the edge's length from is moved onto the level before clipping, when
    /// that provably keeps the topology (see `warp`). Its position stays the grid vertex, so
    /// it lies off the trilinear level set until the quality pass projects it; use it with
    /// [`crate::improve::improve`].
    pub warp: f64,
    /// Whether edges whose linear cut sags from the trilinear level set are split (default
    /// true; see `decompose::sag`). With warping, the snaps are decided on the split
    /// complex.
    pub split_sags: bool,
    /// Slabs (layers of cells) meshed at a time before they are welded and handed on;
    /// `0` (default) is 4 per worker thread. Bounds the memory of
    /// [`mesh_interval_streamed`]; the output does not depend on it.
    pub slabs_in_flight: usize,
}

impl Default for MeshOptions {
    /// The whole field (`alpha = -inf`, `beta = +inf`), [`Method::Ctd`], all cores.
    fn default() -> Self {
        MeshOptions {
            alpha: f64::NEG_INFINITY,
            beta: f64::INFINITY,
            method: Method::Ctd,
            threads: None,
            warp: 0.0,
            split_sags: true,
            slabs_in_flight: 0,
        }
    }
}

impl MeshOptions {
    /// Options for `(alpha, beta)` with `method` and the default thread pool.
    pub fn new(alpha: f64, beta: f64, method: Method) -> Self {
        MeshOptions {
            alpha,
            beta,
            method,
            ..Default::default()
        }
    }

    /// Sets the lower bound.
    #[must_use]
    pub fn alpha(mut self, alpha: f64) -> Self {
        self.alpha = alpha;
        self
    }

    /// Sets the upper bound.
    #[must_use]
    pub fn beta(mut self, beta: f64) -> Self {
        self.beta = beta;
        self
    }

    /// Sets the decomposition method.
    #[must_use]
    pub fn method(mut self, method: Method) -> Self {
        self.method = method;
        self
    }

    /// Sets whether sagging edges are split (see [`MeshOptions::split_sags`]).
    #[must_use]
    pub fn split_sags(mut self, split: bool) -> Self {
        self.split_sags = split;
        self
    }

    /// Sets the warping threshold (see [`MeshOptions::warp`]).
    #[must_use]
    pub fn warp(mut self, warp: f64) -> Self {
        self.warp = warp;
        self
    }

    /// The slabs meshed at a time: [`MeshOptions::slabs_in_flight`], or when 0, 4 per
    /// worker thread. (While one window is meshed the one before is handed on, so up to
    /// twice as many slabs are held.)
    pub fn window(&self) -> usize {
        match self.slabs_in_flight {
            0 => {
                SLABS_PER_THREAD
                    * self
                        .threads
                        .unwrap_or_else(rayon::current_num_threads)
                        .max(1)
            }
            n => n,
        }
    }

    /// Sets the number of worker threads (`None`: rayon's global pool).
    #[must_use]
    pub fn threads(mut self, threads: Option<usize>) -> Self {
        self.threads = threads;
        self
    }
}

/// Why meshing failed.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// alpha >= beta, or a bound is NaN.
    #[error(
        "invalid interval: alpha ({alpha}) must be less than beta ({beta}) and neither may be NaN"
    )]
    InvalidInterval {
        /// Lower bound given.
        alpha: f64,
        /// Upper bound given.
        beta: f64,
    },
    /// The thread pool could not be built.
    #[error("could not start {0} worker threads: {1}")]
    Threads(usize, String),
    /// More than 2^32 - 1 points or tets.
    #[error("mesh too large: {0} exceeds the 32-bit index range")]
    TooLarge(&'static str),
    /// The sink of [`mesh_interval_streamed`] failed (e.g. writing the output).
    #[error("{0}")]
    Output(#[source] std::io::Error),
}

/// Counters of one run.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct MeshStats {
    /// Cells not entirely outside the interval, per [`CellCase`] (index = case as usize).
    pub cells_by_case: [u64; 6],
    /// Cells in the grid.
    pub cells_total: u64,
}

/// A mesh and its counters.
#[derive(Clone, Debug)]
pub struct MeshOutput {
    /// The mesh, in physical coordinates.
    pub mesh: TetMesh,
    /// Counters.
    pub stats: MeshStats,
    /// The grid vertices that warping put on a level ([`MeshOptions::warp`]), by grid index.
    pub snapped: Vec<Snapped>,
}

/// Meshes `{alpha < f < beta}` (its closure) of the piecewise-trilinear field on `grid`.
///
/// Output invariants: see [`TetMesh`]; the mesh is conforming, every tet has positive volume,
/// and with `tptd`/`ctd` its topology is that of the trilinear interpolant's interval volume.
///
/// # Errors
/// [`MeshError::InvalidInterval`] unless `alpha < beta`; [`MeshError::TooLarge`] past 2^32
/// points; [`MeshError::Threads`] if the pool cannot start.
pub fn mesh_interval(grid: &ScalarGrid, opts: &MeshOptions) -> Result<MeshOutput, MeshError> {
    mesh_interval_with_progress(grid, opts, &|_, _| {})
}

/// [`mesh_interval`] reporting `(slabs_done, slabs_total)` to `progress` (called from worker
/// threads).
///
/// # Errors
/// As [`mesh_interval`].
pub fn mesh_interval_with_progress(
    grid: &ScalarGrid,
    opts: &MeshOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<MeshOutput, MeshError> {
    let mut gather = Gather::default();
    let (stats, snapped) = mesh_in_pool(grid, opts, progress, &mut gather)?;
    Ok(MeshOutput {
        mesh: gather.mesh,
        stats,
        snapped,
    })
}

/// Meshes like [`mesh_interval`] but hands the mesh to `sink` slab by slab ([`MeshChunk`]s in
/// z order, points in physical coordinates, elements in global numbers) instead of building
/// it in memory: at most [`MeshOptions::slabs_in_flight`] slabs are held at a time. The
/// chunks concatenated are exactly the mesh [`mesh_interval`] returns, whatever the number of
/// threads or of slabs in flight.
///
/// # Errors
/// As [`mesh_interval`], and [`MeshError::Output`] with the first error of `sink`.
pub fn mesh_interval_streamed(
    grid: &ScalarGrid,
    opts: &MeshOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
    sink: &mut (dyn MeshSink + Send),
) -> Result<MeshStats, MeshError> {
    mesh_in_pool(grid, opts, progress, sink).map(|(stats, _)| stats)
}

/// [`mesh_interval_streamed`], with the snapped vertices.
fn mesh_in_pool(
    grid: &ScalarGrid,
    opts: &MeshOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
    sink: &mut (dyn MeshSink + Send),
) -> Result<(MeshStats, Vec<Snapped>), MeshError> {
    if opts.alpha.is_nan() || opts.beta.is_nan() || opts.alpha >= opts.beta {
        return Err(MeshError::InvalidInterval {
            alpha: opts.alpha,
            beta: opts.beta,
        });
    }
    match opts.threads {
        Some(n) => {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(n.max(1))
                .build()
                .map_err(|e| MeshError::Threads(n, e.to_string()))?;
            pool.install(|| run(grid, opts, progress, sink))
        }
        None => run(grid, opts, progress, sink),
    }
}

/// Slabs in flight per worker thread when [`MeshOptions::slabs_in_flight`] is 0.
const SLABS_PER_THREAD: usize = 4;

/// What every cell of one run shares.
struct Ctx<'a> {
    grid: &'a ScalarGrid,
    /// [`NEAR_TIE`] × the data range: face and body points this near a level are put on it.
    near_tie: f64,
    interval: Interval,
    planner: Planner<'a>,
    /// Per grid vertex, the level it is snapped to (empty: no warping).
    snaps: Vec<u8>,
}

impl Ctx<'_> {
    /// Snap state and clipping value of grid vertex `gi` with data value `val`.
    #[inline]
    fn corner(&self, gi: usize, val: f64) -> (u8, f64) {
        match self.snaps.get(gi).copied().unwrap_or(SNAP_NONE) {
            SNAP_ALPHA => (SNAP_ALPHA, self.interval.alpha),
            SNAP_BETA => (SNAP_BETA, self.interval.beta),
            _ => (SNAP_NONE, val),
        }
    }

    /// Clipping value of a face or body point of the decomposition with value `val`: on the
    /// level when within [`Ctx::near_tie`] of it. The grid's values are (`without_near_ties`),
    /// but these points' values are computed from them: a face saddle at -3e-19 with alpha 0
    /// put the cuts of its edges within rounding of it, and tets between them were inverted
    /// or flat. On the level they follow the ties rule like tied grid values.
    #[inline]
    fn point_value(&self, val: f64) -> f64 {
        let iv = &self.interval;
        [iv.alpha, iv.beta]
            .into_iter()
            .find(|&l| l.is_finite() && (val - l).abs() <= self.near_tie)
            .unwrap_or(val)
    }
}

fn run(
    grid: &ScalarGrid,
    opts: &MeshOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
    sink: &mut (dyn MeshSink + Send),
) -> Result<(MeshStats, Vec<Snapped>), MeshError> {
    let (tied, alpha, beta) = without_near_ties(grid, opts.alpha, opts.beta);
    let grid = tied.as_ref().unwrap_or(grid);
    let [_, _, cz] = grid.cell_dims();
    let (lo, hi) = grid.value_range();
    let mut ctx = Ctx {
        grid,
        near_tie: NEAR_TIE * (hi - lo),
        interval: Interval::new(alpha, beta, &grid.values),
        planner: Planner {
            grid,
            method: opts.method,
            alpha,
            beta,
            split_sags: opts.split_sags,
        },
        snaps: Vec::new(),
    };
    let warp = snap_vertices(grid, &ctx.planner, &ctx.interval, opts.warp);
    ctx.snaps = warp.snaps;
    let window = opts.window();
    let mut stats = MeshStats {
        cells_total: grid.num_cells() as u64,
        ..Default::default()
    };
    let mut welder = Welder::new(grid);
    let done = AtomicUsize::new(0);
    let mesh_window = |k0: usize| -> Vec<Slab> {
        (k0..(k0 + window).min(cz))
            .into_par_iter()
            .map(|k| {
                let s = process_slab(&ctx, k);
                progress(done.fetch_add(1, Ordering::Relaxed) + 1, cz);
                s
            })
            .collect()
    };
    // One window is meshed while the one before is welded and handed to the sink.
    let mut pending: Option<Vec<Slab>> = None;
    for k0 in (0..cz).step_by(window).map(Some).chain([None]) {
        let (next, handed) = rayon::join(
            || k0.map(mesh_window),
            || match pending.take() {
                Some(slabs) => hand_on(&mut welder, slabs, &mut stats, sink),
                None => Ok(()),
            },
        );
        handed?;
        pending = next;
    }
    Ok((stats, warp.snapped))
}

/// Counts the slabs' cases, welds them and hands the chunks to `sink` in order.
fn hand_on(
    welder: &mut Welder,
    slabs: Vec<Slab>,
    stats: &mut MeshStats,
    sink: &mut (dyn MeshSink + Send),
) -> Result<(), MeshError> {
    for s in &slabs {
        for (a, b) in stats.cells_by_case.iter_mut().zip(s.cases) {
            *a += b;
        }
    }
    for chunk in welder.weld(slabs)? {
        sink.chunk(&chunk).map_err(MeshError::Output)?;
    }
    Ok(())
}

/// Values within this fraction of the data range of a level, but not equal to it, are set
/// onto the level before meshing.
pub const NEAR_TIE: f64 = 1e-9;

/// Removes values within [`NEAR_TIE`] × (data range) of `alpha` or `beta` but not equal to
/// it. Such values (e.g. 0.9999999999999999 for a distance sampled on a sphere of radius 1)
/// would put cuts within rounding of a grid vertex: the cut point and the vertex coincide in
/// floating point, and tets between them vanish. As exact ties they follow the ties rule
/// (`clip`), which keeps every tet non-degenerate. Returns the grid to mesh (`None`: `grid`
/// itself) and the levels to mesh:
/// * integer storage: the level moves onto the integer next to it (the tolerance is far below
///   0.5, so no other value lies between them: the same interval of the data), no copy;
/// * float storage: a copy of the grid with those values set onto the level, in the same
///   storage type when it holds the level exactly, else in `f64`.
fn without_near_ties(grid: &ScalarGrid, alpha: f64, beta: f64) -> (Option<ScalarGrid>, f64, f64) {
    let (lo, hi) = grid.value_range();
    let tol = NEAR_TIE * (hi - lo);
    let near = |v: f64, l: f64| l.is_finite() && v != l && (v - l).abs() <= tol;
    let near_any = |v: f64| [alpha, beta].into_iter().find(|&l| near(v, l));
    if !grid.values.par_any(|v| near_any(v).is_some()) {
        return (None, alpha, beta);
    }
    if grid.values.storage().is_integer() && tol < 0.5 {
        let moved = [alpha, beta].map(|l| match grid.values.par_any(|v| near(v, l)) {
            true => l.round(),
            false => l,
        });
        if moved[0] < moved[1] {
            return (None, moved[0], moved[1]);
        }
    }
    let written = [alpha, beta].into_iter().filter(|l| l.is_finite());
    let mut values = match written.clone().all(|l| grid.values.holds(l)) {
        true => grid.values.clone(),
        false => Samples::F64(grid.values.to_f64_vec()),
    };
    values.par_map_in_place(|v| near_any(v).unwrap_or(v));
    let g = ScalarGrid {
        dims: grid.dims,
        spacing: grid.spacing,
        origin: grid.origin,
        direction: grid.direction,
        values,
    };
    (Some(g), alpha, beta)
}

/// Meshes the cells of layer `k` into a new slab.
fn process_slab(ctx: &Ctx, k: usize) -> Slab {
    let [cx, cy, _] = ctx.grid.cell_dims();
    let mut slab = Slab::new(ctx.grid.dims[0] * ctx.grid.dims[1], k);
    let mut tets: Vec<[u8; 4]> = Vec::with_capacity(64);
    let words = ctx.grid.dims[0].div_ceil(64);
    let outside = outside_cells(ctx, k);
    let skipped: usize = outside.iter().map(|w| w.count_ones() as usize).sum();
    slab.reserve(cx * cy - skipped);
    for j in 0..cy {
        for i in 0..cx {
            if (outside[j * words + i / 64] >> (i % 64)) & 1 == 1 {
                continue;
            }
            process_cell(ctx, [i, j, k], &mut tets, &mut slab);
        }
    }
    slab.seal();
    slab
}

/// Bit rows of the cells of layer `k` entirely below alpha or entirely above beta: bit `i`
/// of word `j * words + i / 64` for cell `(i, j)` (`words` = `ceil(nx / 64)`).
///
/// Bit i of a vertex-row word is set when vertex i of that grid row is below (resp. above);
/// a cell is outside when its eight corners are, i.e. when the AND of its four rows has bits
/// i and i + 1 set. Skips such cells 64 at a time.
fn outside_cells(ctx: &Ctx, k: usize) -> Vec<u64> {
    let cy = ctx.grid.dims[1] - 1;
    let words = ctx.grid.dims[0].div_ceil(64);
    let planes = [plane_bits(ctx, k), plane_bits(ctx, k + 1)];
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
fn plane_bits(ctx: &Ctx, z: usize) -> [Vec<u64>; 2] {
    let [nx, ny, _] = ctx.grid.dims;
    let words = nx.div_ceil(64);
    let mut bits = [vec![0u64; ny * words], vec![0u64; ny * words]];
    let base = ctx.grid.index(0, 0, z);
    let (alpha, beta) = (ctx.interval.alpha, ctx.interval.beta);
    for jj in 0..ny {
        let [below, above] = &mut bits;
        let (below, above) = (&mut below[jj * words..], &mut above[jj * words..]);
        let row = base + jj * nx..base + (jj + 1) * nx;
        ctx.grid.values.for_each_in(row, |i, v| {
            below[i / 64] |= ((v <= alpha) as u64) << (i % 64);
            above[i / 64] |= ((v >= beta) as u64) << (i % 64);
        });
    }
    bits
}

/// One cell: plan → decompose → clip (→ weld, in the slab's sink).
#[inline]
fn process_cell(ctx: &Ctx, c: [usize; 3], tets: &mut Vec<[u8; 4]>, slab: &mut Slab) {
    let v = ctx.grid.cell_values(c[0], c[1], c[2]);
    let plan = plan_cell(&ctx.planner, c, &v);
    if plan.layout == Layout::Outside {
        return;
    }
    let box_planes = cell_box_planes(c, ctx.grid.cell_dims());
    if plan.whole_six() && box_planes == 0 {
        // By far the most common cell: six whole tets over the eight corners.
        emit_six_inside(ctx, c, &v, slab);
        slab.cases[CellCase::I as usize] += 1;
        return;
    }
    tets.clear();
    let (case, pts) = decompose_cell(&plan, &v, tets);
    slab.cases[case as usize] += 1;
    clip_cell(ctx, c, box_planes, &pts, tets, slab);
}

/// Clips the tets (over local ids with points `pts`) of cell `c` into `slab`.
#[inline]
fn clip_cell(
    ctx: &Ctx,
    c: [usize; 3],
    box_planes: u8,
    pts: &CellPoints,
    tets: &[[u8; 4]],
    slab: &mut Slab,
) {
    let grid = ctx.grid;
    let base = grid.index(c[0], c[1], c[2]);
    let stride = [1, grid.dims[0], grid.dims[0] * grid.dims[1]];
    let base_f = c.map(|x| x as f64);
    let mut cv: [Option<ClipVertex>; NUM_LOCAL] = [None; NUM_LOCAL];
    for t in tets {
        let tv = t.map(|id| {
            let id = id as usize;
            *cv[id].get_or_insert_with(|| {
                let p = pts.pos[id];
                let key = local_key(base, stride, id);
                let (snap, val) = match id {
                    0..=7 => ctx.corner(key_index(key), pts.val[id]),
                    _ => (SNAP_NONE, ctx.point_value(pts.val[id])),
                };
                ClipVertex {
                    key,
                    pos: [base_f[0] + p[0], base_f[1] + p[1], base_f[2] + p[2]],
                    val,
                    box_mask: LOCAL_BOX[id],
                    snap,
                }
            })
        });
        clip_tet(&tv, &ctx.interval, box_planes, slab);
    }
}

/// Emits the 6-fold split of a cell whose corners are all inside, straight from the corner
/// ids (what clipping would produce, without clipping).
#[inline]
fn emit_six_inside(ctx: &Ctx, c: [usize; 3], v: &[f64; 8], slab: &mut Slab) {
    let grid = ctx.grid;
    let base = grid.index(c[0], c[1], c[2]);
    let (sy, sz) = (grid.dims[0], grid.dims[0] * grid.dims[1]);
    let mut ids = [0u32; 8];
    for (corner, id) in ids.iter_mut().enumerate() {
        let o = corner_offset(corner);
        let pos = [
            (c[0] + o[0]) as f64,
            (c[1] + o[1]) as f64,
            (c[2] + o[2]) as f64,
        ];
        let gi = base + o[0] + o[1] * sy + o[2] * sz;
        *id = slab.corner_id(gi, pos, ctx.corner(gi, v[corner]).1);
    }
    for t in six::SIX {
        slab.tets.push(t.map(|l| ids[l as usize]));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::signed_volume;
    use crate::mesh::BoundaryLabel;
    use rustc_hash::FxHashMap;

    const ALL: [Method; 5] = [
        Method::Five,
        Method::Six,
        Method::Tptd,
        Method::Std,
        Method::Ctd,
    ];

    fn grid(dims: [usize; 3], f: impl Fn(usize, usize, usize) -> f64) -> ScalarGrid {
        let mut v = Vec::with_capacity(dims[0] * dims[1] * dims[2]);
        for k in 0..dims[2] {
            for j in 0..dims[1] {
                for i in 0..dims[0] {
                    v.push(f(i, j, k));
                }
            }
        }
        ScalarGrid::new(dims, v).unwrap()
    }

    fn noise(dims: [usize; 3], seed: u64) -> ScalarGrid {
        grid(dims, |i, j, k| {
            let h = (seed ^ (i + 97 * j + 9973 * k) as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
            ((h >> 11) as f64) / ((1u64 << 53) as f64) * 2.0 - 1.0
        })
    }

    fn volume(m: &TetMesh) -> f64 {
        m.tets
            .iter()
            .map(|t| {
                let p = t.map(|i| m.points[i as usize]);
                let v = signed_volume(p[0], p[1], p[2], p[3]);
                assert!(v > 0.0, "tet volume {v}");
                v
            })
            .sum()
    }

    /// A 2×2×2-cell grid entirely inside: whole cells, corners welded, box boundary only.
    #[test]
    fn all_inside_grid() {
        let g = grid([3, 3, 3], |i, j, k| (i + j + k) as f64);
        for m in ALL {
            let out = mesh_interval(&g, &MeshOptions::new(-1.0, 7.0, m)).unwrap();
            let per_cell = if m == Method::Five { 5 } else { 6 };
            assert_eq!(out.mesh.tets.len(), 8 * per_cell, "{m:?}");
            assert_eq!(
                out.mesh.points.len(),
                27,
                "{m:?}: corners welded across cells"
            );
            assert_eq!(out.mesh.boundary.len(), 6 * 4 * 2, "{m:?}");
            assert!(out
                .mesh
                .boundary_labels
                .iter()
                .all(|&l| l == BoundaryLabel::Box));
            assert!((volume(&out.mesh) - 8.0).abs() < 1e-12);
            assert_eq!(out.stats.cells_by_case[CellCase::I as usize], 8);
            assert_eq!(out.stats.cells_total, 8);
        }
    }

    /// Every point appears once (no two points at the same place, every point in a tet), and
    /// every tet face is shared by two tets or is a boundary triangle.
    #[test]
    fn welding_shares_points_between_cells() {
        let g = noise([5, 4, 6], 3);
        for m in ALL {
            let mesh = mesh_interval(&g, &MeshOptions::new(-0.3, 0.4, m))
                .unwrap()
                .mesh;
            let mut pos: Vec<[u64; 3]> = mesh.points.iter().map(|p| p.map(f64::to_bits)).collect();
            pos.sort();
            pos.dedup();
            assert_eq!(pos.len(), mesh.points.len(), "{m:?}: duplicate points");
            let mut used = vec![false; mesh.points.len()];
            let mut faces: FxHashMap<[u32; 3], usize> = FxHashMap::default();
            for t in &mesh.tets {
                for skip in 0..4 {
                    let mut f = [t[(skip + 1) % 4], t[(skip + 2) % 4], t[(skip + 3) % 4]];
                    f.sort();
                    *faces.entry(f).or_default() += 1;
                }
                t.iter().for_each(|&i| used[i as usize] = true);
            }
            assert!(used.iter().all(|&u| u), "{m:?}: unused point");
            let once = faces.values().filter(|&&n| n == 1).count();
            assert!(faces.values().all(|&n| n <= 2), "{m:?}");
            assert_eq!(once, mesh.boundary.len(), "{m:?}: open faces");
        }
    }

    /// The same mesh for one and several worker threads (rayon pools).
    #[test]
    fn same_mesh_for_any_thread_count() {
        let g = noise([13, 11, 17], 5);
        for m in ALL {
            let opts = MeshOptions::new(-0.2, 0.5, m);
            let run = |n: usize| {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(n)
                    .build()
                    .unwrap();
                pool.install(|| mesh_interval(&g, &opts).unwrap())
            };
            let (a, b) = (run(1), run(3));
            assert_eq!(a.mesh.points, b.mesh.points, "{m:?}");
            assert_eq!(a.mesh.values, b.mesh.values, "{m:?}");
            assert_eq!(a.mesh.tets, b.mesh.tets, "{m:?}");
            assert_eq!(a.mesh.boundary, b.mesh.boundary, "{m:?}");
            assert_eq!(a.mesh.boundary_labels, b.mesh.boundary_labels, "{m:?}");
            assert_eq!(a.stats, b.stats, "{m:?}");
            let c = mesh_interval(&g, &opts.clone().threads(Some(2))).unwrap();
            assert_eq!(a.mesh.tets, c.mesh.tets, "{m:?}");
        }
    }

    /// A linear field is its own trilinear interpolant: the mesh volume is exact.
    #[test]
    fn values_within_rounding_of_a_level_give_a_closed_mesh() {
        // |p| sampled at multiples of 0.2: some vertices are 1.0, others 1 ± 1 ulp.
        let g = grid([13, 13, 13], |i, j, k| {
            let c = |n: usize| -1.2 + n as f64 * 0.2;
            (c(i) * c(i) + c(j) * c(j) + c(k) * c(k)).sqrt()
        });
        assert!(g.values.iter().any(|v| v != 1.0 && (v - 1.0).abs() < 1e-15));
        for method in ALL {
            let m = mesh_interval(&g, &MeshOptions::new(f64::NEG_INFINITY, 1.0, method))
                .unwrap()
                .mesh;
            let mut faces = std::collections::HashMap::new();
            for (t, tet) in m.tets.iter().enumerate() {
                assert!(m.tet_volume(t) > 0.0, "{method:?}: tet {t} not positive");
                for skip in 0..4 {
                    let mut f: Vec<u32> = (0..4).filter(|&i| i != skip).map(|i| tet[i]).collect();
                    f.sort_unstable();
                    *faces.entry(f).or_insert(0usize) += 1;
                }
            }
            for b in &m.boundary {
                let mut f = b.to_vec();
                f.sort_unstable();
                assert_eq!(faces.get(&f), Some(&1), "{method:?}: boundary {b:?}");
            }
            let open = faces.values().filter(|&&n| n == 1).count();
            assert_eq!(open, m.boundary.len(), "{method:?}: unlabelled open faces");
        }
    }

    #[test]
    fn integer_samples_near_a_level_move_the_level_not_the_grid() {
        // u8 ball; alpha 1e-8 above a data value (tolerance 1e-9 * 255), beta 1e-8 below one
        let vals: Vec<u8> = (0..9 * 9 * 9)
            .map(|n| {
                let d = [n % 9, n / 9 % 9, n / 81].map(|x| x as f64 - 4.0);
                (250.0 - 30.0 * (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()) as u8
            })
            .collect();
        let g = ScalarGrid::new([9, 9, 9], vals).unwrap();
        let (a, b) = (100.0 + 1e-8, 190.0 - 1e-8);
        assert!(g.values.iter().any(|v| v == 100.0) && g.values.iter().any(|v| v == 190.0));
        let (copy, a2, b2) = without_near_ties(&g, a, b);
        assert!(copy.is_none());
        assert_eq!((a2, b2), (100.0, 190.0));
        // a level near no value stays; float storage gets a copy with the value on the level
        assert_eq!(without_near_ties(&g, 100.5, 190.0 - 1e-8).1, 100.5);
        let gf = ScalarGrid::new([9, 9, 9], g.values.to_f64_vec()).unwrap();
        let (copy, a3, _) = without_near_ties(&gf, a, b);
        let copy = copy.expect("a copy for float storage");
        assert_eq!(a3, a);
        assert!(copy.values.iter().any(|v| v == a));
        for method in ALL {
            let exact = mesh_interval(&g, &MeshOptions::new(100.0, 190.0, method)).unwrap();
            let near = mesh_interval(&g, &MeshOptions::new(a, b, method)).unwrap();
            assert_eq!(exact.mesh, near.mesh, "{method:?}");
            assert!(!near.mesh.tets.is_empty());
            for t in 0..near.mesh.tets.len() {
                assert!(near.mesh.tet_volume(t) > 0.0, "{method:?}: tet {t}");
            }
        }
    }

    #[test]
    fn volume_of_a_linear_field() {
        let c = [1.0, 2.0, 0.5];
        let g = grid([6, 5, 4], |i, j, k| {
            c[0] * i as f64 + c[1] * j as f64 + c[2] * k as f64
        });
        let len = [5.0, 4.0, 3.0];
        // volume of {c·x < s} in the box, by inclusion–exclusion over the box's corners (bounds
        // avoid the data values, which are multiples of 0.5, so no tie moves a cut)
        let below = |s: f64| -> f64 {
            let mut v = 0.0;
            for corner in 0..8 {
                let shift: f64 = (0..3)
                    .filter(|a| corner >> a & 1 == 1)
                    .map(|a| c[a] * len[a])
                    .sum();
                let sign = if (corner as u32).count_ones().is_multiple_of(2) {
                    1.0
                } else {
                    -1.0
                };
                v += sign * (s - shift).max(0.0).powi(3);
            }
            v / (6.0 * c[0] * c[1] * c[2])
        };
        for (a, b) in [
            (2.7, 9.3),
            (f64::NEG_INFINITY, 3.1),
            (4.2, f64::INFINITY),
            (3.3, 6.1),
        ] {
            let want = below(b.min(100.0)) - below(a.max(-100.0));
            for m in ALL {
                let got = volume(&mesh_interval(&g, &MeshOptions::new(a, b, m)).unwrap().mesh);
                assert!(
                    (got - want).abs() < 1e-9,
                    "{m:?} ({a}, {b}): {got} vs {want}"
                );
            }
        }
    }

    #[test]
    fn options_default_and_builder() {
        let d = MeshOptions::default();
        assert_eq!((d.alpha, d.beta), (f64::NEG_INFINITY, f64::INFINITY));
        assert_eq!((d.method, d.threads), (Method::Ctd, None));
        let o = MeshOptions::default()
            .alpha(1.0)
            .beta(2.0)
            .method(Method::Tptd)
            .threads(Some(3));
        assert_eq!(
            o,
            MeshOptions {
                threads: Some(3),
                ..MeshOptions::new(1.0, 2.0, Method::Tptd)
            }
        );
        let g = noise([3, 3, 3], 1);
        for (a, b) in [(1.0, 1.0), (2.0, 1.0), (f64::NAN, 1.0)] {
            let e = mesh_interval(&g, &MeshOptions::default().alpha(a).beta(b));
            assert!(matches!(e, Err(MeshError::InvalidInterval { .. })));
        }
    }
}
