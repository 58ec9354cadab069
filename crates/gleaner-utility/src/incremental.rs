//! Statistics maintained as readings arrive (docs/method.md §5: the cell metadata), so that rescoring
//! after a mission costs O(new readings × neighbours + cells × neighbours × modalities) instead
//! of O(history).
//!
//! What is kept, per cell and modality: the cell series' recent points (a time -> (sum, count)
//! map on the grid), running count / mean / M2 (Welford) of all points, min / max / latest, and
//! the Welford statistics of the points *before* the latest one (for the anomaly). Per
//! neighbour pair and modality: the co-moments (n, means, M2x, M2y, Cxy) over common
//! timestamps. A grid slot whose value changes (a second sensor of the cell reporting the same
//! slot, possibly in a later batch) is handled by removing the old value from every statistic
//! and adding the new one, so arrival order does not matter: a timestamp arriving for
//! neighbour j after it arrived for cell i is paired when j's reading arrives.
//!
//! Limits (by design):
//! - only the all-history window ([`HistoryWindow::All`](crate::HistoryWindow::All)) is
//!   supported: a sliding window would need to remove points as they leave it, i.e. keep and
//!   revisit the history. Scoring with another window returns
//!   [`UtilityError::WindowNotIncremental`]; use [`score_cells`](crate::score_cells) instead.
//!   The neighbour-relative anomaly ([`crate::AnomalyReference::Neighbours`]) is not
//!   supported either (it needs the neighbours' history): scoring with it returns
//!   [`UtilityError::Config`].
//! - the statistics hold every reading added so far regardless of the scoring time.
//! - with a retention horizon ([`IncrementalState::set_retention`]), grid slots older than
//!   (newest time seen − retention) are forgotten and readings older than that are rejected
//!   ([`UtilityError::BeyondRetention`]); the statistics stay exact. Without one (the default)
//!   every slot is kept (24 bytes per cell, modality and grid slot).
//! - the state is persisted with [`IncrementalState::to_bytes`] /
//!   [`IncrementalState::from_bytes`] (a versioned little-endian format, see `STATE_MAGIC`
//!   below): a process builds it from the stored readings once
//!   ([`IncrementalState::add_readings`], O(history)), then keeps it up to date. With a
//!   retention horizon and [`IncrementalState::trim`] its size is O(cells × modalities ×
//!   retained slots + pairs × modalities).
//! - each (sensor, modality, grid slot) reading must be added once (the store deduplicates);
//!   several readings falling in one slot are averaged, as in [`cell_series`](crate::cell_series).

use rayon::prelude::*;

use crate::codec::{Reader, Writer};
use crate::engine::{CellTerms, finish_terms};
use crate::probabilities::check_distribution;
use crate::terms::{anomaly_from_stats, finish_pearson, freshness};
use crate::{HistoryWindow, OwnedSeries, TimeGrid, UtilityConfig, UtilityError};
use gleaner_field::UnixSeconds;

/// Running count, mean and sum of squared deviations (Welford), with removal.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RunningStats {
    n: u64,
    mean: f64,
    m2: f64,
}

impl RunningStats {
    /// Statistics from stored parts: count, mean (unit), sum of squared deviations (unit²).
    pub fn from_parts(count: u64, mean: f64, m2: f64) -> Self {
        Self {
            n: count,
            mean,
            m2: m2.max(0.0),
        }
    }

    /// Adds a value.
    pub fn push(&mut self, x: f64) {
        self.n += 1;
        let d = x - self.mean;
        self.mean += d / self.n as f64;
        self.m2 += d * (x - self.mean);
    }

    /// Removes a value previously added (exact inverse of [`push`](Self::push) up to rounding).
    pub fn remove(&mut self, x: f64) {
        if self.n <= 1 {
            *self = Self::default();
            return;
        }
        let n1 = (self.n - 1) as f64;
        let mean_before = self.mean - (x - self.mean) / n1;
        self.m2 -= (x - mean_before) * (x - self.mean);
        self.mean = mean_before;
        self.n -= 1;
        if self.m2 < 0.0 {
            self.m2 = 0.0;
        }
    }

    /// Number of values.
    pub fn count(&self) -> u64 {
        self.n
    }
    /// Mean (the values' unit); 0 when empty.
    pub fn mean(&self) -> f64 {
        self.mean
    }
    /// Sum of squared deviations from the mean (unit²).
    pub fn m2(&self) -> f64 {
        self.m2
    }
    /// Sample variance (n − 1), unit²; 0 with fewer than 2 values.
    pub fn variance(&self) -> f64 {
        if self.n < 2 {
            0.0
        } else {
            self.m2 / (self.n - 1) as f64
        }
    }
    /// Sample standard deviation, the values' unit.
    pub fn std(&self) -> f64 {
        self.variance().sqrt()
    }
}

/// Co-moment statistics of a pair of series over their common timestamps, with removal.
/// The correlation is refreshed on every change, so scoring only reads it.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PairStats {
    n: u64,
    mean_x: f64,
    mean_y: f64,
    m2x: f64,
    m2y: f64,
    cxy: f64,
    /// Pearson correlation of the points (0 below 2 points or with zero variance).
    corr: f64,
}

impl PairStats {
    /// Statistics from stored parts, as returned by [`parts`](Self::parts).
    pub fn from_parts(parts: [f64; 6]) -> Self {
        let [n, moments @ ..] = parts;
        Self::from_moments(n.max(0.0) as u64, moments)
    }

    /// Statistics of `n` points from their moments `[mean_x, mean_y, M2x, M2y, Cxy]`, the
    /// correlation computed.
    fn from_moments(n: u64, [mean_x, mean_y, m2x, m2y, cxy]: [f64; 5]) -> Self {
        let mut s = Self {
            n,
            mean_x,
            mean_y,
            m2x,
            m2y,
            cxy,
            corr: 0.0,
        };
        s.refresh();
        s
    }

    /// The stored parts: [n, mean_x, mean_y, M2x, M2y, Cxy] (x is the lower cell position).
    pub fn parts(&self) -> [f64; 6] {
        [
            self.n as f64,
            self.mean_x,
            self.mean_y,
            self.m2x,
            self.m2y,
            self.cxy,
        ]
    }

    /// Adds a common point.
    pub fn push(&mut self, x: f64, y: f64) {
        self.n += 1;
        let n = self.n as f64;
        let dx = x - self.mean_x;
        self.mean_x += dx / n;
        let dy = y - self.mean_y;
        self.mean_y += dy / n;
        self.m2x += dx * (x - self.mean_x);
        self.m2y += dy * (y - self.mean_y);
        self.cxy += dx * (y - self.mean_y);
        self.refresh();
    }

    fn refresh(&mut self) {
        self.corr = if self.n < 2 {
            0.0
        } else {
            let [n, mean_x, mean_y, m2x, m2y, cxy] = self.parts();
            finish_pearson(n, mean_x, mean_y, m2x, m2y, cxy).unwrap_or(0.0)
        };
    }

    /// Removes a common point previously added.
    pub fn remove(&mut self, x: f64, y: f64) {
        if self.n <= 1 {
            *self = Self::default();
            return;
        }
        let n1 = (self.n - 1) as f64;
        let mx = self.mean_x - (x - self.mean_x) / n1;
        let my = self.mean_y - (y - self.mean_y) / n1;
        self.m2x -= (x - mx) * (x - self.mean_x);
        self.m2y -= (y - my) * (y - self.mean_y);
        self.cxy -= (x - mx) * (y - self.mean_y);
        self.mean_x = mx;
        self.mean_y = my;
        self.n -= 1;
        self.refresh();
    }

    /// Number of common points.
    pub fn count(&self) -> u64 {
        self.n
    }

    /// Pearson correlation over the common points, with the rules of
    /// [`series_correlation`](crate::series_correlation): 0 with fewer than `min_overlap`
    /// points or zero variance. Dimensionless in [−1, 1].
    pub fn correlation(&self, min_overlap: usize) -> f64 {
        if self.n < min_overlap.max(2) as u64 {
            return 0.0;
        }
        self.corr
    }
}

/// Summary of one cell series (one cell, one modality).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SeriesStats {
    /// Count / mean / std of every point, the modality's unit.
    pub all: RunningStats,
    /// Count / mean / std of the points before the latest one (the anomaly's reference).
    pub before_latest: RunningStats,
    /// The latest point (s, value).
    pub latest: Option<(UnixSeconds, f64)>,
    /// Smallest value (+inf when empty). Exact, also with a retention horizon (the extremes of
    /// the forgotten slots are kept).
    pub min: f64,
    /// Largest value (−inf when empty).
    pub max: f64,
}

impl Default for SeriesStats {
    fn default() -> Self {
        Self {
            all: RunningStats::default(),
            before_latest: RunningStats::default(),
            latest: None,
            min: f64::INFINITY,
            max: f64::NEG_INFINITY,
        }
    }
}

impl SeriesStats {
    /// Raw anomaly A^m (standard deviations) of the latest point against the earlier ones;
    /// `None` without any point, 0 with fewer than 2 earlier points. `epsilon` in the unit.
    pub fn anomaly(&self, epsilon: f64) -> Option<f64> {
        let (_, latest) = self.latest?;
        if self.before_latest.count() < 2 {
            return Some(0.0);
        }
        Some(anomaly_from_stats(
            latest,
            self.before_latest.mean(),
            self.before_latest.variance(),
            epsilon,
        ))
    }
}

/// One reading of one sensor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reading {
    /// Cell position.
    pub cell: usize,
    /// The sensor's position within its cell (0-based).
    pub sensor: usize,
    /// Modality position.
    pub modality: usize,
    /// Time, s (snapped to the state's grid).
    pub time: UnixSeconds,
    /// Value, the modality's unit (finite).
    pub value: f64,
}

#[derive(Debug, Clone, Copy, PartialEq)]
struct Slot {
    time: UnixSeconds,
    sum: f64,
    count: u32,
}

impl Slot {
    fn value(&self) -> f64 {
        self.sum / f64::from(self.count)
    }
}

/// The incrementally maintained statistics of every cell (see the module docs).
///
/// ```
/// use gleaner_utility::{IncrementalState, Reading, TimeGrid, UtilityConfig};
/// // Two cells of one sensor each, neighbours of each other, one modality.
/// let mut state = IncrementalState::new(&[1, 1], &[vec![1], vec![0]], 1, TimeGrid::DAILY).unwrap();
/// for d in 0..12i64 {
///     for cell in 0..2 {
///         let value = 0.3 + 0.01 * d as f64 * (cell as f64 + 1.0);
///         state.add_reading(Reading { cell, sensor: 0, modality: 0, time: d * 86_400, value }).unwrap();
///     }
/// }
/// state.record_collection(0, 0, 11 * 86_400).unwrap();
/// let terms = state.score(12 * 86_400, &UtilityConfig::default(), &[]).unwrap();
/// assert!((terms[0].r - 1.0).abs() < 1e-9);
/// assert_eq!(terms[1].f, 1.0); // cell 1 never collected
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct IncrementalState {
    grid: TimeGrid,
    n_modalities: usize,
    last_collected: Vec<Vec<Option<UnixSeconds>>>,
    neighbours: Vec<Vec<usize>>,
    /// Per cell × modality: grid slots sorted by time.
    slots: Vec<Vec<Slot>>,
    /// Per cell × modality.
    stats: Vec<SeriesStats>,
    /// Per undirected pair × modality.
    pairs: Vec<PairStats>,
    /// Per cell, per neighbour position: the pair id.
    neighbour_pair: Vec<Vec<usize>>,
    /// Per cell: (pair id, other cell, this cell is the pair's x).
    incident: Vec<Vec<(usize, usize, bool)>>,
    retention_s: Option<i64>,
    /// Slots kept per series whatever their age (see [`IncrementalState::set_min_points`]).
    min_points: usize,
    /// Per cell × modality: (min, max) of the slots already forgotten (retention), so the
    /// extremes stay exact after a rescan.
    frozen: Vec<(f64, f64)>,
    newest: UnixSeconds,
}

impl IncrementalState {
    /// An empty state for cells with `sensors_per_cell[i]` sensors (>= 1) and neighbour lists
    /// `neighbours[i]` (cell positions), `n_modalities` modalities, on `grid`.
    pub fn new(
        sensors_per_cell: &[usize],
        neighbours: &[Vec<usize>],
        n_modalities: usize,
        grid: TimeGrid,
    ) -> Result<Self, UtilityError> {
        let n = sensors_per_cell.len();
        if neighbours.len() != n {
            return Err(UtilityError::Config(format!(
                "{} neighbour lists for {n} cells",
                neighbours.len()
            )));
        }
        if grid.step_s <= 0 {
            return Err(UtilityError::Config(format!(
                "grid step {} s must be positive",
                grid.step_s
            )));
        }
        if let Some(i) = sensors_per_cell.iter().position(|&s| s == 0) {
            return Err(UtilityError::NoSensors(i));
        }
        let mut pair_of = std::collections::HashMap::new();
        let mut incident = vec![Vec::new(); n];
        let mut neighbour_pair = Vec::with_capacity(n);
        for (i, nbs) in neighbours.iter().enumerate() {
            let mut ids = Vec::with_capacity(nbs.len());
            for &j in nbs {
                if j >= n || j == i {
                    return Err(UtilityError::Neighbour {
                        cell: i,
                        neighbour: j,
                        cells: n,
                    });
                }
                let key = (i.min(j), i.max(j));
                let next = pair_of.len();
                let id = *pair_of.entry(key).or_insert_with(|| {
                    incident[key.0].push((next, key.1, true));
                    incident[key.1].push((next, key.0, false));
                    next
                });
                ids.push(id);
            }
            neighbour_pair.push(ids);
        }
        Ok(Self {
            grid,
            n_modalities,
            last_collected: sensors_per_cell.iter().map(|&s| vec![None; s]).collect(),
            neighbours: neighbours.to_vec(),
            slots: vec![Vec::new(); n * n_modalities],
            stats: vec![SeriesStats::default(); n * n_modalities],
            pairs: vec![PairStats::default(); pair_of.len() * n_modalities],
            neighbour_pair,
            incident,
            retention_s: None,
            min_points: 0,
            frozen: vec![(f64::INFINITY, f64::NEG_INFINITY); n * n_modalities],
            newest: UnixSeconds::MIN,
        })
    }

    /// Number of cells.
    pub fn n_cells(&self) -> usize {
        self.last_collected.len()
    }

    /// Keep grid slots only for `retention_s` seconds before the newest reading (`None`: keep
    /// all, the default). See the module docs.
    pub fn set_retention(&mut self, retention_s: Option<i64>) {
        self.retention_s = retention_s.map(|r| r.max(0));
    }

    /// Keep at least the last `points` grid slots of every series even when they are older
    /// than the retention horizon (default 0), so that e.g. a trend over the last points or
    /// the latest value of a sparse series can be read back with
    /// [`cell_series`](Self::cell_series). Readings older than the horizon are still rejected.
    pub fn set_min_points(&mut self, points: usize) {
        self.min_points = points;
    }

    /// The retention horizon length, s (`None`: every slot is kept).
    pub fn retention(&self) -> Option<i64> {
        self.retention_s
    }

    /// Slots kept per series whatever their age ([`set_min_points`](Self::set_min_points)).
    pub fn min_points(&self) -> usize {
        self.min_points
    }

    /// The newest grid time (s) of any reading added; `None` before the first.
    pub fn newest(&self) -> Option<UnixSeconds> {
        (self.newest != UnixSeconds::MIN).then_some(self.newest)
    }

    /// The sampling grid readings are snapped to.
    pub fn grid(&self) -> TimeGrid {
        self.grid
    }

    /// Number of modalities.
    pub fn n_modalities(&self) -> usize {
        self.n_modalities
    }

    /// Forgets, in every series, the slots older than the retention horizon (keeping the
    /// last [`min_points`](Self::min_points)). [`add_readings`](Self::add_readings) only trims
    /// the series it touches; call this before persisting to keep the state small. Statistics
    /// are unchanged. No-op without a retention horizon.
    pub fn trim(&mut self) {
        if self.retention_s.is_none() {
            return;
        }
        for key in 0..self.slots.len() {
            self.trim_key(key);
        }
    }

    fn trim_key(&mut self, key: usize) {
        let horizon = self.horizon();
        let slots = &mut self.slots[key];
        let stale = slots
            .partition_point(|s| s.time < horizon)
            .min(slots.len().saturating_sub(self.min_points));
        if stale > 0 {
            let frozen = &mut self.frozen[key];
            for s in slots.drain(..stale) {
                let v = s.value();
                frozen.0 = frozen.0.min(v);
                frozen.1 = frozen.1.max(v);
            }
        }
    }

    /// Replaces the last collection times of cell `cell`'s sensors (s, one per sensor,
    /// `None` = never collected); unlike [`record_collection`](Self::record_collection) a time
    /// may move back (e.g. to score at a time before a recorded collection).
    pub fn set_last_collected(
        &mut self,
        cell: usize,
        last: &[Option<UnixSeconds>],
    ) -> Result<(), UtilityError> {
        let cell = in_range("cell", cell, self.n_cells())?;
        let sensors = &mut self.last_collected[cell];
        if last.len() != sensors.len() {
            return Err(UtilityError::ReadingIndex {
                what: "sensor",
                index: last.len(),
                count: sensors.len(),
            });
        }
        sensors.copy_from_slice(last);
        Ok(())
    }

    /// The retained series of modality `modality` for every cell, in cell order (empty series
    /// for an out-of-range modality). With [`set_min_points`](Self::set_min_points) >= the
    /// condition model's `trend_points`, these give the same
    /// [`ConditionModel::predict_proba`](crate::ConditionModel::predict_proba) at any time at or
    /// after [`newest`](Self::newest) as the full history.
    pub fn recent_series(&self, modality: usize) -> Vec<OwnedSeries> {
        if modality >= self.n_modalities {
            return vec![OwnedSeries::default(); self.n_cells()];
        }
        (0..self.n_cells())
            .map(|cell| self.cell_series(cell, modality))
            .collect()
    }

    /// The oldest reading time (s) still accepted.
    pub fn horizon(&self) -> UnixSeconds {
        match self.retention_s {
            Some(r) if self.newest != UnixSeconds::MIN => self.newest.saturating_sub(r),
            _ => UnixSeconds::MIN,
        }
    }

    /// Records that sensor `sensor` (position within the cell) of cell `cell` was collected at
    /// `t` (s); an earlier time than the one known is ignored.
    pub fn record_collection(
        &mut self,
        cell: usize,
        sensor: usize,
        t: UnixSeconds,
    ) -> Result<(), UtilityError> {
        let cell = in_range("cell", cell, self.n_cells())?;
        let sensors = &mut self.last_collected[cell];
        let sensor = in_range("sensor", sensor, sensors.len())?;
        let slot = &mut sensors[sensor];
        *slot = Some(slot.map_or(t, |old| old.max(t)));
        Ok(())
    }

    fn check_reading(&self, r: &Reading) -> Result<(), UtilityError> {
        let cell = in_range("cell", r.cell, self.n_cells())?;
        in_range("sensor", r.sensor, self.last_collected[cell].len())?;
        in_range("modality", r.modality, self.n_modalities)?;
        if !r.value.is_finite() {
            return Err(UtilityError::NonFinite {
                cell: r.cell,
                modality: r.modality,
                time: r.time,
                value: r.value,
            });
        }
        let horizon = self.horizon();
        if self.grid.snap(r.time) < horizon {
            return Err(UtilityError::BeyondRetention {
                time: r.time,
                horizon,
            });
        }
        Ok(())
    }

    /// Adds one reading. Cost O(log slots + neighbours).
    pub fn add_reading(&mut self, reading: Reading) -> Result<(), UtilityError> {
        self.add_readings(&[reading])
    }

    /// Adds a batch of readings (any order). All are checked first: on error nothing changes.
    pub fn add_readings(&mut self, readings: &[Reading]) -> Result<(), UtilityError> {
        for r in readings {
            self.check_reading(r)?;
        }
        for r in readings {
            self.apply(r);
        }
        if self.retention_s.is_some() {
            for r in readings {
                self.trim_key(r.cell * self.n_modalities + r.modality);
            }
        }
        Ok(())
    }

    fn apply(&mut self, r: &Reading) {
        let m_count = self.n_modalities;
        let key = r.cell * m_count + r.modality;
        let t = self.grid.snap(r.time);
        self.newest = self.newest.max(t);
        let slots = &mut self.slots[key];
        let (old, new) = match slots.binary_search_by_key(&t, |s| s.time) {
            Ok(k) => {
                let old = slots[k].value();
                slots[k].sum += r.value;
                slots[k].count += 1;
                (Some(old), slots[k].value())
            }
            Err(k) => {
                slots.insert(
                    k,
                    Slot {
                        time: t,
                        sum: r.value,
                        count: 1,
                    },
                );
                (None, r.value)
            }
        };
        self.update_stats(key, t, old, new);
        for &(pair, other, is_x) in &self.incident[r.cell] {
            let other_slots = &self.slots[other * m_count + r.modality];
            let Ok(k) = other_slots.binary_search_by_key(&t, |s| s.time) else {
                continue;
            };
            let y = other_slots[k].value();
            let p = &mut self.pairs[pair * m_count + r.modality];
            let order = |v: f64| if is_x { (v, y) } else { (y, v) };
            if let Some(o) = old {
                let (a, b) = order(o);
                p.remove(a, b);
            }
            let (a, b) = order(new);
            p.push(a, b);
        }
    }

    fn update_stats(&mut self, key: usize, t: UnixSeconds, old: Option<f64>, new: f64) {
        let st = &mut self.stats[key];
        if let Some(o) = old {
            st.all.remove(o);
        }
        st.all.push(new);
        match st.latest {
            None => st.latest = Some((t, new)),
            Some((tl, vl)) if t > tl => {
                st.before_latest.push(vl);
                st.latest = Some((t, new));
            }
            Some((tl, _)) if t == tl => st.latest = Some((t, new)),
            Some(_) => {
                if let Some(o) = old {
                    st.before_latest.remove(o);
                }
                st.before_latest.push(new);
            }
        }
        let extreme_changed = old.is_some_and(|o| o == st.min || o == st.max);
        if extreme_changed {
            let (lo, hi) = self.slots[key]
                .iter()
                .map(Slot::value)
                .fold(self.frozen[key], |(lo, hi), v| (lo.min(v), hi.max(v)));
            st.min = lo;
            st.max = hi;
        } else {
            st.min = st.min.min(new);
            st.max = st.max.max(new);
        }
    }

    /// Summary statistics of cell `cell`, modality `modality` (panics on out-of-range
    /// positions: they are the caller's own indices).
    pub fn series_stats(&self, cell: usize, modality: usize) -> &SeriesStats {
        &self.stats[cell * self.n_modalities + modality]
    }

    /// Co-moments of cell `cell` with its `k`-th neighbour for `modality` (panics on
    /// out-of-range positions).
    pub fn neighbour_pair(&self, cell: usize, k: usize, modality: usize) -> &PairStats {
        &self.pairs[self.neighbour_pair[cell][k] * self.n_modalities + modality]
    }

    /// The retained points of the cell series (s, unit), as an owned series (panics on
    /// out-of-range positions).
    pub fn cell_series(&self, cell: usize, modality: usize) -> OwnedSeries {
        let slots = &self.slots[cell * self.n_modalities + modality];
        OwnedSeries {
            times: slots.iter().map(|s| s.time).collect(),
            values: slots.iter().map(Slot::value).collect(),
        }
    }

    /// Last collection time of each sensor of `cell`, s (panics on an out-of-range cell).
    pub fn last_collected(&self, cell: usize) -> &[Option<UnixSeconds>] {
        &self.last_collected[cell]
    }

    /// Scores every cell at mission time `t` (s) from the maintained statistics, in
    /// O(cells × neighbours × modalities), the cells spread over rayon's global pool (each
    /// cell's terms depend only on the statistics, so the result is the same on any number of
    /// threads, in cell order). `probabilities` is empty (no model, U = 0) or one distribution
    /// per cell. Only [`HistoryWindow::All`] is supported; every reading added counts,
    /// whatever `t`.
    pub fn score(
        &self,
        t: UnixSeconds,
        config: &UtilityConfig,
        probabilities: &[Vec<f64>],
    ) -> Result<Vec<CellTerms>, UtilityError> {
        self.check_scoring(config, probabilities)?;
        Ok((0..self.n_cells())
            .into_par_iter()
            .map(|i| self.cell_terms(i, t, config, probabilities))
            .collect())
    }

    fn cell_terms(
        &self,
        i: usize,
        t: UnixSeconds,
        config: &UtilityConfig,
        probabilities: &[Vec<f64>],
    ) -> CellTerms {
        let lambda = config.lambda_per_s();
        let m_count = self.n_modalities;
        let f = freshness(t, &self.last_collected[i], lambda);
        let nbs = &self.neighbour_pair[i];
        let mut r_sum = [0.0; 8];
        let mut r_sum_vec;
        let r_sum: &mut [f64] = if m_count <= 8 {
            &mut r_sum[..m_count]
        } else {
            r_sum_vec = vec![0.0; m_count];
            &mut r_sum_vec
        };
        for &p in nbs {
            let pairs = &self.pairs[p * m_count..(p + 1) * m_count];
            for (acc, pair) in r_sum.iter_mut().zip(pairs) {
                *acc += pair.correlation(config.min_overlap).max(0.0);
            }
        }
        let mut r_by = Vec::with_capacity(m_count);
        let mut a_by = Vec::with_capacity(m_count);
        for (m, &total) in r_sum.iter().enumerate() {
            match self.stats[i * m_count + m].anomaly(config.epsilon) {
                None => {
                    r_by.push(None);
                    a_by.push(None);
                }
                Some(a) => {
                    let r = if nbs.is_empty() {
                        0.0
                    } else {
                        (total / nbs.len() as f64).clamp(0.0, 1.0)
                    };
                    r_by.push(Some(r));
                    a_by.push(Some(a));
                }
            }
        }
        let p = probabilities.get(i).map_or(&[][..], Vec::as_slice);
        finish_terms(f, r_by, a_by, p, config)
    }

    fn check_scoring(
        &self,
        config: &UtilityConfig,
        probabilities: &[Vec<f64>],
    ) -> Result<(), UtilityError> {
        config.validate(self.n_modalities)?;
        if let HistoryWindow::Last { seconds } = config.window {
            return Err(UtilityError::WindowNotIncremental(seconds));
        }
        if config.anomaly_reference != crate::AnomalyReference::OwnHistory {
            return Err(UtilityError::Config(format!(
                "the {} anomaly is computed from the history, not the incremental state",
                config.anomaly_reference.label()
            )));
        }
        let n = self.n_cells();
        if !probabilities.is_empty() {
            if probabilities.len() != n {
                return Err(UtilityError::Probabilities {
                    cell: "all".to_string(),
                    reason: format!("{} distributions for {n} cells", probabilities.len()),
                });
            }
            let k = probabilities[0].len();
            for (i, p) in probabilities.iter().enumerate() {
                check_distribution(p, k).map_err(|reason| UtilityError::Probabilities {
                    cell: format!("#{i}"),
                    reason,
                })?;
            }
        }
        Ok(())
    }

    /// The neighbour lists the state was built with.
    pub fn neighbours(&self) -> &[Vec<usize>] {
        &self.neighbours
    }
}

/// Magic of a serialised [`IncrementalState`] (8 bytes).
const STATE_MAGIC: &[u8; 8] = b"GLNINCST";

impl IncrementalState {
    /// Version of the format written by [`to_bytes`](Self::to_bytes).
    pub const FORMAT_VERSION: u32 = 1;

    /// The state as bytes: deterministic (equal states give equal bytes), little-endian,
    /// starting with the 8-byte magic `GLNINCST` and the `u32`
    /// [`FORMAT_VERSION`](Self::FORMAT_VERSION). Size O(cells × modalities × retained slots
    /// (20 bytes each) + pairs × modalities (48 bytes each)); call [`trim`](Self::trim) first to
    /// drop slots beyond the retention horizon.
    ///
    /// Layout (version 1): grid origin (i64, s), grid step (i64, s), modalities (u64),
    /// retention (option of i64, s), min points (u64), newest (i64, s); cells (u64), then per
    /// cell its last collection times (u64 count, then option of i64 each, s) and its neighbour
    /// list (u64 count, u64 each); per cell × modality: slots (u64 count, then time i64, sum
    /// f64, count u32 each), statistics (count u64, mean f64, M2 f64 for all points and for
    /// the points before the latest; latest as option of (i64, f64); min, max f64), forgotten
    /// extremes (min, max f64); pairs (u64), then per pair × modality n (u64), mean x, mean y,
    /// M2x, M2y, Cxy (f64).
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut w = Writer::with_header(STATE_MAGIC, Self::FORMAT_VERSION);
        w.i64(self.grid.origin);
        w.i64(self.grid.step_s);
        w.len(self.n_modalities);
        w.opt_i64(self.retention_s);
        w.len(self.min_points);
        w.i64(self.newest);
        w.len(self.n_cells());
        for (last, nbs) in self.last_collected.iter().zip(&self.neighbours) {
            w.len(last.len());
            for &l in last {
                w.opt_i64(l);
            }
            w.len(nbs.len());
            for &j in nbs {
                w.len(j);
            }
        }
        for ((slots, st), frozen) in self.slots.iter().zip(&self.stats).zip(&self.frozen) {
            w.len(slots.len());
            for s in slots {
                w.i64(s.time);
                w.f64(s.sum);
                w.u32(s.count);
            }
            for r in [st.all, st.before_latest] {
                w.u64(r.n);
                w.f64(r.mean);
                w.f64(r.m2);
            }
            match st.latest {
                Some((t, v)) => {
                    w.u8(1);
                    w.i64(t);
                    w.f64(v);
                }
                None => w.u8(0),
            }
            w.f64(st.min);
            w.f64(st.max);
            w.f64(frozen.0);
            w.f64(frozen.1);
        }
        w.len(self.pairs.len() / self.n_modalities.max(1));
        for p in &self.pairs {
            w.u64(p.n);
            for x in [p.mean_x, p.mean_y, p.m2x, p.m2y, p.cxy] {
                w.f64(x);
            }
        }
        w.buf
    }

    /// Decodes [`to_bytes`](Self::to_bytes)'s output. Wrong magic or version, truncated or
    /// trailing bytes, and inconsistent content (bad neighbour lists, slots out of order,
    /// non-finite values, counts that do not match) are [`UtilityError::Decode`] (or the error
    /// [`new`](Self::new) gives); never a panic, whatever the input.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, UtilityError> {
        let (mut r, _) = Reader::with_header(
            bytes,
            STATE_MAGIC,
            Self::FORMAT_VERSION..=Self::FORMAT_VERSION,
            "incremental state",
        )?;
        let grid = TimeGrid {
            origin: r.i64()?,
            step_s: r.i64()?,
        };
        // Each modality takes at least 4 × 8 bytes per cell below.
        let n_modalities = r.len(1)?;
        let retention = r.opt_i64()?;
        if retention.is_some_and(|x| x < 0) {
            return Err(r.error(format!("negative retention {retention:?} s")));
        }
        let min_points = r.len(0)?;
        let newest = r.i64()?;
        let n_cells = r.len(2 * 8)?;
        let mut sensors = Vec::with_capacity(n_cells);
        let mut last = Vec::with_capacity(n_cells);
        let mut neighbours = Vec::with_capacity(n_cells);
        for _ in 0..n_cells {
            let k = r.len(1)?;
            let l: Vec<Option<UnixSeconds>> =
                (0..k).map(|_| r.opt_i64()).collect::<Result<_, _>>()?;
            sensors.push(k);
            last.push(l);
            let m = r.len(8)?;
            let nb: Vec<usize> = (0..m)
                .map(|_| {
                    let j = r.u64()?;
                    usize::try_from(j).map_err(|_| r.error(format!("neighbour {j} too large")))
                })
                .collect::<Result<_, _>>()?;
            neighbours.push(nb);
        }
        // Every cell × modality takes at least 64 bytes below and every pair × modality 48:
        // refuse sizes the input cannot hold before allocating for them.
        let entries: usize = neighbours.iter().map(Vec::len).sum();
        let need = n_cells
            .saturating_mul(n_modalities)
            .saturating_mul(64)
            .saturating_add(
                (entries / 2)
                    .saturating_mul(n_modalities)
                    .saturating_mul(48),
            );
        if need > r.remaining() {
            return Err(r.error(format!(
                "{n_cells} cells × {n_modalities} modalities with {entries} neighbour entries \
                 exceed the {} bytes left",
                r.remaining()
            )));
        }
        let mut state = Self::new(&sensors, &neighbours, n_modalities, grid)?;
        state.last_collected = last;
        state.retention_s = retention;
        state.min_points = min_points;
        state.newest = newest;
        for key in 0..n_cells * n_modalities {
            let k = r.len(20)?;
            let mut slots = Vec::with_capacity(k);
            for _ in 0..k {
                let slot = Slot {
                    time: r.i64()?,
                    sum: r.finite()?,
                    count: r.u32()?,
                };
                if slot.count == 0 {
                    return Err(r.error(format!("empty slot at {} s", slot.time)));
                }
                if slots.last().is_some_and(|p: &Slot| p.time >= slot.time) {
                    return Err(r.error(format!("slot at {} s out of order", slot.time)));
                }
                slots.push(slot);
            }
            let mut running = [RunningStats::default(); 2];
            for x in &mut running {
                let (n, mean, m2) = (r.u64()?, r.finite()?, r.finite()?);
                *x = RunningStats { n, mean, m2 };
            }
            let latest = match r.u8()? {
                0 => None,
                1 => Some((r.i64()?, r.finite()?)),
                b => return Err(r.error(format!("invalid option tag {b}"))),
            };
            let (min, max) = (r.f64()?, r.f64()?);
            let frozen = (r.f64()?, r.f64()?);
            if [min, max, frozen.0, frozen.1].iter().any(|v| v.is_nan()) {
                return Err(r.error("NaN extreme".to_string()));
            }
            state.slots[key] = slots;
            state.stats[key] = SeriesStats {
                all: running[0],
                before_latest: running[1],
                latest,
                min,
                max,
            };
            state.frozen[key] = frozen;
        }
        let n_pairs = r.len(0)?;
        if n_pairs.checked_mul(n_modalities) != Some(state.pairs.len()) {
            return Err(r.error(format!(
                "{n_pairs} pairs, but the neighbour lists give {}",
                state.pairs.len() / n_modalities.max(1)
            )));
        }
        for p in &mut state.pairs {
            let n = r.u64()?;
            let mut v = [0.0; 5];
            for x in &mut v {
                *x = r.finite()?;
            }
            *p = PairStats::from_moments(n, v);
        }
        r.finish()?;
        Ok(state)
    }
}

/// `index` when it is below `count`, else the [`UtilityError::ReadingIndex`] that names the
/// `what` ("cell", "sensor" or "modality") out of range.
fn in_range(what: &'static str, index: usize, count: usize) -> Result<usize, UtilityError> {
    if index < count {
        Ok(index)
    } else {
        Err(UtilityError::ReadingIndex { what, index, count })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{CellInputs, Series, cell_series, score_cells};
    use rand::seq::SliceRandom;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    const DAY: i64 = 86_400;

    #[test]
    fn running_stats_remove_inverts_push() {
        let mut s = RunningStats::default();
        for x in [1.0, 4.0, 2.0, 8.0] {
            s.push(x);
        }
        s.remove(4.0);
        assert_eq!(s.count(), 3);
        assert!((s.mean() - 11.0 / 3.0).abs() < 1e-12);
        let m = 11.0 / 3.0;
        let m2 = (1.0f64 - m).powi(2) + (2.0f64 - m).powi(2) + (8.0f64 - m).powi(2);
        assert!((s.variance() - m2 / 2.0).abs() < 1e-12);
        let mut p = PairStats::default();
        for (x, y) in [(1.0, 2.0), (2.0, 4.0), (3.0, 7.0), (9.0, -1.0)] {
            p.push(x, y);
        }
        p.remove(9.0, -1.0);
        assert_eq!(PairStats::from_parts(p.parts()), p);
        let r = RunningStats::from_parts(s.count(), s.mean(), s.m2());
        assert_eq!(r, s);
        let want = 5.0 / (2.0f64 * 38.0 / 3.0).sqrt();
        assert!((p.correlation(3) - want).abs() < 1e-12);
        assert_eq!(p.correlation(4), 0.0);
    }

    fn rel_close(got: f64, want: f64, what: &str) {
        assert!(
            (got - want).abs() <= 1e-9 * want.abs().max(1e-3),
            "{what}: incremental {got} vs scratch {want}"
        );
    }

    /// Random field: per cell, per sensor, per modality a daily series with gaps; some cells
    /// lack a modality entirely; neighbours random and sometimes one-sided.
    struct World {
        sensors: Vec<usize>,
        neighbours: Vec<Vec<usize>>,
        /// (cell, sensor, modality, time, value)
        readings: Vec<Reading>,
        last: Vec<Vec<Option<i64>>>,
    }

    fn world(seed: u64) -> World {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let n = 25;
        let sensors: Vec<usize> = (0..n).map(|_| rng.random_range(1..4)).collect();
        let neighbours: Vec<Vec<usize>> = (0..n)
            .map(|i| {
                let mut nb: Vec<usize> = (0..rng.random_range(0..6))
                    .map(|_| rng.random_range(0..n))
                    .filter(|&j| j != i)
                    .collect();
                nb.sort_unstable();
                nb.dedup();
                nb
            })
            .collect();
        let mut readings = Vec::new();
        for (cell, &ns) in sensors.iter().enumerate() {
            for modality in 0..3 {
                if rng.random_bool(0.1) {
                    continue; // the cell lacks this modality
                }
                let base = 0.2 + 0.1 * modality as f64;
                for sensor in 0..ns {
                    let mut x = base;
                    for d in 0..40 {
                        x += rng.random_range(-0.01..0.01);
                        if rng.random_bool(0.7) {
                            let jitter = rng.random_range(0..3600);
                            readings.push(Reading {
                                cell,
                                sensor,
                                modality,
                                time: d * DAY + jitter,
                                value: x,
                            });
                        }
                    }
                }
            }
        }
        let last = sensors
            .iter()
            .map(|&ns| {
                (0..ns)
                    .map(|_| rng.random_bool(0.8).then(|| rng.random_range(0..41) * DAY))
                    .collect()
            })
            .collect();
        readings.shuffle(&mut rng);
        World {
            sensors,
            neighbours,
            readings,
            last,
        }
    }

    fn scratch(w: &World, t: i64, config: &UtilityConfig, p: &[Vec<f64>]) -> Vec<CellTerms> {
        let n = w.sensors.len();
        let series: Vec<Vec<OwnedSeries>> = (0..n)
            .map(|cell| {
                (0..3)
                    .map(|m| {
                        let per_sensor: Vec<(Vec<i64>, Vec<f64>)> = (0..w.sensors[cell])
                            .map(|s| {
                                let mut pts: Vec<(i64, f64)> = w
                                    .readings
                                    .iter()
                                    .filter(|r| r.cell == cell && r.modality == m && r.sensor == s)
                                    .map(|r| (r.time, r.value))
                                    .collect();
                                pts.sort_by_key(|p| p.0);
                                pts.into_iter().unzip()
                            })
                            .collect();
                        let views: Vec<Series> =
                            per_sensor.iter().map(|(t, v)| Series::new(t, v)).collect();
                        cell_series(&views, TimeGrid::DAILY)
                    })
                    .collect()
            })
            .collect();
        let inputs: Vec<CellInputs> = (0..n)
            .map(|i| CellInputs {
                last_collected: &w.last[i],
                series: series[i].iter().map(OwnedSeries::as_series).collect(),
                neighbours: &w.neighbours[i],
                probabilities: p.get(i).map_or(&[][..], Vec::as_slice),
            })
            .collect();
        score_cells(&inputs, t, config).unwrap()
    }

    #[test]
    fn incremental_equals_scratch_on_random_data() {
        let config = UtilityConfig {
            min_overlap: 5,
            ..UtilityConfig::default()
        };
        for seed in 0..6 {
            let w = world(seed);
            let mut state =
                IncrementalState::new(&w.sensors, &w.neighbours, 3, TimeGrid::DAILY).unwrap();
            for (cell, ls) in w.last.iter().enumerate() {
                for (s, l) in ls.iter().enumerate() {
                    if let Some(l) = l {
                        state.record_collection(cell, s, *l).unwrap();
                    }
                }
            }
            // Out of order across cells and sensors, in uneven batches.
            let mut rng = ChaCha8Rng::seed_from_u64(seed + 100);
            let mut rest = &w.readings[..];
            while !rest.is_empty() {
                let k = rng.random_range(1..50).min(rest.len());
                state.add_readings(&rest[..k]).unwrap();
                rest = &rest[k..];
            }
            let p: Vec<Vec<f64>> = (0..w.sensors.len())
                .map(|i| vec![0.1 * (i % 5) as f64 + 0.1, 0.9 - 0.1 * (i % 5) as f64])
                .collect();
            let t = 41 * DAY;
            let want = scratch(&w, t, &config, &p);
            let got = state.score(t, &config, &p).unwrap();
            let mut nonzero_r = 0;
            for (i, (g, e)) in got.iter().zip(&want).enumerate() {
                let what = format!("seed {seed} cell {i}");
                for (name, a, b) in [
                    ("F", g.f, e.f),
                    ("R", g.r, e.r),
                    ("A", g.a, e.a),
                    ("U", g.u, e.u),
                    ("S", g.s, e.s),
                ] {
                    rel_close(a, b, &format!("{what} {name}"));
                }
                for m in 0..3 {
                    assert_eq!(
                        g.r_by_modality[m].is_some(),
                        e.r_by_modality[m].is_some(),
                        "{what}"
                    );
                    if let (Some(a), Some(b)) = (g.a_by_modality[m], e.a_by_modality[m]) {
                        rel_close(a, b, &format!("{what} A^{m}"));
                    }
                }
                nonzero_r += usize::from(g.r > 0.0);
                let st = state.series_stats(i, 0);
                let s = state.cell_series(i, 0);
                if !s.is_empty() {
                    let mn = s.values.iter().copied().fold(f64::INFINITY, f64::min);
                    let mx = s.values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                    assert_eq!((st.min, st.max), (mn, mx), "{what} min/max");
                    assert_eq!(st.all.count() as usize, s.len());
                    assert_eq!(st.latest.map(|l| l.0), s.times.last().copied());
                }
            }
            assert!(
                nonzero_r > 3,
                "seed {seed}: the test should exercise redundancy"
            );
        }
    }

    #[test]
    fn retention_keeps_statistics_exact_and_rejects_old_readings() {
        let w = world(7);
        let mut readings = w.readings.clone();
        readings.sort_by_key(|r| r.time);
        let mut state =
            IncrementalState::new(&w.sensors, &w.neighbours, 3, TimeGrid::DAILY).unwrap();
        state.set_retention(Some(5 * DAY));
        for chunk in readings.chunks(97) {
            state.add_readings(chunk).unwrap();
        }
        let mut full =
            IncrementalState::new(&w.sensors, &w.neighbours, 3, TimeGrid::DAILY).unwrap();
        full.add_readings(&readings).unwrap();
        let config = UtilityConfig {
            min_overlap: 5,
            ..UtilityConfig::default()
        };
        let a = state.score(41 * DAY, &config, &[]).unwrap();
        let b = full.score(41 * DAY, &config, &[]).unwrap();
        let one_thread = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(|| full.score(41 * DAY, &config, &[]).unwrap());
        assert_eq!(b, one_thread, "the same terms on one thread as on the pool");
        for (x, y) in a.iter().zip(&b) {
            rel_close(x.s, y.s, "retention");
        }
        assert!(state.cell_series(0, 0).len() <= 7);
        let old = Reading {
            cell: 0,
            sensor: 0,
            modality: 0,
            time: 0,
            value: 1.0,
        };
        assert!(matches!(
            state.add_reading(old),
            Err(UtilityError::BeyondRetention { .. })
        ));
    }

    #[test]
    fn bad_readings_and_windows_are_rejected() {
        let mut s = IncrementalState::new(&[1, 2], &[vec![1], vec![]], 1, TimeGrid::DAILY).unwrap();
        let ok = Reading {
            cell: 1,
            sensor: 1,
            modality: 0,
            time: 0,
            value: 1.0,
        };
        for bad in [
            Reading { cell: 2, ..ok },
            Reading { sensor: 2, ..ok },
            Reading { modality: 1, ..ok },
            Reading {
                value: f64::NAN,
                ..ok
            },
        ] {
            assert!(s.add_readings(&[ok, bad]).is_err(), "{bad:?}");
        }
        assert_eq!(
            s.series_stats(1, 0).all.count(),
            0,
            "a failed batch changes nothing"
        );
        let windowed = UtilityConfig {
            window: HistoryWindow::Last { seconds: DAY },
            ..Default::default()
        };
        assert_eq!(
            s.score(0, &windowed, &[]),
            Err(UtilityError::WindowNotIncremental(DAY))
        );
        let neighbour_relative = UtilityConfig {
            anomaly_reference: crate::AnomalyReference::Neighbours { min_neighbours: 1 },
            ..Default::default()
        };
        assert!(matches!(
            s.score(0, &neighbour_relative, &[]),
            Err(UtilityError::Config(_))
        ));
        assert!(IncrementalState::new(&[1], &[vec![0]], 1, TimeGrid::DAILY).is_err());
        assert!(IncrementalState::new(&[0], &[vec![]], 1, TimeGrid::DAILY).is_err());
        assert!(s.record_collection(0, 1, 5).is_err());
    }

    fn built(seed: u64, retention: Option<i64>, min_points: usize) -> (World, IncrementalState) {
        let w = world(seed);
        let mut readings = w.readings.clone();
        readings.sort_by_key(|r| r.time);
        let mut state =
            IncrementalState::new(&w.sensors, &w.neighbours, 3, TimeGrid::DAILY).unwrap();
        state.set_retention(retention);
        state.set_min_points(min_points);
        for (cell, ls) in w.last.iter().enumerate() {
            for (s, l) in ls.iter().enumerate() {
                if let Some(l) = l {
                    state.record_collection(cell, s, *l).unwrap();
                }
            }
        }
        for chunk in readings.chunks(61) {
            state.add_readings(chunk).unwrap();
        }
        (w, state)
    }

    #[test]
    fn retention_keeps_extremes_exact() {
        let (_, mut kept) = built(11, Some(4 * DAY), 0);
        kept.trim();
        let (w, full) = built(11, None, 0);
        for i in 0..w.sensors.len() {
            for m in 0..3 {
                let (a, b) = (kept.series_stats(i, m), full.series_stats(i, m));
                assert_eq!((a.min, a.max), (b.min, b.max), "cell {i} modality {m}");
                assert_eq!(a.all.count(), b.all.count());
            }
        }
    }

    #[test]
    fn bytes_round_trip_and_reject_corruption() {
        let config = UtilityConfig {
            min_overlap: 5,
            ..UtilityConfig::default()
        };
        for (seed, retention, min_points) in [(1, None, 0), (2, Some(6 * DAY), 5), (3, Some(0), 2)]
        {
            let (_, mut state) = built(seed, retention, min_points);
            state.trim();
            let bytes = state.to_bytes();
            assert_eq!(bytes, state.clone().to_bytes(), "deterministic");
            assert_eq!(&bytes[..8], b"GLNINCST");
            let back = IncrementalState::from_bytes(&bytes).unwrap();
            assert_eq!(back, state);
            assert_eq!(back.to_bytes(), bytes);
            assert_eq!(
                back.score(41 * DAY, &config, &[]).unwrap(),
                state.score(41 * DAY, &config, &[]).unwrap()
            );
            // Every truncation is an error, never a panic.
            for n in (0..bytes.len()).step_by(7).chain([bytes.len() - 1]) {
                assert!(
                    IncrementalState::from_bytes(&bytes[..n]).is_err(),
                    "prefix {n}"
                );
            }
            let mut longer = bytes.clone();
            longer.push(0);
            assert!(IncrementalState::from_bytes(&longer).is_err());
            let mut version = bytes.clone();
            version[8] = 9;
            let e = IncrementalState::from_bytes(&version).unwrap_err();
            assert!(e.to_string().contains("version 9"), "{e}");
            // Flipped bytes give an error or a state, never a panic; a decoded state scores.
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            for _ in 0..300 {
                let mut b = bytes.clone();
                let k = rng.random_range(12..b.len());
                b[k] ^= 1 << rng.random_range(0..8);
                if let Ok(s) = IncrementalState::from_bytes(&b) {
                    let _ = s.score(41 * DAY, &config, &[]);
                }
            }
        }
    }

    #[test]
    fn more_readings_after_a_round_trip_equal_more_readings_before() {
        let w = world(5);
        let mut readings = w.readings.clone();
        readings.sort_by_key(|r| r.time);
        let (old, new) = readings.split_at(readings.len() * 3 / 4);
        let mut a = IncrementalState::new(&w.sensors, &w.neighbours, 3, TimeGrid::DAILY).unwrap();
        a.set_retention(Some(10 * DAY));
        a.set_min_points(5);
        a.add_readings(old).unwrap();
        a.trim();
        let mut b = IncrementalState::from_bytes(&a.to_bytes()).unwrap();
        a.add_readings(new).unwrap();
        b.add_readings(new).unwrap();
        assert_eq!(a, b);
    }

    proptest::proptest! {
        #![proptest_config(proptest::test_runner::Config::with_cases(64))]
        /// Arbitrary bytes, with or without a valid header, never make decoding panic.
        #[test]
        fn arbitrary_bytes_never_panic(
            body in proptest::collection::vec(proptest::num::u8::ANY, 0..600),
            header in proptest::bool::ANY,
        ) {
            let mut bytes = Vec::new();
            if header {
                bytes.extend_from_slice(b"GLNINCST");
                bytes.extend_from_slice(&1u32.to_le_bytes());
            }
            bytes.extend_from_slice(&body);
            let _ = IncrementalState::from_bytes(&bytes);
        }

        /// Small valid-looking prefixes (a real state's first bytes) followed by noise.
        #[test]
        fn real_prefix_then_noise_never_panics(
            cut in 12usize..400,
            noise in proptest::collection::vec(proptest::num::u8::ANY, 0..200),
        ) {
            let (_, state) = built(4, Some(3 * DAY), 1);
            let mut bytes = state.to_bytes();
            bytes.truncate(cut.min(bytes.len()));
            bytes.extend_from_slice(&noise);
            let _ = IncrementalState::from_bytes(&bytes);
        }

        /// Round trip equality and scoring equality on random worlds.
        #[test]
        fn round_trip_scores_equal(seed in 0u64..1000, retention in proptest::option::of(0i64..20), points in 0usize..6) {
            let (_, mut state) = built(seed, retention.map(|d| d * DAY), points);
            if seed % 2 == 0 {
                state.trim();
            }
            let back = IncrementalState::from_bytes(&state.to_bytes()).unwrap();
            proptest::prop_assert_eq!(&back, &state);
            let config = UtilityConfig { min_overlap: 3, ..UtilityConfig::default() };
            proptest::prop_assert_eq!(
                back.score(45 * DAY, &config, &[]).unwrap(),
                state.score(45 * DAY, &config, &[]).unwrap()
            );
        }
    }

    #[test]
    fn recent_series_predict_like_the_full_history() {
        use crate::{ConditionConfig, ConditionModel};
        for seed in [21, 22] {
            // Sparse: drop most readings of some cells so their last points are old.
            let mut w = world(seed);
            w.readings
                .retain(|r| r.cell % 4 != 0 || r.time < 12 * DAY || r.time % (7 * DAY) < DAY);
            let mut full =
                IncrementalState::new(&w.sensors, &w.neighbours, 3, TimeGrid::DAILY).unwrap();
            full.add_readings(&w.readings).unwrap();
            let config = ConditionConfig::default();
            let mut recent = full.clone();
            recent.set_retention(Some(3 * DAY));
            recent.set_min_points(config.trend_points);
            recent.trim();
            let recent = IncrementalState::from_bytes(&recent.to_bytes()).unwrap();
            let all = full.recent_series(0);
            let kept = recent.recent_series(0);
            assert!(
                kept.iter().map(OwnedSeries::len).sum::<usize>() * 3
                    < all.iter().map(OwnedSeries::len).sum::<usize>()
            );
            fn views(s: &[OwnedSeries]) -> Vec<Series<'_>> {
                s.iter().map(OwnedSeries::as_series).collect()
            }
            let model =
                ConditionModel::fit(&views(&all), &w.neighbours, 0, 30 * DAY, &config).unwrap();
            let model = ConditionModel::from_bytes(&model.to_bytes()).unwrap();
            let newest = full.newest().unwrap();
            for t in [newest, newest + DAY / 2, newest + 9 * DAY] {
                assert_eq!(
                    model.predict_proba(&views(&kept), &w.neighbours, t),
                    model.predict_proba(&views(&all), &w.neighbours, t),
                    "seed {seed} t {t}"
                );
            }
        }
    }
}
