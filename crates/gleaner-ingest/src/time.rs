//! Timestamp parsing: RFC 3339, ISO dates, US `MM/DD/YYYY` dates and `H:MM` clock times, all
//! converted to [`UnixSeconds`] (UTC). Impossible dates (`2014-02-30`) are errors.

use gleaner_field::UnixSeconds;
pub use gleaner_field::time::{civil_from_days, days_from_civil, format_rfc3339};

fn digits(s: &[u8]) -> Option<i64> {
    if s.is_empty() || s.len() > 9 || !s.iter().all(u8::is_ascii_digit) {
        return None;
    }
    Some(s.iter().fold(0i64, |a, &c| a * 10 + i64::from(c - b'0')))
}

/// Parses `YYYY-MM-DD` to days since the epoch.
fn iso_date(s: &[u8]) -> Option<i64> {
    if s.len() != 10 || s[4] != b'-' || s[7] != b'-' {
        return None;
    }
    days_from_civil(
        digits(&s[0..4])?,
        digits(&s[5..7])? as u32,
        digits(&s[8..10])? as u32,
    )
}

/// Parses an RFC 3339 timestamp (`2014-01-01T06:30:00Z`, `...T06:30:00.5+02:00`; a space may
/// replace `T`; fractional seconds are truncated) or a bare date `2014-01-01` (midnight UTC).
/// A timestamp without an offset is read as UTC.
pub fn parse_timestamp(s: &str) -> Option<UnixSeconds> {
    let b = s.trim().as_bytes();
    if b.len() < 10 {
        return None;
    }
    let days = iso_date(&b[..10])?;
    if b.len() == 10 {
        return Some(days * 86_400);
    }
    if !(b[10] == b'T' || b[10] == b't' || b[10] == b' ') || b.len() < 19 {
        return None;
    }
    let (h, mi, se) = (
        digits(&b[11..13])?,
        digits(&b[14..16])?,
        digits(&b[17..19])?,
    );
    if b[13] != b':' || b[16] != b':' || h > 23 || mi > 59 || se > 60 {
        return None;
    }
    let mut rest = &b[19..];
    if rest.first() == Some(&b'.') {
        let n = rest[1..].iter().take_while(|c| c.is_ascii_digit()).count();
        if n == 0 {
            return None;
        }
        rest = &rest[1 + n..];
    }
    let offset = match rest {
        [] | [b'Z'] | [b'z'] => 0,
        [sign @ (b'+' | b'-'), oh1, oh2, b':', om1, om2] => {
            let oh = digits(&[*oh1, *oh2])?;
            let om = digits(&[*om1, *om2])?;
            if oh > 23 || om > 59 {
                return None;
            }
            let o = oh * 3600 + om * 60;
            if *sign == b'+' { o } else { -o }
        }
        _ => return None,
    };
    Some(days * 86_400 + h * 3600 + mi * 60 + se.min(59) - offset)
}

/// Parses a US date `MM/DD/YYYY` (as in the CAF daily files) to midnight UTC.
pub fn parse_us_date(s: &str) -> Option<UnixSeconds> {
    let mut it = s.trim().split('/');
    let (m, d, y) = (it.next()?, it.next()?, it.next()?);
    if it.next().is_some() || y.len() != 4 {
        return None;
    }
    let days = days_from_civil(
        digits(y.as_bytes())?,
        digits(m.as_bytes())? as u32,
        digits(d.as_bytes())? as u32,
    )?;
    Some(days * 86_400)
}

/// Parses a date column (`YYYY-MM-DD` or `MM/DD/YYYY`) to midnight UTC.
pub fn parse_date(s: &str) -> Option<UnixSeconds> {
    let t = s.trim();
    iso_date(t.as_bytes())
        .map(|d| d * 86_400)
        .or_else(|| parse_us_date(t))
}

/// Parses a clock time `H:MM` or `HH:MM:SS` to seconds after midnight.
pub fn parse_clock(s: &str) -> Option<i64> {
    let mut it = s.trim().split(':');
    let h = digits(it.next()?.as_bytes())?;
    let m = digits(it.next()?.as_bytes())?;
    let sec = match it.next() {
        Some(x) => digits(x.as_bytes())?,
        None => 0,
    };
    if it.next().is_some() || h > 23 || m > 59 || sec > 59 {
        return None;
    }
    Some(h * 3600 + m * 60 + sec)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn check(input: &str, expected: Option<i64>) {
        assert_eq!(parse_timestamp(input), expected, "{input:?}");
    }

    #[test]
    fn rfc3339_cases() {
        check("1970-01-01T00:00:00Z", Some(0));
        check("2014-01-01", Some(1_388_534_400));
        check("2014-01-01T00:00:00Z", Some(1_388_534_400));
        check("2014-01-01 01:00:00", Some(1_388_538_000));
        check("2014-01-01T02:00:00+02:00", Some(1_388_534_400));
        check("2014-01-01T00:00:00.999-00:30", Some(1_388_536_200));
        check("2016-02-29T00:00:00Z", Some(1_456_704_000));
        check("2014-02-29T00:00:00Z", None);
        check("2014-02-30", None);
        check("2014-13-01", None);
        check("2014-01-01T24:00:00Z", None);
        check("2014-01-01T00:00:00+2:00", None);
        check("2014-1-1", None);
        check("yesterday", None);
        check("", None);
    }

    #[test]
    fn us_dates_and_clocks() {
        assert_eq!(parse_us_date("04/20/2007"), Some(1_177_027_200));
        assert_eq!(parse_us_date("02/30/2007"), None);
        assert_eq!(parse_date("2015-01-01"), Some(1_420_070_400));
        assert_eq!(parse_clock("9:00"), Some(32_400));
        assert_eq!(parse_clock("23:59:59"), Some(86_399));
        assert_eq!(parse_clock("24:00"), None);
        assert_eq!(format_rfc3339(1_388_538_000), "2014-01-01T01:00:00Z");
    }

    proptest! {
        #[test]
        fn format_parse_round_trip(t in -62_000_000_000i64..253_000_000_000) {
            prop_assert_eq!(parse_timestamp(&format_rfc3339(t)), Some(t));
        }
    }
}
