//! Volume input by file extension: [`read_volume`] (regular volumes) and
//! [`read_curvilinear`] (curvilinear grids) choose the reader from the extension table in
//! [`super::formats`]; the readers share [`super::read_common`], never this dispatcher.

use std::path::Path;

use super::formats::VolumeFormat;
use super::read_common::ReadError;
use crate::grid::{CurvilinearGrid, ScalarGrid};

/// Reads a 3-D scalar volume, choosing the reader by file extension (case-insensitive):
///
/// | extension          | reader                       |
/// |--------------------|------------------------------|
/// | `.npy`             | [`super::npy::read_npy`]     |
/// | `.nrrd`, `.nhdr`   | [`super::nrrd::read_nrrd`]   |
/// | `.nii`, `.nii.gz`  | [`super::nifti::read_nifti`] |
/// | `.mhd`, `.mha`     | [`super::mhd::read_mhd`]     |
///
/// # Errors
/// [`ReadError::UnknownFormat`] for any other extension, otherwise whatever the chosen
/// reader returns. Never panics, whatever the file holds.
pub fn read_volume(path: &Path) -> Result<ScalarGrid, ReadError> {
    match VolumeFormat::of(path) {
        Some(VolumeFormat::Npy) => super::npy::read_npy(path),
        Some(VolumeFormat::Nrrd) => super::nrrd::read_nrrd(path),
        Some(VolumeFormat::Nifti) => super::nifti::read_nifti(path),
        Some(VolumeFormat::MetaImage) => super::mhd::read_mhd(path),
        Some(VolumeFormat::Vts | VolumeFormat::Plot3d) | None => {
            Err(ReadError::unknown_format(path))
        }
    }
}

/// Whether `path` names a curvilinear-grid file ([`read_curvilinear`]): `.vts` or a Plot3D
/// grid `.xyz`.
pub fn is_curvilinear(path: &Path) -> bool {
    VolumeFormat::of(path).is_some_and(VolumeFormat::is_curvilinear)
}

/// Whether `path` as written ends in a Plot3D grid's `.xyz` (any case), the input that
/// takes a function file.
pub fn is_plot3d(path: &Path) -> bool {
    VolumeFormat::of_whole_path(path) == Some(VolumeFormat::Plot3d)
}

/// Reads a curvilinear grid by extension: `.vts` ([`super::vts::read_vts`]) or a Plot3D grid
/// `.xyz` with its function file ([`super::plot3d::read_plot3d`]; `function` names it when it
/// is not the `.q` / `.f` next to the grid). `field` picks the scalar (default the first).
///
/// # Errors
/// [`ReadError::UnknownFormat`] for another extension, otherwise the reader's errors.
pub fn read_curvilinear(
    path: &Path,
    function: Option<&Path>,
    field: Option<&str>,
) -> Result<CurvilinearGrid, ReadError> {
    match VolumeFormat::of_whole_path(path) {
        Some(VolumeFormat::Vts) => super::vts::read_vts(path, field),
        Some(VolumeFormat::Plot3d) => super::plot3d::read_plot3d(path, function, field),
        _ => Err(ReadError::unknown_format(path)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_extension_lists_supported() {
        let e = read_volume(Path::new("volume.xyz")).unwrap_err();
        assert!(matches!(e, ReadError::UnknownFormat { .. }));
        let s = e.to_string();
        assert!(
            s.contains("volume.xyz") && s.contains(".nii.gz") && s.contains(".npy"),
            "{s}"
        );
    }
}
