//! Copying a project's data between stores (SQLite file <-> PostgreSQL project), losslessly:
//! every row the [`StoreRead`] interface can see arrives unchanged, mission ids included.

use std::path::PathBuf;

use gleaner_store::{ConflictPolicy, StoreError};

use crate::progress::Progress;
use crate::{Store, StoreRead, StoreWrite};
use gleaner_scoring::{AppError, Project, Result, database};

/// What a copy moved.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct MigrateOutcome {
    /// Sensors copied.
    pub sensors: usize,
    /// Modalities copied.
    pub modalities: usize,
    /// Readings copied.
    pub readings: u64,
    /// Ingest provenance records copied.
    pub ingests: usize,
    /// Cells copied (with their metadata).
    pub cells: usize,
    /// Missions copied (with stops and visits).
    pub missions: usize,
    /// Settings and opaque values (e.g. the persisted utility state) copied.
    pub config_and_blobs: usize,
}

/// What [`migrate_project`] copies from where to where.
#[derive(Debug, Clone, Default)]
pub struct MigrateProjectRequest {
    /// The project directory.
    pub dir: PathBuf,
    /// The source database instead of the project's `database` setting (an SQLite file
    /// relative to `dir`, or a `postgres://` URL).
    pub database: Option<String>,
    /// The target database, as `database`; it must be empty (it is created when missing).
    pub to: String,
    /// Afterwards, point the project's `database` setting at the target.
    pub switch: bool,
}

/// A project's data copied into another database.
#[derive(Debug, Clone)]
pub struct ProjectMigration {
    /// What was copied.
    pub outcome: MigrateOutcome,
    /// The source database, as text (no password).
    pub from: String,
    /// The target database, as text (no password).
    pub to: String,
    /// Whether the project's `database` setting now names the target.
    pub switched: bool,
}

/// Copies the project in `r.dir` from its database (or `r.database`) into `r.to` with
/// [`migrate`]; with `r.switch` the project's settings then name the target. A target that is
/// the source itself is refused.
pub fn migrate_project(
    r: &MigrateProjectRequest,
    progress: &dyn Progress,
) -> Result<ProjectMigration> {
    let source = Project::open_with(&r.dir, r.database.as_deref())?;
    let mut settings = source.settings().clone();
    let target = database(&r.dir, &settings, Some(&r.to))?;
    let from = database(&r.dir, &settings, r.database.as_deref())?;
    if target == from {
        return Err(AppError::Invalid(format!(
            "the target {target} is the project's own database"
        )));
    }
    let mut store = target
        .open()
        .map_err(|e| AppError::Invalid(format!("opening the target {target}: {e}")))?;
    let outcome = migrate(source.store(), &mut store, progress)?;
    if r.switch {
        settings.project.database = PathBuf::from(&r.to);
        settings.save(&r.dir)?;
    }
    Ok(ProjectMigration {
        outcome,
        from: from.to_string(),
        to: target.to_string(),
        switched: r.switch,
    })
}

/// Copies everything in `from` into `to`, which must be empty (no sensors, readings or
/// missions), in one transaction of `to`: a failure (or a crash) leaves `to` empty.
///
/// Every table goes through the store interface, so the copy works between any two backends;
/// mission ids are kept ([`StoreWrite::import_mission`]), and the persisted utility state is
/// an opaque blob copied byte for byte.
pub fn migrate<F: StoreRead, T: Store>(
    from: &F,
    to: &mut T,
    progress: &dyn Progress,
) -> Result<MigrateOutcome> {
    if !to.sensors()?.is_empty() || to.reading_count()? != 0 || !to.missions()?.is_empty() {
        return Err(AppError::Invalid(
            "the target database already holds a project (sensors, readings or missions); \
             copy into an empty one"
                .into(),
        ));
    }
    progress.start("reading the source project", None);
    let sensors = from.sensors()?;
    let modalities = from.modalities()?;
    let readings = from.readings_for(None, i64::MIN..=i64::MAX)?;
    let ingests = from.ingests()?;
    let cells = from.cells()?;
    let metadata = from.cell_metadata()?;
    let collected = from.sensor_last_collected()?;
    let missions = from.missions()?;
    let config = from.config_entries()?;
    let mut blobs = Vec::new();
    for key in from.blob_keys()? {
        let value = from
            .blob_get(&key)?
            .ok_or_else(|| AppError::Invalid(format!("blob {key:?} vanished while copying")))?;
        blobs.push((key, value));
    }
    progress.finish();
    progress.start(&format!("writing {} readings", readings.len()), None);
    let outcome = to.write(|tx| -> Result<MigrateOutcome> {
        tx.upsert_sensors(&sensors)?;
        tx.upsert_modalities(&modalities)?;
        let stats = tx.insert_readings(&readings, ConflictPolicy::Fail)?;
        for i in &ingests {
            tx.record_ingest(i)?;
        }
        tx.replace_cells(&cells)?;
        // Metadata of cells never described is empty on both sides: skip it.
        let described: Vec<_> = metadata
            .iter()
            .filter(|m| **m != gleaner_store::CellMetadata::new(m.cell))
            .cloned()
            .collect();
        tx.upsert_cell_metadata(&described)?;
        tx.set_sensors_collected(&collected)?;
        for m in &missions {
            tx.import_mission(m)?;
        }
        for (k, v) in &config {
            tx.config_set(k, v)?;
        }
        for (k, v) in &blobs {
            tx.blob_put(k, v)?;
        }
        Ok(MigrateOutcome {
            sensors: sensors.len(),
            modalities: modalities.len(),
            readings: stats.inserted,
            ingests: ingests.len(),
            cells: cells.len(),
            missions: missions.len(),
            config_and_blobs: config.len() + blobs.len(),
        })
    })?;
    progress.finish();
    if outcome.readings != readings.len() as u64 {
        return Err(AppError::Store(StoreError::Invalid {
            what: "copy",
            detail: format!(
                "{} of {} readings written",
                outcome.readings,
                readings.len()
            ),
        }));
    }
    Ok(outcome)
}
