//! gleaner's HTTP adapter: a JSON API under `/api/v1` and an offline web dashboard, over the
//! same application use cases the CLI calls (`gleaner serve`).
//!
//! - [`router`] builds the axum router: the API handlers ([`handlers`]), whose OpenAPI
//!   document ([`openapi`]) is generated from the handlers themselves and served at
//!   `/api/v1/openapi.json`, and the dashboard ([`dashboard`]: HTML, CSS and JavaScript
//!   embedded in the binary; no CDN, no third-party code, works offline).
//! - [`serve`] runs it on a bound listener until a shutdown future completes (ctrl-c in the
//!   CLI), finishing the requests in flight; [`start`] is `gleaner serve`'s start-up (the
//!   write token, malloc settings, log, runtime, until ctrl-c or SIGTERM) and `farm-token`.
//! - Every use case runs on a blocking thread over a small pool of open projects
//!   ([`AppState`]); planning and exploration searches queue one at a time, so reads keep
//!   being answered while a mission is planned. Writes through the server run one at a time;
//!   the reads polled while plans are saved (`/project`, `/field`, `/cells`) are cached
//!   until a write changes what they read ([`state::Changes`]), which recomputes them before
//!   it answers, and for at most [`state::CACHE_TTL`].
//! - Security: [`ServerConfig::check`] refuses a non-loopback address without a token; every
//!   request that writes needs `Authorization: Bearer <token>` ([`auth`], constant-time
//!   compare, never logged); uploads are size-limited and saved under sanitised names in a
//!   temporary folder; downloads are made in memory from the export use case, never read from
//!   a client-given path; CORS is off unless origins are configured.
//! - Many farms ([`farms`], `gleaner serve --farms DIR`): every project of a directory under
//!   `/api/v1/farms/{farm}/`, each guarded by its own hashed tokens of read or write scope
//!   ([`farms_router`], [`farms_openapi`]); several such servers may serve one PostgreSQL
//!   database, the writing use cases holding each farm's lock in the database.
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
pub mod farms;
pub mod handlers;
pub mod start;
pub mod state;
mod token;

mod security;

use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Duration;

use axum::Router;
use axum::extract::DefaultBodyLimit;
use axum::http::{HeaderValue, Method, header};
use tower_http::cors::{AllowOrigin, CorsLayer};
use utoipa::OpenApi as _;
use utoipa_axum::router::OpenApiRouter;
use utoipa_axum::routes;

pub use error::{ApiError, ErrorBody};
pub use farms::{FarmTokens, Farms, Scope};
pub use state::{AppState, Event, Hook};
pub use token::{Token, TokenError};

/// Default address: loopback only.
pub const DEFAULT_ADDR: &str = "127.0.0.1:8080";
/// Default upload limit, bytes (64 MiB: a few years of a farm's daily files).
pub const DEFAULT_MAX_UPLOAD_BYTES: usize = 64 << 20;
/// Largest JSON request body, bytes.
pub const MAX_JSON_BYTES: usize = 1 << 20;
/// Default time a connection has to send a request's head (line and headers), a new
/// connection or a kept-alive one between requests: after it, the connection is closed.
pub const DEFAULT_HEADER_READ_TIMEOUT: Duration = Duration::from_secs(10);
/// Default longest pause while a request's body is being sent.
pub const DEFAULT_BODY_TIMEOUT: Duration = Duration::from_secs(30);
/// Default most connections open at once; further ones wait in the listen queue.
pub const DEFAULT_MAX_CONNECTIONS: usize = 256;
/// Default longest wait at shutdown for requests in flight and for work still running.
pub const DEFAULT_SHUTDOWN_GRACE: Duration = Duration::from_secs(30);

/// How the server runs.
#[derive(Debug, Clone)]
pub struct ServerConfig {
    /// Project directory (`gleaner.toml`); unused with [`ServerConfig::farms`].
    pub project: PathBuf,
    /// A directory of farms (`gleaner serve --farms DIR`): each subdirectory holding a
    /// `gleaner.toml` is a project served under `/api/v1/farms/{farm}/` ([`farms`]), with
    /// the farm tokens of [`ServerConfig::tokens_file`] instead of one server token.
    pub farms: Option<PathBuf>,
    /// The farm tokens file (`farm scope sha256-hex` lines) [default: `tokens` in the farms
    /// directory].
    pub tokens_file: Option<PathBuf>,
    /// Address to listen on.
    pub addr: SocketAddr,
    /// Write token; without one, writes are refused (403) and only loopback may be bound.
    pub token: Option<Token>,
    /// Whether computations that store nothing (plan previews, dry-run scorings and
    /// explorations, simulations, reconstructions, map previews) may run without the token.
    /// Only ever on a loopback address ([`ServerConfig::open_compute`]); true by default.
    pub anonymous_compute: bool,
    /// Host names (besides `localhost` and IP literals) the server answers to in the `Host`
    /// header, e.g. the name of a reverse proxy; any other name is refused (421), so a page
    /// on another site cannot reach the server through DNS rebinding.
    pub allowed_hosts: Vec<String>,
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
    /// Time a connection has to send a request head ([`DEFAULT_HEADER_READ_TIMEOUT`]); also
    /// the idle time after which a kept-alive connection is closed.
    pub header_read_timeout: Duration,
    /// Longest pause while a request body arrives ([`DEFAULT_BODY_TIMEOUT`]).
    pub body_timeout: Duration,
    /// Most connections open at once ([`DEFAULT_MAX_CONNECTIONS`]).
    pub max_connections: usize,
    /// Longest wait at shutdown ([`DEFAULT_SHUTDOWN_GRACE`]).
    pub shutdown_grace: Duration,
    /// How long a cached read is answered before it is refreshed when nothing was written
    /// through this server ([`state::CACHE_TTL`]): the bound on how late another process's
    /// write shows.
    pub cache_ttl: Duration,
}

impl ServerConfig {
    /// Defaults for the project in `project`: loopback, no token, no CORS, no basemap.
    pub fn new(project: PathBuf) -> Self {
        Self {
            project,
            farms: None,
            tokens_file: None,
            addr: DEFAULT_ADDR.parse().expect("a valid constant address"),
            token: None,
            anonymous_compute: true,
            allowed_hosts: Vec::new(),
            cors_origins: Vec::new(),
            basemap_url: None,
            max_upload_bytes: DEFAULT_MAX_UPLOAD_BYTES,
            max_time_limit_s: 60.0,
            pool_size: 8,
            header_read_timeout: DEFAULT_HEADER_READ_TIMEOUT,
            body_timeout: DEFAULT_BODY_TIMEOUT,
            max_connections: DEFAULT_MAX_CONNECTIONS,
            shutdown_grace: DEFAULT_SHUTDOWN_GRACE,
            cache_ttl: state::CACHE_TTL,
        }
    }

    /// Whether computations that store nothing run without the token: only when allowed and
    /// bound to loopback.
    pub fn open_compute(&self) -> bool {
        self.anonymous_compute && self.addr.ip().is_loopback()
    }

    /// Refuses an unsafe configuration: a non-loopback address without a token, an unusable
    /// CORS origin, allowed host or basemap URL, a zero upload limit, timeout or connection
    /// cap.
    pub fn check(&self) -> Result<(), ServerError> {
        if self.farms.is_some() && self.token.is_some() {
            return Err(ServerError::Config(
                "a farms server takes the farm tokens of its tokens file, not one server token (unset GLEANER_TOKEN / --token-file)".into(),
            ));
        }
        // A farms server answers nothing without a farm token, whatever the address.
        if self.farms.is_none() && !self.addr.ip().is_loopback() && self.token.is_none() {
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
        for h in &self.allowed_hosts {
            let ok = !h.is_empty()
                && h.chars()
                    .all(|c| c.is_ascii_alphanumeric() || matches!(c, '.' | '-'));
            if !ok {
                return Err(ServerError::Config(format!(
                    "allowed host {h:?}: expected a host name (letters, digits, '.', '-'), without port"
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
        if self.header_read_timeout.is_zero()
            || self.body_timeout.is_zero()
            || self.max_connections == 0
        {
            return Err(ServerError::Config(
                "the header and body timeouts and the connection cap must be > 0".into(),
            ));
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
        .routes(routes!(handlers::reconstruct_map_svg))
        .routes(routes!(handlers::reconstruct_map_png))
        .routes(routes!(handlers::simulate))
        .routes(routes!(handlers::missions))
        .routes(routes!(handlers::missions_page))
        .routes(routes!(handlers::mission, handlers::delete_mission))
        .routes(routes!(handlers::cancel_mission))
        .routes(routes!(handlers::plan))
        .routes(routes!(handlers::plan_sorties))
        .routes(routes!(handlers::explore))
        .routes(routes!(handlers::mission_file))
        .routes(routes!(handlers::replan))
        .routes(routes!(handlers::map, handlers::map_of))
        .routes(routes!(handlers::openapi_json))
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

/// The OpenAPI document of a farms server (`gleaner serve --farms`): every path of
/// [`openapi`] under `/api/v1/farms/{farm}` (with the `farm` path parameter and the bearer
/// scheme on every operation: each needs a farm token), `GET /api/v1/farms`, and this
/// document at `/api/v1/openapi.json`.
pub fn farms_openapi() -> utoipa::openapi::OpenApi {
    use utoipa::openapi::path::{ParameterBuilder, ParameterIn};
    use utoipa::openapi::security::SecurityRequirement;
    use utoipa::openapi::{ObjectBuilder, Required, Type};
    let single = openapi();
    let mut doc = single.clone();
    doc.paths.paths.clear();
    for (path, mut item) in single.paths.paths {
        let tail = path.strip_prefix("/api/v1").unwrap_or(&path);
        let farm = ParameterBuilder::new()
            .name("farm")
            .parameter_in(ParameterIn::Path)
            .required(Required::True)
            .description(Some(
                "The farm: a subdirectory of the server's farms directory",
            ))
            .schema(Some(ObjectBuilder::new().schema_type(Type::String)))
            .build();
        let mut params = vec![farm];
        params.extend(item.parameters.take().unwrap_or_default());
        item.parameters = Some(params);
        for op in [
            &mut item.get,
            &mut item.post,
            &mut item.put,
            &mut item.delete,
            &mut item.patch,
        ]
        .into_iter()
        .flatten()
        {
            op.security = Some(vec![SecurityRequirement::new(
                "bearer",
                Vec::<String>::new(),
            )]);
            op.operation_id = op.operation_id.take().map(|id| format!("farm_{id}"));
            for (code, why) in [
                ("401", "No farm token, or one that is no farm's"),
                ("403", "A read-scope token on a write"),
                (
                    "404",
                    "No such farm for this token (another farm's token gets the same)",
                ),
            ] {
                op.responses
                    .responses
                    .entry(code.to_string())
                    .or_insert_with(|| {
                        utoipa::openapi::ResponseBuilder::new()
                            .description(why)
                            .content(
                                "application/json",
                                utoipa::openapi::ContentBuilder::new()
                                    .schema(Some(utoipa::openapi::Ref::from_schema_name(
                                        "ErrorBody",
                                    )))
                                    .build(),
                            )
                            .build()
                            .into()
                    });
            }
        }
        doc.paths
            .paths
            .insert(format!("/api/v1/farms/{{farm}}{tail}"), item);
    }
    let (_, extra): (Router<Farms>, _) = OpenApiRouter::new()
        .routes(routes!(farms::farms_list))
        .routes(routes!(handlers::openapi_json))
        .split_for_parts();
    doc.merge(extra);
    let components = doc.components.get_or_insert_with(Default::default);
    for (name, schema) in [
        (
            "FarmDoc",
            <farms::FarmDoc as utoipa::PartialSchema>::schema(),
        ),
        ("Scope", <farms::Scope as utoipa::PartialSchema>::schema()),
    ] {
        components.schemas.insert(name.to_string(), schema);
    }
    doc.tags
        .get_or_insert_with(Vec::new)
        .push(utoipa::openapi::tag::Tag::new("farms"));
    doc.info.description = Some(format!(
        "{} A farms server (`gleaner serve --farms DIR`) serves every farm's API under `/api/v1/farms/{{farm}}/`; every request needs that farm's token (read or write scope) in `Authorization: Bearer`.",
        doc.info.description.unwrap_or_default()
    ));
    doc
}

/// One project's API (and with `dashboard` its dashboard) over `state`, without the
/// security layers [`secure`] adds: what [`router`] serves, and what a farm's requests are
/// dispatched to. `/api/v1/openapi.json` serves `doc_json`.
pub(crate) fn project_router(
    state: AppState,
    config: &ServerConfig,
    doc_json: Arc<str>,
    dashboard: bool,
) -> Router {
    let (api, _) = api_routes(config.max_upload_bytes);
    let app = match dashboard {
        true => api.merge(dashboard::routes(config.basemap_url.as_deref(), false)),
        false => api,
    };
    app.fallback(|| async {
        ApiError::not_found(None, "no such page or endpoint (see /api/v1/openapi.json)")
    })
    .method_not_allowed_fallback(security::method_not_allowed)
    .layer(axum::Extension(handlers::OpenApiJson(doc_json)))
    .with_state(state)
}

/// The whole application: API, OpenAPI document, dashboard, request logging (paths and
/// redacted queries only), CORS, the `Host` allow-list and the security headers on every
/// response.
pub fn router(state: AppState, config: &ServerConfig) -> Router {
    let doc = api_routes(config.max_upload_bytes).1;
    let doc_json: Arc<str> = doc.to_json().unwrap_or_else(|_| "{}".to_string()).into();
    secure(project_router(state, config, doc_json, true), config)
}

/// A farms server's application: `GET /api/v1/farms`, every farm's API under
/// `/api/v1/farms/{farm}/` ([`Farms`]), the farms' OpenAPI document at
/// `/api/v1/openapi.json` and the dashboard with its farm picker, with the same security
/// layers as [`router`].
pub fn farms_router(farms: &Farms, config: &ServerConfig) -> Router {
    let doc_json: Arc<str> = farms_openapi()
        .to_json()
        .unwrap_or_else(|_| "{}".to_string())
        .into();
    let app = farms
        .router()
        .merge(dashboard::routes(config.basemap_url.as_deref(), true))
        .route(
            "/api/v1/openapi.json",
            axum::routing::get(handlers::openapi_json),
        )
        .layer(axum::Extension(handlers::OpenApiJson(doc_json)))
        .method_not_allowed_fallback(security::method_not_allowed);
    secure(app, config)
}

/// CORS (when configured), the wrong-token refusal, the `Host` allow-list, the security
/// headers and the request log around `app`.
fn secure(app: Router, config: &ServerConfig) -> Router {
    let mut app = app;
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
    let hosts = Arc::new(security::Hosts::new(&config.allowed_hosts));
    let token = Arc::new(config.token.clone());
    app.layer(axum::middleware::from_fn(
        move |req: axum::extract::Request, next: axum::middleware::Next| {
            security::refuse_wrong_tokens(Arc::clone(&token), req, next)
        },
    ))
    .layer(axum::middleware::from_fn(
        move |req: axum::extract::Request, next: axum::middleware::Next| {
            security::check_host(Arc::clone(&hosts), req, next)
        },
    ))
    .layer(axum::middleware::from_fn(security::headers))
    .layer(security::trace_layer())
}

/// Serves `config`'s project on `listener` until `shutdown` completes, then finishes the
/// requests in flight.
pub async fn serve(
    listener: tokio::net::TcpListener,
    config: &ServerConfig,
    shutdown: impl std::future::Future<Output = ()> + Send + 'static,
) -> Result<(), ServerError> {
    config.check()?;
    if config.farms.is_some() {
        let farms = Farms::open(config)?;
        return serve_farms(listener, config, farms, shutdown).await;
    }
    let state = AppState::new(config)?;
    serve_state(listener, config, state, shutdown).await
}

/// [`serve`] for a farms server made by the caller ([`Farms::open`]).
pub async fn serve_farms(
    listener: tokio::net::TcpListener,
    config: &ServerConfig,
    farms: Farms,
    shutdown: impl std::future::Future<Output = ()> + Send + 'static,
) -> Result<(), ServerError> {
    config.check()?;
    let app = farms_router(&farms, config);
    serve_app(listener, config, app, farms.states(), shutdown).await
}

/// [`serve`] with a state made by the caller (who may keep a clone to watch it, e.g. with
/// [`AppState::set_hook`]).
///
/// Each connection is served by hyper's HTTP/1.1 server with a header-read timeout (which is
/// also the idle timeout of kept-alive connections) and a body timeout; at most
/// `max_connections` are open at once, the others wait in the listen queue. At shutdown the
/// listener closes, cancellable work (simulations) is cancelled, the requests in flight are
/// finished, and the work still running (whose client left) is waited for, each wait bounded
/// by `shutdown_grace`.
pub async fn serve_state(
    listener: tokio::net::TcpListener,
    config: &ServerConfig,
    state: AppState,
    shutdown: impl std::future::Future<Output = ()> + Send + 'static,
) -> Result<(), ServerError> {
    config.check()?;
    let app = router(state.clone(), config);
    serve_app(listener, config, app, vec![state], shutdown).await
}

/// Serves `app` on `listener` (see [`serve_state`]); `states` are the projects' states it
/// serves: told about the connections' events, shut down and drained at the end.
async fn serve_app(
    listener: tokio::net::TcpListener,
    config: &ServerConfig,
    app: Router,
    states: Vec<AppState>,
    shutdown: impl std::future::Future<Output = ()> + Send + 'static,
) -> Result<(), ServerError> {
    use hyper_util::rt::{TokioIo, TokioTimer};
    use tokio::sync::Semaphore;
    let states = Arc::new(states);
    let event = {
        let states = Arc::clone(&states);
        move |e: Event| {
            for s in states.iter() {
                s.event(e.clone());
            }
        }
    };
    let service = hyper_util::service::TowerToHyperService::new(
        tower_http::timeout::RequestBodyTimeout::new(app, config.body_timeout),
    );
    let mut http = hyper::server::conn::http1::Builder::new();
    http.timer(TokioTimer::new())
        .header_read_timeout(config.header_read_timeout)
        .keep_alive(true);
    let graceful = hyper_util::server::graceful::GracefulShutdown::new();
    let limit = Arc::new(Semaphore::new(config.max_connections));
    let open = Arc::new(AtomicUsize::new(0));
    tracing::info!(addr = %listener.local_addr()?, "serving gleaner");
    tokio::pin!(shutdown);
    loop {
        let permit = match Arc::clone(&limit).try_acquire_owned() {
            Ok(p) => p,
            Err(_) => {
                event(Event::AtCapacity);
                tokio::select! {
                    p = Arc::clone(&limit).acquire_owned() => match p {
                        Ok(p) => p,
                        Err(_) => break,
                    },
                    () = &mut shutdown => break,
                }
            }
        };
        let stream = tokio::select! {
            r = listener.accept() => match r {
                Ok((stream, _)) => stream,
                Err(e) => {
                    // Out of file descriptors and the like: the connection is lost, the
                    // server goes on.
                    tracing::warn!(error = %e, "accepting a connection failed");
                    continue;
                }
            },
            () = &mut shutdown => break,
        };
        stream.set_nodelay(true).ok();
        let n = open.fetch_add(1, Ordering::SeqCst) + 1;
        event(Event::Accepted { open: n });
        let conn = graceful.watch(http.serve_connection(TokioIo::new(stream), service.clone()));
        let (event, open) = (event.clone(), Arc::clone(&open));
        tokio::spawn(async move {
            if let Err(e) = conn.await {
                tracing::debug!(error = %e, "connection ended with an error");
            }
            let n = open.fetch_sub(1, Ordering::SeqCst) - 1;
            event(Event::Closed { open: n });
            drop(permit);
        });
    }
    drop(listener);
    for s in states.iter() {
        s.begin_shutdown();
    }
    if tokio::time::timeout(config.shutdown_grace, graceful.shutdown())
        .await
        .is_err()
    {
        tracing::warn!("shutdown: requests still in flight after the grace period, closed");
    }
    let drain = async {
        for s in states.iter() {
            s.drain().await;
        }
    };
    if tokio::time::timeout(config.shutdown_grace, drain)
        .await
        .is_err()
    {
        tracing::warn!("shutdown: work still running after the grace period, left behind");
    }
    // The pooled projects are closed on a blocking thread: a PostgreSQL client cannot be
    // dropped on the runtime's threads.
    let pools: Vec<_> = states.iter().flat_map(AppState::take_pool).collect();
    tokio::task::spawn_blocking(move || drop(pools)).await.ok();
    Ok(())
}

/// What `gleaner serve` prints when it starts: the dashboard's address. A token drawn at
/// start-up (`generated`) is put in the address's fragment (which never reaches a server's
/// log) only when standard output is a terminal (`terminal`): output that goes to a file or
/// a service's journal never holds it. A token the operator supplied is never printed.
pub fn announce(
    addr: SocketAddr,
    token: Option<&Token>,
    generated: bool,
    terminal: bool,
) -> String {
    let mut text = match (token, generated, terminal) {
        (Some(t), true, true) => format!(
            "dashboard: http://{addr}/#token={}  (this session's write token; set GLEANER_TOKEN to choose one)",
            t.reveal()
        ),
        (Some(_), true, false) => format!(
            "dashboard: http://{addr}/  (a write token was drawn for this session and not printed, as standard output is not a terminal; set GLEANER_TOKEN or --token-file to choose one)"
        ),
        (Some(_), false, _) => format!("dashboard: http://{addr}/"),
        (None, _, _) => format!("dashboard: http://{addr}/  (read-only)"),
    };
    text.push_str(&format!(
        "\nAPI: http://{addr}/api/v1/openapi.json · stop with ctrl-c"
    ));
    text
}
