use std::path::PathBuf;

use thiserror::Error;

/// What was wrong with one field of one row.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum Problem {
    /// Not a number.
    #[error("not a number")]
    NotANumber,
    /// NaN or infinite.
    #[error("not a finite number")]
    NotFinite,
    /// A timestamp or date that does not exist or cannot be parsed.
    #[error("invalid or impossible timestamp")]
    BadTimestamp,
    /// A sensor the project does not know.
    #[error("unknown sensor (add it to the sensors file first)")]
    UnknownSensor,
    /// An invalid sensor id.
    #[error("invalid sensor id")]
    BadSensorId,
    /// An invalid modality name.
    #[error("invalid modality (expected e.g. `vw@30cm`)")]
    BadModality,
    /// A position out of range.
    #[error("invalid position")]
    BadPosition,
    /// The row has the wrong number of fields.
    #[error("wrong number of fields")]
    FieldCount,
    /// The bytes are not UTF-8.
    #[error("not valid UTF-8")]
    NotUtf8,
    /// Same sensor, modality and time as an earlier row, with a different value.
    #[error("conflicts with line {first_line} (value {first_value})")]
    ConflictingDuplicate {
        /// Line of the earlier row.
        first_line: u64,
        /// The earlier row's value, as written.
        first_value: String,
    },
    /// Two sensors rows with the same id.
    #[error("duplicate sensor id (first on line {first_line})")]
    DuplicateSensor {
        /// Line of the first occurrence.
        first_line: u64,
    },
    /// A unit that differs from the one given earlier for the same modality.
    #[error("unit differs from `{expected}` given earlier for this modality")]
    UnitMismatch {
        /// The unit seen first.
        expected: String,
    },
}

/// An ingest failure. Every variant names the file; row-level ones name line (1-based, the
/// header is line 1), column and the offending value.
#[derive(Debug, Error)]
pub enum IngestError {
    /// The file could not be read.
    #[error("{path}: cannot read: {source}", path = path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// The file has no header line.
    #[error("{path}: empty file: expected a header line", path = path.display())]
    Empty {
        /// The file.
        path: PathBuf,
    },
    /// A required column is absent from the header.
    #[error("{path}:1: missing column `{column}` (header has: {found})", path = path.display())]
    MissingColumn {
        /// The file.
        path: PathBuf,
        /// The column that was expected (alternatives separated by `|`).
        column: String,
        /// The header as read.
        found: String,
    },
    /// One field of one row is bad.
    #[error("{path}:{line}: column `{column}`: {problem}: {value:?}", path = path.display())]
    Field {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        line: u64,
        /// The column's header name.
        column: String,
        /// The offending text.
        value: String,
        /// What is wrong with it.
        problem: Problem,
    },
    /// A setting given to the reader is invalid for this file.
    #[error("{path}: {message}", path = path.display())]
    Options {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
}
