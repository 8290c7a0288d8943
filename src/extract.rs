//! The parallel cell loop and the deterministic merge of points by key.
//!
//! Cells are processed in z-slabs (one slab = one layer of cells) in parallel. Each slab welds
//! its points by [`PointKey`] into slab-local numbering. A sequential pass then numbers points
//! globally in slab order; only keys on the plane shared by two slabs are looked up across
//! slabs. Output is therefore identical for every thread count.

use std::sync::atomic::{AtomicUsize, Ordering};

use rayon::prelude::*;
use rustc_hash::FxHashMap;

use crate::clip::{clip_tet, ClipPoint, ClipSink, ClipVertex, Interval};
use crate::decompose::plan::{corners_connected, face_needed, is_full, CellClasses};
use crate::decompose::{five, six, tptd, CellCase, CellPoints, BODY0, NUM_LOCAL};
use crate::grid::{corner_faces, corner_offset, ScalarGrid, LOW_FACES};
use crate::keys::{on_z_plane, split, vertex_key, vertex_point, PointKey, BODY, CORNER, FACE};
use crate::mesh::{BoundaryLabel, TetMesh};
use crate::trilinear::{body_saddles, face_saddle, face_saddle_point, BodySaddle};

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
}

impl MeshOptions {
    /// Options with the default thread pool.
    pub fn new(alpha: f64, beta: f64, method: Method) -> Self {
        MeshOptions {
            alpha,
            beta,
            method,
            threads: None,
        }
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
            pool.install(|| run(grid, opts, progress))
        }
        None => run(grid, opts, progress),
    }
}

/// Points, tets and boundary triangles of one slab, numbered locally.
struct Slab {
    /// Slab-local id of each grid vertex on the slab's two planes (`u32::MAX`: none yet).
    corner_ids: Vec<u32>,
    /// Grid index of the first vertex of the slab's lower plane.
    plane_base: usize,
    /// Direct-mapped cache in front of `map` (points recur within and across nearby cells).
    recent: Box<[(PointKey, u32); RECENT]>,
    map: FxHashMap<PointKey, u32>,
    keys: Vec<PointKey>,
    pos: Vec<[f64; 3]>,
    val: Vec<f64>,
    tets: Vec<[u32; 4]>,
    tris: Vec<[u32; 3]>,
    labels: Vec<BoundaryLabel>,
    cases: [u64; 6],
}

const RECENT: usize = 256;

impl Slab {
    fn new(plane: usize, k: usize) -> Self {
        Slab {
            corner_ids: vec![u32::MAX; 2 * plane],
            plane_base: k * plane,
            recent: Box::new([(PointKey::MAX, 0); RECENT]),
            map: FxHashMap::with_capacity_and_hasher(plane / 4, Default::default()),
            keys: Vec::new(),
            pos: Vec::new(),
            val: Vec::new(),
            tets: Vec::new(),
            tris: Vec::new(),
            labels: Vec::new(),
            cases: [0; 6],
        }
    }

    #[inline]
    fn push_point(&mut self, key: PointKey, pos: [f64; 3], val: f64) -> u32 {
        let i = self.keys.len() as u32;
        self.keys.push(key);
        self.pos.push(pos);
        self.val.push(val);
        i
    }

    /// Slab-local id of grid vertex `grid_index` (on one of the slab's two planes).
    #[inline]
    fn corner_id(&mut self, grid_index: usize, pos: [f64; 3], val: f64) -> u32 {
        let slot = grid_index - self.plane_base;
        let id = self.corner_ids[slot];
        if id != u32::MAX {
            return id;
        }
        let id = self.push_point(vertex_point(vertex_key(grid_index, CORNER)), pos, val);
        self.corner_ids[slot] = id;
        id
    }

    #[inline]
    fn id(&mut self, p: &ClipPoint) -> u32 {
        let (vk, rest) = split(p.key);
        if rest.is_none() && vk & 7 == CORNER {
            return self.corner_id((vk >> 3) as usize, p.pos, p.val);
        }
        let h = ((p.key as u64) ^ ((p.key >> 64) as u64)).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 56;
        let slot = &mut self.recent[h as usize % RECENT];
        if slot.0 == p.key {
            return slot.1;
        }
        if let Some(&i) = self.map.get(&p.key) {
            *slot = (p.key, i);
            return i;
        }
        let i = self.push_point(p.key, p.pos, p.val);
        self.recent[h as usize % RECENT] = (p.key, i);
        self.map.insert(p.key, i);
        i
    }
}

impl ClipSink for Slab {
    #[inline]
    fn tet(&mut self, points: &[ClipPoint], t: [usize; 4]) {
        let ids = t.map(|i| self.id(&points[i]));
        self.tets.push(ids);
    }
    #[inline]
    fn triangle(&mut self, points: &[ClipPoint], t: [usize; 3], label: BoundaryLabel) {
        let ids = t.map(|i| self.id(&points[i]));
        self.tris.push(ids);
        self.labels.push(label);
    }
}

struct Ctx<'a> {
    grid: &'a ScalarGrid,
    interval: Interval,
    method: Method,
    /// Box-plane mask of every local id (corners: their three faces; face saddles: their face).
    local_box: [u8; NUM_LOCAL],
}

impl Ctx<'_> {
    /// Whether the cell at `c` is full (uses every saddle), computed from its values when
    /// asked: only cells with a face saddle ask about the neighbour across it, which is far
    /// cheaper than a pass over all cells.
    #[inline]
    fn cell_full(&self, c: [usize; 3]) -> bool {
        match self.method {
            Method::Tptd => true,
            Method::Ctd | Method::Std => compute_full(
                self.grid,
                self.method,
                self.interval.alpha,
                self.interval.beta,
                c,
            ),
            Method::Five | Method::Six => false,
        }
    }
}

/// Whether the cell at `c` uses all its saddles (computed from its values).
fn compute_full(grid: &ScalarGrid, method: Method, alpha: f64, beta: f64, c: [usize; 3]) -> bool {
    let v = grid.cell_values(c[0], c[1], c[2]);
    let cls = CellClasses::new(&v, alpha, beta);
    if !(cls.crosses_alpha() || cls.crosses_beta()) {
        return false;
    }
    let nb = body_saddles(&v).1;
    is_full(method, cls, nb)
}

fn run(
    grid: &ScalarGrid,
    opts: &MeshOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<MeshOutput, MeshError> {
    let mut local_box = [0u8; NUM_LOCAL];
    for (c, b) in local_box.iter_mut().enumerate().take(8) {
        *b = corner_faces(c).iter().fold(0, |m, &f| m | (1 << f));
    }
    for f in 0..6 {
        local_box[8 + f] = 1 << f;
    }
    let [_, _, cz] = grid.cell_dims();
    let ctx = Ctx {
        grid,
        interval: Interval::new(opts.alpha, opts.beta, &grid.values),
        method: opts.method,
        local_box,
    };
    let done = AtomicUsize::new(0);
    let slabs: Vec<Slab> = (0..cz)
        .into_par_iter()
        .map(|k| {
            let s = process_slab(&ctx, k);
            let d = done.fetch_add(1, Ordering::Relaxed) + 1;
            progress(d, cz);
            s
        })
        .collect();
    let mut stats = MeshStats {
        cells_total: grid.num_cells() as u64,
        ..Default::default()
    };
    for s in &slabs {
        for (a, b) in stats.cells_by_case.iter_mut().zip(s.cases) {
            *a += b;
        }
    }
    let mesh = merge(grid, slabs)?;
    Ok(MeshOutput { mesh, stats })
}

/// Global numbering in slab order; returns the mesh in physical coordinates.
fn merge(grid: &ScalarGrid, slabs: Vec<Slab>) -> Result<TetMesh, MeshError> {
    let stride = grid.dims[0] * grid.dims[1];
    let mut maps: Vec<Vec<u32>> = Vec::with_capacity(slabs.len());
    // Points of the plane shared with the slab below: grid vertices in a dense array (indexed
    // by position in the plane), every other point (cuts, saddles of z-faces) in a hash map.
    let mut prev_corners: Vec<u32> = vec![u32::MAX; stride];
    let mut top_corners: Vec<u32> = vec![u32::MAX; stride];
    let mut prev_top: FxHashMap<PointKey, u32> = FxHashMap::default();
    let mut next = 0u64;
    let mut new_from: Vec<(usize, Vec<u32>)> = Vec::with_capacity(slabs.len());
    for (k, s) in slabs.iter().enumerate() {
        let mut map = Vec::with_capacity(s.keys.len());
        let mut fresh = Vec::new();
        let mut top: FxHashMap<PointKey, u32> = FxHashMap::default();
        top_corners.fill(u32::MAX);
        for (li, &key) in s.keys.iter().enumerate() {
            let (vk, rest) = split(key);
            let corner = rest.is_none() && vk & 7 == CORNER;
            let gi = (vk >> 3) as usize;
            let shared = if corner {
                let g = if gi / stride == k {
                    prev_corners[gi % stride]
                } else {
                    u32::MAX
                };
                (g != u32::MAX).then_some(g)
            } else if on_z_plane(key, k, stride) {
                prev_top.get(&key).copied()
            } else {
                None
            };
            let gid = match shared {
                Some(g) => g,
                None => {
                    let g = u32::try_from(next).map_err(|_| MeshError::TooLarge("points"))?;
                    next += 1;
                    fresh.push(li as u32);
                    g
                }
            };
            if corner {
                if gi / stride == k + 1 {
                    top_corners[gi % stride] = gid;
                }
            } else if on_z_plane(key, k + 1, stride) {
                top.insert(key, gid);
            }
            map.push(gid);
        }
        prev_top = top;
        std::mem::swap(&mut prev_corners, &mut top_corners);
        maps.push(map);
        new_from.push((k, fresh));
    }
    let n = next as usize;
    let mut points = Vec::with_capacity(n);
    let mut values = Vec::with_capacity(n);
    for (k, fresh) in &new_from {
        let s = &slabs[*k];
        for &li in fresh {
            points.push(s.pos[li as usize]);
            values.push(s.val[li as usize]);
        }
    }
    let total_tets: usize = slabs.iter().map(|s| s.tets.len()).sum();
    if total_tets > u32::MAX as usize {
        return Err(MeshError::TooLarge("tets"));
    }
    let flip = grid.affine_determinant() < 0.0;
    let tets = remap(
        &slabs,
        &maps,
        |s| &s.tets,
        |t, m| {
            let g = t.map(|i| m[i as usize]);
            if flip {
                [g[0], g[1], g[3], g[2]]
            } else {
                g
            }
        },
    );
    let boundary = remap(
        &slabs,
        &maps,
        |s| &s.tris,
        |t, m| {
            let g = t.map(|i| m[i as usize]);
            if flip {
                [g[0], g[2], g[1]]
            } else {
                g
            }
        },
    );
    let boundary_labels: Vec<BoundaryLabel> = slabs
        .iter()
        .flat_map(|s| s.labels.iter().copied())
        .collect();
    drop(slabs);
    let lin = grid.linear_map();
    let origin = grid.origin;
    points.par_iter_mut().for_each(|p| {
        let q = *p;
        for r in 0..3 {
            p[r] = origin[r] + lin[r][0] * q[0] + lin[r][1] * q[1] + lin[r][2] * q[2];
        }
    });
    Ok(TetMesh {
        points,
        values,
        tets,
        boundary,
        boundary_labels,
    })
}

/// Concatenates one per-slab list in slab order, renumbering each element through its slab's
/// local-to-global map, in parallel into an exactly sized vector.
fn remap<T: Copy + Default + Send + Sync>(
    slabs: &[Slab],
    maps: &[Vec<u32>],
    list: impl Fn(&Slab) -> &Vec<T> + Sync,
    f: impl Fn(&T, &[u32]) -> T + Sync,
) -> Vec<T> {
    let total = slabs.iter().map(|s| list(s).len()).sum();
    let mut out = vec![T::default(); total];
    let mut chunks = Vec::with_capacity(slabs.len());
    let mut rest = &mut out[..];
    for s in slabs {
        let (a, b) = rest.split_at_mut(list(s).len());
        chunks.push(a);
        rest = b;
    }
    chunks
        .into_par_iter()
        .zip(slabs.par_iter())
        .zip(maps.par_iter())
        .for_each(|((dst, s), m)| {
            for (d, t) in dst.iter_mut().zip(list(s)) {
                *d = f(t, m);
            }
        });
    out
}

fn process_slab(ctx: &Ctx, k: usize) -> Slab {
    let [cx, cy, _] = ctx.grid.cell_dims();
    let mut slab = Slab::new(ctx.grid.dims[0] * ctx.grid.dims[1], k);
    let mut tets: Vec<[u8; 4]> = Vec::with_capacity(64);
    // Skip cells entirely below alpha or above beta 64 at a time: bit i of a row word is set
    // when vertex i of that grid row is below (resp. above); a cell is outside when its eight
    // corners are, i.e. when the AND of its four rows has bits i and i + 1 set.
    let nx = ctx.grid.dims[0];
    let words = nx.div_ceil(64);
    let ny = ctx.grid.dims[1];
    // plane_bits[p][side][j * words + w]: plane z = k + p, side 0 below / 1 above
    let mut plane_bits = [
        [vec![0u64; ny * words], vec![0u64; ny * words]],
        [vec![0u64; ny * words], vec![0u64; ny * words]],
    ];
    for (p, bits) in plane_bits.iter_mut().enumerate() {
        let base = ctx.grid.index(0, 0, k + p);
        for (jj, row) in ctx.grid.values[base..base + nx * ny]
            .chunks_exact(nx)
            .enumerate()
        {
            for (i, &v) in row.iter().enumerate() {
                bits[0][jj * words + i / 64] |= ((v <= ctx.interval.alpha) as u64) << (i % 64);
                bits[1][jj * words + i / 64] |= ((v >= ctx.interval.beta) as u64) << (i % 64);
            }
        }
    }
    let mut outside = vec![0u64; words * cy];
    for j in 0..cy {
        let out = &mut outside[j * words..(j + 1) * words];
        for side in 0..2 {
            let row = |p: usize, jj: usize, w: usize| plane_bits[p][side][jj * words + w];
            let all = |w: usize| row(0, j, w) & row(0, j + 1, w) & row(1, j, w) & row(1, j + 1, w);
            for (w, o) in out.iter_mut().enumerate() {
                let here = all(w);
                let next = if w + 1 < words { all(w + 1) } else { 0 };
                *o |= here & ((here >> 1) | (next << 63));
            }
        }
    }
    // Reserve for the cells to be meshed (about 7 tets and 2 new points each) so the slab's
    // vectors do not grow by copying.
    let meshed = cx * cy
        - outside
            .iter()
            .map(|w| w.count_ones() as usize)
            .sum::<usize>();
    slab.tets.reserve(7 * meshed);
    slab.keys.reserve(2 * meshed);
    slab.pos.reserve(2 * meshed);
    slab.val.reserve(2 * meshed);
    slab.tris.reserve(meshed);
    slab.labels.reserve(meshed);
    for j in 0..cy {
        for i in 0..cx {
            if (outside[j * words + i / 64] >> (i % 64)) & 1 == 1 {
                continue;
            }
            process_cell(ctx, [i, j, k], &mut tets, &mut slab);
        }
    }
    slab.map = FxHashMap::default();
    slab.recent = Box::new([(PointKey::MAX, 0); RECENT]);
    slab.corner_ids = Vec::new();
    slab
}

fn process_cell(ctx: &Ctx, c: [usize; 3], tets: &mut Vec<[u8; 4]>, slab: &mut Slab) {
    let grid = ctx.grid;
    let [i, j, k] = c;
    let v = grid.cell_values(i, j, k);
    let cls = CellClasses::new(&v, ctx.interval.alpha, ctx.interval.beta);
    if cls.all_outside() {
        return;
    }
    let cd = grid.cell_dims();
    let mut pts = CellPoints::from_corners(&v);
    tets.clear();
    let case = match ctx.method {
        Method::Six => {
            if cls.all_inside() && !on_box(c, cd) {
                emit_six_inside(grid, c, &v, slab);
                slab.cases[CellCase::I as usize] += 1;
                return;
            }
            six::decompose_six(tets);
            CellCase::I
        }
        Method::Five => {
            five::decompose_five((i + j + k) % 2 == 1, tets);
            CellCase::I
        }
        method => {
            let crosses = cls.crosses_alpha() || cls.crosses_beta();
            let (bodies, nb): ([BodySaddle; 2], usize) = if crosses || method == Method::Tptd {
                body_saddles(&v)
            } else {
                (bs_none(), 0)
            };
            // A cell crossing a level with a body saddle is full (so non-full cells use none).
            let full = method == Method::Tptd || (crosses && is_full(method, cls, nb));
            let mut used = 0u8;
            let mut own = 0u8;
            let mut fv = [0.0; 6];
            for f in 0..6 {
                let axis = f / 2;
                let Some(s) = face_saddle(&v, f) else {
                    continue;
                };
                let mine = full || face_needed(cls, f);
                let need = mine || {
                    let mut n = c;
                    if f % 2 == 0 {
                        n[axis] = n[axis].wrapping_sub(1);
                    } else {
                        n[axis] += 1;
                    }
                    n[axis] < cd[axis] && ctx.cell_full(n)
                };
                if !need {
                    continue;
                }
                if mine {
                    own |= 1 << f;
                }
                used |= 1 << f;
                fv[f] = s.value;
                pts.pos[8 + f] = face_saddle_point(f, s.uv);
                pts.val[8 + f] = s.value;
            }
            if used == 0 && nb == 0 && cls.all_inside() && !on_box(c, cd) {
                // By far the most common cell: six whole tets over the eight corners.
                emit_six_inside(grid, c, &v, slab);
                slab.cases[CellCase::I as usize] += 1;
                return;
            }
            if !full && own == 0 && used & LOW_FACES != 0 && used & !LOW_FACES != 0 {
                // Saddles used only for full neighbours, on faces of both parities: no corner
                // apex fits, so one of them must be the apex. Safe are those on the side of
                // the level whose corners are edge-connected (the apex joins all of them).
                own = if crosses {
                    safe_apexes(ctx, cls, used, &fv)
                } else {
                    used
                };
            }
            tptd::decompose_tptd(used, own, &fv, &bodies[..nb], &mut pts, tets)
        }
    };
    slab.cases[case as usize] += 1;

    // Keys and clip vertices of the local ids.
    let base = grid.index(i, j, k);
    let stride = [1, grid.dims[0], grid.dims[0] * grid.dims[1]];
    let key_of = |id: usize| -> u64 {
        match id {
            0..=7 => {
                let o = corner_offset(id);
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
            _ => vertex_key(base, BODY + (id as u64 - BODY0 as u64)),
        }
    };
    let mut box_planes = 0u8;
    for axis in 0..3 {
        if c[axis] == 0 {
            box_planes |= 1 << (2 * axis);
        }
        if c[axis] + 1 == cd[axis] {
            box_planes |= 1 << (2 * axis + 1);
        }
    }
    let mut cv: [Option<ClipVertex>; NUM_LOCAL] = [None; NUM_LOCAL];
    let base_f = [i as f64, j as f64, k as f64];
    for t in tets.iter() {
        let tv = t.map(|id| {
            let id = id as usize;
            *cv[id].get_or_insert_with(|| {
                let p = pts.pos[id];
                ClipVertex {
                    key: key_of(id),
                    pos: [base_f[0] + p[0], base_f[1] + p[1], base_f[2] + p[2]],
                    val: pts.val[id],
                    box_mask: ctx.local_box[id],
                }
            })
        });
        clip_tet(&tv, &ctx.interval, box_planes, slab);
    }
}

/// Whether cell `c` touches the grid box (its faces may carry `box` triangles).
#[inline]
fn on_box(c: [usize; 3], cd: [usize; 3]) -> bool {
    (0..3).any(|a| c[a] == 0 || c[a] + 1 == cd[a])
}

/// Emits the 6-fold split of a cell whose corners are all inside, straight from the corner
/// ids (what clipping would produce, without clipping).
#[inline]
fn emit_six_inside(grid: &ScalarGrid, c: [usize; 3], v: &[f64; 8], slab: &mut Slab) {
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
        *id = slab.corner_id(base + o[0] + o[1] * sy + o[2] * sz, pos, v[corner]);
    }
    for t in six::SIX {
        slab.tets.push(t.map(|l| ids[l as usize]));
    }
}

/// The used faces whose saddle lies on a side of the (single) level crossing the cell whose
/// corners are edge-connected.
fn safe_apexes(ctx: &Ctx, cls: CellClasses, used: u8, fv: &[f64; 6]) -> u8 {
    let mut safe = 0u8;
    for f in 0..6 {
        if used & (1 << f) == 0 {
            continue;
        }
        let m = if cls.crosses_alpha() {
            if fv[f] <= ctx.interval.alpha {
                cls.below
            } else {
                !cls.below
            }
        } else if fv[f] >= ctx.interval.beta {
            cls.above
        } else {
            !cls.above
        };
        if corners_connected(m) {
            safe |= 1 << f;
        }
    }
    safe
}

fn bs_none() -> [BodySaddle; 2] {
    [BodySaddle {
        pos: [0.0; 3],
        value: 0.0,
    }; 2]
}
