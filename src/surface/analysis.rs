//! What a triangle surface is: counts, area, Betti numbers, closed 2-manifold, oriented.
//!
//! Betti numbers of a 2-complex: b0 = connected components, b2 = closed components that are
//! orientable (every edge in two triangles, a consistent orientation exists), and
//! b1 = b0 + b2 − χ with χ = V − E + F. Exact for surfaces (2-manifolds with or without
//! boundary), which is what the isosurfaces are.

use rayon::prelude::*;
use serde::Serialize;

use crate::geom::{cross, sub};
use crate::mesh::TriSurface;
use crate::union_find::{ParityUnionFind, UnionFind};

/// The analysis of a triangle surface (the `surface` section of the JSON report).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SurfaceAnalysis {
    /// Number of vertices.
    pub vertices: usize,
    /// Number of triangles.
    pub triangles: usize,
    /// Total area (physical units).
    pub area: f64,
    /// Betti numbers `[b0, b1, b2]` of the surface.
    pub betti: [usize; 3],
    /// Every edge in exactly two triangles and every vertex link one cycle.
    pub closed_manifold: bool,
    /// Every edge shared by two triangles is traversed in opposite directions by them.
    pub oriented: bool,
    /// Edges in one triangle only (the surface's border, e.g. where it meets the grid box).
    pub border_edges: usize,
    /// Edges in more than two triangles.
    pub nonmanifold_edges: usize,
    /// Vertices whose link is not connected (pinch points).
    pub pinched_vertices: usize,
}

/// One directed triangle edge: `(undirected key, triangle, forward)`.
type Edge = (u64, u32, bool);

/// The triangle edges sorted by undirected key, then triangle (a total order: deterministic).
fn sorted_edges(s: &TriSurface) -> Vec<Edge> {
    let mut e: Vec<Edge> = s
        .triangles
        .par_iter()
        .enumerate()
        .flat_map_iter(|(t, tri)| {
            (0..3).map(move |i| {
                let (a, b) = (tri[i], tri[(i + 1) % 3]);
                let key = (u64::from(a.min(b)) << 32) | u64::from(a.max(b));
                (key, t as u32, a < b)
            })
        })
        .collect();
    e.par_sort_unstable_by_key(|&(k, t, _)| (k, t));
    e
}

/// Edge statistics: (edges, border, non-manifold, consistently oriented, orientable
/// components' flags per triangle root).
struct EdgeStats {
    edges: usize,
    border: usize,
    nonmanifold: usize,
    oriented: bool,
    /// Triangles of components with a border or non-manifold edge, or not orientable.
    not_closed: Vec<bool>,
}

fn edge_stats(s: &TriSurface, edges: &[Edge]) -> EdgeStats {
    let n = s.triangles.len();
    // triangles, with the parity "orientation flipped relative to the root"
    let mut dsu = ParityUnionFind::new(n);
    let mut bad = Vec::new();
    let mut st = EdgeStats {
        edges: 0,
        border: 0,
        nonmanifold: 0,
        oriented: true,
        not_closed: vec![false; n],
    };
    for group in edges.chunk_by(|a, b| a.0 == b.0) {
        st.edges += 1;
        match group {
            [(_, t, _)] => {
                st.border += 1;
                bad.push(*t);
            }
            [(_, t1, d1), (_, t2, d2)] => {
                // same direction: one of the two must be flipped
                st.oriented &= d1 != d2;
                if !dsu.relate(*t1, *t2, d1 == d2) {
                    bad.push(*t1);
                }
            }
            _ => {
                st.nonmanifold += 1;
                bad.push(group[0].1);
            }
        }
    }
    for t in bad {
        let r = dsu.find(t).0;
        st.not_closed[r as usize] = true;
    }
    for t in 0..n as u32 {
        let r = dsu.find(t).0;
        st.not_closed[t as usize] = st.not_closed[r as usize];
    }
    st
}

/// Number of vertices whose link (the opposite edges of their triangles) is disconnected.
fn pinched_vertices(s: &TriSurface) -> usize {
    let mut link: Vec<(u32, u32, u32)> = s
        .triangles
        .iter()
        .flat_map(|t| (0..3).map(move |i| (t[i], t[(i + 1) % 3], t[(i + 2) % 3])))
        .collect();
    link.par_sort_unstable();
    link.chunk_by(|a, b| a.0 == b.0)
        .filter(|g| link_components(g) > 1)
        .count()
}

/// Connected components of one vertex's link edges.
fn link_components(edges: &[(u32, u32, u32)]) -> usize {
    let mut ids: Vec<u32> = edges.iter().flat_map(|e| [e.1, e.2]).collect();
    ids.sort_unstable();
    ids.dedup();
    let mut d = UnionFind::new(ids.len());
    let local = |v: u32| ids.binary_search(&v).expect("listed") as u32;
    for e in edges {
        d.union(local(e.1), local(e.2));
    }
    (0..ids.len() as u32).filter(|&i| d.find(i) == i).count()
}

/// Area, summed in fixed-size blocks added in order (independent of the thread count).
fn area(s: &TriSurface) -> f64 {
    let partial: Vec<f64> = s
        .triangles
        .par_chunks(1 << 14)
        .map(|c| {
            c.iter()
                .map(|t| {
                    let [a, b, c] = t.map(|i| s.points[i as usize]);
                    let n = cross(sub(b, a), sub(c, a));
                    0.5 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt()
                })
                .sum()
        })
        .collect();
    partial.iter().sum()
}

/// Analyses `s` (see [`SurfaceAnalysis`]).
pub fn analyse_surface(s: &TriSurface) -> SurfaceAnalysis {
    let edges = sorted_edges(s);
    let st = edge_stats(s, &edges);
    let mut d = UnionFind::new(s.points.len());
    for t in &s.triangles {
        d.union(t[0], t[1]);
        d.union(t[0], t[2]);
    }
    let mut roots: Vec<u32> = (0..s.points.len() as u32).map(|v| d.find(v)).collect();
    // a component is closed when none of its triangles is marked
    let mut open = vec![false; s.points.len()];
    for (t, tri) in s.triangles.iter().enumerate() {
        if st.not_closed[t] {
            open[roots[tri[0] as usize] as usize] = true;
        }
    }
    let b2 = s
        .triangles
        .iter()
        .map(|t| roots[t[0] as usize])
        .filter(|&r| !open[r as usize])
        .collect::<std::collections::BTreeSet<_>>()
        .len();
    roots.sort_unstable();
    roots.dedup();
    let b0 = roots.len();
    let chi = s.points.len() as i64 - st.edges as i64 + s.triangles.len() as i64;
    let pinched = pinched_vertices(s);
    SurfaceAnalysis {
        vertices: s.points.len(),
        triangles: s.triangles.len(),
        area: area(s),
        betti: [b0, (b0 as i64 + b2 as i64 - chi).max(0) as usize, b2],
        closed_manifold: st.border == 0 && st.nonmanifold == 0 && pinched == 0,
        oriented: st.oriented,
        border_edges: st.border,
        nonmanifold_edges: st.nonmanifold,
        pinched_vertices: pinched,
    }
}
