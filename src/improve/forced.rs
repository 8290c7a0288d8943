//! Domain-forced bad elements: after the quality pass, every tet whose smallest dihedral angle
//! is below a floor is given a reason.
//!
//! * `near_critical`: a critical point of the trilinear field (a critical grid vertex, or a
//!   face or body saddle) in a cell the tet touches has a value `s` near alpha or beta: either
//!   `|s − level|` is within the tolerance (relative to the data range, as `--critical-tol`),
//!   or the neck (or gap) the level set makes there is narrower than the tet can span above the
//!   floor. The neck's width `w` is measured: along each of the 13 lattice directions through
//!   the critical point, the distance between the first crossings of the level on either side
//!   (the smallest; an upper bound of the true width). Where no direction crosses on both
//!   sides within 2 voxels, the quadratic estimate `w = 2·sqrt(δ / k)` (`δ = |s − level|`, `k`
//!   the Hessian magnitude) stands in. (At a critical *grid vertex* the field is only piecewise
//!   smooth and grows linearly away from it, so the estimate there can be several times too
//!   wide.) A tet whose longest edge `L` crosses the neck has a dihedral angle of about `w / L`
//!   there, so with no vertex insertion the floor cannot hold when `w < L · floor` (radians).
//! * `thin_layer`: the domain between the alpha and beta level sets is thinner at the tet than
//!   `L · floor` (`L` its longest edge), or than both `L · sin(min_angle)` and the embedding
//!   guard's distance (where the pass leaves such tets alone, `thin.rs`). The thickness `h` is the smaller of the shortest
//!   distance between a corner on alpha and one on beta (a bound: that segment crosses the
//!   layer) and the shortest chord of the layer through the centroid, measured along the
//!   gradient there and the 13 lattice directions (exact across a flat layer, an upper bound
//!   across a curved one; where the centroid lies outside the interval, the first-order
//!   `(beta − alpha) / |∇f|` there). A tet inside a layer of thickness `h` with extent `L`
//!   along it has a dihedral angle of about `h / L`, and the pass adds no vertices, so it
//!   cannot make `L` smaller than the boundary's own spacing. That angle is the estimate; the
//!   thickness is measured, and both numbers are in the report.
//! * `box_angle`: the tet has an edge (or a face) on a grid box plane and one on a level set,
//!   and the level set meets the box at an interior dihedral angle below the floor at the tet.
//! * `grid_mapping` (curvilinear grids only): the tet is above the floor in the grid's
//!   parameter space, where the pass works and the reasons above are found, and the grid's
//!   geometry map flattens it ([`classify_forced_mapped`]).
//! * `unexplained`: none of these; the pass failed there.

use rayon::prelude::*;

pub use crate::pass_report::{ForcedCounts, ForcedElement, ForcedReason, ForcedReport};

use super::outcome::PointMap;
use super::QualityOptions;
use crate::algebra::{array3, vector3};
use crate::critical::find::vertex_class;
use crate::field::Field;
use crate::field::GUARD_DISTANCE;
use crate::geom::{distance, dot, norm};
use crate::grid::{corner_offset, ScalarGrid};
use crate::levels::Levels;
use crate::mesh::{BoundaryLabel, LabelBits, TetMesh};
use crate::quality::{cosine_extremes, tet_dihedral_range};
use crate::trilinear::{body_saddles, coefficients, face_point, face_saddle, hessian};

/// How far (voxels) [`Classifier::measured_width`] looks on either side of a critical point.
const WIDTH_REACH: f64 = 2.0;
/// Its sampling step (voxels); crossings are then refined by bisection.
const WIDTH_STEP: f64 = 0.01;
/// The 13 lattice directions: the axes, the face diagonals and the body diagonals.
const LATTICE_DIRECTIONS: [[f64; 3]; 13] = [
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
    [1.0, 1.0, 0.0],
    [1.0, -1.0, 0.0],
    [1.0, 0.0, 1.0],
    [1.0, 0.0, -1.0],
    [0.0, 1.0, 1.0],
    [0.0, 1.0, -1.0],
    [1.0, 1.0, 1.0],
    [1.0, 1.0, -1.0],
    [1.0, -1.0, 1.0],
    [-1.0, 1.0, 1.0],
];

/// Everything the classification of one tet needs.
struct Classifier<'a> {
    mesh: &'a TetMesh,
    field: Field<'a>,
    levels: Levels,
    range: f64,
    /// The floor, radians.
    floor: f64,
    /// The sine of the pass's smallest target angle ([`QualityOptions::min_angle`]).
    target_sine: f64,
    tol: f64,
    /// Per point: the labels of the boundary triangles (and interfaces) around it
    /// ([`TetMesh::vertex_label_bits`]).
    labels: &'a [LabelBits],
    /// The index in the run of `levels`' first level (the tet's region's; 0 for one
    /// interval).
    first: u32,
}

/// Classifies every tet of `mesh` (a mesh of `{alpha <= f <= beta}` of `grid`, in the grid's
/// physical coordinates, level vertices carrying their level as value) whose smallest
/// dihedral angle is below `opts.forced_floor`.
pub fn classify_forced(
    mesh: &TetMesh,
    grid: &ScalarGrid,
    alpha: f64,
    beta: f64,
    opts: &QualityOptions,
) -> ForcedReport {
    classify_forced_mapped(mesh, grid, &Levels::interval(alpha, beta), opts, None)
}

/// [`classify_forced`] for a mesh made in a curvilinear grid's parameter space (`grid` its
/// values), whose tets are measured after `map` (the grid's geometry map; `None`: as they
/// are): a tet below the floor after `map` but not before it is [`ForcedReason::GridMapping`];
/// the others get their reasons in parameter space. Positions are given after `map`.
///
/// With several regions (`levels` the run's), each tet is classified in its region's
/// interval.
pub fn classify_forced_mapped(
    mesh: &TetMesh,
    grid: &ScalarGrid,
    levels: &Levels,
    opts: &QualityOptions,
    map: Option<PointMap>,
) -> ForcedReport {
    let floor = opts.forced_floor;
    let (lo, hi) = grid.value_range();
    let labels = mesh.vertex_label_bits();
    let classifiers: Vec<Classifier> = (0..levels.regions())
        .map(|r| Classifier {
            mesh,
            field: Field::new(grid),
            levels: Levels::interval(levels[r], levels[r + 1]),
            range: (hi - lo).max(f64::MIN_POSITIVE),
            floor: floor.to_radians(),
            target_sine: opts.min_angle.to_radians().sin(),
            tol: opts.forced_critical_tol,
            labels: &labels,
            first: r as u32,
        })
        .collect();
    let of = |t: usize| {
        let r = mesh.regions.tets.get(t).copied().unwrap_or(0);
        &classifiers[r as usize]
    };
    // A smallest angle whose cosine is below this is not below the floor, whatever `acos`
    // rounds to.
    let clear_of_floor = floor.to_radians().cos() - 1e-9;
    // The reasons of all, cheaply; the details only for the listed ones.
    let mut below: Vec<(f64, f64, usize, ForcedReason)> = (0..mesh.tets.len())
        .into_par_iter()
        .filter_map(|t| {
            let p = tet_points(mesh, t);
            let q = map.map_or(p, |m| p.map(m));
            // Most tets are far above the floor: their largest cosine tells, without `acos`.
            if cosine_extremes(q).0 < clear_of_floor {
                return None;
            }
            let (lo, hi) = tet_dihedral_range(q);
            if lo >= floor {
                return None;
            }
            let flattened = map.is_some() && tet_dihedral_range(p).0 >= floor;
            let reason = if flattened {
                ForcedReason::GridMapping
            } else {
                of(t).reason(t)
            };
            Some((lo, hi, t, reason))
        })
        .collect();
    let mut counts = ForcedCounts::default();
    for &(_, _, _, reason) in &below {
        *match reason {
            ForcedReason::NearCritical => &mut counts.near_critical,
            ForcedReason::ThinLayer => &mut counts.thin_layer,
            ForcedReason::BoxAngle => &mut counts.box_angle,
            ForcedReason::GridMapping => &mut counts.grid_mapping,
            ForcedReason::Unexplained => &mut counts.unexplained,
        } += 1;
    }
    below.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.2.cmp(&b.2)));
    below.truncate(opts.forced_list_cap);
    let elements = below
        .into_par_iter()
        .map(|(lo, hi, t, reason)| {
            let mut e = of(t).details(t, lo, hi, reason);
            if let Some(m) = map {
                let q = tet_points(mesh, t).map(m);
                e.point = [0, 1, 2].map(|a| q.iter().map(|x| x[a]).sum::<f64>() / 4.0);
            }
            e
        })
        .collect();
    ForcedReport {
        floor_degrees: floor,
        critical_tolerance: opts.forced_critical_tol,
        counts,
        elements,
    }
}

/// [`LATTICE_DIRECTIONS`] as unit vectors.
fn unit_lattice_directions() -> impl Iterator<Item = [f64; 3]> {
    LATTICE_DIRECTIONS.into_iter().map(|d| {
        let n = norm(d);
        d.map(|x| x / n)
    })
}

/// The longest edge of a tet with corners `p`.
fn longest_edge(p: &[[f64; 3]; 4]) -> f64 {
    (0..4)
        .flat_map(|i| (i + 1..4).map(move |j| (i, j)))
        .map(|(i, j)| distance(p[i], p[j]))
        .fold(0.0, f64::max)
}

fn tet_points(mesh: &TetMesh, t: usize) -> [[f64; 3]; 4] {
    mesh.tets[t].map(|v| mesh.points[v as usize])
}

/// Magnitude `sqrt(Fxy² + Fyz² + Fxz²)` of the Hessian (zero diagonal) of the trilinear
/// function with coefficients `k` at cell-local point `p`: `sqrt(Σλ² / 2)`, the Frobenius norm
/// over `√2` (summed over the upper triangle, in this order).
fn hessian_magnitude(k: &[f64; 8], p: [f64; 3]) -> f64 {
    let h = hessian(k, p);
    let (fxy, fyz, fxz) = (h[(0, 1)], h[(1, 2)], h[(0, 2)]);
    (fxy * fxy + fyz * fyz + fxz * fxz).sqrt()
}

/// The tet's cells: the index-space box of its corners, a few cells per axis at most.
fn tet_cells(index: &[[f64; 3]; 4], cd: [usize; 3]) -> ([usize; 3], [usize; 3]) {
    let mut lo = [0usize; 3];
    let mut hi = [0usize; 3];
    for a in 0..3 {
        let mn = index.iter().map(|u| u[a]).fold(f64::INFINITY, f64::min);
        let mx = index.iter().map(|u| u[a]).fold(f64::NEG_INFINITY, f64::max);
        let cell = |x: f64| (x.floor().max(0.0) as usize).min(cd[a] - 1);
        lo[a] = cell(mn - 1e-9);
        hi[a] = cell(mx + 1e-9).min(lo[a] + 3);
    }
    (lo, hi)
}

impl Classifier<'_> {
    /// Why tet `t` is below the floor (the same as [`Classifier::details`] finds, without
    /// measuring necks that cannot explain it).
    fn reason(&self, t: usize) -> ForcedReason {
        let index = tet_points(self.mesh, t).map(|q| self.field.to_index(q));
        let limit = longest_edge(&index) * self.floor;
        let near_critical = self.near_critical(&index, limit);
        // A layer is thin where the pass leaves it alone (`thin.rs`): thinner than the
        // longest edge times the target's sine and than the guard distance; or where even
        // the floor cannot hold.
        let thin = (longest_edge(&index) * self.target_sine)
            .min(GUARD_DISTANCE)
            .max(limit);
        // A chord of the layer shorter than `thin` has both its ends within `thin`.
        let layer_thickness = || self.layer_thickness(self.mesh.tets[t], &index, thin);
        let box_angle = || self.box_angle(self.mesh.tets[t], &index);
        self.decide(near_critical, thin, layer_thickness, box_angle)
    }

    /// The reason, given whether a critical point explains the tet, the layer thickness
    /// `limit` below which it is thin, and (computed only if needed) its layer thickness and
    /// box angle.
    fn decide(
        &self,
        near_critical: bool,
        limit: f64,
        layer_thickness: impl FnOnce() -> Option<f64>,
        box_angle: impl FnOnce() -> Option<f64>,
    ) -> ForcedReason {
        if near_critical {
            ForcedReason::NearCritical
        } else if layer_thickness().is_some_and(|h| h < limit) {
            ForcedReason::ThinLayer
        } else if box_angle().is_some_and(|a| a.to_radians() < self.floor) {
            ForcedReason::BoxAngle
        } else {
            ForcedReason::Unexplained
        }
    }

    /// Tet `t` (angles `lo`, `hi`, reason `reason`) with every measure the report gives.
    fn details(&self, t: usize, lo: f64, hi: f64, reason: ForcedReason) -> ForcedElement {
        let p = tet_points(self.mesh, t);
        let centroid = [0, 1, 2].map(|a| p.iter().map(|q| q[a]).sum::<f64>() / 4.0);
        let index = p.map(|q| self.field.to_index(q));
        let (critical_distance, neck_width) = self.nearest_critical(&index);
        ForcedElement {
            tet: t,
            min_dihedral: lo,
            max_dihedral: hi,
            reason,
            point: centroid,
            critical_distance,
            neck_width,
            layer_thickness: self.layer_thickness(
                self.mesh.tets[t],
                &index,
                WIDTH_REACH.max(longest_edge(&index) * self.floor),
            ),
            box_angle: self.box_angle(self.mesh.tets[t], &index),
        }
    }

    /// How thick (index space) the layer between the two level sets is at the tet: the
    /// shortest distance between a corner on the alpha level set and one on the beta level
    /// set (a bound: the segment crosses the layer), and the shortest chord of the layer
    /// through the centroid ([`Classifier::shortest_chord`], chords with both ends within
    /// `reach`), whichever is smaller. Where the centroid lies outside the interval (a linear
    /// tet inscribed in a curved layer), `(beta − alpha) / |∇f|` there (the first-order
    /// distance between the level sets) stands in for the chord. `None` for a one-sided
    /// interval, or where neither bound is found.
    fn layer_thickness(&self, tet: [u32; 4], index: &[[f64; 3]; 4], reach: f64) -> Option<f64> {
        let gap = self.levels[1] - self.levels[0];
        if !gap.is_finite() {
            return None;
        }
        let centroid = [0, 1, 2].map(|a| index.iter().map(|u| u[a]).sum::<f64>() / 4.0);
        let (f, g) = self.field.value_gradient(centroid);
        let mut thinnest = if self.outside(f) {
            gap / norm(g)
        } else {
            self.shortest_chord(centroid, g, reach)
                .unwrap_or(f64::INFINITY)
        };
        let on = |i: usize, l: BoundaryLabel| {
            (self.labels[tet[i] as usize] >> self.first) & l.bit() != 0
        };
        for i in (0..4).filter(|&i| on(i, BoundaryLabel::Level(0))) {
            for j in (0..4).filter(|&j| j != i && on(j, BoundaryLabel::Level(1))) {
                thinnest = thinnest.min(distance(index[i], index[j]));
            }
        }
        thinnest.is_finite().then_some(thinnest)
    }

    /// Whether value `f` lies outside the interval.
    fn outside(&self, f: f64) -> bool {
        f < self.levels[0] || f > self.levels[1]
    }

    /// The shortest chord of the interval's domain through `c` (inside it) along the gradient
    /// `g` there and the 13 lattice directions: the distance between the first points on
    /// either side where the field leaves `[alpha, beta]`, over the chords with both within
    /// `reach`. For a layer, measured across it: exact for a flat one, and an upper bound of
    /// the distance between its level sets at `c` otherwise.
    fn shortest_chord(&self, c: [f64; 3], g: [f64; 3], reach: f64) -> Option<f64> {
        let n = norm(g);
        let along_gradient = (n > 0.0 && n.is_finite()).then(|| g.map(|x| x / n));
        let outside = |f: f64| self.outside(f);
        along_gradient
            .into_iter()
            .chain(unit_lattice_directions())
            .filter_map(|d| {
                let ahead = self.exit(c, d, reach, outside)?;
                let behind = self.exit(c, d.map(|x| -x), reach, outside)?;
                Some(ahead + behind)
            })
            .reduce(f64::min)
    }

    /// The critical points in the cells touched by the tet with index-space corners `index`,
    /// as (`|value − bound|` to the nearer bound, that bound, Hessian magnitude, position).
    fn tet_critical_points(
        &self,
        index: &[[f64; 3]; 4],
    ) -> impl Iterator<Item = (f64, f64, f64, [f64; 3])> + '_ {
        let (lo, hi) = tet_cells(index, self.field.grid().cell_dims());
        (lo[2]..=hi[2])
            .flat_map(move |k| {
                (lo[1]..=hi[1]).flat_map(move |j| (lo[0]..=hi[0]).map(move |i| [i, j, k]))
            })
            .flat_map(|c| self.cell_critical_points(c))
            .map(|(v, hess, pos)| {
                let (da, db) = ((v - self.levels[0]).abs(), (v - self.levels[1]).abs());
                if da <= db {
                    (da, self.levels[0], hess, pos)
                } else {
                    (db, self.levels[1], hess, pos)
                }
            })
    }

    /// Over the critical points in the cells touched by the tet with index-space corners
    /// `index`: the smallest `|value − bound|` relative to the data range, and the narrowest
    /// neck the nearer bound leaves there ([`Classifier::measured_width`], else the quadratic
    /// estimate `2·sqrt(|value − bound| / k)`).
    fn nearest_critical(&self, index: &[[f64; 3]; 4]) -> (Option<f64>, Option<f64>) {
        let (mut dist, mut neck): (Option<f64>, Option<f64>) = (None, None);
        for (d, level, hess, pos) in self.tet_critical_points(index) {
            let w = if d == 0.0 {
                0.0
            } else {
                self.measured_width(pos, level)
                    .unwrap_or(2.0 * (d / hess).sqrt())
            };
            dist = Some(dist.map_or(d / self.range, |b| b.min(d / self.range)));
            neck = Some(neck.map_or(w, |b| b.min(w)));
        }
        (dist, neck)
    }

    /// Whether [`Classifier::nearest_critical`] would find a critical value within the
    /// tolerance or a neck narrower than `limit`, measuring necks only as far as `limit` needs:
    /// a measured width below `limit` has both its crossings within `limit`, and the full
    /// reach is walked only where the quadratic estimate would be below `limit`.
    fn near_critical(&self, index: &[[f64; 3]; 4], limit: f64) -> bool {
        self.tet_critical_points(index)
            .any(|(d, level, hess, pos)| {
                if d / self.range <= self.tol {
                    return true;
                }
                if d == 0.0 {
                    // The level passes through the critical point: a neck of width 0.
                    return limit > 0.0;
                }
                self.neck_below(pos, level, limit)
                    || 2.0 * (d / hess).sqrt() < limit && self.measured_width(pos, level).is_none()
            })
    }

    /// Whether [`Classifier::measured_width`] at `c` is below `limit`: some direction crosses
    /// the level at `a` ahead and `b` behind with `a + b < limit`. Walks `limit` ahead and
    /// only `limit − a` behind (so the crossings found are those of the full walk), and not at
    /// all where the field cannot reach the level within `limit` ([`Classifier::slope_bound`]).
    fn neck_below(&self, c: [f64; 3], level: f64, limit: f64) -> bool {
        let f = self.field.value(c);
        if (f - level).abs() >= self.slope_bound(c, limit) * limit {
            return false;
        }
        let side = (f - level).signum();
        unit_lattice_directions().any(|d| {
            self.crossing(c, d, level, side, limit).is_some_and(|a| {
                self.crossing(c, d.map(|x| -x), level, side, limit - a)
                    .is_some_and(|b| a + b < limit)
            })
        })
    }

    /// A bound on `|∇f|` (index space) within `reach` of `c`: √3 times the spread of the grid
    /// values around (`∂f/∂x` in a cell interpolates its x-edge differences). Infinite for a
    /// reach above a voxel.
    fn slope_bound(&self, c: [f64; 3], reach: f64) -> f64 {
        if reach > 1.0 {
            return f64::INFINITY;
        }
        let grid = self.field.grid();
        let span = |a: usize| {
            let base = c[a].floor() as isize;
            let top = grid.dims[a] as isize - 1;
            (base - 1).clamp(0, top) as usize..=(base + 2).clamp(0, top) as usize
        };
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for k in span(2) {
            for j in span(1) {
                for i in span(0) {
                    let v = grid.value(i, j, k);
                    lo = lo.min(v);
                    hi = hi.max(v);
                }
            }
        }
        3f64.sqrt() * (hi - lo)
    }

    /// The width of the neck (or gap) the level set `level` makes at the critical point at
    /// index point `c`, measured: along each of the 13 lattice directions through `c`, the
    /// distance between the first crossings of the level on either side; the smallest. `None`
    /// when no direction crosses on both sides within [`WIDTH_REACH`] voxels.
    fn measured_width(&self, c: [f64; 3], level: f64) -> Option<f64> {
        let side = (self.field.value(c) - level).signum();
        unit_lattice_directions()
            .filter_map(|d| {
                let ahead = self.crossing(c, d, level, side, WIDTH_REACH)?;
                let behind = self.crossing(c, d.map(|x| -x), level, side, WIDTH_REACH)?;
                Some(ahead + behind)
            })
            .reduce(f64::min)
    }

    /// The distance from `c` along unit direction `d` to where `f − level` first leaves the
    /// sign `side` (to 1e-6 voxel), within `reach` (sampled in [`WIDTH_STEP`]s) and the grid
    /// box.
    fn crossing(&self, c: [f64; 3], d: [f64; 3], level: f64, side: f64, reach: f64) -> Option<f64> {
        self.exit(c, d, reach, |f| (f - level) * side <= 0.0)
    }

    /// The distance from `c` along unit direction `d` to the first point where `crossed`
    /// holds for the field's value (to 1e-6 voxel), within `reach` (sampled in
    /// [`WIDTH_STEP`]s) and the grid box.
    fn exit(
        &self,
        c: [f64; 3],
        d: [f64; 3],
        reach: f64,
        crossed: impl Fn(f64) -> bool,
    ) -> Option<f64> {
        let at = |t: f64| [0, 1, 2].map(|a| c[a] + t * d[a]);
        let crossed = |t: f64| crossed(self.field.value(at(t)));
        let (mut lo, mut hi) = self
            .field
            .first_step_across(c, d, (WIDTH_STEP, reach), crossed)?;
        while hi - lo > 1e-6 {
            let mid = 0.5 * (lo + hi);
            if crossed(mid) {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        Some(hi)
    }

    /// Critical points in cell `c` as (value, Hessian magnitude there): its critical (or
    /// plateau) corners, its face saddles and its body saddles.
    fn cell_critical_points(&self, c: [usize; 3]) -> Vec<(f64, f64, [f64; 3])> {
        let grid = self.field.grid();
        let v = grid.cell_values(c[0], c[1], c[2]);
        let k = coefficients(&v);
        let at = |local: [f64; 3]| [0, 1, 2].map(|a| c[a] as f64 + local[a]);
        let mut out = Vec::new();
        for (corner, &value) in v.iter().enumerate() {
            let o = corner_offset(corner);
            let p = [0, 1, 2].map(|a| c[a] + o[a]);
            if vertex_class(grid, p).is_none_or(|class| class.critical()) {
                let local = o.map(|x| x as f64);
                out.push((value, hessian_magnitude(&k, local), at(local)));
            }
        }
        for f in 0..6 {
            if let Some(s) = face_saddle(&v, f) {
                let local = face_point(f, s.uv);
                out.push((s.value, hessian_magnitude(&k, local), at(local)));
            }
        }
        let (bs, n) = body_saddles(&v);
        out.extend(
            bs[..n]
                .iter()
                .map(|s| (s.value, hessian_magnitude(&k, s.pos), at(s.pos))),
        );
        out
    }

    /// Smallest interior dihedral angle (degrees) of the domain between a box plane on which
    /// the tet (`verts`, index-space corners `index`) has an edge and a level set on which it
    /// has an edge (two corners carrying the level as value), at those level corners' middle.
    fn box_angle(&self, verts: [u32; 4], index: &[[f64; 3]; 4]) -> Option<f64> {
        let dims = self.field.grid().dims;
        let mut best: Option<f64> = None;
        for (l, level) in self.levels.iter().enumerate() {
            let on: Vec<usize> = (0..4)
                .filter(|&i| self.mesh.values[verts[i] as usize] == level)
                .collect();
            if on.len() < 2 {
                continue;
            }
            let at =
                [0, 1, 2].map(|a| on.iter().map(|&i| index[i][a]).sum::<f64>() / on.len() as f64);
            for a in 0..3 {
                for (side, plane) in [0.0, (dims[a] - 1) as f64].into_iter().enumerate() {
                    let hits = index.iter().filter(|u| (u[a] - plane).abs() < 1e-6).count();
                    if hits >= 2 {
                        let angle = self.wedge(at, l == 1, a, side == 1);
                        best = match (best, angle) {
                            (Some(b), Some(x)) => Some(b.min(x)),
                            (b, x) => b.or(x),
                        };
                    }
                }
            }
        }
        best
    }

    /// Interior dihedral angle (degrees) at index point `u` between the level set (of beta if
    /// `beta`, the domain on its lower side; else of alpha) and the box plane normal to `axis`
    /// (its high side if `high`).
    fn wedge(&self, u: [f64; 3], beta: bool, axis: usize, high: bool) -> Option<f64> {
        let (_, g) = self.field.value_gradient(u);
        let inv = self.field.inverse_matrix();
        // physical gradient = inverse^T · index gradient; row `axis` of inverse is the box
        // plane's normal
        let gx = array3(&(inv.transpose() * vector3(g)));
        let nl = gx.map(|x| if beta { -x } else { x });
        let nb = array3(&inv.row(axis).transpose()).map(|x| if high { -x } else { x });
        let norm = (dot(nl, nl) * dot(nb, nb)).sqrt();
        if norm == 0.0 || !norm.is_finite() {
            return None;
        }
        // half-spaces with inward normals n1, n2 meet at the angle π − ∠(n1, n2)
        Some((-dot(nl, nb) / norm).clamp(-1.0, 1.0).acos().to_degrees())
    }
}

#[cfg(test)]
mod tests;
