//! The server's shared state: the project directory, a small pool of open projects, the
//! token and the limits, the one-at-a-time slots, the read cache and the work in flight.
//!
//! Use cases run on tokio's blocking threads (the store is synchronous), so a long planning
//! request never holds up the reads. Every permit a use case needs (the planning slot, the
//! writer slot, a pooled project) moves into the blocking closure with it: a client that hangs
//! up drops its request, not the permits, so the slot stays taken until the work really ends.
//! Work that can stop early (a simulation) is cancelled when its client leaves or the server
//! shuts down ([`Cancel`]); [`AppState::drain`] waits for whatever is still running.

use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, RwLock};
use std::time::{Duration, Instant};

use axum::body::Bytes;

use gleaner_app::Project;
use tokio::sync::{OwnedSemaphorePermit, Semaphore, watch};
use tokio_util::sync::CancellationToken;
use tokio_util::task::TaskTracker;

use crate::error::{ApiError, ApiResult};
use crate::token::Token;

/// A project as [`Project::open`] opens it (the one place naming the backend it returns).
pub type Opened = Project<gleaner_app::AnyStore>;

/// What every handler shares.
#[derive(Clone)]
pub struct AppState(pub(crate) Arc<Inner>);

/// A point in the life of the server's work or connections, reported to the hook set with
/// [`AppState::set_hook`] (tests synchronise on these; nothing else depends on them).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Event {
    /// A use case of this kind starts on its blocking thread, holding its permits.
    Started(&'static str),
    /// Its client left before the answer (the request was dropped); the work is cancelled
    /// if it can stop early and otherwise runs on, keeping its permits.
    Abandoned(&'static str),
    /// A use case ended and released its permits; `cancelled` when it stopped early.
    Ended {
        /// The kind of work.
        kind: &'static str,
        /// Whether it stopped early ([`gleaner_app::AppError::Cancelled`]).
        cancelled: bool,
    },
    /// A connection was accepted; `open` connections now.
    Accepted {
        /// Open connections, this one included.
        open: usize,
    },
    /// A connection closed; `open` connections remain.
    Closed {
        /// Open connections left.
        open: usize,
    },
    /// The connection cap is reached: no connection is accepted until one closes.
    AtCapacity,
    /// Shutdown began: no new connection, cancellable work cancelled.
    ShuttingDown,
    /// A read found its cached answer being computed and waits for that computation.
    CacheJoined,
    /// A write recomputed the cached answer of this key before answering (it changed
    /// something the answer reads).
    Refilled(String),
}

/// A hook called at every [`Event`]. Called on the thread where the event happens (a blocking
/// thread for `Started`, an async worker otherwise): it may block only at `Started`.
pub type Hook = Arc<dyn Fn(&Event) + Send + Sync>;

/// What a write through the server may change, and what a cached answer reads: a write
/// recomputes (or makes outdated) only the cached answers that read something it changes;
/// the others stay as they are.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Changes(u8);

impl Changes {
    /// Nothing: a read.
    pub const NOTHING: Self = Self(0);
    /// The missions: their list, stops, status and visits (plans, explorations,
    /// cancellations, deletions; a recorded flight).
    pub const MISSIONS: Self = Self(1);
    /// The cells' stored description (`/cells`, `/field`): scores and their time, expected
    /// collection energies, pending volumes, series summaries, correlations, class
    /// probabilities, last collections (a scoring, a stored plan's scoring, ingests, records).
    pub const CELLS: Self = Self(2);
    /// Everything else: readings, sensors, the grid, settings, zones.
    pub const DATA: Self = Self(4);
    /// Everything.
    pub const ALL: Self = Self(7);

    /// Both.
    pub const fn and(self, other: Self) -> Self {
        Self(self.0 | other.0)
    }

    /// Whether the two share something.
    pub const fn meets(self, other: Self) -> bool {
        self.0 & other.0 != 0
    }
}

/// What a use case needs before it runs.
#[derive(Debug, Clone, Copy)]
pub struct Job {
    /// A short name (`plan`, `simulate`, `read`), for events and logs.
    pub kind: &'static str,
    /// Takes the one planning slot (planning, exploration and simulation searches).
    pub planning: bool,
    /// What it writes ([`Changes::NOTHING`] for a read): a write is queued behind the other
    /// writes, and the cached answers that read what it changes are recomputed before it
    /// answers (or, for those computed on demand, made outdated when it ends).
    pub writes: Changes,
}

impl Job {
    /// A read: a pooled project only.
    pub const fn read(kind: &'static str) -> Self {
        Self {
            kind,
            planning: false,
            writes: Changes::NOTHING,
        }
    }

    fn is_write(&self) -> bool {
        self.writes != Changes::NOTHING
    }
}

/// What the answers recomputed after one write share, each read from the store at most once
/// (the field view behind both `/field` and `/cells`).
#[derive(Default)]
pub struct Inputs {
    view: Option<gleaner_app::FieldView>,
}

impl Inputs {
    /// The project's field view ([`gleaner_app::field_view`]), read once.
    pub fn field_view(&mut self, p: &Opened) -> ApiResult<&gleaner_app::FieldView> {
        if self.view.is_none() {
            self.view = Some(gleaner_app::field_view(p)?);
        }
        self.view
            .as_ref()
            .ok_or_else(|| ApiError::internal("the field view"))
    }
}

/// Whether the work's client left or the server is shutting down: a use case that can stop
/// early checks it (as the campaign's [`gleaner_app::Progress::cancelled`]).
#[derive(Debug, Clone)]
pub struct Cancel(CancellationToken);

impl Cancel {
    /// Whether the work should stop.
    pub fn is_cancelled(&self) -> bool {
        self.0.is_cancelled()
    }
}

impl gleaner_app::Progress for Cancel {
    fn cancelled(&self) -> bool {
        self.is_cancelled()
    }
}

pub(crate) struct Inner {
    pub(crate) dir: PathBuf,
    /// Projects opened at start-up: opening one runs the store's schema check, which takes a
    /// write lock, so none is opened while requests are being answered (unless one was lost
    /// to a panic).
    pool: Mutex<Vec<Opened>>,
    /// One permit per pooled project: a request waits for a free one.
    slots: Arc<Semaphore>,
    pub(crate) token: Option<Token>,
    /// One farm of a `--farms` server: the dispatcher checked the request's farm token and
    /// put its scope in the request (`farms.rs`'s `FarmAccess`); `token` is unused.
    pub(crate) farm: bool,
    /// Whether computations that write nothing (previews, dry runs, simulations,
    /// reconstructions) may run without the token: on loopback only.
    pub(crate) open_compute: bool,
    pub(crate) basemap_url: Option<String>,
    pub(crate) max_upload_bytes: usize,
    pub(crate) max_time_limit_s: f64,
    /// One writing use case at a time in this server: they queue here instead of racing into
    /// the store's busy timeout (a scoring that rebuilds the utility state holds its
    /// transaction for seconds on a large history). Across processes (server replicas, the
    /// CLI) the use cases serialise on the project's exclusion in the store
    /// (`Project::exclusive`); this queue only keeps this server's writers from all waiting
    /// there at once.
    writer: Arc<Semaphore>,
    /// One planning, exploration or simulation search at a time: they use a core each for
    /// seconds, and queueing them keeps a core for the reads.
    planning: Arc<Semaphore>,
    /// Bumped after every write through this server; an answer it leaves current (it reads
    /// nothing the write changed) moves to the new generation with it.
    generation: AtomicU64,
    /// Serialised answers of the reads, by key.
    cache: Mutex<HashMap<String, CacheSlot>>,
    /// The blocking work in flight (including work whose client left).
    work: TaskTracker,
    /// Cancelled at shutdown; each job's token is a child.
    shutdown: CancellationToken,
    hook: RwLock<Option<Hook>>,
    /// [`CACHE_TTL`] unless configured.
    cache_ttl: Duration,
}

/// How long a cached read is served without recomputing it when nothing was written through
/// this server: the bound on how late a write by another process (a CLI command on the same
/// project) shows. After it, the first reader starts one recomputation and every reader is
/// answered from the previous value until it is done.
pub const CACHE_TTL: Duration = Duration::from_secs(1);

/// Most cached answers kept (one per mission read, plus the project, field and cells).
const CACHE_ENTRIES: usize = 1024;

type Fill = watch::Receiver<Option<ApiResult<Bytes>>>;

/// How an answer kept fresh by the writes is computed ([`AppState::cached_eager`]).
type Refill = Arc<dyn Fn(&mut Opened, &mut Inputs) -> ApiResult<Vec<u8>> + Send + Sync>;

struct CacheSlot {
    /// The latest answer: the write generation it is current at (computed then, refilled
    /// by the write that ends it, or kept by a write that changed nothing it reads), when it
    /// was started.
    current: Option<(u64, Instant, Bytes)>,
    /// The recomputation in flight, for the generation it serves.
    filling: Option<(u64, Fill)>,
    /// Set for the answers the writes that change what they read recompute before they end.
    refill: Option<Refill>,
    /// What the answer reads.
    reads: Changes,
}

impl Default for CacheSlot {
    fn default() -> Self {
        Self {
            current: None,
            filling: None,
            refill: None,
            reads: Changes::ALL,
        }
    }
}

enum Next {
    Wait(Fill),
    Start(watch::Sender<Option<ApiResult<Bytes>>>, Option<Bytes>),
}

impl AppState {
    /// State for the project in `config.project`, with `config.pool_size` (at least 1)
    /// projects opened here, so a missing project fails at start-up, not at a request.
    pub fn new(config: &crate::ServerConfig) -> Result<Self, gleaner_app::AppError> {
        Self::build(config, &config.project, Arc::new(Semaphore::new(1)), false)
    }

    /// State for one farm of a `--farms` server: the project in `dir`, `config.pool_size`
    /// projects opened here, and the server's planning slot `planning` (shared by its farms,
    /// so one search runs at a time on the whole server). Access is the farm tokens' (checked
    /// by the dispatcher), not `config.token`.
    pub fn for_farm(
        config: &crate::ServerConfig,
        dir: &std::path::Path,
        planning: Arc<Semaphore>,
    ) -> Result<Self, gleaner_app::AppError> {
        Self::build(config, dir, planning, true)
    }

    fn build(
        config: &crate::ServerConfig,
        dir: &std::path::Path,
        planning: Arc<Semaphore>,
        farm: bool,
    ) -> Result<Self, gleaner_app::AppError> {
        let n = config.pool_size.max(1);
        let pool = (0..n)
            .map(|_| Project::open(dir))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self(Arc::new(Inner {
            dir: dir.to_path_buf(),
            pool: Mutex::new(pool),
            slots: Arc::new(Semaphore::new(n)),
            token: if farm { None } else { config.token.clone() },
            farm,
            // A farm's requests all carry a farm token (checked before they reach it).
            open_compute: farm || config.open_compute(),
            basemap_url: config.basemap_url.clone(),
            max_upload_bytes: config.max_upload_bytes,
            max_time_limit_s: config.max_time_limit_s,
            writer: Arc::new(Semaphore::new(1)),
            planning,
            generation: AtomicU64::new(0),
            cache: Mutex::new(HashMap::new()),
            work: TaskTracker::new(),
            shutdown: CancellationToken::new(),
            hook: RwLock::new(None),
            cache_ttl: config.cache_ttl,
        })))
    }

    /// Sets the hook called at every [`Event`] (replacing any).
    pub fn set_hook(&self, hook: Hook) {
        if let Ok(mut h) = self.0.hook.write() {
            *h = Some(hook);
        }
    }

    pub(crate) fn event(&self, e: Event) {
        let hook = self.0.hook.read().ok().and_then(|h| h.clone());
        if let Some(h) = hook {
            h(&e);
        }
    }

    /// Whether the planning slot is free (no planning, exploration or simulation search is
    /// running, abandoned or not).
    pub fn planning_idle(&self) -> bool {
        self.0.planning.available_permits() > 0
    }

    /// Starts the shutdown: cancels the work that can stop early.
    pub(crate) fn begin_shutdown(&self) {
        self.0.shutdown.cancel();
        self.event(Event::ShuttingDown);
    }

    /// Waits until no use case runs any more (each started one ends, cancelled or not).
    pub(crate) async fn drain(&self) {
        self.0.work.close();
        self.0.work.wait().await;
    }

    fn take(&self) -> ApiResult<Opened> {
        let pooled = self.0.pool.lock().map_or(None, |mut p| p.pop());
        match pooled {
            Some(p) => Ok(p),
            None => Ok(Project::open(&self.0.dir)?),
        }
    }

    /// Empties the pool of open projects (at shutdown, so the caller closes them where it
    /// may block); a later request would open its own.
    pub(crate) fn take_pool(&self) -> Vec<Opened> {
        self.0
            .pool
            .lock()
            .map(|mut p| std::mem::take(&mut *p))
            .unwrap_or_default()
    }

    fn give_back(&self, p: Opened) {
        if let Ok(mut pool) = self.0.pool.lock() {
            pool.push(p);
        }
    }

    /// Runs `f` on a pooled project on a blocking thread, once a project is free. A use case
    /// that fails leaves its store as it was (one transaction each), so the project goes back
    /// to the pool either way; one lost to a panic is replaced at the next request.
    pub async fn run<T: Send + 'static>(
        &self,
        f: impl FnOnce(&mut Opened) -> ApiResult<T> + Send + 'static,
    ) -> ApiResult<T> {
        self.run_job(Job::read("read"), move |p, _| f(p)).await
    }

    /// [`AppState::run`] for a use case that changes `changes` (unless `dry_run`): after the
    /// writes queued before it.
    pub async fn run_write<T: Send + 'static>(
        &self,
        changes: Changes,
        dry_run: bool,
        f: impl FnOnce(&mut Opened) -> ApiResult<T> + Send + 'static,
    ) -> ApiResult<T> {
        let job = Job {
            kind: "write",
            planning: false,
            writes: if dry_run { Changes::NOTHING } else { changes },
        };
        self.run_job(job, move |p, _| f(p)).await
    }

    /// Runs `f` as `job`: waits for the permits it needs (planning slot, writer slot, a pooled
    /// project), then runs it on a blocking thread that owns them until `f` returns. When the
    /// request is dropped first (its client left), `f` is told through its [`Cancel`] and the
    /// permits stay with it; a write moves the cache to a new generation when it ends either
    /// way.
    pub async fn run_job<T: Send + 'static>(
        &self,
        job: Job,
        f: impl FnOnce(&mut Opened, &Cancel) -> ApiResult<T> + Send + 'static,
    ) -> ApiResult<T> {
        let cancel = Cancel(self.0.shutdown.child_token());
        let mut guard = AbandonGuard {
            state: self.clone(),
            cancel: cancel.clone(),
            kind: job.kind,
            armed: true,
        };
        let closed = |_| ApiError::unavailable("the server is shutting down");
        let planning = match job.planning {
            true => Some(
                Arc::clone(&self.0.planning)
                    .acquire_owned()
                    .await
                    .map_err(closed)?,
            ),
            false => None,
        };
        let writer = match job.is_write() {
            true => Some(
                Arc::clone(&self.0.writer)
                    .acquire_owned()
                    .await
                    .map_err(closed)?,
            ),
            false => None,
        };
        let slot = Arc::clone(&self.0.slots)
            .acquire_owned()
            .await
            .map_err(closed)?;
        let state = self.clone();
        let handle = self.0.work.spawn_blocking(move || {
            let finish = Finish {
                state: state.clone(),
                job,
                permits: Some((planning, writer, slot)),
                cancelled: false,
            };
            state.event(Event::Started(job.kind));
            let out = state.take().and_then(|mut p| {
                let out = f(&mut p, &cancel);
                if job.is_write() && out.is_ok() {
                    state.refill(&mut p, job.writes);
                }
                state.give_back(p);
                out
            });
            let mut finish = finish;
            finish.cancelled = out.as_ref().is_err_and(ApiError::is_cancelled);
            drop(finish);
            out
        });
        let out = handle
            .await
            .map_err(|e| ApiError::internal(format!("the request's worker failed: {e}")))?;
        guard.armed = false;
        out
    }

    /// Recomputes, after a write that changed `changes` and before its generation is
    /// published, every answer of [`AppState::cached_eager`] that is cached and reads
    /// something it changed, and keeps it under the generation the write ends: readers get
    /// the previous answer until the write ends and the new one from then on, and none waits
    /// for a computation after a write. The answers share their inputs ([`Inputs`]). Runs on
    /// the write's thread with its project and writer permit (no other write can
    /// interleave). A failed computation leaves the answer to be computed by the next reader.
    fn refill(&self, p: &mut Opened, changes: Changes) {
        let next = self.0.generation.load(Ordering::SeqCst) + 1;
        let mut refills: Vec<(String, Refill)> = match self.0.cache.lock() {
            Ok(cache) => cache
                .iter()
                .filter(|(_, s)| s.current.is_some() && s.reads.meets(changes))
                .filter_map(|(k, s)| s.refill.clone().map(|r| (k.clone(), r)))
                .collect(),
            Err(_) => return,
        };
        refills.sort_by(|a, b| a.0.cmp(&b.0));
        let mut inputs = Inputs::default();
        for (key, refill) in refills {
            let started = Instant::now();
            let Ok(bytes) = refill(p, &mut inputs) else {
                continue;
            };
            if let Ok(mut cache) = self.0.cache.lock() {
                let slot = cache.entry(key.clone()).or_default();
                if slot.current.as_ref().is_none_or(|c| c.0 <= next) {
                    slot.current = Some((next, started, Bytes::from(bytes)));
                }
            }
            self.event(Event::Refilled(key));
        }
    }

    /// [`AppState::cached`] for an answer that reads `reads` and that every write through
    /// this server changing any of it recomputes before it ends ([`AppState::refill`]), once
    /// a reader has asked for it: the project, the field and the cell table, which readers
    /// poll while plans are saved. A write that changes none of it keeps the answer.
    pub async fn cached_eager(
        &self,
        key: &str,
        reads: Changes,
        f: impl Fn(&mut Opened, &mut Inputs) -> ApiResult<Vec<u8>> + Send + Sync + 'static,
    ) -> ApiResult<Bytes> {
        let f: Refill = Arc::new(f);
        if let Ok(mut cache) = self.0.cache.lock() {
            let slot = cache.entry(key.to_string()).or_default();
            slot.reads = reads;
            if slot.refill.is_none() {
                slot.refill = Some(Arc::clone(&f));
            }
        }
        self.cached(key, move |p| f(p, &mut Inputs::default()))
            .await
    }

    /// The serialised answer of the read `key`, computed by `f` once per write through this
    /// server (concurrent readers of a missing or outdated answer wait for the one
    /// computation), and refreshed in the background after [`CACHE_TTL`] (readers meanwhile
    /// get the previous answer). Errors are answered, not kept.
    pub async fn cached(
        &self,
        key: &str,
        f: impl FnOnce(&mut Opened) -> ApiResult<Vec<u8>> + Send + 'static,
    ) -> ApiResult<Bytes> {
        let generation = self.0.generation.load(Ordering::SeqCst);
        let next = {
            let mut cache = self
                .0
                .cache
                .lock()
                .map_err(|_| ApiError::internal("the read cache was poisoned"))?;
            if cache.len() >= CACHE_ENTRIES && !cache.contains_key(key) {
                cache.retain(|_, s| {
                    s.filling.is_some() || s.current.as_ref().is_some_and(|c| c.0 >= generation)
                });
            }
            let slot = cache.entry(key.to_string()).or_default();
            // An answer refilled by a write that is ending is newer than `generation`: fine.
            let current = slot
                .current
                .as_ref()
                .filter(|c| c.0 >= generation)
                .map(|c| (c.1.elapsed() < self.0.cache_ttl, c.2.clone()));
            let filling = slot
                .filling
                .as_ref()
                .filter(|f| f.0 == generation)
                .map(|f| f.1.clone());
            match (current, filling) {
                (Some((true, bytes)), _) | (Some((false, bytes)), Some(_)) => return Ok(bytes),
                (None, Some(rx)) => {
                    drop(cache);
                    self.event(Event::CacheJoined);
                    Next::Wait(rx)
                }
                (stale, None) => {
                    let (tx, rx) = watch::channel(None);
                    slot.filling = Some((generation, rx));
                    Next::Start(tx, stale.map(|s| s.1))
                }
            }
        };
        let rx = match next {
            Next::Wait(rx) => rx,
            Next::Start(tx, stale) => {
                let rx = tx.subscribe();
                // The fill runs on its own task: a reader that hangs up does not stop it for
                // the others.
                let state = self.clone();
                let key = key.to_string();
                tokio::spawn(async move {
                    let started = Instant::now();
                    let out = state
                        .run_job(Job::read("cache-fill"), move |p, _| f(p))
                        .await
                        .map(Bytes::from);
                    if let Ok(mut cache) = state.0.cache.lock() {
                        let slot = cache.entry(key).or_default();
                        if slot.filling.as_ref().is_some_and(|f| f.0 == generation) {
                            slot.filling = None;
                        }
                        if let Ok(bytes) = &out
                            && slot.current.as_ref().is_none_or(|c| c.0 <= generation)
                        {
                            slot.current = Some((generation, started, bytes.clone()));
                        }
                    }
                    tx.send(Some(out)).ok();
                });
                if let Some(bytes) = stale {
                    return Ok(bytes);
                }
                rx
            }
        };
        let mut rx = rx;
        let out = rx
            .wait_for(Option::is_some)
            .await
            .map_err(|_| ApiError::internal("the read's computation failed"))?
            .clone();
        out.unwrap_or_else(|| Err(ApiError::internal("the read's computation failed")))
    }
}

/// Dropped with the request: when the answer was not reached, the client left.
struct AbandonGuard {
    state: AppState,
    cancel: Cancel,
    kind: &'static str,
    armed: bool,
}

impl Drop for AbandonGuard {
    fn drop(&mut self) {
        if self.armed {
            self.cancel.0.cancel();
            self.state.event(Event::Abandoned(self.kind));
        }
    }
}

type Permits = (
    Option<OwnedSemaphorePermit>,
    Option<OwnedSemaphorePermit>,
    OwnedSemaphorePermit,
);

/// Ends a job on its blocking thread, even when it panics: a write bumps the generation
/// before its writer permit goes, then the permits are released, then `Ended` is reported.
struct Finish {
    state: AppState,
    job: Job,
    permits: Option<Permits>,
    cancelled: bool,
}

impl Drop for Finish {
    fn drop(&mut self) {
        if self.job.is_write() {
            // Even a failed write is assumed to have changed what it may change: the cache
            // only costs a recomputation. The answers current now that read none of it stay
            // current in the next generation; the cache is held so that no reader sees the
            // new generation before they moved.
            let inner = &self.state.0;
            match inner.cache.lock() {
                Ok(mut cache) => {
                    let now = inner.generation.load(Ordering::SeqCst);
                    for slot in cache.values_mut() {
                        if let Some(c) = slot.current.as_mut()
                            && c.0 == now
                            && !slot.reads.meets(self.job.writes)
                        {
                            c.0 = now + 1;
                        }
                    }
                    inner.generation.fetch_add(1, Ordering::SeqCst);
                }
                Err(_) => {
                    inner.generation.fetch_add(1, Ordering::SeqCst);
                }
            }
        }
        drop(self.permits.take());
        self.state.event(Event::Ended {
            kind: self.job.kind,
            cancelled: self.cancelled,
        });
    }
}
