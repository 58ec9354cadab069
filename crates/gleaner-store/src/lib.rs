//! Persistence for gleaner: the only crate that knows SQL.
//!
//! - [`Store`] is the backend-neutral interface the rest of gleaner programs against; a
//!   PostgreSQL implementation can be added beside [`SqliteStore`] without touching callers.
//! - [`SqliteStore`] keeps a project in one SQLite file (WAL journal, `synchronous=NORMAL`,
//!   foreign keys on, versioned migrations).
//! - Values in and out are plain Rust types: [`SensorRecord`], [`ModalityRecord`], the columnar
//!   [`ReadingBatch`] (built with [`ReadingBatchBuilder`]), [`CellRecord`], [`CellMetadata`]
//!   (the SPEC §5 cell metadata table with [`ModalitySummary`], [`Correlation`],
//!   [`AnomalyRecord`], [`ClassProbability`] and [`CellScores`]), [`MissionRecord`] and
//!   [`VisitRecord`].
//!
//! Every write is one transaction: when a method returns an error, the database is exactly as
//! before the call. Re-inserting readings already stored changes nothing
//! ([`InsertStats::unchanged`]); a reading that contradicts a stored one is a [`Conflict`],
//! handled by [`ConflictPolicy`].
//!
//! ```
//! use gleaner_field::{LatLon, Modality, SensorId};
//! use gleaner_store::{
//!     ConflictPolicy, ModalityRecord, ReadingBatchBuilder, SensorRecord, SqliteStore, Store,
//! };
//!
//! let mut store = SqliteStore::open_in_memory()?;
//! let id = SensorId::new("CAF003").unwrap();
//! let vw = Modality::new("vw@30cm").unwrap();
//! store.upsert_sensors(&[SensorRecord {
//!     id: id.clone(),
//!     position: LatLon::new(46.7788, -117.0867).unwrap(),
//!     elevation_m: Some(790.0),
//!     source: "example".into(),
//! }])?;
//! store.upsert_modalities(&[ModalityRecord { modality: vw.clone(), unit: Some("m3/m3".into()) }])?;
//!
//! let mut batch = ReadingBatchBuilder::new();
//! batch.push(&id, &vw, 1_262_304_000, 0.31); // 2010-01-01T00:00:00Z
//! batch.push(&id, &vw, 1_262_390_400, 0.29);
//! let batch = batch.finish();
//! let first = store.insert_readings(&batch, ConflictPolicy::Fail)?;
//! let again = store.insert_readings(&batch, ConflictPolicy::Fail)?;
//! assert_eq!((first.inserted, again.inserted, again.unchanged), (2, 0, 2));
//!
//! let summary = &store.sensor_summaries()?[0];
//! assert!((summary.stats.mean - 0.30).abs() < 1e-12);
//! # Ok::<(), gleaner_store::StoreError>(())
//! ```
//!
//! # Schema (SQLite)
//!
//! Units everywhere: times are INTEGER seconds since 1970-01-01T00:00:00Z (UTC); positions
//! WGS84 degrees; lengths metres; energies joules (J); data volumes bytes. Sensors, modalities
//! and cells have an INTEGER surrogate key (`id`) used by the other tables; their names
//! (`name`, `label`) are unique.
//!
//! | table | columns | notes |
//! |---|---|---|
//! | `schema_migrations` | `version`, `applied_at` (s), `description` | one row per applied migration; `PRAGMA user_version` mirrors the latest |
//! | `sensors` | `id`, `name` (unique), `lat`, `lon` (deg), `elevation_m` (m, nullable), `source` | |
//! | `modalities` | `id`, `name` (unique, e.g. `vw@30cm`), `unit` (nullable) | |
//! | `readings` | `sensor`, `modality`, `t` (s), `value` (modality unit) | primary key (`sensor`, `modality`, `t`), `WITHOUT ROWID`; keys not declared as foreign keys (see below) |
//! | `ingests` | `id`, `file_name`, `format`, `rows_read`, `rows_inserted`, `rows_unchanged`, `rows_skipped`, `at` (s) | ingest provenance |
//! | `sensor_collection` | `sensor`, `last_collected` (s) | last time a UAV collected each sensor |
//! | `cells` | `id`, `label` (`x12y-3`, unique), `i`, `j`, `lat`, `lon` (centre, deg), `cell_size_m` (m) | the current grid |
//! | `cell_sensors` | `cell`, `sensor` (unique) | each sensor in at most one cell |
//! | `cell_metadata` | `cell`, `last_collected` (s), `pending_bytes` (bytes), `expected_energy_j` (J), `freshness`, `redundancy`, `anomaly`, `uncertainty`, `score`, `computed_at` (s) | one row per cell (SPEC §5) |
//! | `cell_class_probabilities` | `cell`, `k`, `class`, `probability` | the distribution behind U |
//! | `cell_summaries` | `cell`, `modality`, `count`, `mean`, `std` (sample), `min`, `max`, `latest_t` (s), `latest_value` | of the cell series |
//! | `cell_correlations` | `cell`, `neighbour`, `modality`, `correlation`, `overlap` (points) | Pearson, per neighbour |
//! | `cell_anomalies` | `cell`, `modality`, `t` (s), `anomaly`, `flagged` (0/1) | anomaly history |
//! | `missions` | `id`, `created_at` (s), `kind` (`exploration`/`adaptive`), `planned_at` (s), `solver`, `budget_j` (J), `energy_j` (J), `status` (`planned`/`flown`), `summary_json` | |
//! | `visits` | `mission`, `position`, `cell` (label), `arrived_at` (s), `energy_j` (J) | by label, so history survives a new grid |
//! | `config` | `key`, `value` | project settings as text |
//!
//! Every `cell_*` table cascades on deletion of its cell, so [`Store::replace_cells`] drops the
//! metadata of cells that no longer exist.
//!
//! `readings.sensor` and `readings.modality` hold `sensors.id` and `modalities.id` but are not
//! declared `REFERENCES`: [`Store::insert_readings`] resolves every name to an existing key
//! before inserting and the store never deletes sensors or modalities, while the per-row
//! foreign-key lookups cost about 40% of bulk-insert CPU time.
#![deny(missing_docs)]

mod error;
mod schema;
mod sqlite;
mod store;
mod types;

#[cfg(test)]
mod tests;

pub use error::{Result, StoreError};
pub use sqlite::SqliteStore;
pub use store::{Store, StoreRead, StoreWrite};
pub use types::{
    AnomalyRecord, CellMetadata, CellRecord, CellScores, ClassProbability, Conflict,
    ConflictPolicy, Correlation, EnergyBreakdown, FlightProfile, IngestRecord, InsertStats,
    MissionId, MissionKind, MissionRecord, MissionStatus, ModalityRecord, ModalitySummary,
    NewMission, Reading, ReadingBatch, ReadingBatchBuilder, ReplaceCellsStats, SensorRecord,
    SensorSummary, SeriesStats, StopRecord, UpsertStats, VisitRecord,
};

/// The schema version this build of gleaner writes.
pub fn schema_version_supported() -> i64 {
    schema::latest_version()
}
