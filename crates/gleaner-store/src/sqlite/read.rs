//! The queries, written once over a `&Connection` and shared by [`super::SqliteStore`] (in a
//! read snapshot) and [`super::SqliteTx`] (inside the transaction).

use std::collections::HashMap;
use std::ops::RangeInclusive;

use gleaner_field::{CellIndex, LatLon, Modality, SensorId, UnixSeconds};
use rusqlite::{Connection, OptionalExtension, Params, Row, params};

use super::Db;
use crate::{
    AnomalyRecord, CellMetadata, CellRecord, CellScores, ClassProbability, Correlation,
    EnergyBreakdown, FlightProfile, IngestRecord, MissionId, MissionKind, MissionRecord,
    MissionStatus, ModalityRecord, ModalitySummary, NewMission, Reading, ReadingBatch, Result,
    SensorRecord, SeriesStats, StopRecord, StoreError, VisitRecord,
};

pub(super) fn parse_sensor(table: &'static str, name: String) -> Result<SensorId> {
    SensorId::new(name).map_err(|e| StoreError::Corrupt {
        table,
        detail: e.to_string(),
    })
}

pub(super) fn parse_modality(table: &'static str, name: &str) -> Result<Modality> {
    Modality::new(name).map_err(|e| StoreError::Corrupt {
        table,
        detail: e.to_string(),
    })
}

fn parse_latlon(table: &'static str, lat: f64, lon: f64) -> Result<LatLon> {
    LatLon::new(lat, lon).map_err(|e| StoreError::Corrupt {
        table,
        detail: e.to_string(),
    })
}

fn parse_cell(table: &'static str, label: &str) -> Result<CellIndex> {
    CellIndex::parse(label).ok_or_else(|| StoreError::Corrupt {
        table,
        detail: format!("cell label {label:?} is not of the form x<i>y<j>"),
    })
}

/// A count read back as `u64` (SQLite stores it as a signed integer).
fn count(table: &'static str, n: i64) -> Result<u64> {
    u64::try_from(n).map_err(|_| StoreError::Corrupt {
        table,
        detail: format!("negative count {n}"),
    })
}

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
    let rows: Vec<(String, f64, f64, Option<f64>, String)> = select(
        c,
        "SELECT name, lat, lon, elevation_m, source FROM sensors ORDER BY name",
        [],
    )?;
    let mut out = Vec::with_capacity(rows.len());
    for (name, lat, lon, elevation_m, source) in rows {
        out.push(SensorRecord {
            id: parse_sensor("sensors", name)?,
            position: parse_latlon("sensors", lat, lon)?,
            elevation_m,
            source,
        });
    }
    Ok(out)
}

pub(super) fn modalities(c: &Connection) -> Result<Vec<ModalityRecord>> {
    let rows: Vec<(String, Option<String>)> =
        select(c, "SELECT name, unit FROM modalities ORDER BY name", [])?;
    let mut out = Vec::with_capacity(rows.len());
    for (name, unit) in rows {
        out.push(ModalityRecord {
            modality: parse_modality("modalities", &name)?,
            unit,
        });
    }
    Ok(out)
}

/// `(name, key)` pairs sorted by name.
fn sorted(map: HashMap<String, i64>) -> Vec<(String, i64)> {
    let mut v: Vec<(String, i64)> = map.into_iter().collect();
    v.sort();
    v
}

pub(super) fn readings_for(
    c: &Connection,
    modality: Option<&Modality>,
    range: RangeInclusive<UnixSeconds>,
) -> Result<ReadingBatch> {
    let sensors = sorted(sensor_ids(c)?);
    let mut modalities = sorted(modality_ids(c)?);
    modalities.retain(|(name, _)| modality.is_none_or(|m| m.as_str() == name));
    collect_readings(c, &sensors, &modalities, range)
}

pub(super) fn readings_of_sensors(
    c: &Connection,
    sensors: &[SensorId],
    range: RangeInclusive<UnixSeconds>,
) -> Result<ReadingBatch> {
    let ids = sensor_ids(c)?;
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
    let modalities = sorted(modality_ids(c)?);
    collect_readings(c, &wanted, &modalities, range)
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
            out.push((parse_sensor("sensors", sname)?, t, v));
        }
    }
    Ok(out)
}

/// The readings of `sensors` x `modalities` (both sorted by name) in `range`, in that order
/// and by time: one primary-key range seek per (sensor, modality), so the cost is the rows
/// returned plus one B-tree descent per pair.
fn collect_readings(
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
    let mut batch = ReadingBatch::new();
    let mut modality_index: HashMap<i64, u32> = HashMap::new();
    for (sname, skey) in sensors {
        let mut sensor_index = None;
        for (mname, mkey) in modalities {
            let mut rows = stmt
                .query(params![skey, mkey, range.start(), range.end()])
                .db()?;
            while let Some(row) = rows.next().db()? {
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
                batch.rows.push(Reading {
                    sensor: s,
                    modality: m,
                    t: row.get(0).db()?,
                    value: row.get(1).db()?,
                });
            }
        }
    }
    Ok(batch)
}

pub(super) fn reading_count(c: &Connection) -> Result<u64> {
    let n: i64 = c
        .query_row("SELECT COUNT(*) FROM readings", [], |r| r.get(0))
        .db()?;
    count("readings", n)
}

pub(super) fn ingests(c: &Connection) -> Result<Vec<IngestRecord>> {
    let rows: Vec<(String, String, i64, i64, i64, i64, i64)> = select(
        c,
        "SELECT file_name, format, rows_read, rows_inserted, rows_unchanged, rows_skipped, at
             FROM ingests ORDER BY id",
        [],
    )?;
    let mut out = Vec::with_capacity(rows.len());
    for (file_name, format, read, inserted, unchanged, skipped, at) in rows {
        out.push(IngestRecord {
            file_name,
            format,
            rows_read: count("ingests", read)?,
            rows_inserted: count("ingests", inserted)?,
            rows_unchanged: count("ingests", unchanged)?,
            rows_skipped: count("ingests", skipped)?,
            at,
        });
    }
    Ok(out)
}

pub(super) fn cells(c: &Connection) -> Result<Vec<CellRecord>> {
    let rows: Vec<(i64, String, f64, f64, f64)> = select(
        c,
        "SELECT id, label, lat, lon, cell_size_m FROM cells ORDER BY i, j",
        [],
    )?;
    let mut out = Vec::with_capacity(rows.len());
    for (id, label, lat, lon, cell_size_m) in rows {
        let names: Vec<(String,)> = select(
            c,
            "SELECT s.name FROM cell_sensors cs JOIN sensors s ON s.id = cs.sensor
             WHERE cs.cell = ?1 ORDER BY s.name",
            [id],
        )?;
        let sensors = names
            .into_iter()
            .map(|(n,)| parse_sensor("cell_sensors", n))
            .collect::<Result<_>>()?;
        out.push(CellRecord {
            index: parse_cell("cells", &label)?,
            centre: parse_latlon("cells", lat, lon)?,
            cell_size_m,
            sensors,
        });
    }
    Ok(out)
}

pub(super) fn cell_metadata(c: &Connection) -> Result<Vec<CellMetadata>> {
    cell_metadata_with(c, true)
}

/// The cell metadata rows without the child lists (summaries, correlations, anomalies).
pub(super) fn cell_metadata_scalars(c: &Connection) -> Result<Vec<CellMetadata>> {
    cell_metadata_with(c, false)
}

/// The cell metadata rows, with the child lists when `children`.
fn cell_metadata_with(c: &Connection, children: bool) -> Result<Vec<CellMetadata>> {
    type MetaRow = (
        i64,
        String,
        Option<i64>,
        Option<f64>,
        Option<f64>,
        Option<f64>,
        Option<f64>,
        Option<f64>,
        Option<f64>,
        Option<f64>,
        Option<i64>,
    );
    let rows: Vec<MetaRow> = select(
        c,
        "SELECT c.id, c.label, md.last_collected, md.pending_bytes, md.expected_energy_j,
                    md.freshness, md.redundancy, md.anomaly, md.uncertainty, md.score,
                    md.computed_at
             FROM cells c LEFT JOIN cell_metadata md ON md.cell = c.id ORDER BY c.i, c.j",
        [],
    )?;
    let mut out = Vec::with_capacity(rows.len());
    for (id, label, last_collected, pending_bytes, expected_energy_j, f, r, a, u, s, at) in rows {
        let mut md = CellMetadata::new(parse_cell("cells", &label)?);
        md.last_collected = last_collected;
        md.pending_bytes = pending_bytes;
        md.expected_energy_j = expected_energy_j;
        if let (Some(f), Some(r), Some(a), Some(u), Some(s), Some(at)) = (f, r, a, u, s, at) {
            md.scores = Some(CellScores {
                freshness: f,
                redundancy: r,
                anomaly: a,
                uncertainty: u,
                score: s,
                computed_at: at,
            });
        }
        let prows: Vec<(String, f64)> = select(
            c,
            "SELECT class, probability FROM cell_class_probabilities WHERE cell = ?1 ORDER BY k",
            [id],
        )?;
        for (class, probability) in prows {
            md.class_probabilities
                .push(ClassProbability { class, probability });
        }
        if children {
            type SummaryRow = (String, i64, f64, Option<f64>, f64, f64, i64, f64);
            let srows: Vec<SummaryRow> = select(
                c,
                "SELECT m.name, cs.count, cs.mean, cs.std, cs.min, cs.max, cs.latest_t, cs.latest_value
                 FROM cell_summaries cs JOIN modalities m ON m.id = cs.modality
                 WHERE cs.cell = ?1 ORDER BY m.name",
                [id],
            )?;
            for (m, n, mean, std, min, max, latest_t, latest_value) in srows {
                md.summaries.push(ModalitySummary {
                    modality: parse_modality("cell_summaries", &m)?,
                    stats: SeriesStats {
                        count: count("cell_summaries", n)?,
                        mean,
                        std,
                        min,
                        max,
                        latest_t,
                        latest_value,
                    },
                });
            }
            let crows: Vec<(String, String, f64, i64)> = select(
                c,
                "SELECT n.label, m.name, cc.correlation, cc.overlap
                 FROM cell_correlations cc JOIN cells n ON n.id = cc.neighbour
                      JOIN modalities m ON m.id = cc.modality
                 WHERE cc.cell = ?1 ORDER BY n.i, n.j, m.name",
                [id],
            )?;
            for (n, m, correlation, overlap) in crows {
                md.correlations.push(Correlation {
                    neighbour: parse_cell("cell_correlations", &n)?,
                    modality: parse_modality("cell_correlations", &m)?,
                    correlation,
                    overlap: count("cell_correlations", overlap)?,
                });
            }
            let arows: Vec<(String, i64, f64, bool)> = select(
                c,
                "SELECT m.name, ca.t, ca.anomaly, ca.flagged
                 FROM cell_anomalies ca JOIN modalities m ON m.id = ca.modality
                 WHERE ca.cell = ?1 ORDER BY m.name, ca.t",
                [id],
            )?;
            for (m, t, anomaly, flagged) in arows {
                md.anomalies.push(AnomalyRecord {
                    modality: parse_modality("cell_anomalies", &m)?,
                    t,
                    anomaly,
                    flagged,
                });
            }
        }
        out.push(md);
    }
    Ok(out)
}

pub(super) fn sensor_last_collected(c: &Connection) -> Result<Vec<(SensorId, UnixSeconds)>> {
    let rows: Vec<(String, UnixSeconds)> = select(
        c,
        "SELECT s.name, sc.last_collected FROM sensor_collection sc
             JOIN sensors s ON s.id = sc.sensor ORDER BY s.name",
        [],
    )?;
    rows.into_iter()
        .map(|(name, t)| Ok((parse_sensor("sensor_collection", name)?, t)))
        .collect()
}

pub(super) fn sensor_reading_counts(c: &Connection) -> Result<Vec<(SensorId, u64)>> {
    let rows: Vec<(String, i64)> = select(
        c,
        "SELECT s.name, n.count FROM (SELECT sensor, COUNT(*) AS count FROM readings
             GROUP BY sensor) n JOIN sensors s ON s.id = n.sensor ORDER BY s.name",
        [],
    )?;
    rows.into_iter()
        .map(|(name, n)| Ok((parse_sensor("readings", name)?, count("readings", n)?)))
        .collect()
}

/// A `missions` row as read, before its stops and visits.
struct MissionRow {
    id: i64,
    created_at: i64,
    kind: String,
    planned_at: i64,
    solver: String,
    seed: i64,
    weights: [f64; 4],
    anomaly_form: String,
    total_score: f64,
    base: (f64, f64),
    base_alt_m: f64,
    altitude_m: f64,
    cruise_speed_mps: f64,
    energy: EnergyBreakdown,
    return_distance_m: f64,
    status: String,
    flown_at: Option<i64>,
    wind: (f64, f64),
    cancelled: bool,
}

impl TryFrom<&Row<'_>> for MissionRow {
    type Error = rusqlite::Error;

    fn try_from(r: &Row<'_>) -> rusqlite::Result<Self> {
        Ok(Self {
            id: r.get(0)?,
            created_at: r.get(1)?,
            kind: r.get(2)?,
            planned_at: r.get(3)?,
            solver: r.get(4)?,
            seed: r.get(5)?,
            weights: [r.get(6)?, r.get(7)?, r.get(8)?, r.get(9)?],
            anomaly_form: r.get(10)?,
            total_score: r.get(11)?,
            base: (r.get(12)?, r.get(13)?),
            base_alt_m: r.get(14)?,
            altitude_m: r.get(15)?,
            cruise_speed_mps: r.get(16)?,
            energy: EnergyBreakdown {
                travel_j: r.get(17)?,
                hover_j: r.get(18)?,
                comm_j: r.get(19)?,
                return_j: r.get(20)?,
                total_j: r.get(21)?,
                budget_j: r.get(22)?,
                distance_m: r.get(23)?,
                flight_time_s: r.get(24)?,
            },
            return_distance_m: r.get(25)?,
            status: r.get(26)?,
            flown_at: r.get(27)?,
            wind: (r.get(28)?, r.get(29)?),
            cancelled: r.get(30)?,
        })
    }
}

/// All missions (`id` = `None`) or one, oldest first, with their stops and visits.
pub(super) fn missions(c: &Connection, id: Option<MissionId>) -> Result<Vec<MissionRecord>> {
    let rows: Vec<MissionRow> = select(
        c,
        "SELECT id, created_at, kind, planned_at, solver, seed,
                    weight_alpha, weight_beta, weight_gamma, weight_delta, anomaly_form,
                    total_score, base_lat, base_lon, base_alt_m, altitude_m, cruise_speed_mps,
                    travel_j, hover_j, comm_j, return_j, total_j, budget_j, distance_m,
                    flight_time_s, return_distance_m, status, flown_at, wind_mps, wind_from_deg,
                    cancelled
             FROM missions WHERE ?1 IS NULL OR id = ?1 ORDER BY id",
        [id.map(|m| m.0)],
    )?;
    let mut out = Vec::with_capacity(rows.len());
    for m in rows {
        let corrupt = |detail: String| StoreError::Corrupt {
            table: "missions",
            detail,
        };
        let kind = MissionKind::parse(&m.kind)
            .ok_or_else(|| corrupt(format!("mission {}: unknown kind {:?}", m.id, m.kind)))?;
        let status = match MissionStatus::parse(&m.status) {
            Some(MissionStatus::Planned) if m.cancelled => MissionStatus::Cancelled,
            Some(s @ (MissionStatus::Planned | MissionStatus::Flown)) => s,
            _ => {
                return Err(corrupt(format!(
                    "mission {}: unknown status {:?}",
                    m.id, m.status
                )));
            }
        };
        let mut stop_list = Vec::new();
        type StopRow = (
            u32,
            String,
            f64,
            f64,
            f64,
            Option<f64>,
            Option<f64>,
            Option<f64>,
            Option<f64>,
            f64,
            f64,
            f64,
            f64,
            f64,
            f64,
        );
        let srows: Vec<StopRow> = select(
            c,
            "SELECT position, cell, lat, lon, score, freshness, redundancy, anomaly, uncertainty,
                    leg_distance_m, leg_energy_j, collection_s, hover_s, hover_j, comm_j
             FROM mission_stops WHERE mission = ?1 ORDER BY position",
            [m.id],
        )?;
        for s in srows {
            let terms = match (s.5, s.6, s.7, s.8) {
                (Some(f), Some(r), Some(a), Some(u)) => Some([f, r, a, u]),
                _ => None,
            };
            stop_list.push(StopRecord {
                order: s.0,
                cell: parse_cell("mission_stops", &s.1)?,
                centre: parse_latlon("mission_stops", s.2, s.3)?,
                score: s.4,
                terms,
                leg_distance_m: s.9,
                leg_energy_j: s.10,
                collection_s: s.11,
                hover_s: s.12,
                hover_j: s.13,
                comm_j: s.14,
            });
        }
        let mut visit_list = Vec::new();
        let vrows: Vec<(u32, String, Option<i64>, Option<f64>)> = select(
            c,
            "SELECT position, cell, arrived_at, energy_j FROM visits WHERE mission = ?1
             ORDER BY position",
            [m.id],
        )?;
        for (order, cell, arrived_at, energy_j) in vrows {
            visit_list.push(VisitRecord {
                order,
                cell: parse_cell("visits", &cell)?,
                arrived_at,
                energy_j,
            });
        }
        out.push(MissionRecord {
            id: MissionId(m.id),
            mission: NewMission {
                created_at: m.created_at,
                kind,
                planned_at: m.planned_at,
                solver: m.solver,
                // Stored as the two's-complement i64 of the same 64 bits.
                seed: m.seed as u64,
                weights: m.weights,
                anomaly_form: m.anomaly_form,
                total_score: m.total_score,
                profile: FlightProfile {
                    base: parse_latlon("missions", m.base.0, m.base.1)?,
                    base_alt_m: m.base_alt_m,
                    altitude_m: m.altitude_m,
                    cruise_speed_mps: m.cruise_speed_mps,
                    wind_mps: m.wind.0,
                    wind_from_deg: m.wind.1,
                },
                energy: m.energy,
                return_distance_m: m.return_distance_m,
                stops: stop_list,
            },
            status,
            flown_at: m.flown_at,
            visits: visit_list,
        });
    }
    Ok(out)
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
