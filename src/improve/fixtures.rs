//! Test domains shared by the unit tests of the quality pass.

use crate::ScalarGrid;

/// A torus with a wavy surface on a coarse grid, with its interval: many boundary vertices,
/// short edges and both outcomes of the link condition.
pub fn wavy_torus() -> (ScalarGrid, f64, f64) {
    let n = 18;
    let mut values = Vec::with_capacity(n * n * n);
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let (x, y, z) = (i as f64 - 8.3, j as f64 - 8.6, k as f64 - 8.9);
                let ring = ((x * x + y * y).sqrt() - 5.0).hypot(z);
                values.push(ring + 0.4 * (1.7 * x).sin() * (1.3 * y + z).cos());
            }
        }
    }
    (ScalarGrid::new([n, n, n], values).unwrap(), -10.0, 2.2)
}
