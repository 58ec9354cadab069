//! Recording a flight (docs/method.md §5 step 5): the cells actually visited, when, and the readings
//! brought home — one transaction.

use std::collections::{HashMap, HashSet};

use gleaner_field::{CellIndex, SensorId, UnixSeconds};
use gleaner_ingest::time::format_rfc3339;
use gleaner_store::{
    ConflictPolicy, MissionId, MissionRecord, MissionStatus, Store, StoreWrite, VisitRecord,
};

use crate::ingest::{IngestRequest, Parsed, StatePolicy, known_sensors, parse_files, store_parsed};
use crate::progress::Progress;
use gleaner_scoring::Project;
use gleaner_scoring::summaries;
use gleaner_scoring::{AppError, Result};

/// A flown mission to record.
#[derive(Debug, Clone)]
pub struct RecordRequest {
    /// The planned mission.
    pub mission: MissionId,
    /// When the data was collected, seconds [default: the mission's planned time, or the
    /// newest reading brought back when that is later]; not before the planned time.
    pub at: Option<UnixSeconds>,
    /// Cells actually visited, in order (ids like `x3y-1`), each one of the mission's stops
    /// [default: the planned stops].
    pub cells: Option<Vec<String>>,
    /// The readings brought back (files and how to read them), if any.
    pub readings: Option<IngestRequest>,
    /// Replace an earlier record of this mission instead of refusing.
    pub amend: bool,
}

/// What was recorded.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordOutcome {
    /// The mission.
    pub mission: MissionId,
    /// Collection time, seconds.
    pub at: UnixSeconds,
    /// Cells visited, in order.
    pub cells: Vec<CellIndex>,
    /// Sensors marked collected.
    pub sensors_collected: usize,
    /// Readings brought back and newly stored.
    pub readings_inserted: u64,
    /// Readings brought back that were already stored.
    pub readings_unchanged: u64,
    /// Whether an earlier record was replaced.
    pub amended: bool,
}

/// The use case: checks the flight against the plan and the grid, then in one transaction
/// stores the readings brought back, marks the visited cells' sensors collected at `at`,
/// records the visits and refreshes those cells' summaries. Refused, writing nothing: an
/// unknown mission or cell; a mission without stops; a visited cell that is not one of the
/// mission's stops; a collection time outside 1900..=2199 or before the mission's planned
/// time; a mission already recorded (unless `amend`); a reading from a sensor outside the
/// visited cells, or dated after the collection time.
pub fn record_flight<S: Store>(
    project: &mut Project<S>,
    request: &RecordRequest,
    clock_now: UnixSeconds,
    progress: &dyn Progress,
) -> Result<RecordOutcome> {
    let parsed = match &request.readings {
        Some(r) if !r.files.is_empty() => Some(parse_files(
            r,
            known_sensors(project.store())?,
            &project.settings().ingest.value_limits(),
            progress,
        )?),
        _ => None,
    };
    project.exclusive(|project| record_parsed(project, request, parsed, clock_now))
}

/// [`record_flight`] with the readings already read (from files, or from a simulated flight).
pub fn record_parsed<S: Store>(
    project: &mut Project<S>,
    request: &RecordRequest,
    parsed: Option<Parsed>,
    clock_now: UnixSeconds,
) -> Result<RecordOutcome> {
    let mission = recordable_mission(project, request)?;
    let at = collection_time(request, &mission, parsed.as_ref())?;
    if mission.mission.stops.is_empty() {
        return Err(AppError::Invalid(format!(
            "mission #{} has no stops: there is no flight to record",
            request.mission
        )));
    }
    let flown = Flown::of(project, request, &mission, at)?;
    if let Some(parsed) = &parsed {
        flown.check_brought_back(parsed)?;
    }
    let Flown {
        visits, collected, ..
    } = flown;
    let settings = project.settings().clone();
    let id = request.mission;
    let amend = request.amend;
    let (inserted, unchanged) = project.store_mut().write(|tx| {
        let mut stats = (0, 0);
        let mut added = Vec::new();
        if let Some(parsed) = &parsed {
            let (s, _, new_rows) = store_parsed(
                tx,
                parsed,
                ConflictPolicy::Fail,
                clock_now,
                at,
                &settings,
                StatePolicy::Maintain,
            )?;
            stats = (s.inserted, s.unchanged);
            added = new_rows;
        }
        tx.set_sensors_collected(&collected)?;
        tx.record_visits(id, &visits, at, amend)?;
        let sensors: Vec<SensorId> = collected.iter().map(|(s, _)| s.clone()).collect();
        summaries::refresh_cells_after(tx, &sensors, &added, at, &settings)?;
        Ok::<_, AppError>(stats)
    })?;
    Ok(RecordOutcome {
        mission: id,
        at,
        cells: visits.iter().map(|v| v.cell).collect(),
        sensors_collected: collected.len(),
        readings_inserted: inserted,
        readings_unchanged: unchanged,
        amended: mission.status == MissionStatus::Flown,
    })
}

/// The mission to record: it exists, is not cancelled and, unless `amend`, not yet flown.
fn recordable_mission<S: Store>(
    project: &Project<S>,
    request: &RecordRequest,
) -> Result<MissionRecord> {
    let mission = project
        .store()
        .mission(request.mission)?
        .ok_or_else(|| AppError::NotFound {
            what: "mission",
            id: format!("#{}", request.mission),
        })?;
    crate::missions::refuse_cancelled(&mission, "recorded")?;
    if mission.status == MissionStatus::Flown && !request.amend {
        return Err(AppError::Conflict(format!(
            "mission #{} was already recorded as flown{}; pass --amend to replace that record",
            request.mission,
            mission
                .flown_at
                .map_or(String::new(), |t| format!(" at {}", format_rfc3339(t)))
        )));
    }
    Ok(mission)
}

/// The collection time: the request's, else the planned time or the newest reading brought
/// back when that is later; never before the planned time.
fn collection_time(
    request: &RecordRequest,
    mission: &MissionRecord,
    parsed: Option<&Parsed>,
) -> Result<UnixSeconds> {
    gleaner_scoring::when::check("collection time", request.at)?;
    let planned_at = mission.mission.planned_at;
    // Without a collection time, the flight was no earlier than the newest reading it
    // brought back (a same-day reading is not "after the flight"), nor than its planned time.
    let newest_brought = parsed.and_then(|p| {
        p.files
            .iter()
            .flat_map(|(_, _, readings, _)| readings.rows.iter().map(|r| r.t))
            .max()
    });
    let at = request
        .at
        .unwrap_or_else(|| newest_brought.map_or(planned_at, |t| t.max(planned_at)));
    if at < planned_at {
        return Err(AppError::Invalid(format!(
            "collection time {} is before mission #{}'s planned time {}: a mission is flown at \
             or after the time it was planned for; nothing was recorded",
            format_rfc3339(at),
            request.mission,
            format_rfc3339(planned_at)
        )));
    }
    Ok(at)
}

/// The flight as recorded: the cells visited (each a stop of the mission, once) and their
/// sensors, collected at `at`.
struct Flown {
    /// The visits, in order.
    visits: Vec<VisitRecord>,
    /// Every visited cell's sensors, collected at `at`.
    collected: Vec<(SensorId, UnixSeconds)>,
    /// Each sensor's cell, over the grid.
    cell_of: HashMap<SensorId, CellIndex>,
    /// The visited cells' ids as given.
    labels: Vec<String>,
    /// The collection time.
    at: UnixSeconds,
}

impl Flown {
    /// The request's visited cells (else the planned stops), checked against the grid and
    /// the mission's stops.
    fn of<S: Store>(
        project: &Project<S>,
        request: &RecordRequest,
        mission: &MissionRecord,
        at: UnixSeconds,
    ) -> Result<Self> {
        let stops = &mission.mission.stops;
        let planned_labels: Vec<String> = stops.iter().map(|s| s.cell.to_string()).collect();
        let labels: Vec<String> = match &request.cells {
            Some(c) => c.clone(),
            None => planned_labels.clone(),
        };
        let cells = project.store().cells()?;
        let mut visits = Vec::new();
        let mut collected: Vec<(SensorId, UnixSeconds)> = Vec::new();
        let mut cell_of: HashMap<SensorId, CellIndex> = HashMap::new();
        for cell in &cells {
            for s in &cell.sensors {
                cell_of.insert(s.clone(), cell.index);
            }
        }
        let planned: HashSet<CellIndex> = stops.iter().map(|s| s.cell).collect();
        if labels.is_empty() {
            return Err(AppError::Invalid(
                "no cell visited: list the cells the flight visited".into(),
            ));
        }
        let mut seen = HashSet::new();
        for (order, label) in labels.iter().enumerate() {
            let index = CellIndex::parse(label.trim()).ok_or_else(|| {
                AppError::Invalid(format!(
                    "cell {label:?}: expected a cell id like x3y-1 (see `gleaner cells`)"
                ))
            })?;
            let cell =
                cells
                    .iter()
                    .find(|c| c.index == index)
                    .ok_or_else(|| AppError::NotFound {
                        what: "cell",
                        id: format!("{label} in the project's grid"),
                    })?;
            if !seen.insert(index) {
                return Err(AppError::Invalid(format!("cell {label} is listed twice")));
            }
            if !planned.contains(&index) {
                return Err(AppError::Invalid(format!(
                    "cell {label} is not a stop of mission #{} (its stops: {}); nothing was recorded",
                    request.mission,
                    planned_labels.join(",")
                )));
            }
            collected.extend(cell.sensors.iter().map(|s| (s.clone(), at)));
            visits.push(VisitRecord {
                order: order as u32,
                cell: index,
                arrived_at: Some(at),
                energy_j: None,
            });
        }
        Ok(Self {
            visits,
            collected,
            cell_of,
            labels,
            at,
        })
    }

    /// Refuses a reading brought back from a sensor outside the visited cells, or dated
    /// after the collection.
    fn check_brought_back(&self, parsed: &Parsed) -> Result<()> {
        let visited: HashSet<&SensorId> = self.collected.iter().map(|(s, _)| s).collect();
        for (path, _, readings, _) in &parsed.files {
            for row in &readings.rows {
                let Some(sensor) = readings.sensors.get(row.sensor as usize) else {
                    continue;
                };
                if !visited.contains(sensor) {
                    return Err(AppError::Invalid(format!(
                        "{}: sensor {sensor} is in cell {}, which this flight did not visit \
                             (visited: {}); nothing was recorded",
                        path.display(),
                        self.cell_of
                            .get(sensor)
                            .map_or("?".into(), ToString::to_string),
                        self.labels.join(",")
                    )));
                }
                if row.t > self.at {
                    return Err(AppError::Invalid(format!(
                        "{}: reading of {sensor} at {} is after the collection time {}; \
                             nothing was recorded",
                        path.display(),
                        format_rfc3339(row.t),
                        format_rfc3339(self.at)
                    )));
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plan::{PlanRequest, plan};
    use gleaner_store::StoreRead;

    const DAY: UnixSeconds = 86_400;

    /// A synthetic farm with every reading ingested and one mission planned 30 days in.
    fn farm_with_a_mission() -> (crate::test_farm::SynthProject, MissionId, UnixSeconds) {
        let mut p = crate::test_farm::ingested_synth_project(&gleaner_synth::SynthConfig {
            seed: 3,
            sensor_count: 12,
            days: 40,
            vw_depths_cm: vec![30],
            t_depths_cm: vec![],
            ..gleaner_synth::SynthConfig::default()
        });
        let at = p.farm.times()[0] + 30 * DAY;
        let planned = plan(
            &mut p.project,
            &PlanRequest {
                at: Some(at),
                max_iterations: Some(50),
                ..Default::default()
            },
            UnixSeconds::MAX / 4,
        )
        .unwrap();
        let id = planned.id.expect("stored");
        assert!(!planned.mission.stops.is_empty());
        (p, id, at)
    }

    fn record(
        p: &mut crate::test_farm::SynthProject,
        mission: MissionId,
        at: Option<UnixSeconds>,
        cells: Option<Vec<String>>,
    ) -> Result<RecordOutcome> {
        record_flight(
            &mut p.project,
            &RecordRequest {
                mission,
                at,
                cells,
                readings: None,
                amend: false,
            },
            UnixSeconds::MAX / 4,
            &crate::Silent,
        )
    }

    fn still_planned(p: &crate::test_farm::SynthProject, mission: MissionId) -> bool {
        let m = p.project.store().mission(mission).unwrap().unwrap();
        m.status == MissionStatus::Planned
    }

    #[test]
    fn a_cell_of_the_grid_that_is_not_a_stop_is_refused_and_nothing_recorded() {
        let (mut p, id, _) = farm_with_a_mission();
        let stops: HashSet<CellIndex> = p
            .project
            .store()
            .mission(id)
            .unwrap()
            .unwrap()
            .mission
            .stops
            .iter()
            .map(|s| s.cell)
            .collect();
        let other = p
            .project
            .store()
            .cells()
            .unwrap()
            .into_iter()
            .find(|c| !stops.contains(&c.index))
            .expect("a cell the mission does not visit")
            .index;
        let err = record(&mut p, id, None, Some(vec![other.to_string()])).unwrap_err();
        assert!(matches!(err, AppError::Invalid(_)), "{err:?}");
        assert!(
            err.to_string().contains("is not a stop of mission"),
            "{err}"
        );
        assert!(still_planned(&p, id));
    }

    #[test]
    fn implausible_collection_times_are_refused_and_nothing_recorded() {
        let (mut p, id, planned_at) = farm_with_a_mission();
        // 0001-01-01, 9999-12-31, and a day before the mission was planned.
        for at in [-62_135_596_800, 253_402_214_400, planned_at - DAY] {
            let err = record(&mut p, id, Some(at), None).unwrap_err();
            assert!(matches!(err, AppError::Invalid(_)), "{at}: {err:?}");
            assert!(still_planned(&p, id), "{at} recorded");
        }
        let ok = record(&mut p, id, Some(planned_at + 3600), None).unwrap();
        assert_eq!(ok.at, planned_at + 3600);
        assert!(!still_planned(&p, id));
    }
}
