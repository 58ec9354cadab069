//! Event detection judged against ground truth (pure): the paper's own-history z-score
//! (docs/method.md §2's anomaly A on a one-sensor cell) and a neighbour-relative z-score, flagged at
//! |z| > threshold on every station-day, scored against the farm's known events.
//!
//! The neighbour-relative measure: each day, the station's residual `r_i(t) = x_i(t) -
//! median_j x_j(t)` over its `k` nearest stations that reported that day (at least two), then
//! the same own-history z-score applied to the residual series. Weather moves every station
//! together, so it cancels in the residual; a leak or dry patch moves a few stations away from
//! the rest and stands out.

use gleaner_field::LocalPoint;

use crate::SynthFarm;
use crate::farm::EventKind;

/// Own-history z-score of every day of `series`: `(x[t] - mean) / (sd + 1e-6)` with the mean
/// and sample sd (n - 1) of all present values before day `t`. NaN on missing days and on
/// days with fewer than `min_history` (at least 2) earlier present values.
pub fn own_history_z(series: &[f64], min_history: usize) -> Vec<f64> {
    let (mut n, mut mean, mut m2) = (0usize, 0.0f64, 0.0f64);
    let min = min_history.max(2);
    series
        .iter()
        .map(|&x| {
            if x.is_nan() {
                return f64::NAN;
            }
            let z = if n >= min {
                let sd = (m2 / (n - 1) as f64).sqrt();
                (x - mean) / (sd + 1e-6)
            } else {
                f64::NAN
            };
            n += 1;
            let d = x - mean;
            mean += d / n as f64;
            m2 += d * (x - mean);
            z
        })
        .collect()
}

/// Indices of the `k` nearest other stations of every station (ties by index).
pub fn nearest_neighbours(positions: &[LocalPoint], k: usize) -> Vec<Vec<usize>> {
    (0..positions.len())
        .map(|i| {
            let mut others: Vec<(f64, usize)> = (0..positions.len())
                .filter(|&j| j != i)
                .map(|j| (positions[i].distance(&positions[j]), j))
                .collect();
            others.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            others.into_iter().take(k).map(|(_, j)| j).collect()
        })
        .collect()
}

/// The median of `xs` (sorted in place), in the unit of the values; NaN when `xs` is empty.
pub(crate) fn median(xs: &mut [f64]) -> f64 {
    if xs.is_empty() {
        return f64::NAN;
    }
    xs.sort_by(f64::total_cmp);
    let n = xs.len();
    if n % 2 == 1 {
        xs[n / 2]
    } else {
        0.5 * (xs[n / 2 - 1] + xs[n / 2])
    }
}

/// Residual of every station against the median of its neighbours that reported the same
/// day (`neighbours[i]` from [`nearest_neighbours`]); NaN when the station is missing or
/// fewer than two neighbours reported.
pub fn neighbour_residuals(series: &[Vec<f64>], neighbours: &[Vec<usize>]) -> Vec<Vec<f64>> {
    let mut buf = Vec::new();
    series
        .iter()
        .enumerate()
        .map(|(i, s)| {
            s.iter()
                .enumerate()
                .map(|(t, &x)| {
                    if x.is_nan() {
                        return f64::NAN;
                    }
                    buf.clear();
                    buf.extend(
                        neighbours[i]
                            .iter()
                            .filter_map(|&j| series[j].get(t).copied())
                            .filter(|v| !v.is_nan()),
                    );
                    if buf.len() < 2 {
                        f64::NAN
                    } else {
                        x - median(&mut buf)
                    }
                })
                .collect()
        })
        .collect()
}

/// Neighbour-relative z-score of every station-day: [`own_history_z`] of
/// [`neighbour_residuals`] over the `k` nearest stations.
pub fn neighbour_z(
    series: &[Vec<f64>],
    positions: &[LocalPoint],
    k: usize,
    min_history: usize,
) -> Vec<Vec<f64>> {
    let nb = nearest_neighbours(positions, k);
    neighbour_residuals(series, &nb)
        .iter()
        .map(|r| own_history_z(r, min_history))
        .collect()
}

/// Own-history z-score of every station-day (see [`own_history_z`]).
pub fn own_z(series: &[Vec<f64>], min_history: usize) -> Vec<Vec<f64>> {
    series
        .iter()
        .map(|s| own_history_z(s, min_history))
        .collect()
}

/// What a station-day is in the ground truth.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DayTruth {
    /// Touched by the active phase of event number `usize` (a leak or dry patch).
    Event(usize),
    /// No event: a flag here is a false alarm.
    Quiet,
    /// Neither (an event's fading tail, a failing sensor): not scored.
    Ignore,
}

/// Detection scores of one measure.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct DetectionScore {
    /// Scored event station-days (z defined).
    pub event_days: usize,
    /// Of which flagged.
    pub event_hits: usize,
    /// Scored quiet station-days.
    pub quiet_days: usize,
    /// Of which flagged (false alarms).
    pub quiet_hits: usize,
    /// Events with at least one scored station-day.
    pub events: usize,
    /// Events with at least one flagged station-day.
    pub events_caught: usize,
    /// Sum over caught events of the days from the event's start to its first flag.
    pub delay_days_sum: f64,
}

impl DetectionScore {
    /// Fraction of event station-days flagged.
    pub fn detection_rate(&self) -> f64 {
        ratio(self.event_hits, self.event_days)
    }
    /// Fraction of quiet station-days flagged.
    pub fn false_alarm_rate(&self) -> f64 {
        ratio(self.quiet_hits, self.quiet_days)
    }
    /// Fraction of events caught at least once.
    pub fn event_catch_rate(&self) -> f64 {
        ratio(self.events_caught, self.events)
    }
    /// Mean days from an event's start to its first flag, over caught events.
    pub fn mean_delay_days(&self) -> f64 {
        if self.events_caught == 0 {
            f64::NAN
        } else {
            self.delay_days_sum / self.events_caught as f64
        }
    }
    /// Adds another score's counts to this one.
    pub fn add(&mut self, o: &DetectionScore) {
        self.event_days += o.event_days;
        self.event_hits += o.event_hits;
        self.quiet_days += o.quiet_days;
        self.quiet_hits += o.quiet_hits;
        self.events += o.events;
        self.events_caught += o.events_caught;
        self.delay_days_sum += o.delay_days_sum;
    }
}

fn ratio(a: usize, b: usize) -> f64 {
    if b == 0 {
        f64::NAN
    } else {
        a as f64 / b as f64
    }
}

/// Scores `z[sensor][day]` flagged at `|z| > threshold` against `truth[sensor][day]`;
/// `event_start[e]` is event `e`'s first day (for the delay).
pub fn score_detection(
    z: &[Vec<f64>],
    truth: &[Vec<DayTruth>],
    event_start: &[usize],
    threshold: f64,
) -> DetectionScore {
    let mut s = DetectionScore::default();
    let mut first_flag = vec![None::<usize>; event_start.len()];
    let mut scored = vec![false; event_start.len()];
    for (zs, ts) in z.iter().zip(truth) {
        for (d, (&zd, &td)) in zs.iter().zip(ts).enumerate() {
            if zd.is_nan() {
                continue;
            }
            let flag = zd.abs() > threshold;
            match td {
                DayTruth::Event(e) => {
                    s.event_days += 1;
                    scored[e] = true;
                    if flag {
                        s.event_hits += 1;
                        first_flag[e] = Some(first_flag[e].map_or(d, |f: usize| f.min(d)));
                    }
                }
                DayTruth::Quiet => {
                    s.quiet_days += 1;
                    s.quiet_hits += usize::from(flag);
                }
                DayTruth::Ignore => {}
            }
        }
    }
    s.events = scored.iter().filter(|&&x| x).count();
    for (e, f) in first_flag.iter().enumerate() {
        if let Some(f) = f {
            s.events_caught += 1;
            s.delay_days_sum += f.saturating_sub(event_start[e]) as f64;
        }
    }
    s
}

impl SynthFarm {
    /// Ground truth per station-day of a daily-sampled farm (days = steps): leak and dry-patch
    /// days from start to end are [`DayTruth::Event`], the 30 days after an end (the effect
    /// fading) and every day of a failing sensor from its start to its replacement (30 days
    /// after its end) are [`DayTruth::Ignore`], the
    /// rest [`DayTruth::Quiet`]. Also returns each event's first day (failing sensors too).
    pub fn day_truth(&self) -> (Vec<Vec<DayTruth>>, Vec<usize>) {
        let days = self.times.len();
        let first = self.times.first().copied().unwrap_or(0);
        let step = self
            .times
            .windows(2)
            .next()
            .map_or(86_400, |w| (w[1] - w[0]).max(1));
        let day_of = |t: i64| ((t - first).max(0) / step) as usize;
        let mut truth = vec![vec![DayTruth::Quiet; days]; self.sensors.len()];
        let mut starts = Vec::with_capacity(self.events.len());
        for (e, ev) in self.events.iter().enumerate() {
            let (from, to) = (day_of(ev.start), day_of(ev.end));
            starts.push(from);
            for &s in &ev.affected {
                let row = &mut truth[s];
                match ev.kind {
                    EventKind::Leak | EventKind::DryPatch => {
                        for d in row.iter_mut().take(to).skip(from) {
                            *d = DayTruth::Event(e);
                        }
                        for d in row.iter_mut().take(to + 30).skip(to) {
                            if *d == DayTruth::Quiet {
                                *d = DayTruth::Ignore;
                            }
                        }
                    }
                    EventKind::SensorDrift | EventKind::SensorStuck => {
                        for d in row.iter_mut().take(to + 30).skip(from) {
                            if *d == DayTruth::Quiet {
                                *d = DayTruth::Ignore;
                            }
                        }
                    }
                }
            }
        }
        (truth, starts)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const NAN: f64 = f64::NAN;

    #[test]
    fn own_history_z_by_hand() {
        // Day 3: history 1, 2, 3 -> mean 2, sd 1 -> z = (6 - 2) / 1.
        let z = own_history_z(&[1.0, 2.0, NAN, 3.0, 6.0], 3);
        assert!(z[0].is_nan() && z[1].is_nan() && z[2].is_nan() && z[3].is_nan());
        assert!((z[4] - 4.0 / (1.0 + 1e-6)).abs() < 1e-9, "{z:?}");
    }

    #[test]
    fn neighbour_residual_cancels_shared_weather() {
        let p = |e: f64| LocalPoint::new(e, 0.0);
        let positions = [p(0.0), p(10.0), p(20.0), p(1000.0)];
        let nb = nearest_neighbours(&positions, 2);
        assert_eq!(nb[0], vec![1, 2]);
        assert_eq!(nb[3], vec![2, 1]);
        // Everyone shares the weather w; station 0 gets +1 on the last day.
        let w = [0.0, 5.0, -3.0, 2.0];
        let mut series: Vec<Vec<f64>> = (0..4)
            .map(|k| w.iter().map(|x| x + k as f64).collect())
            .collect();
        series[0][3] += 1.0;
        series[2][1] = NAN;
        let r = neighbour_residuals(&series, &nb);
        // Station 0 against stations 1, 2: median of (1 + w, 2 + w) = 1.5 + w.
        assert_eq!(r[0][0], -1.5);
        assert_eq!(r[0][3], -0.5);
        // Day 1: station 2 missing, one neighbour left: undefined.
        assert!(r[0][1].is_nan());
        assert!(r[2][1].is_nan());
    }

    #[test]
    fn scores_count_hits_false_alarms_and_delay() {
        use DayTruth::*;
        let z = vec![vec![NAN, 0.5, 4.0, 5.0, 0.0], vec![4.0, 0.0, 0.0, 0.0, 9.0]];
        let truth = vec![
            vec![Quiet, Event(0), Event(0), Event(0), Ignore],
            vec![Quiet, Quiet, Quiet, Quiet, Quiet],
        ];
        let s = score_detection(&z, &truth, &[1], 3.0);
        assert_eq!((s.event_days, s.event_hits), (3, 2));
        assert_eq!((s.quiet_days, s.quiet_hits), (5, 2));
        assert_eq!((s.events, s.events_caught), (1, 1));
        assert_eq!(s.mean_delay_days(), 1.0);
        assert!((s.detection_rate() - 2.0 / 3.0).abs() < 1e-12);
        assert!((s.false_alarm_rate() - 0.4).abs() < 1e-12);
    }
}
