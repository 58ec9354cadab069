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
    /// A stable code: `bad_request`, `unauthorized`, `forbidden`, `not_found`, `conflict`,
    /// `payload_too_large`, `unavailable`, `internal`.
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
        let reason = e.to_string();
        match &e {
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
        }
    }
}

impl IntoResponse for ApiError {
    fn into_response(self) -> Response {
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
