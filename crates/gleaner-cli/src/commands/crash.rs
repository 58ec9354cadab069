//! `gleaner crash-test`: the crash-safety harness. Kills `gleaner ingest`, `plan` and
//! `record` with SIGKILL at chosen write steps, on SQLite and on PostgreSQL, then checks the
//! store.
//!
//! A kill point is a count of the store's write steps (one statement or one block of bulk
//! rows of a write transaction, or its commit; `GLEANER_CRASH_AFTER`, see
//! `gleaner_store::failpoint`): the child process kills itself with SIGKILL exactly there,
//! so the trials are driven by what has been written, never by timing. For each use case the
//! harness first runs it once to completion on a copy of its starting project (learning its
//! step count and its end state), then for every kill point:
//!
//! 1. copies the starting project (an SQLite file, or a fresh PostgreSQL project filled by
//!    `migrate`), runs the use case as a child process killed at that step;
//! 2. checks the store: the backend's integrity check passes, and its content (every table
//!    but wall-clock provenance) equals the state before the use case or the state after a
//!    complete run, never anything in between (no partial ingest, no mission without stops,
//!    no half-recorded flight), which also means no committed reading was lost;
//! 3. reruns the use case without a kill: it completes, and the store equals the complete
//!    run's end state.

use std::fmt::Write as _;
use std::os::unix::process::ExitStatusExt as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use anyhow::{Context, Result, bail};
use clap::{Args, ValueEnum};
use gleaner_app::{self as app, AnyStore, Database, Project, Silent, StoreRead};

/// `gleaner crash-test` arguments.
#[derive(Args)]
pub struct CrashArgs {
    /// Kill points per use case and backend (spread evenly over the use case's write steps,
    /// the first and the last included).
    #[arg(long, default_value_t = 34)]
    pub kill_points: usize,
    /// Backends to test.
    #[arg(long, value_enum, default_value_t = Backends::Both)]
    pub backend: Backends,
    /// PostgreSQL server (`postgres://...`) [default: GLEANER_TEST_PG_URL].
    #[arg(long, env = "GLEANER_TEST_PG_URL")]
    pub postgres: Option<String>,
    /// Working directory for the trial projects [default: a temporary directory].
    #[arg(long)]
    pub work: Option<PathBuf>,
    /// Use cases to test.
    #[arg(long, value_enum, value_delimiter = ',', default_values_t = [UseCase::FirstIngest, UseCase::Ingest, UseCase::Plan, UseCase::Record])]
    pub use_cases: Vec<UseCase>,
    /// The shared data directory [default: GLEANER_DATA_DIR or ../shared/data].
    #[arg(long, env = "GLEANER_DATA_DIR", default_value = "../shared/data")]
    pub data: PathBuf,
}

/// Which backends a run covers.
#[derive(Clone, Copy, ValueEnum, PartialEq, Eq)]
pub enum Backends {
    /// SQLite only.
    Sqlite,
    /// PostgreSQL only.
    Postgres,
    /// Both.
    Both,
}

/// The use cases under test.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum UseCase {
    /// `gleaner ingest` of half the CAF stations' 2011 files into a project holding no
    /// readings yet (PostgreSQL's bulk load: the primary key dropped and built again).
    FirstIngest,
    /// `gleaner ingest` of half the CAF stations' 2011 files into a project holding the other
    /// half.
    Ingest,
    /// `gleaner plan` at 2012-01-01 (seed 1, 200 iterations) on all of 2011.
    Plan,
    /// `gleaner record` of mission 1 with the visited stations' January 2012 readings.
    Record,
}

impl UseCase {
    fn name(self) -> &'static str {
        match self {
            Self::FirstIngest => "first-ingest",
            Self::Ingest => "ingest",
            Self::Plan => "plan",
            Self::Record => "record",
        }
    }

    /// The `gleaner` subcommand it runs.
    fn command(self) -> &'static str {
        match self {
            Self::FirstIngest | Self::Ingest => "ingest",
            Self::Plan => "plan",
            Self::Record => "record",
        }
    }
}

/// What one kill point did.
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
    flight: PathBuf,
}

/// Runs the harness; returns the report (a table) and whether every trial passed.
pub fn run(args: &CrashArgs) -> Result<(String, bool)> {
    let tmp;
    let work = match &args.work {
        Some(w) => w.clone(),
        None => {
            tmp = tempdir()?;
            tmp.clone()
        }
    };
    let postgres = match args.backend {
        Backends::Sqlite => None,
        _ => Some(args.postgres.clone().context(
            "PostgreSQL needs --postgres or GLEANER_TEST_PG_URL (scripts/pg-cluster.sh starts a server)",
        )?),
    };
    let fixture = fixture(&args.data, &work.join("fixture"))?;
    let mut report = String::from(
        "backend   use case  steps  trials  rolled back  committed  completed  failures\n",
    );
    let mut ok = true;
    let mut totals = Tally::default();
    let backends: Vec<Option<&str>> = match args.backend {
        Backends::Sqlite => vec![None],
        Backends::Postgres => vec![postgres.as_deref()],
        Backends::Both => vec![None, postgres.as_deref()],
    };
    let mut trial = 0usize;
    for pg in backends {
        for &case in &args.use_cases {
            let (steps, tally) = sweep(&fixture, case, pg, args.kill_points, &work, &mut trial)?;
            writeln!(
                report,
                "{:<9} {:<9} {:>5}  {:>6}  {:>11}  {:>9}  {:>9}  {:>8}",
                if pg.is_some() { "postgres" } else { "sqlite" },
                case.name(),
                steps,
                tally.trials,
                tally.rolled_back,
                tally.committed,
                tally.completed,
                tally.failures.len()
            )?;
            for f in &tally.failures {
                writeln!(report, "  FAIL {f}")?;
            }
            ok &= tally.failures.is_empty();
            totals.trials += tally.trials;
            totals.rolled_back += tally.rolled_back;
            totals.committed += tally.committed;
            totals.completed += tally.completed;
            totals.failures.extend(tally.failures);
        }
    }
    writeln!(
        report,
        "total: {} kill points, {} rolled back, {} committed, {} completed, {} failures (integrity, partial state, lost readings, rerun)",
        totals.trials,
        totals.rolled_back,
        totals.committed,
        totals.completed,
        totals.failures.len()
    )?;
    if args.work.is_none() {
        let _ = std::fs::remove_dir_all(&work);
    }
    Ok((report, ok))
}

/// A new temporary directory.
fn tempdir() -> Result<PathBuf> {
    let dir = std::env::temp_dir().join(format!("gleaner-crash-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir)?;
    Ok(dir)
}

/// Builds the starting projects from the real CAF data: 2011 readings, first half of the
/// stations ingested (ingest adds the second half); all of 2011 (plan plans a mission at
/// 2012-01-01); that plus the planned mission #1 (record records it with the visited
/// stations' January 2012 readings).
fn fixture(data: &Path, dir: &Path) -> Result<Fixture> {
    let _ = std::fs::remove_dir_all(dir);
    std::fs::create_dir_all(dir)?;
    let daily = data.join("caf/Daily");
    let mut names: Vec<PathBuf> = std::fs::read_dir(&daily)
        .with_context(|| format!("{} (set GLEANER_DATA_DIR)", daily.display()))?
        .map(|e| e.map(|e| e.path()))
        .collect::<std::io::Result<_>>()?;
    names.sort();
    let input = dir.join("input");
    std::fs::create_dir_all(&input)?;
    let mut files = Vec::new();
    for path in &names {
        let text = std::fs::read_to_string(path)?;
        let mut lines = text.lines();
        let mut kept: Vec<&str> = lines.next().into_iter().collect();
        kept.extend(lines.filter(|l| l.split('\t').nth(1).is_some_and(|d| d.ends_with("/2011"))));
        let target = input.join(path.file_name().context("file name")?);
        std::fs::write(&target, kept.join("\n") + "\n")?;
        files.push(target);
    }
    let (first, second) = files.split_at(files.len() / 2);
    let ingest_start = dir.join("ingest");
    let (p, _) = app::init(&app::InitRequest {
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
    let mut p = Project::open(&record_start)?;
    let planned = app::plan(&mut p, &plan_request(), 0)?;
    let mission = app::mission(&p, planned.id.context("stored mission")?)?;
    // The visited stations' real January 2012 VW readings, as a long CSV.
    let cells: std::collections::HashSet<_> =
        mission.mission.stops.iter().map(|s| s.cell).collect();
    let mut csv = String::from("sensor_id,timestamp,modality,value\n");
    for cell in p.store().cells()? {
        if !cells.contains(&cell.index) {
            continue;
        }
        for s in &cell.sensors {
            let text = std::fs::read_to_string(daily.join(format!("{s}.txt")))?;
            for line in text.lines().skip(1) {
                let f: Vec<&str> = line.split('\t').collect();
                if let [_, date, vw, ..] = f[..]
                    && let [m, d, y] = date.split('/').collect::<Vec<_>>()[..]
                    && y == "2012"
                    && m == "01"
                    && vw != "NA"
                {
                    writeln!(csv, "{s},2012-01-{d},vw@30cm,{vw}")?;
                }
            }
        }
    }
    let flight = dir.join("flight.csv");
    std::fs::write(&flight, csv)?;
    Ok(Fixture {
        first_ingest_start,
        ingest_start,
        plan_start,
        record_start,
        first_files: first.to_vec(),
        ingest_files: second.to_vec(),
        flight,
    })
}

fn ingest(p: &mut Project<AnyStore>, files: &[PathBuf]) -> Result<()> {
    app::ingest(
        p,
        &app::IngestRequest {
            files: files.to_vec(),
            ..Default::default()
        },
        0,
        &Silent,
    )?;
    Ok(())
}

/// The plan every trial makes: fixed time, seed and iteration cap (deterministic).
fn plan_request() -> app::PlanRequest {
    app::PlanRequest {
        at: app::parse_timestamp("2012-01-01"),
        seed: Some(1),
        max_iterations: Some(200),
        time_limit_s: Some(60.0),
        ..Default::default()
    }
}

/// Copies an SQLite project directory (settings and a checkpointed database).
fn copy_project(from: &Path, to: &Path) -> Result<()> {
    let _ = std::fs::remove_dir_all(to);
    std::fs::create_dir_all(to)?;
    for name in ["gleaner.toml", "gleaner.db"] {
        std::fs::copy(from.join(name), to.join(name))
            .with_context(|| format!("copying {}", from.join(name).display()))?;
    }
    // The sensors file is referenced relative to the project directory.
    let settings = app::Settings::load(from)?;
    let mut s = settings.clone();
    s.sensors.file = from
        .join(&settings.sensors.file)
        .to_string_lossy()
        .into_owned();
    s.save(to)?;
    Ok(())
}

/// A trial project: a copy of `start`; on PostgreSQL, its data in a fresh project `schema`
/// (the `--database` to pass). Returns that option.
fn trial_project(
    start: &Path,
    dir: &Path,
    pg: Option<&str>,
    schema: &str,
) -> Result<Option<String>> {
    copy_project(start, dir)?;
    let Some(url) = pg else { return Ok(None) };
    let _ = app::PgStore::drop_project(url, schema);
    let source = Project::open(dir)?;
    let mut target = Database::Postgres {
        url: url.to_string(),
        project: schema.to_string(),
    }
    .open()?;
    app::migrate(source.store(), &mut target, &Silent)?;
    Ok(Some(format!("{url}#{schema}")))
}

/// Runs the use case as a child process; `kill_at` sets `GLEANER_CRASH_AFTER`, `report`
/// `GLEANER_CRASH_REPORT`. Returns whether it was killed by SIGKILL.
fn run_child(
    fixture: &Fixture,
    case: UseCase,
    dir: &Path,
    database: &Option<String>,
    kill_at: Option<u64>,
    report: Option<&Path>,
) -> Result<bool> {
    let mut cmd = Command::new(std::env::current_exe()?);
    cmd.arg(case.command()).arg("--project").arg(dir);
    if let Some(db) = database {
        cmd.arg("--database").arg(db);
    }
    match case {
        UseCase::FirstIngest => {
            cmd.args(&fixture.first_files);
        }
        UseCase::Ingest => {
            cmd.args(&fixture.ingest_files);
        }
        UseCase::Plan => {
            cmd.args(["--at", "2012-01-01", "--seed", "1", "--iterations", "200"]);
            cmd.args(["--time-limit", "60"]);
        }
        UseCase::Record => {
            cmd.args(["--mission", "1", "--at", "2012-02-01"]);
            cmd.arg(&fixture.flight);
        }
    }
    cmd.env_remove("GLEANER_CRASH_AFTER")
        .env_remove("GLEANER_CRASH_REPORT")
        .env_remove("GLEANER_DATABASE");
    if let Some(k) = kill_at {
        cmd.env("GLEANER_CRASH_AFTER", k.to_string());
    }
    if let Some(r) = report {
        cmd.env("GLEANER_CRASH_REPORT", r);
    }
    let out = cmd
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .output()?;
    if out.status.signal() == Some(9) {
        return Ok(true);
    }
    if !out.status.success() {
        bail!(
            "{} failed: {}",
            case.name(),
            String::from_utf8_lossy(&out.stderr).trim()
        );
    }
    Ok(false)
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
fn inspect(dir: &Path, database: &Option<String>) -> Result<(Vec<String>, Digest)> {
    let p = Project::open_with(dir, database.as_deref())?;
    let problems = p.store().integrity_check()?;
    // Every mission has its stops; a flown one its visits.
    let mut problems = problems;
    for m in p.store().missions()? {
        if m.mission.stops.is_empty() {
            problems.push(format!("mission {} without stops", m.id));
        }
        if (m.status == app::MissionStatus::Flown) == m.visits.is_empty() {
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

/// One use case on one backend: the complete run, then the kill points.
fn sweep(
    fixture: &Fixture,
    case: UseCase,
    pg: Option<&str>,
    n: usize,
    work: &Path,
    trial: &mut usize,
) -> Result<(u64, Tally)> {
    let start = match case {
        UseCase::FirstIngest => &fixture.first_ingest_start,
        UseCase::Ingest => &fixture.ingest_start,
        UseCase::Plan => &fixture.plan_start,
        UseCase::Record => &fixture.record_start,
    };
    let backend = if pg.is_some() { "postgres" } else { "sqlite" };
    let schema = |k: usize| format!("crash_{}_{k}", std::process::id());
    // The complete run: its step count and end state.
    let dir = work.join("reference");
    let db = trial_project(start, &dir, pg, &schema(0))?;
    let (_, before) = inspect(&dir, &db)?;
    let report = work.join("steps");
    let _ = std::fs::remove_file(&report);
    run_child(fixture, case, &dir, &db, None, Some(&report))?;
    let steps: u64 = std::fs::read_to_string(&report)
        .context("the complete run reported no write steps")?
        .trim()
        .parse()?;
    let (problems, after) = inspect(&dir, &db)?;
    if !problems.is_empty() || after == before {
        bail!(
            "{backend} {}: the complete run left {problems:?} (changed: {})",
            case.name(),
            after != before
        );
    }
    if let (Some(url), Some(_)) = (pg, &db) {
        app::PgStore::drop_project(url, &schema(0))?;
    }
    let mut tally = Tally::default();
    for k in kill_points(steps, n) {
        *trial += 1;
        tally.trials += 1;
        let label = format!("{backend} {} killed at step {k}/{steps}", case.name());
        let dir = work.join("trial");
        let db = trial_project(start, &dir, pg, &schema(*trial))?;
        let killed =
            run_child(fixture, case, &dir, &db, Some(k), None).with_context(|| label.clone())?;
        let (problems, state) = inspect(&dir, &db)?;
        if !problems.is_empty() {
            tally
                .failures
                .push(format!("{label}: integrity: {problems:?}"));
        } else if !killed {
            tally.completed += 1;
        } else if state == before {
            tally.rolled_back += 1;
        } else if state == after {
            tally.committed += 1;
        } else {
            tally
                .failures
                .push(format!("{label}: partial state (neither before nor after)"));
        }
        // Rerunning completes, and ends where a complete run ends.
        if killed {
            match run_child(fixture, case, &dir, &db, None, None) {
                Ok(_) => {
                    let (problems, state) = inspect(&dir, &db)?;
                    if !problems.is_empty() || state != after {
                        tally.failures.push(format!(
                            "{label}: rerun ended elsewhere: {problems:?}; differs in {}",
                            differing_parts(&state, &after)
                        ));
                    }
                }
                Err(e) => tally.failures.push(format!("{label}: rerun failed: {e}")),
            }
        }
        if let (Some(url), Some(_)) = (pg, &db) {
            app::PgStore::drop_project(url, &schema(*trial))?;
        }
    }
    Ok((steps, tally))
}
