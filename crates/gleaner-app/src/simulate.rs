//! Simulated flights: a dataset stands for everything the sensors logged (the ground truth),
//! and a flight brings back exactly what the visited sensors logged since their last
//! collection. Drives the same record use case as a real flight.

use std::collections::{HashMap, HashSet};
use std::path::PathBuf;

use gleaner_field::{SensorId, UnixSeconds};
use gleaner_ingest::{IngestReport, Readings, Row};
use gleaner_store::{MissionId, Store};

use crate::error::{AppError, Result};
use crate::ingest::{Format, IngestRequest, Parsed, known_sensors, parse_files};
use crate::progress::Progress;
use crate::project::Project;
use crate::record::{RecordOutcome, RecordRequest, record_parsed};

/// Everything the sensors logged, whether collected or not (seconds, modality units).
pub struct Truth {
    readings: Readings,
    /// The logging period, seconds: a reading stamped t summarises (t, t + period] and is
    /// available only from t + period on (a daily mean stamped at midnight is known at the
    /// next midnight).
    pub period_s: i64,
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
        Ok(Self { readings, period_s })
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
    /// `at` (t + period <= at).
    fn brought_back(
        &self,
        sensors: &HashSet<SensorId>,
        last: &HashMap<SensorId, UnixSeconds>,
        at: UnixSeconds,
    ) -> Readings {
        let r = &self.readings;
        let keep: Vec<Option<Option<UnixSeconds>>> = r
            .sensors
            .iter()
            .map(|s| sensors.contains(s).then(|| last.get(s).copied()))
            .collect();
        let rows: Vec<Row> = r
            .rows
            .iter()
            .filter(|row| match keep.get(row.sensor as usize) {
                Some(Some(since)) => {
                    row.t.saturating_add(self.period_s) <= at
                        && since.is_none_or(|since| row.t > since - self.period_s)
                }
                _ => false,
            })
            .copied()
            .collect();
        Readings {
            sensors: r.sensors.clone(),
            modalities: r.modalities.clone(),
            rows,
        }
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
    let mission = project
        .store()
        .mission(id)?
        .ok_or_else(|| AppError::NotFound {
            what: "mission",
            id: format!("#{id}"),
        })?;
    let visited: HashSet<_> = mission.mission.stops.iter().map(|s| s.cell).collect();
    let sensors: HashSet<SensorId> = project
        .store()
        .cells()?
        .into_iter()
        .filter(|c| visited.contains(&c.index))
        .flat_map(|c| c.sensors)
        .collect();
    // The last collection, or the latest reading already stored for a sensor never flown to
    // (its history came from an earlier ingest).
    let last: HashMap<SensorId, UnixSeconds> = project
        .store()
        .sensor_last_collected()?
        .into_iter()
        .collect();
    let readings = truth.brought_back(&sensors, &last, at);
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
    record_parsed(
        project,
        &RecordRequest {
            mission: id,
            at: Some(at),
            cells: None,
            readings: None,
            amend: false,
        },
        Some(parsed),
        clock_now,
    )
}
