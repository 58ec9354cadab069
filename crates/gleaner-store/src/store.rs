//! The backend-neutral store interface: [`StoreRead`] (queries), [`StoreWrite`] (the writes a
//! use case makes) and [`Store`] (a database that runs a use case's writes as one
//! transaction, [`Store::write`]).
//!
//! The traits are shaped by the application layer's use cases, not by a backend: a scoring, a
//! planned mission with its stops, a recorded flight with its readings are each one call to
//! [`Store::write`], all or nothing. No backend type appears in them, and no statistics are
//! computed by the database: summaries, scores and pending volumes are computed in Rust by the
//! caller and stored as given.

use std::ops::RangeInclusive;

use gleaner_field::{Modality, SensorId, UnixSeconds};

use crate::{
    CellMetadata, CellRecord, ConflictPolicy, IngestRecord, InsertStats, MissionId, MissionRecord,
    ModalityRecord, NewMission, ReadingBatch, ReplaceCellsStats, Result, SensorRecord, StoreError,
    UpsertStats, VisitRecord,
};

/// Queries. Implemented by a store and by its open transaction (a use case reads its own
/// writes). Times are seconds since the Unix epoch (UTC), distances metres, energies joules,
/// data volumes bytes. Results come in a deterministic order (by name, cell index, time).
pub trait StoreRead {
    /// The schema version of the open database.
    fn schema_version(&self) -> Result<i64>;

    /// All sensors, sorted by id.
    fn sensors(&self) -> Result<Vec<SensorRecord>>;
    /// All modalities, sorted by name.
    fn modalities(&self) -> Result<Vec<ModalityRecord>>;

    /// Readings of `modality` (or of all modalities) with `t` in `range` (seconds, inclusive),
    /// ordered by sensor id, modality name, time.
    fn readings_for(
        &self,
        modality: Option<&Modality>,
        range: RangeInclusive<UnixSeconds>,
    ) -> Result<ReadingBatch>;
    /// Readings of the given sensors only (all modalities), with `t` in `range`, ordered by
    /// sensor id, modality name, time. Costs in proportion to those sensors' readings.
    fn readings_of_sensors(
        &self,
        sensors: &[SensorId],
        range: RangeInclusive<UnixSeconds>,
    ) -> Result<ReadingBatch>;
    /// Each sensor's latest reading of `modality` with `t` in `range` (seconds, inclusive), as
    /// `(sensor, t, value)` sorted by sensor id; sensors without one in the range are left
    /// out. The last row per sensor of [`readings_for`](Self::readings_for) over the same
    /// range, at the cost of one index seek per sensor.
    fn latest_readings(
        &self,
        modality: &Modality,
        range: RangeInclusive<UnixSeconds>,
    ) -> Result<Vec<(SensorId, UnixSeconds, f64)>>;
    /// Number of stored readings.
    fn reading_count(&self) -> Result<u64>;
    /// All ingest records, oldest first.
    fn ingests(&self) -> Result<Vec<IngestRecord>>;

    /// All cells, sorted by index (column, then row).
    fn cells(&self) -> Result<Vec<CellRecord>>;
    /// The cell metadata table: one entry per stored cell (empty for cells never described),
    /// sorted by cell index.
    fn cell_metadata(&self) -> Result<Vec<CellMetadata>>;
    /// [`cell_metadata`](Self::cell_metadata) without the child lists: every row's scalar
    /// fields, scores and class probabilities, with `summaries`, `correlations` and
    /// `anomalies` empty (what a writer that replaces the scalar fields needs to carry over;
    /// the anomaly history grows with every scoring, so reading it back costs ever more).
    fn cell_metadata_scalars(&self) -> Result<Vec<CellMetadata>>;
    /// Last collection time per sensor (collected sensors only), sorted by sensor id.
    fn sensor_last_collected(&self) -> Result<Vec<(SensorId, UnixSeconds)>>;
    /// The number of stored readings per sensor (sensors with readings only), sorted by
    /// sensor id.
    fn sensor_reading_counts(&self) -> Result<Vec<(SensorId, u64)>>;

    /// All missions with their stops and visits, oldest first.
    fn missions(&self) -> Result<Vec<MissionRecord>>;
    /// One mission with its stops and visits, if it exists.
    fn mission(&self, id: MissionId) -> Result<Option<MissionRecord>>;
    /// One page of the mission history, newest first: at most `limit` missions with an id
    /// below `before` (all ids when `None`), in descending id order, so that the last id of a
    /// page is the `before` of the next one and a mission planned meanwhile never shifts a
    /// page.
    fn missions_page(&self, before: Option<MissionId>, limit: usize) -> Result<Vec<MissionRecord>> {
        let mut all = self.missions()?;
        all.retain(|m| before.is_none_or(|b| m.id < b));
        all.sort_by_key(|m| std::cmp::Reverse(m.id));
        all.truncate(limit);
        Ok(all)
    }

    /// A project setting, if set.
    fn config_get(&self, key: &str) -> Result<Option<String>>;
    /// A stored opaque value (e.g. the serialised incremental utility state), if set.
    fn blob_get(&self, key: &str) -> Result<Option<Vec<u8>>>;
    /// Every project setting as `(key, value)`, sorted by key (byte-wise).
    fn config_entries(&self) -> Result<Vec<(String, String)>>;
    /// The keys of every stored opaque value, sorted (byte-wise).
    fn blob_keys(&self) -> Result<Vec<String>>;
}

/// The writes a use case makes, inside one transaction opened by [`Store::write`].
pub trait StoreWrite: StoreRead {
    /// Adds new sensors and updates changed ones (position, elevation, source); idempotent.
    /// Fails on a sensor listed twice with different content.
    fn upsert_sensors(&mut self, sensors: &[SensorRecord]) -> Result<UpsertStats>;
    /// Adds new modalities; idempotent. A modality stored with a unit keeps it: a different
    /// unit for it is [`StoreError::UnitMismatch`] (naming both), never a relabelling of the
    /// stored readings. A unit given for a modality stored without one is recorded.
    fn upsert_modalities(&mut self, modalities: &[ModalityRecord]) -> Result<UpsertStats>;
    /// Stores a batch of readings. Identical readings already stored are counted as unchanged;
    /// a stored reading with the same (sensor, modality, t) but a different value (relative
    /// difference above 1e-12) is a conflict, handled by `policy`. Unknown sensors or
    /// modalities, bad indices and non-finite values are errors.
    fn insert_readings(
        &mut self,
        batch: &ReadingBatch,
        policy: ConflictPolicy,
    ) -> Result<InsertStats>;
    /// Records the provenance of an ingest; returns its row id.
    fn record_ingest(&mut self, ingest: &IngestRecord) -> Result<i64>;

    /// Replaces the cell grid. A stored cell identical to a new one (label, centre, side,
    /// sensors) is kept with its metadata; every other stored cell is deleted with all its
    /// metadata (summaries, correlations, anomalies, class probabilities).
    fn replace_cells(&mut self, cells: &[CellRecord]) -> Result<ReplaceCellsStats>;
    /// Writes cell metadata (see [`CellMetadata`] for what is replaced and what is upserted).
    fn upsert_cell_metadata(&mut self, metadata: &[CellMetadata]) -> Result<()>;
    /// Marks sensors as collected at the given times (seconds); a time earlier than the stored
    /// one leaves the stored one (last collection never moves back).
    fn set_sensors_collected(&mut self, collected: &[(SensorId, UnixSeconds)]) -> Result<()>;

    /// Creates a planned mission with its stops; returns its id.
    fn create_mission(&mut self, mission: &NewMission) -> Result<MissionId>;
    /// Records the cells a mission actually visited, in order, and marks it flown at
    /// `flown_at` (s). A mission already flown is refused ([`StoreError::AlreadyFlown`])
    /// unless `amend`, which replaces the earlier record.
    fn record_visits(
        &mut self,
        mission: MissionId,
        visits: &[VisitRecord],
        flown_at: UnixSeconds,
        amend: bool,
    ) -> Result<()>;

    /// Flags a planned mission cancelled (it keeps its id, stops and place in the history).
    /// Fails when the mission does not exist or is not planned (flown or already cancelled).
    fn cancel_mission(&mut self, mission: MissionId) -> Result<()>;
    /// Deletes a mission with its stops and visits. Fails with [`StoreError::Unknown`] when
    /// it does not exist. Whether it may be deleted is the caller's rule.
    fn delete_mission(&mut self, mission: MissionId) -> Result<()>;

    /// Stores a mission exactly as read from another store (for copying a project between
    /// backends): same id, status, `flown_at`, stops and visits. Fails when a mission with
    /// that id exists; later [`StoreWrite::create_mission`] calls get ids above it.
    fn import_mission(&mut self, record: &MissionRecord) -> Result<()>;

    /// Sets a project setting.
    fn config_set(&mut self, key: &str, value: &str) -> Result<()>;
    /// Stores an opaque value under `key` (replacing any).
    fn blob_put(&mut self, key: &str, value: &[u8]) -> Result<()>;
}

/// Persistent state of a gleaner project: sensors, readings, cells, the cell metadata table
/// (docs/method.md §5), missions and settings.
///
/// Every write goes through [`Store::write`]: the closure's writes are one transaction, kept
/// when it returns `Ok`, all discarded when it returns `Err` (or panics, or the process dies).
/// Writers are serialised: a second writer waits for the first (up to a backend-specific
/// timeout) rather than failing at once.
pub trait Store: StoreRead {
    /// An open write transaction.
    type Tx<'a>: StoreWrite
    where
        Self: 'a;

    /// Runs `f` in one write transaction; commits when it returns `Ok`.
    fn write<R, E>(&mut self, f: impl FnOnce(&mut Self::Tx<'_>) -> Result<R, E>) -> Result<R, E>
    where
        E: From<StoreError>;

    /// Takes the project's *exclusion*, held across connections, processes and machines
    /// until [`unlock_project`](Self::unlock_project): on PostgreSQL the project's
    /// session-level advisory lock (`pg_advisory_lock`, the key every write transaction of
    /// the project takes with `pg_advisory_xact_lock`, so a holder also keeps out every
    /// other writer); on an SQLite file an exclusive lock on the file `<database>-lock`
    /// beside it (`flock`); a database in memory has no one to share with (nothing is
    /// taken). A use case that reads, computes and then writes (a plan: scoring, search,
    /// store) holds it throughout, so it runs whole before or after another holder's,
    /// whichever server replica or CLI process runs each.
    ///
    /// Waits for another holder up to the backend's lock timeout ([`crate::PG_LOCK_TIMEOUT`],
    /// [`crate::SQLITE_BUSY_TIMEOUT`]), then fails with "another gleaner process has been writing
    /// to ...". Re-entrant: a holder may take it again; each successful call needs one
    /// `unlock_project`. Released by the operating system or the server if the process or
    /// the connection dies.
    fn lock_project(&self) -> Result<()>;

    /// Gives back one hold of [`lock_project`](Self::lock_project). Never fails: a hold
    /// that cannot be given back (the connection is gone) ends with the connection.
    fn unlock_project(&self);
}
