//! `gleaner crash-test`: the crash-safety harness (`gleaner_app::crash_test`). This module
//! translates the arguments, runs each child as this binary's own `ingest`, `plan` or
//! `record` with `GLEANER_CRASH_AFTER` set, and tabulates the sweeps.

use std::os::unix::process::ExitStatusExt as _;
use std::path::PathBuf;
use std::process::{Command, Stdio};

use anyhow::Result;
use clap::{Args, ValueEnum};
use gleaner_app::crash_test::{self as harness, Backend, ChildRun, CrashTestRequest};

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

impl From<UseCase> for harness::UseCase {
    fn from(u: UseCase) -> Self {
        match u {
            UseCase::FirstIngest => Self::FirstIngest,
            UseCase::Ingest => Self::Ingest,
            UseCase::Plan => Self::Plan,
            UseCase::Record => Self::Record,
        }
    }
}

/// Runs the use case as a child process of this binary. Returns whether it was killed by
/// SIGKILL.
fn run_child(run: &ChildRun) -> Result<bool, String> {
    use harness::UseCase;
    let exe = std::env::current_exe().map_err(|e| e.to_string())?;
    let mut cmd = Command::new(exe);
    let command = match run.case {
        UseCase::FirstIngest | UseCase::Ingest => "ingest",
        UseCase::Plan => "plan",
        UseCase::Record => "record",
    };
    cmd.arg(command).arg("--project").arg(run.project);
    if let Some(db) = run.database {
        cmd.arg("--database").arg(db);
    }
    if run.case == UseCase::Plan {
        cmd.args(["--at", harness::PLAN_AT]);
        cmd.args(["--seed", &harness::PLAN_SEED.to_string()]);
        cmd.args(["--iterations", &harness::PLAN_ITERATIONS.to_string()]);
        cmd.args(["--time-limit", &harness::PLAN_TIME_LIMIT_S.to_string()]);
    }
    if run.case == UseCase::Record {
        cmd.args(["--mission", &harness::RECORD_MISSION.to_string()]);
        cmd.args(["--at", harness::RECORD_AT]);
    }
    cmd.args(run.files);
    cmd.env_remove("GLEANER_CRASH_AFTER")
        .env_remove("GLEANER_CRASH_REPORT")
        .env_remove("GLEANER_DATABASE");
    if let Some(k) = run.kill_after {
        cmd.env("GLEANER_CRASH_AFTER", k.to_string());
    }
    if let Some(r) = run.report {
        cmd.env("GLEANER_CRASH_REPORT", r);
    }
    let out = cmd
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .output()
        .map_err(|e| e.to_string())?;
    if out.status.signal() == Some(9) {
        return Ok(true);
    }
    if !out.status.success() {
        return Err(format!(
            "{} failed: {}",
            run.case.name(),
            String::from_utf8_lossy(&out.stderr).trim()
        ));
    }
    Ok(false)
}

/// Runs the harness; returns the report (a table) and whether every trial passed.
pub fn run(args: &CrashArgs) -> Result<(String, bool)> {
    let backends = match args.backend {
        Backends::Sqlite => vec![Backend::Sqlite],
        Backends::Postgres => vec![Backend::Postgres],
        Backends::Both => vec![Backend::Sqlite, Backend::Postgres],
    };
    let request = CrashTestRequest {
        data: args.data.clone(),
        work: args.work.clone(),
        backends,
        postgres: args.postgres.clone(),
        use_cases: args.use_cases.iter().map(|&u| u.into()).collect(),
        kill_points: args.kill_points,
    };
    let sweeps = harness::crash_test(&request, &mut run_child)?;
    Ok(gleaner_wire::text::crash_report(sweeps))
}
