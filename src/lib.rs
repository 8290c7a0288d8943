//! tptd: topology-preserving tetrahedral meshing of interval volumes
//! `{alpha <= f <= beta}` of piecewise-trilinear scalar fields.
//!
//! Pipeline (see `docs/ARCHITECTURE.md`): a [`grid::ScalarGrid`] is read by [`io`];
//! [`extract::mesh_interval`] decomposes every cell into tetrahedra ([`decompose`], using the
//! saddles of [`trilinear`]), clips each tetrahedron to the interval ([`clip`]), welds points by
//! identity and returns a [`mesh::TetMesh`]; [`topology`] and [`quality`] analyse it and the
//! writers in [`io`] export it.

// Index loops over small fixed arrays (corners, faces, axes) read better than iterator chains.
#![allow(clippy::needless_range_loop)]

pub mod clip;
pub mod decompose;
pub mod demo;
pub mod extract;
pub mod geom;
pub mod grid;
pub mod improve;
pub mod io;
pub mod keys;
pub mod mesh;
pub mod quality;
pub mod report;
pub mod topology;
pub mod trilinear;

pub use extract::{
    mesh_interval, mesh_interval_with_progress, MeshError, MeshOptions, MeshOutput, MeshStats,
    Method,
};
pub use grid::ScalarGrid;
pub use mesh::{BoundaryLabel, TetMesh};
