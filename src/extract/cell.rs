//! One slab of cells: each cell planned, decomposed and clipped into the slab (the most
//! common cell, six whole tets, emitted straight from its corners).

use crate::clip::{clip_tet, ClipVertex, SNAP_ALPHA, SNAP_BETA, SNAP_NONE};
use crate::decompose::plan::{plan_cell, Layout, Planner};
use crate::decompose::{decompose_cell, six, CellCase, CellPoints, LOCAL_BOX, NUM_LOCAL};
use crate::grid::{cell_box_planes, corner_offset, ScalarGrid};
use crate::keys::{key_index, local_key};
use crate::levels::{Bounds, Levels};
use crate::weld::Slab;

use super::outside::outside_cells;

/// What every cell of one run shares.
pub(super) struct Ctx<'a> {
    pub(super) grid: &'a ScalarGrid,
    /// [`NEAR_TIE`](super::NEAR_TIE) × the data range: face and body points this near a
    /// level are put on it.
    pub(super) near_tie: f64,
    /// The levels, with their ties.
    pub(super) levels: Levels,
    pub(super) planner: Planner<'a>,
    /// Each region's two levels as the clipper sees them ([`Levels::region`]; one for one
    /// interval).
    pub(super) regions: Vec<Bounds>,
    /// Per grid vertex, the level it is snapped to (empty: no warping).
    pub(super) snaps: Vec<u8>,
}

impl Ctx<'_> {
    /// Snap state and clipping value of grid vertex `gi` with data value `val`.
    #[inline]
    fn corner(&self, gi: usize, val: f64) -> (u8, f64) {
        match self.snaps.get(gi).copied().unwrap_or(SNAP_NONE) {
            SNAP_ALPHA => (SNAP_ALPHA, self.levels.get(0)),
            SNAP_BETA => (SNAP_BETA, self.levels.get(1)),
            _ => (SNAP_NONE, val),
        }
    }

    /// Clipping value of a face or body point of the decomposition with value `val`: on the
    /// level when within [`Ctx::near_tie`] of it. The grid's values are
    /// ([`Levels::without_near_ties`]), but these points' values are computed from them: a
    /// face saddle at -3e-19 with alpha 0 put the cuts of its edges within rounding of it, and
    /// tets between them were inverted or flat. On the level they follow the ties rule like
    /// tied grid values.
    #[inline]
    fn point_value(&self, val: f64) -> f64 {
        self.levels.onto_near(val, self.near_tie)
    }
}

/// Meshes the cells of layer `k` into a new slab.
pub(super) fn process_slab(ctx: &Ctx, k: usize) -> Slab {
    let [cx, cy, _] = ctx.grid.cell_dims();
    let mut slab = Slab::new(ctx.grid.dims[0] * ctx.grid.dims[1], k);
    slab.set_levels(ctx.levels.len());
    let mut tets: Vec<[u8; 4]> = Vec::with_capacity(64);
    let words = ctx.grid.dims[0].div_ceil(64);
    let outside = outside_cells(ctx.grid, &ctx.levels, k);
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
        if slab.tags_regions() {
            slab.region = ctx.planner.pair_index(&v) as u8;
        }
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
        match ctx.regions.as_slice() {
            [one] => clip_tet(&tv, one, box_planes, slab),
            several => clip_regions(&tv, several, box_planes, slab),
        }
    }
}

/// Clips tet `tv` into each of `regions` that it reaches, tagging the pieces with the
/// region. A region whose lower level is above every corner, or whose upper level is below
/// every corner, would get nothing from [`clip_tet`]: it is skipped after two comparisons
/// (below and above are monotone in the value). Snapped corners count as inside whatever
/// their value, so a tet with one is clipped against every region.
#[inline]
fn clip_regions(tv: &[ClipVertex; 4], regions: &[Bounds], box_planes: u8, slab: &mut Slab) {
    let snapped = tv.iter().any(|v| v.snap != SNAP_NONE);
    let lo = tv.iter().map(|v| v.val).fold(f64::INFINITY, f64::min);
    let hi = tv.iter().map(|v| v.val).fold(f64::NEG_INFINITY, f64::max);
    for (k, lv) in regions.iter().enumerate() {
        if !snapped && (lv.below(0, hi) || lv.above(1, lo)) {
            continue;
        }
        slab.region = k as u8;
        clip_tet(tv, lv, box_planes, slab);
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
    if slab.tags_regions() {
        slab.regions.extend([slab.region; 6]);
    }
}
