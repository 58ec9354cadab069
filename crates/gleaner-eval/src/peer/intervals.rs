//! The dynamic model's calibrated 90% intervals on the protocol: the back-test origins, the
//! multiplier for a tour ([`Fitted::interval_multiplier`]) and the coverage it reaches.

use std::ops::Range;

use super::{Fitted, Outcome, Planner, sensor_series};

/// The 90% intervals' coverage of the unvisited sensors' test values.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Coverage {
    /// Share inside the calibrated interval `mean ± q·sd` (NaN: nothing judged).
    pub calibrated: f64,
    /// Share inside the Gaussian interval `mean ± 1.645·sd`.
    pub gaussian: f64,
    /// The calibrated multiplier `q`.
    pub multiplier: f64,
}

impl Default for Coverage {
    /// Nothing judged: NaN shares, the Gaussian multiplier.
    fn default() -> Self {
        Self {
            calibrated: f64::NAN,
            gaussian: f64::NAN,
            multiplier: gleaner_kriging::Z90,
        }
    }
}

/// Most back-test origins per fit ([`backtest_origins`]).
pub const BACKTEST_ORIGINS: usize = gleaner_kriging::BACKTEST_STRETCHES;

/// The interval back-tests' origins in `train` for stretches of `rows` rows: the last
/// stretch of the training rows first, then each `rows` earlier, at most
/// [`BACKTEST_ORIGINS`], every origin leaving at least half the training rows before it to
/// fit on ([`gleaner_kriging::backtest_stretches`] in rows). Empty when `rows` is 0.
pub fn backtest_origins(train: &Range<usize>, rows: usize) -> Vec<usize> {
    if rows == 0 || train.len() < 2 {
        return Vec::new();
    }
    let earliest = train.start + train.len() / 2;
    gleaner_kriging::backtest_stretches(train.end as i64, rows as i64, earliest as i64)
        .into_iter()
        .map(|(start, _)| start as usize)
        .collect()
}

/// The mean over `outcomes` of `planner` of a coverage `pick`s (finite ones only; NaN when
/// there is none).
pub fn mean_coverage<'a>(
    outcomes: impl IntoIterator<Item = &'a Outcome>,
    planner: Planner,
    pick: fn(&Outcome) -> f64,
) -> f64 {
    let c: Vec<f64> = outcomes
        .into_iter()
        .filter(|o| o.planner == planner)
        .map(pick)
        .filter(|c| c.is_finite())
        .collect();
    if c.is_empty() {
        f64::NAN
    } else {
        c.iter().sum::<f64>() / c.len() as f64
    }
}

impl Fitted {
    /// The calibrated 90% interval's multiplier for `visited`: the split-conformal quantile
    /// ([`gleaner_kriging::interval_multiplier`]) of the standardised errors of back-tests on
    /// the training rows — at each origin the dynamic model fitted on the rows before it is
    /// run over the next rows reading only the visited sensors, as the test will
    /// ([`gleaner_kriging::backtest_errors`]) — and never below the Gaussian
    /// [`gleaner_kriging::Z90`] (a back-test can only widen the model's own interval).
    pub fn interval_multiplier(&self, visited: &[usize]) -> f64 {
        let n = self.matrix.labels.len();
        let mut read = vec![false; n];
        for &v in visited {
            if v < n {
                read[v] = true;
            }
        }
        let train = self.protocol.train.clone();
        let (times, values) = &self.train_series;
        let input = sensor_series(times, values);
        let t = &self.matrix.times;
        let mut errors = Vec::new();
        for (origin, model) in &self.backtests {
            let last = (origin + self.backtest_rows).min(train.end) - 1;
            errors.extend(gleaner_kriging::backtest_errors(
                model,
                &input,
                t[train.start],
                t[*origin],
                t[last],
                &read,
            ));
        }
        gleaner_kriging::interval_multiplier(&errors).max(gleaner_kriging::Z90)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Origins: the last stretch first, each a stretch earlier, at most four, none with less
    /// than half the training rows before it.
    #[test]
    fn backtest_origins_step_back_by_a_stretch() {
        assert_eq!(backtest_origins(&(0..365), 21), vec![344, 323, 302, 281]);
        assert_eq!(backtest_origins(&(0..1001), 500), vec![501]);
        assert_eq!(backtest_origins(&(10..110), 30), vec![80]);
        assert_eq!(backtest_origins(&(0..10), 0), Vec::<usize>::new());
        assert_eq!(backtest_origins(&(0..1), 1), Vec::<usize>::new());
    }
}
