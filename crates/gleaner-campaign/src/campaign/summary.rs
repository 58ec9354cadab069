//! Schedules, intervals and the summaries of a campaign's results.

use std::collections::BTreeMap;

use gleaner_field::UnixSeconds;

use gleaner_app::{AppError, Result};

use super::strategy::Strategy;
use super::types::{CampaignRequest, CampaignResult, MissionMetrics, RunResult};

/// A schedule: every `step_s` seconds from `start` to `end` inclusive.
pub fn every(start: UnixSeconds, end: UnixSeconds, step_s: i64) -> Result<Vec<UnixSeconds>> {
    if step_s <= 0 {
        return Err(AppError::Invalid(format!(
            "mission interval {step_s} s must be positive"
        )));
    }
    if end < start {
        return Err(AppError::Invalid(
            "the schedule ends before it starts".into(),
        ));
    }
    let n = (end - start) / step_s + 1;
    if n > 1_000_000 {
        return Err(AppError::Invalid(format!(
            "{n} missions: at most 1,000,000"
        )));
    }
    Ok((0..n).map(|k| start + k * step_s).collect())
}

/// A mean with its 95% confidence interval.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Interval {
    /// The mean.
    pub mean: f64,
    /// Lower end of the 95% interval.
    pub low: f64,
    /// Upper end of the 95% interval.
    pub high: f64,
    /// Number of independent values the interval rests on.
    pub n: usize,
}

/// Two-sided 97.5% quantile of Student's t with `df` degrees of freedom.
fn t975(df: usize) -> f64 {
    const T: [f64; 30] = [
        12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228, 2.201, 2.179, 2.160,
        2.145, 2.131, 2.120, 2.110, 2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064, 2.060, 2.056,
        2.052, 2.048, 2.045, 2.042,
    ];
    match df {
        0 => f64::NAN,
        1..=30 => T[df - 1],
        31..=60 => 2.000 + (2.042 - 2.000) * (60 - df) as f64 / 30.0,
        61..=120 => 1.980 + (2.000 - 1.980) * (120 - df) as f64 / 60.0,
        _ => 1.960,
    }
}

/// The mean of `values` (non-finite ones left out) with Student's t 95% interval (the
/// interval is the mean itself for a single value).
pub fn interval(values: &[f64]) -> Interval {
    let v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    let n = v.len();
    if n == 0 {
        return Interval {
            mean: f64::NAN,
            low: f64::NAN,
            high: f64::NAN,
            n,
        };
    }
    let mean = v.iter().sum::<f64>() / n as f64;
    if n == 1 {
        return Interval {
            mean,
            low: mean,
            high: mean,
            n,
        };
    }
    let sd = (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt();
    let h = t975(n - 1) * sd / (n as f64).sqrt();
    Interval {
        mean,
        low: mean - h,
        high: mean + h,
        n,
    }
}

/// Days of mission time per block: consecutive missions are correlated (the same weather,
/// the same stale sensors), so intervals rest on the means of blocks of this many days of
/// missions, not on single missions.
pub const BLOCK_DAYS: i64 = 7;

/// Fewest blocks an interval rests on: with fewer, Student's t over so few block means is
/// too wide to mean anything (or, worse, too narrow by chance), and no interval is given.
pub const MIN_BLOCKS: usize = 10;

/// The values an interval rests on: per block of [`BLOCK_DAYS`] days of mission time (from the
/// first mission of any run), the mean over runs of each run's mean over its missions in
/// that block. Runs are averaged within a block rather than counted as separate values, so
/// replicates of the same dataset (which share its weather) do not pass for independent
/// evidence; blocks are the units, taken as approximately independent at a week apart.
pub fn block_means(per_run: &[Vec<(UnixSeconds, f64)>]) -> Vec<f64> {
    let Some(t0) = per_run.iter().flatten().map(|p| p.0).min() else {
        return Vec::new();
    };
    let block_s = BLOCK_DAYS * 86_400;
    let mut blocks: BTreeMap<i64, (f64, usize)> = BTreeMap::new();
    for run in per_run {
        let mut own: BTreeMap<i64, (f64, usize)> = BTreeMap::new();
        for &(t, v) in run.iter().filter(|p| p.1.is_finite()) {
            let e = own.entry((t - t0).div_euclid(block_s)).or_insert((0.0, 0));
            e.0 += v;
            e.1 += 1;
        }
        for (b, (sum, n)) in own {
            let e = blocks.entry(b).or_insert((0.0, 0));
            e.0 += sum / n as f64;
            e.1 += 1;
        }
    }
    blocks.values().map(|(sum, n)| sum / *n as f64).collect()
}

/// The mean over blocks with Student's t 95% interval over the [`block_means`], given only
/// when there are at least [`MIN_BLOCKS`] blocks (else `low` and `high` are NaN).
pub fn block_interval(per_run: &[Vec<(UnixSeconds, f64)>]) -> Interval {
    let mut i = interval(&block_means(per_run));
    if i.n < MIN_BLOCKS {
        i.low = f64::NAN;
        i.high = f64::NAN;
    }
    i
}

/// A per-mission metric, by name: `rmse_kriged`, `rmse_carried`, `rmse_kriged_before`,
/// `rmse_carried_before`, `mae_kriged`,
/// `mae_carried`, `staleness_mean_days`, `staleness_max_days`, `energy_kj`, `utilisation`,
/// `cells`, `classifier_accuracy`, `lost_readings`, `mean_sd` (square root of the mean
/// kriging variance), `coverage90` (share of estimated sensors inside their 90% interval).
pub fn metric(m: &MissionMetrics, name: &str) -> f64 {
    match name {
        "rmse_kriged" => m.rmse_kriged,
        "rmse_carried" => m.rmse_carried,
        "rmse_kriged_before" => m.rmse_kriged_before,
        "rmse_carried_before" => m.rmse_carried_before,
        "mae_kriged" => m.mae_kriged,
        "mae_carried" => m.mae_carried,
        "staleness_mean_days" => m.staleness_mean_s / 86_400.0,
        "staleness_max_days" => m.staleness_max_s / 86_400.0,
        "energy_kj" => m.energy_j / 1_000.0,
        "utilisation" => {
            if m.budget_j > 0.0 && m.sorties > 0 {
                m.energy_j / (m.budget_j * m.sorties as f64)
            } else {
                0.0
            }
        }
        "cells" => m.cells as f64,
        "classifier_accuracy" => m.classifier_accuracy.unwrap_or(f64::NAN),
        "lost_readings" => m.lost_readings as f64,
        "mean_sd" => m.mean_variance.sqrt(),
        "coverage90" => m.coverage90.unwrap_or(f64::NAN),
        _ => f64::NAN,
    }
}

/// The per-mission metrics [`metric`] knows, in report order.
pub const METRICS: [&str; 15] = [
    "rmse_kriged",
    "rmse_carried",
    "rmse_kriged_before",
    "rmse_carried_before",
    "mae_kriged",
    "mae_carried",
    "mean_sd",
    "coverage90",
    "staleness_mean_days",
    "staleness_max_days",
    "energy_kj",
    "utilisation",
    "cells",
    "classifier_accuracy",
    "lost_readings",
];

/// One strategy at one budget, over every run (and dataset) given.
#[derive(Debug, Clone)]
pub struct Summary {
    /// Strategy.
    pub strategy: Strategy,
    /// Budget fraction.
    pub budget: f64,
    /// Runs pooled.
    pub runs: usize,
    /// Per [`METRICS`] name: the mean over blocks of missions with its 95% interval
    /// ([`block_interval`]).
    pub metrics: Vec<(&'static str, Interval)>,
    /// Events caught / events, pooled.
    pub events_caught: (usize, usize),
    /// Delay from an event's first available reading to its catch, days (caught events).
    pub delay_days: Interval,
    /// Kriging RMSE minus the reference strategy's, paired by mission (same dataset, seed,
    /// budget), with its 95% interval over blocks ([`block_interval`]); `None` for the
    /// reference itself or without a pair.
    pub rmse_vs_reference: Option<Interval>,
    /// Catch delay minus the reference strategy's, days, over the events both caught (same
    /// dataset, seed, budget), with Student's t 95% interval over those events; `None` for
    /// the reference itself or without a pair.
    pub delay_vs_reference: Option<Interval>,
}

/// What one campaign found, per strategy and budget: what `POST /api/v1/simulate` answers.
#[derive(Debug, Clone)]
pub struct CampaignSummary {
    /// The dataset's name.
    pub label: String,
    /// The evaluated modality.
    pub modality: String,
    /// The logging period, s.
    pub period_s: i64,
    /// End of the history, s.
    pub history_until: UnixSeconds,
    /// Mission times, s.
    pub schedule: Vec<UnixSeconds>,
    /// Events that became available during the campaign.
    pub events: usize,
    /// The strategy the differences are taken against (gleaner when it ran, else the
    /// first).
    pub reference: Strategy,
    /// Per (strategy, budget), in the request's order.
    pub summaries: Vec<Summary>,
}

impl CampaignRequest {
    /// Missions the campaign flies in all: missions × strategies × seeds × budgets.
    pub fn mission_runs(&self) -> usize {
        self.schedule
            .len()
            .saturating_mul(self.strategies.len())
            .saturating_mul(self.seeds.len())
            .saturating_mul(self.budgets.len())
    }
}

/// [`summarise`] of one campaign, against gleaner when it ran.
pub fn campaign_summary(request: &CampaignRequest, result: &CampaignResult) -> CampaignSummary {
    let reference = if request.strategies.contains(&Strategy::Gleaner) {
        Strategy::Gleaner
    } else {
        request
            .strategies
            .first()
            .copied()
            .unwrap_or(Strategy::Gleaner)
    };
    CampaignSummary {
        label: result.label.clone(),
        modality: result.modality.clone(),
        period_s: result.period_s,
        history_until: request.history_until,
        schedule: request.schedule.clone(),
        events: result.events.len(),
        reference,
        summaries: summarise(std::slice::from_ref(result), reference),
    }
}

/// Summaries of every (strategy, budget) over the given campaigns (e.g. one per synthetic
/// seed), with paired RMSE differences against `reference`.
pub fn summarise(results: &[CampaignResult], reference: Strategy) -> Vec<Summary> {
    let mut keys: Vec<(Strategy, u64)> = Vec::new();
    for r in results {
        for run in &r.runs {
            let k = (run.key.strategy, run.key.budget.to_bits());
            if !keys.contains(&k) {
                keys.push(k);
            }
        }
    }
    let mut out = Vec::new();
    for (strategy, budget_bits) in keys {
        let budget = f64::from_bits(budget_bits);
        let runs: Vec<(&CampaignResult, &RunResult)> = results
            .iter()
            .flat_map(|r| r.runs.iter().map(move |run| (r, run)))
            .filter(|(_, run)| run.key.strategy == strategy && run.key.budget == budget)
            .collect();
        let metrics = METRICS
            .iter()
            .map(|&name| {
                let per_run: Vec<Vec<(UnixSeconds, f64)>> = runs
                    .iter()
                    .map(|(_, run)| {
                        run.missions
                            .iter()
                            .map(|m| (m.t, metric(m, name)))
                            .collect()
                    })
                    .collect();
                (name, block_interval(&per_run))
            })
            .collect();
        let mut caught = 0;
        let mut total = 0;
        let mut delays = Vec::new();
        for (r, run) in &runs {
            for (e, c) in r.events.iter().zip(&run.caught) {
                total += 1;
                if let Some(at) = c {
                    caught += 1;
                    delays.push((at - e.start - r.period_s) as f64 / 86_400.0);
                }
            }
        }
        let rmse_vs_reference = (strategy != reference)
            .then(|| {
                let per_run: Vec<Vec<(UnixSeconds, f64)>> = runs
                    .iter()
                    .filter_map(|(r, run)| {
                        let other = r.runs.iter().find(|o| {
                            o.key.strategy == reference
                                && o.key.seed == run.key.seed
                                && o.key.budget == run.key.budget
                        })?;
                        Some(
                            run.missions
                                .iter()
                                .zip(&other.missions)
                                .map(|(a, b)| (a.t, a.rmse_kriged - b.rmse_kriged))
                                .collect(),
                        )
                    })
                    .collect();
                (!per_run.is_empty()).then(|| block_interval(&per_run))
            })
            .flatten();
        let delay_vs_reference = (strategy != reference)
            .then(|| {
                let mut diffs = Vec::new();
                for (r, run) in &runs {
                    let Some(other) = r.runs.iter().find(|o| {
                        o.key.strategy == reference
                            && o.key.seed == run.key.seed
                            && o.key.budget == run.key.budget
                    }) else {
                        continue;
                    };
                    for (a, b) in run.caught.iter().zip(&other.caught) {
                        if let (Some(a), Some(b)) = (a, b) {
                            diffs.push((a - b) as f64 / 86_400.0);
                        }
                    }
                }
                (!diffs.is_empty()).then(|| interval(&diffs))
            })
            .flatten();
        out.push(Summary {
            strategy,
            budget,
            runs: runs.len(),
            metrics,
            events_caught: (caught, total),
            delay_days: interval(&delays),
            rmse_vs_reference,
            delay_vs_reference,
        });
    }
    out
}

/// One strategy's flights over every run and dataset given (missions with a flight record).
#[derive(Debug, Clone, PartialEq)]
pub struct FlightSummary {
    /// Strategy.
    pub strategy: Strategy,
    /// Missions with a flight record.
    pub missions: usize,
    /// Mean forecast wind, m/s.
    pub mean_forecast_mps: f64,
    /// Missions of which a sortie re-planned in the air.
    pub replanned: usize,
    /// Planned stops the re-plans dropped.
    pub cells_dropped: usize,
    /// Readings brought back.
    pub readings: u64,
    /// Readings brought back on missions whose forecast was below [`CALM_DAY_MPS`].
    pub readings_calm_days: u64,
    /// Missions whose forecast was below [`CALM_DAY_MPS`].
    pub calm_days: usize,
    /// Missions of which a sortie flew more energy than its battery could give above the
    /// reserve (must be 0).
    pub over_budget: usize,
    /// The largest flown energy less the usable energy over every sortie, J (< 0: every
    /// sortie landed with at least that much to spare above the reserve).
    pub max_excess_j: f64,
}

/// Forecast speed below which a mission day counts as moderate, m/s (the flight-day target:
/// data within 10% of still air's on such days).
pub const CALM_DAY_MPS: f64 = 6.0;

/// [`FlightSummary`] per strategy, in order of first appearance.
pub fn flight_summaries(results: &[CampaignResult]) -> Vec<FlightSummary> {
    let mut out: Vec<FlightSummary> = Vec::new();
    let mut wind_sum: Vec<f64> = Vec::new();
    for run in results.iter().flat_map(|r| &r.runs) {
        let k = match out.iter().position(|f| f.strategy == run.key.strategy) {
            Some(k) => k,
            None => {
                out.push(FlightSummary {
                    strategy: run.key.strategy,
                    missions: 0,
                    mean_forecast_mps: f64::NAN,
                    replanned: 0,
                    cells_dropped: 0,
                    readings: 0,
                    readings_calm_days: 0,
                    calm_days: 0,
                    over_budget: 0,
                    max_excess_j: f64::NEG_INFINITY,
                });
                wind_sum.push(0.0);
                out.len() - 1
            }
        };
        let f = &mut out[k];
        for d in run.missions.iter().filter_map(|m| m.flight.as_ref()) {
            f.missions += 1;
            wind_sum[k] += d.wind.forecast.speed_mps;
            f.replanned += usize::from(d.replanned > 0);
            f.cells_dropped += d.cells_dropped;
            f.readings += d.readings;
            if d.wind.forecast.speed_mps < CALM_DAY_MPS {
                f.calm_days += 1;
                f.readings_calm_days += d.readings;
            }
            f.over_budget += usize::from(d.over_budget > 0);
            f.max_excess_j = f.max_excess_j.max(d.max_excess_j);
        }
    }
    for (f, w) in out.iter_mut().zip(wind_sum) {
        if f.missions > 0 {
            f.mean_forecast_mps = w / f.missions as f64;
        }
    }
    out.retain(|f| f.missions > 0);
    out
}
