//! One run of a campaign: its missions, each scored, planned, flown, recorded and judged
//! against the truth.

use std::collections::{BTreeMap, HashMap, HashSet};
use std::path::PathBuf;

use gleaner_field::{CellIndex, Modality, Sensor, SensorId, UnixSeconds};
use gleaner_ingest::{IngestReport, Readings};
use gleaner_kriging::{FieldModel, IncrementModel, variance_reduction};
use gleaner_store::{SqliteStore, StoreRead};

use gleaner_app::ExploreRequest;
use gleaner_app::settings::Settings;
use gleaner_app::shortcuts::{
    EstimateReads, ExplorationMemo, Parsed, estimate_with, explore_with, ingest_parsed, plan_scored,
};
use gleaner_app::{AppError, Result};
use gleaner_app::{Format, IngestRequest};
use gleaner_app::{Objective, PlanRequest};
use gleaner_app::{Progress, Silent};
use gleaner_app::{Project, SensorEstimate};
use gleaner_app::{ScoreRequest, compute, score};
use gleaner_app::{init_store, init_store_with};

use super::strategy::Strategy;
use super::types::{CampaignRequest, MissionMetrics, RunKey, RunResult, TruthEvent, Visit};
use crate::campaign_flight::{DayWind, FlightDay, WindSource, fly_in_wind};
use crate::seed::splitmix;
use crate::simulate::{Truth, fly_buffered, fly_cells};

/// A run's settings: the strategy's ([`Strategy::settings`]) with the run's budget, planner
/// and seed.
pub(super) fn run_settings(request: &CampaignRequest, key: &RunKey) -> Result<Settings> {
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

/// What every run shares: the history, the truth's evaluation series, the cells' sensors.
pub(super) struct Shared<'a> {
    pub(super) request: &'a CampaignRequest,
    pub(super) truth: &'a Truth,
    pub(super) history: Readings,
    pub(super) modality: Modality,
    /// Truth series of the evaluated modality, per sensor id.
    pub(super) series: BTreeMap<SensorId, (Vec<UnixSeconds>, Vec<f64>)>,
    /// Truth series of the condition modality (may equal `series`).
    pub(super) class_series: BTreeMap<SensorId, (Vec<UnixSeconds>, Vec<f64>)>,
    pub(super) events: Vec<TruthEvent>,
    pub(super) model: FieldModel,
    /// The model of changes fitted on the history.
    pub(super) changes: IncrementModel,
    /// The dynamic field model fitted on the history (None when it cannot be fitted).
    pub(super) dynamic: Option<gleaner_kriging::DynamicModel>,
    /// The request's estimator, resolved against the models ([`gleaner_app::Estimator::resolve`]).
    pub(super) estimator: gleaner_app::Estimator,
    pub(super) step_s: i64,
    /// The store every run starts from (the history ingested, the utility state built),
    /// copied for each run.
    pub(super) template: Option<std::sync::Mutex<SqliteStore>>,
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
pub(super) fn new_run_project(
    shared: &Shared<'_>,
    settings: Settings,
) -> Result<Project<SqliteStore>> {
    let request = shared.request;
    if let Some(template) = &shared.template {
        let store = template
            .lock()
            .map_err(|_| AppError::Invalid("a campaign run panicked".into()))?
            .copy_in_memory()?;
        let mut project = Project::new(&request.init.dir, settings, store);
        score_history(&mut project, request.history_until)?;
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
    score_history(&mut project, request.history_until)?;
    Ok(project)
}

/// Scores the run's project at the end of its history, `until` (s): the scoring a run
/// starts from, which also leaves the persisted utility state for the missions' fast path.
fn score_history(project: &mut Project<SqliteStore>, until: UnixSeconds) -> Result<()> {
    score(
        project,
        &ScoreRequest {
            at: Some(until),
            ..ScoreRequest::default()
        },
    )?;
    Ok(())
}

pub(super) fn run_one(
    shared: &Shared<'_>,
    key: RunKey,
    progress: &(dyn Progress + Sync),
) -> Result<RunResult> {
    let request = shared.request;
    let truth = shared.truth;
    let period = truth.period_s;
    let settings = run_settings(request, &key)?;
    let mut project = new_run_project(shared, settings)?;
    let grid = RunGrid::of(&project)?;
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
        let ages: Vec<Option<f64>> = (0..grid.centres.len())
            .map(|c| grid.cell_age(c, &last, t))
            .collect();
        let given = selection_scores(
            shared,
            &key,
            &grid,
            (index, target, &ages),
            &before_estimates,
        )?;
        let accuracy = classifier_accuracy(&scoring, &grid.cells, &shared.class_series, t - period);
        // The day's forecast (planned for) and the wind the sorties meet.
        let day = request.flight.day(t)?;
        let planned = plan_day(
            &mut project,
            shared,
            &key,
            (t, &day),
            (given, scoring),
            &mut exploration_memo,
        )?;
        let day_flown = fly_day(
            &mut project,
            shared,
            &grid,
            (index, t, day),
            &planned,
            (&ages, &mut visits),
        )?;
        let events_caught = catch_events(shared, &mut caught, &day_flown.visited, t);
        // Reconstruction of every sensor's value stamped T − period, after the flights.
        let (after, _) = errors_now(&project, &mut estimate_reads, false)?;
        for s in &day_flown.visited {
            last.insert(s.clone(), t);
        }
        // Staleness over every sensor (one never brought home counts from the campaign start).
        let ages: Vec<f64> = grid
            .sensors
            .iter()
            .map(|s| (t - last.get(&s.id).copied().unwrap_or(request.history_until)).max(0) as f64)
            .collect();
        let staleness_mean_s = ages.iter().sum::<f64>() / (ages.len() as f64).max(1.0);
        let staleness_max_s = ages.iter().fold(0.0f64, |a, b| a.max(*b));
        missions.push(MissionMetrics {
            index,
            t,
            sorties: planned.flown.len(),
            cells: day_flown.cells_visited,
            energy_j: planned.energy_j,
            budget_j: planned.budget_j,
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
            lost_readings: day_flown.lost_readings,
            events_caught,
            flight: Some(day_flown.flight),
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

/// A run's grid as its project stores it: the cells with their sensors, in store order and
/// in field order.
struct RunGrid {
    /// Each stored cell with its sensors' ids.
    cells: Vec<(CellIndex, Vec<SensorId>)>,
    /// The project's sensors.
    sensors: Vec<Sensor>,
    /// Each cell's centre in field order, local metres [e, n].
    centres: Vec<[f64; 2]>,
    /// Each cell's sensors' ids in field order.
    cell_sensor_ids: Vec<Vec<SensorId>>,
    /// Each stored cell's sensors' ids.
    sensors_of_cell: HashMap<CellIndex, Vec<SensorId>>,
}

impl RunGrid {
    fn of(project: &Project<SqliteStore>) -> Result<Self> {
        let cells: Vec<(CellIndex, Vec<SensorId>)> = project
            .store()
            .cells()?
            .into_iter()
            .map(|c| (c.index, c.sensors))
            .collect();
        let (sensors, field) = project.field()?;
        let sensors_of_cell = cells.iter().map(|(i, s)| (*i, s.clone())).collect();
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
        Ok(Self {
            cells,
            sensors,
            centres,
            cell_sensor_ids,
            sensors_of_cell,
        })
    }

    /// Seconds at `t` since cell `c` (field order) was last brought home: its freshest
    /// sensor's; `None` when none of them ever was.
    fn cell_age(
        &self,
        c: usize,
        last: &HashMap<SensorId, UnixSeconds>,
        t: UnixSeconds,
    ) -> Option<f64> {
        self.cell_sensor_ids[c]
            .iter()
            .filter_map(|s| last.get(s))
            .min()
            .map(|&l| (t - l).max(0) as f64)
    }
}

/// The cell scores a selection strategy plans by (in field order), or `None` when it plans
/// by the utility engine. `ages`: each cell's age ([`RunGrid::cell_age`]).
fn selection_scores(
    shared: &Shared<'_>,
    key: &RunKey,
    grid: &RunGrid,
    (index, target, ages): (usize, UnixSeconds, &[Option<f64>]),
    before_estimates: &[SensorEstimate],
) -> Result<Option<Vec<f64>>> {
    let n = grid.centres.len();
    let cell_sensor_ids = &grid.cell_sensor_ids;
    Ok(match key.strategy.selection() {
        Some(Strategy::RoundRobin) => {
            let oldest = ages.iter().flatten().fold(0.0f64, |a, b| a.max(*b));
            Some(
                ages.iter()
                    .map(|a| a.unwrap_or(oldest + 86_400.0) / 86_400.0 + 1e-3)
                    .collect(),
            )
        }
        Some(Strategy::Random) => Some(
            (0..n)
                .map(|c| {
                    let x = splitmix(key.seed ^ splitmix(index as u64 ^ ((c as u64) << 32)));
                    ((x >> 11) as f64 + 1.0) / (1u64 << 53) as f64
                })
                .collect(),
        ),
        Some(Strategy::Nearest) => Some(vec![1.0; n]),
        Some(Strategy::Expected) => Some(expected_scores(before_estimates, cell_sensor_ids)),
        Some(Strategy::Oracle) => Some(oracle_scores(
            before_estimates,
            cell_sensor_ids,
            &shared.series,
            target,
        )),
        Some(Strategy::Variance) => {
            let weights: Vec<f64> = cell_sensor_ids.iter().map(|s| s.len() as f64).collect();
            Some(
                variance_reduction(&shared.model.covariance, &grid.centres, ages, &weights)
                    .map_err(|e| AppError::core("variance-reduction utility", e))?,
            )
        }
        _ => None,
    })
}

/// A mission day as planned and stored.
struct DayPlan {
    /// The stored sorties to fly, in order.
    flown: Vec<gleaner_app::MissionId>,
    /// Their planned energy, J.
    energy_j: f64,
    /// The usable budget of one sortie, J.
    budget_j: f64,
    /// The scoring the cells' terms come from (the pre-flight one, or the planner's own).
    scoring: gleaner_app::Scoring,
}

/// Plans (and stores) the day's sorties: exhaustive collection explores, every other
/// strategy plans by `given` scores or, without them, by the pre-flight `scoring`.
fn plan_day(
    project: &mut Project<SqliteStore>,
    shared: &Shared<'_>,
    key: &RunKey,
    (t, day): (UnixSeconds, &DayWind),
    (given, scoring): (Option<Vec<f64>>, gleaner_app::Scoring),
    exploration_memo: &mut ExplorationMemo,
) -> Result<DayPlan> {
    let request = shared.request;
    let mut flown = Vec::new();
    let (mut energy_j, mut budget_j) = (0.0, 0.0);
    // The pre-flight scoring, handed to the planner when it scores by the utility engine
    // (the same store, the same time: what `plan` would compute again) and taken back.
    let mut scoring = Some(scoring);
    if key.strategy.selection() == Some(Strategy::Exhaustive) {
        let plan = explore_with(
            project,
            &ExploreRequest {
                at: Some(t),
                dry_run: false,
                wind: request.flight.plan_wind(day),
            },
            request.clock_now,
            exploration_memo,
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
            project,
            &PlanRequest {
                at: Some(t),
                cell_scores: given,
                max_iterations: Some(request.planner_iterations),
                time_limit_s: Some(3_600.0),
                sorties: Some(request.sorties),
                wind: match request.flight.wind {
                    WindSource::Still => None,
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
    Ok(DayPlan {
        flown,
        energy_j,
        budget_j,
        scoring,
    })
}

/// What a mission day's flights brought back.
struct DayFlown {
    /// The sensors of the cells visited.
    visited: HashSet<SensorId>,
    /// Cells visited over the sorties.
    cells_visited: usize,
    /// Readings lost to full sensor buffers.
    lost_readings: u64,
    /// The day's flights (energy, batteries, re-plans, readings).
    flight: FlightDay,
}

/// Flies the day's sorties (as planned in still air, else in the day's wind, re-planning in
/// the air) and records them; each visited cell's terms at planning go into `visits`.
fn fly_day(
    project: &mut Project<SqliteStore>,
    shared: &Shared<'_>,
    grid: &RunGrid,
    (index, t, day): (usize, UnixSeconds, DayWind),
    planned: &DayPlan,
    (ages, visits): (&[Option<f64>], &mut Vec<Visit>),
) -> Result<DayFlown> {
    let request = shared.request;
    let truth = shared.truth;
    let scoring = &planned.scoring;
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
    for (sortie, id) in planned.flown.iter().enumerate() {
        let (outcome, lost) = if request.flight.is_still() {
            // Flown exactly as planned.
            let e = gleaner_app::mission(project, *id)?.mission.energy;
            flight.add((e.total_j, e.budget_j), 1.0, false, 0);
            fly_buffered(project, truth, *id, t, request.clock_now)?
        } else {
            let factor = request.flight.battery_factor(t, sortie);
            let f = fly_in_wind(
                project,
                *id,
                request.flight.sortie(t, sortie, day.actual),
                factor,
                request.planner_iterations,
            )?;
            flight.add((f.energy_j, f.usable_j), factor, f.replanned, f.dropped);
            fly_cells(project, truth, *id, Some(&f.cells), t, request.clock_now)?
        };
        flight.readings += outcome.readings_inserted;
        lost_readings += lost;
        cells_visited += outcome.cells.len();
        for c in &outcome.cells {
            if let Some(&(k, terms)) = terms_of.get(c) {
                visits.push(Visit {
                    index,
                    cell: *c,
                    age_days: ages[k].unwrap_or(f64::NAN) / 86_400.0,
                    f: terms.f,
                    a: terms.a,
                    u: terms.u,
                    r: terms.r,
                    s: terms.s,
                });
            }
            if let Some(s) = grid.sensors_of_cell.get(c) {
                visited.extend(s.iter().cloned());
            }
        }
    }
    Ok(DayFlown {
        visited,
        cells_visited,
        lost_readings,
        flight,
    })
}

/// Marks the events first caught at `t`: a visited sensor brought back one of the event's
/// readings (still in its buffer). Returns how many.
fn catch_events(
    shared: &Shared<'_>,
    caught: &mut [Option<UnixSeconds>],
    visited: &HashSet<SensorId>,
    t: UnixSeconds,
) -> usize {
    let period = shared.truth.period_s;
    let mut events_caught = 0;
    let keep_from = shared
        .truth
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
    events_caught
}

/// [`Strategy::Oracle`]'s scores in field order: per cell, the squared error of its sensors'
/// model-based estimates against the true values stamped `target`, ×10⁶ (the unit squared:
/// (m³/m³)² ×10⁶ for soil water), plus 10⁻⁹ so that a cell with nothing to correct still
/// counts as a place (the planner's scores are positive).
pub(super) fn oracle_scores(
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
