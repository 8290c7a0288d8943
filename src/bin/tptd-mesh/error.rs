//! Errors of a run: every failure displays as `{file}: {problem}` (see
//! [`tptd::pipeline::PipelineError`]).

use std::fmt;

use tptd::io::WriteError;
use tptd::pipeline::PipelineError;

/// An error about `file` as an [`anyhow::Error`]: displays as `{file}: {problem}`.
pub(crate) fn file_error(file: impl fmt::Display, problem: impl fmt::Display) -> anyhow::Error {
    PipelineError::file(file, problem).into()
}

/// Rewrites a [`WriteError`] as `{file}: {problem}`.
pub(crate) fn write_error(e: WriteError) -> anyhow::Error {
    PipelineError::from(e).into()
}
