//! Reads the shared CAF daily data into calibration panels (test and example helper; the
//! library itself does no file input).

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use gleaner_field::LocalPoint;
use gleaner_synth::DailyPanel;

/// The shared data folder: `GLEANER_DATA_DIR`, else `../shared/data` beside the workspace.
pub fn data_dir() -> PathBuf {
    std::env::var_os("GLEANER_DATA_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/data"))
        })
}

/// Days since 1970-01-01 of a civil date.
fn days(y: i64, m: i64, d: i64) -> i64 {
    let y = if m <= 2 { y - 1 } else { y };
    let era = y.div_euclid(400);
    let yoe = y.rem_euclid(400);
    let doy = (153 * (if m > 2 { m - 3 } else { m + 9 }) + 2) / 5 + d - 1;
    era * 146_097 + yoe * 365 + yoe / 4 - yoe / 100 + doy - 719_468
}

fn parse_date(s: &str) -> Option<i64> {
    let mut it = s.split('/');
    let m = it.next()?.parse().ok()?;
    let d = it.next()?.parse().ok()?;
    let y = it.next()?.parse().ok()?;
    Some(days(y, m, d))
}

/// One panel per requested column (e.g. `VW_30cm`), sensors in file-name order, days aligned
/// on the earliest date in the data. Positions are UTM metres.
pub fn caf_panels(dir: &Path, columns: &[&str]) -> Result<Vec<DailyPanel>, String> {
    let caf = dir.join("caf");
    let locations = std::fs::read_to_string(caf.join("sensors/CAF_sensor_locations.csv"))
        .map_err(|e| format!("reading CAF sensor locations under {}: {e}", caf.display()))?;
    let mut pos = HashMap::new();
    for line in locations.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        if f.len() < 3 {
            continue;
        }
        let (Ok(e), Ok(n)) = (f[1].parse::<f64>(), f[2].parse::<f64>()) else {
            continue;
        };
        pos.insert(f[0].to_string(), LocalPoint::new(e, n));
    }
    let mut files: Vec<PathBuf> = std::fs::read_dir(caf.join("Daily"))
        .map_err(|e| format!("listing CAF daily files: {e}"))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "txt"))
        .collect();
    files.sort();
    let mut rows_per_sensor = Vec::new();
    let mut first_day = i64::MAX;
    for path in &files {
        let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let mut lines = text.lines();
        let header: Vec<&str> = lines.next().unwrap_or_default().split('\t').collect();
        let idx: Vec<usize> = columns
            .iter()
            .map(|c| {
                header
                    .iter()
                    .position(|h| h == c)
                    .ok_or(format!("{c} missing"))
            })
            .collect::<Result<_, _>>()?;
        let mut name = String::new();
        let mut rows = Vec::new();
        for line in lines {
            let f: Vec<&str> = line.split('\t').collect();
            let Some(day) = f.get(1).and_then(|d| parse_date(d)) else {
                continue;
            };
            name = f[0].to_string();
            first_day = first_day.min(day);
            let vals: Vec<f64> = idx
                .iter()
                .map(|&i| f.get(i).and_then(|v| v.parse().ok()).unwrap_or(f64::NAN))
                .collect();
            rows.push((day, vals));
        }
        if let Some(p) = pos.get(&name) {
            rows_per_sensor.push((*p, rows));
        }
    }
    let mut panels = vec![DailyPanel::default(); columns.len()];
    for (p, rows) in rows_per_sensor {
        let len = rows
            .iter()
            .map(|(d, _)| d - first_day + 1)
            .max()
            .unwrap_or(0) as usize;
        for (c, panel) in panels.iter_mut().enumerate() {
            let mut series = vec![f64::NAN; len];
            for (d, vals) in &rows {
                series[(d - first_day) as usize] = vals[c];
            }
            panel.positions.push(p);
            panel.series.push(series);
        }
    }
    Ok(panels)
}

/// The CAF daily network between two civil dates (inclusive), as a [`NetworkPanel`] with the
/// default farm's modalities: VW at 30, 60 and 90 cm and soil temperature at 30 cm.
#[allow(dead_code)]
pub fn caf_network(
    dir: &Path,
    from: (i64, i64, i64),
    to: (i64, i64, i64),
) -> Result<gleaner_synth::NetworkPanel, String> {
    caf_network_columns(dir, from, to, &["VW_30cm", "VW_60cm", "VW_90cm", "T_30cm"])
}

/// Every CAF column: VW and soil temperature at 30, 60, 90, 120 and 150 cm.
#[allow(dead_code)]
pub const ALL_COLUMNS: [&str; 10] = [
    "VW_30cm", "VW_60cm", "VW_90cm", "VW_120cm", "VW_150cm", "T_30cm", "T_60cm", "T_90cm",
    "T_120cm", "T_150cm",
];

/// The CAF daily network between two civil dates (inclusive) with the given columns (e.g.
/// [`ALL_COLUMNS`]), named as modalities (`VW_30cm` -> `vw@30cm`).
#[allow(dead_code)]
pub fn caf_network_columns(
    dir: &Path,
    from: (i64, i64, i64),
    to: (i64, i64, i64),
    columns: &[&str],
) -> Result<gleaner_synth::NetworkPanel, String> {
    let names: Vec<String> = columns
        .iter()
        .map(|c| c.to_lowercase().replacen('_', "@", 1))
        .collect();
    let panels = caf_panels(dir, columns)?;
    let first = first_day(dir)?;
    let (a, b) = (days(from.0, from.1, from.2), days(to.0, to.1, to.2));
    let (i, j) = ((a - first).max(0) as usize, (b - first + 1).max(0) as usize);
    let modalities = panels
        .iter()
        .zip(&names)
        .map(|(p, name)| gleaner_synth::PanelModality {
            name: name.to_string(),
            is_water: name.starts_with("vw"),
            depth_cm: name[name.find('@').unwrap_or(0) + 1..name.len() - 2]
                .parse()
                .unwrap_or(0),
            series: p
                .series
                .iter()
                .map(|s| {
                    (i..j)
                        .map(|d| s.get(d).copied().unwrap_or(f64::NAN))
                        .collect()
                })
                .collect(),
        })
        .collect();
    Ok(gleaner_synth::NetworkPanel {
        positions: panels[0].positions.clone(),
        first_day: a,
        modalities,
        event_days: Vec::new(),
    })
}

/// Earliest date in the CAF daily files, days since 1970-01-01.
fn first_day(dir: &Path) -> Result<i64, String> {
    let daily = dir.join("caf").join("Daily");
    let mut first = i64::MAX;
    for e in std::fs::read_dir(&daily).map_err(|e| format!("listing {}: {e}", daily.display()))? {
        let path = e.map_err(|e| e.to_string())?.path();
        if path.extension().is_none_or(|x| x != "txt") {
            continue;
        }
        let text =
            std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
        if let Some(d) = text
            .lines()
            .nth(1)
            .and_then(|l| l.split('\t').nth(1))
            .and_then(parse_date)
        {
            first = first.min(d);
        }
    }
    Ok(first)
}
