//! DJI WPML: the KMZ archive DJI Pilot 2 imports (`wpmz/template.kml` + `wpmz/waylines.wpml`),
//! written following DJI's published WPML reference (namespace `http://www.dji.com/wpmz/1.0.2`).
//! Not flown: it follows the reference, and parses and round-trips here.
//!
//! Both documents are KML 2.2 (`http://www.opengis.net/kml/2.2`) with `wpml:` extension
//! elements. `waylines.wpml` is what the aircraft executes; `template.kml` is the editable
//! waypoint template Pilot 2 shows. They carry the same flight as the MAVLink files:
//!
//! - `wpml:missionConfig`: fly to the first waypoint `safely` (climb first), finish with
//!   `goHome`, keep flying the wayline if the remote-control link is lost (`goContinue`),
//!   take-off security height, global return-to-home height and global transitional speed =
//!   the flight altitude (m above take-off) and the commanded speed (m/s), the aircraft
//!   (`wpml:droneInfo`, [`WpmlOptions`]), and the take-off reference point (the base) in
//!   the template;
//! - one waypoint `Placemark` per stop in visiting order: `Point/coordinates` =
//!   `longitude,latitude` (**lon first**, degrees to 1e-7), `wpml:index` from 0, the height
//!   relative to the take-off point (`wpml:executeHeightMode` `relativeToStartPoint` in the
//!   waylines; `wpml:heightMode` `relativeToStartPoint` and `wpml:height` in the template), the
//!   waypoint speed (m/s), `toPointAndStopWithDiscontinuityCurvature` (stop at the
//!   waypoint), and an action group triggered on `reachPoint` with one `hover` action whose
//!   `wpml:hoverTime` is the hold (s; WPML requires > 0, so a stop without a hold has none).
//!
//! The holds, speed and positions are those of the MAVLink files (rounded before planning);
//! [`wpml_kmz`] reads its archive back ([`parse_wpml_kmz`]), prices the waylines' flight with
//! the document's energy model and refuses it above the usable budget, like the other writers.

use std::io::{Cursor, Read, Write};

use gleaner_energy::{CommandedFlight, flight_hold_s, flight_speed_mps};
use gleaner_field::LatLon;
use quick_xml::events::{BytesDecl, BytesText, Event};
use quick_xml::{Reader, Writer};

use crate::check::{check_flyable, deg7};
use crate::flight::check_commanded;
use crate::{ExportError, MissionDoc};

/// The name the KMZ goes by in errors.
pub const WPML_FILE: &str = "mission.kmz";
/// The archive entry of the template.
pub const TEMPLATE_ENTRY: &str = "wpmz/template.kml";
/// The archive entry of the executable waylines.
pub const WAYLINES_ENTRY: &str = "wpmz/waylines.wpml";
/// The KML 2.2 namespace.
pub const KML_NS: &str = "http://www.opengis.net/kml/2.2";
/// The WPML namespace (version 1.0.2 of the published reference).
pub const WPML_NS: &str = "http://www.dji.com/wpmz/1.0.2";
/// The largest speed WPML accepts for `wpml:globalTransitionalSpeed`, m/s.
pub const MAX_WPML_SPEED_MPS: f64 = 15.0;
/// The lowest take-off security height WPML accepts (`wpml:takeOffSecurityHeight`), m: the
/// flight altitude is written there, so lower flights are refused.
pub const MIN_WPML_HEIGHT_M: f64 = 2.0;

/// Which aircraft the archive declares (`wpml:droneInfo`, `wpml:payloadInfo`): enumeration
/// values of DJI's product-support tables.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct WpmlOptions {
    /// `wpml:droneEnumValue` (77: Mavic 3 Enterprise series, the default).
    pub drone_enum: u32,
    /// `wpml:droneSubEnumValue` (for 77: 0 = M3E, 1 = M3T, 2 = M3M).
    pub drone_sub_enum: u32,
    /// `wpml:payloadEnumValue` (66: the M3E camera, the default).
    pub payload_enum: u32,
}

impl Default for WpmlOptions {
    fn default() -> Self {
        Self {
            drone_enum: 77,
            drone_sub_enum: 0,
            payload_enum: 66,
        }
    }
}

type W = Writer<Cursor<Vec<u8>>>;

fn xml_err(file: &str, e: impl std::fmt::Display) -> ExportError {
    ExportError::FileValue {
        file: file.to_string(),
        line: 0,
        reason: e.to_string(),
    }
}

/// A number as WPML writes it: shortest round-trip decimal.
fn num(x: f64) -> String {
    format!("{x}")
}

/// `<name>text</name>`.
fn leaf(w: &mut W, name: &str, text: &str) -> Result<(), ExportError> {
    w.create_element(name)
        .write_text_content(BytesText::new(text))
        .map(|_| ())
        .map_err(|e| xml_err(WPML_FILE, e))
}

/// `<name>` children `</name>`.
fn parent(
    w: &mut W,
    name: &str,
    children: impl FnOnce(&mut W) -> Result<(), ExportError>,
) -> Result<(), ExportError> {
    let mut result = Ok(());
    w.create_element(name)
        .write_inner_content(|w| {
            result = children(w);
            Ok::<_, std::io::Error>(())
        })
        .map_err(|e| xml_err(WPML_FILE, e))?;
    result
}

/// The two documents share their header and mission configuration.
struct Flight<'a> {
    m: &'a MissionDoc,
    options: WpmlOptions,
    speed: f64,
    altitude: f64,
}

impl Flight<'_> {
    fn document(
        &self,
        body: impl FnOnce(&mut W) -> Result<(), ExportError>,
    ) -> Result<String, ExportError> {
        let mut w = Writer::new_with_indent(Cursor::new(Vec::new()), b' ', 2);
        w.write_event(Event::Decl(BytesDecl::new("1.0", Some("UTF-8"), None)))
            .map_err(|e| xml_err(WPML_FILE, e))?;
        let mut result = Ok(());
        w.create_element("kml")
            .with_attribute(("xmlns", KML_NS))
            .with_attribute(("xmlns:wpml", WPML_NS))
            .write_inner_content(|w| {
                result = parent(w, "Document", body);
                Ok::<_, std::io::Error>(())
            })
            .map_err(|e| xml_err(WPML_FILE, e))?;
        result?;
        String::from_utf8(w.into_inner().into_inner()).map_err(|e| xml_err(WPML_FILE, e))
    }

    fn mission_config(&self, w: &mut W, template: bool) -> Result<(), ExportError> {
        parent(w, "wpml:missionConfig", |w| {
            leaf(w, "wpml:flyToWaylineMode", "safely")?;
            leaf(w, "wpml:finishAction", "goHome")?;
            leaf(w, "wpml:exitOnRCLost", "goContinue")?;
            leaf(w, "wpml:takeOffSecurityHeight", &num(self.altitude))?;
            if template {
                let [lon, lat] = self.m.profile.base_lon_lat;
                let point = format!(
                    "{:.7},{:.7},{}",
                    deg7(lat),
                    deg7(lon),
                    num(self.m.profile.base_alt_m)
                );
                leaf(w, "wpml:takeOffRefPoint", &point)?;
            }
            leaf(w, "wpml:globalTransitionalSpeed", &num(self.speed))?;
            leaf(w, "wpml:globalRTHHeight", &num(self.altitude))?;
            parent(w, "wpml:droneInfo", |w| {
                leaf(
                    w,
                    "wpml:droneEnumValue",
                    &self.options.drone_enum.to_string(),
                )?;
                leaf(
                    w,
                    "wpml:droneSubEnumValue",
                    &self.options.drone_sub_enum.to_string(),
                )
            })?;
            parent(w, "wpml:payloadInfo", |w| {
                leaf(
                    w,
                    "wpml:payloadEnumValue",
                    &self.options.payload_enum.to_string(),
                )?;
                leaf(w, "wpml:payloadPositionIndex", "0")
            })
        })
    }

    /// One waypoint: position, index, height, speed, stop-at-point turn, hover action.
    fn placemark(&self, w: &mut W, k: usize, template: bool) -> Result<(), ExportError> {
        let s = &self.m.stops[k];
        let [lon, lat] = s.centre_lon_lat;
        parent(w, "Placemark", |w| {
            parent(w, "Point", |w| {
                leaf(
                    w,
                    "coordinates",
                    &format!("{:.7},{:.7}", deg7(lon), deg7(lat)),
                )
            })?;
            leaf(w, "wpml:index", &k.to_string())?;
            if template {
                leaf(w, "wpml:height", &num(self.altitude))?;
                leaf(w, "wpml:useGlobalHeight", "0")?;
                leaf(w, "wpml:useGlobalSpeed", "0")?;
                leaf(w, "wpml:useGlobalHeadingParam", "1")?;
                leaf(w, "wpml:useGlobalTurnParam", "0")?;
            } else {
                leaf(w, "wpml:executeHeight", &num(self.altitude))?;
            }
            leaf(w, "wpml:waypointSpeed", &num(self.speed))?;
            if !template {
                parent(w, "wpml:waypointHeadingParam", |w| {
                    leaf(w, "wpml:waypointHeadingMode", "followWayline")
                })?;
            }
            parent(w, "wpml:waypointTurnParam", |w| {
                leaf(
                    w,
                    "wpml:waypointTurnMode",
                    "toPointAndStopWithDiscontinuityCurvature",
                )?;
                leaf(w, "wpml:waypointTurnDampingDist", "0")
            })?;
            let hold = flight_hold_s(s.hover_s);
            if hold <= 0.0 {
                // WPML's hoverTime must be > 0: a stop without a hold has no action.
                return Ok(());
            }
            parent(w, "wpml:actionGroup", |w| {
                leaf(w, "wpml:actionGroupId", &k.to_string())?;
                leaf(w, "wpml:actionGroupStartIndex", &k.to_string())?;
                leaf(w, "wpml:actionGroupEndIndex", &k.to_string())?;
                leaf(w, "wpml:actionGroupMode", "sequence")?;
                parent(w, "wpml:actionTrigger", |w| {
                    leaf(w, "wpml:actionTriggerType", "reachPoint")
                })?;
                parent(w, "wpml:action", |w| {
                    leaf(w, "wpml:actionId", "0")?;
                    leaf(w, "wpml:actionActuatorFunc", "hover")?;
                    parent(w, "wpml:actionActuatorFuncParam", |w| {
                        leaf(w, "wpml:hoverTime", &num(hold))
                    })
                })
            })
        })
    }

    fn template(&self) -> Result<String, ExportError> {
        self.document(|w| {
            leaf(w, "wpml:author", "gleaner")?;
            self.mission_config(w, true)?;
            parent(w, "Folder", |w| {
                leaf(w, "wpml:templateType", "waypoint")?;
                leaf(w, "wpml:templateId", "0")?;
                parent(w, "wpml:waylineCoordinateSysParam", |w| {
                    leaf(w, "wpml:coordinateMode", "WGS84")?;
                    leaf(w, "wpml:heightMode", "relativeToStartPoint")
                })?;
                leaf(w, "wpml:autoFlightSpeed", &num(self.speed))?;
                parent(w, "wpml:globalWaypointHeadingParam", |w| {
                    leaf(w, "wpml:waypointHeadingMode", "followWayline")
                })?;
                leaf(
                    w,
                    "wpml:globalWaypointTurnMode",
                    "toPointAndStopWithDiscontinuityCurvature",
                )?;
                leaf(w, "wpml:globalHeight", &num(self.altitude))?;
                for k in 0..self.m.stops.len() {
                    self.placemark(w, k, true)?;
                }
                Ok(())
            })
        })
    }

    fn waylines(&self) -> Result<String, ExportError> {
        self.document(|w| {
            self.mission_config(w, false)?;
            parent(w, "Folder", |w| {
                leaf(w, "wpml:templateId", "0")?;
                leaf(w, "wpml:executeHeightMode", "relativeToStartPoint")?;
                leaf(w, "wpml:waylineId", "0")?;
                leaf(w, "wpml:autoFlightSpeed", &num(self.speed))?;
                for k in 0..self.m.stops.len() {
                    self.placemark(w, k, false)?;
                }
                Ok(())
            })
        })
    }
}

/// The two XML documents of the archive (`template.kml`, `waylines.wpml`) for mission `m`,
/// after [`check_flyable`] and the WPML limits (speed <= 15 m/s, altitude >= 2 m, at most
/// 65,536 waypoints).
///
/// # Errors
/// [`check_flyable`]'s refusals; [`ExportError::FileValue`] for a mission WPML cannot carry.
pub fn wpml_documents(
    m: &MissionDoc,
    options: WpmlOptions,
) -> Result<(String, String), ExportError> {
    check_flyable(m)?;
    if m.continuation.is_some() {
        return Err(ExportError::FileValue {
            file: WPML_FILE.to_string(),
            line: 0,
            reason: "a continuation re-planned in the air has no WPML form (a DJI wayline \
                     mission starts with its own take-off): upload the .plan or the WPL"
                .into(),
        });
    }
    let speed = flight_speed_mps(m.profile.cruise_speed_mps);
    if speed > MAX_WPML_SPEED_MPS {
        return Err(ExportError::FileValue {
            file: WPML_FILE.to_string(),
            line: 0,
            reason: format!(
                "the commanded speed {speed} m/s exceeds WPML's {MAX_WPML_SPEED_MPS} m/s"
            ),
        });
    }
    let altitude = gleaner_energy::flight_altitude_m(m.profile.altitude_m);
    if altitude < MIN_WPML_HEIGHT_M {
        return Err(ExportError::FileValue {
            file: WPML_FILE.to_string(),
            line: 0,
            reason: format!(
                "the flight altitude {altitude} m is below WPML's take-off security height of {MIN_WPML_HEIGHT_M} m"
            ),
        });
    }
    if m.stops.len() > 65_536 {
        return Err(ExportError::FileValue {
            file: WPML_FILE.to_string(),
            line: 0,
            reason: format!("{} waypoints: WPML numbers at most 65,536", m.stops.len()),
        });
    }
    let f = Flight {
        m,
        options,
        speed,
        altitude,
    };
    Ok((f.template()?, f.waylines()?))
}

/// The DJI WPML KMZ of mission `m` (a ZIP archive with [`TEMPLATE_ENTRY`] and
/// [`WAYLINES_ENTRY`], deflated), read back and priced before it is returned: refused above
/// the usable budget like the MAVLink files.
///
/// # Errors
/// As [`wpml_documents`]; [`ExportError::CommandedOverBudget`] (file `mission.kmz`),
/// [`ExportError::NoEnergyModel`].
pub fn wpml_kmz(m: &MissionDoc, options: WpmlOptions) -> Result<Vec<u8>, ExportError> {
    let (template, waylines) = wpml_documents(m, options)?;
    let mut zip = zip::ZipWriter::new(Cursor::new(Vec::new()));
    let opts = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated);
    for (name, text) in [(TEMPLATE_ENTRY, &template), (WAYLINES_ENTRY, &waylines)] {
        zip.start_file(name, opts)
            .map_err(|e| xml_err(WPML_FILE, e))?;
        zip.write_all(text.as_bytes())
            .map_err(|e| xml_err(WPML_FILE, e))?;
    }
    let bytes = zip
        .finish()
        .map_err(|e| xml_err(WPML_FILE, e))?
        .into_inner();
    let read = parse_wpml_kmz(&bytes)?;
    let [lon, lat] = m.profile.base_lon_lat;
    let home = LatLon::new(deg7(lat), deg7(lon)).map_err(|_| ExportError::Coordinate {
        what: "base".into(),
        lon,
        lat,
    })?;
    check_commanded(m, WPML_FILE, &read.flight(home))?;
    Ok(bytes)
}

/// One waypoint as a WPML document states it.
#[derive(Debug, Clone, PartialEq)]
pub struct WpmlWaypoint {
    /// `wpml:index`.
    pub index: usize,
    /// Position (from `coordinates`: longitude, latitude), WGS84.
    pub position: LatLon,
    /// Height above the take-off point, m (`wpml:executeHeight` or `wpml:height`).
    pub height_m: f64,
    /// `wpml:waypointSpeed`, m/s.
    pub speed_mps: f64,
    /// Sum of the `hover` actions' `wpml:hoverTime`, s.
    pub hover_s: f64,
}

/// A WPML document read back: its global speeds and heights and its waypoints.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct WpmlDocument {
    /// `wpml:globalTransitionalSpeed`, m/s.
    pub transitional_speed_mps: Option<f64>,
    /// `wpml:autoFlightSpeed`, m/s.
    pub auto_flight_speed_mps: Option<f64>,
    /// `wpml:takeOffSecurityHeight`, m.
    pub take_off_height_m: Option<f64>,
    /// `wpml:executeHeightMode` (waylines) or `wpml:heightMode` (template).
    pub height_mode: Option<String>,
    /// `wpml:finishAction`.
    pub finish_action: Option<String>,
    /// The waypoints in document order.
    pub waypoints: Vec<WpmlWaypoint>,
}

/// Both documents of a KMZ, read back.
#[derive(Debug, Clone, PartialEq)]
pub struct WpmlArchive {
    /// `wpmz/template.kml`.
    pub template: WpmlDocument,
    /// `wpmz/waylines.wpml` (what the aircraft executes).
    pub waylines: WpmlDocument,
}

impl WpmlArchive {
    /// The flight the waylines command from `home`: their waypoints and hovers, at their
    /// (single) speed and height. Checked by [`parse_wpml_kmz`] to be one speed and one
    /// height.
    #[must_use]
    pub fn flight(&self, home: LatLon) -> CommandedFlight {
        let w = &self.waylines;
        CommandedFlight {
            home,
            altitude_m: w.take_off_height_m.unwrap_or(f64::NAN),
            speed_mps: w.auto_flight_speed_mps.unwrap_or(f64::NAN),
            waypoints: w
                .waypoints
                .iter()
                .map(|p| (p.position, p.hover_s))
                .collect(),
            airborne: false,
        }
    }
}

/// Reads a KMZ written by [`wpml_kmz`]: both entries must be there and parse as XML; the
/// waylines must fly one speed (transitional, wayline and every waypoint) at one height
/// relative to the take-off point (security height and every waypoint), index the waypoints
/// 0, 1, ... and finish with `goHome`; the template must list the same waypoints, speeds,
/// heights and hovers.
///
/// # Errors
/// [`ExportError::FileValue`] naming the entry and what is wrong.
pub fn parse_wpml_kmz(bytes: &[u8]) -> Result<WpmlArchive, ExportError> {
    let mut archive =
        zip::ZipArchive::new(Cursor::new(bytes)).map_err(|e| xml_err(WPML_FILE, e))?;
    let mut entry = |name: &str| -> Result<String, ExportError> {
        let mut f = archive
            .by_name(name)
            .map_err(|e| xml_err(WPML_FILE, format!("{name}: {e}")))?;
        let mut text = String::new();
        // Bounded: a hostile archive cannot make us read more than 64 MiB.
        f.by_ref()
            .take(64 << 20)
            .read_to_string(&mut text)
            .map_err(|e| xml_err(name, e))?;
        Ok(text)
    };
    let template = parse_wpml_document(TEMPLATE_ENTRY, &entry(TEMPLATE_ENTRY)?)?;
    let waylines = parse_wpml_document(WAYLINES_ENTRY, &entry(WAYLINES_ENTRY)?)?;
    let bad = |file: &str, reason: String| ExportError::FileValue {
        file: file.to_string(),
        line: 0,
        reason,
    };
    let w = &waylines;
    if w.height_mode.as_deref() != Some("relativeToStartPoint") {
        return Err(bad(
            WAYLINES_ENTRY,
            format!(
                "executeHeightMode {:?}, expected relativeToStartPoint",
                w.height_mode
            ),
        ));
    }
    if w.finish_action.as_deref() != Some("goHome") {
        return Err(bad(
            WAYLINES_ENTRY,
            format!("finishAction {:?}, expected goHome", w.finish_action),
        ));
    }
    let (Some(speed), Some(height)) = (w.auto_flight_speed_mps, w.take_off_height_m) else {
        return Err(bad(
            WAYLINES_ENTRY,
            "no autoFlightSpeed or takeOffSecurityHeight".into(),
        ));
    };
    if w.transitional_speed_mps != Some(speed) {
        return Err(bad(
            WAYLINES_ENTRY,
            format!(
                "globalTransitionalSpeed {:?} differs from autoFlightSpeed {speed} m/s",
                w.transitional_speed_mps
            ),
        ));
    }
    for (k, p) in w.waypoints.iter().enumerate() {
        if p.index != k || p.speed_mps != speed || p.height_m != height {
            return Err(bad(
                WAYLINES_ENTRY,
                format!(
                    "waypoint {k}: index {}, speed {} m/s, height {} m (expected {k}, {speed} m/s, {height} m)",
                    p.index, p.speed_mps, p.height_m
                ),
            ));
        }
    }
    if template.waypoints != waylines.waypoints
        || template.auto_flight_speed_mps != Some(speed)
        || template.take_off_height_m != Some(height)
    {
        return Err(bad(
            TEMPLATE_ENTRY,
            "its waypoints, speeds or heights differ from the waylines'".into(),
        ));
    }
    Ok(WpmlArchive { template, waylines })
}

/// A waypoint while its `Placemark` is being read.
#[derive(Default)]
struct Partial {
    position: Option<LatLon>,
    index: Option<usize>,
    height_m: Option<f64>,
    speed_mps: Option<f64>,
    hover_s: f64,
}

/// Reads one WPML document (`file` names it in errors): the elements of [`WpmlDocument`],
/// by local name within the KML and WPML namespaces' usual prefixes.
///
/// # Errors
/// [`ExportError::FileValue`] for XML that does not parse or a value that is not a number.
pub fn parse_wpml_document(file: &str, text: &str) -> Result<WpmlDocument, ExportError> {
    let mut reader = Reader::from_str(text);
    reader.config_mut().trim_text(true);
    let mut doc = WpmlDocument::default();
    let mut path: Vec<String> = Vec::new();
    let mut current: Option<Partial> = None;
    let mut hover_action = false;
    let number = |name: &str, text: &str| -> Result<f64, ExportError> {
        text.trim()
            .parse::<f64>()
            .map_err(|_| xml_err(file, format!("{name} = {text:?} is not a number")))
    };
    loop {
        let event = reader
            .read_event()
            .map_err(|e| xml_err(file, format!("at byte {}: {e}", reader.buffer_position())))?;
        match event {
            Event::Start(e) => {
                let name = String::from_utf8_lossy(e.name().as_ref()).into_owned();
                if name == "Placemark" {
                    current = Some(Partial::default());
                }
                if name == "wpml:action" {
                    hover_action = false;
                }
                path.push(name);
            }
            Event::End(_) => {
                let closed = path.pop();
                if closed.as_deref() != Some("Placemark") {
                    continue;
                }
                let Some(Partial {
                    position: Some(position),
                    index: Some(index),
                    height_m: Some(height_m),
                    speed_mps: Some(speed_mps),
                    hover_s,
                }) = current.take()
                else {
                    return Err(xml_err(
                        file,
                        format!(
                            "waypoint {}: needs coordinates, index, height and speed",
                            doc.waypoints.len()
                        ),
                    ));
                };
                doc.waypoints.push(WpmlWaypoint {
                    index,
                    position,
                    height_m,
                    speed_mps,
                    hover_s,
                });
            }
            Event::Text(t) => {
                let text = t.decode().map_err(|e| xml_err(file, e))?.into_owned();
                let Some(name) = path.last().map(String::as_str) else {
                    continue;
                };
                let in_placemark = path.iter().any(|p| p == "Placemark");
                match (name, in_placemark) {
                    ("wpml:globalTransitionalSpeed", false) => {
                        doc.transitional_speed_mps = Some(number(name, &text)?);
                    }
                    ("wpml:autoFlightSpeed", false) => {
                        doc.auto_flight_speed_mps = Some(number(name, &text)?);
                    }
                    ("wpml:takeOffSecurityHeight", false) => {
                        doc.take_off_height_m = Some(number(name, &text)?);
                    }
                    ("wpml:executeHeightMode" | "wpml:heightMode", false) => {
                        doc.height_mode = Some(text.trim().to_string());
                    }
                    ("wpml:finishAction", false) => {
                        doc.finish_action = Some(text.trim().to_string());
                    }
                    (_, true) => {
                        let Some(c) = current.as_mut() else { continue };
                        match name {
                            "coordinates" => {
                                let parts: Vec<&str> = text.trim().split(',').collect();
                                let (Some(lon), Some(lat)) = (parts.first(), parts.get(1)) else {
                                    return Err(xml_err(file, format!("coordinates {text:?}")));
                                };
                                let (lon, lat) =
                                    (number("longitude", lon)?, number("latitude", lat)?);
                                c.position = Some(LatLon::new(lat, lon).map_err(|_| {
                                    ExportError::Coordinate {
                                        what: format!("{file} waypoint {}", doc.waypoints.len()),
                                        lon,
                                        lat,
                                    }
                                })?);
                            }
                            "wpml:index" => {
                                c.index =
                                    Some(text.trim().parse().map_err(|_| {
                                        xml_err(file, format!("wpml:index {text:?}"))
                                    })?);
                            }
                            "wpml:executeHeight" | "wpml:height" => {
                                c.height_m = Some(number(name, &text)?);
                            }
                            "wpml:waypointSpeed" => c.speed_mps = Some(number(name, &text)?),
                            "wpml:actionActuatorFunc" => hover_action = text.trim() == "hover",
                            "wpml:hoverTime" if hover_action => c.hover_s += number(name, &text)?,
                            _ => {}
                        }
                    }
                    _ => {}
                }
            }
            Event::Eof => break,
            _ => {}
        }
    }
    if !path.is_empty() {
        return Err(xml_err(file, format!("unclosed element {:?}", path.last())));
    }
    Ok(doc)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::samples::{adaptive_mission, exploration_sortie};
    use crate::{commanded_flight, qgc_plan};
    use proptest::prelude::*;

    fn home(m: &MissionDoc) -> LatLon {
        let [lon, lat] = m.profile.base_lon_lat;
        LatLon::new(deg7(lat), deg7(lon)).unwrap()
    }

    /// The archive holds exactly the two entries; both are KML 2.2 documents with the WPML
    /// namespace that parse as XML to the end.
    #[test]
    fn the_archive_holds_two_kml_documents() {
        let kmz = wpml_kmz(&adaptive_mission(), WpmlOptions::default()).unwrap();
        let mut zip = zip::ZipArchive::new(Cursor::new(&kmz[..])).unwrap();
        let mut names: Vec<String> = zip.file_names().map(str::to_string).collect();
        names.sort();
        assert_eq!(names, [TEMPLATE_ENTRY, WAYLINES_ENTRY]);
        for name in [TEMPLATE_ENTRY, WAYLINES_ENTRY] {
            let mut text = String::new();
            zip.by_name(name)
                .unwrap()
                .read_to_string(&mut text)
                .unwrap();
            assert!(text.starts_with("<?xml version=\"1.0\" encoding=\"UTF-8\"?>"));
            let mut r = Reader::from_str(&text);
            let mut depth = 0i32;
            let mut root = None;
            loop {
                match r.read_event().unwrap() {
                    Event::Start(e) => {
                        if root.is_none() {
                            let attrs: Vec<(String, String)> = e
                                .attributes()
                                .map(|a| {
                                    let a = a.unwrap();
                                    (
                                        String::from_utf8_lossy(a.key.as_ref()).into_owned(),
                                        String::from_utf8_lossy(&a.value).into_owned(),
                                    )
                                })
                                .collect();
                            root = Some((
                                String::from_utf8_lossy(e.name().as_ref()).into_owned(),
                                attrs,
                            ));
                        }
                        depth += 1;
                    }
                    Event::End(_) => depth -= 1,
                    Event::Eof => break,
                    _ => {}
                }
            }
            assert_eq!(depth, 0, "{name}");
            let (root, attrs) = root.unwrap();
            assert_eq!(root, "kml");
            assert!(
                attrs.contains(&("xmlns".into(), KML_NS.into())),
                "{attrs:?}"
            );
            assert!(
                attrs.contains(&("xmlns:wpml".into(), WPML_NS.into())),
                "{attrs:?}"
            );
        }
    }

    /// Reading the archive back gives the waypoints, speeds, heights and holds written, and
    /// the same flight the MAVLink files command.
    #[test]
    fn a_round_trip_gives_back_waypoints_speeds_and_holds() {
        for m in [adaptive_mission(), exploration_sortie()] {
            let a = parse_wpml_kmz(&wpml_kmz(&m, WpmlOptions::default()).unwrap()).unwrap();
            for doc in [&a.template, &a.waylines] {
                assert_eq!(doc.waypoints.len(), m.stops.len());
                assert_eq!(doc.auto_flight_speed_mps, Some(10.25));
                assert_eq!(doc.take_off_height_m, Some(30.0));
                for (k, (w, s)) in doc.waypoints.iter().zip(&m.stops).enumerate() {
                    assert_eq!(w.index, k);
                    assert_eq!(w.position.lon(), deg7(s.centre_lon_lat[0]));
                    assert_eq!(w.position.lat(), deg7(s.centre_lon_lat[1]));
                    assert_eq!(w.speed_mps, 10.25);
                    assert_eq!(w.height_m, 30.0);
                    assert_eq!(w.hover_s, flight_hold_s(s.hover_s));
                }
            }
            assert_eq!(
                a.template.height_mode.as_deref(),
                Some("relativeToStartPoint")
            );
            assert_eq!(a.waylines.finish_action.as_deref(), Some("goHome"));
            assert_eq!(a.flight(home(&m)), commanded_flight(&m).unwrap());
        }
    }

    /// Above the budget, refused like the MAVLink files, naming the KMZ; WPML's speed limit
    /// and every other writer's refusal hold too.
    #[test]
    fn refusals() {
        let m = adaptive_mission();
        let mut tight = m.clone();
        if let Some(model) = &mut tight.energy_model {
            model.usable_budget_j = m.energy.total_j;
        }
        let e = wpml_kmz(&tight, WpmlOptions::default()).unwrap_err();
        assert!(
            matches!(&e, ExportError::CommandedOverBudget { file, .. } if file == WPML_FILE),
            "{e}"
        );
        assert!(qgc_plan(&tight).is_err());
        let mut fast = m.clone();
        fast.profile.cruise_speed_mps = 15.2;
        let e = wpml_kmz(&fast, WpmlOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("15 m/s"), "{e}");
        let mut low = m.clone();
        low.profile.altitude_m = 1.5;
        let e = wpml_kmz(&low, WpmlOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("2 m"), "{e}");
        let mut none = m.clone();
        none.energy_model = None;
        assert!(matches!(
            wpml_kmz(&none, WpmlOptions::default()),
            Err(ExportError::NoEnergyModel)
        ));
        let mut over = m;
        over.energy.total_j = over.energy.budget_j + 1.0;
        assert!(matches!(
            wpml_kmz(&over, WpmlOptions::default()),
            Err(ExportError::OverBudget { .. })
        ));
    }

    /// The documents, for review.
    #[test]
    fn snapshots() {
        let (template, waylines) =
            wpml_documents(&adaptive_mission(), WpmlOptions::default()).unwrap();
        insta::assert_snapshot!("adaptive.template.kml", template);
        insta::assert_snapshot!("adaptive.waylines.wpml", waylines);
    }

    /// Broken archives and documents are errors, never panics.
    #[test]
    fn broken_archives_are_errors() {
        assert!(parse_wpml_kmz(b"not a zip").is_err());
        let (template, waylines) =
            wpml_documents(&adaptive_mission(), WpmlOptions::default()).unwrap();
        for (broken, says) in [
            (waylines.replace("</kml>", ""), "unclosed"),
            (waylines.replace("goHome", "noAction"), "goHome"),
            (
                waylines.replace("relativeToStartPoint", "WGS84"),
                "relativeToStartPoint",
            ),
            (
                waylines.replacen("<wpml:waypointSpeed>10.25", "<wpml:waypointSpeed>12", 1),
                "speed",
            ),
            (
                waylines.replacen("<wpml:index>1<", "<wpml:index>x<", 1),
                "wpml:index",
            ),
        ] {
            let doc = parse_wpml_document(WAYLINES_ENTRY, &broken);
            let e = match doc {
                Err(e) => e.to_string(),
                Ok(_) => {
                    let mut zip = zip::ZipWriter::new(Cursor::new(Vec::new()));
                    let o = zip::write::SimpleFileOptions::default();
                    zip.start_file(TEMPLATE_ENTRY, o).unwrap();
                    zip.write_all(template.as_bytes()).unwrap();
                    zip.start_file(WAYLINES_ENTRY, o).unwrap();
                    zip.write_all(broken.as_bytes()).unwrap();
                    let bytes = zip.finish().unwrap().into_inner();
                    parse_wpml_kmz(&bytes).unwrap_err().to_string()
                }
            };
            assert!(e.contains(says), "{says}: {e}");
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        /// Any bytes: an error or an archive, never a panic.
        #[test]
        fn any_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..600)) {
            let _ = parse_wpml_kmz(&bytes);
            let _ = parse_wpml_document("x", &String::from_utf8_lossy(&bytes));
        }

        /// Any flyable mission within WPML's limits round-trips to the MAVLink files' flight.
        #[test]
        fn any_mission_round_trips(
            dlon in proptest::collection::vec((-0.01..0.01f64, -0.01..0.01f64, 0.0..500.0f64), 1..10),
            speed in 0.2..14.0f64,
            alt in 2.0..120.0f64,
        ) {
            let mut m = adaptive_mission();
            m.energy.budget_j = 1e12;
            if let Some(model) = &mut m.energy_model {
                model.usable_budget_j = 1e12;
            }
            m.profile.cruise_speed_mps = speed;
            m.profile.altitude_m = alt;
            let template = m.stops[0].clone();
            let [lon, lat] = m.profile.base_lon_lat;
            m.stops = dlon
                .iter()
                .enumerate()
                .map(|(k, &(de, dn, h))| crate::StopDoc {
                    order: k as u32 + 1,
                    centre_lon_lat: [lon + de, lat + dn],
                    hover_s: h,
                    ..template.clone()
                })
                .collect();
            let a = parse_wpml_kmz(&wpml_kmz(&m, WpmlOptions::default()).unwrap()).unwrap();
            prop_assert_eq!(a.flight(home(&m)), commanded_flight(&m).unwrap());
        }
    }
}
