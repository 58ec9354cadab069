//! `gleaner`: plans UAV data-collection missions over a farm's sensor network so that each
//! flight brings back the data worth most to science.
//!
//! This binary is the only place that knows clap: arguments are parsed here, turned into plain
//! settings, and handed to the `commands` modules.

mod args;
mod commands;
mod output;
mod progress;

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;
use clap::{Parser, Subcommand};

use commands::{
    bench, cells, crash, demo, evaluate, explore, export, ingest, init, migrate, missions, plan,
    reconstruct, record, replan, score, serve, simulate, synth,
};
use output::{out, outln};

/// Evaluation protocols.
#[derive(Debug, Subcommand)]
enum EvaluateCommand {
    /// The peer study's one-shot selection protocol on CAF: 5 random layouts of 32 sensors
    /// and the real one, capacities 0-42 kJ (10 J/m + 70 J per visit, one free), the visited
    /// sensors known at every test hour, the others estimated (carried forward, the Gaussian
    /// conditional of levels, gleaner's dynamic field model); writes outcomes.csv and
    /// summary.md beside the peer's published errors.
    #[command(
        after_help = "The frozen settings and the tuning behind them: docs/evaluation/.\n\nExamples:\n  gleaner evaluate peer --out eval/peer\n  gleaner evaluate peer --on tuning --out eval/peer-tuning\n  gleaner evaluate peer --on hubbard-brook --out eval/peer-hb"
    )]
    Peer(evaluate::PeerArgs),
}

/// Utility-driven UAV data collection for farm sensor networks.
///
/// A project is a directory with `gleaner.toml` (settings) and `gleaner.db` (SQLite: sensors,
/// readings, cells and the cell metadata table, missions).
#[derive(Parser)]
#[command(name = "gleaner", version, about, long_about = None, after_help = "Start with `gleaner demo` for a tour on a synthetic farm.")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Create a project from a sensors file: settings, database, sensors and the cell grid.
    #[command(
        after_help = "Examples:\n  gleaner init --dir farm --sensors sensors.csv --cell-size 40\n  gleaner init --dir caf --sensors ../shared/data/caf/sensors/CAF_sensor_locations.csv --utm-zone 11N\n  gleaner init --dir farm --sensors sensors.csv --method gleaner   (plan by gleaner's method)\n  gleaner init --dir farm --sensors sensors.csv --geofence fence.geojson --no-fly buildings.geojson --no-fly-buffer 5"
    )]
    Init(commands::init::InitArgs),
    /// Ingest readings files into the project, all or nothing; re-ingesting changes nothing.
    #[command(
        after_help = "Formats (auto-detected from the header):\n  long-csv   sensor_id,timestamp,modality,value[,unit]   (RFC 3339 or YYYY-MM-DD)\n  wide-csv   Date[,Time] or timestamp, then one column per sensor (needs --modality)\n  caf-daily  CAF daily files: Location<TAB>Date<TAB>VW_30cm ... T_150cm, NA = missing\n  hubbard-brook  logger files timestamp,p<port>:<model>:<variable>:<unit> (UTC-04:00), with\n             sensor_metadata.csv beside them or --metadata\n\nExamples:\n  gleaner ingest --project farm readings.csv\n  gleaner ingest --project caf ../shared/data/caf/Daily/*.txt\n  gleaner ingest --project caf --modality vw@30cm hourly.csv"
    )]
    Ingest(commands::ingest::IngestArgs),
    /// Show the cell table with its metadata (summaries, scores, pending data).
    #[command(
        after_help = "Examples:\n  gleaner cells --project farm\n  gleaner cells --project farm --sort score --json"
    )]
    Cells(commands::cells::CellsArgs),
    /// Score every cell at a mission time: F, R, A, U and S, printed and kept in the cell
    /// metadata table.
    #[command(
        after_help = "S is gated, alpha·F·max(0, 1 + beta·A + gamma·U − delta·R) (score_form = \"gated\", what `init`\nwrites by default), or additive, alpha·F + beta·A + gamma·U − delta·R (\"additive\", `init --method\npaper`), with the weights of [utility] in gleaner.toml.\nU comes from the built-in condition model (dry/adequate/wet from soil moisture) or from\n--probabilities (CSV: cell_id,p_1,...,p_K with a header).\n\nExamples:\n  gleaner score --project caf --at 2014-03-01 --history-from 2011-01-01 --history-until 2013-12-31\n  gleaner score --project farm --json --limit 20"
    )]
    Score(commands::score::ScoreArgs),
    /// Plan a mission: score the cells (or read --scores), then choose and order the cells that
    /// fit the battery, and print the mission summary (table or JSON). The mission is stored as
    /// planned.
    #[command(
        after_help = "Energy settings come from [energy] in gleaner.toml (preset `paper`: 66.5 kJ usable,\nmax-endurance cruise, 30 s hover overhead).\n\nExamples:\n  gleaner plan --project farm\n  gleaner plan --project caf --at 2014-03-01 --history-until 2013-12-31 --solver greedy\n  gleaner plan --project farm --scores my_scores.csv --json"
    )]
    Plan(commands::plan::PlanArgs),
    /// Plan the exploration phase: as few sorties as possible, each within the battery, that
    /// together visit every cell; each sortie is stored as an exploration mission.
    #[command(
        after_help = "Examples:\n  gleaner explore --project farm\n  gleaner explore --project caf --json --dry-run"
    )]
    Explore(commands::explore::ExploreArgs),
    /// Export a planned mission for flying and mapping: GeoJSON (cells with their scores, the
    /// route, the base), a QGroundControl .plan, a QGC WPL 110 waypoint file, a DJI WPML
    /// archive (mission.kmz, for DJI Pilot 2) and an SVG map.
    #[command(
        after_help = "Waypoints: take-off, the cruise speed the energy model assumed (MAV_CMD_DO_CHANGE_SPEED,\n178), one NAV_WAYPOINT (16) per cell at the cell centre holding for the\nplanned hold (param 1: the hover rounded up to 0.25 s), return-to-launch (20); altitude from\n[energy] altitude_m. Every flight file is read back and its energy recomputed from what it\ncommands; a file above the usable budget is refused.\n\nmission.kmz (wpmz/template.kml + wpmz/waylines.wpml) follows DJI's published WPML reference:\nheights relative to the take-off point, the speed per waypoint, a hover action per waypoint,\nreturn home at the end. It has not been flown; check it in DJI Pilot 2 first. Not written when\nthe speed exceeds WPML's 15 m/s.\n\nExamples:\n  gleaner export --project farm --mission 1\n  gleaner export --project farm --mission 1 --out flight1\n  gleaner export --project farm --mission 1 --dji-drone 77 --dji-drone-sub 2 --dji-payload 68"
    )]
    Export(commands::export::ExportArgs),
    /// Re-plan a mission in the air: the best continuation from the stop the aircraft is
    /// over with the energy it has left — the remaining stops dropped and reordered so that it
    /// still reaches the base with the battery's reserve — written as a new file set
    /// (.plan, WPL, GeoJSON, JSON) that starts where the aircraft is.
    #[command(
        after_help = "The continuation's files have no take-off: DO_CHANGE_SPEED to the mission's speed, a 0 s\nwaypoint where the aircraft is, the kept stops with their holds, return-to-launch. Their energy\nis recomputed from what they command (no climb; the descent at the base) and must fit the energy\nleft less the reserve ([energy] battery_j x reserve_fraction). Nothing is stored: record the\nflight against the mission itself (its stops include the continuation's).\n\nExamples:\n  gleaner replan --project farm --mission 3 --after-stop 4 --energy-left 30000\n  gleaner replan --project farm --mission 3 --after-stop 0 --energy-left 52000 --json"
    )]
    Replan(commands::replan::ReplanArgs),
    /// Draw the exploration overview: every exploration sortie on one map, one colour each
    /// (SVG and PNG).
    #[command(after_help = "Example:\n  gleaner map-exploration --project farm")]
    MapExploration(commands::export::MapExplorationArgs),
    /// Record a flown mission: the cells visited, when, and the readings brought back; the
    /// visited cells' sensors count as collected from then on.
    #[command(
        after_help = "Examples:\n  gleaner record --project farm --mission 1\n  gleaner record --project farm --mission 1 --at 2014-06-30T10:00:00Z --cells x1y2,x3y0 flight1.csv"
    )]
    Record(commands::record::RecordArgs),
    /// List the missions (planned, flown and cancelled), or show one with its stops.
    #[command(
        after_help = "Without --limit or --before every mission is listed, oldest first. With either, one page is listed, newest first (by id, so missions planned meanwhile never shift a page), followed by the --before of the next page.\n\nExamples:\n  gleaner missions --project farm\n  gleaner missions --project farm --limit 20\n  gleaner missions --project farm --limit 20 --before 41\n  gleaner missions --project farm --mission 3 --json"
    )]
    Missions(commands::missions::MissionsArgs),
    /// Cancel a planned mission: it stays in the history, marked cancelled, and can no longer
    /// be recorded, exported or re-planned. A flown mission cannot be cancelled.
    #[command(after_help = "Examples:\n  gleaner cancel --project farm --mission 3")]
    Cancel(commands::missions::CancelArgs),
    /// Delete a mission that was never flown (planned or cancelled) with its stops. A flown
    /// mission, the record of stored readings, is kept.
    #[command(after_help = "Examples:\n  gleaner delete --project farm --mission 3")]
    Delete(commands::missions::DeleteArgs),
    /// Benchmarks.
    #[command(subcommand)]
    Bench(BenchCommand),
    /// Write a seeded synthetic farm (sensors, long readings, ground truth, faults) as CSV.
    #[command(
        after_help = "Defaults are calibrated to the CAF network, 2012-13 (seasons, rain, drainage, depth lag, synchrony, faults, value distributions, spatial correlation; see docs/synth-calibration.md). Each farm has ground-truth events (leaks, dry patches, failing sensors; 7-28 days).\n\nExamples:\n  gleaner synth --out farm-data --sensors 60 --days 120 --seed 1\n  gleaner synth --out big --sensors 10000 --days 365 --scale-extent --vw-depths 30 --t-depths 30"
    )]
    Synth(synth::SynthArgs),
    /// Copy the project's data into another database, losslessly and all or nothing: an
    /// SQLite project into PostgreSQL, or back.
    #[command(
        after_help = "Examples:\n  gleaner migrate --project farm --to postgres://gleaner@localhost/farms\n  gleaner migrate --project farm --to 'postgres://gleaner@localhost/farms#farm_a' --switch\n  gleaner migrate --project farm --database postgres://gleaner@localhost/farms --to farm-copy.db"
    )]
    Migrate(migrate::MigrateArgs),
    /// Crash-safety harness: kill `ingest` (into an empty and a filled project), `plan` and
    /// `record` with SIGKILL at evenly spread write steps on SQLite and PostgreSQL, then check
    /// integrity, all-or-nothing and that a rerun completes (real CAF data; a benchmark-style
    /// run, minutes).
    #[command(
        name = "crash-test",
        after_help = "Examples:\n  gleaner crash-test --kill-points 34          # up to 272 kill points: 4 use cases x 2 backends\n  gleaner crash-test --backend sqlite --kill-points 5"
    )]
    CrashTest(crash::CrashArgs),
    /// The main job on built-in data: synthetic farm -> project -> exploration sorties -> five
    /// daily missions, each planned (against the paper's greedy), exported, flown in simulation
    /// and recorded -> rescoring. `--data` runs it on the real CAF network.
    #[command(after_help = "Example:\n  gleaner demo --dir gleaner-demo --seed 1")]
    Demo(demo::DemoArgs),
    /// Serve the HTTP API (/api/v1) and the web dashboard for a project until ctrl-c.
    #[command(
        after_help = "Binds 127.0.0.1:8080 by default. Writes (saving a plan, scoring, uploads) need\n`Authorization: Bearer <token>`: the token comes from --token-file or GLEANER_TOKEN, or on\nloopback is drawn at start-up and printed once in the dashboard's address. Binding any other\naddress needs a token. Request log on standard error (GLEANER_LOG=debug for more).\n\nExamples:\n  gleaner serve --project caf\n  GLEANER_TOKEN=$(cat token) gleaner serve --project caf --addr 0.0.0.0:8080\n  gleaner serve --farms farms --addr 0.0.0.0:8080   # every farms/*/gleaner.toml, farm tokens in farms/tokens"
    )]
    Serve(serve::ServeArgs),
    /// Draw a token for one farm of a farms server (`serve --farms`): its SHA-256 is appended
    /// to the tokens file, the token printed once.
    #[command(
        after_help = "Example:\n  gleaner farm-token --farms farms --farm north --scope write > north.token"
    )]
    FarmToken(serve::FarmTokenArgs),
    /// Replay a dataset (or a project's own record) as a campaign of missions, one run per
    /// strategy, seed and budget, through the same score, plan and record use cases; writes CSV
    /// results and a report.
    #[command(
        after_help = "Each run is its own in-memory project: it starts with the history (readings available by
--history-until) and knows only what its flights bring back; a reading stamped t is
available from t + period on. After each mission every sensor's value is reconstructed
(last value carried forward, and kriging of changes: --level-kriging / --simple-kriging for
kriging of levels) and compared with the truth.

Examples:
  gleaner simulate --dataset caf-daily --out sims/caf
  gleaner simulate --dataset caf-daily --out sims/caf --strategies all --budgets 0.25,0.5,1,1.5,2
  gleaner simulate --dataset synthetic --out sims/synth --farm-seeds 1,2,3,4,5,6,7,8,9,10
  gleaner simulate --dataset hubbard-brook --out sims/hb   (large-pack battery)
  gleaner simulate --project farm --out sims/farm   (the farm's last 30 days)"
    )]
    Simulate(Box<simulate::SimulateArgs>),
    /// Run a published evaluation protocol and compare gleaner with the published results.
    #[command(subcommand)]
    Evaluate(EvaluateCommand),
    /// Write report.md (tables with 95% intervals, SVG charts) from a simulation directory.
    #[command(after_help = "Example:\n  gleaner report sims/caf")]
    Report {
        /// The directory `gleaner simulate --out` wrote.
        dir: PathBuf,
    },
    /// Estimate every sensor's current value of a modality from what is known: last value
    /// carried forward, and a model-based estimate (kriging of changes by default) with its
    /// standard deviation.
    #[command(
        after_help = "Models are fitted on the readings known at --at. The \"kriged\" column is by default kriging
of changes: each sensor's last known reading plus its change since, estimated from the changes
its neighbours read later made over that interval (a model of changes: a spatially correlated
field-wide part plus each sensor's own part; exactly the carried value when no neighbour knows
more). --dynamic: the dynamic field model (each sensor's mean, a covariance of levels between
sensors learned from history and shrunk, AR(1) persistence of the deviations, a Kalman filter
over the readings known: a sensor read lately is known from its own reading, one not read for
long from the sensors read now; docs/method.md §7); --levels: ordinary kriging of levels (a
separable exponential space-time covariance with a temporal nugget); --simple: simple kriging
of levels.

--from/--to/--every-hours: every sensor's mean, sd and 90% interval at each time of a range, by
the same estimator (one fit on the readings up to --to; each time uses only readings stamped at
or before it; the interval mean ± q·sd, q calibrated on back-tests: docs/method.md §7) as CSV
(time,sensor,mean,sd,lo90,hi90), or with --json the `gleaner.reconstruction-series` document
(as GET /api/v1/reconstruct?from=..&to=..).

--map FILE.svg|FILE.png: the map of the estimated field at --at, a two-panel figure for a paper
(178 mm wide; the PNG at 300 dpi): left the estimate, right its uncertainty (the posterior sd),
each cell coloured by its sensors' mean on a colour-blind-safe scale (viridis; reversed magma)
with a colour bar in the modality's unit; sensors read within one sampling step before the time
are dark discs, those only estimated white diamonds; the field's outline, a scale bar in
metres, a north arrow, and the modality, time (UTC) and estimator in the title (as GET
/api/v1/reconstruct/map.svg, .png).

--json: the `gleaner.reconstruction` document (as GET /api/v1/reconstruct): sd = the model's
standard deviation, lo90/hi90 the calibrated 90% interval (as in the table), positions WGS84
[lon, lat].

Examples:
  gleaner reconstruct --project caf --at 2014-03-01 --modality vw@30cm
  gleaner reconstruct --project caf --at 2014-03-01 --json
  gleaner reconstruct --project caf --from 2015-02-11 --to 2015-03-04 --every-hours 1 --out vw30.csv
  gleaner reconstruct --project caf --at 2014-03-01 --map vw30-2014-03-01.svg
  gleaner reconstruct --project caf --at 2014-03-01 --dynamic --map vw30-2014-03-01.png"
    )]
    Reconstruct(commands::reconstruct::ReconstructArgs),
}

#[derive(Subcommand)]
enum BenchCommand {
    /// Solve standard orienteering benchmarks (classic Tsiligirides/Chao sets and OPLib) and
    /// compare with the known targets; every route is re-checked with the instance's own
    /// distance rule.
    #[command(
        after_help = "Examples:\n  gleaner bench op ../shared/data/op/classic --time-limit 1\n  gleaner bench op ../shared/data/op/oplib --max-n 400 --time-limit 10 --csv oplib.csv\n  gleaner bench op ../shared/data/op/classic/Tsiligirides_1 --solver greedy"
    )]
    Op(bench::BenchOpArgs),
}

fn run(cli: Cli) -> Result<()> {
    let progress = progress::Terminal::default();
    match cli.command {
        Command::Init(args) => init::run(args),
        Command::Ingest(args) => ingest::run(args, &progress),
        Command::Cells(args) => cells::run(args),
        Command::Score(args) => score::run(args),
        Command::Plan(args) => plan::run(args),
        Command::Explore(args) => explore::run(args),
        Command::Export(args) => export::run(args),
        Command::Replan(args) => replan::run(args),
        Command::MapExploration(args) => export::map_exploration(args),
        Command::Record(args) => record::run(args, &progress),
        Command::Missions(args) => missions::run(args),
        Command::Cancel(args) => missions::cancel(args),
        Command::Delete(args) => missions::delete(args),
        Command::Bench(BenchCommand::Op(args)) => out(&bench::run(&args)?.1),
        Command::Synth(args) => outln(&synth::run(&args)?),
        Command::Demo(args) => out(&demo::run(&args)?),
        Command::Migrate(args) => outln(&migrate::run(args, &progress)?),
        Command::Serve(args) => serve::run(args),
        Command::FarmToken(args) => serve::farm_token(args),
        Command::Simulate(args) => {
            let line: Vec<String> = std::env::args().skip(1).collect();
            let command = format!("gleaner {}", line.join(" "));
            out(&simulate::run(&args, &command, &progress)?)
        }
        Command::Evaluate(EvaluateCommand::Peer(args)) => {
            print!("{}", evaluate::run_peer(&args)?);
            Ok(())
        }
        Command::Report { dir } => outln(
            &gleaner_campaign::report::write_report(&dir)?
                .display()
                .to_string(),
        ),
        Command::Reconstruct(args) => reconstruct::run(args),
        Command::CrashTest(args) => {
            let (report, ok) = crash::run(&args)?;
            out(&report)?;
            anyhow::ensure!(ok, "crash-safety failures (listed above)");
            Ok(())
        }
    }
}

/// The error and its causes, each said once: a cause whose text the message already contains
/// is not repeated.
fn error_report(e: &anyhow::Error) -> String {
    let mut out = e.to_string();
    for cause in e.chain().skip(1) {
        let text = cause.to_string();
        if !out.contains(&text) {
            out.push_str(": ");
            out.push_str(&text);
        }
    }
    out
}

/// `text` with every run of more than 30 digits cut to its first 6 and its length, so an
/// argument error does not echo a number typed with hundreds of digits in full.
fn shorten_long_numbers(text: &str) -> String {
    const LONGEST: usize = 30;
    let mut out = String::with_capacity(text.len().min(4096));
    let mut digits = String::new();
    let flush = |digits: &mut String, out: &mut String| {
        if digits.len() > LONGEST {
            out.push_str(&digits[..6]);
            out.push_str(&format!("…({} digits)", digits.len()));
        } else {
            out.push_str(digits);
        }
        digits.clear();
    };
    for c in text.chars() {
        if c.is_ascii_digit() {
            digits.push(c);
        } else {
            flush(&mut digits, &mut out);
            out.push(c);
        }
    }
    flush(&mut digits, &mut out);
    out
}

/// The command line, or clap's message (help, version, usage error) and its exit code; a
/// usage error's long numbers shortened.
fn parse_cli() -> std::result::Result<Cli, ExitCode> {
    Cli::try_parse().map_err(|e| {
        let text = e.to_string();
        let short = shorten_long_numbers(&text);
        if short == text {
            e.exit()
        }
        eprint!("{short}");
        ExitCode::from(u8::try_from(e.exit_code()).unwrap_or(2))
    })
}

fn main() -> ExitCode {
    let cli = match parse_cli() {
        Ok(cli) => cli,
        Err(code) => return code,
    };
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", error_report(&e));
            ExitCode::FAILURE
        }
    }
}

#[cfg(test)]
mod tests {
    use super::shorten_long_numbers;

    #[test]
    fn only_runs_of_more_than_30_digits_are_shortened() {
        let long = "1".repeat(301);
        assert_eq!(
            shorten_long_numbers(&format!("invalid value '{long}' for '--at <AT>'")),
            "invalid value '111111…(301 digits)' for '--at <AT>'"
        );
        let kept = format!("2014-01-20 x3y-1 {}", "9".repeat(30));
        assert_eq!(shorten_long_numbers(&kept), kept);
        assert_eq!(shorten_long_numbers(""), "");
    }
}
