//! Creating a project from a sensors file: settings, database, sensors and the cell grid.

use std::path::{Component, Path, PathBuf};

use gleaner_field::{
    Field, LatLon, LocalPoint, Sensor, TransverseMercator, cell_size_from_half_angle,
};
use gleaner_ingest::{
    SensorsOptions, hubbard_brook_main_water_depth, read_hubbard_brook_sensors, read_sensors_csv,
};
use gleaner_store::{
    AnyStore, CellRecord, ReplaceCellsStats, SensorRecord, Store, StoreRead, StoreWrite,
    UpsertStats,
};

use gleaner_scoring::Project;
use gleaner_scoring::settings::{
    CONFIG_FILE, FieldSection, IngestSection, ProjectSection, SensorsSection, Settings,
    parse_utm_zone,
};
use gleaner_scoring::{AppError, Result};

/// Default cell side, metres: the paper scenario's 40 m cells.
pub const DEFAULT_CELL_SIZE_M: f64 = 40.0;

/// A new project.
#[derive(Debug, Clone, Default)]
pub struct InitRequest {
    /// Project directory (created if missing).
    pub dir: PathBuf,
    /// Sensors file.
    pub sensors: PathBuf,
    /// UTM zone for easting/northing input, e.g. `11N`.
    pub utm_zone: Option<String>,
    /// The sensors file is Hubbard Brook's `sensor_metadata.csv` (one sensor per probe).
    pub hubbard_brook: bool,
    /// Base station, WGS84 [default: 10 m south of the middle of the sensors' southern edge].
    pub base: Option<LatLon>,
    /// Base altitude above mean sea level, m [default 0].
    pub base_alt_m: Option<f64>,
    /// Cell side, metres [default 40].
    pub cell_size_m: Option<f64>,
    /// Neighbour fallback radius, metres (`[field] neighbour_radius_m`: a cell with no
    /// non-empty adjacent cell takes its `neighbour_k` nearest non-empty cells within it as
    /// neighbours), at most 100 cell sides [default: 200 m, or 100 cell sides when the cells
    /// are smaller than 2 m].
    pub neighbour_radius_m: Option<f64>,
    /// UAV altitude (m) and antenna half-angle (degrees) to derive the cell side.
    pub coverage: Option<(f64, f64)>,
    /// Project name [default: the directory's name].
    pub name: Option<String>,
    /// Overwrite an existing project file (its database is kept and updated).
    pub force: bool,
    /// Where to keep the data: an SQLite file relative to the project directory, or a
    /// `postgres://...[#project]` URL [default: `gleaner.db`].
    pub database: Option<String>,
    /// Write gleaner's method as the project's `[utility]` (the gated score with each sensor's
    /// drift as F and the bounded anomaly, [`gleaner_scoring::settings::UtilitySection::gleaner`])
    /// instead of the paper's S (docs/method.md §2, the default).
    pub gleaner_method: bool,
    /// GeoJSON file of the geofence (`[field] geofence`): the polygons the flight stays inside.
    pub geofence: Option<PathBuf>,
    /// GeoJSON file of the no-fly zones (`[field] no_fly`).
    pub no_fly: Option<PathBuf>,
    /// Safety buffer around the no-fly zones and inside the geofence, m [default 5].
    pub no_fly_buffer_m: Option<f64>,
}

/// What `init` did.
#[derive(Debug, Clone)]
pub struct InitOutcome {
    /// The settings written.
    pub settings: Settings,
    /// Sensors read.
    pub sensors: usize,
    /// Sensor upsert counts.
    pub upsert: UpsertStats,
    /// Grid replacement counts.
    pub cells: ReplaceCellsStats,
    /// Number of non-empty cells.
    pub n_cells: usize,
}

/// The use case, on the backend `request.database` names (an SQLite file in the project
/// directory by default).
pub fn init(request: &InitRequest) -> Result<(Project<AnyStore>, InitOutcome)> {
    let config_path = request.dir.join(CONFIG_FILE);
    if config_path.exists() && !request.force {
        return Err(AppError::Invalid(format!(
            "{}: a project already exists here (use --force to overwrite its settings)",
            config_path.display()
        )));
    }
    // Read and check everything before creating anything: a refused init leaves no trace.
    let settings = settings_for(request)?;
    let created_dir = !request.dir.exists();
    let database = gleaner_scoring::database(&request.dir, &settings, None)?;
    let db_path = match &database {
        gleaner_store::Database::Sqlite(path) => Some(path.clone()),
        gleaner_store::Database::Postgres { .. } => None,
    };
    let created_db = db_path.as_ref().is_some_and(|p| !p.exists());
    let result = (|| {
        std::fs::create_dir_all(&request.dir).map_err(|e| AppError::io(&request.dir, e))?;
        let store = database.open()?;
        let mut project = Project::new(&request.dir, settings, store);
        let outcome = init_store(&mut project, request)?;
        outcome.settings.save(&request.dir)?;
        Ok((project, outcome))
    })();
    if result.is_err() {
        // Best effort: remove only what this call created (the error is what matters). A
        // PostgreSQL schema is kept: it holds at most empty tables, which a rerun reuses.
        if created_dir {
            let _ = std::fs::remove_dir_all(&request.dir);
        } else if let (true, Some(db_path)) = (created_db, &db_path) {
            for suffix in ["", "-wal", "-shm", "-lock"] {
                let mut p = db_path.clone().into_os_string();
                p.push(suffix);
                let _ = std::fs::remove_file(p);
            }
        }
    }
    result
}

/// The settings for a new project (reads the sensors file to place the base).
fn settings_for(request: &InitRequest) -> Result<Settings> {
    let sensors = read_sensors(request)?;
    let base = match request.base {
        Some(b) => b,
        None => default_base(&sensors),
    };
    let cell_size_m = match (request.cell_size_m, request.coverage) {
        (Some(_), Some(_)) => {
            return Err(AppError::Invalid(
                "give either a cell size or an altitude with a half-angle, not both".into(),
            ));
        }
        (Some(s), None) => s,
        (None, Some((h, a))) => {
            cell_size_from_half_angle(h, a).map_err(|e| AppError::core("cell size", e))?
        }
        (None, None) => DEFAULT_CELL_SIZE_M,
    };
    let name = request.name.clone().unwrap_or_else(|| {
        request
            .dir
            .canonicalize()
            .ok()
            .or_else(|| std::path::absolute(&request.dir).ok())
            .and_then(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
            .unwrap_or_else(|| "gleaner".into())
    });
    let defaults = gleaner_field::FieldConfig::default();
    // Hubbard Brook's probes sit at many depths, few at 30 cm: its condition (and evaluated)
    // modality is the soil moisture at the depth most of its water-content probes share.
    let mut utility = gleaner_scoring::settings::UtilitySection::default();
    if request.hubbard_brook {
        utility.condition_modality =
            hubbard_brook_main_water_depth(&request.sensors)?.map(|depth| format!("vw@{depth}cm"));
    }
    if request.gleaner_method {
        utility = utility.gleaner();
    }
    let settings = Settings {
        project: ProjectSection {
            name,
            database: PathBuf::from(request.database.as_deref().unwrap_or("gleaner.db")),
        },
        field: FieldSection {
            base_lat: base.lat(),
            base_lon: base.lon(),
            base_alt_m: request.base_alt_m.unwrap_or(0.0),
            cell_size_m,
            neighbour_k: defaults.fallback_k,
            neighbour_radius_m: request.neighbour_radius_m.unwrap_or(
                // The default radius, within the 100 cell sides allowed for small cells.
                defaults
                    .fallback_radius_m
                    .min(gleaner_scoring::settings::MAX_RADIUS_CELLS * cell_size_m),
            ),
            geofence: request
                .geofence
                .as_ref()
                .map(|p| relative_to(p, &request.dir)),
            no_fly: request
                .no_fly
                .as_ref()
                .map(|p| relative_to(p, &request.dir)),
            no_fly_buffer_m: request
                .no_fly_buffer_m
                .unwrap_or(gleaner_scoring::settings::DEFAULT_NO_FLY_BUFFER_M),
        },
        sensors: SensorsSection {
            file: relative_to(&request.sensors, &request.dir),
            utm_zone: request.utm_zone.clone(),
        },
        ingest: IngestSection::default(),
        utility,
        energy: Default::default(),
        planner: Default::default(),
        flight: Default::default(),
    };
    settings.validate()?;
    check_grid_size(&sensors, base, &settings)?;
    // The zone files are read now (as given, relative to the working directory: the
    // project directory may not exist yet), so a bad one is refused before anything is
    // created.
    let given = FieldSection {
        geofence: request.geofence.as_ref().map(|p| p.display().to_string()),
        no_fly: request.no_fly.as_ref().map(|p| p.display().to_string()),
        ..settings.field.clone()
    };
    crate::airspace::load(&given, Path::new("."), &TransverseMercator::local(base))?;
    Ok(settings)
}

/// Refuses grids so fine that building them would take minutes (the neighbour search grows
/// with (radius / cell side)^2 per cell): at most 1e6 cells' worth of extent.
fn check_grid_size(sensors: &[Sensor], base: LatLon, settings: &Settings) -> Result<()> {
    let frame = TransverseMercator::local(base);
    let (mut e0, mut e1, mut n0, mut n1) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for s in sensors {
        let p = frame.forward(s.position);
        e0 = e0.min(p.e);
        e1 = e1.max(p.e);
        n0 = n0.min(p.n);
        n1 = n1.max(p.n);
    }
    let side = settings.field.cell_size_m;
    let extent_cells = ((e1 - e0) / side + 1.0) * ((n1 - n0) / side + 1.0);
    let reach = (settings.field.neighbour_radius_m / side).powi(2);
    if extent_cells > 1e8 || reach * sensors.len() as f64 > 1e8 {
        return Err(AppError::Invalid(format!(
            "cell side {} m over sensors spread {:.0} m x {:.0} m (neighbour radius {} m) \
             makes a grid too large to build; use larger cells",
            gleaner_ingest::number(side),
            e1 - e0,
            n1 - n0,
            gleaner_ingest::number(settings.field.neighbour_radius_m)
        )));
    }
    Ok(())
}

fn read_sensors(request: &InitRequest) -> Result<Vec<Sensor>> {
    if request.hubbard_brook {
        let (inputs, _) = read_hubbard_brook_sensors(&request.sensors)?;
        return non_empty(
            &request.sensors,
            inputs.into_iter().map(|s| s.sensor).collect(),
        );
    }
    read_sensors_file(&request.sensors, request.utm_zone.as_deref())
}

/// The stations of a sensors file (CSV or tab-separated: id and WGS84 latitude/longitude,
/// or UTM easting/northing in m with `utm_zone`, e.g. `11N`), as `init` reads it; at least
/// one. Errors name the file, line and field.
pub fn read_sensors_file(path: &Path, utm_zone: Option<&str>) -> Result<Vec<Sensor>> {
    let utm = utm_zone.map(parse_utm_zone).transpose()?;
    let (inputs, _) = read_sensors_csv(
        path,
        &SensorsOptions {
            utm,
            ..Default::default()
        },
    )?;
    non_empty(path, inputs.into_iter().map(|s| s.sensor).collect())
}

fn non_empty(path: &Path, sensors: Vec<Sensor>) -> Result<Vec<Sensor>> {
    if sensors.is_empty() {
        return Err(AppError::Invalid(format!("{}: no sensors", path.display())));
    }
    Ok(sensors)
}

/// Writes the sensors and the grid into the project's store, in one transaction.
pub fn init_store<S: Store>(
    project: &mut Project<S>,
    request: &InitRequest,
) -> Result<InitOutcome> {
    let sensors = read_sensors(request)?;
    let source = request
        .sensors
        .file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
    init_store_with(project, &sensors, &source)
}

/// [`init_store`] with the sensors already read (e.g. another project's own), `source` the
/// provenance stored with each.
pub fn init_store_with<S: Store>(
    project: &mut Project<S>,
    sensors: &[Sensor],
    source: &str,
) -> Result<InitOutcome> {
    if sensors.is_empty() {
        return Err(AppError::Invalid("no sensors".into()));
    }
    let settings = project.settings().clone();
    let field = Field::build(sensors, settings.base()?, &settings.field_config())
        .map_err(|e| AppError::core("cell grid", e))?;
    let records: Vec<SensorRecord> = sensors
        .iter()
        .map(|s| SensorRecord {
            id: s.id.clone(),
            position: s.position,
            elevation_m: s.elevation_m,
            source: source.to_string(),
        })
        .collect();
    let cells = cell_records(sensors, &field);
    let (upsert, replaced) = project.store_mut().write(|tx| {
        let upsert = tx.upsert_sensors(&records)?;
        let replaced = tx.replace_cells(&cells)?;
        if replaced.added > 0 && tx.reading_count()? > 0 {
            // A re-grid of a project with readings: the new cells are described at once (their
            // summaries, last collections and pending volumes at the newest reading, as an
            // ingest describes them), not only after a scoring.
            let now = latest_reading(&*tx)?;
            let ids: Vec<gleaner_field::SensorId> = sensors.iter().map(|s| s.id.clone()).collect();
            gleaner_scoring::summaries::refresh_cells(tx, &ids, now, &settings)?;
            gleaner_scoring::summaries::invalidate_cache(tx)?;
        }
        Ok::<_, AppError>((upsert, replaced))
    })?;
    Ok(InitOutcome {
        settings,
        sensors: sensors.len(),
        upsert,
        cells: replaced,
        n_cells: field.cells().len(),
    })
}

/// The newest stored reading's time, s (0 without readings).
fn latest_reading<R: gleaner_store::StoreRead>(store: &R) -> Result<gleaner_field::UnixSeconds> {
    Ok(store
        .readings_for(
            None,
            gleaner_field::UnixSeconds::MIN..=gleaner_field::UnixSeconds::MAX,
        )?
        .rows
        .iter()
        .map(|r| r.t)
        .max()
        .unwrap_or(0))
}

/// The store's view of the field's cells.
pub fn cell_records(sensors: &[Sensor], field: &Field) -> Vec<CellRecord> {
    field
        .cells()
        .iter()
        .map(|c| CellRecord {
            index: c.index,
            centre: field.frame().inverse(c.centre),
            cell_size_m: field.cell_size_m(),
            sensors: c.sensors.iter().map(|&k| sensors[k].id.clone()).collect(),
        })
        .collect()
}

/// The default base station: 10 m south of the middle of the southern edge of the sensors'
/// bounding box (operators usually launch from the field's edge).
fn default_base(sensors: &[Sensor]) -> LatLon {
    let frame = TransverseMercator::local(sensors[0].position);
    let pts: Vec<LocalPoint> = sensors.iter().map(|s| frame.forward(s.position)).collect();
    let (mut e0, mut e1, mut n0) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY);
    for p in &pts {
        e0 = e0.min(p.e);
        e1 = e1.max(p.e);
        n0 = n0.min(p.n);
    }
    frame.inverse(LocalPoint::new((e0 + e1) / 2.0, n0 - 10.0))
}

/// `path` relative to `dir` (both made absolute), so the project file stays valid wherever
/// the project is opened from; absolute when they share no ancestor.
pub fn relative_to(path: &Path, dir: &Path) -> String {
    let abs = |p: &Path| -> PathBuf {
        let p = p.canonicalize().unwrap_or_else(|_| {
            std::env::current_dir()
                .map(|c| c.join(p))
                .unwrap_or_else(|_| p.to_path_buf())
        });
        p.components().collect()
    };
    let (path, dir) = (abs(path), abs(dir));
    let a: Vec<Component<'_>> = path.components().collect();
    let b: Vec<Component<'_>> = dir.components().collect();
    let common = a.iter().zip(&b).take_while(|(x, y)| x == y).count();
    if common <= 1 {
        return path.display().to_string();
    }
    let mut rel = PathBuf::new();
    for _ in common..b.len() {
        rel.push("..");
    }
    for c in &a[common..] {
        rel.push(c.as_os_str());
    }
    rel.display().to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sensors_path_is_kept_relative_to_the_project() {
        let tmp = tempfile::tempdir().unwrap();
        let data = tmp.path().join("data");
        let project = tmp.path().join("farms").join("north");
        std::fs::create_dir_all(&data).unwrap();
        std::fs::create_dir_all(&project).unwrap();
        let sensors = data.join("sensors.csv");
        std::fs::write(&sensors, "id,lat,lon\n").unwrap();
        let rel = relative_to(&sensors, &project);
        assert_eq!(rel, "../../data/sensors.csv");
        assert!(project.join(&rel).exists());
    }
}
