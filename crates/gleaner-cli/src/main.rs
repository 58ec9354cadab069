//! `gleaner`: plans UAV data-collection missions over a farm's sensor network so that each
//! flight brings back the data worth most to science.
//!
//! This binary is the only place that knows clap: arguments are parsed here, turned into plain
//! settings, and handed to the `commands` modules.

mod commands;
mod progress;

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::{Args, Parser, Subcommand, ValueEnum};
use gleaner_app as app;
use gleaner_app::{MissionId, Project};

use commands::{
    bench, cells, crash, demo, evaluate, export, migrate, plan, reconstruct, score, serve,
    simulate, synth,
};

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
    Init {
        /// Project directory (created if missing).
        #[arg(long, default_value = ".")]
        dir: PathBuf,
        /// Sensors CSV: `id,lat,lon[,elevation_m]` (WGS84 degrees), or `easting,northing` metres
        /// with --utm-zone (CAF_sensor_locations.csv works as is).
        #[arg(long)]
        sensors: PathBuf,
        /// Read positions as UTM easting/northing in this zone, e.g. `11N` (EPSG:26911/32611).
        #[arg(long)]
        utm_zone: Option<String>,
        /// The sensors file's layout: `generic` (id,lat,lon...) or `hubbard-brook`
        /// (sensor_metadata.csv: one sensor per logger probe, id `<logger>:p<port>`).
        #[arg(long, value_enum, default_value_t = SensorsFormatArg::Generic)]
        sensors_format: SensorsFormatArg,
        /// Base station (take-off and landing) as `LAT,LON` in WGS84 degrees [default: 10 m
        /// south of the middle of the sensors' southern edge].
        #[arg(long, value_parser = parse_lat_lon, allow_hyphen_values = true)]
        base: Option<(f64, f64)>,
        /// Base station altitude above mean sea level, metres (the flight files' home
        /// altitude) [default: 0].
        #[arg(long, allow_hyphen_values = true)]
        base_alt: Option<f64>,
        /// Cell side in metres (the UAV's ground coverage), at least 0.5 [default: 40].
        #[arg(long)]
        cell_size: Option<f64>,
        /// Neighbour fallback radius in metres: a cell with fewer than `neighbour_k` adjacent
        /// cells takes the cells within it as neighbours; at most 100 cell sides [default:
        /// 200, or 100 cell sides for cells under 2 m].
        #[arg(long)]
        neighbour_radius: Option<f64>,
        /// UAV altitude, metres; with --half-angle derives the cell side (r = h·tan θ, side = r·√2).
        #[arg(long, requires = "half_angle")]
        altitude: Option<f64>,
        /// Antenna half-angle, degrees (with --altitude).
        #[arg(long, requires = "altitude")]
        half_angle: Option<f64>,
        /// Project name [default: the directory's name].
        #[arg(long)]
        name: Option<String>,
        /// Overwrite the settings of an existing project (its database is kept).
        #[arg(long)]
        force: bool,
        /// Where to keep the data: an SQLite file relative to the project directory, or a
        /// PostgreSQL database `postgres://user:password@host:port/db[#schema]` (one schema
        /// per project, named after `#` or after the project name) [default: gleaner.db].
        #[arg(long, value_name = "FILE_OR_URL")]
        database: Option<String>,
        /// The score the project plans by: `gleaner` (gleaner's method, the default: the gated
        /// score with each sensor's drift as freshness and the bounded anomaly, β = 4,
        /// γ = δ = 0; less error and sooner catches than coverage and far less than the
        /// paper's S on CAF, docs/method.md §2, docs/method-improvement.md) or `paper` (the paper's S exactly,
        /// which loses to random sampling on CAF 2014). Written into `[utility]`.
        #[arg(long, value_enum, default_value_t = MethodArg::Gleaner)]
        method: MethodArg,
        /// GeoJSON file of the geofence: a Polygon or MultiPolygon (or Features of them),
        /// `[lon, lat]` WGS84 degrees; every flight stays inside it, `--no-fly-buffer`
        /// metres from its edge (`[field] geofence`).
        #[arg(long, value_name = "GEOJSON")]
        geofence: Option<PathBuf>,
        /// GeoJSON file of the no-fly zones: Polygons (buildings, tree rows, neighbours),
        /// LineStrings (power lines) or Points, `[lon, lat]` WGS84 degrees; every leg keeps
        /// `--no-fly-buffer` metres away, flying the shortest way around; cells inside are
        /// reported unreachable (`[field] no_fly`).
        #[arg(long, value_name = "GEOJSON")]
        no_fly: Option<PathBuf>,
        /// Safety buffer around the no-fly zones and inside the geofence, metres, 0..=1000
        /// (`[field] no_fly_buffer_m`) [default: 5].
        #[arg(long, value_name = "M")]
        no_fly_buffer: Option<f64>,
    },
    /// Ingest readings files into the project, all or nothing; re-ingesting changes nothing.
    #[command(
        after_help = "Formats (auto-detected from the header):\n  long-csv   sensor_id,timestamp,modality,value[,unit]   (RFC 3339 or YYYY-MM-DD)\n  wide-csv   Date[,Time] or timestamp, then one column per sensor (needs --modality)\n  caf-daily  CAF daily files: Location<TAB>Date<TAB>VW_30cm ... T_150cm, NA = missing\n  hubbard-brook  logger files timestamp,p<port>:<model>:<variable>:<unit> (UTC-04:00), with\n             sensor_metadata.csv beside them or --metadata\n\nExamples:\n  gleaner ingest --project farm readings.csv\n  gleaner ingest --project caf ../shared/data/caf/Daily/*.txt\n  gleaner ingest --project caf --modality vw@30cm hourly.csv"
    )]
    Ingest {
        /// Files to ingest.
        #[arg(required = true)]
        files: Vec<PathBuf>,
        #[command(flatten)]
        project: ProjectArg,
        /// File format.
        #[arg(long, value_enum, default_value_t = FormatArg::Auto)]
        format: FormatArg,
        /// Wide files: the modality of every sensor column, e.g. `vw@30cm`.
        #[arg(long)]
        modality: Option<String>,
        /// Wide files: the unit of the values, e.g. `m3/m3`.
        #[arg(long)]
        unit: Option<String>,
        /// Wide files: hours the file's clock is ahead of UTC (e.g. -8 for PST).
        #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
        utc_offset: f64,
        /// What to do with a bad row: stop and store nothing, or skip it and report it.
        #[arg(long, value_enum, default_value_t = OnErrorArg::Fail)]
        on_error: OnErrorArg,
        /// Hubbard Brook logger files: the probe metadata [default: sensor_metadata.csv beside
        /// each file].
        #[arg(long)]
        metadata: Option<PathBuf>,
    },
    /// Show the cell table with its metadata (summaries, scores, pending data).
    #[command(
        after_help = "Examples:\n  gleaner cells --project farm\n  gleaner cells --project farm --sort score --json"
    )]
    Cells {
        #[command(flatten)]
        project: ProjectArg,
        #[command(flatten)]
        json: JsonArg,
        /// Order of the rows.
        #[arg(long, value_enum, default_value_t = cells::SortKey::Label)]
        sort: cells::SortKey,
    },
    /// Score every cell at a mission time: F, R, A, U and S, printed and kept in the cell
    /// metadata table.
    #[command(
        after_help = "S = alpha·F + beta·A + gamma·U − delta·R with the weights of [utility] in gleaner.toml.\nU comes from the built-in condition model (dry/adequate/wet from soil moisture) or from\n--probabilities (CSV: cell_id,p_1,...,p_K with a header).\n\nExamples:\n  gleaner score --project caf --at 2014-03-01 --history-from 2011-01-01 --history-until 2013-12-31\n  gleaner score --project farm --json --limit 20"
    )]
    Score {
        #[command(flatten)]
        project: ProjectArg,
        #[command(flatten)]
        when: WhenArgs,
        /// Per-cell class probabilities from your own model, instead of the built-in one.
        #[arg(long)]
        probabilities: Option<PathBuf>,
        #[command(flatten)]
        json: JsonArg,
        /// Rows of the table.
        #[arg(long, default_value_t = 20)]
        limit: usize,
        /// Order of the rows (largest first; `cell` by id).
        #[arg(long, value_enum, default_value_t = score::ScoreSort::Score)]
        sort: score::ScoreSort,
    },
    /// Plan a mission: score the cells (or read --scores), then choose and order the cells that
    /// fit the battery, and print the mission summary (table or JSON). The mission is stored as
    /// planned.
    #[command(
        after_help = "Energy settings come from [energy] in gleaner.toml (preset `paper`: 66.5 kJ usable,\nmax-endurance cruise, 30 s hover overhead).\n\nExamples:\n  gleaner plan --project farm\n  gleaner plan --project caf --at 2014-03-01 --history-until 2013-12-31 --solver greedy\n  gleaner plan --project farm --scores my_scores.csv --json"
    )]
    Plan {
        #[command(flatten)]
        project: ProjectArg,
        #[command(flatten)]
        when: WhenArgs,
        /// Per-cell scores (CSV `cell_id,score` with a header) instead of the utility engine;
        /// cells left out score 0.
        #[arg(long)]
        scores: Option<PathBuf>,
        /// Route planner: default (iterated local search), greedy (the paper's), exact.
        #[arg(long)]
        solver: Option<String>,
        /// Planner time limit, seconds [default: [planner] time_limit_s, 5].
        #[arg(long)]
        time_limit: Option<f64>,
        /// Seed of the planner [default: [planner] seed, 0].
        #[arg(long)]
        seed: Option<u64>,
        /// Stop the search after this many iterations, so the route does not depend on the
        /// machine's speed (the time limit still applies).
        #[arg(long)]
        iterations: Option<u64>,
        #[command(flatten)]
        json: JsonArg,
        /// Do not store the mission.
        #[arg(long)]
        dry_run: bool,
        /// Sorties this mission day (battery swaps), 1..=20: disjoint routes from the base, each
        /// within the budget, planned together to maximise total S; each is stored as its own
        /// mission (export/record each by its id). With K > 1, --json prints an array.
        #[arg(long, default_value_t = 1)]
        sorties: usize,
        /// Plan with this energy preset's battery instead of `[energy] preset` (`paper`,
        /// `large-pack`); fields set in `[energy]` still override the preset's values.
        #[arg(long, value_parser = parse_energy_preset)]
        energy_preset: Option<app::EnergyPreset>,
        /// What the route maximises: `score` (the sum of the visited cells' S) or
        /// `information` (the expected reduction of the dynamic field model's posterior
        /// variance over the whole field, non-additive: correlated cells share information)
        /// or `hybrid` (the route's share of the total S and its information share, blended
        /// by [planner] information_weight, default 0.5) [default: [planner] objective,
        /// score].
        #[arg(long, value_parser = parse_objective)]
        objective: Option<app::Objective>,
        /// Forecast wind at the flight altitude as SPEED@FROM: m/s @ degrees clockwise from
        /// north the wind blows from (e.g. 6@270, a 6 m/s west wind) [default: [flight]
        /// wind_mps@wind_from_deg, still air]. Legs are priced at the airspeed that holds
        /// their track at the planned ground speed, in this wind plus [flight]
        /// wind_margin_mps (2 m/s); the plan prints the strongest wind it stands.
        #[arg(long, value_name = "SPEED@FROM", value_parser = parse_wind)]
        wind: Option<app::Wind>,
    },
    /// Plan the exploration phase: as few sorties as possible, each within the battery, that
    /// together visit every cell; each sortie is stored as an exploration mission.
    #[command(
        after_help = "Examples:\n  gleaner explore --project farm\n  gleaner explore --project caf --json --dry-run"
    )]
    Explore {
        #[command(flatten)]
        project: ProjectArg,
        /// Planning time (RFC 3339 or date, years 1900..=2199) [default: the latest reading;
        /// without readings it must be given].
        #[arg(long, value_parser = parse_time)]
        at: Option<i64>,
        #[command(flatten)]
        json: JsonArg,
        /// Do not store the sorties.
        #[arg(long)]
        dry_run: bool,
        /// Forecast wind at the flight altitude as SPEED@FROM (m/s @ degrees clockwise from
        /// north it blows from, e.g. 6@270) [default: [flight] wind_mps@wind_from_deg, still
        /// air]. The sorties are planned in it plus [flight] wind_margin_mps, as `plan`'s.
        #[arg(long, value_name = "SPEED@FROM", value_parser = parse_wind)]
        wind: Option<app::Wind>,
    },
    /// Export a planned mission for flying and mapping: GeoJSON (cells with their scores, the
    /// route, the base), a QGroundControl .plan, a QGC WPL 110 waypoint file, a DJI WPML
    /// archive (mission.kmz, for DJI Pilot 2) and an SVG map.
    #[command(
        after_help = "Waypoints: take-off, the cruise speed the energy model assumed (MAV_CMD_DO_CHANGE_SPEED,\n178), one NAV_WAYPOINT (16) per cell at the cell centre holding for the\nplanned hold (param 1: the hover rounded up to 0.25 s), return-to-launch (20); altitude from\n[energy] altitude_m. Every flight file is read back and its energy recomputed from what it\ncommands; a file above the usable budget is refused.\n\nmission.kmz (wpmz/template.kml + wpmz/waylines.wpml) follows DJI's published WPML reference:\nheights relative to the take-off point, the speed per waypoint, a hover action per waypoint,\nreturn home at the end. It has not been flown; check it in DJI Pilot 2 first. Not written when\nthe speed exceeds WPML's 15 m/s.\n\nExamples:\n  gleaner export --project farm --mission 1\n  gleaner export --project farm --mission 1 --out flight1\n  gleaner export --project farm --mission 1 --dji-drone 77 --dji-drone-sub 2 --dji-payload 68"
    )]
    Export {
        #[command(flatten)]
        project: ProjectArg,
        /// The mission's id (printed by `gleaner plan`).
        #[arg(long)]
        mission: i64,
        /// Output directory [default: <project>/missions/<id>].
        #[arg(long)]
        out: Option<PathBuf>,
        /// mission.kmz: DJI's aircraft enumeration value (wpml:droneEnumValue; 77 = Mavic 3
        /// Enterprise series).
        #[arg(long, default_value_t = 77)]
        dji_drone: u32,
        /// mission.kmz: DJI's aircraft sub-type (wpml:droneSubEnumValue; for 77: 0 = M3E,
        /// 1 = M3T, 2 = M3M).
        #[arg(long, default_value_t = 0)]
        dji_drone_sub: u32,
        /// mission.kmz: DJI's payload enumeration value (wpml:payloadEnumValue; 66 = M3E camera).
        #[arg(long, default_value_t = 66)]
        dji_payload: u32,
    },
    /// Re-plan a mission in the air: the best continuation from the stop the aircraft is
    /// over with the energy it has left — the remaining stops dropped and reordered so that it
    /// still reaches the base with the battery's reserve — written as a new file set
    /// (.plan, WPL, GeoJSON, JSON) that starts where the aircraft is.
    #[command(
        after_help = "The continuation's files have no take-off: DO_CHANGE_SPEED to the mission's speed, a 0 s\nwaypoint where the aircraft is, the kept stops with their holds, return-to-launch. Their energy\nis recomputed from what they command (no climb; the descent at the base) and must fit the energy\nleft less the reserve ([energy] capacity_j x reserve_fraction). Nothing is stored: record the\nflight against the mission itself (its stops include the continuation's).\n\nExamples:\n  gleaner replan --project farm --mission 3 --after-stop 4 --energy-left 30000\n  gleaner replan --project farm --mission 3 --after-stop 0 --energy-left 52000 --json"
    )]
    Replan {
        #[command(flatten)]
        project: ProjectArg,
        /// The mission in flight (planned, not yet recorded).
        #[arg(long)]
        mission: i64,
        /// Stops already flown: the aircraft is over this stop, done collecting (1-based in
        /// the mission's order; 0 = airborne over the base).
        #[arg(long)]
        after_stop: usize,
        /// Energy left in the battery, J (as the autopilot reports it).
        #[arg(long, value_name = "J")]
        energy_left: f64,
        /// Output directory [default: <project>/missions/<id>/replan-after-<K>].
        #[arg(long)]
        out: Option<PathBuf>,
        /// Planner seed [default: the mission's].
        #[arg(long)]
        seed: Option<u64>,
        /// Wall-clock limit of the search, seconds.
        #[arg(long, default_value_t = gleaner_app::REPLAN_TIME_LIMIT_S)]
        time_limit: f64,
        /// Iteration cap of the search (deterministic answers).
        #[arg(long, default_value_t = gleaner_app::REPLAN_ITERATIONS)]
        iterations: u64,
        /// The wind now as SPEED@FROM (m/s @ degrees from north it blows from, e.g. 8@250),
        /// plus [flight] wind_margin_mps; the continuation and its files are priced in it
        /// [default: the wind the mission was planned in].
        #[arg(long, value_name = "SPEED@FROM", value_parser = parse_wind)]
        wind: Option<app::Wind>,
        #[command(flatten)]
        json: JsonArg,
    },
    /// Draw the exploration overview: every exploration sortie on one map, one colour each
    /// (SVG and PNG).
    #[command(after_help = "Example:\n  gleaner map-exploration --project farm")]
    MapExploration {
        #[command(flatten)]
        project: ProjectArg,
        /// Output directory [default: <project>/missions].
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Record a flown mission: the cells visited, when, and the readings brought back; the
    /// visited cells' sensors count as collected from then on.
    #[command(
        after_help = "Examples:\n  gleaner record --project farm --mission 1\n  gleaner record --project farm --mission 1 --at 2014-06-30T10:00:00Z --cells x1y2,x3y0 flight1.csv"
    )]
    Record {
        #[command(flatten)]
        project: ProjectArg,
        /// The planned mission's id (printed by `gleaner plan`).
        #[arg(long)]
        mission: i64,
        /// Collection time (RFC 3339 or date), not before the mission's planned time [default:
        /// the planned time].
        #[arg(long, value_parser = parse_time)]
        at: Option<i64>,
        /// Cells actually visited, comma-separated, in order, each one of the mission's stops
        /// [default: the planned stops].
        #[arg(long, value_delimiter = ',')]
        cells: Option<Vec<String>>,
        /// Replace an earlier record of this mission (otherwise recording a mission twice is
        /// refused).
        #[arg(long)]
        amend: bool,
        /// Readings files brought back (any format `gleaner ingest` reads); every reading must
        /// come from a sensor in a visited cell and be dated no later than the collection.
        files: Vec<PathBuf>,
    },
    /// List the missions (planned, flown and cancelled), or show one with its stops.
    #[command(
        after_help = "Without --limit or --before every mission is listed, oldest first. With either, one page is listed, newest first (by id, so missions planned meanwhile never shift a page), followed by the --before of the next page.\n\nExamples:\n  gleaner missions --project farm\n  gleaner missions --project farm --limit 20\n  gleaner missions --project farm --limit 20 --before 41\n  gleaner missions --project farm --mission 3 --json"
    )]
    Missions {
        #[command(flatten)]
        project: ProjectArg,
        /// Show this mission with its stops and energy breakdown.
        #[arg(long, conflicts_with_all = ["limit", "before"])]
        mission: Option<i64>,
        /// List one page of at most this many missions (1 to 500), newest first [default with
        /// --before: 20].
        #[arg(long)]
        limit: Option<usize>,
        /// List only missions with an id below this one (the next page's cursor).
        #[arg(long)]
        before: Option<i64>,
        /// Print JSON (the `gleaner.mission` document) instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Cancel a planned mission: it stays in the history, marked cancelled, and can no longer
    /// be recorded, exported or re-planned. A flown mission cannot be cancelled.
    #[command(after_help = "Examples:\n  gleaner cancel --project farm --mission 3")]
    Cancel {
        #[command(flatten)]
        project: ProjectArg,
        /// The mission to cancel.
        #[arg(long)]
        mission: i64,
    },
    /// Delete a mission that was never flown (planned or cancelled) with its stops. A flown
    /// mission, the record of stored readings, is kept.
    #[command(after_help = "Examples:\n  gleaner delete --project farm --mission 3")]
    Delete {
        #[command(flatten)]
        project: ProjectArg,
        /// The mission to delete.
        #[arg(long)]
        mission: i64,
    },
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
    /// Crash-safety harness: kill `ingest`, `plan` and `record` with SIGKILL at evenly spread
    /// write steps on SQLite and PostgreSQL, then check integrity, all-or-nothing and that a
    /// rerun completes (real CAF data; a benchmark-style run, minutes).
    #[command(
        name = "crash-test",
        after_help = "Examples:\n  gleaner crash-test --kill-points 34          # 204 kill points on both backends\n  gleaner crash-test --backend sqlite --kill-points 5"
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

--from/--to/--every-hours: every sensor's mean, sd and 90% interval (mean ± 1.645·sd) at each
time of a range, by the same estimator (one fit on the readings up to --to; each time uses only
readings stamped at or before it) as CSV (time,sensor,mean,sd,lo90,hi90), or with --json the
`gleaner.reconstruction-series` document (as GET /api/v1/reconstruct?from=..&to=..).

--map FILE.svg|FILE.png: the map of the estimated field at --at, a two-panel figure for a paper
(178 mm wide; the PNG at 300 dpi): left the estimate, right its uncertainty (the posterior sd),
each cell coloured by its sensors' mean on a colour-blind-safe scale (viridis; reversed magma)
with a colour bar in the modality's unit; sensors read within one sampling step before the time
are dark discs, those only estimated white diamonds; the field's outline, a scale bar in
metres, a north arrow, and the modality, time (UTC) and estimator in the title (as GET
/api/v1/reconstruct/map.svg, .png).

--json: the `gleaner.reconstruction` document (as GET /api/v1/reconstruct): sd = the model's
standard deviation, positions WGS84 [lon, lat].

Examples:
  gleaner reconstruct --project caf --at 2014-03-01 --modality vw@30cm
  gleaner reconstruct --project caf --at 2014-03-01 --json
  gleaner reconstruct --project caf --from 2015-02-11 --to 2015-03-04 --every-hours 1 --out vw30.csv
  gleaner reconstruct --project caf --at 2014-03-01 --map vw30-2014-03-01.svg
  gleaner reconstruct --project caf --at 2014-03-01 --dynamic --map vw30-2014-03-01.png"
    )]
    Reconstruct {
        #[command(flatten)]
        project: ProjectArg,
        /// Estimation time (RFC 3339 or date) [default: the latest reading].
        #[arg(long, value_parser = parse_time)]
        at: Option<i64>,
        /// Modality [default: vw@30cm, else the first vw@...].
        #[arg(long)]
        modality: Option<String>,
        /// Observations per estimate.
        #[arg(long, default_value_t = app::DEFAULT_NEIGHBOURS)]
        neighbours: usize,
        /// Simple kriging of levels towards each sensor's long-run mean instead of kriging
        /// of changes.
        #[arg(long, conflicts_with = "levels")]
        simple: bool,
        /// Ordinary kriging of levels (from every sensor's latest reading) instead of kriging
        /// of changes.
        #[arg(long, conflicts_with = "simple")]
        levels: bool,
        /// The dynamic field model (a learned, shrunk covariance of levels between sensors
        /// with AR(1) dynamics, a Kalman filter over the readings known) instead of kriging
        /// of changes.
        #[arg(long, conflicts_with_all = ["simple", "levels"])]
        dynamic: bool,
        /// Reconstruct over a range instead of at one time: the first estimation time
        /// (RFC 3339 or date; needs --to).
        #[arg(long, value_parser = parse_time, requires = "to", conflicts_with_all = ["at", "map"])]
        from: Option<i64>,
        /// The range's last estimation time (RFC 3339 or date).
        #[arg(long, value_parser = parse_time, requires = "from")]
        to: Option<i64>,
        /// Spacing of the range's estimation times, hours.
        #[arg(long, default_value_t = 24.0, requires = "from")]
        every_hours: f64,
        /// Write the range's CSV (time, sensor, mean, sd, lo90, hi90) to this file instead of
        /// standard output (`-`: standard output).
        #[arg(long, requires = "from")]
        out: Option<PathBuf>,
        /// Print the `gleaner.reconstruction` JSON document (as `GET /api/v1/reconstruct`)
        /// instead of the table.
        #[arg(long)]
        json: bool,
        /// Draw the map of the estimate and its uncertainty at --at into this file: SVG or
        /// PNG by its extension (`.svg`, `.png`).
        #[arg(long, value_name = "FILE", conflicts_with = "json")]
        map: Option<PathBuf>,
    },
}

/// `--project`: the project directory.
#[derive(Args)]
struct ProjectArg {
    /// Project directory.
    #[arg(
        long = "project",
        id = "project",
        value_name = "PROJECT",
        default_value = "."
    )]
    dir: PathBuf,
    /// The project's database instead of its `database` setting: an SQLite file (relative to
    /// the project directory) or `postgres://user:password@host:port/db[#schema]`.
    #[arg(long, value_name = "FILE_OR_URL", env = "GLEANER_DATABASE")]
    database: Option<String>,
}

impl ProjectArg {
    fn open(&self) -> Result<Project<app::AnyStore>> {
        Ok(Project::open_with(&self.dir, self.database.as_deref())?)
    }
}

/// `--json`: JSON on standard output instead of a table.
#[derive(Args)]
struct JsonArg {
    /// Print JSON instead of a table.
    #[arg(long)]
    json: bool,
}

impl JsonArg {
    /// Prints `value` as pretty JSON when `--json`, else the text `table` renders.
    fn emit<T: serde::Serialize>(
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
struct WhenArgs {
    /// Mission time (RFC 3339 or YYYY-MM-DD, UTC; years 1900..=2199) [default: the latest
    /// reading]. Only data up to this time is used.
    #[arg(long, value_parser = parse_time)]
    at: Option<i64>,
    /// Use only readings from this time on (RFC 3339 or date) as collected history.
    #[arg(long, value_parser = parse_time)]
    history_from: Option<i64>,
    /// Use only readings up to this time as collected history (later ones are not yet
    /// collected at the mission time, unless a recorded collection brought them back), e.g.
    /// score 2014 from 2011-2013 data.
    #[arg(long, value_parser = parse_time)]
    history_until: Option<i64>,
}

impl WhenArgs {
    fn history(&self) -> app::History {
        app::History {
            from: self.history_from.unwrap_or(i64::MIN),
            until: self.history_until.unwrap_or(i64::MAX),
        }
    }
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

#[derive(Clone, Copy, ValueEnum)]
enum FormatArg {
    Auto,
    LongCsv,
    WideCsv,
    CafDaily,
    HubbardBrook,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum MethodArg {
    Paper,
    Gleaner,
}

#[derive(Clone, Copy, ValueEnum)]
enum SensorsFormatArg {
    Generic,
    HubbardBrook,
}

#[derive(Clone, Copy, ValueEnum)]
enum OnErrorArg {
    Fail,
    Skip,
}

/// Prints the scoring's warnings on standard error.
fn warn(scoring: &app::Scoring) {
    for w in &scoring.warnings {
        eprintln!("warning: {w}");
    }
}

/// Prints `value` as pretty JSON when `json`, else the text `table` renders.
fn emit<T: serde::Serialize>(
    json: bool,
    value: &T,
    what: &str,
    table: impl FnOnce() -> String,
) -> Result<()> {
    if json {
        let mut text = serde_json::to_string_pretty(value).with_context(|| what.to_string())?;
        text.push('\n');
        out(&text)
    } else {
        out(&table())
    }
}

/// Writes `text` to standard output. A reader that closes the pipe early (`gleaner cells
/// --json | head`) has what it wanted: the rest is dropped quietly, not a panic or an error.
fn out(text: &str) -> Result<()> {
    use std::io::Write;
    let mut stdout = std::io::stdout().lock();
    match stdout
        .write_all(text.as_bytes())
        .and_then(|()| stdout.flush())
    {
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        r => r.context("writing to standard output"),
    }
}

/// [`out`] with a newline.
fn outln(text: &str) -> Result<()> {
    out(&format!("{text}\n"))
}

fn parse_lat_lon(s: &str) -> Result<(f64, f64), String> {
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

fn parse_energy_preset(s: &str) -> Result<app::EnergyPreset, String> {
    s.parse().map_err(|e: app::AppError| e.to_string())
}

fn parse_wind(s: &str) -> Result<app::Wind, String> {
    app::wind::parse(s).map_err(|e| e.to_string())
}

fn parse_objective(s: &str) -> Result<app::Objective, String> {
    s.parse().map_err(|e: app::AppError| e.to_string())
}

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

fn format_arg(f: FormatArg) -> app::Format {
    match f {
        FormatArg::Auto => app::Format::Auto,
        FormatArg::LongCsv => app::Format::Long,
        FormatArg::WideCsv => app::Format::Wide,
        FormatArg::CafDaily => app::Format::CafDaily,
        FormatArg::HubbardBrook => app::Format::HubbardBrook,
    }
}

/// The one-line summary of an ingest.
fn ingest_line(o: &app::IngestOutcome) -> String {
    let r = &o.report;
    let mut out = format!(
        "ingested {} file(s): {} rows read, {} readings ({} new, {} already stored), {} missing values, {} duplicate rows, {} rows skipped, {} conflicts kept as stored",
        o.files,
        r.rows_read,
        r.readings,
        o.inserted,
        o.unchanged,
        r.missing,
        r.duplicates,
        r.skipped,
        o.conflicts
    );
    for s in &r.skipped_rows {
        out.push_str(&format!("\n  skipped: {}", s.reason));
    }
    out
}

fn init_line(o: &app::InitOutcome, dir: &Path) -> String {
    format!(
        "project {} in {}\n  sensors: {} ({} new, {} updated)\n  base station: {:.6}, {:.6}\n  cells: {} non-empty cells of {} m ({} kept, {} added, {} removed)",
        o.settings.project.name,
        dir.display(),
        o.sensors,
        o.upsert.added.len(),
        o.upsert.updated.len(),
        o.settings.field.base_lat,
        o.settings.field.base_lon,
        o.n_cells,
        o.settings.field.cell_size_m,
        o.cells.kept,
        o.cells.added,
        o.cells.removed,
    )
}

fn record_line(o: &app::RecordOutcome) -> String {
    format!(
        "mission #{} recorded as flown at {}{}: {} cells, {} sensors collected, {} readings brought back ({} new)",
        o.mission,
        app::format_rfc3339(o.at),
        if o.amended { " (amended)" } else { "" },
        o.cells.len(),
        o.sensors_collected,
        o.readings_inserted + o.readings_unchanged,
        o.readings_inserted
    )
}

fn missions_table(missions: &[app::MissionRecord]) -> String {
    let mut out = format!(
        "{:>4} {:<11} {:<8} {:<20} {:<11} {:>5} {:>9} {:>11} {:>6}\n",
        "id", "kind", "status", "planned_at", "planner", "cells", "total_S", "energy_J", "use"
    );
    for m in missions {
        let e = &m.mission.energy;
        out.push_str(&format!(
            "{:>4} {:<11} {:<8} {:<20} {:<11} {:>5} {:>9.3} {:>11.1} {:>5.1}%\n",
            m.id,
            m.mission.kind.as_str(),
            m.status.as_str(),
            app::format_rfc3339(m.mission.planned_at),
            m.mission.solver,
            m.mission.stops.len(),
            m.mission.total_score,
            e.total_j,
            if e.budget_j > 0.0 {
                100.0 * e.total_j / e.budget_j
            } else {
                0.0
            }
        ));
    }
    out
}

fn run(cli: Cli) -> Result<()> {
    let progress = progress::Terminal::default();
    match cli.command {
        Command::Init {
            dir,
            sensors,
            utm_zone,
            sensors_format,
            base,
            base_alt,
            cell_size,
            neighbour_radius,
            altitude,
            half_angle,
            name,
            force,
            database,
            method,
            geofence,
            no_fly,
            no_fly_buffer,
        } => {
            let base = base
                .map(|(lat, lon)| gleaner_field::LatLon::new(lat, lon).context("--base"))
                .transpose()?;
            let (_, outcome) = app::init(&app::InitRequest {
                dir: dir.clone(),
                sensors,
                utm_zone,
                hubbard_brook: matches!(sensors_format, SensorsFormatArg::HubbardBrook),
                base,
                base_alt_m: base_alt,
                cell_size_m: cell_size,
                neighbour_radius_m: neighbour_radius,
                coverage: altitude.zip(half_angle),
                name,
                force,
                database,
                gleaner_method: matches!(method, MethodArg::Gleaner),
                geofence,
                no_fly,
                no_fly_buffer_m: no_fly_buffer,
            })?;
            outln(&init_line(&outcome, &dir))?;
        }
        Command::Ingest {
            files,
            project,
            format,
            modality,
            unit,
            utc_offset,
            on_error,
            metadata,
        } => {
            let mut p = project.open()?;
            let outcome = app::ingest(
                &mut p,
                &app::IngestRequest {
                    files,
                    format: format_arg(format),
                    modality,
                    unit,
                    utc_offset_h: utc_offset,
                    on_error: match on_error {
                        OnErrorArg::Fail => app::OnError::Fail,
                        OnErrorArg::Skip => app::OnError::Skip,
                    },
                    metadata,
                    now: None,
                },
                clock_now(),
                &progress,
            )?;
            outln(&ingest_line(&outcome))?;
        }
        Command::Cells {
            project,
            json,
            sort,
        } => {
            let p = project.open()?;
            let view = app::field_view(&p)?;
            let mut rows: Vec<_> = view
                .cells
                .iter()
                .map(|c| gleaner_wire::convert::cell_row(c, view.cell_size_m))
                .collect();
            cells::sort(&mut rows, sort);
            if json.json {
                json.emit(&rows, "serialising cells", String::new)?;
            } else {
                let counts = app::cell_reading_counts(&p)?;
                json.emit(&rows, "serialising cells", || cells::table(&rows, &counts))?;
            }
        }
        Command::Score {
            project,
            when,
            probabilities,
            json,
            limit,
            sort,
        } => {
            let mut p = project.open()?;
            let scoring = app::score(
                &mut p,
                &app::ScoreRequest {
                    at: when.at,
                    history: when.history(),
                    probabilities,
                    dry_run: false,
                },
            )?;
            warn(&scoring);
            let mut doc = gleaner_wire::convert::scoring(&scoring);
            score::sort(&mut doc, sort);
            json.emit(&doc, "serialising scores", || score::table(&doc, limit))?;
        }
        Command::Plan {
            project,
            when,
            scores,
            solver,
            time_limit,
            seed,
            iterations,
            json,
            dry_run,
            sorties,
            energy_preset,
            objective,
            wind,
        } => {
            let mut p = project.open()?;
            let planned = app::plan_with_preset(
                &mut p,
                &app::PlanRequest {
                    at: when.at,
                    history: when.history(),
                    scores,
                    cell_scores: None,
                    planner: solver.as_deref().map(app::parse_planner).transpose()?,
                    time_limit_s: time_limit,
                    seed,
                    max_iterations: iterations,
                    dry_run,
                    sorties: Some(sorties),
                    objective,
                    wind,
                },
                energy_preset.map(app::EnergyPreset::name),
                clock_now(),
            )?;
            if let Some(s) = &planned.scoring {
                warn(s);
            }
            let doc = gleaner_wire::convert::planned_mission(&planned);
            if planned.extra_sorties.is_empty() {
                json.emit(&doc, "serialising the mission", || plan::table(&doc))?;
            } else {
                let mut docs = vec![doc];
                docs.extend(planned.extra_sorties.iter().map(|e| {
                    let mut doc = gleaner_wire::convert::mission_doc(
                        e.id,
                        &e.mission,
                        if e.id.is_some() { "planned" } else { "dry-run" },
                        None,
                    );
                    // The sorties of one day are chosen together from the same cells.
                    doc.candidates = Some(planned.candidates);
                    doc.wind = Some(gleaner_wire::convert::wind(&e.wind));
                    doc
                }));
                json.emit(&docs, "serialising the sorties", || {
                    plan::sorties_table(&docs)
                })?;
            }
        }
        Command::Explore {
            project,
            at,
            json,
            dry_run,
            wind,
        } => {
            let mut p = project.open()?;
            let e = app::explore(
                &mut p,
                &app::ExploreRequest { at, dry_run, wind },
                clock_now(),
            )?;
            let doc = gleaner_wire::convert::exploration(&e);
            json.emit(&doc, "serialising the plan", || {
                plan::exploration_table(&doc)
            })?;
        }
        Command::Export {
            project,
            mission,
            out,
            dji_drone,
            dji_drone_sub,
            dji_payload,
        } => {
            let p = project.open()?;
            let export = app::export(&p, MissionId(mission))?;
            let dir = out.unwrap_or_else(|| project.dir.join("missions").join(mission.to_string()));
            let wpml = gleaner_wire::WpmlOptions {
                drone_enum: dji_drone,
                drone_sub_enum: dji_drone_sub,
                payload_enum: dji_payload,
            };
            let written = export::write_files_with(&export, &dir, wpml)?;
            let names: Vec<String> = written
                .files
                .iter()
                .map(|f| f.display().to_string())
                .collect();
            outln(&format!("wrote {}", names.join(", ")))?;
            for note in &written.skipped {
                outln(&format!("not written: {note}"))?;
            }
        }
        Command::Replan {
            project,
            mission,
            after_stop,
            energy_left,
            out,
            seed,
            time_limit,
            iterations,
            wind,
            json,
        } => {
            let p = project.open()?;
            let r = app::replan(
                &p,
                &app::ReplanRequest {
                    mission: MissionId(mission),
                    after_stop,
                    energy_left_j: energy_left,
                    seed,
                    iterations: Some(iterations),
                    time_limit_s: Some(time_limit),
                    wind,
                    wind_margin_mps: None,
                },
            )?;
            let dir = out.unwrap_or_else(|| {
                project
                    .dir
                    .join("missions")
                    .join(mission.to_string())
                    .join(format!("replan-after-{after_stop}"))
            });
            let written = export::write_replan_files(&p, &r, &dir)?;
            let doc = gleaner_wire::convert::replanned_mission(&r);
            json.emit(&doc, "serialising the continuation", || {
                let mut t = plan::replan_table(&doc, &r.dropped);
                let names: Vec<String> = written
                    .files
                    .iter()
                    .map(|f| f.display().to_string())
                    .collect();
                t.push_str(&format!("wrote {}\n", names.join(", ")));
                for note in &written.skipped {
                    t.push_str(&format!("not written: {note}\n"));
                }
                t
            })?;
        }
        Command::MapExploration { project, out } => {
            let p = project.open()?;
            let dir = out.unwrap_or_else(|| project.dir.join("missions"));
            let files = export::write_exploration_map(&p, &dir)?;
            outln(&format!("wrote {}", files.join(", ")))?;
        }
        Command::Record {
            project,
            mission,
            at,
            cells,
            amend,
            files,
        } => {
            let mut p = project.open()?;
            let outcome = app::record_flight(
                &mut p,
                &app::RecordRequest {
                    mission: MissionId(mission),
                    at,
                    cells,
                    readings: (!files.is_empty()).then(|| app::IngestRequest {
                        files,
                        ..Default::default()
                    }),
                    amend,
                },
                clock_now(),
                &progress,
            )?;
            outln(&record_line(&outcome))?;
        }
        Command::Missions {
            project,
            mission,
            limit,
            before,
            json,
        } => {
            let p = project.open()?;
            if limit.is_some() || before.is_some() {
                let page = app::missions_page(&p, before.map(MissionId), limit.unwrap_or(20))?;
                if json {
                    let docs: Vec<_> = page
                        .missions
                        .iter()
                        .map(gleaner_wire::convert::stored_mission)
                        .collect();
                    let doc = serde_json::json!({"missions": docs, "next": page.next.map(|m| m.0)});
                    emit(true, &doc, "serialising missions", String::new)?;
                } else {
                    out(&missions_table(&page.missions))?;
                    match page.next {
                        Some(n) => outln(&format!("next page: --before {n}"))?,
                        None => outln("no older missions")?,
                    }
                }
                return Ok(());
            }
            match mission {
                Some(id) => {
                    let m = app::mission(&p, MissionId(id))?;
                    let doc = gleaner_wire::convert::stored_mission(&m);
                    emit(json, &doc, "serialising the mission", || plan::table(&doc))?;
                }
                None => {
                    let all = app::missions(&p)?;
                    let docs: Vec<_> = all
                        .iter()
                        .map(gleaner_wire::convert::stored_mission)
                        .collect();
                    emit(json, &docs, "serialising missions", || missions_table(&all))?;
                }
            }
        }
        Command::Cancel { project, mission } => {
            let mut p = project.open()?;
            let m = app::cancel_mission(&mut p, MissionId(mission))?;
            outln(&format!(
                "cancelled mission #{}: it stays in the history and can no longer be recorded or exported",
                m.id
            ))?;
        }
        Command::Delete { project, mission } => {
            let mut p = project.open()?;
            app::delete_mission(&mut p, MissionId(mission))?;
            outln(&format!("deleted mission #{mission}"))?;
        }
        Command::Bench(BenchCommand::Op(args)) => {
            let (_, table) = bench::run(&args)?;
            out(&table)?;
        }
        Command::Synth(args) => {
            let (farm, files) = synth::run(&args)?;
            outln(&format!(
                "wrote {} sensors, {} readings, {} events to {}",
                farm.sensors().len(),
                farm.reading_count(),
                farm.events().len(),
                files
                    .sensors
                    .parent()
                    .map_or(String::new(), |p| p.display().to_string())
            ))?;
        }
        Command::Demo(args) => out(&demo::run(&args)?)?,
        Command::Migrate(args) => outln(&migrate::run(&args, &progress)?)?,
        Command::Serve(args) => serve::run(args)?,
        Command::FarmToken(args) => serve::farm_token(args)?,
        Command::Simulate(args) => {
            let line: Vec<String> = std::env::args().skip(1).collect();
            let command = format!("gleaner {}", line.join(" "));
            out(&simulate::run(&args, &command, &progress)?)?;
        }
        Command::Evaluate(EvaluateCommand::Peer(args)) => print!("{}", evaluate::run_peer(&args)?),
        Command::Report { dir } => {
            outln(
                &gleaner_campaign::report::write_report(&dir)?
                    .display()
                    .to_string(),
            )?;
        }
        Command::Reconstruct {
            project,
            at,
            modality,
            neighbours,
            simple,
            levels,
            dynamic,
            from,
            to,
            every_hours,
            out,
            json,
            map,
        } => {
            let p = project.open()?;
            let estimator = if dynamic {
                app::Estimator::Dynamic
            } else if simple {
                app::Estimator::Levels(gleaner_kriging::Mean::Known)
            } else if levels {
                app::Estimator::Levels(gleaner_kriging::Mean::Unknown)
            } else {
                app::Estimator::Changes
            };
            if let Some(path) = map {
                let kind = reconstruct::MapFile::of(&path)?;
                let m = app::reconstruct_map(
                    &p,
                    &app::ReconstructMapRequest {
                        reconstruct: app::ReconstructRequest {
                            at,
                            modality,
                            neighbours: Some(neighbours),
                            estimator,
                        },
                        read_within_s: None,
                    },
                )?;
                let bytes =
                    reconstruct::map_file(&gleaner_wire::convert::reconstruction_map(&m), kind)?;
                std::fs::write(&path, bytes)
                    .with_context(|| format!("cannot write {}", path.display()))?;
                outln(&format!(
                    "{}: {} at {} ({}), {} cells, {} of {} sensors read within {} s",
                    path.display(),
                    m.reconstruction.modality,
                    app::format_rfc3339(m.reconstruction.at),
                    m.reconstruction.estimator.name(),
                    m.cells.len(),
                    m.read.iter().filter(|&&r| r).count(),
                    m.read.len(),
                    m.read_within_s
                ))?;
                return Ok(());
            }
            if let (Some(from), Some(to)) = (from, to) {
                if !(every_hours.is_finite() && every_hours > 0.0 && every_hours <= 24.0 * 3660.0) {
                    anyhow::bail!(
                        "--every-hours must be a positive number of hours (at most 10 years)"
                    );
                }
                let r = app::reconstruct_series(
                    &p,
                    &app::ReconstructSeriesRequest {
                        from,
                        to,
                        every_s: ((every_hours * 3600.0).round() as i64).max(1),
                        modality,
                        estimator,
                        neighbours: Some(neighbours),
                        cell: None,
                    },
                )?;
                if json {
                    let doc = gleaner_wire::convert::reconstruction_series(&r);
                    println!("{}", serde_json::to_string_pretty(&doc)?);
                    return Ok(());
                }
                let csv = reconstruct::series_csv(&r);
                match out.as_deref() {
                    Some(path) if path != Path::new("-") => {
                        std::fs::write(path, csv)
                            .with_context(|| format!("cannot write {}", path.display()))?;
                        println!(
                            "{}: {} times × {} sensors",
                            path.display(),
                            r.times.len(),
                            r.sensors.len()
                        );
                    }
                    _ => print!("{csv}"),
                }
                return Ok(());
            }
            let r = app::reconstruct(
                &p,
                &app::ReconstructRequest {
                    at,
                    modality,
                    neighbours: Some(neighbours),
                    estimator,
                },
            )?;
            emit(
                json,
                &gleaner_wire::convert::reconstruction(&r),
                "reconstruction",
                || reconstruct::table(&r),
            )?;
        }
        Command::CrashTest(args) => {
            let (report, ok) = crash::run(&args)?;
            out(&report)?;
            if !ok {
                anyhow::bail!("crash-safety failures (listed above)");
            }
        }
    }
    Ok(())
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
