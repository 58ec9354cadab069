//! The dynamic field model: every sensor's value as a Gaussian process over sensors × time,
//! with a cross-sensor covariance of *levels* learned from history and first-order
//! autoregressive dynamics of the deviations from each sensor's mean, run as a Kalman filter.
//!
//! Model ([`DynamicModel`]): `x_i(t) = μ_i + d_i(t)`, the deviations `d(t)` stationary with
//! covariance `Σ` (sensors × sensors) and `d(t + Δ) = a(Δ)·d(t) + w`, `a(Δ) = φ^(Δ/step)`,
//! `w ~ N(0, (1 − a²)·Σ)`; a reading is `x_i(t) + ε`, `ε ~ N(0, noise)`. So
//! `cov(x_i(t), x_j(t')) = Σ_ij · φ^(|t − t'|/step)` (separable), which joins the two
//! classical estimates: a sensor read a moment ago is known from its own reading (the last
//! value carried forward, with its change since inferred from the sensors read since), one
//! not read for a long time from the sensors read now (the Gaussian conditional of levels,
//! `μ_u + Σ_us Σ_ss⁻¹ (x_s − μ_s)`), and everything in between is weighed by the model.
//!
//! - [`fit_dynamic`] learns `μ`, `Σ` and `φ` from sensor series with missing values:
//!   pairwise-complete covariances, shrunk towards their diagonal (Schäfer & Strimmer's
//!   intensity for the correlations, with the effective sample size of autocorrelated
//!   series; raised further until `Σ` is positive definite), `φ` from the pooled
//!   autocorrelation of the deviations.
//! - [`FieldFilter`] is the Kalman filter: [`FieldFilter::advance`] in time,
//!   [`FieldFilter::observe`] a reading, [`FieldFilter::estimate`] any sensor's posterior
//!   mean and variance; O(n²) per step and per reading, no refit per query.
//!
//! Units: times and steps seconds; values and means in the modality's unit, variances in
//! its square.

use crate::{KrigingError, SensorSeries, cholesky, paired};

/// Largest number of sensors of a [`DynamicModel`] (a dense sensors × sensors covariance and
/// O(n²) work per reading).
pub const MAX_DYNAMIC_SENSORS: usize = 2_000;

/// How the sample correlations are shrunk towards 0 (the covariance towards its diagonal).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Shrinkage {
    /// Schäfer & Strimmer's estimated intensity, `Σ var(r_ij) / Σ r_ij²` over pairs, with
    /// `var(r_ij) ≈ (1 − r_ij²)² / (n_eff − 1)` and `n_eff = n_ij · (1 − φ) / (1 + φ)`
    /// (the effective sample size of two AR(1) series).
    Auto,
    /// A given intensity in [0, 1] (0: the sample correlations).
    Fixed(f64),
}

/// Options of [`fit_dynamic`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DynamicFitOptions {
    /// Sampling step of the series, seconds (the unit of `φ`).
    pub step_s: i64,
    /// Largest lag of the autocorrelation fit of `φ`, seconds.
    pub max_lag_s: i64,
    /// Fewest common points for a pair's covariance to count (fewer: 0).
    pub min_overlap: usize,
    /// Shrinkage of the correlations.
    pub shrinkage: Shrinkage,
    /// Reading noise variance as a share of the mean sensor variance (the nugget that keeps
    /// the filter well conditioned; readings are nearly exact).
    pub noise_share: f64,
    /// Model a common level shared by every sensor (the field-wide wetness) as its own
    /// state with its own persistence, the sensors' deviations from it with theirs
    /// ([`DynamicModel::common`]); false: one persistence for the whole deviation.
    pub common_mode: bool,
}

impl Default for DynamicFitOptions {
    /// Daily step, lags up to 14 days, 10 common points, automatic shrinkage, noise 0.1% of
    /// the variance.
    fn default() -> Self {
        Self {
            step_s: 86_400,
            max_lag_s: 14 * 86_400,
            min_overlap: 10,
            shrinkage: Shrinkage::Auto,
            noise_share: 1e-3,
            common_mode: false,
        }
    }
}

/// A fitted dynamic field model (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct DynamicModel {
    means: Vec<f64>,
    cov: Vec<f64>,
    phi: f64,
    step_s: f64,
    noise: f64,
    shrinkage: f64,
    /// Stationary variance (unit²) and per-step persistence of the common level (0, 0: none).
    common_var: f64,
    common_phi: f64,
    /// Per-sensor growth rate (unit²/s) of the unshared component's variance (empty: none).
    own_rate: Vec<f64>,
}

impl DynamicModel {
    /// A model from its parts: per-sensor means (unit), the stationary covariance of the
    /// deviations (row-major n × n, unit², symmetric positive definite), the lag-one
    /// autocorrelation `phi` per `step_s` seconds (in [0, 1]) and the reading noise variance
    /// (unit², ≥ 0).
    ///
    /// Errors: lengths that do not match, a non-finite entry, an asymmetric or not positive
    /// definite covariance, `phi` outside [0, 1], a non-positive step, a negative noise.
    pub fn new(
        means: Vec<f64>,
        cov: Vec<f64>,
        phi: f64,
        step_s: f64,
        noise: f64,
    ) -> Result<Self, KrigingError> {
        let n = means.len();
        if n > MAX_DYNAMIC_SENSORS {
            return Err(KrigingError::Fit(format!(
                "{n} sensors: the dynamic model handles at most {MAX_DYNAMIC_SENSORS}"
            )));
        }
        if cov.len() != n * n {
            return Err(KrigingError::Length {
                what: "covariance entries",
                got: cov.len(),
                expected: n * n,
            });
        }
        check("phi", phi, (0.0..=1.0).contains(&phi), "in [0, 1]")?;
        check("step_s", step_s, step_s > 0.0 && step_s.is_finite(), "> 0")?;
        check("noise", noise, noise >= 0.0 && noise.is_finite(), ">= 0")?;
        for &m in &means {
            check("mean", m, m.is_finite(), "finite")?;
        }
        for i in 0..n {
            for j in 0..n {
                let (a, b) = (cov[i * n + j], cov[j * n + i]);
                check("covariance", a, a.is_finite(), "finite")?;
                let tol = 1e-9 * (cov[i * n + i].abs() + cov[j * n + j].abs()).max(1e-300);
                check("covariance", a - b, (a - b).abs() <= tol, "symmetric")?;
            }
        }
        let mut l = cov.clone();
        if n > 0 && !cholesky(&mut l, n) {
            return Err(KrigingError::Fit(
                "the covariance is not positive definite".into(),
            ));
        }
        Ok(Self {
            means,
            cov,
            phi,
            step_s,
            noise,
            shrinkage: 0.0,
            common_var: 0.0,
            common_phi: 0.0,
            own_rate: Vec::new(),
        })
    }

    /// The same model with a common level: `x_i(t) = μ_i + c(t) + d_i(t)`, `c` stationary
    /// with variance `var` (unit²) and lag-one autocorrelation `phi` per step, independent of
    /// the deviations `d`.
    ///
    /// Errors: a negative or non-finite variance, `phi` outside [0, 1].
    pub fn with_common(mut self, var: f64, phi: f64) -> Result<Self, KrigingError> {
        check(
            "common variance",
            var,
            var >= 0.0 && var.is_finite(),
            ">= 0",
        )?;
        check("common phi", phi, (0.0..=1.0).contains(&phi), "in [0, 1]")?;
        self.common_var = var;
        self.common_phi = phi;
        Ok(self)
    }

    /// The same model with an unshared per-sensor component: a random walk per sensor whose
    /// variance grows by `rates[i]` (unit²/s) for every second since sensor `i` was last
    /// read, added to that sensor's predictive variance. A reading of a sensor removes its
    /// own unshared uncertainty and says nothing about the other sensors' unshared parts.
    /// All rates 0 gives the model without the component exactly.
    ///
    /// Errors: a length other than the number of sensors, a negative or non-finite rate.
    pub fn with_own_rates(mut self, rates: Vec<f64>) -> Result<Self, KrigingError> {
        if rates.len() != self.len() {
            return Err(KrigingError::Length {
                what: "unshared rates",
                got: rates.len(),
                expected: self.len(),
            });
        }
        for &r in &rates {
            check("unshared rate", r, r >= 0.0 && r.is_finite(), ">= 0")?;
        }
        self.own_rate = if rates.iter().all(|&r| r == 0.0) {
            Vec::new()
        } else {
            rates
        };
        Ok(self)
    }

    /// Per-sensor growth rates (unit²/s) of the unshared component (empty when none).
    pub fn own_rates(&self) -> &[f64] {
        &self.own_rate
    }

    /// The common level's stationary variance (unit²) and per-step persistence (0, 0 when
    /// the model has none).
    pub fn common(&self) -> (f64, f64) {
        (self.common_var, self.common_phi)
    }

    /// A sensor's stationary (prior) variance, unit²: its deviation's plus the common level's.
    pub fn prior_variance(&self, sensor: usize) -> f64 {
        let n = self.len();
        if sensor >= n {
            return f64::NAN;
        }
        self.cov[sensor * n + sensor] + self.common_var
    }

    /// Number of sensors.
    pub fn len(&self) -> usize {
        self.means.len()
    }

    /// Whether the model has no sensors.
    pub fn is_empty(&self) -> bool {
        self.means.is_empty()
    }

    /// Per-sensor means, the modality's unit.
    pub fn means(&self) -> &[f64] {
        &self.means
    }

    /// The stationary covariance of the deviations, row-major n × n, unit².
    pub fn covariance(&self) -> &[f64] {
        &self.cov
    }

    /// Lag-one autocorrelation of the deviations per [`Self::step_s`].
    pub fn phi(&self) -> f64 {
        self.phi
    }

    /// The step `phi` is given for, seconds.
    pub fn step_s(&self) -> f64 {
        self.step_s
    }

    /// Reading noise variance, unit².
    pub fn noise(&self) -> f64 {
        self.noise
    }

    /// The shrinkage intensity the fit used (0 for a model built with [`Self::new`]).
    pub fn shrinkage(&self) -> f64 {
        self.shrinkage
    }

    /// Correlation of a deviation with itself `lag_s` seconds later: `φ^(|lag|/step)`.
    pub fn persistence(&self, lag_s: f64) -> f64 {
        decay(self.phi, lag_s, self.step_s)
    }

    /// A filter at time `time_s` (seconds) holding the stationary prior (nothing known yet).
    pub fn filter(&self, time_s: f64) -> FieldFilter<'_> {
        let n = self.len();
        let m = n + 1;
        let mut cov = vec![0.0; m * m];
        for i in 0..n {
            cov[i * m..i * m + n].copy_from_slice(&self.cov[i * n..(i + 1) * n]);
        }
        cov[n * m + n] = self.common_var;
        FieldFilter {
            model: self,
            time_s,
            mean: vec![0.0; m],
            cov,
            own_var: vec![0.0; self.own_rate.len()],
        }
    }

    /// The Gaussian conditional of levels at one time: every sensor's posterior mean and
    /// variance given readings `(sensor, value)` taken at that time (no dynamics).
    pub fn conditional(&self, readings: &[(usize, f64)]) -> Vec<(f64, f64)> {
        let mut f = self.filter(0.0);
        for &(i, v) in readings {
            f.observe(i, v);
        }
        (0..self.len()).map(|i| f.estimate(i)).collect()
    }

    /// Sum over all sensors of the posterior variance (unit²) given exact-up-to-noise
    /// readings of `sensors` at one time, from the stationary prior: what a visit to them
    /// leaves unknown. Lower is better; the prior total minus this is the information a
    /// visit brings.
    pub fn remaining_variance(&self, sensors: &[usize]) -> f64 {
        let mut f = self.filter(0.0);
        for &i in sensors {
            f.observe_variance_only(i);
        }
        f.total_variance()
    }
}

/// `phi^(|lag|/step)`, 1 at lag 0 even for `phi` = 0.
fn decay(phi: f64, lag_s: f64, step_s: f64) -> f64 {
    if lag_s == 0.0 {
        return 1.0;
    }
    if phi <= 0.0 {
        return 0.0;
    }
    (phi.ln() * lag_s.abs() / step_s).exp()
}

fn check(
    what: &'static str,
    value: f64,
    ok: bool,
    expected: &'static str,
) -> Result<(), KrigingError> {
    if ok {
        Ok(())
    } else {
        Err(KrigingError::Parameter {
            what,
            value,
            expected,
        })
    }
}

/// The Kalman filter of a [`DynamicModel`]: the posterior of every sensor's deviation and of
/// the common level (the last of the n + 1 states) given the readings observed so far, at
/// [`FieldFilter::time_s`].
#[derive(Debug, Clone)]
pub struct FieldFilter<'m> {
    model: &'m DynamicModel,
    time_s: f64,
    mean: Vec<f64>,
    cov: Vec<f64>,
    /// Unshared variance (unit²) each sensor has gathered since its last reading (empty when
    /// the model has no unshared component).
    own_var: Vec<f64>,
}

impl FieldFilter<'_> {
    /// The filter's current time, seconds.
    pub fn time_s(&self) -> f64 {
        self.time_s
    }

    /// Moves the filter to `time_s` (seconds): deviations decay by `a = φ^(Δ/step)` and the
    /// covariance relaxes towards the prior, `P ← a²·P + (1 − a²)·Σ`. A time not after the
    /// current one leaves the filter as it is (readings are taken in time order).
    pub fn advance(&mut self, time_s: f64) {
        let dt = time_s - self.time_s;
        if dt.is_nan() || dt <= 0.0 {
            return;
        }
        self.time_s = time_s;
        let model = self.model;
        for (v, r) in self.own_var.iter_mut().zip(&model.own_rate) {
            *v += r * dt;
        }
        let n = model.len();
        let m = n + 1;
        let a = model.persistence(dt);
        let ac = decay(model.common_phi, dt, model.step_s);
        if a == 1.0 && ac == 1.0 {
            return;
        }
        for x in &mut self.mean[..n] {
            *x *= a;
        }
        self.mean[n] *= ac;
        let a2 = a * a;
        for i in 0..n {
            let row = &mut self.cov[i * m..(i + 1) * m];
            for (p, s) in row[..n].iter_mut().zip(&model.cov[i * n..(i + 1) * n]) {
                *p = a2 * *p + (1.0 - a2) * s;
            }
            row[n] *= a * ac;
        }
        for j in 0..n {
            self.cov[n * m + j] *= a * ac;
        }
        let c = &mut self.cov[n * m + n];
        *c = ac * ac * *c + (1.0 - ac * ac) * model.common_var;
    }

    /// Takes a reading `value` (the modality's unit) of `sensor` at the filter's time.
    /// Out-of-range sensors and non-finite values are ignored.
    pub fn observe(&mut self, sensor: usize, value: f64) {
        let n = self.model.len();
        if sensor >= n || !value.is_finite() {
            return;
        }
        let innovation = value - self.model.means[sensor] - self.mean[sensor] - self.mean[n];
        if let Some(gain) = self.update(sensor) {
            for (m, g) in self.mean.iter_mut().zip(&gain) {
                *m += g * innovation;
            }
        }
        self.reset_own(sensor);
    }

    /// The covariance part of [`Self::observe`] only (the variance a reading leaves does not
    /// depend on its value).
    fn observe_variance_only(&mut self, sensor: usize) {
        if sensor < self.model.len() {
            self.update(sensor);
        }
    }

    /// Clears `sensor`'s unshared variance (a reading of it removes its own drift).
    fn reset_own(&mut self, sensor: usize) {
        if let Some(v) = self.own_var.get_mut(sensor) {
            *v = 0.0;
        }
    }

    /// The unshared variance (unit²) `sensor` has gathered since its last reading (0 when
    /// the model has no unshared component or the sensor is out of range).
    pub fn own_variance(&self, sensor: usize) -> f64 {
        self.own_var.get(sensor).copied().unwrap_or(0.0)
    }

    /// Rank-one covariance update for a reading of `sensor` (observation vector: its
    /// deviation plus the common level); the gain, or None when the reading carries no
    /// information (its variance is already at the noise floor).
    fn update(&mut self, sensor: usize) -> Option<Vec<f64>> {
        let n = self.model.len();
        let m = n + 1;
        // P hᵀ = P[:, sensor] + P[:, n].
        let col: Vec<f64> = (0..m)
            .map(|j| self.cov[j * m + sensor] + self.cov[j * m + n])
            .collect();
        let s = col[sensor] + col[n] + self.model.noise;
        let floor = 1e-12 * self.model.prior_variance(sensor).max(1e-300);
        if s.is_nan() || s <= floor {
            return None;
        }
        let gain: Vec<f64> = col.iter().map(|c| c / s).collect();
        for (i, &gi) in gain.iter().enumerate() {
            if gi == 0.0 {
                continue;
            }
            let row = &mut self.cov[i * m..(i + 1) * m];
            for (p, c) in row.iter_mut().zip(&col) {
                *p -= gi * c;
            }
        }
        // Keep the diagonal non-negative against rounding.
        for i in 0..m {
            let d = &mut self.cov[i * m + i];
            if *d < 0.0 {
                *d = 0.0;
            }
        }
        Some(gain)
    }

    /// Posterior mean (unit) and variance (unit²) of `sensor`'s value at the filter's time,
    /// without the reading noise. Out of range: NaN.
    pub fn estimate(&self, sensor: usize) -> (f64, f64) {
        let n = self.model.len();
        if sensor >= n {
            return (f64::NAN, f64::NAN);
        }
        let m = n + 1;
        let var = self.cov[sensor * m + sensor]
            + 2.0 * self.cov[sensor * m + n]
            + self.cov[n * m + n]
            + self.own_variance(sensor);
        (
            self.model.means[sensor] + self.mean[sensor] + self.mean[n],
            var.max(0.0),
        )
    }

    /// Sum of every sensor's posterior variance, unit².
    pub fn total_variance(&self) -> f64 {
        (0..self.model.len()).map(|i| self.estimate(i).1).sum()
    }

    /// The information a reading of each of `sensors` at the filter's time would bring:
    /// the expected reduction of [`Self::total_variance`] (unit², summed over *every*
    /// sensor, not only those read), which does not depend on the values read. Not additive:
    /// two correlated sensors tell less together than the sum of what each tells alone.
    /// Repeated and out-of-range sensors add nothing. The filter itself is left unchanged.
    ///
    /// Only the covariance entries the answer depends on are updated: every diagonal entry,
    /// the common level's column and the columns of the sensors still to be read (each
    /// entry through the same operations in the same order as the full rank-one updates of
    /// [`Self::observe`], so the same bits; about (k + 2)·(n + 1) instead of (n + 1)² per
    /// reading of k).
    pub fn information(&self, sensors: &[usize]) -> f64 {
        let before = self.total_variance();
        let n = self.model.len();
        let m = n + 1;
        let mut after = self.clone();
        let mut col = vec![0.0; m];
        let mut later: Vec<usize> = Vec::with_capacity(sensors.len() + 1);
        let mut is_later = vec![false; m];
        for (j, &sensor) in sensors.iter().enumerate() {
            if sensor < n {
                // The columns read by the updates still to come, and the level's.
                later.clear();
                is_later.iter_mut().for_each(|x| *x = false);
                for &c in sensors[j + 1..].iter().filter(|&&c| c < n).chain([&n]) {
                    if !is_later[c] {
                        is_later[c] = true;
                        later.push(c);
                    }
                }
                after.update_columns(sensor, &mut col, &later, &is_later);
            }
            after.reset_own(sensor);
        }
        (before - after.total_variance()).max(0.0)
    }

    /// [`Self::update`] for a reading of `sensor`, restricted to the columns `later` (flagged
    /// in `is_later`) and the diagonal; `col` is scratch of n + 1 values. Every entry kept
    /// gets exactly the operations of the full update.
    fn update_columns(
        &mut self,
        sensor: usize,
        col: &mut [f64],
        later: &[usize],
        is_later: &[bool],
    ) {
        let n = self.model.len();
        let m = n + 1;
        for (j, c) in col.iter_mut().enumerate() {
            *c = self.cov[j * m + sensor] + self.cov[j * m + n];
        }
        let s = col[sensor] + col[n] + self.model.noise;
        let floor = 1e-12 * self.model.prior_variance(sensor).max(1e-300);
        if s.is_nan() || s <= floor {
            return;
        }
        for i in 0..m {
            let gi = col[i] / s;
            if gi == 0.0 {
                continue;
            }
            let row = &mut self.cov[i * m..(i + 1) * m];
            for &c in later {
                row[c] -= gi * col[c];
            }
            if !is_later[i] {
                row[i] -= gi * col[i];
            }
        }
        for i in 0..m {
            let d = &mut self.cov[i * m + i];
            if *d < 0.0 {
                *d = 0.0;
            }
        }
    }
}

/// Learns the growth rates (unit²/s) of the unshared per-sensor component
/// ([`DynamicModel::with_own_rates`]) from history: for each sensor, the variance of the
/// one-step change of its deviation from the field mean (the mean over the sensors read at
/// that time), per second, halved (a change of a difference of two independent walks counts
/// each once), shrunk towards the pooled rate of all sensors with weight `prior_weight`
/// pseudo-changes: `r_i = (k_i·r̂_i + w·r̄)/(k_i + w)`. Steps whose two ends are not
/// `step_s` apart are skipped; a sensor with no usable change gets the pooled rate; no
/// usable change anywhere gives all zeros.
///
/// Errors: a non-positive step, a negative or non-finite prior weight.
pub fn fit_own_rates(
    series: &[SensorSeries<'_>],
    step_s: i64,
    prior_weight: f64,
) -> Result<Vec<f64>, KrigingError> {
    check("step_s", step_s as f64, step_s > 0, "> 0")?;
    check(
        "prior weight",
        prior_weight,
        prior_weight >= 0.0 && prior_weight.is_finite(),
        ">= 0",
    )?;
    let mut field: std::collections::BTreeMap<i64, (f64, usize)> = Default::default();
    for s in series {
        for (&t, &v) in s.times.iter().zip(s.values) {
            if v.is_finite() {
                let e = field.entry(t).or_insert((0.0, 0));
                e.0 += v;
                e.1 += 1;
            }
        }
    }
    let dev = |t: i64, v: f64| field.get(&t).map(|&(sum, k)| v - sum / k as f64);
    let mut per: Vec<(f64, usize)> = Vec::with_capacity(series.len());
    for s in series {
        let (mut sq, mut k) = (0.0, 0usize);
        for w in 0..s.times.len().saturating_sub(1) {
            let (t0, t1) = (s.times[w], s.times[w + 1]);
            let (v0, v1) = (s.values[w], s.values[w + 1]);
            if t1 - t0 != step_s || !v0.is_finite() || !v1.is_finite() {
                continue;
            }
            if let (Some(d0), Some(d1)) = (dev(t0, v0), dev(t1, v1)) {
                sq += (d1 - d0) * (d1 - d0);
                k += 1;
            }
        }
        let rate = if k > 0 {
            0.5 * sq / k as f64 / step_s as f64
        } else {
            0.0
        };
        per.push((rate, k));
    }
    let total: usize = per.iter().map(|p| p.1).sum();
    if total == 0 {
        return Ok(vec![0.0; series.len()]);
    }
    let pooled = per.iter().map(|&(r, k)| r * k as f64).sum::<f64>() / total as f64;
    Ok(per
        .iter()
        .map(|&(r, k)| {
            let k = k as f64;
            if k + prior_weight == 0.0 {
                pooled
            } else {
                (k * r + prior_weight * pooled) / (k + prior_weight)
            }
        })
        .collect())
}

/// Fits a [`DynamicModel`] from sensor series (positions are not used: the covariance is
/// learned, not assumed to follow distance).
///
/// Means are each sensor's mean reading (the mean of all sensors for one without readings,
/// whose variance is then the mean variance and its correlations 0). Covariances are over
/// the times both sensors have readings, of the deviations from those means, 0 for pairs with
/// fewer than `min_overlap` common times. `φ` is `exp(Σ k ln ρ_k / Σ k²)` over the pooled
/// lag-k autocorrelations `ρ_k > 0.05` of the deviations (k steps up to `max_lag_s`, at most
/// 64 lags spread geometrically), clamped to [0, 0.999999].
///
/// Errors: no sensors, more than [`MAX_DYNAMIC_SENSORS`], no sensor with two readings, a
/// non-positive step.
pub fn fit_dynamic(
    series: &[SensorSeries<'_>],
    options: &DynamicFitOptions,
) -> Result<DynamicModel, KrigingError> {
    let n = series.len();
    if n == 0 {
        return Err(KrigingError::Fit("no sensors".into()));
    }
    if n > MAX_DYNAMIC_SENSORS {
        return Err(KrigingError::Fit(format!(
            "{n} sensors: the dynamic model handles at most {MAX_DYNAMIC_SENSORS}"
        )));
    }
    if options.step_s <= 0 {
        return Err(KrigingError::Parameter {
            what: "step_s",
            value: options.step_s as f64,
            expected: "> 0",
        });
    }
    // Finite readings only, per sensor.
    let mut clean: Vec<(Vec<i64>, Vec<f64>)> = series
        .iter()
        .map(|s| {
            s.times
                .iter()
                .zip(s.values)
                .filter(|(_, v)| v.is_finite())
                .map(|(&t, &v)| (t, v))
                .unzip()
        })
        .collect();
    let means_opt: Vec<Option<f64>> = clean
        .iter()
        .map(|(_, v)| (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64))
        .collect();
    let known: Vec<f64> = means_opt.iter().flatten().copied().collect();
    if known.is_empty() {
        return Err(KrigingError::Fit("no sensor has readings".into()));
    }
    let global = known.iter().sum::<f64>() / known.len() as f64;
    let means: Vec<f64> = means_opt.iter().map(|m| m.unwrap_or(global)).collect();
    let mut dev: Vec<Vec<f64>> = clean
        .iter()
        .zip(&means)
        .map(|((_, v), m)| v.iter().map(|x| x - m).collect())
        .collect();
    // The common level: at each time read by at least two sensors, the mean deviation; the
    // sensors' deviations from it are what the covariance and φ describe.
    let common = if options.common_mode && n >= 2 {
        remove_common_level(&mut clean, &mut dev, options)
    } else {
        (0.0, 0.0)
    };
    let vars: Vec<Option<f64>> = dev
        .iter()
        .map(|d| (d.len() >= 2).then(|| d.iter().map(|x| x * x).sum::<f64>() / d.len() as f64))
        .collect();
    let known_vars: Vec<f64> = vars
        .iter()
        .flatten()
        .copied()
        .filter(|v| *v > 0.0)
        .collect();
    if known_vars.is_empty() {
        return Err(KrigingError::Fit(
            "no sensor has two different readings".into(),
        ));
    }
    let mean_var = known_vars.iter().sum::<f64>() / known_vars.len() as f64;
    let var: Vec<f64> = vars
        .iter()
        .map(|v| match v {
            Some(v) if *v > 0.0 => *v,
            _ => mean_var,
        })
        .collect();

    // φ from the pooled autocorrelation of the deviations.
    let pooled: Vec<(&[i64], &[f64])> = clean
        .iter()
        .zip(&dev)
        .map(|((t, _), d)| (t.as_slice(), d.as_slice()))
        .collect();
    let phi = persistence_fit(&pooled, options);
    let step = options.step_s;

    // Pairwise-complete correlations.
    let (corr, count) = pairwise_correlations(&clean, &dev, &var, options.min_overlap);
    let lambda = shrinkage_intensity(options.shrinkage, phi, &corr, &count, n)?;
    let (cov, lambda) = positive_definite_shrunk(&corr, &var, lambda);
    let noise = options.noise_share.max(0.0) * mean_var;
    let mut model =
        DynamicModel::new(means, cov, phi, step as f64, noise)?.with_common(common.0, common.1)?;
    model.shrinkage = lambda;
    Ok(model)
}

/// Removes the common level from the deviations: at each time read by at least two sensors,
/// the mean deviation, subtracted from each sensor's deviation there (times read by one
/// sensor are dropped). Returns the common level's variance (unit²) and persistence per step
/// (0, 0 with fewer than two such times).
fn remove_common_level(
    clean: &mut [(Vec<i64>, Vec<f64>)],
    dev: &mut [Vec<f64>],
    options: &DynamicFitOptions,
) -> (f64, f64) {
    let mut level: std::collections::BTreeMap<i64, (f64, usize)> = Default::default();
    for ((t, _), d) in clean.iter().zip(dev.iter()) {
        for (&ti, &di) in t.iter().zip(d) {
            let e = level.entry(ti).or_insert((0.0, 0));
            e.0 += di;
            e.1 += 1;
        }
    }
    level.retain(|_, (_, c)| *c >= 2);
    let (ct, cv): (Vec<i64>, Vec<f64>) =
        level.iter().map(|(&t, &(s, c))| (t, s / c as f64)).unzip();
    for ((t, _), d) in clean.iter_mut().zip(dev.iter_mut()) {
        let mut keep_t = Vec::with_capacity(t.len());
        let mut keep_d = Vec::with_capacity(t.len());
        for (&ti, &di) in t.iter().zip(d.iter()) {
            if let Ok(k) = ct.binary_search(&ti) {
                keep_t.push(ti);
                keep_d.push(di - cv[k]);
            }
        }
        *t = keep_t;
        *d = keep_d;
    }
    if cv.len() >= 2 {
        let var_c = cv.iter().map(|x| x * x).sum::<f64>() / cv.len() as f64;
        let phi_c = persistence_fit(&[(ct.as_slice(), cv.as_slice())], options);
        return (var_c, phi_c);
    }
    (0.0, 0.0)
}

/// Pairwise-complete correlations of the deviations (row-major n × n, 1 on the diagonal, 0
/// for pairs with fewer than `min_overlap` (at least 2) common times) and each upper pair's
/// count of common times.
fn pairwise_correlations(
    clean: &[(Vec<i64>, Vec<f64>)],
    dev: &[Vec<f64>],
    var: &[f64],
    min_overlap: usize,
) -> (Vec<f64>, Vec<usize>) {
    let n = clean.len();
    let mut corr = vec![0.0; n * n];
    let mut count = vec![0usize; n * n];
    for i in 0..n {
        corr[i * n + i] = 1.0;
        for j in i + 1..n {
            let (ti, tj) = (&clean[i].0, &clean[j].0);
            let (sab, _, _, cnt) = paired(ti, &dev[i], tj, &dev[j], 0);
            if cnt >= min_overlap.max(2) {
                let r = (sab / cnt as f64 / (var[i] * var[j]).sqrt()).clamp(-1.0, 1.0);
                corr[i * n + j] = r;
                corr[j * n + i] = r;
                count[i * n + j] = cnt;
            }
        }
    }
    (corr, count)
}

/// The shrinkage intensity towards zero correlation: a fixed one (checked in [0, 1]), or the
/// automatic one from the correlations' sampling noise with each pair's count of common
/// times reduced by the persistence `phi` (per step).
fn shrinkage_intensity(
    shrinkage: Shrinkage,
    phi: f64,
    corr: &[f64],
    count: &[usize],
    n: usize,
) -> Result<f64, KrigingError> {
    Ok(match shrinkage {
        Shrinkage::Fixed(l) => {
            if !(0.0..=1.0).contains(&l) {
                return Err(KrigingError::Parameter {
                    what: "shrinkage",
                    value: l,
                    expected: "in [0, 1]",
                });
            }
            l
        }
        Shrinkage::Auto => {
            let factor = if phi < 1.0 {
                (1.0 - phi) / (1.0 + phi)
            } else {
                0.0
            };
            let (mut num, mut den) = (0.0, 0.0);
            for i in 0..n {
                for j in i + 1..n {
                    let cnt = count[i * n + j];
                    if cnt == 0 {
                        continue;
                    }
                    let r = corr[i * n + j];
                    let n_eff = (cnt as f64 * factor).max(2.0);
                    num += (1.0 - r * r).powi(2) / (n_eff - 1.0).max(1.0);
                    den += r * r;
                }
            }
            if den > 0.0 {
                (num / den).clamp(0.0, 1.0)
            } else {
                1.0
            }
        }
    })
}

/// The covariance from correlations shrunk by `lambda` and the variances, with the intensity
/// raised until it is positive definite (pairwise-complete correlations need not be);
/// returns it and the intensity used.
fn positive_definite_shrunk(corr: &[f64], var: &[f64], mut lambda: f64) -> (Vec<f64>, f64) {
    let n = var.len();
    let build = |lambda: f64| -> Vec<f64> {
        let mut c = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                let r = if i == j {
                    1.0
                } else {
                    (1.0 - lambda) * corr[i * n + j]
                };
                c[i * n + j] = r * (var[i] * var[j]).sqrt();
            }
        }
        c
    };
    // Raise the intensity until the covariance is positive definite (pairwise-complete
    // correlations need not be).
    let mut cov = build(lambda);
    loop {
        let mut l = cov.clone();
        if positive_definite(&mut l, n) || lambda >= 1.0 {
            break;
        }
        lambda = (lambda + (1.0 - lambda) * 0.25 + 1e-3).min(1.0);
        cov = build(lambda);
    }
    (cov, lambda)
}

/// `exp(Σ k ln ρ_k / Σ k²)` over the pooled lag-k autocorrelations `ρ_k > 0.05` of the series
/// (k steps up to `max_lag_s`, at most 64 lags spread geometrically), clamped to
/// [0, 0.999999]; 0 without any.
fn persistence_fit(series: &[(&[i64], &[f64])], options: &DynamicFitOptions) -> f64 {
    let step = options.step_s;
    let max_k = (options.max_lag_s / step).max(1);
    let mut lags: Vec<i64> = Vec::new();
    let mut k = 1i64;
    while k <= max_k && lags.len() < 64 {
        lags.push(k);
        k = (k + 1).max((k as f64 * 1.15).ceil() as i64);
    }
    let (mut skl, mut skk) = (0.0, 0.0);
    for &k in &lags {
        let (mut sab, mut saa, mut sbb, mut cnt) = (0.0, 0.0, 0.0, 0usize);
        for (t, d) in series {
            let (a, b, c, m) = paired(t, d, t, d, k * step);
            sab += a;
            saa += b;
            sbb += c;
            cnt += m;
        }
        if cnt >= options.min_overlap && saa > 0.0 && sbb > 0.0 {
            let rho = sab / (saa * sbb).sqrt();
            if rho > 0.05 {
                let kf = k as f64;
                skl += kf * rho.ln();
                skk += kf * kf;
            }
        }
    }
    if skk > 0.0 {
        (skl / skk).exp().clamp(0.0, 0.999_999)
    } else {
        0.0
    }
}

/// Strict Cholesky test (no jitter): whether the matrix is numerically positive definite
/// with a margin.
fn positive_definite(a: &mut [f64], n: usize) -> bool {
    for j in 0..n {
        let mut d = a[j * n + j];
        for k in 0..j {
            d -= a[j * n + k] * a[j * n + k];
        }
        let margin = 1e-10 * a[j * n + j].abs().max(1e-300);
        if d.is_nan() || d <= margin {
            return false;
        }
        let d = d.sqrt();
        a[j * n + j] = d;
        for i in j + 1..n {
            let mut s = a[i * n + j];
            for k in 0..j {
                s -= a[i * n + k] * a[j * n + k];
            }
            a[i * n + j] = s / d;
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn two_sensor(rho: f64, phi: f64) -> DynamicModel {
        DynamicModel::new(
            vec![0.3, 0.2],
            vec![1e-4, rho * 1e-4, rho * 1e-4, 1e-4],
            phi,
            3600.0,
            0.0,
        )
        .unwrap()
    }

    #[test]
    fn unshared_variance_grows_with_time_since_reading_and_a_reading_resets_it() {
        let rate = 1e-9; // unit²/s
        let m = two_sensor(0.9, 0.99)
            .with_own_rates(vec![rate, 2.0 * rate])
            .unwrap();
        let base = two_sensor(0.9, 0.99);
        let mut f = m.filter(0.0);
        let mut g = base.filter(0.0);
        for t in [3600.0, 7200.0, 36000.0] {
            f.advance(t);
            g.advance(t);
            for i in 0..2 {
                let expect = g.estimate(i).1 + (i as f64 + 1.0) * rate * t;
                assert!((f.estimate(i).1 - expect).abs() < 1e-18, "t {t} sensor {i}");
            }
        }
        // Reading sensor 0 removes its own unshared part only.
        let info = f.information(&[0]);
        assert!((info - (g.information(&[0]) + rate * 36000.0)).abs() < 1e-18);
        f.observe(0, 0.31);
        g.observe(0, 0.31);
        assert_eq!(f.own_variance(0), 0.0);
        assert!((f.own_variance(1) - 2.0 * rate * 36000.0).abs() < 1e-18);
        assert!((f.estimate(0).1 - g.estimate(0).1).abs() < 1e-18);
        f.advance(36000.0 + 100.0);
        assert!((f.own_variance(0) - rate * 100.0).abs() < 1e-18);
        // A sensor correlated with one just read still gains information from its own part.
        let mut f2 = m.filter(0.0);
        f2.advance(86400.0);
        f2.observe(0, 0.3);
        assert!(f2.information(&[1]) >= 2.0 * rate * 86400.0);
    }

    #[test]
    fn own_rates_come_from_the_deviations_changes_and_shrink_to_the_pool() {
        // Sensor 0 jumps by ±0.02 against the field every day, sensor 1 follows the field
        // exactly with sensor 2: a quiet pair and one drifting sensor.
        let times: Vec<i64> = (0..50).map(|d| d * 86_400).collect();
        let field: Vec<f64> = (0..50).map(|d| 0.3 + 0.001 * d as f64).collect();
        let s0: Vec<f64> = (0..50)
            .map(|d| field[d] + if d % 2 == 0 { 0.02 } else { -0.02 })
            .collect();
        let series: Vec<SensorSeries<'_>> = [&s0, &field, &field]
            .into_iter()
            .map(|v| SensorSeries {
                position: [0.0, 0.0],
                times: &times,
                values: v,
            })
            .collect();
        let raw = fit_own_rates(&series, 86_400, 0.0).unwrap();
        // The field mean holds a third of sensor 0's jump: its deviation moves twice as far
        // as the others' (four times the rate).
        assert!((raw[0] / raw[1] - 4.0).abs() < 1e-9, "{raw:?}");
        assert!(raw.iter().all(|&r| r > 0.0 && r.is_finite()));
        let shrunk = fit_own_rates(&series, 86_400, 1e9).unwrap();
        assert!(
            (shrunk[0] - shrunk[1]).abs() < 1e-6 * shrunk[0],
            "{shrunk:?}"
        );
        // Nothing usable: zeros; bad options: errors.
        let lone = [SensorSeries {
            position: [0.0, 0.0],
            times: &[0],
            values: &[0.3],
        }];
        assert_eq!(fit_own_rates(&lone, 86_400, 5.0).unwrap(), vec![0.0]);
        assert!(fit_own_rates(&series, 0, 5.0).is_err());
        assert!(fit_own_rates(&series, 86_400, -1.0).is_err());
    }

    #[test]
    fn zero_unshared_rates_give_todays_model_exactly() {
        let base = two_sensor(0.6, 0.9);
        let zero = two_sensor(0.6, 0.9).with_own_rates(vec![0.0, 0.0]).unwrap();
        assert_eq!(base, zero);
        let mut f = zero.filter(0.0);
        let mut g = base.filter(0.0);
        for (t, i, v) in [(3600.0, 0, 0.32), (9000.0, 1, 0.18), (90000.0, 0, 0.29)] {
            f.advance(t);
            g.advance(t);
            f.observe(i, v);
            g.observe(i, v);
            for j in 0..2 {
                assert_eq!(f.estimate(j), g.estimate(j));
            }
            assert_eq!(f.information(&[1 - i]), g.information(&[1 - i]));
        }
    }

    #[test]
    fn bad_unshared_rates_are_refused() {
        assert!(two_sensor(0.5, 0.9).with_own_rates(vec![1e-9]).is_err());
        assert!(
            two_sensor(0.5, 0.9)
                .with_own_rates(vec![1e-9, -1e-9])
                .is_err()
        );
        assert!(
            two_sensor(0.5, 0.9)
                .with_own_rates(vec![f64::NAN, 0.0])
                .is_err()
        );
    }

    #[test]
    fn information_is_the_variance_a_reading_removes_field_wide_and_not_additive() {
        let m = two_sensor(0.8, 0.9);
        let f = m.filter(0.0);
        // Reading sensor 0 (noise-free model): its own 1e-4 and 0.64 of sensor 1's.
        let one = f.information(&[0]);
        assert!((one - 1e-4 * (1.0 + 0.64)).abs() < 1e-12, "{one}");
        // Both: every variance gone, less than the sum of the singletons.
        let both = f.information(&[0, 1]);
        assert!((both - 2e-4).abs() < 1e-12, "{both}");
        assert!(both < one + f.information(&[1]));
        // Repeats and strangers add nothing; the filter is unchanged.
        assert_eq!(f.information(&[0, 0, 7]), one);
        assert_eq!(f.information(&[]), 0.0);
        assert!((f.total_variance() - 2e-4).abs() < 1e-15);
        // Uncorrelated sensors: additive.
        let g = two_sensor(0.0, 0.9);
        let gf = g.filter(0.0);
        assert!(
            (gf.information(&[0, 1]) - gf.information(&[0]) - gf.information(&[1])).abs() < 1e-15
        );
    }

    #[test]
    fn conditional_of_levels_is_the_textbook_formula() {
        let m = two_sensor(0.8, 0.9);
        let est = m.conditional(&[(0, 0.31)]);
        // μ_u + Σ_us/Σ_ss (x_s − μ_s), variance Σ_uu (1 − ρ²).
        assert!((est[1].0 - (0.2 + 0.8 * 0.01)).abs() < 1e-12);
        assert!((est[1].1 - 1e-4 * (1.0 - 0.64)).abs() < 1e-12);
        assert!(est[0].1.abs() < 1e-15);
        assert!((est[0].0 - 0.31).abs() < 1e-12);
    }

    #[test]
    fn a_fresh_own_reading_beats_the_neighbours_and_decays_to_the_conditional() {
        let m = two_sensor(0.5, 0.99);
        let mut f = m.filter(0.0);
        f.observe(0, 0.35);
        f.observe(1, 0.25);
        // One hour later sensor 1 is close to its own reading, far later to the conditional
        // given sensor 0's new reading alone.
        let mut soon = f.clone();
        soon.advance(3600.0);
        soon.observe(0, 0.35);
        let (m1, v1) = soon.estimate(1);
        assert!((m1 - 0.25).abs() < 0.002, "{m1}");
        assert!(v1 < 0.05 * 1e-4);
        let mut late = f.clone();
        late.advance(3600.0 * 10_000.0);
        late.observe(0, 0.35);
        let cond = m.conditional(&[(0, 0.35)]);
        let (m2, v2) = late.estimate(1);
        assert!((m2 - cond[1].0).abs() < 1e-9 && (v2 - cond[1].1).abs() < 1e-12);
    }

    #[test]
    fn advance_matches_the_closed_form_of_the_separable_covariance() {
        // Observe sensor 0 at t = 0, predict sensor 1 at t = h: mean ρ φ^h x0', var Σ(1 − ρ²φ^2h).
        let m = two_sensor(0.7, 0.95);
        let mut f = m.filter(0.0);
        f.observe(0, 0.32);
        f.advance(5.0 * 3600.0);
        let a = 0.95f64.powi(5);
        let (mu, var) = f.estimate(1);
        assert!((mu - (0.2 + 0.7 * a * 0.02)).abs() < 1e-12);
        assert!((var - 1e-4 * (1.0 - 0.49 * a * a)).abs() < 1e-12);
        // Going back in time changes nothing.
        let before = f.estimate(1);
        f.advance(0.0);
        assert_eq!(f.estimate(1), before);
    }

    #[test]
    fn bad_parts_are_refused() {
        assert!(DynamicModel::new(vec![0.0; 2], vec![1.0; 3], 0.5, 1.0, 0.0).is_err());
        assert!(DynamicModel::new(vec![0.0; 2], vec![1.0, 2.0, 2.0, 1.0], 0.5, 1.0, 0.0).is_err());
        assert!(DynamicModel::new(vec![0.0], vec![1.0], 1.5, 1.0, 0.0).is_err());
        assert!(DynamicModel::new(vec![0.0], vec![1.0], 0.5, 0.0, 0.0).is_err());
        assert!(DynamicModel::new(vec![0.0], vec![f64::NAN], 0.5, 1.0, 0.0).is_err());
        assert!(fit_dynamic(&[], &DynamicFitOptions::default()).is_err());
    }

    /// A seeded AR(1) pair with correlated innovations (an LCG's uniform sums as noise).
    fn simulate(n_steps: usize, phi: f64, rho: f64) -> (Vec<i64>, Vec<f64>, Vec<f64>) {
        let mut state = 12345u64;
        let mut gauss = || {
            let mut s = 0.0;
            for _ in 0..12 {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                s += (state >> 11) as f64 / (1u64 << 53) as f64;
            }
            s - 6.0
        };
        let (mut a, mut b) = (0.0, 0.0);
        let (mut xs, mut ys, mut ts) = (Vec::new(), Vec::new(), Vec::new());
        let q = (1.0 - phi * phi).sqrt();
        for t in 0..n_steps {
            let (e1, e2) = (gauss(), gauss());
            let e2 = rho * e1 + (1.0 - rho * rho).sqrt() * e2;
            a = phi * a + q * e1;
            b = phi * b + q * e2;
            ts.push(t as i64 * 60);
            xs.push(1.0 + 0.1 * a);
            ys.push(2.0 + 0.2 * b);
        }
        (ts, xs, ys)
    }

    #[test]
    fn fit_recovers_a_simulated_process() {
        let (t, x, y) = simulate(20_000, 0.9, 0.6);
        let series = [
            SensorSeries {
                position: [0.0, 0.0],
                times: &t,
                values: &x,
            },
            SensorSeries {
                position: [0.0, 0.0],
                times: &t,
                values: &y,
            },
        ];
        let opts = DynamicFitOptions {
            step_s: 60,
            max_lag_s: 600,
            shrinkage: Shrinkage::Fixed(0.0),
            ..DynamicFitOptions::default()
        };
        let m = fit_dynamic(&series, &opts).unwrap();
        assert!((m.phi() - 0.9).abs() < 0.02, "phi {}", m.phi());
        let c = m.covariance();
        let r = c[1] / (c[0] * c[3]).sqrt();
        assert!((r - 0.6).abs() < 0.05, "rho {r}");
        assert!((m.means()[0] - 1.0).abs() < 0.02 && (m.means()[1] - 2.0).abs() < 0.04);
        let auto = fit_dynamic(
            &series,
            &DynamicFitOptions {
                shrinkage: Shrinkage::Auto,
                ..opts
            },
        )
        .unwrap();
        assert!(
            auto.shrinkage() > 0.0 && auto.shrinkage() < 0.1,
            "{}",
            auto.shrinkage()
        );
    }

    #[test]
    fn missing_values_and_constant_sensors_do_not_break_the_fit() {
        let t: Vec<i64> = (0..50).map(|i| i * 86_400).collect();
        let x: Vec<f64> = (0..50)
            .map(|i| {
                if i % 7 == 3 {
                    f64::NAN
                } else {
                    (i as f64 * 0.3).sin()
                }
            })
            .collect();
        let y = vec![0.5; 50];
        let z: Vec<f64> = x.iter().map(|v| -v).collect();
        let series = [
            SensorSeries {
                position: [0.0, 0.0],
                times: &t,
                values: &x,
            },
            SensorSeries {
                position: [0.0, 0.0],
                times: &t,
                values: &y,
            },
            SensorSeries {
                position: [0.0, 0.0],
                times: &t,
                values: &z,
            },
            SensorSeries {
                position: [0.0, 0.0],
                times: &[],
                values: &[],
            },
        ];
        let m = fit_dynamic(&series, &DynamicFitOptions::default()).unwrap();
        assert_eq!(m.len(), 4);
        // Perfectly anti-correlated sensors need shrinkage to be positive definite.
        assert!(m.shrinkage() > 0.0);
        let est = m.conditional(&[(0, 0.5)]);
        assert!(est[2].0 < m.means()[2]);
        assert!(
            est.iter()
                .all(|(mu, v)| mu.is_finite() && v.is_finite() && *v >= 0.0)
        );
    }

    #[test]
    fn a_common_level_is_learned_and_carries_unread_sensors() {
        // Four sensors: a slow common level (a ramp) plus fast own deviations.
        let t: Vec<i64> = (0..600).map(|i| i * 3600).collect();
        let own = |k: usize, i: usize| ((i * (k + 3)) as f64 * 0.7).sin() * 0.002;
        let level = |i: usize| 0.05 * (i as f64 / 100.0).sin();
        let vals: Vec<Vec<f64>> = (0..4)
            .map(|k| {
                (0..600)
                    .map(|i| 0.2 + 0.01 * k as f64 + level(i) + own(k, i))
                    .collect()
            })
            .collect();
        let series: Vec<SensorSeries<'_>> = vals
            .iter()
            .map(|v| SensorSeries {
                position: [0.0, 0.0],
                times: &t,
                values: v,
            })
            .collect();
        let opts = DynamicFitOptions {
            step_s: 3600,
            max_lag_s: 48 * 3600,
            common_mode: true,
            ..DynamicFitOptions::default()
        };
        let m = fit_dynamic(&series, &opts).unwrap();
        let (var_c, phi_c) = m.common();
        assert!(var_c > 10.0 * m.covariance()[0], "{var_c}");
        assert!(phi_c > m.phi(), "{phi_c} vs {}", m.phi());
        // Sensor 3 read at hour 0 only; the others every hour: its estimate follows the level.
        let mut f = m.filter(0.0);
        f.observe(3, vals[3][0]);
        for (i, &time) in t.iter().enumerate().take(300).skip(1) {
            f.advance(time as f64);
            for (k, v) in vals.iter().enumerate().take(3) {
                f.observe(k, v[i]);
            }
        }
        let (mu, var) = f.estimate(3);
        assert!((mu - vals[3][299]).abs() < 0.01, "{mu} vs {}", vals[3][299]);
        assert!(var < m.prior_variance(3));
        // Without a common level the filter equals the plain model's.
        let plain = m.clone().with_common(0.0, 0.0).unwrap();
        let base = DynamicModel::new(
            m.means().to_vec(),
            m.covariance().to_vec(),
            m.phi(),
            3600.0,
            m.noise(),
        )
        .unwrap();
        let (mut a, mut b) = (plain.filter(0.0), base.filter(0.0));
        for (k, v) in [(0, 0.21), (2, 0.19)] {
            a.observe(k, v);
            b.observe(k, v);
        }
        a.advance(7200.0);
        b.advance(7200.0);
        for k in 0..4 {
            assert_eq!(a.estimate(k), b.estimate(k));
        }
    }

    /// The information of reading `sensors` by full rank-one updates (the reference of
    /// [`FieldFilter::information`]'s restricted updates).
    fn information_full(f: &FieldFilter<'_>, sensors: &[usize]) -> f64 {
        let before = f.total_variance();
        let mut after = f.clone();
        for &i in sensors {
            after.observe_variance_only(i);
            after.reset_own(i);
        }
        (before - after.total_variance()).max(0.0)
    }

    proptest! {
        #[test]
        fn information_equals_the_full_updates_bit_for_bit(
            n in 1usize..7,
            seed in proptest::collection::vec(-1.0f64..1.0, 64),
            noise in prop_oneof![Just(0.0), 1e-6f64..1e-3],
            own in proptest::option::of(1e-10f64..1e-8),
            reads in proptest::collection::vec((0usize..8, -0.5f64..0.5), 0..6),
            sensors in proptest::collection::vec(0usize..9, 0..9),
        ) {
            // A positive-definite covariance from random factors: Σ = L·Lᵀ + 0.1·I.
            let l: Vec<f64> = (0..n * n).map(|i| seed[i % seed.len()] * 0.03).collect();
            let mut cov = vec![0.0; n * n];
            for i in 0..n {
                for j in 0..n {
                    let dot: f64 = (0..n).map(|q| l[i * n + q] * l[j * n + q]).sum();
                    cov[i * n + j] = dot + if i == j { 1e-3 } else { 0.0 };
                }
            }
            let mut m = DynamicModel::new(vec![0.3; n], cov, 0.95, 3600.0, noise).unwrap();
            if let Some(r) = own {
                m = m.with_own_rates((0..n).map(|i| r * (1.0 + i as f64)).collect()).unwrap();
            }
            let mut f = m.filter(0.0);
            for (k, &(s, v)) in reads.iter().enumerate() {
                f.advance(3600.0 * (k + 1) as f64);
                f.observe(s, 0.3 + v);
            }
            f.advance(3600.0 * (reads.len() + 2) as f64);
            let got = f.information(&sensors);
            let want = information_full(&f, &sensors);
            prop_assert_eq!(got.to_bits(), want.to_bits(), "{} vs {}", got, want);
        }

        #[test]
        fn readings_never_raise_a_variance(
            rho in -0.85f64..0.85, phi in 0.0f64..1.0, dt in 0.0f64..1e6,
            picks in proptest::collection::vec((0usize..3, -1.0f64..1.0), 0..8),
        ) {
            let cov = vec![1.0, rho, 0.0, rho, 1.0, rho * 0.5, 0.0, rho * 0.5, 1.0];
            let m = DynamicModel::new(vec![0.0; 3], cov, phi, 3600.0, 1e-6).unwrap();
            let mut f = m.filter(0.0);
            for (k, &(s, v)) in picks.iter().enumerate() {
                let before: Vec<f64> = (0..3).map(|i| f.estimate(i).1).collect();
                f.observe(s, v);
                for (i, b) in before.iter().enumerate() {
                    prop_assert!(f.estimate(i).1 <= b + 1e-12);
                    prop_assert!(f.estimate(i).1 >= 0.0);
                }
                f.advance(dt * (k + 1) as f64);
                for i in 0..3 {
                    prop_assert!(f.estimate(i).1 <= 1.0 + 1e-12);
                }
            }
            let sum = m.remaining_variance(&picks.iter().map(|p| p.0).collect::<Vec<_>>());
            prop_assert!((0.0..=3.0 + 1e-12).contains(&sum));
        }
    }
}
