//! Sensors and modalities.

use std::fmt;

use crate::{FieldError, LatLon};

/// A sensor's identifier as the network names it (e.g. `CAF003`): non-empty, at most 128
/// characters, no control characters, no surrounding whitespace.
#[derive(Debug, Clone, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct SensorId(String);

impl SensorId {
    /// Validates and wraps an identifier.
    pub fn new(id: impl Into<String>) -> Result<Self, FieldError> {
        let id = id.into();
        if id.is_empty()
            || id.chars().count() > 128
            || id.chars().any(char::is_control)
            || id.trim() != id
        {
            return Err(FieldError::InvalidSensorId(id));
        }
        Ok(Self(id))
    }
    /// The identifier as text.
    pub fn as_str(&self) -> &str {
        &self.0
    }
}

impl fmt::Display for SensorId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

/// A measured quantity, optionally at a depth: `vw@30cm` (volumetric water at 30 cm),
/// `t@150cm`, `vwc-a@15cm`, `vw@15.5cm`, `vwc@0.15m`, `humidity`.
///
/// The grammar, after lower-casing and trimming: `quantity[@depth]`, where
///
/// - `quantity` is 1 to 64 ASCII letters, digits, `-` or `_`, starting with a letter;
/// - `depth` is a decimal number — digits, optionally followed by `.` and more digits (no
///   sign, no exponent, at most 16 characters) — and the unit `cm` or `m`.
///
/// The name is kept as written (`vwc@0.15m` and `vwc@15cm` are different modalities, as the
/// networks name them); [`Modality::depth_cm`] gives the depth as a number. The unit of the
/// measured value is carried beside the modality, not in it.
#[derive(Debug, Clone, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Modality(String);

/// Longest quantity name, characters.
const MAX_QUANTITY: usize = 64;
/// Longest depth number (before the unit), characters.
const MAX_DEPTH_NUMBER: usize = 16;

/// Parses a depth `<decimal>cm` or `<decimal>m` into centimetres.
fn parse_depth_cm(depth: &str) -> Option<f64> {
    let (number, cm_per_unit) = if let Some(n) = depth.strip_suffix("cm") {
        (n, 1.0)
    } else {
        (depth.strip_suffix('m')?, 100.0)
    };
    let (whole, fraction) = match number.split_once('.') {
        Some((w, f)) => (w, Some(f)),
        None => (number, None),
    };
    let digits = |t: &str| !t.is_empty() && t.bytes().all(|b| b.is_ascii_digit());
    if number.len() > MAX_DEPTH_NUMBER || !digits(whole) || fraction.is_some_and(|f| !digits(f)) {
        return None;
    }
    // At most 16 digits: always finite.
    number.parse::<f64>().ok().map(|v| v * cm_per_unit)
}

impl Modality {
    /// Parses and validates a modality name (see the type's docs). Upper-case input is
    /// lower-cased: `VW@30cm` is `vw@30cm`.
    ///
    /// # Errors
    /// [`FieldError::InvalidModality`], whose message states the grammar.
    pub fn new(name: &str) -> Result<Self, FieldError> {
        let lower = name.trim().to_ascii_lowercase();
        let bad = || FieldError::InvalidModality(name.to_string());
        let (quantity, depth) = match lower.split_once('@') {
            Some((q, d)) => (q, Some(d)),
            None => (lower.as_str(), None),
        };
        let quantity_ok = !quantity.is_empty()
            && quantity.len() <= MAX_QUANTITY
            && quantity
                .bytes()
                .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == b'_' || c == b'-')
            && quantity.starts_with(|c: char| c.is_ascii_lowercase());
        if !quantity_ok {
            return Err(bad());
        }
        if let Some(d) = depth {
            parse_depth_cm(d).ok_or_else(bad)?;
        }
        Ok(Self(lower))
    }
    /// A modality from a quantity and a depth in whole centimetres: `("vw", Some(30))` is
    /// `vw@30cm`.
    pub fn at_depth(quantity: &str, depth_cm: Option<u32>) -> Result<Self, FieldError> {
        match depth_cm {
            Some(d) => Self::new(&format!("{quantity}@{d}cm")),
            None => Self::new(quantity),
        }
    }
    /// The full name, e.g. `vw@30cm`.
    pub fn as_str(&self) -> &str {
        &self.0
    }
    /// The quantity, e.g. `vw`.
    pub fn quantity(&self) -> &str {
        self.0.split('@').next().unwrap_or(&self.0)
    }
    /// The depth in centimetres, if the modality has one (`vwc@0.15m` gives 15.0).
    pub fn depth_cm(&self) -> Option<f64> {
        parse_depth_cm(self.0.split_once('@')?.1)
    }
}

impl fmt::Display for Modality {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

/// A static sensor station: its id, WGS84 position and optional elevation (metres above the
/// ellipsoid or the network's vertical datum, as supplied).
#[derive(Debug, Clone, PartialEq)]
pub struct Sensor {
    /// The station's identifier.
    pub id: SensorId,
    /// WGS84 position, degrees.
    pub position: LatLon,
    /// Elevation, metres, when known.
    pub elevation_m: Option<f64>,
}

impl Sensor {
    /// A sensor with no elevation.
    pub fn new(id: SensorId, position: LatLon) -> Self {
        Self {
            id,
            position,
            elevation_m: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn modality_parsing() {
        let m = Modality::new("VW@30cm").unwrap();
        assert_eq!(m.as_str(), "vw@30cm");
        assert_eq!(m.quantity(), "vw");
        assert_eq!(m.depth_cm(), Some(30.0));
        assert_eq!(Modality::new("humidity").unwrap().depth_cm(), None);
        for bad in [
            "",
            "@30cm",
            "vw@",
            "vw@30",
            "vw@xcm",
            "v w",
            "9vw",
            "-vw",
            "vw@30cm@1cm",
            "vw@cm",
            "vw@m",
            "vw@.5cm",
            "vw@15.cm",
            "vw@1.2.3cm",
            "vw@-5cm",
            "vw@+5cm",
            "vw@1e3cm",
            "vw@30mm",
            "vw@30 cm",
            "vw@nancm",
            "vw@infm",
            "vw@12345678901234567cm",
            "vw.a@30cm",
        ] {
            assert!(Modality::new(bad).is_err(), "{bad:?} accepted");
        }
        assert_eq!(
            Modality::at_depth("t", Some(150)).unwrap().as_str(),
            "t@150cm"
        );
    }

    #[test]
    fn real_network_modalities_are_accepted() {
        for (name, quantity, depth) in [
            ("vwc-a@15cm", "vwc-a", Some(15.0)),
            ("vw@15.5cm", "vw", Some(15.5)),
            ("vwc@0.15m", "vwc", Some(15.0)),
            ("VWC@0.15M", "vwc", Some(15.0)),
            ("soil_temp-2@100cm", "soil_temp-2", Some(100.0)),
            ("vw@0cm", "vw", Some(0.0)),
            ("vw@1m", "vw", Some(100.0)),
            ("rh", "rh", None),
        ] {
            let m = Modality::new(name).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_eq!(m.quantity(), quantity, "{name}");
            let d = m.depth_cm();
            match (d, depth) {
                (Some(a), Some(b)) => assert!((a - b).abs() < 1e-9, "{name}: {a} vs {b}"),
                (a, b) => assert_eq!(a, b, "{name}"),
            }
        }
        // Kept as written, lower-cased.
        assert_eq!(Modality::new("VWC@0.15M").unwrap().as_str(), "vwc@0.15m");
    }

    #[test]
    fn the_error_states_the_grammar() {
        let msg = Modality::new("vw@30in").unwrap_err().to_string();
        for part in [
            "vw@30in",
            "letters, digits, `-` or `_`",
            "`cm` or `m`",
            "vwc@0.15m",
        ] {
            assert!(msg.contains(part), "{msg:?} lacks {part:?}");
        }
    }

    proptest! {
        #[test]
        fn valid_names_round_trip(
            q in "[a-z][a-z0-9_-]{0,20}",
            whole in 0u32..100_000,
            frac in proptest::option::of("[0-9]{1,4}"),
            metres in any::<bool>(),
        ) {
            let number = match &frac { Some(f) => format!("{whole}.{f}"), None => whole.to_string() };
            let unit = if metres { "m" } else { "cm" };
            let name = format!("{q}@{number}{unit}");
            let m = Modality::new(&name).unwrap();
            prop_assert_eq!(m.as_str(), name.as_str());
            prop_assert_eq!(m.quantity(), q.as_str());
            let expected = number.parse::<f64>().unwrap() * if metres { 100.0 } else { 1.0 };
            prop_assert_eq!(m.depth_cm(), Some(expected));
            prop_assert_eq!(Modality::new(m.as_str()).unwrap(), m);
        }

        #[test]
        fn arbitrary_text_never_panics(s in "\\PC{0,40}") {
            if let Ok(m) = Modality::new(&s) {
                prop_assert!(m.depth_cm().is_none_or(f64::is_finite));
            }
        }
    }

    #[test]
    fn sensor_id_validation() {
        assert!(SensorId::new("CAF003").is_ok());
        for bad in ["", " a", "a ", "a\tb"] {
            assert!(SensorId::new(bad).is_err(), "{bad:?} accepted");
        }
    }
}
