//! Summary statistics used to calibrate the generator against real data (pure: values in,
//! values out). The same function summarises CAF and a synthetic farm, so the two can be
//! compared like for like (see the crate docs, "Calibration").

use gleaner_field::LocalPoint;

use crate::SynthFarm;

/// One modality of a sensor network on a daily grid: per sensor, its position and its
/// series (NaN = missing), all series aligned on the same days (they may differ in length).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct DailyPanel {
    /// Sensor positions in any metric frame, metres.
    pub positions: Vec<LocalPoint>,
    /// Per sensor, one value per day in the modality's unit; NaN when missing.
    pub series: Vec<Vec<f64>>,
}

/// What [`panel_stats`] measures and how.
#[derive(Debug, Clone, PartialEq)]
pub struct StatsOptions {
    /// A day-to-day change whose magnitude exceeds this is a "big jump", in the modality's unit
    /// (default 0.02, for m³/m³).
    pub big_jump: f64,
    /// Distance bin edges for the correlation-versus-distance curve, metres, ascending (default
    /// 0, 100, 200, 300, 450, infinity).
    pub bin_edges_m: Vec<f64>,
    /// Minimum number of common days for a pair's correlation to count (default 30).
    pub min_overlap: usize,
    /// Minimum number of present days for a sensor's mean to count in the between-sensor
    /// spread (default 100).
    pub min_days_for_mean: usize,
}

impl Default for StatsOptions {
    fn default() -> Self {
        Self {
            big_jump: 0.02,
            bin_edges_m: vec![0.0, 100.0, 200.0, 300.0, 450.0, f64::INFINITY],
            min_overlap: 30,
            min_days_for_mean: 100,
        }
    }
}

/// Pairwise series correlation within one distance bin.
#[derive(Debug, Clone, PartialEq)]
pub struct DistanceBin {
    /// Lower edge (inclusive), metres.
    pub from_m: f64,
    /// Upper edge (exclusive), metres.
    pub to_m: f64,
    /// Mean Pearson correlation of the pairs' series over their common days (NaN if no pair).
    pub mean_corr: f64,
    /// Mean Pearson correlation of the pairs' day-to-day changes (NaN if no pair).
    pub mean_change_corr: f64,
    /// Number of pairs with enough overlap.
    pub pairs: usize,
}

/// Summary of a [`DailyPanel`], all in the modality's unit unless stated.
#[derive(Debug, Clone, PartialEq)]
pub struct PanelStats {
    /// Number of present values.
    pub count: usize,
    /// Mean of all present values.
    pub mean: f64,
    /// Standard deviation of all present values (n - 1).
    pub std: f64,
    /// 1st and 99th percentiles of all present values.
    pub p01: f64,
    /// See `p01`.
    pub p99: f64,
    /// Standard deviation (n - 1) of the per-sensor means: the spatial spread.
    pub between_sensor_std: f64,
    /// Mean over sensors of each sensor's own standard deviation: the temporal spread.
    pub within_sensor_std: f64,
    /// Standard deviation of day-to-day changes (consecutive present days only).
    pub change_std: f64,
    /// Fraction of day-to-day changes with magnitude above [`StatsOptions::big_jump`].
    pub big_jump_fraction: f64,
    /// 50th, 90th and 99th percentiles of the magnitude of day-to-day changes.
    pub change_abs_quantiles: [f64; 3],
    /// Correlation versus distance.
    pub bins: Vec<DistanceBin>,
}

fn mean_std(xs: &[f64]) -> (f64, f64) {
    let n = xs.len() as f64;
    if xs.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    let m = xs.iter().sum::<f64>() / n;
    let var = xs.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (n - 1.0).max(1.0);
    (m, var.sqrt())
}

/// Pearson's correlation of paired samples; `None` when either has no spread.
pub(crate) fn pearson(xs: &[f64], ys: &[f64]) -> Option<f64> {
    let n = xs.len() as f64;
    let mx = xs.iter().sum::<f64>() / n;
    let my = ys.iter().sum::<f64>() / n;
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for (x, y) in xs.iter().zip(ys) {
        let (a, b) = (x - mx, y - my);
        sxy += a * b;
        sxx += a * a;
        syy += b * b;
    }
    (sxx > 0.0 && syy > 0.0).then(|| sxy / (sxx * syy).sqrt())
}

/// Summarises a panel. Cost O(S² x D) for S sensors and D days (all pairs), so keep S to a
/// few hundred.
pub fn panel_stats(panel: &DailyPanel, options: &StatsOptions) -> PanelStats {
    let mut all = Vec::new();
    let mut changes = Vec::new();
    let mut means = Vec::new();
    let mut within = Vec::new();
    for s in &panel.series {
        let present: Vec<f64> = s.iter().copied().filter(|v| !v.is_nan()).collect();
        all.extend_from_slice(&present);
        changes.extend(
            s.windows(2)
                .filter(|w| !w[0].is_nan() && !w[1].is_nan())
                .map(|w| w[1] - w[0]),
        );
        if present.len() >= options.min_days_for_mean.max(2) {
            let (m, sd) = mean_std(&present);
            means.push(m);
            within.push(sd);
        }
    }
    let (mean, std) = mean_std(&all);
    all.sort_by(f64::total_cmp);
    let quantile = |p: f64| nearest_rank(&all, p);
    let (_, change_std) = mean_std(&changes);
    let mut abs_changes: Vec<f64> = changes.iter().map(|c| c.abs()).collect();
    abs_changes.sort_by(f64::total_cmp);
    let abs_q = |p: f64| nearest_rank(&abs_changes, p);
    let big = changes
        .iter()
        .filter(|c| c.abs() > options.big_jump)
        .count();

    let nbins = options.bin_edges_m.len().saturating_sub(1);
    let mut sums = vec![(0.0, 0.0, 0usize, 0usize); nbins];
    let (mut xs, mut ys, mut dxs, mut dys) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for i in 0..panel.series.len() {
        for j in i + 1..panel.series.len() {
            let d = panel.positions[i].distance(&panel.positions[j]);
            let Some(b) =
                (0..nbins).find(|&b| d >= options.bin_edges_m[b] && d < options.bin_edges_m[b + 1])
            else {
                continue;
            };
            let (a, c) = (&panel.series[i], &panel.series[j]);
            let len = a.len().min(c.len());
            xs.clear();
            ys.clear();
            dxs.clear();
            dys.clear();
            for t in 0..len {
                if a[t].is_nan() || c[t].is_nan() {
                    continue;
                }
                xs.push(a[t]);
                ys.push(c[t]);
                if t + 1 < len && !a[t + 1].is_nan() && !c[t + 1].is_nan() {
                    dxs.push(a[t + 1] - a[t]);
                    dys.push(c[t + 1] - c[t]);
                }
            }
            if let Some(r) = (xs.len() >= options.min_overlap)
                .then(|| pearson(&xs, &ys))
                .flatten()
            {
                sums[b].0 += r;
                sums[b].2 += 1;
            }
            if let Some(r) = (dxs.len() >= options.min_overlap)
                .then(|| pearson(&dxs, &dys))
                .flatten()
            {
                sums[b].1 += r;
                sums[b].3 += 1;
            }
        }
    }
    let bins = sums
        .iter()
        .enumerate()
        .map(|(b, &(sr, sd, nr, nd))| DistanceBin {
            from_m: options.bin_edges_m[b],
            to_m: options.bin_edges_m[b + 1],
            mean_corr: if nr > 0 { sr / nr as f64 } else { f64::NAN },
            mean_change_corr: if nd > 0 { sd / nd as f64 } else { f64::NAN },
            pairs: nr,
        })
        .collect();
    PanelStats {
        count: all.len(),
        mean,
        std,
        p01: quantile(0.01),
        p99: quantile(0.99),
        between_sensor_std: mean_std(&means).1,
        within_sensor_std: if within.is_empty() {
            f64::NAN
        } else {
            within.iter().sum::<f64>() / within.len() as f64
        },
        change_std,
        big_jump_fraction: if changes.is_empty() {
            f64::NAN
        } else {
            big as f64 / changes.len() as f64
        },
        change_abs_quantiles: [abs_q(0.5), abs_q(0.9), abs_q(0.99)],
        bins,
    }
}

impl SynthFarm {
    /// The farm's `modality` (index into [`SynthFarm::modalities`]) as a daily panel: one value
    /// per day (the first sampling time of each day), positions in the local frame. `None` if
    /// the index is out of range.
    pub fn daily_panel(&self, modality: usize) -> Option<DailyPanel> {
        if modality >= self.modalities.len() {
            return None;
        }
        let per_day = self
            .times
            .windows(2)
            .next()
            .map_or(1, |w| (86_400 / (w[1] - w[0]).max(1)).max(1) as usize);
        let series = (0..self.sensors.len())
            .map(|s| {
                self.series(s, modality)
                    .iter()
                    .step_by(per_day)
                    .map(|&v| f64::from(v))
                    .collect()
            })
            .collect();
        Some(DailyPanel {
            positions: self.local.clone(),
            series,
        })
    }
}

/// The `p` quantile of `sorted` (ascending) by the nearest rank; NaN when empty.
fn nearest_rank(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        f64::NAN
    } else {
        sorted[((sorted.len() - 1) as f64 * p).round() as usize]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stats_of_a_tiny_panel() {
        let panel = DailyPanel {
            positions: vec![LocalPoint::new(0.0, 0.0), LocalPoint::new(50.0, 0.0)],
            series: vec![
                vec![0.1, 0.2, f64::NAN, 0.2, 0.25],
                vec![0.2, 0.3, 0.3, 0.3, 0.35],
            ],
        };
        let options = StatsOptions {
            min_overlap: 3,
            min_days_for_mean: 2,
            big_jump: 0.07,
            ..Default::default()
        };
        let s = panel_stats(&panel, &options);
        assert_eq!(s.count, 9);
        assert!((s.mean - 2.2 / 9.0).abs() < 1e-12);
        // Changes: 0.1, 0.05 (sensor 1); 0.1, 0, 0, 0.05 (sensor 2): two above 0.07.
        assert!((s.big_jump_fraction - 2.0 / 6.0).abs() < 1e-12);
        // Common days 0, 1, 3, 4: sensor 2 is sensor 1 + 0.1 there, so correlation 1.
        assert!((s.bins[0].mean_corr - 1.0).abs() < 1e-12);
        assert_eq!(s.bins[0].pairs, 1);
        assert!(s.bins[1].mean_corr.is_nan());
    }
}
