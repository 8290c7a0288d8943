//! Readers and writers, one file per format. `io` never imports the algorithms and the
//! algorithms never import `io`: both only share [`crate::grid::ScalarGrid`] and
//! [`crate::mesh::TetMesh`] (and [`crate::mesh::TriSurface`]).
//!
//! Each side has a dispatcher that picks the format by extension over a module of what its
//! formats share: `volume.rs` over `read_common.rs` (volume readers), `surface_in.rs` over
//! `surface_read_common.rs` (closed surfaces), `mesh_in.rs` over `mesh_read_common.rs` (mesh
//! readers), `mesh_out.rs` over `write_common.rs` (writers). Every extension is named once, in
//! `formats.rs`. No reader or writer imports its dispatcher.

pub mod atomic;
mod file_out;
mod formats;
mod header;
pub mod inp;
mod inputs;
mod mesh_out;
pub mod mhd;
pub mod msh;
mod msh_binary;
pub mod nifti;
pub mod npy;
pub mod nrrd;
pub mod obj;
pub mod plot3d;
pub mod ply;
mod read_common;
mod source;
mod spill;
pub use spill::SpilledMesh;
pub mod stl;
pub mod transfer_out;
mod volume;
mod vtk_xml;
pub mod vts;
pub mod vtu;
mod write_common;

pub use atomic::{
    check_writable, remove_pending_temporaries, same_file, write_atomically, write_pending,
    PendingFile, WriteError,
};
pub use inputs::{
    check_clashes, input_files, input_run_files, output_run_files, FileClash, RunFile,
};
pub use mesh_out::{
    spill_for, spill_for_levels, write_mesh, write_mesh_pending, write_spilled_pending,
    write_surface, write_surface_pending, MeshFormat, SurfaceFormat, WriteOptions,
};
pub use read_common::ReadError;
pub use transfer_out::{write_transfer, TransferFormat, TransferTable};
pub use volume::{is_curvilinear, is_plot3d, read_curvilinear, read_volume};

// Mesh readers (the twins of the writers above, and TetGen's and Medit's formats), used by
// `solver-demo` and `inspect`.
mod inp_read;
mod medit_read;
mod mesh_in;
mod mesh_read_common;
mod msh_read;
mod msh_read_binary;
mod tetgen_read;
mod vtk_read;
mod vtu_read;
pub use mesh_in::{mesh_files, read_mesh};
pub use mesh_read_common::{MeshFile, MeshReadError, NodeGroup, MESH_EXTENSIONS};

// Closed-surface readers (the twins of the surface writers), for signed-distance input.
pub mod obj_read;
pub mod ply_read;
pub mod stl_read;
mod surface_in;
mod surface_read_common;
pub use surface_in::{is_surface, read_surface};
pub use surface_read_common::TriSoup;
