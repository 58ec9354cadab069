//! Cell series summaries and pending data volumes, computed in Rust (never in the database)
//! and stored in the cell metadata table.

use std::collections::{BTreeMap, HashMap, HashSet};

use gleaner_field::{CellIndex, Modality, SensorId, UnixSeconds};
use gleaner_store::{CellMetadata, ModalitySummary, SeriesStats, StoreWrite};
use gleaner_utility::Series;

use crate::error::AppError;
use crate::settings::Settings;

/// Count, mean, sample std, min, max and latest point of a series; `None` when empty. Values
/// in the modality's unit, times seconds since the Unix epoch.
pub fn series_summary(modality: &Modality, s: Series<'_>) -> Option<ModalitySummary> {
    let n = s.values.len();
    let (&latest_t, &latest_value) = (s.times.last()?, s.values.last()?);
    let mean = s.values.iter().sum::<f64>() / n as f64;
    let ss: f64 = s.values.iter().map(|v| (v - mean) * (v - mean)).sum();
    let (min, max) = s
        .values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    Some(ModalitySummary {
        modality: modality.clone(),
        stats: SeriesStats {
            count: n as u64,
            mean,
            std: (n >= 2).then(|| (ss / (n - 1) as f64).sqrt()),
            min,
            max,
            latest_t,
            latest_value,
        },
    })
}

/// Bytes a sensor has logged since it was last emptied: per series, the time since the later
/// of its latest stored reading and the sensor's last collection, divided by the series' mean
/// logging interval (the default interval with fewer than 2 readings), times the bytes per
/// reading. `series` holds (count, first t, last t) per modality; times in seconds.
pub fn pending_bytes(
    series: &[(u64, UnixSeconds, UnixSeconds)],
    last_collected: Option<UnixSeconds>,
    now: UnixSeconds,
    settings: &Settings,
) -> f64 {
    series
        .iter()
        .map(|&(n, t0, t1)| {
            let since = t1.max(last_collected.unwrap_or(t1));
            let interval = if n >= 2 && t1 > t0 {
                (t1 - t0) as f64 / (n - 1) as f64
            } else {
                settings.ingest.default_interval_s
            };
            (now - since).max(0) as f64 / interval
        })
        .sum::<f64>()
        * settings.ingest.bytes_per_reading
}

/// Recomputes, inside a write transaction, the series summaries, last collection and pending
/// volume of every stored cell holding one of `changed` sensors, from the stored readings;
/// the cells' scores and other fields are kept. Costs in proportion to those cells' readings.
pub(crate) fn refresh_cells<W: StoreWrite>(
    tx: &mut W,
    changed: &[SensorId],
    now: UnixSeconds,
    settings: &Settings,
) -> Result<usize, AppError> {
    let changed: HashSet<&SensorId> = changed.iter().collect();
    let cells: Vec<_> = tx
        .cells()?
        .into_iter()
        .filter(|c| c.sensors.iter().any(|s| changed.contains(s)))
        .collect();
    if cells.is_empty() {
        return Ok(0);
    }
    let collected: HashMap<SensorId, UnixSeconds> =
        tx.sensor_last_collected()?.into_iter().collect();
    let mut stored: HashMap<CellIndex, CellMetadata> = tx
        .cell_metadata()?
        .into_iter()
        .map(|m| (m.cell, m))
        .collect();
    let mut rows = Vec::with_capacity(cells.len());
    for cell in &cells {
        let batch = tx.readings_of_sensors(&cell.sensors, UnixSeconds::MIN..=UnixSeconds::MAX)?;
        // Cell series per modality: mean over the cell's sensors at each t (SPEC §2).
        let mut slots: BTreeMap<&Modality, BTreeMap<UnixSeconds, (f64, u32)>> = BTreeMap::new();
        // Per sensor and modality: (count, first t, last t). Ordered, so the pending volume
        // is summed in the same order by every process (a hash map's order varies per run
        // and changed the last bits of the sum).
        let mut per_series: BTreeMap<(u32, u32), (u64, UnixSeconds, UnixSeconds)> = BTreeMap::new();
        for r in &batch.rows {
            let Some(m) = batch.modalities.get(r.modality as usize) else {
                continue;
            };
            let slot = slots.entry(m).or_default().entry(r.t).or_insert((0.0, 0));
            slot.0 += r.value;
            slot.1 += 1;
            let e = per_series
                .entry((r.sensor, r.modality))
                .or_insert((0, r.t, r.t));
            e.0 += 1;
            e.1 = e.1.min(r.t);
            e.2 = e.2.max(r.t);
        }
        let mut m = stored
            .remove(&cell.index)
            .unwrap_or_else(|| CellMetadata::new(cell.index));
        m.correlations.clear();
        m.anomalies.clear();
        m.summaries = slots
            .into_iter()
            .filter_map(|(modality, points)| {
                let (times, values): (Vec<UnixSeconds>, Vec<f64>) = points
                    .into_iter()
                    .map(|(t, (sum, n))| (t, sum / f64::from(n)))
                    .unzip();
                series_summary(modality, Series::new(&times, &values))
            })
            .collect();
        let mut pending = 0.0;
        let mut last = m.last_collected;
        for (k, sensor) in batch.sensors.iter().enumerate() {
            let series: Vec<_> = per_series
                .iter()
                .filter(|((s, _), _)| *s as usize == k)
                .map(|(_, v)| *v)
                .collect();
            let collected_at = collected.get(sensor).copied();
            last = last.max(collected_at);
            pending += pending_bytes(&series, collected_at, now, settings);
        }
        m.last_collected = last;
        m.pending_bytes = Some(pending);
        rows.push(m);
    }
    tx.upsert_cell_metadata(&rows)?;
    Ok(rows.len())
}
