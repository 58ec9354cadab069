//! Plain values that go in and out of a [`crate::Store`].

use std::collections::HashMap;
use std::fmt;

use gleaner_field::{CellIndex, LatLon, Modality, SensorId, UnixSeconds};

/// A sensor station as stored.
#[derive(Debug, Clone, PartialEq)]
pub struct SensorRecord {
    /// The station's identifier.
    pub id: SensorId,
    /// WGS84 position, degrees.
    pub position: LatLon,
    /// Elevation, metres, when known.
    pub elevation_m: Option<f64>,
    /// Where the record came from (a file name, `manual`, ...).
    pub source: String,
}

/// A modality and its unit (e.g. `vw@30cm` in `m3/m3`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ModalityRecord {
    /// The modality.
    pub modality: Modality,
    /// Its unit as text, when known.
    pub unit: Option<String>,
}

/// What an upsert of sensors or modalities did.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct UpsertStats {
    /// Names of records that were new.
    pub added: Vec<String>,
    /// Names of records that existed with different content and were updated (for sensors: a
    /// changed position, elevation or source; for modalities: a changed unit).
    pub updated: Vec<String>,
    /// How many records were already stored exactly as given.
    pub unchanged: usize,
}

/// One reading inside a [`ReadingBatch`]: indices into the batch's sensor and modality lists,
/// a time and a value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reading {
    /// Index into [`ReadingBatch::sensors`].
    pub sensor: u32,
    /// Index into [`ReadingBatch::modalities`].
    pub modality: u32,
    /// Time, seconds since the Unix epoch (UTC).
    pub t: UnixSeconds,
    /// The value, in the modality's unit. Must be finite.
    pub value: f64,
}

/// A columnar set of readings: the sensors and modalities once, and compact rows that index
/// them. Built by ingest, returned by [`crate::StoreRead::readings_for`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ReadingBatch {
    /// The sensors the rows refer to.
    pub sensors: Vec<SensorId>,
    /// The modalities the rows refer to.
    pub modalities: Vec<Modality>,
    /// The readings.
    pub rows: Vec<Reading>,
}

impl ReadingBatch {
    /// An empty batch.
    pub fn new() -> Self {
        Self::default()
    }
    /// Number of readings.
    pub fn len(&self) -> usize {
        self.rows.len()
    }
    /// Whether the batch has no readings.
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }
    /// Every reading with its sensor and modality resolved. Rows with out-of-range indices are
    /// skipped (the store rejects them on insert).
    pub fn iter(&self) -> impl Iterator<Item = (&SensorId, &Modality, UnixSeconds, f64)> + '_ {
        self.rows.iter().filter_map(|r| {
            Some((
                self.sensors.get(r.sensor as usize)?,
                self.modalities.get(r.modality as usize)?,
                r.t,
                r.value,
            ))
        })
    }
}

/// Builds a [`ReadingBatch`] one reading at a time, interning sensors and modalities.
#[derive(Debug, Default)]
pub struct ReadingBatchBuilder {
    batch: ReadingBatch,
    sensor_index: HashMap<SensorId, u32>,
    modality_index: HashMap<Modality, u32>,
}

impl ReadingBatchBuilder {
    /// An empty builder.
    pub fn new() -> Self {
        Self::default()
    }
    /// Adds a reading of `modality` by `sensor` at `t` (seconds since the epoch, UTC).
    pub fn push(&mut self, sensor: &SensorId, modality: &Modality, t: UnixSeconds, value: f64) {
        let s = intern(&mut self.sensor_index, &mut self.batch.sensors, sensor);
        let m = intern(
            &mut self.modality_index,
            &mut self.batch.modalities,
            modality,
        );
        self.batch.rows.push(Reading {
            sensor: s,
            modality: m,
            t,
            value,
        });
    }
    /// The batch built so far.
    pub fn finish(self) -> ReadingBatch {
        self.batch
    }
}

fn intern<K: Clone + Eq + std::hash::Hash>(
    index: &mut HashMap<K, u32>,
    list: &mut Vec<K>,
    key: &K,
) -> u32 {
    if let Some(&k) = index.get(key) {
        return k;
    }
    let k = list.len() as u32;
    list.push(key.clone());
    index.insert(key.clone(), k);
    k
}

/// What to do with an incoming reading whose key (sensor, modality, t) is already stored with a
/// different value (beyond a relative tolerance of 1e-12).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ConflictPolicy {
    /// Roll back the whole insert and return [`crate::StoreError::Conflicts`].
    #[default]
    Fail,
    /// Keep the stored value, report the conflict in [`InsertStats::conflicts`], go on.
    Skip,
}

/// A reading whose key was already stored with a different value.
#[derive(Debug, Clone, PartialEq)]
pub struct Conflict {
    /// Sensor.
    pub sensor: SensorId,
    /// Modality.
    pub modality: Modality,
    /// Time, seconds since the Unix epoch (UTC).
    pub t: UnixSeconds,
    /// The value already in the store (kept).
    pub stored: f64,
    /// The value that was offered.
    pub incoming: f64,
}

/// What an insert of readings did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct InsertStats {
    /// Readings newly stored.
    pub inserted: u64,
    /// Readings already stored with the same value (or repeated within the batch).
    pub unchanged: u64,
    /// Readings already stored with a different value, kept as stored
    /// ([`ConflictPolicy::Skip`] only).
    pub conflicts: Vec<Conflict>,
}

/// One row of the `ingests` provenance table.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct IngestRecord {
    /// File name (or path) the readings came from.
    pub file_name: String,
    /// Format name (e.g. `caf-daily-csv`).
    pub format: String,
    /// Rows read from the file.
    pub rows_read: u64,
    /// Readings newly stored.
    pub rows_inserted: u64,
    /// Readings already stored identically.
    pub rows_unchanged: u64,
    /// Rows skipped (unparseable, missing values, conflicts kept as stored).
    pub rows_skipped: u64,
    /// When the ingest ran, seconds since the Unix epoch (UTC).
    pub at: UnixSeconds,
}

/// Summary statistics of one series (a sensor's or a cell's readings of one modality), values
/// in the modality's unit.
#[derive(Debug, Clone, PartialEq)]
pub struct SeriesStats {
    /// Number of points.
    pub count: u64,
    /// Mean.
    pub mean: f64,
    /// Sample standard deviation (n − 1); `None` with fewer than 2 points.
    pub std: Option<f64>,
    /// Minimum.
    pub min: f64,
    /// Maximum.
    pub max: f64,
    /// Time of the latest point, seconds since the Unix epoch (UTC).
    pub latest_t: UnixSeconds,
    /// Value of the latest point.
    pub latest_value: f64,
}

/// Summary of one sensor's readings of one modality.
#[derive(Debug, Clone, PartialEq)]
pub struct SensorSummary {
    /// Sensor.
    pub sensor: SensorId,
    /// Modality.
    pub modality: Modality,
    /// The statistics.
    pub stats: SeriesStats,
}

/// A grid cell as stored: its index (label `x12y-3`), centre, side and sensors.
#[derive(Debug, Clone, PartialEq)]
pub struct CellRecord {
    /// Grid index; its label (`x12y-3`) is the cell's id in the database.
    pub index: CellIndex,
    /// Centre, WGS84 degrees.
    pub centre: LatLon,
    /// Side of the square, metres.
    pub cell_size_m: f64,
    /// The sensors in the cell, in any order (stored sorted).
    pub sensors: Vec<SensorId>,
}

/// Summary of a cell's series of one modality (the cell series is the mean over the cell's
/// sensors at each time, docs/method.md §2).
#[derive(Debug, Clone, PartialEq)]
pub struct ModalitySummary {
    /// Modality.
    pub modality: Modality,
    /// The statistics of the cell series.
    pub stats: SeriesStats,
}

/// Pearson correlation of a cell's series with a neighbour's, for one modality.
#[derive(Debug, Clone, PartialEq)]
pub struct Correlation {
    /// The neighbouring cell.
    pub neighbour: CellIndex,
    /// Modality.
    pub modality: Modality,
    /// Correlation coefficient in [-1, 1] (0 when there is no evidence, docs/method.md §2).
    pub correlation: f64,
    /// Number of common timestamps it was computed over.
    pub overlap: u64,
}

/// One entry of a cell's anomaly history: the anomaly score A of one modality at one time.
#[derive(Debug, Clone, PartialEq)]
pub struct AnomalyRecord {
    /// Modality.
    pub modality: Modality,
    /// Time of the judged reading, seconds since the Unix epoch (UTC).
    pub t: UnixSeconds,
    /// Anomaly score A (dimensionless, in standard deviations).
    pub anomaly: f64,
    /// Whether the collection was flagged as anomalous.
    pub flagged: bool,
}

/// A class probability of the cell's predicted agricultural condition.
#[derive(Debug, Clone, PartialEq)]
pub struct ClassProbability {
    /// Class name (e.g. `dry`).
    pub class: String,
    /// Probability in [0, 1].
    pub probability: f64,
}

/// The latest utility terms of a cell (docs/method.md §2).
#[derive(Debug, Clone, PartialEq)]
pub struct CellScores {
    /// Freshness F in [0, 1].
    pub freshness: f64,
    /// Redundancy R in [0, 1].
    pub redundancy: f64,
    /// Anomaly A (>= 0).
    pub anomaly: f64,
    /// Model uncertainty U in [0, 1].
    pub uncertainty: f64,
    /// Score S.
    pub score: f64,
    /// When the terms were computed, seconds since the Unix epoch (UTC).
    pub computed_at: UnixSeconds,
}

/// One row of the cell metadata table (docs/method.md §5) with its child records.
///
/// On [`crate::StoreWrite::upsert_cell_metadata`] the scalar fields, `scores` and
/// `class_probabilities` replace what is stored for the cell; `summaries`, `correlations` and
/// `anomalies` are upserted by key (modality; neighbour + modality; modality + t) and never
/// deleted, so an empty list leaves them as they are.
#[derive(Debug, Clone, PartialEq)]
pub struct CellMetadata {
    /// The cell.
    pub cell: CellIndex,
    /// Last time a UAV collected the cell, seconds since the Unix epoch (UTC).
    pub last_collected: Option<UnixSeconds>,
    /// Estimated data waiting in the cell's sensors, bytes.
    pub pending_bytes: Option<f64>,
    /// Expected energy to collect the cell (hover + receiver), joules.
    pub expected_energy_j: Option<f64>,
    /// The latest F, R, A, U, S.
    pub scores: Option<CellScores>,
    /// The model's class distribution behind U.
    pub class_probabilities: Vec<ClassProbability>,
    /// Per-modality summaries of the cell series.
    pub summaries: Vec<ModalitySummary>,
    /// Correlations with neighbours, per modality.
    pub correlations: Vec<Correlation>,
    /// Anomaly history, per modality and time.
    pub anomalies: Vec<AnomalyRecord>,
}

impl CellMetadata {
    /// Empty metadata for `cell`.
    pub fn new(cell: CellIndex) -> Self {
        Self {
            cell,
            last_collected: None,
            pending_bytes: None,
            expected_energy_j: None,
            scores: None,
            class_probabilities: Vec::new(),
            summaries: Vec::new(),
            correlations: Vec::new(),
            anomalies: Vec::new(),
        }
    }
}

/// Whether a mission explores (visits every cell) or adapts (visits the best cells).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MissionKind {
    /// An exploration sortie (docs/method.md §5 step 3).
    Exploration,
    /// An adaptive mission (docs/method.md §5 step 4).
    Adaptive,
}

impl MissionKind {
    /// The name stored in the database.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Exploration => "exploration",
            Self::Adaptive => "adaptive",
        }
    }
    /// Parses [`Self::as_str`].
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "exploration" => Some(Self::Exploration),
            "adaptive" => Some(Self::Adaptive),
            _ => None,
        }
    }
}

/// Whether a mission has been flown.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MissionStatus {
    /// Planned, not yet recorded as flown.
    Planned,
    /// Flown: its visits have been recorded.
    Flown,
    /// Cancelled before it was flown: kept in the history, never recorded or exported.
    Cancelled,
}

impl MissionStatus {
    /// The name stored in the database.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Planned => "planned",
            Self::Flown => "flown",
            Self::Cancelled => "cancelled",
        }
    }
    /// Parses [`Self::as_str`].
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "planned" => Some(Self::Planned),
            "flown" => Some(Self::Flown),
            "cancelled" => Some(Self::Cancelled),
            _ => None,
        }
    }
}

/// A mission's id in the database.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct MissionId(pub i64);

impl fmt::Display for MissionId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.0)
    }
}

/// The energy breakdown of a sortie B -> c_1 -> ... -> c_k -> B (docs/method.md §3).
///
/// `total_j = travel_j + hover_j + comm_j + return_j`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct EnergyBreakdown {
    /// E_t: cruise from the base through the cells (with climb and descent), J.
    pub travel_j: f64,
    /// E_h: hover energy over all cells, J.
    pub hover_j: f64,
    /// E_c: receiver energy over all cells, J.
    pub comm_j: f64,
    /// E_r: return leg to the base, J.
    pub return_j: f64,
    /// E_t + E_h + E_c + E_r, J.
    pub total_j: f64,
    /// Usable budget the route was planned against, J.
    pub budget_j: f64,
    /// Cruise distance including the return leg, m.
    pub distance_m: f64,
    /// Flight time including hovers, s.
    pub flight_time_s: f64,
}

/// How the aircraft is to fly a mission: what the energy model assumed, so that flight files
/// command exactly that.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlightProfile {
    /// Base station (take-off and landing), WGS84 degrees.
    pub base: LatLon,
    /// Base station altitude above mean sea level, m.
    pub base_alt_m: f64,
    /// Flight altitude above the base, m.
    pub altitude_m: f64,
    /// Cruise ground speed between cells, m/s.
    pub cruise_speed_mps: f64,
    /// The steady wind the legs were priced in (the forecast plus the planning margin), m/s
    /// (>= 0; 0: still air, and every mission stored before winds were planned).
    pub wind_mps: f64,
    /// Direction that wind blows from, degrees clockwise from north (meteorological).
    pub wind_from_deg: f64,
}

/// One planned stop of a mission, in visiting order.
#[derive(Debug, Clone, PartialEq)]
pub struct StopRecord {
    /// Position in the visiting order, from 0.
    pub order: u32,
    /// The cell (stored by label, so history survives a new grid).
    pub cell: CellIndex,
    /// Cell centre, WGS84 degrees: where the aircraft hovers.
    pub centre: LatLon,
    /// Score S when planned (0 for exploration sorties), dimensionless.
    pub score: f64,
    /// F, R, A, U when planned (absent for exploration or scores from a file).
    pub terms: Option<[f64; 4]>,
    /// Leg from the previous stop (the base for the first), m.
    pub leg_distance_m: f64,
    /// Propulsion energy of that leg, J.
    pub leg_energy_j: f64,
    /// Upload time t_comm, s.
    pub collection_s: f64,
    /// Hover time at the cell, s.
    pub hover_s: f64,
    /// Hover energy, J.
    pub hover_j: f64,
    /// Receiver energy, J.
    pub comm_j: f64,
}

/// A mission to create (status `planned`).
#[derive(Debug, Clone, PartialEq)]
pub struct NewMission {
    /// When it was created, seconds since the Unix epoch (UTC).
    pub created_at: UnixSeconds,
    /// Exploration or adaptive.
    pub kind: MissionKind,
    /// The mission time t it was planned for, seconds since the Unix epoch (UTC).
    pub planned_at: UnixSeconds,
    /// The planner that produced it (e.g. `greedy`, `default`, `exploration`).
    pub solver: String,
    /// The planner's seed.
    pub seed: u64,
    /// Utility weights alpha, beta, gamma, delta the scores were computed with.
    pub weights: [f64; 4],
    /// The anomaly form label (`raw`, `bounded(kappa=3)`, `n/a`).
    pub anomaly_form: String,
    /// Sum of S over the stops.
    pub total_score: f64,
    /// How the aircraft flies it.
    pub profile: FlightProfile,
    /// The energy model's breakdown of the route.
    pub energy: EnergyBreakdown,
    /// Return leg from the last stop to the base, m.
    pub return_distance_m: f64,
    /// The stops, in visiting order.
    pub stops: Vec<StopRecord>,
}

/// A stored mission with its stops and visits.
#[derive(Debug, Clone, PartialEq)]
pub struct MissionRecord {
    /// Its id.
    pub id: MissionId,
    /// The fields it was created with.
    pub mission: NewMission,
    /// Planned, flown or cancelled.
    pub status: MissionStatus,
    /// When it was recorded as flown, seconds since the Unix epoch (UTC).
    pub flown_at: Option<UnixSeconds>,
    /// The recorded visits in visiting order (empty while planned).
    pub visits: Vec<VisitRecord>,
}

/// A cell actually visited during a flown mission.
#[derive(Debug, Clone, PartialEq)]
pub struct VisitRecord {
    /// Position in the visiting order, from 0.
    pub order: u32,
    /// The cell (stored by label, so history survives a change of grid).
    pub cell: CellIndex,
    /// Arrival time, seconds since the Unix epoch (UTC), when known.
    pub arrived_at: Option<UnixSeconds>,
    /// Energy spent at (and on the leg to) the cell, joules, when known.
    pub energy_j: Option<f64>,
}

/// What [`crate::StoreWrite::replace_cells`] did.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ReplaceCellsStats {
    /// Cells kept with their metadata (same label, side and sensors).
    pub kept: usize,
    /// Cells deleted with their metadata.
    pub removed: usize,
    /// Cells added.
    pub added: usize,
}
