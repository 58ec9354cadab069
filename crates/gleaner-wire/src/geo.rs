//! The GeoJSON map of a mission over its field (RFC 7946).

use geojson::{Feature, FeatureCollection, Geometry, JsonObject, feature::Id};
use serde::{Deserialize, Serialize};

use crate::check::{deg7, field_doc, mission_doc};
use crate::flight::FlightMeta;
use crate::{ExportError, FieldDoc, MissionDoc};

/// Properties of a cell Polygon feature.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CellProperties {
    /// Always `cell`.
    pub kind: String,
    /// Cell id.
    pub cell: String,
    /// Sensors in the cell.
    pub sensors: usize,
    /// Position in the mission's visiting order from 1, `null` if not visited.
    pub visit_order: Option<u32>,
    /// Latest score S (`null` if not scored).
    #[serde(rename = "S")]
    pub s: Option<f64>,
    /// Latest freshness F.
    #[serde(rename = "F")]
    pub f: Option<f64>,
    /// Latest redundancy R.
    #[serde(rename = "R")]
    pub r: Option<f64>,
    /// Latest anomaly A (as used in S).
    #[serde(rename = "A")]
    pub a: Option<f64>,
    /// Latest uncertainty U.
    #[serde(rename = "U")]
    pub u: Option<f64>,
    /// When the scores were computed, seconds since the Unix epoch.
    pub scores_computed_at_s: Option<i64>,
    /// S when the mission was planned (visited cells only; 0 for exploration).
    pub planned_s: Option<f64>,
    /// Planned hover time at the cell, s (visited cells only).
    pub hover_s: Option<f64>,
}

/// Properties of a stop Point feature (the waypoint at a visited cell's centre).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StopProperties {
    /// Always `stop`.
    pub kind: String,
    /// Position in the visiting order from 1.
    pub visit_order: u32,
    /// Cell id.
    pub cell: String,
    /// S when planned.
    #[serde(rename = "S")]
    pub s: f64,
    /// Leg from the previous stop (the base for the first), m.
    pub leg_distance_m: f64,
    /// Propulsion energy of that leg, J.
    pub leg_energy_j: f64,
    /// Planned hover time, s.
    pub hover_s: f64,
    /// Hover energy, J.
    pub hover_j: f64,
    /// Receiver energy, J.
    pub comm_j: f64,
}

/// Properties of the route LineString feature.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RouteProperties {
    /// Always `route`.
    pub kind: String,
    /// Cells visited, in order.
    pub cells: Vec<String>,
    /// Distance flown, m.
    pub distance_m: f64,
    /// Return leg, m.
    pub return_distance_m: f64,
    /// Flight time including hovers, s.
    pub flight_time_s: f64,
    /// Flight altitude above the base, m.
    pub altitude_m: f64,
    /// Cruise ground speed, m/s.
    pub cruise_speed_mps: f64,
}

/// Properties of the base Point feature.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BaseProperties {
    /// Always `base`.
    pub kind: String,
    /// Altitude above mean sea level, m.
    pub alt_m: f64,
}

/// Properties of a sensor Point feature.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SensorProperties {
    /// Always `sensor`.
    pub kind: String,
    /// Sensor id.
    pub sensor: String,
}

fn properties(p: &impl Serialize) -> Result<Option<JsonObject>, ExportError> {
    match serde_json::to_value(p)? {
        serde_json::Value::Object(map) => Ok(Some(map)),
        other => {
            let mut map = JsonObject::new();
            map.insert("value".to_string(), other);
            Ok(Some(map))
        }
    }
}

fn feature(
    geometry: Geometry,
    id: Option<String>,
    props: &impl Serialize,
) -> Result<Feature, ExportError> {
    Ok(Feature {
        bbox: None,
        geometry: Some(geometry),
        id: id.map(Id::String),
        properties: properties(props)?,
        foreign_members: None,
    })
}

fn pos(lon_lat: [f64; 2]) -> [f64; 2] {
    [deg7(lon_lat[0]), deg7(lon_lat[1])]
}

/// Twice the signed area of a closed ring in the lon/lat plane (> 0: counter-clockwise).
fn signed_area2(ring: &[[f64; 2]]) -> f64 {
    ring.windows(2)
        .map(|w| w[0][0] * w[1][1] - w[1][0] * w[0][1])
        .sum()
}

/// The cell's ring, rounded, closed and counter-clockwise (RFC 7946 §3.1.6).
fn cell_ring(cell: &str, ring: &[[f64; 2]]) -> Result<Vec<[f64; 2]>, ExportError> {
    let bad = |reason: &str| ExportError::Ring {
        cell: cell.to_string(),
        reason: reason.to_string(),
    };
    if ring.len() < 4 {
        return Err(bad(&format!(
            "ring has {} positions; a closed ring needs at least 4",
            ring.len()
        )));
    }
    let mut out: Vec<[f64; 2]> = ring.iter().copied().map(pos).collect();
    if out.first() != out.last() {
        return Err(bad("ring is not closed (first position != last)"));
    }
    let area = signed_area2(&out);
    if area == 0.0 || !area.is_finite() {
        return Err(bad("ring encloses no area"));
    }
    if area < 0.0 {
        out.reverse();
    }
    Ok(out)
}

/// The GeoJSON map of a mission as a value (see [`geojson()`]).
///
/// # Errors
/// [`ExportError::UnsupportedDocument`], [`ExportError::Coordinate`], [`ExportError::Ring`],
/// [`ExportError::UnknownCell`].
pub fn geojson_doc(field: &FieldDoc, m: &MissionDoc) -> Result<FeatureCollection, ExportError> {
    field_doc(field)?;
    mission_doc(m)?;
    for s in &m.stops {
        if !field.cells.iter().any(|c| c.cell == s.cell) {
            return Err(ExportError::UnknownCell {
                order: s.order,
                cell: s.cell.clone(),
            });
        }
    }
    let mut features =
        Vec::with_capacity(field.cells.len() + m.stops.len() + field.sensors.len() + 2);
    for c in &field.cells {
        let ring = cell_ring(&c.cell, &c.ring_lon_lat)?;
        let stop = m.stops.iter().find(|s| s.cell == c.cell);
        let sc = c.scores.as_ref();
        let props = CellProperties {
            kind: "cell".to_string(),
            cell: c.cell.clone(),
            sensors: c.sensors,
            visit_order: stop.map(|s| s.order),
            s: sc.map(|x| x.s),
            f: sc.map(|x| x.f),
            r: sc.map(|x| x.r),
            a: sc.map(|x| x.a),
            u: sc.map(|x| x.u),
            scores_computed_at_s: sc.map(|x| x.computed_at_s),
            planned_s: stop.map(|s| s.s),
            hover_s: stop.map(|s| s.hover_s),
        };
        features.push(feature(
            Geometry::new_polygon([ring]),
            Some(format!("cell:{}", c.cell)),
            &props,
        )?);
    }
    let base = pos(m.profile.base_lon_lat);
    // A continuation's route starts where the aircraft is.
    let mut line = vec![m.continuation.map_or(base, |c| pos(c.start_lon_lat))];
    line.extend(m.stops.iter().map(|s| pos(s.centre_lon_lat)));
    line.push(base);
    features.push(feature(
        Geometry::new_line_string(line),
        Some("route".to_string()),
        &RouteProperties {
            kind: "route".to_string(),
            cells: m.stops.iter().map(|s| s.cell.clone()).collect(),
            distance_m: m.energy.distance_m,
            return_distance_m: m.return_distance_m,
            flight_time_s: m.energy.flight_time_s,
            altitude_m: m.profile.altitude_m,
            cruise_speed_mps: m.profile.cruise_speed_mps,
        },
    )?);
    for s in &m.stops {
        features.push(feature(
            Geometry::new_point(pos(s.centre_lon_lat)),
            Some(format!("stop:{}", s.order)),
            &StopProperties {
                kind: "stop".to_string(),
                visit_order: s.order,
                cell: s.cell.clone(),
                s: s.s,
                leg_distance_m: s.leg_distance_m,
                leg_energy_j: s.leg_energy_j,
                hover_s: s.hover_s,
                hover_j: s.hover_j,
                comm_j: s.comm_j,
            },
        )?);
    }
    features.push(feature(
        Geometry::new_point(base),
        Some("base".to_string()),
        &BaseProperties {
            kind: "base".to_string(),
            alt_m: m.profile.base_alt_m,
        },
    )?);
    for s in &field.sensors {
        features.push(feature(
            Geometry::new_point(pos(s.lon_lat)),
            Some(format!("sensor:{}", s.id)),
            &SensorProperties {
                kind: "sensor".to_string(),
                sensor: s.id.clone(),
            },
        )?);
    }
    let mut members = JsonObject::new();
    members.insert(
        "gleaner".to_string(),
        serde_json::to_value(FlightMeta::of(m))?,
    );
    Ok(FeatureCollection {
        bbox: None,
        features,
        foreign_members: Some(members),
    })
}

/// The GeoJSON (RFC 7946) map of a mission over its field: a FeatureCollection of every cell
/// as a Polygon (counter-clockwise ring) with its latest scores and visiting order, the route
/// LineString base → stops → base, one Point per stop with its planned energy, the base Point
/// and the sensors as Points. Positions are `[lon, lat]` WGS84 degrees rounded to 1e-7; no
/// `crs` member. The mission's id, kind, time, weights, anomaly form, profile and energy
/// breakdown are the collection's `"gleaner"` foreign member ([`FlightMeta`]).
///
/// A map is not a flight file: it is written for any mission with valid geometry, including
/// one that [`crate::check_flyable`] refuses.
///
/// # Errors
/// See [`geojson_doc`].
pub fn geojson(field: &FieldDoc, m: &MissionDoc) -> Result<String, ExportError> {
    let mut text = serde_json::to_string_pretty(&geojson_doc(field, m)?)?;
    text.push('\n');
    Ok(text)
}
