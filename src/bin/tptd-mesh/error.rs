//! Errors of a run: every failure displays as `{file}: {problem}`.

use std::fmt;

use tptd::io::WriteError;

/// An error about one file (or the demo input): displays as `{file}: {problem}`.
#[derive(Debug)]
pub(crate) struct FileError {
    file: String,
    problem: String,
}

impl fmt::Display for FileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.file, self.problem)
    }
}

impl std::error::Error for FileError {}

/// A [`FileError`] as an [`anyhow::Error`].
pub(crate) fn file_error(file: impl fmt::Display, problem: impl fmt::Display) -> anyhow::Error {
    FileError {
        file: file.to_string(),
        problem: problem.to_string(),
    }
    .into()
}

/// Rewrites a [`WriteError`] as `{file}: {problem}`.
pub(crate) fn write_error(e: WriteError) -> anyhow::Error {
    match e {
        WriteError::IsDirectory { path } => file_error(path.display(), "is a directory"),
        WriteError::NotRegularFile { path } => {
            file_error(path.display(), "exists and is not a regular file")
        }
        WriteError::NoFileName { path } => file_error(path.display(), "does not name a file"),
        WriteError::UnknownFormat { path } => file_error(
            path.display(),
            "unknown output format; use a .msh, .inp or .vtu (tetrahedra) or .obj, .ply or .stl \
             (isosurface) extension",
        ),
        WriteError::MissingDirectory { path, dir } => file_error(
            path.display(),
            format_args!("cannot write: directory '{}' does not exist", dir.display()),
        ),
        WriteError::Io { path, source } => {
            file_error(path.display(), format_args!("cannot write: {source}"))
        }
    }
}
