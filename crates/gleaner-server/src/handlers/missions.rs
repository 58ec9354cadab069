//! Missions: listing, planning, replanning, exploration, cancelling and deleting.

use axum::Json;
use axum::body::Bytes;
use axum::extract::rejection::BytesRejection;
use axum::extract::{Path, RawQuery, State};
use axum::http::StatusCode;
use axum::response::Response;
use gleaner_app::{self as app, MissionId};
use gleaner_wire::MissionDoc;
use gleaner_wire::docs::ExplorationDoc;
use serde::{Deserialize, Serialize};
use utoipa::{IntoParams, ToSchema};

use crate::api::{ExploreBody, PlanBody, ReplanBody, ReplanDoc, parse_time, time_and_history};
use crate::auth::{Caller, Computing, Writing};
use crate::error::{ApiError, ApiResult, ErrorBody};
use crate::state::{AppState, Changes, Job};

use super::{
    DryRunErrors, DryRunJson, JsonType, body_bytes, clock_now, energy_preset, json_response,
    mission_id, parse_json, query, to_json,
};

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
    responses((status = 200, body = MissionDoc), DryRunErrors))]
pub async fn plan(
    State(s): State<AppState>,
    DryRunJson(caller, b): DryRunJson<PlanBody>,
) -> ApiResult<Json<MissionDoc>> {
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
    responses((status = 200, body = Vec<MissionDoc>), DryRunErrors))]
pub async fn plan_sorties(
    State(s): State<AppState>,
    DryRunJson(caller, b): DryRunJson<PlanBody>,
) -> ApiResult<Json<Vec<MissionDoc>>> {
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
    let (at, history) = time_and_history(
        b.at.as_deref(),
        b.history_from.as_deref(),
        b.history_until.as_deref(),
    )?;
    let request = app::PlanRequest {
        at,
        history,
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
        docs.extend(
            planned
                .extra_sorties
                .iter()
                .map(gleaner_wire::convert::extra_sortie),
        );
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
    DryRunJson(caller, b): DryRunJson<ExploreBody>,
) -> ApiResult<Json<ExplorationDoc>> {
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
