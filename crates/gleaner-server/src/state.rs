//! The server's shared state: the project directory, a small pool of open projects, the
//! token and the limits. Use cases run on tokio's blocking threads (the store is
//! synchronous), so a long planning request never holds up the reads.

use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use axum::body::Bytes;

use gleaner_app::Project;
use tokio::sync::Semaphore;

use crate::auth::Token;
use crate::error::{ApiError, ApiResult};

/// A project as [`Project::open`] opens it (the one place naming the backend it returns).
pub type Opened = Project<gleaner_app::AnyStore>;

/// What every handler shares.
#[derive(Clone)]
pub struct AppState(pub(crate) Arc<Inner>);

pub(crate) struct Inner {
    pub(crate) dir: PathBuf,
    /// Projects opened at start-up: opening one runs the store's schema check, which takes a
    /// write lock, so none is opened while requests are being answered (unless one was lost
    /// to a panic).
    pool: Mutex<Vec<Opened>>,
    /// One permit per pooled project: a request waits for a free one.
    slots: Semaphore,
    pub(crate) token: Option<Token>,
    pub(crate) basemap_url: Option<String>,
    pub(crate) max_upload_bytes: usize,
    pub(crate) max_time_limit_s: f64,
    /// One writing use case at a time: they queue here instead of racing into the store's
    /// busy timeout (a scoring that rebuilds the utility state holds its transaction for
    /// seconds on a large history).
    pub(crate) writer: tokio::sync::Mutex<()>,
    /// One planning or exploration search at a time: they use a core each for seconds, and
    /// queueing them keeps a core for the reads.
    pub(crate) planning: Semaphore,
    /// Bumped after every write through this server.
    generation: AtomicU64,
    /// Serialised answers of the large reads, with the generation they were computed at.
    cache: Mutex<HashMap<&'static str, (u64, Instant, Bytes)>>,
}

/// How long a cached read is served without recomputing it when nothing was written through
/// this server: the bound on how late a write by another process (a CLI command on the same
/// project) shows.
pub const CACHE_TTL: Duration = Duration::from_secs(1);

impl AppState {
    /// State for the project in `config.project`, with `config.pool_size` (at least 1)
    /// projects opened here, so a missing project fails at start-up, not at a request.
    pub fn new(config: &crate::ServerConfig) -> Result<Self, gleaner_app::AppError> {
        let n = config.pool_size.max(1);
        let pool = (0..n)
            .map(|_| Project::open(&config.project))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self(Arc::new(Inner {
            dir: config.project.clone(),
            pool: Mutex::new(pool),
            slots: Semaphore::new(n),
            token: config.token.clone(),
            basemap_url: config.basemap_url.clone(),
            max_upload_bytes: config.max_upload_bytes,
            max_time_limit_s: config.max_time_limit_s,
            writer: tokio::sync::Mutex::new(()),
            planning: Semaphore::new(1),
            generation: AtomicU64::new(0),
            cache: Mutex::new(HashMap::new()),
        })))
    }

    /// Waits for the one slot planning, exploration and simulation searches share; held
    /// until the returned permit is dropped.
    pub async fn planning_slot(&self) -> ApiResult<tokio::sync::SemaphorePermit<'_>> {
        self.0
            .planning
            .acquire()
            .await
            .map_err(|_| ApiError::unavailable("the server is shutting down"))
    }

    fn take(&self) -> ApiResult<Opened> {
        let pooled = self.0.pool.lock().map_or(None, |mut p| p.pop());
        match pooled {
            Some(p) => Ok(p),
            None => Ok(Project::open(&self.0.dir)?),
        }
    }

    fn give_back(&self, p: Opened) {
        if let Ok(mut pool) = self.0.pool.lock() {
            pool.push(p);
        }
    }

    /// [`AppState::run`] for a use case that writes (unless `dry_run`): after the writes
    /// queued before it.
    pub async fn run_write<T: Send + 'static>(
        &self,
        dry_run: bool,
        f: impl FnOnce(&mut Opened) -> ApiResult<T> + Send + 'static,
    ) -> ApiResult<T> {
        if dry_run {
            return self.run(f).await;
        }
        let _writer = self.0.writer.lock().await;
        let out = self.run(f).await;
        // Even a failed write is assumed to have changed something: the cache only costs a
        // recomputation.
        self.0.generation.fetch_add(1, Ordering::SeqCst);
        out
    }

    /// The serialised answer of the read `key`, recomputed by `f` when something was written
    /// through this server since, or when it is older than [`CACHE_TTL`].
    pub async fn cached(
        &self,
        key: &'static str,
        f: impl FnOnce(&mut Opened) -> ApiResult<Vec<u8>> + Send + 'static,
    ) -> ApiResult<Bytes> {
        let generation = self.0.generation.load(Ordering::SeqCst);
        if let Ok(cache) = self.0.cache.lock()
            && let Some((g, at, bytes)) = cache.get(key)
            && *g == generation
            && at.elapsed() < CACHE_TTL
        {
            return Ok(bytes.clone());
        }
        let started = Instant::now();
        let bytes = Bytes::from(self.run(f).await?);
        if let Ok(mut cache) = self.0.cache.lock() {
            cache.insert(key, (generation, started, bytes.clone()));
        }
        Ok(bytes)
    }

    /// Runs `f` on a pooled project on a blocking thread, once a project is free. A use case
    /// that fails leaves its store as it was (one transaction each), so the project goes back
    /// to the pool either way; one lost to a panic is replaced at the next request.
    pub async fn run<T: Send + 'static>(
        &self,
        f: impl FnOnce(&mut Opened) -> ApiResult<T> + Send + 'static,
    ) -> ApiResult<T> {
        let _slot = self
            .0
            .slots
            .acquire()
            .await
            .map_err(|_| ApiError::unavailable("the server is shutting down"))?;
        let state = self.clone();
        tokio::task::spawn_blocking(move || {
            let mut p = state.take()?;
            let out = f(&mut p);
            state.give_back(p);
            out
        })
        .await
        .map_err(|e| ApiError::internal(format!("the request's worker failed: {e}")))?
    }
}
