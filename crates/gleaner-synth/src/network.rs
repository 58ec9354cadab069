//! Whole-network calibration statistics: seasons, rain seasonality, drainage, depth lag,
//! synchrony, faults, frost and the own-history z-score's false alarms, computed by the same
//! code on CAF and on a synthetic farm (pure: values in, values out).
//!
//! A [`NetworkPanel`] holds several modalities of one sensor network on a shared daily grid;
//! [`network_stats`] summarises it as a [`NetworkStats`]. Every statistic is also a small
//! public function on plain series so that it can be tested on hand-made panels.

use gleaner_field::LocalPoint;
use gleaner_field::time::civil_from_days;

use crate::SynthFarm;
use crate::calibration::{DailyPanel, StatsOptions, panel_stats};
use crate::detection::{median, own_history_z};

/// One modality of a [`NetworkPanel`].
#[derive(Debug, Clone, PartialEq)]
pub struct PanelModality {
    /// Name, e.g. `vw@30cm` or `t@30cm`.
    pub name: String,
    /// True for volumetric water content (m³/m³), false for soil temperature (°C).
    pub is_water: bool,
    /// Depth below the surface, centimetres.
    pub depth_cm: u32,
    /// Per sensor, one value per day (index 0 = [`NetworkPanel::first_day`]); NaN = missing.
    pub series: Vec<Vec<f64>>,
}

/// Several modalities of a sensor network on a shared daily grid.
#[derive(Debug, Clone, PartialEq)]
pub struct NetworkPanel {
    /// Sensor positions in any metric frame, metres.
    pub positions: Vec<LocalPoint>,
    /// Day of index 0 of every series, days since 1970-01-01 (UTC).
    pub first_day: i64,
    /// The modalities, each with one series per sensor.
    pub modalities: Vec<PanelModality>,
    /// Optional mask of station-days touched by a known event, `[sensor][day]` (true =
    /// touched); such days are left out of [`NetworkStats::z_false_alarm_fraction`]. Empty
    /// when there is no ground truth (real data).
    pub event_days: Vec<Vec<bool>>,
}

impl NetworkPanel {
    /// The modality called `name`, if any.
    pub fn modality(&self, name: &str) -> Option<&PanelModality> {
        self.modalities.iter().find(|m| m.name == name)
    }

    /// One modality as a [`DailyPanel`] (for [`panel_stats`]).
    pub fn daily(&self, name: &str) -> Option<DailyPanel> {
        self.modality(name).map(|m| DailyPanel {
            positions: self.positions.clone(),
            series: m.series.clone(),
        })
    }

    /// The panel with every value on a station-day marked in [`Self::event_days`] set to NaN
    /// (and no mask left).
    pub fn without_event_days(&self) -> NetworkPanel {
        let mut out = self.clone();
        out.event_days.clear();
        for m in &mut out.modalities {
            for (s, series) in m.series.iter_mut().enumerate() {
                let Some(mask) = self.event_days.get(s) else {
                    continue;
                };
                for (v, &skip) in series.iter_mut().zip(mask) {
                    if skip {
                        *v = f64::NAN;
                    }
                }
            }
        }
        out
    }

    /// Keeps days `from..to` (indices into the series; clamped), shifting `first_day`.
    pub fn slice_days(&self, from: usize, to: usize) -> NetworkPanel {
        let cut = |s: &Vec<f64>| s[from.min(s.len())..to.min(s.len())].to_vec();
        let cut_b = |s: &Vec<bool>| s[from.min(s.len())..to.min(s.len())].to_vec();
        NetworkPanel {
            positions: self.positions.clone(),
            first_day: self.first_day + from as i64,
            modalities: self
                .modalities
                .iter()
                .map(|m| PanelModality {
                    series: m.series.iter().map(cut).collect(),
                    ..m.clone()
                })
                .collect(),
            event_days: self.event_days.iter().map(cut_b).collect(),
        }
    }
}

/// Month (1..=12) of a day count since 1970-01-01.
pub fn month_of_day(day: i64) -> u32 {
    civil_from_days(day).1
}

/// Meteorological season of a month: 0 winter (Dec-Feb), 1 spring, 2 summer (Jun-Aug), 3 autumn.
fn season_of_month(month: u32) -> usize {
    ((month % 12) / 3) as usize
}

fn mean_of(xs: impl Iterator<Item = f64>) -> f64 {
    let (mut s, mut n) = (0.0, 0usize);
    for x in xs {
        s += x;
        n += 1;
    }
    if n == 0 { f64::NAN } else { s / n as f64 }
}

fn pearson(pairs: &[(f64, f64)]) -> Option<f64> {
    if pairs.len() < 3 {
        return None;
    }
    let n = pairs.len() as f64;
    let mx = pairs.iter().map(|p| p.0).sum::<f64>() / n;
    let my = pairs.iter().map(|p| p.1).sum::<f64>() / n;
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for &(x, y) in pairs {
        sxy += (x - mx) * (y - my);
        sxx += (x - mx) * (x - mx);
        syy += (y - my) * (y - my);
    }
    (sxx > 0.0 && syy > 0.0).then(|| sxy / (sxx * syy).sqrt())
}

/// Mean over sensors of each sensor's station-demeaned values per calendar month (index 0 =
/// January), in the modality's unit: the seasonal cycle, free of which stations happen to
/// report. NaN for a month without data. Sensors with fewer than 30 present days are skipped.
pub fn monthly_cycle(series: &[Vec<f64>], first_day: i64) -> [f64; 12] {
    let mut sum = [0.0; 12];
    let mut n = [0usize; 12];
    for s in series {
        let present: Vec<f64> = s.iter().copied().filter(|v| !v.is_nan()).collect();
        if present.len() < 30 {
            continue;
        }
        let m = present.iter().sum::<f64>() / present.len() as f64;
        for (d, &v) in s.iter().enumerate() {
            if !v.is_nan() {
                let k = month_of_day(first_day + d as i64) as usize - 1;
                sum[k] += v - m;
                n[k] += 1;
            }
        }
    }
    std::array::from_fn(|k| {
        if n[k] > 0 {
            sum[k] / n[k] as f64
        } else {
            f64::NAN
        }
    })
}

/// Index (0 = January) of the largest and the smallest finite entry of a monthly cycle.
pub fn extreme_months(cycle: &[f64; 12]) -> (usize, usize) {
    let finite = || (0..12).filter(|&k| cycle[k].is_finite());
    let wet = finite()
        .max_by(|&a, &b| cycle[a].total_cmp(&cycle[b]))
        .unwrap_or(0);
    let dry = finite()
        .min_by(|&a, &b| cycle[a].total_cmp(&cycle[b]))
        .unwrap_or(0);
    (wet, dry)
}

/// Fraction of day-to-day rises above `threshold` (consecutive present days) per
/// meteorological season `[winter, spring, summer, autumn]`, by the month of the later day.
pub fn seasonal_rise_fractions(series: &[Vec<f64>], first_day: i64, threshold: f64) -> [f64; 4] {
    let mut rises = [0usize; 4];
    let mut pairs = [0usize; 4];
    for s in series {
        for d in 1..s.len() {
            if s[d].is_nan() || s[d - 1].is_nan() {
                continue;
            }
            let k = season_of_month(month_of_day(first_day + d as i64));
            pairs[k] += 1;
            if s[d] - s[d - 1] > threshold {
                rises[k] += 1;
            }
        }
    }
    std::array::from_fn(|k| {
        if pairs[k] > 0 {
            rises[k] as f64 / pairs[k] as f64
        } else {
            f64::NAN
        }
    })
}

/// Drainage: for every rise above `threshold` from day `d - 1` to day `d` (both present and
/// day `d + after` present), the share of the rise still there `after` days later,
/// `(x[d + after] - x[d - 1]) / (x[d] - x[d - 1])`; returns the median over rises and their
/// number (NaN, 0 when there is none).
pub fn drainage_retention(series: &[Vec<f64>], threshold: f64, after: usize) -> (f64, usize) {
    let mut shares = Vec::new();
    for s in series {
        for d in 1..s.len().saturating_sub(after) {
            let (a, b, c) = (s[d - 1], s[d], s[d + after]);
            if a.is_nan() || b.is_nan() || c.is_nan() || b - a <= threshold {
                continue;
            }
            shares.push((c - a) / (b - a));
        }
    }
    (median(&mut shares), shares.len())
}

/// Lag (days, `0..=max_lag`) at which the deep series best follows the shallow one: the lag
/// maximising the pooled Pearson correlation of station-demeaned pairs `(shallow[t], deep[t +
/// lag])` over all sensors. Returns the lag and its correlation (0, NaN without data).
pub fn depth_lag(shallow: &[Vec<f64>], deep: &[Vec<f64>], max_lag: usize) -> (usize, f64) {
    let demean = |s: &Vec<f64>| {
        let m = mean_of(s.iter().copied().filter(|v| !v.is_nan()));
        s.iter().map(|v| v - m).collect::<Vec<f64>>()
    };
    let a: Vec<Vec<f64>> = shallow.iter().map(demean).collect();
    let b: Vec<Vec<f64>> = deep.iter().map(demean).collect();
    let mut best = (0, f64::NAN);
    let mut pairs = Vec::new();
    for lag in 0..=max_lag {
        pairs.clear();
        for (x, y) in a.iter().zip(&b) {
            for t in 0..x.len().min(y.len().saturating_sub(lag)) {
                let (u, v) = (x[t], y[t + lag]);
                if !u.is_nan() && !v.is_nan() {
                    pairs.push((u, v));
                }
            }
        }
        if let Some(r) = pearson(&pairs)
            && (best.1.is_nan() || r > best.1)
        {
            best = (lag, r);
        }
    }
    best
}

/// Mean over sensors of the Pearson correlation of two modalities' same-day day-to-day
/// changes (sensors with fewer than 30 such days are skipped; NaN if none qualifies).
pub fn change_correlation(a: &[Vec<f64>], b: &[Vec<f64>]) -> f64 {
    let mut rs = Vec::new();
    for (x, y) in a.iter().zip(b) {
        let pairs: Vec<(f64, f64)> = (1..x.len().min(y.len()))
            .filter_map(|t| {
                let (dx, dy) = (x[t] - x[t - 1], y[t] - y[t - 1]);
                (!dx.is_nan() && !dy.is_nan()).then_some((dx, dy))
            })
            .collect();
        if pairs.len() >= 30
            && let Some(r) = pearson(&pairs)
        {
            rs.push(r);
        }
    }
    mean_of(rs.into_iter())
}

/// Mean over sensors of the lag-`lag` autocorrelation of each series (pairs of present days
/// `lag` apart; sensors with fewer than 30 pairs are skipped; NaN if none qualifies).
pub fn autocorrelation(series: &[Vec<f64>], lag: usize) -> f64 {
    let mut rs = Vec::new();
    for s in series {
        let pairs: Vec<(f64, f64)> = (lag..s.len())
            .filter_map(|t| (!s[t].is_nan() && !s[t - lag].is_nan()).then_some((s[t - lag], s[t])))
            .collect();
        if pairs.len() >= 30
            && let Some(r) = pearson(&pairs)
        {
            rs.push(r);
        }
    }
    mean_of(rs.into_iter())
}

/// Missing data over `modalities` (each `[sensor][day]`, same shape): the fraction of missing
/// values, and among station-days with at least one modality missing, the fraction where
/// some but not all are missing (a gap that hits single depths rather than the station).
pub fn missing_structure(modalities: &[&[Vec<f64>]]) -> (f64, f64) {
    let (mut missing, mut total, mut gap_days, mut partial) = (0usize, 0usize, 0usize, 0usize);
    let Some(first) = modalities.first() else {
        return (f64::NAN, f64::NAN);
    };
    for s in 0..first.len() {
        for d in 0..first[s].len() {
            let absent = modalities
                .iter()
                .filter(|m| m[s].get(d).is_none_or(|v| v.is_nan()))
                .count();
            missing += absent;
            total += modalities.len();
            if absent > 0 {
                gap_days += 1;
                if absent < modalities.len() {
                    partial += 1;
                }
            }
        }
    }
    let frac = |a: usize, b: usize| if b > 0 { a as f64 / b as f64 } else { f64::NAN };
    (frac(missing, total), frac(partial, gap_days))
}

/// Fraction of station-days with an own-history z-score (docs/method.md §2's anomaly on a one-sensor
/// cell: the day's value against the mean and sd of all the sensor's earlier values) above
/// `threshold` in magnitude, over station-days with at least `min_history` earlier values and
/// not masked by `skip[sensor][day]` (an empty `skip` masks nothing).
pub fn z_exceedance_fraction(
    series: &[Vec<f64>],
    skip: &[Vec<bool>],
    threshold: f64,
    min_history: usize,
) -> f64 {
    let (mut hit, mut n) = (0usize, 0usize);
    for (s, x) in series.iter().enumerate() {
        let z = own_history_z(x, min_history);
        for (d, zd) in z.iter().enumerate() {
            if zd.is_nan() || skip.get(s).and_then(|m| m.get(d)).copied().unwrap_or(false) {
                continue;
            }
            n += 1;
            if zd.abs() > threshold {
                hit += 1;
            }
        }
    }
    if n > 0 {
        hit as f64 / n as f64
    } else {
        f64::NAN
    }
}

/// Every calibration statistic of one network. Water statistics are for the shallowest and
/// deepest water depths present among 30 cm and 90 cm; NaN when a modality is missing.
#[derive(Debug, Clone, PartialEq)]
pub struct NetworkStats {
    /// Per modality: name and [`panel_stats`]-style summary values (see [`ModalityStats`]).
    pub per_modality: Vec<ModalityStats>,
    /// Station-demeaned monthly mean of VW at 30 cm, m³/m³, January first.
    pub monthly_vw30: [f64; 12],
    /// Wettest and driest month of VW at 30 cm (1 = January).
    pub wettest_month: u32,
    /// See `wettest_month`.
    pub driest_month: u32,
    /// Fraction of day-to-day rises > 0.02 m³/m³ at 30 cm, winter (Dec-Feb).
    pub rise_winter: f64,
    /// Same, summer (Jun-Aug).
    pub rise_summer: f64,
    /// Median share of a > 0.02 m³/m³ rise at 30 cm left 7 days later.
    pub retention_7d: f64,
    /// Number of rises behind `retention_7d`.
    pub retention_rises: usize,
    /// Lag (days) by which VW at 90 cm best follows VW at 30 cm.
    pub depth_lag_days: usize,
    /// Correlation of same-day daily changes of VW at 30 cm and 90 cm, same station.
    pub depth_change_corr: f64,
    /// Mean correlation of daily changes between stations < 100 m apart, VW at 30 cm.
    pub sync_30: f64,
    /// Same at 90 cm.
    pub sync_90: f64,
    /// Fraction of missing values over all the panel's modalities.
    pub missing_fraction: f64,
    /// Among station-days with a gap, fraction where only some modalities are missing.
    pub partial_gap_fraction: f64,
    /// Lowest soil temperature at 30 cm, °C.
    pub t30_min: f64,
    /// Fraction of present station-days with soil temperature at 30 cm below 0 °C.
    pub t30_below_zero: f64,
    /// Fraction of station-days of VW at 30 cm with own-history |z| > 3 (at least 30 earlier
    /// values), leaving out station-days touched by a known event.
    pub z_false_alarm_fraction: f64,
}

/// The summary of one modality kept in [`NetworkStats`].
#[derive(Debug, Clone, PartialEq)]
pub struct ModalityStats {
    /// Modality name.
    pub name: String,
    /// Mean of present values.
    pub mean: f64,
    /// Standard deviation of present values.
    pub std: f64,
    /// 1st percentile.
    pub p01: f64,
    /// 99th percentile.
    pub p99: f64,
    /// Spread of per-sensor means.
    pub between_sensor_std: f64,
    /// Standard deviation of day-to-day changes.
    pub change_std: f64,
    /// Mean lag-1 autocorrelation.
    pub acf1: f64,
    /// Mean lag-7 autocorrelation.
    pub acf7: f64,
    /// Mean series correlation between stations < 100 m apart.
    pub corr_near: f64,
    /// Mean series correlation between stations 450 m or more apart.
    pub corr_far: f64,
}

/// Computes every [`NetworkStats`] of `panel`.
pub fn network_stats(panel: &NetworkPanel) -> NetworkStats {
    let all: Vec<&[Vec<f64>]> = panel
        .modalities
        .iter()
        .map(|m| m.series.as_slice())
        .collect();
    let (missing_fraction, _) = missing_structure(&all);
    let water: Vec<&[Vec<f64>]> = panel
        .modalities
        .iter()
        .filter(|m| m.is_water)
        .map(|m| m.series.as_slice())
        .collect();
    let (_, partial_gap_fraction) = missing_structure(&water);
    // Every other statistic describes the undisturbed field: known event days are left out.
    let masked = panel.without_event_days();
    let panel = &masked;
    let empty: Vec<Vec<f64>> = Vec::new();
    let series = |name: &str| panel.modality(name).map_or(&empty, |m| &m.series);
    let per_modality = panel
        .modalities
        .iter()
        .map(|m| {
            let options = StatsOptions {
                big_jump: if m.is_water { 0.02 } else { 1.0 },
                ..StatsOptions::default()
            };
            let s = panel_stats(
                &DailyPanel {
                    positions: panel.positions.clone(),
                    series: m.series.clone(),
                },
                &options,
            );
            ModalityStats {
                name: m.name.clone(),
                mean: s.mean,
                std: s.std,
                p01: s.p01,
                p99: s.p99,
                between_sensor_std: s.between_sensor_std,
                change_std: s.change_std,
                acf1: autocorrelation(&m.series, 1),
                acf7: autocorrelation(&m.series, 7),
                corr_near: s.bins.first().map_or(f64::NAN, |b| b.mean_corr),
                corr_far: s.bins.last().map_or(f64::NAN, |b| b.mean_corr),
            }
        })
        .collect();
    let near_change_corr = |name: &str| {
        panel.daily(name).map_or(f64::NAN, |p| {
            panel_stats(&p, &StatsOptions::default())
                .bins
                .first()
                .map_or(f64::NAN, |b| b.mean_change_corr)
        })
    };
    let vw30 = series("vw@30cm");
    let vw90 = series("vw@90cm");
    let monthly_vw30 = monthly_cycle(vw30, panel.first_day);
    let (wet, dry) = extreme_months(&monthly_vw30);
    let rises = seasonal_rise_fractions(vw30, panel.first_day, 0.02);
    let (retention_7d, retention_rises) = drainage_retention(vw30, 0.02, 7);
    let (depth_lag_days, _) = depth_lag(vw30, vw90, 120);
    let t30: Vec<f64> = series("t@30cm")
        .iter()
        .flatten()
        .copied()
        .filter(|v| !v.is_nan())
        .collect();
    let t30_min = t30.iter().copied().fold(f64::NAN, f64::min);
    let t30_below_zero = if t30.is_empty() {
        f64::NAN
    } else {
        t30.iter().filter(|&&v| v < 0.0).count() as f64 / t30.len() as f64
    };
    NetworkStats {
        per_modality,
        monthly_vw30,
        wettest_month: wet as u32 + 1,
        driest_month: dry as u32 + 1,
        rise_winter: rises[0],
        rise_summer: rises[2],
        retention_7d,
        retention_rises,
        depth_lag_days,
        depth_change_corr: change_correlation(vw30, vw90),
        sync_30: near_change_corr("vw@30cm"),
        sync_90: near_change_corr("vw@90cm"),
        missing_fraction,
        partial_gap_fraction,
        t30_min,
        t30_below_zero,
        z_false_alarm_fraction: z_exceedance_fraction(vw30, &[], 3.0, 30),
    }
}

impl SynthFarm {
    /// Every modality of a daily-sampled farm as a [`NetworkPanel`] (one value per day: the
    /// first sampling time of each day), positions in the local frame, with the station-days
    /// touched by a leak or dry patch (from its start to 30 days after its end, when its
    /// effect has faded) or by a failing sensor (from its start to its replacement 30 days
    /// after its end) masked as event days.
    pub fn network_panel(&self) -> NetworkPanel {
        let per_day = self
            .times
            .windows(2)
            .next()
            .map_or(1, |w| (86_400 / (w[1] - w[0]).max(1)).max(1) as usize);
        let days = self.times.len().div_ceil(per_day);
        let first_day = self.times.first().map_or(0, |t| t.div_euclid(86_400));
        let modalities = self
            .modalities
            .iter()
            .enumerate()
            .map(|(m, spec)| PanelModality {
                name: spec.modality.as_str().to_string(),
                is_water: spec.is_water,
                depth_cm: spec.depth_cm,
                series: (0..self.sensors.len())
                    .map(|s| {
                        self.series(s, m)
                            .iter()
                            .step_by(per_day)
                            .map(|&v| f64::from(v))
                            .collect()
                    })
                    .collect(),
            })
            .collect();
        let mut event_days = vec![vec![false; days]; self.sensors.len()];
        for e in &self.events {
            let from = (e.start.div_euclid(86_400) - first_day).max(0) as usize;
            // A leak or dry patch fades, a failed sensor is replaced, 30 days after the end.
            let to = (e.end.div_euclid(86_400) - first_day + 30).max(0) as usize;
            for &s in &e.affected {
                for d in event_days[s].iter_mut().take(to).skip(from) {
                    *d = true;
                }
            }
        }
        NetworkPanel {
            positions: self.local.clone(),
            first_day,
            modalities,
            event_days,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const NAN: f64 = f64::NAN;

    #[test]
    fn monthly_cycle_and_extremes() {
        // 2014-01-01 is day 16071. 59 days: all of January (31) and February (28).
        let first = gleaner_field::time::days_from_civil(2014, 1, 1).unwrap();
        let s: Vec<f64> = (0..59).map(|d| if d < 31 { 1.0 } else { 3.0 }).collect();
        let c = monthly_cycle(&[s], first);
        let m = (31.0 + 3.0 * 28.0) / 59.0;
        assert!((c[0] - (1.0 - m)).abs() < 1e-12);
        assert!((c[1] - (3.0 - m)).abs() < 1e-12);
        assert!(c[2].is_nan());
        assert_eq!(extreme_months(&c), (1, 0));
    }

    #[test]
    fn rises_are_counted_per_season() {
        // 2013-12-30 .. 2014-01-02: three changes, all in winter; one rise above 0.02.
        let first = gleaner_field::time::days_from_civil(2013, 12, 30).unwrap();
        let s = vec![vec![0.2, 0.23, 0.235, NAN, 0.5]];
        let f = seasonal_rise_fractions(&s, first, 0.02);
        assert!((f[0] - 0.5).abs() < 1e-12, "{f:?}");
        assert!(f[2].is_nan());
    }

    #[test]
    fn retention_is_the_median_share_left() {
        // Rise of 0.1 on day 1; after 2 days 0.03 of it is left: share 0.3.
        let s = vec![
            vec![0.2, 0.3, 0.25, 0.23, 0.22],
            vec![0.1, 0.2, 0.2, 0.2, NAN],
        ];
        let (r, n) = drainage_retention(&s, 0.02, 2);
        // Second sensor: rise 0.1, day 3 = 0.2 -> share 1.0. Median of {0.3, 1.0} = 0.65.
        assert_eq!(n, 2);
        assert!((r - 0.65).abs() < 1e-9, "{r}");
    }

    #[test]
    fn depth_lag_finds_a_shift() {
        let a: Vec<f64> = (0..200).map(|t| (t as f64 / 9.0).sin()).collect();
        let b: Vec<f64> = (0..200).map(|t| ((t as f64 - 12.0) / 9.0).sin()).collect();
        let (lag, r) = depth_lag(std::slice::from_ref(&a), &[b], 30);
        assert_eq!(lag, 12);
        assert!(r > 0.99);
        assert!(
            (change_correlation(std::slice::from_ref(&a), std::slice::from_ref(&a)) - 1.0).abs()
                < 1e-12
        );
        assert!(autocorrelation(&[a], 1) > 0.99);
    }

    #[test]
    fn missing_structure_counts_partial_gaps() {
        let a = vec![vec![1.0, NAN, NAN, 1.0]];
        let b = vec![vec![1.0, NAN, 1.0, 1.0]];
        let (frac, partial) = missing_structure(&[&a, &b]);
        assert!((frac - 3.0 / 8.0).abs() < 1e-12);
        // Gap days: day 1 (both), day 2 (one): half partial.
        assert!((partial - 0.5).abs() < 1e-12);
    }

    #[test]
    fn z_exceedance_skips_masked_days() {
        let mut s: Vec<f64> = (0..40)
            .map(|t| if t % 2 == 0 { 1.0 } else { -1.0 })
            .collect();
        s.push(10.0);
        s.push(0.0);
        let f = z_exceedance_fraction(&[s.clone()], &[], 3.0, 30);
        // Days 30..=41 are scored (12 days), one (day 40) is far out.
        assert!((f - 1.0 / 12.0).abs() < 1e-12, "{f}");
        let mut mask = vec![false; s.len()];
        mask[40] = true;
        assert_eq!(z_exceedance_fraction(&[s], &[mask], 3.0, 30), 0.0);
    }

    #[test]
    fn network_stats_of_a_hand_made_panel() {
        // Two stations 50 m apart with identical daily changes at 30 cm (synchrony 1) and a
        // soil temperature that dips below 0 °C once; the second station's last day is an
        // event day, left out of everything but the missing-data counts.
        let first = gleaner_field::time::days_from_civil(2014, 1, 1).unwrap();
        let base: Vec<f64> = (0..60).map(|d| 0.2 + 0.01 * ((d * 7) % 5) as f64).collect();
        let shifted: Vec<f64> = base.iter().map(|v| v + 0.05).collect();
        let mut t = vec![vec![2.0; 60], vec![3.0; 60]];
        t[0][10] = -1.0;
        t[1][59] = -5.0;
        let mut mask = vec![vec![false; 60], vec![false; 60]];
        mask[1][59] = true;
        let modality = |name: &str, is_water: bool, series: Vec<Vec<f64>>| PanelModality {
            name: name.into(),
            is_water,
            depth_cm: 30,
            series,
        };
        let panel = NetworkPanel {
            positions: vec![LocalPoint::new(0.0, 0.0), LocalPoint::new(50.0, 0.0)],
            first_day: first,
            modalities: vec![
                modality("vw@30cm", true, vec![base.clone(), shifted]),
                modality("t@30cm", false, t),
            ],
            event_days: mask,
        };
        let s = network_stats(&panel);
        assert!((s.sync_30 - 1.0).abs() < 1e-9, "{}", s.sync_30);
        assert!(s.sync_90.is_nan());
        assert_eq!(s.t30_min, -1.0);
        // 119 temperatures left after the mask, one below 0 °C.
        assert!((s.t30_below_zero - 1.0 / 119.0).abs() < 1e-12);
        assert_eq!(s.missing_fraction, 0.0);
        assert_eq!(s.per_modality.len(), 2);
        assert!((s.per_modality[0].corr_near - 1.0).abs() < 1e-9);
    }
}
