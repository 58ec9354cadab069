//! The queries, written once over a `&mut Transaction` and shared by [`super::PgStore`] (in a
//! read-only snapshot) and [`super::PgTx`] (inside the write transaction). Parent rows and
//! their children are fetched with one query per table and grouped in Rust, so a read costs
//! a fixed number of round trips whatever the number of cells or missions.

use std::collections::HashMap;
use std::ops::RangeInclusive;

use gleaner_field::{CellIndex, LatLon, Modality, SensorId, UnixSeconds};
use postgres::Transaction;

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

fn parse_modality(table: &'static str, name: &str) -> Result<Modality> {
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

/// A count read back as `u64` (stored as a signed `BIGINT`).
fn count(table: &'static str, n: i64) -> Result<u64> {
    u64::try_from(n).map_err(|_| StoreError::Corrupt {
        table,
        detail: format!("negative count {n}"),
    })
}

/// A position (stop or visit order) read back as `u32`.
fn position(table: &'static str, n: i64) -> Result<u32> {
    u32::try_from(n).map_err(|_| StoreError::Corrupt {
        table,
        detail: format!("position {n} out of range"),
    })
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
    c.query(
        "SELECT name, lat, lon, elevation_m, source FROM sensors ORDER BY name COLLATE \"C\"",
        &[],
    )
    .db()?
    .iter()
    .map(|r| {
        Ok(SensorRecord {
            id: parse_sensor("sensors", r.get(0))?,
            position: parse_latlon("sensors", r.get(1), r.get(2))?,
            elevation_m: r.get(3),
            source: r.get(4),
        })
    })
    .collect()
}

pub(super) fn modalities(c: &mut Transaction<'_>) -> Result<Vec<ModalityRecord>> {
    c.query(
        "SELECT name, unit FROM modalities ORDER BY name COLLATE \"C\"",
        &[],
    )
    .db()?
    .iter()
    .map(|r| {
        Ok(ModalityRecord {
            modality: parse_modality("modalities", r.get(0))?,
            unit: r.get(1),
        })
    })
    .collect()
}

/// `(name, key)` pairs sorted by name (byte-wise).
fn sorted(map: HashMap<String, i64>) -> Vec<(String, i64)> {
    let mut v: Vec<(String, i64)> = map.into_iter().collect();
    v.sort();
    v
}

pub(super) fn readings_for(
    c: &mut Transaction<'_>,
    modality: Option<&Modality>,
    range: RangeInclusive<UnixSeconds>,
) -> Result<ReadingBatch> {
    let sensors = sorted(sensor_ids(c)?);
    let mut modalities = sorted(modality_ids(c)?);
    modalities.retain(|(name, _)| modality.is_none_or(|m| m.as_str() == name));
    collect_readings(c, &sensors, &modalities, range)
}

pub(super) fn readings_of_sensors(
    c: &mut Transaction<'_>,
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
        .map(|(n, t, v)| Ok((parse_sensor("sensors", n)?, t, v)))
        .collect()
}

/// The readings of `sensors` x `modalities` (both sorted by name) in `range`, in that order
/// and by time. One query, ordered by the primary key (sensor key, modality key, t) so the
/// server streams an index range; the rows are then regrouped by name order in Rust (keys
/// and names need not sort alike).
fn collect_readings(
    c: &mut Transaction<'_>,
    sensors: &[(String, i64)],
    modalities: &[(String, i64)],
    range: RangeInclusive<UnixSeconds>,
) -> Result<ReadingBatch> {
    let mut batch = ReadingBatch::new();
    if sensors.is_empty() || modalities.is_empty() {
        return Ok(batch);
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
    batch.rows.reserve(rows.len());
    let mut modality_index: HashMap<i64, u32> = HashMap::new();
    for (sname, skey) in sensors {
        let mut sensor_index = None;
        for (mname, mkey) in modalities {
            let Some(&(first, n)) = runs.get(&(*skey, *mkey)) else {
                continue;
            };
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
            for r in &rows[first..first + n] {
                batch.rows.push(Reading {
                    sensor: s,
                    modality: m,
                    t: r.get(2),
                    value: r.get(3),
                });
            }
        }
    }
    Ok(batch)
}

pub(super) fn reading_count(c: &mut Transaction<'_>) -> Result<u64> {
    let n: i64 = c
        .query_one("SELECT COUNT(*) FROM readings", &[])
        .db()?
        .get(0);
    count("readings", n)
}

pub(super) fn ingests(c: &mut Transaction<'_>) -> Result<Vec<IngestRecord>> {
    c.query(
        "SELECT file_name, format, rows_read, rows_inserted, rows_unchanged, rows_skipped, at
         FROM ingests ORDER BY id",
        &[],
    )
    .db()?
    .iter()
    .map(|r| {
        Ok(IngestRecord {
            file_name: r.get(0),
            format: r.get(1),
            rows_read: count("ingests", r.get(2))?,
            rows_inserted: count("ingests", r.get(3))?,
            rows_unchanged: count("ingests", r.get(4))?,
            rows_skipped: count("ingests", r.get(5))?,
            at: r.get(6),
        })
    })
    .collect()
}

/// Rows of a child query grouped by their first column (the parent's key), in query order.
fn grouped(rows: Vec<postgres::Row>) -> HashMap<i64, Vec<postgres::Row>> {
    let mut out: HashMap<i64, Vec<postgres::Row>> = HashMap::new();
    for r in rows {
        out.entry(r.get(0)).or_default().push(r);
    }
    out
}

pub(super) fn cells(c: &mut Transaction<'_>) -> Result<Vec<CellRecord>> {
    let rows = c
        .query(
            "SELECT id, label, lat, lon, cell_size_m FROM cells ORDER BY i, j",
            &[],
        )
        .db()?;
    let mut members = grouped(
        c.query(
            "SELECT cs.cell, s.name FROM cell_sensors cs JOIN sensors s ON s.id = cs.sensor
             ORDER BY cs.cell, s.name COLLATE \"C\"",
            &[],
        )
        .db()?,
    );
    rows.iter()
        .map(|r| {
            let id: i64 = r.get(0);
            let label: &str = r.get(1);
            let sensors = members
                .remove(&id)
                .unwrap_or_default()
                .iter()
                .map(|m| parse_sensor("cell_sensors", m.get(1)))
                .collect::<Result<_>>()?;
            Ok(CellRecord {
                index: parse_cell("cells", label)?,
                centre: parse_latlon("cells", r.get(2), r.get(3))?,
                cell_size_m: r.get(4),
                sensors,
            })
        })
        .collect()
}

pub(super) fn cell_metadata(c: &mut Transaction<'_>) -> Result<Vec<CellMetadata>> {
    cell_metadata_with(c, true)
}

/// The cell metadata rows without the child lists (summaries, correlations, anomalies).
pub(super) fn cell_metadata_scalars(c: &mut Transaction<'_>) -> Result<Vec<CellMetadata>> {
    cell_metadata_with(c, false)
}

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
        c.query(
            "SELECT cell, class, probability FROM cell_class_probabilities ORDER BY cell, k",
            &[],
        )
        .db()?,
    );
    // A child table's rows grouped by cell, or none when the children are not wanted.
    let mut child = |sql: &str| -> Result<HashMap<i64, Vec<postgres::Row>>> {
        Ok(if children {
            grouped(c.query(sql, &[]).db()?)
        } else {
            HashMap::new()
        })
    };
    let mut summaries = child(
        "SELECT cs.cell, m.name, cs.count, cs.mean, cs.std, cs.min, cs.max, cs.latest_t,
                        cs.latest_value
                 FROM cell_summaries cs JOIN modalities m ON m.id = cs.modality
                 ORDER BY cs.cell, m.name COLLATE \"C\"",
    )?;
    let mut correlations = child(
        "SELECT cc.cell, n.label, m.name, cc.correlation, cc.overlap
                 FROM cell_correlations cc JOIN cells n ON n.id = cc.neighbour
                      JOIN modalities m ON m.id = cc.modality
                 ORDER BY cc.cell, n.i, n.j, m.name COLLATE \"C\"",
    )?;
    let mut anomalies = child(
        "SELECT ca.cell, m.name, ca.t, ca.anomaly, ca.flagged
                 FROM cell_anomalies ca JOIN modalities m ON m.id = ca.modality
                 ORDER BY ca.cell, m.name COLLATE \"C\", ca.t",
    )?;
    let mut out = Vec::with_capacity(rows.len());
    for r in &rows {
        let id: i64 = r.get(0);
        let mut md = CellMetadata::new(parse_cell("cells", r.get(1))?);
        md.last_collected = r.get(2);
        md.pending_bytes = r.get(3);
        md.expected_energy_j = r.get(4);
        let term = |k: usize| r.get::<_, Option<f64>>(k);
        if let (Some(f), Some(rr), Some(a), Some(u), Some(s), Some(at)) = (
            term(5),
            term(6),
            term(7),
            term(8),
            term(9),
            r.get::<_, Option<i64>>(10),
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
        for p in probs.remove(&id).unwrap_or_default() {
            md.class_probabilities.push(ClassProbability {
                class: p.get(1),
                probability: p.get(2),
            });
        }
        for s in summaries.remove(&id).unwrap_or_default() {
            md.summaries.push(ModalitySummary {
                modality: parse_modality("cell_summaries", s.get(1))?,
                stats: SeriesStats {
                    count: count("cell_summaries", s.get(2))?,
                    mean: s.get(3),
                    std: s.get(4),
                    min: s.get(5),
                    max: s.get(6),
                    latest_t: s.get(7),
                    latest_value: s.get(8),
                },
            });
        }
        for co in correlations.remove(&id).unwrap_or_default() {
            md.correlations.push(Correlation {
                neighbour: parse_cell("cell_correlations", co.get(1))?,
                modality: parse_modality("cell_correlations", co.get(2))?,
                correlation: co.get(3),
                overlap: count("cell_correlations", co.get(4))?,
            });
        }
        for a in anomalies.remove(&id).unwrap_or_default() {
            md.anomalies.push(AnomalyRecord {
                modality: parse_modality("cell_anomalies", a.get(1))?,
                t: a.get(2),
                anomaly: a.get(3),
                flagged: a.get(4),
            });
        }
        out.push(md);
    }
    Ok(out)
}

pub(super) fn sensor_last_collected(
    c: &mut Transaction<'_>,
) -> Result<Vec<(SensorId, UnixSeconds)>> {
    c.query(
        "SELECT s.name, sc.last_collected FROM sensor_collection sc
         JOIN sensors s ON s.id = sc.sensor ORDER BY s.name COLLATE \"C\"",
        &[],
    )
    .db()?
    .iter()
    .map(|r| Ok((parse_sensor("sensor_collection", r.get(0))?, r.get(1))))
    .collect()
}

pub(super) fn sensor_reading_counts(c: &mut Transaction<'_>) -> Result<Vec<(SensorId, u64)>> {
    c.query(
        "SELECT s.name, n.count FROM (SELECT sensor, COUNT(*) AS count FROM readings
             GROUP BY sensor) n JOIN sensors s ON s.id = n.sensor ORDER BY s.name COLLATE \"C\"",
        &[],
    )
    .db()?
    .iter()
    .map(|r| {
        Ok((
            parse_sensor("readings", r.get(0))?,
            count("readings", r.get(1))?,
        ))
    })
    .collect()
}

/// All missions (`id` = `None`) or one, oldest first, with their stops and visits.
pub(super) fn missions(
    c: &mut Transaction<'_>,
    id: Option<MissionId>,
) -> Result<Vec<MissionRecord>> {
    // -1 never names a mission (ids start at 1): "all" without a second query text.
    let only = id.map_or(-1, |m| m.0);
    let rows = c
        .query(
            "SELECT id, created_at, kind, planned_at, solver, seed,
                    weight_alpha, weight_beta, weight_gamma, weight_delta, anomaly_form,
                    total_score, base_lat, base_lon, base_alt_m, altitude_m, cruise_speed_mps,
                    travel_j, hover_j, comm_j, return_j, total_j, budget_j, distance_m,
                    flight_time_s, return_distance_m, status, flown_at, wind_mps, wind_from_deg,
                    cancelled
             FROM missions WHERE $1::BIGINT = -1 OR id = $1::BIGINT ORDER BY id",
            &[&only],
        )
        .db()?;
    let mut stops = grouped(
        c.query(
            "SELECT mission, position, cell, lat, lon, score, freshness, redundancy, anomaly,
                    uncertainty, leg_distance_m, leg_energy_j, collection_s, hover_s, hover_j,
                    comm_j
             FROM mission_stops WHERE $1::BIGINT = -1 OR mission = $1::BIGINT ORDER BY mission, position",
            &[&only],
        )
        .db()?,
    );
    let mut visits = grouped(
        c.query(
            "SELECT mission, position, cell, arrived_at, energy_j FROM visits
             WHERE $1::BIGINT = -1 OR mission = $1::BIGINT ORDER BY mission, position",
            &[&only],
        )
        .db()?,
    );
    let mut out = Vec::with_capacity(rows.len());
    for r in &rows {
        let id: i64 = r.get(0);
        let corrupt = |detail: String| StoreError::Corrupt {
            table: "missions",
            detail,
        };
        let kind_s: &str = r.get(2);
        let kind = MissionKind::parse(kind_s)
            .ok_or_else(|| corrupt(format!("mission {id}: unknown kind {kind_s:?}")))?;
        let status_s: &str = r.get(26);
        let cancelled: bool = r.get(30);
        let status = match MissionStatus::parse(status_s) {
            Some(MissionStatus::Planned) if cancelled => MissionStatus::Cancelled,
            Some(s @ (MissionStatus::Planned | MissionStatus::Flown)) => s,
            _ => {
                return Err(corrupt(format!(
                    "mission {id}: unknown status {status_s:?}"
                )));
            }
        };
        let mut stop_list = Vec::new();
        for s in stops.remove(&id).unwrap_or_default() {
            let terms = match (
                s.get::<_, Option<f64>>(6),
                s.get::<_, Option<f64>>(7),
                s.get::<_, Option<f64>>(8),
                s.get::<_, Option<f64>>(9),
            ) {
                (Some(f), Some(r), Some(a), Some(u)) => Some([f, r, a, u]),
                _ => None,
            };
            stop_list.push(StopRecord {
                order: position("mission_stops", s.get(1))?,
                cell: parse_cell("mission_stops", s.get(2))?,
                centre: parse_latlon("mission_stops", s.get(3), s.get(4))?,
                score: s.get(5),
                terms,
                leg_distance_m: s.get(10),
                leg_energy_j: s.get(11),
                collection_s: s.get(12),
                hover_s: s.get(13),
                hover_j: s.get(14),
                comm_j: s.get(15),
            });
        }
        let mut visit_list = Vec::new();
        for v in visits.remove(&id).unwrap_or_default() {
            visit_list.push(VisitRecord {
                order: position("visits", v.get(1))?,
                cell: parse_cell("visits", v.get(2))?,
                arrived_at: v.get(3),
                energy_j: v.get(4),
            });
        }
        let seed: i64 = r.get(5);
        out.push(MissionRecord {
            id: MissionId(id),
            mission: NewMission {
                created_at: r.get(1),
                kind,
                planned_at: r.get(3),
                solver: r.get(4),
                // Stored as the two's-complement i64 of the same 64 bits.
                seed: seed as u64,
                weights: [r.get(6), r.get(7), r.get(8), r.get(9)],
                anomaly_form: r.get(10),
                total_score: r.get(11),
                profile: FlightProfile {
                    base: parse_latlon("missions", r.get(12), r.get(13))?,
                    base_alt_m: r.get(14),
                    altitude_m: r.get(15),
                    cruise_speed_mps: r.get(16),
                    wind_mps: r.get(28),
                    wind_from_deg: r.get(29),
                },
                energy: EnergyBreakdown {
                    travel_j: r.get(17),
                    hover_j: r.get(18),
                    comm_j: r.get(19),
                    return_j: r.get(20),
                    total_j: r.get(21),
                    budget_j: r.get(22),
                    distance_m: r.get(23),
                    flight_time_s: r.get(24),
                },
                return_distance_m: r.get(25),
                stops: stop_list,
            },
            status,
            flown_at: r.get(27),
            visits: visit_list,
        });
    }
    Ok(out)
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
