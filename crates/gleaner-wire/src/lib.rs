//! gleaner's wire formats: versioned serde documents, apart from the application layer, and
//! the flight files written from them.
//!
//! - [`MissionDoc`] (`gleaner.mission` version 1): a planned or flown mission — the JSON
//!   output of `plan --json`, `explore --json`, the HTTP API's mission resource — and the
//!   input of every flight-file writer.
//! - [`FieldDoc`] (`gleaner.field` version 1): the cell grid with its latest scores and the
//!   sensors, for maps.
//!
//! Positions in documents are WGS84 `[lon, lat]` degrees (GeoJSON order) unless a field's name
//! says otherwise; lengths m, times s (and RFC 3339 text), energies J, speeds m/s.
//!
//! # Flight files
//!
//! Pure functions from documents to text; the caller writes the files. Each refuses, with a
//! typed [`ExportError`], a mission that would not fly as planned (see [`check_flyable`]):
//! energy over budget, altitude not in (0, 120] m, cruise speed not finite and positive, hover
//! times not finite and >= 0, positions out of range. Exploration sorties are missions like
//! any other.
//!
//! Then each autopilot writer reads its own text back ([`parse_qgc_plan`], [`parse_wpl`]:
//! home, altitude, commanded speed, every waypoint and hold), prices that flight with the
//! document's [`EnergyModelDoc`] ([`check_commanded`]) and refuses it above the usable budget
//! ([`ExportError::CommandedOverBudget`], naming the file): the energy checked is the energy of
//! the values in the file, not of the plan. The planner plans with those values already
//! (`gleaner_energy::flight`: holds rounded up to 0.25 s, the speed to 0.25 m/s, positions to
//! 1e-7 degrees, all before planning), so for a mission planned by this build the commanded
//! energy is the planned energy, to the last bit; a mission planned under other rounding is
//! checked all the same. A document without an energy model (one not made by
//! [`convert::export_mission`]) is refused ([`ExportError::NoEnergyModel`]).
//!
//! | function | file | order of coordinates |
//! | --- | --- | --- |
//! | [`qgc_plan`] | QGroundControl `.plan` (JSON, fileType Plan v1, mission v2) | `params` and `plannedHomePosition`: **lat, lon**, alt |
//! | [`wpl`] | `QGC WPL 110` text (tab-separated, line 0 = home) | **lat, lon**, alt |
//! | [`geojson()`] | GeoJSON FeatureCollection (RFC 7946) | **`[lon, lat]`** |
//! | [`flight_notes`] | plain text for the operator, beside the WPL | labelled |
//! | [`wpml_kmz`] | DJI WPML KMZ (`wpmz/template.kml` + `wpmz/waylines.wpml`), see [`wpml`] | `coordinates`: **lon, lat** |
//!
//! Both autopilot files command the same MAVLink items, in this order:
//!
//! 1. (WPL only, line 0) home: `NAV_WAYPOINT` (16), frame 0 (`GLOBAL`), at the base, altitude
//!    `profile.base_alt_m` m above mean sea level. In the `.plan` the same position is
//!    `mission.plannedHomePosition` = `[lat, lon, base_alt_m]`.
//! 2. `NAV_TAKEOFF` (22), frame 3 (`GLOBAL_RELATIVE_ALT`), at the base, to
//!    `profile.altitude_m` m above home.
//! 3. `DO_CHANGE_SPEED` (178), frame 2: param1 = 1 (ground speed), param2 =
//!    `profile.cruise_speed_mps` m/s rounded to 0.25 m/s (what the planner priced), param3 =
//!    -1 (throttle unchanged). An autopilot left at its default speed may run out of battery.
//!    The `.plan`'s `cruiseSpeed` and `hoverSpeed` are the same speed.
//! 4. One `NAV_WAYPOINT` (16) per stop in visiting order, frame 3, at the cell centre (lat/lon
//!    rounded to 1e-7 degrees, i.e. within 6 mm), `profile.altitude_m` m above home; param1 =
//!    hold time, s = the stop's `hover_s` rounded **up** to 0.25 s (exact as a MAVLink
//!    `float32`), so the aircraft hovers at least as long as the collection needs; the
//!    planner planned with that hold.
//! 5. `NAV_RETURN_TO_LAUNCH` (20), frame 2.
//!
//! Yaw: param4 of take-off and waypoints is NaN — `null` in the `.plan` (as QGroundControl
//! writes it; MAVSDK reads `null` as NaN) and `nan` in the WPL (as QGroundControl writes it;
//! pymavlink, MAVSDK and QGroundControl parse it). In MAVLink NaN means "keep the autopilot's
//! yaw behaviour"; 0 would command a north heading at every waypoint on PX4. param4 of
//! `DO_CHANGE_SPEED` and all parameters of return-to-launch are 0.
//!
//! Metadata: the `.plan` carries a top-level `"gleaner"` object and the GeoJSON collection a
//! `"gleaner"` foreign member (RFC 7946 §6.1), both a [`FlightMeta`]: mission id, kind,
//! status, time, planner, weights, anomaly form, base and its altitude, flight altitude,
//! cruise speed, hold rule, yaw note and the energy breakdown against the budget.
//! QGroundControl and MAVSDK ignore unknown top-level keys. The WPL carries none:
//! QGroundControl rejects a file with any line that is not 12 tab-separated fields, so a
//! `#` comment (which pymavlink and MAVSDK skip) would make it unloadable there; write
//! [`flight_notes`] beside it.
//!
//! The GeoJSON map holds every cell as a Polygon (closed counter-clockwise ring) with its
//! latest S, F, R, A, U and visiting order, the route LineString base → stops → base, one
//! Point per stop with its planned energy, the base Point and the sensors as Points. Each
//! feature's `properties.kind` says which (`cell`, `route`, `stop`, `base`, `sensor`).
//!
//! ```
//! use gleaner_wire::{check_commanded, check_flyable, parse_wpl, qgc_plan, samples, wpl, ExportError};
//!
//! let mission = samples::adaptive_mission();
//! check_flyable(&mission)?;
//! let plan = qgc_plan(&mission)?; // JSON text for mission.plan
//! let waypoints = wpl(&mission)?; // text for mission.waypoints
//! assert!(waypoints.lines().any(|l| l.starts_with("2\t0\t2\t178\t1\t10.25\t-1\t")));
//! assert!(plan.contains("\"hoverSpeed\": 10.25"));
//! // The energy of what the file commands, recomputed from its text:
//! let commanded_j = check_commanded(&mission, "mission.waypoints", &parse_wpl(&waypoints)?)?;
//! assert!(commanded_j <= mission.energy.budget_j);
//!
//! let mut over = mission.clone();
//! over.energy.total_j = 87_000.0; // e.g. flown at the autopilot's default 5 m/s
//! assert!(matches!(wpl(&over), Err(ExportError::OverBudget { .. })));
//! # Ok::<(), ExportError>(())
//! ```
//!
//! The files are checked against real consumers (pymavlink's `MAVWPLoader`, MAVSDK's QGC and
//! Mission Planner importers, the `geojson` and `shapely` Python packages) by
//! `tests/real_consumers.rs`; run `scripts/python-env.sh` once to create their environment.
#![deny(missing_docs)]

use serde::{Deserialize, Serialize};

mod check;
pub mod convert;
pub mod docs;
mod error;
mod flight;
mod geo;
pub mod samples;
pub mod text;
pub mod wpml;

pub use check::{MAX_ALTITUDE_M, MAX_HOVER_S, check_flyable};
pub use error::ExportError;
pub use flight::{
    FlightMeta, HOLD_NOTE, MAV_CMD_DO_CHANGE_SPEED, MAV_CMD_NAV_RETURN_TO_LAUNCH,
    MAV_CMD_NAV_TAKEOFF, MAV_CMD_NAV_WAYPOINT, MAV_FRAME_GLOBAL, MAV_FRAME_GLOBAL_RELATIVE_ALT,
    MAV_FRAME_MISSION, PLAN_FILE, QgcGeoFence, QgcItem, QgcMission, QgcPlan, QgcRallyPoints,
    SPEED_TYPE_GROUND, THROTTLE_UNCHANGED, WPL_FILE, YAW_NOTE, check_commanded, commanded_flight,
    flight_notes, parse_qgc_plan, parse_wpl, qgc_plan, qgc_plan_doc, wpl,
};
pub use wpml::{WpmlOptions, parse_wpml_kmz, wpml_documents, wpml_kmz};

/// The cruise ground speed every flight file commands for a planned `speed_mps`, m/s (rounded
/// to `gleaner_energy::SPEED_STEP_MPS`, as the planner priced it).
#[must_use]
pub fn commanded_speed_mps(speed_mps: f64) -> f64 {
    gleaner_energy::flight_speed_mps(speed_mps)
}

/// The flight altitude above home every flight file commands for a planned `altitude_m`, m
/// (rounded to `gleaner_energy::ALTITUDE_STEP_M`, as the planner priced it).
#[must_use]
pub fn commanded_altitude_m(altitude_m: f64) -> f64 {
    gleaner_energy::flight_altitude_m(altitude_m)
}
pub use geo::{
    BaseProperties, CellProperties, RouteProperties, SensorProperties, StopProperties,
    ZoneProperties, geojson, geojson_doc,
};

/// Format name and version of [`MissionDoc`].
pub const MISSION_FORMAT: &str = "gleaner.mission";
/// Format name and version of [`FieldDoc`].
pub const FIELD_FORMAT: &str = "gleaner.field";
/// `format` of [`docs::ReconstructionDoc`].
pub const RECONSTRUCTION_FORMAT: &str = "gleaner.reconstruction";
/// `format` of [`docs::ReconstructionSeriesDoc`].
pub const RECONSTRUCTION_SERIES_FORMAT: &str = "gleaner.reconstruction-series";
/// `format` of [`docs::ReconstructionMapDoc`].
pub const RECONSTRUCTION_MAP_FORMAT: &str = "gleaner.reconstruction-map";
/// `format` of [`docs::CampaignDoc`].
pub const CAMPAIGN_FORMAT: &str = "gleaner.campaign";
/// The version of the documents this build writes.
pub const VERSION: u32 = 1;

/// How the aircraft is to fly a mission: what the energy model assumed.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct ProfileDoc {
    /// Base station (take-off and landing) `[lon, lat]`, WGS84 degrees.
    pub base_lon_lat: [f64; 2],
    /// Base station altitude above mean sea level, m.
    pub base_alt_m: f64,
    /// Flight altitude above the base, m.
    pub altitude_m: f64,
    /// Cruise ground speed between cells, m/s (what the files command: a ground speed).
    pub cruise_speed_mps: f64,
    /// The steady wind the legs were priced in (the forecast plus the margin), m/s; absent:
    /// still air.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub wind_mps: f64,
    /// Direction that wind blows from, degrees clockwise from north; absent: 0.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub wind_from_deg: f64,
}

/// The wind a mission was planned in and what it means for the route (plan and replan
/// output).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct WindDoc {
    /// Forecast wind speed, m/s (0: still air).
    pub forecast_mps: f64,
    /// Direction the forecast wind blows from, degrees clockwise from north.
    pub from_deg: f64,
    /// Margin added to a forecast above 0 m/s, m/s (`[flight] wind_margin_mps`).
    pub margin_mps: f64,
    /// The wind speed the legs and hovers are priced in, m/s, from `from_deg`.
    pub planned_mps: f64,
    /// The strongest wind from `from_deg` at which the route, as its files command it,
    /// stays within the budget, m/s, at every speed from `planned_mps` up to it (absent for
    /// an empty route or one over budget in the planned wind).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub strongest_feasible_mps: Option<f64>,
    /// True when `strongest_feasible_mps` is the search's cap (40 m/s): the route stands
    /// any wind up to it.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub strongest_capped: bool,
    /// True when the route, planned in a wind, is over budget in still air: hovering in a
    /// moderate wind takes less power than in still air, so more hovering fits the battery
    /// in the planned wind than without wind (absent when still air is within budget).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub over_budget_in_still_air: bool,
    /// Each leg at the planned wind: one per stop (the leg arriving there), then the return
    /// leg.
    pub legs: Vec<LegWindDoc>,
}

/// One leg's wind at the planned wind.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct LegWindDoc {
    /// Leg length, m.
    pub distance_m: f64,
    /// Head-wind component, m/s (>= 0).
    pub headwind_mps: f64,
    /// Tail-wind component, m/s (>= 0).
    pub tailwind_mps: f64,
    /// Cross-wind component, m/s: > 0 from the left of the track, < 0 from the right.
    pub crosswind_mps: f64,
    /// Airspeed that holds the track at the planned ground speed, m/s.
    pub airspeed_mps: f64,
    /// Propulsion energy of the leg, J.
    pub energy_j: f64,
}

/// One stop of a mission, in visiting order.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
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
    /// Turn points `[lon, lat]` (WGS84 degrees, on the files' 1e-7° grid) of the leg
    /// arriving here, flown around no-fly zones at the cruise altitude and speed without a
    /// hold; absent for a straight leg. `leg_distance_m` and `leg_energy_j` are the whole
    /// polyline's.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub via_lon_lat: Vec<[f64; 2]>,
}

/// A geofence or no-fly zone as the project's settings give it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct ZoneDoc {
    /// `geofence` (the flight stays inside) or `no-fly` (it keeps out).
    pub kind: String,
    /// The feature's `name`, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Position of the feature in its file, from 0.
    pub feature: usize,
    /// Polygons: rings (exterior first, then holes), each closed, of `[lon, lat]` WGS84
    /// degrees. Empty for a line or point zone.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub polygons_lon_lat: Vec<Vec<Vec<[f64; 2]>>>,
    /// Lines (a power line; a single position for a point zone), `[lon, lat]` WGS84 degrees.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub lines_lon_lat: Vec<Vec<[f64; 2]>>,
    /// The safety buffer the planner kept from the zone (grown) or inside the fence
    /// (shrunk), m.
    pub buffer_m: f64,
}

/// A cell the flight cannot reach.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct UnreachableDoc {
    /// Cell id (`x12y-3`).
    pub cell: String,
    /// Why (inside a buffered no-fly zone, outside the geofence, cut off from the base).
    pub reason: String,
}

/// One waypoint of the flown sequence (see [`flown_waypoints`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlownWaypoint {
    /// `[lon, lat]`, WGS84 degrees.
    pub lon_lat: [f64; 2],
    /// The stop it is (index into `stops`), or `None` for a detour's turn point.
    pub stop: Option<usize>,
}

/// The waypoints a mission flies after take-off, in order: each stop preceded by the turn
/// points of its leg, then the return leg's turn points (the aircraft then returns home).
pub fn flown_waypoints(m: &MissionDoc) -> Vec<FlownWaypoint> {
    let mut out = Vec::new();
    for (k, s) in m.stops.iter().enumerate() {
        out.extend(s.via_lon_lat.iter().map(|&p| FlownWaypoint {
            lon_lat: p,
            stop: None,
        }));
        out.push(FlownWaypoint {
            lon_lat: s.centre_lon_lat,
            stop: Some(k),
        });
    }
    out.extend(m.return_via_lon_lat.iter().map(|&p| FlownWaypoint {
        lon_lat: p,
        stop: None,
    }));
    out
}

/// The energy breakdown of a sortie (docs/method.md §3).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
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
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
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
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
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
    /// Weights alpha, beta, gamma, delta of S (additive alpha·F + beta·A + gamma·U − delta·R, or
    /// gated alpha·F·max(0, 1 + beta·A + gamma·U − delta·R); docs/method.md §2).
    pub weights: [f64; 4],
    /// Anomaly form (`raw`, `bounded(kappa=3)`, `n/a`).
    pub anomaly_form: String,
    /// How the aircraft flies it.
    pub profile: ProfileDoc,
    /// Stops in visiting order.
    pub stops: Vec<StopDoc>,
    /// Return leg, m.
    pub return_distance_m: f64,
    /// Turn points `[lon, lat]` of the return leg around no-fly zones (see
    /// [`StopDoc::via_lon_lat`]); absent when straight.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub return_via_lon_lat: Vec<[f64; 2]>,
    /// The geofence and no-fly zones the route was planned around (absent without zones):
    /// the `.plan`'s `geoFence`, the GeoJSON's zone features.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub zones: Vec<ZoneDoc>,
    /// Cells the flight cannot reach (plan output only; absent when every cell is).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub unreachable: Vec<UnreachableDoc>,
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
    /// The energy model the flight-file writers price the values they write with (present in
    /// documents made for export, [`convert::export_mission`]); a writer refuses a document
    /// without it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub energy_model: Option<EnergyModelDoc>,
    /// Present for a continuation re-planned in the air (`gleaner replan`): its files start
    /// where the aircraft is, with no take-off.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub continuation: Option<ContinuationDoc>,
    /// The wind it was planned in, per leg, and the strongest wind it stands (plan and
    /// replan output only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wind: Option<WindDoc>,
}

/// A continuation's origin: the mission it continues, where the aircraft is and the energy
/// it has left.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct ContinuationDoc {
    /// The mission being flown.
    pub parent_mission_id: i64,
    /// Stops of it already flown (0 = airborne over the base).
    pub after_stop: usize,
    /// Where the aircraft is, WGS84 `[lon, lat]` degrees: the first waypoint (hold 0 s).
    pub start_lon_lat: [f64; 2],
    /// Energy left when re-planned, J.
    pub energy_left_j: f64,
    /// The battery's reserve kept for landing, J (the budget is `energy_left_j − reserve_j`).
    pub reserve_j: f64,
}

/// The parameters that price what a flight file commands (`gleaner_energy::FlightEnergyModel`):
/// the power curve, the receiver power, the optional linear and climb/descent models and the
/// usable budget. Speed, altitude, positions and holds are read from the file itself.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct EnergyModelDoc {
    /// Blade profile power in hover P0, W.
    pub blade_profile_power_w: f64,
    /// Induced power in hover Pi, W.
    pub induced_power_w: f64,
    /// Mean rotor induced velocity in hover v0, m/s.
    pub mean_induced_velocity_mps: f64,
    /// Rotor blade tip speed U_tip, m/s.
    pub tip_speed_mps: f64,
    /// Parasite drag factor d0·rho·s·A, kg/m.
    pub parasite_drag_factor_kg_m: f64,
    /// Aircraft weight W, N.
    pub weight_n: f64,
    /// Receiver power while hovering, W.
    pub rx_power_w: f64,
    /// The linear model's energy per metre, J/m (with `linear_j_per_cell`; absent: the
    /// physical model).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub linear_j_per_m: Option<f64>,
    /// The linear model's energy per cell visited, J.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub linear_j_per_cell: Option<f64>,
    /// Climb rate after take-off, m/s (with `descent_speed_mps`; absent: not modelled).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub climb_speed_mps: Option<f64>,
    /// Descent rate before landing, m/s.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub descent_speed_mps: Option<f64>,
    /// Usable battery energy, J.
    pub usable_budget_j: f64,
    /// The steady wind the mission was planned in (the forecast plus the planning margin),
    /// m/s; absent: still air. The writers price the file in this wind.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub wind_mps: f64,
    /// Direction that wind blows from, degrees clockwise from north (meteorological).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub wind_from_deg: f64,
}

/// Serde helper: leave out a zero (still air keeps documents as they were).
#[allow(clippy::trivially_copy_pass_by_ref)]
fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

impl From<gleaner_energy::FlightEnergyModel> for EnergyModelDoc {
    fn from(m: gleaner_energy::FlightEnergyModel) -> Self {
        let p = m.power;
        Self {
            blade_profile_power_w: p.blade_profile_power_w,
            induced_power_w: p.induced_power_w,
            mean_induced_velocity_mps: p.mean_induced_velocity_mps,
            tip_speed_mps: p.tip_speed_mps,
            parasite_drag_factor_kg_m: p.parasite_drag_factor_kg_m,
            weight_n: p.weight_n,
            rx_power_w: m.rx_power_w,
            linear_j_per_m: m.linear.map(|l| l.j_per_m),
            linear_j_per_cell: m.linear.map(|l| l.j_per_cell),
            climb_speed_mps: m.vertical.map(|v| v.climb_speed_mps),
            descent_speed_mps: m.vertical.map(|v| v.descent_speed_mps),
            usable_budget_j: m.usable_budget_j,
            wind_mps: m.wind.speed_mps,
            wind_from_deg: m.wind.from_deg,
        }
    }
}

impl EnergyModelDoc {
    /// The core model (a linear or climb/descent model needs both of its fields).
    #[must_use]
    pub fn to_core(&self) -> gleaner_energy::FlightEnergyModel {
        gleaner_energy::FlightEnergyModel {
            power: gleaner_energy::PowerParameters {
                blade_profile_power_w: self.blade_profile_power_w,
                induced_power_w: self.induced_power_w,
                mean_induced_velocity_mps: self.mean_induced_velocity_mps,
                tip_speed_mps: self.tip_speed_mps,
                parasite_drag_factor_kg_m: self.parasite_drag_factor_kg_m,
                weight_n: self.weight_n,
            },
            rx_power_w: self.rx_power_w,
            linear: match (self.linear_j_per_m, self.linear_j_per_cell) {
                (Some(j_per_m), Some(j_per_cell)) => Some(gleaner_energy::LinearEnergy {
                    j_per_m,
                    j_per_cell,
                }),
                _ => None,
            },
            vertical: match (self.climb_speed_mps, self.descent_speed_mps) {
                (Some(climb_speed_mps), Some(descent_speed_mps)) => {
                    Some(gleaner_energy::VerticalConfig {
                        climb_speed_mps,
                        descent_speed_mps,
                    })
                }
                _ => None,
            },
            usable_budget_j: self.usable_budget_j,
            wind: gleaner_energy::Wind {
                speed_mps: self.wind_mps,
                from_deg: self.wind_from_deg,
            },
        }
    }
}

/// A cell's latest utility terms.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
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
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
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
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct SensorDoc {
    /// Sensor id.
    pub id: String,
    /// Position `[lon, lat]`, WGS84 degrees.
    pub lon_lat: [f64; 2],
}

/// The field: grid, scores and sensors (`gleaner.field` version 1).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
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
    /// The geofence and no-fly zones of the project's settings (absent without).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub zones: Vec<ZoneDoc>,
}

#[cfg(test)]
mod tests;
