//! The checks every writer makes before it writes anything.

use crate::{ExportError, FIELD_FORMAT, FieldDoc, MISSION_FORMAT, MissionDoc, VERSION};

/// The highest flight altitude above the base a flight file may command, m (the usual legal
/// ceiling for small unmanned aircraft).
pub const MAX_ALTITUDE_M: f64 = 120.0;

/// The longest hover at one stop a flight file may command, s (a day: far beyond any battery,
/// so only nonsense is refused).
pub const MAX_HOVER_S: f64 = 86_400.0;

/// Rounds a WGS84 coordinate to 1e-7 degrees (at most 5.6 mm off), the resolution autopilots
/// store (MAVLink `int32` degE7).
pub(crate) fn deg7(x: f64) -> f64 {
    gleaner_energy::flight_degrees(x)
}

/// Checks a `[lon, lat]` position: finite, lon in [-180, 180], lat in [-90, 90] degrees.
pub(crate) fn position(
    what: impl FnOnce() -> String,
    lon_lat: [f64; 2],
) -> Result<(), ExportError> {
    let [lon, lat] = lon_lat;
    let ok = lon.is_finite()
        && lat.is_finite()
        && (-180.0..=180.0).contains(&lon)
        && (-90.0..=90.0).contains(&lat);
    if ok {
        Ok(())
    } else {
        Err(ExportError::Coordinate {
            what: what(),
            lon,
            lat,
        })
    }
}

/// Checks that a document's `format` and `version` are `expected` at this build's [`VERSION`].
fn supported(format: &str, version: u32, expected: &'static str) -> Result<(), ExportError> {
    if format == expected && version == VERSION {
        Ok(())
    } else {
        Err(ExportError::UnsupportedDocument {
            format: format.to_string(),
            version,
            expected,
            expected_version: VERSION,
        })
    }
}

/// Checks that `m` is a `gleaner.mission` this build writes, with valid positions.
pub(crate) fn mission_doc(m: &MissionDoc) -> Result<(), ExportError> {
    supported(&m.format, m.version, MISSION_FORMAT)?;
    position(|| "base".to_string(), m.profile.base_lon_lat)?;
    if let Some(c) = &m.continuation {
        position(|| "continuation start".to_string(), c.start_lon_lat)?;
    }
    for s in &m.stops {
        position(
            || format!("stop {} (cell {})", s.order, s.cell),
            s.centre_lon_lat,
        )?;
    }
    Ok(())
}

/// Checks that `f` is a `gleaner.field` this build writes, with valid positions.
pub(crate) fn field_doc(f: &FieldDoc) -> Result<(), ExportError> {
    supported(&f.format, f.version, FIELD_FORMAT)?;
    position(|| "field base".to_string(), f.base_lon_lat)?;
    for c in &f.cells {
        position(|| format!("cell {} centre", c.cell), c.centre_lon_lat)?;
        for (k, p) in c.ring_lon_lat.iter().enumerate() {
            position(|| format!("cell {} ring position {k}", c.cell), *p)?;
        }
    }
    for s in &f.sensors {
        position(|| format!("sensor {}", s.id), s.lon_lat)?;
    }
    Ok(())
}

/// Checks that a mission is safe to hand to an autopilot, exactly as planned:
///
/// - it is a `gleaner.mission` version [`VERSION`] document with at least one stop;
/// - every position (base, stop centres) is a finite WGS84 `[lon, lat]`;
/// - the planned energy `energy.total_j` is finite and within the finite usable budget
///   `energy.budget_j` (J);
/// - the flight altitude `profile.altitude_m` is finite and in (0, [`MAX_ALTITUDE_M`]] m above
///   the base, and the base altitude `profile.base_alt_m` is finite and in [-500, 9000] m AMSL;
/// - the cruise speed `profile.cruise_speed_mps` is finite and > 0 m/s;
/// - every hover time `hover_s` is finite and in [0, [`MAX_HOVER_S`]] s.
///
/// Exploration sorties are missions like any other and pass the same checks. Every flight-file
/// writer calls this first; call it yourself to refuse before writing any file.
///
/// # Errors
/// The first check that fails, as an [`ExportError`] carrying the offending value.
pub fn check_flyable(m: &MissionDoc) -> Result<(), ExportError> {
    mission_doc(m)?;
    if m.stops.is_empty() {
        return Err(ExportError::NoStops);
    }
    let e = &m.energy;
    if !(e.total_j.is_finite() && e.budget_j.is_finite() && e.total_j <= e.budget_j) {
        return Err(ExportError::OverBudget {
            total_j: e.total_j,
            budget_j: e.budget_j,
        });
    }
    let p = &m.profile;
    if !(p.altitude_m.is_finite() && p.altitude_m > 0.0 && p.altitude_m <= MAX_ALTITUDE_M) {
        return Err(ExportError::Altitude {
            altitude_m: p.altitude_m,
            max_m: MAX_ALTITUDE_M,
        });
    }
    if !(p.base_alt_m.is_finite() && (-500.0..=9000.0).contains(&p.base_alt_m)) {
        return Err(ExportError::BaseAltitude {
            base_alt_m: p.base_alt_m,
        });
    }
    if !(p.cruise_speed_mps.is_finite() && p.cruise_speed_mps > 0.0) {
        return Err(ExportError::CruiseSpeed {
            speed_mps: p.cruise_speed_mps,
        });
    }
    for s in &m.stops {
        if !(s.hover_s.is_finite() && (0.0..=MAX_HOVER_S).contains(&s.hover_s)) {
            return Err(ExportError::HoverTime {
                order: s.order,
                cell: s.cell.clone(),
                hover_s: s.hover_s,
                max_s: MAX_HOVER_S,
            });
        }
    }
    Ok(())
}
