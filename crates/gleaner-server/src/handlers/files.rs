//! A mission's downloadable files and the field and mission maps.

use axum::body::Bytes;
use axum::extract::rejection::BytesRejection;
use axum::extract::{Path, RawQuery, State};
use axum::http::{HeaderValue, header};
use axum::response::{IntoResponse, Response};
use gleaner_app::{self as app, MissionId};
use gleaner_wire::MissionDoc;
use serde::Deserialize;
use utoipa::IntoParams;

use crate::auth::Computing;
use crate::error::{ApiError, ApiResult, ErrorBody};
use crate::state::AppState;

use super::{JsonType, json_body, mission_id, query, svg_response};

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
            let file = gleaner_render::files::mission_file(name, &field, &doc, Default::default());
            match file {
                Some(Ok(bytes)) => Ok(bytes),
                Some(Err(gleaner_render::FileError::Export(e))) => {
                    Err(ApiError::bad_request(None, e.to_string()))
                }
                Some(Err(e)) => Err(ApiError::internal(e.to_string())),
                None => Err(ApiError::internal(format!("no mission file {name:?}"))),
            }
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

/// Which mission the map shows.
#[derive(Debug, Deserialize, IntoParams)]
#[into_params(parameter_in = Query)]
#[serde(deny_unknown_fields)]
pub struct MapQuery {
    /// Mission id [default: the newest mission; none: the field alone].
    pub mission: Option<i64>,
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
                    let via = app::airspace::stored_via(p, &m);
                    let doc = gleaner_wire::convert::routed_mission(&m, &via);
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
