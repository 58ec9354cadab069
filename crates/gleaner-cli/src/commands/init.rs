//! `gleaner init`: a new project from a sensors file.

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use gleaner_field::{
    Field, LatLon, LocalPoint, Sensor, TransverseMercator, cell_size_from_half_angle,
};
use gleaner_ingest::{SensorsOptions, read_hubbard_brook_sensors, read_sensors_csv};
use gleaner_store::{CellRecord, SensorRecord, SqliteStore, Store};

use crate::config::{
    CONFIG_FILE, FieldSection, IngestSection, ProjectFile, ProjectSection, SensorsSection,
    parse_utm_zone,
};

/// Settings for a new project, as parsed from the command line.
pub struct InitArgs {
    /// Project directory (created if missing).
    pub dir: PathBuf,
    /// Sensors file.
    pub sensors: PathBuf,
    /// UTM zone for easting/northing input, e.g. `11N`.
    pub utm_zone: Option<String>,
    /// The sensors file is Hubbard Brook's `sensor_metadata.csv` (one sensor per probe).
    pub hubbard_brook: bool,
    /// Base station `(lat, lon)`, degrees; default: the middle of the sensors' southern edge.
    pub base: Option<(f64, f64)>,
    /// Cell side, metres.
    pub cell_size_m: Option<f64>,
    /// UAV altitude, metres, and antenna half-angle, degrees, to derive the cell side.
    pub coverage: Option<(f64, f64)>,
    /// Project name.
    pub name: Option<String>,
    /// Overwrite an existing project file (the database is kept and updated).
    pub force: bool,
}

/// Default cell side, metres: the paper scenario's 40 m cells.
pub const DEFAULT_CELL_SIZE_M: f64 = 40.0;

/// Creates the project; returns a one-paragraph summary.
pub fn run(args: &InitArgs) -> Result<String> {
    let config_path = args.dir.join(CONFIG_FILE);
    if config_path.exists() && !args.force {
        bail!(
            "{}: a project already exists here (use --force to overwrite its settings)",
            config_path.display()
        );
    }
    std::fs::create_dir_all(&args.dir)
        .with_context(|| format!("{}: cannot create", args.dir.display()))?;
    let utm = args.utm_zone.as_deref().map(parse_utm_zone).transpose()?;
    let (inputs, _) = if args.hubbard_brook {
        read_hubbard_brook_sensors(&args.sensors)?
    } else {
        read_sensors_csv(
            &args.sensors,
            &SensorsOptions {
                utm,
                ..Default::default()
            },
        )?
    };
    if inputs.is_empty() {
        bail!("{}: no sensors", args.sensors.display());
    }
    let sensors: Vec<Sensor> = inputs.into_iter().map(|s| s.sensor).collect();
    let base = match args.base {
        Some((lat, lon)) => LatLon::new(lat, lon).context("--base")?,
        None => default_base(&sensors),
    };
    let cell_size_m = match (args.cell_size_m, args.coverage) {
        (Some(_), Some(_)) => {
            bail!("give either --cell-size or --altitude with --half-angle, not both")
        }
        (Some(s), None) => s,
        (None, Some((h, a))) => cell_size_from_half_angle(h, a)?,
        (None, None) => DEFAULT_CELL_SIZE_M,
    };
    let name = args.name.clone().unwrap_or_else(|| {
        args.dir
            .canonicalize()
            .ok()
            .and_then(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
            .unwrap_or_else(|| "gleaner".into())
    });
    let file = ProjectFile {
        project: ProjectSection {
            name,
            database: PathBuf::from("gleaner.db"),
        },
        field: FieldSection {
            base_lat: base.lat(),
            base_lon: base.lon(),
            base_alt_m: 0.0,
            cell_size_m,
            neighbour_k: 3,
            neighbour_radius_m: 200.0,
        },
        sensors: SensorsSection {
            file: args.sensors.display().to_string(),
            utm_zone: args.utm_zone.clone(),
        },
        ingest: IngestSection::default(),
        utility: Default::default(),
        energy: Default::default(),
        planner: Default::default(),
    };
    let field = Field::build(&sensors, base, &file.field_config())?;
    let mut store = SqliteStore::open(&args.dir.join(&file.project.database))?;
    let source = args
        .sensors
        .file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
    let records: Vec<SensorRecord> = sensors
        .iter()
        .map(|s| SensorRecord {
            id: s.id.clone(),
            position: s.position,
            elevation_m: s.elevation_m,
            source: source.clone(),
        })
        .collect();
    let upsert = store.upsert_sensors(&records)?;
    let replaced = store.replace_cells(&cell_records(&sensors, &field))?;
    file.save(&args.dir)?;
    Ok(format!(
        "project {} in {}\n  sensors: {} ({} new, {} updated)\n  base station: {:.6}, {:.6}\n  cells: {} non-empty cells of {} m ({} kept, {} added, {} removed)",
        file.project.name,
        args.dir.display(),
        sensors.len(),
        upsert.added.len(),
        upsert.updated.len(),
        base.lat(),
        base.lon(),
        field.cells().len(),
        cell_size_m,
        replaced.kept,
        replaced.added,
        replaced.removed,
    ))
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

/// The default base station: the middle of the southern edge of the sensors' bounding box
/// (operators usually launch from the field's edge), in a local frame at the first sensor.
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
