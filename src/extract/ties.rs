//! Values within rounding of a level set onto it before meshing, so that they follow the
//! ties rule of the clipper instead of putting cuts within rounding of a grid vertex.

use crate::grid::{Samples, ScalarGrid};

/// Values within this fraction of the data range of a level, but not equal to it, are set
/// onto the level before meshing.
pub const NEAR_TIE: f64 = 1e-9;

/// Removes values within [`NEAR_TIE`] × (data range) of `alpha` or `beta` but not equal to
/// it. Such values (e.g. 0.9999999999999999 for a distance sampled on a sphere of radius 1)
/// would put cuts within rounding of a grid vertex: the cut point and the vertex coincide in
/// floating point, and tets between them vanish. As exact ties they follow the ties rule
/// (`clip`), which keeps every tet non-degenerate. Returns the grid to mesh (`None`: `grid`
/// itself) and the levels to mesh:
/// * integer storage: the level moves onto the integer next to it (the tolerance is far below
///   0.5, so no other value lies between them: the same interval of the data), no copy;
/// * float storage: a copy of the grid with those values set onto the level, in the same
///   storage type when it holds the level exactly, else in `f64`.
pub(super) fn without_near_ties(
    grid: &ScalarGrid,
    alpha: f64,
    beta: f64,
) -> (Option<ScalarGrid>, f64, f64) {
    let (lo, hi) = grid.value_range();
    let tol = NEAR_TIE * (hi - lo);
    let near = |v: f64, l: f64| l.is_finite() && v != l && (v - l).abs() <= tol;
    let near_any = |v: f64| [alpha, beta].into_iter().find(|&l| near(v, l));
    if !grid.values.par_any(|v| near_any(v).is_some()) {
        return (None, alpha, beta);
    }
    if grid.values.storage().is_integer() && tol < 0.5 {
        let moved = [alpha, beta].map(|l| match grid.values.par_any(|v| near(v, l)) {
            true => l.round(),
            false => l,
        });
        if moved[0] < moved[1] {
            return (None, moved[0], moved[1]);
        }
    }
    let written = [alpha, beta].into_iter().filter(|l| l.is_finite());
    let mut values = match written.clone().all(|l| grid.values.holds(l)) {
        true => grid.values.clone(),
        false => Samples::F64(grid.values.to_f64_vec()),
    };
    values.par_map_in_place(|v| near_any(v).unwrap_or(v));
    let g = ScalarGrid {
        dims: grid.dims,
        spacing: grid.spacing,
        origin: grid.origin,
        direction: grid.direction,
        values,
    };
    (Some(g), alpha, beta)
}
