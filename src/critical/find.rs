//! The whole detection: vertices, faces, cells and plateaus, in parallel over z slabs, then
//! persistence, then a deterministic order and the filters.

use rayon::prelude::*;

use super::body::classify_body_saddles;
use super::face::classify_face_saddle;
use super::vertex::{link_class, vertex_octants, LinkClass, VERTEX_TABLE};
use super::{CriticalError, CriticalKind, CriticalOptions, CriticalPoint};
use crate::grid::{face_corners, ScalarGrid};
use crate::keys::{vertex_key, BODY, CORNER, FACE};
use crate::trilinear::{face_point, face_saddle_of};

/// Every critical point and region of the field, sorted by value (see
/// [`find_critical_with_options`]).
///
/// # Errors
/// [`CriticalError::Constant`] for a constant volume.
pub fn find_critical(grid: &ScalarGrid) -> Result<Vec<CriticalPoint>, CriticalError> {
    find_critical_with_options(grid, &CriticalOptions::default())
}

/// The critical points and regions that pass the filters of `opts`, sorted by value, then
/// kind, then index position. Output is identical for any number of threads.
///
/// # Errors
/// [`CriticalError::Constant`] for a constant volume; [`CriticalError::EmptyRange`] when the
/// value range of `opts` holds no data value; [`CriticalError::BadFilter`] for a NaN or
/// inverted range or a negative or NaN persistence threshold.
pub fn find_critical_with_options(
    grid: &ScalarGrid,
    opts: &CriticalOptions,
) -> Result<Vec<CriticalPoint>, CriticalError> {
    let (min, max) = grid.value_range();
    check_filters(opts, min, max)?;
    if min == max {
        return Err(CriticalError::Constant(min));
    }
    let run = || {
        let mut all = all_critical(grid);
        if opts.persistence {
            super::persistence::assign_persistence(grid, &mut all);
        }
        all.retain(|p| opts.keeps(p));
        all
    };
    Ok(match opts.threads {
        Some(n) => match rayon::ThreadPoolBuilder::new()
            .num_threads(n.max(1))
            .build()
        {
            Ok(pool) => pool.install(run),
            Err(_) => run(),
        },
        None => run(),
    })
}

fn check_filters(opts: &CriticalOptions, min: f64, max: f64) -> Result<(), CriticalError> {
    let (lo, hi) = (opts.min_value, opts.max_value);
    if lo.is_nan() || hi.is_nan() || lo > hi {
        return Err(CriticalError::BadFilter(format!(
            "bad value range [{lo}, {hi}]"
        )));
    }
    if opts.min_persistence.is_nan() || opts.min_persistence < 0.0 {
        return Err(CriticalError::BadFilter(format!(
            "minimum persistence must be >= 0 (got {})",
            opts.min_persistence
        )));
    }
    if hi < min || lo > max {
        return Err(CriticalError::EmptyRange { lo, hi, min, max });
    }
    Ok(())
}

/// All critical points and regions, persistence unset, in the deterministic order.
pub fn all_critical(grid: &ScalarGrid) -> Vec<CriticalPoint> {
    critical_in_windows(grid, &[(f64::NEG_INFINITY, f64::INFINITY)])
}

/// Value windows `[lo, hi]`: only points with a value inside one are looked for.
pub(crate) type Windows<'a> = &'a [(f64, f64)];

/// Whether some window meets `[lo, hi]`.
#[inline]
pub(crate) fn meets(w: Windows, lo: f64, hi: f64) -> bool {
    w.iter().any(|&(a, b)| lo <= b && hi >= a)
}

/// The critical points and regions with a value in one of `windows` (persistence unset,
/// deterministic order). Vertices, faces and cells whose values cannot reach a window are
/// skipped, which makes checking a mesh bound much cheaper than [`all_critical`].
pub fn critical_in_windows(grid: &ScalarGrid, windows: Windows) -> Vec<CriticalPoint> {
    let nz = grid.dims[2];
    let mut all: Vec<CriticalPoint> = (0..nz)
        .into_par_iter()
        .flat_map_iter(|k| {
            let mut out = Vec::new();
            let rows = RowRanges::new(grid, k);
            vertices_in_slab(grid, k, windows, &rows, &mut out);
            faces_in_slab(grid, k, windows, &rows, &mut out);
            if k + 1 < nz {
                cells_in_slab(grid, k, windows, &rows, &mut out);
            }
            out
        })
        .collect();
    all.extend(super::region::critical_regions(grid, windows));
    all.retain(|p| meets(windows, p.value, p.value));
    sort_points(&mut all);
    all
}

/// Sorts by value, then kind, then index position (a total order on distinct points).
pub fn sort_points(points: &mut [CriticalPoint]) {
    points.par_sort_unstable_by(|a, b| {
        a.value
            .total_cmp(&b.value)
            .then(a.kind.cmp(&b.kind))
            .then(a.index[2].total_cmp(&b.index[2]))
            .then(a.index[1].total_cmp(&b.index[1]))
            .then(a.index[0].total_cmp(&b.index[0]))
    });
}

/// Strides of the six neighbour directions (`2 * axis + side`) and whether each exists.
#[inline]
fn neighbours(grid: &ScalarGrid, p: [usize; 3]) -> [Option<usize>; 6] {
    let idx = grid.index(p[0], p[1], p[2]);
    let stride = [1, grid.dims[0], grid.dims[0] * grid.dims[1]];
    std::array::from_fn(|d| {
        let (a, side) = (d / 2, d % 2);
        if side == 0 {
            (p[a] > 0).then(|| idx - stride[a])
        } else {
            (p[a] + 1 < grid.dims[a]).then(|| idx + stride[a])
        }
    })
}

/// The link class of grid vertex `p` from its neighbours, `None` when a neighbour has the same
/// value (the vertex belongs to a plateau, see [`super::region`]).
#[inline]
pub fn vertex_class(grid: &ScalarGrid, p: [usize; 3]) -> Option<LinkClass> {
    let centre = grid.index(p[0], p[1], p[2]);
    let nbrs = neighbours(grid, p);
    // the vertex and its neighbours (itself where there is none), one access
    let vals = grid
        .values
        .gather(std::array::from_fn::<usize, 7, _>(|d| match d {
            0 => centre,
            _ => nbrs[d - 1].unwrap_or(centre),
        }));
    let v = vals[0];
    let mut upper = 0u8;
    let mut interior = true;
    for (d, n) in nbrs.into_iter().enumerate() {
        match n {
            Some(_) => {
                let w = vals[d + 1];
                if w == v {
                    return None;
                }
                if w > v {
                    upper |= 1 << d;
                }
            }
            None => interior = false,
        }
    }
    Some(if interior {
        VERTEX_TABLE[upper as usize]
    } else {
        link_class(upper, vertex_octants(p, grid.dims))
    })
}

/// The value ranges of the grid rows (along x) of planes `k` and `k + 1`: a row of faces or
/// cells whose rows' values cannot reach a window is skipped without reading its corners.
pub(crate) struct RowRanges {
    /// `(min, max)` of row `j` of plane `k` at `[j]`, of plane `k + 1` at `[ny + j]`.
    ranges: Vec<(f64, f64)>,
    ny: usize,
    k: usize,
    planes: usize,
}

/// Grid positions along x per block of [`RowRanges::live_x`].
const X_BLOCK: usize = 32;

impl RowRanges {
    /// The row ranges of planes `k` and `k + 1` (the latter when it exists).
    pub(crate) fn new(grid: &ScalarGrid, k: usize) -> RowRanges {
        let [nx, ny, nz] = grid.dims;
        let planes = if k + 1 < nz { 2 } else { 1 };
        let ranges = (0..planes * ny)
            .map(|r| {
                let start = grid.index(0, r % ny, k + r / ny);
                grid.values.min_max_in(start..start + nx)
            })
            .collect();
        RowRanges {
            ranges,
            ny,
            k,
            planes,
        }
    }

    /// The range of row `j` of plane `k` alone.
    #[inline]
    pub(crate) fn row(&self, j: usize) -> (f64, f64) {
        self.ranges[j]
    }

    /// The range of rows `j`, `j + 1` of planes `k`, `k + 1` (those that exist): every face
    /// and cell whose smallest corner is in row `j` of plane `k` has its corners there.
    #[inline]
    pub(crate) fn quad(&self, j: usize) -> (f64, f64) {
        let mut r = (f64::INFINITY, f64::NEG_INFINITY);
        for dk in 0..self.planes {
            for jj in j..(j + 2).min(self.ny) {
                let x = self.ranges[dk * self.ny + jj];
                r = (r.0.min(x.0), r.1.max(x.1));
            }
        }
        r
    }

    /// The x positions `0..len` of row `j` of plane `k` whose faces or cells may have a value
    /// `hit` accepts (`hit(lo, hi)`: whether `[lo, hi]` meets the values looked for). Rows
    /// whose [`RowRanges::quad`] misses are skipped whole, then blocks of [`X_BLOCK`]
    /// positions whose corners (x from the block's start − 1 to its end + 1, rows `j`, `j + 1`,
    /// planes `k`, `k + 1`) miss.
    pub(crate) fn live_x<'a>(
        &'a self,
        grid: &'a ScalarGrid,
        j: usize,
        len: usize,
        hit: impl Fn(f64, f64) -> bool + 'a,
    ) -> impl Iterator<Item = usize> + 'a {
        let (lo, hi) = self.quad(j);
        let len = if hit(lo, hi) { len } else { 0 };
        let nx = grid.dims[0];
        (0..len)
            .step_by(X_BLOCK)
            .filter(move |&i0| {
                // one position before the block too: a clamped cell at the box starts there
                let (start, end) = (i0.saturating_sub(1), (i0 + X_BLOCK + 1).min(nx));
                let mut r = (f64::INFINITY, f64::NEG_INFINITY);
                for dk in 0..self.planes {
                    for jj in j..(j + 2).min(self.ny) {
                        let s = grid.index(0, jj, self.k + dk);
                        let x = grid.values.min_max_in(s + start..s + end);
                        r = (r.0.min(x.0), r.1.max(x.1));
                    }
                }
                hit(r.0, r.1)
            })
            .flat_map(move |i0| i0..(i0 + X_BLOCK).min(len))
    }
}

fn vertices_in_slab(
    grid: &ScalarGrid,
    k: usize,
    w: Windows,
    rows: &RowRanges,
    out: &mut Vec<CriticalPoint>,
) {
    for j in 0..grid.dims[1] {
        let (lo, hi) = rows.row(j);
        if !meets(w, lo, hi) {
            continue;
        }
        for i in 0..grid.dims[0] {
            let v = grid.value(i, j, k);
            if !meets(w, v, v) {
                continue;
            }
            let Some(class) = vertex_class(grid, [i, j, k]) else {
                continue;
            };
            if !class.critical() {
                continue;
            }
            let kind = if class.is_minimum() {
                CriticalKind::Minimum
            } else if class.is_maximum() {
                CriticalKind::Maximum
            } else {
                CriticalKind::Saddle
            };
            let index = [i as f64, j as f64, k as f64];
            let mut pt = CriticalPoint::new(grid, kind, grid.value(i, j, k), index, class, false);
            pt.keys = vec![vertex_key(grid.index(i, j, k), CORNER)];
            out.push(pt);
        }
    }
}

/// Face saddles of the faces whose smallest corner lies in slab `k`.
fn faces_in_slab(
    grid: &ScalarGrid,
    k: usize,
    w: Windows,
    rows: &RowRanges,
    out: &mut Vec<CriticalPoint>,
) {
    let dims = grid.dims;
    let stride = [1, dims[0], dims[0] * dims[1]];
    for j in 0..dims[1] {
        for i in rows.live_x(grid, j, dims[0], |lo, hi| meets(w, lo, hi)) {
            let p = [i, j, k];
            for axis in 0..3 {
                let fits = (0..3).all(|a| a == axis || p[a] + 1 < dims[a]);
                if !fits {
                    continue;
                }
                let base = grid.index(i, j, k);
                let fc = face_corners(2 * axis);
                let corner = |c: usize| {
                    let o = crate::grid::corner_offset(c);
                    base + o[0] * stride[0] + o[1] * stride[1] + o[2] * stride[2]
                };
                let q = grid.values.gather(fc.map(corner));
                let (lo, hi) = q
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                        (a.min(x), b.max(x))
                    });
                if !meets(w, lo, hi) {
                    continue;
                }
                let Some(s) = face_saddle_of(q) else {
                    continue;
                };
                let lower =
                    (p[axis] > 0).then(|| grid.values.gather(fc.map(|c| corner(c) - stride[axis])));
                let upper = (p[axis] + 1 < dims[axis])
                    .then(|| grid.values.gather(fc.map(|c| corner(c) + stride[axis])));
                let Some((class, degenerate)) = classify_face_saddle(q, s.value, [lower, upper])
                else {
                    continue;
                };
                let local = face_point(2 * axis, s.uv);
                let index = [
                    i as f64 + local[0],
                    j as f64 + local[1],
                    k as f64 + local[2],
                ];
                let mut pt = CriticalPoint::new(
                    grid,
                    CriticalKind::FaceSaddle,
                    s.value,
                    index,
                    class,
                    degenerate,
                );
                pt.keys = vec![vertex_key(base, FACE + axis as u64)];
                out.push(pt);
            }
        }
    }
}

fn cells_in_slab(
    grid: &ScalarGrid,
    k: usize,
    w: Windows,
    rows: &RowRanges,
    out: &mut Vec<CriticalPoint>,
) {
    let cd = grid.cell_dims();
    for j in 0..cd[1] {
        for i in rows.live_x(grid, j, cd[0], |lo, hi| meets(w, lo, hi)) {
            let v = grid.cell_values(i, j, k);
            let (lo, hi) = v
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                    (a.min(x), b.max(x))
                });
            if !meets(w, lo, hi) {
                continue;
            }
            let base = grid.index(i, j, k);
            for (n, (s, class)) in classify_body_saddles(&v).into_iter().enumerate() {
                let index = [
                    i as f64 + s.pos[0],
                    j as f64 + s.pos[1],
                    k as f64 + s.pos[2],
                ];
                let (class, degenerate) = match class {
                    Some(c) => (c, false),
                    None => (
                        LinkClass {
                            upper: [2, 0, 0],
                            lower: [2, 0, 0],
                        },
                        true,
                    ),
                };
                let mut pt = CriticalPoint::new(
                    grid,
                    CriticalKind::BodySaddle,
                    s.value,
                    index,
                    class,
                    degenerate,
                );
                pt.keys = vec![vertex_key(base, BODY + n as u64)];
                out.push(pt);
            }
        }
    }
}
