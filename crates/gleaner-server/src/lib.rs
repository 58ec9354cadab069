//! gleaner's HTTP adapter: a JSON API under `/api/v1` and an offline web dashboard, over the
//! same application use cases the CLI calls (`gleaner serve`).
//!
//! - [`router`] builds the axum router: the API handlers ([`handlers`]), whose OpenAPI
//!   document ([`openapi`]) is generated from the handlers themselves and served at
//!   `/api/v1/openapi.json`, and the dashboard ([`dashboard`]: HTML, CSS and JavaScript
//!   embedded in the binary; no CDN, no third-party code, works offline).
//! - [`serve`] runs it on a bound listener until a shutdown future completes (ctrl-c in the
//!   CLI), finishing the requests in flight.
//! - Every use case runs on a blocking thread over a small pool of open projects
//!   ([`AppState`]); planning and exploration searches queue one at a time, so reads keep
//!   being answered while a mission is planned. Writes through the server run one at a time;
//!   the large reads (`/cells`, `/field`) are cached until the next write and for at most
//!   [`state::CACHE_TTL`].
//! - Security: [`ServerConfig::check`] refuses a non-loopback address without a token; every
//!   request that writes needs `Authorization: Bearer <token>` ([`auth`], constant-time
//!   compare, never logged); uploads are size-limited and saved under sanitised names in a
//!   temporary folder; downloads are made in memory from the export use case, never read from
//!   a client-given path; CORS is off unless origins are configured.
//! - Errors are JSON `{error, field, reason}` ([`ErrorBody`]) with 400, 401, 403, 404, 409,
//!   413 or 500.
//!
//! ```no_run
//! # async fn run() -> Result<(), Box<dyn std::error::Error>> {
//! use gleaner_server::{ServerConfig, serve};
//! let config = ServerConfig::new("farm".into());
//! let listener = tokio::net::TcpListener::bind(config.addr).await?;
//! serve(listener, &config, async { tokio::signal::ctrl_c().await.ok(); }).await?;
//! # Ok(()) }
//! ```
#![deny(missing_docs)]

pub mod api;
pub mod auth;
pub mod client;
pub mod dashboard;
mod error;
pub mod handlers;
pub mod state;

use std::net::SocketAddr;
use std::path::PathBuf;

use axum::Router;
use axum::extract::DefaultBodyLimit;
use axum::http::{HeaderValue, Method, header};
use tower_http::cors::{AllowOrigin, CorsLayer};
use tower_http::trace::TraceLayer;
use utoipa::OpenApi as _;
use utoipa_axum::router::OpenApiRouter;
use utoipa_axum::routes;

pub use auth::{Token, TokenError};
pub use error::{ApiError, ErrorBody};
pub use state::AppState;

/// Default address: loopback only.
pub const DEFAULT_ADDR: &str = "127.0.0.1:8080";
/// Default upload limit, bytes (64 MiB: a few years of a farm's daily files).
pub const DEFAULT_MAX_UPLOAD_BYTES: usize = 64 << 20;
/// Largest JSON request body, bytes.
pub const MAX_JSON_BYTES: usize = 1 << 20;

/// How the server runs.
#[derive(Debug, Clone)]
pub struct ServerConfig {
    /// Project directory (`gleaner.toml`).
    pub project: PathBuf,
    /// Address to listen on.
    pub addr: SocketAddr,
    /// Write token; without one, writes are refused (403) and only loopback may be bound.
    pub token: Option<Token>,
    /// Origins allowed by CORS (none: CORS off, same origin only).
    pub cors_origins: Vec<String>,
    /// Basemap tile URL template (`https://…/{z}/{x}/{y}.png`) the dashboard draws under the
    /// cells; none by default (the dashboard needs no network).
    pub basemap_url: Option<String>,
    /// Largest upload, bytes.
    pub max_upload_bytes: usize,
    /// Longest planner time limit a request may ask for, s.
    pub max_time_limit_s: f64,
    /// Projects opened at start-up and shared by the requests (at most this many use cases
    /// run at once).
    pub pool_size: usize,
}

impl ServerConfig {
    /// Defaults for the project in `project`: loopback, no token, no CORS, no basemap.
    pub fn new(project: PathBuf) -> Self {
        Self {
            project,
            addr: DEFAULT_ADDR.parse().expect("a valid constant address"),
            token: None,
            cors_origins: Vec::new(),
            basemap_url: None,
            max_upload_bytes: DEFAULT_MAX_UPLOAD_BYTES,
            max_time_limit_s: 60.0,
            pool_size: 8,
        }
    }

    /// Refuses an unsafe configuration: a non-loopback address without a token, an unusable
    /// CORS origin or basemap URL, a zero upload limit.
    pub fn check(&self) -> Result<(), ServerError> {
        if !self.addr.ip().is_loopback() && self.token.is_none() {
            return Err(ServerError::Config(format!(
                "listening on {} (not loopback) needs a token: set GLEANER_TOKEN or --token-file",
                self.addr
            )));
        }
        for o in &self.cors_origins {
            if HeaderValue::from_str(o).is_err()
                || !(o.starts_with("http://") || o.starts_with("https://"))
            {
                return Err(ServerError::Config(format!(
                    "CORS origin {o:?}: expected http(s)://host[:port]"
                )));
            }
        }
        if let Some(u) = &self.basemap_url {
            let ok = (u.starts_with("https://") || u.starts_with("http://"))
                && ["{z}", "{x}", "{y}"].iter().all(|p| u.contains(p))
                && !u.contains(['"', '\'', '<', '>', ' ']);
            if !ok {
                return Err(ServerError::Config(format!(
                    "basemap URL {u:?}: expected http(s)://…/{{z}}/{{x}}/{{y}}…"
                )));
            }
        }
        if self.max_upload_bytes == 0 {
            return Err(ServerError::Config(
                "the upload limit must be > 0 bytes".into(),
            ));
        }
        if !(self.max_time_limit_s.is_finite() && self.max_time_limit_s >= 0.0) {
            return Err(ServerError::Config(format!(
                "max planner time limit {} s: expected seconds >= 0",
                self.max_time_limit_s
            )));
        }
        Ok(())
    }
}

/// Why the server could not start or stopped.
#[derive(Debug, thiserror::Error)]
pub enum ServerError {
    /// An unsafe or invalid configuration.
    #[error("{0}")]
    Config(String),
    /// The project could not be opened.
    #[error(transparent)]
    Project(#[from] gleaner_app::AppError),
    /// The listener failed.
    #[error("server: {0}")]
    Io(#[from] std::io::Error),
}

/// Adds the bearer scheme the write endpoints name.
struct BearerScheme;

impl utoipa::Modify for BearerScheme {
    fn modify(&self, api: &mut utoipa::openapi::OpenApi) {
        use utoipa::openapi::security::{HttpAuthScheme, HttpBuilder, SecurityScheme};
        let components = api.components.get_or_insert_with(Default::default);
        components.add_security_scheme(
            "bearer",
            SecurityScheme::Http(HttpBuilder::new().scheme(HttpAuthScheme::Bearer).build()),
        );
    }
}

/// The API routes with their OpenAPI document.
/// Uploads (multipart) are limited to `max_upload_bytes`, every other body to
/// [`MAX_JSON_BYTES`].
fn api_routes(max_upload_bytes: usize) -> (Router<AppState>, utoipa::openapi::OpenApi) {
    let mut doc = handlers::ApiDoc::openapi();
    utoipa::Modify::modify(&BearerScheme, &mut doc);
    let json = OpenApiRouter::with_openapi(doc)
        .routes(routes!(handlers::project))
        .routes(routes!(handlers::field))
        .routes(routes!(handlers::cells))
        .routes(routes!(handlers::cell))
        .routes(routes!(handlers::score))
        .routes(routes!(handlers::reconstruct))
        .routes(routes!(handlers::simulate))
        .routes(routes!(handlers::missions))
        .routes(routes!(handlers::mission))
        .routes(routes!(handlers::plan))
        .routes(routes!(handlers::plan_sorties))
        .routes(routes!(handlers::explore))
        .routes(routes!(handlers::mission_file))
        .routes(routes!(handlers::map, handlers::map_of))
        .layer(DefaultBodyLimit::max(MAX_JSON_BYTES));
    let uploads = OpenApiRouter::new()
        .routes(routes!(handlers::ingest))
        .routes(routes!(handlers::record))
        .layer(DefaultBodyLimit::max(max_upload_bytes));
    json.merge(uploads).split_for_parts()
}

/// The OpenAPI document of the API (what `/api/v1/openapi.json` serves).
pub fn openapi() -> utoipa::openapi::OpenApi {
    api_routes(DEFAULT_MAX_UPLOAD_BYTES).1
}

/// The whole application: API, OpenAPI document, dashboard, request logging, CORS.
pub fn router(state: AppState, config: &ServerConfig) -> Router {
    let (api, doc) = api_routes(config.max_upload_bytes);
    let doc_json = doc.to_json().unwrap_or_else(|_| "{}".to_string());
    let mut app = api
        .route(
            "/api/v1/openapi.json",
            axum::routing::get(move || async move {
                (
                    [(header::CONTENT_TYPE, "application/json")],
                    doc_json.clone(),
                )
            }),
        )
        .merge(dashboard::routes(config.basemap_url.as_deref()))
        .fallback(|| async {
            ApiError::not_found(None, "no such page or endpoint (see /api/v1/openapi.json)")
        })
        .with_state(state);
    if !config.cors_origins.is_empty() {
        let origins: Vec<HeaderValue> = config
            .cors_origins
            .iter()
            .filter_map(|o| HeaderValue::from_str(o).ok())
            .collect();
        app = app.layer(
            CorsLayer::new()
                .allow_origin(AllowOrigin::list(origins))
                .allow_methods([Method::GET, Method::POST])
                .allow_headers([header::AUTHORIZATION, header::CONTENT_TYPE]),
        );
    }
    app.layer(TraceLayer::new_for_http())
}

/// Serves `config`'s project on `listener` until `shutdown` completes, then finishes the
/// requests in flight.
pub async fn serve(
    listener: tokio::net::TcpListener,
    config: &ServerConfig,
    shutdown: impl std::future::Future<Output = ()> + Send + 'static,
) -> Result<(), ServerError> {
    config.check()?;
    let state = AppState::new(config)?;
    let app = router(state, config);
    tracing::info!(addr = %listener.local_addr()?, "serving gleaner");
    axum::serve(listener, app)
        .with_graceful_shutdown(shutdown)
        .await?;
    Ok(())
}
