//! The times a request gives (a mission's time, a collection's time), checked and resolved
//! once, the same way by every use case.
//!
//! A given time must lie within the years readings may carry (1900..=2199, see
//! [`gleaner_ingest::limits`]): 0001-01-01 or 9999-12-31 is a typing error, not a mission.
//! A time not given is the latest known reading; without any reading there is no default
//! and the use case refuses (it never falls back to the wall clock, which is provenance only).

use gleaner_field::UnixSeconds;
use gleaner_ingest::limits::{MAX_YEAR, MIN_YEAR, plausible_time};
use gleaner_ingest::time::format_rfc3339;

use crate::error::{AppError, Result};

/// Refuses a given time outside the years [`MIN_YEAR`]..=[`MAX_YEAR`]; `what` names it in
/// the error (e.g. `mission time`).
pub fn check(what: &str, t: Option<UnixSeconds>) -> Result<()> {
    match t {
        Some(t) if !plausible_time(t) => Err(AppError::Invalid(format!(
            "{what} {}: outside the years {MIN_YEAR}..={MAX_YEAR} gleaner accepts",
            // Calendar arithmetic is only asked of years it can hold.
            if t.unsigned_abs() < 10_000_000_000_000 {
                format_rfc3339(t)
            } else {
                format!("{t} s after 1970")
            }
        ))),
        _ => Ok(()),
    }
}

/// The mission time of a request: the given one (checked by [`check`]), else the latest
/// known reading; refused when neither exists.
pub fn mission_time(at: Option<UnixSeconds>, latest: Option<UnixSeconds>) -> Result<UnixSeconds> {
    check("mission time", at)?;
    at.or(latest).ok_or_else(|| {
        AppError::Invalid(
            "no mission time given and no readings to take it from: ingest readings first, \
             or give the mission time"
                .into(),
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use gleaner_ingest::time::parse_timestamp;

    fn t(s: &str) -> UnixSeconds {
        parse_timestamp(s).expect("a time")
    }

    #[test]
    fn absurd_times_are_refused_and_plausible_ones_kept() {
        for bad in [
            "0001-01-01",
            "9999-12-31",
            "1899-12-31T23:59:59Z",
            "2200-01-01",
        ] {
            let err = check("mission time", Some(t(bad)))
                .expect_err(bad)
                .to_string();
            assert!(
                err.contains("outside the years 1900..=2199"),
                "{bad}: {err}"
            );
        }
        for good in ["1900-01-01", "2014-03-01", "2199-12-31T23:59:59Z"] {
            check("mission time", Some(t(good))).expect(good);
        }
        check("mission time", None).expect("nothing given");
    }

    #[test]
    fn a_time_not_given_is_the_latest_reading_else_refused() {
        assert_eq!(mission_time(None, Some(5)).expect("latest"), 5);
        assert_eq!(
            mission_time(Some(t("2014-03-01")), Some(5)).expect("given"),
            t("2014-03-01")
        );
        let err = mission_time(None, None).expect_err("no time").to_string();
        assert!(err.contains("no mission time given"), "{err}");
        assert!(mission_time(Some(t("0001-01-01")), Some(5)).is_err());
    }
}
