use thiserror::Error;

/// Invalid arguments to the field model. Each message carries the offending value.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum FieldError {
    /// Latitude outside [-90, 90] degrees or longitude outside [-180, 180] degrees, or not finite.
    #[error(
        "invalid WGS84 position: lat {} deg, lon {} deg (need -90..=90, -180..=180)",
        Short(*.lat),
        Short(*.lon)
    )]
    InvalidLatLon {
        /// Latitude, degrees.
        lat: f64,
        /// Longitude, degrees.
        lon: f64,
    },
    /// A cell size that is not a positive finite number of metres.
    #[error("invalid cell size {} m: must be positive and finite", Short(*.0))]
    InvalidCellSize(f64),
    /// A UTM zone outside 1..=60.
    #[error("invalid UTM zone {0}: must be 1..=60")]
    InvalidUtmZone(u8),
    /// An empty or malformed sensor identifier.
    #[error(
        "invalid sensor id {0:?}: must be non-empty, at most 128 characters, no control characters"
    )]
    InvalidSensorId(String),
    /// A malformed modality name.
    #[error(
        "invalid modality {0:?}: expected `<quantity>` or `<quantity>@<depth><unit>`: the quantity is 1 to 64 ASCII letters, digits, `-` or `_`, starting with a letter; the depth a decimal number (digits, optionally `.` and more digits, no sign or exponent); the unit `cm` or `m` (e.g. `vw@30cm`, `vwc-a@15cm`, `vw@15.5cm`, `vwc@0.15m`)"
    )]
    InvalidModality(String),
    /// Two sensors share an id.
    #[error("duplicate sensor id {0:?}")]
    DuplicateSensor(String),
    /// The field has no sensors.
    #[error("a field needs at least one sensor")]
    NoSensors,
    /// A derived cell size that cannot exist (e.g. altitude above the link range).
    #[error("cannot derive a cell size: {0}")]
    Coverage(String),
}

/// A number for a message: as Rust writes it when short, else in scientific notation (1e300,
/// not 301 digits).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Short(pub f64);

impl std::fmt::Display for Short {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let plain = self.0.to_string();
        if plain.len() <= 24 {
            f.write_str(&plain)
        } else {
            write!(f, "{:e}", self.0)
        }
    }
}
