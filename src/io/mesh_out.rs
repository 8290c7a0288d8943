//! Mesh output by file extension: [`write_mesh`] is the twin of [`super::read_volume`], and
//! [`MeshFormat`] chooses among the writers [`super::msh`], [`super::inp`] and [`super::vtu`].
//! Isosurfaces likewise: [`write_surface`] and [`SurfaceFormat`] choose among [`super::obj`],
//! [`super::ply`] and [`super::stl`].

use std::io::{self, Write};
use std::path::Path;

use super::atomic::{write_atomically, write_pending, PendingFile, WriteError};
use super::inp::{write_inp, write_inp_source};
use super::msh::{write_msh, write_msh_source, MshVersion};
use super::obj::write_obj;
use super::ply::write_ply;
use super::source::MeshSource;
use super::spill::SpilledMesh;
use super::stl::write_stl;
use super::vtu::{write_vtu_source, write_vtu_with, VtuEncoding};
use crate::mesh::{TetMesh, TriSurface, INTERVAL_LEVELS};

pub use super::formats::{MeshFormat, SurfaceFormat};

impl MeshFormat {
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
            MeshFormat::Vtu => write_vtu_with(mesh, w, options.vtu_encoding),
        }
    }

    /// Writes the mesh `src` in this format to `w` (the writers' common path).
    fn write_source(
        self,
        src: &dyn MeshSource,
        w: &mut dyn Write,
        options: &WriteOptions,
    ) -> io::Result<()> {
        match self {
            MeshFormat::Msh => write_msh_source(src, w, options.msh_version),
            MeshFormat::Inp => write_inp_source(src, w),
            MeshFormat::Vtu => write_vtu_source(src, w, options.vtu_encoding),
        }
    }
}

/// Options of the mesh writers; [`WriteOptions::default`] gives the defaults of the CLI.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub struct WriteOptions {
    /// The `.msh` format version (default 4.1); ignored by the other formats.
    pub msh_version: MshVersion,
    /// ASCII instead of binary `.ply` / `.stl` (default binary); ignored by the other formats.
    pub ascii: bool,
    /// The `.vtu` data encoding (default base64); ignored by the other formats.
    pub vtu_encoding: VtuEncoding,
}

impl WriteOptions {
    /// These options with `.msh` output in `version`.
    #[must_use]
    pub fn with_msh_version(mut self, version: MshVersion) -> Self {
        self.msh_version = version;
        self
    }

    /// These options with `.vtu` data in `encoding`.
    #[must_use]
    pub fn with_vtu_encoding(mut self, encoding: VtuEncoding) -> Self {
        self.vtu_encoding = encoding;
        self
    }
}

impl WriteOptions {
    /// These options with ASCII (`true`) or binary `.ply` / `.stl` output.
    #[must_use]
    pub fn with_ascii(mut self, ascii: bool) -> Self {
        self.ascii = ascii;
        self
    }
}

impl SurfaceFormat {
    /// Writes `s` in this format to `w` (not atomically; see [`write_surface`]).
    ///
    /// # Errors
    /// Whatever the format's writer returns.
    pub fn write(
        self,
        s: &TriSurface,
        w: &mut dyn Write,
        options: &WriteOptions,
    ) -> io::Result<()> {
        match self {
            SurfaceFormat::Obj => write_obj(s, w),
            SurfaceFormat::Ply => write_ply(s, w, options.ascii),
            SurfaceFormat::Stl => write_stl(s, w, options.ascii),
        }
    }
}

/// Writes the surface `s` to `path` atomically, in the format chosen by the extension of
/// `path` ([`SurfaceFormat::from_path`]).
///
/// # Errors
/// [`WriteError::UnknownFormat`] for an extension that names no surface format (nothing is
/// created), otherwise whatever [`write_atomically`] returns.
pub fn write_surface(
    path: &Path,
    s: &TriSurface,
    options: &WriteOptions,
) -> Result<(), WriteError> {
    let format = SurfaceFormat::from_path(path).ok_or_else(|| WriteError::UnknownFormat {
        path: path.to_path_buf(),
    })?;
    write_atomically(path, |w| format.write(s, w, options))
}

/// Writes the surface `s` to a temporary of `path` (see [`write_pending`]), in the format
/// chosen by the extension of `path`; the caller commits it.
///
/// # Errors
/// As [`write_surface`].
pub fn write_surface_pending(
    path: &Path,
    s: &TriSurface,
    options: &WriteOptions,
) -> Result<PendingFile, WriteError> {
    let format = SurfaceFormat::from_path(path).ok_or_else(|| WriteError::UnknownFormat {
        path: path.to_path_buf(),
    })?;
    write_pending(path, |w| format.write(s, w, options))
}

/// Writes `mesh` to `path` atomically (see [`super::write_atomically`]), in the format chosen by
/// the extension of `path` ([`MeshFormat::from_path`]).
///
/// # Errors
/// [`WriteError::UnknownFormat`] for an unknown extension (nothing is created), otherwise
/// whatever [`super::write_atomically`] returns; a writer's error is reported as [`WriteError::Io`].
pub fn write_mesh(path: &Path, mesh: &TetMesh, options: &WriteOptions) -> Result<(), WriteError> {
    write_mesh_pending(path, mesh, options)?.commit()
}

/// As [`write_mesh`], but leaves the complete file under its temporary name until
/// [`PendingFile::commit`] (see [`write_pending`]).
///
/// # Errors
/// As [`write_mesh`].
pub fn write_mesh_pending(
    path: &Path,
    mesh: &TetMesh,
    options: &WriteOptions,
) -> Result<PendingFile, WriteError> {
    let format = MeshFormat::from_path(path)?;
    write_pending(path, |w| format.write(mesh, w, options))
}

/// A [`SpilledMesh`] for a mesh of one interval bound for `path`: its files in the folder
/// of `path`, with the boundary faces when the format (by extension) needs them. Feed it to
/// [`crate::mesh_interval_streamed`], then write it with [`write_spilled_pending`].
///
/// # Errors
/// [`WriteError::UnknownFormat`] for an unknown extension; [`WriteError::Io`] when the files
/// cannot be created.
pub fn spill_for(path: &Path) -> Result<SpilledMesh, WriteError> {
    spill_for_levels(path, INTERVAL_LEVELS, Vec::new())
}

/// [`spill_for`] a mesh of a run of `levels` levels ([`crate::MeshOptions::levels`]; 2 for
/// one interval) whose regions are called `names` (missing ones: `region1`, `region2`, …).
///
/// # Errors
/// As [`spill_for`].
pub fn spill_for_levels(
    path: &Path,
    levels: usize,
    names: Vec<String>,
) -> Result<SpilledMesh, WriteError> {
    let format = MeshFormat::from_path(path)?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    SpilledMesh::new(dir, format == MeshFormat::Inp, levels, names).map_err(|source| {
        WriteError::Io {
            path: path.to_path_buf(),
            source,
        }
    })
}

/// Writes a streamed mesh to a temporary of `path` (see [`write_pending`]), in the format
/// chosen by the extension of `path`; the bytes equal what [`write_mesh_pending`] writes for
/// the same mesh in memory.
///
/// # Errors
/// As [`write_mesh`].
pub fn write_spilled_pending(
    path: &Path,
    mesh: &mut SpilledMesh,
    options: &WriteOptions,
) -> Result<PendingFile, WriteError> {
    let format = MeshFormat::from_path(path)?;
    mesh.finish().map_err(|source| WriteError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let mesh = &*mesh;
    write_pending(path, |w| format.write_source(mesh, w, options))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::BoundaryLabel;

    fn one_tet() -> TetMesh {
        TetMesh {
            regions: Default::default(),
            points: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            values: vec![0.0, 1.0, 2.0, 3.0],
            tets: vec![[0, 1, 2, 3]],
            boundary: vec![[0, 2, 1]],
            boundary_labels: vec![BoundaryLabel::ALPHA],
        }
    }

    #[test]
    fn format_follows_the_extension_case_insensitively() {
        let f = |p: &str| MeshFormat::from_path(Path::new(p)).ok();
        assert_eq!(f("a.msh"), Some(MeshFormat::Msh));
        assert_eq!(f("dir/a.INP"), Some(MeshFormat::Inp));
        assert_eq!(f("a.b.Vtu"), Some(MeshFormat::Vtu));
        for p in ["a.vtk", "msh", ".msh", "a"] {
            let e = MeshFormat::from_path(Path::new(p)).unwrap_err();
            assert!(matches!(e, WriteError::UnknownFormat { .. }), "{p}: {e}");
        }
    }

    #[test]
    fn write_mesh_matches_the_format_writers() {
        let mesh = one_tet();
        let dir = tempfile::tempdir().unwrap();
        let v22 = WriteOptions::default().with_msh_version(MshVersion::V22);
        for (name, opts) in [
            ("a.msh", WriteOptions::default()),
            ("b.msh", v22),
            ("c.inp", WriteOptions::default()),
            ("d.vtu", WriteOptions::default()),
            (
                "e.vtu",
                WriteOptions::default().with_vtu_encoding(VtuEncoding::Raw),
            ),
        ] {
            let path = dir.path().join(name);
            write_mesh(&path, &mesh, &opts).unwrap();
            let mut expected = Vec::new();
            match MeshFormat::from_path(&path).unwrap() {
                MeshFormat::Msh => write_msh(&mesh, &mut expected, opts.msh_version),
                MeshFormat::Inp => write_inp(&mesh, &mut expected),
                MeshFormat::Vtu => write_vtu_with(&mesh, &mut expected, opts.vtu_encoding),
            }
            .unwrap();
            assert_eq!(std::fs::read(&path).unwrap(), expected, "{name}");
        }
        let bad = dir.path().join("e.off");
        assert!(matches!(
            write_mesh(&bad, &mesh, &WriteOptions::default()),
            Err(WriteError::UnknownFormat { .. })
        ));
        assert!(!bad.exists());
    }

    #[test]
    fn check_writable_rejects_directories_and_missing_parents() {
        use super::super::atomic::check_writable;
        let dir = tempfile::tempdir().unwrap();
        assert!(check_writable(&dir.path().join("new.msh")).is_ok());
        assert!(matches!(
            check_writable(dir.path()),
            Err(WriteError::IsDirectory { .. })
        ));
        let missing = dir.path().join("no/such/x.msh");
        assert!(matches!(
            check_writable(&missing),
            Err(WriteError::MissingDirectory { .. })
        ));
        assert_eq!(
            WriteOptions::default().msh_version,
            MshVersion::V41,
            "default .msh version"
        );
    }
}
