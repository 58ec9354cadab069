//! Kriging of changes: a sensor's value now is its last known reading plus its change since,
//! estimated from the changes its neighbours are known to have made over (part of) the same
//! interval.
//!
//! Sensors buffer their readings: a collection brings a sensor's whole series home, so for a
//! neighbour collected after the target was, its change over the target's unseen interval is
//! known. Levels differ persistently between stations; changes are what transfers between
//! them. The model of changes ([`IncrementModel`]) is a sum of two intrinsic processes with
//! stationary increments:
//!
//! - a field-wide part whose changes over one interval correlate between two sensors `d`
//!   metres apart as `exp(−d/range)`, with temporal variogram [`IncrementModel::shared`];
//! - each sensor's own part (independent between sensors), variogram [`IncrementModel::own`].
//!
//! For a variogram `D(h) = E[(x(t + h) − x(t))²]`, the covariance of one sensor's changes over
//! `[a, b]` and `[c, e]` is `½[D(b − c) + D(a − e) − D(b − e) − D(a − c)]` ([`Variogram::cov`]),
//! so changes over different, overlapping or misaligned intervals are all weighed
//! consistently; the covariance of all changes is the spatial correlation times that (a Schur
//! product of two covariance matrices, so positive semi-definite). [`estimate_change`] is
//! simple kriging of the target's change (zero mean): without an informative change the
//! estimate is exactly the last value carried forward, and its variance never exceeds the
//! carried-forward variance `D_shared(h) + D_own(h)` under the model.
//!
//! Units: positions east/north metres; times seconds (as `f64`, any common origin); values
//! in the modality's unit, variances and variograms its square.

use super::{KrigingError, cholesky, distance, forward};

/// A temporal variogram of changes, the unit squared: `D(0) = 0` and, for `h > 0`,
/// `D(h) = nugget + partial · (1 − exp(−h/scale))` (an exponential variogram with a nugget: a
/// bounded, mean-reverting process plus fresh noise at every step).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Variogram {
    /// Jump at any positive lag, the unit squared (>= 0).
    pub nugget: f64,
    /// Further growth up to the sill, the unit squared (>= 0).
    pub partial: f64,
    /// E-folding time of that growth, seconds (> 0).
    pub scale_s: f64,
}

impl Variogram {
    /// The variogram at lag `h_s` seconds (either sign), the unit squared.
    pub fn at(&self, h_s: f64) -> f64 {
        let h = h_s.abs();
        if h == 0.0 {
            0.0
        } else {
            self.nugget + self.partial * (1.0 - (-h / self.scale_s).exp())
        }
    }

    /// Covariance of the changes over `[a, b]` and `[c, e]` (seconds) of a process with this
    /// variogram: `½[D(b − c) + D(a − e) − D(b − e) − D(a − c)]`.
    pub fn cov(&self, (a, b): (f64, f64), (c, e): (f64, f64)) -> f64 {
        0.5 * (self.at(b - c) + self.at(a - e) - self.at(b - e) - self.at(a - c))
    }

    fn check(&self, what: &'static str) -> Result<(), KrigingError> {
        let ok = self.nugget.is_finite()
            && self.nugget >= 0.0
            && self.partial.is_finite()
            && self.partial >= 0.0
            && self.scale_s.is_finite()
            && self.scale_s > 0.0;
        if ok {
            Ok(())
        } else {
            Err(KrigingError::Parameter {
                what,
                value: self.nugget + self.partial + self.scale_s,
                expected: "non-negative nugget and partial sill, positive scale",
            })
        }
    }
}

/// The model of changes (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IncrementModel {
    /// Variogram of the field-wide part, the unit squared.
    pub shared: Variogram,
    /// Spatial e-folding distance of the field-wide part's correlation, metres (> 0).
    pub range_m: f64,
    /// Variogram of each sensor's own part, the unit squared.
    pub own: Variogram,
}

impl IncrementModel {
    /// A model; the variograms' parameters must be finite, non-negative (scales positive),
    /// the range positive.
    pub fn new(shared: Variogram, range_m: f64, own: Variogram) -> Result<Self, KrigingError> {
        shared.check("shared variogram")?;
        own.check("own variogram")?;
        if !(range_m.is_finite() && range_m > 0.0) {
            return Err(KrigingError::Parameter {
                what: "range (m)",
                value: range_m,
                expected: "positive",
            });
        }
        Ok(Self {
            shared,
            range_m,
            own,
        })
    }

    /// Covariance of a change at `p` over `i` and one at `q` over `j` (positions metres,
    /// intervals seconds); the same position means the same sensor (its own part counts).
    pub fn cov(&self, p: [f64; 2], i: (f64, f64), q: [f64; 2], j: (f64, f64)) -> f64 {
        let d = distance(p, q);
        let shared = (-d / self.range_m).exp() * self.shared.cov(i, j);
        if d == 0.0 {
            shared + self.own.cov(i, j)
        } else {
            shared
        }
    }

    /// Variance of one sensor's change over `h_s` seconds: the mean squared error of
    /// carrying its value forward that long, the unit squared.
    pub fn carried_variance(&self, h_s: f64) -> f64 {
        self.shared.at(h_s) + self.own.at(h_s)
    }
}

/// A known change: a sensor's reading at `to_s` minus its reading at `from_s`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Change {
    /// The sensor's position, east/north metres (the target's own position: the target).
    pub position: [f64; 2],
    /// Start of the interval, seconds.
    pub from_s: f64,
    /// End of the interval, seconds (> `from_s`).
    pub to_s: f64,
    /// The reading at `to_s` minus the one at `from_s`, the modality's unit.
    pub change: f64,
}

/// An estimated change and its variance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChangeEstimate {
    /// Conditional mean of the target's change, the modality's unit (0 without information).
    pub change: f64,
    /// Conditional variance, the unit squared (at most the carried-forward variance).
    pub variance: f64,
    /// The carried-forward variance under the model (the variance of the change), the unit
    /// squared.
    pub carried_variance: f64,
}

/// Simple kriging of the target's change at `target` (metres) from `from_s` (its last known
/// reading) to `to_s` (seconds), from the `max_changes` known changes that explain most of
/// its variance alone. Changes with an empty or reversed interval or a non-finite value are
/// left out; without any (or when the system is singular) the estimate is 0 with the
/// carried-forward variance.
pub fn estimate_change(
    model: &IncrementModel,
    changes: &[Change],
    target: [f64; 2],
    (from_s, to_s): (f64, f64),
    max_changes: usize,
) -> ChangeEstimate {
    let interval = (from_s, to_s);
    let prior = model.carried_variance(to_s - from_s);
    let none = ChangeEstimate {
        change: 0.0,
        variance: prior,
        carried_variance: prior,
    };
    let valid = to_s > from_s && prior > 0.0 && prior.is_finite();
    if !valid {
        return ChangeEstimate {
            variance: prior.max(0.0),
            carried_variance: prior.max(0.0),
            ..none
        };
    }
    // (cross covariance, own variance, change) of each usable change.
    let mut chosen: Vec<(f64, f64, &Change)> = changes
        .iter()
        .filter(|c| c.to_s > c.from_s && c.change.is_finite() && c.from_s.is_finite())
        .filter_map(|c| {
            let own = (c.from_s, c.to_s);
            let k = model.cov(c.position, own, target, interval);
            let v = model.cov(c.position, own, c.position, own);
            (v > 0.0 && k != 0.0 && k.is_finite()).then_some((k, v, c))
        })
        .collect();
    let key = |x: &(f64, f64, &Change)| x.0 * x.0 / x.1;
    let k = max_changes.max(1);
    if chosen.len() > k {
        chosen.select_nth_unstable_by(k - 1, |a, b| key(b).total_cmp(&key(a)));
        chosen.truncate(k);
    }
    chosen.sort_by(|a, b| {
        key(b)
            .total_cmp(&key(a))
            .then(a.2.position[0].total_cmp(&b.2.position[0]))
            .then(a.2.position[1].total_cmp(&b.2.position[1]))
            .then(a.2.from_s.total_cmp(&b.2.from_s))
            .then(a.2.to_s.total_cmp(&b.2.to_s))
    });
    let n = chosen.len();
    if n == 0 {
        return none;
    }
    let mut a = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..=i {
            let (p, q) = (chosen[i].2, chosen[j].2);
            let c = if i == j {
                chosen[i].1
            } else {
                model.cov(
                    p.position,
                    (p.from_s, p.to_s),
                    q.position,
                    (q.from_s, q.to_s),
                )
            };
            a[i * n + j] = c;
            a[j * n + i] = c;
        }
    }
    if !cholesky(&mut a, n) {
        return none;
    }
    let mut y: Vec<f64> = chosen.iter().map(|c| c.0).collect();
    let mut z: Vec<f64> = chosen.iter().map(|c| c.2.change).collect();
    forward(&a, n, &mut y);
    forward(&a, n, &mut z);
    let mean: f64 = y.iter().zip(&z).map(|(p, q)| p * q).sum();
    let explained: f64 = y.iter().map(|p| p * p).sum();
    if !mean.is_finite() {
        return none;
    }
    ChangeEstimate {
        change: mean,
        variance: (prior - explained).clamp(0.0, prior),
        carried_variance: prior,
    }
}

/// Options of [`fit_increments`].
#[derive(Debug, Clone, PartialEq)]
pub struct IncrementFitOptions {
    /// Sampling step of the series, seconds.
    pub step_s: i64,
    /// The lags fitted, in steps (each >= 1).
    pub lags_steps: Vec<i64>,
    /// Fewest common changes for a lag (pooled) or a pair to count.
    pub min_overlap: usize,
    /// At most this many sensors enter the pairwise fit (an even subsample beyond).
    pub max_pair_sensors: usize,
    /// Bounds of the spatial range, metres.
    pub range_bounds_m: (f64, f64),
}

impl Default for IncrementFitOptions {
    /// Daily step; lags 1, 2, 3, 5, 7, 10, 14, 21, 28, 42 and 56 steps; 10 common changes;
    /// 200 sensors in the pairwise fit; range 1 m .. 100 km.
    fn default() -> Self {
        Self {
            step_s: 86_400,
            lags_steps: vec![1, 2, 3, 5, 7, 10, 14, 21, 28, 42, 56],
            min_overlap: 10,
            max_pair_sensors: 200,
            range_bounds_m: (1.0, 100_000.0),
        }
    }
}

/// A sensor's series as a dense grid of values (NaN where missing) from a common origin.
fn grid(series: &[super::SensorSeries<'_>], step: i64) -> (Vec<Vec<f64>>, usize) {
    // The grid most readings share (a logger's first readings at :15 before it settles on the
    // hour are left out instead of every other sensor's).
    let phase =
        gleaner_field::time::grid_phase(series.iter().flat_map(|s| s.times.iter().copied()), step);
    let first = series
        .iter()
        .filter_map(|s| s.times.first())
        .min()
        .copied()
        .unwrap_or(0);
    let t0 = gleaner_field::time::grid_floor(first, step, phase);
    let t1 = series
        .iter()
        .filter_map(|s| s.times.last())
        .max()
        .copied()
        .unwrap_or(0);
    let len = usize::try_from((t1 - t0) / step + 1).unwrap_or(0);
    let grids = series
        .iter()
        .map(|s| {
            let mut g = vec![f64::NAN; len];
            for (t, v) in s.times.iter().zip(s.values) {
                let k = (t - t0) / step;
                if (t - t0) % step == 0 && k >= 0 && (k as usize) < len {
                    g[k as usize] = *v;
                }
            }
            g
        })
        .collect();
    (grids, len)
}

/// Least squares of `y ≈ n + p·x` with `n, p >= 0`, weights `w`: (n, p, weighted SSE).
fn nonneg_line(points: &[(f64, f64, f64)]) -> (f64, f64, f64) {
    let sse = |n: f64, p: f64| -> f64 {
        points
            .iter()
            .map(|&(x, y, w)| w * (y - n - p * x).powi(2))
            .sum()
    };
    let (mut sw, mut sx, mut sy, mut sxx, mut sxy) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for &(x, y, w) in points {
        sw += w;
        sx += w * x;
        sy += w * y;
        sxx += w * x * x;
        sxy += w * x * y;
    }
    let det = sw * sxx - sx * sx;
    let mut candidates = Vec::new();
    if det.abs() > 1e-300 {
        let p = (sw * sxy - sx * sy) / det;
        let n = (sy - p * sx) / sw;
        if n >= 0.0 && p >= 0.0 {
            candidates.push((n, p));
        }
    }
    if sw > 0.0 {
        candidates.push(((sy / sw).max(0.0), 0.0));
    }
    if sxx > 0.0 {
        candidates.push((0.0, (sxy / sxx).max(0.0)));
    }
    candidates
        .into_iter()
        .map(|(n, p)| (n, p, sse(n, p)))
        .min_by(|a, b| a.2.total_cmp(&b.2))
        .unwrap_or((0.0, 0.0, 0.0))
}

/// Fits a [`Variogram`] to (lag s, value) points by least squares relative to the values,
/// scanning the scale on a log grid from one step to a year.
fn fit_variogram(points: &[(f64, f64)], step: f64) -> Variogram {
    let mut best: Option<(f64, Variogram)> = None;
    let top = 365.0 * 86_400.0_f64.max(step);
    let mut scale = step.max(1.0);
    while scale <= top {
        let pts: Vec<(f64, f64, f64)> = points
            .iter()
            .map(|&(h, y)| (1.0 - (-h / scale).exp(), y, 1.0 / y.max(1e-300).powi(2)))
            .collect();
        let (n, p, sse) = nonneg_line(&pts);
        if best.is_none_or(|b| sse < b.0) {
            best = Some((
                sse,
                Variogram {
                    nugget: n,
                    partial: p,
                    scale_s: scale,
                },
            ));
        }
        scale *= 1.15;
    }
    best.map_or(
        Variogram {
            nugget: 0.0,
            partial: 0.0,
            scale_s: step.max(1.0),
        },
        |b| b.1,
    )
}

/// Fits the model of changes from sensor series on a regular grid.
///
/// For every lag `h`: the pooled mean square of all sensors' `h`-step changes, `D(h)`, and for
/// every pair of sensors (beyond `max_pair_sensors` sensors: every pair of an even subsample of
/// that many, and each of them with its 8 nearest sensors) the mean product of their
/// simultaneous `h`-step changes. The range is the one whose
/// `exp(−d/range) · S(h)` (with `S(h)` the least-squares factor per lag) fits the pairs' mean
/// products best relative to `D(h)`; `S(h)`, clamped to `[0, D(h)]`, is the field-wide part's
/// variogram, `D(h) − S(h)` the sensors' own; each is then fitted by [`Variogram`]'s form.
/// Errors when fewer than 2 sensors have readings or no lag has enough changes.
pub fn fit_increments(
    series: &[super::SensorSeries<'_>],
    options: &IncrementFitOptions,
) -> Result<IncrementModel, KrigingError> {
    let step = options.step_s.max(1);
    let with_data = series.iter().filter(|s| !s.values.is_empty()).count();
    if with_data < 2 {
        return Err(KrigingError::Fit(format!(
            "{with_data} sensors with readings; at least 2 are needed"
        )));
    }
    let (grids, len) = grid(series, step);
    let stride = series
        .len()
        .div_ceil(options.max_pair_sensors.max(2))
        .max(1);
    let paired: Vec<usize> = (0..series.len()).step_by(stride).collect();
    // The pairs: every pair of the subsample, and each subsampled sensor with its nearest
    // `NEAR_PAIRS` sensors of all (on a large network an even subsample alone has no near
    // pairs, and the short-range correlation would go unseen).
    const NEAR_PAIRS: usize = 8;
    let mut pair_list: Vec<(usize, usize)> = Vec::new();
    for (x, &i) in paired.iter().enumerate() {
        for &j in &paired[x + 1..] {
            pair_list.push((i, j));
        }
    }
    if stride > 1 {
        for &i in &paired {
            let mut near: Vec<(f64, usize)> = (0..series.len())
                .filter(|&j| j != i)
                .map(|j| (distance(series[i].position, series[j].position), j))
                .collect();
            let m = NEAR_PAIRS.min(near.len());
            if m > 0 && near.len() > m {
                near.select_nth_unstable_by(m - 1, |a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            }
            pair_list.extend(near[..m].iter().map(|&(_, j)| (i.min(j), i.max(j))));
        }
        pair_list.sort_unstable();
        pair_list.dedup();
    }
    let (lo, hi) = options.range_bounds_m;
    // Range candidates, metres (log grid).
    let mut ranges = Vec::new();
    let mut r = lo.max(1e-3);
    while r <= hi {
        ranges.push(r);
        r *= 1.2;
    }
    // Per lag: D(h) and the pairs' (distance, mean product).
    // (lag s, D(h), pairs' (distance m, mean product)).
    type Lag = (f64, f64, Vec<(f64, f64)>);
    let mut lags: Vec<Lag> = Vec::new();
    for &h in &options.lags_steps {
        let h = usize::try_from(h.max(1)).unwrap_or(1);
        if h >= len {
            continue;
        }
        let changes: Vec<Vec<f64>> = grids
            .iter()
            .map(|g| (0..len - h).map(|t| g[t + h] - g[t]).collect())
            .collect();
        let (mut ss, mut n) = (0.0, 0usize);
        for c in &changes {
            for v in c.iter().filter(|v| v.is_finite()) {
                ss += v * v;
                n += 1;
            }
        }
        if n < options.min_overlap || ss <= 0.0 {
            continue;
        }
        let mut pairs = Vec::new();
        for &(i, j) in &pair_list {
            let (mut s, mut m) = (0.0, 0usize);
            for (a, b) in changes[i].iter().zip(&changes[j]) {
                if a.is_finite() && b.is_finite() {
                    s += a * b;
                    m += 1;
                }
            }
            let d = distance(series[i].position, series[j].position);
            if m >= options.min_overlap && d > 0.0 {
                pairs.push((d, s / m as f64));
            }
        }
        lags.push(((h as i64 * step) as f64, ss / n as f64, pairs));
    }
    if lags.is_empty() {
        return Err(KrigingError::Fit(
            "no lag with enough changes to fit the model of changes".into(),
        ));
    }
    // The range: least squares of the pairs' products, relative to D(h), with the best
    // factor S(h) per lag.
    let mut best: Option<(f64, f64)> = None;
    for &r in &ranges {
        let mut sse = 0.0;
        for (_, d_h, pairs) in &lags {
            let (mut swy, mut sww) = (0.0, 0.0);
            for &(d, y) in pairs {
                let w = (-d / r).exp();
                swy += w * y;
                sww += w * w;
            }
            let s = if sww > 0.0 { swy / sww } else { 0.0 };
            sse += pairs
                .iter()
                .map(|&(d, y)| (y - s * (-d / r).exp()).powi(2))
                .sum::<f64>()
                / d_h.powi(2);
        }
        if best.is_none_or(|b| sse < b.0) {
            best = Some((sse, r));
        }
    }
    let range_m = best.map_or(lo.max(1e-3), |b| b.1);
    let mut shared_points = Vec::new();
    let mut own_points = Vec::new();
    for (h, d_h, pairs) in &lags {
        let (mut swy, mut sww) = (0.0, 0.0);
        for &(d, y) in pairs {
            let w = (-d / range_m).exp();
            swy += w * y;
            sww += w * w;
        }
        let s = if sww > 0.0 { swy / sww } else { 0.0 }.clamp(0.0, *d_h);
        shared_points.push((*h, s.max(d_h * 1e-6)));
        own_points.push((*h, (d_h - s).max(d_h * 1e-6)));
    }
    IncrementModel::new(
        fit_variogram(&shared_points, step as f64),
        range_m,
        fit_variogram(&own_points, step as f64),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::SensorSeries;
    use proptest::prelude::*;

    const DAY: f64 = 86_400.0;

    fn model() -> IncrementModel {
        IncrementModel::new(
            Variogram {
                nugget: 1e-5,
                partial: 4e-4,
                scale_s: 20.0 * DAY,
            },
            300.0,
            Variogram {
                nugget: 1e-5,
                partial: 2e-4,
                scale_s: 10.0 * DAY,
            },
        )
        .unwrap()
    }

    #[test]
    fn without_changes_it_is_carried_forward() {
        let m = model();
        let e = estimate_change(&m, &[], [0.0, 0.0], (0.0, 5.0 * DAY), 16);
        assert_eq!(e.change, 0.0);
        assert_eq!(e.variance, m.carried_variance(5.0 * DAY));
        assert_eq!(e.carried_variance, e.variance);
        // A neighbour too far away to correlate changes nothing.
        let far = Change {
            position: [1e9, 0.0],
            from_s: 0.0,
            to_s: 5.0 * DAY,
            change: 0.3,
        };
        let e = estimate_change(&m, &[far], [0.0, 0.0], (0.0, 5.0 * DAY), 16);
        assert_eq!(e.change, 0.0);
    }

    #[test]
    fn a_near_neighbours_change_over_the_same_interval_transfers() {
        let m = model();
        let near = |d: f64| Change {
            position: [d, 0.0],
            from_s: 0.0,
            to_s: 7.0 * DAY,
            change: 0.05,
        };
        let e10 = estimate_change(&m, &[near(10.0)], [0.0, 0.0], (0.0, 7.0 * DAY), 16);
        let e500 = estimate_change(&m, &[near(500.0)], [0.0, 0.0], (0.0, 7.0 * DAY), 16);
        assert!(
            e10.change > e500.change && e500.change > 0.0,
            "{e10:?} {e500:?}"
        );
        assert!(e10.change < 0.05, "shrunk towards no change: {e10:?}");
        assert!(e10.variance < e500.variance && e500.variance < e10.carried_variance);
        // A change over only half the interval is worth less.
        let half = Change {
            to_s: 3.5 * DAY,
            ..near(10.0)
        };
        let eh = estimate_change(&m, &[half], [0.0, 0.0], (0.0, 7.0 * DAY), 16);
        assert!(eh.variance > e10.variance, "{eh:?} {e10:?}");
    }

    #[test]
    fn variogram_covariance_is_the_variance_on_the_diagonal() {
        let v = model().shared;
        let i = (2.0 * DAY, 9.0 * DAY);
        assert!((v.cov(i, i) - v.at(7.0 * DAY)).abs() < 1e-15);
        // Disjoint intervals of a process with a concave variogram correlate negatively
        // (mean reversion: a rise tends to drain).
        assert!(v.cov((0.0, DAY), (DAY, 8.0 * DAY)) < 0.0);
    }

    #[test]
    fn invalid_models_are_refused() {
        let v = model().shared;
        assert!(IncrementModel::new(v, 0.0, v).is_err());
        let bad = Variogram { nugget: -1.0, ..v };
        assert!(IncrementModel::new(bad, 10.0, v).is_err());
        assert!(IncrementModel::new(v, 10.0, Variogram { scale_s: 0.0, ..v }).is_err());
    }

    #[test]
    fn fit_separates_shared_and_own_changes() {
        // A common random walk plus each sensor's own noise: the shared part carries most of
        // the long-lag variance, and the range is long (the sensors share the walk fully).
        let day = 86_400;
        let n = 500;
        let times: Vec<i64> = (0..n).map(|d| d * day).collect();
        let noise =
            |k: i64, s: f64| ((k as f64 * 12.9898 + s * 78.233).sin() * 43_758.545).fract() - 0.5;
        let mut walk = vec![0.0; n as usize];
        for k in 1..n as usize {
            walk[k] = 0.98 * walk[k - 1] + 0.01 * noise(k as i64, 0.5);
        }
        let values: Vec<Vec<f64>> = (0..4)
            .map(|s| {
                (0..n)
                    .map(|k| {
                        0.3 + 0.01 * s as f64 + walk[k as usize] + 0.002 * noise(k, s as f64 + 1.0)
                    })
                    .collect()
            })
            .collect();
        let series: Vec<SensorSeries<'_>> = values
            .iter()
            .enumerate()
            .map(|(s, v)| SensorSeries {
                position: [50.0 * s as f64, 0.0],
                times: &times,
                values: v,
            })
            .collect();
        let m = fit_increments(&series, &IncrementFitOptions::default()).unwrap();
        assert!(m.range_m > 1_000.0, "{m:?}");
        let h = 14.0 * DAY;
        assert!(m.shared.at(h) > 3.0 * m.own.at(h), "{m:?}");
        // A sensor's neighbour's change over the interval then predicts most of its own.
        let c = Change {
            position: [50.0, 0.0],
            from_s: 0.0,
            to_s: h,
            change: 0.02,
        };
        let e = estimate_change(&m, &[c], [0.0, 0.0], (0.0, h), 16);
        assert!(e.variance < 0.5 * e.carried_variance, "{e:?}");
        assert!(fit_increments(&series[..1], &IncrementFitOptions::default()).is_err());
    }

    #[test]
    fn fit_sees_near_pairs_on_a_subsampled_network() {
        // Six clusters 50 km apart, two sensors 5 m apart in each sharing the cluster's walk:
        // an even subsample of 3 sensors has only far pairs; the near pairs show the sharing.
        let day = 86_400;
        let n = 300;
        let times: Vec<i64> = (0..n).map(|d| d * day).collect();
        // Independent uniform noise in [-0.5, 0.5) per (step, stream): an integer hash.
        let noise = |k: i64, s: f64| {
            let mut x = (k as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
                ^ (s as u64).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            x ^= x >> 31;
            x = x.wrapping_mul(0x94D0_49BB_1331_11EB);
            x ^= x >> 29;
            (x >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let values: Vec<Vec<f64>> = (0..12)
            .map(|s| {
                let cluster = (s / 2) as f64;
                let mut walk = 0.0;
                (0..n)
                    .map(|k| {
                        walk = 0.97 * walk + 0.01 * noise(k, cluster + 100.0);
                        0.3 + walk + 0.001 * noise(k, s as f64)
                    })
                    .collect()
            })
            .collect();
        let series: Vec<SensorSeries<'_>> = values
            .iter()
            .enumerate()
            .map(|(s, v)| SensorSeries {
                position: [50_000.0 * (s / 2) as f64, 5.0 * (s % 2) as f64],
                times: &times,
                values: v,
            })
            .collect();
        let options = IncrementFitOptions {
            max_pair_sensors: 3,
            ..IncrementFitOptions::default()
        };
        let m = fit_increments(&series, &options).unwrap();
        let h = 14.0 * DAY;
        assert!(m.shared.at(h) > 3.0 * m.own.at(h), "{m:?}");
        // Correlated at 5 m, not across clusters.
        assert!((-5.0 / m.range_m).exp() > 0.9, "{m:?}");
        assert!((-50_000.0 / m.range_m).exp() < 0.1, "{m:?}");
    }

    proptest! {
        #[test]
        fn the_estimate_never_does_worse_than_carried_forward_under_its_model(
            obs in proptest::collection::vec(
                (-500.0f64..500.0, -500.0f64..500.0, -10.0f64..20.0, 0.1f64..20.0, -0.1f64..0.1),
                0..24),
            tx in -500.0f64..500.0,
            h in 0.1f64..30.0,
        ) {
            let m = model();
            let changes: Vec<Change> = obs.iter().map(|&(x, y, from, len, c)| Change {
                position: [x, y], from_s: from * DAY, to_s: (from + len) * DAY, change: c,
            }).collect();
            let e = estimate_change(&m, &changes, [tx, 0.0], (0.0, h * DAY), 16);
            prop_assert!(e.change.is_finite());
            prop_assert!(e.variance >= 0.0);
            prop_assert!(e.variance <= e.carried_variance + 1e-18);
            prop_assert!((e.carried_variance - m.carried_variance(h * DAY)).abs() < 1e-18);
            // Linear in the changes: doubling every change doubles the estimate.
            let doubled: Vec<Change> = changes.iter().map(|c| Change { change: 2.0 * c.change, ..*c }).collect();
            let f = estimate_change(&m, &doubled, [tx, 0.0], (0.0, h * DAY), 16);
            prop_assert!((f.change - 2.0 * e.change).abs() < 1e-9);
        }
    }
}
