//! Time series of a cell: borrowed views, owned series, the sampling grid and the cell mean
//! over sensors (docs/method.md §2, x̂_i^m(t)).

use gleaner_field::UnixSeconds;

/// A borrowed time series: `times` in s (strictly increasing) and `values` in the modality's
/// unit, same length. Missing readings are simply absent (never zeros, never NaN).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Series<'a> {
    /// Timestamps, s, strictly increasing.
    pub times: &'a [UnixSeconds],
    /// Values, one per timestamp, in the modality's unit.
    pub values: &'a [f64],
}

impl<'a> Series<'a> {
    /// A view on two parallel slices (the caller guarantees equal length and order; the
    /// scoring functions validate them).
    pub fn new(times: &'a [UnixSeconds], values: &'a [f64]) -> Self {
        Self { times, values }
    }

    /// An empty series (the cell lacks the modality).
    pub fn empty() -> Self {
        Self::default()
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.times.len().min(self.values.len())
    }

    /// True when the series has no point.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The points with `from <= time <= to` (times in s).
    pub fn between(&self, from: UnixSeconds, to: UnixSeconds) -> Series<'a> {
        let n = self.len();
        let times = &self.times[..n];
        let lo = times.partition_point(|&t| t < from);
        let hi = times.partition_point(|&t| t <= to).max(lo);
        Series {
            times: &self.times[lo..hi],
            values: &self.values[lo..hi],
        }
    }

    /// The last point, (s, value), if any.
    pub fn last(&self) -> Option<(UnixSeconds, f64)> {
        let n = self.len();
        (n > 0).then(|| (self.times[n - 1], self.values[n - 1]))
    }

    /// The value at time `t` (s), if the series has one there.
    pub fn value_at(&self, t: UnixSeconds) -> Option<f64> {
        let n = self.len();
        self.times[..n]
            .binary_search(&t)
            .ok()
            .map(|k| self.values[k])
    }
}

/// An owned time series (see [`Series`] for the invariants).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct OwnedSeries {
    /// Timestamps, s, strictly increasing.
    pub times: Vec<UnixSeconds>,
    /// Values, one per timestamp.
    pub values: Vec<f64>,
}

impl OwnedSeries {
    /// The borrowed view.
    pub fn as_series(&self) -> Series<'_> {
        Series::new(&self.times, &self.values)
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.times.len()
    }

    /// True when the series has no point.
    pub fn is_empty(&self) -> bool {
        self.times.is_empty()
    }
}

/// The dataset's sampling grid: slots of `step_s` seconds starting at `origin` (s). Every
/// timestamp is snapped down to the start of its slot, so readings taken a few seconds apart
/// by different sensors land on the same grid time.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TimeGrid {
    /// A slot boundary, s since the epoch (default 0 = midnight UTC).
    pub origin: UnixSeconds,
    /// Slot length, s, > 0 (86,400 for daily data, 3,600 for hourly).
    pub step_s: i64,
}

impl TimeGrid {
    /// Daily slots starting at midnight UTC.
    pub const DAILY: TimeGrid = TimeGrid {
        origin: 0,
        step_s: 86_400,
    };
    /// Hourly slots.
    pub const HOURLY: TimeGrid = TimeGrid {
        origin: 0,
        step_s: 3_600,
    };

    /// The start (s) of the slot containing `t` (s). A non-positive step leaves `t` unchanged.
    pub fn snap(&self, t: UnixSeconds) -> UnixSeconds {
        if self.step_s <= 0 {
            return t;
        }
        // Saturating: a time or origin near the ends of i64 must not overflow.
        let slots = t.saturating_sub(self.origin).div_euclid(self.step_s);
        self.origin
            .saturating_add(slots.saturating_mul(self.step_s))
    }
}

/// The cell series x̂_i^m: for each grid slot, the mean of the readings of the cell's sensors
/// that fall in that slot (docs/method.md §2). Missing readings are absent and never count as zeros;
/// non-finite values (NaN, ±inf) are treated as missing. With at most one reading per sensor
/// per slot (the usual case) this is exactly the mean over the sensors having a reading at t.
///
/// `sensors` holds one series of modality m per sensor of the cell (times in s, any order).
///
/// ```
/// use gleaner_utility::{cell_series, Series, TimeGrid};
/// let (t1, v1) = (vec![0, 86_400, 172_800], vec![0.30, 0.31, 0.32]);
/// let (t2, v2) = (vec![0, 172_800], vec![0.20, 0.22]);
/// let s = cell_series(&[Series::new(&t1, &v1), Series::new(&t2, &v2)], TimeGrid::DAILY);
/// assert_eq!(s.times, vec![0, 86_400, 172_800]);
/// assert!((s.values[1] - 0.31).abs() < 1e-12); // sensor 2 missing: not a zero
/// assert!((s.values[2] - 0.27).abs() < 1e-12);
/// ```
pub fn cell_series(sensors: &[Series<'_>], grid: TimeGrid) -> OwnedSeries {
    let mut points: Vec<(UnixSeconds, usize, f64)> = Vec::new();
    for (k, s) in sensors.iter().enumerate() {
        for (&t, &v) in s.times.iter().zip(s.values) {
            if v.is_finite() {
                points.push((grid.snap(t), k, v));
            }
        }
    }
    points.sort_by(|a, b| a.0.cmp(&b.0).then(a.1.cmp(&b.1)));
    let mut out = OwnedSeries::default();
    let mut i = 0;
    while i < points.len() {
        let t = points[i].0;
        let mut sum = 0.0;
        let mut n = 0usize;
        while i < points.len() && points[i].0 == t {
            sum += points[i].2;
            n += 1;
            i += 1;
        }
        out.times.push(t);
        out.values.push(sum / n as f64);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn check(sensors: &[(&[i64], &[f64])], grid: TimeGrid, expected: &[(i64, f64)]) {
        let views: Vec<Series> = sensors.iter().map(|(t, v)| Series::new(t, v)).collect();
        let s = cell_series(&views, grid);
        let got: Vec<(i64, f64)> = s
            .times
            .iter()
            .copied()
            .zip(s.values.iter().copied())
            .collect();
        assert_eq!(got.len(), expected.len(), "{got:?}");
        for (g, e) in got.iter().zip(expected) {
            assert!(
                g.0 == e.0 && (g.1 - e.1).abs() < 1e-12,
                "{got:?} != {expected:?}"
            );
        }
    }

    #[test]
    fn cell_series_by_hand() {
        let daily = TimeGrid::DAILY;
        // Mean over the sensors having a reading; missing is skipped.
        check(
            &[(&[0, 86_400], &[1.0, 2.0]), (&[0], &[3.0])],
            daily,
            &[(0, 2.0), (86_400, 2.0)],
        );
        // Readings a few seconds apart share a slot; NaN counts as missing.
        check(
            &[(&[10, 86_410], &[1.0, f64::NAN]), (&[20], &[2.0])],
            daily,
            &[(0, 1.5)],
        );
        // Hourly grid keeps them apart; negative times snap down.
        check(
            &[(&[-10, 3_700], &[1.0, 2.0])],
            TimeGrid::HOURLY,
            &[(-3_600, 1.0), (3_600, 2.0)],
        );
        check(&[], daily, &[]);
    }

    #[test]
    fn series_windows() {
        let (t, v) = (vec![0, 10, 20, 30], vec![1.0, 2.0, 3.0, 4.0]);
        let s = Series::new(&t, &v);
        assert_eq!(s.between(10, 20).values, &[2.0, 3.0]);
        assert_eq!(s.between(11, 19).len(), 0);
        assert_eq!(s.between(40, 10).len(), 0);
        assert_eq!(s.last(), Some((30, 4.0)));
        assert_eq!(s.value_at(20), Some(3.0));
        assert_eq!(s.value_at(21), None);
    }

    proptest! {
        /// Missing readings never count as zeros: the cell value is the mean of the present
        /// readings only, whatever is missing.
        #[test]
        fn missing_never_counts_as_zero(
            rows in proptest::collection::vec(proptest::collection::vec(proptest::option::of(1.0f64..2.0), 1..5), 1..20)
        ) {
            let n_sensors = rows.iter().map(Vec::len).max().unwrap_or(0);
            let mut data: Vec<(Vec<i64>, Vec<f64>)> = vec![(vec![], vec![]); n_sensors];
            for (d, row) in rows.iter().enumerate() {
                for (k, v) in row.iter().enumerate() {
                    if let Some(v) = v {
                        data[k].0.push(d as i64 * 86_400);
                        data[k].1.push(*v);
                    }
                }
            }
            let views: Vec<Series> = data.iter().map(|(t, v)| Series::new(t, v)).collect();
            let s = cell_series(&views, TimeGrid::DAILY);
            for (t, v) in s.times.iter().zip(&s.values) {
                // All readings are in [1, 2): a zero counted in would drag the mean below 1.
                prop_assert!(*v >= 1.0 && *v < 2.0);
                let present: Vec<f64> = rows[(*t / 86_400) as usize].iter().flatten().copied().collect();
                let mean = present.iter().sum::<f64>() / present.len() as f64;
                prop_assert!((v - mean).abs() < 1e-12);
            }
            let expected_days = rows.iter().filter(|r| r.iter().any(Option::is_some)).count();
            prop_assert_eq!(s.len(), expected_days);
        }
    }
}
