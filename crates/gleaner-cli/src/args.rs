//! What several commands take: the project (`--project`, `--database`), `--json`, the
//! mission time (`--at`, `--history-from`, `--history-until`), the method of a new project,
//! the argument parsers (times, positions, winds) and the wall clock.

use std::path::PathBuf;

use anyhow::Result;
use clap::{Args, ValueEnum};
use gleaner_app as app;
use gleaner_app::Project;

use crate::output::emit;

/// `--project`: the project directory.
#[derive(Args)]
pub(crate) struct ProjectArg {
    /// Project directory.
    #[arg(
        long = "project",
        id = "project",
        value_name = "PROJECT",
        default_value = "."
    )]
    pub(crate) dir: PathBuf,
    /// The project's database instead of its `database` setting: an SQLite file (relative to
    /// the project directory) or `postgres://user:password@host:port/db[#schema]`.
    #[arg(long, value_name = "FILE_OR_URL", env = "GLEANER_DATABASE")]
    pub(crate) database: Option<String>,
}

impl ProjectArg {
    pub(crate) fn open(&self) -> Result<Project<app::AnyStore>> {
        Ok(Project::open_with(&self.dir, self.database.as_deref())?)
    }
}

/// `--json`: JSON on standard output instead of a table.
#[derive(Args)]
pub(crate) struct JsonArg {
    /// Print JSON instead of a table.
    #[arg(long)]
    pub(crate) json: bool,
}

impl JsonArg {
    /// Prints `value` as pretty JSON when `--json`, else the text `table` renders.
    pub(crate) fn emit<T: serde::Serialize>(
        &self,
        value: &T,
        what: &str,
        table: impl FnOnce() -> String,
    ) -> Result<()> {
        emit(self.json, value, what, table)
    }
}

/// The mission time and which stored readings count as collected by then.
#[derive(Args)]
pub(crate) struct WhenArgs {
    /// Mission time (RFC 3339 or YYYY-MM-DD, UTC; years 1900..=2199) [default: the latest
    /// reading]. Only data up to this time is used.
    #[arg(long, value_parser = parse_time)]
    pub(crate) at: Option<i64>,
    /// Use only readings from this time on (RFC 3339 or date) as collected history.
    #[arg(long, value_parser = parse_time)]
    pub(crate) history_from: Option<i64>,
    /// Use only readings up to this time as collected history (later ones are not yet
    /// collected at the mission time, unless a recorded collection brought them back), e.g.
    /// score 2014 from 2011-2013 data.
    #[arg(long, value_parser = parse_time)]
    pub(crate) history_until: Option<i64>,
}

impl WhenArgs {
    pub(crate) fn history(&self) -> app::History {
        app::History {
            from: self.history_from.unwrap_or(i64::MIN),
            until: self.history_until.unwrap_or(i64::MAX),
        }
    }
}

/// `--method` of a new project (`init`, `demo`): the paper's score or gleaner's.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum MethodArg {
    Paper,
    Gleaner,
}

/// `LAT,LON` in degrees.
pub(crate) fn parse_lat_lon(s: &str) -> Result<(f64, f64), String> {
    let (a, b) = s
        .split_once(',')
        .ok_or_else(|| format!("expected LAT,LON, got {s:?}"))?;
    let lat = a
        .trim()
        .parse()
        .map_err(|_| format!("bad latitude {a:?}"))?;
    let lon = b
        .trim()
        .parse()
        .map_err(|_| format!("bad longitude {b:?}"))?;
    Ok((lat, lon))
}

/// A wind as `SPEED@FROM` (m/s, degrees from north), as the app reads it.
pub(crate) fn parse_wind(s: &str) -> Result<app::Wind, String> {
    app::wind::parse(s).map_err(|e| e.to_string())
}

/// A time as RFC 3339 or a date (UTC), seconds since the epoch.
pub(crate) fn parse_time(s: &str) -> Result<i64, String> {
    gleaner_app::parse_timestamp(s).ok_or_else(|| {
        format!("expected RFC 3339 (2014-03-01T12:00:00Z) or a date (2014-03-01), got {s:?}")
    })
}

/// The wall clock, seconds since the epoch: provenance only (creation times), never results.
pub(crate) fn clock_now() -> i64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs() as i64)
}
