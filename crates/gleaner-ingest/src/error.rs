use std::path::PathBuf;

use thiserror::Error;

/// What was wrong with one field of one row.
#[derive(Debug, Clone, PartialEq, Error)]
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
    /// A column name that appears twice in the header (the first would silently win).
    #[error("column repeated (first as column {first_column})")]
    DuplicateColumn {
        /// 1-based position of the first column with this name.
        first_column: usize,
    },
    /// A value outside the plausible physical range of its modality's unit.
    #[error(
        "outside the plausible range {min}..={max} {unit} (override with `[ingest] value_limits`)"
    )]
    OutOfRange {
        /// The unit (or quantity) the range is for.
        unit: String,
        /// Lowest plausible value.
        min: f64,
        /// Highest plausible value.
        max: f64,
    },
    /// A sensor elevation outside what is plausible on Earth's surface.
    #[error("elevation outside {min}..={max} m")]
    Elevation {
        /// Lowest plausible elevation, metres.
        min: f64,
        /// Highest plausible elevation, metres.
        max: f64,
    },
    /// A valid date outside the years readings can plausibly carry.
    #[error("date outside {min_year}..={max_year}")]
    ImplausibleTime {
        /// Earliest accepted year.
        min_year: i64,
        /// Latest accepted year.
        max_year: i64,
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
    #[error("{path}:1: missing column `{column}` (header has: {found})", path = path.display(), found = Shown(found))]
    MissingColumn {
        /// The file.
        path: PathBuf,
        /// The column that was expected (alternatives separated by `|`).
        column: String,
        /// The header as read.
        found: String,
    },
    /// One field of one row is bad.
    #[error("{path}:{line}: column `{column}`: {problem}: {value}", path = path.display(), column = Shown(column), value = Quoted(value))]
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

/// Longest text an error message repeats from the input, in characters; longer values are cut
/// with their full length noted, so a 10 MB field never floods a terminal or a log.
pub const SHOWN_CHARS: usize = 80;

/// Cuts `text` to [`SHOWN_CHARS`] characters, noting how long it was.
pub fn shorten(text: &str) -> std::borrow::Cow<'_, str> {
    match text.char_indices().nth(SHOWN_CHARS) {
        None => std::borrow::Cow::Borrowed(text),
        Some((end, _)) => {
            std::borrow::Cow::Owned(format!("{}… ({} bytes in all)", &text[..end], text.len()))
        }
    }
}

/// Displays a text cut by [`shorten`].
struct Shown<'a>(&'a str);

impl std::fmt::Display for Shown<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&shorten(self.0))
    }
}

/// A value quoted and escaped, cut by [`shorten`] (the note of the cut outside the quotes).
pub fn quoted(text: &str) -> String {
    Quoted(text).to_string()
}

/// A number for a message: as written by Rust when short, else in scientific notation (so
/// 1e300 does not print as 301 digits).
pub fn number(x: f64) -> String {
    let plain = x.to_string();
    if plain.len() <= 24 {
        plain
    } else {
        format!("{x:e}")
    }
}

/// Displays a value quoted and escaped (`"wet"`, `"s\u{fffd}1"`), cut by [`shorten`].
struct Quoted<'a>(&'a str);

impl std::fmt::Display for Quoted<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.0.char_indices().nth(SHOWN_CHARS) {
            None => write!(f, "{:?}", self.0),
            Some((end, _)) => write!(f, "{:?}… ({} bytes in all)", &self.0[..end], self.0.len()),
        }
    }
}
