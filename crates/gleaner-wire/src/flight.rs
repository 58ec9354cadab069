//! The autopilot files: QGroundControl `.plan` and `QGC WPL 110`, from one list of MAVLink
//! mission items so that both files command exactly the same flight.

use std::fmt::Write as _;

use serde::{Deserialize, Serialize};

use gleaner_energy::{CommandedFlight, flight_speed_mps};
use gleaner_field::LatLon;

use crate::check::{check_flyable, deg7};
use crate::{EnergyDoc, ExportError, MissionDoc};

/// MAVLink `MAV_CMD_NAV_WAYPOINT`: fly to a position, hold param1 seconds.
pub const MAV_CMD_NAV_WAYPOINT: u16 = 16;
/// MAVLink `MAV_CMD_NAV_RETURN_TO_LAUNCH`: fly home and land.
pub const MAV_CMD_NAV_RETURN_TO_LAUNCH: u16 = 20;
/// MAVLink `MAV_CMD_NAV_TAKEOFF`: take off to param7 m.
pub const MAV_CMD_NAV_TAKEOFF: u16 = 22;
/// MAVLink `MAV_CMD_DO_CHANGE_SPEED`: param1 speed type, param2 speed m/s, param3 throttle.
pub const MAV_CMD_DO_CHANGE_SPEED: u16 = 178;
/// MAVLink `MAV_FRAME_GLOBAL`: altitude above mean sea level (the WPL home line).
pub const MAV_FRAME_GLOBAL: u8 = 0;
/// MAVLink `MAV_FRAME_MISSION`: the item has no position.
pub const MAV_FRAME_MISSION: u8 = 2;
/// MAVLink `MAV_FRAME_GLOBAL_RELATIVE_ALT`: altitude above the home position.
pub const MAV_FRAME_GLOBAL_RELATIVE_ALT: u8 = 3;
/// `DO_CHANGE_SPEED` param1: the speed is a ground speed.
pub const SPEED_TYPE_GROUND: f64 = 1.0;
/// `DO_CHANGE_SPEED` param3: leave the throttle unchanged.
pub const THROTTLE_UNCHANGED: f64 = -1.0;

/// What the yaw parameter (param4 of take-off and waypoints) says, in every file's metadata.
pub const YAW_NOTE: &str = "param4 (yaw) of take-off and waypoints is NaN (null in .plan, nan in WPL): \
     the autopilot keeps its own yaw behaviour; 0 would command a north heading";
/// How hold times are derived, in every file's metadata.
pub const HOLD_NOTE: &str = "param1 (hold, s) of each waypoint is the stop's hover_s rounded up to 0.25 s, \
     the hold the mission was planned with; the speed is rounded to 0.25 m/s and positions to 1e-7 degrees \
     before planning, and the writer recomputes the energy from the values in the file";

/// The hold written for a hover of `hover_s` seconds, s: rounded up to
/// `gleaner_energy::HOLD_STEP_S` (exact in `f64` and as a MAVLink `float32`).
pub(crate) fn hold_s(hover_s: f64) -> f64 {
    gleaner_energy::flight_hold_s(hover_s)
}

/// One MAVLink mission item after the home position.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Item {
    command: u16,
    frame: u8,
    /// param1..param7; param5/6 = lat/lon degrees, param7 = altitude m; NaN = "unset".
    params: [f64; 7],
    /// Whether param5..7 are a position (QGC's altitude keys are written for these only).
    positioned: bool,
}

/// Take-off, speed, one waypoint per stop, return to launch; checks the mission first. A
/// continuation has no take-off: speed, a 0 s waypoint where the aircraft is, the stops,
/// return to launch.
fn items(m: &MissionDoc) -> Result<Vec<Item>, ExportError> {
    check_flyable(m)?;
    let p = &m.profile;
    let [base_lon, base_lat] = p.base_lon_lat;
    let alt = gleaner_energy::flight_altitude_m(p.altitude_m);
    let mut out = Vec::with_capacity(m.stops.len() + 4);
    if m.continuation.is_none() {
        out.push(Item {
            command: MAV_CMD_NAV_TAKEOFF,
            frame: MAV_FRAME_GLOBAL_RELATIVE_ALT,
            params: [0.0, 0.0, 0.0, f64::NAN, deg7(base_lat), deg7(base_lon), alt],
            positioned: true,
        });
    }
    out.push(Item {
        command: MAV_CMD_DO_CHANGE_SPEED,
        frame: MAV_FRAME_MISSION,
        params: [
            SPEED_TYPE_GROUND,
            flight_speed_mps(p.cruise_speed_mps),
            THROTTLE_UNCHANGED,
            0.0,
            0.0,
            0.0,
            0.0,
        ],
        positioned: false,
    });
    // A continuation starts where the aircraft is: a first waypoint there, no hold.
    if let Some(c) = &m.continuation {
        let [lon, lat] = c.start_lon_lat;
        out.push(Item {
            command: MAV_CMD_NAV_WAYPOINT,
            frame: MAV_FRAME_GLOBAL_RELATIVE_ALT,
            params: [0.0, 0.0, 0.0, f64::NAN, deg7(lat), deg7(lon), alt],
            positioned: true,
        });
    }
    for w in crate::flown_waypoints(m) {
        let [lon, lat] = w.lon_lat;
        // A detour's turn point holds 0 s (a stop at least 0.25 s): flown through.
        let hold = w.stop.map_or(0.0, |k| hold_s(m.stops[k].hover_s));
        out.push(Item {
            command: MAV_CMD_NAV_WAYPOINT,
            frame: MAV_FRAME_GLOBAL_RELATIVE_ALT,
            params: [hold, 0.0, 0.0, f64::NAN, deg7(lat), deg7(lon), alt],
            positioned: true,
        });
    }
    out.push(Item {
        command: MAV_CMD_NAV_RETURN_TO_LAUNCH,
        frame: MAV_FRAME_MISSION,
        params: [0.0; 7],
        positioned: false,
    });
    Ok(out)
}

/// The assumptions a flight file was written under: what the energy model assumed and which
/// mission it is. Written as the `.plan`'s top-level `"gleaner"` object and the GeoJSON
/// collection's `"gleaner"` foreign member.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FlightMeta {
    /// The mission document's format, `gleaner.mission`.
    pub mission_format: String,
    /// The mission document's version.
    pub mission_version: u32,
    /// Stored mission id (absent for a dry run).
    pub mission_id: Option<i64>,
    /// `adaptive` or `exploration`.
    pub kind: String,
    /// `planned`, `flown` or `dry-run`.
    pub status: String,
    /// Mission time t, RFC 3339 UTC.
    pub planned_at: String,
    /// Mission time t, seconds since the Unix epoch.
    pub planned_at_s: i64,
    /// Planner name.
    pub planner: String,
    /// Planner seed.
    pub seed: u64,
    /// Weights alpha, beta, gamma, delta of S (additive alpha·F + beta·A + gamma·U − delta·R, or
    /// gated alpha·F·max(0, 1 + beta·A + gamma·U − delta·R); docs/method.md §2).
    pub weights: [f64; 4],
    /// Anomaly form (`raw`, `bounded(kappa=3)`, `n/a`).
    pub anomaly_form: String,
    /// Base (home) `[lon, lat]`, WGS84 degrees.
    pub base_lon_lat: [f64; 2],
    /// Base (home) altitude above mean sea level, m.
    pub base_alt_m: f64,
    /// Flight altitude above the base (home), m.
    pub altitude_m: f64,
    /// Commanded cruise ground speed, m/s: the speed the energy model assumed.
    pub cruise_speed_mps: f64,
    /// How hold times were derived from the planned hover times.
    pub hold_rule: String,
    /// What the yaw parameter commands.
    pub yaw: String,
    /// Number of stops.
    pub stops: usize,
    /// Sum of S over the stops.
    pub total_score: f64,
    /// The planned energy breakdown (J, m, s).
    pub energy: EnergyDoc,
}

impl FlightMeta {
    /// The metadata of mission `m` (no checks).
    #[must_use]
    pub fn of(m: &MissionDoc) -> Self {
        Self {
            mission_format: m.format.clone(),
            mission_version: m.version,
            mission_id: m.mission_id,
            kind: m.kind.clone(),
            status: m.status.clone(),
            planned_at: m.planned_at.clone(),
            planned_at_s: m.planned_at_s,
            planner: m.planner.clone(),
            seed: m.seed,
            weights: m.weights,
            anomaly_form: m.anomaly_form.clone(),
            base_lon_lat: m.profile.base_lon_lat,
            base_alt_m: m.profile.base_alt_m,
            altitude_m: m.profile.altitude_m,
            cruise_speed_mps: m.profile.cruise_speed_mps,
            hold_rule: HOLD_NOTE.to_string(),
            yaw: YAW_NOTE.to_string(),
            stops: m.stops.len(),
            total_score: m.total_score,
            energy: m.energy,
        }
    }
}

/// A QGroundControl plan file (`fileType` "Plan", version 1).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct QgcPlan {
    /// Always `Plan`.
    pub file_type: String,
    /// Always 1.
    pub version: u32,
    /// `gleaner`.
    pub ground_station: String,
    /// The mission.
    pub mission: QgcMission,
    /// The geofence and no-fly zones (version 2; empty without zones): MAVSDK's importer
    /// requires the object.
    pub geo_fence: QgcGeoFence,
    /// No rally points (version 2): MAVSDK's importer requires the object.
    pub rally_points: QgcRallyPoints,
    /// gleaner's assumptions; QGroundControl and MAVSDK ignore unknown top-level keys.
    pub gleaner: FlightMeta,
}

/// The `mission` object of a [`QgcPlan`] (version 2).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct QgcMission {
    /// Always 2.
    pub version: u32,
    /// MAV_AUTOPILOT: 12 = PX4 (QGroundControl's default; the items are plain MAVLink).
    pub firmware_type: u32,
    /// MAV_TYPE: 2 = quadrotor.
    pub vehicle_type: u32,
    /// Fixed-wing cruise speed QGroundControl assumes, m/s: the planned cruise speed.
    pub cruise_speed: f64,
    /// Multirotor speed QGroundControl assumes, m/s: the planned cruise speed.
    pub hover_speed: f64,
    /// 1 = altitudes relative to home.
    pub global_plan_altitude_mode: u32,
    /// Home `[lat, lon, alt]`: degrees, degrees, m above mean sea level. Note the order.
    pub planned_home_position: [f64; 3],
    /// The mission items.
    pub items: Vec<QgcItem>,
}

/// One `SimpleItem` of a QGroundControl mission.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct QgcItem {
    /// Always `SimpleItem`.
    #[serde(rename = "type")]
    pub kind: String,
    /// MAV_CMD.
    pub command: u16,
    /// MAV_FRAME.
    pub frame: u8,
    /// Continue to the next item on completion.
    pub auto_continue: bool,
    /// Item number from 1.
    pub do_jump_id: usize,
    /// param1..param7; `null` = NaN ("unset"); for positioned items param5 = latitude and
    /// param6 = longitude (degrees), param7 = altitude (m, per `frame`).
    pub params: [Option<f64>; 7],
    /// Altitude, m (positioned items).
    #[serde(rename = "Altitude", default, skip_serializing_if = "Option::is_none")]
    pub altitude: Option<f64>,
    /// 1 = relative to home (positioned items).
    #[serde(
        rename = "AltitudeMode",
        default,
        skip_serializing_if = "Option::is_none"
    )]
    pub altitude_mode: Option<u8>,
    /// Terrain-following altitude: always `null` (not used), written with the two keys above
    /// as QGroundControl expects.
    #[serde(rename = "AMSLAltAboveTerrain", default)]
    #[serde(skip_serializing_if = "is_unpositioned")]
    pub amsl_alt_above_terrain: Option<Option<f64>>,
}

fn is_unpositioned(x: &Option<Option<f64>>) -> bool {
    x.is_none()
}

/// The geofence of a [`QgcPlan`] (QGroundControl's `geoFence`, version 2): the mission's
/// zones as QGroundControl polygons (`inclusion` true for the geofence, false for a no-fly
/// zone; vertices `[lat, lon]` degrees, not repeating the first) and circles (a point zone:
/// centre `[lat, lon]`, radius = the buffer, m). A geofence's holes are exclusion polygons;
/// a no-fly polygon's holes are not written (the whole exterior is excluded, which is
/// safer). Line zones (power lines) have no QGroundControl fence shape and are written only
/// to the GeoJSON; the route keeps their buffer all the same.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct QgcGeoFence {
    /// Circles.
    pub circles: Vec<serde_json::Value>,
    /// Polygons.
    pub polygons: Vec<serde_json::Value>,
    /// Always 2.
    pub version: u32,
}

impl QgcGeoFence {
    /// The fence of `m`'s zones.
    pub fn of(m: &MissionDoc) -> Self {
        let mut polygons = Vec::new();
        let mut circles = Vec::new();
        let vertices = |ring: &[[f64; 2]]| -> serde_json::Value {
            let open = match ring.split_last() {
                Some((last, rest)) if Some(last) == ring.first() => rest,
                _ => ring,
            };
            open.iter()
                .map(|&[lon, lat]| serde_json::json!([deg7(lat), deg7(lon)]))
                .collect()
        };
        for z in &m.zones {
            let fence = z.kind == "geofence";
            for p in &z.polygons_lon_lat {
                let Some((outer, holes)) = p.split_first() else {
                    continue;
                };
                polygons.push(serde_json::json!({
                    "inclusion": fence, "polygon": vertices(outer), "version": 1
                }));
                if fence {
                    for h in holes {
                        polygons.push(serde_json::json!({
                            "inclusion": false, "polygon": vertices(h), "version": 1
                        }));
                    }
                }
            }
            for l in &z.lines_lon_lat {
                if let [[lon, lat]] = l[..] {
                    circles.push(serde_json::json!({
                        "circle": {"center": [deg7(lat), deg7(lon)], "radius": z.buffer_m},
                        "inclusion": false,
                        "version": 1
                    }));
                }
            }
        }
        Self {
            circles,
            polygons,
            version: 2,
        }
    }
}

/// Empty rally points of a [`QgcPlan`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct QgcRallyPoints {
    /// Points (none).
    pub points: Vec<serde_json::Value>,
    /// Always 2.
    pub version: u32,
}

/// The QGroundControl `.plan` of a mission as a value (see [`qgc_plan`]).
///
/// # Errors
/// [`check_flyable`]'s refusals.
pub fn qgc_plan_doc(m: &MissionDoc) -> Result<QgcPlan, ExportError> {
    let items = items(m)?;
    let p = &m.profile;
    let [lon, lat] = p.base_lon_lat;
    let items = items
        .into_iter()
        .enumerate()
        .map(|(k, it)| QgcItem {
            kind: "SimpleItem".to_string(),
            command: it.command,
            frame: it.frame,
            auto_continue: true,
            do_jump_id: k + 1,
            params: it.params.map(|x| if x.is_nan() { None } else { Some(x) }),
            altitude: it.positioned.then_some(it.params[6]),
            altitude_mode: it.positioned.then_some(1),
            amsl_alt_above_terrain: it.positioned.then_some(None),
        })
        .collect();
    Ok(QgcPlan {
        file_type: "Plan".to_string(),
        version: 1,
        ground_station: "gleaner".to_string(),
        mission: QgcMission {
            version: 2,
            firmware_type: 12,
            vehicle_type: 2,
            cruise_speed: flight_speed_mps(p.cruise_speed_mps),
            hover_speed: flight_speed_mps(p.cruise_speed_mps),
            global_plan_altitude_mode: 1,
            planned_home_position: [deg7(lat), deg7(lon), p.base_alt_m],
            items,
        },
        geo_fence: QgcGeoFence::of(m),
        rally_points: QgcRallyPoints {
            points: Vec::new(),
            version: 2,
        },
        gleaner: FlightMeta::of(m),
    })
}

/// The QGroundControl `.plan` (JSON) of a mission: take-off to `profile.altitude_m` above
/// home at the base, `DO_CHANGE_SPEED` to the planned cruise ground speed, one `NAV_WAYPOINT`
/// per stop at its cell centre holding its hover time, return to launch. `cruiseSpeed` and
/// `hoverSpeed` are the planned cruise speed; `plannedHomePosition` is `[lat, lon, alt AMSL]`.
/// The assumptions are in the top-level `"gleaner"` object ([`FlightMeta`]).
///
/// # Errors
/// [`check_flyable`]'s refusals; [`ExportError::Json`] never in practice.
pub fn qgc_plan(m: &MissionDoc) -> Result<String, ExportError> {
    let mut text = serde_json::to_string_pretty(&qgc_plan_doc(m)?)?;
    text.push('\n');
    check_commanded(m, PLAN_FILE, &parse_qgc_plan(&text)?)?;
    Ok(text)
}

/// The name the `.plan` goes by in errors.
pub const PLAN_FILE: &str = "mission.plan";
/// The name the WPL file goes by in errors.
pub const WPL_FILE: &str = "mission.waypoints";

/// The flight a mission's files command: the values [`qgc_plan`] and [`wpl`] write (speed,
/// holds and positions rounded as `gleaner_energy::flight` rounds them), before any text is
/// written.
///
/// # Errors
/// [`check_flyable`]'s refusals.
pub fn commanded_flight(m: &MissionDoc) -> Result<CommandedFlight, ExportError> {
    let items = items(m)?;
    let [lon, lat] = m.profile.base_lon_lat;
    let home = latlon("home", deg7(lat), deg7(lon))?;
    flight_of_items(
        "mission document",
        home,
        items.iter().map(|it| (0, it.command, it.params)),
    )
}

fn latlon(what: &str, lat: f64, lon: f64) -> Result<LatLon, ExportError> {
    LatLon::new(lat, lon).map_err(|_| ExportError::Coordinate {
        what: what.to_string(),
        lon,
        lat,
    })
}

/// The flight that MAVLink items command, read the way an autopilot flies them: take-off
/// altitude, the last `DO_CHANGE_SPEED` ground speed, one waypoint per `NAV_WAYPOINT` (all at
/// the take-off altitude), return to launch last. Without a take-off the flight is a
/// continuation flown from the air ([`CommandedFlight::airborne`]): it starts at its first
/// waypoint, whose altitude every other waypoint must share. `items` are (line, command,
/// params).
fn flight_of_items(
    file: &str,
    home: LatLon,
    items: impl Iterator<Item = (usize, u16, [f64; 7])>,
) -> Result<CommandedFlight, ExportError> {
    let bad = |line: usize, reason: String| ExportError::FileValue {
        file: file.to_string(),
        line,
        reason,
    };
    let mut altitude_m = None;
    let mut speed_mps = None;
    let mut waypoints = Vec::new();
    let mut returned = false;
    let mut airborne = false;
    for (line, command, p) in items {
        if returned {
            return Err(bad(
                line,
                format!("command {command} after return to launch"),
            ));
        }
        match command {
            MAV_CMD_NAV_TAKEOFF if altitude_m.is_none() => altitude_m = Some(p[6]),
            MAV_CMD_NAV_TAKEOFF => {
                return Err(bad(line, "a take-off after the flight started".into()));
            }
            MAV_CMD_DO_CHANGE_SPEED => {
                if p[0] != SPEED_TYPE_GROUND {
                    return Err(bad(
                        line,
                        format!("speed type {} is not ground speed", p[0]),
                    ));
                }
                speed_mps = Some(p[1]);
            }
            MAV_CMD_NAV_WAYPOINT => {
                // No take-off: a continuation, in the air at its first waypoint.
                let alt = *altitude_m.get_or_insert_with(|| {
                    airborne = true;
                    p[6]
                });
                if speed_mps.is_none() {
                    return Err(bad(line, "a waypoint before the speed is set".into()));
                }
                if p[6] != alt {
                    return Err(bad(
                        line,
                        format!(
                            "waypoint altitude {} m differs from take-off's {alt} m",
                            p[6]
                        ),
                    ));
                }
                waypoints.push((latlon(&format!("{file} line {line}"), p[4], p[5])?, p[0]));
            }
            MAV_CMD_NAV_RETURN_TO_LAUNCH => returned = true,
            other => return Err(bad(line, format!("unexpected command {other}"))),
        }
    }
    match (altitude_m, speed_mps, returned) {
        (Some(altitude_m), Some(speed_mps), true) => Ok(CommandedFlight {
            home,
            altitude_m,
            speed_mps,
            waypoints,
            airborne,
        }),
        _ => Err(bad(
            0,
            "needs a take-off (or, for a continuation, a first waypoint), a speed and a return to launch"
                .into(),
        )),
    }
}

/// Reads back the flight a `.plan` written by [`qgc_plan`] commands: home from
/// `plannedHomePosition` (`[lat, lon, alt]`), the items as [`commanded_flight`] reads them.
/// `hoverSpeed` must be the commanded speed.
///
/// # Errors
/// [`ExportError::FileValue`] (or [`ExportError::Json`]) naming what cannot be read.
pub fn parse_qgc_plan(text: &str) -> Result<CommandedFlight, ExportError> {
    let plan: QgcPlan = serde_json::from_str(text)?;
    let [lat, lon, _] = plan.mission.planned_home_position;
    let home = latlon("plannedHomePosition", lat, lon)?;
    let flight = flight_of_items(
        PLAN_FILE,
        home,
        plan.mission
            .items
            .iter()
            .enumerate()
            .map(|(k, it)| (k + 1, it.command, it.params.map(|x| x.unwrap_or(f64::NAN)))),
    )?;
    if plan.mission.hover_speed != flight.speed_mps {
        return Err(ExportError::FileValue {
            file: PLAN_FILE.to_string(),
            line: 0,
            reason: format!(
                "hoverSpeed {} m/s differs from the commanded {} m/s",
                plan.mission.hover_speed, flight.speed_mps
            ),
        });
    }
    Ok(flight)
}

/// Reads back the flight a `QGC WPL 110` file written by [`wpl`] commands: line 0 is home,
/// the rest as [`commanded_flight`] reads them. Fields are parsed as Rust parses decimals
/// (correctly rounded), `nan` included.
///
/// # Errors
/// [`ExportError::FileValue`] naming the line and what cannot be read.
pub fn parse_wpl(text: &str) -> Result<CommandedFlight, ExportError> {
    let bad = |line: usize, reason: String| ExportError::FileValue {
        file: WPL_FILE.to_string(),
        line,
        reason,
    };
    let mut lines = text.lines().enumerate();
    match lines.next() {
        Some((_, "QGC WPL 110")) => {}
        _ => return Err(bad(1, "the first line is not `QGC WPL 110`".into())),
    }
    let mut rows = Vec::new();
    for (k, line) in lines {
        let n = k + 1;
        let fields: Vec<&str> = line.split('\t').collect();
        if fields.len() != 12 {
            return Err(bad(n, format!("{} fields, expected 12", fields.len())));
        }
        let num = |i: usize| -> Result<f64, ExportError> {
            fields[i].parse::<f64>().map_err(|_| {
                bad(
                    n,
                    format!("field {} = {:?} is not a number", i + 1, fields[i]),
                )
            })
        };
        let command: u16 = fields[3]
            .parse()
            .map_err(|_| bad(n, format!("command {:?} is not a number", fields[3])))?;
        let mut p = [0.0; 7];
        for (i, x) in p.iter_mut().enumerate() {
            *x = num(4 + i)?;
        }
        rows.push((n, command, p));
    }
    let Some(((_, home_command, home), rest)) = rows.split_first() else {
        return Err(bad(2, "no home line".into()));
    };
    if *home_command != MAV_CMD_NAV_WAYPOINT {
        return Err(bad(2, format!("home line has command {home_command}")));
    }
    let home = latlon("WPL home", home[4], home[5])?;
    flight_of_items(WPL_FILE, home, rest.iter().copied())
}

/// Prices `flight` — what `file` commands — with the mission's energy model and refuses it
/// above the usable budget (the smaller of the model's and the mission's). Returns the
/// commanded energy, J.
///
/// # Errors
/// [`ExportError::NoEnergyModel`] for a document without one;
/// [`ExportError::CommandedOverBudget`] above the budget; [`ExportError::FileValue`] for a
/// value the energy model refuses.
pub fn check_commanded(
    m: &MissionDoc,
    file: &str,
    flight: &CommandedFlight,
) -> Result<f64, ExportError> {
    let model = m.energy_model.ok_or(ExportError::NoEnergyModel)?;
    let [lon, lat] = m.profile.base_lon_lat;
    let origin = latlon("base", lat, lon)?;
    let energy = model
        .to_core()
        .energy(origin, flight)
        .map_err(|e| ExportError::FileValue {
            file: file.to_string(),
            line: 0,
            reason: e.to_string(),
        })?;
    let budget_j = model.usable_budget_j.min(m.energy.budget_j);
    if !(energy.total_j.is_finite() && energy.total_j <= budget_j) {
        return Err(ExportError::CommandedOverBudget {
            file: file.to_string(),
            commanded_j: energy.total_j,
            planned_j: m.energy.total_j,
            budget_j,
        });
    }
    Ok(energy.total_j)
}

/// A WPL number: shortest round-trip decimal, `nan` for NaN (as QGroundControl writes it).
fn num(x: f64) -> String {
    if x.is_nan() {
        "nan".to_string()
    } else {
        format!("{x}")
    }
}

/// The `QGC WPL 110` waypoint file of a mission: the same items as [`qgc_plan`], one per line,
/// 12 tab-separated fields `seq current frame command p1 p2 p3 p4 lat lon alt autocontinue`
/// (latitude before longitude, degrees with 7 decimals). Line 0 is home at the base, frame 0
/// (altitude AMSL = `profile.base_alt_m`); the rest use frame 3 (altitude above home) or 2 (no
/// position).
///
/// The file has no metadata: QGroundControl rejects any line that is not 12 tab-separated
/// fields, so a comment line would make the file unloadable there (pymavlink and MAVSDK would
/// skip `#` lines). Write [`flight_notes`] beside it instead.
///
/// # Errors
/// [`check_flyable`]'s refusals.
pub fn wpl(m: &MissionDoc) -> Result<String, ExportError> {
    let text = wpl_text(m)?;
    check_commanded(m, WPL_FILE, &parse_wpl(&text)?)?;
    Ok(text)
}

fn wpl_text(m: &MissionDoc) -> Result<String, ExportError> {
    let items = items(m)?;
    let p = &m.profile;
    let [lon, lat] = p.base_lon_lat;
    let mut out = String::from("QGC WPL 110\n");
    let _ = writeln!(
        out,
        "0\t1\t{MAV_FRAME_GLOBAL}\t{MAV_CMD_NAV_WAYPOINT}\t0\t0\t0\t0\t{:.7}\t{:.7}\t{}\t1",
        deg7(lat),
        deg7(lon),
        num(p.base_alt_m)
    );
    for (k, it) in items.iter().enumerate() {
        let [p1, p2, p3, p4, x, y, z] = it.params;
        let (x, y) = if it.positioned {
            (format!("{x:.7}"), format!("{y:.7}"))
        } else {
            (num(x), num(y))
        };
        let _ = writeln!(
            out,
            "{}\t0\t{}\t{}\t{}\t{}\t{}\t{}\t{x}\t{y}\t{}\t1",
            k + 1,
            it.frame,
            it.command,
            num(p1),
            num(p2),
            num(p3),
            num(p4),
            num(z)
        );
    }
    Ok(out)
}

/// Plain-text notes for the operator, to write beside the WPL file (which cannot carry them):
/// mission id and time, commanded speed, altitude, hold rule, yaw and the energy total against
/// the budget.
///
/// # Errors
/// [`check_flyable`]'s refusals: notes are written only for a flyable mission.
pub fn flight_notes(m: &MissionDoc) -> Result<String, ExportError> {
    check_flyable(m)?;
    let commanded_j = check_commanded(m, "flight notes", &commanded_flight(m)?)?;
    let meta = FlightMeta::of(m);
    let e = &meta.energy;
    let id = meta
        .mission_id
        .map_or_else(|| "dry run".to_string(), |id| format!("#{id}"));
    let mut out = String::new();
    let _ = writeln!(out, "gleaner mission {id} ({}, {})", meta.kind, meta.status);
    let _ = writeln!(
        out,
        "planned at: {} ({} s)",
        meta.planned_at, meta.planned_at_s
    );
    let _ = writeln!(out, "planner: {} (seed {})", meta.planner, meta.seed);
    let _ = writeln!(
        out,
        "home: lat {:.7} lon {:.7}, {} m AMSL",
        deg7(meta.base_lon_lat[1]),
        deg7(meta.base_lon_lat[0]),
        meta.base_alt_m
    );
    let _ = writeln!(out, "altitude: {} m above home", meta.altitude_m);
    let _ = writeln!(
        out,
        "cruise ground speed: {} m/s (DO_CHANGE_SPEED after take-off)",
        flight_speed_mps(meta.cruise_speed_mps)
    );
    let _ = writeln!(out, "stops: {}; {}", meta.stops, meta.hold_rule);
    let _ = writeln!(out, "yaw: {}", meta.yaw);
    let _ = writeln!(
        out,
        "energy: {:.1} J of {:.1} J usable ({:.1}%): travel {:.1}, hover {:.1}, comm {:.1}, return {:.1}",
        e.total_j,
        e.budget_j,
        100.0 * e.utilisation,
        e.travel_j,
        e.hover_j,
        e.comm_j,
        e.return_j
    );
    let _ = writeln!(
        out,
        "commanded energy: {commanded_j:.1} J of {:.1} J usable, recomputed from the files' holds, speed and positions",
        e.budget_j
    );
    let _ = writeln!(
        out,
        "distance: {:.1} m; flight time {:.1} s",
        e.distance_m, e.flight_time_s
    );
    Ok(out)
}
