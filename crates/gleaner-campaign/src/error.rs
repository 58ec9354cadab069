//! What writing or reading a simulation's results and report can fail on.

use std::path::Path;

use gleaner_app::AppError;

/// An error of `simulate`'s files: the file (and line, column and value) with what is wrong,
/// or the use case's own error.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A use case (the campaign, a dataset's reading) refused or failed.
    #[error(transparent)]
    App(#[from] AppError),
    /// A file or directory could not be read, written or created.
    #[error("{path}: {message}")]
    File {
        /// The file.
        path: String,
        /// What failed, with the OS message.
        message: String,
    },
    /// A results file holds a row that cannot be read back.
    #[error("{path}:{line}: {message}")]
    Malformed {
        /// The file.
        path: String,
        /// The line, from 1.
        line: usize,
        /// What is wrong, with the column and value.
        message: String,
    },
    /// A chart of the report could not be drawn.
    #[error(transparent)]
    Render(#[from] gleaner_render::RenderError),
    /// A mission's files could not be made (the demo's exports).
    #[error(transparent)]
    Files(#[from] gleaner_render::FileError),
    /// Formatting the report failed (writing into memory: never in practice).
    #[error("formatting the report failed")]
    Format(#[from] std::fmt::Error),
}

impl Error {
    /// A file error on `path`.
    pub(crate) fn file(path: &Path, message: impl std::fmt::Display) -> Self {
        Self::File {
            path: path.display().to_string(),
            message: message.to_string(),
        }
    }

    /// A malformed row at `path`:`line`.
    pub(crate) fn malformed(path: &Path, line: usize, message: impl std::fmt::Display) -> Self {
        Self::Malformed {
            path: path.display().to_string(),
            line,
            message: message.to_string(),
        }
    }
}

/// Shorthand for the simulator's file results.
pub type Result<T, E = Error> = std::result::Result<T, E>;
