//! The volume input formats by extension: one table names each extension once, and the
//! dispatcher ([`super::read_volume`], [`super::read_curvilinear`]), [`super::input_files`]
//! and the unknown-format message all read it.

use std::path::Path;

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

/// The supported extensions for messages: the volume ones, then the curvilinear ones in
/// parentheses.
pub(crate) fn supported_extensions() -> String {
    let list = |curvilinear: bool| {
        let exts = EXTENSIONS
            .iter()
            .filter(|(_, f)| f.is_curvilinear() == curvilinear);
        exts.map(|(ext, _)| *ext).collect::<Vec<_>>().join(", ")
    };
    format!("{} (curvilinear: {})", list(false), list(true))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_message_lists_every_extension() {
        assert_eq!(
            supported_extensions(),
            ".npy, .nrrd, .nhdr, .nii, .nii.gz, .mhd, .mha (curvilinear: .vts, .xyz)"
        );
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
