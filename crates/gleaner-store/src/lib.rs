//! Persistence for gleaner: the only crate that knows SQL.
//!
//! - [`StoreRead`] (queries), [`StoreWrite`] (the writes a use case makes) and [`Store`] (a
//!   database that runs a use case's writes as one transaction, [`Store::write`]) are the
//!   backend-neutral interface the rest of gleaner programs against; a PostgreSQL
//!   implementation can be added beside [`SqliteStore`] without touching callers, and checked
//!   with the same `conformance` suite (cargo feature `conformance`).
//! - [`SqliteStore`] keeps a project in one SQLite file (WAL journal, `synchronous=NORMAL`,
//!   foreign keys on, versioned migrations); its write transaction is [`SqliteTx`].
//! - Values in and out are plain Rust types: [`SensorRecord`], [`ModalityRecord`], the columnar
//!   [`ReadingBatch`] (built with [`ReadingBatchBuilder`]), [`CellRecord`], [`CellMetadata`]
//!   (the docs/method.md §5 cell metadata table with [`ModalitySummary`], [`Correlation`],
//!   [`AnomalyRecord`], [`ClassProbability`] and [`CellScores`]), [`NewMission`] (with its
//!   [`FlightProfile`], [`EnergyBreakdown`] and [`StopRecord`]s), [`MissionRecord`] and
//!   [`VisitRecord`]. No backend type appears in the interface: engine errors arrive as
//!   [`StoreError::Backend`] text.
//! - The database computes no statistics: summaries, scores and pending volumes are computed in
//!   Rust by the caller and stored as given ([`StoreWrite::upsert_cell_metadata`]).
//!
//! All writes happen inside [`Store::write`]: the closure's writes are kept together when it
//! returns `Ok` and all discarded when it returns `Err`. Within it, a write method that fails
//! leaves nothing of its own writes behind. Re-inserting readings already stored changes
//! nothing ([`InsertStats::unchanged`]); a reading that contradicts a stored one is a
//! [`Conflict`], handled by [`ConflictPolicy`].
//!
//! ```
//! use gleaner_field::{LatLon, Modality, SensorId};
//! use gleaner_store::{
//!     ConflictPolicy, IngestRecord, ModalityRecord, ReadingBatchBuilder, SensorRecord,
//!     SqliteStore, Store, StoreRead, StoreWrite,
//! };
//!
//! let mut store = SqliteStore::open_in_memory()?;
//! let id = SensorId::new("CAF003").unwrap();
//! let vw = Modality::new("vw@30cm").unwrap();
//! let mut batch = ReadingBatchBuilder::new();
//! batch.push(&id, &vw, 1_262_304_000, 0.31); // 2010-01-01T00:00:00Z, m3/m3
//! batch.push(&id, &vw, 1_262_390_400, 0.29);
//! let batch = batch.finish();
//!
//! // One use case, one transaction: the sensor, its modality, the readings and their
//! // provenance are stored together or not at all.
//! let stats = store.write(|tx| {
//!     tx.upsert_sensors(&[SensorRecord {
//!         id: id.clone(),
//!         position: LatLon::new(46.7788, -117.0867).unwrap(),
//!         elevation_m: Some(790.0),
//!         source: "example".into(),
//!     }])?;
//!     tx.upsert_modalities(&[ModalityRecord { modality: vw.clone(), unit: Some("m3/m3".into()) }])?;
//!     let stats = tx.insert_readings(&batch, ConflictPolicy::Fail)?;
//!     tx.record_ingest(&IngestRecord {
//!         file_name: "example.csv".into(),
//!         format: "long-csv".into(),
//!         rows_read: 2,
//!         rows_inserted: stats.inserted,
//!         rows_unchanged: stats.unchanged,
//!         rows_skipped: 0,
//!         at: 1_262_400_000,
//!     })?;
//!     Ok::<_, gleaner_store::StoreError>(stats)
//! })?;
//! assert_eq!(stats.inserted, 2);
//! let again = store.write(|tx| tx.insert_readings(&batch, ConflictPolicy::Fail))?;
//! assert_eq!((again.inserted, again.unchanged), (0, 2));
//! assert_eq!(store.readings_of_sensors(&[id], i64::MIN..=i64::MAX)?.len(), 2);
//! # Ok::<(), gleaner_store::StoreError>(())
//! ```
//!
//! # Schema (SQLite)
//!
//! Units everywhere: times are INTEGER seconds since 1970-01-01T00:00:00Z (UTC); positions
//! WGS84 degrees; lengths and altitudes metres; speeds m/s; energies joules (J); data volumes
//! bytes. Sensors, modalities and cells have an INTEGER surrogate key (`id`) used by the other
//! tables; their names (`name`, `label`) are unique.
//!
//! | table | columns | notes |
//! |---|---|---|
//! | `schema_migrations` | `version`, `applied_at` (s), `description` | one row per applied migration; `PRAGMA user_version` mirrors the latest |
//! | `sensors` | `id`, `name` (unique), `lat`, `lon` (deg), `elevation_m` (m, nullable), `source` | |
//! | `modalities` | `id`, `name` (unique, e.g. `vw@30cm`), `unit` (nullable; once set, never changed) | |
//! | `readings` | `sensor`, `modality`, `t` (s), `value` (modality unit) | primary key (`sensor`, `modality`, `t`), `WITHOUT ROWID`; keys not declared as foreign keys (see below) |
//! | `ingests` | `id`, `file_name`, `format`, `rows_read`, `rows_inserted`, `rows_unchanged`, `rows_skipped`, `at` (s) | ingest provenance |
//! | `sensor_collection` | `sensor`, `last_collected` (s) | last time a UAV collected each sensor |
//! | `cells` | `id`, `label` (`x12y-3`, unique), `i`, `j`, `lat`, `lon` (centre, deg), `cell_size_m` (m) | the current grid |
//! | `cell_sensors` | `cell`, `sensor` (unique) | each sensor in at most one cell |
//! | `cell_metadata` | `cell`, `last_collected` (s), `pending_bytes` (bytes), `expected_energy_j` (J), `freshness`, `redundancy`, `anomaly`, `uncertainty`, `score`, `computed_at` (s) | one row per cell (docs/method.md §5) |
//! | `cell_class_probabilities` | `cell`, `k`, `class`, `probability` | the distribution behind U |
//! | `cell_summaries` | `cell`, `modality`, `count`, `mean`, `std` (sample), `min`, `max`, `latest_t` (s), `latest_value` | of the cell series, as computed by the caller |
//! | `cell_correlations` | `cell`, `neighbour`, `modality`, `correlation`, `overlap` (points) | Pearson, per neighbour |
//! | `cell_anomalies` | `cell`, `modality`, `t` (s), `anomaly`, `flagged` (0/1) | anomaly history |
//! | `missions` | `id`, `created_at` (s), `kind` (`exploration`/`adaptive`), `planned_at` (s), `solver`, `seed` (the u64's bits as i64), `weight_alpha`..`weight_delta`, `anomaly_form`, `total_score`, `base_lat`, `base_lon` (deg), `base_alt_m` (m AMSL), `altitude_m` (m above base), `cruise_speed_mps` (m/s), `wind_mps` (m/s, >= 0; since v3), `wind_from_deg` (deg from north; since v3), `travel_j`, `hover_j`, `comm_j`, `return_j`, `total_j`, `budget_j` (J), `distance_m` (m), `flight_time_s` (s), `return_distance_m` (m), `status` (`planned`/`flown`), `flown_at` (s, set iff flown), `summary_json` (legacy, nullable) | |
//! | `mission_stops` | `mission`, `position`, `cell` (label), `lat`, `lon` (deg), `score`, `freshness`, `redundancy`, `anomaly`, `uncertainty` (nullable together), `leg_distance_m` (m), `leg_energy_j` (J), `collection_s` (s), `hover_s` (s), `hover_j` (J), `comm_j` (J) | the planned route; primary key (`mission`, `position`); cascades on mission deletion |
//! | `visits` | `mission`, `position`, `cell` (label), `arrived_at` (s), `energy_j` (J) | by label, so history survives a new grid |
//! | `config` | `key`, `value` | project settings as text |
//! | `blobs` | `key`, `value` (bytes) | opaque values, e.g. the serialised incremental utility state |
//!
//! Every `cell_*` table cascades on deletion of its cell, so [`StoreWrite::replace_cells`]
//! drops the metadata of cells that no longer exist.
//!
//! `readings.sensor` and `readings.modality` hold `sensors.id` and `modalities.id` but are not
//! declared `REFERENCES`: [`StoreWrite::insert_readings`] resolves every name to an existing
//! key before inserting and the store never deletes sensors or modalities, while the per-row
//! foreign-key lookups cost about 40% of bulk-insert CPU time.
#![deny(missing_docs)]

/// The [`StoreRead`] methods, each a call of the backend's shared query in its own `read`
/// module (with the backend-neutral steps of `decode`) through the type's own `read` wrapper (the paths resolve where the macro is used:
/// `sqlite.rs` and `postgres.rs`). Defined before those modules so both can use it.
macro_rules! store_read_methods {
    () => {
        fn schema_version(&self) -> Result<i64> {
            self.read(read::schema_version)
        }
        fn sensors(&self) -> Result<Vec<SensorRecord>> {
            self.read(read::sensors)
        }
        fn modalities(&self) -> Result<Vec<ModalityRecord>> {
            self.read(read::modalities)
        }
        fn readings_for(
            &self,
            modality: Option<&Modality>,
            range: RangeInclusive<UnixSeconds>,
        ) -> Result<ReadingBatch> {
            self.read(|c| {
                let (sensors, modalities) = $crate::decode::all_sensors_of(
                    read::sensor_ids(c)?,
                    read::modality_ids(c)?,
                    modality,
                );
                read::collect_readings(c, &sensors, &modalities, range)
            })
        }
        fn readings_of_sensors(
            &self,
            sensors: &[SensorId],
            range: RangeInclusive<UnixSeconds>,
        ) -> Result<ReadingBatch> {
            self.read(|c| {
                let wanted = $crate::decode::wanted_sensors(&read::sensor_ids(c)?, sensors)?;
                let modalities = $crate::decode::sorted(read::modality_ids(c)?);
                read::collect_readings(c, &wanted, &modalities, range)
            })
        }
        fn latest_readings(
            &self,
            modality: &Modality,
            range: RangeInclusive<UnixSeconds>,
        ) -> Result<Vec<(SensorId, UnixSeconds, f64)>> {
            self.read(|c| read::latest_readings(c, modality, range))
        }
        fn ingests(&self) -> Result<Vec<IngestRecord>> {
            self.read(read::ingests)
        }
        fn cells(&self) -> Result<Vec<CellRecord>> {
            self.read(read::cells)
        }
        fn cell_metadata(&self) -> Result<Vec<CellMetadata>> {
            self.read(read::cell_metadata)
        }
        fn cell_metadata_scalars(&self) -> Result<Vec<CellMetadata>> {
            self.read(read::cell_metadata_scalars)
        }
        fn sensor_last_collected(&self) -> Result<Vec<(SensorId, UnixSeconds)>> {
            self.read(read::sensor_last_collected)
        }
        fn sensor_reading_counts(&self) -> Result<Vec<(SensorId, u64)>> {
            self.read(read::sensor_reading_counts)
        }
        fn missions(&self) -> Result<Vec<MissionRecord>> {
            self.read(|c| read::missions(c, None))
        }
        fn mission(&self, id: MissionId) -> Result<Option<MissionRecord>> {
            self.read(|c| Ok(read::missions(c, Some(id))?.pop()))
        }
        fn config_get(&self, key: &str) -> Result<Option<String>> {
            self.read(|c| read::config_get(c, key))
        }
        fn blob_get(&self, key: &str) -> Result<Option<Vec<u8>>> {
            self.read(|c| read::blob_get(c, key))
        }
        fn config_entries(&self) -> Result<Vec<(String, String)>> {
            self.read(read::config_entries)
        }
        fn blob_keys(&self) -> Result<Vec<String>> {
            self.read(read::blob_keys)
        }
    };
}

/// The [`StoreWrite`] methods but `insert_readings` (which each backend runs its own way),
/// listed once: `$method` is given each one's name, arguments and result type, and writes the
/// methods (a backend's, `store_write_methods`; [`AnyTx`]'s, which forward to its backend).
macro_rules! for_each_store_write {
    ($method:ident) => {
        $method! {
            upsert_sensors(sensors: &[SensorRecord]) -> UpsertStats;
            upsert_modalities(modalities: &[ModalityRecord]) -> UpsertStats;
            record_ingest(ingest: &IngestRecord) -> i64;
            replace_cells(cells: &[CellRecord]) -> ReplaceCellsStats;
            upsert_cell_metadata(metadata: &[CellMetadata]) -> ();
            set_sensors_collected(collected: &[(SensorId, UnixSeconds)]) -> ();
            create_mission(mission: &NewMission) -> MissionId;
            record_visits(
                mission: MissionId,
                visits: &[VisitRecord],
                flown_at: UnixSeconds,
                amend: bool
            ) -> ();
            cancel_mission(mission: MissionId) -> ();
            delete_mission(mission: MissionId) -> ();
            import_mission(record: &MissionRecord) -> ();
            config_set(key: &str, value: &str) -> ();
            blob_put(key: &str, value: &[u8]) -> ();
        }
    };
}

/// A backend's [`StoreWrite`] methods from `for_each_store_write`: each a call of the
/// backend's write in its own `write` module inside a savepoint, through the transaction
/// type's own `atomically` (the paths resolve where the macro is used: `sqlite.rs` and
/// `postgres.rs`).
macro_rules! store_write_methods {
    ($($name:ident($($arg:ident: $ty:ty),*) -> $out:ty;)*) => {
        $(fn $name(&mut self, $($arg: $ty),*) -> Result<$out> {
            self.atomically(|c| write::$name(c, $($arg),*))
        })*
    };
}

mod any;
mod checks;
#[cfg(any(test, feature = "conformance"))]
pub mod conformance;
mod decode;
mod error;
pub mod failpoint;
mod postgres;
mod schema;
mod sqlite;
mod store;
mod types;
mod upsert;

#[cfg(test)]
mod pg_tests;
#[cfg(test)]
mod tests;

pub use any::{AnyStore, AnyTx, Database, schema_for_name};
pub use error::{Result, StoreError};
pub use postgres::{
    LOCK_TIMEOUT as PG_LOCK_TIMEOUT, PgStore, PgTx, is_postgres_url, redact, split_project,
    valid_project_name,
};
pub use sqlite::{BUSY_TIMEOUT as SQLITE_BUSY_TIMEOUT, SqliteStore, SqliteTx};
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
