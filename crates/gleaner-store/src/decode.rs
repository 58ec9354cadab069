//! Rows to records, once for both backends: each backend keeps its own SQL and says only how a
//! column is pulled out of its row type ([`Column`]); what the columns mean, how they are
//! checked (a malformed stored name or an out-of-range count is [`StoreError::Corrupt`]) and
//! how rows are assembled into records is written here.
//!
//! A decoder reads the columns of its row by position, in the order both backends' queries
//! select them (documented on each decoder); a child row's column 0 is its parent's key.

use std::collections::HashMap;

use gleaner_field::{CellIndex, LatLon, Modality, SensorId, UnixSeconds};

use crate::{
    AnomalyRecord, CellMetadata, CellRecord, CellScores, ClassProbability, Correlation,
    EnergyBreakdown, FlightProfile, IngestRecord, MissionId, MissionKind, MissionRecord,
    MissionStatus, ModalityRecord, ModalitySummary, NewMission, Reading, ReadingBatch, Result,
    SensorRecord, SeriesStats, StopRecord, StoreError, VisitRecord,
};

/// How a backend pulls column `i` (from 0) of a row out as a `T`.
pub(crate) trait Column<T> {
    /// Column `i` as a `T`, or the engine's error.
    fn column(&self, i: usize) -> Result<T>;
}

/// A row whose columns can be read as every type the decoders use (each backend declares its
/// row type one).
pub(crate) trait Columns:
    Column<i64>
    + Column<f64>
    + Column<bool>
    + Column<String>
    + Column<Option<i64>>
    + Column<Option<f64>>
    + Column<Option<String>>
{
}

/// A `Corrupt` error naming `table`.
fn corrupt(table: &'static str, detail: String) -> StoreError {
    StoreError::Corrupt { table, detail }
}

/// A stored sensor name read back as a [`SensorId`].
pub(crate) fn parse_sensor(table: &'static str, name: String) -> Result<SensorId> {
    SensorId::new(name).map_err(|e| corrupt(table, e.to_string()))
}

/// A stored modality name read back as a [`Modality`].
pub(crate) fn parse_modality(table: &'static str, name: &str) -> Result<Modality> {
    Modality::new(name).map_err(|e| corrupt(table, e.to_string()))
}

/// A stored position (degrees) read back as a [`LatLon`].
fn parse_latlon(table: &'static str, lat: f64, lon: f64) -> Result<LatLon> {
    LatLon::new(lat, lon).map_err(|e| corrupt(table, e.to_string()))
}

/// A stored cell label (`x12y-3`) read back as a [`CellIndex`].
fn parse_cell(table: &'static str, label: &str) -> Result<CellIndex> {
    CellIndex::parse(label).ok_or_else(|| {
        corrupt(
            table,
            format!("cell label {label:?} is not of the form x<i>y<j>"),
        )
    })
}

/// A count read back as `u64` (stored as a signed 64-bit integer).
pub(crate) fn count(table: &'static str, n: i64) -> Result<u64> {
    u64::try_from(n).map_err(|_| corrupt(table, format!("negative count {n}")))
}

/// A position (stop or visit order) read back as `u32`.
fn position(table: &'static str, n: i64) -> Result<u32> {
    u32::try_from(n).map_err(|_| corrupt(table, format!("position {n} out of range")))
}

/// `(name, key)` pairs of stored sensors or modalities.
pub(crate) type Keys = Vec<(String, i64)>;

/// `(name, key)` pairs sorted by name (byte-wise).
pub(crate) fn sorted(map: HashMap<String, i64>) -> Keys {
    let mut v: Vec<(String, i64)> = map.into_iter().collect();
    v.sort();
    v
}

/// The `(name, key)` lists of every stored sensor and of every stored modality or only
/// `modality`, from the stored `name -> key` maps, each sorted by name: what
/// [`crate::StoreRead::readings_for`] reads.
pub(crate) fn all_sensors_of(
    sensor_ids: HashMap<String, i64>,
    modality_ids: HashMap<String, i64>,
    modality: Option<&Modality>,
) -> (Keys, Keys) {
    let mut modalities = sorted(modality_ids);
    modalities.retain(|(name, _)| modality.is_none_or(|m| m.as_str() == name));
    (sorted(sensor_ids), modalities)
}

/// The `(name, key)` of each of `sensors` in `ids` (name -> key), sorted by name and without
/// repeats; [`StoreError::UnknownSensor`] for the first one not stored: what
/// [`crate::StoreRead::readings_of_sensors`] reads, with every modality.
pub(crate) fn wanted_sensors(
    ids: &HashMap<String, i64>,
    sensors: &[SensorId],
) -> Result<Vec<(String, i64)>> {
    let mut wanted = sensors
        .iter()
        .map(|s| {
            ids.get(s.as_str())
                .map(|&k| (s.to_string(), k))
                .ok_or_else(|| StoreError::UnknownSensor(s.clone()))
        })
        .collect::<Result<Vec<_>>>()?;
    wanted.sort();
    wanted.dedup();
    Ok(wanted)
}

/// The readings of `sensors` x `modalities` (`(name, key)`, both sorted by name), in that order:
/// `pair(sensor key, modality key, out)` appends that pair's `(t, value)` rows (time in s, in
/// time order) to the emptied `out`. A sensor or modality enters the batch with its first row.
pub(crate) fn assemble_readings(
    sensors: &[(String, i64)],
    modalities: &[(String, i64)],
    mut pair: impl FnMut(i64, i64, &mut Vec<(UnixSeconds, f64)>) -> Result<()>,
) -> Result<ReadingBatch> {
    let mut batch = ReadingBatch::new();
    let mut modality_index: HashMap<i64, u32> = HashMap::new();
    let mut rows = Vec::new();
    for (sname, skey) in sensors {
        let mut sensor_index = None;
        for (mname, mkey) in modalities {
            rows.clear();
            pair(*skey, *mkey, &mut rows)?;
            if rows.is_empty() {
                continue;
            }
            let s = match sensor_index {
                Some(s) => s,
                None => {
                    batch.sensors.push(parse_sensor("sensors", sname.clone())?);
                    let s = batch.sensors.len() as u32 - 1;
                    sensor_index = Some(s);
                    s
                }
            };
            let m = match modality_index.get(mkey) {
                Some(&m) => m,
                None => {
                    batch.modalities.push(parse_modality("modalities", mname)?);
                    let m = batch.modalities.len() as u32 - 1;
                    modality_index.insert(*mkey, m);
                    m
                }
            };
            batch.rows.extend(rows.iter().map(|&(t, value)| Reading {
                sensor: s,
                modality: m,
                t,
                value,
            }));
        }
    }
    Ok(batch)
}

/// `name, lat, lon, elevation_m, source` of `sensors`.
pub(crate) fn sensor(r: &impl Columns) -> Result<SensorRecord> {
    Ok(SensorRecord {
        id: parse_sensor("sensors", r.column(0)?)?,
        position: parse_latlon("sensors", r.column(1)?, r.column(2)?)?,
        elevation_m: r.column(3)?,
        source: r.column(4)?,
    })
}

/// `name, unit` of `modalities`.
pub(crate) fn modality(r: &impl Columns) -> Result<ModalityRecord> {
    let name: String = r.column(0)?;
    Ok(ModalityRecord {
        modality: parse_modality("modalities", &name)?,
        unit: r.column(1)?,
    })
}

/// `file_name, format, rows_read, rows_inserted, rows_unchanged, rows_skipped, at` of
/// `ingests`.
pub(crate) fn ingest(r: &impl Columns) -> Result<IngestRecord> {
    let n = |i: usize| -> Result<u64> { count("ingests", r.column(i)?) };
    Ok(IngestRecord {
        file_name: r.column(0)?,
        format: r.column(1)?,
        rows_read: n(2)?,
        rows_inserted: n(3)?,
        rows_unchanged: n(4)?,
        rows_skipped: n(5)?,
        at: r.column(6)?,
    })
}

/// The sensor named in column 1 of a `cell_sensors` row (column 0: the cell's key).
pub(crate) fn cell_member(r: &impl Columns) -> Result<SensorId> {
    parse_sensor("cell_sensors", r.column(1)?)
}

/// `id, label, lat, lon, cell_size_m` of `cells`, with its member `sensors`.
pub(crate) fn cell(r: &impl Columns, sensors: Vec<SensorId>) -> Result<CellRecord> {
    let label: String = r.column(1)?;
    Ok(CellRecord {
        index: parse_cell("cells", &label)?,
        centre: parse_latlon("cells", r.column(2)?, r.column(3)?)?,
        cell_size_m: r.column(4)?,
        sensors,
    })
}

/// `c.id, c.label, last_collected, pending_bytes, expected_energy_j, freshness, redundancy,
/// anomaly, uncertainty, score, computed_at` of `cells` left-joined with `cell_metadata`:
/// the cell's scalars, without its child lists. The scores are set only when all six are.
pub(crate) fn cell_metadata(r: &impl Columns) -> Result<CellMetadata> {
    let label: String = r.column(1)?;
    let mut md = CellMetadata::new(parse_cell("cells", &label)?);
    md.last_collected = r.column(2)?;
    md.pending_bytes = r.column(3)?;
    md.expected_energy_j = r.column(4)?;
    let term = |k: usize| -> Result<Option<f64>> { r.column(k) };
    let computed_at: Option<i64> = r.column(10)?;
    if let (Some(f), Some(rr), Some(a), Some(u), Some(s), Some(at)) = (
        term(5)?,
        term(6)?,
        term(7)?,
        term(8)?,
        term(9)?,
        computed_at,
    ) {
        md.scores = Some(CellScores {
            freshness: f,
            redundancy: rr,
            anomaly: a,
            uncertainty: u,
            score: s,
            computed_at: at,
        });
    }
    Ok(md)
}

/// `cell, class, probability` of `cell_class_probabilities`.
pub(crate) fn class_probability(r: &impl Columns) -> Result<ClassProbability> {
    Ok(ClassProbability {
        class: r.column(1)?,
        probability: r.column(2)?,
    })
}

/// `cell, modality name, count, mean, std, min, max, latest_t, latest_value` of
/// `cell_summaries`.
pub(crate) fn summary(r: &impl Columns) -> Result<ModalitySummary> {
    let name: String = r.column(1)?;
    Ok(ModalitySummary {
        modality: parse_modality("cell_summaries", &name)?,
        stats: SeriesStats {
            count: count("cell_summaries", r.column(2)?)?,
            mean: r.column(3)?,
            std: r.column(4)?,
            min: r.column(5)?,
            max: r.column(6)?,
            latest_t: r.column(7)?,
            latest_value: r.column(8)?,
        },
    })
}

/// `cell, neighbour label, modality name, correlation, overlap` of `cell_correlations`.
pub(crate) fn correlation(r: &impl Columns) -> Result<Correlation> {
    let (neighbour, name): (String, String) = (r.column(1)?, r.column(2)?);
    Ok(Correlation {
        neighbour: parse_cell("cell_correlations", &neighbour)?,
        modality: parse_modality("cell_correlations", &name)?,
        correlation: r.column(3)?,
        overlap: count("cell_correlations", r.column(4)?)?,
    })
}

/// `cell, modality name, t, anomaly, flagged` of `cell_anomalies`.
pub(crate) fn anomaly(r: &impl Columns) -> Result<AnomalyRecord> {
    let name: String = r.column(1)?;
    Ok(AnomalyRecord {
        modality: parse_modality("cell_anomalies", &name)?,
        t: r.column(2)?,
        anomaly: r.column(3)?,
        flagged: r.column(4)?,
    })
}

/// `sensor name, last_collected` of `sensor_collection`.
pub(crate) fn sensor_last_collected(r: &impl Columns) -> Result<(SensorId, UnixSeconds)> {
    Ok((
        parse_sensor("sensor_collection", r.column(0)?)?,
        r.column(1)?,
    ))
}

/// `sensor name, count` of the readings per sensor.
pub(crate) fn sensor_reading_count(r: &impl Columns) -> Result<(SensorId, u64)> {
    Ok((
        parse_sensor("readings", r.column(0)?)?,
        count("readings", r.column(1)?)?,
    ))
}

/// `mission, position, cell, lat, lon, score, freshness, redundancy, anomaly, uncertainty,
/// leg_distance_m, leg_energy_j, collection_s, hover_s, hover_j, comm_j` of `mission_stops`;
/// the four terms are set only when all four are.
pub(crate) fn stop(s: &impl Columns) -> Result<StopRecord> {
    let term = |k: usize| -> Result<Option<f64>> { s.column(k) };
    let terms = match (term(6)?, term(7)?, term(8)?, term(9)?) {
        (Some(f), Some(r), Some(a), Some(u)) => Some([f, r, a, u]),
        _ => None,
    };
    let cell: String = s.column(2)?;
    Ok(StopRecord {
        order: position("mission_stops", s.column(1)?)?,
        cell: parse_cell("mission_stops", &cell)?,
        centre: parse_latlon("mission_stops", s.column(3)?, s.column(4)?)?,
        score: s.column(5)?,
        terms,
        leg_distance_m: s.column(10)?,
        leg_energy_j: s.column(11)?,
        collection_s: s.column(12)?,
        hover_s: s.column(13)?,
        hover_j: s.column(14)?,
        comm_j: s.column(15)?,
    })
}

/// `mission, position, cell, arrived_at, energy_j` of `visits`.
pub(crate) fn visit(v: &impl Columns) -> Result<VisitRecord> {
    let cell: String = v.column(2)?;
    Ok(VisitRecord {
        order: position("visits", v.column(1)?)?,
        cell: parse_cell("visits", &cell)?,
        arrived_at: v.column(3)?,
        energy_j: v.column(4)?,
    })
}

/// A mission's kind and status from their stored texts and the `cancelled` flag (a planned
/// mission that was cancelled).
fn kind_and_status(r: &impl Columns, id: i64) -> Result<(MissionKind, MissionStatus)> {
    let kind_s: String = r.column(2)?;
    let kind = MissionKind::parse(&kind_s)
        .ok_or_else(|| corrupt("missions", format!("mission {id}: unknown kind {kind_s:?}")))?;
    let status_s: String = r.column(26)?;
    let cancelled: bool = r.column(30)?;
    let status = match MissionStatus::parse(&status_s) {
        Some(MissionStatus::Planned) if cancelled => MissionStatus::Cancelled,
        Some(s @ (MissionStatus::Planned | MissionStatus::Flown)) => s,
        _ => {
            return Err(corrupt(
                "missions",
                format!("mission {id}: unknown status {status_s:?}"),
            ));
        }
    };
    Ok((kind, status))
}

/// The columns of `missions` that [`mission`] decodes, in its order: a string literal, for
/// each backend's `concat!` of its own query.
macro_rules! mission_columns {
    () => {
        "id, created_at, kind, planned_at, solver, seed,
         weight_alpha, weight_beta, weight_gamma, weight_delta, anomaly_form,
         total_score, base_lat, base_lon, base_alt_m, altitude_m, cruise_speed_mps,
         travel_j, hover_j, comm_j, return_j, total_j, budget_j, distance_m,
         flight_time_s, return_distance_m, status, flown_at, wind_mps, wind_from_deg,
         cancelled"
    };
}
pub(crate) use mission_columns;

/// A `missions` row ([`mission_columns`]) with its `stops` and `visits`.
pub(crate) fn mission(
    r: &impl Columns,
    stops: Vec<StopRecord>,
    visits: Vec<VisitRecord>,
) -> Result<MissionRecord> {
    let id: i64 = r.column(0)?;
    let (kind, status) = kind_and_status(r, id)?;
    let seed: i64 = r.column(5)?;
    Ok(MissionRecord {
        id: MissionId(id),
        mission: NewMission {
            created_at: r.column(1)?,
            kind,
            planned_at: r.column(3)?,
            solver: r.column(4)?,
            // Stored as the two's-complement i64 of the same 64 bits.
            seed: seed as u64,
            weights: [r.column(6)?, r.column(7)?, r.column(8)?, r.column(9)?],
            anomaly_form: r.column(10)?,
            total_score: r.column(11)?,
            profile: FlightProfile {
                base: parse_latlon("missions", r.column(12)?, r.column(13)?)?,
                base_alt_m: r.column(14)?,
                altitude_m: r.column(15)?,
                cruise_speed_mps: r.column(16)?,
                wind_mps: r.column(28)?,
                wind_from_deg: r.column(29)?,
            },
            energy: EnergyBreakdown {
                travel_j: r.column(17)?,
                hover_j: r.column(18)?,
                comm_j: r.column(19)?,
                return_j: r.column(20)?,
                total_j: r.column(21)?,
                budget_j: r.column(22)?,
                distance_m: r.column(23)?,
                flight_time_s: r.column(24)?,
            },
            return_distance_m: r.column(25)?,
            stops,
        },
        status,
        flown_at: r.column(27)?,
        visits,
    })
}
