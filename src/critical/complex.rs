//! The second route: the TPTD tetrahedral complex of the whole grid (every cell split by the
//! topology-preserving decomposition with all its face and body saddles, [`crate::decompose`]).
//! Its piecewise-linear field has level sets with the topology of the trilinear interpolant,
//! so the Betti numbers of its superlevel and sublevel sets are those of the trilinear field.
//!
//! For a level `w` that is no vertex value, `{f >= w}` deformation-retracts onto the full
//! subcomplex on the vertices above `w`, so `b0` is a union–find over its edges, `χ` a count of
//! its simplices, `b2` the number of components of the complementary full subcomplex that do
//! not reach the grid box (bounded complementary components in the box), and
//! `b1 = b0 + b2 − χ`.
//!
//! Vertex keys are those of [`crate::keys`] (grid vertex, face saddle, body saddle).

use rayon::prelude::*;

use crate::decompose::plan::{plan_cell, Planner};
use crate::decompose::{decompose_cell, NUM_LOCAL};
use crate::grid::ScalarGrid;
use crate::keys::{local_key, CORNER, FACE};
use crate::union_find::UnionFind;
use crate::Method;

/// The TPTD complex over dense vertex ids.
#[derive(Clone, Debug)]
pub struct Complex {
    /// Vertex keys, ascending (grid vertices are `vertex_key(i, CORNER)`).
    pub keys: Vec<u64>,
    /// Field value of each vertex.
    pub values: Vec<f64>,
    /// Whether each vertex lies on the grid box.
    pub on_box: Vec<bool>,
    /// Unique edges (ascending vertex ids).
    pub edges: Vec<[u32; 2]>,
    /// Unique triangles.
    pub triangles: Vec<[u32; 3]>,
    /// Tetrahedra.
    pub tets: Vec<[u32; 4]>,
}

/// The tets of cell `c` over vertex keys, with the values of the keys; appended to `out`.
pub fn cell_tets(grid: &ScalarGrid, c: [usize; 3], out: &mut Vec<([u64; 4], [f64; 4])>) {
    let planner = Planner {
        grid,
        method: Method::Tptd,
        levels: crate::levels::Levels::interval(f64::NEG_INFINITY, f64::INFINITY),
        split_sags: false,
    };
    let v = grid.cell_values(c[0], c[1], c[2]);
    let plan = plan_cell(&planner, c, &v);
    let mut local = Vec::with_capacity(32);
    let (_, pts) = decompose_cell(&plan, &v, &mut local);
    let base = grid.index(c[0], c[1], c[2]);
    let stride = [1, grid.dims[0], grid.dims[0] * grid.dims[1]];
    let keys: [u64; NUM_LOCAL] = std::array::from_fn(|id| local_key(base, stride, id));
    for t in local {
        let k = t.map(|id| keys[id as usize]);
        let val = t.map(|id| pts.val[id as usize]);
        out.push((k, val));
    }
}

/// Whether the vertex with key `key` lies on the grid box.
pub fn key_on_box(grid: &ScalarGrid, key: u64) -> bool {
    let kind = crate::keys::key_kind(key);
    let p = grid.vertex_ijk(crate::keys::key_index(key));
    let at_box = |a: usize| p[a] == 0 || p[a] + 1 == grid.dims[a];
    match kind {
        CORNER => (0..3).any(at_box),
        k if (FACE..FACE + 3).contains(&k) => at_box((k - FACE) as usize),
        _ => false,
    }
}

/// Builds the complex of the whole grid (memory: tens of tets per cell; meant for volumes of
/// up to about a million cells).
pub fn build_complex(grid: &ScalarGrid) -> Complex {
    let cd = grid.cell_dims();
    let raw: Vec<([u64; 4], [f64; 4])> = (0..cd[2])
        .into_par_iter()
        .flat_map_iter(|k| {
            let mut out = Vec::new();
            for j in 0..cd[1] {
                for i in 0..cd[0] {
                    cell_tets(grid, [i, j, k], &mut out);
                }
            }
            out
        })
        .collect();
    let mut kv: Vec<(u64, f64)> = raw
        .iter()
        .flat_map(|(k, v)| k.iter().copied().zip(v.iter().copied()))
        .collect();
    kv.par_sort_unstable_by_key(|x| x.0);
    kv.dedup_by_key(|x| x.0);
    let keys: Vec<u64> = kv.iter().map(|x| x.0).collect();
    let values: Vec<f64> = kv.iter().map(|x| x.1).collect();
    let on_box = keys.iter().map(|&k| key_on_box(grid, k)).collect();
    let id = |k: u64| keys.binary_search(&k).expect("key of a tet vertex") as u32;
    let tets: Vec<[u32; 4]> = raw
        .iter()
        .map(|(k, _)| {
            let mut t = k.map(id);
            t.sort_unstable();
            t
        })
        .collect();
    let mut edges: Vec<[u32; 2]> = tets
        .iter()
        .flat_map(|t| [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)].map(|(a, b)| [t[a], t[b]]))
        .collect();
    edges.par_sort_unstable();
    edges.dedup();
    let mut triangles: Vec<[u32; 3]> = tets
        .iter()
        .flat_map(|t| [[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]].map(|f| f.map(|i| t[i])))
        .collect();
    triangles.par_sort_unstable();
    triangles.dedup();
    Complex {
        keys,
        values,
        on_box,
        edges,
        triangles,
        tets,
    }
}

impl Complex {
    /// Betti numbers `[b0, b1, b2]` of `{f >= w}` (`superlevel`) or `{f <= w}`, for a level `w`
    /// that is no vertex value.
    pub fn betti(&self, w: f64, superlevel: bool) -> [usize; 3] {
        self.spectrum(&[w], superlevel)[0]
    }

    /// Betti numbers of `{f >= w}` (`superlevel`) or `{f <= w}` at each of `levels` (none a
    /// vertex value), in one sweep per filtration.
    pub fn spectrum(&self, levels: &[f64], superlevel: bool) -> Vec<[usize; 3]> {
        // {f <= w} of f is {-f >= -w}: flip the values and reuse the superlevel sweep
        let sgn = if superlevel { 1.0 } else { -1.0 };
        let vals: Vec<f64> = self.values.iter().map(|&x| sgn * x).collect();
        let ws: Vec<f64> = levels.iter().map(|&w| sgn * w).collect();
        let adj = self.adjacency();
        let b0 = self.count_components(&vals, &ws, &adj, true);
        let b2 = self.count_components(&vals, &ws, &adj, false);
        let chi = self.euler(&vals, &ws);
        (0..ws.len())
            .map(|i| {
                let b1 = b0[i] as i64 + b2[i] as i64 - chi[i];
                [b0[i], b1.max(0) as usize, b2[i]]
            })
            .collect()
    }

    fn adjacency(&self) -> Vec<Vec<u32>> {
        let mut adj = vec![Vec::new(); self.values.len()];
        for e in &self.edges {
            adj[e[0] as usize].push(e[1]);
            adj[e[1] as usize].push(e[0]);
        }
        adj
    }

    /// `above`: components of the vertices above each level; otherwise the components of the
    /// vertices below that do not reach the grid box.
    fn count_components(
        &self,
        vals: &[f64],
        ws: &[f64],
        adj: &[Vec<u32>],
        above: bool,
    ) -> Vec<usize> {
        let n = vals.len();
        let mut order: Vec<u32> = (0..n as u32).collect();
        order.sort_by(|&a, &b| vals[a as usize].total_cmp(&vals[b as usize]));
        if above {
            order.reverse();
        }
        let mut qs: Vec<usize> = (0..ws.len()).collect();
        qs.sort_by(|&a, &b| ws[a].total_cmp(&ws[b]));
        if above {
            qs.reverse();
        }
        let mut sets = UnionFind::new(n);
        let mut added = vec![false; n];
        let mut touch = self.on_box.clone();
        let mut count = 0i64;
        let mut out = vec![0usize; ws.len()];
        let mut next = 0;
        let inside = |x: f64, w: f64| if above { x > w } else { x < w };
        for q in qs {
            while next < n && inside(vals[order[next] as usize], ws[q]) {
                let x = order[next];
                next += 1;
                added[x as usize] = true;
                count += (above || !touch[x as usize]) as i64;
                for &y in &adj[x as usize] {
                    if !added[y as usize] {
                        continue;
                    }
                    let (rx, ry) = (sets.find(x), sets.find(y));
                    if rx == ry {
                        continue;
                    }
                    let (tx, ty) = (touch[rx as usize], touch[ry as usize]);
                    // the merged component counts once, and not at all once it reaches the box
                    count -= if above {
                        1
                    } else {
                        (!tx) as i64 + (!ty) as i64 - (!(tx || ty)) as i64
                    };
                    let (lo, hi) = (rx.min(ry), rx.max(ry));
                    sets.link(lo, hi);
                    touch[lo as usize] = tx || ty;
                }
            }
            out[q] = count as usize;
        }
        out
    }

    /// Euler characteristic of the full subcomplex above each level.
    fn euler(&self, vals: &[f64], ws: &[f64]) -> Vec<i64> {
        let mut mins: Vec<(f64, i64)> = Vec::new();
        let min_of = |s: &[u32]| {
            s.iter()
                .map(|&i| vals[i as usize])
                .fold(f64::INFINITY, f64::min)
        };
        mins.extend(vals.iter().map(|&x| (x, 1)));
        mins.extend(self.edges.iter().map(|e| (min_of(e), -1)));
        mins.extend(self.triangles.iter().map(|t| (min_of(t), 1)));
        mins.extend(self.tets.iter().map(|t| (min_of(t), -1)));
        mins.sort_by(|a, b| a.0.total_cmp(&b.0));
        // suffix sums: chi(w) = sum of signs with min > w
        let mut suffix = vec![0i64; mins.len() + 1];
        for i in (0..mins.len()).rev() {
            suffix[i] = suffix[i + 1] + mins[i].1;
        }
        ws.iter()
            .map(|&w| suffix[mins.partition_point(|m| m.0 <= w)])
            .collect()
    }

    /// The sorted distinct vertex values.
    pub fn levels(&self) -> Vec<f64> {
        let mut v = self.values.clone();
        v.sort_by(f64::total_cmp);
        v.dedup();
        v
    }

    /// The values across which the Betti numbers of `{f >= w}` (`superlevel`) or `{f <= w}`
    /// change: each vertex value `c` where the Betti numbers just below and just above differ.
    pub fn critical_values(&self, superlevel: bool) -> Vec<f64> {
        let lv = self.levels();
        let mids: Vec<f64> = std::iter::once(lv[0] - 1.0)
            .chain(lv.windows(2).map(|w| 0.5 * (w[0] + w[1])))
            .chain(std::iter::once(lv[lv.len() - 1] + 1.0))
            .collect();
        let betti = self.spectrum(&mids, superlevel);
        (0..lv.len())
            .filter(|&i| betti[i] != betti[i + 1])
            .map(|i| lv[i])
            .collect()
    }
}
