//! Read models: the cell table, the field for maps, missions, and a mission ready to export.

use std::collections::HashMap;

use gleaner_energy::FlightEnergyModel;
use gleaner_field::{CellId, CellIndex, LatLon, SensorId};
use gleaner_store::{CellMetadata, MissionId, MissionRecord, Store};

use gleaner_scoring::Project;
use gleaner_scoring::{AppError, Result};

/// One cell with its metadata (docs/method.md §5).
#[derive(Debug, Clone, PartialEq)]
pub struct CellView {
    /// Grid index (`x12y-3`).
    pub index: CellIndex,
    /// Centre, WGS84.
    pub centre: LatLon,
    /// The square's corners, WGS84, counter-clockwise from south-west.
    pub corners: [LatLon; 4],
    /// Its sensors, sorted.
    pub sensors: Vec<SensorId>,
    /// Its metadata row (empty when never described).
    pub metadata: CellMetadata,
}

/// The field for maps and exports: grid, metadata, sensors, base.
#[derive(Debug, Clone, PartialEq)]
pub struct FieldView {
    /// Project name.
    pub project: String,
    /// Base station, WGS84.
    pub base: LatLon,
    /// Base altitude above mean sea level, m.
    pub base_alt_m: f64,
    /// Cell side, m.
    pub cell_size_m: f64,
    /// Cells, by grid index.
    pub cells: Vec<CellView>,
    /// Sensors with their positions, sorted by id.
    pub sensors: Vec<(SensorId, LatLon)>,
    /// The geofence and no-fly zones as the settings' files give them (empty without).
    pub zones: Vec<crate::airspace::ZoneView>,
    /// The safety buffer kept from the zones (`[field] no_fly_buffer_m`), m.
    pub zone_buffer_m: f64,
}

/// The cell table with its metadata, by grid index.
pub fn field_view<S: Store>(project: &Project<S>) -> Result<FieldView> {
    let (sensors, field) = project.field()?;
    let mut metadata: HashMap<CellIndex, CellMetadata> = project
        .store()
        .cell_metadata()?
        .into_iter()
        .map(|m| (m.cell, m))
        .collect();
    let frame = field.frame();
    let cells = field
        .cells()
        .iter()
        .enumerate()
        .map(|(k, c)| {
            let corners = field
                .cell_corners(CellId(k as u32))
                .map(|p| frame.inverse(p));
            let mut ids: Vec<SensorId> = c.sensors.iter().map(|&s| sensors[s].id.clone()).collect();
            ids.sort();
            CellView {
                index: c.index,
                centre: frame.inverse(c.centre),
                corners,
                sensors: ids,
                metadata: metadata
                    .remove(&c.index)
                    .unwrap_or_else(|| CellMetadata::new(c.index)),
            }
        })
        .collect();
    let settings = project.settings();
    Ok(FieldView {
        project: settings.project.name.clone(),
        base: settings.base()?,
        base_alt_m: settings.field.base_alt_m,
        cell_size_m: field.cell_size_m(),
        cells,
        sensors: sensors.into_iter().map(|s| (s.id, s.position)).collect(),
        zones: crate::airspace::of_project(project)?
            .map(|a| a.zones)
            .unwrap_or_default(),
        zone_buffer_m: settings.field.no_fly_buffer_m,
    })
}

/// The number of stored readings of each cell's sensors, every modality, by grid index (the
/// cell table's `readings`; a cell series' summary counts its points, which are means over
/// the cell's sensors). From the stored grid: true whatever has been scored.
pub fn cell_reading_counts<S: Store>(project: &Project<S>) -> Result<HashMap<CellIndex, u64>> {
    let per_sensor: HashMap<SensorId, u64> = project
        .store()
        .sensor_reading_counts()?
        .into_iter()
        .collect();
    Ok(project
        .store()
        .cells()?
        .into_iter()
        .map(|c| {
            let n = c.sensors.iter().filter_map(|s| per_sensor.get(s)).sum();
            (c.index, n)
        })
        .collect())
}

/// All missions with their stops and visits, oldest first.
pub fn missions<S: Store>(project: &Project<S>) -> Result<Vec<MissionRecord>> {
    Ok(project.store().missions()?)
}

/// One mission, or [`AppError::NotFound`].
pub fn mission<S: Store>(project: &Project<S>, id: MissionId) -> Result<MissionRecord> {
    project
        .store()
        .mission(id)?
        .ok_or_else(|| AppError::NotFound {
            what: "mission",
            id: format!("#{id}"),
        })
}

/// A stored mission and the turn points of its legs around the no-fly zones (WGS84; one list
/// per stop's leg, then the return leg's; empty without zones), for its map.
pub type RoutedMission = (MissionRecord, Vec<Vec<LatLon>>);

/// Every exploration sortie of the project, oldest first, with its turn points: the
/// exploration map's routes.
pub fn exploration_sorties<S: Store>(project: &Project<S>) -> Result<Vec<RoutedMission>> {
    Ok(missions(project)?
        .into_iter()
        .filter(|m| m.mission.kind == gleaner_store::MissionKind::Exploration)
        .map(|m| {
            let via = crate::airspace::stored_via(project, &m);
            (m, via)
        })
        .collect())
}

/// Writes `files` (name, bytes) into `dir`, created if missing: an adapter's file set of an
/// export (flight files, document, maps). Returns the paths written, in order.
pub fn write_files(
    dir: &std::path::Path,
    files: &[(&str, Vec<u8>)],
) -> Result<Vec<std::path::PathBuf>> {
    std::fs::create_dir_all(dir).map_err(|e| AppError::io(dir, format!("cannot create: {e}")))?;
    let mut written = Vec::with_capacity(files.len());
    for (name, bytes) in files {
        let path = dir.join(name);
        std::fs::write(&path, bytes)
            .map_err(|e| AppError::io(&path, format!("cannot write: {e}")))?;
        written.push(path);
    }
    Ok(written)
}

/// A mission with everything its files and maps need.
#[derive(Debug, Clone, PartialEq)]
pub struct MissionExport {
    /// The field, with the latest scores.
    pub field: FieldView,
    /// The mission.
    pub mission: MissionRecord,
    /// The energy model every flight-file writer prices the values it writes with (the
    /// project's aircraft, with the battery the mission was planned against).
    pub energy: FlightEnergyModel,
    /// The turn points of each leg around the no-fly zones (one list per stop, one for the
    /// return leg; WGS84 on the files' 1e-7° grid), recomputed from the zones as they are:
    /// the files fly them and the writers price them. Empty without zones.
    pub via: Vec<Vec<LatLon>>,
}

/// The use case behind every export: the mission and its field, checked safe to fly — the
/// planned energy within the budget it was planned against, a finite positive cruise speed,
/// an altitude in (0, 120] m, finite non-negative hover times — and the energy model the
/// writers recompute the commanded energy with ([`export_energy_model`]). A mission failing
/// any check is refused: no flight file is ever written for a route the battery cannot carry.
pub fn export<S: Store>(project: &Project<S>, id: MissionId) -> Result<MissionExport> {
    let mission = mission(project, id)?;
    crate::missions::refuse_cancelled(&mission, "exported")?;
    check_flyable(&mission)?;
    let energy = export_energy_model(project, &mission)?;
    let via = match crate::airspace::of_project(project)? {
        Some(a) => a.mission_via(&mission)?,
        None => Vec::new(),
    };
    Ok(MissionExport {
        field: field_view(project)?,
        mission,
        energy,
        via,
    })
}

/// The energy presets a mission may have been planned with (`plan --energy-preset`).
const ENERGY_PRESETS: [&str; 2] = ["paper", "large-pack"];

/// The energy model a mission's files are priced with: the project's `[energy]` settings as
/// they are now (the aircraft that will fly), with the battery the mission was planned
/// against — the settings' own preset, or the preset (`paper`, `large-pack`, fields set in
/// `[energy]` still overriding) whose usable budget (J) is the mission's — in the wind the
/// mission was planned in (stored with it: the forecast plus the margin; still air for
/// missions planned before winds were).
///
/// # Errors
/// [`AppError::Invalid`] when no such model gives the mission's usable budget (the battery
/// settings changed since it was planned: re-plan it); invalid `[energy]` settings.
pub fn export_energy_model<S: Store>(
    project: &Project<S>,
    m: &MissionRecord,
) -> Result<FlightEnergyModel> {
    let budget_j = m.mission.energy.budget_j;
    let p = &m.mission.profile;
    let wind = gleaner_energy::Wind::new(p.wind_mps, p.wind_from_deg)
        .map_err(|e| AppError::core("the mission's planned wind", e))?;
    let in_wind = |f: FlightEnergyModel| FlightEnergyModel { wind, ..f };
    let own = project.settings().energy.clone();
    let model = crate::plan::flight_model(&own, "[energy] settings")?;
    if model.usable_budget_j() == budget_j {
        return Ok(in_wind(model.flight_energy_model()));
    }
    for preset in ENERGY_PRESETS {
        let mut energy = own.clone();
        energy.preset = preset.to_string();
        if let Ok(m) = crate::plan::flight_model(&energy, "energy preset")
            && m.usable_budget_j() == budget_j
        {
            return Ok(in_wind(m.flight_energy_model()));
        }
    }
    Err(AppError::Invalid(format!(
        "mission #{} cannot be exported for flight: it was planned against a usable budget of \
         {budget_j:.1} J, but the project's [energy] settings give {:.1} J (and no energy preset \
         gives {budget_j:.1} J): the battery settings changed since it was planned; re-plan it",
        m.id,
        model.usable_budget_j()
    )))
}

/// The safety checks of [`export`].
pub fn check_flyable(m: &MissionRecord) -> Result<()> {
    let refuse = |why: String| {
        Err(AppError::Invalid(format!(
            "mission #{} cannot be exported for flight: {why}",
            m.id
        )))
    };
    let e = &m.mission.energy;
    if !(e.total_j.is_finite() && e.budget_j.is_finite() && e.total_j <= e.budget_j) {
        return refuse(format!(
            "it needs {:.1} J but {:.1} J are usable",
            e.total_j, e.budget_j
        ));
    }
    let p = &m.mission.profile;
    if !(p.cruise_speed_mps.is_finite() && p.cruise_speed_mps > 0.0) {
        return refuse(format!("cruise speed {} m/s", p.cruise_speed_mps));
    }
    if !(p.altitude_m.is_finite() && p.altitude_m > 0.0 && p.altitude_m <= 120.0) {
        return refuse(format!("altitude {} m is outside (0, 120] m", p.altitude_m));
    }
    if !p.base_alt_m.is_finite() {
        return refuse(format!("base altitude {} m", p.base_alt_m));
    }
    if let Some(s) = m
        .mission
        .stops
        .iter()
        .find(|s| !(s.hover_s.is_finite() && s.hover_s >= 0.0))
    {
        return refuse(format!("hover time {} s at cell {}", s.hover_s, s.cell));
    }
    Ok(())
}

/// The newest stored reading's time (any sensor, any modality), seconds; none without
/// readings. One index seek per sensor and modality, not a scan of the readings (the cell
/// summaries are not used: they may be stale after a bulk ingest).
pub fn newest_reading<S: Store>(
    project: &Project<S>,
) -> Result<Option<gleaner_field::UnixSeconds>> {
    let store = project.store();
    let mut newest = None;
    for m in store.modalities()? {
        for (_, t, _) in store.latest_readings(&m.modality, i64::MIN..=i64::MAX)? {
            newest = newest.max(Some(t));
        }
    }
    Ok(newest)
}
