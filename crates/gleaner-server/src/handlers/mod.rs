//! The endpoints under `/api/v1`: each parses its request, calls one application use case on
//! a blocking thread and converts the result. No lifecycle logic lives here.
//!
//! One file per resource: `project` (project, field, cells, scoring), `reconstruct`
//! (estimates and their maps), `simulate` (campaign replays), `missions` (listing, planning,
//! exploring, cancelling, deleting), `files` (a mission's downloads and maps), `ingest`
//! (readings uploads, recorded flights). This module holds the request parsing and responses
//! they share and re-exports every endpoint, so paths stay `handlers::NAME`.

mod files;
mod ingest;
mod missions;
mod project;
mod reconstruct;
mod simulate;

pub use files::*;
pub use ingest::*;
pub use missions::*;
pub use project::*;
pub use reconstruct::*;
pub use simulate::*;

use axum::body::Bytes;
use axum::extract::rejection::BytesRejection;
use axum::extract::{FromRequest, FromRequestParts, Request};
use axum::http::request::Parts;
use axum::http::{HeaderValue, StatusCode, header};
use axum::response::{IntoResponse, Response};
use gleaner_app::MissionId;
use serde::de::DeserializeOwned;
use utoipa::OpenApi;

use crate::auth::{Caller, Computing};
use crate::error::{ApiError, ApiResult, ErrorBody};
use crate::state::AppState;

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

/// The caller and JSON body of a computation that writes unless it says `"dry_run": true`:
/// the caller is checked ([`Computing`]) and the `Content-Type` ([`JsonType`]) before the body
/// is read, then the body is parsed as by [`json_body_for`].
pub struct DryRunJson<T>(pub Caller, pub T);

impl<T: DeserializeOwned> FromRequest<AppState> for DryRunJson<T> {
    type Rejection = ApiError;

    async fn from_request(req: Request, state: &AppState) -> Result<Self, ApiError> {
        let (mut parts, body) = req.into_parts();
        let Computing(caller) = Computing::from_request_parts(&mut parts, state).await?;
        JsonType::from_request_parts(&mut parts, state).await?;
        let bytes = Bytes::from_request(Request::from_parts(parts, body), state).await;
        Ok(Self(caller, json_body_for(state, caller, bytes)?))
    }
}

/// The error answers of a [`DryRunJson`] endpoint, for its OpenAPI `responses`: 400 (a bad
/// body), 401 (no token for a write or a computation), 403 (computations disabled), 413 (the
/// body over the upload limit). The variants carry no doc comment: it would become their
/// description, which the OpenAPI document leaves empty.
#[derive(utoipa::IntoResponses)]
#[allow(missing_docs)]
pub enum DryRunErrors {
    // A bad body.
    #[response(status = 400, description = "")]
    BadRequest(ErrorBody),
    // No token.
    #[response(status = 401, description = "")]
    Unauthorized(ErrorBody),
    // Computations disabled.
    #[response(status = 403, description = "")]
    Forbidden(ErrorBody),
    // The body over the upload limit.
    #[response(status = 413, description = "")]
    TooLarge(ErrorBody),
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

/// Bytes with their media type.
fn image_response(bytes: Vec<u8>, media: &'static str) -> Response {
    let mut r = bytes.into_response();
    r.headers_mut()
        .insert(header::CONTENT_TYPE, HeaderValue::from_static(media));
    r
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

fn svg_response(svg: String) -> Response {
    let mut r = svg.into_response();
    r.headers_mut().insert(
        header::CONTENT_TYPE,
        HeaderValue::from_static("image/svg+xml"),
    );
    r
}
