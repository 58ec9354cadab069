//! The crash-safety harness (`gleaner crash-test`): `ingest`, `plan` and `record` killed with
//! SIGKILL at chosen write steps, on SQLite and on PostgreSQL, then the store checked.
//!
//! A kill point is a count of the store's write steps (one statement or one block of bulk
//! rows of a write transaction, or its commit; `GLEANER_CRASH_AFTER`, see
//! `gleaner_store::failpoint`): the child process kills itself with SIGKILL exactly there,
//! so the trials are driven by what has been written, never by timing. The adapter runs the
//! child (its own binary, its own command line) through the [`ChildRun`] callback; this
//! module builds the fixtures and judges the stores. For each use case it first runs it once
//! to completion on a copy of its starting project (learning its step count and its end
//! state), then for every kill point:
//!
//! 1. copies the starting project (an SQLite file, or a fresh PostgreSQL project filled by
//!    [`migrate`](crate::migrate)), runs the use case as a child process killed at that step;
//! 2. checks the store: the backend's integrity check passes, and its content (every table
//!    but wall-clock provenance) equals the state before the use case or the state after a
//!    complete run, never anything in between (no partial ingest, no mission without stops,
//!    no half-recorded flight), which also means no committed reading was lost;
//! 3. reruns the use case without a kill: it completes, and the store equals the complete
//!    run's end state.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use gleaner_store::{AnyStore, Database, MissionStatus, PgStore, StoreRead};

use crate::{AppError, IngestRequest, PlanRequest, Project, Result, Settings, Silent};

/// The time `plan` plans at, as the child's `--at` and the fixture's plan take it.
pub const PLAN_AT: &str = "2012-01-01";
/// The planner's seed in every plan of the harness.
pub const PLAN_SEED: u64 = 1;
/// The planner's iteration cap in every plan of the harness (deterministic routes).
pub const PLAN_ITERATIONS: u64 = 200;
/// The planner's time limit in every plan of the harness, s.
pub const PLAN_TIME_LIMIT_S: u64 = 60;
/// The mission `record` records (the fixture's planned mission).
pub const RECORD_MISSION: i64 = 1;
/// The collection time `record` gives.
pub const RECORD_AT: &str = "2012-02-01";

/// The use cases under test.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum UseCase {
    /// `ingest` of half the CAF stations' 2011 files into a project holding no readings yet
    /// (PostgreSQL's bulk load: the primary key dropped and built again).
    FirstIngest,
    /// `ingest` of half the CAF stations' 2011 files into a project holding the other half.
    Ingest,
    /// `plan` at [`PLAN_AT`] (seed 1, 200 iterations) on all of 2011.
    Plan,
    /// `record` of mission 1 with the visited stations' January 2012 readings.
    Record,
}

impl UseCase {
    /// The name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Self::FirstIngest => "first-ingest",
            Self::Ingest => "ingest",
            Self::Plan => "plan",
            Self::Record => "record",
        }
    }
}

/// A backend the harness covers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Backend {
    /// SQLite (the trial projects' own files).
    Sqlite,
    /// PostgreSQL at [`CrashTestRequest::postgres`].
    Postgres,
}

impl Backend {
    /// The name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Self::Sqlite => "sqlite",
            Self::Postgres => "postgres",
        }
    }
}

/// What to test.
#[derive(Clone, Debug)]
pub struct CrashTestRequest {
    /// The data directory holding `caf/Daily` and `caf/sensors`.
    pub data: PathBuf,
    /// Working directory for the trial projects (replaced); `None`: a temporary one, removed
    /// at the end.
    pub work: Option<PathBuf>,
    /// The backends, in order.
    pub backends: Vec<Backend>,
    /// The PostgreSQL server (`postgres://...`), needed with [`Backend::Postgres`].
    pub postgres: Option<String>,
    /// The use cases, in order.
    pub use_cases: Vec<UseCase>,
    /// Kill points per use case and backend (spread evenly over the use case's write steps,
    /// the first and the last included).
    pub kill_points: usize,
}

/// One run of a use case as a child process, for the adapter to start.
#[derive(Debug)]
pub struct ChildRun<'a> {
    /// The use case.
    pub case: UseCase,
    /// The project directory.
    pub project: &'a Path,
    /// The `--database` to pass (a PostgreSQL trial project), if any.
    pub database: Option<&'a str>,
    /// The readings files: ingest's, or the flight's for record; none for plan.
    pub files: &'a [PathBuf],
    /// `GLEANER_CRASH_AFTER`: the write step the child kills itself at.
    pub kill_after: Option<u64>,
    /// `GLEANER_CRASH_REPORT`: the file the child writes its write-step count into.
    pub report: Option<&'a Path>,
}

/// Starts a [`ChildRun`] and waits for it: `Ok(true)` when it was killed by SIGKILL,
/// `Ok(false)` when it completed, `Err` (the child's message) when it failed.
pub type ChildRunner<'a> = dyn FnMut(&ChildRun) -> std::result::Result<bool, String> + 'a;

/// What the kill points of one use case on one backend did.
#[derive(Debug, Default, Clone)]
pub struct Tally {
    /// Trials run.
    pub trials: usize,
    /// Killed; the store was as before the use case.
    pub rolled_back: usize,
    /// Killed after the commit; the store was as after a complete run.
    pub committed: usize,
    /// The kill point lay beyond the run's last step: it completed.
    pub completed: usize,
    /// Failures, described.
    pub failures: Vec<String>,
}

/// One use case on one backend.
#[derive(Debug, Clone)]
pub struct Sweep {
    /// The backend.
    pub backend: Backend,
    /// The use case.
    pub case: UseCase,
    /// Write steps of its complete run.
    pub steps: u64,
    /// What its kill points did.
    pub tally: Tally,
}

/// The fixtures: starting projects (SQLite directories) and the use cases' arguments.
struct Fixture {
    /// Starting project of each use case.
    first_ingest_start: PathBuf,
    ingest_start: PathBuf,
    plan_start: PathBuf,
    record_start: PathBuf,
    /// The files the first ingest stores.
    first_files: Vec<PathBuf>,
    /// The files the ingest use case stores.
    ingest_files: Vec<PathBuf>,
    /// The flight's readings file.
    flight: Vec<PathBuf>,
}

impl Fixture {
    fn start(&self, case: UseCase) -> &Path {
        match case {
            UseCase::FirstIngest => &self.first_ingest_start,
            UseCase::Ingest => &self.ingest_start,
            UseCase::Plan => &self.plan_start,
            UseCase::Record => &self.record_start,
        }
    }

    fn files(&self, case: UseCase) -> &[PathBuf] {
        match case {
            UseCase::FirstIngest => &self.first_files,
            UseCase::Ingest => &self.ingest_files,
            UseCase::Plan => &[],
            UseCase::Record => &self.flight,
        }
    }
}

/// Runs the harness: every use case on every backend, `run_child` starting each child
/// process. Returns the sweeps in order.
pub fn crash_test(
    request: &CrashTestRequest,
    run_child: &mut ChildRunner<'_>,
) -> Result<Vec<Sweep>> {
    let postgres = if request.backends.contains(&Backend::Postgres) {
        Some(request.postgres.clone().ok_or_else(|| {
            invalid("PostgreSQL needs --postgres or GLEANER_TEST_PG_URL (scripts/pg-cluster.sh starts a server)")
        })?)
    } else {
        None
    };
    let work = match &request.work {
        Some(w) => w.clone(),
        None => tempdir()?,
    };
    let fixture = fixture(&request.data, &work.join("fixture"))?;
    let mut sweeps = Vec::new();
    let mut trial = 0usize;
    for &backend in &request.backends {
        let pg = match backend {
            Backend::Sqlite => None,
            Backend::Postgres => postgres.as_deref(),
        };
        for &case in &request.use_cases {
            let mut trials = Trials {
                fixture: &fixture,
                case,
                backend,
                pg,
                work: &work,
                trial: &mut trial,
                run_child: &mut *run_child,
            };
            let (steps, tally) = trials.sweep(request.kill_points)?;
            sweeps.push(Sweep {
                backend,
                case,
                steps,
                tally,
            });
        }
    }
    if request.work.is_none() {
        let _ = std::fs::remove_dir_all(&work);
    }
    Ok(sweeps)
}

fn invalid(message: impl Into<String>) -> AppError {
    AppError::Invalid(message.into())
}

/// A new temporary directory.
fn tempdir() -> Result<PathBuf> {
    let dir = std::env::temp_dir().join(format!("gleaner-crash-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).map_err(|e| AppError::io(&dir, e))?;
    Ok(dir)
}

fn read_text(path: &Path) -> Result<String> {
    std::fs::read_to_string(path).map_err(|e| AppError::io(path, e))
}

fn write_text(path: &Path, text: &str) -> Result<()> {
    std::fs::write(path, text).map_err(|e| AppError::io(path, e))
}

fn create_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| AppError::io(dir, e))
}

/// The CAF daily files, sorted.
fn daily_files(daily: &Path) -> Result<Vec<PathBuf>> {
    let context = |e| AppError::io(&daily.join("(set GLEANER_DATA_DIR)"), e);
    let mut names: Vec<PathBuf> = std::fs::read_dir(daily)
        .map_err(context)?
        .map(|e| e.map(|e| e.path()))
        .collect::<std::io::Result<_>>()
        .map_err(context)?;
    names.sort();
    Ok(names)
}

/// Copies of the daily files holding their 2011 rows only, in `input`.
fn files_of_2011(names: &[PathBuf], input: &Path) -> Result<Vec<PathBuf>> {
    create_dir(input)?;
    let mut files = Vec::new();
    for path in names {
        let text = read_text(path)?;
        let mut lines = text.lines();
        let mut kept: Vec<&str> = lines.next().into_iter().collect();
        kept.extend(lines.filter(|l| l.split('\t').nth(1).is_some_and(|d| d.ends_with("/2011"))));
        let name = path
            .file_name()
            .ok_or_else(|| invalid(format!("{}: no file name", path.display())))?;
        let target = input.join(name);
        write_text(&target, &(kept.join("\n") + "\n"))?;
        files.push(target);
    }
    Ok(files)
}

/// Builds the starting projects from the real CAF data: 2011 readings, first half of the
/// stations ingested (ingest adds the second half); all of 2011 (plan plans a mission at
/// 2012-01-01); that plus the planned mission #1 (record records it with the visited
/// stations' January 2012 readings).
fn fixture(data: &Path, dir: &Path) -> Result<Fixture> {
    let _ = std::fs::remove_dir_all(dir);
    create_dir(dir)?;
    let daily = data.join("caf/Daily");
    let files = files_of_2011(&daily_files(&daily)?, &dir.join("input"))?;
    let (first, second) = files.split_at(files.len() / 2);
    let ingest_start = dir.join("ingest");
    let (p, _) = crate::init(&crate::InitRequest {
        dir: ingest_start.clone(),
        sensors: data.join("caf/sensors/CAF_sensor_locations.csv"),
        utm_zone: Some("11N".into()),
        name: Some("crash".into()),
        ..Default::default()
    })?;
    drop(p);
    let first_ingest_start = dir.join("first-ingest");
    copy_project(&ingest_start, &first_ingest_start)?;
    ingest(&mut Project::open(&ingest_start)?, first)?;
    let plan_start = dir.join("plan");
    copy_project(&ingest_start, &plan_start)?;
    ingest(&mut Project::open(&plan_start)?, second)?;
    let record_start = dir.join("record");
    copy_project(&plan_start, &record_start)?;
    let flight = dir.join("flight.csv");
    write_text(&flight, &flight_csv(&record_start, &daily)?)?;
    Ok(Fixture {
        first_ingest_start,
        ingest_start,
        plan_start,
        record_start,
        first_files: first.to_vec(),
        ingest_files: second.to_vec(),
        flight: vec![flight],
    })
}

/// Plans mission #1 in the project at `dir`; returns the visited stations' real January 2012
/// VW readings as a long CSV.
fn flight_csv(dir: &Path, daily: &Path) -> Result<String> {
    let mut p = Project::open(dir)?;
    let planned = crate::plan(&mut p, &plan_request(), 0)?;
    let id = planned
        .id
        .ok_or_else(|| invalid("the fixture's mission was not stored"))?;
    let mission = crate::mission(&p, id)?;
    let cells: std::collections::HashSet<_> =
        mission.mission.stops.iter().map(|s| s.cell).collect();
    let mut csv = String::from("sensor_id,timestamp,modality,value\n");
    for cell in p.store().cells()? {
        if !cells.contains(&cell.index) {
            continue;
        }
        for s in &cell.sensors {
            let text = read_text(&daily.join(format!("{s}.txt")))?;
            for line in text.lines().skip(1) {
                let f: Vec<&str> = line.split('\t').collect();
                if let [_, date, vw, ..] = f[..]
                    && let [m, d, y] = date.split('/').collect::<Vec<_>>()[..]
                    && y == "2012"
                    && m == "01"
                    && vw != "NA"
                {
                    let _ = writeln!(csv, "{s},2012-01-{d},vw@30cm,{vw}");
                }
            }
        }
    }
    Ok(csv)
}

fn ingest(p: &mut Project<AnyStore>, files: &[PathBuf]) -> Result<()> {
    crate::ingest(
        p,
        &IngestRequest {
            files: files.to_vec(),
            ..Default::default()
        },
        0,
        &Silent,
    )?;
    Ok(())
}

/// The plan every trial makes: fixed time, seed and iteration cap (deterministic).
fn plan_request() -> PlanRequest {
    PlanRequest {
        at: crate::parse_timestamp(PLAN_AT),
        seed: Some(PLAN_SEED),
        max_iterations: Some(PLAN_ITERATIONS),
        time_limit_s: Some(PLAN_TIME_LIMIT_S as f64),
        ..Default::default()
    }
}

/// Copies an SQLite project directory (settings and a checkpointed database).
fn copy_project(from: &Path, to: &Path) -> Result<()> {
    let _ = std::fs::remove_dir_all(to);
    create_dir(to)?;
    for name in ["gleaner.toml", "gleaner.db"] {
        let source = from.join(name);
        std::fs::copy(&source, to.join(name)).map_err(|e| AppError::io(&source, e))?;
    }
    // The sensors file is referenced relative to the project directory.
    let settings = Settings::load(from)?;
    let mut s = settings.clone();
    s.sensors.file = from
        .join(&settings.sensors.file)
        .to_string_lossy()
        .into_owned();
    s.save(to)?;
    Ok(())
}

/// Every table's content as text, named: equal states have equal digests.
type Digest = Vec<(&'static str, String)>;

/// Everything the store holds but wall-clock provenance (ingest times, mission creation
/// times), table by table.
fn digest(store: &AnyStore) -> Result<Digest> {
    let mut ingests = store.ingests()?;
    for i in &mut ingests {
        i.at = 0;
    }
    let mut missions = store.missions()?;
    for m in &mut missions {
        m.mission.created_at = 0;
    }
    let mut blobs = Vec::new();
    for k in store.blob_keys()? {
        blobs.push((k.clone(), store.blob_get(&k)?));
    }
    Ok(vec![
        ("sensors", format!("{:?}", store.sensors()?)),
        ("modalities", format!("{:?}", store.modalities()?)),
        (
            "readings",
            format!("{:?}", store.readings_for(None, i64::MIN..=i64::MAX)?),
        ),
        ("ingests", format!("{ingests:?}")),
        ("cells", format!("{:?}", store.cells()?)),
        ("cell metadata", format!("{:?}", store.cell_metadata()?)),
        (
            "sensor collection",
            format!("{:?}", store.sensor_last_collected()?),
        ),
        ("missions", format!("{missions:?}")),
        ("config", format!("{:?}", store.config_entries()?)),
        ("blobs", format!("{blobs:?}")),
    ])
}

/// The tables in which two digests differ, each with both values around the first
/// difference, for a failure report.
fn differing_parts(a: &Digest, b: &Digest) -> String {
    a.iter()
        .zip(b)
        .filter(|((_, x), (_, y))| x != y)
        .map(|((name, x), (_, y))| {
            let at = x.bytes().zip(y.bytes()).take_while(|(p, q)| p == q).count();
            let show = |s: &str| {
                s.get(at.saturating_sub(40)..(at + 80).min(s.len()))
                    .unwrap_or("")
                    .to_string()
            };
            format!("{name} (…{}… vs …{}…)", show(x), show(y))
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// The store of a trial project, its integrity problems and its digest.
fn inspect(dir: &Path, database: Option<&str>) -> Result<(Vec<String>, Digest)> {
    let p = Project::open_with(dir, database)?;
    let mut problems = p.store().integrity_check()?;
    // Every mission has its stops; a flown one its visits.
    for m in p.store().missions()? {
        if m.mission.stops.is_empty() {
            problems.push(format!("mission {} without stops", m.id));
        }
        if (m.status == MissionStatus::Flown) == m.visits.is_empty() {
            problems.push(format!(
                "mission {} {:?} with {} visits",
                m.id,
                m.status,
                m.visits.len()
            ));
        }
    }
    Ok((problems, digest(p.store())?))
}

/// Kill points `1..=steps`: `n` spread evenly, the first and the last included.
fn kill_points(steps: u64, n: usize) -> Vec<u64> {
    let n = n.max(1) as u64;
    let mut v: Vec<u64> = (0..n)
        .map(|i| {
            if n == 1 {
                steps
            } else {
                1 + i * (steps - 1) / (n - 1)
            }
        })
        .collect();
    v.dedup();
    v
}

/// The trials of one use case on one backend.
struct Trials<'a, 'b> {
    fixture: &'a Fixture,
    case: UseCase,
    backend: Backend,
    pg: Option<&'a str>,
    work: &'a Path,
    /// Trials so far over the whole harness (PostgreSQL schemas are named after them).
    trial: &'a mut usize,
    run_child: &'a mut ChildRunner<'b>,
}

/// The states a complete run starts and ends in, and its write steps.
struct Reference {
    before: Digest,
    after: Digest,
    steps: u64,
}

impl Trials<'_, '_> {
    fn schema(k: usize) -> String {
        format!("crash_{}_{k}", std::process::id())
    }

    /// A trial project: a copy of the use case's start; on PostgreSQL, its data in a fresh
    /// project `schema` (the `--database` to pass). Returns that option.
    fn project(&self, dir: &Path, schema: &str) -> Result<Option<String>> {
        copy_project(self.fixture.start(self.case), dir)?;
        let Some(url) = self.pg else { return Ok(None) };
        let _ = PgStore::drop_project(url, schema);
        let source = Project::open(dir)?;
        let mut target = Database::Postgres {
            url: url.to_string(),
            project: schema.to_string(),
        }
        .open()?;
        crate::migrate(source.store(), &mut target, &Silent)?;
        Ok(Some(format!("{url}#{schema}")))
    }

    /// Drops a PostgreSQL trial project.
    fn drop(&self, database: &Option<String>, schema: &str) -> Result<()> {
        if let (Some(url), Some(_)) = (self.pg, database) {
            PgStore::drop_project(url, schema)?;
        }
        Ok(())
    }

    fn run(
        &mut self,
        dir: &Path,
        database: &Option<String>,
        kill_after: Option<u64>,
        report: Option<&Path>,
    ) -> std::result::Result<bool, String> {
        (self.run_child)(&ChildRun {
            case: self.case,
            project: dir,
            database: database.as_deref(),
            files: self.fixture.files(self.case),
            kill_after,
            report,
        })
    }

    fn label(&self) -> String {
        format!("{} {}", self.backend.name(), self.case.name())
    }

    /// The complete run: its step count and end state.
    fn reference(&mut self) -> Result<Reference> {
        let dir = self.work.join("reference");
        let db = self.project(&dir, &Self::schema(0))?;
        let (_, before) = inspect(&dir, db.as_deref())?;
        let report = self.work.join("steps");
        let _ = std::fs::remove_file(&report);
        self.run(&dir, &db, None, Some(&report)).map_err(invalid)?;
        let steps: u64 = read_text(&report)
            .map_err(|_| invalid("the complete run reported no write steps"))?
            .trim()
            .parse()
            .map_err(|e| invalid(format!("{}: {e}", report.display())))?;
        let (problems, after) = inspect(&dir, db.as_deref())?;
        if !problems.is_empty() || after == before {
            return Err(invalid(format!(
                "{}: the complete run left {problems:?} (changed: {})",
                self.label(),
                after != before
            )));
        }
        self.drop(&db, &Self::schema(0))?;
        Ok(Reference {
            before,
            after,
            steps,
        })
    }

    /// The complete run, then the kill points.
    fn sweep(&mut self, n: usize) -> Result<(u64, Tally)> {
        let reference = self.reference()?;
        let mut tally = Tally::default();
        for k in kill_points(reference.steps, n) {
            *self.trial += 1;
            tally.trials += 1;
            self.kill_at(k, &reference, &mut tally)?;
        }
        Ok((reference.steps, tally))
    }

    /// One trial: killed at step `k`, the store judged, then the rerun.
    fn kill_at(&mut self, k: u64, reference: &Reference, tally: &mut Tally) -> Result<()> {
        let label = format!("{} killed at step {k}/{}", self.label(), reference.steps);
        let dir = self.work.join("trial");
        let schema = Self::schema(*self.trial);
        let db = self.project(&dir, &schema)?;
        let killed = self
            .run(&dir, &db, Some(k), None)
            .map_err(|e| invalid(format!("{label}: {e}")))?;
        let (problems, state) = inspect(&dir, db.as_deref())?;
        if !problems.is_empty() {
            tally
                .failures
                .push(format!("{label}: integrity: {problems:?}"));
        } else if !killed {
            tally.completed += 1;
        } else if state == reference.before {
            tally.rolled_back += 1;
        } else if state == reference.after {
            tally.committed += 1;
        } else {
            tally
                .failures
                .push(format!("{label}: partial state (neither before nor after)"));
        }
        // Rerunning completes, and ends where a complete run ends.
        if killed {
            match self.run(&dir, &db, None, None) {
                Ok(_) => {
                    let (problems, state) = inspect(&dir, db.as_deref())?;
                    if !problems.is_empty() || state != reference.after {
                        tally.failures.push(format!(
                            "{label}: rerun ended elsewhere: {problems:?}; differs in {}",
                            differing_parts(&state, &reference.after)
                        ));
                    }
                }
                Err(e) => tally.failures.push(format!("{label}: rerun failed: {e}")),
            }
        }
        self.drop(&db, &schema)
    }
}

#[cfg(test)]
mod tests {
    use super::kill_points;

    #[test]
    fn kill_points_spread_over_the_steps_with_both_ends() {
        assert_eq!(kill_points(10, 1), vec![10]);
        assert_eq!(kill_points(10, 4), vec![1, 4, 7, 10]);
        assert_eq!(kill_points(3, 10), vec![1, 2, 3]);
        assert_eq!(kill_points(1, 5), vec![1]);
    }
}
