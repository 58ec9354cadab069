//! The writes of [`super::PgTx`], each run by it inside a savepoint: a function that returns
//! an error leaves the transaction as it found it. Arguments are checked with the same
//! functions as SQLite's (`crate::checks`) before the first statement.

use std::collections::{HashMap, HashSet};
use std::io::Write;

use gleaner_field::{CellIndex, Modality, SensorId, UnixSeconds};
use postgres::Transaction;

use super::Db;
use super::read::{cell_ids, modality_ids, sensor_ids};
use crate::checks::{self, ImportFlight, MetadataKeys, UnitChange};
use crate::upsert::{ANOMALIES, CORRELATIONS, SUMMARIES};
use crate::{
    CellMetadata, CellRecord, ConflictPolicy, IngestRecord, InsertStats, MissionId, MissionRecord,
    MissionStatus, ModalityRecord, NewMission, ReadingBatch, ReplaceCellsStats, Result,
    SensorRecord, StoreError, UpsertStats, VisitRecord,
};

/// Rows per block of the binary `COPY` stream in [`insert_readings`] (one failpoint step
/// each).
const COPY_BLOCK: usize = 8192;

pub(super) fn upsert_sensors(
    c: &mut Transaction<'_>,
    sensors: &[SensorRecord],
) -> Result<UpsertStats> {
    checks::check_sensor_list(sensors)?;
    let mut stats = UpsertStats::default();
    let stored: HashMap<String, (f64, f64, Option<f64>, String)> = c
        .query(
            "SELECT name, lat, lon, elevation_m, source FROM sensors",
            &[],
        )
        .db()?
        .iter()
        .map(|r| (r.get(0), (r.get(1), r.get(2), r.get(3), r.get(4))))
        .collect();
    let insert = c
        .prepare(
            "INSERT INTO sensors (name, lat, lon, elevation_m, source) VALUES ($1, $2, $3, $4, $5)",
        )
        .db()?;
    let update = c
        .prepare(
            "UPDATE sensors SET lat = $2, lon = $3, elevation_m = $4, source = $5 WHERE name = $1",
        )
        .db()?;
    let mut done = HashSet::new();
    for s in sensors {
        if !done.insert(s.id.as_str()) {
            continue;
        }
        let (lat, lon) = (s.position.lat(), s.position.lon());
        let p: [&(dyn postgres::types::ToSql + Sync); 5] =
            [&s.id.as_str(), &lat, &lon, &s.elevation_m, &s.source];
        match stored.get(s.id.as_str()) {
            None => {
                c.execute(&insert, &p).db()?;
                stats.added.push(s.id.to_string());
            }
            Some((slat, slon, elev, source))
                if checks::sensor_unchanged((*slat, *slon, *elev, source), s) =>
            {
                stats.unchanged += 1;
            }
            Some(_) => {
                c.execute(&update, &p).db()?;
                stats.updated.push(s.id.to_string());
            }
        }
    }
    Ok(stats)
}

pub(super) fn upsert_modalities(
    c: &mut Transaction<'_>,
    modalities: &[ModalityRecord],
) -> Result<UpsertStats> {
    checks::check_modality_list(modalities)?;
    let mut stats = UpsertStats::default();
    let stored: HashMap<String, Option<String>> = c
        .query("SELECT name, unit FROM modalities", &[])
        .db()?
        .iter()
        .map(|r| (r.get(0), r.get(1)))
        .collect();
    let mut done = HashSet::new();
    for m in modalities {
        let name = m.modality.as_str();
        if !done.insert(name) {
            continue;
        }
        match checks::unit_change(m, stored.get(name).map(Option::as_deref))? {
            UnitChange::Add => {
                c.execute(
                    "INSERT INTO modalities (name, unit) VALUES ($1, $2)",
                    &[&name, &m.unit],
                )
                .db()?;
                stats.added.push(name.to_string());
            }
            UnitChange::SetUnit(unit) => {
                c.execute(
                    "UPDATE modalities SET unit = $2 WHERE name = $1",
                    &[&name, &unit],
                )
                .db()?;
                stats.updated.push(name.to_string());
            }
            UnitChange::Unchanged => stats.unchanged += 1,
        }
    }
    Ok(stats)
}

/// Fewest new rows for which an insert into an empty `readings` table drops its primary key
/// and builds it again at the end (see [`BulkLoad`]).
const BULK_MIN_ROWS: usize = 4096;

/// A bulk load in progress: the primary key of `readings` has been dropped in this
/// transaction because the table was empty when a large insert began (PostgreSQL's advice
/// for populating a database: one index build after the load is much cheaper than keeping
/// a B-tree up to date row by row). `spans` holds, per (sensor key, modality key), the time
/// span (s) of every row inserted since, so a later batch that cannot meet them needs no
/// lookup. The key is built again by [`restore_primary_key`] before anything reads the table
/// and before commit; the drop is transactional, so a crash or a rollback restores it too.
#[derive(Debug, Default, Clone)]
pub(super) struct BulkLoad {
    spans: HashMap<(i64, i64), (i64, i64)>,
}

impl BulkLoad {
    /// Whether a stored reading of (`s`, `m`) may lie in `[t_first, t_last]`.
    fn may_meet(&self, s: i64, m: i64, t_first: i64, t_last: i64) -> bool {
        self.spans
            .get(&(s, m))
            .is_some_and(|&(a, b)| a <= t_last && t_first <= b)
    }
}

/// Builds the primary key of `readings` again if a bulk load dropped it; `bulk` is then
/// `None`. Costs one sort of the table (about 0.5 s for 760,000 readings).
pub(super) fn restore_primary_key(
    c: &mut Transaction<'_>,
    bulk: &mut Option<BulkLoad>,
) -> Result<()> {
    if bulk.is_some() {
        c.batch_execute(
            "ALTER TABLE readings ADD CONSTRAINT readings_pkey PRIMARY KEY (sensor, modality, t)",
        )
        .db()?;
        *bulk = None;
    }
    Ok(())
}

/// Inserts the new rows of `batch` (classified first, see [`plan_insert`]) with one binary
/// `COPY`. `bulk` is the transaction's bulk-load state: a large insert into an empty table
/// starts one (drops the primary key); while one runs, duplicate lookups are needed only
/// for runs that meet earlier rows of the load (the key is built again first).
pub(super) fn insert_readings(
    c: &mut Transaction<'_>,
    batch: &ReadingBatch,
    policy: ConflictPolicy,
    bulk: &mut Option<BulkLoad>,
) -> Result<InsertStats> {
    let known_sensors = sensor_ids(c)?;
    let known_modalities = modality_ids(c)?;
    let sensor_keys = checks::keys(&batch.sensors, &known_sensors, SensorId::as_str, |s| {
        StoreError::UnknownSensor(s.clone())
    })?;
    let modality_keys = checks::keys(
        &batch.modalities,
        &known_modalities,
        Modality::as_str,
        |m| StoreError::UnknownModality(m.clone()),
    )?;
    if batch.rows.is_empty() {
        return Ok(InsertStats::default());
    }
    // The stored readings the batch could meet: one index range per (sensor, modality) run
    // (new data usually meets none). During a bulk load the table holds only the load's
    // rows: a run outside their spans meets nothing, one inside needs the key back first.
    let mut stored_range = None;
    let (order, fresh, stats) = checks::plan_insert(
        batch,
        &sensor_keys,
        &modality_keys,
        policy,
        |s, m, t_first, t_last, stored| {
            if let Some(load) = bulk.as_ref() {
                if !load.may_meet(s, m, t_first, t_last) {
                    return Ok(());
                }
                restore_primary_key(c, bulk)?;
            }
            let query = match &stored_range {
                Some(q) => q,
                None => stored_range.insert(
                    c.prepare(
                        "SELECT t, value FROM readings
                         WHERE sensor = $1 AND modality = $2 AND t BETWEEN $3 AND $4 ORDER BY t",
                    )
                    .db()?,
                ),
            };
            for r in c.query(query, &[&s, &m, &t_first, &t_last]).db()? {
                stored.push((r.get(0), r.get(1)));
            }
            Ok(())
        },
    )?;
    if stats.inserted == 0 {
        return Ok(stats);
    }
    if bulk.is_none()
        && stats.inserted as usize >= BULK_MIN_ROWS
        && !c
            .query_one("SELECT EXISTS (SELECT 1 FROM readings)", &[])
            .db()?
            .get::<_, bool>(0)
    {
        c.batch_execute("ALTER TABLE readings DROP CONSTRAINT readings_pkey")
            .db()?;
        *bulk = Some(BulkLoad::default());
    }
    // The new rows, in key order, as one binary COPY stream: a header, then per row a field
    // count and each field as length + big-endian bytes, then the trailer.
    let mut writer = c
        .copy_in("COPY readings (sensor, modality, t, value) FROM STDIN (FORMAT binary)")
        .db()?;
    let io = |e: std::io::Error| StoreError::Backend(format!("COPY readings: {e}"));
    let mut buf: Vec<u8> = Vec::with_capacity(COPY_BLOCK * 46 + 32);
    buf.extend_from_slice(b"PGCOPY\n\xff\r\n\0");
    buf.extend_from_slice(&0i32.to_be_bytes()); // flags
    buf.extend_from_slice(&0i32.to_be_bytes()); // header extension length
    let mut in_block = 0;
    for (&(s, m, t, row), _) in order.iter().zip(&fresh).filter(|(_, f)| **f) {
        buf.extend_from_slice(&4i16.to_be_bytes());
        for v in [s, m, t] {
            buf.extend_from_slice(&8i32.to_be_bytes());
            buf.extend_from_slice(&v.to_be_bytes());
        }
        buf.extend_from_slice(&8i32.to_be_bytes());
        buf.extend_from_slice(&batch.rows[row].value.to_be_bytes());
        if let Some(load) = bulk.as_mut() {
            let span = load.spans.entry((s, m)).or_insert((t, t));
            span.0 = span.0.min(t);
            span.1 = span.1.max(t);
        }
        in_block += 1;
        if in_block == COPY_BLOCK {
            writer.write_all(&buf).map_err(io)?;
            buf.clear();
            in_block = 0;
            crate::failpoint::step();
        }
    }
    buf.extend_from_slice(&(-1i16).to_be_bytes());
    writer.write_all(&buf).map_err(io)?;
    writer.finish().db()?;
    Ok(stats)
}

pub(super) fn record_ingest(c: &mut Transaction<'_>, ingest: &IngestRecord) -> Result<i64> {
    Ok(c.query_one(
        "INSERT INTO ingests (file_name, format, rows_read, rows_inserted, rows_unchanged,
                              rows_skipped, at)
         VALUES ($1, $2, $3, $4, $5, $6, $7) RETURNING id",
        &[
            &ingest.file_name,
            &ingest.format,
            &checks::as_i64(ingest.rows_read),
            &checks::as_i64(ingest.rows_inserted),
            &checks::as_i64(ingest.rows_unchanged),
            &checks::as_i64(ingest.rows_skipped),
            &ingest.at,
        ],
    )
    .db()?
    .get(0))
}

pub(super) fn replace_cells(
    c: &mut Transaction<'_>,
    cells: &[CellRecord],
) -> Result<ReplaceCellsStats> {
    checks::check_cells(cells)?;
    let stored = super::read::cells(c)?;
    let sensor_keys = sensor_ids(c)?;
    let plan = checks::plan_cells(&stored, cells, &sensor_keys)?;
    if !plan.gone.is_empty() {
        let gone: Vec<String> = plan.gone.iter().map(|x| x.to_string()).collect();
        c.execute("DELETE FROM cells WHERE label = ANY($1)", &[&gone])
            .db()?;
    }
    let insert_cell = c
        .prepare(
            "INSERT INTO cells (label, i, j, lat, lon, cell_size_m) VALUES ($1, $2, $3, $4, $5, $6)
             RETURNING id",
        )
        .db()?;
    let insert_member = c
        .prepare("INSERT INTO cell_sensors (cell, sensor) VALUES ($1, $2)")
        .db()?;
    for (cell, members) in &plan.added {
        let cell_key: i64 = c
            .query_one(
                &insert_cell,
                &[
                    &cell.index.to_string(),
                    &i64::from(cell.index.i),
                    &i64::from(cell.index.j),
                    &cell.centre.lat(),
                    &cell.centre.lon(),
                    &cell.cell_size_m,
                ],
            )
            .db()?
            .get(0);
        for sensor_key in members {
            c.execute(&insert_member, &[&cell_key, sensor_key]).db()?;
        }
    }
    Ok(ReplaceCellsStats {
        added: plan.added.len(),
        removed: plan.gone.len(),
        kept: plan.kept,
    })
}

pub(super) fn set_sensors_collected(
    c: &mut Transaction<'_>,
    collected: &[(SensorId, UnixSeconds)],
) -> Result<()> {
    let keys = sensor_ids(c)?;
    let stmt = c
        .prepare(
            "INSERT INTO sensor_collection (sensor, last_collected) VALUES ($1, $2)
             ON CONFLICT (sensor) DO UPDATE
             SET last_collected = GREATEST(sensor_collection.last_collected,
                                           excluded.last_collected)",
        )
        .db()?;
    for (s, t) in collected {
        let key = keys
            .get(s.as_str())
            .ok_or_else(|| StoreError::UnknownSensor(s.clone()))?;
        c.execute(&stmt, &[key, t]).db()?;
    }
    Ok(())
}

pub(super) fn create_mission(c: &mut Transaction<'_>, m: &NewMission) -> Result<MissionId> {
    insert_mission(c, m, None)
}

/// Inserts a mission and its stops, with the id `id` or (`None`) the next one.
fn insert_mission(c: &mut Transaction<'_>, m: &NewMission, id: Option<i64>) -> Result<MissionId> {
    checks::validate_mission(m)?;
    let e = &m.energy;
    let p = &m.profile;
    // The same 64 bits as a signed integer (BIGINT is signed).
    let seed = m.seed as i64;
    // The next id is max + 1, like SQLite's, not the identity sequence: sequences are not
    // transactional, so a rolled-back plan would leave a gap and a rerun a different id. Safe
    // because the project's writers are serialised by its advisory lock.
    let id: i64 = c
        .query_one(
            "INSERT INTO missions (created_at, kind, planned_at, solver, seed,
                 weight_alpha, weight_beta, weight_gamma, weight_delta, anomaly_form, total_score,
                 base_lat, base_lon, base_alt_m, altitude_m, cruise_speed_mps,
                 travel_j, hover_j, comm_j, return_j, total_j, budget_j, distance_m,
                 flight_time_s, return_distance_m, status, flown_at, summary_json, id,
                 wind_mps, wind_from_deg)
             VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9, $10, $11, $12, $13, $14, $15, $16, $17,
                     $18, $19, $20, $21, $22, $23, $24, $25, $26, NULL, NULL,
                     COALESCE($27, (SELECT COALESCE(MAX(id), 0) + 1 FROM missions)), $28, $29)
             RETURNING id",
            &[
                &m.created_at,
                &m.kind.as_str(),
                &m.planned_at,
                &m.solver,
                &seed,
                &m.weights[0],
                &m.weights[1],
                &m.weights[2],
                &m.weights[3],
                &m.anomaly_form,
                &m.total_score,
                &p.base.lat(),
                &p.base.lon(),
                &p.base_alt_m,
                &p.altitude_m,
                &p.cruise_speed_mps,
                &e.travel_j,
                &e.hover_j,
                &e.comm_j,
                &e.return_j,
                &e.total_j,
                &e.budget_j,
                &e.distance_m,
                &e.flight_time_s,
                &m.return_distance_m,
                &MissionStatus::Planned.as_str(),
                &id,
                &p.wind_mps,
                &p.wind_from_deg,
            ],
        )
        .db()?
        .get(0);
    let stop = c
        .prepare(
            "INSERT INTO mission_stops (mission, position, cell, lat, lon, score, freshness,
                 redundancy, anomaly, uncertainty, leg_distance_m, leg_energy_j, collection_s,
                 hover_s, hover_j, comm_j)
             VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9, $10, $11, $12, $13, $14, $15, $16)",
        )
        .db()?;
    for s in &m.stops {
        let t = s.terms;
        crate::failpoint::step();
        c.execute(
            &stop,
            &[
                &id,
                &i64::from(s.order),
                &s.cell.to_string(),
                &s.centre.lat(),
                &s.centre.lon(),
                &s.score,
                &t.map(|t| t[0]),
                &t.map(|t| t[1]),
                &t.map(|t| t[2]),
                &t.map(|t| t[3]),
                &s.leg_distance_m,
                &s.leg_energy_j,
                &s.collection_s,
                &s.hover_s,
                &s.hover_j,
                &s.comm_j,
            ],
        )
        .db()?;
    }
    Ok(MissionId(id))
}

pub(super) fn record_visits(
    c: &mut Transaction<'_>,
    mission: MissionId,
    visits: &[VisitRecord],
    flown_at: UnixSeconds,
    amend: bool,
) -> Result<()> {
    checks::check_visits(mission, visits)?;
    // FOR UPDATE: the row stays locked to the end of the transaction.
    let stored = c
        .query_opt(
            "SELECT status, flown_at FROM missions WHERE id = $1 FOR UPDATE",
            &[&mission.0],
        )
        .db()?;
    checks::check_recordable(
        mission,
        stored.as_ref().map(|row| (row.get(0), row.get(1))),
        flown_at,
        amend,
    )?;
    c.execute(
        "UPDATE missions SET status = $2, flown_at = $3 WHERE id = $1",
        &[&mission.0, &MissionStatus::Flown.as_str(), &flown_at],
    )
    .db()?;
    c.execute("DELETE FROM visits WHERE mission = $1", &[&mission.0])
        .db()?;
    let stmt = c
        .prepare(
            "INSERT INTO visits (mission, position, cell, arrived_at, energy_j)
             VALUES ($1, $2, $3, $4, $5)",
        )
        .db()?;
    for v in visits {
        crate::failpoint::step();
        c.execute(
            &stmt,
            &[
                &mission.0,
                &i64::from(v.order),
                &v.cell.to_string(),
                &v.arrived_at,
                &v.energy_j,
            ],
        )
        .db()?;
    }
    Ok(())
}

pub(super) fn config_set(c: &mut Transaction<'_>, key: &str, value: &str) -> Result<()> {
    c.execute(
        "INSERT INTO config (key, value) VALUES ($1, $2)
         ON CONFLICT (key) DO UPDATE SET value = excluded.value",
        &[&key, &value],
    )
    .db()?;
    Ok(())
}

pub(super) fn blob_put(c: &mut Transaction<'_>, key: &str, value: &[u8]) -> Result<()> {
    c.execute(
        "INSERT INTO blobs (key, value) VALUES ($1, $2)
         ON CONFLICT (key) DO UPDATE SET value = excluded.value",
        &[&key, &value],
    )
    .db()?;
    Ok(())
}

pub(super) fn upsert_cell_metadata(
    c: &mut Transaction<'_>,
    metadata: &[CellMetadata],
) -> Result<()> {
    checks::validate_metadata(metadata)?;
    let keys = MetadataKeys {
        cells: cell_ids(c)?,
        modalities: modality_ids(c)?,
    };
    let cell_key = |c: &CellIndex| keys.cell(c);
    let modality_key = |m: &Modality| keys.modality(m);
    let row = c
        .prepare(
            "INSERT INTO cell_metadata (cell, last_collected, pending_bytes, expected_energy_j,
                 freshness, redundancy, anomaly, uncertainty, score, computed_at)
             VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9, $10)
             ON CONFLICT (cell) DO UPDATE SET last_collected = excluded.last_collected,
                 pending_bytes = excluded.pending_bytes,
                 expected_energy_j = excluded.expected_energy_j,
                 freshness = excluded.freshness, redundancy = excluded.redundancy,
                 anomaly = excluded.anomaly, uncertainty = excluded.uncertainty,
                 score = excluded.score, computed_at = excluded.computed_at",
        )
        .db()?;
    let clear_probs = c
        .prepare("DELETE FROM cell_class_probabilities WHERE cell = $1")
        .db()?;
    let prob = c
        .prepare(
            "INSERT INTO cell_class_probabilities (cell, k, class, probability)
             VALUES ($1, $2, $3, $4)",
        )
        .db()?;
    let [summary, correlation, anomaly] =
        [SUMMARIES, CORRELATIONS, ANOMALIES].map(|t| t.upsert('$'));
    let summary = c.prepare(&summary).db()?;
    let correlation = c.prepare(&correlation).db()?;
    let anomaly = c.prepare(&anomaly).db()?;
    for md in metadata {
        // One write step per cell's metadata rows (crash-safety harness).
        crate::failpoint::step();
        let ck = cell_key(&md.cell)?;
        let s = md.scores.as_ref();
        c.execute(
            &row,
            &[
                &ck,
                &md.last_collected,
                &md.pending_bytes,
                &md.expected_energy_j,
                &s.map(|s| s.freshness),
                &s.map(|s| s.redundancy),
                &s.map(|s| s.anomaly),
                &s.map(|s| s.uncertainty),
                &s.map(|s| s.score),
                &s.map(|s| s.computed_at),
            ],
        )
        .db()?;
        c.execute(&clear_probs, &[&ck]).db()?;
        for (k, p) in md.class_probabilities.iter().enumerate() {
            c.execute(&prob, &[&ck, &(k as i64), &p.class, &p.probability])
                .db()?;
        }
        for su in &md.summaries {
            let st = &su.stats;
            c.execute(
                &summary,
                &[
                    &ck,
                    &modality_key(&su.modality)?,
                    &checks::as_i64(st.count),
                    &st.mean,
                    &st.std,
                    &st.min,
                    &st.max,
                    &st.latest_t,
                    &st.latest_value,
                ],
            )
            .db()?;
        }
        for co in &md.correlations {
            c.execute(
                &correlation,
                &[
                    &ck,
                    &cell_key(&co.neighbour)?,
                    &modality_key(&co.modality)?,
                    &co.correlation,
                    &checks::as_i64(co.overlap),
                ],
            )
            .db()?;
        }
        for a in &md.anomalies {
            c.execute(
                &anomaly,
                &[
                    &ck,
                    &modality_key(&a.modality)?,
                    &a.t,
                    &a.anomaly,
                    &a.flagged,
                ],
            )
            .db()?;
        }
    }
    Ok(())
}

/// [`crate::StoreWrite::import_mission`]: the mission with its own id (the id sequence moved
/// past it), then its visits.
pub(super) fn import_mission(c: &mut Transaction<'_>, record: &MissionRecord) -> Result<()> {
    insert_mission(c, &record.mission, Some(record.id.0))?;
    c.execute(
        "SELECT setval(pg_get_serial_sequence('missions', 'id'),
                       GREATEST((SELECT MAX(id) FROM missions), 1))",
        &[],
    )
    .db()?;
    match checks::import_flight(record)? {
        ImportFlight::Nothing => Ok(()),
        ImportFlight::Record(flown_at) => {
            record_visits(c, record.id, &record.visits, flown_at, false)
        }
        ImportFlight::Cancel => cancel_mission(c, record.id),
    }
}

/// [`crate::StoreWrite::cancel_mission`].
pub(super) fn cancel_mission(c: &mut Transaction<'_>, mission: MissionId) -> Result<()> {
    let n = c
        .execute(
            "UPDATE missions SET cancelled = TRUE
             WHERE id = $1 AND status = 'planned' AND NOT cancelled",
            &[&mission.0],
        )
        .db()?;
    if n == 0 {
        return Err(checks::not_cancellable(mission));
    }
    Ok(())
}

/// [`crate::StoreWrite::delete_mission`].
pub(super) fn delete_mission(c: &mut Transaction<'_>, mission: MissionId) -> Result<()> {
    let n = c
        .execute("DELETE FROM missions WHERE id = $1", &[&mission.0])
        .db()?;
    checks::mission_deleted(mission, n)
}
