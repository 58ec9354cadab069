//! The CLI's and the HTTP API's JSON documents for cells, scorings and explorations.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

/// Latest F, R, A, U, S of a cell.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct CellScoresDoc {
    /// Freshness in [0, 1].
    pub freshness: f64,
    /// Redundancy in [0, 1].
    pub redundancy: f64,
    /// Anomaly, >= 0.
    pub anomaly: f64,
    /// Uncertainty in [0, 1].
    pub uncertainty: f64,
    /// Score.
    pub score: f64,
    /// When computed, RFC 3339 UTC.
    pub computed_at: String,
}

/// A cell series summary, values in the modality's unit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct SummaryDoc {
    /// Modality.
    pub modality: String,
    /// Points.
    pub count: u64,
    /// Mean.
    pub mean: f64,
    /// Sample standard deviation.
    pub std: Option<f64>,
    /// Minimum.
    pub min: f64,
    /// Maximum.
    pub max: f64,
    /// Latest value.
    pub latest_value: f64,
    /// Latest time, RFC 3339 UTC.
    pub latest_t: String,
}

/// A neighbour correlation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct CorrelationDoc {
    /// Neighbour cell id.
    pub neighbour: String,
    /// Modality.
    pub modality: String,
    /// Pearson correlation.
    pub correlation: f64,
    /// Common points.
    pub overlap: u64,
}

/// One row of the cell metadata table (docs/method.md §5). Positions `[lon, lat]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct CellRowDoc {
    /// Cell id, e.g. `x3y-1`.
    pub cell: String,
    /// Grid column.
    pub i: i32,
    /// Grid row.
    pub j: i32,
    /// Centre, `[lon, lat]` degrees.
    pub centre_lon_lat: [f64; 2],
    /// Side, metres.
    pub cell_size_m: f64,
    /// Sensor ids.
    pub sensors: Vec<String>,
    /// Last collection, RFC 3339 UTC.
    pub last_collected: Option<String>,
    /// Estimated pending data, bytes.
    pub pending_bytes: Option<f64>,
    /// Expected collection energy, J.
    pub expected_energy_j: Option<f64>,
    /// Latest utility terms.
    pub scores: Option<CellScoresDoc>,
    /// Per-modality summaries of the cell series.
    pub summaries: Vec<SummaryDoc>,
    /// Correlations with neighbours.
    pub correlations: Vec<CorrelationDoc>,
    /// Class probabilities behind U.
    pub class_probabilities: Vec<(String, f64)>,
}

/// One scored cell. Positions `[lon, lat]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct ScoreRowDoc {
    /// Cell id.
    pub cell: String,
    /// Centre `[lon, lat]`, degrees.
    pub centre_lon_lat: [f64; 2],
    /// Number of sensors.
    pub sensors: usize,
    /// Freshness F.
    pub f: f64,
    /// Redundancy R.
    pub r: f64,
    /// Anomaly A as used in S (see `anomaly_form`).
    pub a: f64,
    /// Raw anomaly.
    pub a_raw: f64,
    /// Uncertainty U.
    pub u: f64,
    /// Score S.
    pub s: f64,
    /// The largest weighted term: what drives S.
    pub driver: String,
    /// R per modality (null where the cell lacks it).
    pub r_by_modality: BTreeMap<String, Option<f64>>,
    /// A per modality.
    pub a_by_modality: BTreeMap<String, Option<f64>>,
    /// Class probabilities.
    pub probabilities: Vec<f64>,
}

/// The condition model behind U.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct ConditionDoc {
    /// Modality the classes come from (`user` for user probabilities).
    pub modality: String,
    /// Class names.
    pub classes: Vec<String>,
    /// Class thresholds in the modality's unit.
    pub thresholds: Vec<f64>,
}

/// A scoring at mission time t.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct ScoringDoc {
    /// Mission time, RFC 3339.
    pub t: String,
    /// Weights alpha, beta, gamma, delta.
    pub weights: [f64; 4],
    /// `raw` or `bounded(kappa=..)`.
    pub anomaly_form: String,
    /// The condition model, if any.
    pub condition: Option<ConditionDoc>,
    /// Warnings (e.g. no condition model: U = 0).
    pub warnings: Vec<String>,
    /// Cells.
    pub cells: Vec<ScoreRowDoc>,
}

/// An exploration plan: its sorties as missions.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct ExplorationDoc {
    /// Planned for, RFC 3339.
    pub planned_at: String,
    /// Cells to visit.
    pub cells: usize,
    /// Usable budget per sortie, J.
    pub budget_j: f64,
    /// A lower bound on the number of sorties.
    pub lower_bound_sorties: usize,
    /// Total energy over all sorties, J.
    pub total_energy_j: f64,
    /// The sorties.
    pub sorties: Vec<crate::MissionDoc>,
    /// Cells the flight cannot reach, left out of the sorties (absent when every cell is).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub unreachable: Vec<crate::UnreachableDoc>,
}

/// A temporal variogram of changes, `nugget + partial · (1 − exp(−h / scale_s))` at lag
/// h > 0, the modality's unit squared.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct VariogramDoc {
    /// Jump at any positive lag, the unit squared.
    pub nugget: f64,
    /// Further growth up to the sill, the unit squared.
    pub partial: f64,
    /// E-folding time of that growth, s.
    pub scale_s: f64,
}

/// The models a reconstruction was made with, fitted on the known readings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct ReconstructionModelDoc {
    /// Levels: residual sill, the unit squared.
    pub levels_sill: f64,
    /// Levels: nugget, the unit squared.
    pub levels_nugget: f64,
    /// Levels: spatial range, m.
    pub levels_range_m: f64,
    /// Levels: time scale, s.
    pub levels_time_scale_s: f64,
    /// Changes: the field-wide part's temporal variogram.
    pub changes_shared: VariogramDoc,
    /// Changes: spatial e-folding distance of the field-wide part, m.
    pub changes_range_m: f64,
    /// Changes: each sensor's own part's temporal variogram.
    pub changes_own: VariogramDoc,
}

/// One sensor's estimated value.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct SensorEstimateDoc {
    /// Sensor id.
    pub sensor: String,
    /// Position, WGS84 [lon, lat] degrees.
    pub lon_lat: [f64; 2],
    /// Its latest known reading's time, RFC 3339 UTC (none: never read).
    pub last_reading: Option<String>,
    /// Last value carried forward (its mean when never read), the modality's unit.
    pub carried: f64,
    /// Model-based estimate, the modality's unit.
    pub estimate: f64,
    /// Its standard deviation under the model, the modality's unit.
    pub sd: f64,
    /// Lower end of its 90% prediction interval, the modality's unit: `estimate − q·sd`,
    /// q calibrated on back-tests (under the dynamic model the sd in the interval includes
    /// the reading noise); null in documents of earlier builds.
    #[serde(default)]
    pub lo90: Option<f64>,
    /// Upper end of its 90% prediction interval, the modality's unit.
    #[serde(default)]
    pub hi90: Option<f64>,
}

/// Every sensor's estimated value of one modality at one time from what is known
/// (`gleaner reconstruct --json`, `GET /api/v1/reconstruct`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct ReconstructionDoc {
    /// Always [`crate::RECONSTRUCTION_FORMAT`].
    pub format: String,
    /// Always [`crate::VERSION`] when written by this build.
    pub version: u32,
    /// Estimation time, RFC 3339 UTC.
    pub at: String,
    /// The modality (e.g. `vw@30cm`).
    pub modality: String,
    /// `changes` (kriging of changes: last value plus the neighbours' known changes since),
    /// `levels` (ordinary kriging of levels), `simple` (simple kriging of levels) or `dynamic`
    /// (the dynamic field model).
    pub estimator: String,
    /// Sampling step of the modality's readings, s.
    pub step_s: i64,
    /// The fitted models.
    pub model: ReconstructionModelDoc,
    /// One per sensor, by id.
    pub sensors: Vec<SensorEstimateDoc>,
}

/// Every sensor's estimate over a range of times (`gleaner reconstruct --from .. --to ..
/// --json`, `GET /api/v1/reconstruct?from=..&to=..`): rows are times, columns the sensors in
/// `sensors`' order.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct ReconstructionSeriesDoc {
    /// Always [`crate::RECONSTRUCTION_SERIES_FORMAT`].
    pub format: String,
    /// Always [`crate::VERSION`] when written by this build.
    pub version: u32,
    /// The modality (e.g. `vw@30cm`).
    pub modality: String,
    /// The modality's unit as stored (e.g. `m3/m3`), if known.
    #[serde(default)]
    pub unit: Option<String>,
    /// `changes` (kriging of changes), `levels` (ordinary kriging of levels), `simple`
    /// (simple kriging of levels) or `dynamic` (the dynamic field model).
    pub estimator: String,
    /// The dynamic model, when it is the estimator: lag-one persistence per step, the step
    /// (s), the shrinkage intensity of the correlations, the reading noise variance (unit²);
    /// null for the other estimators.
    pub model: Option<DynamicModelDoc>,
    /// Estimation times, RFC 3339 UTC.
    pub times: Vec<String>,
    /// Sensor ids and WGS84 positions [lon, lat].
    pub sensors: Vec<SeriesSensorDoc>,
    /// Posterior means, `[time][sensor]`, the modality's unit.
    pub mean: Vec<Vec<f64>>,
    /// Posterior standard deviations, same layout, the unit.
    pub sd: Vec<Vec<f64>>,
    /// Lower ends of the 90% intervals (mean ± q·sd, q calibrated on back-tests;
    /// under the dynamic model the sd includes the reading noise), same layout.
    pub lo90: Vec<Vec<f64>>,
    /// Upper ends of the 90% intervals, same layout.
    pub hi90: Vec<Vec<f64>>,
}

/// The map of a reconstruction at one time (`gleaner reconstruct --at T --map F`,
/// `GET /api/v1/reconstruct/map.svg`): every cell's estimated value and its uncertainty,
/// every sensor's estimate and whether it was read at the time, the field's outline. The
/// input of the reconstruction figure.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct ReconstructionMapDoc {
    /// Always [`crate::RECONSTRUCTION_MAP_FORMAT`].
    pub format: String,
    /// Always [`crate::VERSION`] when written by this build.
    pub version: u32,
    /// Project name.
    pub project: String,
    /// Estimation time, RFC 3339 UTC.
    pub at: String,
    /// The modality (e.g. `vw@30cm`).
    pub modality: String,
    /// The modality's unit as stored (e.g. `m3/m3`), if known.
    pub unit: Option<String>,
    /// `changes`, `levels`, `simple` or `dynamic` (as [`ReconstructionDoc::estimator`]).
    pub estimator: String,
    /// Base station, WGS84 [lon, lat] degrees.
    pub base_lon_lat: [f64; 2],
    /// Cell side, m.
    pub cell_size_m: f64,
    /// A sensor counts as read at the time when its latest reading is at most this long
    /// before it, s.
    pub read_within_s: i64,
    /// The cells, by grid index.
    pub cells: Vec<MapCellDoc>,
    /// The sensors, by id.
    pub sensors: Vec<MapSensorDoc>,
    /// The field's outline (the boundary of its cells' union) as closed rings, WGS84
    /// [lon, lat] degrees.
    pub outline_lon_lat: Vec<Vec<[f64; 2]>>,
}

/// A cell of a [`ReconstructionMapDoc`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct MapCellDoc {
    /// Cell id (`x12y-3`).
    pub cell: String,
    /// The square, closed (first corner repeated), WGS84 [lon, lat] degrees.
    pub ring_lon_lat: Vec<[f64; 2]>,
    /// Its sensors' ids.
    pub sensors: Vec<String>,
    /// The mean of its sensors' estimates, the modality's unit.
    pub mean: f64,
    /// The root mean of its sensors' posterior variances, the modality's unit.
    pub sd: f64,
}

/// A sensor of a [`ReconstructionMapDoc`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct MapSensorDoc {
    /// Sensor id.
    pub sensor: String,
    /// Position, WGS84 [lon, lat] degrees.
    pub lon_lat: [f64; 2],
    /// Model-based estimate, the modality's unit.
    pub estimate: f64,
    /// Its posterior standard deviation, the modality's unit.
    pub sd: f64,
    /// Its latest known reading's time, RFC 3339 UTC (none: never read).
    pub last_reading: Option<String>,
    /// Whether it was read at the time (within `read_within_s`).
    pub read: bool,
}

/// The dynamic field model's parameters in a [`ReconstructionSeriesDoc`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct DynamicModelDoc {
    /// Lag-one autocorrelation of the deviations per `step_s`.
    pub phi: f64,
    /// The step of `phi`, s.
    pub step_s: f64,
    /// Shrinkage intensity of the correlations, [0, 1].
    pub shrinkage: f64,
    /// Reading noise variance, the unit squared.
    pub noise: f64,
}

/// A sensor of a [`ReconstructionSeriesDoc`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct SeriesSensorDoc {
    /// Sensor id.
    pub sensor: String,
    /// WGS84 [lon, lat].
    pub lon_lat: [f64; 2],
}

/// A mean with its 95% interval; `null` where undefined (no value, or too few blocks for an
/// interval: then `low` = `high` = `null` and `mean` stands alone).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct IntervalDoc {
    /// The mean.
    pub mean: Option<f64>,
    /// Lower end of the 95% interval.
    pub low: Option<f64>,
    /// Upper end of the 95% interval.
    pub high: Option<f64>,
    /// Independent values the interval rests on (7-day blocks of missions, or events).
    pub n: usize,
}

/// One strategy at one battery budget over a campaign.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct StrategySummaryDoc {
    /// Strategy (`gleaner`, `round-robin`, ...).
    pub strategy: String,
    /// Battery capacity as a fraction of the settings' preset.
    pub budget: f64,
    /// Runs pooled (seeds).
    pub runs: usize,
    /// Per mission, means over 7-day blocks with 95% intervals: `rmse_kriged`,
    /// `rmse_carried`, `mae_kriged`, `mae_carried` (after the flights; the modality's unit),
    /// `rmse_kriged_before`, `rmse_carried_before` (before them), `mean_sd` (the
    /// model's standard deviation, the modality's unit), `coverage90` (fraction of the
    /// estimated sensors inside their 90% interval), `staleness_mean_days`,
    /// `staleness_max_days` (d), `energy_kj` (kJ per mission), `utilisation` (energy /
    /// budget), `cells`, `classifier_accuracy` (fraction), `lost_readings`.
    pub metrics: BTreeMap<String, IntervalDoc>,
    /// Events caught.
    pub events_caught: usize,
    /// Events available during the campaign (pooled over runs).
    pub events: usize,
    /// Delay from an event's first available reading to its catch, days (caught events).
    pub delay_days: IntervalDoc,
    /// Kriging RMSE minus the reference strategy's, paired by mission (the modality's unit);
    /// `null` for the reference itself.
    pub rmse_vs_reference: Option<IntervalDoc>,
    /// Catch delay minus the reference strategy's over the events both caught, days;
    /// `null` for the reference itself.
    pub delay_vs_reference: Option<IntervalDoc>,
}

/// What a campaign found (`POST /api/v1/simulate`: the served project's own record
/// replayed, as `gleaner simulate --project`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct CampaignDoc {
    /// Always [`crate::CAMPAIGN_FORMAT`].
    pub format: String,
    /// Always [`crate::VERSION`] when written by this build.
    pub version: u32,
    /// The dataset's (project's) name.
    pub label: String,
    /// The evaluated modality (e.g. `vw@30cm`).
    pub modality: String,
    /// The readings' logging period, s.
    pub period_s: i64,
    /// End of the history every run starts with, RFC 3339 UTC.
    pub history_until: String,
    /// Missions per run.
    pub missions: usize,
    /// First mission, RFC 3339 UTC (`null` without missions).
    pub first_mission: Option<String>,
    /// Last mission, RFC 3339 UTC.
    pub last_mission: Option<String>,
    /// Anomaly events that became available during the campaign (the real-data rule).
    pub events: usize,
    /// The strategy the differences are taken against.
    pub reference: String,
    /// Per strategy and budget, in the request's order.
    pub strategies: Vec<StrategySummaryDoc>,
    /// How each strategy's sorties flew in the simulated weather (wind, gusts, weak
    /// batteries), in order of first appearance; left out in still air.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub flights: Vec<FlightSummaryDoc>,
}

/// One strategy's flights in a campaign's weather: every run and mission.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct FlightSummaryDoc {
    /// The strategy.
    pub strategy: String,
    /// Missions with a flight record.
    pub missions: usize,
    /// Mean forecast wind speed, m/s.
    pub mean_forecast_mps: f64,
    /// Missions of which a sortie re-planned in the air (or turned home early).
    pub replanned: usize,
    /// Planned stops the re-plans dropped.
    pub cells_dropped: usize,
    /// Readings brought back.
    pub readings: u64,
    /// Readings brought back on missions whose forecast was under 6 m/s.
    pub readings_calm_days: u64,
    /// Missions whose forecast was under 6 m/s.
    pub calm_days: usize,
    /// Missions of which a sortie flew more energy than its battery gives above the
    /// reserve (0 when the margins hold).
    pub over_budget: usize,
    /// The largest flown energy less the usable energy over every sortie, J (< 0: energy to
    /// spare); `null` without a sortie.
    pub max_excess_j: Option<f64>,
}
