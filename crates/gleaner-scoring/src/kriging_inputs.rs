//! The kriging estimators' inputs at one time and the neighbours' known changes the kriging
//! of changes uses (docs/method.md §7), for [`estimate_with`](crate::estimate_with).

use gleaner_field::UnixSeconds;
use gleaner_kriging::{
    Change, FieldModel, IncrementModel, Mean, Observation, estimate_change, krige_with,
};

use crate::choices::Estimator;

/// One sensor's readings: times (seconds, ascending) and values.
pub(crate) type Column = (Vec<UnixSeconds>, Vec<f64>);

/// Per sensor: the times (seconds, ascending) and values of its readings.
pub(crate) type Columns = Vec<Column>;

/// At most this many (sensor, unseen interval) pairs are back-tested for the calibration of
/// the kriging of changes' intervals ([`interval_multiplier`]).
pub const BACKTEST_SAMPLES: usize = 160;

/// Sensors whose latest reading is within this of the newest one count as read last, s
/// (readings of one visit are stamped within minutes of each other).
pub const BACKTEST_FRESH_S: i64 = 3_600;

pub use gleaner_kriging::interval_multiplier;

/// Fewest candidate neighbours (the nearest read after the target) the kriging of changes
/// weighs for each estimate, before choosing the most informative of them; at least 4 times
/// the neighbours asked for. Bounds the cost on large networks.
pub const CHANGE_CANDIDATES: usize = 64;

pub use gleaner_kriging::Z90;

/// A sensor's latest known reading: time (s) and value, if any.
pub(crate) type Latest = Option<(UnixSeconds, f64)>;

/// What the kriging estimators need at one time: the sensors' positions (east/north m), the
/// fitted models, each sensor's latest known reading (time s, value) and, for the kriging of
/// changes, every sensor's readings in the change window (times ascending, s).
pub(crate) struct KrigingInputs<'a> {
    positions: &'a [[f64; 2]],
    /// Each sensor's cell (an index of the field's cells): cell-mates are read together.
    cells: &'a [usize],
    model: &'a FieldModel,
    changes: &'a IncrementModel,
    latest: &'a [Latest],
    series: &'a [Column],
    observations: Vec<Observation>,
    at: UnixSeconds,
    neighbours: usize,
    estimator: Estimator,
}

impl<'a> KrigingInputs<'a> {
    pub(crate) fn new(
        (positions, cells): (&'a [[f64; 2]], &'a [usize]),
        (model, changes): (&'a FieldModel, &'a IncrementModel),
        (latest, series): (&'a [Latest], &'a [Column]),
        at: UnixSeconds,
        (neighbours, estimator): (usize, Estimator),
    ) -> Self {
        let observations: Vec<Observation> = latest
            .iter()
            .zip(positions)
            .zip(&model.means)
            .filter_map(|((l, p), mean)| {
                l.map(|(t, v)| Observation {
                    position: *p,
                    age_s: (at - t).max(0) as f64,
                    residual: v - mean,
                })
            })
            .collect();
        Self {
            positions,
            cells,
            model,
            changes,
            latest,
            series,
            observations,
            at,
            neighbours,
            estimator,
        }
    }

    /// Sensor `k`'s estimate (the modality's unit) and variance (its square) by the kriging
    /// of changes or of levels; kriging of levels (ordinary) for a sensor never read and for
    /// [`Estimator::Dynamic`] (whose caller answers from the filter).
    pub(crate) fn estimate(&self, k: usize) -> (f64, f64) {
        // Kriging of levels: the estimator itself, or for a sensor never read, ordinary.
        let level_mean = match self.estimator {
            Estimator::Levels(mean) => mean,
            Estimator::Changes | Estimator::Dynamic => Mean::Unknown,
        };
        match (self.estimator, self.latest[k]) {
            (Estimator::Levels(_) | Estimator::Dynamic, _) | (Estimator::Changes, None) => {
                let e = krige_with(
                    &self.model.covariance,
                    &self.observations,
                    self.positions[k],
                    self.neighbours,
                    level_mean,
                );
                (self.model.means[k] + e.residual, e.variance)
            }
            (Estimator::Changes, Some((t_k, v_k))) => {
                let known = neighbour_changes(
                    self.series,
                    self.positions,
                    (k, t_k),
                    self.at,
                    CHANGE_CANDIDATES.max(4 * self.neighbours),
                    |_| false,
                );
                let e = estimate_change(
                    self.changes,
                    &known,
                    self.positions[k],
                    ((t_k - self.at) as f64, 0.0),
                    self.neighbours,
                );
                (v_k + e.change, e.variance)
            }
        }
    }

    /// The kriging of changes' standardised out-of-sample errors `|z|`, for the calibration
    /// of its intervals: the sensors read last (within [`BACKTEST_FRESH_S`] of the latest
    /// reading), each estimated at its latest reading as if it had been unseen as long as
    /// the sensors unseen now are (their ages, up to [`BACKTEST_SAMPLES`] pairs in all, the
    /// ages evenly spread over their sorted list): from its reading at or before that long
    /// before and the changes then known of the sensors outside its cell (cell-mates are read
    /// together, so they are never known when it is not), against the reading:
    /// `|v − v̂| / sd`. Empty for the other estimators, or when no sensor is unseen now.
    fn backtest(&self) -> Vec<f64> {
        if self.estimator != Estimator::Changes {
            return Vec::new();
        }
        let Some(newest) = self.latest.iter().flatten().map(|l| l.0).max() else {
            return Vec::new();
        };
        let mut ages: Vec<i64> = self
            .latest
            .iter()
            .flatten()
            .map(|l| self.at - l.0)
            .filter(|&a| a > self.at - newest + BACKTEST_FRESH_S)
            .collect();
        ages.sort_unstable();
        let targets: Vec<usize> = (0..self.latest.len())
            .filter(|&k| self.latest[k].is_some_and(|l| l.0 >= newest - BACKTEST_FRESH_S))
            .collect();
        if ages.is_empty() || targets.is_empty() {
            return Vec::new();
        }
        let per = (BACKTEST_SAMPLES / targets.len()).clamp(1, ages.len());
        let picks: Vec<i64> = (0..per)
            .map(|i| ages[((2 * i + 1) * ages.len()) / (2 * per)])
            .collect();
        let mut errors = Vec::new();
        for &k in &targets {
            let (times, values) = &self.series[k];
            let (Some(&tau), Some(&v)) = (times.last(), values.last()) else {
                continue;
            };
            for &age in &picks {
                // The same gap before this sensor's last reading as the unseen sensor's
                // before the estimation time.
                let gap = age - (self.at - tau);
                let start = times.partition_point(|&t| t <= tau - gap);
                if start == 0 {
                    continue;
                }
                let (t0, v0) = (times[start - 1], values[start - 1]);
                let known = neighbour_changes(
                    self.series,
                    self.positions,
                    (k, t0),
                    tau,
                    CHANGE_CANDIDATES.max(4 * self.neighbours),
                    |j| self.cells[j] == self.cells[k],
                );
                let e = estimate_change(
                    self.changes,
                    &known,
                    self.positions[k],
                    ((t0 - tau) as f64, 0.0),
                    self.neighbours,
                );
                if e.variance > 0.0 && e.variance.is_finite() {
                    errors.push((v - v0 - e.change).abs() / e.variance.sqrt());
                }
            }
        }
        errors
    }

    /// The multiplier of this time's 90% intervals for sensor estimates by the kriging of
    /// changes ([`interval_multiplier`] of [`Self::backtest`]).
    pub(crate) fn multiplier(&self) -> f64 {
        interval_multiplier(&self.backtest())
    }

    /// Sensor `k`'s 90% half-width for an estimate of variance `variance` (the unit
    /// squared): `q`·sd for the kriging of changes from a reading, `Z90`·sd otherwise.
    pub(crate) fn half90(&self, k: usize, variance: f64, q: f64) -> f64 {
        let calibrated = self.estimator == Estimator::Changes && self.latest[k].is_some();
        (if calibrated { q } else { Z90 }) * variance.max(0.0).sqrt()
    }
}

/// The changes known over the unseen interval of sensor `k` (last read at `t_k`, estimated
/// at `at`), times in seconds relative to `at`: for the `max_candidates` sensors nearest to it
/// among those read after `t_k` and by `at` (other than those `skip` names; `k` itself is
/// always skipped), the latest reading by `at` minus the reading at or just before `t_k` (the
/// first reading in `series` when there is none by then). `series` per sensor, ascending;
/// positions metres.
fn neighbour_changes(
    series: &[(Vec<UnixSeconds>, Vec<f64>)],
    positions: &[[f64; 2]],
    (k, t_k): (usize, UnixSeconds),
    at: UnixSeconds,
    max_candidates: usize,
    skip: impl Fn(usize) -> bool,
) -> Vec<Change> {
    let p = positions[k];
    // The index of each sensor's latest reading by `at`, if any.
    let last = |times: &[UnixSeconds]| times.partition_point(|&t| t <= at).checked_sub(1);
    // Squared distance and index of every sensor read after t_k (and by `at`).
    let mut candidates: Vec<(f64, usize)> = series
        .iter()
        .enumerate()
        .filter(|(j, (times, _))| {
            *j != k && !skip(*j) && last(times.as_slice()).is_some_and(|b| times[b] > t_k)
        })
        .map(|(j, _)| {
            let q = positions[j];
            ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2), j)
        })
        .collect();
    let m = max_candidates.max(1);
    if candidates.len() > m {
        candidates.select_nth_unstable_by(m - 1, |a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        candidates.truncate(m);
    }
    candidates.sort_by_key(|c| c.1);
    let mut out = Vec::with_capacity(candidates.len());
    for (_, j) in candidates {
        let (times, values) = &series[j];
        let Some(end) = last(times.as_slice()) else {
            continue;
        };
        let (b, vb) = (times[end], values[end]);
        // Readings at or before t_k: the latest of them, else the first reading.
        let i = times.partition_point(|&t| t <= t_k).saturating_sub(1);
        let (a, va) = (times[i], values[i]);
        if a >= b {
            continue;
        }
        out.push(Change {
            position: positions[j],
            from_s: (a - at) as f64,
            to_s: (b - at) as f64,
            change: vb - va,
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const DAY: i64 = 86_400;

    #[test]
    fn neighbour_changes_cover_the_targets_unseen_interval() {
        let at = 100 * DAY;
        let series = vec![
            // 0: the target, last read on day 90.
            (vec![89 * DAY, 90 * DAY], vec![0.20, 0.21]),
            // 1: read daily to day 99: change from day 90 to day 99.
            (
                (85..100).map(|d| d * DAY).collect(),
                (85..100).map(|d| 0.30 + 0.01 * (d - 85) as f64).collect(),
            ),
            // 2: last read on day 90 too: nothing known after the target's last reading.
            (vec![88 * DAY, 90 * DAY], vec![0.1, 0.4]),
            // 3: missing on day 90: from day 87 (the latest before) to day 95.
            (vec![87 * DAY, 95 * DAY], vec![0.10, 0.15]),
            // 4: first read after day 90 (day 92) and again on day 96.
            (vec![92 * DAY, 96 * DAY], vec![0.50, 0.45]),
            // 5: never read.
            (vec![], vec![]),
        ];
        let positions: Vec<[f64; 2]> = (0..6).map(|k| [10.0 * k as f64, 0.0]).collect();
        let c = neighbour_changes(&series, &positions, (0, 90 * DAY), at, 64, |_| false);
        // Only the nearest 2 candidates: sensors 1 and 3 (sensor 2 knows nothing newer).
        let near = neighbour_changes(&series, &positions, (0, 90 * DAY), at, 2, |_| false);
        assert_eq!(near.len(), 2, "{near:?}");
        assert_eq!(
            (near[0].position, near[1].position),
            ([10.0, 0.0], [30.0, 0.0])
        );
        assert_eq!(c.len(), 3, "{c:?}");
        let rel = |d: i64| ((d * DAY) - at) as f64;
        assert_eq!((c[0].from_s, c[0].to_s), (rel(90), rel(99)));
        assert!((c[0].change - 0.09).abs() < 1e-12);
        assert_eq!(c[0].position, [10.0, 0.0]);
        assert_eq!((c[1].from_s, c[1].to_s), (rel(87), rel(95)));
        assert!((c[1].change - 0.05).abs() < 1e-12);
        assert_eq!((c[2].from_s, c[2].to_s), (rel(92), rel(96)));
        assert!((c[2].change + 0.05).abs() < 1e-12);
        // A target read after everyone else: no neighbour knows more.
        assert!(
            neighbour_changes(&series, &positions, (1, 99 * DAY), at, 64, |_| false).is_empty()
        );
    }

    /// The back-test replays age differences, not ages: the same reads give the same
    /// multiplier bit for bit at any later estimation time (what the campaign's kept
    /// multiplier relies on), and a changed reading changes it.
    #[test]
    fn the_multiplier_does_not_depend_on_the_estimation_time() {
        use gleaner_kriging::{Covariance, Variogram};
        let n = 30;
        // Sensors on a line, read daily with staggered last readings: 0..10 read on day 99
        // (the freshest), the others last read 1..20 days before.
        let positions: Vec<[f64; 2]> = (0..n)
            .map(|k| [37.0 * k as f64, 11.0 * (k % 3) as f64])
            .collect();
        let cells: Vec<usize> = (0..n).map(|k| k / 2).collect();
        let series: Vec<Column> = (0..n)
            .map(|k| {
                let last = if k < 10 { 99 } else { 99 - (k as i64 - 9) };
                let days: Vec<i64> = (40..=last).collect();
                let values = days
                    .iter()
                    .map(|&d| {
                        0.25 + 0.002 * ((d * 7 + k as i64 * 13) % 17) as f64 + 0.001 * k as f64
                    })
                    .collect();
                (days.iter().map(|d| d * DAY).collect(), values)
            })
            .collect();
        let latest: Vec<Latest> = series
            .iter()
            .map(|(t, v)| Some((*t.last().unwrap(), *v.last().unwrap())))
            .collect();
        let model = FieldModel {
            covariance: Covariance {
                sill: 1e-3,
                nugget: 1e-4,
                range_m: 500.0,
                time_scale_s: 20.0 * DAY as f64,
                temporal_share: 0.9,
            },
            means: vec![0.27; n],
        };
        let vg = |nugget: f64, partial: f64| Variogram {
            nugget,
            partial,
            scale_s: 10.0 * DAY as f64,
        };
        let changes = IncrementModel::new(vg(1e-6, 1e-4), 400.0, vg(1e-6, 5e-5)).unwrap();
        let q_at = |at: UnixSeconds, latest: &[Latest], series: &[Column]| {
            KrigingInputs::new(
                (&positions, &cells),
                (&model, &changes),
                (latest, series),
                at,
                (8, Estimator::Changes),
            )
            .multiplier()
        };
        let q = q_at(100 * DAY, &latest, &series);
        assert_ne!(
            q, Z90,
            "enough back-tested errors for a calibrated multiplier"
        );
        for at in [100 * DAY + 1, 101 * DAY, 130 * DAY + 3_601] {
            assert_eq!(q_at(at, &latest, &series).to_bits(), q.to_bits(), "at {at}");
        }
        let mut other = series.clone();
        *other[3].1.last_mut().unwrap() += 0.05;
        let mut other_latest = latest.clone();
        other_latest[3] = Some((99 * DAY, *other[3].1.last().unwrap()));
        assert_ne!(
            q_at(100 * DAY, &other_latest, &other).to_bits(),
            q.to_bits()
        );
    }
}
