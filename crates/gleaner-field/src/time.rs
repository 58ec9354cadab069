//! Calendar arithmetic on [`UnixSeconds`] (proleptic Gregorian calendar, UTC), without a date
//! crate: civil dates, day of year and RFC 3339 text.

use crate::UnixSeconds;

/// Days since 1970-01-01 of a proleptic Gregorian date, or `None` when the date does not
/// exist (month outside 1..=12, day outside the month, year outside 1..=9999).
pub fn days_from_civil(year: i64, month: u32, day: u32) -> Option<i64> {
    if !(1..=9999).contains(&year) || !(1..=12).contains(&month) || day == 0 {
        return None;
    }
    let leap = (year % 4 == 0 && year % 100 != 0) || year % 400 == 0;
    let dim = [
        31,
        if leap { 29 } else { 28 },
        31,
        30,
        31,
        30,
        31,
        31,
        30,
        31,
        30,
        31,
    ];
    if day > dim[month as usize - 1] {
        return None;
    }
    // Days-from-civil in the era-based form (eras of 400 years, March-based years).
    let y = if month <= 2 { year - 1 } else { year };
    let era = y.div_euclid(400);
    let yoe = y - era * 400;
    let m = i64::from(month);
    let mp = if m > 2 { m - 3 } else { m + 9 };
    let doy = (153 * mp + 2) / 5 + i64::from(day) - 1;
    let doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    Some(era * 146_097 + doe - 719_468)
}

/// The civil date (year, month, day) of a day count since 1970-01-01.
pub fn civil_from_days(days: i64) -> (i64, u32, u32) {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let m = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    let y = yoe + era * 400 + i64::from(m <= 2);
    (y, m, d)
}

/// Formats `t` as RFC 3339 UTC, e.g. `2014-01-01T00:00:00Z`.
pub fn format_rfc3339(t: UnixSeconds) -> String {
    let days = t.div_euclid(86_400);
    let secs = t.rem_euclid(86_400);
    let (y, m, d) = civil_from_days(days);
    format!(
        "{y:04}-{m:02}-{d:02}T{:02}:{:02}:{:02}Z",
        secs / 3600,
        (secs / 60) % 60,
        secs % 60
    )
}

/// Fractional day of the year, days: 0 at 1 January 00:00 UTC.
pub fn day_of_year(t: UnixSeconds) -> f64 {
    let days = t.div_euclid(86_400);
    let (y, _, _) = civil_from_days(days);
    let jan1 = days_from_civil(y, 1, 1).unwrap_or(days);
    (days - jan1) as f64 + t.rem_euclid(86_400) as f64 / 86_400.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn check(t: UnixSeconds, text: &str, doy: f64) {
        assert_eq!(format_rfc3339(t), text);
        assert!(
            (day_of_year(t) - doy).abs() < 1e-9,
            "{t}: {}",
            day_of_year(t)
        );
    }

    #[test]
    fn known_dates() {
        check(0, "1970-01-01T00:00:00Z", 0.0);
        check(1_388_534_400, "2014-01-01T00:00:00Z", 0.0);
        check(
            1_388_534_400 + 86_400 * 59 + 43_200,
            "2014-03-01T12:00:00Z",
            59.5,
        );
        check(951_782_400, "2000-02-29T00:00:00Z", 59.0);
        check(-1, "1969-12-31T23:59:59Z", 364.0 + 86_399.0 / 86_400.0);
        assert_eq!(days_from_civil(2014, 2, 29), None);
        assert_eq!(days_from_civil(2016, 2, 29), Some(16_860));
    }

    proptest! {
        #[test]
        fn civil_round_trip(days in -700_000i64..2_900_000) {
            let (y, m, d) = civil_from_days(days);
            prop_assert_eq!(days_from_civil(y, m, d), Some(days));
        }
    }
}

/// The most common phase of `times` on a grid of `step_s` seconds, in `0..step_s` (ties: the
/// smallest; 0 without times or with `step_s <= 0`). A series logged on the hour with a few
/// readings at :15 (Hubbard Brook's first days) has phase 0: gridding from the first reading
/// would leave every later one off the grid.
pub fn grid_phase(times: impl IntoIterator<Item = UnixSeconds>, step_s: i64) -> UnixSeconds {
    if step_s <= 0 {
        return 0;
    }
    let mut counts: std::collections::HashMap<i64, usize> = std::collections::HashMap::new();
    for t in times {
        *counts.entry(t.rem_euclid(step_s)).or_default() += 1;
    }
    counts
        .into_iter()
        .max_by_key(|&(phase, n)| (n, std::cmp::Reverse(phase)))
        .map_or(0, |(phase, _)| phase)
}

/// The latest time on the grid of `step_s` seconds with `phase` at or before `t`.
pub fn grid_floor(t: UnixSeconds, step_s: i64, phase: UnixSeconds) -> UnixSeconds {
    if step_s <= 0 {
        return t;
    }
    t - (t - phase).rem_euclid(step_s)
}

#[cfg(test)]
mod grid_tests {
    use super::*;

    #[test]
    fn the_grid_follows_most_readings() {
        // Two readings at :15, then on the hour.
        let times = [900, 4_500, 7_200, 10_800, 14_400];
        assert_eq!(grid_phase(times, 3_600), 0);
        assert_eq!(grid_floor(900, 3_600, 0), 0);
        assert_eq!(grid_floor(-900, 3_600, 0), -3_600);
        assert_eq!(grid_floor(7_200, 3_600, 0), 7_200);
        assert_eq!(grid_phase([5, 5, 7, 7], 10), 5);
        assert_eq!(grid_phase([], 10), 0);
        assert_eq!(grid_phase([5], 0), 0);
    }
}
