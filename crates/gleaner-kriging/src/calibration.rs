//! Calibrated prediction intervals: a split-conformal multiplier from out-of-sample errors.
//!
//! A Gaussian model's 90% interval is `mean ± 1.645·sd`; when the model is wrong about its
//! own uncertainty (heavy-tailed changes, a drift the covariance does not carry) the interval
//! covers more or less than 90%. The interval becomes `mean ± q·sd`, `q` the split-conformal
//! quantile of the model's standardised errors `|z| = |v − v̂| / sd` on readings it did not
//! see ([`interval_multiplier`]). [`backtest_errors`] produces those errors for the dynamic
//! field model in the one-shot regime: a stretch of history in which only the sensors that
//! will be read are read, the others estimated as they will be.
//!
//! Units: times seconds; values in the modality's unit; `z` dimensionless.

use crate::SensorSeries;
use crate::dynamic::DynamicModel;

/// The standard normal's 95% quantile: a Gaussian 90% interval is `mean ± Z90·sd`.
pub const Z90: f64 = 1.644_853_626_951_472_2;

/// Fewest back-tested errors for a calibrated interval; with fewer, [`Z90`]·sd.
pub const BACKTEST_MIN: usize = 20;

/// The multiplier `q` of a 90% prediction interval `estimate ± q·sd` from standardised
/// out-of-sample errors `|z|`: their split-conformal quantile, the ⌈0.9 (n + 1)⌉-th smallest
/// (so a new error as exchangeable with them falls inside with probability ≥ 90%); [`Z90`]
/// (the Gaussian interval) with fewer than [`BACKTEST_MIN`] errors. Non-finite errors are
/// left out.
pub fn interval_multiplier(errors: &[f64]) -> f64 {
    let mut z: Vec<f64> = errors.iter().copied().filter(|z| z.is_finite()).collect();
    if z.len() < BACKTEST_MIN {
        return Z90;
    }
    z.sort_by(f64::total_cmp);
    let rank = (0.9 * (z.len() + 1) as f64).ceil() as usize;
    z[rank.clamp(1, z.len()) - 1]
}

/// Most back-test stretches one calibration pools ([`backtest_stretches`]).
pub const BACKTEST_STRETCHES: usize = 4;

/// The back-test stretches `(start, end)`, each `span` long, ending at `end`, `end − span`,
/// `end − 2·span`, … (the latest first): at most [`BACKTEST_STRETCHES`], none starting before
/// `earliest`; empty when `span` is not positive. Units are the caller's (seconds, or row
/// indices).
pub fn backtest_stretches(end: i64, span: i64, earliest: i64) -> Vec<(i64, i64)> {
    if span <= 0 {
        return Vec::new();
    }
    (0..BACKTEST_STRETCHES as i64)
        .map(|j| (end - (j + 1) * span, end - j * span))
        .take_while(|&(start, _)| start >= earliest)
        .collect()
}

/// The dynamic model's standardised errors on a back-test stretch `[split_s, end_s]`
/// (seconds) in which only the sensors with `read[i]` are read: [`backtest_errors_hidden`]
/// with every unread sensor hidden from `split_s` on.
///
/// `model` should be fitted on readings before `split_s` only (the errors are then out of
/// sample).
pub fn backtest_errors(
    model: &DynamicModel,
    series: &[SensorSeries<'_>],
    start_s: i64,
    split_s: i64,
    end_s: i64,
    read: &[bool],
) -> Vec<f64> {
    let hidden_from: Vec<Option<i64>> = (0..series.len())
        .map(|i| (!read.get(i).copied().unwrap_or(false)).then_some(split_s))
        .collect();
    backtest_errors_hidden(model, series, start_s, &hidden_from, end_s)
}

/// The dynamic model's standardised errors when sensor `i`'s readings from `hidden_from[i]`
/// (seconds; `None`: never hidden) to `end_s` are withheld and estimated instead.
///
/// The Kalman filter starts at `start_s` and takes every reading of `series` in
/// `[start_s, end_s]` that is not hidden; each hidden reading is estimated at its time (after
/// the readings the filter takes stamped at the same time) and gives
/// `|z| = |v − mean| / √(variance + reading noise)`. `model` should be fitted on readings
/// before the earliest `hidden_from` only (the errors are then out of sample). Sensors beyond
/// the model's and non-finite values are skipped; a zero standard deviation gives no error.
pub fn backtest_errors_hidden(
    model: &DynamicModel,
    series: &[SensorSeries<'_>],
    start_s: i64,
    hidden_from: &[Option<i64>],
    end_s: i64,
) -> Vec<f64> {
    let n = model.len().min(series.len());
    // (time, 0 = a reading the filter takes / 1 = a reading to estimate, sensor, value)
    let mut events: Vec<(i64, u8, usize, f64)> = Vec::new();
    for (i, s) in series.iter().enumerate().take(n) {
        let hidden = hidden_from.get(i).copied().flatten();
        for (&t, &v) in s.times.iter().zip(s.values) {
            if t < start_s || t > end_s || !v.is_finite() {
                continue;
            }
            let kind = u8::from(hidden.is_some_and(|h| t >= h));
            events.push((t, kind, i, v));
        }
    }
    events.sort_by(|a, b| a.0.cmp(&b.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
    let mut filter = model.filter(start_s as f64);
    let mut errors = Vec::new();
    for (t, kind, i, v) in events {
        filter.advance(t as f64);
        if kind == 0 {
            filter.observe(i, v);
        } else {
            let (mean, var) = filter.estimate(i);
            let sd = (var + model.noise()).sqrt();
            if sd > 0.0 && mean.is_finite() {
                errors.push((v - mean).abs() / sd);
            }
        }
    }
    errors
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interval_multiplier_is_the_conformal_quantile() {
        let errors: Vec<f64> = (1..=99).rev().map(|i| f64::from(i) / 100.0).collect();
        assert_eq!(interval_multiplier(&errors), 0.90);
        let mut with_nan = errors.clone();
        with_nan.push(f64::NAN);
        assert_eq!(interval_multiplier(&with_nan), 0.90);
        // n = 19: ⌈0.9·20⌉ = 18 → the 18th smallest; fewer than 20 → Z90.
        assert_eq!(interval_multiplier(&errors[..19]), Z90);
        let twenty: Vec<f64> = (1..=20).map(f64::from).collect();
        assert_eq!(interval_multiplier(&twenty), 19.0);
        assert_eq!(interval_multiplier(&[]), Z90);
    }

    /// Two sensors 1 apart read at `times`, with values `a` and `b`.
    fn two_sensors<'a>(times: &'a [i64], a: &'a [f64], b: &'a [f64]) -> [SensorSeries<'a>; 2] {
        [
            SensorSeries {
                position: [0.0, 0.0],
                times,
                values: a,
            },
            SensorSeries {
                position: [1.0, 0.0],
                times,
                values: b,
            },
        ]
    }

    #[test]
    fn backtest_stretches_step_back_by_a_span() {
        assert_eq!(
            backtest_stretches(365, 21, 182),
            vec![(344, 365), (323, 344), (302, 323), (281, 302)]
        );
        assert_eq!(backtest_stretches(1001, 500, 500), vec![(501, 1001)]);
        assert_eq!(backtest_stretches(100, 30, 80), Vec::<(i64, i64)>::new());
        assert!(backtest_stretches(100, 0, 0).is_empty());
    }

    /// Two sensors, perfectly known model: sensor 0 read through the back-test, sensor 1
    /// estimated. The errors are the standardised distances of sensor 1's values from the
    /// filter's estimate, and only back-test readings of the unread sensor give one.
    #[test]
    fn backtest_estimates_the_unread_sensors_after_the_split() {
        let model =
            DynamicModel::new(vec![0.0, 0.0], vec![1.0, 0.9, 0.9, 1.0], 0.5, 1.0, 0.01).unwrap();
        let times: Vec<i64> = (0..10).collect();
        let a: Vec<f64> = times.iter().map(|&t| (t as f64 * 0.7).sin()).collect();
        let b: Vec<f64> = times
            .iter()
            .map(|&t| (t as f64 * 0.7).sin() + 0.3)
            .collect();
        let series = two_sensors(&times, &a, &b);
        let z = backtest_errors(&model, &series, 0, 6, 9, &[true, false]);
        assert_eq!(z.len(), 4, "sensor 1 at t = 6, 7, 8, 9");
        // The same by hand for the first of them.
        let mut f = model.filter(0.0);
        for t in 0..6usize {
            f.advance(t as f64);
            f.observe(0, a[t]);
            f.observe(1, b[t]);
        }
        f.advance(6.0);
        f.observe(0, a[6]);
        let (m, v) = f.estimate(1);
        assert!((z[0] - (b[6] - m).abs() / (v + 0.01).sqrt()).abs() < 1e-12);
        // Everything read: nothing to back-test.
        assert!(backtest_errors(&model, &series, 0, 6, 9, &[true, true]).is_empty());
        // Sensors beyond the model's are ignored.
        assert_eq!(
            backtest_errors(&model, &series[..1], 0, 6, 9, &[false]).len(),
            4
        );
    }

    /// Hiding each sensor from its own time: a sensor hidden from the split is the unread
    /// sensor of [`backtest_errors`]; one hidden later gives errors only from then on.
    #[test]
    fn hidden_from_generalises_the_unread_sensors() {
        let model =
            DynamicModel::new(vec![0.0, 0.0], vec![1.0, 0.8, 0.8, 1.0], 0.6, 1.0, 0.02).unwrap();
        let times: Vec<i64> = (0..12).collect();
        let a: Vec<f64> = times.iter().map(|&t| (t as f64 * 0.5).cos()).collect();
        let b: Vec<f64> = times.iter().map(|&t| (t as f64 * 0.4).sin()).collect();
        let series = two_sensors(&times, &a, &b);
        let unread = backtest_errors(&model, &series, 0, 5, 11, &[true, false]);
        let hidden = backtest_errors_hidden(&model, &series, 0, &[None, Some(5)], 11);
        assert_eq!(unread, hidden);
        let later = backtest_errors_hidden(&model, &series, 0, &[None, Some(9)], 11);
        assert_eq!(later.len(), 3, "sensor 1 at t = 9, 10, 11");
        let both = backtest_errors_hidden(&model, &series, 0, &[Some(10), Some(9)], 11);
        assert_eq!(both.len(), 5);
        assert!(backtest_errors_hidden(&model, &series, 0, &[None, None], 11).is_empty());
    }

    proptest::proptest! {
        /// One error per hidden finite reading inside the stretch of a sensor the model
        /// knows, every error finite and non-negative; hiding a sensor later never gives it
        /// more errors.
        #[test]
        fn one_error_per_hidden_reading(
            n in 1usize..5,
            len in 1usize..30,
            hide in proptest::collection::vec(proptest::option::of(0i64..35), 5),
            start in 0i64..10,
            end in 0i64..35,
            gaps in proptest::collection::vec(proptest::bool::weighted(0.2), 150),
        ) {
            let mut cov = vec![0.0; n * n];
            for i in 0..n {
                for j in 0..n {
                    cov[i * n + j] = if i == j { 1.0 } else { 0.5 };
                }
            }
            let model = DynamicModel::new(vec![0.0; n], cov, 0.8, 1.0, 0.01).unwrap();
            let times: Vec<i64> = (0..len as i64).collect();
            let values: Vec<Vec<f64>> = (0..5)
                .map(|i| {
                    (0..len)
                        .map(|t| if gaps[i * 30 + t] { f64::NAN } else { (t as f64 * 0.3 + i as f64).sin() })
                        .collect()
                })
                .collect();
            // One more series than the model knows, so the sensors beyond it are exercised.
            let series: Vec<SensorSeries<'_>> = values
                .iter()
                .take(n + 1)
                .map(|v| SensorSeries { position: [0.0, 0.0], times: &times, values: v })
                .collect();
            let z = backtest_errors_hidden(&model, &series, start, &hide, end);
            let expected: usize = (0..n)
                .map(|i| {
                    (0..len)
                        .filter(|&t| {
                            let t64 = t as i64;
                            t64 >= start
                                && t64 <= end
                                && values[i][t].is_finite()
                                && hide[i].is_some_and(|h| t64 >= h)
                        })
                        .count()
                })
                .sum();
            proptest::prop_assert_eq!(z.len(), expected);
            proptest::prop_assert!(z.iter().all(|e| e.is_finite() && *e >= 0.0));
            let later: Vec<Option<i64>> = hide.iter().map(|h| h.map(|h| h + 3)).collect();
            let fewer = backtest_errors_hidden(&model, &series, start, &later, end);
            proptest::prop_assert!(fewer.len() <= z.len());
        }
    }
}
