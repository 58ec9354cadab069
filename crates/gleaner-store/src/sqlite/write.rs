//! The writes of [`super::SqliteTx`], each over the connection of a savepoint: a function that
//! returns an error leaves the database as it found it (the savepoint is rolled back).

use std::collections::{HashMap, HashSet};

use gleaner_field::{CellIndex, Modality, SensorId, UnixSeconds};
use rusqlite::{CachedStatement, Connection, OptionalExtension, params};

use super::Db;
use super::read::{cell_ids, modality_ids, sensor_ids};
use crate::checks::{
    ImportFlight, MetadataKeys, UnitChange, as_i64, check_cells, check_modality_list,
    check_recordable, check_sensor_list, check_visits, import_flight, keys, mission_deleted,
    not_cancellable, plan_cells, plan_insert, sensor_unchanged, unit_change, validate_metadata,
    validate_mission,
};
use crate::upsert::{ANOMALIES, CORRELATIONS, SUMMARIES};
use crate::{
    CellMetadata, CellRecord, ConflictPolicy, IngestRecord, InsertStats, MissionId, MissionRecord,
    MissionStatus, ModalityRecord, NewMission, ReadingBatch, ReplaceCellsStats, Result,
    SensorRecord, StoreError, UpsertStats, VisitRecord,
};

/// [`Connection::execute`] through the connection's statement cache: the statement is parsed
/// once per connection instead of at every call (the same SQL, so the same effect).
fn execute_cached<P: rusqlite::Params>(
    c: &Connection,
    sql: &str,
    params: P,
) -> rusqlite::Result<usize> {
    c.prepare_cached(sql)?.execute(params)
}

/// The statements of `sql`, each through the connection's statement cache (parsed once per
/// connection).
fn prepared<'c, const N: usize>(
    c: &'c Connection,
    sql: [&str; N],
) -> Result<[CachedStatement<'c>; N]> {
    let mut statements = Vec::with_capacity(N);
    for s in sql {
        statements.push(c.prepare_cached(s).db()?);
    }
    Ok(statements
        .try_into()
        .ok()
        .expect("one statement for each SQL text"))
}

/// Rows per multi-row `INSERT` statement in [`insert_readings`] (4 parameters each).
const CHUNK: usize = 128;

pub(super) fn upsert_sensors(c: &Connection, sensors: &[SensorRecord]) -> Result<UpsertStats> {
    check_sensor_list(sensors)?;
    let mut stats = UpsertStats::default();
    let [mut get, mut insert, mut update] = prepared(
        c,
        [
            "SELECT lat, lon, elevation_m, source FROM sensors WHERE name = ?1",
            "INSERT INTO sensors (name, lat, lon, elevation_m, source) VALUES (?1, ?2, ?3, ?4, ?5)",
            "UPDATE sensors SET lat = ?2, lon = ?3, elevation_m = ?4, source = ?5 WHERE name = ?1",
        ],
    )?;
    let mut done = HashSet::new();
    for s in sensors {
        if !done.insert(s.id.as_str()) {
            continue;
        }
        let p = params![
            s.id.as_str(),
            s.position.lat(),
            s.position.lon(),
            s.elevation_m,
            s.source
        ];
        let stored: Option<(f64, f64, Option<f64>, String)> = get
            .query_row([s.id.as_str()], |r| {
                Ok((r.get(0)?, r.get(1)?, r.get(2)?, r.get(3)?))
            })
            .optional()
            .db()?;
        match stored {
            None => {
                insert.execute(p).db()?;
                stats.added.push(s.id.to_string());
            }
            Some((lat, lon, elev, source)) if sensor_unchanged((lat, lon, elev, &source), s) => {
                stats.unchanged += 1;
            }
            Some(_) => {
                update.execute(p).db()?;
                stats.updated.push(s.id.to_string());
            }
        }
    }
    Ok(stats)
}

pub(super) fn upsert_modalities(
    c: &Connection,
    modalities: &[ModalityRecord],
) -> Result<UpsertStats> {
    check_modality_list(modalities)?;
    let mut stats = UpsertStats::default();
    let [mut get, mut insert, mut update] = prepared(
        c,
        [
            "SELECT unit FROM modalities WHERE name = ?1",
            "INSERT INTO modalities (name, unit) VALUES (?1, ?2)",
            "UPDATE modalities SET unit = ?2 WHERE name = ?1",
        ],
    )?;
    let mut done = HashSet::new();
    for m in modalities {
        let name = m.modality.as_str();
        if !done.insert(name) {
            continue;
        }
        let stored: Option<Option<String>> = get.query_row([name], |r| r.get(0)).optional().db()?;
        match unit_change(m, stored.as_ref().map(Option::as_deref))? {
            UnitChange::Add => {
                insert.execute(params![name, m.unit]).db()?;
                stats.added.push(name.to_string());
            }
            UnitChange::SetUnit(unit) => {
                update.execute(params![name, unit]).db()?;
                stats.updated.push(name.to_string());
            }
            UnitChange::Unchanged => stats.unchanged += 1,
        }
    }
    Ok(stats)
}

pub(super) fn insert_readings(
    c: &Connection,
    batch: &ReadingBatch,
    policy: ConflictPolicy,
) -> Result<InsertStats> {
    // Resolve names to integer keys and validate every row before touching the database.
    let known_sensors = sensor_ids(c)?;
    let known_modalities = modality_ids(c)?;
    let sensor_keys = keys(&batch.sensors, &known_sensors, SensorId::as_str, |s| {
        StoreError::UnknownSensor(s.clone())
    })?;
    let modality_keys = keys(
        &batch.modalities,
        &known_modalities,
        Modality::as_str,
        |m| StoreError::UnknownModality(m.clone()),
    )?;
    let mut stored_in_range = c
        .prepare_cached(
            "SELECT t, value FROM readings
             WHERE sensor = ?1 AND modality = ?2 AND t BETWEEN ?3 AND ?4 ORDER BY t",
        )
        .db()?;
    let (order, fresh, stats) = plan_insert(
        batch,
        &sensor_keys,
        &modality_keys,
        policy,
        |s, m, t_first, t_last, stored| {
            let mut q = stored_in_range.query(params![s, m, t_first, t_last]).db()?;
            while let Some(row) = q.next().db()? {
                stored.push((row.get(0).db()?, row.get(1).db()?));
            }
            Ok(())
        },
    )?;

    // Insert the new rows in key order, many per statement.
    let many_sql = format!(
        "INSERT INTO readings (sensor, modality, t, value) VALUES {}",
        vec!["(?, ?, ?, ?)"; CHUNK].join(", ")
    );
    let mut many = c.prepare_cached(&many_sql).db()?;
    let mut one = c
        .prepare_cached("INSERT INTO readings (sensor, modality, t, value) VALUES (?1, ?2, ?3, ?4)")
        .db()?;
    let new_rows: Vec<&(i64, i64, i64, usize)> = order
        .iter()
        .zip(&fresh)
        .filter_map(|(o, &f)| f.then_some(o))
        .collect();
    for chunk in new_rows.chunks(CHUNK) {
        if chunk.len() == CHUNK {
            for (k, &&(s, m, t, row)) in chunk.iter().enumerate() {
                many.raw_bind_parameter(4 * k + 1, s).db()?;
                many.raw_bind_parameter(4 * k + 2, m).db()?;
                many.raw_bind_parameter(4 * k + 3, t).db()?;
                many.raw_bind_parameter(4 * k + 4, batch.rows[row].value)
                    .db()?;
            }
            many.raw_execute().db()?;
            crate::failpoint::step();
        } else {
            for &&(s, m, t, row) in chunk {
                one.execute(params![s, m, t, batch.rows[row].value]).db()?;
            }
        }
    }
    Ok(stats)
}

pub(super) fn record_ingest(c: &Connection, ingest: &IngestRecord) -> Result<i64> {
    execute_cached(
        c,
        "INSERT INTO ingests (file_name, format, rows_read, rows_inserted, rows_unchanged,
                              rows_skipped, at)
         VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7)",
        params![
            ingest.file_name,
            ingest.format,
            as_i64(ingest.rows_read),
            as_i64(ingest.rows_inserted),
            as_i64(ingest.rows_unchanged),
            as_i64(ingest.rows_skipped),
            ingest.at
        ],
    )
    .db()?;
    Ok(c.last_insert_rowid())
}

pub(super) fn replace_cells(c: &Connection, cells: &[CellRecord]) -> Result<ReplaceCellsStats> {
    check_cells(cells)?;
    let stored = super::read::cells(c)?;
    let sensor_keys = sensor_ids(c)?;
    let plan = plan_cells(&stored, cells, &sensor_keys)?;
    let mut delete = c
        .prepare_cached("DELETE FROM cells WHERE label = ?1")
        .db()?;
    for label in &plan.gone {
        delete.execute([label.to_string()]).db()?;
    }
    let mut insert_cell = c
        .prepare_cached(
            "INSERT INTO cells (label, i, j, lat, lon, cell_size_m) VALUES (?1, ?2, ?3, ?4, ?5, ?6)",
        )
        .db()?;
    let mut insert_member = c
        .prepare_cached("INSERT INTO cell_sensors (cell, sensor) VALUES (?1, ?2)")
        .db()?;
    for (cell, members) in &plan.added {
        insert_cell
            .execute(params![
                cell.index.to_string(),
                cell.index.i,
                cell.index.j,
                cell.centre.lat(),
                cell.centre.lon(),
                cell.cell_size_m
            ])
            .db()?;
        let cell_key = c.last_insert_rowid();
        for sensor_key in members {
            insert_member.execute(params![cell_key, sensor_key]).db()?;
        }
    }
    Ok(ReplaceCellsStats {
        added: plan.added.len(),
        removed: plan.gone.len(),
        kept: plan.kept,
    })
}

pub(super) fn set_sensors_collected(
    c: &Connection,
    collected: &[(SensorId, UnixSeconds)],
) -> Result<()> {
    let keys = sensor_ids(c)?;
    let mut stmt = c
        .prepare_cached(
            "INSERT INTO sensor_collection (sensor, last_collected) VALUES (?1, ?2)
             ON CONFLICT (sensor) DO UPDATE
             SET last_collected = MAX(last_collected, excluded.last_collected)",
        )
        .db()?;
    for (s, t) in collected {
        let key = keys
            .get(s.as_str())
            .ok_or_else(|| StoreError::UnknownSensor(s.clone()))?;
        stmt.execute(params![key, t]).db()?;
    }
    Ok(())
}

pub(super) fn create_mission(c: &Connection, m: &NewMission) -> Result<MissionId> {
    insert_mission(c, m, None)
}

/// Inserts a mission and its stops, with the id `id` or (`None`) the next one.
fn insert_mission(c: &Connection, m: &NewMission, id: Option<i64>) -> Result<MissionId> {
    validate_mission(m)?;
    let e = &m.energy;
    let p = &m.profile;
    execute_cached(
        c,
        "INSERT INTO missions (created_at, kind, planned_at, solver, seed,
             weight_alpha, weight_beta, weight_gamma, weight_delta, anomaly_form, total_score,
             base_lat, base_lon, base_alt_m, altitude_m, cruise_speed_mps,
             travel_j, hover_j, comm_j, return_j, total_j, budget_j, distance_m, flight_time_s,
             return_distance_m, status, flown_at, summary_json, id, wind_mps, wind_from_deg)
         VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14, ?15, ?16, ?17, ?18,
                 ?19, ?20, ?21, ?22, ?23, ?24, ?25, ?26, NULL, NULL, ?27, ?28, ?29)",
        params![
            m.created_at,
            m.kind.as_str(),
            m.planned_at,
            m.solver,
            // The same 64 bits as a signed integer (SQLite has no unsigned 64-bit type).
            m.seed as i64,
            m.weights[0],
            m.weights[1],
            m.weights[2],
            m.weights[3],
            m.anomaly_form,
            m.total_score,
            p.base.lat(),
            p.base.lon(),
            p.base_alt_m,
            p.altitude_m,
            p.cruise_speed_mps,
            e.travel_j,
            e.hover_j,
            e.comm_j,
            e.return_j,
            e.total_j,
            e.budget_j,
            e.distance_m,
            e.flight_time_s,
            m.return_distance_m,
            MissionStatus::Planned.as_str(),
            id,
            p.wind_mps,
            p.wind_from_deg,
        ],
    )
    .db()?;
    let id = c.last_insert_rowid();
    let mut stop = c
        .prepare_cached(
            "INSERT INTO mission_stops (mission, position, cell, lat, lon, score, freshness,
                 redundancy, anomaly, uncertainty, leg_distance_m, leg_energy_j, collection_s,
                 hover_s, hover_j, comm_j)
             VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14, ?15, ?16)",
        )
        .db()?;
    for s in &m.stops {
        let t = s.terms;
        stop.execute(params![
            id,
            s.order,
            s.cell.to_string(),
            s.centre.lat(),
            s.centre.lon(),
            s.score,
            t.map(|t| t[0]),
            t.map(|t| t[1]),
            t.map(|t| t[2]),
            t.map(|t| t[3]),
            s.leg_distance_m,
            s.leg_energy_j,
            s.collection_s,
            s.hover_s,
            s.hover_j,
            s.comm_j
        ])
        .db()?;
    }
    Ok(MissionId(id))
}

pub(super) fn record_visits(
    c: &Connection,
    mission: MissionId,
    visits: &[VisitRecord],
    flown_at: UnixSeconds,
    amend: bool,
) -> Result<()> {
    check_visits(mission, visits)?;
    let stored: Option<(String, Option<i64>)> = c
        .query_row(
            "SELECT status, flown_at FROM missions WHERE id = ?1",
            [mission.0],
            |r| Ok((r.get(0)?, r.get(1)?)),
        )
        .optional()
        .db()?;
    check_recordable(
        mission,
        stored.as_ref().map(|(s, t)| (s.as_str(), *t)),
        flown_at,
        amend,
    )?;
    execute_cached(
        c,
        "UPDATE missions SET status = ?2, flown_at = ?3 WHERE id = ?1",
        params![mission.0, MissionStatus::Flown.as_str(), flown_at],
    )
    .db()?;
    execute_cached(c, "DELETE FROM visits WHERE mission = ?1", [mission.0]).db()?;
    let mut stmt = c
        .prepare_cached(
            "INSERT INTO visits (mission, position, cell, arrived_at, energy_j)
             VALUES (?1, ?2, ?3, ?4, ?5)",
        )
        .db()?;
    for v in visits {
        stmt.execute(params![
            mission.0,
            v.order,
            v.cell.to_string(),
            v.arrived_at,
            v.energy_j
        ])
        .db()?;
    }
    Ok(())
}

pub(super) fn config_set(c: &Connection, key: &str, value: &str) -> Result<()> {
    execute_cached(
        c,
        "INSERT INTO config (key, value) VALUES (?1, ?2)
         ON CONFLICT (key) DO UPDATE SET value = excluded.value",
        [key, value],
    )
    .db()?;
    Ok(())
}

pub(super) fn blob_put(c: &Connection, key: &str, value: &[u8]) -> Result<()> {
    execute_cached(
        c,
        "INSERT INTO blobs (key, value) VALUES (?1, ?2)
         ON CONFLICT (key) DO UPDATE SET value = excluded.value",
        params![key, value],
    )
    .db()?;
    Ok(())
}

pub(super) fn upsert_cell_metadata(c: &Connection, metadata: &[CellMetadata]) -> Result<()> {
    validate_metadata(metadata)?;
    write_metadata(c, metadata)
}

/// A stored summary row's values: count, mean, std, min, max, latest t, latest value.
type SummaryRow = (i64, f64, Option<f64>, f64, f64, i64, f64);

/// Stored summaries by (cell, modality) key and correlations (value, overlap) by (cell,
/// neighbour, modality) key.
type StoredChildRows = (
    HashMap<(i64, i64), SummaryRow>,
    HashMap<(i64, i64, i64), (f64, i64)>,
);

/// The stored child rows (summaries, correlations) of the cells `metadata` gives summaries or
/// correlations for, by (cell, modality) and (cell, neighbour, modality) keys.
fn stored_child_rows(
    c: &Connection,
    metadata: &[CellMetadata],
    cell_key: &dyn Fn(&CellIndex) -> Result<i64>,
) -> Result<StoredChildRows> {
    let mut stored_summaries: HashMap<(i64, i64), SummaryRow> = HashMap::new();
    let mut stored_correlations: HashMap<(i64, i64, i64), (f64, i64)> = HashMap::new();
    let mut summaries = c
        .prepare_cached(
            "SELECT modality, count, mean, std, min, max, latest_t, latest_value
             FROM cell_summaries WHERE cell = ?1",
        )
        .db()?;
    let mut correlations = c
        .prepare_cached(
            "SELECT neighbour, modality, correlation, overlap FROM cell_correlations
             WHERE cell = ?1",
        )
        .db()?;
    for md in metadata {
        if !md.summaries.is_empty() {
            let ck = cell_key(&md.cell)?;
            let mut rows = summaries.query([ck]).db()?;
            while let Some(r) = rows.next().db()? {
                stored_summaries.insert(
                    (ck, r.get(0).db()?),
                    (
                        r.get(1).db()?,
                        r.get(2).db()?,
                        r.get(3).db()?,
                        r.get(4).db()?,
                        r.get(5).db()?,
                        r.get(6).db()?,
                        r.get(7).db()?,
                    ),
                );
            }
        }
        if !md.correlations.is_empty() {
            let ck = cell_key(&md.cell)?;
            let mut rows = correlations.query([ck]).db()?;
            while let Some(r) = rows.next().db()? {
                stored_correlations.insert(
                    (ck, r.get(0).db()?, r.get(1).db()?),
                    (r.get(2).db()?, r.get(3).db()?),
                );
            }
        }
    }
    Ok((stored_summaries, stored_correlations))
}

/// Writes validated metadata. The child rows (summaries, correlations, anomalies) are
/// upserts that leave a row untouched when its values are already stored, instead of
/// `INSERT OR REPLACE`, which deletes and reinserts each row with its index entries and
/// foreign-key checks; summaries and correlations already stored with the same values (the
/// common case: a rescoring rewrites every cell's rows, most unchanged) are found first (one
/// primary-key range read per written cell and table) and not written at all. The table contents are the same either way.
fn write_metadata(c: &Connection, metadata: &[CellMetadata]) -> Result<()> {
    let keys = MetadataKeys {
        cells: cell_ids(c)?,
        modalities: modality_ids(c)?,
    };
    let cell_key = |c: &CellIndex| keys.cell(c);
    let modality_key = |m: &Modality| keys.modality(m);
    let (mut stored_summaries, mut stored_correlations) =
        stored_child_rows(c, metadata, &cell_key)?;
    let mut row = c
        .prepare_cached(
            "INSERT OR REPLACE INTO cell_metadata (cell, last_collected, pending_bytes,
             expected_energy_j, freshness, redundancy, anomaly, uncertainty, score, computed_at)
         VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10)",
        )
        .db()?;
    let mut clear_probs = c
        .prepare_cached("DELETE FROM cell_class_probabilities WHERE cell = ?1")
        .db()?;
    let mut prob = c.prepare_cached(
        "INSERT INTO cell_class_probabilities (cell, k, class, probability) VALUES (?1, ?2, ?3, ?4)",
    ).db()?;
    // A child row stored with the same values is left untouched (`IS NOT`: SQLite's
    // null-safe `<>`), so it costs no index or foreign-key work.
    let [summary, correlation, anomaly] = [SUMMARIES, CORRELATIONS, ANOMALIES].map(|t| {
        format!(
            "{} WHERE {}",
            t.upsert('?'),
            t.each_value(" IS NOT ", " OR ")
        )
    });
    let [mut summary, mut correlation, mut anomaly] =
        prepared(c, [&summary, &correlation, &anomaly].map(String::as_str))?;
    for md in metadata {
        // One write step per cell's metadata rows (crash-safety harness).
        crate::failpoint::step();
        let ck = cell_key(&md.cell)?;
        let s = md.scores.as_ref();
        row.execute(params![
            ck,
            md.last_collected,
            md.pending_bytes,
            md.expected_energy_j,
            s.map(|s| s.freshness),
            s.map(|s| s.redundancy),
            s.map(|s| s.anomaly),
            s.map(|s| s.uncertainty),
            s.map(|s| s.score),
            s.map(|s| s.computed_at)
        ])
        .db()?;
        clear_probs.execute([ck]).db()?;
        for (k, p) in md.class_probabilities.iter().enumerate() {
            prob.execute(params![ck, k as i64, p.class, p.probability])
                .db()?;
        }
        for su in &md.summaries {
            let st = &su.stats;
            let mk = modality_key(&su.modality)?;
            let row: SummaryRow = (
                as_i64(st.count),
                st.mean,
                st.std,
                st.min,
                st.max,
                st.latest_t,
                st.latest_value,
            );
            if stored_summaries.get(&(ck, mk)) == Some(&row) {
                continue;
            }
            let (count, mean, std, min, max, latest_t, latest_value) = row;
            summary
                .execute(params![
                    ck,
                    mk,
                    count,
                    mean,
                    std,
                    min,
                    max,
                    latest_t,
                    latest_value
                ])
                .db()?;
            // What is stored now (a key listed twice in one call: the last values win).
            stored_summaries.insert((ck, mk), row);
        }
        for co in &md.correlations {
            let key = (ck, cell_key(&co.neighbour)?, modality_key(&co.modality)?);
            if stored_correlations.get(&key) == Some(&(co.correlation, as_i64(co.overlap))) {
                continue;
            }
            correlation
                .execute(params![
                    key.0,
                    key.1,
                    key.2,
                    co.correlation,
                    as_i64(co.overlap)
                ])
                .db()?;
            stored_correlations.insert(key, (co.correlation, as_i64(co.overlap)));
        }
        for a in &md.anomalies {
            anomaly
                .execute(params![
                    ck,
                    modality_key(&a.modality)?,
                    a.t,
                    a.anomaly,
                    a.flagged
                ])
                .db()?;
        }
    }
    Ok(())
}

/// [`crate::StoreWrite::import_mission`]: the mission with its own id, then its visits.
pub(super) fn import_mission(c: &Connection, record: &MissionRecord) -> Result<()> {
    insert_mission(c, &record.mission, Some(record.id.0))?;
    match import_flight(record)? {
        ImportFlight::Nothing => Ok(()),
        ImportFlight::Record(flown_at) => {
            record_visits(c, record.id, &record.visits, flown_at, false)
        }
        ImportFlight::Cancel => cancel_mission(c, record.id),
    }
}

/// [`crate::StoreWrite::cancel_mission`].
pub(super) fn cancel_mission(c: &Connection, mission: MissionId) -> Result<()> {
    let n = c
        .execute(
            "UPDATE missions SET cancelled = 1
             WHERE id = ?1 AND status = 'planned' AND cancelled = 0",
            [mission.0],
        )
        .db()?;
    if n == 0 {
        return Err(not_cancellable(mission));
    }
    Ok(())
}

/// [`crate::StoreWrite::delete_mission`].
pub(super) fn delete_mission(c: &Connection, mission: MissionId) -> Result<()> {
    let n = c
        .execute("DELETE FROM missions WHERE id = ?1", [mission.0])
        .db()?;
    mission_deleted(mission, n as u64)
}
