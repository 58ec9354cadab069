//! Campaign simulation (docs/method.md §7): a dataset replayed as a campaign of missions, one run per
//! strategy, seed and budget, each against its own real store and through the same use cases
//! the CLI calls (`score`/`compute`, `plan`, `explore`, `fly` → `record`).
//!
//! The planner knows only what its project's store holds: the history available when the
//! campaign starts plus what its flights brought back. A reading stamped t becomes available
//! at t + period ([`Truth::period_s`]); a flight at T brings back only readings available by T
//! ([`crate::fly`]). The evaluator alone reads the whole [`Truth`]: after each mission it
//! compares every sensor's estimated value (last value carried forward, and kriging from
//! the field model fitted on the history) with the true reading stamped T − period, checks
//! which anomaly events the flights have caught, how stale the sensors are, and how well the
//! condition model predicted the cells' classes before the flight.

use std::collections::{BTreeMap, HashMap, HashSet};
use std::path::PathBuf;

use gleaner_field::{CellIndex, Modality, Sensor, SensorId, UnixSeconds};
use gleaner_ingest::{IngestReport, Readings};
use gleaner_kriging::{Covariance, FieldModel, IncrementModel, variance_reduction};
use gleaner_mission::Planner;
use gleaner_store::{SqliteStore, Store, StoreRead};

use gleaner_app::settings::Settings;
use gleaner_app::shortcuts::{
    EstimateReads, ExplorationMemo, Parsed, estimate_with, explore_with, fit_models, ingest_parsed,
    plan_scored, target_modality,
};
use gleaner_app::{AppError, Result};
use gleaner_app::{ExploreRequest, explore};
use gleaner_app::{Format, IngestRequest};
use gleaner_app::{InitRequest, init_store, init_store_with};
use gleaner_app::{Objective, PlanRequest};
use gleaner_app::{Progress, Silent};
use gleaner_app::{Project, SensorEstimate};
use gleaner_app::{ScoreRequest, compute, score};

use crate::campaign_flight::{FlightConditions, FlightDay, fly_in_wind};
use crate::simulate::{Truth, fly_buffered, fly_cells};

/// A utility term, for ablations.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Term {
    /// Freshness F (alpha).
    Freshness,
    /// Anomaly A (beta).
    Anomaly,
    /// Model uncertainty U (gamma).
    Uncertainty,
    /// Redundancy R (delta).
    Redundancy,
}

/// How a run chooses the cells of each mission.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Strategy {
    /// Every cell, in as many sorties as it takes (the exploration plan at each mission).
    Exhaustive,
    /// Longest-unvisited first: score = days since the cell's last collection.
    RoundRobin,
    /// S with freshness only (alpha = 1, the other weights 0), default planner.
    Freshness,
    /// Uniform random scores in (0, 1], seeded, default planner.
    Random,
    /// Every cell worth the same, the paper's greedy insertion: the nearest cells first.
    Nearest,
    /// The paper's method: its S (docs/method.md §2 at the paper's values,
    /// [`gleaner_app::settings::UtilitySection::paper`], whatever the project's), its greedy planner.
    Paper,
    /// gleaner's method: the project's utility settings made gleaner's
    /// ([`gleaner_app::settings::UtilitySection::gleaner`]: gated S with the drift freshness, the
    /// bounded anomaly, γ = δ = 0; plus η·V when `[utility] variance_weight` is set), the
    /// default planner.
    Gleaner,
    /// gleaner's method with one utility term switched off (with α = 0 the gated S is 0
    /// everywhere: nothing is worth a flight).
    Without(Term),
    /// Expected reduction of the field's posterior variance (greedy marginal gains of the
    /// kriging model fitted on the history), default planner.
    Variance,
    /// The information objective (docs/method.md §7): the route whose readings remove the
    /// most posterior variance of the dynamic field model (fitted on the history, run as a
    /// filter over what is known at each mission), summed over every sensor; marginal-gain
    /// orienteering ([`gleaner_app::Objective::Information`]).
    Information,
    /// The oracle's flyable twin: each cell worth its sensors' *predicted* squared error
    /// before the flight — the campaign estimator's variance from what is known, nothing
    /// clairvoyant — routed by the default planner.
    Expected,
    /// gleaner's earlier method ([`gleaner_app::settings::UtilitySection::gated`]: gated S with a
    /// 14-day freshness half-life and the bounded anomaly, the project's γ and δ), the
    /// default planner.
    Gated,
    /// gleaner's score and the information objective together
    /// ([`gleaner_app::Objective::Hybrid`]): gleaner's utility settings, a route worth its
    /// cells' share of the total S blended with the share of the dynamic field model's
    /// posterior variance its readings remove (`[planner] information_weight`), marginal-gain
    /// orienteering.
    Hybrid,
    /// A clairvoyant yardstick, not a strategy a UAV could fly: each cell is worth the squared
    /// error its sensors' pre-flight model-based estimates have against the values the flight
    /// will bring back (the truth stamped T − period, (m³/m³)² ×10⁶ for soil water), routed by
    /// the default planner. What choosing cells could buy at the budget if one knew the
    /// answer (up to the planner, and to the neighbours' estimates a visit also improves); never
    /// among [`Strategy::ALL`] nor counted as a same-energy competitor.
    Oracle,
}

impl Strategy {
    /// Every strategy, ablations included, in report order.
    pub const ALL: [Strategy; 16] = [
        Strategy::Gleaner,
        Strategy::Paper,
        Strategy::Variance,
        Strategy::Information,
        Strategy::Freshness,
        Strategy::RoundRobin,
        Strategy::Random,
        Strategy::Nearest,
        Strategy::Exhaustive,
        Strategy::Without(Term::Freshness),
        Strategy::Without(Term::Anomaly),
        Strategy::Without(Term::Uncertainty),
        Strategy::Without(Term::Redundancy),
        Strategy::Gated,
        Strategy::Expected,
        Strategy::Hybrid,
    ];

    /// The main strategies (`main`): gleaner, paper, variance, information, freshness,
    /// round-robin, random, nearest, exhaustive — the first nine of [`Strategy::ALL`], no
    /// ablations.
    pub const MAIN: &'static [Strategy] = Self::ALL.as_slice().split_at(9).0;

    /// Yardsticks run only when named: they see the truth (see [`Strategy::Oracle`]).
    pub const YARDSTICKS: [Strategy; 1] = [Strategy::Oracle];

    /// Whether the strategy sees the truth (a yardstick, not a competitor).
    pub fn is_yardstick(self) -> bool {
        Self::YARDSTICKS.contains(&self)
    }

    /// The strategy's name in outputs and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Strategy::Exhaustive => "exhaustive",
            Strategy::RoundRobin => "round-robin",
            Strategy::Freshness => "freshness",
            Strategy::Random => "random",
            Strategy::Nearest => "nearest",
            Strategy::Paper => "paper",
            Strategy::Gleaner => "gleaner",
            Strategy::Without(Term::Freshness) => "no-freshness",
            Strategy::Without(Term::Anomaly) => "no-anomaly",
            Strategy::Without(Term::Uncertainty) => "no-uncertainty",
            Strategy::Without(Term::Redundancy) => "no-redundancy",
            Strategy::Variance => "variance",
            Strategy::Information => "information",
            Strategy::Hybrid => "hybrid",
            Strategy::Expected => "expected-error",
            Strategy::Gated => "gated",
            Strategy::Oracle => "oracle",
        }
    }

    /// Parses a name of [`Strategy::name`].
    pub fn parse(name: &str) -> Result<Self> {
        Self::ALL
            .iter()
            .chain(&Self::YARDSTICKS)
            .copied()
            .find(|s| s.name() == name)
            .ok_or_else(|| {
                AppError::Invalid(format!(
                    "unknown strategy {name:?}: expected one of {}, or the yardstick {}",
                    Self::ALL.map(Strategy::name).join(", "),
                    Self::YARDSTICKS.map(Strategy::name).join(", ")
                ))
            })
    }

    /// Strategies by name, in order, duplicates next to each other dropped: `all` is
    /// [`Strategy::ALL`], `main` [`Strategy::MAIN`].
    pub fn parse_list<S: AsRef<str>>(names: &[S]) -> Result<Vec<Self>> {
        let mut out = Vec::new();
        for n in names {
            match n.as_ref() {
                "all" => out.extend(Self::ALL),
                "main" => out.extend_from_slice(Self::MAIN),
                other => out.push(Self::parse(other)?),
            }
        }
        out.dedup();
        if out.is_empty() {
            return Err(AppError::Invalid("no strategy named".into()));
        }
        Ok(out)
    }

    /// The run's settings: the campaign's with this strategy's weights and planner.
    fn settings(self, base: &Settings) -> Settings {
        let mut s = base.clone();
        match self {
            Strategy::Paper => s.utility = s.utility.paper(),
            Strategy::Gleaner | Strategy::Without(_) | Strategy::Hybrid => {
                s.utility = s.utility.gleaner()
            }
            Strategy::Gated => s.utility = s.utility.gated(),
            _ => {}
        }
        let u = &mut s.utility;
        match self {
            Strategy::Freshness => {
                (u.alpha, u.beta, u.gamma, u.delta) = (1.0, 0.0, 0.0, 0.0);
                u.variance_weight = 0.0;
            }
            Strategy::Without(Term::Freshness) => u.alpha = 0.0,
            Strategy::Without(Term::Anomaly) => u.beta = 0.0,
            Strategy::Without(Term::Uncertainty) => u.gamma = 0.0,
            Strategy::Without(Term::Redundancy) => u.delta = 0.0,
            _ => {}
        }
        s
    }

    /// A rough rank of a run's cost (higher: longer), for scheduling the longest runs first:
    /// exhaustive flies several sorties per mission and records each; the drift freshness
    /// reads and scores its window at every scoring; given scores skip the utility engine's
    /// second scoring. Only the order of the runs depends on it, never a result.
    fn expected_cost(self) -> u8 {
        match self {
            Strategy::Exhaustive => 4,
            Strategy::Gleaner | Strategy::Without(_) | Strategy::Hybrid => 3,
            Strategy::Freshness | Strategy::Gated | Strategy::Paper | Strategy::Information => 2,
            Strategy::Variance
            | Strategy::RoundRobin
            | Strategy::Random
            | Strategy::Oracle
            | Strategy::Expected => 1,
            Strategy::Nearest => 0,
        }
    }

    fn planner(self) -> Planner {
        match self {
            Strategy::Paper | Strategy::Nearest => Planner::Greedy,
            _ => Planner::Default,
        }
    }

    /// How a run of this strategy chooses its cells besides its settings: the strategy itself
    /// when [`run_one`] gives the planner its own per-cell scores or explores (exhaustive);
    /// `None` when the utility engine scores by the run's settings alone. Two runs with the
    /// same selection and the same settings ([`run_settings`]) compute the same results.
    fn selection(self) -> Option<Strategy> {
        match self {
            Strategy::Exhaustive
            | Strategy::RoundRobin
            | Strategy::Random
            | Strategy::Nearest
            | Strategy::Variance
            | Strategy::Information
            | Strategy::Hybrid
            | Strategy::Expected
            | Strategy::Oracle => Some(self),
            Strategy::Freshness
            | Strategy::Paper
            | Strategy::Gleaner
            | Strategy::Without(_)
            | Strategy::Gated => None,
        }
    }
}

/// A run's settings: the strategy's ([`Strategy::settings`]) with the run's budget, planner
/// and seed.
fn run_settings(request: &CampaignRequest, key: &RunKey) -> Result<Settings> {
    let mut settings = key.strategy.settings(&request.settings);
    let battery = settings.energy.to_core()?.battery.capacity_j;
    settings.energy.battery_j = Some(battery * key.budget);
    settings.planner.solver = key.strategy.planner().name().to_string();
    settings.planner.seed = key.seed;
    settings.flight.wind_margin_mps = request
        .flight
        .planning_margin_mps(settings.flight.wind_margin_mps);
    Ok(settings)
}

/// Everything a run's results depend on besides what every run shares: the strategy's
/// selection ([`Strategy::selection`]), the seed, the budget (bits) and the run's settings
/// (their `Debug` text: every field, floats to the last bit and signed zeros distinct).
/// Runs with equal signatures are the same deterministic computation, so a campaign runs
/// one of them and gives its results to the others (e.g. gleaner's method has γ = δ = 0, so
/// its `no-uncertainty` and `no-redundancy` ablations are gleaner's run itself).
fn run_signature(request: &CampaignRequest, key: &RunKey) -> Result<String> {
    let settings = run_settings(request, key)?;
    Ok(format!(
        "{:?} {} {:016x} {settings:?}",
        key.strategy.selection(),
        key.seed,
        key.budget.to_bits()
    ))
}

/// An anomaly event to catch: sensors, and the readings' times it covers.
#[derive(Debug, Clone, PartialEq)]
pub struct TruthEvent {
    /// Identifier.
    pub id: String,
    /// The affected sensors (caught when any of them is collected with an event reading).
    pub sensors: Vec<SensorId>,
    /// First affected reading's time, seconds.
    pub start: UnixSeconds,
    /// End (exclusive), seconds: the first reading time no longer in the event.
    pub end: UnixSeconds,
}

/// Events of the real-data rule: for each sensor, z = (Δ − mean Δ) / sd Δ of its consecutive
/// one-step changes over its whole `modality` series in the truth; an event is a maximal run
/// of consecutive steps with |z| > `z_threshold` (a sudden wetting or drying).
pub fn rule_events(truth: &Truth, modality: &str, z_threshold: f64) -> Vec<TruthEvent> {
    let series = truth_series(truth, modality);
    let mut events = Vec::new();
    for (sensor, (times, values)) in &series {
        let step = gleaner_app::shortcuts::sampling_step(std::slice::from_ref(times)).max(1);
        let changes: Vec<(UnixSeconds, f64)> = times
            .windows(2)
            .zip(values.windows(2))
            .filter(|(t, _)| t[1] - t[0] == step)
            .map(|(t, v)| (t[1], v[1] - v[0]))
            .collect();
        if changes.len() < 10 {
            continue;
        }
        let n = changes.len() as f64;
        let mean = changes.iter().map(|c| c.1).sum::<f64>() / n;
        let sd = (changes.iter().map(|c| (c.1 - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        if sd.is_nan() || sd <= 0.0 {
            continue;
        }
        let mut run: Option<(UnixSeconds, UnixSeconds)> = None;
        let close = |run: (UnixSeconds, UnixSeconds), events: &mut Vec<TruthEvent>| {
            events.push(TruthEvent {
                id: String::new(),
                sensors: vec![sensor.clone()],
                start: run.0,
                end: run.1 + step,
            });
        };
        for &(t, d) in &changes {
            if ((d - mean) / sd).abs() > z_threshold {
                run = match run {
                    Some((s, e)) if t - e == step => Some((s, t)),
                    Some(r) => {
                        close(r, &mut events);
                        Some((t, t))
                    }
                    None => Some((t, t)),
                };
            }
        }
        if let Some(r) = run {
            close(r, &mut events);
        }
    }
    events.sort_by(|a, b| (a.start, &a.sensors).cmp(&(b.start, &b.sensors)));
    for (k, e) in events.iter_mut().enumerate() {
        e.id = format!("Z{:04}", k + 1);
    }
    events
}

/// Per sensor: the truth's `modality` series (times ascending, seconds; values).
fn truth_series(truth: &Truth, modality: &str) -> BTreeMap<SensorId, (Vec<UnixSeconds>, Vec<f64>)> {
    let r = truth.readings();
    let Some(m) = r
        .modalities
        .iter()
        .position(|x| x.modality.to_string() == modality)
    else {
        return BTreeMap::new();
    };
    let mut out: BTreeMap<SensorId, Vec<(UnixSeconds, f64)>> = BTreeMap::new();
    for row in r.rows.iter().filter(|row| row.modality as usize == m) {
        if let Some(s) = r.sensors.get(row.sensor as usize) {
            out.entry(s.clone()).or_default().push((row.t, row.value));
        }
    }
    out.into_iter()
        .map(|(s, mut v)| {
            v.sort_by_key(|p| p.0);
            v.dedup_by_key(|p| p.0);
            (
                s,
                (
                    v.iter().map(|p| p.0).collect(),
                    v.iter().map(|p| p.1).collect(),
                ),
            )
        })
        .collect()
}

/// A campaign to run.
#[derive(Debug, Clone)]
pub struct CampaignRequest {
    /// The dataset's name in outputs.
    pub label: String,
    /// The sensors (as for `init`; its directory is not used).
    pub init: InitRequest,
    /// The sensors themselves (e.g. a project's own, `simulate --project`), used instead of
    /// reading `init.sensors` when given.
    pub sensors: Option<Vec<Sensor>>,
    /// The settings every run starts from (grid, utility, energy at 100% budget, planner).
    pub settings: Settings,
    /// Readings available by this time (t + period <= it) are the history every run starts
    /// with, seconds.
    pub history_until: UnixSeconds,
    /// Readings before this time are left out of the history, seconds [default: none].
    pub history_from: Option<UnixSeconds>,
    /// Mission times, seconds, ascending, after `history_until`.
    pub schedule: Vec<UnixSeconds>,
    /// Strategies.
    pub strategies: Vec<Strategy>,
    /// Replicate seeds (planner and random choices).
    pub seeds: Vec<u64>,
    /// Battery capacities as fractions of the settings' (1 = the paper's budget).
    pub budgets: Vec<f64>,
    /// The evaluated modality [default: the condition modality].
    pub modality: Option<String>,
    /// Ground-truth events (synthetic farms) [default: [`rule_events`] with `event_z`].
    pub events: Option<Vec<TruthEvent>>,
    /// |z| threshold of the real-data event rule.
    pub event_z: f64,
    /// Planner iteration cap (results independent of the machine's speed).
    pub planner_iterations: u64,
    /// Sorties per mission of the planned strategies (battery swaps, each within the budget,
    /// planned together by `plan`'s team solver), in 1..=[`gleaner_app::MAX_SORTIES`];
    /// exhaustive collection flies as many as it takes whatever this says.
    pub sorties: usize,
    /// Observations per kriging estimate.
    pub neighbours: usize,
    /// The reconstruction's model-based estimator (the `kriged` metrics): kriging of changes
    /// (the default), the dynamic field model or kriging of levels.
    pub estimator: gleaner_app::Estimator,
    /// Runs in parallel (threads; 0 = rayon's default).
    pub jobs: usize,
    /// Provenance time stamped on missions, seconds.
    pub clock_now: UnixSeconds,
    /// The wind and batteries the flights meet [default: still air, full batteries: flown
    /// as planned]; every run meets the same.
    pub flight: FlightConditions,
}

/// A dataset as a campaign takes it: the truth, the sensors, the settings, and the dataset's
/// own defaults for the period.
pub struct DatasetParts {
    /// The dataset's name in outputs.
    pub label: String,
    /// The sensors file (as for `init`; its directory is the runs' project directory).
    pub init: InitRequest,
    /// The sensors themselves, used instead of reading `init.sensors` when given.
    pub sensors: Option<Vec<Sensor>>,
    /// The settings every run starts from.
    pub settings: Settings,
    /// Everything the sensors logged.
    pub truth: Truth,
    /// Default end of the history, s.
    pub history_until: UnixSeconds,
    /// Default start of the history, s (`None`: all of it).
    pub history_from: Option<UnixSeconds>,
    /// Default last mission, s.
    pub end: UnixSeconds,
    /// Whether a first mission given without an end of the history moves the history's end
    /// there too (a project's own record: the history is everything before the missions).
    pub history_follows_start: bool,
    /// Ground-truth events (synthetic farms) [default: the real-data rule].
    pub events: Option<Vec<TruthEvent>>,
}

/// What a replay asks of a dataset beyond its parts: the period, the strategies and the
/// options of `gleaner simulate` and `POST /api/v1/simulate` (times in s).
#[derive(Debug, Clone, PartialEq)]
pub struct ReplayOptions {
    /// End of the history [default: the dataset's].
    pub history_until: Option<UnixSeconds>,
    /// Start of the history [default: the dataset's].
    pub history_from: Option<UnixSeconds>,
    /// First mission [default: the end of the history].
    pub start: Option<UnixSeconds>,
    /// Last mission at or before this time [default: the dataset's].
    pub end: Option<UnixSeconds>,
    /// Seconds between missions.
    pub every_s: i64,
    /// Mission times instead of a period.
    pub times: Option<Vec<UnixSeconds>>,
    /// Strategies.
    pub strategies: Vec<Strategy>,
    /// Replicate seeds.
    pub seeds: Vec<u64>,
    /// Battery capacities as fractions of the settings'.
    pub budgets: Vec<f64>,
    /// The evaluated modality [default: the condition modality].
    pub modality: Option<String>,
    /// |z| threshold of the real-data event rule.
    pub event_z: f64,
    /// Planner iteration cap per mission.
    pub planner_iterations: u64,
    /// Sorties per mission of the planned strategies.
    pub sorties: usize,
    /// Observations per model-based estimate.
    pub neighbours: usize,
    /// The model-based estimator.
    pub estimator: gleaner_app::Estimator,
    /// Sensor buffers' capacity in readings per modality [default: unlimited].
    pub buffer: Option<usize>,
    /// Runs in parallel (0 = rayon's default).
    pub jobs: usize,
    /// Energy preset (`paper`, `large-pack`) instead of the dataset's settings'.
    pub energy_preset: Option<String>,
    /// The wind and batteries the flights meet.
    pub flight: FlightConditions,
    /// `[planner] unshared_weight` instead of the dataset's settings' (the dynamic field
    /// model's unshared per-sensor drift; 0: none).
    pub unshared_weight: Option<f64>,
    /// `[planner] information_weight` instead of the dataset's settings' (the hybrid
    /// objective's weight on information, in [0, 1]).
    pub information_weight: Option<f64>,
}

impl Default for ReplayOptions {
    fn default() -> Self {
        Self {
            history_until: None,
            history_from: None,
            start: None,
            end: None,
            every_s: 86_400,
            times: None,
            strategies: Strategy::MAIN.to_vec(),
            seeds: vec![1],
            budgets: vec![1.0],
            modality: None,
            event_z: 3.0,
            planner_iterations: 300,
            sorties: 1,
            neighbours: gleaner_app::DEFAULT_NEIGHBOURS,
            estimator: gleaner_app::Estimator::default(),
            buffer: None,
            jobs: 2,
            energy_preset: None,
            flight: FlightConditions::default(),
            unshared_weight: None,
            information_weight: None,
        }
    }
}

/// A campaign ready to run: its request and its truth.
pub struct Replay {
    /// The request.
    pub request: CampaignRequest,
    /// Everything the sensors logged (with the options' buffer).
    pub truth: Truth,
}

/// The campaign `options` make of `dataset`, missions stamped with `clock_now` (s).
pub fn replay(
    dataset: DatasetParts,
    options: &ReplayOptions,
    clock_now: UnixSeconds,
) -> Result<Replay> {
    let mut truth = dataset.truth;
    truth.buffer_readings = options.buffer;
    let mut settings = dataset.settings;
    if let Some(preset) = &options.energy_preset {
        settings.energy.preset = preset.clone();
    }
    if let Some(w) = options.unshared_weight {
        settings.planner.unshared_weight = w;
    }
    if let Some(w) = options.information_weight {
        settings.planner.information_weight = w;
    }
    settings.validate()?;
    let history_until = match (options.history_until, options.start) {
        (Some(t), _) => t,
        (None, Some(start)) if dataset.history_follows_start => start,
        (None, _) => dataset.history_until,
    };
    let start = options.start.unwrap_or(history_until);
    let end = options.end.unwrap_or(dataset.end);
    let schedule = match &options.times {
        Some(t) => t.clone(),
        None => every(start, end, options.every_s)?,
    };
    Ok(Replay {
        request: CampaignRequest {
            label: dataset.label,
            init: dataset.init,
            sensors: dataset.sensors,
            settings,
            history_until,
            history_from: options.history_from.or(dataset.history_from),
            schedule,
            strategies: options.strategies.clone(),
            seeds: options.seeds.clone(),
            budgets: options.budgets.clone(),
            modality: options.modality.clone(),
            events: dataset.events,
            event_z: options.event_z,
            planner_iterations: options.planner_iterations,
            sorties: options.sorties,
            neighbours: options.neighbours,
            estimator: options.estimator,
            jobs: options.jobs,
            clock_now,
            flight: options.flight.clone(),
        },
        truth,
    })
}

/// One mission's metrics (after its flights were recorded).
#[derive(Debug, Clone, PartialEq)]
pub struct MissionMetrics {
    /// Mission number, from 0.
    pub index: usize,
    /// Mission time T, seconds.
    pub t: UnixSeconds,
    /// Sorties flown.
    pub sorties: usize,
    /// Cells visited.
    pub cells: usize,
    /// Energy of all sorties, J.
    pub energy_j: f64,
    /// Usable budget per sortie, J.
    pub budget_j: f64,
    /// Root-mean-square error of last value carried forward, the modality's unit.
    pub rmse_carried: f64,
    /// Mean absolute error of last value carried forward.
    pub mae_carried: f64,
    /// Root-mean-square error of the kriging estimate.
    pub rmse_kriged: f64,
    /// Mean absolute error of the kriging estimate.
    pub mae_kriged: f64,
    /// Mean kriging variance, the unit squared.
    pub mean_variance: f64,
    /// Share of the sensors *estimated* (not read at T − period: their estimate is not their
    /// own reading) whose true value lies in the estimator's 90% interval, estimate ±
    /// 1.645·sd; None when none was estimated (or results of an older version). A calibrated
    /// model covers 90%.
    pub coverage90: Option<f64>,
    /// Root-mean-square error of last value carried forward from what was known before this
    /// mission's flights (after the previous mission's), against the same truth: the error the
    /// operator lived with between the two missions, at its largest. NaN when not measured
    /// (results files of an older version).
    pub rmse_carried_before: f64,
    /// The same for the kriging estimate.
    pub rmse_kriged_before: f64,
    /// Sensors with a true value at T − period (those evaluated).
    pub evaluated: usize,
    /// Mean time since each sensor's last collection, seconds.
    pub staleness_mean_s: f64,
    /// Largest time since a sensor's last collection, seconds.
    pub staleness_max_s: f64,
    /// Share of cells whose class the condition model predicted right before the flight.
    pub classifier_accuracy: Option<f64>,
    /// Readings dropped by full buffers, brought to light by this mission's collections.
    pub lost_readings: u64,
    /// Events first caught at this mission.
    pub events_caught: usize,
    /// How its sorties flew: wind, batteries, re-plans, energy against the battery (`None`
    /// in results files written before flights were simulated).
    pub flight: Option<FlightDay>,
}

/// A run's identity.
#[derive(Debug, Clone, PartialEq)]
pub struct RunKey {
    /// Strategy.
    pub strategy: Strategy,
    /// Replicate seed.
    pub seed: u64,
    /// Budget as a fraction of the settings' battery.
    pub budget: f64,
}

/// One run's results.
#[derive(Debug, Clone)]
pub struct RunResult {
    /// Which run.
    pub key: RunKey,
    /// One per scheduled mission.
    pub missions: Vec<MissionMetrics>,
    /// Per campaign event (same order as [`CampaignResult::events`]): when it was caught
    /// (the mission time), seconds.
    pub caught: Vec<Option<UnixSeconds>>,
    /// Every cell visited, with the utility terms the planner's scoring gave it before the
    /// flight (diagnostics: which terms drove the choice, revisit counts). Empty when the
    /// results were read back from files that do not hold it.
    pub visits: Vec<Visit>,
}

/// One visited cell of one mission, with its pre-flight utility terms (the project's weights
/// and forms, whatever the strategy chose by).
#[derive(Debug, Clone, PartialEq)]
pub struct Visit {
    /// Mission number, from 0.
    pub index: usize,
    /// The cell.
    pub cell: CellIndex,
    /// Days since the cell was last collected (its stalest sensor), at the mission time.
    pub age_days: f64,
    /// Freshness F, in [0, 1].
    pub f: f64,
    /// Anomaly as scored (raw or bounded).
    pub a: f64,
    /// Uncertainty U, in [0, 1].
    pub u: f64,
    /// Redundancy R, in [0, 1].
    pub r: f64,
    /// Score S with the project's weights.
    pub s: f64,
}

/// A campaign's results.
#[derive(Debug, Clone)]
pub struct CampaignResult {
    /// The dataset's name.
    pub label: String,
    /// The evaluated modality.
    pub modality: String,
    /// The logging period, seconds.
    pub period_s: i64,
    /// The field model fitted on the history.
    pub covariance: Covariance,
    /// The model of changes fitted on the history (`None` in results written before it).
    pub changes: Option<IncrementModel>,
    /// The estimator every run was judged by, resolved against the fitted models (`None` in
    /// results written before it was recorded).
    pub estimator: Option<gleaner_app::Estimator>,
    /// Events that became available during the campaign.
    pub events: Vec<TruthEvent>,
    /// One per (strategy, seed, budget), in that order.
    pub runs: Vec<RunResult>,
}

/// A small deterministic generator (SplitMix64): the random strategy's and the campaign
/// weather's draws.
pub(crate) fn splitmix(mut x: u64) -> u64 {
    x = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    x ^ (x >> 31)
}

/// What every run shares: the history, the truth's evaluation series, the cells' sensors.
struct Shared<'a> {
    request: &'a CampaignRequest,
    truth: &'a Truth,
    history: Readings,
    modality: Modality,
    /// Truth series of the evaluated modality, per sensor id.
    series: BTreeMap<SensorId, (Vec<UnixSeconds>, Vec<f64>)>,
    /// Truth series of the condition modality (may equal `series`).
    class_series: BTreeMap<SensorId, (Vec<UnixSeconds>, Vec<f64>)>,
    events: Vec<TruthEvent>,
    model: FieldModel,
    /// The model of changes fitted on the history.
    changes: IncrementModel,
    /// The dynamic field model fitted on the history (None when it cannot be fitted).
    dynamic: Option<gleaner_kriging::DynamicModel>,
    /// The request's estimator, resolved against the models ([`gleaner_app::Estimator::resolve`]).
    estimator: gleaner_app::Estimator,
    step_s: i64,
    /// The store every run starts from (the history ingested, the utility state built),
    /// copied for each run.
    template: Option<std::sync::Mutex<SqliteStore>>,
}

fn value_at(
    series: &BTreeMap<SensorId, (Vec<UnixSeconds>, Vec<f64>)>,
    s: &SensorId,
    t: UnixSeconds,
) -> Option<f64> {
    let (times, values) = series.get(s)?;
    times.binary_search(&t).ok().map(|k| values[k])
}

/// A new in-memory project for one run, with the history ingested: a copy of the campaign's
/// template store when there is one (what the steps below would write again), scored once
/// with the run's settings.
fn new_run_project(shared: &Shared<'_>, settings: Settings) -> Result<Project<SqliteStore>> {
    let request = shared.request;
    if let Some(template) = &shared.template {
        let store = template
            .lock()
            .map_err(|_| AppError::Invalid("a campaign run panicked".into()))?
            .copy_in_memory()?;
        let mut project = Project::new(&request.init.dir, settings, store);
        score(
            &mut project,
            &ScoreRequest {
                at: Some(request.history_until),
                ..ScoreRequest::default()
            },
        )?;
        return Ok(project);
    }
    let store = SqliteStore::open_in_memory()?;
    let dir = request.init.dir.clone();
    let mut project = Project::new(&dir, settings, store);
    match &request.sensors {
        Some(sensors) => init_store_with(&mut project, sensors, &request.label)?,
        None => init_store(&mut project, &request.init)?,
    };
    let report = IngestReport {
        rows_read: shared.history.rows.len() as u64,
        readings: shared.history.rows.len() as u64,
        ..IngestReport::default()
    };
    let parsed = Parsed {
        files: vec![(
            PathBuf::from(format!("{} history", request.label)),
            Format::Long,
            shared.history.clone(),
            report.clone(),
        )],
        report,
    };
    ingest_parsed(
        &mut project,
        parsed,
        &IngestRequest {
            now: Some(request.history_until),
            ..IngestRequest::default()
        },
        request.clock_now,
        &Silent,
    )?;
    // As after any bulk ingest: the first scoring rebuilds the persisted utility state, so
    // every mission's scoring takes the fast path.
    score(
        &mut project,
        &ScoreRequest {
            at: Some(request.history_until),
            ..ScoreRequest::default()
        },
    )?;
    Ok(project)
}

/// Runs the campaign: every (strategy, seed, budget) in parallel over `jobs` threads, each
/// deterministic, so the results do not depend on the thread count.
pub fn run_campaign(
    request: &CampaignRequest,
    truth: &Truth,
    progress: &(dyn Progress + Sync),
) -> Result<CampaignResult> {
    if request.schedule.is_empty() {
        return Err(AppError::Invalid(
            "the campaign has no mission times".into(),
        ));
    }
    if request.schedule.windows(2).any(|w| w[1] <= w[0]) {
        return Err(AppError::Invalid(
            "mission times must be strictly increasing".into(),
        ));
    }
    if request.schedule[0] < request.history_until {
        return Err(AppError::Invalid(
            "the first mission is before the end of the history".into(),
        ));
    }
    if request.budgets.iter().any(|b| !(b.is_finite() && *b > 0.0)) {
        return Err(AppError::Invalid(
            "budgets must be positive fractions".into(),
        ));
    }
    if !(1..=gleaner_app::MAX_SORTIES).contains(&request.sorties) {
        return Err(AppError::Invalid(format!(
            "sorties = {}: allowed 1..={}",
            request.sorties,
            gleaner_app::MAX_SORTIES
        )));
    }
    request.flight.check(&request.schedule)?;
    let airspace = &request.settings.field;
    if !request.flight.is_still() && (airspace.geofence.is_some() || airspace.no_fly.is_some()) {
        return Err(AppError::Invalid(
            "a campaign in wind or with weak batteries re-plans in the air with straight legs, \
             and these settings set [field] geofence or no_fly: simulate it in still air"
                .into(),
        ));
    }
    let mut history = truth.available_by(request.history_until);
    if let Some(from) = request.history_from {
        history.rows.retain(|r| r.t >= from);
    }
    // The field model, fitted once on the history (the exploration history every run shares).
    let probe = {
        let shared0 = Shared {
            request,
            truth,
            history: history.clone(),
            modality: Modality::new("vw@30cm").map_err(|e| AppError::Invalid(e.to_string()))?,
            series: BTreeMap::new(),
            class_series: BTreeMap::new(),
            events: Vec::new(),
            model: FieldModel {
                covariance: Covariance::new(1.0, 0.0, 1.0, 1.0)
                    .map_err(|e| AppError::core("field model", e))?,
                means: Vec::new(),
            },
            changes: {
                let none = gleaner_kriging::Variogram {
                    nugget: 0.0,
                    partial: 0.0,
                    scale_s: 1.0,
                };
                IncrementModel::new(none, 1.0, none)
                    .map_err(|e| AppError::core("model of changes", e))?
            },
            dynamic: None,
            estimator: request.estimator,
            step_s: 1,
            template: None,
        };
        new_run_project(&shared0, request.settings.clone())?
    };
    let modality = target_modality(&probe, request.modality.as_deref())?;
    let gleaner_app::shortcuts::Models {
        levels: model,
        changes,
        dynamic,
        step_s,
    } = fit_models(&probe, &modality, request.history_until)?;
    let names: Vec<String> = probe
        .store()
        .modalities()?
        .into_iter()
        .map(|m| m.modality.to_string())
        .collect();
    let class_name = gleaner_app::shortcuts::condition_modality(probe.settings(), &names);
    let (dir, probe_settings, mut template) = probe.into_parts();
    // Exhaustive collection must reach every cell within one battery: refuse a budget that
    // cannot, now rather than when its run fails after the others have run for minutes.
    if request.strategies.contains(&Strategy::Exhaustive) {
        for &budget in &request.budgets {
            let mut settings = probe_settings.clone();
            let battery = settings.energy.to_core()?.battery.capacity_j;
            settings.energy.battery_j = Some(battery * budget);
            let mut check = Project::new(&dir, settings, template);
            let explored = explore(
                &mut check,
                &ExploreRequest {
                    at: Some(request.history_until),
                    dry_run: true,
                    wind: None,
                },
                request.clock_now,
            );
            (_, _, template) = check.into_parts();
            if let Err(e) = explored {
                return Err(AppError::Invalid(format!(
                    "budget {budget} ({:.1} kJ battery): exhaustive collection cannot be flown \
                     ({e}); raise the budget or leave exhaustive out of the strategies",
                    battery * budget / 1_000.0
                )));
            }
        }
    }
    // Every run's first recorded flight would otherwise rebuild the cell-summary cache from
    // the whole history; built once here, every copy starts with it.
    template.write(|tx| gleaner_app::shortcuts::prepare_cache(tx))?;
    let series = truth_series(truth, &modality.to_string());
    let class_series = match &class_name {
        Some(c) if *c != modality.to_string() => truth_series(truth, c),
        _ => series.clone(),
    };
    let last = *request.schedule.last().unwrap_or(&request.history_until);
    let all_events = match &request.events {
        Some(e) => e.clone(),
        None => rule_events(truth, &modality.to_string(), request.event_z),
    };
    let events: Vec<TruthEvent> = all_events
        .into_iter()
        .filter(|e| {
            let available = e.start.saturating_add(truth.period_s);
            available > request.history_until && available <= last
        })
        .collect();
    let shared = Shared {
        request,
        truth,
        history,
        modality,
        series,
        class_series,
        events,
        model,
        changes,
        estimator: request.estimator.resolve(dynamic.as_ref()),
        dynamic,
        step_s,
        template: Some(std::sync::Mutex::new(template)),
    };
    let keys = run_keys(request);
    progress.start(
        &format!("{}: missions", request.label),
        Some((keys.len() * request.schedule.len()) as u64),
    );
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(request.jobs)
        .build()
        .map_err(|e| AppError::Invalid(format!("cannot start {} threads: {e}", request.jobs)))?;
    // Runs that are the same computation ([`run_signature`]) run once: `same[k]` is the first
    // key with k's signature, whose results k takes.
    let same = same_runs(request, &keys)?;
    // Longest runs first (LPT): each worker takes the next run off one queue, so the last runs
    // to start are short ones and the workers finish together. Results keep the keys' order.
    let mut order: Vec<usize> = (0..keys.len()).filter(|&k| same[k] == k).collect();
    order.sort_by_key(|&k| std::cmp::Reverse(keys[k].strategy.expected_cost()));
    let next = std::sync::atomic::AtomicUsize::new(0);
    let slots: Vec<std::sync::Mutex<Option<Result<RunResult>>>> =
        keys.iter().map(|_| std::sync::Mutex::new(None)).collect();
    pool.scope(|scope| {
        for _ in 0..pool.current_num_threads() {
            scope.spawn(|_| {
                loop {
                    let n = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    let Some(&k) = order.get(n) else { break };
                    if progress.cancelled() {
                        if let Ok(mut slot) = slots[k].lock() {
                            *slot = Some(Err(AppError::Cancelled));
                        }
                        continue;
                    }
                    let result = run_one(&shared, keys[k].clone(), progress);
                    let copies = same.iter().enumerate().filter(|&(j, &r)| r == k && j != k);
                    progress.advance((copies.count() * request.schedule.len()) as u64);
                    if let Ok(mut slot) = slots[k].lock() {
                        *slot = Some(result);
                    }
                }
            });
        }
    });
    progress.finish();
    let mut done: Vec<Option<Result<RunResult>>> = slots
        .into_iter()
        .map(|slot| slot.into_inner().ok().flatten())
        .collect();
    // Last key first: a copy comes after the run it copies, which is taken after it.
    let mut runs = Vec::with_capacity(keys.len());
    for (k, key) in keys.iter().enumerate().rev() {
        let result = if same[k] == k {
            done[k].take()
        } else {
            match &done[same[k]] {
                Some(Ok(run)) => Some(Ok(RunResult {
                    key: key.clone(),
                    ..run.clone()
                })),
                Some(Err(e)) => Some(Err(AppError::Invalid(format!(
                    "run {} seed {} budget {}: {e}",
                    keys[same[k]].strategy.name(),
                    keys[same[k]].seed,
                    keys[same[k]].budget
                )))),
                None => None,
            }
        };
        runs.push(
            result.unwrap_or_else(|| Err(AppError::Invalid("a campaign run panicked".into()))),
        );
    }
    let runs = runs.into_iter().rev().collect::<Result<Vec<_>>>()?;
    Ok(CampaignResult {
        label: request.label.clone(),
        modality: shared.modality.to_string(),
        period_s: truth.period_s,
        covariance: shared.model.covariance,
        changes: Some(shared.changes),
        estimator: Some(shared.estimator),
        events: shared.events,
        runs,
    })
}

/// For every key, the first key with the same [`run_signature`] (itself when none before).
fn same_runs(request: &CampaignRequest, keys: &[RunKey]) -> Result<Vec<usize>> {
    let mut first: HashMap<String, usize> = HashMap::new();
    keys.iter()
        .enumerate()
        .map(|(k, key)| Ok(*first.entry(run_signature(request, key)?).or_insert(k)))
        .collect()
}

/// The predicted (argmax) and true class of every cell, as a share right.
fn classifier_accuracy(
    scoring: &gleaner_app::Scoring,
    cells: &[(CellIndex, Vec<SensorId>)],
    class_series: &BTreeMap<SensorId, (Vec<UnixSeconds>, Vec<f64>)>,
    at: UnixSeconds,
) -> Option<f64> {
    let cond = scoring.condition.as_ref()?;
    if cond.thresholds.is_empty() {
        return None;
    }
    let k = &scoring.knowledge;
    let mut right = 0usize;
    let mut total = 0usize;
    for (c, cell) in k.field.cells().iter().enumerate() {
        let Some((_, sensors)) = cells.iter().find(|(i, _)| *i == cell.index) else {
            continue;
        };
        let values: Vec<f64> = sensors
            .iter()
            .filter_map(|s| value_at(class_series, s, at))
            .collect();
        if values.is_empty() {
            continue;
        }
        let truth = values.iter().sum::<f64>() / values.len() as f64;
        let true_class = gleaner_utility::class_of(truth, &cond.thresholds);
        let predicted = cond.probabilities[c]
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))
            .map(|p| p.0)?;
        total += 1;
        right += usize::from(predicted == true_class);
    }
    (total > 0).then(|| right as f64 / total as f64)
}

/// Every run of `request`: strategies, then seeds, then budgets, in the request's order.
fn run_keys(request: &CampaignRequest) -> Vec<RunKey> {
    let mut keys = Vec::new();
    for &strategy in &request.strategies {
        for &seed in &request.seeds {
            for &budget in &request.budgets {
                keys.push(RunKey {
                    strategy,
                    seed,
                    budget,
                });
            }
        }
    }
    keys
}

fn run_one(
    shared: &Shared<'_>,
    key: RunKey,
    progress: &(dyn Progress + Sync),
) -> Result<RunResult> {
    let request = shared.request;
    let truth = shared.truth;
    let period = truth.period_s;
    let settings = run_settings(request, &key)?;
    let mut project = new_run_project(shared, settings)?;
    let cells: Vec<(CellIndex, Vec<SensorId>)> = project
        .store()
        .cells()?
        .into_iter()
        .map(|c| (c.index, c.sensors))
        .collect();
    let (sensors, field) = project.field()?;
    let sensor_of_cell: HashMap<CellIndex, &Vec<SensorId>> =
        cells.iter().map(|(i, s)| (*i, s)).collect();
    let centres: Vec<[f64; 2]> = field
        .cells()
        .iter()
        .map(|c| [c.centre.e, c.centre.n])
        .collect();
    let cell_sensor_ids: Vec<Vec<SensorId>> = field
        .cells()
        .iter()
        .map(|c| c.sensors.iter().map(|&s| sensors[s].id.clone()).collect())
        .collect();
    let lookback = (5.0 * shared.model.covariance.time_scale_s).clamp(
        7.0 * 86_400.0_f64.max(shared.step_s as f64),
        730.0 * 86_400.0,
    ) as i64;
    // When each sensor's data was last brought home: its latest history reading's
    // availability, then its collections.
    let mut last: HashMap<SensorId, UnixSeconds> = HashMap::new();
    for r in &shared.history.rows {
        if let Some(s) = shared.history.sensors.get(r.sensor as usize) {
            let t = r.t.saturating_add(period);
            let e = last.entry(s.clone()).or_insert(t);
            *e = (*e).max(t);
        }
    }
    let mut caught: Vec<Option<UnixSeconds>> = vec![None; shared.events.len()];
    let mut exploration_memo = ExplorationMemo::default();
    let mut estimate_reads = EstimateReads::default();
    let mut missions = Vec::with_capacity(request.schedule.len());
    let mut visits = Vec::new();
    for (index, &t) in request.schedule.iter().enumerate() {
        if progress.cancelled() {
            return Err(AppError::Cancelled);
        }
        let cell_age = |c: usize| -> Option<f64> {
            cell_sensor_ids[c]
                .iter()
                .filter_map(|s| last.get(s))
                .min()
                .map(|&l| (t - l).max(0) as f64)
        };
        // What the planner believed before the flight (for the classifier's accuracy).
        let scoring = compute(
            &project,
            &ScoreRequest {
                at: Some(t),
                dry_run: true,
                ..ScoreRequest::default()
            },
        )?;
        // Reconstruction of every sensor's value stamped T − period from what was known
        // before the flights. `reuse`: nothing was written since the last estimate (the
        // previous mission's, after its flights, which brought back only readings stamped at
        // or before its target).
        let target = t - period;
        let errors_now = |project: &Project<SqliteStore>,
                          reads: &mut EstimateReads,
                          reuse: bool|
         -> Result<(Errors, Vec<SensorEstimate>)> {
            let estimates = estimate_with(
                project,
                &shared.modality,
                (&shared.model, &shared.changes, shared.dynamic.as_ref()),
                (target, lookback),
                (request.neighbours, shared.estimator),
                (reads, reuse),
            )?;
            Ok((
                reconstruction_errors(&estimates, &shared.series, target),
                estimates,
            ))
        };
        let (before, before_estimates) = errors_now(&project, &mut estimate_reads, true)?;
        let given: Option<Vec<f64>> = match key.strategy.selection() {
            Some(Strategy::RoundRobin) => {
                let ages: Vec<Option<f64>> = (0..centres.len()).map(cell_age).collect();
                let oldest = ages.iter().flatten().fold(0.0f64, |a, b| a.max(*b));
                Some(
                    ages.iter()
                        .map(|a| a.unwrap_or(oldest + 86_400.0) / 86_400.0 + 1e-3)
                        .collect(),
                )
            }
            Some(Strategy::Random) => Some(
                (0..centres.len())
                    .map(|c| {
                        let x = splitmix(key.seed ^ splitmix(index as u64 ^ ((c as u64) << 32)));
                        ((x >> 11) as f64 + 1.0) / (1u64 << 53) as f64
                    })
                    .collect(),
            ),
            Some(Strategy::Nearest) => Some(vec![1.0; centres.len()]),
            Some(Strategy::Expected) => Some(expected_scores(&before_estimates, &cell_sensor_ids)),
            Some(Strategy::Oracle) => Some(oracle_scores(
                &before_estimates,
                &cell_sensor_ids,
                &shared.series,
                target,
            )),
            Some(Strategy::Variance) => {
                let ages: Vec<Option<f64>> = (0..centres.len()).map(cell_age).collect();
                let weights: Vec<f64> = cell_sensor_ids.iter().map(|s| s.len() as f64).collect();
                Some(
                    variance_reduction(&shared.model.covariance, &centres, &ages, &weights)
                        .map_err(|e| AppError::core("variance-reduction utility", e))?,
                )
            }
            _ => None,
        };
        let accuracy = classifier_accuracy(&scoring, &cells, &shared.class_series, t - period);
        // The day's forecast (planned for) and the wind the sorties meet.
        let day = request.flight.day(t)?;
        let mut flown = Vec::new();
        let (mut energy_j, mut budget_j) = (0.0, 0.0);
        // The pre-flight scoring, handed to the planner when it scores by the utility engine
        // (the same store, the same time: what `plan` would compute again) and taken back.
        let mut scoring = Some(scoring);
        if key.strategy.selection() == Some(Strategy::Exhaustive) {
            let plan = explore_with(
                &mut project,
                &ExploreRequest {
                    at: Some(t),
                    dry_run: false,
                    wind: request.flight.plan_wind(&day),
                },
                request.clock_now,
                &mut exploration_memo,
            )?;
            for (id, m) in &plan.sorties {
                energy_j += m.energy.total_j;
                budget_j = m.energy.budget_j;
                flown.extend(*id);
            }
        } else {
            let scored = if given.is_none() {
                scoring.take()
            } else {
                None
            };
            let mut planned = plan_scored(
                &mut project,
                &PlanRequest {
                    at: Some(t),
                    cell_scores: given,
                    max_iterations: Some(request.planner_iterations),
                    time_limit_s: Some(3_600.0),
                    sorties: Some(request.sorties),
                    wind: match request.flight.wind {
                        crate::campaign_flight::WindSource::Still => None,
                        _ => Some(day.forecast),
                    },
                    objective: Some(match key.strategy.selection() {
                        Some(Strategy::Information) => Objective::Information,
                        Some(Strategy::Hybrid) => Objective::Hybrid,
                        _ => Objective::Score,
                    }),
                    ..PlanRequest::default()
                },
                None,
                (scored, shared.dynamic.as_ref()),
                false,
                request.clock_now,
            )?;
            if scoring.is_none() {
                scoring = planned.scoring.take();
            }
            energy_j = planned.mission.energy.total_j;
            budget_j = planned.mission.energy.budget_j;
            if !planned.mission.stops.is_empty() {
                flown.extend(planned.id);
            }
            for extra in &planned.extra_sorties {
                if !extra.mission.stops.is_empty() {
                    energy_j += extra.mission.energy.total_j;
                    flown.extend(extra.id);
                }
            }
        }
        let scoring = scoring.ok_or_else(|| {
            AppError::Invalid("the planner did not give back the mission's scoring".into())
        })?;
        let terms_of: HashMap<CellIndex, (usize, &gleaner_utility::CellTerms)> = scoring
            .knowledge
            .field
            .cells()
            .iter()
            .zip(&scoring.terms)
            .enumerate()
            .map(|(k, (c, terms))| (c.index, (k, terms)))
            .collect();
        let mut visited: HashSet<SensorId> = HashSet::new();
        let mut cells_visited = 0;
        let mut lost_readings = 0;
        let mut flight = FlightDay::new(day);
        for (sortie, id) in flown.iter().enumerate() {
            let (outcome, lost) = if request.flight.is_still() {
                // Flown exactly as planned.
                let e = gleaner_app::mission(&project, *id)?.mission.energy;
                flight.add((e.total_j, e.budget_j), 1.0, false, 0);
                fly_buffered(&mut project, truth, *id, t, request.clock_now)?
            } else {
                let factor = request.flight.battery_factor(t, sortie);
                let f = fly_in_wind(
                    &project,
                    *id,
                    request.flight.sortie(t, sortie, day.actual),
                    factor,
                    request.planner_iterations,
                )?;
                flight.add((f.energy_j, f.usable_j), factor, f.replanned, f.dropped);
                fly_cells(
                    &mut project,
                    truth,
                    *id,
                    Some(&f.cells),
                    t,
                    request.clock_now,
                )?
            };
            flight.readings += outcome.readings_inserted;
            lost_readings += lost;
            cells_visited += outcome.cells.len();
            for c in &outcome.cells {
                if let Some(&(k, terms)) = terms_of.get(c) {
                    visits.push(Visit {
                        index,
                        cell: *c,
                        age_days: cell_age(k).unwrap_or(f64::NAN) / 86_400.0,
                        f: terms.f,
                        a: terms.a,
                        u: terms.u,
                        r: terms.r,
                        s: terms.s,
                    });
                }
                if let Some(s) = sensor_of_cell.get(c) {
                    visited.extend(s.iter().cloned());
                }
            }
        }
        drop(terms_of);
        drop(scoring);
        // Events first caught now: a visited sensor brought back one of the event's readings
        // (still in its buffer).
        let mut events_caught = 0;
        let keep_from = truth
            .buffer_readings
            .map(|n| t - period - (n as i64 - 1) * shared.step_s);
        for (e, event) in shared.events.iter().enumerate() {
            if caught[e].is_some() || event.start.saturating_add(period) > t {
                continue;
            }
            let in_buffer = keep_from.is_none_or(|from| event.end - shared.step_s >= from);
            if in_buffer && event.sensors.iter().any(|s| visited.contains(s)) {
                caught[e] = Some(t);
                events_caught += 1;
            }
        }
        // Reconstruction of every sensor's value stamped T − period, after the flights.
        let (after, _) = errors_now(&project, &mut estimate_reads, false)?;
        for s in &visited {
            last.insert(s.clone(), t);
        }
        // Staleness over every sensor (one never brought home counts from the campaign start).
        let ages: Vec<f64> = sensors
            .iter()
            .map(|s| (t - last.get(&s.id).copied().unwrap_or(request.history_until)).max(0) as f64)
            .collect();
        let staleness_mean_s = ages.iter().sum::<f64>() / (ages.len() as f64).max(1.0);
        let staleness_max_s = ages.iter().fold(0.0f64, |a, b| a.max(*b));
        missions.push(MissionMetrics {
            index,
            t,
            sorties: flown.len(),
            cells: cells_visited,
            energy_j,
            budget_j,
            rmse_carried: after.rmse_carried,
            mae_carried: after.mae_carried,
            rmse_kriged: after.rmse_kriged,
            mae_kriged: after.mae_kriged,
            mean_variance: after.mean_variance,
            coverage90: after.coverage90,
            rmse_carried_before: before.rmse_carried,
            rmse_kriged_before: before.rmse_kriged,
            evaluated: after.evaluated,
            staleness_mean_s,
            staleness_max_s,
            classifier_accuracy: accuracy,
            lost_readings,
            events_caught,
            flight: Some(flight),
        });
        progress.advance(1);
    }
    Ok(RunResult {
        key,
        missions,
        caught,
        visits,
    })
}

/// [`Strategy::Oracle`]'s scores in field order: per cell, the squared error of its sensors'
/// model-based estimates against the true values stamped `target`, ×10⁶ (the unit squared:
/// (m³/m³)² ×10⁶ for soil water), plus 10⁻⁹ so that a cell with nothing to correct still
/// counts as a place (the planner's scores are positive).
fn oracle_scores(
    estimates: &[SensorEstimate],
    cell_sensor_ids: &[Vec<SensorId>],
    series: &BTreeMap<SensorId, (Vec<UnixSeconds>, Vec<f64>)>,
    target: UnixSeconds,
) -> Vec<f64> {
    let error: HashMap<&SensorId, f64> = estimates
        .iter()
        .filter_map(|e| {
            value_at(series, &e.sensor, target).map(|v| (&e.sensor, (e.kriged - v).powi(2)))
        })
        .collect();
    cell_sensor_ids
        .iter()
        .map(|ids| 1e-9 + 1e6 * ids.iter().filter_map(|s| error.get(s)).sum::<f64>())
        .collect()
}

/// Each cell's predicted squared error before the flight: the sum of its sensors' estimator
/// variances ((unit)² ×10⁶, + 1e-9 so every cell stays eligible).
fn expected_scores(estimates: &[SensorEstimate], cell_sensor_ids: &[Vec<SensorId>]) -> Vec<f64> {
    let variance: HashMap<&SensorId, f64> = estimates
        .iter()
        .filter(|e| e.variance.is_finite())
        .map(|e| (&e.sensor, e.variance.max(0.0)))
        .collect();
    cell_sensor_ids
        .iter()
        .map(|ids| 1e-9 + 1e6 * ids.iter().filter_map(|s| variance.get(s)).sum::<f64>())
        .collect()
}

/// The errors of one reconstruction against the truth (see [`MissionMetrics`]).
struct Errors {
    rmse_carried: f64,
    mae_carried: f64,
    rmse_kriged: f64,
    mae_kriged: f64,
    mean_variance: f64,
    coverage90: Option<f64>,
    evaluated: usize,
}

/// Errors of `estimates` against the true values stamped `target` (sensors without one are
/// left out; 0 when none has one).
fn reconstruction_errors(
    estimates: &[SensorEstimate],
    series: &BTreeMap<SensorId, (Vec<UnixSeconds>, Vec<f64>)>,
    target: UnixSeconds,
) -> Errors {
    let (mut se_c, mut ae_c, mut se_k, mut ae_k, mut var, mut n) = (0.0, 0.0, 0.0, 0.0, 0.0, 0);
    let (mut covered, mut estimated) = (0usize, 0usize);
    for e in estimates {
        let Some(v) = value_at(series, &e.sensor, target) else {
            continue;
        };
        if e.last_time != Some(target) {
            estimated += 1;
            covered += usize::from((e.kriged - v).abs() <= e.half90);
        }
        se_c += (e.carried - v).powi(2);
        ae_c += (e.carried - v).abs();
        se_k += (e.kriged - v).powi(2);
        ae_k += (e.kriged - v).abs();
        var += e.variance;
        n += 1;
    }
    let nf = (n as f64).max(1.0);
    Errors {
        rmse_carried: (se_c / nf).sqrt(),
        mae_carried: ae_c / nf,
        rmse_kriged: (se_k / nf).sqrt(),
        mae_kriged: ae_k / nf,
        mean_variance: var / nf,
        coverage90: (estimated > 0).then(|| covered as f64 / estimated as f64),
        evaluated: n,
    }
}

/// A schedule: every `step_s` seconds from `start` to `end` inclusive.
pub fn every(start: UnixSeconds, end: UnixSeconds, step_s: i64) -> Result<Vec<UnixSeconds>> {
    if step_s <= 0 {
        return Err(AppError::Invalid(format!(
            "mission interval {step_s} s must be positive"
        )));
    }
    if end < start {
        return Err(AppError::Invalid(
            "the schedule ends before it starts".into(),
        ));
    }
    let n = (end - start) / step_s + 1;
    if n > 1_000_000 {
        return Err(AppError::Invalid(format!(
            "{n} missions: at most 1,000,000"
        )));
    }
    Ok((0..n).map(|k| start + k * step_s).collect())
}

/// A mean with its 95% confidence interval.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Interval {
    /// The mean.
    pub mean: f64,
    /// Lower end of the 95% interval.
    pub low: f64,
    /// Upper end of the 95% interval.
    pub high: f64,
    /// Number of independent values the interval rests on.
    pub n: usize,
}

/// Two-sided 97.5% quantile of Student's t with `df` degrees of freedom.
fn t975(df: usize) -> f64 {
    const T: [f64; 30] = [
        12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228, 2.201, 2.179, 2.160,
        2.145, 2.131, 2.120, 2.110, 2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064, 2.060, 2.056,
        2.052, 2.048, 2.045, 2.042,
    ];
    match df {
        0 => f64::NAN,
        1..=30 => T[df - 1],
        31..=60 => 2.000 + (2.042 - 2.000) * (60 - df) as f64 / 30.0,
        61..=120 => 1.980 + (2.000 - 1.980) * (120 - df) as f64 / 60.0,
        _ => 1.960,
    }
}

/// The mean of `values` (non-finite ones left out) with Student's t 95% interval (the
/// interval is the mean itself for a single value).
pub fn interval(values: &[f64]) -> Interval {
    let v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    let n = v.len();
    if n == 0 {
        return Interval {
            mean: f64::NAN,
            low: f64::NAN,
            high: f64::NAN,
            n,
        };
    }
    let mean = v.iter().sum::<f64>() / n as f64;
    if n == 1 {
        return Interval {
            mean,
            low: mean,
            high: mean,
            n,
        };
    }
    let sd = (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt();
    let h = t975(n - 1) * sd / (n as f64).sqrt();
    Interval {
        mean,
        low: mean - h,
        high: mean + h,
        n,
    }
}

/// Days of mission time per block: consecutive missions are correlated (the same weather,
/// the same stale sensors), so intervals rest on the means of blocks of this many days of
/// missions, not on single missions.
pub const BLOCK_DAYS: i64 = 7;

/// Fewest blocks an interval rests on: with fewer, Student's t over so few block means is
/// too wide to mean anything (or, worse, too narrow by chance), and no interval is given.
pub const MIN_BLOCKS: usize = 10;

/// The values an interval rests on: per block of [`BLOCK_DAYS`] days of mission time (from the
/// first mission of any run), the mean over runs of each run's mean over its missions in
/// that block. Runs are averaged within a block rather than counted as separate values, so
/// replicates of the same dataset (which share its weather) do not pass for independent
/// evidence; blocks are the units, taken as approximately independent at a week apart.
pub fn block_means(per_run: &[Vec<(UnixSeconds, f64)>]) -> Vec<f64> {
    let Some(t0) = per_run.iter().flatten().map(|p| p.0).min() else {
        return Vec::new();
    };
    let block_s = BLOCK_DAYS * 86_400;
    let mut blocks: BTreeMap<i64, (f64, usize)> = BTreeMap::new();
    for run in per_run {
        let mut own: BTreeMap<i64, (f64, usize)> = BTreeMap::new();
        for &(t, v) in run.iter().filter(|p| p.1.is_finite()) {
            let e = own.entry((t - t0).div_euclid(block_s)).or_insert((0.0, 0));
            e.0 += v;
            e.1 += 1;
        }
        for (b, (sum, n)) in own {
            let e = blocks.entry(b).or_insert((0.0, 0));
            e.0 += sum / n as f64;
            e.1 += 1;
        }
    }
    blocks.values().map(|(sum, n)| sum / *n as f64).collect()
}

/// The mean over blocks with Student's t 95% interval over the [`block_means`], given only
/// when there are at least [`MIN_BLOCKS`] blocks (else `low` and `high` are NaN).
pub fn block_interval(per_run: &[Vec<(UnixSeconds, f64)>]) -> Interval {
    let mut i = interval(&block_means(per_run));
    if i.n < MIN_BLOCKS {
        i.low = f64::NAN;
        i.high = f64::NAN;
    }
    i
}

/// A per-mission metric, by name: `rmse_kriged`, `rmse_carried`, `rmse_kriged_before`,
/// `rmse_carried_before`, `mae_kriged`,
/// `mae_carried`, `staleness_mean_days`, `staleness_max_days`, `energy_kj`, `utilisation`,
/// `cells`, `classifier_accuracy`, `lost_readings`, `mean_sd` (square root of the mean
/// kriging variance), `coverage90` (share of estimated sensors inside their 90% interval).
pub fn metric(m: &MissionMetrics, name: &str) -> f64 {
    match name {
        "rmse_kriged" => m.rmse_kriged,
        "rmse_carried" => m.rmse_carried,
        "rmse_kriged_before" => m.rmse_kriged_before,
        "rmse_carried_before" => m.rmse_carried_before,
        "mae_kriged" => m.mae_kriged,
        "mae_carried" => m.mae_carried,
        "staleness_mean_days" => m.staleness_mean_s / 86_400.0,
        "staleness_max_days" => m.staleness_max_s / 86_400.0,
        "energy_kj" => m.energy_j / 1_000.0,
        "utilisation" => {
            if m.budget_j > 0.0 && m.sorties > 0 {
                m.energy_j / (m.budget_j * m.sorties as f64)
            } else {
                0.0
            }
        }
        "cells" => m.cells as f64,
        "classifier_accuracy" => m.classifier_accuracy.unwrap_or(f64::NAN),
        "lost_readings" => m.lost_readings as f64,
        "mean_sd" => m.mean_variance.sqrt(),
        "coverage90" => m.coverage90.unwrap_or(f64::NAN),
        _ => f64::NAN,
    }
}

/// The per-mission metrics [`metric`] knows, in report order.
pub const METRICS: [&str; 15] = [
    "rmse_kriged",
    "rmse_carried",
    "rmse_kriged_before",
    "rmse_carried_before",
    "mae_kriged",
    "mae_carried",
    "mean_sd",
    "coverage90",
    "staleness_mean_days",
    "staleness_max_days",
    "energy_kj",
    "utilisation",
    "cells",
    "classifier_accuracy",
    "lost_readings",
];

/// One strategy at one budget, over every run (and dataset) given.
#[derive(Debug, Clone)]
pub struct Summary {
    /// Strategy.
    pub strategy: Strategy,
    /// Budget fraction.
    pub budget: f64,
    /// Runs pooled.
    pub runs: usize,
    /// Per [`METRICS`] name: the mean over blocks of missions with its 95% interval
    /// ([`block_interval`]).
    pub metrics: Vec<(&'static str, Interval)>,
    /// Events caught / events, pooled.
    pub events_caught: (usize, usize),
    /// Delay from an event's first available reading to its catch, days (caught events).
    pub delay_days: Interval,
    /// Kriging RMSE minus the reference strategy's, paired by mission (same dataset, seed,
    /// budget), with its 95% interval over blocks ([`block_interval`]); `None` for the
    /// reference itself or without a pair.
    pub rmse_vs_reference: Option<Interval>,
    /// Catch delay minus the reference strategy's, days, over the events both caught (same
    /// dataset, seed, budget), with Student's t 95% interval over those events; `None` for
    /// the reference itself or without a pair.
    pub delay_vs_reference: Option<Interval>,
}

/// What one campaign found, per strategy and budget: what `POST /api/v1/simulate` answers.
#[derive(Debug, Clone)]
pub struct CampaignSummary {
    /// The dataset's name.
    pub label: String,
    /// The evaluated modality.
    pub modality: String,
    /// The logging period, s.
    pub period_s: i64,
    /// End of the history, s.
    pub history_until: UnixSeconds,
    /// Mission times, s.
    pub schedule: Vec<UnixSeconds>,
    /// Events that became available during the campaign.
    pub events: usize,
    /// The strategy the differences are taken against (gleaner when it ran, else the
    /// first).
    pub reference: Strategy,
    /// Per (strategy, budget), in the request's order.
    pub summaries: Vec<Summary>,
}

impl CampaignRequest {
    /// Missions the campaign flies in all: missions × strategies × seeds × budgets.
    pub fn mission_runs(&self) -> usize {
        self.schedule
            .len()
            .saturating_mul(self.strategies.len())
            .saturating_mul(self.seeds.len())
            .saturating_mul(self.budgets.len())
    }
}

/// [`summarise`] of one campaign, against gleaner when it ran.
pub fn campaign_summary(request: &CampaignRequest, result: &CampaignResult) -> CampaignSummary {
    let reference = if request.strategies.contains(&Strategy::Gleaner) {
        Strategy::Gleaner
    } else {
        request
            .strategies
            .first()
            .copied()
            .unwrap_or(Strategy::Gleaner)
    };
    CampaignSummary {
        label: result.label.clone(),
        modality: result.modality.clone(),
        period_s: result.period_s,
        history_until: request.history_until,
        schedule: request.schedule.clone(),
        events: result.events.len(),
        reference,
        summaries: summarise(std::slice::from_ref(result), reference),
    }
}

/// Summaries of every (strategy, budget) over the given campaigns (e.g. one per synthetic
/// seed), with paired RMSE differences against `reference`.
pub fn summarise(results: &[CampaignResult], reference: Strategy) -> Vec<Summary> {
    let mut keys: Vec<(Strategy, u64)> = Vec::new();
    for r in results {
        for run in &r.runs {
            let k = (run.key.strategy, run.key.budget.to_bits());
            if !keys.contains(&k) {
                keys.push(k);
            }
        }
    }
    let mut out = Vec::new();
    for (strategy, budget_bits) in keys {
        let budget = f64::from_bits(budget_bits);
        let runs: Vec<(&CampaignResult, &RunResult)> = results
            .iter()
            .flat_map(|r| r.runs.iter().map(move |run| (r, run)))
            .filter(|(_, run)| run.key.strategy == strategy && run.key.budget == budget)
            .collect();
        let metrics = METRICS
            .iter()
            .map(|&name| {
                let per_run: Vec<Vec<(UnixSeconds, f64)>> = runs
                    .iter()
                    .map(|(_, run)| {
                        run.missions
                            .iter()
                            .map(|m| (m.t, metric(m, name)))
                            .collect()
                    })
                    .collect();
                (name, block_interval(&per_run))
            })
            .collect();
        let mut caught = 0;
        let mut total = 0;
        let mut delays = Vec::new();
        for (r, run) in &runs {
            for (e, c) in r.events.iter().zip(&run.caught) {
                total += 1;
                if let Some(at) = c {
                    caught += 1;
                    delays.push((at - e.start - r.period_s) as f64 / 86_400.0);
                }
            }
        }
        let rmse_vs_reference = (strategy != reference)
            .then(|| {
                let per_run: Vec<Vec<(UnixSeconds, f64)>> = runs
                    .iter()
                    .filter_map(|(r, run)| {
                        let other = r.runs.iter().find(|o| {
                            o.key.strategy == reference
                                && o.key.seed == run.key.seed
                                && o.key.budget == run.key.budget
                        })?;
                        Some(
                            run.missions
                                .iter()
                                .zip(&other.missions)
                                .map(|(a, b)| (a.t, a.rmse_kriged - b.rmse_kriged))
                                .collect(),
                        )
                    })
                    .collect();
                (!per_run.is_empty()).then(|| block_interval(&per_run))
            })
            .flatten();
        let delay_vs_reference = (strategy != reference)
            .then(|| {
                let mut diffs = Vec::new();
                for (r, run) in &runs {
                    let Some(other) = r.runs.iter().find(|o| {
                        o.key.strategy == reference
                            && o.key.seed == run.key.seed
                            && o.key.budget == run.key.budget
                    }) else {
                        continue;
                    };
                    for (a, b) in run.caught.iter().zip(&other.caught) {
                        if let (Some(a), Some(b)) = (a, b) {
                            diffs.push((a - b) as f64 / 86_400.0);
                        }
                    }
                }
                (!diffs.is_empty()).then(|| interval(&diffs))
            })
            .flatten();
        out.push(Summary {
            strategy,
            budget,
            runs: runs.len(),
            metrics,
            events_caught: (caught, total),
            delay_days: interval(&delays),
            rmse_vs_reference,
            delay_vs_reference,
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const DAY: i64 = 86_400;

    #[test]
    fn oracle_scores_are_the_cells_squared_errors() {
        let id = |s: &str| SensorId::new(s).unwrap();
        let est = |s: &str, kriged: f64| SensorEstimate {
            sensor: id(s),
            position: gleaner_field::LatLon::new(0.0, 0.0).unwrap(),
            last_time: Some(0),
            carried: 0.0,
            kriged,
            variance: 1.0,
            half90: gleaner_app::Z90,
        };
        let estimates = [est("a", 0.10), est("b", 0.20), est("c", 0.30)];
        let mut series = BTreeMap::new();
        series.insert(id("a"), (vec![0, DAY], vec![0.0, 0.13]));
        series.insert(id("b"), (vec![0, DAY], vec![0.0, 0.20]));
        // c has no true value at the target: it adds nothing.
        series.insert(id("c"), (vec![0], vec![0.5]));
        let cells = vec![vec![id("a"), id("b")], vec![id("c")], vec![]];
        let s = oracle_scores(&estimates, &cells, &series, DAY);
        assert!(
            (s[0] - (1e-9 + 1e6 * 0.03f64.powi(2))).abs() < 1e-9,
            "{s:?}"
        );
        assert_eq!(s[1], 1e-9);
        assert_eq!(s[2], 1e-9);
        assert!(Strategy::Oracle.is_yardstick() && !Strategy::ALL.contains(&Strategy::Oracle));
        assert_eq!(Strategy::parse("oracle").unwrap(), Strategy::Oracle);
    }

    #[test]
    fn blocks_are_seven_days_of_missions_averaged_over_runs() {
        // Daily missions over 3 weeks: 3 blocks; two runs averaged within each block.
        let a: Vec<(UnixSeconds, f64)> = (0..21).map(|d| (d * DAY, (d / 7) as f64)).collect();
        let b: Vec<(UnixSeconds, f64)> = (0..21).map(|d| (d * DAY, 10.0)).collect();
        assert_eq!(block_means(std::slice::from_ref(&a)), vec![0.0, 1.0, 2.0]);
        assert_eq!(block_means(&[a, b]), vec![5.0, 5.5, 6.0]);
        // Weekly missions: one per block; non-finite values left out.
        let w: Vec<(UnixSeconds, f64)> = (0..4)
            .map(|k| (k * 7 * DAY, if k == 2 { f64::NAN } else { k as f64 }))
            .collect();
        assert_eq!(block_means(&[w]), vec![0.0, 1.0, 3.0]);
        assert!(block_means(&[]).is_empty());
    }

    #[test]
    fn no_interval_on_fewer_than_ten_blocks() {
        let short: Vec<(UnixSeconds, f64)> = (0..63).map(|d| (d * DAY, d as f64)).collect();
        let i = block_interval(&[short]);
        assert_eq!(i.n, 9);
        assert!(i.mean.is_finite() && i.low.is_nan() && i.high.is_nan());
        let long: Vec<(UnixSeconds, f64)> = (0..70).map(|d| (d * DAY, (d % 3) as f64)).collect();
        let i = block_interval(&[long]);
        assert_eq!(i.n, 10);
        assert!(i.low <= i.mean && i.mean <= i.high, "{i:?}");
    }

    #[test]
    fn paper_and_gleaner_strategies_score_their_own_way() {
        let mut base = gleaner_app::settings::Settings::parse(
            "[project]\nname = \"p\"\ndatabase = \"g.db\"\n[field]\nbase_lat = 38.7\n\
             base_lon = -117.1\ncell_size_m = 40.0\n[sensors]\nfile = \"s.csv\"\n",
        )
        .unwrap();
        base.utility.alpha = 3.0;
        base.utility.score_form = "gated".into();
        let paper = Strategy::Paper.settings(&base).utility;
        assert_eq!(paper, base.utility.paper());
        assert_eq!((paper.alpha, paper.score_form.as_str()), (1.0, "additive"));
        assert_eq!(Strategy::Paper.planner(), Planner::Greedy);
        let gleaner = Strategy::Gleaner.settings(&base).utility;
        assert_eq!(gleaner, base.utility.gleaner());
        assert_eq!(gleaner.alpha, 3.0);
        assert_eq!(Strategy::Gleaner.planner(), Planner::Default);
        let ablation = Strategy::Without(Term::Anomaly).settings(&base).utility;
        assert_eq!(
            (ablation.beta, ablation.score_form.as_str()),
            (0.0, "gated")
        );
        let fresh = Strategy::Freshness.settings(&base).utility;
        assert_eq!((fresh.beta, fresh.variance_weight), (0.0, 0.0));
    }

    /// Only runs that are the same computation share one: gleaner's γ = δ = 0 makes its
    /// U and R ablations gleaner itself; every other strategy, seed and budget runs alone.
    #[test]
    fn only_identical_runs_share_a_run() {
        let settings = gleaner_app::settings::Settings::parse(
            "[project]\nname = \"p\"\ndatabase = \"g.db\"\n[field]\nbase_lat = 38.7\n\
             base_lon = -117.1\ncell_size_m = 40.0\n[sensors]\nfile = \"s.csv\"\n",
        )
        .unwrap();
        let mut request = CampaignRequest {
            label: "t".into(),
            init: gleaner_app::InitRequest::default(),
            sensors: None,
            settings,
            history_until: 0,
            history_from: None,
            schedule: vec![86_400],
            strategies: Strategy::ALL.to_vec(),
            seeds: vec![1, 2],
            budgets: vec![1.0, 0.5],
            modality: None,
            events: None,
            event_z: 3.0,
            planner_iterations: 100,
            sorties: 1,
            neighbours: 16,
            estimator: gleaner_app::Estimator::Changes,
            jobs: 1,
            clock_now: 0,
            flight: FlightConditions::default(),
        };
        let all = run_keys(&request);
        let same = same_runs(&request, &all).unwrap();
        for (k, key) in all.iter().enumerate() {
            let first = &all[same[k]];
            assert!(same[k] <= k);
            assert_eq!((first.seed, first.budget), (key.seed, key.budget));
            let expected = match key.strategy {
                Strategy::Without(Term::Uncertainty) | Strategy::Without(Term::Redundancy) => {
                    Strategy::Gleaner
                }
                s => s,
            };
            assert_eq!(first.strategy, expected, "{key:?}");
        }
        // With γ and δ set in the project, gleaner's method zeroes them itself: still one
        // run (keys 44..48 are no-uncertainty's, 0..4 gleaner's); the gated strategy keeps
        // the project's γ and δ, so a changed γ is seen in its signature.
        let gated_before = run_signature(&request, &all[52]).unwrap();
        request.settings.utility.gamma = 0.5;
        request.settings.utility.delta = 0.5;
        assert_eq!(same_runs(&request, &all).unwrap(), same);
        assert_eq!(
            (all[44].strategy, same[44]),
            (Strategy::Without(Term::Uncertainty), 0)
        );
        assert_eq!(all[52].strategy, Strategy::Gated);
        assert_ne!(run_signature(&request, &all[52]).unwrap(), gated_before);
        // Given scores never share a run with the utility engine's, even with equal settings.
        assert_ne!(
            run_signature(&request, &all[0]).unwrap(),
            run_signature(
                &request,
                &RunKey {
                    strategy: Strategy::Random,
                    ..all[0].clone()
                }
            )
            .unwrap()
        );
    }
}
