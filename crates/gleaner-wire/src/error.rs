//! Why a document could not be written as a flight file or a map.

use thiserror::Error;

/// A refusal to write a file: the document is not one this build understands, or flying it
/// would not be safe or would not be the plan. Messages carry the offending values.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum ExportError {
    /// The document's `format`/`version` is not one this build writes.
    #[error(
        "unsupported document {format:?} version {version} (this build writes {expected:?} version {expected_version})"
    )]
    UnsupportedDocument {
        /// The document's `format`.
        format: String,
        /// The document's `version`.
        version: u32,
        /// The format this writer takes.
        expected: &'static str,
        /// The version this writer takes.
        expected_version: u32,
    },
    /// The mission's energy total exceeds its usable budget (or either is not finite).
    #[error(
        "mission energy {total_j} J exceeds the usable budget {budget_j} J: refusing to write a flight file"
    )]
    OverBudget {
        /// Planned total energy, J.
        total_j: f64,
        /// Usable budget, J.
        budget_j: f64,
    },
    /// The flight altitude above the base is not finite or not in (0, 120] m.
    #[error("flight altitude {altitude_m} m above the base is not in (0, {max_m}] m")]
    Altitude {
        /// The profile's altitude, m above the base.
        altitude_m: f64,
        /// The largest altitude written, m.
        max_m: f64,
    },
    /// The base altitude above mean sea level is not finite or outside [-500, 9000] m.
    #[error("base altitude {base_alt_m} m AMSL is not finite or outside [-500, 9000] m")]
    BaseAltitude {
        /// The profile's base altitude, m AMSL.
        base_alt_m: f64,
    },
    /// The cruise speed is not finite or not positive.
    #[error("cruise speed {speed_mps} m/s is not a finite positive speed")]
    CruiseSpeed {
        /// The profile's cruise speed, m/s.
        speed_mps: f64,
    },
    /// A stop's hover time is not finite, negative, or longer than the writers accept.
    #[error("stop {order} (cell {cell}): hover time {hover_s} s is not in [0, {max_s}] s")]
    HoverTime {
        /// The stop's visiting order.
        order: u32,
        /// The stop's cell id.
        cell: String,
        /// The stop's hover time, s.
        hover_s: f64,
        /// The longest hover written, s.
        max_s: f64,
    },
    /// A position is not a finite WGS84 `[lon, lat]` in [-180, 180] x [-90, 90] degrees.
    #[error("{what}: [lon, lat] = [{lon}, {lat}] is not a WGS84 position")]
    Coordinate {
        /// Which position (`base`, `stop 3 (cell x1y2)`, ...).
        what: String,
        /// Longitude, degrees.
        lon: f64,
        /// Latitude, degrees.
        lat: f64,
    },
    /// The mission has no stops: there is nothing to fly.
    #[error("the mission has no stops: nothing to fly")]
    NoStops,
    /// A cell's ring is not a closed ring of at least 4 positions enclosing an area.
    #[error("cell {cell}: {reason}")]
    Ring {
        /// The cell id.
        cell: String,
        /// What is wrong with it.
        reason: String,
    },
    /// A stop names a cell the field document does not have.
    #[error("stop {order} visits cell {cell}, which the field document does not have")]
    UnknownCell {
        /// The stop's visiting order.
        order: u32,
        /// The stop's cell id.
        cell: String,
    },
    /// The energy recomputed from the values a file commands exceeds the usable budget.
    #[error(
        "{file}: the flight it commands needs {commanded_j:.1} J (recomputed from its holds, speed and positions; planned {planned_j:.1} J) but {budget_j:.1} J are usable: refusing to write it"
    )]
    CommandedOverBudget {
        /// The file (`mission.plan`, `mission.waypoints`, ...).
        file: String,
        /// Energy of the flight the file commands, J.
        commanded_j: f64,
        /// The mission's planned total, J.
        planned_j: f64,
        /// Usable budget, J.
        budget_j: f64,
    },
    /// The document carries no energy model, so what a file commands cannot be priced.
    #[error(
        "the mission document has no energy_model: a flight file's energy cannot be recomputed (export the mission through the export use case)"
    )]
    NoEnergyModel,
    /// A value of a flight file cannot be read back or priced.
    #[error("{file} line {line}: {reason}")]
    FileValue {
        /// The file.
        file: String,
        /// The line (1-based; the `.plan`: the item number; 0: the file as a whole).
        line: usize,
        /// What is wrong.
        reason: String,
    },
    /// Serialising the file failed.
    #[error("cannot serialise: {0}")]
    Json(#[from] serde_json::Error),
}
