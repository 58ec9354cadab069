//! The queries, written once over a `&Connection` and shared by [`super::SqliteStore`] (in a
//! read snapshot) and [`super::SqliteTx`] (inside the transaction).

use std::collections::HashMap;
use std::ops::RangeInclusive;

use gleaner_field::{Modality, SensorId, UnixSeconds};
use rusqlite::types::FromSql;
use rusqlite::{Connection, OptionalExtension, Params, Row, params};

use super::Db;
use crate::decode::{self, Column, Columns, sorted};
use crate::{
    CellMetadata, CellRecord, IngestRecord, MissionId, MissionRecord, ModalityRecord, ReadingBatch,
    Result, SensorRecord,
};

impl Columns for Row<'_> {}

/// Every row the (cached) statement `sql` returns for `params`, each read as a tuple of its
/// columns in select order (`(String, Option<f64>)` for `SELECT name, elevation_m ...`),
/// collected into `C`.
fn select<T, C>(c: &Connection, sql: &str, params: impl Params) -> Result<C>
where
    T: for<'a> TryFrom<&'a Row<'a>, Error = rusqlite::Error>,
    C: FromIterator<T>,
{
    let mut stmt = c.prepare_cached(sql).db()?;
    stmt.query_map(params, |r| T::try_from(r))
        .db()?
        .collect::<rusqlite::Result<C>>()
        .db()
}

impl<T: FromSql> Column<T> for Row<'_> {
    fn column(&self, i: usize) -> Result<T> {
        self.get(i).db()
    }
}

/// Every row the (cached) statement `sql` returns for `params`, decoded by `decode`.
fn rows<T>(
    c: &Connection,
    sql: &str,
    params: impl Params,
    mut decode: impl FnMut(&Row<'_>) -> Result<T>,
) -> Result<Vec<T>> {
    let mut stmt = c.prepare_cached(sql).db()?;
    let mut rows = stmt.query(params).db()?;
    let mut out = Vec::new();
    while let Some(r) = rows.next().db()? {
        out.push(decode(r)?);
    }
    Ok(out)
}

/// `key -> id` for every row of a `SELECT key, id` statement.
fn ids(c: &Connection, sql: &str) -> Result<HashMap<String, i64>> {
    select(c, sql, [])
}

/// `name -> id` for every stored sensor.
pub(super) fn sensor_ids(c: &Connection) -> Result<HashMap<String, i64>> {
    ids(c, "SELECT name, id FROM sensors")
}

/// `name -> id` for every stored modality.
pub(super) fn modality_ids(c: &Connection) -> Result<HashMap<String, i64>> {
    ids(c, "SELECT name, id FROM modalities")
}

/// `label -> id` for every stored cell.
pub(super) fn cell_ids(c: &Connection) -> Result<HashMap<String, i64>> {
    ids(c, "SELECT label, id FROM cells")
}

pub(super) fn schema_version(c: &Connection) -> Result<i64> {
    Ok(
        c.query_row("SELECT MAX(version) FROM schema_migrations", [], |r| {
            r.get::<_, Option<i64>>(0)
        })
        .db()?
        .unwrap_or(0),
    )
}

pub(super) fn sensors(c: &Connection) -> Result<Vec<SensorRecord>> {
    rows(
        c,
        "SELECT name, lat, lon, elevation_m, source FROM sensors ORDER BY name",
        [],
        |r| decode::sensor(r),
    )
}

pub(super) fn modalities(c: &Connection) -> Result<Vec<ModalityRecord>> {
    rows(
        c,
        "SELECT name, unit FROM modalities ORDER BY name",
        [],
        |r| decode::modality(r),
    )
}

/// Each sensor's latest `modality` reading in `range`, sorted by sensor name: one
/// primary-key seek per sensor (descending from the range's end), one row each.
pub(super) fn latest_readings(
    c: &Connection,
    modality: &Modality,
    range: RangeInclusive<UnixSeconds>,
) -> Result<Vec<(SensorId, UnixSeconds, f64)>> {
    let Some(&mkey) = modality_ids(c)?.get(modality.as_str()) else {
        return Ok(Vec::new());
    };
    let mut stmt = c
        .prepare_cached(
            "SELECT t, value FROM readings
             WHERE sensor = ?1 AND modality = ?2 AND t BETWEEN ?3 AND ?4
             ORDER BY t DESC LIMIT 1",
        )
        .db()?;
    let mut out = Vec::new();
    for (sname, skey) in sorted(sensor_ids(c)?) {
        let row: Option<(UnixSeconds, f64)> = stmt
            .query_row(params![skey, mkey, range.start(), range.end()], |r| {
                Ok((r.get(0)?, r.get(1)?))
            })
            .optional()
            .db()?;
        if let Some((t, v)) = row {
            out.push((decode::parse_sensor("sensors", sname)?, t, v));
        }
    }
    Ok(out)
}

/// The readings of `sensors` x `modalities` (both sorted by name) in `range`, in that order
/// and by time: one primary-key range seek per (sensor, modality), so the cost is the rows
/// returned plus one B-tree descent per pair.
pub(super) fn collect_readings(
    c: &Connection,
    sensors: &[(String, i64)],
    modalities: &[(String, i64)],
    range: RangeInclusive<UnixSeconds>,
) -> Result<ReadingBatch> {
    let mut stmt = c
        .prepare_cached(
            "SELECT t, value FROM readings
             WHERE sensor = ?1 AND modality = ?2 AND t BETWEEN ?3 AND ?4 ORDER BY t",
        )
        .db()?;
    decode::assemble_readings(sensors, modalities, |skey, mkey, out| {
        let mut rows = stmt
            .query(params![skey, mkey, range.start(), range.end()])
            .db()?;
        while let Some(row) = rows.next().db()? {
            out.push((row.get(0).db()?, row.get(1).db()?));
        }
        Ok(())
    })
}

pub(super) fn reading_count(c: &Connection) -> Result<u64> {
    let n: i64 = c
        .query_row("SELECT COUNT(*) FROM readings", [], |r| r.get(0))
        .db()?;
    decode::count("readings", n)
}

pub(super) fn ingests(c: &Connection) -> Result<Vec<IngestRecord>> {
    rows(
        c,
        "SELECT file_name, format, rows_read, rows_inserted, rows_unchanged, rows_skipped, at
             FROM ingests ORDER BY id",
        [],
        |r| decode::ingest(r),
    )
}

pub(super) fn cells(c: &Connection) -> Result<Vec<CellRecord>> {
    rows(
        c,
        "SELECT id, label, lat, lon, cell_size_m FROM cells ORDER BY i, j",
        [],
        |r| {
            let id: i64 = r.column(0)?;
            let sensors = rows(
                c,
                "SELECT cs.cell, s.name FROM cell_sensors cs JOIN sensors s ON s.id = cs.sensor
                 WHERE cs.cell = ?1 ORDER BY s.name",
                [id],
                |r| decode::cell_member(r),
            )?;
            decode::cell(r, sensors)
        },
    )
}

pub(super) fn cell_metadata(c: &Connection) -> Result<Vec<CellMetadata>> {
    cell_metadata_with(c, true)
}

/// The cell metadata rows without the child lists (summaries, correlations, anomalies).
pub(super) fn cell_metadata_scalars(c: &Connection) -> Result<Vec<CellMetadata>> {
    cell_metadata_with(c, false)
}

/// One cell's (`?1`) summaries, by modality, as [`decode::summary`] reads them.
const CELL_SUMMARIES: &str = "SELECT cs.cell, m.name, cs.count, cs.mean, cs.std, cs.min, cs.max,
        cs.latest_t, cs.latest_value
    FROM cell_summaries cs JOIN modalities m ON m.id = cs.modality
    WHERE cs.cell = ?1 ORDER BY m.name";

/// One cell's (`?1`) correlations, by neighbour then modality, as [`decode::correlation`]
/// reads them.
const CELL_CORRELATIONS: &str = "SELECT cc.cell, n.label, m.name, cc.correlation, cc.overlap
    FROM cell_correlations cc JOIN cells n ON n.id = cc.neighbour
        JOIN modalities m ON m.id = cc.modality
    WHERE cc.cell = ?1 ORDER BY n.i, n.j, m.name";

/// One cell's (`?1`) anomalies, by modality then time, as [`decode::anomaly`] reads them.
const CELL_ANOMALIES: &str = "SELECT ca.cell, m.name, ca.t, ca.anomaly, ca.flagged
    FROM cell_anomalies ca JOIN modalities m ON m.id = ca.modality
    WHERE ca.cell = ?1 ORDER BY m.name, ca.t";

/// The cell metadata rows, with the child lists when `children`.
fn cell_metadata_with(c: &Connection, children: bool) -> Result<Vec<CellMetadata>> {
    rows(
        c,
        "SELECT c.id, c.label, md.last_collected, md.pending_bytes, md.expected_energy_j,
                    md.freshness, md.redundancy, md.anomaly, md.uncertainty, md.score,
                    md.computed_at
             FROM cells c LEFT JOIN cell_metadata md ON md.cell = c.id ORDER BY c.i, c.j",
        [],
        |r| {
            let id: i64 = r.column(0)?;
            let mut md = decode::cell_metadata(r)?;
            md.class_probabilities = rows(
                c,
                "SELECT cell, class, probability FROM cell_class_probabilities
                 WHERE cell = ?1 ORDER BY k",
                [id],
                |r| decode::class_probability(r),
            )?;
            if children {
                md.summaries = rows(c, CELL_SUMMARIES, [id], |r| decode::summary(r))?;
                md.correlations = rows(c, CELL_CORRELATIONS, [id], |r| decode::correlation(r))?;
                md.anomalies = rows(c, CELL_ANOMALIES, [id], |r| decode::anomaly(r))?;
            }
            Ok(md)
        },
    )
}

pub(super) fn sensor_last_collected(c: &Connection) -> Result<Vec<(SensorId, UnixSeconds)>> {
    rows(
        c,
        "SELECT s.name, sc.last_collected FROM sensor_collection sc
             JOIN sensors s ON s.id = sc.sensor ORDER BY s.name",
        [],
        |r| decode::sensor_last_collected(r),
    )
}

pub(super) fn sensor_reading_counts(c: &Connection) -> Result<Vec<(SensorId, u64)>> {
    rows(
        c,
        "SELECT s.name, n.count FROM (SELECT sensor, COUNT(*) AS count FROM readings
             GROUP BY sensor) n JOIN sensors s ON s.id = n.sensor ORDER BY s.name",
        [],
        |r| decode::sensor_reading_count(r),
    )
}

/// All missions (`id` = `None`) or one, oldest first, with their stops and visits.
pub(super) fn missions(c: &Connection, id: Option<MissionId>) -> Result<Vec<MissionRecord>> {
    rows(
        c,
        concat!(
            "SELECT ",
            decode::mission_columns!(),
            " FROM missions WHERE ?1 IS NULL OR id = ?1 ORDER BY id"
        ),
        [id.map(|m| m.0)],
        |r| {
            let id: i64 = r.column(0)?;
            let stops = rows(
                c,
                "SELECT mission, position, cell, lat, lon, score, freshness, redundancy,
                        anomaly, uncertainty, leg_distance_m, leg_energy_j, collection_s,
                        hover_s, hover_j, comm_j
                 FROM mission_stops WHERE mission = ?1 ORDER BY position",
                [id],
                |r| decode::stop(r),
            )?;
            let visits = rows(
                c,
                "SELECT mission, position, cell, arrived_at, energy_j FROM visits
                 WHERE mission = ?1 ORDER BY position",
                [id],
                |r| decode::visit(r),
            )?;
            decode::mission(r, stops, visits)
        },
    )
}

pub(super) fn config_get(c: &Connection, key: &str) -> Result<Option<String>> {
    c.prepare_cached("SELECT value FROM config WHERE key = ?1")
        .db()?
        .query_row([key], |r| r.get(0))
        .optional()
        .db()
}

pub(super) fn blob_get(c: &Connection, key: &str) -> Result<Option<Vec<u8>>> {
    c.prepare_cached("SELECT value FROM blobs WHERE key = ?1")
        .db()?
        .query_row([key], |r| r.get(0))
        .optional()
        .db()
}

pub(super) fn config_entries(c: &Connection) -> Result<Vec<(String, String)>> {
    select(c, "SELECT key, value FROM config ORDER BY key", [])
}

pub(super) fn blob_keys(c: &Connection) -> Result<Vec<String>> {
    let keys: Vec<(String,)> = select(c, "SELECT key FROM blobs ORDER BY key", [])?;
    Ok(keys.into_iter().map(|(k,)| k).collect())
}
