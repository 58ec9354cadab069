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

/// A measured quantity, optionally at a depth: `vw@30cm` (volumetric water at 30 cm), `t@150cm`,
/// `humidity`. Names are lower-case ASCII letters, digits and `_`; the depth is a whole number
/// of centimetres. The unit is carried beside the modality, not in it.
#[derive(Debug, Clone, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Modality(String);

impl Modality {
    /// Parses and validates a modality name (see the type's docs). Upper-case input is
    /// lower-cased: `VW@30cm` is `vw@30cm`.
    pub fn new(name: &str) -> Result<Self, FieldError> {
        let lower = name.trim().to_ascii_lowercase();
        let bad = || FieldError::InvalidModality(name.to_string());
        let (quantity, depth) = match lower.split_once('@') {
            Some((q, d)) => (q, Some(d)),
            None => (lower.as_str(), None),
        };
        let quantity_ok = !quantity.is_empty()
            && quantity.len() <= 64
            && quantity
                .chars()
                .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
            && quantity.starts_with(|c: char| c.is_ascii_lowercase());
        if !quantity_ok {
            return Err(bad());
        }
        if let Some(d) = depth {
            let digits = d.strip_suffix("cm").ok_or_else(bad)?;
            if digits.is_empty() || digits.len() > 6 || !digits.chars().all(|c| c.is_ascii_digit())
            {
                return Err(bad());
            }
        }
        Ok(Self(lower))
    }
    /// A modality from a quantity and a depth in centimetres: `("vw", Some(30))` is `vw@30cm`.
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
    /// The depth in centimetres, if the modality has one.
    pub fn depth_cm(&self) -> Option<u32> {
        let d = self.0.split_once('@')?.1;
        d.strip_suffix("cm")?.parse().ok()
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

    #[test]
    fn modality_parsing() {
        let m = Modality::new("VW@30cm").unwrap();
        assert_eq!(m.as_str(), "vw@30cm");
        assert_eq!(m.quantity(), "vw");
        assert_eq!(m.depth_cm(), Some(30));
        assert_eq!(Modality::new("humidity").unwrap().depth_cm(), None);
        for bad in [
            "",
            "@30cm",
            "vw@",
            "vw@30",
            "vw@xcm",
            "v w",
            "9vw",
            "vw@30cm@1cm",
        ] {
            assert!(Modality::new(bad).is_err(), "{bad:?} accepted");
        }
        assert_eq!(
            Modality::at_depth("t", Some(150)).unwrap().as_str(),
            "t@150cm"
        );
    }

    #[test]
    fn sensor_id_validation() {
        assert!(SensorId::new("CAF003").is_ok());
        for bad in ["", " a", "a ", "a\tb"] {
            assert!(SensorId::new(bad).is_err(), "{bad:?} accepted");
        }
    }
}
