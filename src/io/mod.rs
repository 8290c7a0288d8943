//! Readers and writers, one file per format. `io` never imports the algorithms and the
//! algorithms never import `io`: both only share [`crate::grid::ScalarGrid`] and
//! [`crate::mesh::TetMesh`].

pub mod atomic;
mod header;
pub mod inp;
mod mesh_out;
pub mod mhd;
pub mod msh;
pub mod nifti;
pub mod npy;
pub mod nrrd;
mod volume;
pub mod vtu;
mod write_common;

pub use atomic::{
    check_writable, remove_pending_temporaries, same_file, write_atomically, write_pending,
    PendingFile, WriteError,
};
pub use mesh_out::{write_mesh, write_mesh_pending, MeshFormat, WriteOptions};
pub use volume::{read_volume, ReadError};
