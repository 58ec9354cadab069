//! `gleaner cells`: the cell table with its metadata, as text or JSON.

use anyhow::Result;
use gleaner_ingest::time::format_rfc3339;
use gleaner_store::{CellMetadata, CellRecord, Store};
use serde::Serialize;

use crate::project::Project;

/// How to order the table.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SortKey {
    /// By grid index (column, then row).
    Label,
    /// Most sensors first.
    Sensors,
    /// Highest score first (cells never scored last).
    Score,
    /// Longest since last collection first (never collected first).
    Stale,
}

/// One cell as written by `--json`. WGS84 positions are `[lon, lat]` as in GeoJSON.
#[derive(Debug, Serialize)]
pub struct CellJson {
    /// Cell id, e.g. `x3y-1`.
    pub cell: String,
    /// Grid column.
    pub i: i32,
    /// Grid row.
    pub j: i32,
    /// Centre, `[lon, lat]` degrees.
    pub centre_lon_lat: [f64; 2],
    /// Side, metres.
    pub cell_size_m: f64,
    /// Sensor ids.
    pub sensors: Vec<String>,
    /// Last collection, RFC 3339 UTC.
    pub last_collected: Option<String>,
    /// Estimated pending data, bytes.
    pub pending_bytes: Option<f64>,
    /// Expected collection energy, J.
    pub expected_energy_j: Option<f64>,
    /// Latest utility terms.
    pub scores: Option<ScoresJson>,
    /// Per-modality summaries of the cell series.
    pub summaries: Vec<SummaryJson>,
    /// Correlations with neighbours.
    pub correlations: Vec<CorrelationJson>,
    /// Class probabilities behind U.
    pub class_probabilities: Vec<(String, f64)>,
}

/// Latest F, R, A, U, S.
#[derive(Debug, Serialize)]
pub struct ScoresJson {
    /// Freshness in [0, 1].
    pub freshness: f64,
    /// Redundancy in [0, 1].
    pub redundancy: f64,
    /// Anomaly, >= 0.
    pub anomaly: f64,
    /// Uncertainty in [0, 1].
    pub uncertainty: f64,
    /// Score.
    pub score: f64,
    /// When computed, RFC 3339 UTC.
    pub computed_at: String,
}

/// A cell series summary.
#[derive(Debug, Serialize)]
pub struct SummaryJson {
    /// Modality.
    pub modality: String,
    /// Points.
    pub count: u64,
    /// Mean.
    pub mean: f64,
    /// Sample standard deviation.
    pub std: Option<f64>,
    /// Minimum.
    pub min: f64,
    /// Maximum.
    pub max: f64,
    /// Latest value.
    pub latest_value: f64,
    /// Latest time, RFC 3339 UTC.
    pub latest_t: String,
}

/// A neighbour correlation.
#[derive(Debug, Serialize)]
pub struct CorrelationJson {
    /// Neighbour cell id.
    pub neighbour: String,
    /// Modality.
    pub modality: String,
    /// Pearson correlation.
    pub correlation: f64,
    /// Common points.
    pub overlap: u64,
}

/// Joins cells with their metadata, converted to the wire form.
pub fn cell_rows(project: &Project) -> Result<Vec<CellJson>> {
    let cells = project.store.cells()?;
    let meta = project.store.cell_metadata()?;
    Ok(cells
        .iter()
        .map(|c| to_json(c, meta.iter().find(|m| m.cell == c.index)))
        .collect())
}

fn to_json(c: &CellRecord, m: Option<&CellMetadata>) -> CellJson {
    CellJson {
        cell: c.index.to_string(),
        i: c.index.i,
        j: c.index.j,
        centre_lon_lat: [c.centre.lon(), c.centre.lat()],
        cell_size_m: c.cell_size_m,
        sensors: c.sensors.iter().map(ToString::to_string).collect(),
        last_collected: m.and_then(|m| m.last_collected).map(format_rfc3339),
        pending_bytes: m.and_then(|m| m.pending_bytes),
        expected_energy_j: m.and_then(|m| m.expected_energy_j),
        scores: m.and_then(|m| m.scores.as_ref()).map(|s| ScoresJson {
            freshness: s.freshness,
            redundancy: s.redundancy,
            anomaly: s.anomaly,
            uncertainty: s.uncertainty,
            score: s.score,
            computed_at: format_rfc3339(s.computed_at),
        }),
        summaries: m
            .map(|m| {
                m.summaries
                    .iter()
                    .map(|s| SummaryJson {
                        modality: s.modality.to_string(),
                        count: s.stats.count,
                        mean: s.stats.mean,
                        std: s.stats.std,
                        min: s.stats.min,
                        max: s.stats.max,
                        latest_value: s.stats.latest_value,
                        latest_t: format_rfc3339(s.stats.latest_t),
                    })
                    .collect()
            })
            .unwrap_or_default(),
        correlations: m
            .map(|m| {
                m.correlations
                    .iter()
                    .map(|c| CorrelationJson {
                        neighbour: c.neighbour.to_string(),
                        modality: c.modality.to_string(),
                        correlation: c.correlation,
                        overlap: c.overlap,
                    })
                    .collect()
            })
            .unwrap_or_default(),
        class_probabilities: m
            .map(|m| {
                m.class_probabilities
                    .iter()
                    .map(|p| (p.class.clone(), p.probability))
                    .collect()
            })
            .unwrap_or_default(),
    }
}

/// Sorts rows in place.
pub fn sort(rows: &mut [CellJson], key: SortKey) {
    match key {
        SortKey::Label => rows.sort_by_key(|r| (r.i, r.j)),
        SortKey::Sensors => rows.sort_by(|a, b| {
            b.sensors
                .len()
                .cmp(&a.sensors.len())
                .then((a.i, a.j).cmp(&(b.i, b.j)))
        }),
        SortKey::Score => rows.sort_by(|a, b| {
            let sa = a.scores.as_ref().map_or(f64::NEG_INFINITY, |s| s.score);
            let sb = b.scores.as_ref().map_or(f64::NEG_INFINITY, |s| s.score);
            sb.total_cmp(&sa).then((a.i, a.j).cmp(&(b.i, b.j)))
        }),
        SortKey::Stale => rows.sort_by(|a, b| {
            a.last_collected
                .cmp(&b.last_collected)
                .then((a.i, a.j).cmp(&(b.i, b.j)))
        }),
    }
}

/// The table as aligned text, one line per cell.
pub fn table(rows: &[CellJson]) -> String {
    let mut out = format!(
        "{:<10} {:>10} {:>11} {:>7} {:>8} {:>20} {:>10} {:>6} {:>6} {:>6} {:>6} {:>7}\n",
        "cell",
        "lat",
        "lon",
        "sensors",
        "readings",
        "latest",
        "pending_kB",
        "F",
        "R",
        "A",
        "U",
        "S"
    );
    for r in rows {
        let readings: u64 = r.summaries.iter().map(|s| s.count).sum();
        let latest = r
            .summaries
            .iter()
            .map(|s| s.latest_t.as_str())
            .max()
            .unwrap_or("-");
        let f = |x: Option<f64>| x.map_or("-".to_string(), |v| format!("{v:.3}"));
        let s = r.scores.as_ref();
        out.push_str(&format!(
            "{:<10} {:>10.6} {:>11.6} {:>7} {:>8} {:>20} {:>10} {:>6} {:>6} {:>6} {:>6} {:>7}\n",
            r.cell,
            r.centre_lon_lat[1],
            r.centre_lon_lat[0],
            r.sensors.len(),
            readings,
            latest,
            r.pending_bytes
                .map_or("-".to_string(), |b| format!("{:.1}", b / 1000.0)),
            f(s.map(|s| s.freshness)),
            f(s.map(|s| s.redundancy)),
            f(s.map(|s| s.anomaly)),
            f(s.map(|s| s.uncertainty)),
            f(s.map(|s| s.score)),
        ));
    }
    out
}
