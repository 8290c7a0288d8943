//! Mesh output by file extension: [`write_mesh`] is the twin of [`super::read_volume`], and
//! [`MeshFormat`] chooses among the writers [`super::msh`], [`super::inp`] and [`super::vtu`].

use std::io::{self, Write};
use std::path::Path;

use super::atomic::{write_atomically, WriteError};
use super::inp::write_inp;
use super::msh::{write_msh, MshVersion};
use super::vtu::write_vtu;
use crate::mesh::TetMesh;

/// An output mesh format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MeshFormat {
    /// Gmsh ASCII `.msh` ([`write_msh`]).
    Msh,
    /// Abaqus / CalculiX `.inp` ([`write_inp`]).
    Inp,
    /// VTK XML UnstructuredGrid `.vtu` ([`write_vtu`]).
    Vtu,
}

impl MeshFormat {
    /// The format named by the extension of `path` (case-insensitive): `.msh`, `.inp` or
    /// `.vtu`.
    ///
    /// # Errors
    /// [`WriteError::UnknownFormat`] for any other extension or none.
    pub fn from_path(path: &Path) -> Result<Self, WriteError> {
        let ext = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
        match ext.as_deref() {
            Some("msh") => Ok(MeshFormat::Msh),
            Some("inp") => Ok(MeshFormat::Inp),
            Some("vtu") => Ok(MeshFormat::Vtu),
            _ => Err(WriteError::UnknownFormat {
                path: path.to_path_buf(),
            }),
        }
    }

    /// Writes `mesh` in this format to `w` (not atomically; see [`write_mesh`]).
    ///
    /// # Errors
    /// Whatever the format's writer returns: the first error of `w`, or
    /// [`io::ErrorKind::InvalidInput`] for an inconsistent mesh.
    pub fn write(
        self,
        mesh: &TetMesh,
        w: &mut dyn Write,
        options: &WriteOptions,
    ) -> io::Result<()> {
        match self {
            MeshFormat::Msh => write_msh(mesh, w, options.msh_version),
            MeshFormat::Inp => write_inp(mesh, w),
            MeshFormat::Vtu => write_vtu(mesh, w),
        }
    }
}

/// Options of the mesh writers; [`WriteOptions::default`] gives the defaults of the CLI.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub struct WriteOptions {
    /// The `.msh` format version (default 4.1); ignored by the other formats.
    pub msh_version: MshVersion,
}

impl WriteOptions {
    /// These options with `.msh` output in `version`.
    #[must_use]
    pub fn with_msh_version(mut self, version: MshVersion) -> Self {
        self.msh_version = version;
        self
    }
}

/// Writes `mesh` to `path` atomically (see [`write_atomically`]), in the format chosen by
/// the extension of `path` ([`MeshFormat::from_path`]).
///
/// # Errors
/// [`WriteError::UnknownFormat`] for an unknown extension (nothing is created), otherwise
/// whatever [`write_atomically`] returns; a writer's error is reported as [`WriteError::Io`].
pub fn write_mesh(path: &Path, mesh: &TetMesh, options: &WriteOptions) -> Result<(), WriteError> {
    let format = MeshFormat::from_path(path)?;
    write_atomically(path, |w| format.write(mesh, w, options))
}
