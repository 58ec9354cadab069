//! Reconstructions of the field's readings: estimates, series and their maps.

use axum::Json;
use axum::extract::{RawQuery, State};
use axum::response::Response;
use gleaner_app as app;
use gleaner_wire::docs::{ReconstructionDoc, ReconstructionSeriesDoc};
use serde::Deserialize;
use utoipa::IntoParams;

use crate::api::parse_time;
use crate::auth::Computing;
use crate::error::{ApiError, ApiResult, ErrorBody};
use crate::state::{AppState, Job};

use super::{cell_index, image_response, query};

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
        let format = match png {
            true => gleaner_render::ImageFormat::Png,
            false => gleaner_render::ImageFormat::Svg,
        };
        gleaner_render::files::reconstruction_map_file(
            &gleaner_wire::convert::reconstruction_map(&m),
            format,
        )
        .map_err(|e| ApiError::internal(e.to_string()))
    })
    .await
    .map_err(|e| match has_modality {
        true => e.in_field("modality"),
        false => e,
    })
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

/// Most observations per estimate a request may ask for (the kriging system is this size).
const MAX_NEIGHBOURS: usize = 256;
