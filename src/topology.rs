//! Betti numbers of a tetrahedral mesh of a domain in R³.
//!
//! For a compact 3-manifold with boundary embedded in R³: b0 = connected components,
//! b2 = boundary-surface components − b0 (cavities), and χ(M) = χ(∂M)/2, so
//! b1 = b0 + b2 − χ. Requires the mesher's invariants (closed manifold boundary).

use crate::mesh::TetMesh;
use crate::union_find::UnionFind;

/// Number of connected components among the `used` elements of `0..n` linked by the pairs
/// `links` yields for each item. Items are split among threads, each building its own
/// union–find; the forests are then merged (linking each element to its root in the other
/// forest keeps exactly the same components).
fn count_components<T: Sync>(
    n: usize,
    used: &[bool],
    items: &[T],
    links: impl Fn(&T) -> [(u32, u32); 3] + Sync,
) -> usize {
    use rayon::prelude::*;
    let chunk = items
        .len()
        .div_ceil(rayon::current_num_threads())
        .max(1 << 16);
    let mut d = items
        .par_chunks(chunk)
        .map(|c| {
            let mut d = UnionFind::new(n);
            for t in c {
                for (a, b) in links(t) {
                    d.union(a, b);
                }
            }
            d
        })
        .reduce_with(|mut a, mut b| {
            for v in 0..n as u32 {
                let r = b.find(v);
                if r != v {
                    a.union(v, r);
                }
            }
            a
        })
        .unwrap_or_else(|| UnionFind::new(n));
    d.count_roots(used)
}

/// The pairs that join a tet's corners (a spanning star).
pub(crate) fn tet_links(t: &[u32; 4]) -> [(u32, u32); 3] {
    [(t[0], t[1]), (t[0], t[2]), (t[0], t[3])]
}

/// The pairs that join a triangle's corners.
pub(crate) fn triangle_links(t: &[u32; 3]) -> [(u32, u32); 3] {
    [(t[0], t[1]), (t[0], t[2]), (t[1], t[2])]
}

/// Betti numbers `[b0, b1, b2]` of the meshed domain.
pub fn betti(mesh: &TetMesh) -> [usize; 3] {
    betti_with_boundary(mesh, &mesh.boundary)
}

/// [`betti`] with the boundary triangles given (a closed manifold surface: the faces of one
/// tet of `mesh`) instead of the mesh's labelled ones.
pub(crate) fn betti_with_boundary(mesh: &TetMesh, boundary: &[[u32; 3]]) -> [usize; 3] {
    let n = mesh.points.len();
    if mesh.tets.is_empty() {
        return [0, 0, 0];
    }
    let mut used = vec![false; n];
    for t in &mesh.tets {
        for &i in t {
            used[i as usize] = true;
        }
    }
    let b0 = count_components(n, &used, &mesh.tets, tet_links);
    let mut on_b = vec![false; n];
    for t in boundary {
        for &i in t {
            on_b[i as usize] = true;
        }
    }
    let surfaces = count_components(n, &on_b, boundary, triangle_links);
    let vb = on_b.iter().filter(|&&x| x).count() as i64;
    betti_from_counts(b0, surfaces, vb, boundary.len() as i64)
}

/// Betti numbers from the counts: `b0` solid components, boundary-surface components, and
/// the boundary's vertices `vb` and triangles `fb`.
pub(crate) fn betti_from_counts(b0: usize, surfaces: usize, vb: i64, fb: i64) -> [usize; 3] {
    // χ(∂M) = V − E + F with E = 3F/2; χ(M) = χ(∂M)/2
    let chi = (2 * vb - fb) / 4;
    let b2 = surfaces.saturating_sub(b0);
    let b1 = (b0 as i64 + b2 as i64 - chi).max(0) as usize;
    [b0, b1, b2]
}
