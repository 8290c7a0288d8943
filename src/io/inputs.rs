//! Which files a run reads and writes: [`input_files`] lists the files an input consists of
//! (reading headers only), and [`check_clashes`] refuses an output that is one of them or
//! another output, comparing files by identity ([`same_file`]), not spelling.

use std::path::{Path, PathBuf};

use super::atomic::same_file;
use super::formats::VolumeFormat;
use super::read_common::ReadError;

/// The files the readers read for the input `path`: `path` itself first, then the files its
/// header names — the detached data file of an NRRD header (`data file:`) or a MetaImage
/// header (`ElementDataFile`), and the function file of a Plot3D grid (`function`, else the
/// `.q` or `.f` next to it; `function` is ignored for other inputs). A closed surface
/// (`.obj`, `.stl`, `.ply`) is its one file: an `.obj`'s material library is not read. Reads
/// only the headers, never the samples.
///
/// Multi-file data (file lists and patterns) are refused here as the readers refuse them.
/// An extension no reader knows gives `path` alone (the reader refuses it later).
///
/// # Errors
/// The readers' [`ReadError`]s about the header: it cannot be read or is malformed, or a
/// Plot3D grid has no function file.
pub fn input_files(path: &Path, function: Option<&Path>) -> Result<Vec<PathBuf>, ReadError> {
    match VolumeFormat::of(path) {
        Some(VolumeFormat::Nrrd) => super::nrrd::nrrd_files(path),
        Some(VolumeFormat::MetaImage) => super::mhd::mhd_files(path),
        Some(VolumeFormat::Plot3d) => {
            let f = super::plot3d::function_file(path, function)?;
            Ok(vec![path.to_path_buf(), f])
        }
        // a closed surface, a `.npy`, a NIfTI image, a `.vts`: one file
        _ => Ok(vec![path.to_path_buf()]),
    }
}

/// A file of a run with what it is, for messages: `-o` or `--report` for an output, `the
/// input` for an input.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RunFile {
    /// What the file is, e.g. `--json` or `the input`.
    pub role: String,
    /// The file as the user named it.
    pub path: PathBuf,
}

impl RunFile {
    /// The file `path` in the role `role`.
    pub fn new(role: impl Into<String>, path: impl Into<PathBuf>) -> Self {
        RunFile {
            role: role.into(),
            path: path.into(),
        }
    }
}

/// The files of input `path` ([`input_files`]) as run files: the input itself, then the files
/// read with it (`read with the input PATH`).
///
/// # Errors
/// As [`input_files`].
pub fn input_run_files(path: &Path, function: Option<&Path>) -> Result<Vec<RunFile>, ReadError> {
    let read_with = format!("read with the input {}", path.display());
    Ok(input_files(path, function)?
        .into_iter()
        .enumerate()
        .map(|(n, f)| RunFile::new(if n == 0 { "the input" } else { &read_with }, f))
        .collect())
}

/// The outputs that are given, each named by its option (`-o`, `--report`, …), in order.
pub fn output_run_files(outputs: &[(&str, Option<&Path>)]) -> Vec<RunFile> {
    outputs
        .iter()
        .filter_map(|&(role, path)| path.map(|p| RunFile::new(role, p)))
        .collect()
}

/// An output that is the same file as an input or as another output. Displays as one line
/// naming both files.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "{}: {} names the same file as {} ({}); refusing to overwrite it",
    .output.path.display(),
    .output.role,
    .other.path.display(),
    .other.role
)]
pub struct FileClash {
    /// The output.
    pub output: RunFile,
    /// The input or the earlier output it is the same file as.
    pub other: RunFile,
}

/// Checks that no output is the same file ([`same_file`]: device and inode after resolving
/// links, or the canonical path of a file that does not exist yet) as an input or as another
/// output. Nothing is created or opened.
///
/// # Errors
/// The first [`FileClash`]: outputs in order, each against every input, then against the
/// outputs before it.
pub fn check_clashes(inputs: &[RunFile], outputs: &[RunFile]) -> Result<(), FileClash> {
    for (n, out) in outputs.iter().enumerate() {
        let others = inputs.iter().chain(&outputs[..n]);
        if let Some(other) = others.into_iter().find(|f| same_file(&out.path, &f.path)) {
            return Err(FileClash {
                output: out.clone(),
                other: other.clone(),
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs;

    #[test]
    fn headers_name_their_data_and_function_files() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let nhdr = d.join("v.nhdr");
        fs::write(
            &nhdr,
            "NRRD0004\ntype: double\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n\
             endian: little\ndata file: data.msh\n",
        )
        .unwrap();
        assert_eq!(
            input_files(&nhdr, None).unwrap(),
            [nhdr.clone(), d.join("data.msh")]
        );
        let mhd = d.join("v.mhd");
        fs::write(
            &mhd,
            "NDims = 3\nDimSize = 2 2 2\nElementType = MET_DOUBLE\nElementDataFile = v.raw\n",
        )
        .unwrap();
        assert_eq!(
            input_files(&mhd, None).unwrap(),
            [mhd.clone(), d.join("v.raw")]
        );
        let mha = d.join("v.mha");
        let mut bytes =
            b"NDims = 3\nDimSize = 2 2 2\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n"
                .to_vec();
        bytes.extend([0xff, 0, 1, 2, b'\n', 3, 4, 5]);
        fs::write(&mha, bytes).unwrap();
        assert_eq!(input_files(&mha, None).unwrap(), [mha]);
        let xyz = d.join("g.xyz");
        assert!(input_files(&xyz, None).is_err(), "no .q or .f next to it");
        fs::write(d.join("g.f"), b"").unwrap();
        assert_eq!(
            input_files(&xyz, None).unwrap(),
            [xyz.clone(), d.join("g.f")]
        );
        let q = d.join("other.q");
        assert_eq!(input_files(&xyz, Some(&q)).unwrap(), [xyz.clone(), q]);
        let npy = d.join("v.npy");
        assert_eq!(input_files(&npy, Some(&nhdr)).unwrap(), [npy]);
        let obj = d.join("s.OBJ");
        assert_eq!(input_files(&obj, None).unwrap(), [obj]);
    }

    #[test]
    fn clashes_are_found_by_identity() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        fs::write(d.join("in.npy"), b"x").unwrap();
        fs::create_dir(d.join("sub")).unwrap();
        let inputs = [RunFile::new("the input", d.join("in.npy"))];
        let ok = [
            RunFile::new("-o", d.join("m.vtu")),
            RunFile::new("--report", d.join("r.json")),
        ];
        assert_eq!(check_clashes(&inputs, &ok), Ok(()));
        let e = check_clashes(&inputs, &[RunFile::new("-o", d.join("sub/../in.npy"))]);
        assert_eq!(e.unwrap_err().other, inputs[0]);
        // Two outputs that do not exist yet, spelled differently.
        let two = [
            RunFile::new("--json", d.join("new.json")),
            RunFile::new("--spectrum", d.join("sub/../new.json")),
        ];
        let e = check_clashes(&inputs, &two).unwrap_err();
        assert_eq!(
            (e.output.role.as_str(), e.other.role.as_str()),
            ("--spectrum", "--json")
        );
        assert_eq!(e.to_string().lines().count(), 1);
    }
}
