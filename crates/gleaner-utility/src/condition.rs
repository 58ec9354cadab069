//! The agricultural-condition model behind the uncertainty term U (docs/method.md §2).
//!
//! Classes come from one modality (by default soil moisture at 30 cm: K = 3, dry / adequate /
//! wet) cut at thresholds given in the configuration or taken at the quantiles 1/K, 2/K, … of
//! the training history. A multinomial logistic regression (softmax, L2-regularised,
//! standardised features, trained by damped Newton's method — deterministic, no seed needed)
//! predicts the class at time t from what is known when the cell was last collected:
//!
//! | # | feature ([`FEATURE_NAMES`]) | unit |
//! |---|---|---|
//! | 0 | last collected value x_l | modality unit |
//! | 1 | its age a = t − t_l | days |
//! | 2 | x_l · a | unit·days |
//! | 3 | trend: least-squares slope over the last `trend_points` collected points | unit/day |
//! | 4 | trend · a (linear extrapolation) | unit |
//! | 5, 6 | season: sin, cos of 2π·(t in days)/365.2425 (day-of-year phase; 0 if disabled) | — |
//! | 7 | mean of the neighbours' latest values (x_l when none has data) | unit |
//! | 8 | that mean · a | unit·days |
//! | 9.. | per threshold θ_k: (x_l − θ_k) / √(a + 0.5) | unit/√day |
//!
//! The interactions with the age let the model learn that an old value says less than a fresh
//! one, so the predicted distribution flattens (U grows) with staleness. The threshold
//! distances are what a random walk from the last value would give (its spread grows as
//! √age): the logits are sharp near a fresh value and soften as it ages, and values near a
//! class threshold give split probabilities.
//!
//! Training set: for every cell and every time t of its series inside the training period, and
//! for every lag L in `lags_days`, the features are computed as if the data known were only the
//! cell's and neighbours' points at or before t − L (days); the label is the class of the true
//! value at t. A train/test split is a split of the label times.
//!
//! On the CAF network (42 sensors, vw@30cm, trained on 2011–2012, tested on 2013 to mid-2014,
//! see `tests/caf.rs`) the default model reaches about 0.89 held-out accuracy and 0.29 nats
//! log-loss against 0.31 / 1.10 for the majority class / class frequencies; persisting the last
//! value's class is right 0.91 of the time (it gives no probabilities). Mean U is about 0.20
//! for values at most 2 days old and 0.42 for values 10–30 days old.

use crate::codec::{Reader, Writer};
use crate::{DAY_S, Series, UtilityError};
use gleaner_field::UnixSeconds;

/// Design rows per [`ConditionModel::softmax_block`].
const BLOCK: usize = 8;

/// Number of features before the threshold distances.
const BASE: usize = 9;

/// Age offset in the threshold distances, days (keeps them finite at age 0).
const AGE_OFFSET_DAYS: f64 = 0.5;

/// Names of the model's first features, in order (see the module docs for their units); the
/// K − 1 threshold distances follow.
pub const FEATURE_NAMES: [&str; BASE] = [
    "last_value",
    "age_days",
    "last_value_x_age",
    "trend_per_day",
    "trend_x_age",
    "season_sin",
    "season_cos",
    "neighbour_mean",
    "neighbour_mean_x_age",
];

/// Where the class thresholds come from.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum ClassThresholds {
    /// Quantiles 1/K, …, (K−1)/K of the training history's values (the default).
    #[default]
    Quantiles,
    /// K − 1 strictly increasing thresholds in the modality's unit (e.g. m³/m³).
    Fixed(Vec<f64>),
}

/// Configuration of the condition model.
#[derive(Debug, Clone, PartialEq)]
pub struct ConditionConfig {
    /// Number of classes K (default 3: dry / adequate / wet), >= 2.
    pub n_classes: usize,
    /// Class thresholds (default: quantiles of the history).
    pub thresholds: ClassThresholds,
    /// Simulated staleness of the training rows, days (default 1, 2, 3, 5, 7, 10, 14).
    pub lags_days: Vec<i64>,
    /// Points in the trend's least-squares fit (default 5, >= 2).
    pub trend_points: usize,
    /// Use the season features (default true, as docs/method.md §2 lists them; with only a couple of
    /// training years they can learn one year's weather, see the crate's CAF evaluation).
    pub season: bool,
    /// L2 penalty on the standardised weights (default 1e-4; the bias gets 1e-6).
    pub l2: f64,
    /// Newton iterations at most (default 100).
    pub max_iterations: usize,
    /// Stop when the largest gradient component is below this (default 1e-9).
    pub tolerance: f64,
}

impl Default for ConditionConfig {
    fn default() -> Self {
        Self {
            n_classes: 3,
            thresholds: ClassThresholds::Quantiles,
            lags_days: vec![1, 2, 3, 5, 7, 10, 14],
            trend_points: 5,
            season: true,
            l2: 1e-4,
            max_iterations: 100,
            tolerance: 1e-9,
        }
    }
}

impl ConditionConfig {
    fn validate(&self) -> Result<(), UtilityError> {
        let bad = |m: String| Err(UtilityError::Model(m));
        if self.n_classes < 2 {
            return bad(format!("need at least 2 classes, got {}", self.n_classes));
        }
        if let ClassThresholds::Fixed(th) = &self.thresholds {
            if th.len() != self.n_classes - 1 {
                return bad(format!(
                    "{} thresholds for {} classes (need {})",
                    th.len(),
                    self.n_classes,
                    self.n_classes - 1
                ));
            }
            if th.iter().any(|x| !x.is_finite()) || th.windows(2).any(|w| w[1] <= w[0]) {
                return bad(format!(
                    "thresholds {th:?} must be finite and strictly increasing"
                ));
            }
        }
        if self.lags_days.is_empty() || self.lags_days.iter().any(|&l| l <= 0) {
            return bad(format!(
                "lags {:?} days must be non-empty and positive",
                self.lags_days
            ));
        }
        if self.trend_points < 2 {
            return bad(format!(
                "trend_points {} must be at least 2",
                self.trend_points
            ));
        }
        if !(self.l2.is_finite() && self.l2 >= 0.0) {
            return bad(format!("l2 {} must be finite and non-negative", self.l2));
        }
        Ok(())
    }
}

/// Thresholds at the quantiles j/K (j = 1..K−1) of `values` (linear interpolation between
/// order statistics, "type 7"). Non-finite values are ignored; empty input gives an error.
pub fn quantile_thresholds(values: &[f64], n_classes: usize) -> Result<Vec<f64>, UtilityError> {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return Err(UtilityError::Model(
            "no values to take quantiles of".to_string(),
        ));
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    Ok((1..n_classes)
        .map(|j| {
            let h = (n - 1) as f64 * j as f64 / n_classes as f64;
            let lo = h.floor() as usize;
            let hi = (lo + 1).min(n - 1);
            v[lo] + (h - lo as f64) * (v[hi] - v[lo])
        })
        .collect())
}

/// The class (0-based) of value `x`: the number of thresholds at or below it.
pub fn class_of(x: f64, thresholds: &[f64]) -> usize {
    thresholds.iter().filter(|&&th| x >= th).count()
}

/// Least-squares slope (unit per day) of the last `k` points of `s`; 0 with fewer than 2.
fn trend_per_day(s: Series<'_>, k: usize) -> f64 {
    let n = s.len();
    let start = n.saturating_sub(k);
    let (times, values) = (&s.times[start..n], &s.values[start..n]);
    let m = times.len();
    if m < 2 {
        return 0.0;
    }
    let t0 = times[m - 1];
    let x: Vec<f64> = times.iter().map(|&t| (t - t0) as f64 / DAY_S).collect();
    let mx = x.iter().sum::<f64>() / m as f64;
    let my = values.iter().sum::<f64>() / m as f64;
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for (a, b) in x.iter().zip(values) {
        sxy += (a - mx) * (b - my);
        sxx += (a - mx) * (a - mx);
    }
    if sxx > 0.0 { sxy / sxx } else { 0.0 }
}

/// The model's features (see [`FEATURE_NAMES`], then one distance per threshold) for a cell at
/// time `t` (s) when only the points at or before `known_until` (s) are known: `cell` is the
/// cell's series of the class modality, `neighbours` the neighbours' series, `thresholds` the
/// class thresholds (unit); `config` gives the trend length and whether the season is used.
/// `None` when the cell has no known point.
pub fn condition_features(
    cell: Series<'_>,
    neighbours: &[Series<'_>],
    t: UnixSeconds,
    known_until: UnixSeconds,
    thresholds: &[f64],
    config: &ConditionConfig,
) -> Option<Vec<f64>> {
    let trend_points = config.trend_points;
    let known = cell.between(UnixSeconds::MIN, known_until);
    let (t_last, x_last) = known.last()?;
    let age = (t - t_last).max(0) as f64 / DAY_S;
    let trend = trend_per_day(known, trend_points);
    let phase = std::f64::consts::TAU * (t as f64 / DAY_S) / 365.2425;
    let season = if config.season { 1.0 } else { 0.0 };
    let (mut sum, mut count) = (0.0, 0usize);
    for nb in neighbours {
        if let Some((_, v)) = nb.between(UnixSeconds::MIN, known_until).last() {
            sum += v;
            count += 1;
        }
    }
    let nb_mean = if count > 0 {
        sum / count as f64
    } else {
        x_last
    };
    let mut out = Vec::with_capacity(BASE + thresholds.len());
    out.extend_from_slice(&[
        x_last,
        age,
        x_last * age,
        trend,
        trend * age,
        season * phase.sin(),
        season * phase.cos(),
        nb_mean,
        nb_mean * age,
    ]);
    let spread = (age + AGE_OFFSET_DAYS).sqrt();
    out.extend(thresholds.iter().map(|th| (x_last - th) / spread));
    Some(out)
}

/// Rows for training or evaluating the model (see the module docs for the construction).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TrainingSet {
    /// Feature rows.
    pub features: Vec<Vec<f64>>,
    /// Class of the true value, 0-based.
    pub labels: Vec<usize>,
    /// Label time of each row, s.
    pub times: Vec<UnixSeconds>,
    /// Cell position of each row.
    pub cells: Vec<usize>,
}

impl TrainingSet {
    /// Rows for every cell, every label time `from <= t < to` (s) of its series and every lag
    /// of `config.lags_days`. `cells[i]` is cell i's series of the class modality,
    /// `neighbours[i]` its neighbour positions (out-of-range positions are skipped).
    pub fn build(
        cells: &[Series<'_>],
        neighbours: &[Vec<usize>],
        thresholds: &[f64],
        from: UnixSeconds,
        to: UnixSeconds,
        config: &ConditionConfig,
    ) -> TrainingSet {
        let mut set = TrainingSet::default();
        let mut nb_series = Vec::new();
        for (i, cell) in cells.iter().enumerate() {
            nb_series.clear();
            if let Some(nbs) = neighbours.get(i) {
                nb_series.extend(nbs.iter().filter_map(|&j| cells.get(j).copied()));
            }
            let window = cell.between(from, to.saturating_sub(1));
            for (&t, &x) in window.times.iter().zip(window.values) {
                for &lag in &config.lags_days {
                    let known = t - lag * 86_400;
                    if let Some(f) =
                        condition_features(*cell, &nb_series, t, known, thresholds, config)
                    {
                        set.features.push(f);
                        set.labels.push(class_of(x, thresholds));
                        set.times.push(t);
                        set.cells.push(i);
                    }
                }
            }
        }
        set
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.labels.len()
    }

    /// True without rows.
    pub fn is_empty(&self) -> bool {
        self.labels.is_empty()
    }
}

/// Held-out performance of a model, next to the majority-class and persistence baselines.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Evaluation {
    /// Number of rows evaluated.
    pub n: usize,
    /// Fraction of rows whose most probable class is the true one.
    pub accuracy: f64,
    /// Mean −ln p(true class) (nats), probabilities clipped at 1e-15.
    pub log_loss: f64,
    /// Accuracy of always predicting the training set's most frequent class.
    pub baseline_accuracy: f64,
    /// Log-loss of predicting the training class frequencies everywhere (nats).
    pub baseline_log_loss: f64,
    /// Accuracy of persistence: predicting the class of the last collected value.
    pub persistence_accuracy: f64,
}

/// A trained multinomial logistic regression over [`FEATURE_NAMES`].
///
/// ```
/// use gleaner_utility::{ConditionConfig, ConditionModel, Series};
/// // One cell whose moisture follows a slow seasonal cycle, daily for two years.
/// let times: Vec<i64> = (0..730).map(|d| d * 86_400).collect();
/// let values: Vec<f64> = (0..730)
///     .map(|d| 0.3 + 0.1 * (d as f64 * std::f64::consts::TAU / 365.0).sin())
///     .collect();
/// let cells = [Series::new(&times, &values)];
/// let config = ConditionConfig { lags_days: vec![1, 7], ..ConditionConfig::default() };
/// let model = ConditionModel::fit(&cells, &[vec![]], 0, 365 * 86_400, &config).unwrap();
/// let p = model.predict_proba(&cells, &[vec![]], 400 * 86_400);
/// assert_eq!(p[0].len(), 3);
/// assert!((p[0].iter().sum::<f64>() - 1.0).abs() < 1e-12);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct ConditionModel {
    thresholds: Vec<f64>,
    n_classes: usize,
    config: ConditionConfig,
    mean: Vec<f64>,
    scale: Vec<f64>,
    /// Class-major with a stride of (features + 1): the bias, then the features' weights.
    weights: Vec<f64>,
    prior: Vec<f64>,
}

impl ConditionModel {
    /// Thresholds from the configuration or from the quantiles of the values with time in
    /// [`from`, `to`) (s), then a training set over the same period, then [`train`](Self::train).
    pub fn fit(
        cells: &[Series<'_>],
        neighbours: &[Vec<usize>],
        from: UnixSeconds,
        to: UnixSeconds,
        config: &ConditionConfig,
    ) -> Result<Self, UtilityError> {
        Self::fit_from(cells, neighbours, from, to, config, None)
    }

    /// [`fit`](Self::fit), with Newton's method started from `start`'s parameters (re-expressed
    /// in this training set's standardisation) instead of zero: the same strictly convex
    /// problem and stopping rule, so the same model to the solver's tolerance, in fewer
    /// iterations when `start` was trained on most of the same data. A `start` of another
    /// shape (classes, features) is ignored.
    pub fn fit_from(
        cells: &[Series<'_>],
        neighbours: &[Vec<usize>],
        from: UnixSeconds,
        to: UnixSeconds,
        config: &ConditionConfig,
        start: Option<&ConditionModel>,
    ) -> Result<Self, UtilityError> {
        config.validate()?;
        let thresholds = match &config.thresholds {
            ClassThresholds::Fixed(th) => th.clone(),
            ClassThresholds::Quantiles => {
                let values: Vec<f64> = cells
                    .iter()
                    .flat_map(|s| s.between(from, to.saturating_sub(1)).values.iter().copied())
                    .collect();
                quantile_thresholds(&values, config.n_classes)?
            }
        };
        let set = TrainingSet::build(cells, neighbours, &thresholds, from, to, config);
        Self::train_from(&set, thresholds, config, start)
    }

    /// Trains on the label times [`from`, `split`) and evaluates on [`split`, `to`) (s): the
    /// held-out rows use the training thresholds; their features may use any data before the
    /// label time minus the lag, as in operation.
    pub fn fit_and_evaluate(
        cells: &[Series<'_>],
        neighbours: &[Vec<usize>],
        from: UnixSeconds,
        split: UnixSeconds,
        to: UnixSeconds,
        config: &ConditionConfig,
    ) -> Result<(Self, Evaluation), UtilityError> {
        let model = Self::fit(cells, neighbours, from, split, config)?;
        let test = TrainingSet::build(cells, neighbours, &model.thresholds, split, to, config);
        if test.is_empty() {
            return Err(UtilityError::Model(format!(
                "no held-out rows with label times in [{split}, {to}) s"
            )));
        }
        let evaluation = model.evaluate(&test);
        Ok((model, evaluation))
    }

    /// Trains on `set` with the given thresholds (K − 1 of them, K = `config.n_classes`).
    pub fn train(
        set: &TrainingSet,
        thresholds: Vec<f64>,
        config: &ConditionConfig,
    ) -> Result<Self, UtilityError> {
        Self::train_from(set, thresholds, config, None)
    }

    /// [`train`](Self::train), warm-started from `start` (see [`fit_from`](Self::fit_from)).
    pub fn train_from(
        set: &TrainingSet,
        thresholds: Vec<f64>,
        config: &ConditionConfig,
        start: Option<&ConditionModel>,
    ) -> Result<Self, UtilityError> {
        config.validate()?;
        let k = config.n_classes;
        if thresholds.len() != k - 1 {
            return Err(UtilityError::Model(format!(
                "{} thresholds for {k} classes",
                thresholds.len()
            )));
        }
        if set.is_empty() {
            return Err(UtilityError::Model("empty training set".to_string()));
        }
        if let Some(&bad) = set.labels.iter().find(|&&y| y >= k) {
            return Err(UtilityError::Model(format!(
                "label {bad} out of range for {k} classes"
            )));
        }
        let d = BASE + k - 1;
        if let Some(row) = set.features.iter().find(|r| r.len() != d) {
            return Err(UtilityError::Model(format!(
                "feature row of length {}, expected {d}",
                row.len()
            )));
        }
        let n = set.len() as f64;
        let mut mean = vec![0.0; d];
        let mut scale = vec![0.0; d];
        for row in &set.features {
            for f in 0..d {
                mean[f] += row[f] / n;
            }
        }
        for row in &set.features {
            for f in 0..d {
                scale[f] += (row[f] - mean[f]).powi(2) / n;
            }
        }
        for s in &mut scale {
            *s = if *s > 0.0 { s.sqrt() } else { 1.0 };
        }
        let mut prior = vec![0.0; k];
        for &y in &set.labels {
            prior[y] += 1.0 / n;
        }
        let mut model = ConditionModel {
            thresholds,
            n_classes: k,
            config: config.clone(),
            mean,
            scale,
            weights: vec![0.0; k * (d + 1)],
            prior,
        };
        if let Some(start) = start {
            model.warm_start(start);
        }
        let stride = model.stride();
        let mut rows = Vec::with_capacity(set.len() * stride);
        for x in &set.features {
            model.design_into(x, &mut rows);
        }
        model.newton(&rows, &set.labels, config);
        Ok(model)
    }

    /// Sets the weights to `start`'s logits re-expressed in this model's standardisation
    /// (the same function of the raw features): with z = (x − m)/s, a weight w₀ on
    /// (x − m₀)/s₀ becomes w₀·s/s₀ and the bias gains w₀·(m − m₀)/s₀. Ignored when the
    /// shapes differ or a parameter would not be finite.
    fn warm_start(&mut self, start: &ConditionModel) {
        let stride = self.stride();
        if start.n_classes != self.n_classes
            || start.mean.len() != self.mean.len()
            || start.weights.len() != self.weights.len()
        {
            return;
        }
        let mut w = vec![0.0; self.weights.len()];
        for c in 0..self.n_classes {
            let (old, new) = (
                &start.weights[c * stride..(c + 1) * stride],
                &mut w[c * stride..(c + 1) * stride],
            );
            let mut bias = old[0];
            for f in 0..self.mean.len() {
                bias += old[f + 1] * (self.mean[f] - start.mean[f]) / start.scale[f];
                new[f + 1] = old[f + 1] * self.scale[f] / start.scale[f];
            }
            new[0] = bias;
        }
        if w.iter().all(|v| v.is_finite()) {
            self.weights = w;
        }
    }

    /// Bias term and standardised features.
    fn design(&self, x: &[f64]) -> Vec<f64> {
        let mut z = Vec::with_capacity(self.stride());
        self.design_into(x, &mut z);
        z
    }

    /// [`design`](Self::design) of `x`, appended to `out`.
    fn design_into(&self, x: &[f64], out: &mut Vec<f64>) {
        out.push(1.0);
        for (f, (m, s)) in self.mean.iter().zip(&self.scale).enumerate() {
            out.push((x.get(f).copied().unwrap_or(*m) - m) / s);
        }
    }

    /// Parameters per class (bias + features).
    fn stride(&self) -> usize {
        self.mean.len() + 1
    }

    fn softmax(&self, w: &[f64], z: &[f64], out: &mut [f64]) {
        let k = self.n_classes;
        let stride = self.stride();
        for c in 0..k {
            out[c] = (0..stride).map(|f| w[c * stride + f] * z[f]).sum();
        }
        Self::normalise(k, out);
    }

    /// [`softmax`](Self::softmax) of [`BLOCK`] consecutive design rows into `out` (K per
    /// row), the rows given feature-major (`zt`: feature f of row b at f·BLOCK + b, see
    /// [`transpose_blocks`](Self::transpose_blocks)): the same operations in the same order
    /// per row (each logit summed from −0.0, as `Iterator::sum` does, in feature order; then
    /// [`normalise`](Self::normalise)), so the same bits; the rows' independent sums are
    /// interleaved, which the processor overlaps (one row's sums are a chain of dependent
    /// additions), and read contiguously.
    fn softmax_block(&self, w: &[f64], zt: &[f64], out: &mut [f64]) {
        let k = self.n_classes;
        let stride = self.stride();
        for c in 0..k {
            let wc = &w[c * stride..(c + 1) * stride];
            let mut acc = [-0.0f64; BLOCK];
            for (&wf, col) in wc.iter().zip(zt.chunks_exact(BLOCK)) {
                for (a, &z) in acc.iter_mut().zip(col) {
                    *a += wf * z;
                }
            }
            for (b, a) in acc.iter().enumerate() {
                out[b * k + c] = *a;
            }
        }
        for p in out.chunks_exact_mut(k) {
            Self::normalise(k, p);
        }
    }

    /// The whole blocks of [`BLOCK`] design rows of `rows` (`stride` values each), each block
    /// feature-major (feature f of the block's row b at f·BLOCK + b), for
    /// [`softmax_block`](Self::softmax_block).
    fn transpose_blocks(rows: &[f64], stride: usize) -> Vec<f64> {
        let whole = rows.len() / stride / BLOCK * BLOCK;
        let mut zt = vec![0.0; whole * stride];
        for (src, dst) in rows[..whole * stride]
            .chunks_exact(BLOCK * stride)
            .zip(zt.chunks_exact_mut(BLOCK * stride))
        {
            for (b, z) in src.chunks_exact(stride).enumerate() {
                for (f, &v) in z.iter().enumerate() {
                    dst[f * BLOCK + b] = v;
                }
            }
        }
        zt
    }

    /// Logits (the first `k` of `out`) to probabilities: shifted by their maximum,
    /// exponentiated, divided by their sum. A shifted logit of zero (the maximum's) is
    /// e⁰ = 1 exactly, without calling `exp`.
    fn normalise(k: usize, out: &mut [f64]) {
        let mut max = f64::NEG_INFINITY;
        for &s in out.iter().take(k) {
            max = max.max(s);
        }
        let mut total = 0.0;
        for o in out.iter_mut().take(k) {
            let d = *o - max;
            *o = if d == 0.0 { 1.0 } else { d.exp() };
            total += *o;
        }
        for o in out.iter_mut().take(k) {
            *o /= total;
        }
    }

    fn penalty(config: &ConditionConfig, f: usize) -> f64 {
        if f == 0 { 1e-6 } else { config.l2 }
    }

    /// Mean negative log-likelihood plus the L2 penalty; `rows` are design rows (bias and
    /// standardised features), [`stride`](Self::stride) values each. Every row's class
    /// probabilities at `w` are left in `probs` (K per row, row order), for Newton's next
    /// step when `w` is accepted.
    #[cfg(test)]
    fn objective(
        &self,
        w: &[f64],
        rows: &[f64],
        labels: &[usize],
        config: &ConditionConfig,
        probs: &mut [f64],
    ) -> f64 {
        let zt = Self::transpose_blocks(rows, self.stride());
        self.objective_with(w, rows, &zt, labels, config, probs)
    }

    /// [`objective`](Self::objective), given also the whole blocks of `rows` feature-major
    /// (`zt`, from [`transpose_blocks`](Self::transpose_blocks)).
    fn objective_with(
        &self,
        w: &[f64],
        rows: &[f64],
        zt: &[f64],
        labels: &[usize],
        config: &ConditionConfig,
        probs: &mut [f64],
    ) -> f64 {
        let stride = self.stride();
        let k = self.n_classes;
        let whole = labels.len() / BLOCK * BLOCK;
        for (zs, ps) in zt[..whole * stride]
            .chunks_exact(BLOCK * stride)
            .zip(probs[..whole * k].chunks_exact_mut(BLOCK * k))
        {
            self.softmax_block(w, zs, ps);
        }
        for (z, p) in rows[whole * stride..]
            .chunks_exact(stride)
            .zip(probs[whole * k..].chunks_exact_mut(k))
        {
            self.softmax(w, z, p);
        }
        let mut nll = 0.0;
        for (p, &y) in probs.chunks_exact(k).zip(labels) {
            nll -= p[y].max(1e-300).ln();
        }
        let reg: f64 = w
            .iter()
            .enumerate()
            .map(|(i, v)| 0.5 * Self::penalty(config, i % stride) * v * v)
            .sum();
        nll / labels.len() as f64 + reg
    }

    /// Damped Newton's method on the (strictly convex) penalised log-likelihood, from the
    /// current weights. `rows`: design rows, [`stride`](Self::stride) values each.
    ///
    /// The Hessian's block (c, c2) is the sum over rows of p_c·(δ − p_c2)·z·zᵀ: each row's
    /// z·zᵀ is formed once (its upper triangle) and added to the K·(K+1)/2 upper blocks with
    /// their weights, then mirrored.
    fn newton(&mut self, rows: &[f64], labels: &[usize], config: &ConditionConfig) {
        let k = self.n_classes;
        let stride = self.stride();
        let p_len = k * stride;
        let n = labels.len() as f64;
        let tri = stride * (stride + 1) / 2;
        let pairs: Vec<(usize, usize)> =
            (0..k).flat_map(|c| (c..k).map(move |c2| (c, c2))).collect();
        let mut zz = vec![0.0; tri];
        let mut acc = vec![0.0; pairs.len() * tri];
        // Every row's probabilities at the current weights (from the objective's evaluation
        // that accepted them: the same softmax, so the same bits), and a scratch for trials.
        let mut probs = vec![0.0; labels.len() * k];
        let mut trial_probs = vec![0.0; labels.len() * k];
        let zt = Self::transpose_blocks(rows, stride);
        let mut current = self.objective_with(&self.weights, rows, &zt, labels, config, &mut probs);
        // Per block of ROWS rows: each row's z·zᵀ and pair weights, then every accumulator
        // gains the rows' terms one row after another (the same additions in the same order
        // as row by row, so the same bits) while it is held in a register.
        const ROWS: usize = 4;
        let mut zzs = vec![0.0; ROWS * tri];
        let mut ws = vec![0.0; pairs.len() * ROWS];
        for _ in 0..config.max_iterations {
            let mut grad = vec![0.0; p_len];
            acc.iter_mut().for_each(|a| *a = 0.0);
            let whole = labels.len() / ROWS * ROWS;
            for ((zb, yb), pb) in rows[..whole * stride]
                .chunks_exact(ROWS * stride)
                .zip(labels[..whole].chunks_exact(ROWS))
                .zip(probs[..whole * k].chunks_exact(ROWS * k))
            {
                for (j, ((z, &y), p)) in zb
                    .chunks_exact(stride)
                    .zip(yb)
                    .zip(pb.chunks_exact(k))
                    .enumerate()
                {
                    Self::add_gradient(&mut grad, z, y, p, k, stride);
                    Self::outer_upper(z, &mut zzs[j * tri..(j + 1) * tri]);
                    for (b, &(c, c2)) in pairs.iter().enumerate() {
                        ws[b * ROWS + j] = p[c] * (if c == c2 { 1.0 } else { 0.0 } - p[c2]);
                    }
                }
                let (z0, rest) = zzs.split_at(tri);
                let (z1, rest) = rest.split_at(tri);
                let (z2, z3) = rest.split_at(tri);
                for (b, w) in ws.chunks_exact(ROWS).enumerate() {
                    let (w0, w1, w2, w3) = (w[0], w[1], w[2], w[3]);
                    for ((((a, v0), v1), v2), v3) in acc[b * tri..(b + 1) * tri]
                        .iter_mut()
                        .zip(z0)
                        .zip(z1)
                        .zip(z2)
                        .zip(z3)
                    {
                        let mut x = *a;
                        x += w0 * v0;
                        x += w1 * v1;
                        x += w2 * v2;
                        x += w3 * v3;
                        *a = x;
                    }
                }
            }
            for ((z, &y), p) in rows[whole * stride..]
                .chunks_exact(stride)
                .zip(&labels[whole..])
                .zip(probs[whole * k..].chunks_exact(k))
            {
                Self::add_gradient(&mut grad, z, y, p, k, stride);
                Self::outer_upper(z, &mut zz);
                for (b, &(c, c2)) in pairs.iter().enumerate() {
                    let w = p[c] * (if c == c2 { 1.0 } else { 0.0 } - p[c2]);
                    for (a, v) in acc[b * tri..(b + 1) * tri].iter_mut().zip(&zz) {
                        *a += w * v;
                    }
                }
            }
            let mut hess = vec![0.0; p_len * p_len];
            for (b, &(c, c2)) in pairs.iter().enumerate() {
                let mut o = b * tri;
                for f in 0..stride {
                    for g in f..stride {
                        let v = acc[o] / n;
                        o += 1;
                        let (i, j) = (c * stride + f, c2 * stride + g);
                        let (i2, j2) = (c * stride + g, c2 * stride + f);
                        hess[i * p_len + j] = v;
                        hess[i2 * p_len + j2] = v;
                        hess[j * p_len + i] = v;
                        hess[j2 * p_len + i2] = v;
                    }
                }
            }
            for i in 0..p_len {
                grad[i] = grad[i] / n + Self::penalty(config, i % stride) * self.weights[i];
                hess[i * p_len + i] += Self::penalty(config, i % stride);
            }
            let Some(step) = cholesky_solve(&hess, &grad, p_len) else {
                break;
            };
            if grad.iter().all(|g| g.abs() < config.tolerance) {
                // Converged: one last full Newton step squares the remaining error, so fits
                // from different starts (warm or cold) agree to rounding, not to the tolerance.
                for (w, s) in self.weights.iter_mut().zip(&step) {
                    *w -= s;
                }
                break;
            }
            let mut t = 1.0;
            let mut improved = false;
            let full: Vec<f64> = self.weights.iter().zip(&step).map(|(w, s)| w - s).collect();
            for _ in 0..40 {
                let trial: Vec<f64> = self
                    .weights
                    .iter()
                    .zip(&step)
                    .map(|(w, s)| w - t * s)
                    .collect();
                let value =
                    self.objective_with(&trial, rows, &zt, labels, config, &mut trial_probs);
                if value <= current {
                    improved = value < current;
                    self.weights = trial;
                    std::mem::swap(&mut probs, &mut trial_probs);
                    current = value;
                    break;
                }
                t *= 0.5;
            }
            if !improved {
                // Near the optimum the objective no longer changes in floating point: take
                // the full Newton step while it still shrinks the gradient (quadratic
                // convergence), so fits from different starts agree to rounding.
                let max_abs = |g: &[f64]| g.iter().fold(0.0f64, |a, b| a.max(b.abs()));
                let trial = self.gradient(&full, rows, labels, config);
                if max_abs(&trial) < max_abs(&grad) {
                    self.weights = full;
                    current =
                        self.objective_with(&self.weights, rows, &zt, labels, config, &mut probs);
                    continue;
                }
                break;
            }
        }
    }

    /// Adds one row's gradient terms, (p_c − δ_cy)·z per class, to `grad`.
    fn add_gradient(grad: &mut [f64], z: &[f64], y: usize, p: &[f64], k: usize, stride: usize) {
        for c in 0..k {
            let r = p[c] - if c == y { 1.0 } else { 0.0 };
            for (g, zf) in grad[c * stride..(c + 1) * stride].iter_mut().zip(z) {
                *g += r * zf;
            }
        }
    }

    /// The upper triangle of z·zᵀ, row by row, into `zz`.
    fn outer_upper(z: &[f64], zz: &mut [f64]) {
        let stride = z.len();
        let mut o = 0;
        for f in 0..stride {
            let zf = z[f];
            for (dst, zg) in zz[o..o + stride - f].iter_mut().zip(&z[f..]) {
                *dst = zf * zg;
            }
            o += stride - f;
        }
    }

    /// Gradient of [`objective`](Self::objective) at `w`.
    fn gradient(
        &self,
        w: &[f64],
        rows: &[f64],
        labels: &[usize],
        config: &ConditionConfig,
    ) -> Vec<f64> {
        let k = self.n_classes;
        let stride = self.stride();
        let mut p = vec![0.0; k];
        let mut grad = vec![0.0; k * stride];
        for (z, &y) in rows.chunks_exact(stride).zip(labels) {
            self.softmax(w, z, &mut p);
            for c in 0..k {
                let r = p[c] - if c == y { 1.0 } else { 0.0 };
                for (g, zf) in grad[c * stride..(c + 1) * stride].iter_mut().zip(z) {
                    *g += r * zf;
                }
            }
        }
        let n = labels.len() as f64;
        for (i, g) in grad.iter_mut().enumerate() {
            *g = *g / n + Self::penalty(config, i % stride) * w[i];
        }
        grad
    }

    /// Class probabilities for one feature row (see [`condition_features`]).
    pub fn predict_features(&self, x: &[f64]) -> Vec<f64> {
        let mut p = vec![0.0; self.n_classes];
        self.softmax(&self.weights, &self.design(x), &mut p);
        p
    }

    /// Class probabilities of every cell at time `t` (s), from all the data in `cells` up to
    /// `t` (pass only collected data) and the neighbours' latest values. A cell with no data
    /// gets the uniform distribution (U = 1).
    pub fn predict_proba(
        &self,
        cells: &[Series<'_>],
        neighbours: &[Vec<usize>],
        t: UnixSeconds,
    ) -> Vec<Vec<f64>> {
        let mut nb_series = Vec::new();
        cells
            .iter()
            .enumerate()
            .map(|(i, cell)| {
                nb_series.clear();
                if let Some(nbs) = neighbours.get(i) {
                    nb_series.extend(nbs.iter().filter_map(|&j| cells.get(j).copied()));
                }
                match condition_features(*cell, &nb_series, t, t, &self.thresholds, &self.config) {
                    Some(x) => self.predict_features(&x),
                    None => vec![1.0 / self.n_classes as f64; self.n_classes],
                }
            })
            .collect()
    }

    /// Accuracy and log-loss on `set` (e.g. rows with label times after the training period),
    /// next to the majority-class / class-frequency baselines of the training set.
    pub fn evaluate(&self, set: &TrainingSet) -> Evaluation {
        let n = set.len();
        let majority = (0..self.n_classes)
            .max_by(|&a, &b| self.prior[a].total_cmp(&self.prior[b]).then(b.cmp(&a)))
            .unwrap_or(0);
        let (mut hits, mut loss, mut base_hits, mut base_loss) = (0usize, 0.0, 0usize, 0.0);
        let mut persistence_hits = 0usize;
        for (x, &y) in set.features.iter().zip(&set.labels) {
            let p = self.predict_features(x);
            let best = (0..self.n_classes)
                .max_by(|&a, &b| p[a].total_cmp(&p[b]).then(b.cmp(&a)))
                .unwrap_or(0);
            hits += usize::from(best == y);
            loss -= p.get(y).copied().unwrap_or(0.0).max(1e-15).ln();
            base_hits += usize::from(majority == y);
            let last = x.first().copied().unwrap_or(f64::NAN);
            persistence_hits += usize::from(class_of(last, &self.thresholds) == y);
            base_loss -= self.prior.get(y).copied().unwrap_or(0.0).max(1e-15).ln();
        }
        let nf = n.max(1) as f64;
        Evaluation {
            n,
            accuracy: hits as f64 / nf,
            log_loss: loss / nf,
            baseline_accuracy: base_hits as f64 / nf,
            baseline_log_loss: base_loss / nf,
            persistence_accuracy: persistence_hits as f64 / nf,
        }
    }

    /// The class thresholds (K − 1, ascending, the class modality's unit).
    pub fn thresholds(&self) -> &[f64] {
        &self.thresholds
    }

    /// Number of classes K.
    pub fn n_classes(&self) -> usize {
        self.n_classes
    }

    /// Training class frequencies.
    pub fn prior(&self) -> &[f64] {
        &self.prior
    }

    /// Weight of feature `f` ([`FEATURE_NAMES`] order, then the threshold distances;
    /// standardised scale) for class `class`. Panics on positions out of range.
    pub fn weight(&self, class: usize, f: usize) -> f64 {
        self.weights[class * self.stride() + 1 + f]
    }
}

/// Longest lag a decoded model may carry, days (100 years; keeps the lag arithmetic in range).
const MAX_LAG_DAYS: i64 = 36_525;

/// Magic of a serialised [`ConditionModel`] (8 bytes).
const MODEL_MAGIC: &[u8; 8] = b"GLNCONDM";

impl ConditionModel {
    /// Version of the format written by [`to_bytes`](Self::to_bytes).
    pub const FORMAT_VERSION: u32 = 1;

    /// The trained model as bytes (deterministic, little-endian), so scoring need not refit
    /// it: the 8-byte magic `GLNCONDM`, the `u32` [`FORMAT_VERSION`](Self::FORMAT_VERSION),
    /// then the configuration (classes u64; thresholds kind u8 (0 quantiles, 1 fixed) and
    /// fixed thresholds as f64 list; lags as i64 list, days; trend points u64; season u8; L2,
    /// tolerance f64; max iterations u64), the thresholds used (f64 list, unit), the
    /// standardisation (mean and scale per feature, f64 lists), the weights (f64 list,
    /// class-major, bias first) and the training class frequencies (f64 list). Lists are a u64
    /// length then the elements.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut w = Writer::with_header(MODEL_MAGIC, Self::FORMAT_VERSION);
        let c = &self.config;
        w.len(c.n_classes);
        match &c.thresholds {
            ClassThresholds::Quantiles => w.u8(0),
            ClassThresholds::Fixed(th) => {
                w.u8(1);
                w.f64s(th);
            }
        }
        w.i64s(&c.lags_days);
        w.len(c.trend_points);
        w.bool(c.season);
        w.f64(c.l2);
        w.f64(c.tolerance);
        w.len(c.max_iterations);
        w.f64s(&self.thresholds);
        w.f64s(&self.mean);
        w.f64s(&self.scale);
        w.f64s(&self.weights);
        w.f64s(&self.prior);
        w.buf
    }

    /// Decodes [`to_bytes`](Self::to_bytes)'s output. Wrong magic or version, truncated or
    /// trailing bytes, an invalid configuration, non-finite parameters or lengths that do not
    /// fit K classes and the feature count are errors ([`UtilityError::Decode`] or
    /// [`UtilityError::Model`]); never a panic.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, UtilityError> {
        let (mut r, _) = Reader::with_header(
            bytes,
            MODEL_MAGIC,
            Self::FORMAT_VERSION..=Self::FORMAT_VERSION,
            "condition model",
        )?;
        let n_classes = r.len(0)?;
        let thresholds = match r.u8()? {
            0 => ClassThresholds::Quantiles,
            1 => ClassThresholds::Fixed(r.f64s()?),
            b => return Err(r.error(format!("invalid thresholds kind {b}"))),
        };
        let config = ConditionConfig {
            n_classes,
            thresholds,
            lags_days: r.i64s()?,
            trend_points: r.len(0)?,
            season: r.bool()?,
            l2: r.f64()?,
            tolerance: r.f64()?,
            max_iterations: r.len(0)?,
        };
        config.validate()?;
        let thresholds = r.finite_f64s()?;
        let mean = r.finite_f64s()?;
        let scale = r.finite_f64s()?;
        let weights = r.finite_f64s()?;
        let prior = r.finite_f64s()?;
        r.finish()?;
        let k = n_classes;
        let bad = |what: &str, got: usize, want: usize| {
            Err(UtilityError::Model(format!(
                "serialised model: {got} {what}, expected {want} for {k} classes"
            )))
        };
        // k >= 2 (validated); checked against a list read from the input before any
        // arithmetic on it.
        if thresholds.len() != k - 1 {
            return bad("thresholds", thresholds.len(), k - 1);
        }
        if let Some(lag) = config.lags_days.iter().find(|&&l| l > MAX_LAG_DAYS) {
            return Err(UtilityError::Model(format!(
                "serialised model: lag {lag} days exceeds {MAX_LAG_DAYS}"
            )));
        }
        let d = BASE + k - 1;
        if mean.len() != d || scale.len() != d {
            return bad("standardisation entries", mean.len().min(scale.len()), d);
        }
        if Some(weights.len()) != k.checked_mul(d + 1) {
            return bad("weights", weights.len(), k.saturating_mul(d + 1));
        }
        if prior.len() != k {
            return bad("class frequencies", prior.len(), k);
        }
        if scale.iter().any(|&s| s <= 0.0) {
            return Err(UtilityError::Model(format!(
                "serialised model: non-positive feature scale in {scale:?}"
            )));
        }
        Ok(Self {
            thresholds,
            n_classes: k,
            config,
            mean,
            scale,
            weights,
            prior,
        })
    }

    /// The configuration the model was trained with.
    pub fn config(&self) -> &ConditionConfig {
        &self.config
    }
}

/// Solves the symmetric positive definite system A x = b (n × n, row-major) by Cholesky;
/// `None` if A is not positive definite.
fn cholesky_solve(a: &[f64], b: &[f64], n: usize) -> Option<Vec<f64>> {
    let mut l = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..=i {
            let mut s = a[i * n + j];
            for k in 0..j {
                s -= l[i * n + k] * l[j * n + k];
            }
            if i == j {
                if s.is_nan() || s <= 0.0 {
                    return None;
                }
                l[i * n + i] = s.sqrt();
            } else {
                l[i * n + j] = s / l[j * n + j];
            }
        }
    }
    let mut y = vec![0.0; n];
    for i in 0..n {
        let s: f64 = (0..i).map(|k| l[i * n + k] * y[k]).sum();
        y[i] = (b[i] - s) / l[i * n + i];
    }
    let mut x = vec![0.0; n];
    for i in (0..n).rev() {
        let s: f64 = (i + 1..n).map(|k| l[k * n + i] * x[k]).sum();
        x[i] = (y[i] - s) / l[i * n + i];
    }
    Some(x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn quantiles_and_classes() {
        let th = quantile_thresholds(&[4.0, 1.0, 3.0, 2.0, f64::NAN], 3).unwrap();
        assert!(
            (th[0] - 2.0).abs() < 1e-12 && (th[1] - 3.0).abs() < 1e-12,
            "{th:?}"
        );
        assert_eq!(class_of(1.9, &th), 0);
        assert_eq!(class_of(2.0, &th), 1);
        assert_eq!(class_of(5.0, &th), 2);
        assert!(quantile_thresholds(&[], 3).is_err());
    }

    #[test]
    fn features_by_hand() {
        let t = [0, 86_400, 2 * 86_400, 3 * 86_400];
        let v = [1.0, 2.0, 3.0, 10.0];
        let nt = [0, 86_400];
        let nv = [5.0, 7.0];
        let s = Series::new(&t, &v);
        // Known until day 2 (so day 3 is unknown), predicting day 5.
        let f = condition_features(
            s,
            &[Series::new(&nt, &nv), Series::empty()],
            5 * 86_400,
            2 * 86_400,
            &[2.0, 7.0],
            &ConditionConfig::default(),
        )
        .unwrap();
        assert_eq!(f.len(), 11);
        assert!((f[9] - 1.0 / 3.5f64.sqrt()).abs() < 1e-12);
        assert!((f[10] + 4.0 / 3.5f64.sqrt()).abs() < 1e-12);
        assert_eq!(f[0], 3.0);
        assert_eq!(f[1], 3.0);
        assert_eq!(f[2], 9.0);
        assert!((f[3] - 1.0).abs() < 1e-12);
        assert!((f[4] - 3.0).abs() < 1e-12);
        assert!((f[5].powi(2) + f[6].powi(2) - 1.0).abs() < 1e-12);
        assert_eq!(f[7], 7.0);
        assert_eq!(f[8], 21.0);
        assert!(condition_features(s, &[], 5, -1, &[], &ConditionConfig::default()).is_none());
    }

    /// Synthetic cells: a noisy seasonal moisture cycle with cell offsets.
    fn synthetic(seed: u64) -> (Vec<Vec<i64>>, Vec<Vec<f64>>) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut times = Vec::new();
        let mut values = Vec::new();
        for c in 0..6 {
            let offset = 0.01 * c as f64;
            let mut x = 0.0;
            let (mut ts, mut vs) = (Vec::new(), Vec::new());
            for d in 0..730i64 {
                x = 0.9 * x + rng.random_range(-0.02..0.02);
                if rng.random_bool(0.8) {
                    ts.push(d * 86_400);
                    vs.push(
                        0.3 + offset + 0.08 * (d as f64 * std::f64::consts::TAU / 365.0).sin() + x,
                    );
                }
            }
            times.push(ts);
            values.push(vs);
        }
        (times, values)
    }

    #[test]
    fn model_beats_the_baseline_and_flattens_with_staleness() {
        let (times, values) = synthetic(3);
        let cells: Vec<Series> = times
            .iter()
            .zip(&values)
            .map(|(t, v)| Series::new(t, v))
            .collect();
        let neighbours: Vec<Vec<usize>> = (0..6).map(|i| vec![(i + 1) % 6, (i + 5) % 6]).collect();
        let config = ConditionConfig::default();
        let split = 500 * 86_400;
        let model = ConditionModel::fit(&cells, &neighbours, 0, split, &config).unwrap();
        let test = TrainingSet::build(
            &cells,
            &neighbours,
            model.thresholds(),
            split,
            i64::MAX,
            &config,
        );
        let e = model.evaluate(&test);
        assert!(e.n > 1000);
        assert!(e.accuracy > e.baseline_accuracy + 0.1, "{e:?}");
        assert!(e.log_loss < e.baseline_log_loss, "{e:?}");
        // Same cell, same known data: the further t is from the last collection, the flatter.
        let known = 600 * 86_400;
        let entropy = |lag: i64| {
            let f = condition_features(
                cells[0],
                &[],
                known + lag * 86_400,
                known,
                model.thresholds(),
                &config,
            )
            .unwrap();
            crate::uncertainty(&model.predict_features(&f))
        };
        assert!(
            entropy(14) > entropy(1),
            "{} vs {}",
            entropy(14),
            entropy(1)
        );
        let p = model.predict_proba(&cells, &neighbours, known);
        assert!(
            p.iter()
                .all(|p| (p.iter().sum::<f64>() - 1.0).abs() < 1e-12)
        );
        // Training is deterministic.
        assert_eq!(
            ConditionModel::fit(&cells, &neighbours, 0, split, &config).unwrap(),
            model
        );
    }

    #[test]
    fn warm_start_reaches_the_cold_fit() {
        let (times, values) = synthetic(5);
        let cells: Vec<Series> = times
            .iter()
            .zip(&values)
            .map(|(t, v)| Series::new(t, v))
            .collect();
        let neighbours: Vec<Vec<usize>> = (0..6).map(|i| vec![(i + 1) % 6, (i + 5) % 6]).collect();
        let config = ConditionConfig::default();
        let early = ConditionModel::fit(&cells, &neighbours, 0, 400 * 86_400, &config).unwrap();
        for to in [401, 430, 600] {
            let to = to * 86_400;
            let cold = ConditionModel::fit(&cells, &neighbours, 0, to, &config).unwrap();
            let warm = ConditionModel::fit_from(&cells, &neighbours, 0, to, &config, Some(&early))
                .unwrap();
            assert_eq!(warm.thresholds, cold.thresholds);
            assert_eq!(warm.mean, cold.mean);
            let diff = warm
                .weights
                .iter()
                .zip(&cold.weights)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            // Both run to the optimum (to rounding, see `newton`).
            assert!(diff < 1e-9, "weights differ by {diff} (to = {to})");
            let (pw, pc) = (
                warm.predict_proba(&cells, &neighbours, to + 86_400),
                cold.predict_proba(&cells, &neighbours, to + 86_400),
            );
            for (a, b) in pw.iter().flatten().zip(pc.iter().flatten()) {
                assert!((a - b).abs() < 1e-12, "{a} vs {b}");
            }
        }
        // A start of another shape is ignored.
        let four = ConditionConfig {
            n_classes: 4,
            ..ConditionConfig::default()
        };
        let other = ConditionModel::fit(&cells, &neighbours, 0, 400 * 86_400, &four).unwrap();
        let cold = ConditionModel::fit(&cells, &neighbours, 0, 500 * 86_400, &config).unwrap();
        let warm =
            ConditionModel::fit_from(&cells, &neighbours, 0, 500 * 86_400, &config, Some(&other))
                .unwrap();
        assert_eq!(warm, cold);
    }

    #[test]
    fn bad_configurations() {
        let (t, v) = (vec![0i64], vec![1.0]);
        let cells = [Series::new(&t, &v)];
        for c in [
            ConditionConfig {
                n_classes: 1,
                ..Default::default()
            },
            ConditionConfig {
                thresholds: ClassThresholds::Fixed(vec![0.3]),
                ..Default::default()
            },
            ConditionConfig {
                thresholds: ClassThresholds::Fixed(vec![0.3, 0.2]),
                ..Default::default()
            },
            ConditionConfig {
                lags_days: vec![0],
                ..Default::default()
            },
            ConditionConfig {
                trend_points: 1,
                ..Default::default()
            },
        ] {
            assert!(
                ConditionModel::fit(&cells, &[vec![]], 0, 10, &c).is_err(),
                "{c:?}"
            );
        }
        // No rows at all (nothing before the lag).
        assert!(
            ConditionModel::fit(&cells, &[vec![]], 0, 10, &ConditionConfig::default()).is_err()
        );
    }

    #[test]
    fn model_bytes_round_trip_and_reject_corruption() {
        let (times, values) = synthetic(5);
        let cells: Vec<Series> = times
            .iter()
            .zip(&values)
            .map(|(t, v)| Series::new(t, v))
            .collect();
        let neighbours: Vec<Vec<usize>> = (0..6).map(|i| vec![(i + 1) % 6]).collect();
        for config in [
            ConditionConfig::default(),
            ConditionConfig {
                n_classes: 2,
                thresholds: ClassThresholds::Fixed(vec![0.3]),
                lags_days: vec![1, 3],
                season: false,
                ..ConditionConfig::default()
            },
        ] {
            let model = ConditionModel::fit(&cells, &neighbours, 0, 400 * 86_400, &config).unwrap();
            let bytes = model.to_bytes();
            assert_eq!(&bytes[..8], b"GLNCONDM");
            let back = ConditionModel::from_bytes(&bytes).unwrap();
            assert_eq!(back, model);
            assert_eq!(back.to_bytes(), bytes);
            assert_eq!(back.config(), &config);
            assert_eq!(
                back.predict_proba(&cells, &neighbours, 500 * 86_400),
                model.predict_proba(&cells, &neighbours, 500 * 86_400)
            );
            for n in 0..bytes.len() {
                assert!(
                    ConditionModel::from_bytes(&bytes[..n]).is_err(),
                    "prefix {n}"
                );
            }
            let mut rng = ChaCha8Rng::seed_from_u64(9);
            for _ in 0..2000 {
                let mut b = bytes.clone();
                let k = rng.random_range(0..b.len());
                b[k] = rng.random();
                if let Ok(m) = ConditionModel::from_bytes(&b) {
                    let _ = m.predict_proba(&cells, &neighbours, 500 * 86_400);
                }
            }
        }
    }

    /// A model of `k` classes with the given weights (standardisation irrelevant here).
    fn bare_model(k: usize, weights: Vec<f64>) -> ConditionModel {
        let d = BASE + k - 1;
        ConditionModel {
            thresholds: vec![0.0; k - 1],
            n_classes: k,
            config: ConditionConfig {
                n_classes: k,
                ..ConditionConfig::default()
            },
            mean: vec![0.0; d],
            scale: vec![1.0; d],
            weights,
            prior: vec![1.0 / k as f64; k],
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::test_runner::Config::with_cases(64))]
        /// The objective's blocked softmax gives every row the bits the one-row softmax gives
        /// (the Newton step reuses them), and the objective the value of the one-row loop.
        #[test]
        fn blocked_softmax_is_the_row_softmax_to_the_bit(
            k in 2usize..=4,
            n in 0usize..40,
            seed in proptest::num::u64::ANY,
        ) {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let d = BASE + k - 1;
            let stride = d + 1;
            let pick = |rng: &mut ChaCha8Rng| -> f64 {
                match rng.random_range(0..8) {
                    0 => 0.0,
                    1 => -0.0,
                    2 => rng.random_range(-1e3..1e3),
                    _ => rng.random_range(-3.0..3.0),
                }
            };
            let weights: Vec<f64> = (0..k * stride).map(|_| pick(&mut rng)).collect();
            let model = bare_model(k, weights.clone());
            let rows: Vec<f64> = (0..n * stride)
                .map(|i| if i % stride == 0 { 1.0 } else { pick(&mut rng) })
                .collect();
            let labels: Vec<usize> = (0..n).map(|_| rng.random_range(0..k)).collect();
            let config = model.config.clone();
            let mut probs = vec![f64::NAN; n * k];
            let value = model.objective(&weights, &rows, &labels, &config, &mut probs);
            let mut p = vec![0.0; k];
            let mut nll = 0.0;
            for (r, (z, &y)) in rows.chunks_exact(stride).zip(&labels).enumerate() {
                model.softmax(&weights, z, &mut p);
                for c in 0..k {
                    proptest::prop_assert_eq!(probs[r * k + c].to_bits(), p[c].to_bits());
                }
                nll -= p[y].max(1e-300).ln();
            }
            let reg: f64 = weights
                .iter()
                .enumerate()
                .map(|(i, v)| 0.5 * ConditionModel::penalty(&config, i % stride) * v * v)
                .sum();
            let want = nll / labels.len() as f64 + reg;
            proptest::prop_assert_eq!(value.to_bits(), want.to_bits());
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::test_runner::Config::with_cases(256))]
        /// `normalise` skips `exp` for the maximum's shifted logit (zero): the same bits as
        /// exponentiating every shifted logit, ties, signed zeros and infinities included.
        #[test]
        fn normalise_is_the_plain_softmax_to_the_bit(
            logits in proptest::collection::vec(
                proptest::prop_oneof![
                    proptest::strategy::Just(0.0),
                    proptest::strategy::Just(-0.0),
                    proptest::strategy::Just(f64::INFINITY),
                    proptest::strategy::Just(f64::NEG_INFINITY),
                    proptest::strategy::Just(1.5),
                    -800.0f64..800.0,
                ],
                1..6,
            ),
        ) {
            let k = logits.len();
            let mut got = logits.clone();
            ConditionModel::normalise(k, &mut got);
            let max = logits.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b));
            let mut want: Vec<f64> = logits.iter().map(|&o| (o - max).exp()).collect();
            let total: f64 = want.iter().fold(0.0, |a, &b| a + b);
            want.iter_mut().for_each(|w| *w /= total);
            for (g, w) in got.iter().zip(&want) {
                proptest::prop_assert_eq!(g.to_bits(), w.to_bits(), "{:?}: {:?} vs {:?}", logits, got, want);
            }
        }

        #[test]
        fn arbitrary_model_bytes_never_panic(
            body in proptest::collection::vec(proptest::num::u8::ANY, 0..400),
        ) {
            let mut bytes = b"GLNCONDM".to_vec();
            bytes.extend_from_slice(&1u32.to_le_bytes());
            bytes.extend_from_slice(&body);
            let _ = ConditionModel::from_bytes(&bytes);
            let _ = ConditionModel::from_bytes(&body);
        }
    }
}
