//! Drift: how fast a sensor's value wanders away from its last collected reading, and what a
//! visit is worth because of it.
//!
//! The error of carrying a sensor's last collected value forward grows with the time since
//! it was collected, at a rate of the sensor's own: on CAF the root-mean-square one-day change
//! of the 30 cm soil moisture ranges from 2.7 to 26.7 ×10⁻³ m³/m³ between stations (a
//! factor of 95 in variance). A freshness term that treats every cell alike (F, one
//! half-life for all) spends visits on cells whose value has hardly moved.
//!
//! - [`mean_squared_change`]: the empirical structure function D(h) = mean over pairs of
//!   (x(t + h) − x(t))² of one series on a regular grid, for lags h = 1..H grid steps (the
//!   expected squared error of the value carried forward h steps), in the value's unit squared.
//! - [`staleness_index`]: the index a·D(a) − ∫₀ᵃ D(h) dh of a sensor last collected a steps
//!   ago. For a wandering value (D(h) = v·h) it is v·a²/2: the Whittle index of the age of
//!   information with a linear cost, whose visiting rule gives each sensor a revisit interval
//!   ∝ 1/√v — the schedule that minimises the time-averaged squared error of the carried-forward
//!   values for a given number of visits. Where D stops growing the index stops growing too (it is
//!   constant past the last lag H, at H·D(H) − ∫₀ᴴ D): a value that has wandered as far as it
//!   ever does is not worth more for waiting longer. Units: the value's unit squared × grid steps.

use gleaner_field::UnixSeconds;

/// The empirical mean squared change of one series at lags 1..=`max_lag` grid steps of
/// `step_s` seconds: entry k − 1 is the mean of (x(t + k·step) − x(t))² over every pair of
/// points exactly k steps apart, or `None` with fewer than `min_pairs` pairs (value unit²).
///
/// `times` must be ascending (seconds); points off the grid most of them share (phase
/// [`gleaner_field::time::grid_phase`]) are ignored, as are non-finite values; with `step_s <= 0` every lag is `None`.
pub fn mean_squared_change(
    times: &[UnixSeconds],
    values: &[f64],
    step_s: i64,
    max_lag: usize,
    min_pairs: usize,
) -> Vec<Option<f64>> {
    let mut out = vec![None; max_lag];
    let (Some(&first), true) = (times.first(), step_s > 0) else {
        return out;
    };
    // The grid of most readings (a few off it, e.g. a logger's first readings at :15 before it
    // settles on the hour, are left out instead of all the others).
    let phase = gleaner_field::time::grid_phase(times.iter().copied(), step_s);
    let t0 = gleaner_field::time::grid_floor(first, step_s, phase);
    // The series as grid slots (index from t0), only exact grid points with finite values.
    let mut slots: Vec<(i64, f64)> = times
        .iter()
        .zip(values)
        .filter(|(t, v)| v.is_finite() && (**t - t0) % step_s == 0)
        .map(|(t, v)| ((*t - t0) / step_s, *v))
        .collect();
    slots.dedup_by_key(|p| p.0);
    let Some(&(last, _)) = slots.last() else {
        return out;
    };
    let mut grid = vec![f64::NAN; (last + 1) as usize];
    for (k, v) in &slots {
        grid[*k as usize] = *v;
    }
    for (lag, o) in out.iter_mut().enumerate() {
        let h = lag + 1;
        let (mut sum, mut n) = (0.0, 0usize);
        for i in 0..grid.len().saturating_sub(h) {
            let d = grid[i + h] - grid[i];
            if d.is_finite() {
                sum += d * d;
                n += 1;
            }
        }
        if n >= min_pairs.max(1) {
            *o = Some(sum / n as f64);
        }
    }
    out
}

/// The staleness index a·D(a) − ∫₀ᵃ D(h) dh of a sensor last collected `age_steps` grid
/// steps ago, with D the structure function `d` (entry k − 1 at lag k, value unit²), taken as
/// D(0) = 0, made non-decreasing (a running maximum), interpolated linearly between lags and
/// held constant after the last one. Unit: value unit² × grid steps; 0 for `age_steps <= 0`
/// or an empty `d`; never negative. See the module docs.
pub fn staleness_index(d: &[f64], age_steps: f64) -> f64 {
    if age_steps.is_nan() || age_steps <= 0.0 || d.is_empty() {
        return 0.0;
    }
    // Running maximum, non-finite entries skipped.
    let mut at = Vec::with_capacity(d.len() + 1);
    at.push(0.0f64);
    for &x in d {
        let prev = *at.last().unwrap_or(&0.0);
        at.push(if x.is_finite() { prev.max(x) } else { prev });
    }
    let h_max = (at.len() - 1) as f64;
    let value_at = |h: f64| -> f64 {
        if h >= h_max {
            return at[at.len() - 1];
        }
        let k = h.floor() as usize;
        let f = h - k as f64;
        at[k] + f * (at[k + 1] - at[k])
    };
    // ∫₀ᵃ D: whole trapezoids, then the last partial one, then the flat tail.
    let a = age_steps;
    let whole = a.min(h_max).floor() as usize;
    let mut integral = 0.0;
    for k in 0..whole {
        integral += 0.5 * (at[k] + at[k + 1]);
    }
    let part = a.min(h_max) - whole as f64;
    if part > 0.0 {
        integral += 0.5 * part * (at[whole] + value_at(a.min(h_max)));
    }
    if a > h_max {
        integral += (a - h_max) * at[at.len() - 1];
    }
    (a * value_at(a) - integral).max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    const DAY: i64 = 86_400;

    #[test]
    fn a_random_walk_has_a_linear_structure_function() {
        // Steps of ±1 alternating in pairs: x = 0, 1, 2, 1, 0, 1, 2, ...
        let v: Vec<f64> = (0..400).map(|i| [0.0, 1.0, 2.0, 1.0][i % 4]).collect();
        let t: Vec<i64> = (0..400).map(|i| i as i64 * DAY).collect();
        let d = mean_squared_change(&t, &v, DAY, 4, 10);
        assert_eq!(d[0], Some(1.0));
        assert_eq!(d[1], Some(2.0)); // (2-0)², (1-1)², (0-2)², (1-1)²: mean 2
        assert_eq!(d[3], Some(0.0)); // period 4
    }

    #[test]
    fn gaps_and_off_grid_points_are_left_out() {
        let t = [0, DAY, 2 * DAY + 5, 3 * DAY, 5 * DAY];
        let v = [0.0, 1.0, 100.0, 3.0, f64::NAN];
        let d = mean_squared_change(&t, &v, DAY, 3, 1);
        assert_eq!(d[0], Some(1.0)); // only (0,1)
        assert_eq!(d[1], Some(4.0)); // only (1,3)
        assert_eq!(d[2], Some(9.0)); // only (0,3)
        assert_eq!(mean_squared_change(&t, &v, DAY, 3, 2)[0], None);
        assert_eq!(mean_squared_change(&[], &[], DAY, 2, 1), vec![None, None]);
        assert_eq!(mean_squared_change(&t, &v, 0, 1, 1), vec![None]);
    }

    #[test]
    fn the_index_of_a_linear_structure_function_is_half_v_a_squared() {
        let v = 3.0;
        let d: Vec<f64> = (1..=50).map(|h| v * h as f64).collect();
        for a in [0.5, 1.0, 2.0, 7.25, 30.0] {
            let got = staleness_index(&d, a);
            assert!((got - v * a * a / 2.0).abs() < 1e-9, "a = {a}: {got}");
        }
        // Past the last lag D is held, and so is the index.
        let h = 50.0;
        let tail = staleness_index(&d, h + 10.0) - staleness_index(&d, h);
        assert!(tail.abs() < 1e-6, "{tail}");
        // A saturating D: the index rises while D does.
        let sat = [1.0, 1.5, 1.75, 1.75];
        assert!((staleness_index(&sat, 1.0) - 0.5).abs() < 1e-12);
        assert!((staleness_index(&sat, 3.0) - (3.0 * 1.75 - (0.5 + 1.25 + 1.625))).abs() < 1e-12);
        assert_eq!(staleness_index(&d, 0.0), 0.0);
        assert_eq!(staleness_index(&[], 5.0), 0.0);
    }

    #[test]
    fn a_first_reading_off_the_grid_does_not_hide_the_rest() {
        // Hourly on the hour after one reading at :15: the lag-1 change is that of the rest.
        let times = [900, 3_600, 7_200, 10_800, 14_400];
        let values = [9.0, 1.0, 2.0, 3.0, 4.0];
        let d = mean_squared_change(&times, &values, 3_600, 2, 1);
        assert_eq!(d, vec![Some(1.0), Some(4.0)]);
    }

    proptest! {
        #[test]
        fn the_index_never_decreases_with_age_and_scales_with_d(
            d in proptest::collection::vec(0.0f64..10.0, 1..40),
            a in 0.0f64..60.0,
            da in 0.0f64..10.0,
            k in 0.1f64..10.0,
        ) {
            let i = staleness_index(&d, a);
            prop_assert!(i >= 0.0);
            prop_assert!(staleness_index(&d, a + da) >= i - 1e-9);
            let scaled: Vec<f64> = d.iter().map(|x| k * x).collect();
            prop_assert!((staleness_index(&scaled, a) - k * i).abs() <= 1e-9 * (1.0 + k * i));
        }
    }
}
