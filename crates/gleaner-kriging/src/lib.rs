//! Space-time Gaussian field models for gleaner's campaign evaluation. Pure: no IO.
//!
//! A sensor's reading is modelled as its own long-run mean plus a zero-mean Gaussian residual:
//! a smooth field with a separable exponential covariance plus the sensor's own deviation
//! from it (the `nugget`: site-specific, independent between sensors, decaying in time like
//! the field), so ([`Covariance::between`])
//! `cov(r(x, t), r(x', t')) = (sill · exp(−d/range) + nugget · [x = x']) · ρ(t − t')`, with
//! `ρ(0) = 1` and `ρ(Δ) = temporal_share · exp(−|Δ|/time_scale)` otherwise (the part of the
//! variance renewed at every time step, `1 − temporal_share`, is a temporal nugget).
//!
//! - [`fit`] estimates the means and the covariance from sensor series (pooled temporal
//!   autocorrelation for the time scale, pairwise correlations against distance for the range
//!   and the nugget);
//! - [`krige`] is simple kriging of one target from the most informative observations: the
//!   Gaussian conditional mean of the target's residual now and its variance, given every
//!   observation's residual and age — the last value carried forward and the neighbours'
//!   fresher values are weighed by the model instead of by hand; [`krige_with`] with
//!   [`Mean::Unknown`] is ordinary kriging (the field's current level is estimated from the
//!   observations, weights sum to 1), which does not pull a wet winter back towards the
//!   sensors' long-run means;
//! - [`estimate_change`] is kriging of changes: a sensor's value now is its last known
//!   reading plus its change since, estimated from its neighbours' known changes over the
//!   same interval with a model of changes ([`IncrementModel`], fitted by [`fit_increments`]);
//!   without an informative change it is exactly the last value carried forward;
//! - [`DynamicModel`] (fitted by [`fit_dynamic`], run by [`FieldFilter`]) is the field model
//!   over sensors × time: a learned, shrunk covariance of levels between sensors and AR(1)
//!   dynamics of the deviations, as a Kalman filter — the Gaussian conditional of levels for
//!   sensors not read for long, the last value and its inferred change for those read lately;
//! - [`variance_reduction`] is the expected reduction of the field's posterior variance from
//!   visiting cells, picked greedily on the (submodular) marginal gain;
//! - [`interval_multiplier`] calibrates a 90% interval from out-of-sample errors (split
//!   conformal), [`backtest_errors`] gives the dynamic model's on a stretch of history.
//!
//! Units: positions are east/north metres in one local frame; times and ages seconds; values
//! and residuals in the modality's unit (variances in its square).
//!
//! ```
//! use gleaner_kriging::{Covariance, Observation, krige};
//! let cov = Covariance::new(0.004, 0.0001, 300.0, 30.0 * 86_400.0).unwrap();
//! // A neighbour 50 m away read +0.03 today; the target itself was read +0.01 ten days ago.
//! let obs = [
//!     Observation { position: [50.0, 0.0], age_s: 0.0, residual: 0.03 },
//!     Observation { position: [0.0, 0.0], age_s: 864_000.0, residual: 0.01 },
//! ];
//! let e = krige(&cov, &obs, [0.0, 0.0], 16);
//! assert!(e.residual > 0.01 && e.residual < 0.03);
//! assert!(e.variance < cov.prior_variance());
//! ```
#![deny(missing_docs)]

use thiserror::Error;

mod calibration;
mod dynamic;
mod increments;
pub use calibration::{
    BACKTEST_MIN, BACKTEST_STRETCHES, Z90, backtest_errors, backtest_errors_hidden,
    backtest_stretches, interval_multiplier,
};
pub use dynamic::{
    DynamicFitOptions, DynamicModel, FieldFilter, MAX_DYNAMIC_SENSORS, Shrinkage, fit_dynamic,
    fit_own_rates,
};
pub use increments::{
    Change, ChangeEstimate, IncrementFitOptions, IncrementModel, Variogram, estimate_change,
    fit_increments,
};

/// Invalid arguments to the field models.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum KrigingError {
    /// A covariance parameter out of range.
    #[error("covariance parameter {what} = {value} must be {expected}")]
    Parameter {
        /// Which parameter.
        what: &'static str,
        /// The value given.
        value: f64,
        /// What it must be.
        expected: &'static str,
    },
    /// Not enough data to fit a model.
    #[error("cannot fit the field model: {0}")]
    Fit(String),
    /// Inputs of different lengths.
    #[error("{what}: {got} entries for {expected} cells")]
    Length {
        /// Which input.
        what: &'static str,
        /// Its length.
        got: usize,
        /// The length expected.
        expected: usize,
    },
    /// Too many cells for the dense posterior covariance.
    #[error("{cells} cells: the variance-reduction utility handles at most {max} cells")]
    TooLarge {
        /// Cells given.
        cells: usize,
        /// The limit.
        max: usize,
    },
}

/// A separable exponential space-time covariance of a residual field.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Covariance {
    /// Variance of the smooth field, the modality's unit squared.
    pub sill: f64,
    /// Variance of each sensor's own deviation from the smooth field (independent between
    /// sensors, correlated in time like the field), the modality's unit squared.
    pub nugget: f64,
    /// Spatial e-folding distance, metres.
    pub range_m: f64,
    /// Temporal e-folding time, seconds.
    pub time_scale_s: f64,
    /// Share of the variance that persists from one time step to the next, in (0, 1]
    /// (dimensionless; 1 = no temporal nugget). The rest, `1 − temporal_share`, is renewed
    /// at every step (fast weather, measurement noise): a reading a step old already misses
    /// it, a fresh neighbour's reading does not.
    pub temporal_share: f64,
}

impl Covariance {
    /// A covariance; every parameter must be finite, the sill and the scales positive and the
    /// nugget non-negative.
    pub fn new(
        sill: f64,
        nugget: f64,
        range_m: f64,
        time_scale_s: f64,
    ) -> Result<Self, KrigingError> {
        let check = |what, value: f64, ok: bool, expected| {
            if value.is_finite() && ok {
                Ok(())
            } else {
                Err(KrigingError::Parameter {
                    what,
                    value,
                    expected,
                })
            }
        };
        check("sill", sill, sill > 0.0, "positive")?;
        check("nugget", nugget, nugget >= 0.0, "non-negative")?;
        check("range (m)", range_m, range_m > 0.0, "positive")?;
        check(
            "time scale (s)",
            time_scale_s,
            time_scale_s > 0.0,
            "positive",
        )?;
        Ok(Self {
            sill,
            nugget,
            range_m,
            time_scale_s,
            temporal_share: 1.0,
        })
    }

    /// The same covariance with a temporal nugget: `share` of the variance persists in time
    /// (decaying with the time scale), `1 − share` is renewed at every time step. `share`
    /// must be in (0, 1].
    pub fn with_temporal_share(mut self, share: f64) -> Result<Self, KrigingError> {
        if !(share.is_finite() && share > 0.0 && share <= 1.0) {
            return Err(KrigingError::Parameter {
                what: "temporal share",
                value: share,
                expected: "in (0, 1]",
            });
        }
        self.temporal_share = share;
        Ok(self)
    }

    /// Temporal correlation at `lag_s` seconds: 1 at lag 0, else
    /// `temporal_share · exp(−|lag|/time_scale)`.
    pub fn temporal(&self, lag_s: f64) -> f64 {
        if lag_s == 0.0 {
            1.0
        } else {
            self.temporal_share * (-lag_s.abs() / self.time_scale_s).exp()
        }
    }

    /// Covariance of the smooth field between two points `distance_m` apart and `lag_s`
    /// apart in time (no nugget).
    pub fn smooth(&self, distance_m: f64, lag_s: f64) -> f64 {
        self.sill * (-distance_m.abs() / self.range_m).exp() * self.temporal(lag_s)
    }

    /// Covariance of two readings `distance_m` apart (0: the same sensor, which adds the
    /// nugget) and `lag_s` apart in time.
    pub fn between(&self, distance_m: f64, lag_s: f64) -> f64 {
        let own = if distance_m == 0.0 { self.nugget } else { 0.0 };
        (self.sill * (-distance_m.abs() / self.range_m).exp() + own) * self.temporal(lag_s)
    }

    /// Variance of one reading with no information: sill + nugget.
    pub fn prior_variance(&self) -> f64 {
        self.sill + self.nugget
    }
}

/// A known residual: where, how old (relative to the estimation time) and its value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Observation {
    /// Position, east/north metres.
    pub position: [f64; 2],
    /// Age at the estimation time, seconds (>= 0).
    pub age_s: f64,
    /// Reading minus its sensor's mean, the modality's unit.
    pub residual: f64,
}

/// A kriged residual and its variance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    /// Conditional mean of the target's residual, the modality's unit (0 without information).
    pub residual: f64,
    /// Conditional variance, the unit squared (at most the prior variance).
    pub variance: f64,
}

fn distance(a: [f64; 2], b: [f64; 2]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
}

/// In-place Cholesky factor (lower triangle, row-major `n × n`) with a relative jitter on the
/// diagonal when the matrix is not numerically positive definite. Returns false when even the
/// jitter does not help.
fn cholesky(a: &mut [f64], n: usize) -> bool {
    let scale = (0..n)
        .map(|i| a[i * n + i])
        .fold(0.0f64, f64::max)
        .max(1e-300);
    for attempt in 0..4 {
        let mut l = a.to_vec();
        if attempt > 0 {
            let jitter = scale * 1e-10 * 100f64.powi(attempt);
            for i in 0..n {
                l[i * n + i] += jitter;
            }
        }
        let mut ok = true;
        'outer: for j in 0..n {
            let mut d = l[j * n + j];
            for k in 0..j {
                d -= l[j * n + k] * l[j * n + k];
            }
            if !(d > 0.0 && d.is_finite()) {
                ok = false;
                break 'outer;
            }
            let d = d.sqrt();
            l[j * n + j] = d;
            for i in j + 1..n {
                let mut s = l[i * n + j];
                for k in 0..j {
                    s -= l[i * n + k] * l[j * n + k];
                }
                l[i * n + j] = s / d;
            }
        }
        if ok {
            a.copy_from_slice(&l);
            return true;
        }
    }
    false
}

/// Solves L y = b (forward substitution) in place.
fn forward(l: &[f64], n: usize, b: &mut [f64]) {
    for i in 0..n {
        let mut s = b[i];
        for k in 0..i {
            s -= l[i * n + k] * b[k];
        }
        b[i] = s / l[i * n + i];
    }
}

/// What kriging assumes about the residuals' mean at the estimation time.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Mean {
    /// Known and zero (simple kriging): the residuals revert to the sensors' long-run means.
    #[default]
    Known,
    /// Unknown and common to the observations used (ordinary kriging): the weights sum to 1,
    /// so a field-wide shift (a wet winter, a storm) carries through instead of being pulled
    /// back towards the long-run means. The variance then includes the uncertainty of that
    /// level and may exceed the prior.
    Unknown,
}

/// Simple kriging of the residual at `target` (age 0) from the `max_neighbours` observations
/// most correlated with it (all of them when fewer). An observation at the target's position
/// (the same sensor) shares its nugget; one of age 0 is the target itself, so the estimate
/// returns it with variance 0. Without observations the estimate is the prior: residual 0,
/// variance sill + nugget. Same as [`krige_with`] with [`Mean::Known`].
pub fn krige(
    cov: &Covariance,
    observations: &[Observation],
    target: [f64; 2],
    max_neighbours: usize,
) -> Estimate {
    krige_with(cov, observations, target, max_neighbours, Mean::Known)
}

/// Kriging of the residual at `target` (age 0) from the `max_neighbours` observations most
/// correlated with it, simple ([`Mean::Known`], see [`krige`]) or ordinary
/// ([`Mean::Unknown`]). Ordinary kriging returns a fresh reading at the target exactly too;
/// without observations both give the prior (residual 0, variance sill + nugget).
pub fn krige_with(
    cov: &Covariance,
    observations: &[Observation],
    target: [f64; 2],
    max_neighbours: usize,
    mean_model: Mean,
) -> Estimate {
    let cross = |o: &Observation| cov.between(distance(o.position, target), o.age_s);
    let mut chosen: Vec<(f64, &Observation)> = observations
        .iter()
        .filter(|o| o.age_s.is_finite() && o.residual.is_finite())
        .map(|o| (cross(o), o))
        .filter(|(c, _)| *c > 0.0)
        .collect();
    let k = max_neighbours.max(1);
    if chosen.len() > k {
        chosen.select_nth_unstable_by(k - 1, |a, b| b.0.total_cmp(&a.0));
        chosen.truncate(k);
    }
    // Deterministic order whatever the selection did.
    chosen.sort_by(|a, b| {
        b.0.total_cmp(&a.0)
            .then(a.1.position[0].total_cmp(&b.1.position[0]))
            .then(a.1.position[1].total_cmp(&b.1.position[1]))
            .then(a.1.age_s.total_cmp(&b.1.age_s))
    });
    let prior = cov.prior_variance();
    let n = chosen.len();
    if n == 0 {
        return Estimate {
            residual: 0.0,
            variance: prior,
        };
    }
    let mut a = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..=i {
            let (p, q) = (chosen[i].1, chosen[j].1);
            let c = cov.between(distance(p.position, q.position), p.age_s - q.age_s);
            a[i * n + j] = c;
            a[j * n + i] = c;
        }
    }
    if !cholesky(&mut a, n) {
        return Estimate {
            residual: 0.0,
            variance: prior,
        };
    }
    // y = L⁻¹ k, z = L⁻¹ r: mean = yᵀz, variance = prior − yᵀy.
    let mut y: Vec<f64> = chosen.iter().map(|c| c.0).collect();
    let mut z: Vec<f64> = chosen.iter().map(|c| c.1.residual).collect();
    forward(&a, n, &mut y);
    forward(&a, n, &mut z);
    let dot = |p: &[f64], q: &[f64]| p.iter().zip(q).map(|(a, b)| a * b).sum::<f64>();
    let mean = dot(&y, &z);
    let explained = dot(&y, &y);
    match mean_model {
        Mean::Known => Estimate {
            residual: mean,
            variance: (prior - explained).clamp(0.0, prior),
        },
        Mean::Unknown => {
            // o = L⁻¹1; the Lagrange multiplier mu = (1 − 1ᵀK⁻¹k) / 1ᵀK⁻¹1 moves the simple
            // kriging weights K⁻¹k along K⁻¹1 until they sum to 1.
            let mut o = vec![1.0; n];
            forward(&a, n, &mut o);
            let oo = dot(&o, &o);
            if !(oo > 0.0 && oo.is_finite()) {
                return Estimate {
                    residual: mean,
                    variance: (prior - explained).clamp(0.0, prior),
                };
            }
            let mu = (1.0 - dot(&o, &y)) / oo;
            let residual = mean + mu * dot(&o, &z);
            let variance = (prior - explained + mu * mu * oo).max(0.0);
            if residual.is_finite() && variance.is_finite() {
                Estimate { residual, variance }
            } else {
                Estimate {
                    residual: mean,
                    variance: (prior - explained).clamp(0.0, prior),
                }
            }
        }
    }
}

/// One sensor's series for fitting: position and readings on a regular time grid.
#[derive(Debug, Clone, Copy)]
pub struct SensorSeries<'a> {
    /// Position, east/north metres.
    pub position: [f64; 2],
    /// Reading times, seconds, ascending, on multiples of the grid step from a common origin.
    pub times: &'a [i64],
    /// Readings, the modality's unit.
    pub values: &'a [f64],
}

impl<'a> SensorSeries<'a> {
    /// The readings stamped before `t` (seconds): a prefix, same position.
    pub fn before(&self, t: i64) -> SensorSeries<'a> {
        let n = self.times.partition_point(|&x| x < t);
        SensorSeries {
            times: &self.times[..n],
            values: &self.values[..n],
            ..*self
        }
    }
}

/// Options of [`fit`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitOptions {
    /// Sampling step of the series, seconds.
    pub step_s: i64,
    /// Largest lag used for the temporal fit, in steps.
    pub max_lag_steps: i64,
    /// Fewest common points for a pair's correlation to count.
    pub min_overlap: usize,
    /// At most this many sensor pairs for the spatial fit (an even subsample beyond).
    pub max_pairs: usize,
    /// Bounds of the spatial range, metres.
    pub range_bounds_m: (f64, f64),
    /// Fit a temporal nugget (the intercept of the lag fit, [`Covariance::temporal_share`])
    /// instead of forcing the temporal correlation through 1 at lag 0.
    pub temporal_nugget: bool,
}

impl Default for FitOptions {
    /// Daily step, lags up to 14 steps, 10 common points, 20,000 pairs, range 1 m .. 100 km,
    /// with a temporal nugget.
    fn default() -> Self {
        Self {
            step_s: 86_400,
            max_lag_steps: 14,
            min_overlap: 10,
            max_pairs: 20_000,
            range_bounds_m: (1.0, 100_000.0),
            temporal_nugget: true,
        }
    }
}

/// A fitted field model: the covariance and every sensor's mean.
#[derive(Debug, Clone, PartialEq)]
pub struct FieldModel {
    /// The residual covariance.
    pub covariance: Covariance,
    /// Per sensor (input order): its mean, the modality's unit (the mean of all sensors for a
    /// sensor without readings).
    pub means: Vec<f64>,
}

/// Pearson correlation of two residual series at common times (sorted), with the count.
fn paired(ta: &[i64], ra: &[f64], tb: &[i64], rb: &[f64], shift: i64) -> (f64, f64, f64, usize) {
    let (mut i, mut j) = (0, 0);
    let (mut sab, mut saa, mut sbb, mut n) = (0.0, 0.0, 0.0, 0usize);
    while i < ta.len() && j < tb.len() {
        let (x, y) = (ta[i] + shift, tb[j]);
        match x.cmp(&y) {
            std::cmp::Ordering::Less => i += 1,
            std::cmp::Ordering::Greater => j += 1,
            std::cmp::Ordering::Equal => {
                sab += ra[i] * rb[j];
                saa += ra[i] * ra[i];
                sbb += rb[j] * rb[j];
                n += 1;
                i += 1;
                j += 1;
            }
        }
    }
    (sab, saa, sbb, n)
}

/// Least-squares line through (x, y) points: (slope, intercept).
fn line(points: &[(f64, f64)]) -> (f64, f64) {
    let m = points.len() as f64;
    let mx = points.iter().map(|p| p.0).sum::<f64>() / m;
    let my = points.iter().map(|p| p.1).sum::<f64>() / m;
    let sxy: f64 = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = points.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let slope = if sxx > 0.0 { sxy / sxx } else { 0.0 };
    (slope, my - slope * mx)
}

/// Fits the means and the covariance from sensor series.
///
/// The mean of each sensor is the mean of its readings; residuals are readings minus means.
/// The total variance is the pooled residual variance. The time scale comes from the pooled
/// lag-k autocorrelation (k = 1..max_lag): −1/slope of a least-squares line through
/// (k·step, ln ρ_k), and its intercept the share of the variance that persists past one step
/// ([`Covariance::temporal_share`], when [`FitOptions::temporal_nugget`]). The pairwise zero-lag correlations ρ(d) ≈ c·exp(−d/range) give, by a
/// least-squares line through (d, ln ρ), the range (−1/slope, clamped to the bounds) and the
/// smooth field's share c = e^intercept of the variance: sill = c·total, nugget =
/// (1 − c)·total. Errors when fewer than 2 sensors or too few points.
pub fn fit(series: &[SensorSeries<'_>], options: &FitOptions) -> Result<FieldModel, KrigingError> {
    let step = options.step_s.max(1);
    let means_opt: Vec<Option<f64>> = series
        .iter()
        .map(|s| {
            let v: Vec<f64> = s.values.iter().copied().filter(|x| x.is_finite()).collect();
            (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
        })
        .collect();
    let known: Vec<f64> = means_opt.iter().flatten().copied().collect();
    if known.len() < 2 {
        return Err(KrigingError::Fit(format!(
            "{} sensors with readings; at least 2 are needed",
            known.len()
        )));
    }
    let global = known.iter().sum::<f64>() / known.len() as f64;
    let means: Vec<f64> = means_opt.iter().map(|m| m.unwrap_or(global)).collect();
    let residuals: Vec<Vec<f64>> = series
        .iter()
        .zip(&means)
        .map(|(s, m)| s.values.iter().map(|v| v - m).collect())
        .collect();
    let (mut ss, mut n) = (0.0, 0usize);
    for r in &residuals {
        ss += r.iter().map(|x| x * x).sum::<f64>();
        n += r.len();
    }
    if n < 3 {
        return Err(KrigingError::Fit(format!(
            "{n} readings; at least 3 are needed"
        )));
    }
    let total = (ss / n as f64).max(1e-300);
    // Temporal: pooled autocorrelation by lag.
    let mut lag_points = Vec::new();
    for k in 1..=options.max_lag_steps.max(1) {
        let (mut sab, mut saa, mut sbb, mut cnt) = (0.0, 0.0, 0.0, 0);
        for (s, r) in series.iter().zip(&residuals) {
            let (a, b, c, m) = paired(s.times, r, s.times, r, k * step);
            sab += a;
            saa += b;
            sbb += c;
            cnt += m;
        }
        if cnt >= options.min_overlap && saa > 0.0 && sbb > 0.0 {
            let rho = sab / (saa * sbb).sqrt();
            if rho > 0.05 {
                lag_points.push(((k * step) as f64, rho.ln()));
            }
        }
    }
    // ln ρ_k ≈ ln share − k·step/τ: the slope gives the time scale, the intercept the share
    // of the variance that persists past one step (the rest is a temporal nugget, renewed at
    // every step). Without the intercept, a fast component (rain pulses, noise) that is gone
    // after a day would be spread over a long time scale and a day-old reading would look
    // almost as good as a fresh one.
    let (time_scale_s, temporal_share) = match lag_points.len() {
        0 => (step as f64 * 0.5, 1.0),
        1 => {
            let (x, y) = lag_points[0];
            (x / (-y).max(1e-6), 1.0)
        }
        _ => {
            let (slope, intercept) = line(&lag_points);
            (
                -1.0 / slope.min(-1e-15),
                if options.temporal_nugget {
                    intercept.exp().clamp(0.05, 1.0)
                } else {
                    1.0
                },
            )
        }
    };
    let time_scale_s = time_scale_s.clamp(step as f64 * 0.1, 1e9);
    // Spatial: pairwise zero-lag correlations against distance; the intercept is the smooth
    // field's share of the variance (the rest is the sensors' own deviations, the nugget).
    let ns = series.len();
    let n_pairs = ns * (ns - 1) / 2;
    let stride = n_pairs.div_ceil(options.max_pairs.max(1)).max(1);
    let mut pair_points = Vec::new();
    let mut pair = 0usize;
    for i in 0..ns {
        for j in i + 1..ns {
            pair += 1;
            if !pair.is_multiple_of(stride) {
                continue;
            }
            let (a, b) = (&series[i], &series[j]);
            let (sab, saa, sbb, cnt) = paired(a.times, &residuals[i], b.times, &residuals[j], 0);
            if cnt < options.min_overlap || saa <= 0.0 || sbb <= 0.0 {
                continue;
            }
            let rho = sab / (saa * sbb).sqrt();
            let d = distance(a.position, b.position);
            if rho > 0.05 && d > 0.0 {
                pair_points.push((d, rho.ln()));
            }
        }
    }
    let (lo, hi) = options.range_bounds_m;
    let (c, range_m) = match pair_points.len() {
        0 => (0.5, lo),
        1 => (
            1.0,
            (pair_points[0].0 / (-pair_points[0].1).max(1e-6)).clamp(lo, hi),
        ),
        _ => {
            let (slope, intercept) = line(&pair_points);
            let c = intercept.exp().clamp(0.05, 0.999);
            (c, (-1.0 / slope.min(-1e-15)).clamp(lo, hi))
        }
    };
    let covariance = Covariance::new(c * total, (1.0 - c) * total, range_m, time_scale_s)?
        .with_temporal_share(temporal_share)?;
    Ok(FieldModel { covariance, means })
}

/// Largest number of cells [`variance_reduction`] accepts (a dense cells × cells matrix).
pub const MAX_VARIANCE_CELLS: usize = 3_000;

/// Expected reduction of the field's posterior variance from visiting cells, greedily.
///
/// Cells are points (`centres`, metres) with a weight (e.g. their number of sensors); cell i
/// was last observed `ages_s[i]` seconds ago (`None`: never). The posterior covariance of the
/// cells' current residuals given those observations is computed once; then the cell whose
/// fresh observation reduces the weighted sum of posterior variances most
/// is picked, the posterior updated (rank one), and so on until every cell is picked (fresh
/// readings are taken as exact: a cell's own deviation, the nugget, is then known). The
/// returned score of a cell is its marginal gain when picked, divided by the prior variance
/// (a dimensionless count of "readings' worth" of variance); gains never increase along the
/// greedy order, which is what makes the set function submodular-friendly for the router.
pub fn variance_reduction(
    cov: &Covariance,
    centres: &[[f64; 2]],
    ages_s: &[Option<f64>],
    weights: &[f64],
) -> Result<Vec<f64>, KrigingError> {
    let m = centres.len();
    for (what, got) in [("ages", ages_s.len()), ("weights", weights.len())] {
        if got != m {
            return Err(KrigingError::Length {
                what,
                got,
                expected: m,
            });
        }
    }
    if m > MAX_VARIANCE_CELLS {
        return Err(KrigingError::TooLarge {
            cells: m,
            max: MAX_VARIANCE_CELLS,
        });
    }
    // Prior covariance of the cells' current residuals (a cell as one sensor at its centre).
    let between = |i: usize, j: usize, lag: f64| {
        let d = if i == j {
            0.0
        } else {
            distance(centres[i], centres[j]).max(1e-9)
        };
        cov.between(d, lag)
    };
    // Fresh readings are exact up to this numerical noise, the unit squared.
    let noise = cov.prior_variance() * 1e-9;
    let mut p = vec![0.0; m * m];
    for i in 0..m {
        for j in 0..=i {
            let c = between(i, j, 0.0);
            p[i * m + j] = c;
            p[j * m + i] = c;
        }
    }
    // Condition on the old observations: P -= K_TO (K_OO + nugget)⁻¹ K_OT.
    let obs: Vec<usize> = (0..m)
        .filter(|&i| ages_s[i].is_some_and(f64::is_finite))
        .collect();
    let no = obs.len();
    if no > 0 {
        let age = |i: usize| ages_s[i].unwrap_or(0.0).max(0.0);
        let mut a = vec![0.0; no * no];
        for x in 0..no {
            for y in 0..=x {
                let (i, j) = (obs[x], obs[y]);
                let mut c = between(i, j, age(i) - age(j));
                if x == y {
                    c += noise;
                }
                a[x * no + y] = c;
                a[y * no + x] = c;
            }
        }
        if cholesky(&mut a, no) {
            // W = L⁻¹ K_OT (no × m), then P -= Wᵀ W.
            let mut w = vec![0.0; no * m];
            for t in 0..m {
                let mut col: Vec<f64> = obs.iter().map(|&i| between(i, t, age(i))).collect();
                forward(&a, no, &mut col);
                for x in 0..no {
                    w[x * m + t] = col[x];
                }
            }
            for i in 0..m {
                for j in 0..=i {
                    let s: f64 = (0..no).map(|x| w[x * m + i] * w[x * m + j]).sum();
                    p[i * m + j] -= s;
                    if i != j {
                        p[j * m + i] -= s;
                    }
                }
            }
        }
    }
    let prior = cov.prior_variance();
    let mut scores = vec![0.0; m];
    let mut picked = vec![false; m];
    for _ in 0..m {
        let mut best: Option<(usize, f64)> = None;
        for c in (0..m).filter(|&c| !picked[c]) {
            let denom = p[c * m + c].max(0.0) + noise;
            let gain: f64 = (0..m)
                .map(|i| weights[i] * p[i * m + c] * p[i * m + c])
                .sum::<f64>()
                / denom;
            if best.is_none_or(|b| gain > b.1) {
                best = Some((c, gain));
            }
        }
        let Some((c, gain)) = best else { break };
        picked[c] = true;
        scores[c] = (gain / prior).max(0.0);
        let denom = p[c * m + c].max(0.0) + noise;
        let col: Vec<f64> = (0..m).map(|i| p[i * m + c]).collect();
        for i in 0..m {
            for j in 0..m {
                p[i * m + j] -= col[i] * col[j] / denom;
            }
        }
    }
    Ok(scores)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn cov() -> Covariance {
        Covariance::new(1.0, 0.01, 100.0, 10.0 * 86_400.0).unwrap()
    }

    #[test]
    fn a_fresh_reading_at_the_target_is_returned_exactly() {
        let obs = [Observation {
            position: [0.0, 0.0],
            age_s: 0.0,
            residual: 0.7,
        }];
        let e = krige(&cov(), &obs, [0.0, 0.0], 8);
        assert!((e.residual - 0.7).abs() < 1e-9, "{e:?}");
        assert!(e.variance < 1e-9, "{e:?}");
    }

    #[test]
    fn without_observations_the_prior() {
        let e = krige(&cov(), &[], [0.0, 0.0], 8);
        assert_eq!(e.residual, 0.0);
        assert!((e.variance - 1.01).abs() < 1e-12);
    }

    #[test]
    fn older_and_farther_observations_weigh_less() {
        let c = cov();
        let near = |age: f64, d: f64| {
            krige(
                &c,
                &[Observation {
                    position: [d, 0.0],
                    age_s: age,
                    residual: 1.0,
                }],
                [0.0, 0.0],
                8,
            )
        };
        assert!(near(86_400.0, 0.0).residual > near(5.0 * 86_400.0, 0.0).residual);
        assert!(near(0.0, 10.0).residual > near(0.0, 200.0).residual);
        assert!(near(0.0, 10.0).variance < near(0.0, 200.0).variance);
    }

    #[test]
    fn ordinary_kriging_keeps_a_field_wide_shift() {
        // Every observation is +0.5 above its long-run mean (a wet spell): simple kriging
        // pulls a stale target back towards its mean, ordinary kriging keeps the level.
        let c = Covariance::new(1.0, 0.1, 100.0, 20.0 * 86_400.0).unwrap();
        let obs: Vec<Observation> = [[0.0, 0.0], [80.0, 0.0], [0.0, 120.0]]
            .iter()
            .enumerate()
            .map(|(k, p)| Observation {
                position: *p,
                age_s: (5 + 3 * k) as f64 * 86_400.0,
                residual: 0.5,
            })
            .collect();
        let simple = krige_with(&c, &obs, [0.0, 0.0], 8, Mean::Known);
        let ordinary = krige_with(&c, &obs, [0.0, 0.0], 8, Mean::Unknown);
        assert!(simple.residual < 0.45, "{simple:?}");
        assert!((ordinary.residual - 0.5).abs() < 1e-9, "{ordinary:?}");
        assert!(ordinary.variance >= simple.variance - 1e-12);
    }

    #[test]
    fn ordinary_kriging_returns_a_fresh_reading_exactly() {
        let obs = [
            Observation {
                position: [0.0, 0.0],
                age_s: 0.0,
                residual: -0.3,
            },
            Observation {
                position: [30.0, 0.0],
                age_s: 86_400.0,
                residual: 0.9,
            },
        ];
        let e = krige_with(&cov(), &obs, [0.0, 0.0], 8, Mean::Unknown);
        assert!((e.residual + 0.3).abs() < 1e-6, "{e:?}");
        assert!(e.variance < 1e-6, "{e:?}");
        // Without observations: the prior.
        let p = krige_with(&cov(), &[], [0.0, 0.0], 8, Mean::Unknown);
        assert_eq!(p.residual, 0.0);
        assert!((p.variance - cov().prior_variance()).abs() < 1e-12);
    }

    #[test]
    fn a_temporal_nugget_makes_a_day_old_reading_worth_less() {
        let c = cov();
        let n = c.with_temporal_share(0.8).unwrap();
        assert_eq!(n.temporal(0.0), 1.0);
        assert!((n.temporal(86_400.0) - 0.8 * c.temporal(86_400.0)).abs() < 1e-12);
        assert!(c.with_temporal_share(0.0).is_err());
        assert!(c.with_temporal_share(1.5).is_err());
        let one = |cov: &Covariance| {
            krige(
                cov,
                &[Observation {
                    position: [0.0, 0.0],
                    age_s: 86_400.0,
                    residual: 1.0,
                }],
                [0.0, 0.0],
                8,
            )
        };
        assert!(one(&n).variance > one(&c).variance);
    }

    #[test]
    fn fit_finds_the_temporal_nugget_of_a_noisy_series() {
        // A slow signal plus fresh noise every day: the lag-1 correlation drops at once by
        // the noise share, then decays slowly; the fit must put the drop in the nugget.
        let day = 86_400;
        let times: Vec<i64> = (0..600).map(|d| d * day).collect();
        let noise = |k: usize, s: f64| ((k as f64 * 12.9898 + s).sin() * 43_758.545).fract() - 0.5;
        let series: Vec<Vec<f64>> = (0..3)
            .map(|s| {
                (0..600)
                    .map(|d| (d as f64 / 60.0).sin() + 0.8 * noise(d, s as f64))
                    .collect()
            })
            .collect();
        let s: Vec<SensorSeries<'_>> = series
            .iter()
            .enumerate()
            .map(|(k, v)| SensorSeries {
                position: [40.0 * k as f64, 0.0],
                times: &times,
                values: v,
            })
            .collect();
        let with = fit(&s, &FitOptions::default()).unwrap().covariance;
        let without = fit(
            &s,
            &FitOptions {
                temporal_nugget: false,
                ..FitOptions::default()
            },
        )
        .unwrap()
        .covariance;
        assert!(with.temporal_share < 0.95, "{with:?}");
        assert_eq!(without.temporal_share, 1.0);
        // The model's lag-1 correlation is close to the data's (well below 1).
        assert!(with.temporal(day as f64) < 0.95, "{with:?}");
    }

    #[test]
    fn invalid_parameters_are_refused() {
        assert!(Covariance::new(0.0, 0.0, 1.0, 1.0).is_err());
        assert!(Covariance::new(1.0, -1.0, 1.0, 1.0).is_err());
        assert!(Covariance::new(1.0, 0.0, f64::NAN, 1.0).is_err());
    }

    #[test]
    fn fit_recovers_a_smooth_correlated_field() {
        // Two sensors 50 m apart sharing an AR(1)-like seasonal signal.
        let day = 86_400;
        let times: Vec<i64> = (0..400).map(|d| d * day).collect();
        let base: Vec<f64> = (0..400)
            .map(|d| (d as f64 / 40.0).sin() + 0.3 * (d as f64 / 7.0).cos())
            .collect();
        let a: Vec<f64> = base.iter().map(|v| 0.3 + 0.05 * v).collect();
        let b: Vec<f64> = base
            .iter()
            .enumerate()
            .map(|(k, v)| 0.2 + 0.05 * v + 0.002 * (k as f64 * 1.7).sin())
            .collect();
        let s = [
            SensorSeries {
                position: [0.0, 0.0],
                times: &times,
                values: &a,
            },
            SensorSeries {
                position: [50.0, 0.0],
                times: &times,
                values: &b,
            },
        ];
        let m = fit(&s, &FitOptions::default()).unwrap();
        assert!((m.means[0] - 0.3).abs() < 0.01 && (m.means[1] - 0.2).abs() < 0.01);
        let c = m.covariance;
        assert!(c.time_scale_s > 5.0 * day as f64, "{c:?}");
        assert!(c.range_m > 200.0, "highly correlated pair: {c:?}");
        assert!(c.nugget < c.sill);
    }

    #[test]
    fn fit_needs_two_sensors() {
        let t = [0i64, 86_400];
        let v = [0.1, 0.2];
        let s = [SensorSeries {
            position: [0.0, 0.0],
            times: &t,
            values: &v,
        }];
        assert!(fit(&s, &FitOptions::default()).is_err());
    }

    #[test]
    fn variance_reduction_prefers_the_unknown_and_isolated() {
        let c = cov();
        // Cells 0 and 1 close together, 2 far away; 0 freshly observed.
        let centres = [[0.0, 0.0], [10.0, 0.0], [1_000.0, 0.0]];
        let ages = [Some(0.0), None, None];
        let s = variance_reduction(&c, &centres, &ages, &[1.0; 3]).unwrap();
        assert!(s[2] > s[1], "{s:?}");
        assert!(s[0] < s[1], "{s:?}");
        assert!(variance_reduction(&c, &centres, &ages[..2], &[1.0; 3]).is_err());
    }

    proptest! {
        #[test]
        fn kriging_variance_is_within_the_prior(
            pts in proptest::collection::vec((-500.0f64..500.0, -500.0f64..500.0, 0.0f64..1e6, -1.0f64..1.0), 0..20),
            tx in -500.0f64..500.0,
        ) {
            let obs: Vec<Observation> = pts.iter().map(|&(x, y, a, r)| Observation {
                position: [x, y], age_s: a, residual: r }).collect();
            let c = cov();
            let e = krige(&c, &obs, [tx, 0.0], 8);
            prop_assert!(e.variance >= 0.0 && e.variance <= c.prior_variance() + 1e-12);
            prop_assert!(e.residual.is_finite());
        }

        #[test]
        fn ordinary_kriging_is_finite_and_its_weights_sum_to_one(
            pts in proptest::collection::vec((-500.0f64..500.0, -500.0f64..500.0, 0.0f64..1e6, -1.0f64..1.0), 1..20),
            tx in -500.0f64..500.0,
            shift in -2.0f64..2.0,
        ) {
            // Weights summing to 1: adding a constant to every residual adds it to the estimate.
            let c = cov().with_temporal_share(0.9).unwrap();
            let obs: Vec<Observation> = pts.iter().map(|&(x, y, a, r)| Observation {
                position: [x, y], age_s: a, residual: r }).collect();
            let shifted: Vec<Observation> = obs.iter().map(|o| Observation {
                residual: o.residual + shift, ..*o }).collect();
            let e = krige_with(&c, &obs, [tx, 0.0], 8, Mean::Unknown);
            let f = krige_with(&c, &shifted, [tx, 0.0], 8, Mean::Unknown);
            prop_assert!(e.residual.is_finite() && e.variance.is_finite() && e.variance >= 0.0);
            prop_assert!((f.residual - e.residual - shift).abs() < 1e-6 * (1.0 + shift.abs()),
                "{e:?} {f:?}");
        }

        #[test]
        fn greedy_gains_are_finite_and_non_negative(
            pts in proptest::collection::vec((-300.0f64..300.0, -300.0f64..300.0, proptest::option::of(0.0f64..1e6)), 1..15),
        ) {
            let centres: Vec<[f64; 2]> = pts.iter().map(|p| [p.0, p.1]).collect();
            let ages: Vec<Option<f64>> = pts.iter().map(|p| p.2).collect();
            let s = variance_reduction(&cov(), &centres, &ages, &vec![1.0; pts.len()]).unwrap();
            let mut sorted = s.clone();
            sorted.sort_by(|a, b| b.total_cmp(a));
            prop_assert!(sorted.iter().all(|v| *v >= 0.0 && v.is_finite()));
        }
    }
}
