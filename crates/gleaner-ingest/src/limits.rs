//! Plausible physical ranges of reading values and times.
//!
//! A sensor file can hold anything; a value far outside what the quantity can physically take
//! (a volumetric water content of 7 m3/m3, a soil temperature of 1.7e308 degC) is a bad row,
//! not a reading, so that it cannot poison every statistic computed from it afterwards.

use std::collections::BTreeMap;

use gleaner_field::UnixSeconds;
use gleaner_field::time::days_from_civil;

use crate::default_unit;

/// Range for a value whose unit gleaner does not know: wide enough for any physical quantity
/// in a sensible unit, small enough that sums of squares over decades of readings stay finite.
pub const GENERIC_LIMIT: f64 = 1e9;

/// Earliest year a reading may carry.
pub const MIN_YEAR: i64 = 1900;
/// Latest year a reading may carry (the application also refuses readings dated after its
/// clock).
pub const MAX_YEAR: i64 = 2199;

/// The built-in plausible range of a value in `unit`, inclusive: `m3/m3` 0..=1, `%` 0..=100,
/// `degC` −60..=80, `K` 213.15..=353.15, `kPa` −1e6..=1e4 (matric potential down to oven-dry
/// soil), `mS/cm` and `dS/m` 0..=1000; any other unit ±[`GENERIC_LIMIT`].
pub fn default_range(unit: Option<&str>) -> (f64, f64) {
    match unit {
        Some("m3/m3") => (0.0, 1.0),
        Some("%") => (0.0, 100.0),
        Some("degC") => (-60.0, 80.0),
        Some("K") => (213.15, 353.15),
        Some("kPa") => (-1e6, 1e4),
        Some("mS/cm" | "dS/m") => (0.0, 1000.0),
        _ => (-GENERIC_LIMIT, GENERIC_LIMIT),
    }
}

/// User overrides of the plausible ranges, keyed by a modality's quantity (`vw`, `ec`) or by a
/// unit (`degC`); a quantity's entry wins over its unit's.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ValueLimits {
    /// `key -> (min, max)`, inclusive, in the unit of the readings.
    pub overrides: BTreeMap<String, (f64, f64)>,
}

impl ValueLimits {
    /// The inclusive range for readings of `quantity` in `unit` (the quantity's default unit
    /// when the file gives none), and the name of what the range is for (unit or quantity).
    pub fn range(&self, quantity: &str, unit: Option<&str>) -> (f64, f64, String) {
        let unit = unit.or_else(|| default_unit(quantity));
        if let Some(&(lo, hi)) = self.overrides.get(quantity) {
            return (lo, hi, unit.unwrap_or(quantity).to_string());
        }
        if let Some(u) = unit
            && let Some(&(lo, hi)) = self.overrides.get(u)
        {
            return (lo, hi, u.to_string());
        }
        let (lo, hi) = default_range(unit);
        (lo, hi, unit.unwrap_or("(no unit)").to_string())
    }

    /// Checks the overrides themselves: finite, `min <= max`; the error names the key.
    pub fn validate(&self) -> Result<(), String> {
        for (k, &(lo, hi)) in &self.overrides {
            if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
                return Err(format!(
                    "value_limits.{k} = [{lo}, {hi}]: need two finite numbers, min <= max"
                ));
            }
            if lo.abs() > 1e15 || hi.abs() > 1e15 {
                return Err(format!(
                    "value_limits.{k} = [{lo}, {hi}]: limits must lie within ±1e15"
                ));
            }
        }
        Ok(())
    }
}

/// Whether `t` lies within [`MIN_YEAR`]..=[`MAX_YEAR`].
pub fn plausible_time(t: UnixSeconds) -> bool {
    let lo = days_from_civil(MIN_YEAR, 1, 1).unwrap_or(i64::MIN / 86_400) * 86_400;
    let hi = days_from_civil(MAX_YEAR + 1, 1, 1).unwrap_or(i64::MAX / 86_400) * 86_400;
    (lo..hi).contains(&t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_by_unit_and_override() {
        let mut l = ValueLimits::default();
        assert_eq!(l.range("vw", None).0..=l.range("vw", None).1, 0.0..=1.0);
        assert_eq!(l.range("t", Some("degC")).1, 80.0);
        assert_eq!(l.range("x", None).1, GENERIC_LIMIT);
        l.overrides.insert("degC".into(), (-90.0, 100.0));
        assert_eq!(l.range("t", None).0, -90.0);
        l.overrides.insert("t".into(), (-1.0, 1.0));
        assert_eq!(l.range("t", Some("degC")).0, -1.0);
        assert!(l.validate().is_ok());
        l.overrides.insert("bad".into(), (2.0, 1.0));
        assert!(l.validate().unwrap_err().contains("value_limits.bad"));
    }

    #[test]
    fn plausible_years() {
        assert!(plausible_time(0));
        assert!(plausible_time(1_388_534_400));
        assert!(!plausible_time(253_370_764_800)); // 9999-01-01
        assert!(!plausible_time(-2_208_988_801)); // 1899-12-31T23:59:59
    }
}
