//! Criticality of a grid vertex from its (up to) six edge-connected neighbours (“Exploring scalar
//! fields using critical isovalues” §3.2).
//!
//! Near a vertex the trilinear field splits each incident cell (an octant) like a linear
//! tetrahedron (Lemma 3 of “Exploring scalar fields using critical isovalues”), so the part of a
//! small sphere around the vertex where `f > f(vertex)` (the *upper link*) is homotopy equivalent
//! to the full subcomplex on the `+` neighbours of the link triangulation: the octahedron with the
//! six neighbour directions as vertices and one triangle per incident cell. Inside the grid box the
//! link is the whole octahedron; on the box it is the part made of the cells that exist (a disk).
//!
//! A vertex changes the topology of the superlevel sets `{f >= w}` when its upper link is not
//! contractible, and of the sublevel sets `{f <= w}` when its lower link is not. Inside the box
//! the two agree (Alexander duality on the sphere); on the box they may not (a box vertex whose
//! inward neighbour is lower and whose neighbours on the box are higher opens a hole in
//! `{f >= w}` but changes nothing in `{f <= w}`). [`VERTEX_TABLE`] is the 64-entry table of
//! “Exploring scalar fields using critical isovalues” for interior vertices, derived here by
//! [`link_class`] rather than typed in.
//!
//! Directions: `2 * axis + side`, side 0 = towards lower index (`-x`, `+x`, `-y`, `+y`, `-z`,
//! `+z`). Octant `o` (bit `a` set = positive side along axis `a`) is the triangle
//! `(o & 1, 2 + (o >> 1 & 1), 4 + (o >> 2 & 1))`.

/// How a vertex (or a face or body point) changes the topology of the level sets.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct LinkClass {
    /// Betti numbers `[b0, b1, b2]` of the upper link (`f > f(x)`).
    pub upper: [u8; 3],
    /// Betti numbers of the lower link (`f < f(x)`).
    pub lower: [u8; 3],
}

impl LinkClass {
    /// Whether crossing the value changes the superlevel sets `{f >= w}`: the upper link is
    /// not contractible (empty counts as not contractible).
    pub const fn superlevel(&self) -> bool {
        !(self.upper[0] == 1 && self.upper[1] == 0 && self.upper[2] == 0)
    }
    /// Whether crossing the value changes the sublevel sets `{f <= w}`.
    pub const fn sublevel(&self) -> bool {
        !(self.lower[0] == 1 && self.lower[1] == 0 && self.lower[2] == 0)
    }
    /// Whether the point is critical for either filtration.
    pub const fn critical(&self) -> bool {
        self.superlevel() || self.sublevel()
    }
    /// Whether no value around is lower (a minimum).
    pub const fn is_minimum(&self) -> bool {
        self.lower[0] == 0
    }
    /// Whether no value around is higher (a maximum).
    pub const fn is_maximum(&self) -> bool {
        self.upper[0] == 0
    }
}

/// The three link vertices (directions) of octant `o`.
pub const fn octant_dirs(o: usize) -> [usize; 3] {
    [o & 1, 2 + ((o >> 1) & 1), 4 + ((o >> 2) & 1)]
}

/// Betti numbers of the full subcomplex on directions `set` of the link made of the
/// octants in `octants` (bit `o` = octant `o` present). Directions outside every present
/// octant must not be in `set`.
pub const fn subcomplex_betti(set: u8, octants: u8) -> [u8; 3] {
    // union-find over 6 directions, written out: this const fn builds `VERTEX_TABLE` at
    // compile time, where `crate::union_find::UnionFind` (a `Vec`) cannot run
    let mut parent = [0usize, 1, 2, 3, 4, 5];
    let mut verts = 0i32;
    let mut d = 0;
    while d < 6 {
        if set & (1 << d) != 0 {
            verts += 1;
        }
        d += 1;
    }
    let mut edges = 0i32;
    let mut tris = 0i32;
    // an edge {a, b} (different axes) is present when some present octant holds both
    let mut a = 0;
    while a < 6 {
        let mut b = a + 1;
        while b < 6 {
            if a / 2 != b / 2 && set & (1 << a) != 0 && set & (1 << b) != 0 {
                let mut present = false;
                let mut o = 0;
                while o < 8 {
                    let t = octant_dirs(o);
                    let has_a = t[0] == a || t[1] == a || t[2] == a;
                    let has_b = t[0] == b || t[1] == b || t[2] == b;
                    if octants & (1 << o) != 0 && has_a && has_b {
                        present = true;
                    }
                    o += 1;
                }
                if present {
                    edges += 1;
                    let (mut ra, mut rb) = (a, b);
                    while parent[ra] != ra {
                        ra = parent[ra];
                    }
                    while parent[rb] != rb {
                        rb = parent[rb];
                    }
                    if ra != rb {
                        parent[rb] = ra;
                    }
                }
            }
            b += 1;
        }
        a += 1;
    }
    let mut o = 0;
    while o < 8 {
        let t = octant_dirs(o);
        if octants & (1 << o) != 0
            && set & (1 << t[0]) != 0
            && set & (1 << t[1]) != 0
            && set & (1 << t[2]) != 0
        {
            tris += 1;
        }
        o += 1;
    }
    let mut b0 = 0i32;
    let mut d = 0;
    while d < 6 {
        if set & (1 << d) != 0 && parent[d] == d {
            b0 += 1;
        }
        d += 1;
    }
    let b2 = if octants == 0xff && set == 0x3f { 1 } else { 0 };
    let chi = verts - edges + tris;
    let b1 = b0 + b2 - chi;
    [b0 as u8, b1 as u8, b2 as u8]
}

/// Directions that belong to some octant in `octants`.
pub const fn present_dirs(octants: u8) -> u8 {
    let mut m = 0u8;
    let mut o = 0;
    while o < 8 {
        if octants & (1 << o) != 0 {
            let t = octant_dirs(o);
            m |= (1 << t[0]) | (1 << t[1]) | (1 << t[2]);
        }
        o += 1;
    }
    m
}

/// Classifies a vertex whose present neighbours (those of the octants in `octants`) are
/// higher where `upper` has a bit and lower elsewhere (no neighbour equal).
pub const fn link_class(upper: u8, octants: u8) -> LinkClass {
    let present = present_dirs(octants);
    let up = upper & present;
    let down = !upper & present;
    LinkClass {
        upper: subcomplex_betti(up, octants),
        lower: subcomplex_betti(down, octants),
    }
}

/// The 64-entry table of “Exploring scalar fields using critical isovalues” for interior vertices:
/// entry `m` classifies a vertex whose neighbours in the directions with a bit in `m` are higher
/// and the others lower.
pub const VERTEX_TABLE: [LinkClass; 64] = vertex_table();

const fn vertex_table() -> [LinkClass; 64] {
    let mut t = [LinkClass {
        upper: [0; 3],
        lower: [0; 3],
    }; 64];
    let mut m = 0;
    while m < 64 {
        t[m] = link_class(m as u8, 0xff);
        m += 1;
    }
    t
}

/// Octants of grid vertex `p` that are cells of a grid with `dims` vertices per axis.
#[inline]
pub fn vertex_octants(p: [usize; 3], dims: [usize; 3]) -> u8 {
    let mut m = 0u8;
    for o in 0..8 {
        let ok = (0..3).all(|a| {
            if (o >> a) & 1 == 1 {
                p[a] + 1 < dims[a]
            } else {
                p[a] > 0
            }
        });
        if ok {
            m |= 1 << o;
        }
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Gerstner–Pajarola's criterion over the octahedron's edge graph (“Exploring scalar fields
    /// using critical isovalues” §3.1): components of `+` and of `-` neighbours after deleting
    /// mixed edges.
    fn edge_graph_components(m: u8) -> (usize, usize) {
        let mut count = [0usize; 2];
        let mut seen = [false; 6];
        for s in 0..6 {
            if seen[s] {
                continue;
            }
            let sign = (m >> s) & 1;
            count[sign as usize] += 1;
            let mut stack = vec![s];
            seen[s] = true;
            while let Some(a) = stack.pop() {
                for b in 0..6 {
                    if !seen[b] && a / 2 != b / 2 && (m >> b) & 1 == sign {
                        seen[b] = true;
                        stack.push(b);
                    }
                }
            }
        }
        (count[1], count[0])
    }

    #[test]
    fn table_matches_the_edge_graph_criterion() {
        let mut kinds = [0usize; 4];
        for m in 0..64u8 {
            let c = VERTEX_TABLE[m as usize];
            let (np, nn) = edge_graph_components(m);
            assert_eq!(c.is_minimum(), nn == 0, "{m:06b}");
            assert_eq!(c.is_maximum(), np == 0, "{m:06b}");
            assert_eq!(c.critical(), !(np == 1 && nn == 1), "{m:06b}");
            // inside the box both filtrations agree
            assert_eq!(c.superlevel(), c.sublevel(), "{m:06b}");
            let k = if c.is_minimum() {
                0
            } else if c.is_maximum() {
                1
            } else if c.critical() {
                2
            } else {
                3
            };
            kinds[k] += 1;
        }
        // one minimum, one maximum; saddles: the two ends of one axis on one side and the
        // other four on the other (3 axes x 2 signs); every other pattern splits the octahedron
        // into one connected upper and one connected lower part
        assert_eq!(kinds, [1, 1, 6, 56]);
    }

    #[test]
    fn table_is_invariant_under_cube_symmetries_and_sign_flip() {
        // the 48 symmetries: permutations of axes and reflections
        let perms = [
            [0, 1, 2],
            [0, 2, 1],
            [1, 0, 2],
            [1, 2, 0],
            [2, 0, 1],
            [2, 1, 0],
        ];
        for m in 0..64u8 {
            let c = VERTEX_TABLE[m as usize];
            let flipped = VERTEX_TABLE[(!m & 0x3f) as usize];
            assert_eq!(c.upper, flipped.lower);
            for p in perms {
                for refl in 0..8 {
                    let mut n = 0u8;
                    for d in 0..6 {
                        if (m >> d) & 1 == 1 {
                            let axis = d / 2;
                            let side = (d % 2) ^ ((refl >> axis) & 1);
                            n |= 1 << (2 * p[axis] + side);
                        }
                    }
                    assert_eq!(VERTEX_TABLE[n as usize], c, "{m:06b} -> {n:06b}");
                }
            }
        }
    }

    #[test]
    fn box_vertices() {
        // a vertex on the -z box face: octants with z bit set only
        let oct = vertex_octants([1, 1, 0], [3, 3, 3]);
        assert_eq!(oct, 0b1111_0000);
        // inward (+z) lower, the four on the face higher: hole in {f >= w}, nothing below
        let upper = 0b00_1111;
        let c = link_class(upper, oct);
        assert!(c.superlevel() && !c.sublevel());
        assert_eq!(c.upper, [1, 1, 0]);
        // all higher: a minimum of the sublevel sets only
        let c = link_class(0x3f, oct);
        assert!(c.is_minimum() && c.sublevel() && !c.superlevel());
        // a box corner with its three neighbours mixed is regular
        let oct = vertex_octants([0, 0, 0], [3, 3, 3]);
        assert_eq!(oct, 0b1000_0000);
        assert!(!link_class(0b00_0010, oct).critical());
        assert!(link_class(0, oct).is_maximum() && link_class(0, oct).superlevel());
        assert!(!link_class(0, oct).sublevel());
    }
}
