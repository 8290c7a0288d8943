//! Closeness on the trilinear field: whether a level set passes near a grid vertex, and
//! whether the surface a snap leaves in a star stays near its level sets.

use crate::field::GUARD_DISTANCE;
use crate::geom::level_polygon;
use crate::geom::sample_points_spaced;
use crate::grid::ScalarGrid;
use crate::levels::Levels;

/// Step 1 on the trilinear field: the crossing found there may lie on a diagonal of the
/// decomposition, where the piecewise-linear level set is closer to the vertex than the
/// trilinear one that the quality pass projects the snapped vertex onto. A vertex is snapped
/// only when the trilinear level set also passes within `eps` (index units) of it.
pub(super) struct TrilinearNear<'a> {
    field: crate::field::Field<'a>,
    tol: f64,
    eps: f64,
}

impl<'a> TrilinearNear<'a> {
    pub(super) fn new(grid: &'a ScalarGrid, eps: f64) -> Self {
        let (lo, hi) = grid.value_range();
        TrilinearNear {
            field: crate::field::Field::new(grid),
            tol: 1e-9 * (hi - lo).max(f64::MIN_POSITIVE),
            eps,
        }
    }

    /// Whether `f = level` passes within `eps` of grid vertex `v`: Newton projections start
    /// just inside each of the eight cells around it.
    pub(super) fn holds(&self, v: usize, level: f64) -> bool {
        let ijk = self.field.grid().vertex_ijk(v).map(|c| c as f64);
        (0..8).any(|o| {
            let start: [f64; 3] =
                std::array::from_fn(|a| ijk[a] + if o >> a & 1 == 1 { 1e-6 } else { -1e-6 });
            self.field
                .project(start, level, 0b111, self.tol)
                .is_some_and(|p| crate::geom::distance(p, ijk) < self.eps)
        })
    }
}

impl TrilinearNear<'_> {
    /// Whether the level sets `levels` (infinite ones skipped) of the linear interpolant of
    /// `f` on tet `p` (index space) lie within [`GUARD_DISTANCE`] of the trilinear level sets,
    /// at points [`SAMPLE_SPACING`] apart (the guard's own are twice as fine; a snap is tested for every
    /// candidate, and the checker after it allows half a voxel).
    pub(super) fn tet_levels_near(&self, p: [[f64; 3]; 4], f: [f64; 4], levels: &Levels) -> bool {
        levels.iter().filter(|l| l.is_finite()).all(|level| {
            let (q, n) = level_polygon(p, f, level);
            let tris: &[[usize; 3]] = match n {
                0 => &[],
                1 => &[[0, 0, 0]],
                2 => &[[0, 1, 1]],
                3 => &[[0, 1, 2]],
                _ => &[[0, 1, 2], [0, 2, 3]],
            };
            tris.iter().all(
                |t| match sample_points_spaced(t.map(|i| q[i]), SAMPLE_SPACING) {
                    Some(mut points) => {
                        points.all(|u| self.field.near_level(u, level, GUARD_DISTANCE, self.tol))
                    }
                    None => false,
                },
            )
        })
    }
}

/// Spacing (index units) of the points at which a snap's surface is measured.
const SAMPLE_SPACING: f64 = 0.5;
