//! The endpoints under `/api/v1`: each parses its request, calls one application use case on
//! a blocking thread and converts the result. No lifecycle logic lives here.

use std::path::PathBuf;

use axum::Json;
use axum::body::Bytes;
use axum::extract::multipart::MultipartRejection;
use axum::extract::rejection::BytesRejection;
use axum::extract::{FromRequestParts, Multipart, Path, RawQuery, State};
use axum::http::request::Parts;
use axum::http::{HeaderValue, StatusCode, header};
use axum::response::{IntoResponse, Response};
use gleaner_app::{self as app, MissionId, StoreRead};
use gleaner_wire::docs::{
    CellRowDoc, ExplorationDoc, ReconstructionDoc, ReconstructionSeriesDoc, ScoringDoc,
};
use gleaner_wire::{FieldDoc, MissionDoc};
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use utoipa::{IntoParams, OpenApi, ToSchema};

use crate::api::{
    CellDetailDoc, ExploreBody, IngestDoc, PlanBody, ProjectDoc, RecordDoc, ReplanBody, ReplanDoc,
    ReportDoc, ScoreBody, SimulateBody, SimulationDoc, WindDayBody, checked_history, parse_time,
};
use crate::auth::{Caller, Computing, Writing};
use crate::error::{ApiError, ApiResult, ErrorBody};
use crate::state::{AppState, Changes, Job};

/// The OpenAPI document's header; the paths come from the handlers (utoipa-axum).
#[derive(OpenApi)]
#[openapi(
    info(
        title = "gleaner",
        description = "Score a farm's sensor cells, plan battery-limited UAV missions, download their flight files and record the flights. Writes need `Authorization: Bearer <token>` (the scheme in any case); on a server bound beyond loopback every computation does too (previews, dry runs, simulations, reconstructions). JSON bodies need `Content-Type: application/json` (415 otherwise). Units: m, s, J, W; positions WGS84 [lon, lat] degrees; times RFC 3339 UTC or `YYYY-MM-DD`, from 2000-01-01 to before 2100-01-01."
    ),
    tags(
        (name = "project", description = "The project, its field and cells"),
        (name = "missions", description = "Planning, exploration, missions and their files"),
        (name = "data", description = "Scoring, readings uploads and recorded flights")
    ),
    components(schemas(ErrorBody))
)]
pub struct ApiDoc;

/// The wall clock, seconds since the epoch: provenance only (creation times), never results.
fn clock_now() -> i64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs() as i64)
}

/// A request's `energy_preset`: none (empty = none), `paper` or `large-pack`.
fn energy_preset(value: Option<&str>) -> ApiResult<Option<String>> {
    match value {
        None | Some("") => Ok(None),
        Some(p @ ("paper" | "large-pack")) => Ok(Some(p.to_string())),
        Some(other) => Err(ApiError::bad_request(
            Some("energy_preset"),
            format!("energy preset {other:?}: expected paper or large-pack"),
        )),
    }
}

/// A JSON route's `Content-Type`: `application/json` (parameters such as `charset` allowed),
/// else 415 before the body is read, so a page on another site cannot post a form or plain
/// text to it.
#[derive(Debug, Clone, Copy)]
pub struct JsonType;

impl<S: Send + Sync> FromRequestParts<S> for JsonType {
    type Rejection = ApiError;

    async fn from_request_parts(parts: &mut Parts, _: &S) -> Result<Self, ApiError> {
        let given = parts
            .headers
            .get(header::CONTENT_TYPE)
            .and_then(|v| v.to_str().ok());
        let essence = given.map(|v| v.split(';').next().unwrap_or("").trim());
        match essence {
            Some(e) if e.eq_ignore_ascii_case("application/json") => Ok(Self),
            _ => Err(ApiError::unsupported_media_type(format!(
                "this endpoint takes a JSON body: send Content-Type: application/json (got {})",
                given.map_or("none".to_string(), |g| format!("{g:?}"))
            ))),
        }
    }
}

/// The API field a deserialisation error is about: the first segment of its path
/// (`seeds[0]` → `seeds`), else the field serde names in its message, else `body`.
fn field_of(path: &str, message: &str) -> String {
    let first = path
        .split(['.', '['])
        .next()
        .unwrap_or("")
        .trim_matches('?');
    if !first.is_empty() {
        return first.to_string();
    }
    if message.contains("field")
        && let Some(name) = message.split('`').nth(1).filter(|n| !n.is_empty())
    {
        return name.to_string();
    }
    "body".to_string()
}

fn body_bytes(body: Result<Bytes, BytesRejection>) -> ApiResult<Bytes> {
    body.map_err(|r| {
        if r.status() == StatusCode::PAYLOAD_TOO_LARGE {
            ApiError::too_large(Some("body"), r.body_text())
        } else {
            ApiError::bad_request(Some("body"), r.body_text())
        }
    })
}

/// A JSON body (empty = `{}`), refusing unknown fields; errors name the field at fault.
fn json_body<T: DeserializeOwned>(body: Result<Bytes, BytesRejection>) -> ApiResult<T> {
    parse_json(&body_bytes(body)?)
}

fn parse_json<T: DeserializeOwned>(bytes: &[u8]) -> ApiResult<T> {
    let bytes: &[u8] = if bytes.iter().all(u8::is_ascii_whitespace) {
        b"{}"
    } else {
        bytes
    };
    let de = &mut serde_json::Deserializer::from_slice(bytes);
    serde_path_to_error::deserialize(de).map_err(|e| {
        let path = e.path().to_string();
        let inner = e.inner().to_string();
        ApiError::bad_request(
            Some(&field_of(&path, &inner)),
            format!("invalid JSON body: {inner}"),
        )
    })
}

/// The JSON body of a request that writes unless it says `"dry_run": true`: a caller without
/// the token is refused (401) unless the body is a well-formed dry run, so a bad body without
/// the token is 401, never a 400 about its content.
fn json_body_for<T: DeserializeOwned>(
    s: &AppState,
    caller: Caller,
    body: Result<Bytes, BytesRejection>,
) -> ApiResult<T> {
    let bytes = body_bytes(body)?;
    if !caller.authenticated {
        let dry_run = bytes
            .iter()
            .all(u8::is_ascii_whitespace)
            .then_some(false)
            .or_else(|| {
                serde_json::from_slice::<serde_json::Value>(&bytes)
                    .ok()
                    .map(|v| v.get("dry_run") == Some(&serde_json::Value::Bool(true)))
            });
        if dry_run != Some(true) {
            caller.require_write(s)?;
        }
    }
    parse_json(&bytes)
}

/// A query string, refusing unknown parameters; errors name the parameter at fault.
fn query<T: DeserializeOwned>(raw: Option<String>) -> ApiResult<T> {
    let raw = raw.unwrap_or_default();
    let de = serde_urlencoded::Deserializer::new(form_urlencoded::parse(raw.as_bytes()));
    serde_path_to_error::deserialize(de).map_err(|e| {
        let path = e.path().to_string();
        let inner = e.inner().to_string();
        ApiError::bad_request(
            Some(&field_of(&path, &inner)),
            format!("invalid query: {inner}"),
        )
    })
}

fn mission_id(text: &str) -> ApiResult<MissionId> {
    text.parse::<i64>().map(MissionId).map_err(|_| {
        ApiError::bad_request(
            Some("mission"),
            format!("mission id {text:?}: expected an integer"),
        )
    })
}

fn cell_index(text: &str) -> ApiResult<gleaner_field::CellIndex> {
    gleaner_field::CellIndex::parse(text).ok_or_else(|| {
        ApiError::bad_request(
            Some("cell"),
            format!("cell {text:?}: expected a cell id like x3y-1"),
        )
    })
}

/// The project and its settings.
#[utoipa::path(get, path = "/api/v1/project", tag = "project",
    responses((status = 200, body = ProjectDoc), (status = 500, body = ErrorBody)))]
pub async fn project(State(s): State<AppState>) -> ApiResult<Response> {
    let basemap_url = s.0.basemap_url.clone();
    let writable = s.0.token.is_some() || s.0.farm;
    let (max_upload_bytes, max_time_limit_s) = (s.0.max_upload_bytes as u64, s.0.max_time_limit_s);
    // Reads no cell's description: kept by a scoring.
    let bytes = s
        .cached_eager(
            "project",
            Changes::MISSIONS.and(Changes::DATA),
            move |p, _| {
                let (sensors, field) = p.field()?;
                let settings = p.settings();
                let base = settings.base()?;
                let u = &settings.utility;
                to_json(&ProjectDoc {
                    name: settings.project.name.clone(),
                    version: env!("CARGO_PKG_VERSION").to_string(),
                    base_lon_lat: [base.lon(), base.lat()],
                    base_alt_m: settings.field.base_alt_m,
                    cell_size_m: field.cell_size_m(),
                    sensors: sensors.len(),
                    readings: p.store().reading_count().map_err(app::AppError::from)?,
                    latest_reading: app::newest_reading(p)?.map(app::format_rfc3339),
                    missions: app::missions(p)?.len(),
                    weights: [u.alpha, u.beta, u.gamma, u.delta],
                    energy_preset: settings.energy.preset.clone(),
                    solver: settings.planner.solver.clone(),
                    time_limit_s: settings.planner.time_limit_s,
                    max_time_limit_s,
                    seed: settings.planner.seed,
                    basemap_url: basemap_url.clone(),
                    writable,
                    max_upload_bytes,
                })
            },
        )
        .await?;
    Ok(json_response(bytes))
}

/// The field for maps: cells with their squares and latest scores, sensors, base
/// (`gleaner.field` version 1).
#[utoipa::path(get, path = "/api/v1/field", tag = "project",
    responses((status = 200, body = FieldDoc), (status = 500, body = ErrorBody)))]
pub async fn field(State(s): State<AppState>) -> ApiResult<Response> {
    // Reads no mission: kept by a plan that stores no scoring, a cancellation, a deletion.
    let bytes = s
        .cached_eager("field", Changes::CELLS.and(Changes::DATA), |p, inputs| {
            to_json(&gleaner_wire::convert::field(inputs.field_view(p)?))
        })
        .await?;
    Ok(json_response(bytes))
}

/// Serialises a document.
fn to_json<T: serde::Serialize>(doc: &T) -> ApiResult<Vec<u8>> {
    serde_json::to_vec(doc).map_err(|e| ApiError::internal(format!("serialising: {e}")))
}

/// A JSON response from serialised bytes.
fn json_response(bytes: Bytes) -> Response {
    let mut r = bytes.into_response();
    r.headers_mut().insert(
        header::CONTENT_TYPE,
        HeaderValue::from_static("application/json"),
    );
    r
}

/// The cell table with its metadata, by cell id (as `gleaner cells --json`).
#[utoipa::path(get, path = "/api/v1/cells", tag = "project",
    responses((status = 200, body = Vec<CellRowDoc>), (status = 500, body = ErrorBody)))]
pub async fn cells(State(s): State<AppState>) -> ApiResult<Response> {
    // Reads no mission (the cells' description only): kept by a cancellation or a deletion;
    // a stored plan changes it (it stores its scoring and expected energies).
    let bytes = s
        .cached_eager("cells", Changes::CELLS.and(Changes::DATA), |p, inputs| {
            let view = inputs.field_view(p)?;
            let rows: Vec<CellRowDoc> = view
                .cells
                .iter()
                .map(|c| gleaner_wire::convert::cell_row(c, view.cell_size_m))
                .collect();
            to_json(&rows)
        })
        .await?;
    Ok(json_response(bytes))
}

/// How much of a cell's series to return.
#[derive(Debug, Deserialize, IntoParams)]
#[into_params(parameter_in = Query)]
#[serde(deny_unknown_fields)]
pub struct SeriesQuery {
    /// Days of readings before the cell's newest one, in [0, 3660] [default: 30].
    pub days: Option<f64>,
}

/// One cell: its row, the weighted terms of S and its rank (why it ranks where it does),
/// and its sensors' recent readings.
#[utoipa::path(get, path = "/api/v1/cells/{cell}", tag = "project",
    params(("cell" = String, Path, description = "Cell id, e.g. x3y-1"), SeriesQuery),
    responses((status = 200, body = CellDetailDoc), (status = 400, body = ErrorBody),
        (status = 404, body = ErrorBody)))]
pub async fn cell(
    State(s): State<AppState>,
    Path(id): Path<String>,
    RawQuery(q): RawQuery,
) -> ApiResult<Json<CellDetailDoc>> {
    let index = cell_index(&id)?;
    let days = query::<SeriesQuery>(q)?.days.unwrap_or(30.0);
    if !(days.is_finite() && (0.0..=3660.0).contains(&days)) {
        return Err(ApiError::bad_request(
            Some("days"),
            format!("days = {days}: expected a number in [0, 3660]"),
        ));
    }
    let doc = s
        .run(move |p| {
            let d = app::cell_detail(p, index, (days * 86_400.0) as i64)?;
            Ok(CellDetailDoc::from_app(&d, p.settings().field.cell_size_m))
        })
        .await?;
    Ok(Json(doc))
}

/// Scores every cell at a mission time and (unless `dry_run`) keeps the scores in the cell
/// metadata table.
#[utoipa::path(post, path = "/api/v1/score", tag = "data", request_body = ScoreBody,
    security((), ("bearer" = [])),
    responses((status = 200, body = ScoringDoc), (status = 400, body = ErrorBody),
        (status = 401, body = ErrorBody), (status = 403, body = ErrorBody),
        (status = 413, body = ErrorBody)))]
pub async fn score(
    State(s): State<AppState>,
    Computing(caller): Computing,
    _: JsonType,
    body: Result<Bytes, BytesRejection>,
) -> ApiResult<Json<ScoringDoc>> {
    let b: ScoreBody = json_body_for(&s, caller, body)?;
    if !b.dry_run {
        caller.require_write(&s)?;
    }
    let at = parse_time("at", b.at.as_deref())?;
    let request = app::ScoreRequest {
        at,
        history: checked_history(
            at,
            parse_time("history_from", b.history_from.as_deref())?,
            parse_time("history_until", b.history_until.as_deref())?,
        )?,
        probabilities: None,
        dry_run: b.dry_run,
    };
    let doc = s
        // A scoring stores the cells' description only.
        .run_write(Changes::CELLS, request.dry_run, move |p| {
            Ok(gleaner_wire::convert::scoring(&app::score(p, &request)?))
        })
        .await?;
    Ok(Json(doc))
}

/// What to reconstruct (as `gleaner reconstruct`): at one time (`at`), or over a range
/// (`from`, `to`, `every_hours`).
#[derive(Debug, Deserialize, IntoParams)]
#[into_params(parameter_in = Query)]
#[serde(deny_unknown_fields)]
pub struct ReconstructQuery {
    /// Estimation time, RFC 3339 UTC or a date [default: the latest known reading]; not with
    /// a range.
    pub at: Option<String>,
    /// A range's first estimation time, RFC 3339 UTC or a date (with `to`).
    pub from: Option<String>,
    /// A range's last estimation time (with `from`), at or after it.
    pub to: Option<String>,
    /// A range's step, hours, > 0 [default: 24]; at most 1,000 times per range.
    pub every_hours: Option<f64>,
    /// A range's columns: only this cell's sensors (e.g. `x3y-1`) [default: every sensor].
    pub cell: Option<String>,
    /// Modality, e.g. `vw@30cm` [default: `vw@30cm`, else the first `vw@...`].
    pub modality: Option<String>,
    /// Observations per estimate, 1..=256 [default: 16].
    pub neighbours: Option<usize>,
    /// `changes` (default: kriging of changes), `dynamic` (the dynamic field model),
    /// `levels` (ordinary kriging of levels) or `simple` (simple kriging of levels).
    pub estimator: Option<String>,
}

/// Most estimation times one range request may ask for.
pub const MAX_RANGE_TIMES: i64 = 1_000;

/// Most estimates (times × sensors) one range request over every sensor may ask for.
pub const MAX_RANGE_ESTIMATES: usize = 100_000;

/// A query's estimator (default: kriging of changes).
fn estimator_of(name: Option<&str>) -> ApiResult<app::Estimator> {
    match name {
        None => Ok(app::Estimator::default()),
        Some(name) => name
            .parse::<app::Estimator>()
            .map_err(|e| ApiError::from(e).in_field("estimator")),
    }
}

/// A query's observations per estimate, checked.
fn neighbours_of(n: Option<usize>) -> ApiResult<Option<usize>> {
    if let Some(n) = n
        && !(1..=MAX_NEIGHBOURS).contains(&n)
    {
        return Err(ApiError::bad_request(
            Some("neighbours"),
            format!("expected 1..={MAX_NEIGHBOURS}, got {n}"),
        ));
    }
    Ok(n)
}

/// A reconstruction at one time or over a range.
#[derive(Debug, serde::Serialize, utoipa::ToSchema)]
#[serde(untagged)]
pub enum ReconstructAnswer {
    /// At one time: `gleaner.reconstruction`.
    At(ReconstructionDoc),
    /// Over a range: `gleaner.reconstruction-series`.
    Range(ReconstructionSeriesDoc),
}

/// Every sensor's estimated value and standard deviation of one modality from the readings
/// known then: at one time (`gleaner.reconstruction`, as `gleaner reconstruct --json`), or
/// with `from`, `to` and `every_hours` at each time of a range, with 90% intervals
/// (`gleaner.reconstruction-series`, as `gleaner reconstruct --from --to --json`: one fit on
/// the readings up to `to`; each time uses only the readings stamped at or before it).
/// Reads only.
#[utoipa::path(get, path = "/api/v1/reconstruct", tag = "data", params(ReconstructQuery),
    security((), ("bearer" = [])),
    responses((status = 200, body = ReconstructAnswer,
            description = "`gleaner.reconstruction` at one time, `gleaner.reconstruction-series` over a range"),
        (status = 400, body = ErrorBody), (status = 401, body = ErrorBody),
        (status = 404, body = ErrorBody), (status = 500, body = ErrorBody)))]
pub async fn reconstruct(
    State(s): State<AppState>,
    _: Computing,
    RawQuery(q): RawQuery,
) -> ApiResult<Json<ReconstructAnswer>> {
    let q: ReconstructQuery = query(q)?;
    let estimator = estimator_of(q.estimator.as_deref())?;
    let neighbours = neighbours_of(q.neighbours)?;
    let has_modality = q.modality.is_some();
    let in_modality = move |e: ApiError| match has_modality {
        true => e.in_field("modality"),
        false => e,
    };
    let range = (q.from.is_some() || q.to.is_some() || q.every_hours.is_some() || q.cell.is_some())
        .then(|| range_request(&q, estimator, neighbours))
        .transpose()?;
    if let Some(request) = range {
        let every_cell = request.cell.is_none();
        let doc = s
            .run_job(Job::read("reconstruct"), move |p, _| {
                let times = ((request.to - request.from) / request.every_s + 1) as usize;
                let sensors = p.sensors()?.len();
                if every_cell && times.saturating_mul(sensors) > MAX_RANGE_ESTIMATES {
                    return Err(ApiError::bad_request(
                        Some("to"),
                        format!(
                            "{times} times × {sensors} sensors = {} estimates: at most {MAX_RANGE_ESTIMATES} per request (ask for one `cell`, a longer `every_hours` or a shorter range)",
                            times * sensors
                        ),
                    ));
                }
                Ok(gleaner_wire::convert::reconstruction_series(
                    &app::reconstruct_series(p, &request)?,
                ))
            })
            .await
            // Without a modality, what the range's readings cannot give is the range's fault
            // (e.g. no readings at or before its end).
            .map_err(|e| in_modality(e).in_field("to"))?;
        return Ok(Json(ReconstructAnswer::Range(doc)));
    }
    let request = app::ReconstructRequest {
        at: parse_time("at", q.at.as_deref())?,
        modality: q.modality,
        neighbours,
        estimator,
    };
    let doc = s
        .run_job(Job::read("reconstruct"), move |p, _| {
            Ok(gleaner_wire::convert::reconstruction(&app::reconstruct(
                p, &request,
            )?))
        })
        .await
        .map_err(in_modality)?;
    Ok(Json(ReconstructAnswer::At(doc)))
}

/// A range query checked: both ends given, in order, a positive step, at most
/// [`MAX_RANGE_TIMES`] times; no `at` beside it. Errors name the field at fault.
fn range_request(
    q: &ReconstructQuery,
    estimator: app::Estimator,
    neighbours: Option<usize>,
) -> ApiResult<app::ReconstructSeriesRequest> {
    if q.at.is_some() {
        return Err(ApiError::bad_request(
            Some("at"),
            "a range (`from`, `to`) has no `at`: give one or the other",
        ));
    }
    let from = parse_time("from", q.from.as_deref())?
        .ok_or_else(|| ApiError::bad_request(Some("from"), "a range needs `from` and `to`"))?;
    let to = parse_time("to", q.to.as_deref())?
        .ok_or_else(|| ApiError::bad_request(Some("to"), "a range needs `from` and `to`"))?;
    if to < from {
        return Err(ApiError::bad_request(
            Some("to"),
            "the range ends before it starts (`to` before `from`)",
        ));
    }
    let every_hours = q.every_hours.unwrap_or(24.0);
    if !(every_hours.is_finite() && every_hours > 0.0 && every_hours <= 24.0 * 3660.0) {
        return Err(ApiError::bad_request(
            Some("every_hours"),
            format!("every_hours = {every_hours}: expected a number of hours in (0, 87840]"),
        ));
    }
    let every_s = ((every_hours * 3600.0).round() as i64).max(1);
    let times = (to - from) / every_s + 1;
    if times > MAX_RANGE_TIMES {
        return Err(ApiError::bad_request(
            Some("to"),
            format!(
                "{times} estimation times from `from` to `to` every {every_hours} h: at most {MAX_RANGE_TIMES} per request (a longer `every_hours`, or a shorter range)"
            ),
        ));
    }
    let cell = q.cell.as_deref().map(cell_index).transpose()?;
    Ok(app::ReconstructSeriesRequest {
        from,
        to,
        every_s,
        modality: q.modality.clone(),
        estimator,
        neighbours,
        cell,
    })
}

/// Which reconstruction the map shows (as `gleaner reconstruct --at T --map F`).
#[derive(Debug, Deserialize, IntoParams)]
#[into_params(parameter_in = Query)]
#[serde(deny_unknown_fields)]
pub struct ReconstructMapQuery {
    /// Estimation time, RFC 3339 UTC or a date [default: the latest known reading].
    pub at: Option<String>,
    /// Modality, e.g. `vw@30cm` [default: `vw@30cm`, else the first `vw@...`].
    pub modality: Option<String>,
    /// Observations per estimate, 1..=256 [default: 16].
    pub neighbours: Option<usize>,
    /// `changes` (default), `dynamic`, `levels` or `simple`.
    pub estimator: Option<String>,
}

/// The reconstruction map for a query: SVG text, or with `png` the PNG at 300 dpi.
async fn reconstruction_map(s: &AppState, q: Option<String>, png: bool) -> ApiResult<Vec<u8>> {
    let q: ReconstructMapQuery = query(q)?;
    let request = app::ReconstructMapRequest {
        reconstruct: app::ReconstructRequest {
            at: parse_time("at", q.at.as_deref())?,
            modality: q.modality,
            neighbours: neighbours_of(q.neighbours)?,
            estimator: estimator_of(q.estimator.as_deref())?,
        },
        read_within_s: None,
    };
    let has_modality = request.reconstruct.modality.is_some();
    s.run_job(Job::read("reconstruct"), move |p, _| {
        let m = app::reconstruct_map(p, &request)?;
        let svg = gleaner_render::reconstruction_map_svg(
            &gleaner_wire::convert::reconstruction_map(&m),
            &reconstruction_map_options(),
        )
        .map_err(|e| ApiError::internal(e.to_string()))?;
        if !png {
            return Ok(svg.into_bytes());
        }
        gleaner_render::svg_to_png(
            &svg,
            gleaner_render::png_width_px(gleaner_render::FULL_WIDTH_MM, 300.0),
        )
        .map_err(|e| ApiError::internal(e.to_string()))
    })
    .await
    .map_err(|e| match has_modality {
        true => e.in_field("modality"),
        false => e,
    })
}

/// The reconstruction map's size: the full page width of a paper (as the CLI's `--map`).
fn reconstruction_map_options() -> gleaner_render::FigureOptions {
    gleaner_render::FigureOptions {
        width_mm: gleaner_render::FULL_WIDTH_MM,
        ..Default::default()
    }
}

/// The map of the estimated field and its uncertainty at one time (as `gleaner reconstruct
/// --at T --map F.svg`): two panels — each cell's estimate and its posterior sd, colour bars
/// in the modality's unit — sensors read then as dark discs, those only estimated as white
/// diamonds, the field's outline, a scale bar and a north arrow. Reads only.
#[utoipa::path(get, path = "/api/v1/reconstruct/map.svg", tag = "data", params(ReconstructMapQuery),
    security((), ("bearer" = [])),
    responses((status = 200, description = "SVG", content_type = "image/svg+xml"),
        (status = 400, body = ErrorBody), (status = 401, body = ErrorBody),
        (status = 500, body = ErrorBody)))]
pub async fn reconstruct_map_svg(
    State(s): State<AppState>,
    _: Computing,
    RawQuery(q): RawQuery,
) -> ApiResult<Response> {
    let bytes = reconstruction_map(&s, q, false).await?;
    Ok(image_response(bytes, "image/svg+xml"))
}

/// Bytes with their media type.
fn image_response(bytes: Vec<u8>, media: &'static str) -> Response {
    let mut r = bytes.into_response();
    r.headers_mut()
        .insert(header::CONTENT_TYPE, HeaderValue::from_static(media));
    r
}

/// The same map as PNG, 300 dpi at the full page width.
#[utoipa::path(get, path = "/api/v1/reconstruct/map.png", tag = "data", params(ReconstructMapQuery),
    security((), ("bearer" = [])),
    responses((status = 200, description = "PNG", content_type = "image/png"),
        (status = 400, body = ErrorBody), (status = 401, body = ErrorBody),
        (status = 500, body = ErrorBody)))]
pub async fn reconstruct_map_png(
    State(s): State<AppState>,
    _: Computing,
    RawQuery(q): RawQuery,
) -> ApiResult<Response> {
    let bytes = reconstruction_map(&s, q, true).await?;
    Ok(image_response(bytes, "image/png"))
}

/// Most missions one simulation request may fly in all (missions × strategies × seeds ×
/// budgets): about a minute of CPU on CAF-sized farms.
pub const MAX_SIMULATED_MISSIONS: usize = 5_000;

/// Replays the served project's own record as a campaign (`gleaner simulate --project`):
/// each strategy flies the same missions from the same history, each run its own in-memory
/// copy; the answer compares them (error after the flights, events caught and how soon,
/// energy, with 95% intervals when the campaign spans 10 weeks or more); with
/// `"report": true` also its report (Markdown and SVG charts, as `gleaner simulate` writes).
/// Reads only; one simulation or planning search at a time.
#[utoipa::path(post, path = "/api/v1/simulate", tag = "data", request_body = SimulateBody,
    responses((status = 200, body = SimulationDoc), (status = 400, body = ErrorBody),
        (status = 413, body = ErrorBody)))]
pub async fn simulate(
    State(s): State<AppState>,
    _: Computing,
    _: JsonType,
    body: Result<Bytes, BytesRejection>,
) -> ApiResult<Json<SimulationDoc>> {
    // The request as given, quoted by the report to reproduce it.
    let request = match &body {
        Ok(bytes) => String::from_utf8_lossy(bytes).trim().to_string(),
        Err(_) => String::new(),
    };
    let b: SimulateBody = json_body(body)?;
    let with_report = b.report;
    let flight = simulated_weather(&b)?;
    let observed = b.winds.is_some();
    let defaults = gleaner_campaign::campaign::ReplayOptions::default();
    let names = b.strategies.unwrap_or_else(|| {
        ["gleaner", "round-robin", "freshness"]
            .map(String::from)
            .to_vec()
    });
    let strategies = gleaner_campaign::campaign::Strategy::parse_list(&names)
        .map_err(|e| ApiError::from(e).in_field("strategies"))?;
    let every_hours = b.every_hours.unwrap_or(defaults.every_s as f64 / 3_600.0);
    if !(every_hours > 0.0 && every_hours <= 8_760.0) {
        return Err(ApiError::bad_request(
            Some("every_hours"),
            format!("expected hours in (0, 8760], got {every_hours}"),
        ));
    }
    let seeds = b.seeds.unwrap_or_else(|| defaults.seeds.clone());
    if seeds.is_empty() || seeds.len() > 10 {
        return Err(ApiError::bad_request(
            Some("seeds"),
            format!("expected 1 to 10 seeds, got {}", seeds.len()),
        ));
    }
    let budgets = b.budgets.unwrap_or_else(|| defaults.budgets.clone());
    if budgets.is_empty() || budgets.len() > 10 || !budgets.iter().all(|&x| x > 0.0 && x <= 10.0) {
        return Err(ApiError::bad_request(
            Some("budgets"),
            "expected 1 to 10 budgets, each in (0, 10]",
        ));
    }
    let planner_iterations = b.planner_iterations.unwrap_or(defaults.planner_iterations);
    if !(1..=10_000).contains(&planner_iterations) {
        return Err(ApiError::bad_request(
            Some("planner_iterations"),
            format!("expected 1..=10000, got {planner_iterations}"),
        ));
    }
    let energy_preset = energy_preset(b.energy_preset.as_deref())?;
    let options = gleaner_campaign::campaign::ReplayOptions {
        history_until: parse_time("history_until", b.history_until.as_deref())?,
        start: parse_time("start", b.start.as_deref())?,
        end: parse_time("end", b.end.as_deref())?,
        every_s: (every_hours * 3_600.0).round() as i64,
        strategies,
        seeds,
        budgets,
        planner_iterations,
        energy_preset,
        flight,
        ..defaults
    };
    let simulation = Job {
        kind: "simulate",
        planning: true,
        writes: Changes::NOTHING,
    };
    let doc = s
        .run_job(simulation, move |p, cancel| {
            let parts = gleaner_campaign::ProjectRecord::read(p)?.into_parts(p.dir());
            let replay = gleaner_campaign::campaign::replay(parts, &options, clock_now())?;
            if observed {
                // Every mission's day must have its wind: a gap names the field.
                replay
                    .request
                    .flight
                    .check(&replay.request.schedule)
                    .map_err(|e| ApiError::from(e).in_field("winds"))?;
            }
            let missions = replay.request.mission_runs();
            if missions > MAX_SIMULATED_MISSIONS {
                return Err(ApiError::bad_request(
                    Some("start"),
                    format!(
                        "{missions} missions in all (missions × strategies × seeds × budgets): \
                         at most {MAX_SIMULATED_MISSIONS} per request; shorten the period or \
                         name fewer strategies (the command line's simulate has no limit)"
                    ),
                ));
            }
            let result =
                gleaner_campaign::campaign::run_campaign(&replay.request, &replay.truth, cancel)?;
            let mut doc = gleaner_campaign::doc::campaign_doc(
                &gleaner_campaign::campaign::campaign_summary(&replay.request, &result),
            );
            if !replay.request.flight.is_still() {
                doc.flights = gleaner_campaign::doc::flights(
                    &gleaner_campaign::campaign_flight::flight_summaries(std::slice::from_ref(
                        &result,
                    )),
                );
            }
            let report = match with_report {
                true => Some(report_doc(
                    gleaner_campaign::report::render_report(
                        std::slice::from_ref(&result),
                        &format!("POST /api/v1/simulate {request}"),
                    )
                    .map_err(|e| match e {
                        gleaner_campaign::Error::App(e) => ApiError::from(e),
                        e => ApiError::internal(format!("the campaign's report: {e}")),
                    })?,
                )),
                false => None,
            };
            Ok(SimulationDoc {
                campaign: doc,
                report,
            })
        })
        .await?;
    Ok(Json(doc))
}

/// A rendered campaign report as the API answers it.
fn report_doc(r: gleaner_campaign::report::RenderedReport) -> ReportDoc {
    ReportDoc {
        markdown: r.markdown,
        figures: r
            .figures
            .into_iter()
            .map(|(name, svg)| crate::api::FigureDoc { name, svg })
            .collect(),
    }
}

/// The weather a simulation's flights meet, from its body (as `simulate --wind`, `--gust`,
/// `--leg-gust`, `--weak-battery`, `--weather-seed`, `--margin-quantile`); each value checked
/// on its own so that a refusal names its field.
fn simulated_weather(
    b: &SimulateBody,
) -> ApiResult<gleaner_campaign::campaign_flight::FlightConditions> {
    use gleaner_campaign::campaign_flight::{DEFAULT_GUST_SD_MPS, FlightConditions, WindSource};
    let wind = match (&b.wind, &b.winds) {
        (Some(_), Some(_)) => {
            return Err(ApiError::bad_request(
                Some("winds"),
                "give either `wind` (a drawn wind) or `winds` (observed days), not both",
            ));
        }
        (_, Some(days)) => WindSource::Observed {
            path: PathBuf::from("winds"),
            days: observed_winds(days)?,
        },
        (Some(text), None) => {
            WindSource::parse(text).map_err(|e| ApiError::from(e).in_field("wind"))?
        }
        (None, None) => WindSource::Still,
    };
    let still = FlightConditions::default();
    let gust_sd_mps = b.gust.unwrap_or(if wind == WindSource::Still {
        0.0
    } else {
        DEFAULT_GUST_SD_MPS
    });
    let one = |field: &str, c: FlightConditions| {
        c.check(&[])
            .map_err(|e| ApiError::from(e).in_field(field))
            .map(|_| ())
    };
    one(
        "gust",
        FlightConditions {
            gust_sd_mps,
            ..still.clone()
        },
    )?;
    let leg_gust_sd_mps = b.leg_gust.unwrap_or(0.0);
    one(
        "leg_gust",
        FlightConditions {
            leg_gust_sd_mps,
            ..still.clone()
        },
    )?;
    let battery_weakening = b.weak_battery.unwrap_or(0.0);
    one(
        "weak_battery",
        FlightConditions {
            battery_weakening,
            ..still.clone()
        },
    )?;
    let margin_quantile = Some(
        b.margin_quantile
            .unwrap_or(gleaner_campaign::campaign_flight::DEFAULT_MARGIN_QUANTILE),
    );
    one(
        "margin_quantile",
        FlightConditions {
            margin_quantile,
            ..still
        },
    )?;
    Ok(FlightConditions {
        wind,
        gust_sd_mps,
        battery_weakening,
        seed: b.weather_seed.unwrap_or(1),
        leg_gust_sd_mps,
        margin_quantile,
    })
}

/// Most days of observed wind one simulation request may give.
const MAX_WIND_DAYS: usize = 36_600;

/// A simulation's observed daily winds, checked as `simulate --wind-csv` checks its file;
/// each refusal names the entry's field (`winds[3].speed_mps`).
fn observed_winds(
    days: &[WindDayBody],
) -> ApiResult<Vec<gleaner_campaign::campaign_flight::DailyWind>> {
    use gleaner_app::wind::MAX_WIND_MPS;
    if days.is_empty() || days.len() > MAX_WIND_DAYS {
        return Err(ApiError::bad_request(
            Some("winds"),
            format!(
                "expected 1 to {MAX_WIND_DAYS} days of wind, got {}",
                days.len()
            ),
        ));
    }
    let mut out = Vec::with_capacity(days.len());
    for (k, d) in days.iter().enumerate() {
        let field = |name: &str| format!("winds[{k}].{name}");
        let day = app::parse_timestamp(&d.date)
            .filter(|t| t.rem_euclid(86_400) == 0 && d.date.trim().len() == 10)
            .ok_or_else(|| {
                ApiError::bad_request(
                    Some(&field("date")),
                    format!("expected a date YYYY-MM-DD (UTC), got {:?}", d.date),
                )
            })?;
        let number = |x: f64, name: &str, hi: f64, unit: &str| {
            if x.is_finite() && (0.0..=hi).contains(&x) {
                Ok(x)
            } else {
                Err(ApiError::bad_request(
                    Some(&field(name)),
                    format!("expected a number in [0, {hi}] {unit}, got {x}"),
                ))
            }
        };
        let speed_mps = number(d.speed_mps, "speed_mps", MAX_WIND_MPS, "m/s")?;
        let from_deg = number(d.from_deg, "from_deg", 360.0, "degrees")?;
        out.push(gleaner_campaign::campaign_flight::DailyWind {
            day,
            speed_mps,
            from_deg: if from_deg == 360.0 { 0.0 } else { from_deg },
            line: k,
        });
    }
    out.sort_by_key(|d| (d.day, d.line));
    if let Some(w) = out.windows(2).find(|w| w[0].day == w[1].day) {
        return Err(ApiError::bad_request(
            Some(&format!("winds[{}].date", w[1].line)),
            format!(
                "{}: given twice (also winds[{}])",
                &app::format_rfc3339(w[1].day)[..10],
                w[0].line
            ),
        ));
    }
    Ok(out)
}

/// Most observations per estimate a request may ask for (the kriging system is this size).
const MAX_NEIGHBOURS: usize = 256;

/// All missions (planned and flown), oldest first (`gleaner.mission` documents).
#[utoipa::path(get, path = "/api/v1/missions", tag = "missions",
    responses((status = 200, body = Vec<MissionDoc>), (status = 500, body = ErrorBody)))]
pub async fn missions(State(s): State<AppState>) -> ApiResult<Json<Vec<MissionDoc>>> {
    let docs = s
        .run(|p| {
            Ok(app::missions(p)?
                .iter()
                .map(gleaner_wire::convert::stored_mission)
                .collect())
        })
        .await?;
    Ok(Json(docs))
}

/// Which page of the mission history: `limit` missions below `before`, newest first.
#[derive(Debug, Deserialize, IntoParams)]
#[into_params(parameter_in = Query)]
#[serde(deny_unknown_fields)]
pub struct MissionsPageQuery {
    /// Most missions on the page, 1 to 500 [default: 20].
    pub limit: Option<usize>,
    /// Only missions with an id below this one (the `next` of the previous page)
    /// [default: from the newest].
    pub before: Option<i64>,
}

/// One page of the mission history, newest first.
#[derive(Debug, Serialize, ToSchema)]
pub struct MissionsPageDoc {
    /// The missions, in descending id order.
    pub missions: Vec<MissionDoc>,
    /// The `before` of the next (older) page; null on the last page.
    pub next: Option<i64>,
}

/// A page of the mission history, newest first, in a stable order (by id): `next` is the
/// `before` of the following page, null on the last one. A mission planned while paging
/// appears on no later page.
#[utoipa::path(get, path = "/api/v1/missions/page", tag = "missions", params(MissionsPageQuery),
    responses((status = 200, body = MissionsPageDoc), (status = 400, body = ErrorBody)))]
pub async fn missions_page(
    State(s): State<AppState>,
    RawQuery(q): RawQuery,
) -> ApiResult<Json<MissionsPageDoc>> {
    let q = query::<MissionsPageQuery>(q)?;
    let limit = q.limit.unwrap_or(20);
    if !(1..=app::missions::MAX_PAGE).contains(&limit) {
        return Err(ApiError::bad_request(
            Some("limit"),
            format!(
                "limit = {limit}: a page holds 1 to {} missions",
                app::missions::MAX_PAGE
            ),
        ));
    }
    if let Some(b) = q.before
        && b < 1
    {
        return Err(ApiError::bad_request(
            Some("before"),
            format!("before = {b}: mission ids start at 1"),
        ));
    }
    let before = q.before.map(MissionId);
    let doc = s
        .run(move |p| {
            let page = app::missions_page(p, before, limit)?;
            Ok(MissionsPageDoc {
                missions: page
                    .missions
                    .iter()
                    .map(gleaner_wire::convert::stored_mission)
                    .collect(),
                next: page.next.map(|m| m.0),
            })
        })
        .await?;
    Ok(Json(doc))
}

/// Cancels a planned mission: it stays in the history with status `cancelled` and can no
/// longer be recorded, exported or re-planned. 409 when it was already flown or cancelled.
#[utoipa::path(post, path = "/api/v1/missions/{id}/cancel", tag = "missions",
    params(("id" = i64, Path, description = "Mission id")),
    security(("bearer" = [])),
    responses((status = 200, body = MissionDoc), (status = 400, body = ErrorBody),
        (status = 401, body = ErrorBody), (status = 403, body = ErrorBody),
        (status = 404, body = ErrorBody), (status = 409, body = ErrorBody)))]
pub async fn cancel_mission(
    State(s): State<AppState>,
    _: Writing,
    Path(id): Path<String>,
) -> ApiResult<Json<MissionDoc>> {
    let id = mission_id(&id)?;
    let doc = s
        .run_write(Changes::MISSIONS, false, move |p| {
            Ok(gleaner_wire::convert::stored_mission(&app::cancel_mission(
                p, id,
            )?))
        })
        .await?;
    Ok(Json(doc))
}

/// Deletes a mission that has no recorded flight (planned or cancelled), with its stops.
/// 409 for a flown mission: its record is the provenance of stored readings. 204 when done.
#[utoipa::path(delete, path = "/api/v1/missions/{id}", tag = "missions",
    params(("id" = i64, Path, description = "Mission id")),
    security(("bearer" = [])),
    responses((status = 204, description = "Deleted"), (status = 400, body = ErrorBody),
        (status = 401, body = ErrorBody), (status = 403, body = ErrorBody),
        (status = 404, body = ErrorBody), (status = 409, body = ErrorBody)))]
pub async fn delete_mission(
    State(s): State<AppState>,
    _: Writing,
    Path(id): Path<String>,
) -> ApiResult<StatusCode> {
    let id = mission_id(&id)?;
    s.run_write(Changes::MISSIONS, false, move |p| {
        Ok(app::delete_mission(p, id)?)
    })
    .await?;
    Ok(StatusCode::NO_CONTENT)
}

/// One mission with its stops and energy breakdown.
#[utoipa::path(get, path = "/api/v1/missions/{id}", tag = "missions",
    params(("id" = i64, Path, description = "Mission id")),
    responses((status = 200, body = MissionDoc), (status = 400, body = ErrorBody),
        (status = 404, body = ErrorBody)))]
pub async fn mission(State(s): State<AppState>, Path(id): Path<String>) -> ApiResult<Response> {
    let id = mission_id(&id)?;
    let bytes = s
        .cached(&format!("mission/{}", id.0), move |p| {
            to_json(&gleaner_wire::convert::stored_mission(&app::mission(
                p, id,
            )?))
        })
        .await?;
    Ok(json_response(bytes))
}

/// Plans a mission: scores the cells, chooses and orders those that fit the battery, and
/// (unless `dry_run`) stores it. One planning search runs at a time; reads are never held up.
#[utoipa::path(post, path = "/api/v1/plan", tag = "missions", request_body = PlanBody,
    security((), ("bearer" = [])),
    responses((status = 200, body = MissionDoc), (status = 400, body = ErrorBody),
        (status = 401, body = ErrorBody), (status = 403, body = ErrorBody),
        (status = 413, body = ErrorBody)))]
pub async fn plan(
    State(s): State<AppState>,
    Computing(caller): Computing,
    _: JsonType,
    body: Result<Bytes, BytesRejection>,
) -> ApiResult<Json<MissionDoc>> {
    let b: PlanBody = json_body_for(&s, caller, body)?;
    if b.sorties.is_some_and(|k| k != 1) {
        return Err(ApiError::bad_request(
            Some("sorties"),
            "several sorties are planned by POST /api/v1/plan/sorties",
        ));
    }
    let mut docs = plan_request(&s, caller, b).await?;
    Ok(Json(docs.swap_remove(0)))
}

/// Re-plans a mission in the air: the best continuation from the stop the aircraft is over
/// with the energy it has left — the remaining stops dropped and reordered so that it still
/// reaches the base with the battery's reserve — with its `.plan` and WPL files (no
/// take-off; each read back and priced within the energy left less the reserve). Stores
/// nothing: the flight is recorded against the mission itself.
#[utoipa::path(post, path = "/api/v1/missions/{id}/replan", tag = "missions",
    params(("id" = i64, Path, description = "Mission id")),
    request_body = ReplanBody,
    security((), ("bearer" = [])),
    responses((status = 200, body = ReplanDoc), (status = 400, body = ErrorBody),
        (status = 401, body = ErrorBody), (status = 403, body = ErrorBody),
        (status = 404, body = ErrorBody), (status = 413, body = ErrorBody),
        (status = 415, body = ErrorBody)))]
pub async fn replan(
    State(s): State<AppState>,
    _: Computing,
    _: JsonType,
    Path(id): Path<String>,
    body: Result<Bytes, BytesRejection>,
) -> ApiResult<Json<ReplanDoc>> {
    let id = mission_id(&id)?;
    let b: ReplanBody = parse_json(&body_bytes(body)?)?;
    search_limits(&s, b.iterations, b.time_limit_s)?;
    let request = app::ReplanRequest {
        mission: id,
        after_stop: b.after_stop,
        energy_left_j: b.energy_left_j,
        seed: b.seed,
        iterations: b.iterations,
        time_limit_s: b.time_limit_s,
        wind: wind(b.wind)?,
        wind_margin_mps: None,
    };
    let doc = s
        .run(move |p| {
            let r = app::replan(p, &request)?;
            let mission = gleaner_wire::convert::replanned_mission(&r);
            let export_err =
                |e: gleaner_wire::ExportError| ApiError::bad_request(None, e.to_string());
            Ok(ReplanDoc {
                plan: gleaner_wire::qgc_plan(&mission).map_err(export_err)?,
                waypoints: gleaner_wire::wpl(&mission).map_err(export_err)?,
                dropped: r.dropped.iter().map(ToString::to_string).collect(),
                solve_seconds: r.solve_seconds,
                mission,
            })
        })
        .await?;
    Ok(Json(doc))
}

/// Plans several disjoint sorties for one mission day (battery swaps; `sorties` in the body,
/// 1..=20): the team orienteering planner shares the cells among them, each within one
/// battery, and (unless `dry_run`) stores each as its own mission in one transaction. The
/// answer lists them in flying order, as `gleaner plan --sorties K --json` does.
#[utoipa::path(post, path = "/api/v1/plan/sorties", tag = "missions", request_body = PlanBody,
    security((), ("bearer" = [])),
    responses((status = 200, body = Vec<MissionDoc>), (status = 400, body = ErrorBody),
        (status = 401, body = ErrorBody), (status = 403, body = ErrorBody),
        (status = 413, body = ErrorBody)))]
pub async fn plan_sorties(
    State(s): State<AppState>,
    Computing(caller): Computing,
    _: JsonType,
    body: Result<Bytes, BytesRejection>,
) -> ApiResult<Json<Vec<MissionDoc>>> {
    let b: PlanBody = json_body_for(&s, caller, body)?;
    Ok(Json(plan_request(&s, caller, b).await?))
}

/// The plan use case behind both plan routes: checks, one planning search at a time, the
/// mission and any further sorties as wire documents, sortie 1 first (never empty).
/// A request's search limits: an iteration cap of at least 1, a time limit in [0, the
/// server's maximum] seconds.
fn search_limits(
    s: &AppState,
    iterations: Option<u64>,
    time_limit_s: Option<f64>,
) -> ApiResult<()> {
    if iterations == Some(0) {
        return Err(ApiError::bad_request(
            Some("iterations"),
            "iterations = 0: expected at least 1 (or leave it out for no cap)",
        ));
    }
    if let Some(t) = time_limit_s
        && !(t.is_finite() && t >= 0.0 && t <= s.0.max_time_limit_s)
    {
        return Err(ApiError::bad_request(
            Some("time_limit_s"),
            format!(
                "time limit {t} s: expected seconds in [0, {}]",
                s.0.max_time_limit_s
            ),
        ));
    }
    Ok(())
}

/// A request's wind, checked (400 naming `wind`).
fn wind(w: Option<crate::api::WindBody>) -> ApiResult<Option<app::Wind>> {
    w.map(|w| app::wind::forecast(w.speed_mps, w.from_deg, "wind"))
        .transpose()
        .map_err(|e| ApiError::from(e).in_field("wind"))
}

async fn plan_request(s: &AppState, caller: Caller, b: PlanBody) -> ApiResult<Vec<MissionDoc>> {
    if !b.dry_run {
        caller.require_write(s)?;
    }
    search_limits(s, b.iterations, b.time_limit_s)?;
    let planner = b
        .solver
        .as_deref()
        .map(app::parse_planner)
        .transpose()
        .map_err(|e| ApiError::from(e).in_field("solver"))?;
    let at = parse_time("at", b.at.as_deref())?;
    let request = app::PlanRequest {
        at,
        history: checked_history(
            at,
            parse_time("history_from", b.history_from.as_deref())?,
            parse_time("history_until", b.history_until.as_deref())?,
        )?,
        scores: None,
        cell_scores: None,
        planner,
        time_limit_s: b.time_limit_s,
        seed: b.seed,
        max_iterations: b.iterations,
        dry_run: b.dry_run,
        sorties: b.sorties,
        objective: b
            .objective
            .as_deref()
            .map(str::parse::<app::Objective>)
            .transpose()
            .map_err(|e| ApiError::from(e).in_field("objective"))?,
        wind: wind(b.wind)?,
    };
    let preset = energy_preset(b.energy_preset.as_deref())?;
    let job = Job {
        kind: "plan",
        planning: true,
        // The missions, and the scoring at the mission time with each cell's expected
        // collection energy (the cells' description).
        writes: match request.dry_run {
            true => Changes::NOTHING,
            false => Changes::MISSIONS.and(Changes::CELLS),
        },
    };
    s.run_job(job, move |p, _| {
        let planned = app::plan_with_preset(p, &request, preset.as_deref(), clock_now())?;
        let mut docs = vec![gleaner_wire::convert::planned_mission(&planned)];
        docs.extend(planned.extra_sorties.iter().map(|e| {
            let mut doc = gleaner_wire::convert::mission_doc(
                e.id,
                &e.mission,
                if e.id.is_some() { "planned" } else { "dry-run" },
                None,
            );
            doc.wind = Some(gleaner_wire::convert::wind(&e.wind));
            doc
        }));
        Ok(docs)
    })
    .await
}

/// Plans the exploration phase: the fewest budget-feasible sorties that together visit every
/// cell, each stored (unless `dry_run`) as an exploration mission.
#[utoipa::path(post, path = "/api/v1/explore", tag = "missions", request_body = ExploreBody,
    security((), ("bearer" = [])),
    responses((status = 200, body = ExplorationDoc), (status = 400, body = ErrorBody),
        (status = 401, body = ErrorBody), (status = 403, body = ErrorBody)))]
pub async fn explore(
    State(s): State<AppState>,
    Computing(caller): Computing,
    _: JsonType,
    body: Result<Bytes, BytesRejection>,
) -> ApiResult<Json<ExplorationDoc>> {
    let b: ExploreBody = json_body_for(&s, caller, body)?;
    if !b.dry_run {
        caller.require_write(&s)?;
    }
    let request = app::ExploreRequest {
        at: parse_time("at", b.at.as_deref())?,
        dry_run: b.dry_run,
        wind: wind(b.wind)?,
    };
    let job = Job {
        kind: "explore",
        planning: true,
        // Its sorties only.
        writes: match request.dry_run {
            true => Changes::NOTHING,
            false => Changes::MISSIONS,
        },
    };
    let doc = s
        .run_job(job, move |p, _| {
            Ok(gleaner_wire::convert::exploration(&app::explore(
                p,
                &request,
                clock_now(),
            )?))
        })
        .await?;
    Ok(Json(doc))
}

/// The files a mission can be downloaded as: name, media type, what it is.
pub const MISSION_FILES: [(&str, &str, &str); 7] = [
    ("mission.plan", "application/json", "QGroundControl plan"),
    (
        "mission.kmz",
        "application/vnd.google-earth.kmz",
        "DJI WPML mission (follows DJI's published reference; not flown)",
    ),
    (
        "mission.waypoints",
        "text/plain; charset=utf-8",
        "QGC WPL 110 waypoints",
    ),
    (
        "mission.geojson",
        "application/geo+json",
        "GeoJSON: cells, route, base",
    ),
    (
        "mission.json",
        "application/json",
        "the gleaner.mission document",
    ),
    ("mission.svg", "image/svg+xml", "the mission map"),
    ("mission.png", "image/png", "the mission map, 1600 px wide"),
];

/// A mission's file for its ground station or report, made in memory from the checked export
/// (no path on disk is ever read, so no request can reach outside the project). Refused (400)
/// for a mission that is not safe to fly.
#[utoipa::path(get, path = "/api/v1/missions/{id}/files/{name}", tag = "missions",
    params(("id" = i64, Path, description = "Mission id"),
        ("name" = String, Path, description = "mission.plan, mission.kmz, mission.waypoints, mission.geojson, mission.json, mission.svg or mission.png")),
    responses((status = 200, description = "The file, as an attachment named `mission-{id}.plan`, `.kmz`, `.waypoints`, `.geojson`, `.json`, `.svg` or `.png`, of its own media type",
            content(
                (serde_json::Value = "application/json"),
                (Vec<u8> = "application/vnd.google-earth.kmz"),
                (String = "text/plain; charset=utf-8"),
                (serde_json::Value = "application/geo+json"),
                (String = "image/svg+xml"),
                (Vec<u8> = "image/png"))),
        (status = 400, body = ErrorBody), (status = 404, body = ErrorBody)))]
pub async fn mission_file(
    State(s): State<AppState>,
    Path((id, name)): Path<(String, String)>,
) -> ApiResult<Response> {
    let id = mission_id(&id)?;
    let Some(&(name, media, _)) = MISSION_FILES.iter().find(|f| f.0 == name) else {
        return Err(ApiError::not_found(
            Some("name"),
            format!(
                "no mission file {name:?}: expected one of {}",
                MISSION_FILES.map(|f| f.0).join(", ")
            ),
        ));
    };
    let bytes = s
        .run(move |p| {
            let export = app::export(p, id)?;
            let doc = gleaner_wire::convert::export_mission(&export);
            let field = gleaner_wire::convert::field(&export.field);
            let export_err =
                |e: gleaner_wire::ExportError| ApiError::bad_request(None, e.to_string());
            let render_err = |e: gleaner_render::RenderError| ApiError::internal(e.to_string());
            Ok(match name {
                "mission.plan" => gleaner_wire::qgc_plan(&doc)
                    .map_err(export_err)?
                    .into_bytes(),
                "mission.waypoints" => gleaner_wire::wpl(&doc).map_err(export_err)?.into_bytes(),
                "mission.kmz" => {
                    gleaner_wire::wpml_kmz(&doc, Default::default()).map_err(export_err)?
                }
                "mission.geojson" => gleaner_wire::geojson(&field, &doc)
                    .map_err(export_err)?
                    .into_bytes(),
                "mission.json" => serde_json::to_vec_pretty(&doc)
                    .map_err(|e| ApiError::internal(e.to_string()))?,
                "mission.svg" => {
                    gleaner_render::mission_figure_svg(&field, &doc, &Default::default())
                        .map_err(render_err)?
                        .into_bytes()
                }
                _ => {
                    let svg = gleaner_render::mission_figure_svg(&field, &doc, &Default::default())
                        .map_err(render_err)?;
                    gleaner_render::svg_to_png(&svg, 1600).map_err(render_err)?
                }
            })
        })
        .await?;
    let disposition = format!(
        "attachment; filename=\"mission-{}.{}\"",
        id.0,
        name.trim_start_matches("mission.")
    );
    let mut r = bytes.into_response();
    let h = r.headers_mut();
    h.insert(header::CONTENT_TYPE, HeaderValue::from_static(media));
    if let Ok(v) = HeaderValue::from_str(&disposition) {
        h.insert(header::CONTENT_DISPOSITION, v);
    }
    Ok(r)
}

/// The serialised OpenAPI document, made once when the router is built.
#[derive(Clone)]
pub struct OpenApiJson(pub std::sync::Arc<str>);

/// This API's OpenAPI 3.1 document (this endpoint included).
#[utoipa::path(get, path = "/api/v1/openapi.json", tag = "project",
    responses((status = 200, description = "The OpenAPI document", body = serde_json::Value,
        content_type = "application/json")))]
pub async fn openapi_json(axum::Extension(doc): axum::Extension<OpenApiJson>) -> Response {
    let mut r = doc.0.to_string().into_response();
    r.headers_mut().insert(
        header::CONTENT_TYPE,
        HeaderValue::from_static("application/json"),
    );
    r
}

/// Which mission the map shows.
#[derive(Debug, Deserialize, IntoParams)]
#[into_params(parameter_in = Query)]
#[serde(deny_unknown_fields)]
pub struct MapQuery {
    /// Mission id [default: the newest mission; none: the field alone].
    pub mission: Option<i64>,
}

fn svg_response(svg: String) -> Response {
    let mut r = svg.into_response();
    r.headers_mut().insert(
        header::CONTENT_TYPE,
        HeaderValue::from_static("image/svg+xml"),
    );
    r
}

/// Dashboard map size: the full page width of a paper, so the map's text stays small on a
/// screen.
fn map_options() -> gleaner_render::FigureOptions {
    gleaner_render::FigureOptions {
        width_mm: 178.0,
        ..Default::default()
    }
}

/// The map the CLI's export draws (cells coloured by S, `<path id="cell-K">` for the K-th
/// cell of `/field`, the route with visiting order, the energy table), for a stored mission.
#[utoipa::path(get, path = "/api/v1/map.svg", tag = "missions", params(MapQuery),
    responses((status = 200, description = "SVG", content_type = "image/svg+xml"),
        (status = 400, body = ErrorBody), (status = 404, body = ErrorBody)))]
pub async fn map(State(s): State<AppState>, RawQuery(q): RawQuery) -> ApiResult<Response> {
    let which = query::<MapQuery>(q)?.mission;
    let svg = s
        .run(move |p| {
            let field = gleaner_wire::convert::field(&app::field_view(p)?);
            let mission = match which {
                Some(id) => Some(app::mission(p, MissionId(id))?),
                None => app::missions(p)?.pop(),
            };
            let svg = match mission {
                Some(m) => {
                    // The route as flown: through the turn points around the no-fly zones.
                    let mut doc = gleaner_wire::convert::stored_mission(&m);
                    gleaner_wire::convert::set_via(&mut doc, &app::airspace::stored_via(p, &m));
                    gleaner_render::mission_figure_svg(&field, &doc, &map_options())
                }
                None => gleaner_render::exploration_map_svg(&field, &[], &map_options()),
            };
            svg.map_err(|e| ApiError::internal(e.to_string()))
        })
        .await?;
    Ok(svg_response(svg))
}

/// The same map for a mission that is not stored (a dry run's `gleaner.mission` document),
/// over the project's field: the dashboard's preview before saving. Writes nothing.
#[utoipa::path(post, path = "/api/v1/map.svg", tag = "missions", request_body = MissionDoc,
    responses((status = 200, description = "SVG", content_type = "image/svg+xml"),
        (status = 400, body = ErrorBody), (status = 413, body = ErrorBody)))]
pub async fn map_of(
    State(s): State<AppState>,
    _: Computing,
    _: JsonType,
    body: Result<Bytes, BytesRejection>,
) -> ApiResult<Response> {
    let doc: MissionDoc = json_body(body)?;
    let svg = s
        .run(move |p| {
            let field = gleaner_wire::convert::field(&app::field_view(p)?);
            gleaner_render::mission_figure_svg(&field, &doc, &map_options())
                .map_err(|e| ApiError::bad_request(Some("body"), e.to_string()))
        })
        .await?;
    Ok(svg_response(svg))
}

/// Multipart form parts of an upload: the files (saved into a temporary folder under
/// sanitised names) and the text fields.
struct Upload {
    _dir: tempfile::TempDir,
    files: Vec<PathBuf>,
    /// The client's name of each file (its last path component).
    names: Vec<String>,
    fields: Vec<(String, String)>,
}

impl Upload {
    /// Rewrites an error's message to name the client's files, not the temporary copies.
    fn client_names(&self, mut e: ApiError) -> ApiError {
        for (path, name) in self.files.iter().zip(&self.names) {
            e.body.reason = e.body.reason.replace(&path.display().to_string(), name);
        }
        e
    }

    fn field(&self, name: &str) -> Option<&str> {
        self.fields
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.as_str())
    }
}

/// A file name reduced to letters, digits, `.`, `-`, `_` (never a path), prefixed with its
/// position so two uploads of the same name stay apart.
fn safe_name(k: usize, name: &str) -> String {
    let base = name.rsplit(['/', '\\']).next().unwrap_or("");
    let clean: String = base
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || matches!(c, '.' | '-' | '_') {
                c
            } else {
                '_'
            }
        })
        .collect();
    let clean = clean.trim_start_matches('.');
    format!("{k:03}-{}", if clean.is_empty() { "upload" } else { clean })
}

fn multipart_type(r: MultipartRejection) -> ApiError {
    ApiError::unsupported_media_type(format!(
        "this endpoint takes a multipart/form-data upload: {}",
        r.body_text()
    ))
}

fn multipart_error(e: axum::extract::multipart::MultipartError) -> ApiError {
    if e.status() == StatusCode::PAYLOAD_TOO_LARGE {
        ApiError::too_large(
            Some("files"),
            format!("the upload is too large: {}", e.body_text()),
        )
    } else {
        ApiError::bad_request(
            Some("files"),
            format!("bad multipart upload: {}", e.body_text()),
        )
    }
}

/// Reads a whole multipart upload to disk before any use case runs, so an upload cut off or
/// over the limit half-way stores nothing.
async fn read_upload(mut m: Multipart) -> ApiResult<Upload> {
    use tokio::io::AsyncWriteExt as _;
    let dir = tempfile::Builder::new()
        .prefix("gleaner-upload-")
        .tempdir()
        .map_err(|e| ApiError::internal(format!("cannot create a temporary folder: {e}")))?;
    let mut files = Vec::new();
    let mut names = Vec::new();
    let mut fields = Vec::new();
    while let Some(mut part) = m.next_field().await.map_err(multipart_error)? {
        let name = part.name().unwrap_or("").to_string();
        match part.file_name().map(str::to_string) {
            Some(file_name) => {
                let path = dir.path().join(safe_name(files.len(), &file_name));
                let mut out = tokio::fs::File::create(&path)
                    .await
                    .map_err(|e| ApiError::internal(format!("cannot store the upload: {e}")))?;
                while let Some(chunk) = part.chunk().await.map_err(multipart_error)? {
                    out.write_all(&chunk)
                        .await
                        .map_err(|e| ApiError::internal(format!("cannot store the upload: {e}")))?;
                }
                out.flush()
                    .await
                    .map_err(|e| ApiError::internal(format!("cannot store the upload: {e}")))?;
                files.push(path);
                names.push(
                    file_name
                        .rsplit(['/', '\\'])
                        .next()
                        .unwrap_or("")
                        .to_string(),
                );
            }
            None => {
                let text = part.text().await.map_err(multipart_error)?;
                fields.push((name, text));
            }
        }
    }
    Ok(Upload {
        _dir: dir,
        files,
        names,
        fields,
    })
}

fn format_of(text: Option<&str>) -> ApiResult<app::Format> {
    Ok(match text.unwrap_or("auto") {
        "auto" => app::Format::Auto,
        "long-csv" => app::Format::Long,
        "wide-csv" => app::Format::Wide,
        "caf-daily" => app::Format::CafDaily,
        "hubbard-brook" => app::Format::HubbardBrook,
        other => {
            return Err(ApiError::bad_request(
                Some("format"),
                format!(
                    "format {other:?}: expected auto, long-csv, wide-csv, caf-daily or hubbard-brook"
                ),
            ));
        }
    })
}

fn flag(upload: &Upload, name: &str) -> ApiResult<bool> {
    match upload.field(name) {
        None | Some("false") | Some("0") | Some("") => Ok(false),
        Some("true") | Some("1") | Some("on") => Ok(true),
        Some(v) => Err(ApiError::bad_request(
            Some(name),
            format!("{name} = {v:?}: expected true or false"),
        )),
    }
}

/// Ingests uploaded readings files (multipart: one or more `files` parts and optional
/// `format`, `modality`, `unit`, `utc_offset_h`, `on_error` fields), all or nothing.
#[utoipa::path(post, path = "/api/v1/ingest", tag = "data",
    request_body(content_type = "multipart/form-data", description = "files (one part per file); format = auto | long-csv | wide-csv | caf-daily | hubbard-brook; modality; unit; utc_offset_h; on_error = fail | skip"),
    security(("bearer" = [])),
    responses((status = 200, body = IngestDoc), (status = 400, body = ErrorBody),
        (status = 401, body = ErrorBody), (status = 403, body = ErrorBody),
        (status = 413, body = ErrorBody)))]
pub async fn ingest(
    State(s): State<AppState>,
    _: Writing,
    m: Result<Multipart, MultipartRejection>,
) -> ApiResult<Json<IngestDoc>> {
    let m = m.map_err(multipart_type)?;
    let upload = read_upload(m).await?;
    if upload.files.is_empty() {
        return Err(ApiError::bad_request(
            Some("files"),
            "no file in the upload: send one or more `files` parts",
        ));
    }
    let utc_offset_h = match upload.field("utc_offset_h") {
        None | Some("") => 0.0,
        Some(v) => v
            .parse::<f64>()
            .ok()
            .filter(|h| h.is_finite())
            .ok_or_else(|| {
                ApiError::bad_request(
                    Some("utc_offset_h"),
                    format!("utc_offset_h = {v:?}: expected hours"),
                )
            })?,
    };
    let on_error = match upload.field("on_error") {
        None | Some("") | Some("fail") => app::OnError::Fail,
        Some("skip") => app::OnError::Skip,
        Some(v) => {
            return Err(ApiError::bad_request(
                Some("on_error"),
                format!("on_error = {v:?}: expected fail or skip"),
            ));
        }
    };
    let request = app::IngestRequest {
        files: upload.files.clone(),
        format: format_of(upload.field("format"))?,
        modality: upload
            .field("modality")
            .filter(|v| !v.is_empty())
            .map(str::to_string),
        unit: upload
            .field("unit")
            .filter(|v| !v.is_empty())
            .map(str::to_string),
        utc_offset_h,
        on_error,
        metadata: None,
        now: None,
    };
    let doc = s
        .run_write(Changes::ALL, false, move |p| {
            let out = app::ingest(p, &request, clock_now(), &app::Silent)
                .map_err(|e| upload.client_names(e.into()));
            Ok(IngestDoc::from_app(&out?))
        })
        .await?;
    Ok(Json(doc))
}

/// Records a flown mission (multipart: optional `at`, `cells` (comma-separated, in visiting
/// order), `amend`, and the readings files brought back as `files` parts). 409 when the
/// mission was already recorded and `amend` is not set.
#[utoipa::path(post, path = "/api/v1/missions/{id}/record", tag = "data",
    params(("id" = i64, Path, description = "Mission id")),
    request_body(content_type = "multipart/form-data", description = "at (RFC 3339 or date); cells (comma-separated ids); amend (true/false); files (readings brought back, any ingest format)"),
    security(("bearer" = [])),
    responses((status = 200, body = RecordDoc), (status = 400, body = ErrorBody),
        (status = 401, body = ErrorBody), (status = 403, body = ErrorBody),
        (status = 404, body = ErrorBody), (status = 409, body = ErrorBody),
        (status = 413, body = ErrorBody)))]
pub async fn record(
    State(s): State<AppState>,
    _: Writing,
    Path(id): Path<String>,
    m: Result<Multipart, MultipartRejection>,
) -> ApiResult<Json<RecordDoc>> {
    let m = m.map_err(multipart_type)?;
    let id = mission_id(&id)?;
    let upload = read_upload(m).await?;
    let cells = upload
        .field("cells")
        .filter(|c| !c.trim().is_empty())
        .map(|c| c.split(',').map(|s| s.trim().to_string()).collect());
    let request = app::RecordRequest {
        mission: id,
        at: parse_time("at", upload.field("at").filter(|v| !v.is_empty()))?,
        cells,
        readings: (!upload.files.is_empty()).then(|| app::IngestRequest {
            files: upload.files.clone(),
            ..Default::default()
        }),
        amend: flag(&upload, "amend")?,
    };
    let doc = s
        .run_write(Changes::ALL, false, move |p| {
            let out = app::record_flight(p, &request, clock_now(), &app::Silent)
                .map_err(|e| upload.client_names(e.into()));
            Ok(RecordDoc::from_app(&out?))
        })
        .await?;
    Ok(Json(doc))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uploaded_names_never_become_paths() {
        assert_eq!(safe_name(0, "../../etc/passwd"), "000-passwd");
        assert_eq!(safe_name(1, "C:\\x\\..\\CAF003.txt"), "001-CAF003.txt");
        assert_eq!(safe_name(2, ".."), "002-upload");
        assert_eq!(safe_name(3, "a b;c.csv"), "003-a_b_c.csv");
    }
}
