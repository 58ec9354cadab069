//! gleaner's drift freshness (`[utility] freshness_form = "drift"`): F as the expected error
//! of each cell's carried-forward values, from each sensor's own drift.
//!
//! Per sensor, the mean squared change D(h) of the condition modality at lags of 1..=90 grid
//! steps — of its deviation from the field's mean at the same time (the field-wide change is
//! what the reconstruction recovers from the neighbours; the sensor's own change is what only a
//! visit brings) — is estimated on its collected readings of the last `drift_window_days`
//! ([`gleaner_utility::mean_squared_change`], at least 10 pairs per lag), then shrunk to the
//! field: lag by lag `own^(1 − w) · median^w` with `w = drift_shrink` (default ½: the
//! geometric mean of the sensor's and the field's median; the median alone where the sensor
//! has too few pairs). Its staleness index
//! ([`gleaner_utility::staleness_index`]) at the time since the sensor was last collected
//! — multiplied by how unusual the days the sensor has not reported were, to the power
//! `drift_spread` (`KnownSpread`: a rain day seen at the cells visited since makes it
//! larger) — summed over the cell's sensors and divided by the largest cell's, is the cell's F
//! in [0, 1] (all 0 when no cell has drifted). Why: on CAF the one-day change of the 30 cm
//! soil moisture differs 95-fold in variance between stations, so equal freshness spends
//! visits on cells that hardly moved, and the error between visits is made of a few rain days
//! (docs/method-improvement.md).

use std::collections::HashMap;

use gleaner_field::{Modality, SensorId, UnixSeconds};
use gleaner_utility::CellTerms;

use crate::Store;
use crate::error::{AppError, Result};
use crate::knowledge::{History, Knowledge, known_until};
use crate::project::Project;

/// Lags of the structure functions, grid steps.
pub const DRIFT_MAX_LAG: usize = 90;
/// Fewest pairs for a sensor's own estimate at a lag.
const MIN_PAIRS: usize = 10;

/// Each cell's drift index (field order; value unit² × grid steps) at `t`, from the readings
/// of `modality` in the store within `window_s` seconds before `t` that the scoring knows
/// (those of `history`, and later ones a recorded collection brought back: a sensor's
/// readings up to the later of `history.until` and its last collection in `k`, as
/// [`Knowledge`] keeps them; grid step: the median gap between a sensor's readings) and each
/// sensor's last collection in `k`; see the module docs.
pub fn drift_index<S: Store>(
    project: &Project<S>,
    k: &Knowledge,
    modality: &Modality,
    t: UnixSeconds,
    window_s: i64,
    history: &History,
) -> Result<Vec<f64>> {
    let from = t.saturating_sub(window_s.max(0)).max(history.from);
    if from > t {
        return Ok(vec![0.0; k.field.cells().len()]);
    }
    let batch = project.store().readings_for(Some(modality), from..=t)?;
    // Per sensor of the batch: its latest known reading time (everything when the history
    // is unbounded, the common case).
    let cutoff: Vec<UnixSeconds> = if history.until == UnixSeconds::MAX {
        vec![UnixSeconds::MAX; batch.sensors.len()]
    } else {
        let collected: HashMap<&SensorId, Option<UnixSeconds>> = k
            .sensors
            .iter()
            .zip(&k.last_collected)
            .map(|(s, l)| (&s.id, *l))
            .collect();
        batch
            .sensors
            .iter()
            .map(|s| known_until(t, history.until, collected.get(s).copied().flatten()))
            .collect()
    };
    let mut series: HashMap<&SensorId, Vec<(UnixSeconds, f64)>> = HashMap::new();
    for r in &batch.rows {
        let j = r.sensor as usize;
        if let Some(s) = batch.sensors.get(j)
            && r.t <= cutoff[j]
        {
            series.entry(s).or_default().push((r.t, r.value));
        }
    }
    for v in series.values_mut() {
        v.sort_by_key(|p| p.0);
    }
    remove_field_mean(&mut series);
    // The sampling step: the median gap between a sensor's consecutive readings.
    let step_s = crate::knowledge::sampling_step(
        &series
            .values()
            .map(|v| v.iter().map(|p| p.0).collect())
            .collect::<Vec<Vec<UnixSeconds>>>(),
    );
    let kappa = project.settings().utility.drift_spread;
    let spread = (kappa > 0.0).then(|| KnownSpread::new(&series, step_s));
    let last_known: HashMap<&SensorId, UnixSeconds> = series
        .iter()
        .filter_map(|(s, v)| v.last().map(|p| (*s, p.0)))
        .collect();
    let own: HashMap<&SensorId, Vec<Option<f64>>> = series
        .into_iter()
        .map(|(s, v)| {
            let times: Vec<UnixSeconds> = v.iter().map(|p| p.0).collect();
            let values: Vec<f64> = v.iter().map(|p| p.1).collect();
            let d = gleaner_utility::mean_squared_change(
                &times,
                &values,
                step_s,
                DRIFT_MAX_LAG,
                MIN_PAIRS,
            );
            (s, d)
        })
        .collect();
    let median: Vec<f64> = (0..DRIFT_MAX_LAG)
        .map(|lag| {
            let mut v: Vec<f64> = own.values().filter_map(|d| d[lag]).collect();
            v.sort_by(f64::total_cmp);
            v.get(v.len() / 2).copied().unwrap_or(0.0)
        })
        .collect();
    let step = step_s.max(1) as f64;
    let shrink = project.settings().utility.drift_shrink;
    let index_of_sensor = |p: usize| -> f64 {
        let id = &k.sensors[p].id;
        let d: Vec<f64> = median
            .iter()
            .enumerate()
            .map(|(lag, m)| match own.get(id).and_then(|d| d[lag]) {
                Some(x) => shrunk(x, *m, shrink),
                None => *m,
            })
            .collect();
        // Never collected: as old as can matter (the index is flat past the last lag).
        let age_s = k.last_collected[p].map_or(f64::INFINITY, |l| (t - l).max(0) as f64);
        let index =
            gleaner_utility::staleness_index(&d, (age_s / step).min((2 * DRIFT_MAX_LAG) as f64));
        match (&spread, last_known.get(id)) {
            (Some(c), Some(&last)) => index * c.ratio(last, t).powf(kappa),
            _ => index,
        }
    };
    Ok(k.field
        .cells()
        .iter()
        .map(|c| c.sensors.iter().map(|&p| index_of_sensor(p)).sum())
        .collect())
}

/// How unusual the sensors' own one-step changes were at each time, from the readings the
/// scoring knows (deviations from the field's mean): on a rain day the stations' jumps differ
/// widely and the median squared own change is many times its usual size, which tells a
/// scoring that a sensor not read since then most likely carries a large error its neighbours
/// cannot explain. The median, not the mean: one station's glitch alone does not make a day
/// unusual (it counts only through the field's mean it shifts).
struct KnownSpread {
    /// Times (s) with a known spread, ascending.
    times: Vec<UnixSeconds>,
    /// Running sums of (spread / usual − 1) over `times`: `excess[k]` sums the first k.
    excess: Vec<f64>,
    /// Grid step, s.
    step_s: i64,
}

/// Fewest sensors whose one-step change is known at a time for its spread to count.
const MIN_SENSORS_FOR_SPREAD: usize = 3;

impl KnownSpread {
    /// From each sensor's deviations (time in s, value) sorted by time; `step_s` the grid
    /// step (a one-step change joins readings exactly one step apart).
    fn new<K>(series: &HashMap<K, Vec<(UnixSeconds, f64)>>, step_s: i64) -> Self {
        let mut squares: HashMap<UnixSeconds, Vec<f64>> = HashMap::new();
        for v in series.values() {
            for w in v.windows(2) {
                if w[1].0 - w[0].0 == step_s {
                    let d = w[1].1 - w[0].1;
                    squares.entry(w[1].0).or_default().push(d * d);
                }
            }
        }
        // Sorted, so the bits never depend on a map's seed.
        let mut spread: Vec<(UnixSeconds, f64)> = squares
            .into_iter()
            .filter(|(_, v)| v.len() >= MIN_SENSORS_FOR_SPREAD)
            .map(|(t, mut v)| {
                v.sort_by(f64::total_cmp);
                (t, gleaner_utility::median_of_sorted(&v))
            })
            .collect();
        spread.sort_by_key(|p| p.0);
        let usual = spread.iter().map(|p| p.1).sum::<f64>() / spread.len().max(1) as f64;
        if !(usual > 0.0 && usual.is_finite()) {
            spread.clear();
        }
        let mut excess = Vec::with_capacity(spread.len() + 1);
        excess.push(0.0);
        for &(_, v) in &spread {
            excess.push(excess[excess.len() - 1] + (v / usual - 1.0));
        }
        Self {
            times: spread.into_iter().map(|p| p.0).collect(),
            excess,
            step_s: step_s.max(1),
        }
    }

    /// The mean over the grid times strictly between `last` (a sensor's newest known reading,
    /// s) and `t` (s) of the spread relative to its usual value, times nobody has reported
    /// counting as usual: 1 when the window is empty or nothing of it is known.
    fn ratio(&self, last: UnixSeconds, t: UnixSeconds) -> f64 {
        let lo = self.times.partition_point(|&s| s <= last);
        let hi = self.times.partition_point(|&s| s < t);
        if hi <= lo {
            return 1.0;
        }
        let steps = (t.saturating_sub(last) + self.step_s - 1) / self.step_s - 1;
        let n = (steps.max(0) as usize).max(hi - lo);
        (1.0 + (self.excess[hi] - self.excess[lo]) / n as f64).max(0.0)
    }
}

/// A sensor's mean squared change `own` shrunk to the field's median `median` by weight
/// `w` in [0, 1]: `own^(1 − w) · median^w` (the unit squared).
fn shrunk(own: f64, median: f64, w: f64) -> f64 {
    if w == 0.5 {
        // The default's exact former arithmetic (the same bits as before the setting existed).
        (own * median).sqrt()
    } else {
        // 0^0 = 1: w = 0 gives `own`, w = 1 gives `median`, even where either is 0.
        own.powf(1.0 - w) * median.powf(w)
    }
}

/// Subtracts from every reading the mean of all sensors' readings at the same time, keeping only
/// times read by at least [`MIN_SENSORS_FOR_FIELD_MEAN`] sensors (unchanged when fewer sensors
/// have readings at all): what is left drifts as the sensor's own part. The field-wide part of
/// a stale sensor's change is what the reconstruction recovers from the neighbours' known
/// changes (kriging of changes), so the error a visit removes is the own part's.
fn remove_field_mean<K: std::hash::Hash + Ord>(series: &mut HashMap<K, Vec<(UnixSeconds, f64)>>) {
    if series.len() < MIN_SENSORS_FOR_FIELD_MEAN {
        return;
    }
    // Sums in the sensors' order, not the map's (seeded per map): the same bits every run.
    let mut keys: Vec<&K> = series.keys().collect();
    keys.sort_unstable();
    let mut field: HashMap<UnixSeconds, (f64, usize)> = HashMap::new();
    for k in keys {
        for &(t, x) in &series[k] {
            let e = field.entry(t).or_default();
            e.0 += x;
            e.1 += 1;
        }
    }
    for v in series.values_mut() {
        v.retain_mut(|(t, x)| match field.get(t) {
            Some(&(sum, n)) if n >= MIN_SENSORS_FOR_FIELD_MEAN => {
                *x -= sum / n as f64;
                true
            }
            _ => false,
        });
    }
}

/// Fewest sensors read at one time for the field's mean then to be removed.
const MIN_SENSORS_FOR_FIELD_MEAN: usize = 3;

/// Replaces every cell's F by its drift index divided by the largest (in [0, 1]) and
/// recomputes S with `config`. `index` in field order, one per term.
pub fn apply(
    terms: &mut [CellTerms],
    index: &[f64],
    config: &gleaner_utility::UtilityConfig,
) -> Result<()> {
    if index.len() != terms.len() {
        return Err(AppError::Invalid(format!(
            "drift index of {} cells for {} cells",
            index.len(),
            terms.len()
        )));
    }
    let top = index
        .iter()
        .copied()
        .filter(|x| x.is_finite())
        .fold(0.0, f64::max);
    for (c, &i) in terms.iter_mut().zip(index) {
        c.f = if top > 0.0 && i.is_finite() {
            (i / top).clamp(0.0, 1.0)
        } else {
            0.0
        };
        c.s = gleaner_utility::score(c.f, c.a, c.u, c.r, config);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn terms(a: f64) -> CellTerms {
        CellTerms {
            f: 0.5,
            r: 0.2,
            a,
            a_raw: a,
            u: 0.1,
            s: 0.0,
            r_by_modality: Vec::new(),
            a_by_modality: Vec::new(),
            probabilities: Vec::new(),
        }
    }

    #[test]
    fn the_field_mean_is_removed_at_times_enough_sensors_share() {
        let mut s: HashMap<&str, Vec<(UnixSeconds, f64)>> = HashMap::new();
        s.insert("a", vec![(0, 1.0), (1, 2.0), (2, 5.0)]);
        s.insert("b", vec![(0, 3.0), (1, 4.0)]);
        s.insert("c", vec![(0, 5.0), (1, 9.0)]);
        remove_field_mean(&mut s);
        // t = 0: mean 3; t = 1: mean 5; t = 2: one sensor only, dropped.
        assert_eq!(s["a"], vec![(0, -2.0), (1, -3.0)]);
        assert_eq!(s["b"], vec![(0, 0.0), (1, -1.0)]);
        assert_eq!(s["c"], vec![(0, 2.0), (1, 4.0)]);
        // A common change leaves no drift.
        let mut common: HashMap<u8, Vec<(UnixSeconds, f64)>> = (0..4u8)
            .map(|k| {
                (
                    k,
                    (0..5).map(|t| (t, f64::from(k) + 0.3 * t as f64)).collect(),
                )
            })
            .collect();
        remove_field_mean(&mut common);
        for v in common.values() {
            assert!(v.windows(2).all(|w| (w[1].1 - w[0].1).abs() < 1e-12));
        }
        // Fewer than three sensors: unchanged.
        let mut two: HashMap<u8, Vec<(UnixSeconds, f64)>> =
            (0..2u8).map(|k| (k, vec![(0, f64::from(k))])).collect();
        let before = two.clone();
        remove_field_mean(&mut two);
        assert_eq!(two, before);
    }

    #[test]
    fn a_window_holding_an_unusual_day_is_worth_more() {
        let day = 86_400;
        // Five sensors over ten days, each with its own small daily wobble; on day 6 three of
        // them rise by 10 (a rain day of very different size between stations).
        let mut series: HashMap<u8, Vec<(UnixSeconds, f64)>> = HashMap::new();
        for k in 0..5u8 {
            let mut x = 0.0;
            let v = (0..10)
                .map(|d| {
                    x += if (d + i64::from(k)) % 2 == 0 {
                        0.5
                    } else {
                        -0.5
                    } * f64::from(k + 1);
                    if d == 6 && k < 3 {
                        x += 10.0;
                    }
                    (d * day, x)
                })
                .collect();
            series.insert(k, v);
        }
        remove_field_mean(&mut series);
        let spread = KnownSpread::new(&series, day);
        // Unread since day 5, scored on day 7: the window is day 6 alone, the rain day.
        let rain = spread.ratio(5 * day, 7 * day);
        assert!(rain > 3.0, "{rain}");
        // A window of quiet days only: less than usual (the usual includes the rain day).
        assert!(spread.ratio(day, 5 * day) < 1.0);
        // Nothing between the last reading and t, or nothing known of the window: usual.
        assert_eq!(spread.ratio(7 * day, 8 * day), 1.0);
        assert_eq!(spread.ratio(9 * day, 12 * day), 1.0);
        // Quiet days in the window dilute the rain day; so do days nobody has reported yet.
        let diluted = spread.ratio(5 * day, 10 * day);
        assert!(diluted > 1.0 && diluted < rain, "{diluted}");
        let unreported = spread.ratio(5 * day, 9 * day + 3 * day);
        assert!(unreported > 1.0 && unreported < diluted, "{unreported}");
        // Fewer than three sensors: nothing is known.
        let two: HashMap<u8, _> = series.into_iter().filter(|(k, _)| *k < 2).collect();
        assert_eq!(KnownSpread::new(&two, day).ratio(5 * day, 7 * day), 1.0);
    }

    #[test]
    fn shrinking_moves_a_sensor_from_its_own_drift_to_the_fields() {
        assert_eq!(shrunk(4.0, 1.0, 0.5), 2.0);
        assert_eq!(shrunk(4.0, 1.0, 0.0), 4.0);
        assert_eq!(shrunk(4.0, 1.0, 1.0), 1.0);
        assert!((shrunk(16.0, 1.0, 0.75) - 2.0).abs() < 1e-12);
        assert_eq!(shrunk(0.0, 3.0, 1.0), 3.0);
        assert_eq!(shrunk(0.0, 3.0, 0.25), 0.0);
    }

    #[test]
    fn apply_scales_f_to_the_largest_and_rescores() {
        let config = gleaner_utility::UtilityConfig {
            score_form: gleaner_utility::ScoreForm::Gated,
            gamma: 0.0,
            delta: 0.0,
            ..gleaner_utility::UtilityConfig::default()
        };
        let mut t = vec![terms(0.0), terms(0.5), terms(0.0)];
        apply(&mut t, &[2.0, 1.0, 0.0], &config).unwrap();
        assert_eq!([t[0].f, t[1].f, t[2].f], [1.0, 0.5, 0.0]);
        assert!((t[0].s - 1.0).abs() < 1e-12);
        assert!((t[1].s - 0.75).abs() < 1e-12); // 0.5 · (1 + 0.5)
        assert_eq!(t[2].s, 0.0);
        // Nothing drifted: F = 0 everywhere.
        apply(&mut t, &[0.0; 3], &config).unwrap();
        assert!(t.iter().all(|c| c.f == 0.0 && c.s == 0.0));
        assert!(apply(&mut t, &[1.0], &config).is_err());
    }
}
