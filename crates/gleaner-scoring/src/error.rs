//! The application layer's error type.

use gleaner_store::StoreError;
use thiserror::Error;

/// Everything a use case can refuse or fail on. Messages name the file, line, field and value
/// where there is one, and never repeat their source's text (a caller printing the chain of
/// sources prints each cause once).
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum AppError {
    /// The store failed or refused a write; nothing of the use case was written.
    #[error(transparent)]
    Store(#[from] StoreError),
    /// A readings or sensors file is malformed; nothing was written.
    #[error(transparent)]
    Ingest(#[from] gleaner_ingest::IngestError),
    /// The project file is missing, unreadable or has an invalid setting.
    #[error("{path}: {reason}")]
    Settings {
        /// The project file.
        path: String,
        /// What is wrong, with the setting's name and value.
        reason: String,
    },
    /// An argument or input value that cannot be used, with the offending value.
    #[error("{0}")]
    Invalid(String),
    /// Something asked for does not exist (a mission id, a cell).
    #[error("no {what} {id}")]
    NotFound {
        /// What was looked for (`mission`, `cell`).
        what: &'static str,
        /// Its id as given.
        id: String,
    },
    /// The request conflicts with the project's state (a mission already recorded as flown).
    #[error("{0}")]
    Conflict(String),
    /// A core computation rejected its inputs (grid, utility, energy, planner).
    #[error("{context}: {message}")]
    Core {
        /// The step (`cell grid`, `scoring`, `energy model`, `planner`).
        context: &'static str,
        /// The core's message.
        message: String,
    },
    /// A file could not be read or written.
    #[error("{path}: {message}")]
    Io {
        /// The file.
        path: String,
        /// The OS message.
        message: String,
    },
    /// The caller gave up on the work (the application layer's `Progress::cancelled`);
    /// nothing was written.
    #[error("the work was cancelled")]
    Cancelled,
}

impl AppError {
    /// A core error in `context`.
    pub fn core(context: &'static str, e: impl std::fmt::Display) -> Self {
        Self::Core {
            context,
            message: e.to_string(),
        }
    }
    /// An IO error on `path`.
    pub fn io(path: &std::path::Path, e: impl std::fmt::Display) -> Self {
        Self::Io {
            path: path.display().to_string(),
            message: e.to_string(),
        }
    }
}

/// Shorthand for the application layer's results.
pub type Result<T, E = AppError> = std::result::Result<T, E>;
