//! The API's own request and response types (serialisable counterparts of the application
//! layer's plain data, converted explicitly here). Documents the CLI also prints
//! (`gleaner.mission`, `gleaner.field`, cell rows, scorings, explorations) are gleaner-wire's.

use gleaner_app as app;
use gleaner_wire::MissionDoc;
use serde::{Deserialize, Serialize};
use utoipa::ToSchema;

use crate::error::ApiError;

/// The project and its settings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct ProjectDoc {
    /// Project name.
    pub name: String,
    /// gleaner's version.
    pub version: String,
    /// Base station `[lon, lat]`, WGS84 degrees.
    pub base_lon_lat: [f64; 2],
    /// Base station altitude above mean sea level, m.
    pub base_alt_m: f64,
    /// Cell side, m.
    pub cell_size_m: f64,
    /// Number of sensors.
    pub sensors: usize,
    /// Number of stored readings.
    pub readings: u64,
    /// Newest stored reading, RFC 3339 UTC (absent without readings).
    pub latest_reading: Option<String>,
    /// Number of missions.
    pub missions: usize,
    /// Weights α, β, γ, δ of S = α·F + β·A + γ·U − δ·R.
    pub weights: [f64; 4],
    /// Energy preset (`paper`, `large_pack`).
    pub energy_preset: String,
    /// Default route planner.
    pub solver: String,
    /// Default planner time limit, s.
    pub time_limit_s: f64,
    /// Longest planner time limit a request may ask for, s.
    pub max_time_limit_s: f64,
    /// Default planner seed.
    pub seed: u64,
    /// Basemap tile URL template (`{z}/{x}/{y}`) the dashboard draws under the cells, if set.
    pub basemap_url: Option<String>,
    /// Whether writes are possible (the server has a token).
    pub writable: bool,
    /// Largest upload accepted, bytes.
    pub max_upload_bytes: u64,
}

/// A time range of collected history and a mission time, as the CLI's `--at`,
/// `--history-from`, `--history-until`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct ScoreBody {
    /// Mission time, RFC 3339 or `YYYY-MM-DD` (UTC) [default: the latest reading].
    pub at: Option<String>,
    /// Use only readings from this time on as collected history.
    pub history_from: Option<String>,
    /// Use only readings up to this time as collected history.
    pub history_until: Option<String>,
    /// Compute without storing the scores.
    #[serde(default)]
    pub dry_run: bool,
}

/// A planning request (`gleaner plan`).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct PlanBody {
    /// Mission time, RFC 3339 or `YYYY-MM-DD` (UTC) [default: the latest reading].
    pub at: Option<String>,
    /// Use only readings from this time on as collected history.
    pub history_from: Option<String>,
    /// Use only readings up to this time as collected history.
    pub history_until: Option<String>,
    /// Route planner: `default`, `greedy`, `exact` [default: the project's].
    pub solver: Option<String>,
    /// Planner time limit, s [default: the project's; at most the server's maximum].
    pub time_limit_s: Option<f64>,
    /// Planner seed [default: the project's].
    pub seed: Option<u64>,
    /// Stop the search after this many iterations (machine-independent routes).
    pub iterations: Option<u64>,
    /// Battery budget preset: `paper` or `large-pack` [default: the project's `[energy]`].
    pub energy_preset: Option<String>,
    /// Plan without storing the mission (the dashboard's preview).
    #[serde(default)]
    pub dry_run: bool,
    /// Disjoint sorties on this mission day (battery swaps), 1..=20, each a battery's worth
    /// and stored as its own mission: only with `POST /api/v1/plan/sorties` [default: 1].
    pub sorties: Option<usize>,
    /// What the route maximises: `score` (the sum of S), `information` (the expected
    /// reduction of the dynamic field model's posterior variance over the whole field) or
    /// `hybrid` (both shares blended by `[planner] information_weight`) [default: the
    /// project's `[planner] objective`].
    pub objective: Option<String>,
    /// Forecast wind at the flight altitude [default: the project's `[flight] wind_mps` and
    /// `wind_from_deg`]; the legs are priced in it plus `[flight] wind_margin_mps`.
    pub wind: Option<WindBody>,
}

/// A forecast wind.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct WindBody {
    /// Wind speed, m/s, in [0, 40].
    pub speed_mps: f64,
    /// Direction the wind blows from, degrees clockwise from north, in [0, 360] (270: a
    /// west wind).
    pub from_deg: f64,
}

/// A re-planning request in the air (`gleaner replan`).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct ReplanBody {
    /// Stops already flown: the aircraft is over this stop, done collecting (1-based; 0 =
    /// airborne over the base).
    pub after_stop: usize,
    /// Energy left in the battery, J.
    pub energy_left_j: f64,
    /// Planner seed [default: the mission's].
    pub seed: Option<u64>,
    /// Stop the search after this many iterations [default: 200, the replan command's cap].
    pub iterations: Option<u64>,
    /// Planner time limit, s [default: 1; at most the server's maximum].
    pub time_limit_s: Option<f64>,
    /// The wind now [default: the wind the mission was planned in]; `[flight]
    /// wind_margin_mps` is added to it.
    pub wind: Option<WindBody>,
}

/// A continuation re-planned in the air: the mission document (status `continuation`, its
/// `continuation` member saying from where and with what energy), the stops dropped, and its
/// flight files, each read back and priced within the energy left less the reserve.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct ReplanDoc {
    /// The continuation.
    pub mission: MissionDoc,
    /// Remaining stops dropped (cell ids, in the mission's order).
    pub dropped: Vec<String>,
    /// The QGroundControl `.plan` (JSON text): no take-off, a 0 s first waypoint where the
    /// aircraft is.
    pub plan: String,
    /// The same flight as a `QGC WPL 110` file.
    pub waypoints: String,
    /// Planning time, s.
    pub solve_seconds: f64,
}

/// A replay of the served project's own record (`gleaner simulate --project`): which
/// strategies would have served this farm best over its recent past.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct SimulateBody {
    /// Strategies (`gleaner`, `paper`, `variance`, `freshness`, `round-robin`, `random`,
    /// `nearest`, `exhaustive`, the ablations, `gated`, `oracle`; or `main`, `all`)
    /// [default: `gleaner`, `round-robin`, `freshness`].
    pub strategies: Option<Vec<String>>,
    /// First mission, RFC 3339 or `YYYY-MM-DD` (UTC) [default: 30 days before the last
    /// reading becomes available]; the history runs to it unless `history_until` says.
    pub start: Option<String>,
    /// Last mission at or before this time [default: when the last reading becomes
    /// available].
    pub end: Option<String>,
    /// End of the history every run starts with [default: the first mission].
    pub history_until: Option<String>,
    /// Hours between missions, (0, 8760] [default: 24].
    pub every_hours: Option<f64>,
    /// Replicate seeds (planner and random choices), at most 10 [default: [1]].
    pub seeds: Option<Vec<u64>>,
    /// Battery capacities as fractions of the preset's, each in (0, 10], at most 10
    /// [default: [1]].
    pub budgets: Option<Vec<f64>>,
    /// Battery budget preset: `paper` or `large-pack` [default: the project's `[energy]`].
    pub energy_preset: Option<String>,
    /// Planner iteration cap per mission, 1..=10000 [default: 300].
    pub planner_iterations: Option<u64>,
    /// Each mission's forecast wind: `still` or `weibull:MEAN[:SHAPE]` (mean speed in m/s,
    /// Weibull shape, default 2; direction uniform), drawn with `weather_seed` [default:
    /// still air]. Missions are planned for the forecast plus a margin tied to the forecast
    /// error (`margin_quantile`) and flown in it with the error and the gusts; a sortie
    /// short of energy re-plans in the air. The answer's `flights` tell how they flew.
    pub wind: Option<String>,
    /// The forecast error's standard deviation (east and north components), m/s, in
    /// [0, 10] [default: 1 with a drawn wind, else 0].
    pub gust: Option<f64>,
    /// Gusts leg by leg: each leg's wind is the day's plus a vector with this standard
    /// deviation per component, m/s, in [0, 10] [default: 0].
    pub leg_gust: Option<f64>,
    /// Each sortie's battery holds a share of its rated capacity drawn uniformly in
    /// [1 − this, 1], in [0, 0.5] [default: 0].
    pub weak_battery: Option<f64>,
    /// Seed of the wind, error, gust and battery draws [default: 1].
    pub weather_seed: Option<u64>,
    /// The share of forecast errors along the wind the planning margin covers, in
    /// [0.5, 0.999] [default: 0.95].
    pub margin_quantile: Option<f64>,
    /// Observed daily winds in place of a drawn `wind` (as `simulate --wind-csv`): one per
    /// day, every mission's day given; each mission is planned for its day's wind (plus the
    /// margin) and flown in it with the forecast error (`gust`, default 1 m/s). At most
    /// 36,600 days.
    pub winds: Option<Vec<WindDayBody>>,
    /// Also render the campaign's report (as `gleaner simulate` writes it: Markdown with its
    /// tables and SVG charts), returned in the answer's `report` [default: false].
    #[serde(default)]
    pub report: bool,
}

/// What a simulation found (`POST /api/v1/simulate`): the `gleaner.campaign` document, and
/// its report when the request asked for one.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct SimulationDoc {
    /// The campaign document's fields.
    #[serde(flatten)]
    pub campaign: gleaner_wire::docs::CampaignDoc,
    /// The report (with `"report": true` only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub report: Option<ReportDoc>,
}

/// A campaign report, as `gleaner simulate` writes it to `report.md` and `figures/`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct ReportDoc {
    /// `report.md`'s text (Markdown): the campaign, per strategy and budget each metric with
    /// its 95% interval, the differences against the reference, the charts linked as
    /// `figures/NAME` (the names of `figures`).
    pub markdown: String,
    /// The charts, in the report's order.
    pub figures: Vec<FigureDoc>,
}

/// One chart of a report.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct FigureDoc {
    /// File name the Markdown links it by (`figures/NAME`), e.g. `rmse_kriged.svg`.
    pub name: String,
    /// The chart, an SVG document (`image/svg+xml`).
    pub svg: String,
}

/// One day of observed wind (a row of `simulate --wind-csv`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct WindDayBody {
    /// The day, `YYYY-MM-DD` (UTC).
    pub date: String,
    /// Mean wind speed at the flight altitude, m/s, in [0, 40].
    pub speed_mps: f64,
    /// Direction it blows from, degrees clockwise from north, in [0, 360].
    pub from_deg: f64,
}

/// An exploration request (`gleaner explore`).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct ExploreBody {
    /// Planning time, RFC 3339 or `YYYY-MM-DD` (UTC) [default: the latest reading].
    pub at: Option<String>,
    /// Plan without storing the sorties.
    #[serde(default)]
    pub dry_run: bool,
    /// Forecast wind at the flight altitude [default: the project's `[flight] wind_mps` and
    /// `wind_from_deg`]; the sorties are planned in it plus `[flight] wind_margin_mps`.
    pub wind: Option<WindBody>,
}

/// The weighted terms of S for one cell.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct ContributionsDoc {
    /// α·F.
    pub freshness: f64,
    /// β·A.
    pub anomaly: f64,
    /// γ·U.
    pub uncertainty: f64,
    /// −δ·R.
    pub redundancy: f64,
}

/// One modality's recent readings from one sensor.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct SeriesDoc {
    /// Sensor id.
    pub sensor: String,
    /// Modality (`vw@30cm`).
    pub modality: String,
    /// Times, seconds since the Unix epoch (UTC), ascending.
    pub t: Vec<i64>,
    /// Values, in the modality's unit, one per time.
    pub values: Vec<f64>,
}

/// One cell for the dashboard's panel: its row, why it ranks where it does, its series.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct CellDetailDoc {
    /// The cell's row (as `gleaner cells --json`).
    pub cell: gleaner_wire::docs::CellRowDoc,
    /// Weights α, β, γ, δ.
    pub weights: [f64; 4],
    /// The weighted terms of its latest scores.
    pub contributions: Option<ContributionsDoc>,
    /// The largest positive weighted term: `freshness`, `anomaly`, `uncertainty` or `none`.
    pub driver: Option<String>,
    /// Rank by S among the scored cells, from 1.
    pub rank: Option<usize>,
    /// Number of scored cells.
    pub scored: usize,
    /// The readings of its sensors within the requested window of their newest one.
    pub series: Vec<SeriesDoc>,
    /// Newest reading of its sensors, RFC 3339 UTC.
    pub latest: Option<String>,
}

impl CellDetailDoc {
    /// Converts the application's cell detail.
    pub fn from_app(d: &app::CellDetail, cell_size_m: f64) -> Self {
        let mut series: Vec<SeriesDoc> = Vec::new();
        for p in &d.series {
            let same = series.last().is_some_and(|s| {
                s.sensor == p.sensor.as_str() && s.modality == p.modality.as_str()
            });
            if !same {
                series.push(SeriesDoc {
                    sensor: p.sensor.as_str().to_string(),
                    modality: p.modality.as_str().to_string(),
                    t: Vec::new(),
                    values: Vec::new(),
                });
            }
            let s = series.last_mut().expect("pushed above");
            s.t.push(p.t);
            s.values.push(p.value);
        }
        Self {
            cell: gleaner_wire::convert::cell_row(&d.cell, cell_size_m),
            weights: d.weights,
            contributions: d.contributions.map(|c| ContributionsDoc {
                freshness: c.freshness,
                anomaly: c.anomaly,
                uncertainty: c.uncertainty,
                redundancy: c.redundancy,
            }),
            driver: d.driver.map(str::to_string),
            rank: d.rank,
            scored: d.scored,
            series,
            latest: d.latest.map(app::format_rfc3339),
        }
    }
}

/// What an ingest stored.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct IngestDoc {
    /// Files read.
    pub files: usize,
    /// Data rows read.
    pub rows_read: u64,
    /// Readings parsed.
    pub readings: u64,
    /// Readings newly stored.
    pub inserted: u64,
    /// Readings already stored.
    pub unchanged: u64,
    /// Conflicting readings kept as stored.
    pub conflicts: u64,
    /// Missing values (`NA`).
    pub missing: u64,
    /// Duplicate rows within a file.
    pub duplicates: u64,
    /// Rows skipped (`on_error = skip` only), with why.
    pub skipped: Vec<String>,
    /// Cells whose summaries were refreshed.
    pub cells_refreshed: usize,
}

impl IngestDoc {
    /// Converts the application's ingest outcome.
    pub fn from_app(o: &app::IngestOutcome) -> Self {
        let r = &o.report;
        Self {
            files: o.files,
            rows_read: r.rows_read,
            readings: r.readings,
            inserted: o.inserted,
            unchanged: o.unchanged,
            conflicts: o.conflicts,
            missing: r.missing,
            duplicates: r.duplicates,
            skipped: r.skipped_rows.iter().map(|s| s.reason.clone()).collect(),
            cells_refreshed: o.cells_refreshed,
        }
    }
}

/// What recording a flight stored.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct RecordDoc {
    /// The mission.
    pub mission: i64,
    /// Collection time, RFC 3339 UTC.
    pub at: String,
    /// Cells visited, in order.
    pub cells: Vec<String>,
    /// Sensors collected.
    pub sensors_collected: usize,
    /// Readings newly stored.
    pub readings_inserted: u64,
    /// Readings brought back that were already stored.
    pub readings_unchanged: u64,
    /// Whether an earlier record was replaced.
    pub amended: bool,
}

impl RecordDoc {
    /// Converts the application's record outcome.
    pub fn from_app(o: &app::RecordOutcome) -> Self {
        Self {
            mission: o.mission.0,
            at: app::format_rfc3339(o.at),
            cells: o.cells.iter().map(|c| c.to_string()).collect(),
            sensors_collected: o.sensors_collected,
            readings_inserted: o.readings_inserted,
            readings_unchanged: o.readings_unchanged,
            amended: o.amended,
        }
    }
}

/// Earliest time a request may name: 2000-01-01T00:00:00Z (s).
pub const EARLIEST_TIME: i64 = 946_684_800;
/// Times a request names are before 2100-01-01T00:00:00Z (s).
pub const LATEST_TIME: i64 = 4_102_444_800;

/// Parses an optional time field (RFC 3339 or `YYYY-MM-DD`, UTC) into seconds; refuses a
/// time outside [2000-01-01, 2100-01-01) (`1900-01-01` is a typing error, not a mission).
pub fn parse_time(field: &str, value: Option<&str>) -> Result<Option<i64>, ApiError> {
    value
        .map(|v| {
            let t = app::parse_timestamp(v).ok_or_else(|| {
                ApiError::bad_request(
                    Some(field),
                    format!(
                        "expected RFC 3339 (2014-03-01T12:00:00Z) or a date (2014-03-01), got {v:?}"
                    ),
                )
            })?;
            if !(EARLIEST_TIME..LATEST_TIME).contains(&t) {
                return Err(ApiError::bad_request(
                    Some(field),
                    format!("{v:?} is outside 2000-01-01 .. 2100-01-01"),
                ));
            }
            Ok(t)
        })
        .transpose()
}

/// A request's mission time and history range from its `at`, `history_from` and
/// `history_until` fields: each parsed in that order ([`parse_time`]), then the range checked
/// ([`checked_history`]).
pub fn time_and_history(
    at: Option<&str>,
    history_from: Option<&str>,
    history_until: Option<&str>,
) -> Result<(Option<i64>, app::History), ApiError> {
    let at = parse_time("at", at)?;
    let from = parse_time("history_from", history_from)?;
    let until = parse_time("history_until", history_until)?;
    Ok((at, checked_history(at, from, until)?))
}

/// The history range of a request (unbounded sides as the CLI's), refusing a start after
/// its end or after the mission time `at`.
pub fn checked_history(
    at: Option<i64>,
    from: Option<i64>,
    until: Option<i64>,
) -> Result<app::History, ApiError> {
    if let (Some(f), Some(u)) = (from, until)
        && f > u
    {
        return Err(ApiError::bad_request(
            Some("history_from"),
            format!(
                "history_from {} is after history_until {}",
                app::format_rfc3339(f),
                app::format_rfc3339(u)
            ),
        ));
    }
    if let (Some(f), Some(a)) = (from, at)
        && f > a
    {
        return Err(ApiError::bad_request(
            Some("history_from"),
            format!(
                "history_from {} is after the mission time at {}: nothing would be known",
                app::format_rfc3339(f),
                app::format_rfc3339(a)
            ),
        ));
    }
    Ok(app::History {
        from: from.unwrap_or(i64::MIN),
        until: until.unwrap_or(i64::MAX),
    })
}
