//! The backend-neutral [`Store`] trait.

use std::ops::RangeInclusive;

use gleaner_field::{Modality, SensorId, UnixSeconds};

use crate::{
    CellMetadata, CellRecord, ConflictPolicy, IngestRecord, InsertStats, MissionId, MissionRecord,
    ModalityRecord, NewMission, ReadingBatch, RefreshParams, ReplaceCellsStats, Result,
    SensorRecord, SensorSummary, UpsertStats, VisitRecord,
};

/// Persistent state of a gleaner project: sensors, readings, cells, the cell metadata table
/// (SPEC §5), missions and settings.
///
/// Every write method is one transaction: if it returns an error, nothing it did is kept.
/// Times are seconds since the Unix epoch (UTC), distances metres, energies joules, data
/// volumes bytes. Results are returned in a deterministic order (by name, cell index, time).
pub trait Store {
    /// The schema version of the open database.
    fn schema_version(&self) -> Result<i64>;

    /// Adds new sensors and updates changed ones (position, elevation, source); idempotent.
    /// Fails on a sensor listed twice with different content.
    fn upsert_sensors(&mut self, sensors: &[SensorRecord]) -> Result<UpsertStats>;
    /// All sensors, sorted by id.
    fn sensors(&self) -> Result<Vec<SensorRecord>>;
    /// Adds new modalities and updates changed units; idempotent.
    fn upsert_modalities(&mut self, modalities: &[ModalityRecord]) -> Result<UpsertStats>;
    /// All modalities, sorted by name.
    fn modalities(&self) -> Result<Vec<ModalityRecord>>;

    /// Stores a batch of readings. Identical readings already stored are counted as unchanged;
    /// a stored reading with the same (sensor, modality, t) but a different value (relative
    /// difference above 1e-12) is a conflict, handled by `policy`. Unknown sensors or
    /// modalities, bad indices and non-finite values are errors.
    fn insert_readings(
        &mut self,
        batch: &ReadingBatch,
        policy: ConflictPolicy,
    ) -> Result<InsertStats>;
    /// Readings of `modality` (or of all modalities) with `t` in `range` (seconds, inclusive),
    /// ordered by sensor id, modality name, time.
    fn readings_for(
        &self,
        modality: Option<&Modality>,
        range: RangeInclusive<UnixSeconds>,
    ) -> Result<ReadingBatch>;
    /// Number of stored readings.
    fn reading_count(&self) -> Result<u64>;
    /// Count, mean, sample std, min, max and latest value per sensor and modality, sorted by
    /// sensor id then modality name.
    fn sensor_summaries(&self) -> Result<Vec<SensorSummary>>;
    /// One whole ingest in one transaction: upserts `modalities`, inserts `batch` under
    /// `policy`, and records each `provenance` entry (its inserted/unchanged counts set from
    /// the insert). On any error nothing is written.
    fn ingest(
        &mut self,
        modalities: &[ModalityRecord],
        batch: &ReadingBatch,
        policy: ConflictPolicy,
        provenance: &[IngestRecord],
    ) -> Result<InsertStats>;
    /// Records the provenance of an ingest; returns its row id.
    fn record_ingest(&mut self, ingest: &IngestRecord) -> Result<i64>;
    /// All ingest records, oldest first.
    fn ingests(&self) -> Result<Vec<IngestRecord>>;

    /// Replaces the cell grid. A stored cell identical to a new one (label, centre, side,
    /// sensors) is kept with its metadata; every other stored cell is deleted with all its
    /// metadata (summaries, correlations, anomalies, class probabilities).
    fn replace_cells(&mut self, cells: &[CellRecord]) -> Result<ReplaceCellsStats>;
    /// All cells, sorted by index (column, then row).
    fn cells(&self) -> Result<Vec<CellRecord>>;
    /// The cell metadata table: one entry per stored cell (empty for cells never described),
    /// sorted by cell index.
    fn cell_metadata(&self) -> Result<Vec<CellMetadata>>;
    /// Writes cell metadata (see [`CellMetadata`] for what is replaced and what is upserted).
    fn upsert_cell_metadata(&mut self, metadata: &[CellMetadata]) -> Result<()>;
    /// Recomputes, from the readings and the sensors' collection times, every cell's
    /// per-modality summaries (cell series = mean over the cell's sensors at each time), its
    /// last collection time (latest of its sensors') and its pending data volume (bytes logged
    /// since the later of the last collection and the latest stored reading, per series, at the
    /// series' mean logging interval). Returns the number of summaries written.
    fn refresh_cell_summaries(&mut self, params: &RefreshParams) -> Result<usize>;
    /// Marks sensors as collected at the given times (seconds); a time earlier than the stored
    /// one leaves the stored one (last collection never moves back).
    fn set_sensors_collected(&mut self, collected: &[(SensorId, UnixSeconds)]) -> Result<()>;
    /// Marks one sensor as collected at `t` (seconds); see [`Store::set_sensors_collected`].
    fn set_sensor_collected(&mut self, sensor: &SensorId, t: UnixSeconds) -> Result<()> {
        self.set_sensors_collected(&[(sensor.clone(), t)])
    }
    /// Last collection time per sensor (collected sensors only), sorted by sensor id.
    fn sensor_last_collected(&self) -> Result<Vec<(SensorId, UnixSeconds)>>;

    /// Creates a planned mission; returns its id.
    fn create_mission(&mut self, mission: &NewMission) -> Result<MissionId>;
    /// Records the cells a mission actually visited (replacing earlier records) and marks it
    /// flown.
    fn record_visits(&mut self, mission: MissionId, visits: &[VisitRecord]) -> Result<()>;
    /// All missions with their visits, oldest first.
    fn missions(&self) -> Result<Vec<MissionRecord>>;

    /// A project setting, if set.
    fn config_get(&self, key: &str) -> Result<Option<String>>;
    /// Sets a project setting.
    fn config_set(&mut self, key: &str, value: &str) -> Result<()>;
}
