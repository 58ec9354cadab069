//! Reconstruction (SPEC §7): every sensor's current value of one modality estimated from what
//! is known — its last collected value carried forward, and a space-time kriging estimate
//! (Gaussian conditional mean, with its variance) from every sensor's latest known reading.

use std::collections::HashMap;

use gleaner_field::{LatLon, Modality, SensorId, UnixSeconds};
use gleaner_kriging::{FieldModel, FitOptions, Mean, Observation, SensorSeries, fit, krige_with};
use gleaner_store::{ReadingBatch, Store};

use crate::error::{AppError, Result};
use crate::knowledge::sampling_step;
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
    /// Simple kriging towards the sensors' long-run means instead of ordinary kriging (the
    /// default, [`Mean::Unknown`]: the field's current level is estimated from the data).
    pub simple: bool,
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
    /// Kriging estimate, the modality's unit.
    pub kriged: f64,
    /// Kriging variance, the unit squared.
    pub variance: f64,
}

/// Every sensor's estimate at one time.
#[derive(Debug, Clone)]
pub struct Reconstruction {
    /// Estimation time, seconds.
    pub at: UnixSeconds,
    /// The modality.
    pub modality: String,
    /// The field model used (means and covariance).
    pub model: FieldModel,
    /// Sampling step of the modality's readings, seconds.
    pub step_s: i64,
    /// One per sensor, sorted by id.
    pub sensors: Vec<SensorEstimate>,
}

/// The modality a reconstruction is about: the requested one, else the condition modality.
pub(crate) fn target_modality<S: Store>(
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
            crate::score::condition_modality(project.settings(), &names).ok_or_else(|| {
                AppError::Invalid(
                    "no soil-moisture modality to reconstruct: give one (e.g. vw@30cm)".into(),
                )
            })?
        }
    };
    Modality::new(&name).map_err(|e| AppError::Invalid(format!("modality {name:?}: {e}")))
}

/// Per project sensor (sorted by id): times and values of one batch's readings.
fn per_sensor(ids: &[SensorId], batch: &ReadingBatch) -> Vec<(Vec<UnixSeconds>, Vec<f64>)> {
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

/// Fits the field model of `modality` on everything known at or before `at` (seconds).
pub(crate) fn fit_model<S: Store>(
    project: &Project<S>,
    modality: &Modality,
    at: UnixSeconds,
) -> Result<(FieldModel, i64)> {
    let sensors = project.sensors()?;
    let (_, field) = project.field()?;
    let ids: Vec<SensorId> = sensors.iter().map(|s| s.id.clone()).collect();
    let batch = project
        .store()
        .readings_for(Some(modality), UnixSeconds::MIN..=at)?;
    let columns = per_sensor(&ids, &batch);
    let times: Vec<Vec<UnixSeconds>> = columns.iter().map(|c| c.0.clone()).collect();
    let step = sampling_step(&times).max(1);
    let positions = positions(&sensors, &field);
    let series: Vec<SensorSeries<'_>> = columns
        .iter()
        .zip(&positions)
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
    Ok((model, step))
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

/// Estimates every sensor's `modality` value at `at` with a fitted model, from each sensor's
/// latest known reading within `lookback_s` before `at`, by kriging with `mean`.
pub(crate) fn estimate<S: Store>(
    project: &Project<S>,
    modality: &Modality,
    model: &FieldModel,
    at: UnixSeconds,
    lookback_s: i64,
    (neighbours, mean): (usize, Mean),
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
    // The latest reading per sensor within the look-back: one index seek per sensor.
    let index: HashMap<&SensorId, usize> = ids.iter().enumerate().map(|(k, s)| (s, k)).collect();
    let mut latest: Vec<Option<(UnixSeconds, f64)>> = vec![None; ids.len()];
    for (sensor, t, v) in project.store().latest_readings(modality, from..=at)? {
        if let Some(&k) = index.get(&sensor) {
            latest[k] = Some((t, v));
        }
    }
    let positions = positions(&sensors, &field);
    let observations: Vec<Observation> = latest
        .iter()
        .zip(&positions)
        .zip(&model.means)
        .filter_map(|((l, p), mean)| {
            l.map(|(t, v)| Observation {
                position: *p,
                age_s: (at - t).max(0) as f64,
                residual: v - mean,
            })
        })
        .collect();
    Ok(sensors
        .iter()
        .enumerate()
        .map(|(k, s)| {
            let e = krige_with(
                &model.covariance,
                &observations,
                positions[k],
                neighbours,
                mean,
            );
            SensorEstimate {
                sensor: s.id.clone(),
                position: s.position,
                last_time: latest[k].map(|l| l.0),
                carried: latest[k].map_or(model.means[k], |l| l.1),
                kriged: model.means[k] + e.residual,
                variance: e.variance,
            }
        })
        .collect())
}

/// The use case: fits the field model of the modality on everything known at `at` and
/// estimates every sensor's value then. Writes nothing.
pub fn reconstruct<S: Store>(
    project: &Project<S>,
    request: &ReconstructRequest,
) -> Result<Reconstruction> {
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
    let (model, step_s) = fit_model(project, &modality, at)?;
    let neighbours = request.neighbours.unwrap_or(DEFAULT_NEIGHBOURS).max(1);
    let sensors = estimate(
        project,
        &modality,
        &model,
        at,
        UnixSeconds::MAX / 4,
        (
            neighbours,
            if request.simple {
                Mean::Known
            } else {
                Mean::Unknown
            },
        ),
    )?;
    Ok(Reconstruction {
        at,
        modality: modality.to_string(),
        model,
        step_s,
        sensors,
    })
}
