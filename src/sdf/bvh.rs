//! A bounding-volume hierarchy over triangles and closest-point queries.
//!
//! The tree is built top-down, serially, by splitting each node's triangles at the median
//! centroid along the longest axis of their centroids' box (ties broken by triangle number,
//! so the tree depends on the input alone), down to leaves of at most [`LEAF_SIZE`]
//! triangles. Nodes are stored depth-first: a node's left child follows it, its right child
//! is at [`Node::right`]; every node covers a contiguous range of the reordered triangles.

use crate::geom::{dot, sub};

/// Most triangles in a leaf.
pub const LEAF_SIZE: usize = 4;

/// A node of the [`Bvh`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Node {
    /// Lower corner of the box of the node's triangles.
    pub lo: [f64; 3],
    /// Upper corner of the box.
    pub hi: [f64; 3],
    /// First of the node's triangles in [`Bvh::tris`].
    pub start: u32,
    /// Number of the node's triangles.
    pub count: u32,
    /// Index of the right child (the left child is the next node); 0 for a leaf.
    pub right: u32,
}

impl Node {
    /// Whether the node has no children.
    pub fn is_leaf(&self) -> bool {
        self.right == 0
    }

    /// Squared distance from `q` to the node's box (0 inside).
    #[inline]
    pub fn box_distance2(&self, q: [f64; 3]) -> f64 {
        let mut d2 = 0.0;
        for a in 0..3 {
            let d = (self.lo[a] - q[a]).max(q[a] - self.hi[a]).max(0.0);
            d2 += d * d;
        }
        d2
    }
}

/// A triangle's three corners.
pub type Tri = [[f64; 3]; 3];

/// A bounding-volume hierarchy over a list of triangles.
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    /// The nodes, depth-first; node 0 is the root.
    pub nodes: Vec<Node>,
    /// The triangles' corners, reordered so that each node's triangles are contiguous.
    pub tris: Vec<Tri>,
    /// For each entry of `tris`, the triangle's number in the input.
    pub ids: Vec<u32>,
}

/// The result of a closest-point query.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Closest {
    /// Squared distance to the closest triangle.
    pub distance2: f64,
    /// The closest triangle's position in [`Bvh::tris`].
    pub slot: u32,
}

impl Bvh {
    /// Builds the hierarchy over `tris` (at least one triangle).
    pub fn new(tris: &[Tri]) -> Bvh {
        let mut items: Vec<(u32, [f64; 3])> = tris
            .iter()
            .enumerate()
            .map(|(i, t)| (i as u32, centroid(t)))
            .collect();
        let mut bvh = Bvh {
            nodes: Vec::with_capacity(2 * tris.len() / LEAF_SIZE + 1),
            tris: Vec::with_capacity(tris.len()),
            ids: Vec::with_capacity(tris.len()),
        };
        if !items.is_empty() {
            bvh.build(tris, &mut items, 0);
        }
        bvh
    }

    /// Builds the subtree over `items`, whose first triangle goes to slot `start`.
    fn build(&mut self, tris: &[Tri], items: &mut [(u32, [f64; 3])], start: usize) -> usize {
        let me = self.nodes.len();
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        let (mut clo, mut chi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for (id, c) in items.iter() {
            for p in &tris[*id as usize] {
                grow(&mut lo, &mut hi, *p);
            }
            grow(&mut clo, &mut chi, *c);
        }
        self.nodes.push(Node {
            lo,
            hi,
            start: start as u32,
            count: items.len() as u32,
            right: 0,
        });
        if items.len() <= LEAF_SIZE {
            for (id, _) in items.iter() {
                self.tris.push(tris[*id as usize]);
                self.ids.push(*id);
            }
            return me;
        }
        let axis = (0..3)
            .max_by(|&a, &b| (chi[a] - clo[a]).total_cmp(&(chi[b] - clo[b])))
            .unwrap_or(0);
        let mid = items.len() / 2;
        items.select_nth_unstable_by(mid, |x, y| {
            x.1[axis].total_cmp(&y.1[axis]).then(x.0.cmp(&y.0))
        });
        let (left, right) = items.split_at_mut(mid);
        self.build(tris, left, start);
        let r = self.build(tris, right, start + mid);
        self.nodes[me].right = r as u32;
        me
    }

    /// The triangle closest to `q` and its squared distance. `hint` (a slot of
    /// [`Bvh::tris`]) is measured first: a triangle known to be near makes the search prune
    /// early. The distance found does not depend on the hint.
    pub fn closest(&self, q: [f64; 3], hint: Option<u32>) -> Closest {
        let mut best = Closest {
            distance2: f64::INFINITY,
            slot: 0,
        };
        if let Some(h) = hint.filter(|&h| (h as usize) < self.tris.len()) {
            best = Closest {
                distance2: point_triangle_distance2(q, &self.tris[h as usize]),
                slot: h,
            };
        }
        let mut stack: Vec<u32> = Vec::with_capacity(64);
        if !self.nodes.is_empty() {
            stack.push(0);
        }
        while let Some(i) = stack.pop() {
            let n = &self.nodes[i as usize];
            if n.box_distance2(q) > best.distance2 {
                continue;
            }
            if n.is_leaf() {
                for s in n.start..n.start + n.count {
                    let d2 = point_triangle_distance2(q, &self.tris[s as usize]);
                    if d2 < best.distance2 {
                        best = Closest {
                            distance2: d2,
                            slot: s,
                        };
                    }
                }
                continue;
            }
            let (l, r) = (i + 1, n.right);
            let dl = self.nodes[l as usize].box_distance2(q);
            let dr = self.nodes[r as usize].box_distance2(q);
            // the nearer child is searched first
            if dl <= dr {
                stack.push(r);
                stack.push(l);
            } else {
                stack.push(l);
                stack.push(r);
            }
        }
        best
    }
}

/// The centroid of a triangle.
pub(crate) fn centroid(t: &Tri) -> [f64; 3] {
    [0, 1, 2].map(|a| (t[0][a] + t[1][a] + t[2][a]) / 3.0)
}

fn grow(lo: &mut [f64; 3], hi: &mut [f64; 3], p: [f64; 3]) {
    for a in 0..3 {
        lo[a] = lo[a].min(p[a]);
        hi[a] = hi[a].max(p[a]);
    }
}

/// `p + s u + t v`.
#[inline]
fn at(p: [f64; 3], u: [f64; 3], s: f64, v: [f64; 3], t: f64) -> [f64; 3] {
    [0, 1, 2].map(|a| p[a] + s * u[a] + t * v[a])
}

/// Squared distance from `p` to the triangle `t` (Ericson, *Real-Time Collision Detection*,
/// 5.1.5: the Voronoi region of `p` among the corners, edges and face). Degenerate
/// triangles give the distance to their segment or point.
pub fn point_triangle_distance2(p: [f64; 3], t: &Tri) -> f64 {
    let c = closest_on_triangle(p, t);
    let d = sub(p, c);
    dot(d, d)
}

/// The point of triangle `t` closest to `p`.
pub fn closest_on_triangle(p: [f64; 3], t: &Tri) -> [f64; 3] {
    let [a, b, c] = *t;
    let (ab, ac, ap) = (sub(b, a), sub(c, a), sub(p, a));
    let (d1, d2) = (dot(ab, ap), dot(ac, ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = sub(p, b);
    let (d3, d4) = (dot(ab, bp), dot(ac, bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return at(a, ab, d1 / (d1 - d3), ac, 0.0);
    }
    let cp = sub(p, c);
    let (d5, d6) = (dot(ab, cp), dot(ac, cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return at(a, ab, 0.0, ac, d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return at(b, sub(c, b), w, ab, 0.0);
    }
    let denom = va + vb + vc;
    if denom.abs() < f64::MIN_POSITIVE || !denom.is_finite() {
        // a degenerate triangle whose tests above did not settle: the nearest of its edges
        return nearest_on_edges(p, t);
    }
    let (v, w) = (vb / denom, vc / denom);
    at(a, ab, v, ac, w)
}

/// The point of the three edges of `t` closest to `p`.
fn nearest_on_edges(p: [f64; 3], t: &Tri) -> [f64; 3] {
    let mut best = (f64::INFINITY, t[0]);
    for e in 0..3 {
        let (a, b) = (t[e], t[(e + 1) % 3]);
        let ab = sub(b, a);
        let len2 = dot(ab, ab);
        let s = if len2 > 0.0 {
            (dot(sub(p, a), ab) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let c = at(a, ab, s, ab, 0.0);
        let d = sub(p, c);
        if dot(d, d) < best.0 {
            best = (dot(d, d), c);
        }
    }
    best.1
}

#[cfg(test)]
mod tests {
    use super::*;

    fn brute(q: [f64; 3], tris: &[Tri]) -> f64 {
        tris.iter()
            .map(|t| point_triangle_distance2(q, t))
            .fold(f64::INFINITY, f64::min)
    }

    #[test]
    fn closest_matches_brute_force() {
        let mut tris = Vec::new();
        let mut s = 12345u64;
        let mut r = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64 * 4.0 - 2.0
        };
        for _ in 0..300 {
            let a = [r(), r(), r()];
            let t = [
                a,
                [a[0] + 0.2 * r(), a[1] + 0.2 * r(), a[2]],
                [a[0], a[1] + 0.2 * r(), a[2] + 0.2 * r()],
            ];
            tris.push(t);
        }
        let bvh = Bvh::new(&tris);
        for _ in 0..200 {
            let q = [r() * 1.5, r() * 1.5, r() * 1.5];
            let got = bvh.closest(q, Some(7));
            assert_eq!(got.distance2, brute(q, &tris));
            let t = &bvh.tris[got.slot as usize];
            assert_eq!(point_triangle_distance2(q, t), got.distance2);
        }
    }

    #[test]
    fn distances_to_regions() {
        let t = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        assert_eq!(point_triangle_distance2([0.2, 0.2, 2.0], &t), 4.0);
        assert_eq!(point_triangle_distance2([-1.0, -1.0, 0.0], &t), 2.0);
        assert_eq!(point_triangle_distance2([0.5, -3.0, 0.0], &t), 9.0);
        assert!((point_triangle_distance2([1.0, 1.0, 0.0], &t) - 0.5).abs() < 1e-15);
        let line = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]];
        assert!((point_triangle_distance2([1.5, 1.0, 0.0], &line) - 1.0).abs() < 1e-15);
    }
}
