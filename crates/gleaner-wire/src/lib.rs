//! gleaner's wire formats: versioned serde documents, apart from the application layer.
//!
//! - [`MissionDoc`] (`gleaner.mission` version 1): a planned or flown mission — the JSON
//!   output of `plan --json`, `explore --json`, the HTTP API's mission resource — and the
//!   input of every flight-file writer.
//! - [`FieldDoc`] (`gleaner.field` version 1): the cell grid with its latest scores and the
//!   sensors, for maps.
//!
//! Positions in documents are WGS84 `[lon, lat]` degrees (GeoJSON order) unless a field's name
//! says otherwise; lengths m, times s (and RFC 3339 text), energies J, speeds m/s.
#![deny(missing_docs)]

use serde::{Deserialize, Serialize};

pub mod convert;
pub mod docs;

/// Format name and version of [`MissionDoc`].
pub const MISSION_FORMAT: &str = "gleaner.mission";
/// Format name and version of [`FieldDoc`].
pub const FIELD_FORMAT: &str = "gleaner.field";
/// The version of the documents this build writes.
pub const VERSION: u32 = 1;

/// How the aircraft is to fly a mission: what the energy model assumed.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ProfileDoc {
    /// Base station (take-off and landing) `[lon, lat]`, WGS84 degrees.
    pub base_lon_lat: [f64; 2],
    /// Base station altitude above mean sea level, m.
    pub base_alt_m: f64,
    /// Flight altitude above the base, m.
    pub altitude_m: f64,
    /// Cruise ground speed between cells, m/s.
    pub cruise_speed_mps: f64,
}

/// One stop of a mission, in visiting order.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StopDoc {
    /// Position in the visiting order, from 1.
    pub order: u32,
    /// Cell id (`x12y-3`).
    pub cell: String,
    /// Cell centre `[lon, lat]`, WGS84 degrees: where the aircraft hovers.
    pub centre_lon_lat: [f64; 2],
    /// Score S when planned (0 for exploration).
    pub s: f64,
    /// F, R, A, U when planned (absent for exploration or scores from a file).
    pub terms: Option<[f64; 4]>,
    /// Leg from the previous stop (the base for the first), m.
    pub leg_distance_m: f64,
    /// Propulsion energy of that leg, J.
    pub leg_energy_j: f64,
    /// Upload time, s.
    pub collection_s: f64,
    /// Hover time, s.
    pub hover_s: f64,
    /// Hover energy, J.
    pub hover_j: f64,
    /// Receiver energy, J.
    pub comm_j: f64,
}

/// The energy breakdown of a sortie (SPEC §3).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct EnergyDoc {
    /// E_t: travel from the base through the cells, J.
    pub travel_j: f64,
    /// E_h: hover, J.
    pub hover_j: f64,
    /// E_c: receiver, J.
    pub comm_j: f64,
    /// E_r: return leg, J.
    pub return_j: f64,
    /// Total, J.
    pub total_j: f64,
    /// Usable budget, J.
    pub budget_j: f64,
    /// total / budget.
    pub utilisation: f64,
    /// Distance flown, m.
    pub distance_m: f64,
    /// Flight time including hovers, s.
    pub flight_time_s: f64,
}

/// Headline numbers of a comparison plan (the paper's greedy on the same instance).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BaselineDoc {
    /// Planner name.
    pub planner: String,
    /// Cells visited.
    pub cells: usize,
    /// Sum of S.
    pub total_score: f64,
    /// Energy, J.
    pub energy_j: f64,
}

/// A planned or flown mission (`gleaner.mission` version 1).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MissionDoc {
    /// Always [`MISSION_FORMAT`].
    pub format: String,
    /// Always [`VERSION`] when written by this build.
    pub version: u32,
    /// Stored mission id (absent for a dry run).
    pub mission_id: Option<i64>,
    /// `adaptive` or `exploration`.
    pub kind: String,
    /// `planned`, `flown` or `dry-run`.
    pub status: String,
    /// Mission time t, RFC 3339 UTC.
    pub planned_at: String,
    /// Mission time t, seconds since the Unix epoch.
    pub planned_at_s: i64,
    /// When recorded as flown, RFC 3339 UTC.
    pub flown_at: Option<String>,
    /// Planner name (`default`, `greedy`, `exact`, `exploration`).
    pub planner: String,
    /// Planner seed.
    pub seed: u64,
    /// Weights alpha, beta, gamma, delta of S = alpha·F + beta·A + gamma·U − delta·R.
    pub weights: [f64; 4],
    /// Anomaly form (`raw`, `bounded(kappa=3)`, `n/a`).
    pub anomaly_form: String,
    /// How the aircraft flies it.
    pub profile: ProfileDoc,
    /// Stops in visiting order.
    pub stops: Vec<StopDoc>,
    /// Return leg, m.
    pub return_distance_m: f64,
    /// Energy totals.
    pub energy: EnergyDoc,
    /// Sum of S over the stops.
    pub total_score: f64,
    /// Cells with S > 0 the planner chose from (plan output only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub candidates: Option<usize>,
    /// The paper's greedy on the same instance (plan output only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub greedy_baseline: Option<BaselineDoc>,
}

/// A cell's latest utility terms.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ScoresDoc {
    /// Freshness F.
    pub f: f64,
    /// Redundancy R.
    pub r: f64,
    /// Anomaly A (as used in S).
    pub a: f64,
    /// Uncertainty U.
    pub u: f64,
    /// Score S.
    pub s: f64,
    /// When computed, seconds since the Unix epoch.
    pub computed_at_s: i64,
}

/// One grid cell for maps.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CellDoc {
    /// Cell id (`x12y-3`).
    pub cell: String,
    /// Centre `[lon, lat]`, WGS84 degrees.
    pub centre_lon_lat: [f64; 2],
    /// The square as a closed counter-clockwise ring of `[lon, lat]` (5 points, first = last).
    pub ring_lon_lat: Vec<[f64; 2]>,
    /// Number of sensors in the cell.
    pub sensors: usize,
    /// Latest terms, if scored.
    pub scores: Option<ScoresDoc>,
}

/// A sensor station for maps.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SensorDoc {
    /// Sensor id.
    pub id: String,
    /// Position `[lon, lat]`, WGS84 degrees.
    pub lon_lat: [f64; 2],
}

/// The field: grid, scores and sensors (`gleaner.field` version 1).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FieldDoc {
    /// Always [`FIELD_FORMAT`].
    pub format: String,
    /// Always [`VERSION`] when written by this build.
    pub version: u32,
    /// Project name.
    pub project: String,
    /// Cell side, m.
    pub cell_size_m: f64,
    /// Base station `[lon, lat]`, WGS84 degrees.
    pub base_lon_lat: [f64; 2],
    /// Cells, sorted by id.
    pub cells: Vec<CellDoc>,
    /// Sensors, sorted by id.
    pub sensors: Vec<SensorDoc>,
}
