//! Betti numbers of a tetrahedral mesh of a domain in R³.
//!
//! For a compact 3-manifold with boundary embedded in R³: b0 = connected components,
//! b2 = boundary-surface components − b0 (cavities), and χ(M) = χ(∂M)/2, so
//! b1 = b0 + b2 − χ. Requires the mesher's invariants (closed manifold boundary).

use crate::mesh::TetMesh;

/// Union–find over `n` elements.
pub(crate) struct Dsu(Vec<u32>);

impl Dsu {
    pub(crate) fn new(n: usize) -> Self {
        Dsu((0..n as u32).collect())
    }
    pub(crate) fn find(&mut self, mut x: u32) -> u32 {
        while self.0[x as usize] != x {
            let p = self.0[self.0[x as usize] as usize];
            self.0[x as usize] = p;
            x = p;
        }
        x
    }
    /// Adds singletons up to `n` elements.
    pub(crate) fn grow(&mut self, n: usize) {
        let from = self.0.len() as u32;
        self.0.extend(from..n as u32);
    }
    /// Number of roots among the elements flagged in `used`.
    pub(crate) fn roots(&mut self, used: &[bool]) -> usize {
        (0..used.len() as u32)
            .filter(|&i| used[i as usize] && self.find(i) == i)
            .count()
    }
    pub(crate) fn union(&mut self, a: u32, b: u32) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            self.0[ra.max(rb) as usize] = ra.min(rb);
        }
    }
}

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
            let mut d = Dsu::new(n);
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
        .unwrap_or_else(|| Dsu::new(n));
    (0..n as u32)
        .filter(|&i| used[i as usize] && d.find(i) == i)
        .count()
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
