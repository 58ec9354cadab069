//! Errors of the benchmark readers.

use std::path::PathBuf;

use thiserror::Error;

/// A benchmark file that cannot be read or understood.
#[derive(Debug, Error)]
pub enum FormatError {
    /// The file could not be read.
    #[error("{file}: cannot read: {source}")]
    Io {
        /// The file.
        file: PathBuf,
        /// The IO error.
        #[source]
        source: std::io::Error,
    },
    /// A benchmark path that does not exist.
    #[error("{}: no such file or directory", file.display())]
    NotFound {
        /// The path.
        file: PathBuf,
    },
    /// A field has a bad value.
    #[error("{file}:{line}: bad {field}: {message}")]
    Parse {
        /// The file (or instance name when parsing from a string).
        file: String,
        /// 1-based line number (0 when not tied to a line).
        line: usize,
        /// Which field.
        field: String,
        /// What is wrong, with the offending text.
        message: String,
    },
    /// The parsed data does not make a valid orienteering problem.
    #[error("{file}: invalid problem: {source}")]
    Problem {
        /// The file.
        file: String,
        /// The problem error.
        #[source]
        source: gleaner_orienteering::ProblemError,
    },
    /// A route does not satisfy the instance.
    #[error("{file}: invalid route: {message}")]
    Route {
        /// The instance.
        file: String,
        /// What is wrong.
        message: String,
    },
}

pub(crate) fn parse_err(
    file: &str,
    line: usize,
    field: &str,
    message: impl Into<String>,
) -> FormatError {
    FormatError::Parse {
        file: file.to_string(),
        line,
        field: field.to_string(),
        message: message.into(),
    }
}
