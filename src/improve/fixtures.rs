//! Test domains shared by the unit tests of the quality pass.

use std::time::Instant;

use super::ctx::context;
use super::quality_cache::tet_qualities;
use super::region::{extract_regions, LocalMesh};
use super::{Ctx, QualityOptions, DEFAULT_WARP};
use crate::levels::Levels;
use crate::mesh::TetMesh;
use crate::{mesh_interval, MeshOptions, Method, ScalarGrid};

/// The interval of [`wavy_torus`].
const WAVY_TORUS_INTERVAL: (f64, f64) = (-10.0, 2.2);

/// A torus with a wavy surface on a coarse grid (its interval: [`WAVY_TORUS_INTERVAL`]): many
/// boundary vertices, short edges and both outcomes of the link condition.
pub fn wavy_torus() -> ScalarGrid {
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
    ScalarGrid::new([n, n, n], values).unwrap()
}

/// The wavy torus meshed with warping (no pass) and its context with the default options.
pub fn wavy_torus_mesh(grid: &ScalarGrid) -> (TetMesh, Ctx<'_>) {
    wavy_torus_mesh_at(grid, WAVY_TORUS_INTERVAL)
}

/// The wavy torus's mesh of the interval `[alpha, beta]`, as in [`wavy_torus_mesh`].
pub fn wavy_torus_mesh_at(grid: &ScalarGrid, (alpha, beta): (f64, f64)) -> (TetMesh, Ctx<'_>) {
    let opts = MeshOptions::new(alpha, beta, Method::Ctd).warp(DEFAULT_WARP);
    let mesh = mesh_interval(grid, &opts).unwrap().mesh;
    let ctx = context(
        grid,
        &Levels::interval(alpha, beta),
        &QualityOptions::default(),
        Instant::now(),
    );
    (mesh, ctx)
}

/// [`wavy_torus_mesh`]'s context and the regions of every vertex in the slabs of each phase
/// in `phases`.
pub fn wavy_torus_regions<'a>(grid: &'a ScalarGrid, phases: &[u32]) -> (Ctx<'a>, Vec<LocalMesh>) {
    let (mesh, ctx) = wavy_torus_mesh(grid);
    let work = vec![true; mesh.points.len()];
    let quality = tet_qualities(&mesh, &ctx);
    let regions = phases
        .iter()
        .flat_map(|&p| extract_regions(&mesh, (&work, None), &quality, &ctx, p).0)
        .collect();
    (ctx, regions)
}
