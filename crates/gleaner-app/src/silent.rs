//! Silent sensors: a sensor whose last recorded collection brought none of its readings back
//! (down, a flat battery, a cut cable) is likely to be silent at the next visit too — on CAF an
//! outage lasts 57 days on average — so a cell is worth its score S times the chance that its
//! sensors deliver (docs/method.md §2, "silent sensors").
//!
//! A sensor is *silent* when it has a recorded collection at time c ≤ t and its latest stored
//! reading (any modality) is more than two sampling steps (at least two days) older than c, or
//! it has none. Its chance to deliver at t is 1 − (1 − r)^((t − c) / 1 day), r the revival
//! rate per day ([`crate::settings::UtilitySection::silent_revival_per_day`]): outages end at a
//! constant rate. A sensor never collected, or whose last collection brought data, delivers
//! with chance 1. A cell's factor is the mean over its sensors (1 for a cell without sensors).

use std::collections::HashMap;

use gleaner_field::{SensorId, UnixSeconds};
use gleaner_store::Store;

use crate::error::Result;
use crate::knowledge::Knowledge;
use crate::project::Project;

/// Seconds in a day.
const DAY_S: f64 = 86_400.0;

/// Per cell in field order: the chance its sensors deliver at `t` (mean over its sensors, in
/// [0, 1]), and the number of silent sensors. `revival_per_day` in [0, 1] (1/day).
pub(crate) fn delivery<S: Store>(
    project: &Project<S>,
    knowledge: &Knowledge,
    t: UnixSeconds,
    revival_per_day: f64,
) -> Result<(Vec<f64>, usize)> {
    let store = project.store();
    let mut collected: HashMap<SensorId, UnixSeconds> = HashMap::new();
    for (id, at) in store.sensor_last_collected()? {
        if at <= t {
            let e = collected.entry(id).or_insert(at);
            *e = (*e).max(at);
        }
    }
    let mut latest: HashMap<SensorId, UnixSeconds> = HashMap::new();
    for m in store.modalities()? {
        for (id, at, _) in store.latest_readings(&m.modality, UnixSeconds::MIN..=t)? {
            let e = latest.entry(id).or_insert(at);
            *e = (*e).max(at);
        }
    }
    let step = step_s(knowledge);
    let chances: Vec<f64> = knowledge
        .sensors
        .iter()
        .map(|s| {
            chance(
                collected.get(&s.id).copied(),
                latest.get(&s.id).copied(),
                t,
                step,
                revival_per_day,
            )
        })
        .collect();
    let silent = chances.iter().filter(|&&p| p < 1.0).count();
    let cells = knowledge
        .field
        .cells()
        .iter()
        .map(|c| {
            if c.sensors.is_empty() {
                1.0
            } else {
                c.sensors.iter().map(|&s| chances[s]).sum::<f64>() / c.sensors.len() as f64
            }
        })
        .collect();
    Ok((cells, silent))
}

/// One sensor's chance to deliver at `t` (see the module's doc): `collected` its last recorded
/// collection, `latest` its latest reading, `step` the sampling step (s).
fn chance(
    collected: Option<UnixSeconds>,
    latest: Option<UnixSeconds>,
    t: UnixSeconds,
    step: i64,
    revival_per_day: f64,
) -> f64 {
    let Some(c) = collected else {
        return 1.0;
    };
    let slack = 2 * step.max(86_400);
    if latest.is_some_and(|l| c.saturating_sub(l) <= slack) {
        return 1.0;
    }
    let days = (t.saturating_sub(c)).max(0) as f64 / DAY_S;
    let r = revival_per_day.clamp(0.0, 1.0);
    1.0 - (1.0 - r).powf(days)
}

/// The sampling step of what is known (s): the median spacing of the cells' first series.
fn step_s(knowledge: &Knowledge) -> i64 {
    let times: Vec<Vec<UnixSeconds>> = knowledge
        .series
        .iter()
        .filter_map(|c| c.first())
        .map(|s| s.times.clone())
        .collect();
    crate::knowledge::sampling_step(&times)
}

#[cfg(test)]
mod tests {
    use super::*;

    const D: i64 = 86_400;

    #[test]
    fn a_sensor_that_delivered_or_was_never_collected_counts_in_full() {
        assert_eq!(chance(None, None, 100 * D, D, 0.02), 1.0);
        assert_eq!(chance(None, Some(D), 100 * D, D, 0.02), 1.0);
        // Collected on day 10, its latest reading stamped day 9: it delivered.
        assert_eq!(chance(Some(10 * D), Some(9 * D), 30 * D, D, 0.02), 1.0);
        // Two days of slack (e.g. a reading held back a day).
        assert_eq!(chance(Some(10 * D), Some(8 * D), 30 * D, D, 0.02), 1.0);
    }

    #[test]
    fn a_silent_sensor_comes_back_at_the_revival_rate() {
        // Collected on day 10, nothing since day 5: silent.
        let p = |t: i64| chance(Some(10 * D), Some(5 * D), t, D, 0.02);
        assert_eq!(p(10 * D), 0.0);
        assert!((p(11 * D) - 0.02).abs() < 1e-12);
        assert!((p(40 * D) - (1.0 - 0.98f64.powi(30))).abs() < 1e-12);
        assert!(p(20 * D) < p(40 * D) && p(40 * D) < 1.0);
        // Never read at all but collected: silent too.
        assert_eq!(chance(Some(10 * D), None, 10 * D, D, 0.02), 0.0);
        // Rate 1: back the next day; rate 0: never.
        assert_eq!(chance(Some(10 * D), None, 11 * D, D, 1.0), 1.0);
        assert_eq!(chance(Some(10 * D), None, 900 * D, D, 0.0), 0.0);
        // Hourly data: the slack is still two days.
        assert_eq!(chance(Some(10 * D), Some(8 * D + 1), 12 * D, 3_600, 0.5), 1.0);
        assert!(chance(Some(10 * D), Some(7 * D), 12 * D, 3_600, 0.5) < 1.0);
    }
}
