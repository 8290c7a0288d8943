//! Warping before clipping: which grid vertices move onto a level.
//!
//! A level that passes very close to a grid vertex cuts the vertex's edges right next to it,
//! and clipping then makes slivers. Isosurface stuffing and lattice cleaving avoid them by
//! *warping*: the vertex itself is put on the level, so those cuts never appear. Here an
//! interior grid vertex `v` is snapped to level `λ` when
//!
//! 1. **close:** some edge of the tetrahedral complex from `v` crosses `λ` at a fraction
//!    `t < eps` of its length from `v` (`t = |f(v) − λ| / |f(u) − f(v)|`), and the trilinear
//!    level set also passes within `eps` (index units) of `v` (on a diagonal of the
//!    decomposition the linear crossing can be much closer than the trilinear one, and the
//!    quality pass must then move the snapped vertex that far to put it on its level), and
//!    the interval's other level does not pass within 0.4 voxel of `v` (a thin layer, which
//!    the quality pass leaves as it is: a snap there would shift the layer's volume);
//! 2. **regular:** in the link of `v` in the complex (the decomposition of its eight cells),
//!    the closed set `S` where the field is at least the level (on the domain side) is a
//!    disk. Then the domain's part in the star of `v` is a ball glued to the rest along `S`
//!    both before the snap and after it (then it is the cone from `v` over `S`), so the
//!    domain stays homeomorphic: the vertex test of “Exploring scalar fields using critical
//!    isovalues” §3.2 in the TPTD complex. On the
//!    link (a triangulated 2-sphere) with up / on-level / down nodes, `S` is a disk when up
//!    and on-level nodes (joined through up ones) are one connected set and down nodes
//!    another, every on-level node touches an up node, and around each on-level node the
//!    down neighbours form one run (the level passes through the node, so each down
//!    neighbour cuts `S` there; on-level neighbours count as on `S`'s side). Two on-level
//!    nodes may be joined only by a link edge whose two link triangles have their third
//!    nodes off the level and not both down: with one up and one down the edge is a piece of
//!    `∂S` (the face it makes with `v` is a boundary face with three snapped corners, which
//!    the clipper emits from the flat piece of the tet on the down side); with both up it
//!    lies inside `S`, where the field touches the level from above. Both down would make
//!    `S` a sheet there, and an on-level third node a tet with four corners on the level.
//!    Coming from below, on-level nodes and edges must lie on `∂S`: the domain in the
//!    star is then a collar of `S` that thins out to nothing only along `∂S`. Such a face
//!    must not lie in a grid plane of constant z, so that the tets on both sides of it are
//!    in one layer of cells (the streamed mesh keeps each boundary triangle in its tet's
//!    chunk). Vertices on the grid box (half-sphere links) are not snapped. The interval's
//!    other level may cross the link: its nodes beyond it count as on the domain side of
//!    the snapped level. The other level then cuts the star's part of the domain where rays
//!    from `v` reach it, at the same edges and the same link points before and after the
//!    snap (`v`'s value stays short of it), so both parts are still balls, bounded by the
//!    same pieces of that level (isotopic rel the link), the same part of the link, and a
//!    disk of the snapped level with boundary `∂S`: a homeomorphism of their boundaries
//!    fixing the link extends to the balls. A link node snapped to the other level is up
//!    too (its value is that level's). The complex is the plain mesh's: its sagging edges
//!    split (`decompose::sag`), so the split points are link nodes like any other;
//! 3. **near on the surface it leaves:** with `v` on its level, both levels' pieces in every
//!    tet of its star lie within the quality pass's guard distance of the trilinear level
//!    sets ([`near::TrilinearNear::tet_levels_near`]). Step 1 looks along one edge; the
//!    triangles from `v` to the cuts on the far side of its link can span a valley of the
//!    field, and the snap also moves the other level's cuts on `v`'s edges. The pass moves
//!    a snapped vertex onto the level set, but not in a thin layer: the snap itself must
//!    leave a surface that the checker accepts;
//! 4. **in rounds:** each round snaps, among the vertices that pass in the current state
//!    (earlier snaps are on-level nodes), those with the smallest `t` among the passing grid
//!    vertices of their link (ties: smaller index). Vertices snapped in one round are never
//!    adjacent, so the round is a sequence of single snaps, each of which keeps the topology.
//!
//! Cells whose corners all lie outside the interval are not decomposed; their part of the
//! link is a disk on one side of `λ`, so all the link nodes in such a cell are joined (and a
//! snapped node there stops the test). The clipper then treats a snapped vertex as a point
//! on its level (`clip::SNAP_ALPHA`, `clip::SNAP_BETA`). Its position stays the grid vertex;
//! the quality pass moves it onto the trilinear level set.

use rayon::prelude::*;
use rustc_hash::FxHashMap;

use crate::clip::{SNAP_ALPHA, SNAP_BETA, SNAP_NONE};
use crate::decompose::decompose_cell;
use crate::decompose::plan::{plan_cell, Layout, Planner};
use crate::geom::interval_volume;
use crate::grid::{corner_offset, ScalarGrid};
use crate::keys::{key_index, key_kind, local_key, vertex_key, VertexKey, CORNER};
use crate::levels::Levels;
use crate::union_find::UnionFind;
use near::TrilinearNear;

mod near;

/// A grid vertex that warping put on a level, and the volume that moved (the mesh's volume
/// with the snap less that without it, in index units: cells of volume 1). The quality pass
/// gives it back ([`crate::improve::improve_meshed`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Snapped {
    /// Grid index of the vertex.
    pub vertex: usize,
    /// Volume the snap added (negative: took).
    pub volume: f64,
}

/// A link vertex: key, index-space position, value.
#[derive(Clone, Copy, Debug)]
struct Node {
    key: VertexKey,
    pos: [f64; 3],
    val: f64,
}

impl Node {
    /// Its snap in state `snaps` ([`SNAP_NONE`] for a node that is not a grid vertex).
    fn state(&self, snaps: &[u8]) -> u8 {
        match key_kind(self.key) == CORNER {
            true => snaps[key_index(self.key)],
            false => SNAP_NONE,
        }
    }
}

/// Rounds of snapping (each snaps an independent set of the vertices that pass).
const ROUNDS: usize = 6;

/// Which grid vertices warping snaps.
#[derive(Default)]
pub(crate) struct Warp {
    /// Per grid vertex: [`SNAP_NONE`], [`SNAP_ALPHA`] or [`SNAP_BETA`]. Empty when nothing
    /// is snapped.
    pub snaps: Vec<u8>,
    /// The snapped vertices and the volume each snap added, by grid index.
    pub snapped: Vec<Snapped>,
}

/// The snaps for threshold `eps` (none when `eps <= 0`).
pub(crate) fn snap_vertices(grid: &ScalarGrid, planner: &Planner, lv: &Levels, eps: f64) -> Warp {
    if eps <= 0.0 || grid.dims.iter().any(|&n| n < 3) {
        return Warp::default();
    }
    let cand = candidates(grid, lv, eps);
    let listed: Vec<(usize, u8)> = cand
        .par_iter()
        .enumerate()
        .filter(|(_, &c)| c != SNAP_NONE)
        .map(|(v, &c)| (v, c))
        .collect();
    drop(cand);
    let near = TrilinearNear::new(grid, eps);
    let stars: Vec<Star> = listed
        .par_iter()
        .filter_map(|&(v, snap)| Star::new(grid, planner, lv, v, snap, eps))
        .filter(|s| near.holds(s.v, level_of(s.snap, lv)))
        .collect();
    let mut snaps = vec![SNAP_NONE; grid.num_vertices()];
    let mut snapped = Vec::new();
    let star_of: FxHashMap<usize, usize> =
        stars.iter().enumerate().map(|(i, s)| (s.v, i)).collect();
    let mut open: Vec<usize> = (0..stars.len()).collect();
    let mut passes = vec![false; stars.len()];
    let mut dirty = open.clone();
    for _ in 0..ROUNDS {
        let tested: Vec<(usize, bool)> = dirty
            .par_iter()
            .map(|&s| (s, stars[s].regular(&snaps, lv)))
            .collect();
        for (s, p) in tested {
            passes[s] = p;
        }
        let mut chosen = snap_round(&stars, &open, &passes);
        if chosen.is_empty() {
            break;
        }
        // The surface test (the costly one) only for the chosen: one that fails it stops
        // passing until its link changes, and the neighbours that gave way to it may be
        // chosen in the next round.
        let near_ok: Vec<bool> = chosen
            .par_iter()
            .map(|&s| stars[s].surface_near(grid, &near, &snaps, lv))
            .collect();
        for (&s, _) in chosen.iter().zip(&near_ok).filter(|(_, &ok)| !ok) {
            passes[s] = false;
        }
        let mut ok = near_ok.into_iter();
        chosen.retain(|_| ok.next().unwrap_or(false));
        // Stars snapped in one round share no tet, so their volume changes add up.
        let moved: Vec<f64> = chosen
            .par_iter()
            .map(|&s| stars[s].snap_volume(grid, &snaps, lv))
            .collect();
        for (&s, volume) in chosen.iter().zip(moved) {
            snaps[stars[s].v] = stars[s].snap;
            snapped.push(Snapped {
                vertex: stars[s].v,
                volume,
            });
        }
        open.retain(|&s| snaps[stars[s].v] == SNAP_NONE);
        // A star's test reads only the states of its link's grid vertices, and links are
        // symmetric: only the stars around this round's snaps can change their answer.
        dirty = chosen
            .iter()
            .flat_map(|&s| stars[s].link.grid_nodes())
            .filter_map(|n| star_of.get(&n).copied())
            .filter(|&s| snaps[stars[s].v] == SNAP_NONE)
            .collect();
        dirty.sort_unstable();
        dirty.dedup();
    }
    snapped.sort_unstable_by_key(|s| s.vertex);
    Warp { snaps, snapped }
}

/// One round: the open stars that pass the test in the current state (`passes`) and have the
/// smallest `t` among the passing grid vertices of their link.
fn snap_round(stars: &[Star], open: &[usize], passes: &[bool]) -> Vec<usize> {
    let passing: Vec<usize> = open.iter().copied().filter(|&s| passes[s]).collect();
    let best: FxHashMap<usize, f64> = passing.iter().map(|&s| (stars[s].v, stars[s].t)).collect();
    passing
        .par_iter()
        .copied()
        .filter(|&s| {
            let (v, t) = (stars[s].v, stars[s].t);
            stars[s]
                .link
                .grid_nodes()
                .all(|n| best.get(&n).is_none_or(|&tn| (t, v) < (tn, n)))
        })
        .collect()
}

/// Whether value `u` lies on the domain side of level `snap` (ties count as outside).
fn domain_side(u: f64, snap: u8, lv: &Levels) -> bool {
    if snap == SNAP_ALPHA {
        u > lv.get(0)
    } else {
        u < lv.get(1)
    }
}

fn level_of(snap: u8, lv: &Levels) -> f64 {
    if snap == SNAP_ALPHA {
        lv.get(0)
    } else {
        lv.get(1)
    }
}

/// Offsets of the 26-neighbourhood as `[di, dj, dk]`.
fn neighbours26() -> impl Iterator<Item = [isize; 3]> {
    (0..27)
        .map(|n| [n % 3 - 1, (n / 3) % 3 - 1, n / 9 - 1])
        .filter(|d| *d != [0, 0, 0])
}

/// Grid index of the neighbour of interior vertex `(i, j, k)` at offset `d`.
fn neighbour(grid: &ScalarGrid, ijk: [usize; 3], d: [isize; 3]) -> usize {
    grid.index(
        (ijk[0] as isize + d[0]) as usize,
        (ijk[1] as isize + d[1]) as usize,
        (ijk[2] as isize + d[2]) as usize,
    )
}

/// Per grid vertex, the level it is a candidate for (step 1, on the 26-neighbourhood, which
/// holds every link vertex's value range: a superset of the close vertices). Only vertices
/// with a neighbour on the other side of a level are examined (found 64 at a time).
fn candidates(grid: &ScalarGrid, lv: &Levels, eps: f64) -> Vec<u8> {
    let [nx, ny, nz] = grid.dims;
    let mut cand = vec![SNAP_NONE; grid.num_vertices()];
    cand.par_chunks_mut(nx * ny)
        .enumerate()
        .filter(|(k, _)| *k > 0 && *k + 1 < nz)
        .for_each(|(k, plane)| {
            let sides = [k - 1, k, k + 1].map(|z| side_bits(grid, lv, z));
            let words = nx.div_ceil(64);
            for j in 1..ny - 1 {
                let mixed = mixed_row(&sides, j, words);
                for (w, &bits) in mixed.iter().enumerate() {
                    let mut b = bits;
                    while b != 0 {
                        let i = 64 * w + b.trailing_zeros() as usize;
                        b &= b - 1;
                        if i > 0 && i + 1 < nx {
                            plane[j * nx + i] = candidate_level(grid, lv, [i, j, k], eps);
                        }
                    }
                }
            }
        });
    cand
}

/// Side bits of grid plane `z` for both levels: `[alpha, beta][j * words + i / 64]` bit
/// `i % 64` set when vertex `(i, j)` lies on the domain side of that level.
fn side_bits(grid: &ScalarGrid, lv: &Levels, z: usize) -> [Vec<u64>; 2] {
    let [nx, ny, _] = grid.dims;
    let words = nx.div_ceil(64);
    let mut bits = [vec![0u64; ny * words], vec![0u64; ny * words]];
    let base = grid.index(0, 0, z);
    let (alpha, beta) = (lv.get(0), lv.get(1));
    for j in 0..ny {
        let [up, down] = &mut bits;
        let (up, down) = (&mut up[j * words..], &mut down[j * words..]);
        let row = base + j * nx..base + (j + 1) * nx;
        grid.values.for_each_in(row, |i, v| {
            up[i / 64] |= ((v > alpha) as u64) << (i % 64);
            down[i / 64] |= ((v < beta) as u64) << (i % 64);
        });
    }
    bits
}

/// Bits of the vertices of row `j` (middle plane) whose 26-neighbourhood has both sides of
/// some level.
fn mixed_row(sides: &[[Vec<u64>; 2]; 3], j: usize, words: usize) -> Vec<u64> {
    let mut mixed = vec![0u64; words];
    for level in 0..2 {
        let mut or9 = vec![0u64; words];
        let mut and9 = vec![u64::MAX; words];
        for plane in sides {
            for jj in j - 1..=j + 1 {
                let row = &plane[level][jj * words..(jj + 1) * words];
                for w in 0..words {
                    or9[w] |= row[w];
                    and9[w] &= row[w];
                }
            }
        }
        for w in 0..words {
            let spread = |x: &[u64], fill: u64| {
                let lo = if w > 0 { x[w - 1] >> 63 } else { fill & 1 };
                let hi = if w + 1 < words {
                    x[w + 1] << 63
                } else {
                    fill << 63
                };
                [x[w], (x[w] << 1) | lo, (x[w] >> 1) | hi]
            };
            let o = spread(&or9, 0);
            let a = spread(&and9, u64::MAX);
            mixed[w] |= (o[0] | o[1] | o[2]) & !(a[0] & a[1] & a[2]);
        }
    }
    mixed
}

fn candidate_level(grid: &ScalarGrid, lv: &Levels, ijk: [usize; 3], eps: f64) -> u8 {
    let f = grid.value(ijk[0], ijk[1], ijk[2]);
    let e = lv.effective(f);
    let mut found = SNAP_NONE;
    for snap in [SNAP_ALPHA, SNAP_BETA] {
        let level = level_of(snap, lv);
        if !level.is_finite() {
            continue;
        }
        let d = (e - level).abs();
        let side = domain_side(f, snap, lv);
        let close = neighbours26().any(|o| {
            let u = grid.values.get(neighbour(grid, ijk, o));
            domain_side(u, snap, lv) != side && d < eps * (u - e).abs()
        });
        if close {
            if found != SNAP_NONE {
                return SNAP_NONE;
            }
            found = snap;
        }
    }
    if found != SNAP_NONE && other_level_near(grid, lv, ijk, found) {
        return SNAP_NONE;
    }
    found
}

/// How close (index units, along an edge from the vertex) the other level of the interval may
/// pass a vertex that is snapped to one level: the quality pass's guard distance
/// (`field::GUARD_DISTANCE`), within which it leaves a thin layer as it is.
const THIN_LAYER: f64 = 0.4;

/// Whether the level other than `snap` crosses an edge from interior vertex `ijk` to one of
/// its 26 neighbours (a superset of its link) within [`THIN_LAYER`] of it, linearly along the
/// edge. Such a vertex lies in a layer thinner than the quality pass works in: snapping it
/// would move one side of the layer by a good part of the layer's thickness (the 3 %-of-std
/// band of a smooth random field, 24³: +0.50 % of the volume from warping alone, +0.25 %
/// without these snaps), and the pass, which leaves the layer's tets alone, could not give
/// that volume back.
fn other_level_near(grid: &ScalarGrid, lv: &Levels, ijk: [usize; 3], snap: u8) -> bool {
    let other = if snap == SNAP_ALPHA {
        SNAP_BETA
    } else {
        SNAP_ALPHA
    };
    let level = level_of(other, lv);
    if !level.is_finite() {
        return false;
    }
    let f = grid.value(ijk[0], ijk[1], ijk[2]);
    let (e, side) = (lv.effective(f), domain_side(f, other, lv));
    let d = (e - level).abs();
    neighbours26().any(|o| {
        let u = grid.values.get(neighbour(grid, ijk, o));
        let len = ((o[0] * o[0] + o[1] * o[1] + o[2] * o[2]) as f64).sqrt();
        domain_side(u, other, lv) != side && d * len < THIN_LAYER * (u - e).abs()
    })
}

/// Step 2: the link of candidate `v` (interior), from the decomposition of the cells
/// around it that are not entirely outside, in cell order.
fn star_link(grid: &ScalarGrid, planner: &Planner, v: usize, link: &mut Link) {
    let ijk = grid.vertex_ijk(v);
    let stride = [1, grid.dims[0], grid.dims[0] * grid.dims[1]];
    let mut tets = Vec::with_capacity(64);
    for corner in (0..8).rev() {
        // The cell in which `v` is corner `corner`.
        let o = corner_offset(corner);
        let c = [0, 1, 2].map(|a| ijk[a] - o[a]);
        let vals = grid.cell_values(c[0], c[1], c[2]);
        let plan = plan_cell(planner, c, &vals);
        if plan.layout == Layout::Outside {
            continue;
        }
        tets.clear();
        let (_, pts) = decompose_cell(&plan, &vals, &mut tets);
        let base = grid.index(c[0], c[1], c[2]);
        let base_f = c.map(|x| x as f64);
        let corner = corner as u8;
        for t in tets.iter().filter(|t| t.contains(&corner)) {
            let mut ids = [0usize; 3];
            for (slot, &x) in ids.iter_mut().zip(t.iter().filter(|&&x| x != corner)) {
                let p = pts.pos[x as usize];
                *slot = link.node(Node {
                    key: local_key(base, stride, x as usize),
                    pos: [base_f[0] + p[0], base_f[1] + p[1], base_f[2] + p[2]],
                    val: pts.val[x as usize],
                });
            }
            link.tris.push(ids);
        }
    }
}

/// A close candidate and its link.
struct Star {
    v: usize,
    snap: u8,
    /// Whether the vertex lies off the domain side of its level.
    from_down: bool,
    /// Fraction of its closest crossing.
    t: f64,
    link: Link,
}

impl Star {
    /// The star of candidate `v` (for level `snap`), if it is close
    /// (step 1 exactly, on the link).
    fn new(
        grid: &ScalarGrid,
        planner: &Planner,
        lv: &Levels,
        v: usize,
        snap: u8,
        eps: f64,
    ) -> Option<Star> {
        let mut link = Link::default();
        star_link(grid, planner, v, &mut link);
        link.add_outside_octants(grid, lv, v);
        let f = grid.values.get(v);
        let side = domain_side(f, snap, lv);
        let (e, level) = (lv.effective(f), level_of(snap, lv));
        let t = link
            .nodes
            .iter()
            .filter(|n| domain_side(n.val, snap, lv) != side)
            .map(|n| (e - level).abs() / (n.val - e).abs())
            .fold(f64::INFINITY, f64::min);
        let from_down = !side;
        link.centre_z = grid.vertex_ijk(v)[2] as f64;
        (t < eps).then_some(Star {
            v,
            snap,
            from_down,
            t,
            link,
        })
    }

    fn regular(&self, snaps: &[u8], lv: &Levels) -> bool {
        self.link.regular(self.snap, self.from_down, snaps, lv)
    }

    /// Whether the surface the snap leaves in the star, in state `snaps`, stays near the
    /// trilinear level sets: both levels' pieces in every tet of the star, with the centre on
    /// its level ([`TrilinearNear::tet_levels_near`]). The linear test of step 1 looks along
    /// one edge; the triangles from the snapped centre to the cuts on the far side of its link
    /// can span a pocket of the field and sag far from the level set, and the snap also moves
    /// the other level's cuts on the centre's edges. The quality pass moves a snapped vertex
    /// onto the level set, but not in a thin layer, which it leaves as it is: the snap itself
    /// must leave a surface that passes the checker.
    fn surface_near(
        &self,
        grid: &ScalarGrid,
        near: &TrilinearNear,
        snaps: &[u8],
        lv: &Levels,
    ) -> bool {
        let centre = grid.vertex_ijk(self.v).map(|c| c as f64);
        let level = level_of(self.snap, lv);
        let value = |n: &Node| match n.state(snaps) {
            SNAP_NONE => lv.effective(n.val),
            snap => level_of(snap, lv),
        };
        self.link.tris.iter().all(|t| {
            let [a, b, c] = t.map(|i| &self.link.nodes[i]);
            let p = [centre, a.pos, b.pos, c.pos];
            near.tet_levels_near(p, [level, value(a), value(b), value(c)], lv)
        })
    }

    /// The volume (index units) that snapping the centre adds to the interval volume of the
    /// piecewise-linear field in its star, in state `snaps` (snapped link nodes on their
    /// level): the interval volume of each tet of the star with the centre's value on the
    /// level, less that with its own value.
    fn snap_volume(&self, grid: &ScalarGrid, snaps: &[u8], lv: &Levels) -> f64 {
        let centre = grid.vertex_ijk(self.v).map(|c| c as f64);
        // The values the clipper cuts with (`clip::placed`): tied ones moved outward.
        let own = lv.effective(grid.values.get(self.v));
        let level = level_of(self.snap, lv);
        let value = |n: &Node| match n.state(snaps) {
            SNAP_NONE => lv.effective(n.val),
            snap => level_of(snap, lv),
        };
        self.link
            .tris
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| &self.link.nodes[i]);
                let p = [centre, a.pos, b.pos, c.pos];
                let f = |x: f64| [x, value(a), value(b), value(c)];
                interval_volume(p, f(level), lv.get(0), lv.get(1))
                    - interval_volume(p, f(own), lv.get(0), lv.get(1))
            })
            .sum()
    }
}

/// Class of a link node in the current state.
const UP: u8 = 0;
const ON: u8 = 1;
const DOWN: u8 = 2;

/// The link of one vertex: a triangulated 2-sphere, less the cells that lie entirely
/// outside the interval, which are kept as groups of nodes.
#[derive(Default)]
struct Link {
    nodes: Vec<Node>,
    tris: Vec<[usize; 3]>,
    /// Groups of nodes that lie in one outside cell (each all on one side, joined).
    groups: Vec<Vec<usize>>,
    /// The centre's z index (its grid plane).
    centre_z: f64,
}

impl Link {
    fn node(&mut self, n: Node) -> usize {
        match self.nodes.iter().position(|m| m.key == n.key) {
            Some(i) => i,
            None => {
                self.nodes.push(n);
                self.nodes.len() - 1
            }
        }
    }

    /// Grid indices of the grid-vertex nodes.
    fn grid_nodes(&self) -> impl Iterator<Item = usize> + '_ {
        self.nodes
            .iter()
            .filter(|n| key_kind(n.key) == CORNER)
            .map(|n| key_index(n.key))
    }

    /// Joins, for each of the eight cells around `v` that lies entirely outside the
    /// interval, its other corners and every link node in its closed box.
    fn add_outside_octants(&mut self, grid: &ScalarGrid, lv: &Levels, v: usize) {
        let ijk = grid.vertex_ijk(v);
        for corner in 0..8 {
            let o = corner_offset(corner);
            let cell = [0, 1, 2].map(|a| ijk[a] + o[a] - 1);
            let vals = grid.cell_values(cell[0], cell[1], cell[2]);
            let outside =
                vals.iter().all(|&x| x <= lv.get(0)) || vals.iter().all(|&x| x >= lv.get(1));
            if !outside {
                continue;
            }
            let lo = cell.map(|x| x as f64);
            let in_box = |p: [f64; 3]| (0..3).all(|a| p[a] >= lo[a] && p[a] <= lo[a] + 1.0);
            let mut group: Vec<usize> = (0..self.nodes.len())
                .filter(|&i| in_box(self.nodes[i].pos))
                .collect();
            for (c2, &val) in vals.iter().enumerate() {
                let o2 = corner_offset(c2);
                let p = [0, 1, 2].map(|a| cell[a] + o2[a]);
                let gi = grid.index(p[0], p[1], p[2]);
                if gi != v {
                    let pos = p.map(|x| x as f64);
                    let key = vertex_key(gi, CORNER);
                    group.push(self.node(Node { key, pos, val }));
                }
            }
            self.groups.push(group);
        }
    }

    /// Classes of the nodes for a snap to `snap` in state `snaps`: a node at, beyond or
    /// snapped to the interval's other level is up (on the domain side of `snap`).
    fn classes(&self, snap: u8, snaps: &[u8], lv: &Levels) -> Vec<u8> {
        self.nodes
            .iter()
            .map(|n| match n.state(snaps) {
                s if s == snap => ON,
                SNAP_NONE if !domain_side(n.val, snap, lv) => DOWN,
                _ => UP,
            })
            .collect()
    }

    /// Whether snapping the centre keeps the domain homeomorphic (module docs): the closed
    /// set `S` of the link where the field is at least the level (up nodes, and snapped
    /// nodes on the level) is a disk whose complement (down nodes) is connected.
    fn regular(&self, snap: u8, from_down: bool, snaps: &[u8], lv: &Levels) -> bool {
        let cls = self.classes(snap, snaps, lv);
        let groups_ok = self.groups.iter().all(|g| {
            let c = cls[g[0]];
            c != ON && g.iter().all(|&i| cls[i] == c)
        });
        groups_ok && self.on_nodes_ok(&cls, from_down) && self.sides_connected(&cls)
    }

    /// Every node on the level touches an up node, and its down neighbours form one run
    /// around it (`S` is then one wedge there, not a pinch: the level passes through the node,
    /// so every down neighbour cuts `S` apart around it; a neighbour on the level counts as on
    /// `S`'s side). A node whose neighbours are all up or on the level is inside `S`; that is
    /// allowed only when the centre comes from above (from below, the domain is a collar of
    /// `S` that must thin out only along `∂S`). Two nodes on the level may be joined only as
    /// [`Link::on_edge_ok`] allows.
    fn on_nodes_ok(&self, cls: &[u8], from_down: bool) -> bool {
        let up_side = |c: u8| c != DOWN;
        (0..self.nodes.len()).filter(|&z| cls[z] == ON).all(|z| {
            let (mut ups, mut mixed) = (0usize, 0usize);
            for t in self.tris.iter().filter(|t| t.contains(&z)) {
                let mut others = t.iter().copied().filter(|&x| x != z);
                let (a, b) = (others.next().unwrap_or(z), others.next().unwrap_or(z));
                for x in [a, b] {
                    if cls[x] == ON && !self.on_edge_ok(z, x, cls, from_down) {
                        return false;
                    }
                }
                ups += (cls[a] == UP) as usize + (cls[b] == UP) as usize;
                mixed += (up_side(cls[a]) != up_side(cls[b])) as usize;
            }
            ups > 0 && (mixed == 2 || (mixed == 0 && !from_down))
        })
    }

    /// Whether the link edge between the nodes `z` and `x`, both on the level, may stay: the
    /// face it makes with the centre will have three corners on the level. The third nodes of
    /// its two link triangles must be off the level (no tet with four corners on it) and not
    /// both down (the face would be a sheet of the level with the outside on both sides).
    /// With one up, the edge lies on `∂S` and the face is a boundary face of the domain; the
    /// clipper emits it from the flat piece of the tet on the down side
    /// (`clip::snapped_face`). With both up, the edge lies inside `S`, where the field touches
    /// the level from above: allowed only when the centre comes from above (from below, the
    /// collar of `S` would pinch along the edge). The face must not lie in a grid plane of
    /// constant z: the tets on both sides are then in the same layer of cells, so the
    /// streamed mesh keeps each boundary triangle in the chunk of its tet.
    fn on_edge_ok(&self, z: usize, x: usize, cls: &[u8], from_down: bool) -> bool {
        let in_plane = [z, x]
            .iter()
            .all(|&n| self.nodes[n].pos[2] == self.centre_z);
        if in_plane {
            return false;
        }
        // A link triangle without a third node cannot occur; counting it as on the level
        // refuses the edge.
        let mut thirds = self
            .tris
            .iter()
            .filter(|t| t.contains(&z) && t.contains(&x))
            .map(|t| {
                t.iter()
                    .find(|&&w| w != z && w != x)
                    .map_or(ON, |&w| cls[w])
            });
        let (Some(c1), Some(c2), None) = (thirds.next(), thirds.next(), thirds.next()) else {
            return false;
        };
        let ups = (c1 == UP) as usize + (c2 == UP) as usize;
        c1 != ON && c2 != ON && if from_down { ups == 1 } else { ups >= 1 }
    }

    /// Up and on nodes (joined by edges with an up end) form one connected set, down nodes
    /// (joined by down-down edges) another, both nonempty; outside cells join their nodes.
    fn sides_connected(&self, cls: &[u8]) -> bool {
        let side = |c: u8| (c == DOWN) as usize;
        let mut uf = UnionFind::new(self.nodes.len());
        for t in &self.tris {
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                let joined = match (cls[a], cls[b]) {
                    (DOWN, DOWN) => true,
                    (DOWN, _) | (_, DOWN) | (ON, ON) => false,
                    _ => true,
                };
                if joined {
                    uf.union(a as u32, b as u32);
                }
            }
        }
        for g in &self.groups {
            for &i in &g[1..] {
                uf.union(g[0] as u32, i as u32);
            }
        }
        let mut roots = [None, None];
        for i in 0..uf.len() {
            let r = uf.find(i as u32);
            match roots[side(cls[i])] {
                None => roots[side(cls[i])] = Some(r),
                Some(r0) if r0 != r => return false,
                _ => {}
            }
        }
        roots.iter().all(Option::is_some) && cls.contains(&UP)
    }
}

#[cfg(test)]
mod tests;
