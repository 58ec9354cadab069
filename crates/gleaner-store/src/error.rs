//! The store's error type.

use std::fmt;

use gleaner_field::{Modality, SensorId, UnixSeconds};
use thiserror::Error;

use crate::Conflict;

/// Everything that can go wrong in the store. Each message carries the offending values.
///
/// A write method that returns an error other than [`StoreError::Backend`] has written nothing;
/// a use case whose closure returns an error leaves the database exactly as it was (see
/// [`crate::Store::write`]).
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum StoreError {
    /// The database engine reported an error (IO, corruption, constraint, lock timeout, ...);
    /// the engine's message as text, so that no backend type leaks into the interface.
    #[error("database error: {0}")]
    Backend(String),
    /// The database could not be opened (missing directory, permissions, not a database).
    #[error("cannot open database {path}: {reason}")]
    Open {
        /// The path or address given.
        path: String,
        /// The engine's message.
        reason: String,
    },
    /// A modality arrived with a unit other than the one its stored readings are in.
    #[error(
        "modality {modality}: readings are stored in {stored:?}, refusing {incoming:?} (convert the file, or ingest it as another modality)"
    )]
    UnitMismatch {
        /// The modality.
        modality: Modality,
        /// The stored unit.
        stored: String,
        /// The unit offered.
        incoming: String,
    },
    /// A mission already recorded as flown was recorded again without asking to amend it.
    #[error(
        "mission #{mission} was already recorded as flown at t = {flown_at} s; pass amend to replace that record"
    )]
    AlreadyFlown {
        /// The mission id.
        mission: i64,
        /// When it was recorded as flown, seconds since the Unix epoch (UTC).
        flown_at: UnixSeconds,
    },
    /// The file is an SQLite database of some other application (it has tables but no
    /// gleaner schema history); gleaner does not add its tables to it.
    #[error("{path} is not a gleaner database (it has tables {tables:?} but no schema_migrations)")]
    NotAGleanerDatabase {
        /// The path given.
        path: String,
        /// Some of its tables.
        tables: Vec<String>,
    },
    /// The database was written by a newer gleaner whose schema this build does not know.
    #[error(
        "database schema version {found} is newer than this gleaner supports ({supported}); \
         upgrade gleaner or use a different database"
    )]
    SchemaTooNew {
        /// Schema version found in the database.
        found: i64,
        /// Latest schema version this build knows.
        supported: i64,
    },
    /// A reading batch names a sensor that has not been stored with `upsert_sensors`.
    #[error("unknown sensor \"{0}\": upsert the sensor before inserting its readings")]
    UnknownSensor(SensorId),
    /// A reading batch names a modality that has not been stored with `upsert_modalities`.
    #[error("unknown modality \"{0}\": upsert the modality before inserting its readings")]
    UnknownModality(Modality),
    /// A cell lists a sensor that is not stored, or a mission visit names an unknown mission.
    #[error("unknown {what} {name:?}")]
    Unknown {
        /// What kind of thing is missing (`sensor`, `cell`, `mission`).
        what: &'static str,
        /// Its name or id.
        name: String,
    },
    /// A reading row whose sensor or modality index lies outside the batch's lists.
    #[error("reading row {row}: {what} index {index} out of range (batch has {len})")]
    BadIndex {
        /// Position of the row in the batch.
        row: usize,
        /// `sensor` or `modality`.
        what: &'static str,
        /// The offending index.
        index: u32,
        /// Length of the list it indexes.
        len: usize,
    },
    /// A reading value that is NaN or infinite (SQLite cannot store NaN).
    #[error("reading of {sensor} {modality} at t = {t} s: value {value} is not finite")]
    NonFiniteValue {
        /// Sensor.
        sensor: SensorId,
        /// Modality.
        modality: Modality,
        /// Time, seconds since the Unix epoch (UTC).
        t: UnixSeconds,
        /// The value.
        value: f64,
    },
    /// Readings that disagree with stored readings under [`crate::ConflictPolicy::Fail`]; nothing
    /// was written.
    #[error("{} conflicting reading(s), nothing written; first: {}", .0.len(), ConflictList(.0))]
    Conflicts(Vec<Conflict>),
    /// An argument that cannot be stored (a non-finite number, a duplicate key, ...).
    #[error("invalid {what}: {detail}")]
    Invalid {
        /// What was invalid.
        what: &'static str,
        /// Why, with the offending values.
        detail: String,
    },
    /// A value read back from the database that does not fit the model (a hand-edited
    /// database, say).
    #[error("corrupt database content in {table}: {detail}")]
    Corrupt {
        /// The table.
        table: &'static str,
        /// What is wrong, with the value.
        detail: String,
    },
}

/// Formats the first few conflicts of a list for an error message.
struct ConflictList<'a>(&'a [Conflict]);

impl fmt::Display for ConflictList<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        const SHOWN: usize = 5;
        for (k, c) in self.0.iter().take(SHOWN).enumerate() {
            if k > 0 {
                f.write_str("; ")?;
            }
            write!(
                f,
                "{} {} t={} s: stored {} vs incoming {}",
                c.sensor, c.modality, c.t, c.stored, c.incoming
            )?;
        }
        if self.0.len() > SHOWN {
            write!(f, "; ... ({} more)", self.0.len() - SHOWN)?;
        }
        Ok(())
    }
}

/// Shorthand for the store's results.
pub type Result<T, E = StoreError> = std::result::Result<T, E>;
