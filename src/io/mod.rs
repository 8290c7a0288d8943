//! Readers and writers, one file per format. `io` never imports the algorithms and the
//! algorithms never import `io`: both only share [`crate::grid::ScalarGrid`] and
//! [`crate::mesh::TetMesh`].

pub mod atomic;
mod header;
pub mod inp;
pub mod mhd;
pub mod msh;
pub mod nifti;
pub mod npy;
pub mod nrrd;
mod volume;
pub mod vtu;

pub use volume::{read_volume, ReadError};
