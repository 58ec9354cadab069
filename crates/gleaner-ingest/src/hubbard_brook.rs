//! The USDA Forest Soil Moisture Monitoring Network loggers at Hubbard Brook (NH).
//!
//! - `sensor_metadata.csv` maps (logger, port) to a site, WGS84 lat/lon and a depth. Every
//!   probe (a logger port) is one gleaner sensor, id `<logger>:p<port>` (e.g. `z6-19506:p3`),
//!   at its site's position: replicate probes at one site then share a cell, whose series
//!   averages them (docs/method.md §2).
//! - Each logger file `z6-NNNNN.csv` has a `timestamp` column (`YYYY-MM-DD HH:MM`, fixed
//!   UTC−04:00) and columns `p<port>:<model>:<variable>:<unit>`; empty = missing. Variables
//!   become quantities at the probe's depth: `Water_Content` -> `vw`, `Soil_Temperature` ->
//!   `t`, `Bulk_EC` -> `ec`, `Saturation_Extract_EC` -> `ec_sat`, `Matric_Potential` ->
//!   `matric` (e.g. `vw@15cm` in m3/m3, `t@15cm` in degC, `matric@50cm` in kPa).

use std::collections::HashMap;
use std::path::Path;

use gleaner_field::{LatLon, Modality, Sensor, SensorId};

use crate::readers::{Policy, Table, finish, read_file};
use crate::readings::Interner;
use crate::time::{parse_clock, parse_date};
use crate::{IngestError, IngestOptions, IngestReport, Problem, Readings, SensorInput};

/// The loggers' clock: fixed UTC−04:00, seconds.
pub const HUBBARD_BROOK_UTC_OFFSET_S: i64 = -4 * 3600;

/// Probe depths from `sensor_metadata.csv`: sensor id (`<logger>:p<port>`) -> depth, cm.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct HubbardBrookMetadata {
    depths: HashMap<String, u32>,
}

/// One probe row of the metadata: line, sensor id, latitude and longitude (degrees), depth (cm),
/// and what the probe measures (the optional `meas` column: `vwc`, `matric`, ...).
type ProbeRow = (u64, String, f64, f64, u32, Option<String>);

fn metadata_rows(path: &Path) -> Result<Vec<ProbeRow>, IngestError> {
    let bytes = read_file(path)?;
    let mut table = Table::open(path, &bytes, b',')?;
    let c_logger = table.require(&["logger"])?;
    let c_port = table.require(&["port"])?;
    let c_lat = table.require(&["lat"])?;
    let c_lon = table.require(&["lon"])?;
    let c_depth = table.require(&["depth_cm"])?;
    let c_meas = table.find(&["meas"]);
    let names = table.header.clone();
    let mut out = Vec::new();
    let mut report = IngestReport::default();
    let policy = Policy::new(path, crate::OnError::Fail);
    while let Some(line) = table.next_row(&policy, &mut report)? {
        let field = |k: usize| table.text(k).map_or_else(|lossy| lossy, str::to_string);
        let bad = |k: usize, problem: Problem| IngestError::Field {
            path: path.to_path_buf(),
            line,
            column: names[k].clone(),
            value: field(k),
            problem,
        };
        for k in [c_logger, c_port, c_lat, c_lon, c_depth] {
            if table.text(k).is_err() {
                return Err(bad(k, Problem::NotUtf8));
            }
        }
        let id = format!("{}:p{}", field(c_logger), field(c_port));
        let lat: f64 = field(c_lat)
            .parse()
            .map_err(|_| bad(c_lat, Problem::NotANumber))?;
        let lon: f64 = field(c_lon)
            .parse()
            .map_err(|_| bad(c_lon, Problem::NotANumber))?;
        let depth: u32 = field(c_depth)
            .parse()
            .map_err(|_| bad(c_depth, Problem::NotANumber))?;
        let meas = c_meas.map(field);
        out.push((line, id, lat, lon, depth, meas));
    }
    Ok(out)
}

/// The depth (cm) at which `sensor_metadata.csv` has the most water-content probes (`meas` =
/// `vwc`; ties go to the shallower depth), `None` without any: the network's main soil-moisture
/// modality is `vw@<depth>cm`. Hubbard Brook's sites have probes at many depths (10-90 cm)
/// but nearly all at 50 cm (22 probes) and 15 cm (12); only two at 30 cm.
pub fn hubbard_brook_main_water_depth(path: &Path) -> Result<Option<u32>, IngestError> {
    let mut counts: std::collections::BTreeMap<u32, usize> = Default::default();
    for (_, _, _, _, depth, meas) in metadata_rows(path)? {
        if meas.is_some_and(|m| m.eq_ignore_ascii_case("vwc")) {
            *counts.entry(depth).or_default() += 1;
        }
    }
    // BTreeMap iterates shallow to deep; `max_by_key` keeps the last maximum, so reverse.
    Ok(counts
        .into_iter()
        .rev()
        .max_by_key(|&(_, n)| n)
        .map(|(d, _)| d))
}

impl HubbardBrookMetadata {
    /// Reads `sensor_metadata.csv`.
    pub fn read(path: &Path) -> Result<Self, IngestError> {
        Ok(Self {
            depths: metadata_rows(path)?
                .into_iter()
                .map(|(_, id, _, _, d, _)| (id, d))
                .collect(),
        })
    }
}

/// The probes of `sensor_metadata.csv` as sensors (id `<logger>:p<port>`, WGS84 position of
/// their site). Duplicate (logger, port) rows are errors.
pub fn read_hubbard_brook_sensors(
    path: &Path,
) -> Result<(Vec<SensorInput>, IngestReport), IngestError> {
    let mut seen: HashMap<String, u64> = HashMap::new();
    let mut out = Vec::new();
    let rows = metadata_rows(path)?;
    let mut report = IngestReport {
        rows_read: rows.len() as u64,
        ..Default::default()
    };
    for (line, id, lat, lon, _, _) in rows {
        let field_err = |value: String, problem| IngestError::Field {
            path: path.to_path_buf(),
            line,
            column: "logger/port".into(),
            value,
            problem,
        };
        if let Some(&first_line) = seen.get(&id) {
            return Err(field_err(id, Problem::DuplicateSensor { first_line }));
        }
        let position = LatLon::new(lat, lon)
            .map_err(|_| field_err(format!("{lat}, {lon}"), Problem::BadPosition))?;
        let sid =
            SensorId::new(id.clone()).map_err(|_| field_err(id.clone(), Problem::BadSensorId))?;
        seen.insert(id, line);
        out.push(SensorInput {
            sensor: Sensor::new(sid, position),
            line,
        });
    }
    report.readings = out.len() as u64;
    Ok((out, report))
}

fn quantity(variable: &str) -> Option<&'static str> {
    Some(match variable {
        "Water_Content" => "vw",
        "Soil_Temperature" => "t",
        "Bulk_EC" => "ec",
        "Saturation_Extract_EC" => "ec_sat",
        "Matric_Potential" => "matric",
        _ => return None,
    })
}

fn unit(raw: &str) -> String {
    raw.replace("_per_", "/")
}

/// Reads one logger file (its name, without `.csv`, is the logger id). A column whose probe is
/// not in `metadata`, or not a known variable, is an error on line 1 (skipped whole under
/// [`crate::OnError::Skip`]).
pub fn read_hubbard_brook_logger(
    path: &Path,
    metadata: &HubbardBrookMetadata,
    options: &IngestOptions,
) -> Result<(Readings, IngestReport), IngestError> {
    let logger = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let bytes = read_file(path)?;
    let mut table = Table::open(path, &bytes, b',')?;
    let c_time = table.require(&["timestamp"])?;
    let names = table.header.clone();
    let policy = Policy::for_readings(path, options);
    let mut report = IngestReport::default();
    let mut interner = Interner::default();
    let mut columns: Vec<(usize, u32, u32)> = Vec::new();
    for (k, name) in names.iter().enumerate() {
        if k == c_time {
            continue;
        }
        let parts: Vec<&str> = name.split(':').collect();
        let parsed = match parts[..] {
            [port, _model, variable, unit_raw] => {
                let id = format!("{logger}:{port}");
                match (metadata.depths.get(&id), quantity(variable)) {
                    (Some(&depth), Some(q)) => {
                        Some((id, Modality::at_depth(q, Some(depth)).ok(), unit(unit_raw)))
                    }
                    _ => None,
                }
            }
            _ => None,
        };
        let Some((id, Some(modality), unit)) = parsed else {
            policy.bad(&mut report, 1, name, name, Problem::BadModality)?;
            continue;
        };
        let sensor = match interner.known_sensor(&id, options) {
            Ok(s) => s,
            Err(p) => {
                policy.bad(&mut report, 1, name, &id, p)?;
                continue;
            }
        };
        let m = interner
            .modality(modality, Some(&unit))
            .map_err(|expected| IngestError::Field {
                path: path.to_path_buf(),
                line: 1,
                column: name.clone(),
                value: unit.clone(),
                problem: Problem::UnitMismatch { expected },
            })?;
        columns.push((k, sensor, m));
    }
    while let Some(line) = table.next_row(&policy, &mut report)? {
        let stamp = match table.text(c_time) {
            Ok(s) => s,
            Err(lossy) => {
                policy.bad(&mut report, line, &names[c_time], &lossy, Problem::NotUtf8)?;
                continue;
            }
        };
        let t = stamp
            .split_once(' ')
            .and_then(|(d, c)| Some(parse_date(d)? + parse_clock(c)?))
            .map(|local| local - HUBBARD_BROOK_UTC_OFFSET_S);
        let Some(t) = t else {
            policy.bad(
                &mut report,
                line,
                &names[c_time],
                stamp,
                Problem::BadTimestamp,
            )?;
            continue;
        };
        if !policy.check_time(&mut report, (line, &names[c_time]), t, stamp)? {
            continue;
        }
        let cells = columns
            .iter()
            .map(|&(c, sensor, modality)| (c, sensor, modality, table.text(c)));
        policy.push_values(&mut interner, &mut report, &names, (line, t), cells)?;
    }
    finish(interner, &policy, report, "value")
}
