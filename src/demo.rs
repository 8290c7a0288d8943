//! A generated sample volume that shows why the decomposition matters: two parallel vessels
//! whose walls come within a fraction of a voxel of each other.
//!
//! The field is the maximum of two Gaussian "tubes" (capsules: a straight segment along x with
//! rounded ends), sampled on a 40 × 24 × 24 grid. The tube axes lie on either side of one cell
//! diagonal in the yz-plane, so along the whole length of the tubes the cells between them have
//! two diagonally opposite corners above [`DEMO_ALPHA`] (one in each tube) and the other two
//! below. The trilinear interpolant dips below alpha between the two high corners (its face
//! saddle is ≈ 0.4965 < 0.5): the interval volume `{f >= 0.5}` has **two** components, the two
//! vessels, separated by a gap of ≈ 0.35 voxel. The 6-fold decomposition splits those cell faces
//! along exactly the diagonal that joins the two high corners, so linear interpolation on it
//! fuses the vessels into **one** component; `tptd` and `ctd` keep them apart.

use crate::grid::{ScalarGrid, IDENTITY};

/// Lower bound of the demo interval.
pub const DEMO_ALPHA: f64 = 0.5;
/// Upper bound of the demo interval (unbounded).
pub const DEMO_BETA: f64 = f64::INFINITY;

/// Grid vertices along x, y, z.
pub const DEMO_DIMS: [usize; 3] = [40, 24, 24];

/// Width (standard deviation, in voxels) of each tube's Gaussian profile; the 0.5 level of a
/// single tube lies at radius σ·√(2 ln 2) ≈ 4.59 voxels.
const SIGMA: f64 = 3.9;
/// Axis positions (y, z) of the two tubes: three voxels beyond either end of the diagonal of
/// the cell column `[11, 12] × [11, 12]`.
const AXES: [[f64; 2]; 2] = [[8.0, 8.0], [15.0, 15.0]];
/// The x-extent of the straight part of each tube.
const X_RANGE: [f64; 2] = [5.0, 34.0];

/// The demo volume: two parallel vessels (Gaussian capsules) whose `f = 0.5` walls are about a
/// third of a voxel apart, on a 40 × 24 × 24 grid with unit spacing.
///
/// With the interval [`DEMO_ALPHA`], [`DEMO_BETA`] the trilinear interval volume has two
/// components; `tptd`/`ctd` reproduce that (`b0 = 2`), the 6-fold decomposition merges them
/// (`b0 = 1`).
pub fn demo_volume() -> ScalarGrid {
    let [nx, ny, nz] = DEMO_DIMS;
    let mut values = Vec::with_capacity(nx * ny * nz);
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let x = i as f64;
                let dx = if x < X_RANGE[0] {
                    X_RANGE[0] - x
                } else if x > X_RANGE[1] {
                    x - X_RANGE[1]
                } else {
                    0.0
                };
                let v = AXES
                    .iter()
                    .map(|a| {
                        let dy = j as f64 - a[0];
                        let dz = k as f64 - a[1];
                        let r2 = dx * dx + dy * dy + dz * dz;
                        (-r2 / (2.0 * SIGMA * SIGMA)).exp()
                    })
                    .fold(0.0, f64::max);
                values.push(v);
            }
        }
    }
    ScalarGrid::with_geometry(DEMO_DIMS, [1.0; 3], [0.0; 3], IDENTITY, values)
        .expect("the demo grid is valid by construction")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::extract::{mesh_interval, MeshOptions, Method};
    use crate::topology::betti;

    fn betti_of(method: Method) -> [usize; 3] {
        let grid = demo_volume();
        let out = mesh_interval(&grid, &MeshOptions::new(DEMO_ALPHA, DEMO_BETA, method))
            .expect("demo meshes");
        assert!(!out.mesh.tets.is_empty());
        betti(&out.mesh)
    }

    #[test]
    fn topology_preserving_methods_keep_the_vessels_apart() {
        assert_eq!(betti_of(Method::Ctd), [2, 0, 0]);
        assert_eq!(betti_of(Method::Tptd), [2, 0, 0]);
    }

    #[test]
    fn six_fold_merges_the_vessels() {
        assert_eq!(betti_of(Method::Six)[0], 1);
    }

    #[test]
    fn no_grid_value_equals_alpha() {
        assert!(demo_volume().values.iter().all(|v| v != DEMO_ALPHA));
    }
}
