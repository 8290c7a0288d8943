//! tptd: topology-preserving tetrahedral meshing of interval volumes
//! `{alpha <= f <= beta}` of piecewise-trilinear scalar fields.
//!
//! Pipeline (see `docs/ARCHITECTURE.md`), read → decompose → clip → weld → improve → write:
//! a [`ScalarGrid`] is read by [`io::read_volume`]; [`mesh_interval`] splits every cell into
//! tetrahedra through the saddles of the trilinear interpolant, clips each tetrahedron to the
//! interval, welds points by identity and returns a [`TetMesh`]; [`improve::improve`] raises
//! the element quality without changing the topology; [`topology`] and [`quality`]
//! analyse the mesh and [`io::write_mesh`] writes it. [`critical`] finds the critical points
//! and regions of the trilinear field (where the topology of the level sets changes), to
//! choose `alpha` and `beta` away from them.

#![warn(missing_docs)]
// Index loops over small fixed arrays (corners, faces, axes) read better than iterator chains.
#![allow(clippy::needless_range_loop)]

pub mod algebra;
pub mod allocator;
pub mod buffer;
pub mod cancel;
pub mod check;
pub(crate) mod clip;
pub mod critical;
pub mod curvilinear;
pub(crate) mod decompose;
pub mod demo;
pub(crate) mod extract;
pub mod facts;
pub mod field;
pub(crate) mod geom;
pub mod grade;
pub mod grid;
pub mod improve;
pub mod inspect;
pub mod io;
pub(crate) mod keys;
pub mod levels;
pub mod memory;
pub mod mesh;
pub mod pass_report;
pub mod pipeline;
pub mod quality;
pub mod report;
pub mod samples;
pub mod sdf;
pub mod surface;
pub mod surface_volume;
pub mod text;
pub mod topology;
pub(crate) mod trilinear;
pub mod union_find;
pub(crate) mod warp;
pub mod weld;

pub use buffer::Buffer;
pub use curvilinear::{mesh_curvilinear, CurvilinearError};
pub use decompose::CellCase;
pub use extract::{
    mesh_interval, mesh_interval_seen_by, mesh_interval_streamed, mesh_interval_with_progress,
    MeshError, MeshOptions, MeshOutput, MeshStats, Method,
};
pub use grid::{CurvilinearGrid, ScalarGrid};
pub use levels::Levels;
pub use mesh::{BoundaryLabel, TetMesh, TriSurface};
pub use mesh::{MeshChunk, MeshSink};
/// The `nalgebra` this crate's geometry types ([`algebra`], [`ScalarGrid::affine`]) come from.
pub use nalgebra;
pub use samples::{SampleStorage, Samples};
pub use surface::{analysis::analyse_surface, level_surface, SurfaceOptions};
pub use surface_volume::{volume_from_surface, SurfaceVolumeError};
pub use warp::Snapped;
