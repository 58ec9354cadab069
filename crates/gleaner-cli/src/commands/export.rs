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
    planned_at: String,
    planner: String,
    base_lon_lat: [f64; 2],
    cruise_speed_mps: f64,
    stops: Vec<StoredStop>,
    energy: StoredEnergy,
    total_score: f64,
}

#[derive(Deserialize)]
struct StoredEnergy {
    travel_j: f64,
    hover_j: f64,
    comm_j: f64,
    return_j: f64,
    total_j: f64,
    budget_j: f64,
    utilisation: f64,
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
    /// `mission.svg`.
    pub map: PathBuf,
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

/// A colour for `x` in [0, 1]: a perceptually ordered ramp from dark blue through teal to yellow
/// (viridis-like, 5 stops, linearly interpolated).
fn ramp(x: f64) -> String {
    const STOPS: [[f64; 3]; 5] = [
        [68.0, 1.0, 84.0],
        [59.0, 82.0, 139.0],
        [33.0, 145.0, 140.0],
        [94.0, 201.0, 98.0],
        [253.0, 231.0, 37.0],
    ];
    let x = if x.is_finite() {
        x.clamp(0.0, 1.0)
    } else {
        0.0
    } * 4.0;
    let k = (x.floor() as usize).min(3);
    let f = x - k as f64;
    let c: Vec<u8> = (0..3)
        .map(|i| (STOPS[k][i] + f * (STOPS[k + 1][i] - STOPS[k][i])).round() as u8)
        .collect();
    format!("#{:02x}{:02x}{:02x}", c[0], c[1], c[2])
}

/// A round scale-bar length, metres: 1, 2 or 5 times a power of ten, about a fifth of `span_m`.
fn scale_bar_m(span_m: f64) -> f64 {
    let target = (span_m / 5.0).max(1.0);
    let p = 10f64.powf(target.log10().floor());
    [5.0, 2.0, 1.0]
        .into_iter()
        .map(|k| k * p)
        .find(|&v| v <= target)
        .unwrap_or(p)
}

/// The mission map as SVG: cells coloured by S, visited cells outlined with their visiting
/// order, the route from the base and back, a scale bar, a colour legend and the energy
/// summary. North is up; the drawing is in the local east/north frame (metres).
fn svg_map(project: &Project, m: &StoredMission) -> Result<String> {
    use std::fmt::Write as _;
    let (_, field) = project.field()?;
    let metadata = project.store.cell_metadata()?;
    let size = field.cell_size_m();
    let base = gleaner_field::LocalPoint::new(0.0, 0.0);
    let (mut e0, mut e1, mut n0, mut n1) = (base.e, base.e, base.n, base.n);
    for k in 0..field.cells().len() {
        for p in field.cell_corners(gleaner_field::CellId(k as u32)) {
            e0 = e0.min(p.e);
            e1 = e1.max(p.e);
            n0 = n0.min(p.n);
            n1 = n1.max(p.n);
        }
    }
    let pad = size;
    let (w_m, h_m) = (e1 - e0 + 2.0 * pad, n1 - n0 + 2.0 * pad);
    let scale = 900.0 / w_m.max(h_m);
    let (w, h) = (w_m * scale, h_m * scale);
    let x = |e: f64| (e - e0 + pad) * scale;
    let y = |n: f64| (n1 + pad - n) * scale;
    let scores: Vec<Option<f64>> = field
        .cells()
        .iter()
        .map(|c| {
            metadata
                .iter()
                .find(|x| x.cell == c.index)
                .and_then(|x| x.scores.as_ref())
                .map(|s| s.score)
        })
        .collect();
    let (lo, hi) = scores
        .iter()
        .flatten()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let norm = |v: f64| if hi > lo { (v - lo) / (hi - lo) } else { 0.5 };
    let panel = 260.0;
    let mut out = String::new();
    writeln!(
        out,
        r##"<svg xmlns="http://www.w3.org/2000/svg" width="{:.0}" height="{:.0}" viewBox="0 0 {:.0} {:.0}" font-family="sans-serif" font-size="12">"##,
        w + panel,
        h.max(320.0),
        w + panel,
        h.max(320.0)
    )?;
    writeln!(
        out,
        r##"<rect width="100%" height="100%" fill="#ffffff"/>"##
    )?;
    for (k, cell) in field.cells().iter().enumerate() {
        let c = field.cell_corners(gleaner_field::CellId(k as u32));
        let fill = scores[k].map_or_else(|| "#dddddd".to_string(), |v| ramp(norm(v)));
        writeln!(
            out,
            r##"<rect x="{:.1}" y="{:.1}" width="{:.1}" height="{:.1}" fill="{fill}" stroke="#555555" stroke-width="0.5"><title>{} S={}</title></rect>"##,
            x(c[0].e),
            y(c[2].n),
            size * scale,
            size * scale,
            cell.index,
            scores[k].map_or("n/a".to_string(), |v| format!("{v:.3}"))
        )?;
    }
    let frame = field.frame();
    let local = |lon_lat: [f64; 2]| -> Result<gleaner_field::LocalPoint> {
        Ok(frame.forward(gleaner_field::LatLon::new(lon_lat[1], lon_lat[0])?))
    };
    let mut path = vec![base];
    for s in &m.stops {
        path.push(local(s.centre_lon_lat)?);
    }
    path.push(base);
    let points: Vec<String> = path
        .iter()
        .map(|p| format!("{:.1},{:.1}", x(p.e), y(p.n)))
        .collect();
    writeln!(
        out,
        r##"<polyline points="{}" fill="none" stroke="#d62728" stroke-width="2.5" stroke-linejoin="round"/>"##,
        points.join(" ")
    )?;
    for s in &m.stops {
        let p = local(s.centre_lon_lat)?;
        writeln!(
            out,
            r##"<circle cx="{:.1}" cy="{:.1}" r="9" fill="#ffffff" stroke="#d62728" stroke-width="2"/><text x="{:.1}" y="{:.1}" text-anchor="middle" font-size="10" font-weight="bold">{}</text>"##,
            x(p.e),
            y(p.n),
            x(p.e),
            y(p.n) + 3.5,
            s.order
        )?;
    }
    writeln!(
        out,
        r##"<rect x="{:.1}" y="{:.1}" width="14" height="14" fill="#000000"/><text x="{:.1}" y="{:.1}" font-weight="bold">base</text>"##,
        x(base.e) - 7.0,
        y(base.n) - 7.0,
        x(base.e) + 10.0,
        y(base.n) + 4.0
    )?;
    let bar = scale_bar_m(w_m);
    writeln!(
        out,
        r##"<line x1="20" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="#000000" stroke-width="3"/><text x="20" y="{:.1}">{bar} m</text><text x="{:.1}" y="24" font-size="16" font-weight="bold">N ↑</text>"##,
        h - 20.0,
        20.0 + bar * scale,
        h - 20.0,
        h - 28.0,
        w - 40.0
    )?;
    let px = w + 20.0;
    writeln!(
        out,
        r##"<text x="{px:.0}" y="30" font-size="14" font-weight="bold">gleaner mission</text>"##
    )?;
    let lines = [
        format!("planned for {}", m.planned_at),
        format!("planner: {}", m.planner),
        format!("{} cells, total S = {:.3}", m.stops.len(), m.total_score),
        format!("E_t travel  {:>9.1} J", m.energy.travel_j),
        format!("E_h hover   {:>9.1} J", m.energy.hover_j),
        format!("E_c comm    {:>9.1} J", m.energy.comm_j),
        format!("E_r return  {:>9.1} J", m.energy.return_j),
        format!(
            "total {:.1} of {:.1} J",
            m.energy.total_j, m.energy.budget_j
        ),
        format!("utilisation {:.1}%", 100.0 * m.energy.utilisation),
    ];
    for (k, line) in lines.iter().enumerate() {
        writeln!(
            out,
            r##"<text x="{px:.0}" y="{:.0}">{line}</text>"##,
            55.0 + 18.0 * k as f64
        )?;
    }
    let ly = 55.0 + 18.0 * lines.len() as f64 + 20.0;
    writeln!(
        out,
        r##"<text x="{px:.0}" y="{ly:.0}" font-weight="bold">score S</text>"##
    )?;
    for k in 0..10 {
        writeln!(
            out,
            r##"<rect x="{:.0}" y="{:.0}" width="20" height="12" fill="{}"/>"##,
            px + 20.0 * k as f64,
            ly + 8.0,
            ramp(k as f64 / 9.0)
        )?;
    }
    if hi >= lo {
        writeln!(
            out,
            r##"<text x="{px:.0}" y="{:.0}">{lo:.2}</text><text x="{:.0}" y="{:.0}" text-anchor="end">{hi:.2}</text>"##,
            ly + 36.0,
            px + 200.0,
            ly + 36.0
        )?;
    }
    writeln!(out, "</svg>")?;
    Ok(out)
}

/// Writes the files for mission `id` into `out` (default: `<project>/missions/<id>`).
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
        map: dir.join("mission.svg"),
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
    write(&files.map, svg_map(project, &m)?)?;
    Ok(files)
}
