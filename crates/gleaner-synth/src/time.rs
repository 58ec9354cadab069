//! Calendar arithmetic on [`UnixSeconds`] (proleptic Gregorian, UTC) without a date crate.

use gleaner_field::UnixSeconds;

/// (year, month 1..=12, day 1..=31) of a day count since 1970-01-01 (days-from-civil inverse,
/// after the era-based method popularised by H. Hinnant).
pub(crate) fn civil_from_days(days: i64) -> (i64, u32, u32) {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let m = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    let y = yoe + era * 400 + i64::from(m <= 2);
    (y, m, d)
}

/// Day count since 1970-01-01 of a civil date.
pub(crate) fn days_from_civil(y: i64, m: u32, d: u32) -> i64 {
    let y = if m <= 2 { y - 1 } else { y };
    let era = y.div_euclid(400);
    let yoe = y.rem_euclid(400);
    let m = i64::from(m);
    let doy = (153 * (if m > 2 { m - 3 } else { m + 9 }) + 2) / 5 + i64::from(d) - 1;
    let doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    era * 146_097 + doe - 719_468
}

/// Fractional day of year (0 at 1 January 00:00 UTC), days.
pub(crate) fn day_of_year(t: UnixSeconds) -> f64 {
    let days = t.div_euclid(86_400);
    let (y, _, _) = civil_from_days(days);
    let jan1 = days_from_civil(y, 1, 1);
    (days - jan1) as f64 + t.rem_euclid(86_400) as f64 / 86_400.0
}

/// RFC 3339 UTC text, `YYYY-MM-DDTHH:MM:SSZ` (20 bytes), for years 0..=9999.
pub(crate) fn rfc3339(t: UnixSeconds) -> String {
    let (y, mo, d) = civil_from_days(t.div_euclid(86_400));
    let s = t.rem_euclid(86_400);
    format!(
        "{y:04}-{mo:02}-{d:02}T{:02}:{:02}:{:02}Z",
        s / 3600,
        s / 60 % 60,
        s % 60
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(t: UnixSeconds, text: &str, doy: f64) {
        assert_eq!(rfc3339(t), text);
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
        check(1_451_606_400 - 86_400, "2015-12-31T00:00:00Z", 364.0);
    }

    #[test]
    fn civil_round_trip() {
        for days in (-800_000..800_000).step_by(997) {
            let (y, m, d) = civil_from_days(days);
            assert_eq!(days_from_civil(y, m, d), days);
        }
    }
}
