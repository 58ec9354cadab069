//! The API's one error shape, `{error, field, reason}`, and how application errors map onto
//! HTTP status codes.

use axum::http::{HeaderValue, StatusCode, header};
use axum::response::{IntoResponse, Response};
use gleaner_app::AppError;
use serde::Serialize;
use utoipa::ToSchema;

/// The JSON body of every error response.
#[derive(Debug, Clone, PartialEq, Serialize, serde::Deserialize, ToSchema)]
pub struct ErrorBody {
    /// A stable code: `bad_request`, `unauthorized`, `forbidden`, `not_found`,
    /// `method_not_allowed`, `conflict`, `payload_too_large`, `unsupported_media_type`,
    /// `misdirected_request`, `unavailable`, `internal`.
    pub error: String,
    /// The request field at fault (`at`, `files`, `mission`), when there is one.
    pub field: Option<String>,
    /// What is wrong, with the offending value.
    pub reason: String,
}

/// An error answered to the client: a status and an [`ErrorBody`].
#[derive(Debug, Clone, PartialEq)]
pub struct ApiError {
    /// HTTP status.
    pub status: StatusCode,
    /// The body.
    pub body: ErrorBody,
}

impl ApiError {
    fn new(
        status: StatusCode,
        error: &str,
        field: Option<&str>,
        reason: impl Into<String>,
    ) -> Self {
        Self {
            status,
            body: ErrorBody {
                error: error.to_string(),
                field: field.map(str::to_string),
                reason: reason.into(),
            },
        }
    }

    /// 400: a request value that cannot be used.
    pub fn bad_request(field: Option<&str>, reason: impl Into<String>) -> Self {
        Self::new(StatusCode::BAD_REQUEST, "bad_request", field, reason)
    }

    /// 401: no or a wrong bearer token.
    pub fn unauthorized(reason: impl Into<String>) -> Self {
        Self::new(
            StatusCode::UNAUTHORIZED,
            "unauthorized",
            Some("Authorization"),
            reason,
        )
    }

    /// 403: writes are disabled (the server has no token).
    pub fn forbidden(reason: impl Into<String>) -> Self {
        Self::new(StatusCode::FORBIDDEN, "forbidden", None, reason)
    }

    /// 404.
    pub fn not_found(field: Option<&str>, reason: impl Into<String>) -> Self {
        Self::new(StatusCode::NOT_FOUND, "not_found", field, reason)
    }

    /// 409: the request conflicts with the project's state.
    pub fn conflict(field: Option<&str>, reason: impl Into<String>) -> Self {
        Self::new(StatusCode::CONFLICT, "conflict", field, reason)
    }

    /// 413: a body over the size limit.
    pub fn too_large(field: Option<&str>, reason: impl Into<String>) -> Self {
        Self::new(
            StatusCode::PAYLOAD_TOO_LARGE,
            "payload_too_large",
            field,
            reason,
        )
    }

    /// 503: busy (another planning request is running and this one asked not to wait).
    pub fn unavailable(reason: impl Into<String>) -> Self {
        Self::new(StatusCode::SERVICE_UNAVAILABLE, "unavailable", None, reason)
    }

    /// 405: the path exists, the method does not.
    pub fn method_not_allowed(reason: impl Into<String>) -> Self {
        Self::new(
            StatusCode::METHOD_NOT_ALLOWED,
            "method_not_allowed",
            Some("method"),
            reason,
        )
    }

    /// 415: a JSON route sent something other than `application/json`.
    pub fn unsupported_media_type(reason: impl Into<String>) -> Self {
        Self::new(
            StatusCode::UNSUPPORTED_MEDIA_TYPE,
            "unsupported_media_type",
            Some("Content-Type"),
            reason,
        )
    }

    /// 421: the `Host` is not one this server answers to.
    pub fn misdirected(reason: impl Into<String>) -> Self {
        Self::new(
            StatusCode::MISDIRECTED_REQUEST,
            "misdirected_request",
            Some("Host"),
            reason,
        )
    }

    /// Whether this is the answer to cancelled work.
    pub fn is_cancelled(&self) -> bool {
        self.status == StatusCode::SERVICE_UNAVAILABLE && self.body.error == "cancelled"
    }

    /// 500: the server failed.
    pub fn internal(reason: impl Into<String>) -> Self {
        Self::new(StatusCode::INTERNAL_SERVER_ERROR, "internal", None, reason)
    }

    /// Sets the field when the error has none.
    pub fn in_field(mut self, field: &str) -> Self {
        if self.body.field.is_none() {
            self.body.field = Some(field.to_string());
        }
        self
    }
}

impl From<AppError> for ApiError {
    fn from(e: AppError) -> Self {
        use gleaner_app::{AppError as E, StoreError as SE};
        let (reason, named) = api_words(&e.to_string());
        let e_field = named;
        let out = match &e {
            E::Cancelled => Self::new(
                StatusCode::SERVICE_UNAVAILABLE,
                "cancelled",
                None,
                "the work was cancelled: its client left or the server is shutting down",
            ),
            E::NotFound { what, .. } => Self::not_found(Some(what), reason),
            E::Conflict(_) => Self::conflict(None, reason),
            E::Invalid(_) | E::Core { .. } => Self::bad_request(None, reason),
            E::Ingest(_) => Self::bad_request(Some("files"), reason),
            E::Store(s) => match s {
                SE::AlreadyFlown { .. } | SE::Conflicts(_) => Self::conflict(None, reason),
                SE::UnknownSensor(_) | SE::UnknownModality(_) | SE::UnitMismatch { .. } => {
                    Self::bad_request(Some("files"), reason)
                }
                // Another process (a CLI command) held the database past the busy timeout.
                SE::Backend(text) if text.contains("database is locked") => Self::unavailable(
                    format!("{reason}: another process is writing to the project; try again"),
                ),
                _ => Self::internal(reason),
            },
            _ => Self::internal(reason),
        };
        match e_field {
            Some(f) => {
                let mut out = out;
                out.body.field = Some(f.to_string());
                out
            }
            None => out,
        }
    }
}

/// The CLI's flags an application message may name, and the API field that means the same.
const FLAG_FIELDS: [(&str, &str); 12] = [
    ("--history-from", "history_from"),
    ("--history-until", "history_until"),
    ("--time-limit", "time_limit_s"),
    ("--energy-preset", "energy_preset"),
    ("--iterations", "iterations"),
    ("--modality", "modality"),
    ("--sorties", "sorties"),
    ("--solver", "solver"),
    ("--amend", "amend"),
    ("--cells", "cells"),
    ("--seed", "seed"),
    ("--at", "at"),
];

/// An application message in the API's words: each CLI flag it names becomes the API field
/// (`--amend` → `amend`), and `gleaner <command>` hints become the endpoint's name; returns
/// the first field named.
fn api_words(message: &str) -> (String, Option<&'static str>) {
    let mut out = message.to_string();
    let mut first: Option<(usize, &'static str)> = None;
    for (flag, field) in FLAG_FIELDS {
        // Longest flags first in the table, so `--history-from` is not read as `--h…`.
        let mut searched = 0;
        while let Some(pos) = out[searched..].find(flag).map(|p| p + searched) {
            let end = pos + flag.len();
            let next = out[end..].chars().next();
            if next.is_some_and(|c| c.is_ascii_alphanumeric() || c == '-') {
                searched = end;
                continue;
            }
            if first.is_none_or(|(p, _)| pos < p) {
                first = Some((pos, field));
            }
            out.replace_range(pos..end, &format!("`{field}`"));
            searched = pos + field.len() + 2;
        }
    }
    let out = out.replace("``", "`");
    (out, first.map(|(_, f)| f))
}

impl IntoResponse for ApiError {
    fn into_response(mut self) -> Response {
        // Every 400 names what is at fault; an error with no better name is about the body.
        if self.status == StatusCode::BAD_REQUEST && self.body.field.is_none() {
            self.body.field = Some("body".to_string());
        }
        let mut r = (self.status, axum::Json(self.body)).into_response();
        if self.status == StatusCode::UNAUTHORIZED {
            r.headers_mut()
                .insert(header::WWW_AUTHENTICATE, HeaderValue::from_static("Bearer"));
        }
        r
    }
}

/// Shorthand for handler results.
pub type ApiResult<T> = Result<T, ApiError>;
