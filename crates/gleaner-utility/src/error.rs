//! Errors of the utility engine.

use thiserror::Error;

/// Everything that can go wrong in this crate: invalid configuration or invalid inputs.
/// Messages carry the offending values and, where there is one, the cell.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum UtilityError {
    /// A configuration value is out of range.
    #[error("invalid utility configuration: {0}")]
    Config(String),
    /// A series' times and values have different lengths.
    #[error("cell {cell}, modality {modality}: {times} times but {values} values")]
    SeriesLength {
        /// Cell position.
        cell: usize,
        /// Modality position.
        modality: usize,
        /// Number of timestamps.
        times: usize,
        /// Number of values.
        values: usize,
    },
    /// A series' timestamps are not strictly increasing.
    #[error("cell {cell}, modality {modality}: timestamps not strictly increasing at {time} s")]
    SeriesOrder {
        /// Cell position.
        cell: usize,
        /// Modality position.
        modality: usize,
        /// The first timestamp out of order, s.
        time: i64,
    },
    /// A series value is NaN or infinite (leave missing readings out instead).
    #[error("cell {cell}, modality {modality}: non-finite value {value} at {time} s")]
    NonFinite {
        /// Cell position.
        cell: usize,
        /// Modality position.
        modality: usize,
        /// Timestamp, s.
        time: i64,
        /// The value.
        value: f64,
    },
    /// A cell has the wrong number of modality series.
    #[error("cell {cell}: {got} modality series, expected {expected}")]
    ModalityCount {
        /// Cell position.
        cell: usize,
        /// Number of series given.
        got: usize,
        /// Number of modalities configured.
        expected: usize,
    },
    /// A cell has no sensors (only non-empty cells are candidates, docs/method.md §1).
    #[error("cell {0} has no sensors")]
    NoSensors(usize),
    /// A neighbour index is out of range or the cell itself.
    #[error("cell {cell}: invalid neighbour {neighbour} (there are {cells} cells)")]
    Neighbour {
        /// Cell position.
        cell: usize,
        /// The bad neighbour index.
        neighbour: usize,
        /// Number of cells.
        cells: usize,
    },
    /// Class probabilities are invalid.
    #[error("cell {cell}: {reason}")]
    Probabilities {
        /// The cell's id (as supplied) or position.
        cell: String,
        /// What is wrong, with the values.
        reason: String,
    },
    /// A reading refers to a cell, sensor or modality that does not exist.
    #[error("reading refers to {what} {index}, but there are only {count}")]
    ReadingIndex {
        /// "cell", "sensor" or "modality".
        what: &'static str,
        /// The index given.
        index: usize,
        /// How many exist.
        count: usize,
    },
    /// A reading is older than the retention horizon of the incremental state.
    #[error("reading at {time} s is older than the retention horizon {horizon} s")]
    BeyondRetention {
        /// The reading's time, s.
        time: i64,
        /// The oldest accepted time, s.
        horizon: i64,
    },
    /// The incremental statistics only support the all-history window.
    #[error("incremental scoring supports only the all-history window, got a window of {0} s")]
    WindowNotIncremental(i64),
    /// Serialised state could not be decoded: wrong magic or version, truncated, or
    /// inconsistent (e.g. [`IncrementalState::from_bytes`](crate::IncrementalState::from_bytes)).
    #[error("cannot decode {what} at byte {offset}: {reason}")]
    Decode {
        /// What was being decoded.
        what: &'static str,
        /// Byte offset where decoding stopped.
        offset: usize,
        /// What is wrong, with the values.
        reason: String,
    },
    /// The condition model could not be built or used.
    #[error("condition model: {0}")]
    Model(String),
}
