//! The error of a run: one line `{file}: {problem}`, whether it is a usage error (an
//! output that would replace an input or another output, found before any work), whether
//! the system refused a file (missing, unreadable, not writable), and whether the run would
//! not fit in memory.

use std::fmt;
use std::io::ErrorKind;

use crate::io::{FileClash, MeshReadError, ReadError, WriteError};

/// Why a run failed: displays as one line naming the file (or the demo input, or the
/// option) and the problem.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PipelineError {
    message: String,
    usage: bool,
    io: bool,
    memory: bool,
    interrupted: bool,
}

impl PipelineError {
    /// An error about `file`: displays as `{file}: {problem}`.
    pub fn file(file: impl fmt::Display, problem: impl fmt::Display) -> Self {
        PipelineError {
            message: format!("{file}: {problem}"),
            usage: false,
            io: false,
            memory: false,
            interrupted: false,
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
            io: false,
            memory: false,
            interrupted: false,
        }
    }

    /// An error about `file` where the run's memory estimate exceeds the limit (or the memory
    /// available): displays as `{file}: {problem}`.
    pub(crate) fn memory(file: impl fmt::Display, problem: impl fmt::Display) -> Self {
        PipelineError {
            memory: true,
            ..Self::file(file, problem)
        }
    }

    /// The run about `file` stopped because its caller asked ([`crate::cancel::Cancel`]).
    pub(crate) fn interrupted(file: impl fmt::Display) -> Self {
        PipelineError {
            interrupted: true,
            ..Self::file(file, "interrupted; nothing written")
        }
    }

    /// An error whose message is `error`'s own, where the system refused a file.
    fn io(error: impl fmt::Display) -> Self {
        PipelineError {
            io: true,
            ..Self::other(error)
        }
    }

    /// Whether the run was refused for how it was asked (a command line exits with status 2
    /// then) rather than failing in the work.
    pub fn is_usage(&self) -> bool {
        self.usage
    }

    /// Whether the system refused a file of the run (missing, unreadable, a missing
    /// directory, not writable), rather than its content or the request being wrong (a
    /// binding raises `OSError` then).
    pub fn is_io(&self) -> bool {
        self.io
    }

    /// Whether the run was refused because it would not fit in memory (its estimate exceeds
    /// the memory limit or the memory available; a binding raises `MemoryError` then).
    pub fn is_memory(&self) -> bool {
        self.memory
    }

    /// Whether the run stopped because its caller asked (a binding raises
    /// `KeyboardInterrupt` then).
    pub fn is_interrupted(&self) -> bool {
        self.interrupted
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
            io: false,
            memory: false,
            interrupted: false,
        }
    }
}

impl From<WriteError> for PipelineError {
    /// Rewrites a [`WriteError`] as `{file}: {problem}`.
    fn from(e: WriteError) -> Self {
        match e {
            WriteError::IsDirectory { path } => {
                Self::io(format_args!("{}: is a directory", path.display()))
            }
            WriteError::NotRegularFile { path } => {
                Self::file(path.display(), "exists and is not a regular file")
            }
            WriteError::NoFileName { path } => Self::file(path.display(), "does not name a file"),
            WriteError::UnknownFormat { path } => Self::file(
                path.display(),
                "unknown output format; use a .msh, .inp or .vtu (tetrahedra) or .obj, .ply or \
                 .stl (isosurface) extension",
            ),
            WriteError::MissingDirectory { path, dir } => Self::io(format_args!(
                "{}: cannot write: directory '{}' does not exist",
                path.display(),
                dir.display()
            )),
            // a writer refusing an inconsistent mesh: the content, not the system
            WriteError::Io { path, source } if source.kind() == ErrorKind::InvalidInput => {
                Self::file(path.display(), format_args!("cannot write: {source}"))
            }
            WriteError::Io { path, source } => {
                Self::io(format_args!("{}: cannot write: {source}", path.display()))
            }
        }
    }
}

impl From<ReadError> for PipelineError {
    /// The reader's message; a file the system refused is marked ([`PipelineError::is_io`]).
    fn from(e: ReadError) -> Self {
        match e {
            ReadError::Io { .. } => Self::io(e),
            ReadError::Memory { .. } => PipelineError {
                memory: true,
                ..Self::other(e)
            },
            e => Self::other(e),
        }
    }
}

impl From<MeshReadError> for PipelineError {
    /// The mesh reader's message; a file the system refused is marked
    /// ([`PipelineError::is_io`]).
    fn from(e: MeshReadError) -> Self {
        match e {
            MeshReadError::Io { .. } | MeshReadError::Vtk(ReadError::Io { .. }) => Self::io(e),
            e => Self::other(e),
        }
    }
}
