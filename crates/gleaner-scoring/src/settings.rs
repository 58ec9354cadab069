//! The project file `gleaner.toml`: the serialisable counterpart of the core configuration
//! types, converted explicitly. Only this module knows the TOML layout. Every default is taken
//! from the core's own defaults, so the two cannot drift.

use std::path::{Path, PathBuf};

use gleaner_field::{FieldConfig, LatLon};
use serde::{Deserialize, Serialize};

use crate::error::{AppError, Result};

macro_rules! bail {
    ($($arg:tt)*) => {
        return Err(AppError::Invalid(format!($($arg)*)))
    };
}

/// File name of the project configuration inside a project directory.
pub const CONFIG_FILE: &str = "gleaner.toml";

/// `gleaner.toml`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Settings {
    /// `[project]`
    pub project: ProjectSection,
    /// `[field]`
    pub field: FieldSection,
    /// `[sensors]`
    pub sensors: SensorsSection,
    /// `[ingest]`
    #[serde(default)]
    pub ingest: IngestSection,
    /// `[utility]`
    #[serde(default)]
    pub utility: UtilitySection,
    /// `[energy]`
    #[serde(default)]
    pub energy: EnergySection,
    /// `[planner]`
    #[serde(default)]
    pub planner: PlannerSection,
    /// `[flight]`: the wind forecast plans are made for (left out of the file when still
    /// air, the default).
    #[serde(default, skip_serializing_if = "FlightSection::is_default")]
    pub flight: FlightSection,
}

/// `[flight]`: the weather a mission is planned for (docs/method.md §3, wind).
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct FlightSection {
    /// Forecast wind speed at the flight altitude, m/s (0: plan in still air, as without
    /// wind; `plan --wind SPEED@FROM` overrides it).
    pub wind_mps: f64,
    /// Direction the forecast wind blows from, degrees clockwise from north
    /// (meteorological: 270 is a west wind).
    pub wind_from_deg: f64,
    /// Added to a forecast wind speed > 0 before pricing the legs, m/s: a plan is feasible
    /// at the forecast plus this margin (default 2 m/s, the usual error of a short-range
    /// wind forecast). Not applied to still air (`wind_mps = 0`).
    pub wind_margin_mps: f64,
}

/// Default `[flight] wind_margin_mps`, m/s.
pub const DEFAULT_WIND_MARGIN_MPS: f64 = 2.0;

impl Default for FlightSection {
    fn default() -> Self {
        Self {
            wind_mps: 0.0,
            wind_from_deg: 0.0,
            wind_margin_mps: DEFAULT_WIND_MARGIN_MPS,
        }
    }
}

impl FlightSection {
    /// True for the defaults (still air).
    pub fn is_default(&self) -> bool {
        *self == Self::default()
    }
}

/// `[project]`: name and database.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ProjectSection {
    /// A display name.
    pub name: String,
    /// SQLite database file, relative to the project directory.
    pub database: PathBuf,
}

/// `[field]`: base station and grid.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FieldSection {
    /// Base station latitude, WGS84 degrees.
    pub base_lat: f64,
    /// Base station longitude, WGS84 degrees.
    pub base_lon: f64,
    /// Base station altitude, metres.
    #[serde(default)]
    pub base_alt_m: f64,
    /// Cell side, metres (the UAV's ground coverage).
    pub cell_size_m: f64,
    /// Neighbour fallback: k nearest non-empty cells for a cell with no 8-neighbour.
    #[serde(default = "default_k")]
    pub neighbour_k: usize,
    /// Neighbour fallback radius, metres.
    #[serde(default = "default_radius")]
    pub neighbour_radius_m: f64,
    /// GeoJSON file (relative to the project directory, or absolute) of the polygons the
    /// flight stays inside (`[lon, lat]` WGS84; a Polygon, MultiPolygon, or Features of
    /// them); none = no geofence.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub geofence: Option<String>,
    /// GeoJSON file (relative to the project directory, or absolute) of the no-fly zones:
    /// polygons (buildings, tree rows, neighbours), lines (power lines) or points, `[lon,
    /// lat]` WGS84; none = no zone.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub no_fly: Option<String>,
    /// Safety buffer, m: every no-fly zone grown by it and the geofence shrunk by it
    /// [default 5 m].
    #[serde(default = "default_no_fly_buffer")]
    pub no_fly_buffer_m: f64,
}

/// The default `[field] no_fly_buffer_m`, m.
pub const DEFAULT_NO_FLY_BUFFER_M: f64 = 5.0;

fn default_no_fly_buffer() -> f64 {
    DEFAULT_NO_FLY_BUFFER_M
}

fn default_k() -> usize {
    FieldConfig::default().fallback_k
}
fn default_radius() -> f64 {
    FieldConfig::default().fallback_radius_m
}

/// `[sensors]`: where the sensor table came from.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SensorsSection {
    /// The sensors file given to `init`, relative to the project directory (or absolute when
    /// it is on another volume).
    pub file: String,
    /// Its UTM zone when positions were read as easting/northing (e.g. `11N`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub utm_zone: Option<String>,
}

/// `[ingest]`: how pending data volume is estimated.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct IngestSection {
    /// Bytes one reading of one modality takes in a sensor's log (default 16).
    pub bytes_per_reading: f64,
    /// Logging interval, seconds, assumed when a series has fewer than 2 readings (default 86 400).
    pub default_interval_s: f64,
    /// Plausible value ranges overriding the built-in ones, `[min, max]` in the readings' unit,
    /// keyed by quantity (`vw`) or unit (`degC`): e.g. `value_limits = { degC = [-80, 90] }`.
    /// Built in: m3/m3 0..1, % 0..100, degC −60..80, K 213.15..353.15, kPa −1e6..1e4,
    /// mS/cm and dS/m 0..1000, anything else ±1e9.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub value_limits: Option<std::collections::BTreeMap<String, [f64; 2]>>,
}

impl IngestSection {
    /// The readers' value limits: the built-in ranges with this section's overrides.
    pub fn value_limits(&self) -> gleaner_ingest::limits::ValueLimits {
        gleaner_ingest::limits::ValueLimits {
            overrides: self
                .value_limits
                .iter()
                .flatten()
                .map(|(k, [lo, hi])| (k.clone(), (*lo, *hi)))
                .collect(),
        }
    }
}

impl Default for IngestSection {
    fn default() -> Self {
        Self {
            bytes_per_reading: 16.0,
            default_interval_s: 86_400.0,
            value_limits: None,
        }
    }
}

/// `[utility]`: the score S, additive (alpha·F + beta·A + gamma·U − delta·R) or gated
/// (alpha·F·max(0, 1 + beta·A + gamma·U − delta·R)) by `score_form` (docs/method.md §2).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct UtilitySection {
    /// Weight of freshness F (default 1).
    pub alpha: f64,
    /// Weight of anomaly A (default 1).
    pub beta: f64,
    /// Weight of model uncertainty U (default 1).
    pub gamma: f64,
    /// Weight of redundancy R (default 1).
    pub delta: f64,
    /// Freshness half-life, seconds (default 259 200 = 3 days); lambda = ln 2 / half-life.
    pub freshness_half_life_s: f64,
    /// History window for R and A, days (default: all history).
    pub history_window_days: Option<f64>,
    /// Fewest common timestamps for a correlation to count (default 10).
    pub min_overlap: usize,
    /// Added to sigma in A, in the modality's unit (default 1e-6).
    pub epsilon: f64,
    /// `raw` (default, the paper's) or `bounded` (1 − exp(−A/kappa)).
    pub anomaly_form: String,
    /// kappa of the bounded anomaly, standard deviations (default 3).
    pub anomaly_kappa: f64,
    /// A collection with A^m at or above this is flagged in the anomaly history (default 3).
    pub anomaly_flag: f64,
    /// What A compares the latest value with: `own` (default, the paper's: the cell's own
    /// history) or `neighbours` (the cell's residual against the median of its neighbour
    /// cells, standardised by that residual's own history; see docs/synth-calibration.md).
    pub anomaly_reference: String,
    /// `neighbours` only: fewest neighbour cells with a value at a timestamp for the residual
    /// to exist (default 2).
    pub anomaly_min_neighbours: usize,
    /// omega: redundancy weight per modality name (default equal; missing names weigh 0).
    pub redundancy_weights: Option<std::collections::BTreeMap<String, f64>>,
    /// phi: anomaly weight per modality name (default equal; missing names weigh 0).
    pub anomaly_weights: Option<std::collections::BTreeMap<String, f64>>,
    /// Modality the condition classes come from (default `vw@30cm`, else the first `vw@...`).
    pub condition_modality: Option<String>,
    /// Number of condition classes K (default 3: dry / adequate / wet).
    pub condition_classes: usize,
    /// K − 1 class thresholds in the modality's unit (default: quantiles of the history).
    pub condition_thresholds: Option<Vec<f64>>,
    /// Refit cadence of the condition model kept in the persisted utility state (what
    /// `record` and `score` keep current): a write refits it only when the class modality's
    /// readings added since the last fit exceed this fraction of the readings it was trained
    /// on; until then scoring predicts with the last fit (default 0.05; 0 = refit at every
    /// write, the exact model of the whole history). With a cadence, a fit also uses the label
    /// at the newest reading when scoring at exactly that time (the exact mode and the full
    /// path leave it out there). Scoring from the whole history (`--history-until`, windows)
    /// always fits afresh.
    pub condition_refit_growth: f64,
    /// How the terms combine: `additive` (the paper's S = αF + βA + γU − δR) or `gated`
    /// (S = αF·max(0, 1 + βA + γU − δR): staleness times the cell's value; see
    /// docs/method-improvement.md).
    pub score_form: String,
    /// η: weight of gleaner's variance-reduction term V in [0, 1] (each cell's expected
    /// reduction of the field's posterior variance, divided by the largest; see
    /// docs/method-improvement.md): the planner routes by S + η·V. 0 = the paper's S alone.
    pub variance_weight: f64,
    /// What F measures: `half-life` (the paper's: 1 − 2^(−age/half-life), the same for every
    /// cell) or `drift` (gleaner's: the expected error of the cell's carried-forward values,
    /// the staleness index a·D(a) − ∫₀ᵃ D of each sensor's own mean squared change D of the
    /// condition modality, less the field's mean at each time (the field-wide change is what
    /// the reconstruction recovers from neighbours), over the last `drift_window_days` of
    /// collected readings, shrunk
    /// halfway to the field's median, summed over the cell's sensors and divided by the
    /// largest cell's: in [0, 1]; see docs/method-improvement.md).
    pub freshness_form: String,
    /// `drift` only: days of collected readings each sensor's drift is estimated on
    /// (default 365).
    pub drift_window_days: f64,
    /// `drift` only: how far each sensor's mean squared change is shrunk to the field's
    /// median, in [0, 1]: lag by lag `own^(1 − w) · median^w` (default 0.5, the geometric
    /// mean; 0 = each sensor's own, 1 = the field's median for every sensor, so F depends on
    /// age alone).
    pub drift_shrink: f64,
    /// `drift` only: exponent κ ≥ 0 on how unusual the sensors' own changes were over the
    /// days a sensor has not been read since its last reading: each sensor's index is
    /// multiplied by (mean over those days of the median squared own one-step change of the
    /// sensors known that day, relative to its usual value)^κ; days nobody has reported yet
    /// count as usual. A rain day seen at a few visited cells makes every cell not read since
    /// worth more (default 0.5; 0 = off, F from age and drift alone; see
    /// docs/method-improvement.md).
    pub drift_spread: f64,
    /// `drift` only: sum each cell's drift index over every depth of the condition
    /// modality's quantity (e.g. `vw@30cm` … `vw@150cm`: the expected squared error of the
    /// cell's carried values summed over its depths, in one unit) instead of the condition
    /// modality alone (default false).
    #[serde(default)]
    pub drift_all_depths: bool,
}

/// gleaner's own freshness half-life, seconds (14 days): F grows about linearly with age
/// over the days between visits instead of saturating (docs/method-improvement.md).
pub const GLEANER_HALF_LIFE_S: f64 = 14.0 * 86_400.0;

/// gleaner's anomaly weight β (4): a cell whose bounded anomaly is near 1 is worth up to 5× its
/// freshness. Chosen among 1, 4 and 10 on synthetic farms of seeds 11–20 (RMSE 9.84, 9.59,
/// 9.64 ×10⁻³ m³/m³), then checked on the report's seeds 1–10 (11.29 → 10.65), CAF 2014 over
/// five planner seeds (5.62 → 5.67, level) and Hubbard Brook (7.77 → 7.52)
/// (docs/method-improvement.md).
pub const GLEANER_BETA: f64 = 4.0;

impl Default for UtilitySection {
    /// The core's defaults ([`gleaner_utility::UtilityConfig::default`],
    /// [`gleaner_utility::ConditionConfig::default`]): the paper's score.
    /// [`UtilitySection::gleaner`] gives gleaner's method.
    fn default() -> Self {
        use gleaner_utility::{AnomalyForm, ConditionConfig, HistoryWindow, UtilityConfig};
        let core = UtilityConfig::default();
        let condition = ConditionConfig::default();
        let (anomaly_form, anomaly_kappa) = match core.anomaly_form {
            AnomalyForm::Raw => ("raw".to_string(), 3.0),
            AnomalyForm::Bounded { kappa } => ("bounded".to_string(), kappa),
        };
        Self {
            alpha: core.alpha,
            beta: core.beta,
            gamma: core.gamma,
            delta: core.delta,
            freshness_half_life_s: core.freshness_half_life_s,
            history_window_days: match core.window {
                HistoryWindow::All => None,
                HistoryWindow::Last { seconds } => Some(seconds as f64 / 86_400.0),
            },
            min_overlap: core.min_overlap,
            epsilon: core.epsilon,
            anomaly_form,
            anomaly_kappa,
            anomaly_flag: 3.0,
            anomaly_reference: "own".to_string(),
            anomaly_min_neighbours: 2,
            redundancy_weights: None,
            anomaly_weights: None,
            condition_modality: None,
            condition_classes: condition.n_classes,
            condition_thresholds: None,
            condition_refit_growth: DEFAULT_CONDITION_REFIT_GROWTH,
            score_form: "additive".into(),
            variance_weight: 0.0,
            freshness_form: "half-life".into(),
            drift_window_days: DEFAULT_DRIFT_WINDOW_DAYS,
            drift_shrink: DEFAULT_DRIFT_SHRINK,
            drift_spread: DEFAULT_DRIFT_SPREAD,
            drift_all_depths: false,
        }
    }
}

/// Default of [`UtilitySection::drift_window_days`], days.
pub const DEFAULT_DRIFT_WINDOW_DAYS: f64 = 365.0;

/// Default of [`UtilitySection::drift_shrink`]: the geometric mean of a sensor's own mean
/// squared change and the field's median.
pub const DEFAULT_DRIFT_SHRINK: f64 = 0.5;

/// Default of [`UtilitySection::drift_spread`]: the square root of how unusual the days a
/// sensor has not reported were. Chosen on CAF 2014 among 0.25, 0.5 and 1 (one planner seed:
/// kriging RMSE 5.64, 5.45, 5.72 ×10⁻³ m³/m³; 5.60 without), checked over five seeds and on
/// the held-out 2015 (docs/method-improvement.md).
pub const DEFAULT_DRIFT_SPREAD: f64 = 0.5;

/// Default of [`UtilitySection::condition_refit_growth`]: refit the persisted condition model
/// once the class modality has grown by 5% since the last fit.
pub const DEFAULT_CONDITION_REFIT_GROWTH: f64 = 0.05;

/// A battery and airframe preset (`[energy] preset`, `plan --energy-preset`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EnergyPreset {
    /// The paper's: 70 kJ, 5% reserve (66.5 kJ usable).
    Paper,
    /// A large pack: 77 Wh, 20% reserve (sites kilometres apart).
    LargePack,
}

impl EnergyPreset {
    /// Every preset, in the order they are listed.
    pub const ALL: [Self; 2] = [Self::Paper, Self::LargePack];

    /// Its name in `gleaner.toml` and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Self::Paper => "paper",
            Self::LargePack => "large-pack",
        }
    }

    /// The core energy configuration of the preset.
    pub fn config(self) -> gleaner_energy::EnergyConfig {
        match self {
            Self::Paper => gleaner_energy::EnergyConfig::paper(),
            Self::LargePack => gleaner_energy::EnergyConfig::large_pack(),
        }
    }
}

impl std::str::FromStr for EnergyPreset {
    type Err = AppError;

    fn from_str(s: &str) -> Result<Self> {
        Self::ALL
            .into_iter()
            .find(|p| p.name() == s)
            .ok_or_else(|| {
                AppError::Invalid(format!(
                    "energy preset {:?}: expected paper or large-pack",
                    gleaner_ingest::shorten(s)
                ))
            })
    }
}

/// `[energy]`: the UAV energy model (docs/method.md §3). Every field left out takes the preset's value.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct EnergySection {
    /// `paper` (70 kJ, 5% reserve: 66.5 kJ usable) or `large-pack` (77 Wh, 20% reserve).
    pub preset: String,
    /// Cruise speed: `max-endurance` (default), `max-range`, or a number in m/s.
    pub cruise: String,
    /// Battery capacity, J.
    pub battery_j: Option<f64>,
    /// Reserve fraction of the battery never planned (0..1).
    pub reserve_fraction: Option<f64>,
    /// Flight altitude, m.
    pub altitude_m: Option<f64>,
    /// Fixed hover overhead per cell, s.
    pub overhead_s: Option<f64>,
    /// Minimum hover per cell, s.
    pub min_hover_s: Option<f64>,
    /// Receiver/processing power during collection, W.
    pub rx_power_w: Option<f64>,
    /// OFDMA bandwidth shared by a cell's sensors, Hz.
    pub bandwidth_hz: Option<f64>,
    /// Sensor transmit power, dBm.
    pub tx_power_dbm: Option<f64>,
    /// Receiver noise power, dBm.
    pub noise_power_dbm: Option<f64>,
    /// Sensor logging interval, s.
    pub reading_interval_s: Option<f64>,
    /// Bytes per logged reading.
    pub bytes_per_reading: Option<f64>,
    /// Plain linear model instead of the physical one: energy per metre flown, J/m (give
    /// `linear_j_per_cell` with it).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub linear_j_per_m: Option<f64>,
    /// Plain linear model: energy per cell visited, J.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub linear_j_per_cell: Option<f64>,
}

impl Default for EnergySection {
    fn default() -> Self {
        Self {
            preset: "paper".into(),
            cruise: "max-endurance".into(),
            battery_j: None,
            reserve_fraction: None,
            altitude_m: None,
            overhead_s: None,
            min_hover_s: None,
            rx_power_w: None,
            bandwidth_hz: None,
            tx_power_dbm: None,
            noise_power_dbm: None,
            reading_interval_s: None,
            bytes_per_reading: None,
            linear_j_per_m: None,
            linear_j_per_cell: None,
        }
    }
}

/// Whether a weight is exactly 0 (left out of a written `gleaner.toml`).
fn is_zero(w: &f64) -> bool {
    *w == 0.0
}

/// `[planner]`: route planner defaults.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct PlannerSection {
    /// `default`, `greedy` or `exact`.
    pub solver: String,
    /// Time limit, seconds.
    pub time_limit_s: f64,
    /// Seed.
    pub seed: u64,
    /// What a route maximises: `score` (the sum of the visited cells' S) or `information`
    /// (the expected reduction of the dynamic field model's posterior variance over the whole
    /// field, docs/method.md §7).
    pub objective: crate::choices::Objective,
    /// Weight of the dynamic field model's unshared per-sensor component: each sensor's own
    /// random-walk drift since its last reading, its rate (unit²/s) fitted on the history
    /// (half the variance per second of the one-step change of the sensor's deviation from
    /// the field mean, shrunk towards the pooled rate) and multiplied by this weight. 0 (the
    /// default): no such component. It widens the posterior variance of sensors unread for
    /// long, so the information objective and the dynamic estimator's intervals count it.
    #[serde(skip_serializing_if = "is_zero")]
    pub unshared_weight: f64,
    /// The hybrid objective's weight on information, in [0, 1]: a route is worth
    /// `(1 − w)·ΣS/ΣS_all + w·I`, its cells' share of the field's total S plus the share of
    /// the field's posterior variance its readings remove [default 0.5].
    #[serde(skip_serializing_if = "is_default_information_weight")]
    pub information_weight: f64,
}

/// The hybrid objective's default weight on information.
pub const DEFAULT_INFORMATION_WEIGHT: f64 = 0.5;

fn is_default_information_weight(w: &f64) -> bool {
    *w == DEFAULT_INFORMATION_WEIGHT
}

impl Default for PlannerSection {
    /// The core's defaults ([`gleaner_mission::PlanOptions::default`]).
    fn default() -> Self {
        let core = gleaner_mission::PlanOptions::default();
        Self {
            solver: core.planner.name().into(),
            time_limit_s: core.time_limit.as_secs_f64(),
            seed: core.seed,
            objective: crate::choices::Objective::default(),
            unshared_weight: 0.0,
            information_weight: DEFAULT_INFORMATION_WEIGHT,
        }
    }
}

impl UtilitySection {
    /// gleaner's method (docs/method-improvement.md): this section with the gated score
    /// form (S = αF·max(0, 1 + βA + γU − δR)), the drift freshness (`freshness_form =
    /// "drift"`), γ = δ = 0 (on CAF, 2014 and 2015, the gated score was more accurate
    /// without U and without R), the bounded anomaly (1 − exp(−A/kappa)) weighted by
    /// β = [`GLEANER_BETA`]; α, kappa, the anomaly's reference, the variance weight and
    /// everything else are kept. The `gleaner` strategy of campaigns uses it.
    pub fn gleaner(&self) -> Self {
        Self {
            freshness_form: "drift".into(),
            beta: GLEANER_BETA,
            gamma: 0.0,
            delta: 0.0,
            ..self.gated()
        }
    }

    /// gleaner's earlier method (the `gated` strategy of campaigns): the gated score form, a
    /// 14-day freshness half-life ([`GLEANER_HALF_LIFE_S`]) and the bounded anomaly; the
    /// weights and everything else are kept.
    pub fn gated(&self) -> Self {
        Self {
            freshness_half_life_s: GLEANER_HALF_LIFE_S,
            anomaly_form: "bounded".into(),
            score_form: "gated".into(),
            freshness_form: "half-life".into(),
            ..self.clone()
        }
    }

    /// The paper's score (docs/method.md §2 exactly): this section with the weights, the freshness
    /// half-life and the anomaly's form and reference at the paper's values (the core
    /// defaults: alpha = beta = gamma = delta = 1, 3 days, raw, own history) and no variance
    /// term; the history window, `min_overlap`, epsilon, modality weights and the condition
    /// model's settings are kept.
    pub fn paper(&self) -> Self {
        let core = gleaner_utility::UtilityConfig::default();
        let paper = Self::default();
        Self {
            alpha: core.alpha,
            beta: core.beta,
            gamma: core.gamma,
            delta: core.delta,
            freshness_half_life_s: core.freshness_half_life_s,
            anomaly_form: "raw".into(),
            anomaly_kappa: paper.anomaly_kappa,
            anomaly_reference: "own".into(),
            score_form: "additive".into(),
            variance_weight: 0.0,
            freshness_form: "half-life".into(),
            ..self.clone()
        }
    }

    /// The core configuration, with modality weights laid out in `modalities` order.
    pub fn to_core(&self, modalities: &[String]) -> Result<gleaner_utility::UtilityConfig> {
        use gleaner_utility::{
            AnomalyForm, AnomalyReference, HistoryWindow, ModalityWeights, ScoreForm, UtilityConfig,
        };
        let weights = |w: &Option<std::collections::BTreeMap<String, f64>>| match w {
            None => ModalityWeights::Equal,
            Some(map) => ModalityWeights::Given(
                modalities
                    .iter()
                    .map(|m| map.get(m).copied().unwrap_or(0.0))
                    .collect(),
            ),
        };
        let config = UtilityConfig {
            alpha: self.alpha,
            beta: self.beta,
            gamma: self.gamma,
            delta: self.delta,
            freshness_half_life_s: self.freshness_half_life_s,
            window: match self.history_window_days {
                None => HistoryWindow::All,
                Some(d) => HistoryWindow::Last {
                    seconds: (d * 86_400.0).round() as i64,
                },
            },
            min_overlap: self.min_overlap,
            epsilon: self.epsilon,
            redundancy_weights: weights(&self.redundancy_weights),
            anomaly_weights: weights(&self.anomaly_weights),
            anomaly_form: match self.anomaly_form.as_str() {
                "raw" => AnomalyForm::Raw,
                "bounded" => AnomalyForm::Bounded {
                    kappa: self.anomaly_kappa,
                },
                other => bail!("utility.anomaly_form = {other:?}: expected \"raw\" or \"bounded\""),
            },
            anomaly_reference: match self.anomaly_reference.as_str() {
                "own" => AnomalyReference::OwnHistory,
                "neighbours" => AnomalyReference::Neighbours {
                    min_neighbours: self.anomaly_min_neighbours,
                },
                other => bail!(
                    "utility.anomaly_reference = {other:?}: expected \"own\" or \"neighbours\""
                ),
            },
            score_form: match self.score_form.as_str() {
                "additive" => ScoreForm::Additive,
                "gated" => ScoreForm::Gated,
                other => {
                    bail!("utility.score_form = {other:?}: expected \"additive\" or \"gated\"")
                }
            },
        };
        config
            .validate(modalities.len())
            .map_err(|e| AppError::core("[utility] settings", e))?;
        Ok(config)
    }
}

impl EnergySection {
    /// The core energy configuration: the preset with every given field overridden.
    pub fn to_core(&self) -> Result<gleaner_energy::EnergyConfig> {
        use gleaner_energy::CruiseSpeed;
        let mut c = match self.preset.parse::<EnergyPreset>() {
            Ok(preset) => preset.config(),
            Err(_) => bail!(
                "energy.preset = {:?}: expected \"paper\" or \"large-pack\"",
                self.preset
            ),
        };
        c.cruise = match self.cruise.as_str() {
            "max-endurance" => CruiseSpeed::MaxEndurance,
            "max-range" => CruiseSpeed::MaxRange,
            v => CruiseSpeed::Fixed(
                v.parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite() && *x > 0.0)
                    .ok_or_else(|| {
                        AppError::Invalid(format!(
                            "energy.cruise = {v:?}: expected max-endurance, max-range or a positive speed in m/s"
                        ))
                    })?,
            ),
        };
        let set = |field: &mut f64, v: Option<f64>| {
            if let Some(v) = v {
                *field = v;
            }
        };
        set(&mut c.battery.capacity_j, self.battery_j);
        set(&mut c.battery.reserve_fraction, self.reserve_fraction);
        set(&mut c.link.altitude_m, self.altitude_m);
        set(&mut c.hover.overhead_s, self.overhead_s);
        set(&mut c.hover.min_hover_s, self.min_hover_s);
        set(&mut c.rx_power_w, self.rx_power_w);
        set(&mut c.link.bandwidth_hz, self.bandwidth_hz);
        set(&mut c.link.tx_power_dbm, self.tx_power_dbm);
        set(&mut c.link.noise_power_dbm, self.noise_power_dbm);
        set(&mut c.logging.reading_interval_s, self.reading_interval_s);
        set(&mut c.logging.bytes_per_reading, self.bytes_per_reading);
        c.linear = match (self.linear_j_per_m, self.linear_j_per_cell) {
            (None, None) => None,
            (Some(j_per_m), Some(j_per_cell)) => Some(gleaner_energy::LinearEnergy {
                j_per_m,
                j_per_cell,
            }),
            _ => bail!(
                "energy.linear_j_per_m and energy.linear_j_per_cell go together: give both or neither"
            ),
        };
        Ok(c)
    }
}

impl Settings {
    /// Reads and validates `dir/gleaner.toml`.
    pub fn load(dir: &Path) -> Result<Self> {
        let path = dir.join(CONFIG_FILE);
        let bytes = std::fs::read(&path).map_err(|e| AppError::Settings {
            path: path.display().to_string(),
            reason: format!(
                "cannot read the project file ({e}); run `gleaner init` first, or pass --project"
            ),
        })?;
        let text = String::from_utf8(bytes).map_err(|e| {
            let bytes = e.as_bytes();
            let valid = e.utf8_error().valid_up_to();
            let line = bytes[..valid].iter().filter(|&&b| b == b'\n').count() + 1;
            AppError::Settings {
                path: format!("{}:{line}", path.display()),
                reason: "not valid UTF-8".into(),
            }
        })?;
        Self::parse(&text).map_err(|reason| AppError::Settings {
            path: path.display().to_string(),
            reason: shorten_lines(&reason),
        })
    }

    /// Parses and validates the text of a project file; the error names the setting.
    pub fn parse(text: &str) -> std::result::Result<Self, String> {
        let file: Self = toml::from_str(text).map_err(|e| format!("invalid project file: {e}"))?;
        file.validate().map_err(|e| e.to_string())?;
        Ok(file)
    }

    /// The text of the project file.
    pub fn to_toml(&self) -> Result<String> {
        let body = toml::to_string_pretty(self)
            .map_err(|e| AppError::Invalid(format!("cannot write the settings: {e}")))?;
        Ok(format!(
            "# gleaner project file. Units: degrees (WGS84), metres, seconds, bytes.\n{body}"
        ))
    }

    /// Writes `dir/gleaner.toml`.
    pub fn save(&self, dir: &Path) -> Result<()> {
        let path = dir.join(CONFIG_FILE);
        std::fs::write(&path, self.to_toml()?).map_err(|e| AppError::io(&path, e))
    }

    /// Checks every setting a use case relies on; the error names the setting and value.
    pub fn validate(&self) -> Result<()> {
        self.base()?;
        self.check_ranges()?;
        if !self.field.base_alt_m.is_finite() {
            bail!(
                "field.base_alt_m = {} must be a finite number of metres",
                self.field.base_alt_m
            );
        }
        if !(self.field.cell_size_m.is_finite() && self.field.cell_size_m >= 0.5) {
            bail!(
                "field.cell_size_m = {} must be a number of metres >= 0.5",
                self.field.cell_size_m
            );
        }
        if !(self.field.neighbour_radius_m.is_finite() && self.field.neighbour_radius_m >= 0.0) {
            bail!(
                "field.neighbour_radius_m = {} must be a number of metres >= 0",
                gleaner_ingest::number(self.field.neighbour_radius_m)
            );
        }
        if self.field.neighbour_k > 64 {
            bail!(
                "field.neighbour_k = {} must be at most 64",
                self.field.neighbour_k
            );
        }
        if !(self.ingest.bytes_per_reading.is_finite()
            && self.ingest.bytes_per_reading > 0.0
            && self.ingest.default_interval_s.is_finite()
            && self.ingest.default_interval_s > 0.0)
        {
            bail!(
                "ingest.bytes_per_reading and ingest.default_interval_s must be positive numbers"
            );
        }
        if !(2..=20).contains(&self.utility.condition_classes) {
            bail!(
                "utility.condition_classes = {} must be between 2 and 20",
                self.utility.condition_classes
            );
        }
        if !(self.planner.time_limit_s.is_finite()
            && (0.0..=86_400.0).contains(&self.planner.time_limit_s))
        {
            bail!(
                "planner.time_limit_s = {} must be between 0 and 86400 seconds",
                self.planner.time_limit_s
            );
        }
        crate::choices::parse_planner(&self.planner.solver)?;
        self.utility.to_core(&[])?;
        let energy = self.energy.to_core()?;
        gleaner_energy::MissionEnergyModel::new(&energy)
            .map_err(|e| AppError::core("[energy] settings", e))?;
        let alt = energy.link.altitude_m;
        if !(alt.is_finite() && alt > 0.0 && alt <= 120.0) {
            bail!("energy.altitude_m = {alt} must be in (0, 120] metres");
        }
        Ok(())
    }

    /// Every numeric setting against its allowed range (see [`RANGES`]); the error names the
    /// key, the value and the range.
    fn check_ranges(&self) -> Result<()> {
        let f = &self.field;
        let i = &self.ingest;
        let u = &self.utility;
        let e = &self.energy;
        let p = &self.planner;
        let fl = &self.flight;
        let values: [(&str, Option<f64>); 43] = [
            ("flight.wind_mps", Some(fl.wind_mps)),
            ("flight.wind_from_deg", Some(fl.wind_from_deg)),
            ("flight.wind_margin_mps", Some(fl.wind_margin_mps)),
            ("field.base_alt_m", Some(f.base_alt_m)),
            ("field.no_fly_buffer_m", Some(f.no_fly_buffer_m)),
            ("field.cell_size_m", Some(f.cell_size_m)),
            ("field.neighbour_k", Some(f.neighbour_k as f64)),
            ("field.neighbour_radius_m", Some(f.neighbour_radius_m)),
            ("ingest.bytes_per_reading", Some(i.bytes_per_reading)),
            ("ingest.default_interval_s", Some(i.default_interval_s)),
            ("utility.alpha", Some(u.alpha)),
            ("utility.beta", Some(u.beta)),
            ("utility.gamma", Some(u.gamma)),
            ("utility.delta", Some(u.delta)),
            (
                "utility.freshness_half_life_s",
                Some(u.freshness_half_life_s),
            ),
            ("utility.history_window_days", u.history_window_days),
            ("utility.min_overlap", Some(u.min_overlap as f64)),
            ("utility.epsilon", Some(u.epsilon)),
            ("utility.anomaly_kappa", Some(u.anomaly_kappa)),
            ("utility.anomaly_flag", Some(u.anomaly_flag)),
            (
                "utility.anomaly_min_neighbours",
                Some(u.anomaly_min_neighbours as f64),
            ),
            (
                "utility.condition_classes",
                Some(u.condition_classes as f64),
            ),
            (
                "utility.condition_refit_growth",
                Some(u.condition_refit_growth),
            ),
            ("utility.variance_weight", Some(u.variance_weight)),
            ("utility.drift_window_days", Some(u.drift_window_days)),
            ("utility.drift_shrink", Some(u.drift_shrink)),
            ("utility.drift_spread", Some(u.drift_spread)),
            ("energy.battery_j", e.battery_j),
            ("energy.reserve_fraction", e.reserve_fraction),
            ("energy.altitude_m", e.altitude_m),
            ("energy.overhead_s", e.overhead_s),
            ("energy.min_hover_s", e.min_hover_s),
            ("energy.rx_power_w", e.rx_power_w),
            ("energy.bandwidth_hz", e.bandwidth_hz),
            ("energy.tx_power_dbm", e.tx_power_dbm),
            ("energy.noise_power_dbm", e.noise_power_dbm),
            ("energy.reading_interval_s", e.reading_interval_s),
            ("energy.bytes_per_reading", e.bytes_per_reading),
            ("planner.time_limit_s", Some(p.time_limit_s)),
            ("planner.unshared_weight", Some(p.unshared_weight)),
            ("planner.information_weight", Some(p.information_weight)),
            (
                "energy.cruise",
                e.cruise
                    .parse::<f64>()
                    .ok()
                    .filter(|_| !matches!(e.cruise.as_str(), "max-endurance" | "max-range")),
            ),
            ("field.base_lat", Some(f.base_lat)),
        ];
        for (key, value) in values {
            if let Some(v) = value {
                check_range(key, v)?;
            }
        }
        if !matches!(u.freshness_form.as_str(), "half-life" | "drift") {
            bail!(
                "utility.freshness_form = {:?}: expected \"half-life\" or \"drift\"",
                u.freshness_form
            );
        }
        let max_radius = MAX_RADIUS_CELLS * f.cell_size_m;
        if f.neighbour_radius_m > max_radius {
            bail!(
                "field.neighbour_radius_m = {}: allowed 0..={MAX_RADIUS_CELLS} cell sides ({} m \
                 with cell_size_m = {}); set a smaller neighbour radius (init: --neighbour-radius)",
                gleaner_ingest::number(f.neighbour_radius_m),
                gleaner_ingest::number(max_radius),
                gleaner_ingest::number(f.cell_size_m)
            );
        }
        for (name, map) in [
            ("utility.redundancy_weights", &u.redundancy_weights),
            ("utility.anomaly_weights", &u.anomaly_weights),
        ] {
            for (m, &w) in map.iter().flatten() {
                if !(w.is_finite() && (0.0..=1e6).contains(&w)) {
                    bail!(
                        "{name}.{m} = {}: allowed 0..=1e6",
                        gleaner_ingest::number(w)
                    );
                }
            }
        }
        if let Some(t) = &u.condition_thresholds {
            if t.len() + 1 != u.condition_classes {
                bail!(
                    "utility.condition_thresholds: {} threshold(s) for condition_classes = {} (need {})",
                    t.len(),
                    u.condition_classes,
                    u.condition_classes.saturating_sub(1)
                );
            }
            if t.iter().any(|x| !x.is_finite() || x.abs() > 1e9)
                || t.windows(2).any(|w| w[0] >= w[1])
            {
                bail!(
                    "utility.condition_thresholds = [{}]: need finite numbers within ±1e9, strictly increasing",
                    t.iter()
                        .map(|x| gleaner_ingest::number(*x))
                        .collect::<Vec<_>>()
                        .join(", ")
                );
            }
        }
        self.ingest
            .value_limits()
            .validate()
            .map_err(|m| AppError::Invalid(format!("ingest.{m}")))?;
        Ok(())
    }

    /// The base station position.
    pub fn base(&self) -> Result<LatLon> {
        LatLon::new(self.field.base_lat, self.field.base_lon)
            .map_err(|e| AppError::Invalid(format!("field.base_lat / field.base_lon: {e}")))
    }

    /// The core grid configuration.
    pub fn field_config(&self) -> FieldConfig {
        FieldConfig {
            cell_size_m: self.field.cell_size_m,
            fallback_k: self.field.neighbour_k,
            fallback_radius_m: self.field.neighbour_radius_m,
        }
    }
}

/// Largest neighbour fallback radius, in cell sides (the neighbour search grows with its
/// square).
pub const MAX_RADIUS_CELLS: f64 = 100.0;

/// Unit of the anomaly settings in [`RANGES`].
const SD: &str = "standard deviations";
/// Unit of the wind direction in [`RANGES`].
const DEG_FROM_NORTH: &str = "degrees from north";

/// The allowed range of every numeric setting of `gleaner.toml`, inclusive unless marked, with
/// its unit: (key, min, max, min exclusive, unit). Values outside are refused with the key, the
/// value and the range; NaN and infinities are always refused.
pub const RANGES: &[(&str, f64, f64, bool, &str)] = &[
    ("field.base_lat", -90.0, 90.0, false, "degrees"),
    ("field.base_alt_m", -500.0, 9_000.0, false, "m"),
    ("field.cell_size_m", 0.5, 10_000.0, false, "m"),
    ("field.neighbour_k", 0.0, 64.0, false, "cells"),
    ("field.neighbour_radius_m", 0.0, 100_000.0, false, "m"),
    ("field.no_fly_buffer_m", 0.0, 1_000.0, false, "m"),
    ("ingest.bytes_per_reading", 0.0, 1e6, true, "bytes"),
    ("ingest.default_interval_s", 1.0, 31_622_400.0, false, "s"),
    ("utility.alpha", 0.0, 1e6, false, ""),
    ("utility.beta", 0.0, 1e6, false, ""),
    ("utility.gamma", 0.0, 1e6, false, ""),
    ("utility.delta", 0.0, 1e6, false, ""),
    ("utility.freshness_half_life_s", 1.0, 3.2e9, false, "s"),
    ("utility.history_window_days", 0.0, 36_525.0, true, "days"),
    ("utility.min_overlap", 2.0, 1e6, false, "timestamps"),
    ("utility.epsilon", 0.0, 1e6, true, "(unit of the modality)"),
    ("utility.anomaly_kappa", 0.0, 1e3, true, SD),
    ("utility.anomaly_flag", 0.0, 1e6, false, SD),
    ("utility.anomaly_min_neighbours", 1.0, 64.0, false, "cells"),
    ("utility.condition_classes", 2.0, 20.0, false, "classes"),
    ("utility.condition_refit_growth", 0.0, 10.0, false, ""),
    ("utility.variance_weight", 0.0, 1e6, false, ""),
    ("utility.drift_window_days", 1.0, 36_500.0, false, "days"),
    ("utility.drift_shrink", 0.0, 1.0, false, ""),
    ("utility.drift_spread", 0.0, 10.0, false, ""),
    ("energy.battery_j", 0.0, 1e9, true, "J"),
    ("energy.reserve_fraction", 0.0, 0.99, false, ""),
    ("energy.altitude_m", 0.0, 120.0, true, "m"),
    ("energy.overhead_s", 0.0, 3_600.0, false, "s"),
    ("energy.min_hover_s", 0.0, 3_600.0, false, "s"),
    ("energy.rx_power_w", 0.0, 1_000.0, false, "W"),
    ("energy.bandwidth_hz", 0.0, 1e10, true, "Hz"),
    ("energy.tx_power_dbm", -50.0, 60.0, false, "dBm"),
    ("energy.noise_power_dbm", -200.0, 0.0, false, "dBm"),
    ("energy.reading_interval_s", 1.0, 31_622_400.0, false, "s"),
    ("energy.bytes_per_reading", 0.0, 1e6, true, "bytes"),
    ("energy.cruise", 0.0, 50.0, true, "m/s"),
    ("planner.time_limit_s", 0.0, 86_400.0, false, "s"),
    ("planner.unshared_weight", 0.0, 100.0, false, ""),
    ("planner.information_weight", 0.0, 1.0, false, ""),
    ("flight.wind_mps", 0.0, 40.0, false, "m/s"),
    ("flight.wind_from_deg", 0.0, 360.0, false, DEG_FROM_NORTH),
    ("flight.wind_margin_mps", 0.0, 20.0, false, "m/s"),
];

/// Checks `value` of setting `key` against [`RANGES`].
fn check_range(key: &str, value: f64) -> Result<()> {
    let Some(&(_, lo, hi, open, unit)) = RANGES.iter().find(|r| r.0 == key) else {
        return Ok(());
    };
    let inside = value.is_finite() && (if open { value > lo } else { value >= lo }) && value <= hi;
    if !inside {
        let (bracket, unit) = (
            if open { "(" } else { "[" },
            if unit.is_empty() {
                String::new()
            } else {
                format!(" {unit}")
            },
        );
        let value = gleaner_ingest::number(value);
        bail!("{key} = {value}: allowed {bracket}{lo}, {hi}]{unit}");
    }
    Ok(())
}

/// Longest line of a settings error, in characters.
const MESSAGE_LINE_CHARS: usize = 160;

/// Cuts every line of a message to [`MESSAGE_LINE_CHARS`] characters, noting the length (a
/// TOML error quotes the offending line, which may be megabytes long).
fn shorten_lines(text: &str) -> String {
    text.lines()
        .map(|l| match l.char_indices().nth(MESSAGE_LINE_CHARS) {
            None => l.to_string(),
            Some((end, _)) => format!("{}… ({} bytes in all)", &l[..end], l.len()),
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// Parses a UTM zone such as `11N` or `33s` into (zone, northern hemisphere).
pub fn parse_utm_zone(s: &str) -> Result<(u8, bool)> {
    let s = s.trim();
    let (digits, hemi) = s.split_at(s.len().saturating_sub(1));
    let north = match hemi {
        "N" | "n" => true,
        "S" | "s" => false,
        _ => bail!("invalid UTM zone {s:?}: expected e.g. `11N` or `33S`"),
    };
    let zone: u8 = digits
        .parse()
        .ok()
        .filter(|z| (1..=60).contains(z))
        .ok_or_else(|| AppError::Invalid(format!("invalid UTM zone {s:?}: zone must be 1..=60")))?;
    Ok((zone, north))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn utm_zones() {
        assert_eq!(parse_utm_zone("11N").unwrap(), (11, true));
        assert_eq!(parse_utm_zone("33s").unwrap(), (33, false));
        assert!(parse_utm_zone("61N").is_err());
        assert!(parse_utm_zone("11").is_err());
    }

    #[test]
    fn anomaly_reference_setting() {
        use gleaner_utility::AnomalyReference;
        let modalities = ["vw@30cm".to_string()];
        let default = UtilitySection::default();
        assert_eq!(default.anomaly_reference, "own");
        let core = default.to_core(&modalities).unwrap();
        assert_eq!(core.anomaly_reference, AnomalyReference::OwnHistory);
        assert_eq!(crate::condition::anomaly_label(&core), "raw");
        let section: UtilitySection =
            toml::from_str("anomaly_reference = \"neighbours\"\nanomaly_min_neighbours = 3\n")
                .unwrap();
        let core = section.to_core(&modalities).unwrap();
        assert_eq!(
            core.anomaly_reference,
            AnomalyReference::Neighbours { min_neighbours: 3 }
        );
        assert_eq!(
            crate::condition::anomaly_label(&core),
            "raw, neighbours(min=3)"
        );
        let bad = UtilitySection {
            anomaly_reference: "nearby".into(),
            ..UtilitySection::default()
        };
        let err = bad.to_core(&modalities).unwrap_err().to_string();
        assert!(err.contains("anomaly_reference"), "{err}");
        let zero = UtilitySection {
            anomaly_reference: "neighbours".into(),
            anomaly_min_neighbours: 0,
            ..UtilitySection::default()
        };
        assert!(zero.to_core(&modalities).is_err());
    }

    #[test]
    fn the_paper_section_restores_the_papers_score_and_keeps_the_rest() {
        let modalities = ["vw@30cm".to_string()];
        let custom: UtilitySection = toml::from_str(
            "alpha = 2.0\nfreshness_half_life_s = 1209600.0\nanomaly_form = \"bounded\"\n\
             anomaly_reference = \"neighbours\"\nvariance_weight = 1.0\nmin_overlap = 20\n",
        )
        .unwrap();
        assert_eq!(custom.variance_weight, 1.0);
        let paper = custom.paper();
        assert_eq!(
            paper.to_core(&modalities).unwrap(),
            gleaner_utility::UtilityConfig {
                min_overlap: 20,
                ..gleaner_utility::UtilityConfig::default()
            }
        );
        assert_eq!(paper.variance_weight, 0.0);
        assert_eq!(paper.min_overlap, 20);
        let gleaner = UtilitySection::default()
            .gleaner()
            .to_core(&modalities)
            .unwrap();
        assert_eq!(gleaner.score_form, gleaner_utility::ScoreForm::Gated);
        assert_eq!((gleaner.gamma, gleaner.delta), (0.0, 0.0));
        assert_eq!(gleaner.beta, GLEANER_BETA);
        assert_eq!(UtilitySection::default().gleaner().freshness_form, "drift");
        let gated = UtilitySection::default().gated();
        assert_eq!(gated.freshness_form, "half-life");
        assert_eq!(gated.freshness_half_life_s, GLEANER_HALF_LIFE_S);
        assert_eq!(
            gleaner.anomaly_form,
            gleaner_utility::AnomalyForm::Bounded { kappa: 3.0 }
        );
        assert_eq!(
            UtilitySection::default().gleaner().paper(),
            UtilitySection::default()
        );
        // Out of range: named with its key.
        let text = "[project]\nname = \"p\"\ndatabase = \"g.db\"\n[field]\nbase_lat = 38.7\n\
                    base_lon = -117.1\ncell_size_m = 40.0\n[sensors]\nfile = \"s.csv\"\n\
                    [utility]\nvariance_weight = -1.0\n";
        let err = Settings::parse(text).unwrap_err();
        assert!(err.contains("utility.variance_weight"), "{err}");
        let err =
            Settings::parse(&text.replace("variance_weight = -1.0", "freshness_form = \"fast\""))
                .unwrap_err();
        assert!(err.contains("utility.freshness_form"), "{err}");
    }
}
