//! Simulated flights: a dataset stands for everything the sensors logged (the ground truth),
//! and a flight brings back exactly what the visited sensors logged since their last
//! collection. Drives the same record use case as a real flight.

use std::collections::{HashMap, HashSet};
use std::path::PathBuf;

use gleaner_field::{SensorId, UnixSeconds};
use gleaner_ingest::{IngestReport, ModalityInfo, Readings, Row};
use gleaner_store::{MissionId, Store};

use gleaner_app::shortcuts::{Parsed, known_sensors, parse_files, record_parsed};
use gleaner_app::{AppError, Result};
use gleaner_app::{Format, IngestRequest, Progress, Project, RecordOutcome, RecordRequest};

/// Everything the sensors logged, whether collected or not (seconds, modality units).
pub struct Truth {
    readings: Readings,
    /// The logging period, seconds: a reading stamped t summarises (t, t + period] and is
    /// available only from t + period on (a daily mean stamped at midnight is known at the
    /// next midnight).
    pub period_s: i64,
    /// A sensor's log holds at most this many readings per modality: when full, the oldest
    /// uncollected reading is dropped (`None`: unlimited).
    pub buffer_readings: Option<usize>,
    /// Per sensor of `readings` (by its index there): (time in s, row index) of its rows,
    /// in time order, so a flight finds what it brings back without scanning every row.
    by_sensor: Vec<Vec<(UnixSeconds, usize)>>,
}

/// [`Truth::by_sensor`] of `readings`.
fn index_by_sensor(readings: &Readings) -> Vec<Vec<(UnixSeconds, usize)>> {
    let mut by_sensor = vec![Vec::new(); readings.sensors.len()];
    for (k, row) in readings.rows.iter().enumerate() {
        if let Some(rows) = by_sensor.get_mut(row.sensor as usize) {
            rows.push((row.t, k));
        }
    }
    for rows in &mut by_sensor {
        rows.sort_unstable();
    }
    by_sensor
}

impl Truth {
    /// The ground truth from readings files (read like `ingest`), with the logging period.
    pub fn from_files<S: Store>(
        project: &Project<S>,
        request: &IngestRequest,
        period_s: i64,
        progress: &dyn Progress,
    ) -> Result<Self> {
        if period_s < 0 {
            return Err(AppError::Invalid(format!(
                "logging period {period_s} s must be >= 0"
            )));
        }
        let parsed = parse_files(
            request,
            known_sensors(project.store())?,
            &project.settings().ingest.value_limits(),
            progress,
        )?;
        let mut readings = Readings::default();
        for (_, _, r, _) in parsed.files {
            readings.append(r);
        }
        Ok(Self {
            by_sensor: index_by_sensor(&readings),
            readings,
            period_s,
            buffer_readings: None,
        })
    }

    /// The ground truth from readings already read, with the logging period (seconds).
    pub fn from_readings(readings: Readings, period_s: i64) -> Result<Self> {
        if period_s < 0 {
            return Err(AppError::Invalid(format!(
                "logging period {period_s} s must be >= 0"
            )));
        }
        Ok(Self {
            by_sensor: index_by_sensor(&readings),
            readings,
            period_s,
            buffer_readings: None,
        })
    }

    /// A project's whole record as the ground truth of a replay (`simulate --project`): every
    /// stored reading, the logging period the sampling step (the median gap between a
    /// series' consecutive readings, s; a day when no series has two readings). Reads the
    /// store only.
    pub fn from_store<S: Store>(project: &Project<S>) -> Result<Self> {
        let store = project.store();
        let units: HashMap<String, Option<String>> = store
            .modalities()?
            .into_iter()
            .map(|m| (m.modality.as_str().to_string(), m.unit))
            .collect();
        let batch = store.readings_for(None, UnixSeconds::MIN..=UnixSeconds::MAX)?;
        if batch.rows.is_empty() {
            return Err(AppError::Invalid(
                "the project holds no readings to replay (run `gleaner ingest`)".into(),
            ));
        }
        let mut series: HashMap<(u32, u32), Vec<UnixSeconds>> = HashMap::new();
        for r in &batch.rows {
            series.entry((r.sensor, r.modality)).or_default().push(r.t);
        }
        let mut times: Vec<(_, Vec<UnixSeconds>)> = series.into_iter().collect();
        times.sort_by_key(|p| p.0);
        for (_, t) in &mut times {
            t.sort_unstable();
        }
        let period_s = gleaner_app::shortcuts::sampling_step(
            &times.into_iter().map(|p| p.1).collect::<Vec<_>>(),
        );
        let readings = Readings {
            modalities: batch
                .modalities
                .iter()
                .map(|m| ModalityInfo {
                    unit: units.get(m.as_str()).cloned().flatten(),
                    modality: m.clone(),
                })
                .collect(),
            sensors: batch.sensors,
            rows: batch
                .rows
                .iter()
                .map(|r| Row {
                    sensor: r.sensor,
                    modality: r.modality,
                    t: r.t,
                    value: r.value,
                    line: 0,
                })
                .collect(),
        };
        Self::from_readings(readings, period_s)
    }

    /// Every reading, whether collected or not.
    pub fn readings(&self) -> &Readings {
        &self.readings
    }

    /// The readings available by `at` (t + period <= at): what a project starting its
    /// campaign at `at` may hold as history.
    pub fn available_by(&self, at: UnixSeconds) -> Readings {
        Readings {
            sensors: self.readings.sensors.clone(),
            modalities: self.readings.modalities.clone(),
            rows: self
                .readings
                .rows
                .iter()
                .filter(|r| r.t.saturating_add(self.period_s) <= at)
                .copied()
                .collect(),
        }
    }

    /// Number of readings.
    pub fn len(&self) -> usize {
        self.readings.rows.len()
    }

    /// Whether there are no readings.
    pub fn is_empty(&self) -> bool {
        self.readings.rows.is_empty()
    }

    /// Earliest and latest reading times, seconds.
    pub fn span(&self) -> Option<(UnixSeconds, UnixSeconds)> {
        let t0 = self.readings.rows.iter().map(|r| r.t).min()?;
        let t1 = self.readings.rows.iter().map(|r| r.t).max()?;
        Some((t0, t1))
    }

    /// What `sensors` logged after their last collection (`None`: ever) and is available at
    /// `at` (t + period <= at), and how many of those readings a full buffer dropped (the
    /// oldest beyond `buffer_readings` per sensor and modality).
    fn brought_back(
        &self,
        sensors: &HashSet<SensorId>,
        last: &HashMap<SensorId, UnixSeconds>,
        at: UnixSeconds,
    ) -> (Readings, u64) {
        let r = &self.readings;
        // Per visited sensor, the time range of its rows that qualify (t + period <= at and
        // t > since − period), then those rows in the readings' own order.
        let mut picked: Vec<usize> = Vec::new();
        for (k, s) in r.sensors.iter().enumerate() {
            if !sensors.contains(s) {
                continue;
            }
            let times = &self.by_sensor[k];
            let hi = times.partition_point(|&(t, _)| t.saturating_add(self.period_s) <= at);
            let lo = match last.get(s) {
                Some(&since) => times.partition_point(|&(t, _)| t <= since - self.period_s),
                None => 0,
            };
            if lo < hi {
                picked.extend(times[lo..hi].iter().map(|&(_, row)| row));
            }
        }
        picked.sort_unstable();
        let mut rows: Vec<Row> = picked.into_iter().map(|k| r.rows[k]).collect();
        let mut lost = 0u64;
        if let Some(capacity) = self.buffer_readings {
            // Newest first within each (sensor, modality); keep the first `capacity`.
            rows.sort_by(|a, b| {
                (a.sensor, a.modality)
                    .cmp(&(b.sensor, b.modality))
                    .then(b.t.cmp(&a.t))
            });
            let mut kept = Vec::with_capacity(rows.len());
            let mut run: Option<(u32, u32, usize)> = None;
            for row in rows {
                let n = match run {
                    Some((s, m, n)) if (s, m) == (row.sensor, row.modality) => n + 1,
                    _ => 1,
                };
                run = Some((row.sensor, row.modality, n));
                if n <= capacity {
                    kept.push(row);
                } else {
                    lost += 1;
                }
            }
            kept.sort_by_key(|row| (row.sensor, row.modality, row.t));
            rows = kept;
        }
        (
            Readings {
                sensors: r.sensors.clone(),
                modalities: r.modalities.clone(),
                rows,
            },
            lost,
        )
    }
}

/// Flies mission `id` in simulation at `at` (seconds): the planned stops are visited, and the
/// readings their sensors logged since their last collection (available by `at`) come back
/// and are recorded like a real flight's, in one transaction.
pub fn fly<S: Store>(
    project: &mut Project<S>,
    truth: &Truth,
    id: MissionId,
    at: UnixSeconds,
    clock_now: UnixSeconds,
) -> Result<RecordOutcome> {
    project.exclusive(|project| {
        fly_buffered(project, truth, id, at, clock_now).map(|(outcome, _)| outcome)
    })
}

/// [`fly`], also returning how many readings the visited sensors' full buffers had dropped
/// (see [`Truth::buffer_readings`]).
pub fn fly_buffered<S: Store>(
    project: &mut Project<S>,
    truth: &Truth,
    id: MissionId,
    at: UnixSeconds,
    clock_now: UnixSeconds,
) -> Result<(RecordOutcome, u64)> {
    fly_cells(project, truth, id, None, at, clock_now)
}

/// [`fly_buffered`] of a flight that visited only `cells` (in the order flown, each one of
/// the mission's stops: a flight that re-planned in the air) [default: every planned stop].
///
/// # Errors
/// As [`fly_buffered`]; a cell that is not one of the mission's stops, or no cell at all.
pub fn fly_cells<S: Store>(
    project: &mut Project<S>,
    truth: &Truth,
    id: MissionId,
    cells: Option<&[gleaner_field::CellIndex]>,
    at: UnixSeconds,
    clock_now: UnixSeconds,
) -> Result<(RecordOutcome, u64)> {
    let mission = project
        .store()
        .mission(id)?
        .ok_or_else(|| AppError::NotFound {
            what: "mission",
            id: format!("#{id}"),
        })?;
    let visited: HashSet<_> = match cells {
        Some(c) => c.iter().copied().collect(),
        None => mission.mission.stops.iter().map(|s| s.cell).collect(),
    };
    let sensors: HashSet<SensorId> = project
        .store()
        .cells()?
        .into_iter()
        .filter(|c| visited.contains(&c.index))
        .flat_map(|c| c.sensors)
        .collect();
    // The last collection, or the latest reading already stored for a sensor never flown to
    // (its history came from an earlier ingest).
    let mut last: HashMap<SensorId, UnixSeconds> = project
        .store()
        .sensor_last_collected()?
        .into_iter()
        .collect();
    let never: Vec<SensorId> = sensors
        .iter()
        .filter(|s| !last.contains_key(*s))
        .cloned()
        .collect();
    if !never.is_empty() {
        // Collected when its latest stored reading became available.
        let stored = project
            .store()
            .readings_of_sensors(&never, UnixSeconds::MIN..=at)?;
        for r in &stored.rows {
            if let Some(s) = stored.sensors.get(r.sensor as usize) {
                let t = r.t.saturating_add(truth.period_s);
                let e = last.entry(s.clone()).or_insert(t);
                *e = (*e).max(t);
            }
        }
    }
    let (readings, lost) = truth.brought_back(&sensors, &last, at);
    let report = IngestReport {
        rows_read: readings.rows.len() as u64,
        readings: readings.rows.len() as u64,
        ..IngestReport::default()
    };
    let parsed = Parsed {
        files: vec![(
            PathBuf::from(format!("simulated flight of mission #{id}")),
            Format::Long,
            readings,
            report.clone(),
        )],
        report,
    };
    let outcome = record_parsed(
        project,
        &RecordRequest {
            mission: id,
            at: Some(at),
            cells: cells.map(|c| c.iter().map(ToString::to_string).collect()),
            readings: None,
            amend: false,
        },
        Some(parsed),
        clock_now,
    )?;
    Ok((outcome, lost))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig { cases: 128, ..ProptestConfig::default() })]

        /// The indexed pick brings back exactly the rows (and in the same order) that
        /// filtering every row by the definition does.
        #[test]
        fn brought_back_is_the_filter_over_every_row(
            rows in prop::collection::vec((0..4u32, 0..2u32, -20..60i64), 0..80),
            since in prop::collection::vec(prop::option::of(-10..50i64), 4),
            visited in prop::collection::vec(any::<bool>(), 4),
            period in 0..5i64,
            at in 0..70i64,
        ) {
            let readings = Readings {
                sensors: (0..4).map(|k| SensorId::new(format!("s{k}")).unwrap()).collect(),
                modalities: Vec::new(),
                rows: rows
                    .iter()
                    .enumerate()
                    .map(|(k, &(sensor, modality, t))| Row {
                        sensor,
                        modality,
                        t,
                        value: k as f64,
                        line: k as u32,
                    })
                    .collect(),
            };
            let truth = Truth::from_readings(readings.clone(), period).unwrap();
            let sensors: HashSet<SensorId> = readings
                .sensors
                .iter()
                .zip(&visited)
                .filter(|(_, v)| **v)
                .map(|(s, _)| s.clone())
                .collect();
            let last: HashMap<SensorId, UnixSeconds> = readings
                .sensors
                .iter()
                .zip(&since)
                .filter_map(|(s, t)| Some((s.clone(), (*t)?)))
                .collect();
            let want: Vec<Row> = readings
                .rows
                .iter()
                .filter(|r| {
                    let s = &readings.sensors[r.sensor as usize];
                    sensors.contains(s)
                        && r.t + period <= at
                        && last.get(s).is_none_or(|&since| r.t > since - period)
                })
                .copied()
                .collect();
            let (got, lost) = truth.brought_back(&sensors, &last, at);
            prop_assert_eq!(got.rows, want);
            prop_assert_eq!(lost, 0);
        }
    }
}
