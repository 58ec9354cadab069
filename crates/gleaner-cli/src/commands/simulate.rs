//! `gleaner simulate`: translates the arguments into replay options and a dataset
//! (`gleaner_campaign::datasets`: the presets, synthetic farms, a project's record) for
//! `gleaner_campaign::simulation`, which runs the campaigns and writes the results as CSV
//! files plus the report.

use std::path::PathBuf;

use anyhow::Result;
use gleaner_app as app;
use gleaner_campaign::campaign::{ReplayOptions, Strategy};
use gleaner_campaign::datasets::{Preset, SyntheticFarm};
use gleaner_campaign::simulation::{self, SimulationRequest, Source};

/// Which data a campaign replays.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Dataset {
    /// CAF daily files (42 stations; VW and T at 5 depths): history to the end of 2013,
    /// missions every day of 2014 by default.
    CafDaily,
    /// The CAF hourly subset (32 stations, VW 30 cm, Jan-Apr 2015, timestamps read as UTC):
    /// history January, missions daily Feb 1 - Apr 21 by default.
    CafHourly,
    /// Hubbard Brook (12 loggers, hourly, sites ~4 km apart; `large-pack` battery): history
    /// to 2024-06-30, missions daily 2024-07-01 .. 2025-06-30 by default.
    HubbardBrook,
    /// Seeded synthetic farms with ground-truth events, one per seed (--farm-seeds).
    Synthetic,
}

// The arguments of `gleaner simulate` (the variant's doc comment is the help).
#[derive(clap::Args)]
pub struct SimulateArgs {
    /// The dataset to replay.
    #[arg(long, value_enum, required_unless_present = "project")]
    pub dataset: Option<Dataset>,
    /// Replay this project's own record instead of a dataset: its sensors, settings (grid,
    /// base, energy) and every stored reading as the truth, sampled at its median step. By
    /// default the last 30 days are the missions and everything before is the history. The
    /// project is only read. With --start (and no --history-until) the history runs to the
    /// first mission.
    #[arg(long, conflicts_with_all = ["dataset", "cell_size"])]
    pub project: Option<PathBuf>,
    /// Output directory (missions.csv, events.csv, catches.csv, campaign.csv, report.md).
    #[arg(long)]
    pub out: PathBuf,
    /// Shared data directory [env GLEANER_DATA_DIR, default ../shared/data].
    #[arg(long, env = "GLEANER_DATA_DIR", default_value = "../shared/data")]
    pub data_dir: PathBuf,
    /// Readings available by this time are the history (RFC 3339 or date) [default: the
    /// dataset's].
    #[arg(long, value_parser = crate::args::parse_time)]
    pub history_until: Option<i64>,
    /// Leave readings before this time out of the history [default: the dataset's].
    #[arg(long, value_parser = crate::args::parse_time)]
    pub history_from: Option<i64>,
    /// First mission [default: the end of the history].
    #[arg(long, value_parser = crate::args::parse_time)]
    pub start: Option<i64>,
    /// Last mission at or before this time [default: the dataset's].
    #[arg(long, value_parser = crate::args::parse_time)]
    pub end: Option<i64>,
    /// Hours between missions.
    #[arg(long, default_value_t = 24.0)]
    pub every_hours: f64,
    /// Mission times instead of a period (comma-separated RFC 3339 or dates).
    #[arg(long, value_delimiter = ',', value_parser = crate::args::parse_time)]
    pub times: Option<Vec<i64>>,
    /// Strategies, comma-separated, or `all` / `main` (gleaner, paper, variance, information,
    /// freshness, round-robin, random, nearest, exhaustive). Names: those, no-freshness,
    /// no-anomaly, no-uncertainty, no-redundancy, gated (gleaner's earlier method: the gated S
    /// with a 14-day freshness half-life), expected-error (each cell worth its sensors'
    /// predicted squared error), hybrid (gleaner's score blended with the information
    /// objective). The yardstick `oracle` runs only when named: it sees the
    /// values each flight will bring back (each cell worth its sensors' squared estimation
    /// error), so it bounds what any choice of cells could buy; it is not a flyable strategy.
    #[arg(long, value_delimiter = ',', default_value = "main")]
    pub strategies: Vec<String>,
    /// Replicate seeds (planner and random choices).
    #[arg(long, value_delimiter = ',', default_value = "1")]
    pub seeds: Vec<u64>,
    /// Battery capacities as fractions of the preset's (1 = the paper's 70 kJ).
    #[arg(long, value_delimiter = ',', default_value = "1")]
    pub budgets: Vec<f64>,
    /// Energy preset: `paper` or `large-pack` [default: paper; large-pack for Hubbard Brook].
    #[arg(long)]
    pub energy_preset: Option<String>,
    /// Sensor buffers hold this many readings per modality; the oldest are dropped
    /// [default: unlimited].
    #[arg(long)]
    pub buffer: Option<usize>,
    /// The evaluated modality [default: the condition modality, vw@30cm or the first vw@...].
    #[arg(long)]
    pub modality: Option<String>,
    /// |z| threshold of the real-data event rule (runs of |z| of the daily change above it).
    #[arg(long, default_value_t = 3.0)]
    pub event_z: f64,
    /// Planner iteration cap per mission (results independent of the machine's speed).
    #[arg(long, default_value_t = 300)]
    pub planner_iterations: u64,
    /// Sorties per mission (battery swaps; each within the budget, planned together by the
    /// team solver, as `plan --sorties`), 1..=20; exhaustive collection flies as many as it
    /// takes.
    #[arg(long, default_value_t = 1, value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..=20))]
    pub sorties: usize,
    /// Observations (changes, or readings for kriging of levels) per model-based estimate.
    #[arg(long, default_value_t = app::DEFAULT_NEIGHBOURS)]
    pub neighbours: usize,
    /// Model-based estimate by simple kriging of levels towards each sensor's long-run mean
    /// instead of kriging of changes (the default: the last value plus the change since,
    /// estimated from the neighbours' known changes).
    #[arg(long, conflicts_with = "level_kriging")]
    pub simple_kriging: bool,
    /// Model-based estimate by ordinary kriging of levels (the field's current level
    /// estimated from every sensor's latest reading) instead of kriging of changes.
    #[arg(long, conflicts_with = "simple_kriging")]
    pub level_kriging: bool,
    /// The model-based estimate every strategy is judged by: `changes` (kriging of changes,
    /// the default), `dynamic` (the dynamic field model: a learned, shrunk covariance of
    /// levels between sensors with AR(1) dynamics, a Kalman filter over the readings known),
    /// `levels` or `simple` (kriging of levels).
    #[arg(long, default_value = "changes", conflicts_with_all = ["simple_kriging", "level_kriging"])]
    pub estimator: app::Estimator,
    /// Weight of the dynamic field model's unshared per-sensor drift (`[planner]
    /// unshared_weight`: each sensor's own random walk since its last reading, its rate
    /// fitted on the history times this weight; 0 = none) [default: the dataset's settings'].
    #[arg(long)]
    pub unshared_weight: Option<f64>,
    /// The `hybrid` strategy's weight on information, in [0, 1] (`[planner]
    /// information_weight`: a route is worth (1 − w)·its share of the total S + w·the share
    /// of the field model's variance it removes) [default: the dataset's settings', 0.5].
    #[arg(long)]
    pub information_weight: Option<f64>,
    /// Runs in parallel.
    #[arg(long, default_value_t = 2)]
    pub jobs: usize,
    /// Cell side, metres [default 40].
    #[arg(long)]
    pub cell_size: Option<f64>,
    /// Synthetic: farm seeds, one campaign each.
    #[arg(long, value_delimiter = ',', default_value = "1,2,3,4,5,6,7,8,9,10")]
    pub farm_seeds: Vec<u64>,
    /// Synthetic: sensor stations per farm.
    #[arg(long, default_value_t = 42)]
    pub farm_sensors: usize,
    /// Synthetic: days of record (history then missions).
    #[arg(long, default_value_t = 365)]
    pub farm_days: u32,
    /// Synthetic: days of history before the first mission.
    #[arg(long, default_value_t = 180)]
    pub farm_history_days: u32,
    /// Synthetic: ground-truth events per farm.
    #[arg(long, default_value_t = 12)]
    pub farm_events: usize,
    /// Synthetic: grow the field with the sensor count (CAF's density).
    #[arg(long)]
    pub farm_scale_extent: bool,
    /// Each mission's forecast wind at the flight altitude: `still` (the default) or
    /// `weibull:MEAN[:SHAPE]`, a speed drawn from a Weibull distribution with that mean (m/s)
    /// and shape (default 2) from a direction drawn uniformly, seeded (--weather-seed). Each
    /// mission is planned for its forecast plus a margin tied to the forecast error
    /// (--margin-quantile) and flown in the forecast plus the error (--gust) and the gusts
    /// (--leg-gust); a sortie that finds over a stop that its energy left cannot fly the rest
    /// with the reserve re-plans from there (as `gleaner replan`).
    #[arg(long, conflicts_with = "wind_csv")]
    pub wind: Option<String>,
    /// Observed daily winds instead of drawn ones: a CSV with a header and the columns
    /// `date` (YYYY-MM-DD), `speed_mps` (m/s) and `from_deg` (degrees clockwise from north
    /// the wind blows from), a row for every mission day; each day's row is its forecast.
    #[arg(long)]
    pub wind_csv: Option<PathBuf>,
    /// The forecast's error: the wind flown in is the forecast plus a vector whose east and
    /// north components are normal with this standard deviation, m/s [default: 1 with --wind
    /// weibull:… or --wind-csv, else 0].
    #[arg(long)]
    pub gust: Option<f64>,
    /// Gusts leg by leg: each leg of a flown sortie (and the hover at its end) meets the
    /// day's wind plus a vector whose east and north components are normal with this
    /// standard deviation, m/s, seeded; in the air a sortie checks the rest of its route and
    /// re-plans in the day's wind plus about 2 of these standard deviations.
    #[arg(long, default_value_t = 0.0, value_name = "SIGMA")]
    pub leg_gust: f64,
    /// The planning margin: each mission is planned for its forecast speed plus the
    /// Q-quantile of the forecast error along the wind, σ·Φ⁻¹(Q) (σ = --gust; Q in
    /// [0.5, 0.999]; 0.5 plans at the forecast), or `settings` for `[flight]
    /// wind_margin_mps` as it is.
    #[arg(
        long,
        value_name = "Q|settings",
        default_value_t = gleaner_campaign::campaign_flight::DEFAULT_MARGIN_QUANTILE.to_string()
    )]
    pub margin_quantile: String,
    /// Weaker batteries: each sortie's battery holds a share of its rated capacity drawn
    /// uniformly in [1 − W, 1] (W in [0, 0.5]; 0: every battery as rated).
    #[arg(long, default_value_t = 0.0)]
    pub weak_battery: f64,
    /// Seed of the wind, forecast-error and battery draws (the same weather for every
    /// strategy and replicate).
    #[arg(long, default_value_t = 1)]
    pub weather_seed: u64,
}

/// The flight conditions the arguments give.
fn flight_conditions(
    args: &SimulateArgs,
) -> Result<gleaner_campaign::campaign_flight::FlightConditions> {
    use gleaner_campaign::campaign_flight::{FlightConditions, WindSource, parse_margin_quantile};
    let wind = WindSource::choose(args.wind.as_deref(), args.wind_csv.as_deref())?;
    Ok(FlightConditions {
        gust_sd_mps: args.gust.unwrap_or(wind.default_gust_sd_mps()),
        wind,
        battery_weakening: args.weak_battery,
        seed: args.weather_seed,
        leg_gust_sd_mps: args.leg_gust,
        margin_quantile: parse_margin_quantile(&args.margin_quantile)?,
    })
}

/// The replay options the arguments give.
fn options(args: &SimulateArgs) -> Result<ReplayOptions> {
    Ok(ReplayOptions {
        history_until: args.history_until,
        history_from: args.history_from,
        start: args.start,
        end: args.end,
        every_s: (args.every_hours * 3600.0).round() as i64,
        times: args.times.clone(),
        strategies: Strategy::parse_list(&args.strategies)?,
        seeds: args.seeds.clone(),
        budgets: args.budgets.clone(),
        modality: args.modality.clone(),
        event_z: args.event_z,
        planner_iterations: args.planner_iterations,
        sorties: args.sorties,
        neighbours: args.neighbours,
        estimator: if args.simple_kriging {
            app::Estimator::Levels(gleaner_kriging::Mean::Known)
        } else if args.level_kriging {
            app::Estimator::Levels(gleaner_kriging::Mean::Unknown)
        } else {
            args.estimator
        },
        buffer: args.buffer,
        jobs: args.jobs,
        energy_preset: args.energy_preset.clone(),
        flight: flight_conditions(args)?,
        unshared_weight: args.unshared_weight,
        information_weight: args.information_weight,
    })
}

/// What the arguments replay.
fn source(args: &SimulateArgs) -> Result<Source> {
    Ok(match (&args.project, args.dataset) {
        (Some(dir), _) => Source::Project(dir.clone()),
        (None, Some(Dataset::CafDaily)) => Source::Preset(Preset::CafDaily),
        (None, Some(Dataset::CafHourly)) => Source::Preset(Preset::CafHourly),
        (None, Some(Dataset::HubbardBrook)) => Source::Preset(Preset::HubbardBrook),
        (None, Some(Dataset::Synthetic)) => Source::Synthetic(
            args.farm_seeds
                .iter()
                .map(|&seed| SyntheticFarm {
                    seed,
                    sensors: args.farm_sensors,
                    days: args.farm_days,
                    events: args.farm_events,
                    scale_extent: args.farm_scale_extent,
                    history_days: args.farm_history_days,
                })
                .collect(),
        ),
        (None, None) => anyhow::bail!("give --dataset or --project"),
    })
}

/// Runs the campaigns the arguments describe (`gleaner_campaign::simulation`), which write
/// the results into `args.out`; returns the summary line.
pub fn run(
    args: &SimulateArgs,
    command_line: &str,
    progress: &crate::progress::Terminal,
) -> Result<String> {
    let request = SimulationRequest {
        source: source(args)?,
        options: options(args)?,
        out: args.out.clone(),
        data_dir: args.data_dir.clone(),
        cell_size_m: args.cell_size,
        command_line: command_line.to_string(),
    };
    let s = simulation::simulate(&request, crate::args::clock_now(), progress)?;
    Ok(format!("{}\n", simulation::summary_line(&s, &args.out)))
}
