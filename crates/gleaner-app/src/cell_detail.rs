//! Read model: one cell with why it ranks where it does and its recent series (the
//! dashboard's cell panel).

use gleaner_field::{CellIndex, Modality, SensorId, UnixSeconds};
use gleaner_store::Store;

use crate::view::{CellView, field_view};
use gleaner_scoring::Project;
use gleaner_scoring::{AppError, Result};

/// The weighted terms of S = α·F + β·A + γ·U − δ·R for one cell (dimensionless).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contributions {
    /// α·F.
    pub freshness: f64,
    /// β·A (A as used in S).
    pub anomaly: f64,
    /// γ·U.
    pub uncertainty: f64,
    /// −δ·R (never positive).
    pub redundancy: f64,
}

/// One stored reading of a cell's sensor.
#[derive(Debug, Clone, PartialEq)]
pub struct SeriesPoint {
    /// The sensor.
    pub sensor: SensorId,
    /// The modality (`vw@30cm`).
    pub modality: Modality,
    /// Time, seconds since the Unix epoch (UTC).
    pub t: UnixSeconds,
    /// Value, in the modality's unit.
    pub value: f64,
}

/// A cell with the reason it ranks where it does and its recent readings.
#[derive(Debug, Clone, PartialEq)]
pub struct CellDetail {
    /// The cell and its metadata.
    pub cell: CellView,
    /// Weights α, β, γ, δ of the project's settings.
    pub weights: [f64; 4],
    /// The weighted terms of its latest scores (absent when never scored).
    pub contributions: Option<Contributions>,
    /// The largest positive weighted term (`freshness`, `anomaly`, `uncertainty`) or `none`;
    /// absent when never scored.
    pub driver: Option<&'static str>,
    /// Its rank by S among the scored cells, from 1 (largest S); absent when never scored.
    pub rank: Option<usize>,
    /// Number of scored cells.
    pub scored: usize,
    /// Its sensors' readings within `window_s` of their newest one, by sensor, modality, time.
    pub series: Vec<SeriesPoint>,
    /// Newest reading time of its sensors, seconds (absent without readings).
    pub latest: Option<UnixSeconds>,
}

/// The use case behind a cell panel: the cell `index` with its weighted terms, its rank by S
/// and the last `window_s` seconds (≥ 0) of its sensors' readings.
/// [`AppError::NotFound`] when the grid has no such cell.
pub fn cell_detail<S: Store>(
    project: &Project<S>,
    index: CellIndex,
    window_s: i64,
) -> Result<CellDetail> {
    if window_s < 0 {
        return Err(AppError::Invalid(format!(
            "series window {window_s} s: expected a number of seconds >= 0"
        )));
    }
    let view = field_view(project)?;
    let u = &project.settings().utility;
    let weights = [u.alpha, u.beta, u.gamma, u.delta];
    let mut scores: Vec<(CellIndex, f64)> = view
        .cells
        .iter()
        .filter_map(|c| c.metadata.scores.as_ref().map(|s| (c.index, s.score)))
        .collect();
    // Largest S first; ties by cell index so the rank is deterministic.
    scores.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
    let rank = scores.iter().position(|(c, _)| *c == index).map(|k| k + 1);
    let cell = view
        .cells
        .into_iter()
        .find(|c| c.index == index)
        .ok_or_else(|| AppError::NotFound {
            what: "cell",
            id: format!("{index} in the project's grid"),
        })?;
    let contributions = cell.metadata.scores.as_ref().map(|s| Contributions {
        freshness: weights[0] * s.freshness,
        anomaly: weights[1] * s.anomaly,
        uncertainty: weights[2] * s.uncertainty,
        redundancy: -weights[3] * s.redundancy,
    });
    let driver = contributions.map(|c| {
        [
            ("freshness", c.freshness),
            ("anomaly", c.anomaly),
            ("uncertainty", c.uncertainty),
        ]
        .into_iter()
        .filter(|p| p.1 > 0.0)
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map_or("none", |p| p.0)
    });
    let batch = project
        .store()
        .readings_of_sensors(&cell.sensors, i64::MIN..=i64::MAX)?;
    let latest = batch.iter().map(|(_, _, t, _)| t).max();
    let series = match latest {
        Some(end) => {
            let start = end.saturating_sub(window_s);
            batch
                .iter()
                .filter(|(_, _, t, _)| *t >= start)
                .map(|(s, m, t, value)| SeriesPoint {
                    sensor: s.clone(),
                    modality: m.clone(),
                    t,
                    value,
                })
                .collect()
        }
        None => Vec::new(),
    };
    Ok(CellDetail {
        cell,
        weights,
        contributions,
        driver,
        rank,
        scored: scores.len(),
        series,
        latest,
    })
}
