//! Union–find (disjoint sets) over the elements `0..n`, and its parity variant.
//!
//! [`UnionFind`] serves every connectivity count of the crate (components of meshes and
//! surfaces, of the level-set graphs around plateaus and snapped vertices, of the superlevel
//! and sublevel sets of the persistence sweep). [`ParityUnionFind`] also keeps, per element,
//! whether it is flipped relative to its root (the orientation of a surface's triangles).

/// Disjoint sets over the elements `0..len()`, with path halving.
///
/// Which element is the root of a set is part of the contract, since callers key data by it:
/// [`union`](Self::union) makes the smaller of the two roots the root of the merged set, so
/// with `union` alone the root of every set is its smallest element, whatever the order of
/// the unions. [`link`](Self::link) lets the caller choose the root instead (e.g. the elder
/// of two components).
#[derive(Clone, Debug, Default)]
pub struct UnionFind {
    parent: Vec<u32>,
}

impl UnionFind {
    /// `n` singletons.
    ///
    /// # Panics
    /// When `n` exceeds `u32::MAX` (elements are `u32`).
    pub fn new(n: usize) -> Self {
        assert!(n <= u32::MAX as usize, "union-find of {n} elements");
        UnionFind {
            parent: (0..n as u32).collect(),
        }
    }

    /// Number of elements.
    pub fn len(&self) -> usize {
        self.parent.len()
    }

    /// Whether there are no elements.
    pub fn is_empty(&self) -> bool {
        self.parent.is_empty()
    }

    /// Adds singletons up to `n` elements (none when there are already that many).
    ///
    /// # Panics
    /// When `n` exceeds `u32::MAX`.
    pub fn grow(&mut self, n: usize) {
        assert!(n <= u32::MAX as usize, "union-find of {n} elements");
        let from = self.parent.len() as u32;
        self.parent.extend(from..n as u32);
    }

    /// The root of `x`'s set (halving the path on the way).
    #[inline]
    pub fn find(&mut self, mut x: u32) -> u32 {
        while self.parent[x as usize] != x {
            let g = self.parent[self.parent[x as usize] as usize];
            self.parent[x as usize] = g;
            x = g;
        }
        x
    }

    /// Merges the sets of `a` and `b`; the smaller of their two roots becomes the root.
    #[inline]
    pub fn union(&mut self, a: u32, b: u32) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            self.parent[ra.max(rb) as usize] = ra.min(rb);
        }
    }

    /// Merges the sets of all of `xs`, as [`union`](Self::union) of the first with each of
    /// the others would, but finding the first's root once (a tet or a triangle: its corners).
    #[inline]
    pub fn union_all(&mut self, xs: &[u32]) {
        let Some((&first, rest)) = xs.split_first() else {
            return;
        };
        let mut r = self.find(first);
        for &x in rest {
            let rx = self.find(x);
            if rx != r {
                self.parent[r.max(rx) as usize] = r.min(rx);
                r = r.min(rx);
            }
        }
    }

    /// Hangs the set of root `child` under root `root` (which stays the root); both must be
    /// roots of different sets.
    #[inline]
    pub fn link(&mut self, root: u32, child: u32) {
        debug_assert!(self.parent[root as usize] == root && self.parent[child as usize] == child);
        debug_assert!(root != child);
        self.parent[child as usize] = root;
    }

    /// Number of roots among the elements flagged in `used` (`used.len()` at most
    /// [`len`](Self::len)): the number of sets that hold a flagged root.
    pub fn count_roots(&mut self, used: &[bool]) -> usize {
        (0..used.len() as u32)
            .filter(|&i| used[i as usize] && self.find(i) == i)
            .count()
    }
}

/// Disjoint sets over `0..n` in which each element also has a parity relative to its root
/// (e.g. whether a triangle's orientation is flipped relative to that of the root's), with
/// full path compression.
#[derive(Clone, Debug, Default)]
pub struct ParityUnionFind {
    parent: Vec<u32>,
    /// Parity relative to the parent (to the root after compression).
    parity: Vec<bool>,
}

impl ParityUnionFind {
    /// `n` singletons, each of parity `false`.
    ///
    /// # Panics
    /// When `n` exceeds `u32::MAX` (elements are `u32`).
    pub fn new(n: usize) -> Self {
        assert!(n <= u32::MAX as usize, "union-find of {n} elements");
        ParityUnionFind {
            parent: (0..n as u32).collect(),
            parity: vec![false; n],
        }
    }

    /// The root of `x`'s set and the parity of `x` relative to it.
    pub fn find(&mut self, x: u32) -> (u32, bool) {
        let mut path = Vec::new();
        let mut r = x;
        while self.parent[r as usize] != r {
            path.push(r);
            r = self.parent[r as usize];
        }
        // compress: parity of each path node relative to the root
        let mut acc = false;
        for &n in path.iter().rev() {
            acc ^= self.parity[n as usize];
            self.parity[n as usize] = acc;
            self.parent[n as usize] = r;
        }
        (
            r,
            if path.is_empty() {
                false
            } else {
                self.parity[x as usize]
            },
        )
    }

    /// Requires `parity(a) ^ parity(b) == p`, merging the two sets (the root of `a`'s stays
    /// the root) when they differ; returns false on a contradiction (same set, other parity).
    pub fn relate(&mut self, a: u32, b: u32, p: bool) -> bool {
        let (ra, pa) = self.find(a);
        let (rb, pb) = self.find(b);
        if ra == rb {
            return pa ^ pb == p;
        }
        self.parent[rb as usize] = ra;
        self.parity[rb as usize] = pa ^ pb ^ p;
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn union_keeps_the_smallest_element_as_root() {
        let mut u = UnionFind::new(6);
        u.union(4, 5);
        u.union(5, 2);
        u.union(3, 1);
        assert_eq!(u.find(4), 2);
        assert_eq!(u.find(5), 2);
        assert_eq!(u.find(3), 1);
        assert_eq!(u.find(0), 0);
        assert_eq!(u.count_roots(&[true; 6]), 3);
        assert_eq!(u.count_roots(&[false, true, false, false, false, false]), 1);
    }

    #[test]
    fn union_all_merges_like_unions_with_the_first() {
        let mut u = UnionFind::new(8);
        u.union(6, 7);
        u.union_all(&[5, 7, 3]);
        u.union_all(&[1]);
        u.union_all(&[]);
        assert_eq!([5, 6, 7, 3].map(|x| u.find(x)), [3; 4]);
        assert_eq!(u.find(1), 1);
        u.union_all(&[0, 1, 1]);
        assert_eq!(u.find(1), 0);
        assert_eq!(u.count_roots(&[true; 8]), 4);
    }

    #[test]
    fn link_chooses_the_root_and_grow_adds_singletons() {
        let mut u = UnionFind::new(3);
        u.link(2, 0);
        assert_eq!(u.find(0), 2);
        u.grow(5);
        assert_eq!(u.len(), 5);
        assert_eq!(u.find(4), 4);
        u.union(4, 0);
        assert_eq!(u.find(4), 2);
        u.grow(2);
        assert_eq!(u.len(), 5);
        assert!(UnionFind::new(0).is_empty());
    }

    #[test]
    fn parity_detects_contradictions() {
        let mut u = ParityUnionFind::new(4);
        assert!(u.relate(0, 1, true));
        assert!(u.relate(1, 2, true));
        assert_eq!(u.find(2), (0, false));
        assert_eq!(u.find(1), (0, true));
        assert!(u.relate(2, 0, false));
        assert!(!u.relate(2, 0, true));
        assert_eq!(u.find(3), (3, false));
    }
}
