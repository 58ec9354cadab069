//! The four terms of docs/method.md §2 as pure functions of plain values.

use crate::{Series, UtilityConfig};
use gleaner_field::UnixSeconds;

/// A sum of squared deviations `m2` over `n` points with mean `mean` counts as zero variance
/// when the standard deviation is below 1e-12 of the mean's magnitude (or `m2` is not
/// positive): rounding in the mean of a constant series must not fake a variance.
pub(crate) fn is_degenerate(m2: f64, n: f64, mean: f64) -> bool {
    m2.is_nan() || m2 <= 0.0 || m2 <= n * (1e-12 * mean).powi(2)
}

/// Freshness F_i = mean over the cell's sensors of 1 − exp(−lambda·(t − t_j^l)) (docs/method.md §2),
/// dimensionless in [0, 1].
///
/// `t` is the mission time (s), `last_collected` the sensors' last collection times (s;
/// `None` = never collected, term 1), `lambda_per_s` the decay rate (1/s, e.g.
/// [`UtilityConfig::lambda_per_s`]). A collection time after `t` counts as age 0. A cell without
/// sensors is maximally stale (1).
///
/// ```
/// use gleaner_utility::freshness;
/// let lambda = std::f64::consts::LN_2 / 259_200.0; // 3-day half-life
/// let f = freshness(1_036_800, &[Some(777_600), None], lambda); // 3 days old, never
/// assert!((f - 0.75).abs() < 1e-12);
/// ```
pub fn freshness(t: UnixSeconds, last_collected: &[Option<UnixSeconds>], lambda_per_s: f64) -> f64 {
    if last_collected.is_empty() {
        return 1.0;
    }
    let total: f64 = last_collected
        .iter()
        .map(|l| match l {
            None => 1.0,
            Some(l) => {
                let age = (t.saturating_sub(*l)).max(0) as f64;
                -(-lambda_per_s * age).exp_m1()
            }
        })
        .sum();
    (total / last_collected.len() as f64).clamp(0.0, 1.0)
}

/// Pearson correlation of two equally long samples, or `None` when fewer than 2 points or
/// either sample has zero variance. Two-pass (means first), clamped to [−1, 1]. Symmetric.
/// Samples longer than `x` or `y`'s common length are truncated to it.
///
/// ```
/// use gleaner_utility::pearson;
/// let r = pearson(&[1.0, 2.0, 3.0], &[2.0, 4.0, 7.0]).unwrap();
/// assert!((r - 0.9933992677987828).abs() < 1e-12);
/// assert_eq!(pearson(&[1.0, 1.0, 1.0], &[1.0, 2.0, 3.0]), None);
/// ```
pub fn pearson(x: &[f64], y: &[f64]) -> Option<f64> {
    let n = x.len().min(y.len());
    if n < 2 {
        return None;
    }
    let (x, y) = (&x[..n], &y[..n]);
    let (a, b) = (Moments::of(x), Moments::of(y));
    let sxy = co_moment(x, a.mean, y, b.mean);
    finish_pearson(n as f64, a.mean, b.mean, a.m2, b.m2, sxy)
}

/// Number of independent accumulators in the summation loops: lets the compiler vectorise
/// the sums (a sequential float sum cannot be reordered) at the price of a different, equally
/// accurate, rounding.
const LANES: usize = 4;

/// Count, mean and sum of squared deviations of a sample (two-pass).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct Moments {
    pub(crate) n: usize,
    pub(crate) mean: f64,
    pub(crate) m2: f64,
}

impl Moments {
    pub(crate) fn of(x: &[f64]) -> Self {
        let n = x.len();
        if n == 0 {
            return Self::default();
        }
        let mut acc = [0.0; LANES];
        let chunks = x.chunks_exact(LANES);
        let rest: f64 = chunks.remainder().iter().sum();
        for c in chunks {
            for l in 0..LANES {
                acc[l] += c[l];
            }
        }
        let mean = ((acc[0] + acc[1]) + (acc[2] + acc[3]) + rest) / n as f64;
        let mut acc = [0.0; LANES];
        let chunks = x.chunks_exact(LANES);
        let rest: f64 = chunks
            .remainder()
            .iter()
            .map(|v| (v - mean) * (v - mean))
            .sum();
        for c in chunks {
            for l in 0..LANES {
                let d = c[l] - mean;
                acc[l] += d * d;
            }
        }
        let m2 = (acc[0] + acc[1]) + (acc[2] + acc[3]) + rest;
        Self { n, mean, m2 }
    }
}

/// Σ (x − mx)(y − my) over equally long samples.
pub(crate) fn co_moment(x: &[f64], mx: f64, y: &[f64], my: f64) -> f64 {
    let n = x.len().min(y.len());
    let (x, y) = (&x[..n], &y[..n]);
    let mut acc = [0.0; LANES];
    let (xc, yc) = (x.chunks_exact(LANES), y.chunks_exact(LANES));
    let rest: f64 = xc
        .remainder()
        .iter()
        .zip(yc.remainder())
        .map(|(a, b)| (a - mx) * (b - my))
        .sum();
    for (a, b) in xc.zip(yc) {
        for l in 0..LANES {
            acc[l] += (a[l] - mx) * (b[l] - my);
        }
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + rest
}

/// Correlation of two series known to share all their timestamps, from their precomputed
/// moments (the fast path of [`series_correlation`]).
pub(crate) fn aligned_correlation(
    x: &[f64],
    a: Moments,
    y: &[f64],
    b: Moments,
    min_overlap: usize,
) -> f64 {
    if a.n < min_overlap.max(2) || a.n != b.n {
        return 0.0;
    }
    let sxy = co_moment(x, a.mean, y, b.mean);
    finish_pearson(a.n as f64, a.mean, b.mean, a.m2, b.m2, sxy).unwrap_or(0.0)
}

pub(crate) fn finish_pearson(
    n: f64,
    mx: f64,
    my: f64,
    sxx: f64,
    syy: f64,
    sxy: f64,
) -> Option<f64> {
    if is_degenerate(sxx, n, mx) || is_degenerate(syy, n, my) {
        return None;
    }
    Some((sxy / (sxx * syy).sqrt()).clamp(-1.0, 1.0))
}

/// Pearson correlation of two series over the timestamps where both have a value (docs/method.md §2):
/// 0 when there are fewer than `min_overlap` common timestamps or either side has zero
/// variance (no evidence of redundancy). Dimensionless in [−1, 1].
pub fn series_correlation(a: Series<'_>, b: Series<'_>, min_overlap: usize) -> f64 {
    let (na, nb) = (a.len(), b.len());
    if na.min(nb) < min_overlap.max(2) {
        return 0.0;
    }
    if a.times[..na] == b.times[..nb] {
        return pearson(&a.values[..na], &b.values[..nb]).unwrap_or(0.0);
    }
    merged_correlation(a, b, min_overlap, &mut Vec::new(), &mut Vec::new())
}

/// The merge-join path of [`series_correlation`], gathering into reusable buffers.
pub(crate) fn merged_correlation(
    a: Series<'_>,
    b: Series<'_>,
    min_overlap: usize,
    xs: &mut Vec<f64>,
    ys: &mut Vec<f64>,
) -> f64 {
    let (na, nb) = (a.len(), b.len());
    if na.min(nb) < min_overlap.max(2) {
        return 0.0;
    }
    // Gather the common points with a branch-free merge join (every step writes a candidate
    // pair and advances the count only on a match), then the two-pass Pearson.
    let cap = na.min(nb) + 1;
    xs.clear();
    ys.clear();
    xs.resize(cap, 0.0);
    ys.resize(cap, 0.0);
    let (mut i, mut j, mut k) = (0, 0, 0);
    while i < na && j < nb {
        let (ta, tb) = (a.times[i], b.times[j]);
        xs[k] = a.values[i];
        ys[k] = b.values[j];
        k += usize::from(ta == tb);
        i += usize::from(ta <= tb);
        j += usize::from(tb <= ta);
    }
    if k < min_overlap.max(2) {
        return 0.0;
    }
    pearson(&xs[..k], &ys[..k]).unwrap_or(0.0)
}

/// Redundancy of one modality R_i^m = (1/|N_i|)·Σ_j max(0, corr(x̂_i^m, x̂_j^m)) (docs/method.md §2),
/// dimensionless in [0, 1]. `neighbours` holds the neighbours' series of modality m (an empty
/// series for a neighbour lacking m: it contributes 0 but still counts in |N_i|). No neighbours
/// gives 0. Window the series (e.g. with [`Series::between`]) before calling.
///
/// ```
/// use gleaner_utility::{redundancy, Series};
/// let t: Vec<i64> = (0..10).collect();
/// let x: Vec<f64> = (0..10).map(|k| k as f64).collect();
/// let r = redundancy(Series::new(&t, &x), &[Series::new(&t, &x), Series::empty()], 10);
/// assert!((r - 0.5).abs() < 1e-12); // one identical neighbour, one without the modality
/// ```
pub fn redundancy(cell: Series<'_>, neighbours: &[Series<'_>], min_overlap: usize) -> f64 {
    if neighbours.is_empty() {
        return 0.0;
    }
    let total: f64 = neighbours
        .iter()
        .map(|nb| series_correlation(cell, *nb, min_overlap).max(0.0))
        .sum();
    (total / neighbours.len() as f64).clamp(0.0, 1.0)
}

/// Anomaly of one modality A_i^m = |x̂(t*) − mu| / (sigma + epsilon) (docs/method.md §2), in standard
/// deviations, >= 0: t* is the series' last timestamp, mu and sigma the mean and the sample
/// standard deviation (n − 1) of the points before t*. Fewer than 2 such points gives 0.
/// `epsilon` is in the modality's unit. Window the series before calling.
///
/// ```
/// use gleaner_utility::{anomaly, Series};
/// let (t, v) = (vec![0, 1, 2, 3], vec![1.0, 2.0, 3.0, 6.0]);
/// let a = anomaly(Series::new(&t, &v), 1e-6); // mu = 2, sigma = 1
/// assert!((a - 4.0 / (1.0 + 1e-6)).abs() < 1e-12);
/// ```
pub fn anomaly(series: Series<'_>, epsilon: f64) -> f64 {
    let n = series.len();
    if n < 3 {
        return 0.0;
    }
    let past = &series.values[..n - 1];
    let latest = series.values[n - 1];
    let k = past.len() as f64;
    let mu = past.iter().sum::<f64>() / k;
    let m2: f64 = past.iter().map(|x| (x - mu) * (x - mu)).sum();
    anomaly_from_stats(latest, mu, m2 / (k - 1.0), epsilon)
}

/// The residual of a cell series against its neighbours: at every timestamp of `own` where at
/// least `min_neighbours` of the `neighbours` series have a value (at that exact timestamp),
/// `own − median(neighbour values)`, in the modality's unit. Returns (times, residuals),
/// ascending. O(own × neighbours × log(neighbour length)).
///
/// ```
/// use gleaner_utility::{neighbour_residuals, Series};
/// let t = [0, 1, 2];
/// let own = Series::new(&t, &[5.0, 6.0, 9.0]);
/// let (a, b) = ([1.0, 2.0, 3.0], [3.0, 4.0, 5.0]);
/// let nbs = [Series::new(&t, &a), Series::new(&t[..2], &b[..2])];
/// let (times, r) = neighbour_residuals(own, &nbs, 1);
/// assert_eq!(times, vec![0, 1, 2]);
/// assert_eq!(r, vec![3.0, 3.0, 6.0]); // medians 2, 3, then 3 alone
/// ```
pub fn neighbour_residuals(
    own: Series<'_>,
    neighbours: &[Series<'_>],
    min_neighbours: usize,
) -> (Vec<UnixSeconds>, Vec<f64>) {
    let mut times = Vec::new();
    let mut residuals = Vec::new();
    let mut buf = Vec::with_capacity(neighbours.len());
    for (&t, &x) in own.times.iter().zip(own.values) {
        buf.clear();
        buf.extend(neighbours.iter().filter_map(|nb| nb.value_at(t)));
        if buf.is_empty() || buf.len() < min_neighbours.max(1) {
            continue;
        }
        buf.sort_by(f64::total_cmp);
        let median = median_of_sorted(&buf);
        times.push(t);
        residuals.push(x - median);
    }
    (times, residuals)
}

/// Neighbour-relative anomaly of one modality ([`crate::AnomalyReference::Neighbours`]), in
/// standard deviations of the residual, >= 0: [`anomaly`] of the series of
/// [`neighbour_residuals`], i.e. the latest residual against the mean and sample sd of the
/// earlier ones. Fewer than 3 residual points gives 0. Window the series before calling.
///
/// ```
/// use gleaner_utility::{neighbour_anomaly, Series};
/// let t: Vec<i64> = (0..6).collect();
/// // Weather moves both cells alike; on the last day the cell alone jumps by 0.1.
/// let w = [0.20, 0.30, 0.25, 0.35, 0.22, 0.30];
/// let own: Vec<f64> = w.iter().enumerate().map(|(k, x)| x + 0.01 * (k % 2) as f64).collect();
/// let mut own = own;
/// own[5] += 0.1;
/// let a = neighbour_anomaly(Series::new(&t, &own), &[Series::new(&t, &w)], 1, 1e-6);
/// assert!(a > 10.0);
/// ```
pub fn neighbour_anomaly(
    own: Series<'_>,
    neighbours: &[Series<'_>],
    min_neighbours: usize,
    epsilon: f64,
) -> f64 {
    let (times, residuals) = neighbour_residuals(own, neighbours, min_neighbours);
    anomaly(Series::new(&times, &residuals), epsilon)
}

/// A_i^m from the latest value, the past mean and the past sample variance (unit²).
pub(crate) fn anomaly_from_stats(latest: f64, mu: f64, variance: f64, epsilon: f64) -> f64 {
    (latest - mu).abs() / (variance.max(0.0).sqrt() + epsilon)
}

/// Model uncertainty U_i = −(1/ln K)·Σ_k p_k ln p_k, with 0·ln 0 = 0 (docs/method.md §2): the normalised
/// entropy of a class distribution, dimensionless in [0, 1]. Fewer than 2 classes gives 0.
/// The probabilities are assumed valid (see [`validate_probabilities`](crate::validate_probabilities)).
///
/// ```
/// use gleaner_utility::uncertainty;
/// assert!((uncertainty(&[0.25; 4]) - 1.0).abs() < 1e-12);
/// assert_eq!(uncertainty(&[0.0, 1.0, 0.0]), 0.0);
/// ```
pub fn uncertainty(probabilities: &[f64]) -> f64 {
    let k = probabilities.len();
    if k < 2 {
        return 0.0;
    }
    let h: f64 = probabilities
        .iter()
        .filter(|&&p| p > 0.0)
        .map(|&p| -p * p.ln())
        .sum();
    (h / (k as f64).ln()).clamp(0.0, 1.0)
}

/// The median of values sorted ascending (the mean of the two middle ones for an even count;
/// NaN for none), in their unit.
pub fn median_of_sorted(sorted: &[f64]) -> f64 {
    let n = sorted.len();
    match n {
        0 => f64::NAN,
        _ if n % 2 == 1 => sorted[n / 2],
        _ => 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]),
    }
}

/// The score S_i = alpha·F + beta·A + gamma·U − delta·R (docs/method.md §2) with the weights of
/// `config`; `a` is the anomaly in the form the configuration uses (raw or bounded).
///
/// ```
/// use gleaner_utility::{score, UtilityConfig};
/// let s = score(0.5, 1.0, 0.25, 0.75, &UtilityConfig::default());
/// assert!((s - 1.0).abs() < 1e-12);
/// ```
///
/// With [`crate::ScoreForm::Gated`]: S = alpha·F·max(0, 1 + beta·A + gamma·U − delta·R).
pub fn score(f: f64, a: f64, u: f64, r: f64, config: &UtilityConfig) -> f64 {
    match config.score_form {
        crate::ScoreForm::Additive => {
            config.alpha * f + config.beta * a + config.gamma * u - config.delta * r
        }
        crate::ScoreForm::Gated => {
            config.alpha
                * f
                * (1.0 + config.beta * a + config.gamma * u - config.delta * r).max(0.0)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_of_sorted_values() {
        assert!(median_of_sorted(&[]).is_nan());
        assert_eq!(median_of_sorted(&[2.0]), 2.0);
        assert_eq!(median_of_sorted(&[1.0, 2.0, 9.0]), 2.0);
        assert_eq!(median_of_sorted(&[1.0, 2.0, 4.0, 9.0]), 3.0);
    }
    use proptest::prelude::*;

    const DAY: i64 = 86_400;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-12 * b.abs().max(1.0)
    }

    /// Freshness of `last` (days before t, None = never) with a 3-day half-life.
    fn check_freshness(last_days_ago: &[Option<i64>], expected: f64) {
        let t = 100 * DAY;
        let last: Vec<Option<i64>> = last_days_ago
            .iter()
            .map(|d| d.map(|d| t - d * DAY))
            .collect();
        let f = freshness(t, &last, std::f64::consts::LN_2 / (3 * DAY) as f64);
        assert!(close(f, expected), "{last_days_ago:?}: {f} != {expected}");
    }

    #[test]
    fn freshness_by_hand() {
        check_freshness(&[Some(0)], 0.0);
        check_freshness(&[Some(3)], 0.5);
        check_freshness(&[Some(6)], 0.75);
        check_freshness(&[None], 1.0);
        check_freshness(&[Some(3), None], 0.75);
        check_freshness(&[Some(-2)], 0.0); // collected "after" t: age 0
        check_freshness(&[], 1.0);
    }

    fn check_correlation(
        a: (&[i64], &[f64]),
        b: (&[i64], &[f64]),
        min_overlap: usize,
        expected: f64,
    ) {
        let r = series_correlation(Series::new(a.0, a.1), Series::new(b.0, b.1), min_overlap);
        assert!(close(r, expected), "{r} != {expected}");
        let r2 = series_correlation(Series::new(b.0, b.1), Series::new(a.0, a.1), min_overlap);
        assert_eq!(r, r2, "not symmetric");
    }

    #[test]
    fn correlation_by_hand() {
        // x = 1,2,3 ; y = 2,4,7: sxy = 5, sxx = 2, syy = 12.667 -> 5/sqrt(25.333)
        let want = 5.0 / (2.0f64 * 38.0 / 3.0).sqrt();
        check_correlation(
            (&[0, 1, 2], &[1.0, 2.0, 3.0]),
            (&[0, 1, 2], &[2.0, 4.0, 7.0]),
            3,
            want,
        );
        // Same through gaps: only the common timestamps 0, 2, 4 count.
        check_correlation(
            (&[0, 1, 2, 4], &[1.0, 100.0, 2.0, 3.0]),
            (&[0, 2, 3, 4], &[2.0, 4.0, -50.0, 7.0]),
            3,
            want,
        );
        // Too few common points, constant series, perfect anti-correlation.
        check_correlation(
            (&[0, 1, 2], &[1.0, 2.0, 3.0]),
            (&[0, 1, 2], &[2.0, 4.0, 7.0]),
            4,
            0.0,
        );
        check_correlation(
            (&[0, 1, 2], &[0.1, 0.1, 0.1]),
            (&[0, 1, 2], &[2.0, 4.0, 7.0]),
            3,
            0.0,
        );
        check_correlation(
            (&[0, 1, 2], &[1.0, 2.0, 3.0]),
            (&[0, 1, 2], &[3.0, 2.0, 1.0]),
            3,
            -1.0,
        );
    }

    #[test]
    fn redundancy_by_hand() {
        let t: Vec<i64> = (0..10).collect();
        let x: Vec<f64> = (0..10).map(|k| (k * k) as f64).collect();
        let neg: Vec<f64> = x.iter().map(|v| -v).collect();
        let own = Series::new(&t, &x);
        // Identical (1), anti-correlated (clipped to 0), lacking the modality (0): 1/3.
        let r = redundancy(own, &[own, Series::new(&t, &neg), Series::empty()], 10);
        assert!(close(r, 1.0 / 3.0), "{r}");
        assert_eq!(redundancy(own, &[], 10), 0.0);
        // Only 9 common points: below min_overlap.
        assert_eq!(redundancy(own, &[Series::new(&t[1..], &x[1..])], 10), 0.0);
    }

    #[test]
    fn anomaly_by_hand() {
        let t = [0, 1, 2, 3];
        // Past 1, 2, 3: mean 2, sample std 1; latest 6 -> 4 / (1 + eps).
        assert!(close(
            anomaly(Series::new(&t, &[1.0, 2.0, 3.0, 6.0]), 1e-6),
            4.0 / (1.0 + 1e-6)
        ));
        // Past 2, 4 (two points): mean 3, std sqrt(2); latest 3 -> 0.
        assert_eq!(anomaly(Series::new(&t[..3], &[2.0, 4.0, 3.0]), 1e-6), 0.0);
        // One past point: 0.
        assert_eq!(anomaly(Series::new(&t[..2], &[2.0, 40.0]), 1e-6), 0.0);
        // Constant past: |x - mu| / epsilon.
        assert!(close(
            anomaly(Series::new(&t, &[1.0, 1.0, 1.0, 1.5]), 0.01),
            50.0
        ));
    }

    #[test]
    fn uncertainty_by_hand() {
        assert_eq!(uncertainty(&[1.0, 0.0, 0.0]), 0.0);
        assert!(close(uncertainty(&[1.0 / 3.0; 3]), 1.0));
        let p = [0.2, 0.5, 0.3];
        let h = -(0.2f64 * 0.2f64.ln() + 0.5 * 0.5f64.ln() + 0.3 * 0.3f64.ln()) / 3f64.ln();
        assert!(close(uncertainty(&p), h));
        assert!(close(uncertainty(&[0.5, 0.5, 0.0]), 2f64.ln() / 3f64.ln()));
        assert_eq!(uncertainty(&[1.0]), 0.0);
    }

    #[test]
    fn score_by_hand() {
        let c = UtilityConfig {
            alpha: 2.0,
            beta: 0.5,
            gamma: 3.0,
            delta: 4.0,
            ..UtilityConfig::default()
        };
        assert!(close(score(0.5, 2.0, 0.1, 0.25, &c), 1.0 + 1.0 + 0.3 - 1.0));
    }

    #[test]
    fn gated_score_by_hand() {
        let c = UtilityConfig {
            alpha: 2.0,
            beta: 0.5,
            gamma: 3.0,
            delta: 4.0,
            score_form: crate::ScoreForm::Gated,
            ..UtilityConfig::default()
        };
        // 2·0.5·(1 + 1 + 0.3 − 1) = 1.3
        assert!(close(score(0.5, 2.0, 0.1, 0.25, &c), 1.3));
        // A just-collected cell is worth nothing however anomalous.
        assert_eq!(score(0.0, 9.0, 1.0, 0.0, &c), 0.0);
        // Never negative: a fully redundant cell is worth 0.
        assert_eq!(score(1.0, 0.0, 0.0, 1.0, &c), 0.0);
    }

    fn series_strategy() -> impl Strategy<Value = (Vec<i64>, Vec<f64>)> {
        proptest::collection::btree_map(0i64..60, -100.0f64..100.0, 0..40)
            .prop_map(|m| m.into_iter().unzip())
    }

    proptest! {
        #[test]
        fn gated_score_is_non_negative_and_grows_with_staleness(
            f1 in 0.0f64..=1.0, df in 0.0f64..=1.0, a in 0.0f64..1.0, u in 0.0f64..=1.0,
            r in 0.0f64..=1.0,
        ) {
            let c = UtilityConfig { score_form: crate::ScoreForm::Gated, ..UtilityConfig::default() };
            let f2 = (f1 + df).min(1.0);
            let (s1, s2) = (score(f1, a, u, r, &c), score(f2, a, u, r, &c));
            prop_assert!(s1 >= 0.0 && s2 >= s1);
        }

        #[test]
        fn pearson_is_symmetric_and_bounded(
            pairs in proptest::collection::vec((-1e3f64..1e3, -1e3f64..1e3), 0..50)
        ) {
            let (x, y): (Vec<f64>, Vec<f64>) = pairs.into_iter().unzip();
            let a = pearson(&x, &y);
            prop_assert_eq!(a, pearson(&y, &x));
            if let Some(r) = a {
                prop_assert!((-1.0..=1.0).contains(&r));
            }
        }

        #[test]
        fn terms_stay_in_range(
            a in series_strategy(),
            nbs in proptest::collection::vec(series_strategy(), 0..4),
            ages in proptest::collection::vec(proptest::option::of(0i64..10_000_000), 1..5),
            raw_p in proptest::collection::vec(0.0f64..1.0, 2..6),
            min_overlap in 2usize..12,
        ) {
            let own = Series::new(&a.0, &a.1);
            let views: Vec<Series> = nbs.iter().map(|(t, v)| Series::new(t, v)).collect();
            let r = redundancy(own, &views, min_overlap);
            prop_assert!((0.0..=1.0).contains(&r));
            prop_assert!(anomaly(own, 1e-6) >= 0.0);
            let t = 10_000_000;
            let last: Vec<Option<i64>> = ages.iter().map(|a| a.map(|a| t - a)).collect();
            let f = freshness(t, &last, 1e-5);
            prop_assert!((0.0..=1.0).contains(&f));
            let total: f64 = raw_p.iter().sum();
            if total > 0.0 {
                let p: Vec<f64> = raw_p.iter().map(|x| x / total).collect();
                let u = uncertainty(&p);
                prop_assert!((0.0..=1.0).contains(&u));
            }
            for v in &views {
                let c = series_correlation(own, *v, min_overlap);
                prop_assert!((-1.0..=1.0).contains(&c));
                prop_assert_eq!(c, series_correlation(*v, own, min_overlap));
            }
        }

        #[test]
        fn uniform_is_one_and_one_hot_is_zero(k in 2usize..20, hot in 0usize..20) {
            prop_assert!((uncertainty(&vec![1.0 / k as f64; k]) - 1.0).abs() < 1e-12);
            let mut p = vec![0.0; k];
            p[hot % k] = 1.0;
            prop_assert_eq!(uncertainty(&p), 0.0);
        }
    }
}
