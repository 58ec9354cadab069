//! `gleaner export`: a planned mission as files that real tools open — GeoJSON (RFC 7946) for
//! GIS, a QGroundControl `.plan` and a `QGC WPL 110` waypoint file for the autopilot.
//!
//! Every wire format here is its own serialisable type, filled explicitly from the stored
//! mission summary and the project's cells.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use gleaner_store::Store;
use serde::{Deserialize, Serialize};
use serde_json::{Value, json};

use crate::project::Project;

/// The fields of a stored mission summary that export needs (written by `gleaner plan`).
#[derive(Deserialize)]
struct StoredMission {
    base_lon_lat: [f64; 2],
    cruise_speed_mps: f64,
    stops: Vec<StoredStop>,
}

#[derive(Deserialize)]
struct StoredStop {
    order: usize,
    cell: String,
    centre_lon_lat: [f64; 2],
    hover_s: f64,
}

/// The files written.
pub struct Exported {
    /// `mission.geojson`.
    pub geojson: PathBuf,
    /// `mission.plan`.
    pub plan: PathBuf,
    /// `mission.waypoints`.
    pub waypoints: PathBuf,
}

/// Rounds a WGS84 coordinate to 1e-7 degrees (about 1 cm), as autopilots store them.
fn deg(x: f64) -> f64 {
    (x * 1e7).round() / 1e7
}

/// The GeoJSON FeatureCollection: every cell as a Polygon (counter-clockwise ring, `[lon, lat]`)
/// with its latest terms and whether/when it is visited, the route as a LineString from the
/// base and back, and the base as a Point.
fn geojson(project: &Project, m: &StoredMission) -> Result<Value> {
    let (_, field) = project.field()?;
    let metadata = project.store.cell_metadata()?;
    let mut features = Vec::new();
    for (k, cell) in field.cells().iter().enumerate() {
        let label = cell.index.to_string();
        let ring: Vec<[f64; 2]> = field
            .cell_corners(gleaner_field::CellId(k as u32))
            .iter()
            .chain(std::iter::once(
                &field.cell_corners(gleaner_field::CellId(k as u32))[0],
            ))
            .map(|p| {
                let ll = field.frame().inverse(*p);
                [deg(ll.lon()), deg(ll.lat())]
            })
            .collect();
        let scores = metadata
            .iter()
            .find(|x| x.cell == cell.index)
            .and_then(|x| x.scores.as_ref());
        let order = m.stops.iter().find(|s| s.cell == label).map(|s| s.order);
        features.push(json!({
            "type": "Feature",
            "geometry": { "type": "Polygon", "coordinates": [ring] },
            "properties": {
                "kind": "cell",
                "cell": label,
                "sensors": cell.sensors.len(),
                "visit_order": order,
                "S": scores.map(|s| s.score),
                "F": scores.map(|s| s.freshness),
                "R": scores.map(|s| s.redundancy),
                "A": scores.map(|s| s.anomaly),
                "U": scores.map(|s| s.uncertainty),
            }
        }));
    }
    let base = [deg(m.base_lon_lat[0]), deg(m.base_lon_lat[1])];
    let mut line = vec![base];
    line.extend(
        m.stops
            .iter()
            .map(|s| [deg(s.centre_lon_lat[0]), deg(s.centre_lon_lat[1])]),
    );
    line.push(base);
    features.push(json!({
        "type": "Feature",
        "geometry": { "type": "LineString", "coordinates": line },
        "properties": { "kind": "route", "cells": m.stops.len() }
    }));
    features.push(json!({
        "type": "Feature",
        "geometry": { "type": "Point", "coordinates": base },
        "properties": { "kind": "base" }
    }));
    Ok(json!({ "type": "FeatureCollection", "features": features }))
}

/// One QGroundControl mission item.
#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct QgcItem {
    #[serde(rename = "AMSLAltAboveTerrain")]
    amsl_alt_above_terrain: Option<f64>,
    #[serde(rename = "Altitude")]
    altitude: f64,
    #[serde(rename = "AltitudeMode")]
    altitude_mode: u8,
    auto_continue: bool,
    command: u16,
    do_jump_id: usize,
    frame: u8,
    params: [Option<f64>; 7],
    #[serde(rename = "type")]
    kind: &'static str,
}

/// MAVLink commands and frames used.
const NAV_WAYPOINT: u16 = 16;
const NAV_RETURN_TO_LAUNCH: u16 = 20;
const NAV_TAKEOFF: u16 = 22;
const FRAME_GLOBAL_RELATIVE_ALT: u8 = 3;
const FRAME_MISSION: u8 = 2;

/// (command, frame, hold s, lat, lon, alt m) for every item after home.
fn items(m: &StoredMission, alt: f64) -> Vec<(u16, u8, f64, f64, f64, f64)> {
    let [lon, lat] = m.base_lon_lat;
    let mut out = vec![(
        NAV_TAKEOFF,
        FRAME_GLOBAL_RELATIVE_ALT,
        0.0,
        deg(lat),
        deg(lon),
        alt,
    )];
    out.extend(m.stops.iter().map(|s| {
        let [lon, lat] = s.centre_lon_lat;
        (
            NAV_WAYPOINT,
            FRAME_GLOBAL_RELATIVE_ALT,
            (s.hover_s * 10.0).ceil() / 10.0,
            deg(lat),
            deg(lon),
            alt,
        )
    }));
    out.push((NAV_RETURN_TO_LAUNCH, FRAME_MISSION, 0.0, 0.0, 0.0, 0.0));
    out
}

/// The QGroundControl `.plan` (fileType Plan, version 1, mission version 2), with the
/// `geoFence` and `rallyPoints` objects MAVSDK's importer requires.
fn qgc_plan(m: &StoredMission, alt: f64) -> Value {
    let [lon, lat] = m.base_lon_lat;
    let items: Vec<QgcItem> = items(m, alt)
        .into_iter()
        .enumerate()
        .map(|(k, (command, frame, hold, lat, lon, alt))| {
            let rtl = command == NAV_RETURN_TO_LAUNCH;
            QgcItem {
                amsl_alt_above_terrain: None,
                altitude: alt,
                altitude_mode: 1,
                auto_continue: true,
                command,
                do_jump_id: k + 1,
                frame,
                params: if rtl {
                    [Some(0.0); 7]
                } else {
                    [
                        Some(hold),
                        Some(0.0),
                        Some(0.0),
                        None,
                        Some(lat),
                        Some(lon),
                        Some(alt),
                    ]
                },
                kind: "SimpleItem",
            }
        })
        .collect();
    json!({
        "fileType": "Plan",
        "version": 1,
        "groundStation": "gleaner",
        "mission": {
            "version": 2,
            "firmwareType": 12,
            "vehicleType": 2,
            "cruiseSpeed": m.cruise_speed_mps,
            "hoverSpeed": 5,
            "globalPlanAltitudeMode": 1,
            "plannedHomePosition": [deg(lat), deg(lon), 0],
            "items": items,
        },
        "geoFence": { "circles": [], "polygons": [], "version": 2 },
        "rallyPoints": { "points": [], "version": 2 },
    })
}

/// The `QGC WPL 110` text file: tab-separated, line 0 = home.
fn wpl(m: &StoredMission, alt: f64) -> String {
    let [lon, lat] = m.base_lon_lat;
    let mut out = String::from("QGC WPL 110\n");
    out.push_str(&format!(
        "0\t1\t0\t{NAV_WAYPOINT}\t0\t0\t0\t0\t{:.7}\t{:.7}\t0\t1\n",
        deg(lat),
        deg(lon)
    ));
    for (k, (command, frame, hold, lat, lon, alt)) in items(m, alt).into_iter().enumerate() {
        out.push_str(&format!(
            "{}\t0\t{frame}\t{command}\t{hold}\t0\t0\t0\t{lat:.7}\t{lon:.7}\t{alt}\t1\n",
            k + 1
        ));
    }
    out
}

/// Writes the three files for mission `id` into `out` (default: `<project>/missions/<id>`).
pub fn run(project: &Project, project_dir: &Path, id: i64, out: Option<&Path>) -> Result<Exported> {
    let missions = project.store.missions()?;
    let Some(mission) = missions.iter().find(|m| m.id.0 == id) else {
        bail!("no mission #{id} (see `gleaner plan`)");
    };
    let m: StoredMission = serde_json::from_str(&mission.mission.summary_json).with_context(|| {
        format!("mission #{id} has no route to export (exploration sorties: plan them with `gleaner plan`)")
    })?;
    let alt = project.config.energy.to_core()?.link.altitude_m;
    let dir = out.map_or_else(
        || project_dir.join("missions").join(id.to_string()),
        Path::to_path_buf,
    );
    std::fs::create_dir_all(&dir).with_context(|| format!("{}: cannot create", dir.display()))?;
    let files = Exported {
        geojson: dir.join("mission.geojson"),
        plan: dir.join("mission.plan"),
        waypoints: dir.join("mission.waypoints"),
    };
    let write = |path: &Path, text: String| {
        std::fs::write(path, text).with_context(|| format!("{}: cannot write", path.display()))
    };
    write(
        &files.geojson,
        serde_json::to_string_pretty(&geojson(project, &m)?)?,
    )?;
    write(
        &files.plan,
        serde_json::to_string_pretty(&qgc_plan(&m, alt))?,
    )?;
    write(&files.waypoints, wpl(&m, alt))?;
    Ok(files)
}
