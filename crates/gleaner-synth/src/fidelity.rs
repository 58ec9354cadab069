//! Per-depth fidelity statistics: the shape of daily changes (zero-change days, percentiles,
//! excess kurtosis), how the correlation of daily changes falls with distance, the delayed
//! wetting front between 30 and 90 cm, the structure of gaps (per-sensor runs and network-wide
//! outages), stuck runs, and the seasonal mean and amplitude. Pure: values in, values out; the
//! same code summarises CAF and a synthetic farm.
//!
//! Every function takes plain `[sensor][day]` series (NaN = missing) so that it can be tested
//! on hand-made panels; [`fidelity_stats`] gathers them for a [`NetworkPanel`].

use gleaner_field::LocalPoint;

use crate::network::{NetworkPanel, monthly_cycle};

/// Distance bands of the change-correlation curve, metres `[from, to)`: under 100 m, 100-300,
/// 300-600 and 600-800 m (CAF's longest separations are about 950 m).
pub const DISTANCE_BANDS_M: [(f64, f64); 4] =
    [(0.0, 100.0), (100.0, 300.0), (300.0, 600.0), (600.0, 800.0)];

/// Two values closer than this are "the same reading" (zero change, stuck runs), in the
/// modality's unit: below every real sensor's resolution (CAF: 0.001 m³/m³, 0.01 °C).
const SAME: f64 = 1.0e-6;

/// A run of at least this many consecutive present days with the same value is a stuck run.
pub const STUCK_MIN_DAYS: usize = 7;

/// Window of the wetting-front statistic: changes over this many days, days.
pub const FRONT_WINDOW_DAYS: usize = 7;

/// Lags searched for the wetting front's peak, days (inclusive).
pub const FRONT_LAGS_DAYS: (usize, usize) = (20, 35);

/// Shape of the day-to-day changes of one modality, pooled over sensors (consecutive present
/// days only), in the modality's unit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChangeShape {
    /// Number of changes.
    pub count: usize,
    /// Fraction of changes that are zero (the same reading two days running).
    pub zero_share: f64,
    /// 5th percentile of the changes.
    pub p05: f64,
    /// 95th percentile of the changes.
    pub p95: f64,
    /// Excess kurtosis of the changes, `m4 / m2² - 3` (0 for a Gaussian; large when most days
    /// barely move and a few jump).
    pub excess_kurtosis: f64,
}

fn consecutive_changes(series: &[Vec<f64>]) -> Vec<f64> {
    series
        .iter()
        .flat_map(|s| {
            s.windows(2)
                .filter(|w| !w[0].is_nan() && !w[1].is_nan())
                .map(|w| w[1] - w[0])
        })
        .collect()
}

/// The `p` quantile of `sorted` (ascending) by linear interpolation; NaN when empty.
fn quantile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let x = p.clamp(0.0, 1.0) * (sorted.len() - 1) as f64;
    let (i, f) = (x.floor() as usize, x - x.floor());
    let j = (i + 1).min(sorted.len() - 1);
    sorted[i] + f * (sorted[j] - sorted[i])
}

/// [`ChangeShape`] of `series` (`[sensor][day]`, NaN = missing). All NaN when there is no change.
pub fn change_shape(series: &[Vec<f64>]) -> ChangeShape {
    let mut c = consecutive_changes(series);
    let n = c.len();
    if n == 0 {
        return ChangeShape {
            count: 0,
            zero_share: f64::NAN,
            p05: f64::NAN,
            p95: f64::NAN,
            excess_kurtosis: f64::NAN,
        };
    }
    let zero = c.iter().filter(|d| d.abs() < SAME).count();
    let m = c.iter().sum::<f64>() / n as f64;
    let (mut m2, mut m4) = (0.0, 0.0);
    for d in &c {
        let e = (d - m) * (d - m);
        m2 += e;
        m4 += e * e;
    }
    let (m2, m4) = (m2 / n as f64, m4 / n as f64);
    c.sort_by(f64::total_cmp);
    ChangeShape {
        count: n,
        zero_share: zero as f64 / n as f64,
        p05: quantile(&c, 0.05),
        p95: quantile(&c, 0.95),
        excess_kurtosis: if m2 > 0.0 {
            m4 / (m2 * m2) - 3.0
        } else {
            f64::NAN
        },
    }
}

fn pearson(xs: &[f64], ys: &[f64]) -> Option<f64> {
    if xs.len() < 3 {
        return None;
    }
    crate::calibration::pearson(xs, ys)
}

/// Mean correlation of same-day day-to-day changes over the station pairs in each band of
/// `bands` (metres, `[from, to)`), and the number of pairs; a pair counts with at least
/// `min_overlap` common changes. NaN for a band without pairs. Cost O(S² x D).
pub fn change_correlation_by_distance(
    positions: &[LocalPoint],
    series: &[Vec<f64>],
    bands: &[(f64, f64)],
    min_overlap: usize,
) -> Vec<(f64, usize)> {
    let mut sums = vec![(0.0, 0usize); bands.len()];
    let (mut xs, mut ys) = (Vec::new(), Vec::new());
    for i in 0..series.len().min(positions.len()) {
        for j in i + 1..series.len().min(positions.len()) {
            let d = positions[i].distance(&positions[j]);
            let Some(b) = bands.iter().position(|&(lo, hi)| d >= lo && d < hi) else {
                continue;
            };
            let (a, c) = (&series[i], &series[j]);
            xs.clear();
            ys.clear();
            for t in 1..a.len().min(c.len()) {
                let (da, dc) = (a[t] - a[t - 1], c[t] - c[t - 1]);
                if !da.is_nan() && !dc.is_nan() {
                    xs.push(da);
                    ys.push(dc);
                }
            }
            if xs.len() >= min_overlap.max(3)
                && let Some(r) = pearson(&xs, &ys)
            {
                sums[b].0 += r;
                sums[b].1 += 1;
            }
        }
    }
    sums.iter()
        .map(|&(s, n)| (if n > 0 { s / n as f64 } else { f64::NAN }, n))
        .collect()
}

/// Pooled correlation, at each lag `0..=max_lag` days, of the shallow layer's `window`-day
/// change starting on day `t` and the deep layer's `window`-day change starting on day `t +
/// lag`, same station (NaN where fewer than 30 pairs). A wetting front that reaches the deep
/// layer `L` days after the shallow one shows as a peak near lag `L`.
pub fn lagged_window_change_correlation(
    shallow: &[Vec<f64>],
    deep: &[Vec<f64>],
    window: usize,
    max_lag: usize,
) -> Vec<f64> {
    let diff = |s: &Vec<f64>| -> Vec<f64> {
        (0..s.len().saturating_sub(window))
            .map(|t| s[t + window] - s[t])
            .collect()
    };
    let a: Vec<Vec<f64>> = shallow.iter().map(diff).collect();
    let b: Vec<Vec<f64>> = deep.iter().map(diff).collect();
    let (mut xs, mut ys) = (Vec::new(), Vec::new());
    (0..=max_lag)
        .map(|lag| {
            xs.clear();
            ys.clear();
            for (x, y) in a.iter().zip(&b) {
                for t in 0..x.len().min(y.len().saturating_sub(lag)) {
                    let (u, v) = (x[t], y[t + lag]);
                    if !u.is_nan() && !v.is_nan() {
                        xs.push(u);
                        ys.push(v);
                    }
                }
            }
            if xs.len() >= 30 {
                pearson(&xs, &ys).unwrap_or(f64::NAN)
            } else {
                f64::NAN
            }
        })
        .collect()
}

/// The lag in `lo..=hi` with the largest finite entry of `curve`, and that entry ((lo, NaN)
/// when none is finite).
pub fn peak_in(curve: &[f64], lo: usize, hi: usize) -> (usize, f64) {
    let mut best = (lo, f64::NAN);
    for (lag, &r) in curve.iter().enumerate().take(hi + 1).skip(lo) {
        if r.is_finite() && (best.1.is_nan() || r > best.1) {
            best = (lag, r);
        }
    }
    best
}

/// Gaps of one modality: maximal runs of missing days inside each sensor's reporting span
/// (between its first and last present day; a sensor never present has no gap).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GapShape {
    /// Number of gaps.
    pub count: usize,
    /// Gaps per sensor-year of reporting span (365.25 days).
    pub per_sensor_year: f64,
    /// Median gap length, days.
    pub median_days: f64,
    /// Mean gap length, days.
    pub mean_days: f64,
    /// 90th percentile of gap length, days.
    pub p90_days: f64,
}

/// [`GapShape`] of `series` (`[sensor][day]`, NaN = missing).
pub fn gap_shape(series: &[Vec<f64>]) -> GapShape {
    let mut lengths = Vec::new();
    let mut span_days = 0usize;
    for s in series {
        let (Some(first), Some(last)) = (
            s.iter().position(|v| !v.is_nan()),
            s.iter().rposition(|v| !v.is_nan()),
        ) else {
            continue;
        };
        span_days += last - first + 1;
        let mut run = 0usize;
        for v in &s[first..=last] {
            if v.is_nan() {
                run += 1;
            } else if run > 0 {
                lengths.push(run as f64);
                run = 0;
            }
        }
    }
    let count = lengths.len();
    lengths.sort_by(f64::total_cmp);
    GapShape {
        count,
        per_sensor_year: if span_days > 0 {
            count as f64 / (span_days as f64 / 365.25)
        } else {
            f64::NAN
        },
        median_days: quantile(&lengths, 0.5),
        mean_days: if count > 0 {
            lengths.iter().sum::<f64>() / count as f64
        } else {
            f64::NAN
        },
        p90_days: quantile(&lengths, 0.9),
    }
}

/// Days on which more than half of the stations are down (every modality of `modalities`
/// missing), each modality `[sensor][day]` of the same shape.
pub fn network_down_days(modalities: &[&[Vec<f64>]]) -> usize {
    let Some(first) = modalities.first() else {
        return 0;
    };
    let sensors = first.len();
    let days = first.iter().map(Vec::len).max().unwrap_or(0);
    (0..days)
        .filter(|&d| {
            let down = (0..sensors)
                .filter(|&s| {
                    modalities
                        .iter()
                        .all(|m| m[s].get(d).is_none_or(|v| v.is_nan()))
                })
                .count();
            2 * down > sensors
        })
        .count()
}

/// Fraction of present values that lie in a run of at least `min_days` consecutive present
/// days with the same value (a sensor repeating itself); NaN without values.
pub fn stuck_share(series: &[Vec<f64>], min_days: usize) -> f64 {
    let (mut stuck, mut present) = (0usize, 0usize);
    for s in series {
        let mut run = 0usize;
        let mut last = f64::NAN;
        let mut close = |run: usize| {
            if run >= min_days {
                stuck += run;
            }
        };
        for &v in s {
            if v.is_nan() {
                close(run);
                run = 0;
                last = f64::NAN;
                continue;
            }
            present += 1;
            if !last.is_nan() && (v - last).abs() < SAME {
                run += 1;
            } else {
                close(run);
                run = 1;
            }
            last = v;
        }
        close(run);
    }
    if present > 0 {
        stuck as f64 / present as f64
    } else {
        f64::NAN
    }
}

/// Mean of all present values and the seasonal amplitude: the peak-to-trough range of the
/// station-demeaned monthly cycle ([`monthly_cycle`]), in the modality's unit.
pub fn mean_and_amplitude(series: &[Vec<f64>], first_day: i64) -> (f64, f64) {
    let (mut sum, mut n) = (0.0, 0usize);
    for v in series.iter().flatten().filter(|v| !v.is_nan()) {
        sum += v;
        n += 1;
    }
    let cycle = monthly_cycle(series, first_day);
    let finite: Vec<f64> = cycle.iter().copied().filter(|v| v.is_finite()).collect();
    let amp = if finite.len() >= 2 {
        finite.iter().copied().fold(f64::NEG_INFINITY, f64::max)
            - finite.iter().copied().fold(f64::INFINITY, f64::min)
    } else {
        f64::NAN
    };
    (if n > 0 { sum / n as f64 } else { f64::NAN }, amp)
}

/// The fidelity statistics of one modality.
#[derive(Debug, Clone, PartialEq)]
pub struct DepthFidelity {
    /// Modality name, e.g. `vw@90cm`.
    pub name: String,
    /// True for volumetric water content (m³/m³), false for temperature (°C).
    pub is_water: bool,
    /// Mean of present values.
    pub mean: f64,
    /// Peak-to-trough range of the station-demeaned monthly cycle.
    pub amplitude: f64,
    /// Shape of the daily changes.
    pub changes: ChangeShape,
    /// Mean correlation of daily changes per [`DISTANCE_BANDS_M`] band, with its pair count.
    pub change_corr_by_band: Vec<(f64, usize)>,
    /// Gaps of this modality (on the unmasked panel).
    pub gaps: GapShape,
    /// [`stuck_share`] with [`STUCK_MIN_DAYS`].
    pub stuck_share: f64,
}

/// Network-wide fidelity statistics and one [`DepthFidelity`] per modality.
#[derive(Debug, Clone, PartialEq)]
pub struct FidelityStats {
    /// Per modality, in the panel's order.
    pub per_depth: Vec<DepthFidelity>,
    /// Correlation of 7-day changes, VW 30 cm against VW 90 cm starting `lag` days later, for
    /// lags 0..=60 days (empty without both modalities).
    pub front_curve: Vec<f64>,
    /// Lag in [`FRONT_LAGS_DAYS`] with the highest correlation in `front_curve`, days.
    pub front_lag_days: usize,
    /// That correlation.
    pub front_corr: f64,
    /// Days with more than half the stations down (every modality missing).
    pub network_down_days: usize,
    /// Number of days in the panel.
    pub days: usize,
}

impl FidelityStats {
    /// The statistics of modality `name`, if present.
    pub fn depth(&self, name: &str) -> Option<&DepthFidelity> {
        self.per_depth.iter().find(|d| d.name == name)
    }
}

/// Computes [`FidelityStats`] of `panel`. Gaps and outages use every value; the other
/// statistics leave out station-days marked in [`NetworkPanel::event_days`] (known events).
pub fn fidelity_stats(panel: &NetworkPanel) -> FidelityStats {
    let all: Vec<&[Vec<f64>]> = panel
        .modalities
        .iter()
        .map(|m| m.series.as_slice())
        .collect();
    let down = network_down_days(&all);
    let days = panel
        .modalities
        .first()
        .map_or(0, |m| m.series.iter().map(Vec::len).max().unwrap_or(0));
    let masked = panel.without_event_days();
    let per_depth = panel
        .modalities
        .iter()
        .zip(&masked.modalities)
        .map(|(raw, m)| {
            let (mean, amplitude) = mean_and_amplitude(&m.series, panel.first_day);
            DepthFidelity {
                name: m.name.clone(),
                is_water: m.is_water,
                mean,
                amplitude,
                changes: change_shape(&m.series),
                change_corr_by_band: change_correlation_by_distance(
                    &panel.positions,
                    &m.series,
                    &DISTANCE_BANDS_M,
                    30,
                ),
                gaps: gap_shape(&raw.series),
                stuck_share: stuck_share(&m.series, STUCK_MIN_DAYS),
            }
        })
        .collect();
    let (front_curve, front_lag_days, front_corr) =
        match (masked.modality("vw@30cm"), masked.modality("vw@90cm")) {
            (Some(a), Some(b)) => {
                let curve =
                    lagged_window_change_correlation(&a.series, &b.series, FRONT_WINDOW_DAYS, 60);
                let (lag, r) = peak_in(&curve, FRONT_LAGS_DAYS.0, FRONT_LAGS_DAYS.1);
                (curve, lag, r)
            }
            _ => (Vec::new(), 0, f64::NAN),
        };
    FidelityStats {
        per_depth,
        front_curve,
        front_lag_days,
        front_corr,
        network_down_days: down,
        days,
    }
}

/// One statistic of a synthetic farm checked against CAF's: the band it must fall in.
#[derive(Debug, Clone, PartialEq)]
pub struct FidelityCheck {
    /// Modality (`vw@90cm`) or `network`.
    pub modality: String,
    /// What is compared, e.g. `zero-change days`.
    pub statistic: &'static str,
    /// CAF's value.
    pub caf: f64,
    /// The synthetic farm's value.
    pub synth: f64,
    /// Lowest accepted value.
    pub lo: f64,
    /// Highest accepted value.
    pub hi: f64,
}

impl FidelityCheck {
    /// True when the synthetic value is finite and inside `[lo, hi]` (a margin of 1e-6, far
    /// below any resolution step, since quantised statistics sit on the band's edges).
    pub fn passes(&self) -> bool {
        self.synth.is_finite() && self.synth >= self.lo - 1e-6 && self.synth <= self.hi + 1e-6
    }
}

/// The tolerance bands of `docs/synth-calibration.md`, built around CAF's values (`caf`) and
/// applied to a synthetic farm's (`synth`), for every modality both have. Bands (their
/// justification, CAF's own spread between single years 2011, 2012 and 2013, is in the doc):
///
/// - mean: CAF's ± 0.04 m³/m³ (± 1 °C);
/// - seasonal amplitude: 0.65-1.35 x CAF's;
/// - zero-change days: CAF's ± 0.15 (VW only; temperature is smoother than its resolution);
/// - 5th / 95th percentile of daily change: CAF's ± max(50 %, 0.002 m³/m³) (VW), ± 50 % (T);
/// - excess kurtosis of daily change: CAF's / 10 .. CAF's x 10 (VW), at most 150 (T);
/// - correlation of daily changes per distance band: CAF's ± 0.12 (VW), ± 0.25 (T);
/// - gaps per station-year, median and mean gap length: 0.5-2 x CAF's;
/// - stuck runs (>= 7 days repeating): 0.4-2.5 x CAF's (VW), at most 0.15 (T);
/// - network: days with more than half the stations down 0.25-2 x CAF's; the 30/90 cm
///   7-day-change correlation peaks in 20-35 days at 0.1-0.45.
pub fn fidelity_checks(caf: &FidelityStats, synth: &FidelityStats) -> Vec<FidelityCheck> {
    let mut out = Vec::new();
    let mut push = |modality: &str, statistic, caf: f64, synth: f64, (lo, hi): (f64, f64)| {
        out.push(FidelityCheck {
            modality: modality.to_string(),
            statistic,
            caf,
            synth,
            lo,
            hi,
        });
    };
    let ratio = |c: f64, a: f64, b: f64| (a * c, b * c);
    for c in &caf.per_depth {
        let Some(s) = synth.depth(&c.name) else {
            continue;
        };
        let m = c.name.as_str();
        let w = c.is_water;
        let mean_tol = if w { 0.04 } else { 1.0 };
        push(
            m,
            "mean",
            c.mean,
            s.mean,
            (c.mean - mean_tol, c.mean + mean_tol),
        );
        push(
            m,
            "seasonal amplitude",
            c.amplitude,
            s.amplitude,
            ratio(c.amplitude, 0.65, 1.35),
        );
        if w {
            let z = c.changes.zero_share;
            push(
                m,
                "zero-change days",
                z,
                s.changes.zero_share,
                (z - 0.15, z + 0.15),
            );
        }
        for (statistic, cv, sv) in [
            ("daily change p05", c.changes.p05, s.changes.p05),
            ("daily change p95", c.changes.p95, s.changes.p95),
        ] {
            let tol = if w {
                (0.5 * cv.abs()).max(0.002)
            } else {
                0.5 * cv.abs()
            };
            push(m, statistic, cv, sv, (cv - tol, cv + tol));
        }
        let k = c.changes.excess_kurtosis;
        let kb = if w {
            (k / 10.0, k * 10.0)
        } else {
            (-1.5, 150.0)
        };
        push(m, "excess kurtosis", k, s.changes.excess_kurtosis, kb);
        let tol = if w { 0.12 } else { 0.25 };
        for (b, name) in [
            "change corr. < 100 m",
            "change corr. 100-300 m",
            "change corr. 300-600 m",
            "change corr. 600-800 m",
        ]
        .into_iter()
        .enumerate()
        {
            let (Some(&(cr, _)), Some(&(sr, _))) =
                (c.change_corr_by_band.get(b), s.change_corr_by_band.get(b))
            else {
                continue;
            };
            push(m, name, cr, sr, (cr - tol, cr + tol));
        }
        push(
            m,
            "gaps per station-year",
            c.gaps.per_sensor_year,
            s.gaps.per_sensor_year,
            ratio(c.gaps.per_sensor_year, 0.5, 2.0),
        );
        push(
            m,
            "median gap, days",
            c.gaps.median_days,
            s.gaps.median_days,
            ratio(c.gaps.median_days, 0.5, 2.0),
        );
        push(
            m,
            "mean gap, days",
            c.gaps.mean_days,
            s.gaps.mean_days,
            ratio(c.gaps.mean_days, 0.5, 2.0),
        );
        let sb = if w {
            ratio(c.stuck_share, 0.4, 2.5)
        } else {
            (0.0, 0.15)
        };
        push(
            m,
            "stuck runs (>= 7 days)",
            c.stuck_share,
            s.stuck_share,
            sb,
        );
    }
    let d = caf.network_down_days as f64 * synth.days.max(1) as f64 / caf.days.max(1) as f64;
    push(
        "network",
        "days with > half the stations down",
        caf.network_down_days as f64,
        synth.network_down_days as f64,
        ratio(d, 0.25, 2.0),
    );
    if !caf.front_curve.is_empty() {
        push(
            "network",
            "30/90 cm 7-day change corr., peak in 20-35 days",
            caf.front_corr,
            synth.front_corr,
            (0.1, 0.45),
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const NAN: f64 = f64::NAN;

    #[test]
    fn change_shape_counts_zero_days_and_tails() {
        // Changes: 0, 0, 0, +0.01 (sensor 1); 0, -0.01 (sensor 2; the gap breaks a pair).
        let s = vec![
            vec![0.2, 0.2, 0.2, 0.2, 0.21],
            vec![0.3, 0.3, NAN, 0.3, 0.29],
        ];
        let c = change_shape(&s);
        assert_eq!(c.count, 6);
        assert!((c.zero_share - 4.0 / 6.0).abs() < 1e-12);
        assert!(c.p05 < 0.0 && c.p95 > 0.0);
        // A Gaussian-like sample has excess kurtosis near 0; one huge jump among many small
        // changes makes it large.
        let mut spiky = vec![0.0; 200];
        for (t, v) in spiky.iter_mut().enumerate() {
            *v = 0.001 * ((t % 3) as f64);
        }
        spiky[100] += 0.5;
        assert!(change_shape(&[spiky]).excess_kurtosis > 20.0);
        assert!(change_shape(&[vec![NAN, 1.0]]).zero_share.is_nan());
    }

    #[test]
    fn change_correlation_falls_into_bands() {
        let a: Vec<f64> = (0..60).map(|t| ((t * 7) % 11) as f64).collect();
        let b: Vec<f64> = a.iter().map(|v| 2.0 * v + 1.0).collect();
        let c: Vec<f64> = a.iter().map(|v| -v).collect();
        let p = [
            LocalPoint::new(0.0, 0.0),
            LocalPoint::new(50.0, 0.0),
            LocalPoint::new(0.0, 700.0),
        ];
        let r = change_correlation_by_distance(&p, &[a, b, c], &DISTANCE_BANDS_M, 30);
        assert!((r[0].0 - 1.0).abs() < 1e-12 && r[0].1 == 1);
        assert!(r[1].0.is_nan() && r[2].0.is_nan());
        // Pairs (0, 2) at 700 m and (1, 2) at 701.8 m: both perfectly anti-correlated.
        assert_eq!(r[3].1, 2);
        assert!((r[3].0 + 1.0).abs() < 1e-12);
    }

    #[test]
    fn wetting_front_peak_is_found_at_its_delay() {
        // The deep series is the shallow one 27 days later, damped: the peak is at lag 27.
        let shallow: Vec<f64> = (0..400)
            .map(|t| (((t * 37) % 101) as f64 / 101.0).powi(3))
            .collect();
        let deep: Vec<f64> = (0..400)
            .map(|t| if t >= 27 { 0.3 * shallow[t - 27] } else { 0.0 })
            .collect();
        let curve = lagged_window_change_correlation(&[shallow], &[deep], 7, 40);
        let (lag, r) = peak_in(&curve, 20, 35);
        assert_eq!(lag, 27);
        assert!(r > 0.99, "{r}");
    }

    #[test]
    fn gaps_outages_and_stuck_runs() {
        // Sensor 1: gaps of 2 and 1 days inside its span (leading NaN not a gap).
        let s = vec![
            vec![NAN, 1.0, NAN, NAN, 2.0, NAN, 3.0],
            vec![1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0],
            vec![NAN; 7],
        ];
        let g = gap_shape(&s);
        assert_eq!(g.count, 2);
        assert!((g.median_days - 1.5).abs() < 1e-12);
        assert!((g.mean_days - 1.5).abs() < 1e-12);
        // Days 0, 2, 3, 5: sensors 1 and 3 down (2 of 3, more than half).
        assert_eq!(network_down_days(&[&s]), 4);
        // Sensor 2 repeats itself for 7 days: 7 of 10 present values.
        assert!((stuck_share(&s, 7) - 0.7).abs() < 1e-12);
        assert_eq!(stuck_share(&s, 8), 0.0);
    }

    #[test]
    fn amplitude_is_peak_to_trough_of_the_monthly_cycle() {
        let first = gleaner_field::time::days_from_civil(2014, 1, 1).unwrap();
        let s: Vec<f64> = (0..59).map(|d| if d < 31 { 0.2 } else { 0.3 }).collect();
        let (mean, amp) = mean_and_amplitude(&[s], first);
        assert!((mean - (0.2 * 31.0 + 0.3 * 28.0) / 59.0).abs() < 1e-12);
        assert!((amp - 0.1).abs() < 1e-12);
    }
}
