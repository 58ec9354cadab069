//! Reads of the project, its field and cells, and scoring.

use axum::Json;
use axum::extract::{Path, RawQuery, State};
use axum::response::Response;
use gleaner_app::{self as app, StoreRead};
use gleaner_wire::FieldDoc;
use gleaner_wire::docs::{CellRowDoc, ScoringDoc};
use serde::Deserialize;
use utoipa::IntoParams;

use crate::api::{CellDetailDoc, ProjectDoc, ScoreBody, time_and_history};
use crate::error::{ApiError, ApiResult, ErrorBody};
use crate::state::{AppState, Changes};

use super::{DryRunErrors, DryRunJson, cell_index, json_response, query, to_json};

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
    responses((status = 200, body = ScoringDoc), DryRunErrors))]
pub async fn score(
    State(s): State<AppState>,
    DryRunJson(caller, b): DryRunJson<ScoreBody>,
) -> ApiResult<Json<ScoringDoc>> {
    if !b.dry_run {
        caller.require_write(&s)?;
    }
    let (at, history) = time_and_history(
        b.at.as_deref(),
        b.history_from.as_deref(),
        b.history_until.as_deref(),
    )?;
    let request = app::ScoreRequest {
        at,
        history,
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
