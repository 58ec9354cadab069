//! [`AnyStore`]: a project's store on whichever backend its settings name, so that the
//! application layer and its adapters run unchanged on SQLite and PostgreSQL.
//!
//! [`Database`] is where a project lives, parsed from the `database` setting (or a
//! `--database` option): a path is an SQLite file (relative to the project directory); a
//! `postgres://` or `postgresql://` URL is a PostgreSQL database, with the project's schema
//! named after `#` or, without one, derived from the project's name ([`schema_for_name`]).
//! [`AnyStore`] implements [`Store`] by delegation; its transaction [`AnyTx`] forwards to the
//! backend's transaction through `dyn StoreWrite` (the write trait is dyn-compatible, checked
//! by the conformance suite).

use std::fmt;
use std::ops::RangeInclusive;
use std::path::{Path, PathBuf};

use gleaner_field::{Modality, SensorId, UnixSeconds};

use crate::postgres::{is_postgres_url, redact, split_project, valid_project_name};
use crate::{
    CellMetadata, CellRecord, ConflictPolicy, IngestRecord, InsertStats, MissionId, MissionRecord,
    ModalityRecord, NewMission, PgStore, ReadingBatch, ReplaceCellsStats, Result, SensorRecord,
    SqliteStore, Store, StoreError, StoreRead, StoreWrite, UpsertStats, VisitRecord,
};

/// Where a project's data lives.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Database {
    /// An SQLite file (absolute, or resolved against the project directory).
    Sqlite(PathBuf),
    /// A schema (`project`) of a PostgreSQL database at `url`.
    Postgres {
        /// Connection URL without the `#project` part.
        url: String,
        /// The project's schema.
        project: String,
    },
}

/// The PostgreSQL schema name for a project called `name`: lower-cased, every character
/// other than `a-z`, `0-9` and `_` replaced by `_`, prefixed with `p_` when it would start
/// with a digit or `pg_` (or be empty), cut to 63 bytes. `Farm A` -> `farm_a`.
pub fn schema_for_name(name: &str) -> String {
    let mut s: String = name
        .chars()
        .map(|c| {
            let c = c.to_ascii_lowercase();
            if c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    if s.is_empty() || s.as_bytes()[0].is_ascii_digit() || s.starts_with("pg_") {
        s.insert_str(0, "p_");
    }
    s.truncate(63);
    s
}

impl Database {
    /// Parses a `database` setting: a `postgres://...[#project]` URL, or an SQLite path
    /// resolved against `dir`. `name` is the project's name, which names the schema when the
    /// URL has no `#project`.
    pub fn parse(setting: &str, dir: &Path, name: &str) -> Result<Self> {
        if is_postgres_url(setting) {
            let (url, project) = split_project(setting);
            let project = project.map_or_else(|| schema_for_name(name), str::to_string);
            if !valid_project_name(&project) {
                return Err(StoreError::Open {
                    path: redact(setting),
                    reason: format!(
                        "{project:?} cannot name a PostgreSQL schema: after '#', use 1-63 \
                         characters a-z, 0-9 and _, starting with a letter or _, not with pg_"
                    ),
                });
            }
            Ok(Self::Postgres {
                url: url.to_string(),
                project,
            })
        } else {
            Ok(Self::Sqlite(dir.join(setting)))
        }
    }

    /// Whether the project's data already exist (the SQLite file; the PostgreSQL schema).
    pub fn exists(&self) -> Result<bool> {
        match self {
            Self::Sqlite(path) => Ok(path.exists()),
            Self::Postgres { url, project } => PgStore::project_exists(url, project),
        }
    }

    /// Opens the store, creating and migrating it when needed.
    pub fn open(&self) -> Result<AnyStore> {
        Ok(match self {
            Self::Sqlite(path) => AnyStore::Sqlite(SqliteStore::open(path)?),
            Self::Postgres { url, project } => {
                AnyStore::Postgres(Box::new(PgStore::open(url, project)?))
            }
        })
    }
}

impl fmt::Display for Database {
    /// The location for messages (a PostgreSQL password is masked).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Sqlite(path) => write!(f, "{}", path.display()),
            Self::Postgres { url, project } => write!(f, "{}#{project}", redact(url)),
        }
    }
}

/// A [`Store`] on either backend.
#[derive(Debug)]
pub enum AnyStore {
    /// An SQLite file.
    Sqlite(SqliteStore),
    /// A PostgreSQL project schema (boxed: its client is large).
    Postgres(Box<PgStore>),
}

/// The write transaction of an [`AnyStore`]: the backend's own transaction behind
/// `dyn StoreWrite`.
pub struct AnyTx<'a> {
    inner: &'a mut (dyn StoreWrite + 'a),
}

impl fmt::Debug for AnyTx<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("AnyTx").finish_non_exhaustive()
    }
}

impl AnyStore {
    /// Which backend: `sqlite` or `postgres`.
    pub fn backend(&self) -> &'static str {
        match self {
            Self::Sqlite(_) => "sqlite",
            Self::Postgres(_) => "postgres",
        }
    }

    /// The backend's own integrity checks: SQLite's `PRAGMA integrity_check` and
    /// `foreign_key_check`, PostgreSQL's re-validation of every key and invariant. Empty when
    /// the store is consistent.
    pub fn integrity_check(&self) -> Result<Vec<String>> {
        match self {
            Self::Sqlite(s) => s.integrity_check(),
            Self::Postgres(s) => s.integrity_check(),
        }
    }
}

/// Forwards a [`StoreRead`] method to the backend.
macro_rules! any_read {
    ($($name:ident($($arg:ident: $ty:ty),*) -> $out:ty;)*) => {
        impl StoreRead for AnyStore {
            $(fn $name(&self, $($arg: $ty),*) -> Result<$out> {
                match self {
                    Self::Sqlite(s) => s.$name($($arg),*),
                    Self::Postgres(s) => s.$name($($arg),*),
                }
            })*
        }
        impl StoreRead for AnyTx<'_> {
            $(fn $name(&self, $($arg: $ty),*) -> Result<$out> {
                self.inner.$name($($arg),*)
            })*
        }
    };
}

any_read! {
    schema_version() -> i64;
    sensors() -> Vec<SensorRecord>;
    modalities() -> Vec<ModalityRecord>;
    readings_for(modality: Option<&Modality>, range: RangeInclusive<UnixSeconds>) -> ReadingBatch;
    readings_of_sensors(sensors: &[SensorId], range: RangeInclusive<UnixSeconds>) -> ReadingBatch;
    latest_readings(modality: &Modality, range: RangeInclusive<UnixSeconds>) -> Vec<(SensorId, UnixSeconds, f64)>;
    reading_count() -> u64;
    ingests() -> Vec<IngestRecord>;
    cells() -> Vec<CellRecord>;
    cell_metadata() -> Vec<CellMetadata>;
    cell_metadata_scalars() -> Vec<CellMetadata>;
    sensor_last_collected() -> Vec<(SensorId, UnixSeconds)>;
    sensor_reading_counts() -> Vec<(SensorId, u64)>;
    missions() -> Vec<MissionRecord>;
    mission(id: MissionId) -> Option<MissionRecord>;
    config_get(key: &str) -> Option<String>;
    blob_get(key: &str) -> Option<Vec<u8>>;
    config_entries() -> Vec<(String, String)>;
    blob_keys() -> Vec<String>;
}

/// Forwards the [`StoreWrite`] methods listed by `for_each_store_write` to the backend's
/// transaction.
macro_rules! any_write {
    ($($name:ident($($arg:ident: $ty:ty),*) -> $out:ty;)*) => {
        $(fn $name(&mut self, $($arg: $ty),*) -> Result<$out> {
            self.inner.$name($($arg),*)
        })*
    };
}

impl StoreWrite for AnyTx<'_> {
    for_each_store_write!(any_write);

    fn insert_readings(
        &mut self,
        batch: &ReadingBatch,
        policy: ConflictPolicy,
    ) -> Result<InsertStats> {
        self.inner.insert_readings(batch, policy)
    }
}

impl Store for AnyStore {
    type Tx<'a>
        = AnyTx<'a>
    where
        Self: 'a;

    fn write<R, E>(&mut self, f: impl FnOnce(&mut AnyTx<'_>) -> Result<R, E>) -> Result<R, E>
    where
        E: From<StoreError>,
    {
        match self {
            Self::Sqlite(s) => s.write(|tx| f(&mut AnyTx { inner: tx })),
            Self::Postgres(s) => s.write(|tx| f(&mut AnyTx { inner: tx })),
        }
    }

    fn lock_project(&self) -> Result<()> {
        match self {
            Self::Sqlite(s) => s.lock_project(),
            Self::Postgres(s) => s.lock_project(),
        }
    }

    fn unlock_project(&self) {
        match self {
            Self::Sqlite(s) => s.unlock_project(),
            Self::Postgres(s) => s.unlock_project(),
        }
    }
}
