//! Mesh input by file extension: [`read_mesh`] is the twin of [`super::write_mesh`] and
//! chooses among the readers `msh_read` (`.msh` 4.1 and 2.2), `msh_read_binary` (binary
//! `.msh` 4.1), `inp_read` (`.inp`), `vtu_read` (`.vtu`), `vtk_read` (legacy `.vtk`),
//! `tetgen_read` (TetGen `.node`/`.ele`/`.face`) and `medit_read` (Medit `.mesh`). All return
//! a [`MeshFile`]; the readers share [`super::mesh_read_common`], never this dispatcher.

use std::path::Path;

use super::formats::MeshReader;
use super::mesh_read_common::{parse_bytes, parse_file, MeshFile, MeshReadError};

/// The files [`read_mesh`] reads for `path`: `path` itself, or for TetGen the `.node`, the
/// `.ele` and (when it exists) the `.face` of the same name. Nothing is opened.
pub fn mesh_files(path: &Path) -> Vec<std::path::PathBuf> {
    match MeshReader::of(path) {
        Some(MeshReader::TetGen) => super::tetgen_read::tetgen_files(path),
        _ => vec![path.to_path_buf()],
    }
}

/// Reads a tetrahedral mesh with its groups from `path`, by extension (case-insensitive):
/// `.msh` (Gmsh ASCII 4.1 or 2.2, see `msh_read`, or binary 4.1, see `msh_read_binary`),
/// `.inp` (Abaqus/CalculiX, see `inp_read`), `.vtu` (VTK XML, see `vtu_read`), `.vtk`
/// (legacy VTK, see `vtk_read`), `.mesh` (Medit ASCII, as fTetWild, CGAL and MMG write it,
/// see `medit_read`), `.node` or `.ele` (TetGen: both files of the same name, and its
/// `.face` when present, see `tetgen_read`).
///
/// # Errors
/// [`MeshReadError`]: unknown extension, unreadable file or malformed content; one line
/// naming the file (for TetGen, the file of the pair where the problem is).
pub fn read_mesh(path: &Path) -> Result<MeshFile, MeshReadError> {
    let file = path.display().to_string();
    let reader = match MeshReader::of(path) {
        Some(MeshReader::Msh) => {
            return parse_bytes(path, |b| {
                if super::msh_read_binary::is_binary_msh(b) {
                    super::msh_read_binary::parse_msh_binary(b)
                } else {
                    super::msh_read::parse_msh(&String::from_utf8_lossy(b))
                }
            })
        }
        Some(MeshReader::Inp) => super::inp_read::parse_inp,
        Some(MeshReader::Medit) => super::medit_read::parse_medit,
        Some(MeshReader::Vtu) => return super::vtu_read::read_vtu(path),
        Some(MeshReader::Vtk) => return parse_bytes(path, super::vtk_read::parse_vtk),
        Some(MeshReader::TetGen) => return super::tetgen_read::read_tetgen(path),
        None => return Err(MeshReadError::UnknownFormat { file }),
    };
    parse_file(path, reader)
}
