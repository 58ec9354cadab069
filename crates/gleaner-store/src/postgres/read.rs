//! The queries, written once over a `&mut Transaction` and shared by [`super::PgStore`] (in a
//! read-only snapshot) and [`super::PgTx`] (inside the write transaction). Parent rows and
//! their children are fetched with one query per table and grouped in Rust, so a read costs
//! a fixed number of round trips whatever the number of cells or missions.

use std::collections::HashMap;
use std::ops::RangeInclusive;

use gleaner_field::{Modality, SensorId, UnixSeconds};
use postgres::types::{FromSql, ToSql};
use postgres::{Row, Transaction};

use super::Db;
use crate::decode::{self, Column, Columns};
use crate::{
    CellMetadata, CellRecord, IngestRecord, MissionId, MissionRecord, ModalityRecord, ReadingBatch,
    Result, SensorRecord,
};

impl<T: for<'a> FromSql<'a>> Column<T> for Row {
    /// Column `i` as a `T`; a type that does not match the column is a programming error and
    /// panics, as [`Row::get`] does.
    fn column(&self, i: usize) -> Result<T> {
        Ok(self.get(i))
    }
}

impl Columns for Row {}

/// Every row `sql` returns for `params`, decoded by `decode`.
fn rows<T>(
    c: &mut Transaction<'_>,
    sql: &str,
    params: &[&(dyn ToSql + Sync)],
    mut decode: impl FnMut(&Row) -> Result<T>,
) -> Result<Vec<T>> {
    c.query(sql, params).db()?.iter().map(&mut decode).collect()
}

/// `key -> id` for every row of a `SELECT key, id` statement.
fn ids(c: &mut Transaction<'_>, sql: &str) -> Result<HashMap<String, i64>> {
    Ok(c.query(sql, &[])
        .db()?
        .iter()
        .map(|r| (r.get(0), r.get(1)))
        .collect())
}

/// `name -> id` for every stored sensor.
pub(super) fn sensor_ids(c: &mut Transaction<'_>) -> Result<HashMap<String, i64>> {
    ids(c, "SELECT name, id FROM sensors")
}

/// `name -> id` for every stored modality.
pub(super) fn modality_ids(c: &mut Transaction<'_>) -> Result<HashMap<String, i64>> {
    ids(c, "SELECT name, id FROM modalities")
}

/// `label -> id` for every stored cell.
pub(super) fn cell_ids(c: &mut Transaction<'_>) -> Result<HashMap<String, i64>> {
    ids(c, "SELECT label, id FROM cells")
}

pub(super) fn schema_version(c: &mut Transaction<'_>) -> Result<i64> {
    Ok(c.query_one(
        "SELECT COALESCE(MAX(version), 0)::BIGINT FROM schema_migrations",
        &[],
    )
    .db()?
    .get(0))
}

pub(super) fn sensors(c: &mut Transaction<'_>) -> Result<Vec<SensorRecord>> {
    rows(
        c,
        "SELECT name, lat, lon, elevation_m, source FROM sensors ORDER BY name COLLATE \"C\"",
        &[],
        decode::sensor,
    )
}

pub(super) fn modalities(c: &mut Transaction<'_>) -> Result<Vec<ModalityRecord>> {
    rows(
        c,
        "SELECT name, unit FROM modalities ORDER BY name COLLATE \"C\"",
        &[],
        decode::modality,
    )
}

/// Each sensor's latest `modality` reading in `range`, sorted by sensor name: one query, the
/// server's `DISTINCT ON` taking the newest row of each sensor's primary-key range.
pub(super) fn latest_readings(
    c: &mut Transaction<'_>,
    modality: &Modality,
    range: RangeInclusive<UnixSeconds>,
) -> Result<Vec<(SensorId, UnixSeconds, f64)>> {
    let Some(&mkey) = modality_ids(c)?.get(modality.as_str()) else {
        return Ok(Vec::new());
    };
    let names: HashMap<i64, String> = sensor_ids(c)?.into_iter().map(|(n, k)| (k, n)).collect();
    let rows = c
        .query(
            "SELECT DISTINCT ON (sensor) sensor, t, value FROM readings
             WHERE modality = $1 AND t BETWEEN $2 AND $3
             ORDER BY sensor, t DESC",
            &[&mkey, range.start(), range.end()],
        )
        .db()?;
    let mut out = Vec::with_capacity(rows.len());
    for r in &rows {
        let key: i64 = r.get(0);
        let Some(name) = names.get(&key) else {
            continue;
        };
        out.push((name.clone(), r.get::<_, i64>(1), r.get::<_, f64>(2)));
    }
    out.sort_by(|a, b| a.0.cmp(&b.0));
    out.into_iter()
        .map(|(n, t, v)| Ok((decode::parse_sensor("sensors", n)?, t, v)))
        .collect()
}

/// The readings of `sensors` x `modalities` (both sorted by name) in `range`, in that order
/// and by time. One query, ordered by the primary key (sensor key, modality key, t) so the
/// server streams an index range; the rows are then regrouped by name order in Rust (keys
/// and names need not sort alike).
pub(super) fn collect_readings(
    c: &mut Transaction<'_>,
    sensors: &[(String, i64)],
    modalities: &[(String, i64)],
    range: RangeInclusive<UnixSeconds>,
) -> Result<ReadingBatch> {
    if sensors.is_empty() || modalities.is_empty() {
        return Ok(ReadingBatch::new());
    }
    let sensor_keys: Vec<i64> = sensors.iter().map(|s| s.1).collect();
    let modality_keys: Vec<i64> = modalities.iter().map(|m| m.1).collect();
    let rows = c
        .query(
            "SELECT sensor, modality, t, value FROM readings
             WHERE sensor = ANY($1) AND modality = ANY($2) AND t BETWEEN $3 AND $4
             ORDER BY sensor, modality, t",
            &[&sensor_keys, &modality_keys, range.start(), range.end()],
        )
        .db()?;
    // Runs of one (sensor, modality) pair: key -> (first row, count).
    let mut runs: HashMap<(i64, i64), (usize, usize)> = HashMap::new();
    for (k, r) in rows.iter().enumerate() {
        let key = (r.get::<_, i64>(0), r.get::<_, i64>(1));
        runs.entry(key).or_insert((k, 0)).1 += 1;
    }
    decode::assemble_readings(sensors, modalities, |skey, mkey, out| {
        if let Some(&(first, n)) = runs.get(&(skey, mkey)) {
            out.extend(rows[first..first + n].iter().map(|r| (r.get(2), r.get(3))));
        }
        Ok(())
    })
}

pub(super) fn reading_count(c: &mut Transaction<'_>) -> Result<u64> {
    let n: i64 = c
        .query_one("SELECT COUNT(*) FROM readings", &[])
        .db()?
        .get(0);
    decode::count("readings", n)
}

pub(super) fn ingests(c: &mut Transaction<'_>) -> Result<Vec<IngestRecord>> {
    rows(
        c,
        "SELECT file_name, format, rows_read, rows_inserted, rows_unchanged, rows_skipped, at
         FROM ingests ORDER BY id",
        &[],
        decode::ingest,
    )
}

/// Rows of a child query grouped by their first column (the parent's key), in query order,
/// each decoded by `decode`.
fn grouped<T>(
    c: &mut Transaction<'_>,
    sql: &str,
    params: &[&(dyn ToSql + Sync)],
    mut decode: impl FnMut(&Row) -> Result<T>,
) -> Result<HashMap<i64, Vec<T>>> {
    let mut out: HashMap<i64, Vec<T>> = HashMap::new();
    for r in c.query(sql, params).db()? {
        out.entry(r.get(0)).or_default().push(decode(&r)?);
    }
    Ok(out)
}

pub(super) fn cells(c: &mut Transaction<'_>) -> Result<Vec<CellRecord>> {
    let mut members = grouped(
        c,
        "SELECT cs.cell, s.name FROM cell_sensors cs JOIN sensors s ON s.id = cs.sensor
         ORDER BY cs.cell, s.name COLLATE \"C\"",
        &[],
        decode::cell_member,
    )?;
    rows(
        c,
        "SELECT id, label, lat, lon, cell_size_m FROM cells ORDER BY i, j",
        &[],
        |r| {
            let id: i64 = r.get(0);
            decode::cell(r, members.remove(&id).unwrap_or_default())
        },
    )
}

pub(super) fn cell_metadata(c: &mut Transaction<'_>) -> Result<Vec<CellMetadata>> {
    cell_metadata_with(c, true)
}

/// The cell metadata rows without the child lists (summaries, correlations, anomalies).
pub(super) fn cell_metadata_scalars(c: &mut Transaction<'_>) -> Result<Vec<CellMetadata>> {
    cell_metadata_with(c, false)
}

/// Every cell's summaries, by cell then modality, as [`decode::summary`] reads them.
const SUMMARIES: &str = "SELECT cs.cell, m.name, cs.count, cs.mean, cs.std, cs.min, cs.max,
        cs.latest_t, cs.latest_value
    FROM cell_summaries cs JOIN modalities m ON m.id = cs.modality
    ORDER BY cs.cell, m.name COLLATE \"C\"";

/// Every cell's correlations, by cell, neighbour, then modality, as [`decode::correlation`]
/// reads them.
const CORRELATIONS: &str = "SELECT cc.cell, n.label, m.name, cc.correlation, cc.overlap
    FROM cell_correlations cc JOIN cells n ON n.id = cc.neighbour
        JOIN modalities m ON m.id = cc.modality
    ORDER BY cc.cell, n.i, n.j, m.name COLLATE \"C\"";

/// Every cell's anomalies, by cell, modality, then time, as [`decode::anomaly`] reads them.
const ANOMALIES: &str = "SELECT ca.cell, m.name, ca.t, ca.anomaly, ca.flagged
    FROM cell_anomalies ca JOIN modalities m ON m.id = ca.modality
    ORDER BY ca.cell, m.name COLLATE \"C\", ca.t";

/// The cell metadata rows, with the child lists when `children`.
fn cell_metadata_with(c: &mut Transaction<'_>, children: bool) -> Result<Vec<CellMetadata>> {
    let rows = c
        .query(
            "SELECT c.id, c.label, md.last_collected, md.pending_bytes, md.expected_energy_j,
                    md.freshness, md.redundancy, md.anomaly, md.uncertainty, md.score,
                    md.computed_at
             FROM cells c LEFT JOIN cell_metadata md ON md.cell = c.id ORDER BY c.i, c.j",
            &[],
        )
        .db()?;
    let mut probs = grouped(
        c,
        "SELECT cell, class, probability FROM cell_class_probabilities ORDER BY cell, k",
        &[],
        decode::class_probability,
    )?;
    // The child tables' rows grouped by cell, or none when the children are not wanted.
    let (mut summaries, mut correlations, mut anomalies) = if children {
        (
            grouped(c, SUMMARIES, &[], decode::summary)?,
            grouped(c, CORRELATIONS, &[], decode::correlation)?,
            grouped(c, ANOMALIES, &[], decode::anomaly)?,
        )
    } else {
        Default::default()
    };
    let mut out = Vec::with_capacity(rows.len());
    for r in &rows {
        let id: i64 = r.get(0);
        let mut md = decode::cell_metadata(r)?;
        md.class_probabilities = probs.remove(&id).unwrap_or_default();
        md.summaries = summaries.remove(&id).unwrap_or_default();
        md.correlations = correlations.remove(&id).unwrap_or_default();
        md.anomalies = anomalies.remove(&id).unwrap_or_default();
        out.push(md);
    }
    Ok(out)
}

pub(super) fn sensor_last_collected(
    c: &mut Transaction<'_>,
) -> Result<Vec<(SensorId, UnixSeconds)>> {
    rows(
        c,
        "SELECT s.name, sc.last_collected FROM sensor_collection sc
         JOIN sensors s ON s.id = sc.sensor ORDER BY s.name COLLATE \"C\"",
        &[],
        decode::sensor_last_collected,
    )
}

pub(super) fn sensor_reading_counts(c: &mut Transaction<'_>) -> Result<Vec<(SensorId, u64)>> {
    rows(
        c,
        "SELECT s.name, n.count FROM (SELECT sensor, COUNT(*) AS count FROM readings
             GROUP BY sensor) n JOIN sensors s ON s.id = n.sensor ORDER BY s.name COLLATE \"C\"",
        &[],
        decode::sensor_reading_count,
    )
}

/// All missions (`id` = `None`) or one, oldest first, with their stops and visits.
pub(super) fn missions(
    c: &mut Transaction<'_>,
    id: Option<MissionId>,
) -> Result<Vec<MissionRecord>> {
    // -1 never names a mission (ids start at 1): "all" without a second query text.
    let only = id.map_or(-1, |m| m.0);
    let mut stops = grouped(
        c,
        "SELECT mission, position, cell, lat, lon, score, freshness, redundancy, anomaly,
                uncertainty, leg_distance_m, leg_energy_j, collection_s, hover_s, hover_j,
                comm_j
         FROM mission_stops WHERE $1::BIGINT = -1 OR mission = $1::BIGINT ORDER BY mission, position",
        &[&only],
        decode::stop,
    )?;
    let mut visits = grouped(
        c,
        "SELECT mission, position, cell, arrived_at, energy_j FROM visits
         WHERE $1::BIGINT = -1 OR mission = $1::BIGINT ORDER BY mission, position",
        &[&only],
        decode::visit,
    )?;
    rows(
        c,
        concat!(
            "SELECT ",
            decode::mission_columns!(),
            " FROM missions WHERE $1::BIGINT = -1 OR id = $1::BIGINT ORDER BY id"
        ),
        &[&only],
        |r| {
            let id: i64 = r.get(0);
            let stops = stops.remove(&id).unwrap_or_default();
            decode::mission(r, stops, visits.remove(&id).unwrap_or_default())
        },
    )
}

pub(super) fn config_get(c: &mut Transaction<'_>, key: &str) -> Result<Option<String>> {
    Ok(
        c.query_opt("SELECT value FROM config WHERE key = $1", &[&key])
            .db()?
            .map(|r| r.get(0)),
    )
}

pub(super) fn blob_get(c: &mut Transaction<'_>, key: &str) -> Result<Option<Vec<u8>>> {
    Ok(
        c.query_opt("SELECT value FROM blobs WHERE key = $1", &[&key])
            .db()?
            .map(|r| r.get(0)),
    )
}

/// Every constraint the server would enforce, checked again over the stored rows (the server
/// enforced them on write; this proves nothing was lost or half-written around a crash):
/// dangling children and rows breaking the model's invariants, as messages.
pub(super) fn integrity_check(c: &mut Transaction<'_>) -> Result<Vec<String>> {
    let checks: &[(&str, &str)] = &[
        (
            "readings of unknown sensors",
            "SELECT COUNT(*) FROM readings r WHERE NOT EXISTS (SELECT 1 FROM sensors s WHERE s.id = r.sensor)",
        ),
        (
            "readings of unknown modalities",
            "SELECT COUNT(*) FROM readings r WHERE NOT EXISTS (SELECT 1 FROM modalities m WHERE m.id = r.modality)",
        ),
        (
            "cell members of unknown cells or sensors",
            "SELECT COUNT(*) FROM cell_sensors cs WHERE NOT EXISTS (SELECT 1 FROM cells c WHERE c.id = cs.cell) OR NOT EXISTS (SELECT 1 FROM sensors s WHERE s.id = cs.sensor)",
        ),
        (
            "stops of unknown missions",
            "SELECT COUNT(*) FROM mission_stops st WHERE NOT EXISTS (SELECT 1 FROM missions m WHERE m.id = st.mission)",
        ),
        (
            "visits of unknown missions",
            "SELECT COUNT(*) FROM visits v WHERE NOT EXISTS (SELECT 1 FROM missions m WHERE m.id = v.mission)",
        ),
        (
            "flown missions without flown_at or planned ones with it",
            "SELECT COUNT(*) FROM missions WHERE (status = 'flown') <> (flown_at IS NOT NULL)",
        ),
        (
            "metadata of unknown cells",
            "SELECT COUNT(*) FROM cell_metadata md WHERE NOT EXISTS (SELECT 1 FROM cells c WHERE c.id = md.cell)",
        ),
        (
            "non-finite reading values",
            "SELECT COUNT(*) FROM readings WHERE value = 'NaN'::float8 OR value IN ('Infinity'::float8, '-Infinity'::float8)",
        ),
    ];
    let mut problems = Vec::new();
    for (what, sql) in checks {
        let n: i64 = c.query_one(*sql, &[]).db()?.get(0);
        if n != 0 {
            problems.push(format!("{n} {what}"));
        }
    }
    Ok(problems)
}

pub(super) fn config_entries(c: &mut Transaction<'_>) -> Result<Vec<(String, String)>> {
    Ok(c.query(
        "SELECT key, value FROM config ORDER BY key COLLATE \"C\"",
        &[],
    )
    .db()?
    .iter()
    .map(|r| (r.get(0), r.get(1)))
    .collect())
}

pub(super) fn blob_keys(c: &mut Transaction<'_>) -> Result<Vec<String>> {
    Ok(
        c.query("SELECT key FROM blobs ORDER BY key COLLATE \"C\"", &[])
            .db()?
            .iter()
            .map(|r| r.get(0))
            .collect(),
    )
}
