//! Persistence by union–find over the superlevel and sublevel sets of the TPTD complex
//! ([`super::complex`]): vertices are added in order of value (ties broken by key, a
//! simulation of simplicity), each new vertex joins the components of its processed
//! neighbours, and when components merge the younger one dies (the elder rule). A point that
//! creates or destroys a component gets the span `|f(birth) − f(death)|`; the births that never
//! die (the first component of each filtration) get the value range. Superlevel components
//! track maxima and merging saddles; sublevel components track minima, merging saddles and,
//! because a bounded component of `{f < w}` is a cavity of `{f >= w}`, cavities too. Saddles
//! that only open or close tunnels keep `None`.
//!
//! The graph carries the connections of the complex's 1-skeleton, cheaply: grid edges
//! everywhere; each face saddle joined to its four face corners; and all edges of the TPTD
//! tets of the cells with a body saddle. Without a body saddle a cell holds no critical point
//! inside, so the parts of `{f >= w}` (and `{f <= w}`) in it are joined exactly as they are on
//! its faces: an unambiguous face joins its corners of one side along its edges, an ambiguous
//! one through its saddle.

use rayon::prelude::*;

use super::complex::cell_tets;
use super::CriticalPoint;
use crate::grid::face_corners;
use crate::grid::ScalarGrid;
use crate::keys::local_key;
use crate::keys::CORNER;
use crate::trilinear::{body_saddles, face_saddle};
use crate::union_find::UnionFind;

/// The extra vertices (saddles) and extra edges (over dense ids; grid vertex `i` is id `i`,
/// extra vertex `e` is `n + e`) of the cells with saddles.
struct Graph {
    extra_keys: Vec<u64>,
    extra_values: Vec<f64>,
    /// CSR adjacency of the extra edges over all ids.
    start: Vec<u32>,
    adj: Vec<u32>,
}

/// The graph of `grid`: its saddle tets and fans ([`saddle_tets`]), their non-corner vertices
/// as the extra vertices, and their edges as CSR adjacency.
fn build_graph(grid: &ScalarGrid) -> Graph {
    let tets = saddle_tets(grid);
    let extra = extra_vertices(&tets);
    let n = grid.num_vertices();
    let extra_keys: Vec<u64> = extra.iter().map(|x| x.0).collect();
    let id = |k: u64| -> u32 {
        if crate::keys::key_kind(k) == CORNER {
            crate::keys::key_index(k) as u32
        } else {
            (n + extra_keys.binary_search(&k).expect("saddle key")) as u32
        }
    };
    let (start, adj) = csr_edges(&tets, id, n + extra_keys.len());
    Graph {
        extra_values: extra.iter().map(|x| x.1).collect(),
        extra_keys,
        start,
        adj,
    }
}

/// Keys and values of the tets that carry the saddles' connections: per slab, the TPTD tets
/// of cells with a body saddle, and the fans of saddle faces (each face from the cell whose
/// low side it is, plus the box faces on the high side; see [`face_fans`]).
fn saddle_tets(grid: &ScalarGrid) -> Vec<([u64; 4], [f64; 4])> {
    let cd = grid.cell_dims();
    (0..cd[2])
        .into_par_iter()
        .flat_map_iter(|k| {
            let mut out = Vec::new();
            for j in 0..cd[1] {
                for i in 0..cd[0] {
                    let v = grid.cell_values(i, j, k);
                    if body_saddles(&v).1 > 0 {
                        cell_tets(grid, [i, j, k], &mut out);
                    } else {
                        face_fans(grid, [i, j, k], &v, &mut out);
                    }
                }
            }
            out
        })
        .collect()
}

/// Appends the fans of the saddle faces that cell `c` (corner values `v`) owns: each face
/// saddle joined to its four face corners, as two degenerate "tets" (saddle, corner, corner,
/// corner) whose edges include the fan.
fn face_fans(grid: &ScalarGrid, c: [usize; 3], v: &[f64; 8], out: &mut Vec<([u64; 4], [f64; 4])>) {
    let cd = grid.cell_dims();
    let stride = [1, grid.dims[0], grid.dims[0] * grid.dims[1]];
    let base = grid.index(c[0], c[1], c[2]);
    for f in 0..6 {
        let own = f % 2 == 0 || c[f / 2] + 1 == cd[f / 2];
        let Some(s) = face_saddle(v, f).filter(|_| own) else {
            continue;
        };
        let key = local_key(base, stride, 8 + f);
        let fc = face_corners(f);
        for t in 0..2 {
            let (a, b) = (fc[2 * t], fc[2 * t + 1]);
            let ka = local_key(base, stride, a);
            let kb = local_key(base, stride, b);
            out.push(([key, ka, kb, kb], [s.value, v[a], v[b], v[b]]));
        }
    }
}

/// The distinct non-corner vertices (saddles) of `tets` with their values, sorted by key.
fn extra_vertices(tets: &[([u64; 4], [f64; 4])]) -> Vec<(u64, f64)> {
    let mut extra: Vec<(u64, f64)> = tets
        .iter()
        .flat_map(|(k, v)| k.iter().copied().zip(v.iter().copied()))
        .filter(|(k, _)| crate::keys::key_kind(*k) != CORNER)
        .collect();
    extra.par_sort_unstable_by_key(|x| x.0);
    extra.dedup_by_key(|x| x.0);
    extra
}

/// The edges of `tets` over the dense ids `id` (`total` of them), both ways and without
/// repeats, as CSR `(start, adj)`.
fn csr_edges(
    tets: &[([u64; 4], [f64; 4])],
    id: impl Fn(u64) -> u32 + Sync,
    total: usize,
) -> (Vec<u32>, Vec<u32>) {
    let mut pairs: Vec<[u32; 2]> = tets
        .par_iter()
        .flat_map_iter(|(k, _)| {
            let t = k.map(&id);
            [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)]
                .into_iter()
                .flat_map(move |(a, b)| [[t[a], t[b]], [t[b], t[a]]])
        })
        .collect();
    pairs.par_sort_unstable();
    pairs.dedup();
    let mut start = vec![0u32; total + 1];
    for p in &pairs {
        start[p[0] as usize + 1] += 1;
    }
    for i in 0..total {
        start[i + 1] += start[i];
    }
    (start, pairs.iter().map(|p| p[1]).collect())
}

/// Order-preserving integer image of a finite f64.
#[inline]
fn ordered(x: f64) -> u64 {
    let b = x.to_bits();
    if b >> 63 == 1 {
        !b
    } else {
        b | (1 << 63)
    }
}

/// The persistence of every vertex id of the graph (0 where nothing is born or dies).
fn vertex_persistence(grid: &ScalarGrid, g: &Graph) -> Vec<f64> {
    let n = grid.num_vertices();
    let total = n + g.extra_keys.len();
    let value = |i: usize| {
        if i < n {
            grid.values.get(i)
        } else {
            g.extra_values[i - n]
        }
    };
    let mut order: Vec<(u64, u32)> = (0..total as u32)
        .into_par_iter()
        .map(|i| (ordered(value(i as usize)), i))
        .collect();
    order.par_sort_unstable();
    let mut rank = vec![0u32; total];
    for (r, &(_, i)) in order.iter().enumerate() {
        rank[i as usize] = r as u32;
    }
    let (lo, hi) = grid.value_range();
    let mut pers = vec![0.0f64; total];
    for superlevel in [true, false] {
        let one = sweep(grid, g, &order, &rank, superlevel, &value);
        for (p, x) in pers.iter_mut().zip(one) {
            *p = p.max(if x.is_infinite() { hi - lo } else { x });
        }
    }
    pers
}

/// One filtration: `superlevel` processes vertices from the highest rank down.
fn sweep(
    grid: &ScalarGrid,
    g: &Graph,
    order: &[(u64, u32)],
    rank: &[u32],
    superlevel: bool,
    value: &dyn Fn(usize) -> f64,
) -> Vec<f64> {
    let mut pers = vec![0.0f64; order.len()];
    let total = order.len();
    let mut sets = UnionFind::new(total);
    // birth vertex of each root; u32::MAX = not yet processed
    let mut birth = vec![u32::MAX; total];
    let before = |a: u32, b: u32| {
        // whether a is processed before b
        if superlevel {
            rank[a as usize] > rank[b as usize]
        } else {
            rank[a as usize] < rank[b as usize]
        }
    };
    let mut roots: Vec<u32> = Vec::with_capacity(16);
    let seq: Box<dyn Iterator<Item = &(u64, u32)>> = if superlevel {
        Box::new(order.iter().rev())
    } else {
        Box::new(order.iter())
    };
    for &(_, x) in seq {
        let xi = x as usize;
        neighbour_roots(grid, g, xi, &birth, &mut sets, &mut roots);
        if roots.is_empty() {
            birth[xi] = x;
            pers[xi] = f64::INFINITY;
            continue;
        }
        let elder = elder_root(&roots, &birth, before);
        let fx = value(xi);
        for &r in &roots {
            if r != elder {
                let b = birth[r as usize] as usize;
                let span = (value(b) - fx).abs();
                // a birth that dies: replace the provisional infinity
                pers[b] = if pers[b].is_infinite() {
                    span
                } else {
                    pers[b].max(span)
                };
                pers[xi] = pers[xi].max(span);
                sets.link(elder, r);
            }
        }
        sets.link(elder, x);
        birth[xi] = birth[elder as usize];
    }
    pers
}

/// Fills `roots` with the distinct roots of the processed neighbours of vertex id `xi` (those
/// with a `birth`): its grid neighbours along the axes if it is a grid vertex, and its extra
/// edges in `g`.
fn neighbour_roots(
    grid: &ScalarGrid,
    g: &Graph,
    xi: usize,
    birth: &[u32],
    sets: &mut UnionFind,
    roots: &mut Vec<u32>,
) {
    roots.clear();
    let stride = [1, grid.dims[0], grid.dims[0] * grid.dims[1]];
    let visit = |y: u32, sets: &mut UnionFind, roots: &mut Vec<u32>| {
        if birth[y as usize] != u32::MAX {
            let r = sets.find(y);
            if !roots.contains(&r) {
                roots.push(r);
            }
        }
    };
    if xi < grid.num_vertices() {
        let p = grid.vertex_ijk(xi);
        for a in 0..3 {
            if p[a] > 0 {
                visit((xi - stride[a]) as u32, sets, roots);
            }
            if p[a] + 1 < grid.dims[a] {
                visit((xi + stride[a]) as u32, sets, roots);
            }
        }
    }
    for &y in &g.adj[g.start[xi] as usize..g.start[xi + 1] as usize] {
        visit(y, sets, roots);
    }
}

/// The elder of the non-empty `roots`: the one born first (`before` on the birth vertices).
fn elder_root(roots: &[u32], birth: &[u32], before: impl Fn(u32, u32) -> bool) -> u32 {
    *roots
        .iter()
        .min_by(|&&a, &&b| {
            if before(birth[a as usize], birth[b as usize]) {
                std::cmp::Ordering::Less
            } else {
                std::cmp::Ordering::Greater
            }
        })
        .expect("non-empty")
}

/// Sets [`CriticalPoint::persistence`] of every point from its vertices' spans (a region: the
/// largest span among its vertices); `None` where it is zero.
pub fn assign_persistence(grid: &ScalarGrid, points: &mut [CriticalPoint]) {
    let g = build_graph(grid);
    let pers = vertex_persistence(grid, &g);
    let n = grid.num_vertices();
    let id = |k: u64| -> Option<usize> {
        if crate::keys::key_kind(k) == CORNER {
            Some(crate::keys::key_index(k))
        } else {
            g.extra_keys.binary_search(&k).ok().map(|e| n + e)
        }
    };
    points.par_iter_mut().for_each(|p| {
        let best = p
            .keys
            .iter()
            .filter_map(|&k| id(k))
            .map(|i| pers[i])
            .fold(0.0f64, f64::max);
        p.persistence = (best > 0.0).then_some(best);
    });
}
