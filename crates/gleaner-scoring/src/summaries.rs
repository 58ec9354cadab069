//! Cell series summaries and pending data volumes, computed in Rust (never in the database)
//! and stored in the cell metadata table.

use std::collections::{BTreeMap, HashMap, HashSet};

use gleaner_field::{CellIndex, Modality, SensorId, UnixSeconds};
use gleaner_store::{
    CellMetadata, CellRecord, ModalitySummary, SeriesStats, StoreRead, StoreWrite,
};
use gleaner_utility::{RunningStats, Series};

use crate::codec::{Fnv, In, Out};
use crate::error::{AppError, Result};
use crate::settings::Settings;
use crate::state::Row;

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
pub fn refresh_cells<W: StoreWrite>(
    tx: &mut W,
    changed: &[SensorId],
    now: UnixSeconds,
    settings: &Settings,
) -> Result<usize> {
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
        // Cell series per modality: mean over the cell's sensors at each t (docs/method.md §2).
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

// ---------------------------------------------------------------------------------------
// Incremental refresh after a flight

/// The store blob holding the summary cache ([`Cache`]).
pub(crate) const CACHE_KEY: &str = "summaries.cells";
/// Magic of the cache blob (8 bytes), followed by [`CACHE_VERSION`] (little-endian `u32`).
const CACHE_MAGIC: &[u8; 8] = b"GLNSUMCA";
/// Cache blob format version; a blob of another version is rebuilt.
const CACHE_VERSION: u32 = 1;

/// One cell series (one cell, one modality; a point is the mean over the cell's sensors at
/// one time) as [`series_summary`] needs it, kept as points are appended in time order. The
/// points before the latest are folded into a sum (in time order, so the mean is the one
/// the full computation gets to the last bit), Welford statistics (the standard deviation,
/// equal to the two-pass one up to rounding), minimum and maximum; the latest point stays
/// open as a sum of its sensors' values (modality unit) and their number, so a sensor's
/// reading at the same time still joins it.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Acc {
    /// Sum of the points before the latest, the modality's unit.
    sum: f64,
    /// Count / mean / M2 of the points before the latest.
    stats: RunningStats,
    /// Smallest and largest point before the latest (±inf when none).
    min: f64,
    max: f64,
    /// The latest point: time (s), sum of its sensors' values, how many sensors.
    latest_t: UnixSeconds,
    latest_sum: f64,
    latest_n: u32,
}

impl Acc {
    /// A series whose first point has one reading `v` at `t` (s).
    fn first(t: UnixSeconds, v: f64) -> Self {
        Self {
            sum: 0.0,
            stats: RunningStats::default(),
            min: f64::INFINITY,
            max: f64::NEG_INFINITY,
            latest_t: t,
            latest_sum: 0.0 + v,
            latest_n: 1,
        }
    }

    /// Adds a reading at `t` (s): to the latest point when at its time, as a new latest
    /// point when later; `false` (nothing changed) when earlier than the latest point.
    fn add(&mut self, t: UnixSeconds, v: f64) -> bool {
        if t == self.latest_t {
            self.latest_sum += v;
            self.latest_n += 1;
        } else if t > self.latest_t {
            let p = self.latest_value();
            self.sum += p;
            self.stats.push(p);
            self.min = self.min.min(p);
            self.max = self.max.max(p);
            self.latest_t = t;
            self.latest_sum = 0.0 + v;
            self.latest_n = 1;
        } else {
            return false;
        }
        true
    }

    fn latest_value(&self) -> f64 {
        self.latest_sum / f64::from(self.latest_n)
    }

    /// The summary over every point (what [`series_summary`] gives on the full series).
    fn summary(&self, modality: &Modality) -> ModalitySummary {
        let p = self.latest_value();
        let n = self.stats.count() + 1;
        let mut all = self.stats;
        all.push(p);
        ModalitySummary {
            modality: modality.clone(),
            stats: SeriesStats {
                count: n,
                mean: (self.sum + p) / n as f64,
                std: (n >= 2).then(|| all.std()),
                min: self.min.min(p),
                max: self.max.max(p),
                latest_t: self.latest_t,
                latest_value: p,
            },
        }
    }
}

/// Per sensor and modality: readings, first and last time (s).
type SeriesSpan = (u64, UnixSeconds, UnixSeconds);

/// What the summaries and pending volumes of every cell are computed from, persisted in the
/// store blob [`CACHE_KEY`] and kept in step by every recorded flight (see
/// [`refresh_cells_after`]). Valid for the store it was written to while the cells are the
/// same (`cells_fp`) and the store holds `reading_count` readings.
#[derive(Debug, Clone, PartialEq)]
struct Cache {
    reading_count: u64,
    cells_fp: u64,
    /// Per cell, in the store's cell order: its series by modality.
    cells: Vec<BTreeMap<Modality, Acc>>,
    /// Per sensor of a cell with readings, per modality.
    series: BTreeMap<SensorId, BTreeMap<Modality, SeriesSpan>>,
}

/// Fingerprint of the cells (grid index and sorted sensors, in the store's order).
fn cells_fingerprint(cells: &[CellRecord]) -> u64 {
    let mut h = Fnv::new();
    h.u64(cells.len() as u64);
    for c in cells {
        h.u64(c.index.i as u64);
        h.u64(c.index.j as u64);
        let mut sensors: Vec<&SensorId> = c.sensors.iter().collect();
        sensors.sort();
        h.u64(sensors.len() as u64);
        for s in sensors {
            h.str(s.as_str());
        }
    }
    h.0
}

/// Sensor id -> position of its cell in `cells`.
fn cell_of(cells: &[CellRecord]) -> HashMap<&SensorId, usize> {
    cells
        .iter()
        .enumerate()
        .flat_map(|(k, c)| c.sensors.iter().map(move |s| (s, k)))
        .collect()
}

impl Cache {
    /// Adds readings new to the store (sensor, modality, time in s, value). `None` when one
    /// is not after its series' last reading or its cell series' latest point (a back-filled
    /// reading: the cache is then rebuilt from the store).
    fn apply(mut self, cells: &[CellRecord], rows: &[Row]) -> Option<Self> {
        let cell_of = cell_of(cells);
        let mut per_cell: BTreeMap<usize, Vec<(Modality, UnixSeconds, &SensorId, f64)>> =
            BTreeMap::new();
        let mut sorted: Vec<(&SensorId, Modality, UnixSeconds, f64)> = rows
            .iter()
            .map(|(s, m, t, v)| Some((s, Modality::new(m).ok()?, *t, *v)))
            .collect::<Option<_>>()?;
        sorted.sort_by(|a, b| (a.0, &a.1, a.2).cmp(&(b.0, &b.1, b.2)));
        for (s, m, t, v) in sorted {
            // Sensors in no cell are no cell's concern.
            let Some(&k) = cell_of.get(s) else { continue };
            let of_sensor = self.series.entry(s.clone()).or_default();
            match of_sensor.get_mut(&m) {
                Some(span) if t <= span.2 => return None,
                Some(span) => *span = (span.0 + 1, span.1, t),
                None => {
                    of_sensor.insert(m.clone(), (1, t, t));
                }
            }
            per_cell.entry(k).or_default().push((m, t, s, v));
        }
        for (k, mut rows) in per_cell {
            // The full computation sums a point's sensors in sensor-id order.
            rows.sort_by(|a, b| (&a.0, a.1, a.2).cmp(&(&b.0, b.1, b.2)));
            let series = self.cells.get_mut(k)?;
            for (m, t, _, v) in rows {
                match series.get_mut(&m) {
                    Some(acc) => {
                        if !acc.add(t, v) {
                            return None;
                        }
                    }
                    None => {
                        series.insert(m, Acc::first(t, v));
                    }
                }
            }
        }
        Some(self)
    }

    /// Builds the cache from every stored reading of the cells' sensors.
    fn build<R: StoreRead>(tx: &R, cells: &[CellRecord], reading_count: u64) -> Result<Self> {
        let mut cache = Cache {
            reading_count,
            cells_fp: cells_fingerprint(cells),
            cells: vec![BTreeMap::new(); cells.len()],
            series: BTreeMap::new(),
        };
        let mut sensors: Vec<SensorId> = cells.iter().flat_map(|c| c.sensors.clone()).collect();
        sensors.sort();
        sensors.dedup();
        if sensors.is_empty() {
            return Ok(cache);
        }
        let batch = tx.readings_of_sensors(&sensors, UnixSeconds::MIN..=UnixSeconds::MAX)?;
        let rows: Vec<Row> = batch
            .rows
            .iter()
            .filter_map(|r| {
                Some((
                    batch.sensors.get(r.sensor as usize)?.clone(),
                    batch.modalities.get(r.modality as usize)?.to_string(),
                    r.t,
                    r.value,
                ))
            })
            .collect();
        cache = cache.apply(cells, &rows).ok_or_else(|| {
            AppError::Invalid("cell summaries: the store returned readings out of order".into())
        })?;
        Ok(cache)
    }

    /// The summaries, last collection and pending volume of cell `k` (what
    /// [`refresh_cells`] computes from the stored readings), into `m`.
    fn fill(
        &self,
        k: usize,
        cell: &CellRecord,
        collected: &HashMap<SensorId, UnixSeconds>,
        now: UnixSeconds,
        settings: &Settings,
        m: &mut CellMetadata,
    ) {
        m.correlations.clear();
        m.anomalies.clear();
        m.summaries = self.cells[k]
            .iter()
            .map(|(modality, acc)| acc.summary(modality))
            .collect();
        let mut sensors: Vec<&SensorId> = cell.sensors.iter().collect();
        sensors.sort();
        sensors.dedup();
        // The order the store's batch numbers the modalities in (first seen, sensors by id
        // and each sensor's modalities by name), which orders each sensor's series in the
        // full computation's sum.
        let mut order: Vec<&Modality> = Vec::new();
        let mut pending = 0.0;
        let mut last = m.last_collected;
        for s in sensors {
            let Some(of_sensor) = self.series.get(s) else {
                continue;
            };
            let mut series: Vec<(usize, SeriesSpan)> = of_sensor
                .iter()
                .map(|(modality, span)| {
                    let pos = order
                        .iter()
                        .position(|o| *o == modality)
                        .unwrap_or_else(|| {
                            order.push(modality);
                            order.len() - 1
                        });
                    (pos, *span)
                })
                .collect();
            if series.is_empty() {
                continue;
            }
            series.sort_by_key(|(pos, _)| *pos);
            let spans: Vec<SeriesSpan> = series.into_iter().map(|(_, span)| span).collect();
            let collected_at = collected.get(s).copied();
            last = last.max(collected_at);
            pending += pending_bytes(&spans, collected_at, now, settings);
        }
        m.last_collected = last;
        m.pending_bytes = Some(pending);
    }

    /// The blob: magic, version, then reading count, fingerprint, the cells (per cell: a
    /// count, then per series the modality name and the [`Acc`] fields) and the sensor
    /// series (id, modality name, count, first, last); little-endian, lists as a u64 count.
    fn to_bytes(&self) -> Vec<u8> {
        let mut o = Out(CACHE_MAGIC.to_vec());
        o.0.extend_from_slice(&CACHE_VERSION.to_le_bytes());
        o.u64(self.reading_count);
        o.u64(self.cells_fp);
        o.u64(self.cells.len() as u64);
        for series in &self.cells {
            o.u64(series.len() as u64);
            for (m, a) in series {
                o.bytes(m.as_str().as_bytes());
                o.u64(a.sum.to_bits());
                o.u64(a.stats.count());
                o.u64(a.stats.mean().to_bits());
                o.u64(a.stats.m2().to_bits());
                o.u64(a.min.to_bits());
                o.u64(a.max.to_bits());
                o.i64(a.latest_t);
                o.u64(a.latest_sum.to_bits());
                o.u64(u64::from(a.latest_n));
            }
        }
        o.u64(self.series.len() as u64);
        for (s, of_sensor) in &self.series {
            o.bytes(s.as_str().as_bytes());
            o.u64(of_sensor.len() as u64);
            for (m, (n, t0, t1)) in of_sensor {
                o.bytes(m.as_str().as_bytes());
                o.u64(*n);
                o.i64(*t0);
                o.i64(*t1);
            }
        }
        o.0
    }

    /// Reads a blob written by [`to_bytes`](Self::to_bytes); `None` when it is not one (an
    /// empty blob marks the cache stale).
    fn from_bytes(b: &[u8]) -> Option<Self> {
        let mut i = In(b);
        if i.take(8)? != CACHE_MAGIC || i.take(4)? != CACHE_VERSION.to_le_bytes() {
            return None;
        }
        let f = |i: &mut In<'_>| Some(f64::from_bits(i.u64()?));
        let reading_count = i.u64()?;
        let cells_fp = i.u64()?;
        let n_cells = i.count(8)?;
        let mut cells = Vec::with_capacity(n_cells);
        for _ in 0..n_cells {
            let n = i.count(80)?;
            let mut series = BTreeMap::new();
            for _ in 0..n {
                let m = Modality::new(&i.string()?).ok()?;
                let sum = f(&mut i)?;
                let count = i.u64()?;
                let stats = RunningStats::from_parts(count, f(&mut i)?, f(&mut i)?);
                let acc = Acc {
                    sum,
                    stats,
                    min: f(&mut i)?,
                    max: f(&mut i)?,
                    latest_t: i.i64()?,
                    latest_sum: f(&mut i)?,
                    latest_n: u32::try_from(i.u64()?).ok().filter(|&n| n > 0)?,
                };
                series.insert(m, acc);
            }
            cells.push(series);
        }
        let n = i.count(16)?;
        let mut spans = BTreeMap::new();
        for _ in 0..n {
            let s = SensorId::new(i.string()?).ok()?;
            let k = i.count(32)?;
            let mut of_sensor = BTreeMap::new();
            for _ in 0..k {
                let m = Modality::new(&i.string()?).ok()?;
                of_sensor.insert(m, (i.u64()?, i.i64()?, i.i64()?));
            }
            spans.insert(s, of_sensor);
        }
        i.0.is_empty().then_some(Cache {
            reading_count,
            cells_fp,
            cells,
            series: spans,
        })
    }
}

/// Marks the summary cache stale (readings were added without maintaining it): the next
/// recorded flight rebuilds it from the store.
pub fn invalidate_cache<W: StoreWrite>(tx: &mut W) -> Result<()> {
    tx.blob_put(CACHE_KEY, &[])?;
    Ok(())
}

/// Builds the summary cache from the store unless it is current (same cells, same reading
/// count), so the next recorded flight only adds its own readings. O(stored readings) when
/// it builds.
pub fn prepare_cache<W: StoreWrite>(tx: &mut W) -> Result<()> {
    let cells = tx.cells()?;
    let count = tx.reading_count()?;
    let fp = cells_fingerprint(&cells);
    let current = tx
        .blob_get(CACHE_KEY)?
        .and_then(|b| Cache::from_bytes(&b))
        .is_some_and(|c| c.cells_fp == fp && c.reading_count == count);
    if !current {
        let cache = Cache::build(&*tx, &cells, count)?;
        tx.blob_put(CACHE_KEY, &cache.to_bytes())?;
    }
    Ok(())
}

/// [`refresh_cells`] after a flight, incrementally: `added` are the readings this
/// transaction inserted (new to the store: sensor, modality, time in s, value). The
/// persisted summary cache is brought up to date from them alone when it matches the store
/// (same cells, and the store's reading count is the cache's plus `added`), else rebuilt from
/// every stored reading once; then every stored cell holding one of `changed` sensors gets
/// its series summaries, last collection and pending volume from the cache. Costs
/// O(added + changed cells' series) instead of O(those cells' history). Same results as
/// [`refresh_cells`], except that a mean over points, standard deviation or pending volume
/// may differ in its last bits (the standard deviation is accumulated by Welford's method,
/// not in two passes).
pub fn refresh_cells_after<W: StoreWrite>(
    tx: &mut W,
    changed: &[SensorId],
    added: &[Row],
    now: UnixSeconds,
    settings: &Settings,
) -> Result<usize> {
    let cells = tx.cells()?;
    let count = tx.reading_count()?;
    let fp = cells_fingerprint(&cells);
    let cache = tx
        .blob_get(CACHE_KEY)?
        .and_then(|b| Cache::from_bytes(&b))
        .filter(|c| {
            c.cells_fp == fp
                && c.cells.len() == cells.len()
                && c.reading_count + added.len() as u64 == count
        })
        .and_then(|c| c.apply(&cells, added));
    let mut cache = match cache {
        Some(c) => c,
        None => Cache::build(&*tx, &cells, count)?,
    };
    cache.reading_count = count;
    tx.blob_put(CACHE_KEY, &cache.to_bytes())?;
    let changed: HashSet<&SensorId> = changed.iter().collect();
    let touched: Vec<usize> = (0..cells.len())
        .filter(|&k| cells[k].sensors.iter().any(|s| changed.contains(s)))
        .collect();
    if touched.is_empty() {
        return Ok(0);
    }
    let collected: HashMap<SensorId, UnixSeconds> =
        tx.sensor_last_collected()?.into_iter().collect();
    let mut stored: HashMap<CellIndex, CellMetadata> = tx
        .cell_metadata_scalars()?
        .into_iter()
        .map(|m| (m.cell, m))
        .collect();
    let mut rows = Vec::with_capacity(touched.len());
    for k in touched {
        let cell = &cells[k];
        let mut m = stored
            .remove(&cell.index)
            .unwrap_or_else(|| CellMetadata::new(cell.index));
        cache.fill(k, cell, &collected, now, settings, &mut m);
        rows.push(m);
    }
    tx.upsert_cell_metadata(&rows)?;
    Ok(rows.len())
}

#[cfg(test)]
mod tests {
    use super::*;
    use gleaner_field::LatLon;
    use gleaner_store::{
        ConflictPolicy, ModalityRecord, ReadingBatchBuilder, SensorRecord, SqliteStore, Store,
    };
    use proptest::prelude::*;

    const HOUR: i64 = 3_600;
    /// Hours per flight window.
    const WINDOW: i64 = 12;
    const MODALITIES: [&str; 2] = ["vw@30cm", "t@5cm"];

    fn settings() -> Settings {
        Settings::parse(
            "[project]\nname = \"p\"\ndatabase = \"g.db\"\n[field]\nbase_lat = 38.7\n\
             base_lon = -117.1\ncell_size_m = 40.0\n[sensors]\nfile = \"s.csv\"\n",
        )
        .unwrap()
    }

    fn id(k: usize) -> SensorId {
        SensorId::new(format!("s{k}")).unwrap()
    }

    /// Six sensors: cells of {s0, s1, s2}, {s3} and {s4, s5}... s5 in no cell.
    fn store() -> SqliteStore {
        let mut store = SqliteStore::open_in_memory().unwrap();
        store
            .write(|tx| {
                let sensors: Vec<SensorRecord> = (0..6)
                    .map(|k| SensorRecord {
                        id: id(k),
                        position: LatLon::new(38.7, -117.1).unwrap(),
                        elevation_m: None,
                        source: "test".into(),
                    })
                    .collect();
                tx.upsert_sensors(&sensors)?;
                let modalities: Vec<ModalityRecord> = MODALITIES
                    .iter()
                    .map(|m| ModalityRecord {
                        modality: Modality::new(m).unwrap(),
                        unit: None,
                    })
                    .collect();
                tx.upsert_modalities(&modalities)?;
                let cell = |i: i32, sensors: &[usize]| CellRecord {
                    index: CellIndex { i, j: 0 },
                    centre: LatLon::new(38.7, -117.1).unwrap(),
                    cell_size_m: 40.0,
                    sensors: sensors.iter().map(|&k| id(k)).collect(),
                };
                tx.replace_cells(&[cell(0, &[2, 0, 1]), cell(1, &[3]), cell(2, &[4])])?;
                Ok::<_, gleaner_store::StoreError>(())
            })
            .unwrap();
        store
    }

    /// One flight: readings (sensor, modality, hour in the window or, when back-filled, an
    /// hour of an earlier window, value) and extra sensors marked collected.
    type Flight = (Vec<(usize, usize, i64, bool, f64)>, Vec<usize>);

    fn flights() -> impl Strategy<Value = Vec<Flight>> {
        let reading = (
            0..6usize,
            0..2usize,
            0..WINDOW,
            prop::bool::weighted(0.05),
            0.0..0.5f64,
        );
        let flight = (
            prop::collection::vec(reading, 0..30),
            prop::collection::vec(0..6usize, 0..3),
        );
        prop::collection::vec(flight, 1..8)
    }

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-9 * a.abs().max(b.abs()).max(1.0)
    }

    /// Every field equal, floats to 1e-9 relative (the Welford standard deviation).
    fn assert_same(a: &[CellMetadata], b: &[CellMetadata]) {
        assert_eq!(a.len(), b.len());
        for (x, y) in a.iter().zip(b) {
            assert_eq!(x.cell, y.cell);
            assert_eq!(x.last_collected, y.last_collected);
            assert_eq!(x.pending_bytes.is_some(), y.pending_bytes.is_some());
            assert!(
                close(
                    x.pending_bytes.unwrap_or(0.0),
                    y.pending_bytes.unwrap_or(0.0)
                ),
                "{x:?} vs {y:?}"
            );
            assert_eq!(x.summaries.len(), y.summaries.len(), "{x:?} vs {y:?}");
            for (p, q) in x.summaries.iter().zip(&y.summaries) {
                let (s, t) = (&p.stats, &q.stats);
                assert_eq!(p.modality, q.modality);
                assert_eq!((s.count, s.latest_t), (t.count, t.latest_t));
                assert_eq!(s.std.is_some(), t.std.is_some());
                for (u, v) in [
                    (s.mean, t.mean),
                    (s.std.unwrap_or(0.0), t.std.unwrap_or(0.0)),
                    (s.min, t.min),
                    (s.max, t.max),
                    (s.latest_value, t.latest_value),
                ] {
                    assert!(close(u, v), "{p:?} vs {q:?}");
                }
            }
        }
    }

    /// Plays the flights into two stores: one refreshed incrementally, one by the full
    /// recomputation; returns both stores.
    fn play(flights: &[Flight]) -> (SqliteStore, SqliteStore) {
        let settings = settings();
        let (mut fast, mut full) = (store(), store());
        let mut stored: HashSet<(usize, usize, i64)> = HashSet::new();
        for (f, (readings, extra)) in flights.iter().enumerate() {
            let f = f as i64;
            let at = (f + 1) * WINDOW * HOUR;
            let mut batch = ReadingBatchBuilder::new();
            let mut added: Vec<Row> = Vec::new();
            let mut visited: Vec<SensorId> = extra.iter().map(|&k| id(k)).collect();
            for &(s, m, hour, backfill, v) in readings {
                let hour = if backfill && f > 0 {
                    hour + WINDOW * (hour % f)
                } else {
                    f * WINDOW + hour + 1
                };
                if !stored.insert((s, m, hour)) {
                    continue;
                }
                let modality = Modality::new(MODALITIES[m]).unwrap();
                batch.push(&id(s), &modality, hour * HOUR, v);
                added.push((id(s), modality.to_string(), hour * HOUR, v));
                visited.push(id(s));
            }
            let batch = batch.finish();
            let collected: Vec<(SensorId, UnixSeconds)> =
                visited.iter().map(|s| (s.clone(), at)).collect();
            for (store, incremental) in [(&mut fast, true), (&mut full, false)] {
                store
                    .write(|tx| {
                        tx.insert_readings(&batch, ConflictPolicy::Fail)?;
                        tx.set_sensors_collected(&collected)?;
                        if incremental {
                            refresh_cells_after(tx, &visited, &added, at, &settings)
                        } else {
                            refresh_cells(tx, &visited, at, &settings)
                        }
                    })
                    .unwrap();
            }
            assert_same(
                &fast.cell_metadata().unwrap(),
                &full.cell_metadata().unwrap(),
            );
        }
        (fast, full)
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

        /// After every flight, the incremental refresh gives what recomputing from every
        /// stored reading gives, and the kept cache is the one built from the store.
        #[test]
        fn incremental_refresh_equals_full_recomputation(flights in flights()) {
            let (fast, _) = play(&flights);
            let kept = Cache::from_bytes(&fast.blob_get(CACHE_KEY).unwrap().unwrap()).unwrap();
            let cells = fast.cells().unwrap();
            let built = Cache::build(&fast, &cells, fast.reading_count().unwrap()).unwrap();
            prop_assert_eq!(&kept.series, &built.series);
            prop_assert_eq!(kept.reading_count, built.reading_count);
            for (a, b) in kept.cells.iter().zip(&built.cells) {
                for (m, acc) in a {
                    let other = b[m];
                    prop_assert_eq!(acc.summary(m).stats.count, other.summary(m).stats.count);
                    prop_assert!(close(acc.summary(m).stats.mean, other.summary(m).stats.mean));
                }
            }
        }
    }

    /// Collected readings that arrive in time order per cell give the full computation's
    /// summaries to the last bit (counts, mean, extremes, latest, pending volume); only the
    /// standard deviation is Welford's.
    #[test]
    fn appended_readings_give_bit_identical_means() {
        let flights: Vec<Flight> = (0..5)
            .map(|f| {
                let readings = (0..6)
                    .flat_map(|s| {
                        (0..WINDOW).map(move |h| {
                            (
                                s,
                                (h % 2) as usize,
                                h,
                                false,
                                0.1 + 0.037 * (f * 7 + s as i64 * 3 + h) as f64 % 0.3,
                            )
                        })
                    })
                    .collect();
                (readings, vec![])
            })
            .collect();
        let (fast, full) = play(&flights);
        let (a, b) = (fast.cell_metadata().unwrap(), full.cell_metadata().unwrap());
        for (x, y) in a.iter().zip(&b) {
            assert_eq!(x.pending_bytes, y.pending_bytes);
            for (p, q) in x.summaries.iter().zip(&y.summaries) {
                let (mut s, t) = (p.stats.clone(), q.stats.clone());
                s.std = t.std;
                assert_eq!(s, t);
            }
        }
    }

    /// A cache blob that does not match the store (readings added without maintaining it)
    /// is rebuilt, not trusted; a damaged blob too.
    #[test]
    fn stale_or_damaged_cache_is_rebuilt() {
        let flights: Vec<Flight> = vec![
            (vec![(0, 0, 1, false, 0.2), (3, 1, 2, false, 0.3)], vec![]),
            (vec![(0, 0, 3, false, 0.25)], vec![4]),
        ];
        let (mut fast, _) = play(&flights);
        let settings = settings();
        // A reading written behind the cache's back, then a flight reporting nothing new.
        let mut batch = ReadingBatchBuilder::new();
        batch.push(&id(1), &Modality::new("vw@30cm").unwrap(), 40 * HOUR, 0.4);
        let batch = batch.finish();
        for blob in [None, Some(b"GLNSUMCA\x01\x00\x00\x00junk".to_vec())] {
            fast.write(|tx| {
                tx.insert_readings(&batch, ConflictPolicy::Skip)?;
                if let Some(b) = &blob {
                    tx.blob_put(CACHE_KEY, b)?;
                }
                refresh_cells_after(tx, &[id(1)], &[], 50 * HOUR, &settings)
            })
            .unwrap();
            let cell0 = &fast.cell_metadata().unwrap()[0];
            let vw = &cell0
                .summaries
                .iter()
                .find(|s| s.modality.as_str() == "vw@30cm")
                .unwrap();
            assert_eq!((vw.stats.latest_t, vw.stats.latest_value), (40 * HOUR, 0.4));
        }
    }
}
