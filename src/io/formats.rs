//! Every file format by extension, each extension named once: the volume readers
//! ([`VolumeFormat`]; the dispatchers [`super::read_volume`] and [`super::read_curvilinear`],
//! [`super::input_files`] and the unknown-format message read its table), the mesh readers
//! ([`MeshReader`], for [`super::read_mesh`]), the mesh writers ([`MeshFormat`], for
//! [`super::write_mesh`]), the surface formats ([`SurfaceFormat`]: the isosurfaces
//! [`super::write_surface`] writes and the closed surfaces [`super::read_surface`] reads) and
//! the transfer-function writers ([`TransferFormat`]).

use std::path::Path;

use super::atomic::WriteError;

/// A volume input format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum VolumeFormat {
    /// NumPy `.npy` ([`super::npy`]).
    Npy,
    /// NRRD, attached `.nrrd` or detached `.nhdr` ([`super::nrrd`]).
    Nrrd,
    /// NIfTI-1 or NIfTI-2, `.nii` or `.nii.gz` ([`super::nifti`]).
    Nifti,
    /// MetaImage, `.mhd` or `.mha` ([`super::mhd`]).
    MetaImage,
    /// VTK XML StructuredGrid `.vts`, a curvilinear grid ([`super::vts`]).
    Vts,
    /// Plot3D grid `.xyz` with its function file, a curvilinear grid ([`super::plot3d`]).
    Plot3d,
}

/// Every extension (lower case, with its dot) and its format, in the order messages list
/// them. No extension ends another, so the order does not decide a match.
const EXTENSIONS: [(&str, VolumeFormat); 9] = [
    (".npy", VolumeFormat::Npy),
    (".nrrd", VolumeFormat::Nrrd),
    (".nhdr", VolumeFormat::Nrrd),
    (".nii", VolumeFormat::Nifti),
    (".nii.gz", VolumeFormat::Nifti),
    (".mhd", VolumeFormat::MetaImage),
    (".mha", VolumeFormat::MetaImage),
    (".vts", VolumeFormat::Vts),
    (".xyz", VolumeFormat::Plot3d),
];

impl VolumeFormat {
    /// Whether the format holds a curvilinear grid ([`super::read_curvilinear`]) rather than
    /// a regular volume ([`super::read_volume`]).
    pub(crate) fn is_curvilinear(self) -> bool {
        matches!(self, VolumeFormat::Vts | VolumeFormat::Plot3d)
    }

    /// The format whose extension ends the file name of `path` (any case); `None` for any
    /// other extension or no file name.
    pub(crate) fn of(path: &Path) -> Option<Self> {
        let name = path.file_name().map(|n| n.to_string_lossy());
        Self::of_name(&name.unwrap_or_default())
    }

    /// The format whose extension ends `path` as written (any case): unlike
    /// [`VolumeFormat::of`], a trailing separator or `.` component names no format.
    pub(crate) fn of_whole_path(path: &Path) -> Option<Self> {
        Self::of_name(&path.to_string_lossy())
    }

    fn of_name(name: &str) -> Option<Self> {
        let name = name.to_ascii_lowercase();
        EXTENSIONS
            .iter()
            .find(|(ext, _)| name.ends_with(ext))
            .map(|&(_, format)| format)
    }
}

/// The supported input extensions for messages: the volume ones, then the curvilinear
/// ones and the closed-surface ones in parentheses.
pub(crate) fn supported_extensions() -> String {
    let list = |curvilinear: bool| {
        let exts = EXTENSIONS
            .iter()
            .filter(|(_, f)| f.is_curvilinear() == curvilinear);
        exts.map(|(ext, _)| *ext).collect::<Vec<_>>().join(", ")
    };
    let surfaces: Vec<String> = SURFACE_FORMATS
        .iter()
        .map(|(e, _)| format!(".{e}"))
        .collect();
    format!(
        "{} (curvilinear: {}; closed surfaces: {})",
        list(false),
        list(true),
        surfaces.join(", ")
    )
}

/// The surface extensions for messages: `.obj, .ply or .stl`.
pub(crate) fn surface_extensions() -> String {
    let exts: Vec<String> = SURFACE_FORMATS
        .iter()
        .map(|(e, _)| format!(".{e}"))
        .collect();
    match exts.split_last() {
        Some((last, rest)) if !rest.is_empty() => format!("{} or {last}", rest.join(", ")),
        _ => exts.join(""),
    }
}

/// The extension of `path` (what follows its file name's last dot), lower case.
fn extension(path: &Path) -> Option<String> {
    path.extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
}

/// The format of `table` for the extension of `path`.
fn by_extension<F: Copy>(table: &[(&str, F)], path: &Path) -> Option<F> {
    let ext = extension(path)?;
    table.iter().find(|(e, _)| *e == ext).map(|&(_, f)| f)
}

/// A mesh input format ([`super::read_mesh`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum MeshReader {
    /// Gmsh `.msh`, ASCII 4.1 and 2.2 or binary 4.1.
    Msh,
    /// Abaqus / CalculiX `.inp`.
    Inp,
    /// VTK XML UnstructuredGrid `.vtu`.
    Vtu,
    /// Legacy VTK `.vtk`.
    Vtk,
    /// Medit `.mesh`.
    Medit,
    /// TetGen `.node` / `.ele` (with `.face`).
    TetGen,
}

/// The mesh readers' extensions (lower case, without the dot).
const MESH_READERS: [(&str, MeshReader); 7] = [
    ("msh", MeshReader::Msh),
    ("inp", MeshReader::Inp),
    ("vtu", MeshReader::Vtu),
    ("vtk", MeshReader::Vtk),
    ("mesh", MeshReader::Medit),
    ("node", MeshReader::TetGen),
    ("ele", MeshReader::TetGen),
];

impl MeshReader {
    /// The reader of the extension of `path` (any case); `None` for any other.
    pub(crate) fn of(path: &Path) -> Option<MeshReader> {
        by_extension(&MESH_READERS, path)
    }
}

/// An output mesh format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MeshFormat {
    /// Gmsh `.msh`, ASCII 4.1 / 2.2 or binary 4.1 ([`super::msh`]).
    Msh,
    /// Abaqus / CalculiX `.inp` ([`super::inp`]).
    Inp,
    /// VTK XML UnstructuredGrid `.vtu` ([`super::vtu`]).
    Vtu,
}

/// The mesh writers' extensions (lower case, without the dot).
const MESH_WRITERS: [(&str, MeshFormat); 3] = [
    ("msh", MeshFormat::Msh),
    ("inp", MeshFormat::Inp),
    ("vtu", MeshFormat::Vtu),
];

impl MeshFormat {
    /// The format named by the extension of `path` (case-insensitive): `.msh`, `.inp` or
    /// `.vtu`.
    ///
    /// # Errors
    /// [`WriteError::UnknownFormat`] for any other extension or none.
    pub fn from_path(path: &Path) -> Result<Self, WriteError> {
        by_extension(&MESH_WRITERS, path).ok_or_else(|| WriteError::UnknownFormat {
            path: path.to_path_buf(),
        })
    }
}

/// A triangle-surface format: an isosurface output, or a closed-surface input meshed as the
/// solid it bounds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SurfaceFormat {
    /// Wavefront `.obj` ([`super::obj`]).
    Obj,
    /// Stanford `.ply` ([`super::ply`]).
    Ply,
    /// `.stl` ([`super::stl`]).
    Stl,
}

/// The surface formats' extensions (lower case, without the dot), written and read alike.
const SURFACE_FORMATS: [(&str, SurfaceFormat); 3] = [
    ("obj", SurfaceFormat::Obj),
    ("ply", SurfaceFormat::Ply),
    ("stl", SurfaceFormat::Stl),
];

impl SurfaceFormat {
    /// The surface format named by the extension of `path` (case-insensitive): `.obj`, `.ply`
    /// or `.stl`; `None` for any other.
    pub fn from_path(path: &Path) -> Option<Self> {
        by_extension(&SURFACE_FORMATS, path)
    }
}

/// An output format for a transfer function.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TransferFormat {
    /// ParaView colour-map preset (JSON).
    ParaView,
    /// Comma-separated `value,r,g,b,opacity`.
    Csv,
}

/// The transfer-function writers' extensions (lower case, without the dot).
const TRANSFER_WRITERS: [(&str, TransferFormat); 2] = [
    ("json", TransferFormat::ParaView),
    ("csv", TransferFormat::Csv),
];

impl TransferFormat {
    /// The format named by the extension of `path` (`.json`, `.csv`, any case).
    pub fn from_path(path: &Path) -> Option<Self> {
        by_extension(&TRANSFER_WRITERS, path)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_message_lists_every_extension() {
        assert_eq!(
            supported_extensions(),
            ".npy, .nrrd, .nhdr, .nii, .nii.gz, .mhd, .mha (curvilinear: .vts, .xyz; closed \
             surfaces: .obj, .ply, .stl)"
        );
        assert_eq!(surface_extensions(), ".obj, .ply or .stl");
    }

    #[test]
    fn formats_follow_the_file_name_in_any_case() {
        let of = |p: &str| VolumeFormat::of(Path::new(p));
        assert_eq!(of("dir.npy/a.NII.GZ"), Some(VolumeFormat::Nifti));
        assert_eq!(of("a.nii"), Some(VolumeFormat::Nifti));
        assert_eq!(of("a.Nhdr"), Some(VolumeFormat::Nrrd));
        assert_eq!(of("a.gz"), None);
        assert_eq!(of(".."), None);
        assert_eq!(of("x.vts/"), Some(VolumeFormat::Vts));
        assert_eq!(VolumeFormat::of_whole_path(Path::new("x.vts/")), None);
        assert_eq!(
            VolumeFormat::of_whole_path(Path::new("X.XYZ")),
            Some(VolumeFormat::Plot3d)
        );
    }
}
