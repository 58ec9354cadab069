//! The server's shared state: the project directory, a small pool of open projects, the
//! token and the limits. Use cases run on tokio's blocking threads (the store is
//! synchronous), so a long planning request never holds up the reads.

use std::path::PathBuf;
use std::sync::{Arc, Mutex};

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
    pool: Mutex<Vec<Opened>>,
    pool_max: usize,
    pub(crate) token: Option<Token>,
    pub(crate) basemap_url: Option<String>,
    pub(crate) max_upload_bytes: usize,
    pub(crate) max_time_limit_s: f64,
    /// One planning or exploration search at a time: they use a core each for seconds, and
    /// queueing them keeps a core for the reads.
    pub(crate) planning: Semaphore,
}

impl AppState {
    /// State for the project in `dir` (opened once here, so a missing project fails at
    /// start-up, not at the first request).
    pub fn new(config: &crate::ServerConfig) -> Result<Self, gleaner_app::AppError> {
        let first = Project::open(&config.project)?;
        Ok(Self(Arc::new(Inner {
            dir: config.project.clone(),
            pool: Mutex::new(vec![first]),
            pool_max: config.pool_size.max(1),
            token: config.token.clone(),
            basemap_url: config.basemap_url.clone(),
            max_upload_bytes: config.max_upload_bytes,
            max_time_limit_s: config.max_time_limit_s,
            planning: Semaphore::new(1),
        })))
    }

    fn take(&self) -> ApiResult<Opened> {
        let pooled = self.0.pool.lock().map_or(None, |mut p| p.pop());
        match pooled {
            Some(p) => Ok(p),
            None => Ok(Project::open(&self.0.dir)?),
        }
    }

    fn give_back(&self, p: Opened) {
        if let Ok(mut pool) = self.0.pool.lock()
            && pool.len() < self.0.pool_max
        {
            pool.push(p);
        }
    }

    /// Runs `f` on an open project on a blocking thread. A project whose use case failed is
    /// dropped rather than pooled (its connection is opened afresh next time).
    pub async fn run<T: Send + 'static>(
        &self,
        f: impl FnOnce(&mut Opened) -> ApiResult<T> + Send + 'static,
    ) -> ApiResult<T> {
        let state = self.clone();
        tokio::task::spawn_blocking(move || {
            let mut p = state.take()?;
            let out = f(&mut p);
            if out.is_ok() {
                state.give_back(p);
            }
            out
        })
        .await
        .map_err(|e| ApiError::internal(format!("the request's worker failed: {e}")))?
    }
}
