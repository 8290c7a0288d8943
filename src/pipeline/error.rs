//! The error of a run: one line `{file}: {problem}`, and whether it is a usage error (an
//! output that would replace an input or another output, found before any work).

use std::fmt;

use crate::io::{FileClash, WriteError};

/// Why a run failed: displays as one line naming the file (or the demo input, or the
/// option) and the problem.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PipelineError {
    message: String,
    usage: bool,
}

impl PipelineError {
    /// An error about `file`: displays as `{file}: {problem}`.
    pub fn file(file: impl fmt::Display, problem: impl fmt::Display) -> Self {
        PipelineError {
            message: format!("{file}: {problem}"),
            usage: false,
        }
    }

    /// A usage error about `file` (a request refused for how it was asked): displays as
    /// `{file}: {problem}`.
    pub(crate) fn usage(file: impl fmt::Display, problem: impl fmt::Display) -> Self {
        PipelineError {
            usage: true,
            ..Self::file(file, problem)
        }
    }

    /// An error whose message is `error`'s own (its `Display`).
    pub fn other(error: impl fmt::Display) -> Self {
        PipelineError {
            message: error.to_string(),
            usage: false,
        }
    }

    /// Whether the run was refused for how it was asked (a command line exits with status 2
    /// then) rather than failing in the work.
    pub fn is_usage(&self) -> bool {
        self.usage
    }

    /// The message (as displayed).
    pub fn message(&self) -> &str {
        &self.message
    }
}

impl fmt::Display for PipelineError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for PipelineError {}

impl From<FileClash> for PipelineError {
    /// An output that is an input or another output: a usage error.
    fn from(e: FileClash) -> Self {
        PipelineError {
            message: e.to_string(),
            usage: true,
        }
    }
}

impl From<WriteError> for PipelineError {
    /// Rewrites a [`WriteError`] as `{file}: {problem}`.
    fn from(e: WriteError) -> Self {
        match e {
            WriteError::IsDirectory { path } => Self::file(path.display(), "is a directory"),
            WriteError::NotRegularFile { path } => {
                Self::file(path.display(), "exists and is not a regular file")
            }
            WriteError::NoFileName { path } => Self::file(path.display(), "does not name a file"),
            WriteError::UnknownFormat { path } => Self::file(
                path.display(),
                "unknown output format; use a .msh, .inp or .vtu (tetrahedra) or .obj, .ply or \
                 .stl (isosurface) extension",
            ),
            WriteError::MissingDirectory { path, dir } => Self::file(
                path.display(),
                format_args!("cannot write: directory '{}' does not exist", dir.display()),
            ),
            WriteError::Io { path, source } => {
                Self::file(path.display(), format_args!("cannot write: {source}"))
            }
        }
    }
}
