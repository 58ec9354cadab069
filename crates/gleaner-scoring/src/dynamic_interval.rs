//! The dynamic field model's calibrated 90% interval (docs/method.md §7): a back-test that
//! replays today's staleness in the past.
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
    DynamicModel, SensorSeries, Z90, backtest_errors_hidden, backtest_stretches,
    interval_multiplier,
};

use crate::error::Result;
use crate::kriging_inputs::Columns;
use crate::reconstruct::{dynamic_from_series, dynamic_window_s, unplaced_series};

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
    use crate::reconstruct::dynamic_from_columns;

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
}
