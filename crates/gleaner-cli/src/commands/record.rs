//! `gleaner record`: a flown mission comes back — the cells actually visited, the time, and the
//! readings brought home — and updates the metadata (SPEC §5 step 5).

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use gleaner_field::{CellIndex, SensorId, UnixSeconds};
use gleaner_store::{MissionId, RefreshParams, Store, VisitRecord};

use crate::commands::ingest::{self, IngestArgs};
use crate::project::Project;

/// Settings from the command line.
pub struct RecordArgs {
    /// The planned mission.
    pub mission: i64,
    /// When the data was collected, seconds [default: the mission's planned time].
    pub at: Option<UnixSeconds>,
    /// Cells actually visited, in order [default: the planned stops].
    pub cells: Option<Vec<String>>,
    /// Readings files brought back (ingested like `gleaner ingest`).
    pub files: Vec<PathBuf>,
    /// Ingest settings for `files`.
    pub ingest: Option<IngestArgs>,
}

/// Records the flight; returns a summary line.
pub fn run(project: &mut Project, args: &RecordArgs) -> Result<String> {
    let missions = project.store.missions()?;
    let Some(mission) = missions.iter().find(|m| m.id.0 == args.mission) else {
        bail!("no mission #{} (see `gleaner plan`)", args.mission);
    };
    let at = args.at.unwrap_or(mission.mission.planned_at);
    let labels: Vec<String> = match &args.cells {
        Some(c) => c.clone(),
        None => {
            let summary: serde_json::Value = serde_json::from_str(&mission.mission.summary_json)
                .with_context(|| format!("mission #{}: unreadable summary", args.mission))?;
            summary["stops"]
                .as_array()
                .map(|stops| {
                    stops
                        .iter()
                        .filter_map(|s| s["cell"].as_str().map(str::to_string))
                        .collect()
                })
                .unwrap_or_default()
        }
    };
    let cells = project.store.cells()?;
    let mut visits = Vec::new();
    let mut collected: Vec<(SensorId, UnixSeconds)> = Vec::new();
    for (order, label) in labels.iter().enumerate() {
        let index =
            CellIndex::parse(label).with_context(|| format!("invalid cell id {label:?}"))?;
        let cell = cells
            .iter()
            .find(|c| c.index == index)
            .with_context(|| format!("cell {label} is not in the project's grid"))?;
        collected.extend(cell.sensors.iter().map(|s| (s.clone(), at)));
        visits.push(VisitRecord {
            order: order as u32,
            cell: index,
            arrived_at: Some(at),
            energy_j: None,
        });
    }
    if let Some(ingest_args) = &args.ingest
        && !args.files.is_empty()
    {
        ingest::run(project, ingest_args)?;
    }
    project.store.set_sensors_collected(&collected)?;
    project
        .store
        .record_visits(MissionId(args.mission), &visits)?;
    project.store.refresh_cell_summaries(&RefreshParams {
        now: at,
        bytes_per_reading: project.config.ingest.bytes_per_reading,
        default_interval_s: project.config.ingest.default_interval_s,
        // Readings brought back were summarised by the ingest above; collection times only
        // change last collection and pending volume.
        changed_sensors: Some(Vec::new()),
    })?;
    Ok(format!(
        "mission #{} recorded as flown at {}: {} cells, {} sensors collected",
        args.mission,
        gleaner_ingest::time::format_rfc3339(at),
        visits.len(),
        collected.len()
    ))
}
