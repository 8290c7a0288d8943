//! Critical regions on plateaus (“Detecting critical regions in scalar fields”): vertices with an
//! edge-connected neighbour of the same value cannot be classified locally. A flood fill collects
//! each plateau `R` (maximal edge-connected set of equal values); every grid edge leaving `R`
//! becomes a node, positive or negative by the sign of `f - f(R)` at its far end; nodes are joined
//! when their edges lie in one connected part of `{f > f(R)}` (or `{f < f(R)}`) near `R` inside
//! some cell ([`join_in_cell`]). With `n_p`, `n_n` components: `n_n = 0` is a region minimum,
//! `n_p = 0` a region maximum, `n_p + n_n > 2` a region saddle (Definition 5 of “Detecting critical
//! regions in scalar fields”).
//!
//! Inside one cell, near a cube-edge-connected piece `S` of `R` (“Detecting critical regions in
//! scalar fields” §5.2, the base cases grouped by what `S` is):
//! * `S` one corner (C1): the cell is split like a linear tetrahedron, all exits of one sign
//!   are joined.
//! * `S` one cube edge (C2): on the slice at parameter `t` along the edge the two neighbours
//!   across the cell (along the two other axes) have values linear in `t`; the parts of one
//!   sign on the two sides are joined when the `t`-ranges where both have that sign overlap
//!   (C2.0–C2.4.1); when both cross `f(R)` at the same `t`, the far corner of that slice
//!   decides (C2.4.0–C2.4.2).
//! * larger `S`: exits of one sign on a common cell face are joined when they are adjacent
//!   near `S` on that face (they share their far corner, or leave one corner or one edge of `S`);
//!   exits leaving a whole face of `S` towards the opposite face `G` follow the contours of `G`
//!   (C8: the asymptotic decider of `G` joins a diagonal pair).

use rustc_hash::FxHashMap;

use rayon::prelude::*;

use super::plateau::{plateaus_in, Plateaus};
use super::vertex::LinkClass;
use super::{CriticalKind, CriticalPoint, RegionInfo};
use crate::grid::{corner_offset, face_corners, ScalarGrid};
use crate::trilinear::face_saddle_of;
use crate::union_find::UnionFind;

/// The critical plateaus of the grid with a value in one of `windows`, classified.
pub fn critical_regions(grid: &ScalarGrid, windows: &[(f64, f64)]) -> Vec<CriticalPoint> {
    let p = plateaus_in(grid, windows);
    p.regions
        .par_iter()
        .enumerate()
        .filter_map(|(id, r)| classify_region(grid, &p, id as u32, r))
        .collect()
}

/// Classifies plateau number `id` of `labels` (vertex indices `region`, ascending); `None`
/// when it is regular.
pub fn classify_region(
    grid: &ScalarGrid,
    labels: &Plateaus,
    id: u32,
    region: &[usize],
) -> Option<CriticalPoint> {
    let v = grid.values.get(region[0]);
    let in_region = |idx: usize| labels.label(idx) == id;
    // a plateau whose exits all go up (down) is a minimum (maximum): no graph needed, a
    // contractible one has one connected part around it
    let (up, down) = exit_sides(grid, &in_region, region, v);
    if !(up && down) {
        let parts = Parts {
            np: up as usize,
            nn: down as usize,
            np_free: 0,
            nn_free: 0,
        };
        return region_point(grid, labels, id, region, v, parts);
    }
    let cells = region_cells(grid, &in_region, region);
    let graph = link_graph(grid, &in_region, &cells, v);
    region_point(grid, labels, id, region, v, graph.parts(grid))
}

/// Whether the plateau `region` (value `v`) has neighbours above (`.0`) and below (`.1`).
fn exit_sides(
    grid: &ScalarGrid,
    in_region: &dyn Fn(usize) -> bool,
    region: &[usize],
    v: f64,
) -> (bool, bool) {
    let stride = [1, grid.dims[0], grid.dims[0] * grid.dims[1]];
    let (mut up, mut down) = (false, false);
    for &r in region {
        let p = grid.vertex_ijk(r);
        for a in 0..3 {
            for (ok, m) in [
                (p[a] > 0, r.wrapping_sub(stride[a])),
                (p[a] + 1 < grid.dims[a], r + stride[a]),
            ] {
                if ok && !in_region(m) {
                    let w = grid.values.get(m);
                    up |= w > v;
                    down |= w < v;
                }
            }
        }
    }
    (up, down)
}

/// The grid indices of the eight corners of cell `c`.
fn cell_corners(grid: &ScalarGrid, c: [usize; 3]) -> [usize; 8] {
    let stride = [1, grid.dims[0], grid.dims[0] * grid.dims[1]];
    let base = grid.index(c[0], c[1], c[2]);
    std::array::from_fn(|k| {
        let o = corner_offset(k);
        base + o[0] * stride[0] + o[1] * stride[1] + o[2] * stride[2]
    })
}

/// Every cell holding a vertex of the region, once (visited from its smallest such vertex).
fn region_cells(
    grid: &ScalarGrid,
    in_region: &dyn Fn(usize) -> bool,
    region: &[usize],
) -> Vec<[usize; 3]> {
    let cd = grid.cell_dims();
    let mut cells: Vec<[usize; 3]> = Vec::new();
    for &r in region {
        let p = grid.vertex_ijk(r);
        for o in 0..8usize {
            let c: [usize; 3] = std::array::from_fn(|a| {
                if (o >> a) & 1 == 1 {
                    p[a]
                } else {
                    p[a].wrapping_sub(1)
                }
            });
            if (0..3).any(|a| c[a] >= cd[a]) {
                continue;
            }
            let first = cell_corners(grid, c).into_iter().find(|&g| in_region(g));
            if first == Some(r) {
                cells.push(c);
            }
        }
    }
    cells
}

/// The graph of the sides of a plateau: a node per grid edge leaving it (keyed by its ends,
/// with the side it leaves to), linked where a cell joins two of them.
struct LinkGraph {
    nodes: FxHashMap<(usize, usize), usize>,
    /// Per node: does it lead up?
    sign: Vec<bool>,
    links: Vec<(usize, usize)>,
}

/// The [`LinkGraph`] of the plateau (value `v`) over its `cells`.
fn link_graph(
    grid: &ScalarGrid,
    in_region: &dyn Fn(usize) -> bool,
    cells: &[[usize; 3]],
    v: f64,
) -> LinkGraph {
    let mut g = LinkGraph {
        nodes: FxHashMap::default(),
        sign: Vec::new(),
        links: Vec::new(),
    };
    for &c in cells {
        let gidx = cell_corners(grid, c);
        let vals = grid.values.gather(gidx);
        let mut rmask = 0u8;
        for k in 0..8 {
            if vals[k] == v && in_region(gidx[k]) {
                rmask |= 1 << k;
            }
        }
        let mut local = Vec::new();
        join_in_cell(&vals, v, rmask, &mut local);
        for (e1, e2) in local {
            let n1 = g.node(gidx[e1.0], gidx[e1.1], vals[e1.1] > v);
            let n2 = g.node(gidx[e2.0], gidx[e2.1], vals[e2.1] > v);
            g.links.push((n1, n2));
        }
    }
    g
}

impl LinkGraph {
    /// The node of grid edge `{a, b}` (new ones lead up when `up`).
    fn node(&mut self, a: usize, b: usize, up: bool) -> usize {
        let key = (a.min(b), a.max(b));
        let n = self.nodes.len();
        let sign = &mut self.sign;
        *self.nodes.entry(key).or_insert_with(|| {
            sign.push(up);
            n
        })
    }

    /// The connected parts above and below, and which of them do not reach the grid box.
    fn parts(&self, grid: &ScalarGrid) -> Parts {
        let n = self.sign.len();
        let mut uf = UnionFind::new(n);
        for &(a, b) in &self.links {
            uf.union(a as u32, b as u32);
        }
        // which nodes lie on the grid box (both ends on one box plane)
        let mut on_box_node = vec![false; n];
        for (&(a, b), &i) in &self.nodes {
            let (pa, pb) = (grid.vertex_ijk(a), grid.vertex_ijk(b));
            on_box_node[i] =
                (0..3).any(|x| pa[x] == pb[x] && (pa[x] == 0 || pa[x] + 1 == grid.dims[x]));
        }
        let mut touch = vec![false; n];
        for i in 0..n {
            let r = uf.find(i as u32) as usize;
            touch[r] |= on_box_node[i];
        }
        let mut parts = Parts::default();
        for i in 0..n {
            if uf.find(i as u32) as usize == i {
                let (count, free) = if self.sign[i] {
                    (&mut parts.np, &mut parts.np_free)
                } else {
                    (&mut parts.nn, &mut parts.nn_free)
                };
                *count += 1;
                *free += !touch[i] as usize;
            }
        }
        parts
    }
}

/// Connected parts of `{f > f(R)}` (`np`) and `{f < f(R)}` (`nn`) near a plateau `R`, and how
/// many of each do not reach the grid box.
#[derive(Default)]
struct Parts {
    np: usize,
    nn: usize,
    np_free: usize,
    nn_free: usize,
}

/// The critical point of a plateau, `None` when it is regular.
///
/// Inside the box the neighbourhood of a (contractible) plateau is a ball around it, so it is
/// regular iff `np = nn = 1` (“Detecting critical regions in scalar fields”). On the box it is a
/// half-ball whose link is a disk: the upper part is contractible iff it is connected and no lower
/// part is enclosed in it (every lower part reaches the box), and likewise for the lower part; a
/// box plateau may thus change one filtration only (a lower pocket below a box plateau opens a hole
/// in `{f >= w}`).
fn region_point(
    grid: &ScalarGrid,
    labels: &Plateaus,
    id: u32,
    region: &[usize],
    v: f64,
    parts: Parts,
) -> Option<CriticalPoint> {
    let mut sum = [0.0; 3];
    let mut lo = [usize::MAX; 3];
    let mut hi = [0usize; 3];
    let mut on_box = false;
    for &r in region {
        let p = grid.vertex_ijk(r);
        for a in 0..3 {
            sum[a] += p[a] as f64;
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
            on_box |= p[a] == 0 || p[a] + 1 == grid.dims[a];
        }
    }
    let Parts {
        np,
        nn,
        np_free,
        nn_free,
    } = parts;
    let (superlevel, sublevel) = if !is_simple(grid, labels, id, region, on_box) {
        // not a ball (or a half-ball on the box): component counts cannot say which
        // filtration changes, so both are flagged (a bound there is reported as unsafe)
        (true, true)
    } else if on_box {
        (np != 1 || nn_free > 0, nn != 1 || np_free > 0)
    } else {
        let c = !(np == 1 && nn == 1);
        (c, c)
    };
    if !(superlevel || sublevel) {
        return None;
    }
    let kind = if nn == 0 {
        CriticalKind::RegionMinimum
    } else if np == 0 {
        CriticalKind::RegionMaximum
    } else {
        CriticalKind::RegionSaddle
    };
    let centroid = grid.to_physical(sum.map(|s| s / region.len() as f64));
    let class = LinkClass {
        upper: [np.min(255) as u8, 0, 0],
        lower: [nn.min(255) as u8, 0, 0],
    };
    let at = nearest_vertex(grid, region, centroid).map(|x| x as f64);
    let mut pt = CriticalPoint::new(grid, kind, v, at, class, false);
    pt.on_box = on_box;
    pt.superlevel = superlevel;
    pt.sublevel = sublevel;
    let corner = |p: [usize; 3]| grid.to_physical(p.map(|x| x as f64));
    let (a, b) = (corner(lo), corner(hi));
    pt.region = Some(RegionInfo {
        vertices: region.len(),
        centroid,
        bbox_min: std::array::from_fn(|k| a[k].min(b[k])),
        bbox_max: std::array::from_fn(|k| a[k].max(b[k])),
    });
    pt.keys = region
        .iter()
        .map(|&r| crate::keys::vertex_key(r, crate::keys::CORNER))
        .collect();
    Some(pt)
}

/// The vertex of `region` nearest (physically) to `point`, the first in `region` of equally
/// near ones: a point of the region where its centroid may lie outside it (in a ring's hole).
fn nearest_vertex(grid: &ScalarGrid, region: &[usize], point: [f64; 3]) -> [usize; 3] {
    let dist2 = |r: usize| {
        let p = grid.to_physical(grid.vertex_ijk(r).map(|x| x as f64));
        (0..3).map(|a| (p[a] - point[a]).powi(2)).sum::<f64>()
    };
    let mut best = (f64::INFINITY, region[0]);
    for &r in region {
        let d = dist2(r);
        if d < best.0 {
            best = (d, r);
        }
    }
    grid.vertex_ijk(best.1)
}

/// Whether the plateau is cube-complex contractible as far as Euler characteristics tell
/// (`χ(R) = 1`) and, when it touches the box, meets the box in one piece with `χ = 1`: then its
/// neighbourhood is a ball (half-ball) and its link a sphere (disk).
fn is_simple(
    grid: &ScalarGrid,
    labels: &Plateaus,
    id: u32,
    region: &[usize],
    on_box: bool,
) -> bool {
    let stride = [1, grid.dims[0], grid.dims[0] * grid.dims[1]];
    let (mut chi, mut chi_box, mut vb) = (0i64, 0i64, 0usize);
    for &r in region {
        let p = grid.vertex_ijk(r);
        // bit c: the vertex at forward offset c (bit a = +1 along axis a) is in the region
        let mut present = 1u8;
        for c in 1..8usize {
            let fits = (0..3).all(|a| (c >> a) & 1 == 0 || p[a] + 1 < grid.dims[a]);
            let off: usize = (0..3).map(|a| ((c >> a) & 1) * stride[a]).sum();
            if fits && labels.label(r + off) == id {
                present |= 1 << c;
            }
        }
        let at_box = |a: usize| p[a] == 0 || p[a] + 1 == grid.dims[a];
        // the cube cell spanned by the axes in `mask` from p is in R when all its corners are
        for mask in 0usize..8 {
            let all = (0usize..8)
                .filter(|c| c & !mask == 0)
                .all(|c| present & (1 << c) != 0);
            if !all {
                continue;
            }
            let sign = if mask.count_ones() % 2 == 0 { 1 } else { -1 };
            chi += sign;
            // a cell in a box plane: some axis it does not span with p on the box there
            if (0..3).any(|a| mask & (1 << a) == 0 && at_box(a)) {
                chi_box += sign;
                vb += (mask == 0) as usize;
            }
        }
    }
    chi == 1 && (!on_box || (chi_box == 1 && vb > 0))
}

/// An exit of the region in a cell: (region corner, far corner), cell-local corner ids.
type Exit = (usize, usize);

/// The pairs of exits of one cell that lie in one part of `{f > v}` or `{f < v}` near the
/// region (see the module docs). `vals`: corner values; `rmask`: region corners. Every exit
/// appears at least once (paired with itself when alone).
pub fn join_in_cell(vals: &[f64; 8], v: f64, rmask: u8, out: &mut Vec<(Exit, Exit)>) {
    let pieces = pieces(rmask);
    for s in pieces {
        let exits: Vec<Exit> = (0..8)
            .filter(|&r| s & (1 << r) != 0)
            .flat_map(|r| (0..3).map(move |a| (r, r ^ (1 << a))))
            .filter(|&(_, a)| rmask & (1 << a) == 0)
            .collect();
        for &e in &exits {
            out.push((e, e));
        }
        let up = |e: Exit| vals[e.1] > v;
        let mut join = |x: Exit, y: Exit| {
            if up(x) == up(y) {
                out.push((x, y));
            }
        };
        match s.count_ones() {
            1 => {
                for i in 0..exits.len() {
                    for j in i + 1..exits.len() {
                        join(exits[i], exits[j]);
                    }
                }
            }
            2 => join_along_edge(vals, v, s, &exits, &mut join),
            _ => join_larger(vals, v, s, &exits, &mut join),
        }
    }
}

/// The cube-edge-connected pieces of a set of corners.
fn pieces(mask: u8) -> Vec<u8> {
    let mut left = mask;
    let mut out = Vec::new();
    while left != 0 {
        let first = left.trailing_zeros() as usize;
        let mut piece = 1u8 << first;
        loop {
            let mut grown = piece;
            for c in 0..8 {
                if piece & (1 << c) != 0 {
                    for a in 0..3 {
                        let n = c ^ (1 << a);
                        if left & (1 << n) != 0 {
                            grown |= 1 << n;
                        }
                    }
                }
            }
            if grown == piece {
                break;
            }
            piece = grown;
        }
        left &= !piece;
        out.push(piece);
    }
    out
}

/// `S` is one cube edge `r0 – r1` (C2).
fn join_along_edge(
    vals: &[f64; 8],
    v: f64,
    s: u8,
    exits: &[Exit],
    join: &mut impl FnMut(Exit, Exit),
) {
    let r0 = s.trailing_zeros() as usize;
    let r1 = 7 - s.leading_zeros() as usize;
    let axis = (r0 ^ r1).trailing_zeros() as usize;
    let others: Vec<usize> = (0..3).filter(|&a| a != axis).collect();
    // the exits along the same side axis are joined when of one sign (a face of the cell)
    for &a in &others {
        join((r0, r0 ^ (1 << a)), (r1, r1 ^ (1 << a)));
    }
    // across the two side axes: t-ranges of each sign
    let (a, b) = (others[0], others[1]);
    let ya = (vals[r0 ^ (1 << a)] - v, vals[r1 ^ (1 << a)] - v);
    let zb = (vals[r0 ^ (1 << b)] - v, vals[r1 ^ (1 << b)] - v);
    for positive in [true, false] {
        let sgn = if positive { 1.0 } else { -1.0 };
        let ra = sign_range(sgn * ya.0, sgn * ya.1);
        let rb = sign_range(sgn * zb.0, sgn * zb.1);
        let (Some(ra), Some(rb)) = (ra, rb) else {
            continue;
        };
        let overlap = ra.0.max(rb.0) < ra.1.min(rb.1)
            || (ra.0.max(rb.0) == ra.1.min(rb.1) && ra.1 > ra.0 && rb.1 > rb.0 && {
                // touching at one t where both cross: the far corner of that slice decides
                let t = ra.0.max(rb.0);
                let far0 = vals[r0 ^ (1 << a) ^ (1 << b)];
                let far1 = vals[r1 ^ (1 << a) ^ (1 << b)];
                sgn * (far0 + t * (far1 - far0) - v) > 0.0
            });
        if overlap {
            let ea = if sgn * ya.0 > 0.0 {
                (r0, r0 ^ (1 << a))
            } else {
                (r1, r1 ^ (1 << a))
            };
            let eb = if sgn * zb.0 > 0.0 {
                (r0, r0 ^ (1 << b))
            } else {
                (r1, r1 ^ (1 << b))
            };
            join(ea, eb);
        }
    }
    let _ = exits;
}

/// The closed `t`-range in `[0, 1]` where `y0 + t (y1 - y0) > 0` (its closure), if any.
fn sign_range(y0: f64, y1: f64) -> Option<(f64, f64)> {
    match (y0 > 0.0, y1 > 0.0) {
        (true, true) => Some((0.0, 1.0)),
        (false, false) => None,
        (true, false) => Some((0.0, y0 / (y0 - y1))),
        (false, true) => Some((y0 / (y0 - y1), 1.0)),
    }
}

/// `S` has three or more corners.
fn join_larger(vals: &[f64; 8], v: f64, s: u8, exits: &[Exit], join: &mut impl FnMut(Exit, Exit)) {
    for i in 0..exits.len() {
        for j in i + 1..exits.len() {
            let (x, y) = (exits[i], exits[j]);
            // same far corner, or the same region corner, or parallel exits from an edge of S
            let parallel = (x.0 ^ x.1) == (y.0 ^ y.1) && (x.0 ^ y.0).count_ones() == 1;
            let same_corner = x.0 == y.0;
            if x.1 == y.1 || parallel || same_corner {
                join(x, y);
            }
        }
    }
    // a whole face of S: the opposite face's contours decide its diagonal pairs
    for f in 0..6 {
        let fc = face_corners(f);
        if !fc.iter().all(|&c| s & (1 << c) != 0) {
            continue;
        }
        let g = f ^ 1;
        let gc = face_corners(g);
        if gc.iter().any(|&c| s & (1 << c) != 0) {
            continue;
        }
        let q = gc.map(|c| vals[c]);
        let Some(sd) = face_saddle_of(q) else {
            continue;
        };
        let positive = sd.value > v;
        if sd.value == v {
            continue;
        }
        for (i, j) in [(0, 2), (1, 3)] {
            let (ci, cj) = (gc[i], gc[j]);
            if (vals[ci] > v) == positive && (vals[cj] > v) == positive {
                let axis = f / 2;
                join((ci ^ (1 << axis), ci), (cj ^ (1 << axis), cj));
            }
        }
    }
}
