//! Level-set distance: every boundary triangle labelled alpha or beta stays within a bound
//! (index units: voxels) of the trilinear level set it is labelled with, at sampled points of
//! the triangle; every box triangle lies on a face of the grid box.

use rayon::prelude::*;
use serde::Serialize;

use super::{ProblemKind, Problems};
use crate::field::Field;
use crate::grid::ScalarGrid;
use crate::levels::Levels;
use crate::mesh::{BoundaryLabel, TetMesh};

type P = [f64; 3];

/// What the level-set distances at the sampled points of the labelled triangles were.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct LevelSummary {
    /// The bound the distances were checked against (index units).
    pub bound: f64,
    /// Points sampled on alpha and beta triangles (corners once per level).
    pub points: usize,
    /// Largest distance (index units) from a sampled point to a point of its level found
    /// within the bound (an upper bound of the true distance at that point).
    pub max_distance: f64,
    /// Points with no point of their level found within the bound.
    pub beyond: usize,
    /// Largest distance found, by the walks out to four times the bound and the segments to
    /// the corners of the point's cell, from a point beyond the bound to its level (infinite
    /// when neither finds one; 0 when no point is beyond).
    pub max_beyond: f64,
    /// Points outside the grid box.
    pub outside: usize,
    /// Box triangles not on a face of the grid box.
    pub box_off: usize,
}

/// Steps per walk of the search along a direction.
const WALK_STEPS: usize = 10;
/// Bisections of the step of a walk that crosses the level.
const BISECTIONS: usize = 40;
/// Most subdivisions of a triangle edge.
const MAX_SUBDIVISION: usize = 64;
/// Lattice steps per bound of the ball search that backs up the walks.
const BALL_STEPS: i32 = 25;

/// Where a point stands against its level.
#[derive(Clone, Copy)]
enum Found {
    /// A point of the level within the bound, at this distance.
    Within(f64),
    /// None found within the bound; the distance found by the walks within four times the
    /// bound or to the cell's corners (infinite if none).
    Beyond(f64),
    /// The point is outside the grid box.
    Outside,
}

struct Search<'a> {
    field: Field<'a>,
    hi: [f64; 3],
    eps: f64,
    bound: f64,
    /// The bound and the rounding of positions (`eps`): a point whose level lies exactly at
    /// the bound, its coordinates a few ulps or a solver's tolerance off, is within it.
    reach: f64,
    tol: f64,
    dirs: Vec<P>,
    /// Offsets of a lattice filling the ball of radius `bound`, nearest first.
    ball: Vec<(f64, P)>,
}

impl<'a> Search<'a> {
    /// The search on `grid` out to `bound` (index units).
    fn new(grid: &'a ScalarGrid, bound: f64) -> Self {
        let field = Field::new(grid);
        let hi = grid.dims.map(|d| (d - 1) as f64);
        let (lo_v, hi_v) = grid.value_range();
        let scale = lo_v.abs().max(hi_v.abs()).max(f64::MIN_POSITIVE);
        let eps = 1e-9 * hi.iter().fold(1.0, |a: f64, &b| a.max(b));
        Search {
            field,
            hi,
            eps,
            bound,
            reach: bound + eps,
            tol: 1e-12 * scale,
            dirs: lattice_directions(),
            ball: ball_lattice(bound),
        }
    }
}

impl Search<'_> {
    fn inside(&self, u: P) -> bool {
        (0..3).all(|k| u[k] >= -self.eps && u[k] <= self.hi[k] + self.eps)
    }

    fn clamp(&self, u: P) -> P {
        [0, 1, 2].map(|k| u[k].clamp(0.0, self.hi[k]))
    }

    /// The distance from `u` (index space) to the level set `f = level`, if within the bound
    /// (a distance beyond it by no more than the rounding `eps` counts as the bound).
    fn distance(&self, u: P, level: f64) -> Found {
        if !level.is_finite() {
            return Found::Beyond(f64::INFINITY);
        }
        if !self.inside(u) {
            return Found::Outside;
        }
        let u = self.clamp(u);
        match self
            .search(u, level, self.bound)
            .or_else(|| self.corner_search(u, level, self.bound))
            .or_else(|| self.ball_search(u, level))
            .or_else(|| self.axis_search(u, level, self.reach))
        {
            Some(d) => Found::Within(d.min(self.bound)),
            None => Found::Beyond(self.far(u, level)),
        }
    }

    /// The least distance found from `u` (in the box) to `level` by the projection, the
    /// walks and the axis lines within four times the bound, and the segments to the corners
    /// of its cell (infinite if none).
    fn far(&self, u: P, level: f64) -> f64 {
        let far = 4.0 * self.bound;
        let Some(side) = self.side(u, level) else {
            return 0.0;
        };
        (self.projected(u, level).filter(|&d| d <= far))
            .into_iter()
            .chain(self.walks(u, level, side, far))
            .chain(self.axis_search(u, level, far))
            .chain(self.corner_search(u, level, f64::INFINITY))
            .min_by(f64::total_cmp)
            .unwrap_or(f64::INFINITY)
    }

    /// The side of `level` that `u` is on (`None`: on it).
    fn side(&self, u: P, level: f64) -> Option<f64> {
        let r0 = self.field.value(u) - level;
        (r0 != 0.0).then(|| r0.signum())
    }

    /// The distance from `u` to a point of `level` found within `bound` (and the rounding
    /// `eps` past it): Newton's projection, else the walks.
    fn search(&self, u: P, level: f64, bound: f64) -> Option<f64> {
        let Some(side) = self.side(u, level) else {
            return Some(0.0);
        };
        if let Some(d) = self.projected(u, level).filter(|&d| d <= bound + self.eps) {
            return Some(d);
        }
        self.walks(u, level, side, bound)
    }

    /// The distance from `u` to its projection on `level` by Newton's method, if it converges.
    fn projected(&self, u: P, level: f64) -> Option<f64> {
        let dist = |p: P| ((0..3).map(|k| (p[k] - u[k]).powi(2)).sum::<f64>()).sqrt();
        (self.field.project(u, level, 0b111, self.tol)).map(dist)
    }

    /// The least distance from `u`, on `side` of `level`, to a crossing of it found by the
    /// walks down the gradient and along the lattice directions within `bound`.
    fn walks(&self, u: P, level: f64, side: f64, bound: f64) -> Option<f64> {
        let g = self.field.value_gradient(u).1;
        let gn = g.iter().map(|x| x * x).sum::<f64>().sqrt();
        let down = (gn > 0.0 && gn.is_finite()).then(|| g.map(|x| -side * x / gn));
        down.iter()
            .chain(&self.dirs)
            .filter_map(|&d| self.walk(u, d, level, side, bound))
            .min_by(f64::total_cmp)
    }

    /// The distance from `u` to the first crossing of `level` on the six axis lines through
    /// it within `bound` (and the rounding `eps` past it), exact up to the bisection: along
    /// an axis the trilinear field is linear between the grid planes, so a crossing shows at
    /// a plane or at the end even where the level set only touches the line (integer data
    /// tied with a level puts it on grid faces and edges, where the walks' steps miss it).
    fn axis_search(&self, u: P, level: f64, bound: f64) -> Option<f64> {
        let side = self.side(u, level)?;
        let reach = bound + self.eps;
        let crossed = |p: P| (self.field.value(p) - level) * side <= 0.0;
        (0..6)
            .filter_map(|a| {
                let (k, s) = (a / 2, if a % 2 == 0 { -1.0 } else { 1.0 });
                let end = u[k] + s * reach;
                let at = |t: f64| -> P {
                    let mut p = u;
                    p[k] = u[k] + s * t;
                    p
                };
                // The planes strictly between u and the end, within the box, then the end
                // (the boundary cells' polynomials extended past the box).
                let planes = {
                    let (lo, hi) = (u[k].min(end), u[k].max(end));
                    let first = lo.floor() as i64 + 1;
                    let last = (hi.ceil() as i64 - 1).min(self.hi[k] as i64);
                    (first.max(0)..=last)
                        .map(|m| m as f64)
                        .filter(|&m| m != u[k])
                };
                let mut stops: Vec<(f64, P)> = planes
                    .map(|m| {
                        let mut p = u;
                        p[k] = m;
                        ((m - u[k]).abs(), p)
                    })
                    .collect();
                stops.sort_by(|x, y| x.0.total_cmp(&y.0));
                stops.push((reach, at(reach)));
                let mut prev = 0.0;
                for (t, p) in stops {
                    if crossed(p) {
                        let on_line = |t: f64| crossed(at(t));
                        return Some(first_crossed(on_line, prev, t));
                    }
                    prev = t;
                }
                None
            })
            .min_by(f64::total_cmp)
    }

    /// The distance from `u` to a crossing of `level` on a segment from `u` to a corner of its
    /// cell on the other side of it (bisected), if within the bound: catches the pockets
    /// around a grid vertex smaller than the walks' and the ball's steps (a vertex of value
    /// 181 among smaller ones puts `f = 180.7` a few hundredths of a voxel around it, where
    /// the gradient has a kink and Newton's projection fails).
    fn corner_search(&self, u: P, level: f64, bound: f64) -> Option<f64> {
        let side = (self.field.value(u) - level).signum();
        let cell = [0, 1, 2].map(|k| u[k].floor().clamp(0.0, (self.hi[k] - 1.0).max(0.0)));
        (0..8)
            .filter_map(|c| {
                let q: P = [0, 1, 2].map(|k| (cell[k] + (c >> k & 1) as f64).min(self.hi[k]));
                let d = [0, 1, 2].map(|k| q[k] - u[k]);
                let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                let at = |t: f64| -> P { [0, 1, 2].map(|k| u[k] + t * d[k]) };
                let crossed = |t: f64| (self.field.value(at(t)) - level) * side <= 0.0;
                if len == 0.0 || !crossed(1.0) {
                    return None;
                }
                Some(first_crossed(crossed, 0.0, 1.0) * len)
            })
            .filter(|&r| r <= bound)
            .min_by(f64::total_cmp)
    }

    /// The distance from `u` to the nearest lattice point of the ball of radius `bound` on
    /// the other side of `level` (or on it): the segment to it meets the level, so this is an
    /// upper bound of the distance. Catches the thin pockets of the level set the walks miss;
    /// pockets thinner than the lattice step (`bound / BALL_STEPS`) can still be missed.
    fn ball_search(&self, u: P, level: f64) -> Option<f64> {
        let side = (self.field.value(u) - level).signum();
        self.ball.iter().find_map(|&(r, o)| {
            let q = [0, 1, 2].map(|k| u[k] + o[k]);
            (self.inside(q) && (self.field.value(self.clamp(q)) - level) * side <= 0.0).then_some(r)
        })
    }

    /// The distance along unit direction `d` from `u` to the first crossing of `level`
    /// within the bound. Near the box the walk may leave it, on the trilinear polynomials of
    /// the boundary cells extended (the level set of a cell does not end at the box).
    fn walk(&self, u: P, d: P, level: f64, side: f64, bound: f64) -> Option<f64> {
        let at = |t: f64| -> P { [0, 1, 2].map(|k| u[k] + t * d[k]) };
        let crossed = |t: f64| (self.field.value(at(t)) - level) * side <= 0.0;
        let h = bound / WALK_STEPS as f64;
        let mut prev = 0.0;
        // The steps, then one more at the rounding `eps` past the bound.
        let steps = (1..=WALK_STEPS).map(|s| h * s as f64);
        for t in steps.chain([bound + self.eps]) {
            if crossed(t) {
                return Some(first_crossed(crossed, prev, t));
            }
            prev = t;
        }
        None
    }
}

/// Bisects `[a, b]` (`crossed(b)` holds, `crossed(a)` does not) [`BISECTIONS`] times and
/// returns the end that has crossed.
fn first_crossed(crossed: impl Fn(f64) -> bool, mut a: f64, mut b: f64) -> f64 {
    for _ in 0..BISECTIONS {
        let m = 0.5 * (a + b);
        if crossed(m) {
            b = m;
        } else {
            a = m;
        }
    }
    b
}

/// The 26 lattice directions, normalised.
fn lattice_directions() -> Vec<P> {
    (0..27usize)
        .filter(|&c| c != 13)
        .map(|c| {
            let d = [c % 3, c / 3 % 3, c / 9].map(|k| k as f64 - 1.0);
            let n = d.iter().map(|x| x * x).sum::<f64>().sqrt();
            d.map(|x| x / n)
        })
        .collect()
}

/// The offsets of the cubic lattice of step `bound / BALL_STEPS` within distance `bound`,
/// with their lengths, nearest first.
fn ball_lattice(bound: f64) -> Vec<(f64, P)> {
    let h = bound / BALL_STEPS as f64;
    let n = BALL_STEPS;
    let mut out: Vec<(f64, P)> = (-n..=n)
        .flat_map(|i| (-n..=n).flat_map(move |j| (-n..=n).map(move |k| [i, j, k])))
        .map(|c| {
            let o = c.map(|x| x as f64 * h);
            ((o[0] * o[0] + o[1] * o[1] + o[2] * o[2]).sqrt(), o)
        })
        .filter(|&(r, _)| r > 0.0 && r <= bound)
        .collect();
    out.sort_by(|a, b| a.0.total_cmp(&b.0));
    out
}

/// Barycentric sample points of a triangle with corners `u` (index space), corners excluded:
/// edge midpoints and the centroid, and for an edge longer than `bound` the points of a
/// barycentric lattice fine enough that neighbours are at most `bound` apart.
fn samples(u: &[P; 3], bound: f64) -> Vec<P> {
    let len = |a: P, b: P| ((0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>()).sqrt();
    let longest = (0..3)
        .map(|k| len(u[k], u[(k + 1) % 3]))
        .fold(0.0, f64::max);
    let n = ((longest / bound).ceil() as usize).clamp(2, MAX_SUBDIVISION);
    let mut out = Vec::new();
    let point =
        |w: [f64; 3]| -> P { [0, 1, 2].map(|k| w[0] * u[0][k] + w[1] * u[1][k] + w[2] * u[2][k]) };
    for i in 0..=n {
        for j in 0..=n - i {
            let k = n - i - j;
            if i == n || j == n || k == n {
                continue; // a corner
            }
            out.push(point([i, j, k].map(|x| x as f64 / n as f64)));
        }
    }
    if !n.is_multiple_of(3) {
        out.push(point([1.0 / 3.0; 3]));
    }
    out
}

/// Checks the labelled triangles of `mesh` (boundary and interfaces), with its points at
/// `points`, against `grid` and the `levels`.
pub(crate) fn level_distance(
    (mesh, points): (&TetMesh, &[[f64; 3]]),
    grid: &ScalarGrid,
    levels: &Levels,
    bound: f64,
    problems: &mut Problems,
) -> LevelSummary {
    let search = Search::new(grid, bound);
    let to_index = |v: u32| search.field.to_index(points[v as usize]);
    let corners = Corners::new(mesh, &search, &to_index, levels);
    let per_tri: Vec<Tri> = labelled(mesh)
        .map(|(t, &label)| triangle(t, label, &search, &to_index, &corners, levels))
        .collect();
    summarize(bound, &corners, &per_tri, problems)
}

/// The labelled triangles: the boundary's, then the interfaces between regions (numbered on
/// after the boundary's in the problems' ids).
fn labelled(mesh: &TetMesh) -> impl IndexedParallelIterator<Item = (&[u32; 3], &BoundaryLabel)> {
    let r = &mesh.regions;
    (mesh.boundary.par_iter().zip(&mesh.boundary_labels))
        .chain(r.interfaces.par_iter().zip(&r.interface_labels))
}

/// The level a triangle's label stands for (`None`: a box triangle).
fn level_of(label: BoundaryLabel, levels: &Levels) -> Option<f64> {
    label.level().map(|i| levels.get(i))
}

/// The corners of the labelled triangles, searched once per (vertex, level).
struct Corners {
    /// (vertex, label as `u8`), sorted, each once.
    list: Vec<(u32, u8)>,
    /// What the search found for each entry of `list`.
    found: Vec<Found>,
}

impl Corners {
    /// Collects the corners of the alpha and beta triangles and searches from each.
    fn new(
        mesh: &TetMesh,
        search: &Search,
        to_index: &(impl Fn(u32) -> P + Sync),
        levels: &Levels,
    ) -> Self {
        let mut list: Vec<(u32, u8)> = labelled(mesh)
            .filter(|(_, &l)| l != BoundaryLabel::Box)
            .flat_map_iter(|(t, &l)| t.iter().map(move |&v| (v, l.index() as u8)))
            .collect();
        list.par_sort_unstable();
        list.dedup();
        let level_for = |l: u8| levels.get(l as usize);
        let found: Vec<Found> = list
            .par_iter()
            .map(|&(v, l)| search.distance(to_index(v), level_for(l)))
            .collect();
        Corners { list, found }
    }

    /// What was found for vertex `v` on the level labelled `l`.
    fn at(&self, v: u32, l: u8) -> Found {
        let i = self.list.partition_point(|&c| c < (v, l));
        self.found[i]
    }
}

/// One labelled triangle `t`: its sampled points searched, its corners looked up in
/// `corners`; a box triangle only checked to lie on the grid box.
fn triangle(
    t: &[u32; 3],
    label: BoundaryLabel,
    search: &Search,
    to_index: &impl Fn(u32) -> P,
    corners: &Corners,
    levels: &Levels,
) -> Tri {
    let u = t.map(to_index);
    let mut acc = Tri::default();
    let Some(level) = level_of(label, levels) else {
        acc.off_box = !on_box(&u, search.hi, search.eps * 100.0);
        return acc;
    };
    let inner = samples(&u, search.bound);
    acc.points = inner.len();
    for &p in &inner {
        match search.distance(p, level) {
            Found::Within(d) => acc.max_distance = acc.max_distance.max(d),
            Found::Beyond(d) => {
                acc.beyond += 1;
                acc.max_beyond = acc.max_beyond.max(d);
            }
            Found::Outside => acc.outside += 1,
        }
    }
    for &v in t {
        match corners.at(v, label.index() as u8) {
            Found::Within(d) => acc.max_distance = acc.max_distance.max(d),
            Found::Beyond(d) => {
                acc.corner_beyond = true;
                acc.max_beyond = acc.max_beyond.max(d);
            }
            Found::Outside => acc.corner_outside = true,
        }
    }
    acc
}

/// Sums the corners and the triangles into the summary and reports the triangles off their
/// level, outside the grid or off the box, in triangle order.
fn summarize(
    bound: f64,
    corners: &Corners,
    per_tri: &[Tri],
    problems: &mut Problems,
) -> LevelSummary {
    let mut s = LevelSummary {
        bound,
        points: corners.list.len(),
        ..LevelSummary::default()
    };
    for f in &corners.found {
        match f {
            Found::Beyond(_) => s.beyond += 1,
            Found::Outside => s.outside += 1,
            Found::Within(_) => {}
        }
    }
    for (i, t) in per_tri.iter().enumerate() {
        s.points += t.points;
        s.max_distance = s.max_distance.max(t.max_distance);
        s.beyond += t.beyond;
        s.max_beyond = s.max_beyond.max(t.max_beyond);
        s.outside += t.outside;
        if t.outside > 0 || t.corner_outside {
            problems.add(ProblemKind::OutsideGrid, vec![i]);
        } else if t.beyond > 0 || t.corner_beyond {
            problems.add(ProblemKind::OffLevel, vec![i]);
        }
        if t.off_box {
            s.box_off += 1;
            problems.add(ProblemKind::BoxTriangleOffBox, vec![i]);
        }
    }
    s
}

/// One labelled triangle's sampled points (corners counted per vertex instead).
#[derive(Default)]
struct Tri {
    points: usize,
    max_distance: f64,
    beyond: usize,
    max_beyond: f64,
    outside: usize,
    corner_beyond: bool,
    corner_outside: bool,
    off_box: bool,
}

/// Whether all corners `u` (index space) lie on one face of the grid box `[0, hi]`.
fn on_box(u: &[P; 3], hi: [f64; 3], eps: f64) -> bool {
    (0..3).any(|k| {
        u.iter().all(|p| p[k].abs() <= eps) || u.iter().all(|p| (p[k] - hi[k]).abs() <= eps)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `n³` grid of seeded white noise in [0, 1).
    fn noise(n: usize, mut seed: u64) -> ScalarGrid {
        let values: Vec<f64> = (0..n * n * n)
            .map(|_| {
                seed = seed
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (seed >> 11) as f64 / (1u64 << 53) as f64
            })
            .collect();
        ScalarGrid::new([n; 3], values).unwrap()
    }

    /// The distance from `u` to the nearest lattice point of step `h` in the ball of radius
    /// `r` on the other side of `level`, by brute force.
    fn brute(field: &Field, hi: P, u: P, level: f64, r: f64, h: f64) -> f64 {
        let side = (field.value(u) - level).signum();
        let n = (r / h).ceil() as i32;
        let mut best = f64::INFINITY;
        for i in -n..=n {
            for j in -n..=n {
                for k in -n..=n {
                    let o = [i, j, k].map(|x| x as f64 * h);
                    let d = (o[0] * o[0] + o[1] * o[1] + o[2] * o[2]).sqrt();
                    let q = [0, 1, 2].map(|a| u[a] + o[a]);
                    let inside = (0..3).all(|a| q[a] >= 0.0 && q[a] <= hi[a]);
                    if d <= r && d < best && inside && (field.value(q) - level) * side <= 0.0 {
                        best = d;
                    }
                }
            }
        }
        best
    }

    /// A point whose level set is exactly the bound away, up to rounding, is within it, and
    /// the far search reports that distance, not the corner's. Integer data tied with level 1
    /// (the rounded bumps of `tests/regions.rs`): on the face z = 8 the values are 1, 1, 2, 1
    /// at (x, y) = (1, 8), (1, 9), (2, 8), (2, 9), at z = 9 all 1, so around (1.5, 8.5, 8) the
    /// field is 1 + (x − 1)(9 − y)(9 − z) and equals 1 on the planes x = 1 and y = 9, 0.5
    /// voxel away, and beyond them drops below 1. The second point is the midpoint of a
    /// boundary edge the quality pass left there (its corners 2.5e-10 voxel off the grid
    /// vertices): 0.5 + 1.2e-10 from y = 9.
    #[test]
    fn a_level_exactly_at_the_bound_is_within_it() {
        let dims = [13, 11, 12];
        let mut values = Vec::with_capacity(dims[0] * dims[1] * dims[2]);
        for k in 0..dims[2] {
            for j in 0..dims[1] {
                for i in 0..dims[0] {
                    let [x, y, z] = [i, j, k].map(|a| a as f64);
                    let b = |cx: f64, cy: f64, cz: f64, w: f64| {
                        (-((x - cx).powi(2) + (y - cy).powi(2) + (z - cz).powi(2)) / (w * w)).exp()
                    };
                    values
                        .push((9.0 * b(4.0, 5.0, 6.0, 3.5) + 7.0 * b(9.0, 5.5, 5.0, 3.0)).round());
                }
            }
        }
        let grid = ScalarGrid::new(dims, values).unwrap();
        let face: Vec<f64> = [(1, 8, 8), (1, 9, 8), (2, 8, 8), (2, 9, 8)]
            .iter()
            .chain(&[(1, 8, 9), (1, 9, 9), (2, 8, 9), (2, 9, 9)])
            .map(|&(i, j, k)| grid.value(i, j, k))
            .collect();
        assert_eq!(face, [1.0, 1.0, 2.0, 1.0, 1.0, 1.0, 1.0, 1.0]);
        let search = Search::new(&grid, 0.5);
        let a = [1.9995002501241896, 8.999999999750624, 8.000000748502247];
        let b = [1.000999000999001, 8.0, 8.0];
        let midpoint = [0, 1, 2].map(|k| 0.5 * a[k] + 0.5 * b[k]);
        for u in [midpoint, [1.5, 8.5, 8.0]] {
            match search.distance(u, 1.0) {
                Found::Within(d) => assert!((d - 0.5).abs() < 1e-6, "{u:?}: {d}"),
                Found::Beyond(d) => panic!("{u:?}: beyond, {d} off"),
                Found::Outside => panic!("{u:?}: outside"),
            }
            let far = search.far(u, 1.0);
            assert!((far - 0.5).abs() < 1e-6, "{u:?}: far search {far}");
        }
        // A thousandth of a voxel farther from both planes is beyond the bound, and the far
        // search says by how much.
        let u = [1.501, 8.499, 8.0];
        match search.distance(u, 1.0) {
            Found::Beyond(d) => assert!((d - 0.501).abs() < 1e-6, "{u:?}: {d}"),
            _ => panic!("{u:?}: not beyond"),
        }
    }

    /// Where the level set comes within the bound only through a thin pocket off the walks'
    /// directions, the search still finds it: no point the brute force puts well within the
    /// bound is reported beyond it. White noise has such pockets around its saddles.
    #[test]
    fn the_search_finds_every_level_well_within_the_bound() {
        let bound = 0.5;
        let mut missed_by_walks = 0;
        for seed in 0..6u64 {
            let grid = noise(6, seed);
            let field = Field::new(&grid);
            let hi = [5.0; 3];
            let search = Search {
                field: Field::new(&grid),
                hi,
                eps: 1e-9,
                bound,
                reach: bound + 1e-9,
                tol: 1e-12,
                dirs: lattice_directions(),
                ball: ball_lattice(bound),
            };
            let mut s = seed.wrapping_mul(0x9E3779B97F4A7C15) | 1;
            let mut next = || {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                (s >> 11) as f64 / (1u64 << 53) as f64
            };
            for _ in 0..150 {
                let u = [0, 1, 2].map(|_| 0.5 + 4.0 * next());
                let level = 0.3 + 0.4 * next();
                let d = brute(&field, hi, u, level, bound, bound / 20.0);
                if d > bound - 2.0 * bound / BALL_STEPS as f64 {
                    continue;
                }
                if search.search(u, level, bound).is_none() {
                    missed_by_walks += 1;
                }
                assert!(
                    matches!(search.distance(u, level), Found::Within(_)),
                    "seed {seed}: {u:?} at level {level} is {d} from it"
                );
            }
        }
        assert!(missed_by_walks > 0, "no case where the walks alone miss");
    }
}
