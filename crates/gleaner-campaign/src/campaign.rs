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

use std::collections::{BTreeMap, HashMap};

use gleaner_field::{Modality, Sensor, SensorId, UnixSeconds};
use gleaner_ingest::Readings;
use gleaner_kriging::{Covariance, FieldModel, IncrementModel};
use gleaner_store::{SqliteStore, Store, StoreRead};

use gleaner_app::settings::Settings;
use gleaner_app::shortcuts::{fit_models, target_modality};
use gleaner_app::{AppError, Result};
use gleaner_app::{ExploreRequest, explore};
use gleaner_app::{InitRequest, Progress, Project};

use crate::campaign_flight::FlightConditions;
use crate::simulate::Truth;

mod run;
mod strategy;
mod summary;
mod types;

#[cfg(test)]
use run::oracle_scores;
use run::{Shared, new_run_project, run_one, run_settings};
pub use strategy::{Strategy, Term};
pub use summary::{
    BLOCK_DAYS, CALM_DAY_MPS, CampaignSummary, FlightSummary, Interval, METRICS, MIN_BLOCKS,
    Summary, block_interval, block_means, campaign_summary, every, flight_summaries, interval,
    metric, summarise,
};
pub use types::{
    CampaignRequest, CampaignResult, MissionMetrics, RunKey, RunResult, TruthEvent, Visit,
};

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

/// Runs the campaign: every (strategy, seed, budget) in parallel over `jobs` threads, each
/// deterministic, so the results do not depend on the thread count.
pub fn run_campaign(
    request: &CampaignRequest,
    truth: &Truth,
    progress: &(dyn Progress + Sync),
) -> Result<CampaignResult> {
    check_request(request)?;
    let mut history = truth.available_by(request.history_until);
    if let Some(from) = request.history_from {
        history.rows.retain(|r| r.t >= from);
    }
    // The field model, fitted once on the history (the exploration history every run shares).
    let probe = probe_project(request, truth, &history)?;
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
    let (dir, probe_settings, template) = probe.into_parts();
    let mut template = check_exhaustive(request, &dir, &probe_settings, template)?;
    // Every run's first recorded flight would otherwise rebuild the cell-summary cache from
    // the whole history; built once here, every copy starts with it.
    template.write(|tx| gleaner_app::shortcuts::prepare_cache(tx))?;
    let series = truth_series(truth, &modality.to_string());
    let class_series = match &class_name {
        Some(c) if *c != modality.to_string() => truth_series(truth, c),
        _ => series.clone(),
    };
    let events = campaign_events(request, truth, &modality);
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
    let runs = run_all(&shared, progress)?;
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

/// Refuses a campaign that cannot run: no or unordered mission times, a first mission before
/// the history's end, a budget that is not a positive fraction, sorties outside
/// 1..=MAX_SORTIES, bad flight conditions, or wind with no-fly zones.
fn check_request(request: &CampaignRequest) -> Result<()> {
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
    Ok(())
}

/// The project every run's is a copy of: the history ingested with the request's settings
/// (placeholder models: nothing is estimated in it).
fn probe_project(
    request: &CampaignRequest,
    truth: &Truth,
    history: &Readings,
) -> Result<Project<SqliteStore>> {
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
    new_run_project(&shared0, request.settings.clone())
}

/// Exhaustive collection must reach every cell within one battery: refuses a budget that
/// cannot, now rather than when its run fails after the others have run for minutes.
/// Returns the template store (each check borrows it).
fn check_exhaustive(
    request: &CampaignRequest,
    dir: &std::path::Path,
    probe_settings: &Settings,
    mut template: SqliteStore,
) -> Result<SqliteStore> {
    if !request.strategies.contains(&Strategy::Exhaustive) {
        return Ok(template);
    }
    for &budget in &request.budgets {
        let mut settings = probe_settings.clone();
        let battery = settings.energy.to_core()?.battery.capacity_j;
        settings.energy.battery_j = Some(battery * budget);
        let mut check = Project::new(dir, settings, template);
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
    Ok(template)
}

/// The events the campaign can catch: the request's (else the rule's on the truth) that
/// become available after the history and by the last mission.
fn campaign_events(
    request: &CampaignRequest,
    truth: &Truth,
    modality: &Modality,
) -> Vec<TruthEvent> {
    let last = *request.schedule.last().unwrap_or(&request.history_until);
    let all_events = match &request.events {
        Some(e) => e.clone(),
        None => rule_events(truth, &modality.to_string(), request.event_z),
    };
    all_events
        .into_iter()
        .filter(|e| {
            let available = e.start.saturating_add(truth.period_s);
            available > request.history_until && available <= last
        })
        .collect()
}

/// Every run of the request on `jobs` threads, longest first, the same computation once;
/// the results in the keys' order.
fn run_all(shared: &Shared<'_>, progress: &(dyn Progress + Sync)) -> Result<Vec<RunResult>> {
    let request = shared.request;
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
                    let result = run_one(shared, keys[k].clone(), progress);
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
    let done: Vec<Option<Result<RunResult>>> = slots
        .into_iter()
        .map(|slot| slot.into_inner().ok().flatten())
        .collect();
    copy_same_runs(&keys, &same, done)
}

/// The runs in the keys' order, each copy ([`same_runs`]) taking the results of the run it
/// copies.
fn copy_same_runs(
    keys: &[RunKey],
    same: &[usize],
    mut done: Vec<Option<Result<RunResult>>>,
) -> Result<Vec<RunResult>> {
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
    runs.into_iter().rev().collect::<Result<Vec<_>>>()
}

/// For every key, the first key with the same [`run_signature`] (itself when none before).
fn same_runs(request: &CampaignRequest, keys: &[RunKey]) -> Result<Vec<usize>> {
    let mut first: HashMap<String, usize> = HashMap::new();
    keys.iter()
        .enumerate()
        .map(|(k, key)| Ok(*first.entry(run_signature(request, key)?).or_insert(k)))
        .collect()
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

#[cfg(test)]
mod tests {
    use super::*;
    use gleaner_app::SensorEstimate;
    use gleaner_mission::Planner;

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
