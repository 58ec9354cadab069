//! What is known at mission time t: the field and the collected history.

use std::collections::HashMap;

use gleaner_field::{Field, Sensor, UnixSeconds};
use gleaner_store::{ReadingBatch, Store};
use gleaner_utility::{OwnedSeries, Series, TimeGrid, cell_series};

use crate::error::Result;
use crate::project::Project;

/// Which stored readings count as collected: those with times in `from..=until` (seconds),
/// plus whatever a recorded collection brought back.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct History {
    /// Earliest reading used, seconds since the Unix epoch.
    pub from: UnixSeconds,
    /// Latest reading used (unless a recorded collection brought later ones back), seconds.
    pub until: UnixSeconds,
}

impl Default for History {
    /// Everything stored.
    fn default() -> Self {
        Self {
            from: UnixSeconds::MIN,
            until: UnixSeconds::MAX,
        }
    }
}

/// What the planner knows at time t: the field and, per cell and modality, the collected
/// cell series; per sensor, the last collection time.
pub struct Knowledge {
    /// The sensors, sorted by id (positions as in `field`).
    pub sensors: Vec<Sensor>,
    /// The grid.
    pub field: Field,
    /// Modality names, sorted.
    pub modalities: Vec<String>,
    /// `series[cell][modality]`: the cell series x̂ on the dataset's time grid.
    pub series: Vec<Vec<OwnedSeries>>,
    /// Per sensor: the later of its recorded collection and its latest known reading at or
    /// before t (a reading in the database has been collected), seconds.
    pub last_collected: Vec<Option<UnixSeconds>>,
    /// Per sensor: its earliest reading, seconds (the start of its log, for pending volume).
    pub first_reading: Vec<Option<UnixSeconds>>,
    /// The latest known reading at or before t, seconds.
    pub latest: Option<UnixSeconds>,
}

/// The median spacing of consecutive readings, seconds (the dataset's sampling interval).
pub fn sampling_step(times: &[Vec<UnixSeconds>]) -> i64 {
    let mut gaps: Vec<i64> = times
        .iter()
        .flat_map(|t| t.windows(2).map(|w| w[1] - w[0]))
        .filter(|&g| g > 0)
        .collect();
    if gaps.is_empty() {
        return 86_400;
    }
    let mid = gaps.len() / 2;
    *gaps.select_nth_unstable(mid).1
}

/// Loads everything collected at or before `t` (default: the latest reading), within
/// `history`. A reading is known when it lies in the history window, or when a recorded
/// collection of its sensor at or before t brought it back.
pub fn knowledge<S: Store>(
    project: &Project<S>,
    t: Option<UnixSeconds>,
    history: History,
) -> Result<Knowledge> {
    let (sensors, field) = project.field()?;
    let index: HashMap<&str, usize> = sensors
        .iter()
        .enumerate()
        .map(|(k, s)| (s.id.as_str(), k))
        .collect();
    let t_max = t.unwrap_or(UnixSeconds::MAX);
    let mut collected: Vec<Option<UnixSeconds>> = vec![None; sensors.len()];
    for (id, at) in project.store().sensor_last_collected()? {
        if let Some(&s) = index.get(id.as_str())
            && at <= t_max
        {
            collected[s] = collected[s].max(Some(at));
        }
    }
    let horizon = collected
        .iter()
        .flatten()
        .copied()
        .max()
        .unwrap_or(UnixSeconds::MIN);
    let until = t_max.min(history.until.max(horizon));
    if history.from > until {
        return Ok(empty(sensors, field, collected));
    }
    let batch = project.store().readings_for(None, history.from..=until)?;
    let c = columns(&sensors, &batch, &collected, t_max, history.until, None);
    let series = cell_series_of(&field, &c, None);
    Ok(Knowledge {
        sensors,
        field,
        modalities: c.modalities,
        series,
        last_collected: c.last_collected,
        first_reading: c.first_reading,
        latest: c.latest,
    })
}

/// Readings sorted into per (sensor, modality) columns: what [`knowledge`] and the persisted
/// utility state (`state.rs`) are built from, so both see exactly the same series.
pub(crate) struct Columns {
    /// Modality names, sorted.
    pub modalities: Vec<String>,
    /// Per sensor × modality (sensor-major): times, seconds, ascending.
    pub times: Vec<Vec<UnixSeconds>>,
    /// Per sensor × modality: values, the modality's unit.
    pub values: Vec<Vec<f64>>,
    /// Per sensor: the later of `collected` and its latest reading kept, seconds.
    pub last_collected: Vec<Option<UnixSeconds>>,
    /// Per sensor: its earliest reading kept, seconds.
    pub first_reading: Vec<Option<UnixSeconds>>,
    /// The latest reading kept, seconds.
    pub latest: Option<UnixSeconds>,
    /// The sampling grid (origin: the earliest reading; step: the median spacing).
    pub grid: TimeGrid,
}

/// The latest reading time a scoring at `t_max` knows of a sensor, seconds: the history's
/// `until`, or later when a recorded collection (`collected`, seconds) brought readings
/// back, never after `t_max`. [`columns`] and the drift freshness keep readings by it.
pub(crate) fn known_until(
    t_max: UnixSeconds,
    until: UnixSeconds,
    collected: Option<UnixSeconds>,
) -> UnixSeconds {
    t_max.min(until.max(collected.unwrap_or(UnixSeconds::MIN)))
}

/// Sorts `batch` into [`Columns`] for `sensors` (sorted by id). A reading is kept when its
/// time is at or before [`known_until`] of its sensor's recorded collection
/// (`collected`, seconds). `grid`: use this grid instead of deriving it.
pub(crate) fn columns(
    sensors: &[Sensor],
    batch: &ReadingBatch,
    collected: &[Option<UnixSeconds>],
    t_max: UnixSeconds,
    until: UnixSeconds,
    grid: Option<TimeGrid>,
) -> Columns {
    let index: HashMap<&str, usize> = sensors
        .iter()
        .enumerate()
        .map(|(k, s)| (s.id.as_str(), k))
        .collect();
    let mut modalities: Vec<String> = batch.modalities.iter().map(ToString::to_string).collect();
    modalities.sort();
    modalities.dedup();
    let mpos: Vec<usize> = batch
        .modalities
        .iter()
        .map(|m| modalities.binary_search(&m.to_string()).unwrap_or(0))
        .collect();
    let nm = modalities.len();
    // Per (sensor, modality): times and values, in time order (the store returns them so).
    let mut times: Vec<Vec<UnixSeconds>> = vec![Vec::new(); sensors.len() * nm];
    let mut values: Vec<Vec<f64>> = vec![Vec::new(); sensors.len() * nm];
    let mut last_collected = collected.to_vec();
    last_collected.resize(sensors.len(), None);
    let mut first_reading: Vec<Option<UnixSeconds>> = vec![None; sensors.len()];
    let mut latest = None;
    for r in &batch.rows {
        let Some(&s) = batch
            .sensors
            .get(r.sensor as usize)
            .and_then(|id| index.get(id.as_str()))
        else {
            continue;
        };
        let own = collected.get(s).copied().flatten();
        if r.t > known_until(t_max, until, own) {
            continue;
        }
        let Some(&m) = mpos.get(r.modality as usize) else {
            continue;
        };
        let k = s * nm + m;
        times[k].push(r.t);
        values[k].push(r.value);
        last_collected[s] = last_collected[s].max(Some(r.t));
        first_reading[s] = Some(first_reading[s].map_or(r.t, |f: i64| f.min(r.t)));
        latest = latest.max(Some(r.t));
    }
    let grid = grid.unwrap_or_else(|| {
        let step = sampling_step(&times);
        let origin = times
            .iter()
            .filter_map(|t| t.first())
            .min()
            .copied()
            .unwrap_or(0);
        TimeGrid {
            origin,
            step_s: step.max(1),
        }
    });
    Columns {
        modalities,
        times,
        values,
        last_collected,
        first_reading,
        latest,
        grid,
    }
}

/// The cell series x̂ of every cell: all modalities of `c`, or only modality `only`.
pub(crate) fn cell_series_of(
    field: &Field,
    c: &Columns,
    only: Option<usize>,
) -> Vec<Vec<OwnedSeries>> {
    let nm = c.modalities.len();
    field
        .cells()
        .iter()
        .map(|cell| {
            (0..nm)
                .filter(|m| only.is_none_or(|o| o == *m))
                .map(|m| {
                    let members: Vec<Series<'_>> = cell
                        .sensors
                        .iter()
                        .map(|&s| Series::new(&c.times[s * nm + m], &c.values[s * nm + m]))
                        .collect();
                    cell_series(&members, c.grid)
                })
                .collect()
        })
        .collect()
}

fn empty(sensors: Vec<Sensor>, field: Field, collected: Vec<Option<UnixSeconds>>) -> Knowledge {
    let n_cells = field.cells().len();
    let n = sensors.len();
    Knowledge {
        sensors,
        field,
        modalities: Vec::new(),
        series: vec![Vec::new(); n_cells],
        last_collected: collected,
        first_reading: vec![None; n],
        latest: None,
    }
}

impl Knowledge {
    /// The cells' ids (`x3y-1`), in field order.
    pub fn cell_labels(&self) -> Vec<String> {
        self.field
            .cells()
            .iter()
            .map(|c| c.index.to_string())
            .collect()
    }
}
