//! Reconstruction (docs/method.md §7): every sensor's current value of one modality estimated from what
//! is known — its last collected value carried forward, and a model-based estimate with its
//! variance: by default kriging of changes ([`Estimator::Changes`]: the last value plus the
//! change since, estimated from the neighbours' known changes over the same interval), or the
//! dynamic field model ([`Estimator::Dynamic`]: a learned covariance of levels between sensors
//! with AR(1) dynamics, a Kalman filter over the readings known), or space-time
//! kriging of levels from every sensor's latest known reading ([`Estimator::Levels`]).
//! [`reconstruct_series`] gives the dynamic model's estimates over a range of times.

use std::collections::HashMap;

use gleaner_field::{CellIndex, LatLon, Modality, SensorId, UnixSeconds};
use gleaner_kriging::{
    DynamicModel, FieldModel, FitOptions, IncrementFitOptions, IncrementModel, SensorSeries, fit,
    fit_increments,
};
use gleaner_store::{ReadingBatch, Store};

use crate::choices::Estimator;
use crate::dynamic::{self, dynamic_from_columns, dynamic_multiplier, dynamic_window_s};
use crate::error::{AppError, Result};
use crate::knowledge::sampling_step;
use crate::kriging_inputs::{Columns, KrigingInputs};
use crate::project::Project;

/// Most observations one kriging estimate uses (the most correlated with the target).
pub const DEFAULT_NEIGHBOURS: usize = 16;

/// What to reconstruct.
#[derive(Debug, Clone, Default)]
pub struct ReconstructRequest {
    /// Estimate every sensor's value at this time, seconds [default: the latest known reading].
    pub at: Option<UnixSeconds>,
    /// The modality [default: the condition modality: `vw@30cm`, else the first `vw@...`].
    pub modality: Option<String>,
    /// Observations per estimate [default: [`DEFAULT_NEIGHBOURS`]].
    pub neighbours: Option<usize>,
    /// The model-based estimator [default: [`Estimator::Changes`]].
    pub estimator: Estimator,
}

impl Estimator {
    /// The estimator that can answer with `dynamic` (the fitted dynamic model, if any): this
    /// one, or kriging of changes in place of [`Estimator::Dynamic`] without a model.
    pub fn resolve(self, dynamic: Option<&DynamicModel>) -> Estimator {
        match (self, dynamic) {
            (Estimator::Dynamic, None) => Estimator::Changes,
            (e, _) => e,
        }
    }
}

/// One sensor's estimate.
#[derive(Debug, Clone, PartialEq)]
pub struct SensorEstimate {
    /// The sensor.
    pub sensor: SensorId,
    /// Its position, WGS84.
    pub position: LatLon,
    /// Its latest known reading's time, seconds, if any.
    pub last_time: Option<UnixSeconds>,
    /// Last value carried forward (its mean when never read), the modality's unit.
    pub carried: f64,
    /// Model-based estimate ([`Estimator`]), the modality's unit.
    pub kriged: f64,
    /// Its variance under the model, the unit squared.
    pub variance: f64,
    /// Half-width of its 90% prediction interval `kriged ± half90`, the modality's unit: for
    /// the kriging of changes calibrated on the estimator's own out-of-sample errors at past
    /// reads ([`interval_multiplier`](crate::kriging_inputs::interval_multiplier)); for the
    /// dynamic model `q`·√(variance + reading noise), `q` from back-tests that hide in the past
    /// what is stale now (docs/method.md §7); otherwise [`Z90`](crate::Z90)·√variance.
    pub half90: f64,
}

/// Every sensor's estimate at one time.
#[derive(Debug, Clone)]
pub struct Reconstruction {
    /// Estimation time, seconds.
    pub at: UnixSeconds,
    /// The modality.
    pub modality: String,
    /// The field model (means and covariance of levels).
    pub model: FieldModel,
    /// The model of changes.
    pub changes: IncrementModel,
    /// The dynamic field model (None when it cannot be fitted, e.g. over
    /// [`gleaner_kriging::MAX_DYNAMIC_SENSORS`] sensors).
    pub dynamic: Option<DynamicModel>,
    /// The estimator used.
    pub estimator: Estimator,
    /// Sampling step of the modality's readings, seconds.
    pub step_s: i64,
    /// One per sensor, sorted by id.
    pub sensors: Vec<SensorEstimate>,
}

/// The modality a reconstruction is about: the requested one, else the condition modality.
pub fn target_modality<S: Store>(
    project: &Project<S>,
    requested: Option<&str>,
) -> Result<Modality> {
    let name = match requested {
        Some(m) => m.to_string(),
        None => {
            let names: Vec<String> = project
                .store()
                .modalities()?
                .into_iter()
                .map(|m| m.modality.to_string())
                .collect();
            crate::condition::condition_modality(project.settings(), &names).ok_or_else(|| {
                AppError::Invalid(
                    "no soil-moisture modality to reconstruct: give one (e.g. vw@30cm)".into(),
                )
            })?
        }
    };
    Modality::new(&name).map_err(|e| AppError::Invalid(format!("modality {name:?}: {e}")))
}

/// Per project sensor (sorted by id): times and values of one batch's readings.
pub(crate) fn per_sensor(ids: &[SensorId], batch: &ReadingBatch) -> Columns {
    let index: HashMap<&SensorId, usize> = ids.iter().enumerate().map(|(k, s)| (s, k)).collect();
    let mut out = vec![(Vec::new(), Vec::new()); ids.len()];
    for r in &batch.rows {
        let Some(&k) = batch
            .sensors
            .get(r.sensor as usize)
            .and_then(|s| index.get(s))
        else {
            continue;
        };
        out[k].0.push(r.t);
        out[k].1.push(r.value);
    }
    for (t, v) in &mut out {
        let mut pairs: Vec<(UnixSeconds, f64)> = t.iter().copied().zip(v.iter().copied()).collect();
        pairs.sort_by_key(|p| p.0);
        pairs.dedup_by_key(|p| p.0);
        *t = pairs.iter().map(|p| p.0).collect();
        *v = pairs.iter().map(|p| p.1).collect();
    }
    out
}

/// Largest lag of the temporal fit, days: the ages readings reach between visits in a
/// campaign (a 14-day fit saw only the slow seasonal part and gave a time scale of months).
pub const FIT_LAG_DAYS: i64 = 28;

/// Fits the field model of `modality` on everything known at or before `at` (seconds); also
/// returns the sampling step, seconds.
pub(crate) fn fit_model<S: Store>(
    project: &Project<S>,
    modality: &Modality,
    at: UnixSeconds,
) -> Result<(FieldModel, i64)> {
    fit_inner(project, modality, at, false).map(|(m, _, step)| (m, step))
}

/// Fits the field model of `modality` and its model of changes on everything known at or
/// before `at` (seconds); also returns the sampling step, seconds.
pub fn fit_models<S: Store>(
    project: &Project<S>,
    modality: &Modality,
    at: UnixSeconds,
) -> Result<Models> {
    let (levels, changes, step_s) = fit_inner(project, modality, at, true)?;
    let changes = changes.ok_or_else(|| AppError::Invalid("no model of changes".into()))?;
    let dynamic = fit_dynamic_model(project, modality, at, Some(step_s))?;
    Ok(Models {
        levels,
        changes,
        dynamic,
        step_s,
    })
}

/// The fitted models of one modality.
#[derive(Debug, Clone)]
pub struct Models {
    /// Means and the parametric covariance of levels.
    pub levels: FieldModel,
    /// The model of changes.
    pub changes: IncrementModel,
    /// The dynamic model (None when it cannot be fitted).
    pub dynamic: Option<DynamicModel>,
    /// Sampling step, seconds.
    pub step_s: i64,
}

/// Why the dynamic model is missing for `modality`, and what to do instead (`advice`).
pub fn unfit_dynamic(modality: &Modality, advice: &str) -> AppError {
    AppError::Invalid(format!(
        "the dynamic field model cannot be fitted on {modality} here (more than {} sensors, or no two distinct readings): {advice}",
        gleaner_kriging::MAX_DYNAMIC_SENSORS
    ))
}

/// Fits the dynamic model of `modality` on every reading stored at or before `at`
/// (seconds), at sampling step `step_s` (seconds; `None`: the readings' median spacing);
/// None when the network is too large for it or has no two distinct readings.
pub fn fit_dynamic_model<S: Store>(
    project: &Project<S>,
    modality: &Modality,
    at: UnixSeconds,
    step_s: Option<i64>,
) -> Result<Option<DynamicModel>> {
    let sensors = project.sensors()?;
    if sensors.len() > gleaner_kriging::MAX_DYNAMIC_SENSORS {
        return Ok(None);
    }
    let ids: Vec<SensorId> = sensors.iter().map(|s| s.id.clone()).collect();
    let batch = project
        .store()
        .readings_for(Some(modality), UnixSeconds::MIN..=at)?;
    let columns = per_sensor(&ids, &batch);
    let step_s = step_s.unwrap_or_else(|| {
        let times: Vec<Vec<UnixSeconds>> = columns.iter().map(|c| c.0.clone()).collect();
        sampling_step(&times).max(1)
    });
    dynamic_from_columns(&columns, step_s, project.settings().planner.unshared_weight)
}

/// Where the kriging of changes' readings start for an estimate at `at` (seconds): a
/// [`CHANGE_MARGIN_S`] before the stalest sensor's latest reading (time s, value), or before
/// `at` when no sensor has one.
fn change_window_start(latest: &[Option<(UnixSeconds, f64)>], at: UnixSeconds) -> UnixSeconds {
    latest
        .iter()
        .flatten()
        .map(|l| l.0)
        .min()
        .unwrap_or(at)
        .saturating_sub(CHANGE_MARGIN_S)
}

/// Runs `model`'s Kalman filter over `columns` (per sensor, times ascending, seconds) from
/// the stationary prior at `start`, stopping at each of `stops` (ascending, seconds) to call
/// `emit` with the filter; readings stamped after the last stop are not used.
pub(crate) fn run_filter<'m>(
    model: &'m DynamicModel,
    columns: &[(Vec<UnixSeconds>, Vec<f64>)],
    start: UnixSeconds,
    stops: &[UnixSeconds],
    mut emit: impl FnMut(usize, &gleaner_kriging::FieldFilter<'m>),
) {
    let mut events: Vec<(UnixSeconds, usize, f64)> = Vec::new();
    let end = stops.last().copied().unwrap_or(start);
    for (k, (times, values)) in columns.iter().enumerate() {
        for (&t, &v) in times.iter().zip(values) {
            if t >= start && t <= end {
                events.push((t, k, v));
            }
        }
    }
    events.sort_by(|a, b| a.0.cmp(&b.0).then(a.1.cmp(&b.1)));
    let mut filter = model.filter(start as f64);
    let mut next = events.iter().peekable();
    for (i, &stop) in stops.iter().enumerate() {
        while let Some(&&(t, k, v)) = next.peek() {
            if t > stop {
                break;
            }
            filter.advance(t as f64);
            filter.observe(k, v);
            next.next();
        }
        filter.advance(stop as f64);
        emit(i, &filter);
    }
}

fn fit_inner<S: Store>(
    project: &Project<S>,
    modality: &Modality,
    at: UnixSeconds,
    with_changes: bool,
) -> Result<(FieldModel, Option<IncrementModel>, i64)> {
    let sensors = project.sensors()?;
    let (_, field) = project.field()?;
    let ids: Vec<SensorId> = sensors.iter().map(|s| s.id.clone()).collect();
    let batch = project
        .store()
        .readings_for(Some(modality), UnixSeconds::MIN..=at)?;
    let columns = per_sensor(&ids, &batch);
    fit_on_columns(
        &positions(&sensors, &field),
        &columns,
        modality,
        with_changes,
    )
}

/// [`fit_inner`] on per-sensor columns already read (times ascending, seconds), the sensors
/// at `positions` (east/north metres).
fn fit_on_columns(
    positions: &[[f64; 2]],
    columns: &Columns,
    modality: &Modality,
    with_changes: bool,
) -> Result<(FieldModel, Option<IncrementModel>, i64)> {
    let times: Vec<Vec<UnixSeconds>> = columns.iter().map(|c| c.0.clone()).collect();
    let step = sampling_step(&times).max(1);
    let series: Vec<SensorSeries<'_>> = columns
        .iter()
        .zip(positions)
        .map(|((t, v), p)| SensorSeries {
            position: *p,
            times: t,
            values: v,
        })
        .collect();
    let options = FitOptions {
        step_s: step,
        // Lags covering the four weeks a campaign's readings typically age, whatever the
        // sampling step; the lag-0 intercept is fitted (a temporal nugget).
        max_lag_steps: (FIT_LAG_DAYS * 86_400 / step).clamp(14, 1_000),
        ..FitOptions::default()
    };
    let model = fit(&series, &options)
        .map_err(|e| AppError::core("field model", format!("{modality}: {e}")))?;
    if !with_changes {
        return Ok((model, None, step));
    }
    let changes = fit_increments(
        &series,
        &IncrementFitOptions {
            step_s: step,
            lags_steps: CHANGE_LAG_DAYS
                .iter()
                .map(|d| (d * 86_400 / step).max(1))
                .collect(),
            ..IncrementFitOptions::default()
        },
    )
    .map_err(|e| AppError::core("model of changes", format!("{modality}: {e}")))?;
    Ok((model, Some(changes), step))
}

/// Lags of the fit of the model of changes, days (up to the two months readings can age
/// between visits in a campaign).
pub const CHANGE_LAG_DAYS: [i64; 11] = [1, 2, 3, 5, 7, 10, 14, 21, 28, 42, 56];

/// How far before the stalest sensor's last reading the kriging of changes reads, seconds (a
/// neighbour missing that day is taken from its latest reading before it).
pub const CHANGE_MARGIN_S: i64 = 8 * 86_400;

/// Each sensor's cell, as an index of the field's cells (sensors in project order).
fn sensor_cells(field: &gleaner_field::Field, sensors: usize) -> Vec<usize> {
    (0..sensors)
        .map(|k| field.cell_of_sensor(k).index())
        .collect()
}

/// Sensor positions in the field's local frame, east/north metres.
fn positions(sensors: &[gleaner_field::Sensor], field: &gleaner_field::Field) -> Vec<[f64; 2]> {
    sensors
        .iter()
        .map(|s| {
            let p = field.frame().forward(s.position);
            [p.e, p.n]
        })
        .collect()
}

/// Estimates every sensor's `modality` value at `at` with the fitted models, from each
/// sensor's latest known reading within `lookback_s` before `at` (and, for
/// [`Estimator::Changes`], every known reading from [`CHANGE_MARGIN_S`] before the stalest
/// sensor's latest one), with
/// `estimator` and at most `neighbours` observations per estimate.
pub(crate) fn estimate<S: Store>(
    project: &Project<S>,
    modality: &Modality,
    (model, changes, dynamic): (&FieldModel, &IncrementModel, Option<&DynamicModel>),
    at: UnixSeconds,
    lookback_s: i64,
    (neighbours, estimator): (usize, Estimator),
) -> Result<Vec<SensorEstimate>> {
    estimate_with(
        project,
        modality,
        (model, changes, dynamic),
        (at, lookback_s),
        (neighbours, estimator),
        (&mut EstimateReads::default(), false),
    )
}

/// The store reads of the last estimate ([`estimate_with`]): every sensor's latest reading in
/// [`from`, `at`] and, for the kriging of changes, every sensor's readings in [`needed`, `at`]
/// (seconds), with the store's reading count when read.
#[derive(Debug, Default)]
pub struct EstimateReads {
    kept: Option<KeptReads>,
    /// Estimates that used kept reads instead of reading the store.
    reused: usize,
}

impl EstimateReads {
    /// Estimates that used kept reads instead of reading the store.
    pub fn reused(&self) -> usize {
        self.reused
    }
}

#[derive(Debug)]
struct KeptReads {
    modality: Modality,
    readings: u64,
    from: UnixSeconds,
    at: UnixSeconds,
    latest: Vec<Option<(UnixSeconds, f64)>>,
    needed: Option<UnixSeconds>,
    series: Columns,
    /// The interval multiplier computed from these reads and what else it depends on.
    multiplier: MultiplierMemo,
}

/// What the interval multiplier ([`KrigingInputs::multiplier`]) of an estimate depends on
/// besides its reads (the latest readings and the change window's series), and its value.
/// Its back-test does not depend on the estimation time: the gaps it replays are each
/// sensor's age difference from the freshest (whole seconds, exact), so an estimate at a
/// later time over the same reads has the same multiplier.
#[derive(Debug)]
struct MultiplierMemo {
    estimator: Estimator,
    neighbours: usize,
    /// The model of changes, `Debug` text (every float to the last bit).
    changes: String,
    positions: Vec<[u64; 2]>,
    cells: Vec<usize>,
    q: f64,
}

impl MultiplierMemo {
    /// Whether both were computed from the same inputs (their `q` aside).
    fn same_inputs(&self, other: &MultiplierMemo) -> bool {
        self.estimator == other.estimator
            && self.neighbours == other.neighbours
            && self.cells == other.cells
            && self.positions == other.positions
            && self.changes == other.changes
    }
}

/// Whether two lists of latest readings (time s, value) are equal to the last bit.
fn same_bits(a: &[Option<(UnixSeconds, f64)>], b: &[Option<(UnixSeconds, f64)>]) -> bool {
    a.len() == b.len()
        && a.iter()
            .zip(b)
            .all(|(a, b)| a.map(|(t, v)| (t, v.to_bits())) == b.map(|(t, v)| (t, v.to_bits())))
}

/// [`estimate`] at `at` with look-back `lookback_s` (seconds), keeping its reads in `reads`.
/// With `reuse`, the caller vouches that the store holds no reading stamped after the kept
/// estimate's time and that no stored reading was replaced since (a campaign between one
/// mission's estimate after its flights and the next mission's before them: a flight at T
/// brings back only readings stamped at or before T − period, the last estimate's time);
/// then, when the store's reading count is the kept one and the windows nest (this estimate's
/// look-back and change window start no earlier than the kept ones), the kept reads
/// restricted to this estimate's windows are what the store would return, and are used.
pub fn estimate_with<S: Store>(
    project: &Project<S>,
    modality: &Modality,
    (model, changes, dynamic): (&FieldModel, &IncrementModel, Option<&DynamicModel>),
    (at, lookback_s): (UnixSeconds, i64),
    (neighbours, estimator): (usize, Estimator),
    (reads, reuse): (&mut EstimateReads, bool),
) -> Result<Vec<SensorEstimate>> {
    let sensors = project.sensors()?;
    let (_, field) = project.field()?;
    if model.means.len() != sensors.len() {
        return Err(AppError::Invalid(format!(
            "the field model has {} sensors, the project {}",
            model.means.len(),
            sensors.len()
        )));
    }
    let ids: Vec<SensorId> = sensors.iter().map(|s| s.id.clone()).collect();
    let from = at.saturating_sub(lookback_s.max(0));
    let readings = project.store().reading_count()?;
    let kept = reads.kept.take().filter(|k| {
        reuse
            && k.modality == *modality
            && k.readings == readings
            && k.latest.len() == ids.len()
            && k.at <= at
            && k.from <= from
    });
    reads.reused += usize::from(kept.is_some());
    // The latest reading per sensor within the look-back: one index seek per sensor (or the
    // kept latest, when still within the look-back: nothing newer is stored).
    let latest: Vec<Option<(UnixSeconds, f64)>> = match &kept {
        Some(k) => k.latest.iter().map(|l| l.filter(|l| l.0 >= from)).collect(),
        None => {
            let index: HashMap<&SensorId, usize> =
                ids.iter().enumerate().map(|(k, s)| (s, k)).collect();
            let mut latest = vec![None; ids.len()];
            for (sensor, t, v) in project.store().latest_readings(modality, from..=at)? {
                if let Some(&k) = index.get(&sensor) {
                    latest[k] = Some((t, v));
                }
            }
            latest
        }
    };
    // The kriging of changes needs every sensor's readings from a little before the stalest
    // sensor's last one: one read (or the kept readings from then on).
    let (needed, series) = match estimator {
        Estimator::Levels(_) => (None, Vec::new()),
        Estimator::Dynamic => {
            // Every reading known (the filter takes its window's, the interval's back-tests
            // all of them): one read.
            dynamic.ok_or_else(|| unfit_dynamic(modality, "use another estimator"))?;
            let batch = project.store().readings_for(Some(modality), from..=at)?;
            (None, per_sensor(&ids, &batch))
        }
        Estimator::Changes => {
            let needed = change_window_start(&latest, at).max(from);
            let series = match &kept {
                Some(KeptReads {
                    needed: Some(was),
                    series,
                    ..
                }) if *was <= needed => series
                    .iter()
                    .map(|(times, values)| {
                        let first = times.partition_point(|&t| t < needed);
                        (times[first..].to_vec(), values[first..].to_vec())
                    })
                    .collect(),
                _ => {
                    let batch = project.store().readings_for(Some(modality), needed..=at)?;
                    per_sensor(&ids, &batch)
                }
            };
            (Some(needed), series)
        }
    };
    let positions = positions(&sensors, &field);
    let cells = sensor_cells(&field, sensors.len());
    let kriging = KrigingInputs::new(
        (&positions, &cells),
        (model, changes),
        (&latest, &series),
        at,
        (neighbours, estimator),
    );
    // The interval multiplier's inputs; the kept multiplier serves when this estimate reads
    // exactly what the kept one read (the same latest readings bit for bit and the same change
    // window: the kept series unrestricted).
    let memo = MultiplierMemo {
        estimator,
        neighbours,
        changes: format!("{changes:?}"),
        positions: positions.iter().map(|p| p.map(f64::to_bits)).collect(),
        cells: cells.clone(),
        q: f64::NAN,
    };
    let kept_q = kept.as_ref().and_then(|k| {
        (same_bits(&k.latest, &latest) && k.needed == needed && k.multiplier.same_inputs(&memo))
            .then_some(k.multiplier.q)
    });
    let q = kept_q.unwrap_or_else(|| kriging.multiplier());
    let dynamic_estimates = match (estimator, dynamic) {
        (Estimator::Dynamic, Some(model)) => dynamic_at(
            model,
            &series,
            (from, at),
            project.settings().planner.unshared_weight,
        )?,
        _ => Vec::new(),
    };
    let estimates = sensors
        .iter()
        .enumerate()
        .map(|(k, s)| {
            let (kriged, variance, half90) = match dynamic_estimates.get(k) {
                Some(&e) => e,
                None => {
                    let (mean, variance) = kriging.estimate(k);
                    (mean, variance, kriging.half90(k, variance, q))
                }
            };
            SensorEstimate {
                sensor: s.id.clone(),
                position: s.position,
                last_time: latest[k].map(|l| l.0),
                carried: latest[k].map_or(model.means[k], |l| l.1),
                kriged,
                variance,
                half90,
            }
        })
        .collect();
    reads.kept = Some(KeptReads {
        modality: modality.clone(),
        readings,
        from,
        at,
        latest,
        needed,
        series,
        multiplier: MultiplierMemo { q, ..memo },
    });
    Ok(estimates)
}

/// The dynamic model's estimate of every sensor at `at` (seconds): (posterior mean, variance,
/// 90% half-width `q`·√(variance + reading noise)), the modality's unit, from `known` (each
/// sensor's readings stamped in `[from, at]`, times ascending): one filter pass over those in
/// the model's window before `at`, `q` from back-tests over all of them
/// ([`dynamic_multiplier`]).
fn dynamic_at(
    model: &DynamicModel,
    known: &Columns,
    (from, at): (UnixSeconds, UnixSeconds),
    unshared_weight: f64,
) -> Result<Vec<(f64, f64, f64)>> {
    let start = at.saturating_sub(dynamic_window_s(model)).max(from);
    let mut filtered: Vec<(f64, f64)> = Vec::new();
    run_filter(model, known, start, &[at], |_, f| {
        filtered = (0..known.len()).map(|k| f.estimate(k)).collect();
    });
    let step = (model.step_s() as i64).max(1);
    let q = dynamic_multiplier(known, at, step, unshared_weight)?;
    Ok(filtered
        .into_iter()
        .map(|(mean, variance)| (mean, variance, dynamic::half90(model, q, variance)))
        .collect())
}

/// The use case: fits the field model of the modality on everything known at `at` and
/// estimates every sensor's value then. Writes nothing.
pub fn reconstruct<S: Store>(
    project: &Project<S>,
    request: &ReconstructRequest,
) -> Result<Reconstruction> {
    crate::when::check("estimation time", request.at)?;
    let modality = target_modality(project, request.modality.as_deref())?;
    let at = match request.at {
        Some(t) => t,
        None => project
            .store()
            .readings_for(Some(&modality), UnixSeconds::MIN..=UnixSeconds::MAX)?
            .rows
            .iter()
            .map(|r| r.t)
            .max()
            .ok_or_else(|| {
                AppError::Invalid(format!("no {modality} readings to reconstruct from"))
            })?,
    };
    let Models {
        levels: model,
        changes,
        dynamic,
        step_s,
    } = fit_models(project, &modality, at)?;
    let neighbours = request.neighbours.unwrap_or(DEFAULT_NEIGHBOURS).max(1);
    let estimator = request.estimator.resolve(dynamic.as_ref());
    let sensors = estimate(
        project,
        &modality,
        (&model, &changes, dynamic.as_ref()),
        at,
        UnixSeconds::MAX / 4,
        (neighbours, estimator),
    )?;
    Ok(Reconstruction {
        at,
        modality: modality.to_string(),
        model,
        changes,
        dynamic,
        estimator,
        step_s,
        sensors,
    })
}

/// What to reconstruct over a range of times (one fit; for the dynamic model one filter
/// pass).
#[derive(Debug, Clone, Default)]
pub struct ReconstructSeriesRequest {
    /// First estimation time, seconds.
    pub from: UnixSeconds,
    /// Last estimation time, seconds (at or after `from`).
    pub to: UnixSeconds,
    /// Spacing of the estimation times, seconds (> 0).
    pub every_s: i64,
    /// The modality [default: the condition modality].
    pub modality: Option<String>,
    /// The model-based estimator [default: [`Estimator::Changes`], as at one time].
    pub estimator: Estimator,
    /// Observations per kriging estimate [default: [`DEFAULT_NEIGHBOURS`]].
    pub neighbours: Option<usize>,
    /// Only the sensors of this cell [default: every sensor].
    pub cell: Option<CellIndex>,
}

/// Most estimation times one series request may ask for.
pub const MAX_SERIES_TIMES: usize = 200_000;

/// Every sensor's estimate at a grid of times.
#[derive(Debug, Clone)]
pub struct ReconstructionSeries {
    /// The modality.
    pub modality: String,
    /// The modality's unit as stored (e.g. `m3/m3`), if known.
    pub unit: Option<String>,
    /// The estimator used ([`Estimator::Dynamic`] falls back to [`Estimator::Changes`]
    /// where the dynamic model cannot be fitted).
    pub estimator: Estimator,
    /// Estimation times, seconds, ascending.
    pub times: Vec<UnixSeconds>,
    /// The sensors (columns), by id, with their WGS84 positions.
    pub sensors: Vec<(SensorId, LatLon)>,
    /// Posterior means, `times × sensors` row-major, the modality's unit.
    pub mean: Vec<f64>,
    /// Posterior variances, same layout, the unit squared (without the reading noise).
    pub variance: Vec<f64>,
    /// Half-widths of the 90% prediction intervals, same layout, the modality's unit: under
    /// the dynamic model `q`·√(variance + reading noise), `q` back-tested on the staleness at
    /// `to` (`Z90` when every sensor is read at `to`; docs/method.md §7); under the kriging of changes
    /// calibrated at each time on the estimator's out-of-sample errors at past readings
    /// ([`interval_multiplier`](crate::kriging_inputs::interval_multiplier)); `Z90`·√variance
    /// otherwise.
    pub half90: Vec<f64>,
    /// The dynamic model (fitted on every reading stamped at or before `to`), when it is
    /// the estimator.
    pub model: Option<DynamicModel>,
}

impl ReconstructionSeries {
    /// The 90% prediction interval `mean ± half90` of entry (time index, sensor index).
    pub fn interval90(&self, t: usize, s: usize) -> (f64, f64) {
        let k = t * self.sensors.len() + s;
        (self.mean[k] - self.half90[k], self.mean[k] + self.half90[k])
    }
}

/// The unit stored for `modality` (e.g. `m3/m3`), if any.
pub(crate) fn modality_unit<S: Store>(
    project: &Project<S>,
    modality: &Modality,
) -> Result<Option<String>> {
    Ok(project
        .store()
        .modalities()?
        .into_iter()
        .find(|m| m.modality == *modality)
        .and_then(|m| m.unit))
}

/// The use case: every sensor's posterior mean and variance of the modality at each time
/// `from, from + every, .., ≤ to`, by the request's estimator. The models' parameters are
/// fitted once, on every reading stamped at or before `to`; each time's estimate uses only
/// the readings stamped at or before it (the dynamic model in one filter pass; the kriging
/// estimators from each sensor's latest reading by then, as [`reconstruct`] at that time).
/// Writes nothing.
///
/// Errors: `to` before `from`, a non-positive step, more than [`MAX_SERIES_TIMES`] times,
/// no readings of the modality, models that cannot be fitted, an unknown `cell`.
pub fn reconstruct_series<S: Store>(
    project: &Project<S>,
    request: &ReconstructSeriesRequest,
) -> Result<ReconstructionSeries> {
    crate::when::check("range start", Some(request.from))?;
    crate::when::check("range end", Some(request.to))?;
    if request.to < request.from {
        return Err(AppError::Invalid(
            "the range ends before it starts (--to before --from)".into(),
        ));
    }
    if request.every_s <= 0 {
        return Err(AppError::Invalid(format!(
            "the step must be positive, got {} s",
            request.every_s
        )));
    }
    let count = (request.to - request.from) / request.every_s + 1;
    if count > MAX_SERIES_TIMES as i64 {
        return Err(AppError::Invalid(format!(
            "{count} estimation times: at most {MAX_SERIES_TIMES} (a longer step, or a shorter range)"
        )));
    }
    let times: Vec<UnixSeconds> = (0..count)
        .map(|k| request.from + k * request.every_s)
        .collect();
    let modality = target_modality(project, request.modality.as_deref())?;
    let sensors = project.sensors()?;
    let (_, field) = project.field()?;
    let ids: Vec<SensorId> = sensors.iter().map(|s| s.id.clone()).collect();
    // The columns: every sensor, or the cell's.
    let wanted: Vec<usize> = match request.cell {
        None => (0..ids.len()).collect(),
        Some(index) => {
            let cell = field.cell_at(index).ok_or_else(|| AppError::NotFound {
                what: "cell",
                id: index.to_string(),
            })?;
            field.cells()[cell.index()].sensors.clone()
        }
    };
    let batch = project
        .store()
        .readings_for(Some(&modality), UnixSeconds::MIN..=request.to)?;
    let columns = per_sensor(&ids, &batch);
    if columns.iter().all(|c| c.0.is_empty()) {
        return Err(AppError::Invalid(format!(
            "no {modality} readings at or before the range's end"
        )));
    }
    let all_times: Vec<Vec<UnixSeconds>> = columns.iter().map(|c| c.0.clone()).collect();
    let step = sampling_step(&all_times).max(1);
    // The dynamic model from the columns just read (they are every reading up to the
    // range's end), when it is asked for.
    let dynamic = match request.estimator {
        Estimator::Dynamic => {
            dynamic_from_columns(&columns, step, project.settings().planner.unshared_weight)?
        }
        _ => None,
    };
    let estimator = request.estimator.resolve(dynamic.as_ref());
    let m = wanted.len();
    let mut mean = vec![0.0; times.len() * m];
    let mut variance = vec![0.0; times.len() * m];
    let mut half90 = vec![0.0; times.len() * m];
    match (&dynamic, estimator) {
        (Some(model), Estimator::Dynamic) => {
            let q = dynamic_multiplier(
                &columns,
                request.to,
                step,
                project.settings().planner.unshared_weight,
            )?;
            let start = request.from.saturating_sub(dynamic_window_s(model));
            run_filter(model, &columns, start, &times, |i, f| {
                for (j, &k) in wanted.iter().enumerate() {
                    let (mu, v) = f.estimate(k);
                    mean[i * m + j] = mu;
                    variance[i * m + j] = v;
                    half90[i * m + j] = dynamic::half90(model, q, v);
                }
            });
        }
        _ => {
            let positions = positions(&sensors, &field);
            let cells = sensor_cells(&field, sensors.len());
            let (levels, changes, _) = fit_on_columns(&positions, &columns, &modality, true)?;
            let changes = changes.ok_or_else(|| AppError::Invalid("no model of changes".into()))?;
            let neighbours = request.neighbours.unwrap_or(DEFAULT_NEIGHBOURS).max(1);
            for (i, &at) in times.iter().enumerate() {
                // What `estimate` reads at `at`: each sensor's latest reading by then and,
                // for the kriging of changes, every reading from a margin before the
                // stalest of them.
                let latest: Vec<Option<(UnixSeconds, f64)>> = columns
                    .iter()
                    .map(|(t, v)| {
                        let n = t.partition_point(|&x| x <= at);
                        (n > 0).then(|| (t[n - 1], v[n - 1]))
                    })
                    .collect();
                let series: Columns = match estimator {
                    Estimator::Changes => {
                        let needed = change_window_start(&latest, at);
                        columns
                            .iter()
                            .map(|(t, v)| {
                                let a = t.partition_point(|&x| x < needed);
                                let b = t.partition_point(|&x| x <= at);
                                (t[a..b].to_vec(), v[a..b].to_vec())
                            })
                            .collect()
                    }
                    _ => Vec::new(),
                };
                let kriging = KrigingInputs::new(
                    (&positions, &cells),
                    (&levels, &changes),
                    (&latest, &series),
                    at,
                    (neighbours, estimator),
                );
                let q = kriging.multiplier();
                for (j, &k) in wanted.iter().enumerate() {
                    let (mu, v) = kriging.estimate(k);
                    mean[i * m + j] = mu;
                    variance[i * m + j] = v;
                    half90[i * m + j] = kriging.half90(k, v, q);
                }
            }
        }
    }
    Ok(ReconstructionSeries {
        modality: modality.to_string(),
        unit: modality_unit(project, &modality)?,
        estimator,
        times,
        sensors: wanted
            .iter()
            .map(|&k| (sensors[k].id.clone(), sensors[k].position))
            .collect(),
        mean,
        variance,
        half90,
        model: dynamic.filter(|_| estimator == Estimator::Dynamic),
    })
}
