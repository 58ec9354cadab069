//! Checks shared by the backends: every argument of a write is validated here, before the
//! backend's first statement, so the backends refuse the same inputs with the same errors;
//! and what a write does with what is stored (new, changed or unchanged rows, the keys it
//! names), decided here so the backends differ only in their SQL.

use std::collections::{HashMap, HashSet};

use gleaner_field::{CellIndex, Modality};

use crate::{
    CellMetadata, CellRecord, Conflict, ConflictPolicy, InsertStats, MissionId, ModalityRecord,
    NewMission, ReadingBatch, Result, SensorRecord, StoreError, VisitRecord,
};

/// Relative tolerance under which two reading values are the same reading.
pub(crate) const SAME_VALUE_RTOL: f64 = 1e-12;

pub(crate) fn same_value(a: f64, b: f64) -> bool {
    a == b || (a - b).abs() <= SAME_VALUE_RTOL * a.abs().max(b.abs())
}

/// [`StoreError::Invalid`].
pub(crate) fn invalid(what: &'static str, detail: String) -> StoreError {
    StoreError::Invalid { what, detail }
}

pub(crate) fn finite(what: &'static str, name: &str, v: f64) -> Result<()> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(invalid(what, format!("{name} = {v} is not finite")))
    }
}

/// A count stored as SQLite's signed integer (saturating; no real count reaches 2^63).
pub(crate) fn as_i64(v: u64) -> i64 {
    i64::try_from(v).unwrap_or(i64::MAX)
}

/// The stored key of each of `names`, or `unknown` of the first one not stored.
pub(crate) fn keys<T>(
    names: &[T],
    known: &HashMap<String, i64>,
    name: impl Fn(&T) -> &str,
    unknown: impl Fn(&T) -> StoreError,
) -> Result<Vec<i64>> {
    names
        .iter()
        .map(|n| known.get(name(n)).copied().ok_or_else(|| unknown(n)))
        .collect()
}

/// Checks every number and the stop order of a mission before anything is written.
pub(crate) fn validate_mission(m: &NewMission) -> Result<()> {
    let e = &m.energy;
    let p = &m.profile;
    let w = m.weights;
    for (name, v) in [
        ("weight alpha", w[0]),
        ("weight beta", w[1]),
        ("weight gamma", w[2]),
        ("weight delta", w[3]),
        ("total_score", m.total_score),
        ("base_alt_m", p.base_alt_m),
        ("altitude_m", p.altitude_m),
        ("cruise_speed_mps", p.cruise_speed_mps),
        ("wind_mps", p.wind_mps),
        ("wind_from_deg", p.wind_from_deg),
        ("travel_j", e.travel_j),
        ("hover_j", e.hover_j),
        ("comm_j", e.comm_j),
        ("return_j", e.return_j),
        ("total_j", e.total_j),
        ("budget_j", e.budget_j),
        ("distance_m", e.distance_m),
        ("flight_time_s", e.flight_time_s),
        ("return_distance_m", m.return_distance_m),
    ] {
        finite("mission", name, v)?;
    }
    if p.wind_mps < 0.0 {
        return Err(invalid(
            "mission",
            format!("wind_mps {} is negative", p.wind_mps),
        ));
    }
    let mut orders = HashSet::new();
    for s in &m.stops {
        if !orders.insert(s.order) {
            return Err(invalid(
                "mission stops",
                format!("stop order {} used twice", s.order),
            ));
        }
        let cell = s.cell.to_string();
        for (name, v) in [
            ("score", s.score),
            ("leg_distance_m", s.leg_distance_m),
            ("leg_energy_j", s.leg_energy_j),
            ("collection_s", s.collection_s),
            ("hover_s", s.hover_s),
            ("hover_j", s.hover_j),
            ("comm_j", s.comm_j),
        ] {
            finite("mission stop", &format!("{cell} {name}"), v)?;
        }
        for (name, v) in ["F", "R", "A", "U"].iter().zip(s.terms.unwrap_or([0.0; 4])) {
            finite("mission stop", &format!("{cell} {name}"), v)?;
        }
    }
    Ok(())
}

/// Checks every number in `metadata` before anything is written.
pub(crate) fn validate_metadata(metadata: &[CellMetadata]) -> Result<()> {
    let mut cells = HashSet::new();
    for md in metadata {
        let cell = md.cell.to_string();
        if !cells.insert(md.cell) {
            return Err(invalid(
                "cell metadata",
                format!("cell {cell} listed twice"),
            ));
        }
        for (name, v) in [
            ("pending_bytes", md.pending_bytes),
            ("expected_energy_j", md.expected_energy_j),
        ] {
            if let Some(v) = v {
                finite("cell metadata", &format!("{cell} {name}"), v)?;
            }
        }
        if let Some(s) = &md.scores {
            for (name, v) in [
                ("F", s.freshness),
                ("R", s.redundancy),
                ("A", s.anomaly),
                ("U", s.uncertainty),
                ("S", s.score),
            ] {
                finite("cell scores", &format!("{cell} {name}"), v)?;
            }
        }
        for p in &md.class_probabilities {
            if !(0.0..=1.0).contains(&p.probability) {
                return Err(invalid(
                    "class probability",
                    format!(
                        "cell {cell} class {:?}: {} not in [0, 1]",
                        p.class, p.probability
                    ),
                ));
            }
        }
        for c in &md.correlations {
            if !(-1.0..=1.0).contains(&c.correlation) {
                return Err(invalid(
                    "correlation",
                    format!(
                        "cell {cell} neighbour {} {}: {} not in [-1, 1]",
                        c.neighbour, c.modality, c.correlation
                    ),
                ));
            }
        }
        // Names are formatted only for a value that fails (most writes have thousands).
        for a in md.anomalies.iter().filter(|a| !a.anomaly.is_finite()) {
            finite(
                "anomaly",
                &format!("{cell} {} t={}", a.modality, a.t),
                a.anomaly,
            )?;
        }
        for s in &md.summaries {
            let st = &s.stats;
            for (name, v) in [
                ("mean", st.mean),
                ("min", st.min),
                ("max", st.max),
                ("latest", st.latest_value),
                ("std", st.std.unwrap_or(0.0)),
            ] {
                if !v.is_finite() {
                    finite("summary", &format!("{cell} {} {name}", s.modality), v)?;
                }
            }
        }
    }
    Ok(())
}

/// Checks a sensor list before an upsert: finite elevations, no sensor twice with different
/// content.
pub(crate) fn check_sensor_list(sensors: &[SensorRecord]) -> Result<()> {
    let mut seen: HashMap<&str, &SensorRecord> = HashMap::new();
    for s in sensors {
        if let Some(e) = s.elevation_m {
            finite("sensor elevation", s.id.as_str(), e)?;
        }
        if let Some(prev) = seen.insert(s.id.as_str(), s)
            && prev != s
        {
            return Err(invalid(
                "sensor list",
                format!(
                    "sensor {:?} listed twice with different content",
                    s.id.as_str()
                ),
            ));
        }
    }
    Ok(())
}

/// Checks a modality list before an upsert: no modality twice with different units.
pub(crate) fn check_modality_list(modalities: &[ModalityRecord]) -> Result<()> {
    let mut seen: HashMap<&str, &ModalityRecord> = HashMap::new();
    for m in modalities {
        if let Some(prev) = seen.insert(m.modality.as_str(), m)
            && prev != m
        {
            return Err(invalid(
                "modality list",
                format!(
                    "modality {:?} listed twice with units {:?} and {:?}",
                    m.modality.as_str(),
                    prev.unit,
                    m.unit
                ),
            ));
        }
    }
    Ok(())
}

/// Rows of an insert in key order: (sensor key, modality key, t, row of the batch).
pub(crate) type KeyOrder = Vec<(i64, i64, i64, usize)>;

/// Validates a reading batch and classifies every row before anything is written: new,
/// unchanged, or conflicting (with a stored reading, or with an earlier row of the batch).
///
/// `stored_in(s, m, t_first, t_last, out)` appends the stored `(t, value)` of sensor key `s`,
/// modality key `m` with `t` in `[t_first, t_last]` (s), sorted by `t`: one range query per
/// (sensor, modality) run of the batch. Returns the rows in key order, which of them are
/// new, and the counts; under [`ConflictPolicy::Fail`] any conflict is an error.
pub(crate) fn plan_insert(
    batch: &ReadingBatch,
    sensor_keys: &[i64],
    modality_keys: &[i64],
    policy: ConflictPolicy,
    mut stored_in: impl FnMut(i64, i64, i64, i64, &mut Vec<(i64, f64)>) -> Result<()>,
) -> Result<(KeyOrder, Vec<bool>, InsertStats)> {
    for (row, r) in batch.rows.iter().enumerate() {
        let bad = |what, index, len| StoreError::BadIndex {
            row,
            what,
            index,
            len,
        };
        let s = batch
            .sensors
            .get(r.sensor as usize)
            .ok_or_else(|| bad("sensor", r.sensor, batch.sensors.len()))?;
        let m = batch
            .modalities
            .get(r.modality as usize)
            .ok_or_else(|| bad("modality", r.modality, batch.modalities.len()))?;
        if !r.value.is_finite() {
            return Err(StoreError::NonFiniteValue {
                sensor: s.clone(),
                modality: m.clone(),
                t: r.t,
                value: r.value,
            });
        }
    }
    // Key order: the stored readings of a (sensor, modality) are one primary-key range, and
    // the new rows go into the B-tree in order. The row's position breaks ties, so duplicates
    // within the batch keep their order and the first one wins.
    let mut order: Vec<(i64, i64, i64, usize)> = batch
        .rows
        .iter()
        .enumerate()
        .map(|(k, r)| {
            (
                sensor_keys[r.sensor as usize],
                modality_keys[r.modality as usize],
                r.t,
                k,
            )
        })
        .collect();
    order.sort_unstable();

    // Classify every row before writing anything: new, unchanged, or conflicting (with a
    // stored reading, or with an earlier row of the batch). One primary-key range scan per
    // (sensor, modality) run of the batch, over the run's time span only. Nothing is written
    // before the classification is complete, so a refused batch leaves no trace without the
    // cost of a savepoint (see `SqliteTx::insert_readings`).
    let mut stats = InsertStats::default();
    let mut fresh = vec![false; order.len()];
    let mut stored: Vec<(i64, f64)> = Vec::new();
    let mut start = 0;
    while let Some(&(s, m, t_first, _)) = order.get(start) {
        let run = order[start..]
            .iter()
            .take_while(|o| o.0 == s && o.1 == m)
            .count();
        let t_last = order[start + run - 1].2;
        stored.clear();
        stored_in(s, m, t_first, t_last, &mut stored)?;
        let mut k = 0; // into `stored`
        let mut first_of_t: Option<(i64, f64)> = None; // the first batch row at its t
        for (offset, &(_, _, t, row)) in order[start..start + run].iter().enumerate() {
            let value = batch.rows[row].value;
            while k < stored.len() && stored[k].0 < t {
                k += 1;
            }
            let existing = match (stored.get(k), first_of_t) {
                (Some(&(ts, v)), _) if ts == t => Some(v),
                (_, Some((tb, v))) if tb == t => Some(v),
                _ => None,
            };
            match existing {
                None => {
                    fresh[start + offset] = true;
                    stats.inserted += 1;
                    first_of_t = Some((t, value));
                }
                Some(v) if same_value(v, value) => stats.unchanged += 1,
                Some(v) => {
                    let r = &batch.rows[row];
                    stats.conflicts.push(Conflict {
                        sensor: batch.sensors[r.sensor as usize].clone(),
                        modality: batch.modalities[r.modality as usize].clone(),
                        t,
                        stored: v,
                        incoming: value,
                    });
                }
            }
        }
        start += run;
    }
    if policy == ConflictPolicy::Fail && !stats.conflicts.is_empty() {
        return Err(StoreError::Conflicts(stats.conflicts));
    }

    Ok((order, fresh, stats))
}

/// Checks a cell grid before it replaces the stored one: unique labels, positive sides, each
/// sensor in one cell.
pub(crate) fn check_cells(cells: &[CellRecord]) -> Result<()> {
    // Validate: unique labels, positive sides, known sensors, each sensor in one cell.
    let mut labels = HashSet::new();
    let mut owner: HashMap<&str, CellIndex> = HashMap::new();
    for cell in cells {
        if !labels.insert(cell.index) {
            return Err(invalid(
                "cell list",
                format!("cell {} listed twice", cell.index),
            ));
        }
        if !(cell.cell_size_m.is_finite() && cell.cell_size_m > 0.0) {
            return Err(invalid(
                "cell size",
                format!(
                    "cell {}: {} m must be positive",
                    cell.index, cell.cell_size_m
                ),
            ));
        }
        for s in &cell.sensors {
            if let Some(other) = owner.insert(s.as_str(), cell.index)
                && other != cell.index
            {
                return Err(invalid(
                    "cell list",
                    format!("sensor {s} is in cells {other} and {}", cell.index),
                ));
            }
        }
    }
    Ok(())
}

/// Checks a visit list before it is recorded: unique orders, finite energies.
pub(crate) fn check_visits(mission: MissionId, visits: &[VisitRecord]) -> Result<()> {
    let mut orders = HashSet::new();
    for v in visits {
        if !orders.insert(v.order) {
            return Err(invalid(
                "visit list",
                format!("visit order {} used twice in mission {mission}", v.order),
            ));
        }
        if let Some(e) = v.energy_j {
            finite("visit energy", &v.cell.to_string(), e)?;
        }
    }
    Ok(())
}

/// What [`crate::StoreWrite::import_mission`] does after inserting a mission.
pub(crate) enum ImportFlight {
    /// Nothing: a planned mission has no flight.
    Nothing,
    /// Records its visits as flown at this time (s).
    Record(i64),
    /// Flags it cancelled.
    Cancel,
}

/// The flight part of [`crate::StoreWrite::import_mission`]: a flown mission's visits are
/// recorded at its `flown_at`; a planned one has none to record; a cancelled one is flagged.
pub(crate) fn import_flight(record: &crate::MissionRecord) -> Result<ImportFlight> {
    match (record.status, record.flown_at) {
        (crate::MissionStatus::Planned, None) if record.visits.is_empty() => {
            Ok(ImportFlight::Nothing)
        }
        (crate::MissionStatus::Cancelled, None) if record.visits.is_empty() => {
            Ok(ImportFlight::Cancel)
        }
        (crate::MissionStatus::Flown, Some(flown_at)) => Ok(ImportFlight::Record(flown_at)),
        _ => Err(invalid(
            "mission record",
            format!(
                "mission {}: status {:?} with flown_at {:?} and {} visit(s)",
                record.id,
                record.status,
                record.flown_at,
                record.visits.len()
            ),
        )),
    }
}

/// The store's refusal to cancel `mission`: it does not exist or is not planned (the use case
/// checks first and names the reason; this guards a direct caller).
pub(crate) fn not_cancellable(mission: crate::MissionId) -> crate::StoreError {
    invalid(
        "mission",
        format!("mission {mission} does not exist or is not a planned mission"),
    )
}

/// The outcome of deleting `mission` when the statement removed `rows` rows: an unknown
/// mission when none.
pub(crate) fn mission_deleted(mission: MissionId, rows: u64) -> Result<()> {
    if rows == 0 {
        return Err(StoreError::Unknown {
            what: "mission",
            name: mission.to_string(),
        });
    }
    Ok(())
}

/// The stored keys of the cells and modalities a metadata write names.
pub(crate) struct MetadataKeys {
    /// `label -> key` of every stored cell.
    pub(crate) cells: HashMap<String, i64>,
    /// `name -> key` of every stored modality.
    pub(crate) modalities: HashMap<String, i64>,
}

impl MetadataKeys {
    /// The key of `cell`, or [`StoreError::Unknown`] when it is not stored.
    pub(crate) fn cell(&self, cell: &CellIndex) -> Result<i64> {
        self.cells
            .get(&cell.to_string())
            .copied()
            .ok_or_else(|| StoreError::Unknown {
                what: "cell",
                name: cell.to_string(),
            })
    }

    /// The key of `modality`, or [`StoreError::UnknownModality`] when it is not stored.
    pub(crate) fn modality(&self, modality: &Modality) -> Result<i64> {
        self.modalities
            .get(modality.as_str())
            .copied()
            .ok_or_else(|| StoreError::UnknownModality(modality.clone()))
    }
}

/// What an upsert does with one modality.
pub(crate) enum UnitChange<'a> {
    /// Inserts it (not stored yet).
    Add,
    /// Records this unit for a modality stored without one.
    SetUnit(&'a str),
    /// Nothing: the same unit, or no unit offered (the stored one stays).
    Unchanged,
}

/// What upserting `m` does given its stored unit (`None`: not stored; `Some(None)`: stored
/// without a unit); [`StoreError::UnitMismatch`] when it names another unit than the stored one.
pub(crate) fn unit_change<'a>(
    m: &'a ModalityRecord,
    stored: Option<Option<&str>>,
) -> Result<UnitChange<'a>> {
    match (stored, m.unit.as_deref()) {
        (None, _) => Ok(UnitChange::Add),
        (Some(None), Some(unit)) => Ok(UnitChange::SetUnit(unit)),
        (Some(Some(stored)), Some(incoming)) if stored != incoming => {
            Err(StoreError::UnitMismatch {
                modality: m.modality.clone(),
                stored: stored.to_string(),
                incoming: incoming.to_string(),
            })
        }
        (Some(_), _) => Ok(UnitChange::Unchanged),
    }
}

/// Whether the stored sensor row `(lat, lon, elevation_m, source)` (deg, deg, m) already is `s`.
pub(crate) fn sensor_unchanged(stored: (f64, f64, Option<f64>, &str), s: &SensorRecord) -> bool {
    let (lat, lon, elevation_m, source) = stored;
    lat == s.position.lat()
        && lon == s.position.lon()
        && elevation_m == s.elevation_m
        && source == s.source
}

/// How [`crate::StoreWrite::replace_cells`] turns the stored grid into the new one.
pub(crate) struct CellPlan {
    /// How many stored cells stay as they are.
    pub(crate) kept: usize,
    /// The stored cells to delete (absent from the new grid, or changed).
    pub(crate) gone: Vec<CellIndex>,
    /// The cells to insert, in index order, sensors sorted and without repeats, each with its
    /// sensors' stored keys.
    pub(crate) added: Vec<(CellRecord, Vec<i64>)>,
}

/// The plan replacing the `stored` grid by `cells` (checked by [`check_cells`]), with
/// `sensor_keys` (`name -> key`); [`StoreError::Unknown`] for the first sensor not stored.
pub(crate) fn plan_cells(
    stored: &[CellRecord],
    cells: &[CellRecord],
    sensor_keys: &HashMap<String, i64>,
) -> Result<CellPlan> {
    let normalised = |cell: &CellRecord| {
        let mut cell = cell.clone();
        cell.sensors.sort();
        cell.sensors.dedup();
        cell
    };
    let mut new_by_label: HashMap<CellIndex, CellRecord> =
        cells.iter().map(|x| (x.index, normalised(x))).collect();
    let mut kept = 0;
    let mut gone = Vec::new();
    for old in stored {
        if new_by_label.get(&old.index) == Some(old) {
            new_by_label.remove(&old.index);
            kept += 1;
        } else {
            gone.push(old.index);
        }
    }
    let mut order: Vec<CellRecord> = new_by_label.into_values().collect();
    order.sort_by_key(|x| x.index);
    let added = order
        .into_iter()
        .map(|cell| {
            let members = keys(
                &cell.sensors,
                sensor_keys,
                |s| s.as_str(),
                |s| StoreError::Unknown {
                    what: "sensor",
                    name: s.to_string(),
                },
            )?;
            Ok((cell, members))
        })
        .collect::<Result<_>>()?;
    Ok(CellPlan { kept, gone, added })
}

/// Checks that visits may be recorded for `mission`, whose stored `(status, flown_at)` is
/// `stored` (`None`: no such mission): a flown one only when `amend`. `flown_at` (s) stands in
/// the error for a flown mission stored without a time.
pub(crate) fn check_recordable(
    mission: MissionId,
    stored: Option<(&str, Option<i64>)>,
    flown_at: i64,
    amend: bool,
) -> Result<()> {
    let Some((status, stored_flown_at)) = stored else {
        return Err(StoreError::Unknown {
            what: "mission",
            name: mission.to_string(),
        });
    };
    if status == crate::MissionStatus::Flown.as_str() && !amend {
        return Err(StoreError::AlreadyFlown {
            mission: mission.0,
            // Migration 2 gives every flown mission a time; the fallback is for hand edits.
            flown_at: stored_flown_at.unwrap_or(flown_at),
        });
    }
    Ok(())
}
