//! The dynamic field model as a project fits it (docs/method.md §7): its fit options, the fit on
//! per-sensor columns with the unshared drift, how far back its filter reads, and its
//! calibrated 90% interval: a back-test that replays today's staleness in the past.
//!
//! The Kalman filter's own interval, `mean ± 1.645·√(variance + reading noise)`, is right only
//! when the model is right about its uncertainty; where the field drifts away from what the
//! read sensors explain, it covers too little (the one-shot evaluations saw 65–81% on Hubbard
//! Brook). The calibrated interval is `mean ± q·√(variance + reading noise)`, `q` the
//! split-conformal quantile ([`gleaner_kriging::interval_multiplier`]) of the model's
//! standardised errors on back-tests that hide, in the past, what is hidden now: at an
//! estimation time `at` sensor `i`'s latest reading is `aᵢ` old, so each back-test stretch
//! ending at `E` hides sensor `i`'s readings in `(E − aᵢ, E]` from a model fitted on the
//! readings before the stretch, and scores the hidden readings against the filter's estimate
//! ([`gleaner_kriging::backtest_errors_hidden`]). In the one-shot case (some sensors read
//! throughout, the others not since a split) this is the evaluation's registered back-test,
//! except that `q` may fall below 1.645 here: in the daily regime the model's own interval is
//! too wide (96.6% and 93.8% → 92.6% coverage on the tuning years with and without that floor;
//! docs/evaluation/dynamic-campaign-interval-preregistration.md).
//!
//! Units: times seconds; values in the modality's unit; `q` dimensionless.

use gleaner_field::UnixSeconds;
use gleaner_kriging::{
    DynamicFitOptions, DynamicModel, SensorSeries, Shrinkage, Z90, backtest_errors_hidden,
    backtest_stretches, fit_dynamic, fit_own_rates, interval_multiplier,
};

use crate::error::{AppError, Result};
use crate::kriging_inputs::Columns;

/// Largest lag of the dynamic model's persistence fit, days.
pub const DYNAMIC_LAG_DAYS: i64 = 14;

/// Whether the dynamic model carries a common level of its own
/// ([`DynamicFitOptions::common_mode`]).
pub const DYNAMIC_COMMON_MODE: bool = false;

/// The dynamic model's fit options at sampling step `step_s` (seconds): automatic
/// shrinkage, reading noise 0.1% of the variance, lags up to [`DYNAMIC_LAG_DAYS`], a common
/// level as [`DYNAMIC_COMMON_MODE`] says.
pub fn dynamic_fit_options(step_s: i64) -> DynamicFitOptions {
    DynamicFitOptions {
        step_s: step_s.max(1),
        max_lag_s: DYNAMIC_LAG_DAYS * 86_400,
        shrinkage: Shrinkage::Auto,
        noise_share: 1e-3,
        common_mode: DYNAMIC_COMMON_MODE,
        ..DynamicFitOptions::default()
    }
}

/// Pseudo-changes of the pooled rate each sensor's unshared drift rate is shrunk towards
/// ([`fit_own_rates`]'s prior weight): a month of daily readings.
pub const UNSHARED_PRIOR_CHANGES: f64 = 30.0;

/// The dynamic model fitted on per-sensor columns (times in seconds, ascending) at sampling
/// step `step_s` (seconds), with the unshared per-sensor drift (rates fitted on the same
/// columns, times `unshared_weight`; `[planner] unshared_weight`) when the weight is above 0;
/// None over [`gleaner_kriging::MAX_DYNAMIC_SENSORS`] sensors or without two distinct
/// readings.
pub(crate) fn dynamic_from_columns(
    columns: &Columns,
    step_s: i64,
    unshared_weight: f64,
) -> Result<Option<DynamicModel>> {
    dynamic_from_series(&unplaced_series(columns), step_s, unshared_weight)
}

/// [`dynamic_from_columns`] on the model's input series (per sensor, times in seconds,
/// ascending).
pub(crate) fn dynamic_from_series(
    series: &[SensorSeries<'_>],
    step_s: i64,
    unshared_weight: f64,
) -> Result<Option<DynamicModel>> {
    if series.len() > gleaner_kriging::MAX_DYNAMIC_SENSORS {
        return Ok(None);
    }
    let Ok(model) = fit_dynamic(series, &dynamic_fit_options(step_s)) else {
        return Ok(None);
    };
    if unshared_weight <= 0.0 {
        return Ok(Some(model));
    }
    let rates = fit_own_rates(series, step_s.max(1), UNSHARED_PRIOR_CHANGES)
        .map_err(|e| AppError::core("unshared drift rates", e))?;
    let model = model
        .with_own_rates(rates.into_iter().map(|r| r * unshared_weight).collect())
        .map_err(|e| AppError::core("unshared drift rates", e))?;
    Ok(Some(model))
}

/// `columns` (per sensor, times in seconds ascending) as the dynamic model's input series,
/// without positions (it does not use them).
pub(crate) fn unplaced_series(columns: &Columns) -> Vec<SensorSeries<'_>> {
    columns
        .iter()
        .map(|(t, v)| SensorSeries {
            position: [0.0, 0.0],
            times: t,
            values: v,
        })
        .collect()
}

/// How far back the dynamic estimator reads, seconds: three persistence times
/// (`−3·step/ln φ`), between 14 and 180 days. Readings older than that have decayed to a
/// few percent of their weight; the filter starts from the stationary prior there.
pub fn dynamic_window_s(model: &DynamicModel) -> i64 {
    let (lo, hi) = (14 * 86_400, 180 * 86_400);
    let phi = model.phi();
    if !(phi > 0.0 && phi < 1.0) {
        return if phi >= 1.0 { hi } else { lo };
    }
    let tau = -model.step_s() / phi.ln();
    ((3.0 * tau) as i64).clamp(lo, hi)
}

/// Half-width of the dynamic model's 90% interval around a posterior mean of `variance` (the
/// modality's unit squared): `q`·√(variance + reading noise), the modality's unit, `q` from
/// [`dynamic_multiplier`].
pub(crate) fn half90(model: &DynamicModel, q: f64, variance: f64) -> f64 {
    q * (variance.max(0.0) + model.noise()).sqrt()
}

/// The back-test stretches for estimation time `at` (seconds) over readings from `first`
/// (seconds): `(start, end)` of each, the latest first, each `span` long (the largest age of
/// `ages`), ending at `at − span`, `at − 2·span`, … — at most
/// [`gleaner_kriging::BACKTEST_STRETCHES`], none starting before the middle of `[first, at]`
/// ([`backtest_stretches`]). Empty when nothing is older than `step_s`. Ages over a quarter of
/// `[first, at]` are cut to it (so one stretch always fits), in place.
fn stretches_for(
    ages: &mut [Option<i64>],
    first: UnixSeconds,
    at: UnixSeconds,
    step_s: i64,
) -> Vec<(UnixSeconds, UnixSeconds)> {
    let cap = (at - first).max(0) / 4;
    for a in ages.iter_mut().flatten() {
        *a = (*a).min(cap);
    }
    let span = ages.iter().flatten().copied().max().unwrap_or(0);
    if span < step_s.max(1) {
        return Vec::new();
    }
    backtest_stretches(at - span, span, first + (at - first) / 2)
}

/// The multiplier `q` of the dynamic model's 90% interval at `at` (seconds), from `columns`
/// (every sensor's readings known at `at`, times ascending, seconds) at sampling step
/// `step_s` (seconds), the model refitted for each back-test on the readings before it
/// (`unshared_weight` as `[planner] unshared_weight`). Below [`Z90`] where the model's own
/// interval is too wide, above it where too narrow; [`Z90`] when no sensor is older than a
/// step, no stretch fits, a refit fails or fewer than [`gleaner_kriging::BACKTEST_MIN`]
/// errors come out.
pub(crate) fn dynamic_multiplier(
    columns: &Columns,
    at: UnixSeconds,
    step_s: i64,
    unshared_weight: f64,
) -> Result<f64> {
    let Some(first) = columns.iter().filter_map(|(t, _)| t.first().copied()).min() else {
        return Ok(Z90);
    };
    let mut ages: Vec<Option<i64>> = columns
        .iter()
        .map(|(t, _)| {
            let n = t.partition_point(|&x| x <= at);
            // A reading less than a step old is as fresh as the data come: not hidden.
            (n > 0).then(|| Some(at - t[n - 1]).filter(|&a| a >= step_s).unwrap_or(0))
        })
        .collect();
    let series = unplaced_series(columns);
    let mut errors = Vec::new();
    for (start, end) in stretches_for(&mut ages, first, at, step_s) {
        let before: Vec<SensorSeries<'_>> = series.iter().map(|s| s.before(start)).collect();
        let Some(model) = dynamic_from_series(&before, step_s, unshared_weight)? else {
            continue;
        };
        errors.extend(stretch_errors(&model, &series, &ages, (start, end)));
    }
    Ok(interval_multiplier(&errors))
}

/// `model`'s standardised errors on the stretch `(start, end]` (seconds) of `series` with
/// sensor `i` hidden for the last `ages[i]` seconds of it (never, for `None`); the filter
/// starts a dynamic window ([`dynamic_window_s`]) before the stretch.
fn stretch_errors(
    model: &DynamicModel,
    series: &[SensorSeries<'_>],
    ages: &[Option<i64>],
    (start, end): (UnixSeconds, UnixSeconds),
) -> Vec<f64> {
    // Hidden strictly after `end − age`: the reading that is `age` old now stays known.
    let hidden_from: Vec<Option<i64>> = ages
        .iter()
        .map(|a| a.filter(|&a| a > 0).map(|a| end - a + 1))
        .collect();
    let filter_start = start.saturating_sub(dynamic_window_s(model));
    backtest_errors_hidden(model, series, filter_start, &hidden_from, end)
}

#[cfg(test)]
mod tests {
    use super::*;

    const DAY: i64 = 86_400;

    #[test]
    fn stretches_step_back_by_the_largest_age() {
        let mut ages = vec![Some(0), Some(10 * DAY), None];
        let s = stretches_for(&mut ages, 0, 400 * DAY, DAY);
        assert_eq!(
            s,
            vec![
                (380 * DAY, 390 * DAY),
                (370 * DAY, 380 * DAY),
                (360 * DAY, 370 * DAY),
                (350 * DAY, 360 * DAY)
            ]
        );
        // A sensor dead for years is cut to a quarter of the history: one stretch fits.
        let mut ages = vec![Some(0), Some(1_000 * DAY)];
        let s = stretches_for(&mut ages, 0, 400 * DAY, DAY);
        assert_eq!(ages[1], Some(100 * DAY));
        assert_eq!(s, vec![(200 * DAY, 300 * DAY)]);
        // Everything read at the last step: nothing to calibrate.
        let mut ages = vec![Some(0), Some(DAY / 2)];
        assert!(stretches_for(&mut ages, 0, 400 * DAY, DAY).is_empty());
    }

    /// Columns of `n` sensors over `days` daily readings: a shared seasonal level plus a
    /// per-sensor random walk (`walk` m³/m³ a day) the shared part does not explain.
    fn columns(n: usize, days: i64, walk: f64) -> Columns {
        let mut state = 12_345_u64;
        let mut uniform = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let times: Vec<i64> = (0..days).map(|d| d * DAY).collect();
        (0..n)
            .map(|i| {
                let mut own = 0.0;
                let values = times
                    .iter()
                    .map(|&t| {
                        own += walk * uniform();
                        0.25 + 0.03 * ((t / DAY) as f64 / 58.0).sin() + 0.01 * i as f64 + own
                    })
                    .collect();
                (times.clone(), values)
            })
            .collect()
    }

    /// `all` with sensors 4.. unread for the last `days` days before `at`.
    fn unread(all: &Columns, at: i64, days: i64) -> Columns {
        let mut stale = all.clone();
        for (t, v) in stale.iter_mut().skip(4) {
            let keep = t.partition_point(|&x| x <= at - days * DAY);
            t.truncate(keep);
            v.truncate(keep);
        }
        stale
    }

    /// With every sensor read at the last step there is nothing stale: the Gaussian multiplier.
    /// With half the sensors unread for three weeks, a back-test gives a multiplier, the same
    /// again from the same inputs; the more each sensor wanders on its own (which the model
    /// without its unshared part does not carry), the wider the interval it calls for.
    #[test]
    fn stale_sensors_give_a_back_tested_multiplier() {
        let at = 399 * DAY;
        let all = columns(8, 400, 0.004);
        assert_eq!(dynamic_multiplier(&all, at, DAY, 0.0).unwrap(), Z90);
        let stale = unread(&all, at, 21);
        let q = dynamic_multiplier(&stale, at, DAY, 0.0).unwrap();
        assert!(q.is_finite() && q > 0.0, "{q}");
        assert_eq!(dynamic_multiplier(&stale, at, DAY, 0.0).unwrap(), q);
        let calm = unread(&columns(8, 400, 0.0005), at, 21);
        let q_calm = dynamic_multiplier(&calm, at, DAY, 0.0).unwrap();
        assert!(q > q_calm, "wandering {q}, calm {q_calm}");
    }

    /// Hiding starts just after the reading that is `age` old: the stretch `(start, end]`
    /// hides sensor 1's last 3 readings (age 3 days: readings at end − 2, end − 1, end days).
    #[test]
    fn a_sensor_is_hidden_for_its_age() {
        let cols = columns(2, 60, 0.0);
        let model = dynamic_from_columns(&cols, DAY, 0.0).unwrap().unwrap();
        let series = unplaced_series(&cols);
        let z = stretch_errors(
            &model,
            &series,
            &[Some(0), Some(3 * DAY)],
            (40 * DAY, 50 * DAY),
        );
        assert_eq!(z.len(), 3);
        let none = stretch_errors(&model, &series, &[Some(0), None], (40 * DAY, 50 * DAY));
        assert!(none.is_empty());
    }

    /// `[planner] unshared_weight` scales the fitted unshared drift rates; 0 leaves the model
    /// without them (the model as before, to the bit).
    #[test]
    fn unshared_weight_scales_the_fitted_rates() {
        let times: Vec<i64> = (0..60).map(|d| d * DAY).collect();
        let columns: Columns = (0..4)
            .map(|i| {
                let values = times
                    .iter()
                    .enumerate()
                    .map(|(d, _)| {
                        0.25 + 0.01 * ((d as f64) * 0.3 + i as f64).sin()
                            + 0.002 * (i * d % 7) as f64
                    })
                    .collect();
                (times.clone(), values)
            })
            .collect();
        let off = dynamic_from_columns(&columns, DAY, 0.0).unwrap().unwrap();
        assert!(off.own_rates().is_empty());
        let series = unplaced_series(&columns);
        let fitted = fit_own_rates(&series, DAY, UNSHARED_PRIOR_CHANGES).unwrap();
        assert!(fitted.iter().all(|&r| r > 0.0));
        let on = dynamic_from_columns(&columns, DAY, 2.5).unwrap().unwrap();
        for (got, want) in on.own_rates().iter().zip(&fitted) {
            assert_eq!(*got, want * 2.5);
        }
        // The shared part is the same fit.
        assert_eq!(on.phi(), off.phi());
    }
}
