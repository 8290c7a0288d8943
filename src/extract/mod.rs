//! The parallel cell loop: plan → decompose → clip, slab by slab.
//!
//! Cells are processed in z-slabs (one slab = one layer of cells), a window of slabs at a
//! time in parallel. Each slab welds its points by key into slab-local numbering; the
//! [`Welder`] then numbers them globally in slab order and hands each slab on as a chunk
//! (see `weld`). Output is therefore identical for every thread count and window size.

mod cell;
mod outside;

use std::sync::atomic::{AtomicUsize, Ordering};

use rayon::prelude::*;

use crate::decompose::plan::Planner;
use crate::grid::ScalarGrid;
use crate::levels::Levels;
use crate::mesh::TetMesh;
use crate::mesh::{Gather, MeshSink, NoSink, Tee};
use crate::warp::{snap_vertices, Snapped};
use crate::weld::{Slab, TooLarge, Welder};
use cell::{process_slab, Ctx};

pub use crate::decompose::plan::Method;
pub use crate::levels::NEAR_TIE;

/// Options of [`mesh_interval`].
#[derive(Clone, Debug, PartialEq)]
pub struct MeshOptions {
    /// Lower bound (may be `-inf`).
    pub alpha: f64,
    /// Upper bound (may be `+inf`); must exceed `alpha`.
    pub beta: f64,
    /// Several levels (2 to [`MAX_LEVELS`](crate::levels::MAX_LEVELS), increasing), meshed
    /// as the regions between consecutive ones in one conforming mesh, each tet tagged with
    /// its region ([`crate::mesh::Regions`]); when not empty, `alpha` and `beta` are not used.
    /// The boundary is labelled with the first and the last level and box; the triangles on
    /// the levels between regions are interfaces ([`crate::mesh::Regions::interfaces`]). Not
    /// with warping.
    pub levels: Vec<f64>,
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
            levels: Vec::new(),
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

    /// Sets the levels of several regions (see [`MeshOptions::levels`]).
    #[must_use]
    pub fn levels(mut self, levels: &[f64]) -> Self {
        self.levels = levels.to_vec();
        self
    }

    /// The run's levels: [`MeshOptions::levels`], or alpha and beta.
    ///
    /// # Errors
    /// [`MeshError::InvalidInterval`] unless `alpha < beta`; [`MeshError::Levels`] for a bad
    /// list of levels, or several regions with warping.
    pub fn run_levels(&self) -> Result<Levels, MeshError> {
        if self.levels.is_empty() {
            if self.alpha.is_nan() || self.beta.is_nan() || self.alpha >= self.beta {
                return Err(MeshError::InvalidInterval {
                    alpha: self.alpha,
                    beta: self.beta,
                });
            }
            return Ok(Levels::interval(self.alpha, self.beta));
        }
        let levels = Levels::new(&self.levels).map_err(|e| MeshError::Levels(e.to_string()))?;
        if levels.len() > 2 && self.warp > 0.0 {
            return Err(MeshError::Levels(
                "warping (the quality pass) takes one interval, not several regions".into(),
            ));
        }
        Ok(levels)
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
    /// A bad list of levels ([`MeshOptions::levels`]).
    #[error("invalid levels: {0}")]
    Levels(String),
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

impl From<TooLarge> for MeshError {
    fn from(TooLarge(what): TooLarge) -> Self {
        MeshError::TooLarge(what)
    }
}

/// Counters of one run.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct MeshStats {
    /// Cells not entirely outside the interval, per
    /// [`CellCase`](crate::decompose::CellCase) (index = case as usize).
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
    mesh_interval_seen_by(grid, opts, progress, &mut NoSink)
}

/// [`mesh_interval_with_progress`] handing each slab to `also` as well, as it is gathered:
/// to analyse the mesh while it is made (as the streamed run does) rather than after.
///
/// # Errors
/// As [`mesh_interval`], and [`MeshError::Output`] with the first error of `also`.
pub fn mesh_interval_seen_by(
    grid: &ScalarGrid,
    opts: &MeshOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
    also: &mut (dyn MeshSink + Send),
) -> Result<MeshOutput, MeshError> {
    let mut gather = Gather::new(opts.levels.len());
    let (stats, snapped) = mesh_in_pool(grid, opts, progress, &mut Tee(&mut gather, also))?;
    Ok(MeshOutput {
        mesh: gather.mesh,
        stats,
        snapped,
    })
}

/// Meshes like [`mesh_interval`] but hands the mesh to `sink` slab by slab
/// ([`MeshChunk`](crate::mesh::MeshChunk)s in z order, points in physical coordinates,
/// elements in global numbers) instead of building it in memory: at most [`MeshOptions::slabs_in_flight`] slabs are held at a time. The
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
    opts.run_levels()?;
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

fn run(
    grid: &ScalarGrid,
    opts: &MeshOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
    sink: &mut (dyn MeshSink + Send),
) -> Result<(MeshStats, Vec<Snapped>), MeshError> {
    let (tied, levels) = opts.run_levels()?.without_near_ties(grid);
    let grid = tied.as_ref().unwrap_or(grid);
    let [_, _, cz] = grid.cell_dims();
    let (lo, hi) = grid.value_range();
    let mut ctx = Ctx {
        grid,
        near_tie: NEAR_TIE * (hi - lo),
        levels: levels.with_ties(&grid.values),
        planner: Planner {
            grid,
            method: opts.method,
            levels,
            split_sags: opts.split_sags,
        },
        regions: Vec::new(),
        snaps: Vec::new(),
    };
    ctx.regions = (0..ctx.levels.regions())
        .map(|k| ctx.levels.region(k))
        .collect();
    let warp = snap_vertices(grid, &ctx.planner, &ctx.levels, opts.warp);
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

#[cfg(test)]
mod tests;
