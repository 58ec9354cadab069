//! [`SqliteStore`]: the [`Store`] on an SQLite file.

use std::collections::{HashMap, HashSet};
use std::ops::RangeInclusive;
use std::path::Path;
use std::time::Duration;

use gleaner_field::{CellIndex, LatLon, Modality, SensorId, UnixSeconds};
use rusqlite::{Connection, OptionalExtension, Transaction, params};

use crate::schema;
use crate::{
    AnomalyRecord, CellMetadata, CellRecord, CellScores, ClassProbability, Conflict,
    ConflictPolicy, Correlation, IngestRecord, InsertStats, MissionId, MissionKind, MissionRecord,
    MissionStatus, ModalityRecord, ModalitySummary, NewMission, Reading, ReadingBatch,
    RefreshParams, ReplaceCellsStats, Result, SensorRecord, SensorSummary, SeriesStats, Store,
    StoreError, UpsertStats, VisitRecord,
};

/// Rows per multi-row `INSERT` statement in [`Store::insert_readings`] (4 parameters each).
const CHUNK: usize = 128;

/// How long a writer waits for another connection's lock before failing.
const BUSY_TIMEOUT: Duration = Duration::from_secs(10);

/// Relative tolerance under which two reading values are the same reading.
const SAME_VALUE_RTOL: f64 = 1e-12;

/// A [`Store`] in an SQLite database (a file, or memory for tests).
///
/// The connection runs with `journal_mode=WAL` (files only), `synchronous=NORMAL`,
/// `foreign_keys=ON` and a 10 s busy timeout. Opening migrates the schema to the latest
/// version; a database written by a newer gleaner is refused with
/// [`StoreError::SchemaTooNew`].
#[derive(Debug)]
pub struct SqliteStore {
    conn: Connection,
}

impl SqliteStore {
    /// Opens (creating if needed) the database file at `path` and migrates it.
    pub fn open(path: &Path) -> Result<Self> {
        let wrap = |source| StoreError::Open {
            path: path.to_path_buf(),
            source,
        };
        let conn = Connection::open(path).map_err(wrap)?;
        // The first statement is where SQLite notices a file that is not a database.
        conn.query_row("SELECT COUNT(*) FROM sqlite_master", [], |r| {
            r.get::<_, i64>(0)
        })
        .map_err(wrap)?;
        Self::setup(conn)
    }

    /// A fresh database in memory (for tests and dry runs).
    pub fn open_in_memory() -> Result<Self> {
        Self::setup(Connection::open_in_memory()?)
    }

    fn setup(mut conn: Connection) -> Result<Self> {
        conn.busy_timeout(BUSY_TIMEOUT)?;
        let foreign: Vec<String> = conn
            .prepare(
                "SELECT name FROM sqlite_master WHERE type = 'table' AND name NOT LIKE 'sqlite_%'
                 AND NOT EXISTS (SELECT 1 FROM sqlite_master WHERE name = 'schema_migrations')
                 ORDER BY name LIMIT 5",
            )?
            .query_map([], |r| r.get(0))?
            .collect::<rusqlite::Result<_>>()?;
        if !foreign.is_empty() {
            return Err(StoreError::NotAGleanerDatabase {
                path: conn.path().unwrap_or(":memory:").to_string(),
                tables: foreign,
            });
        }
        // journal_mode answers with the mode in force ("memory" for in-memory databases).
        let _mode: String = conn.query_row("PRAGMA journal_mode = WAL", [], |r| r.get(0))?;
        conn.execute_batch(
            "PRAGMA synchronous = NORMAL;
             PRAGMA foreign_keys = ON;
             PRAGMA temp_store = MEMORY;
             PRAGMA cache_size = -65536;",
        )?;
        schema::migrate(&mut conn)?;
        Ok(Self { conn })
    }

    /// The underlying connection, for read-only inspection in tests and tools.
    pub fn connection(&self) -> &Connection {
        &self.conn
    }

    /// `name -> id` for every stored sensor.
    fn sensor_ids(conn: &Connection) -> Result<HashMap<String, i64>> {
        let mut stmt = conn.prepare_cached("SELECT name, id FROM sensors")?;
        let rows = stmt.query_map([], |r| Ok((r.get(0)?, r.get(1)?)))?;
        Ok(rows.collect::<rusqlite::Result<_>>()?)
    }

    /// `name -> id` for every stored modality.
    fn modality_ids(conn: &Connection) -> Result<HashMap<String, i64>> {
        let mut stmt = conn.prepare_cached("SELECT name, id FROM modalities")?;
        let rows = stmt.query_map([], |r| Ok((r.get(0)?, r.get(1)?)))?;
        Ok(rows.collect::<rusqlite::Result<_>>()?)
    }

    /// `label -> id` for every stored cell.
    fn cell_ids(conn: &Connection) -> Result<HashMap<String, i64>> {
        let mut stmt = conn.prepare_cached("SELECT label, id FROM cells")?;
        let rows = stmt.query_map([], |r| Ok((r.get(0)?, r.get(1)?)))?;
        Ok(rows.collect::<rusqlite::Result<_>>()?)
    }
}

fn same_value(a: f64, b: f64) -> bool {
    a == b || (a - b).abs() <= SAME_VALUE_RTOL * a.abs().max(b.abs())
}

fn finite(what: &'static str, name: &str, v: f64) -> Result<()> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(StoreError::Invalid {
            what,
            detail: format!("{name} = {v} is not finite"),
        })
    }
}

fn parse_sensor(table: &'static str, name: String) -> Result<SensorId> {
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

/// Sample standard deviation from a sum of squared deviations over `n` points.
fn sample_std(n: u64, sum_sq_dev: Option<f64>) -> Option<f64> {
    if n < 2 {
        return None;
    }
    Some((sum_sq_dev.unwrap_or(0.0).max(0.0) / (n - 1) as f64).sqrt())
}

impl Store for SqliteStore {
    fn schema_version(&self) -> Result<i64> {
        Ok(self
            .conn
            .query_row("SELECT MAX(version) FROM schema_migrations", [], |r| {
                r.get::<_, Option<i64>>(0)
            })?
            .unwrap_or(0))
    }

    fn upsert_sensors(&mut self, sensors: &[SensorRecord]) -> Result<UpsertStats> {
        let mut seen: HashMap<&str, &SensorRecord> = HashMap::new();
        for s in sensors {
            if let Some(e) = s.elevation_m {
                finite("sensor elevation", s.id.as_str(), e)?;
            }
            if let Some(prev) = seen.insert(s.id.as_str(), s)
                && prev != s
            {
                return Err(StoreError::Invalid {
                    what: "sensor list",
                    detail: format!(
                        "sensor {:?} listed twice with different content",
                        s.id.as_str()
                    ),
                });
            }
        }
        let tx = self.conn.transaction()?;
        let mut stats = UpsertStats::default();
        {
            let mut get = tx.prepare_cached(
                "SELECT lat, lon, elevation_m, source FROM sensors WHERE name = ?1",
            )?;
            let mut insert = tx.prepare_cached(
                "INSERT INTO sensors (name, lat, lon, elevation_m, source) VALUES (?1, ?2, ?3, ?4, ?5)",
            )?;
            let mut update = tx.prepare_cached(
                "UPDATE sensors SET lat = ?2, lon = ?3, elevation_m = ?4, source = ?5 WHERE name = ?1",
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
                    .optional()?;
                match stored {
                    None => {
                        insert.execute(p)?;
                        stats.added.push(s.id.to_string());
                    }
                    Some((lat, lon, elev, source))
                        if lat == s.position.lat()
                            && lon == s.position.lon()
                            && elev == s.elevation_m
                            && source == s.source =>
                    {
                        stats.unchanged += 1;
                    }
                    Some(_) => {
                        update.execute(p)?;
                        stats.updated.push(s.id.to_string());
                    }
                }
            }
        }
        tx.commit()?;
        Ok(stats)
    }

    fn sensors(&self) -> Result<Vec<SensorRecord>> {
        let mut stmt = self.conn.prepare_cached(
            "SELECT name, lat, lon, elevation_m, source FROM sensors ORDER BY name",
        )?;
        let rows = stmt.query_map([], |r| {
            Ok((
                r.get::<_, String>(0)?,
                r.get::<_, f64>(1)?,
                r.get::<_, f64>(2)?,
                r.get::<_, Option<f64>>(3)?,
                r.get::<_, String>(4)?,
            ))
        })?;
        let mut out = Vec::new();
        for row in rows {
            let (name, lat, lon, elevation_m, source) = row?;
            out.push(SensorRecord {
                id: parse_sensor("sensors", name)?,
                position: parse_latlon("sensors", lat, lon)?,
                elevation_m,
                source,
            });
        }
        Ok(out)
    }

    fn upsert_modalities(&mut self, modalities: &[ModalityRecord]) -> Result<UpsertStats> {
        let mut seen: HashMap<&str, &ModalityRecord> = HashMap::new();
        for m in modalities {
            if let Some(prev) = seen.insert(m.modality.as_str(), m)
                && prev != m
            {
                return Err(StoreError::Invalid {
                    what: "modality list",
                    detail: format!(
                        "modality {:?} listed twice with units {:?} and {:?}",
                        m.modality.as_str(),
                        prev.unit,
                        m.unit
                    ),
                });
            }
        }
        let tx = self.conn.savepoint()?;
        let mut stats = UpsertStats::default();
        {
            let mut get = tx.prepare_cached("SELECT unit FROM modalities WHERE name = ?1")?;
            let mut insert =
                tx.prepare_cached("INSERT INTO modalities (name, unit) VALUES (?1, ?2)")?;
            let mut update =
                tx.prepare_cached("UPDATE modalities SET unit = ?2 WHERE name = ?1")?;
            let mut done = HashSet::new();
            for m in modalities {
                let name = m.modality.as_str();
                if !done.insert(name) {
                    continue;
                }
                let stored: Option<Option<String>> =
                    get.query_row([name], |r| r.get(0)).optional()?;
                match stored {
                    None => {
                        insert.execute(params![name, m.unit])?;
                        stats.added.push(name.to_string());
                    }
                    Some(unit) if unit == m.unit => stats.unchanged += 1,
                    Some(_) => {
                        update.execute(params![name, m.unit])?;
                        stats.updated.push(name.to_string());
                    }
                }
            }
        }
        tx.commit()?;
        Ok(stats)
    }

    fn modalities(&self) -> Result<Vec<ModalityRecord>> {
        let mut stmt = self
            .conn
            .prepare_cached("SELECT name, unit FROM modalities ORDER BY name")?;
        let rows = stmt.query_map([], |r| Ok((r.get::<_, String>(0)?, r.get(1)?)))?;
        let mut out = Vec::new();
        for row in rows {
            let (name, unit) = row?;
            out.push(ModalityRecord {
                modality: parse_modality("modalities", &name)?,
                unit,
            });
        }
        Ok(out)
    }

    fn insert_readings(
        &mut self,
        batch: &ReadingBatch,
        policy: ConflictPolicy,
    ) -> Result<InsertStats> {
        // Resolve names to integer keys and validate every row before touching the database.
        let known_sensors = Self::sensor_ids(&self.conn)?;
        let known_modalities = Self::modality_ids(&self.conn)?;
        let sensor_keys = batch
            .sensors
            .iter()
            .map(|s| {
                known_sensors
                    .get(s.as_str())
                    .copied()
                    .ok_or_else(|| StoreError::UnknownSensor(s.clone()))
            })
            .collect::<Result<Vec<i64>>>()?;
        let modality_keys = batch
            .modalities
            .iter()
            .map(|m| {
                known_modalities
                    .get(m.as_str())
                    .copied()
                    .ok_or_else(|| StoreError::UnknownModality(m.clone()))
            })
            .collect::<Result<Vec<i64>>>()?;
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
        // Key order makes the B-tree inserts sequential; the sort is stable, so within-batch
        // duplicates keep their order and the first one wins.
        let key = |r: &Reading| {
            (
                sensor_keys[r.sensor as usize],
                modality_keys[r.modality as usize],
                r.t,
            )
        };
        let mut rows: Vec<Reading> = batch.rows.clone();
        rows.sort_by_key(key);

        let tx = self.conn.savepoint()?;
        let mut stats = InsertStats::default();
        {
            let many_sql = format!(
                "INSERT INTO readings (sensor, modality, t, value) VALUES {} ON CONFLICT DO NOTHING",
                vec!["(?, ?, ?, ?)"; CHUNK].join(", ")
            );
            let mut many = tx.prepare_cached(&many_sql)?;
            let mut one = tx.prepare_cached(
                "INSERT INTO readings (sensor, modality, t, value) VALUES (?1, ?2, ?3, ?4)
                 ON CONFLICT DO NOTHING",
            )?;
            let mut stored = tx.prepare_cached(
                "SELECT value FROM readings WHERE sensor = ?1 AND modality = ?2 AND t = ?3",
            )?;
            for chunk in rows.chunks(CHUNK) {
                let changed = if chunk.len() == CHUNK {
                    for (k, r) in chunk.iter().enumerate() {
                        let (s, m, t) = key(r);
                        many.raw_bind_parameter(4 * k + 1, s)?;
                        many.raw_bind_parameter(4 * k + 2, m)?;
                        many.raw_bind_parameter(4 * k + 3, t)?;
                        many.raw_bind_parameter(4 * k + 4, r.value)?;
                    }
                    many.raw_execute()?
                } else {
                    let mut n = 0;
                    for r in chunk {
                        let (s, m, t) = key(r);
                        n += one.execute(params![s, m, t, r.value])?;
                    }
                    n
                };
                stats.inserted += changed as u64;
                if changed == chunk.len() {
                    continue;
                }
                // Some rows were already there: every row whose stored value differs from its
                // own is a conflict; the rest of the non-inserted rows are unchanged.
                let mut chunk_conflicts = 0;
                for r in chunk {
                    let (s, m, t) = key(r);
                    let v: f64 = stored.query_row(params![s, m, t], |row| row.get(0))?;
                    if !same_value(v, r.value) {
                        chunk_conflicts += 1;
                        stats.conflicts.push(Conflict {
                            sensor: batch.sensors[r.sensor as usize].clone(),
                            modality: batch.modalities[r.modality as usize].clone(),
                            t: r.t,
                            stored: v,
                            incoming: r.value,
                        });
                    }
                }
                stats.unchanged += (chunk.len() - changed - chunk_conflicts) as u64;
                if policy == ConflictPolicy::Fail && !stats.conflicts.is_empty() {
                    // Dropping the transaction rolls everything back.
                    return Err(StoreError::Conflicts(stats.conflicts));
                }
            }
        }
        tx.commit()?;
        Ok(stats)
    }

    fn readings_for(
        &self,
        modality: Option<&Modality>,
        range: RangeInclusive<UnixSeconds>,
    ) -> Result<ReadingBatch> {
        let mut sensors: Vec<(String, i64)> = Self::sensor_ids(&self.conn)?.into_iter().collect();
        sensors.sort();
        let mut modalities: Vec<(String, i64)> =
            Self::modality_ids(&self.conn)?.into_iter().collect();
        modalities.retain(|(name, _)| modality.is_none_or(|m| m.as_str() == name));
        modalities.sort();
        let mut stmt = self.conn.prepare_cached(
            "SELECT t, value FROM readings
             WHERE sensor = ?1 AND modality = ?2 AND t BETWEEN ?3 AND ?4 ORDER BY t",
        )?;
        let mut batch = ReadingBatch::new();
        let mut modality_index: HashMap<i64, u32> = HashMap::new();
        for (sname, skey) in &sensors {
            let mut sensor_index = None;
            for (mname, mkey) in &modalities {
                let mut rows = stmt.query(params![skey, mkey, range.start(), range.end()])?;
                while let Some(row) = rows.next()? {
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
                        t: row.get(0)?,
                        value: row.get(1)?,
                    });
                }
            }
        }
        Ok(batch)
    }

    fn reading_count(&self) -> Result<u64> {
        let n: i64 = self
            .conn
            .query_row("SELECT COUNT(*) FROM readings", [], |r| r.get(0))?;
        Ok(n as u64)
    }

    fn sensor_summaries(&self) -> Result<Vec<SensorSummary>> {
        let mut stmt = self.conn.prepare_cached(
            "WITH st AS (
                 SELECT sensor, modality, COUNT(*) AS n, AVG(value) AS mean,
                        MIN(value) AS mn, MAX(value) AS mx, MAX(t) AS latest_t
                 FROM readings GROUP BY sensor, modality
             )
             SELECT s.name, m.name, st.n, st.mean,
                    (SELECT SUM((r.value - st.mean) * (r.value - st.mean)) FROM readings r
                     WHERE r.sensor = st.sensor AND r.modality = st.modality),
                    st.mn, st.mx, st.latest_t,
                    (SELECT r.value FROM readings r
                     WHERE r.sensor = st.sensor AND r.modality = st.modality AND r.t = st.latest_t)
             FROM st JOIN sensors s ON s.id = st.sensor JOIN modalities m ON m.id = st.modality
             ORDER BY s.name, m.name",
        )?;
        let rows = stmt.query_map([], |r| {
            Ok((
                r.get::<_, String>(0)?,
                r.get::<_, String>(1)?,
                r.get::<_, i64>(2)?,
                r.get::<_, f64>(3)?,
                r.get::<_, Option<f64>>(4)?,
                r.get::<_, f64>(5)?,
                r.get::<_, f64>(6)?,
                r.get::<_, i64>(7)?,
                r.get::<_, f64>(8)?,
            ))
        })?;
        let mut out = Vec::new();
        for row in rows {
            let (sensor, modality, n, mean, ss, min, max, latest_t, latest_value) = row?;
            let count = n as u64;
            out.push(SensorSummary {
                sensor: parse_sensor("sensors", sensor)?,
                modality: parse_modality("modalities", &modality)?,
                stats: SeriesStats {
                    count,
                    mean,
                    std: sample_std(count, ss),
                    min,
                    max,
                    latest_t,
                    latest_value,
                },
            });
        }
        Ok(out)
    }

    fn ingest(
        &mut self,
        modalities: &[ModalityRecord],
        batch: &ReadingBatch,
        policy: ConflictPolicy,
        provenance: &[IngestRecord],
    ) -> Result<InsertStats> {
        // One outer savepoint: the nested savepoints of the steps release into it, and any
        // error rolls all of them back together.
        self.conn.execute_batch("SAVEPOINT gleaner_ingest")?;
        let result = (|| {
            self.upsert_modalities(modalities)?;
            let stats = self.insert_readings(batch, policy)?;
            for record in provenance {
                let mut r = record.clone();
                r.rows_inserted = stats.inserted;
                r.rows_unchanged = stats.unchanged;
                self.record_ingest(&r)?;
            }
            Ok(stats)
        })();
        match result {
            Ok(stats) => {
                self.conn.execute_batch("RELEASE gleaner_ingest")?;
                Ok(stats)
            }
            Err(e) => {
                self.conn
                    .execute_batch("ROLLBACK TO gleaner_ingest; RELEASE gleaner_ingest")?;
                Err(e)
            }
        }
    }

    fn record_ingest(&mut self, ingest: &IngestRecord) -> Result<i64> {
        let as_i64 = |v: u64| i64::try_from(v).unwrap_or(i64::MAX);
        self.conn.execute(
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
        )?;
        Ok(self.conn.last_insert_rowid())
    }

    fn ingests(&self) -> Result<Vec<IngestRecord>> {
        let mut stmt = self.conn.prepare_cached(
            "SELECT file_name, format, rows_read, rows_inserted, rows_unchanged, rows_skipped, at
             FROM ingests ORDER BY id",
        )?;
        let rows = stmt.query_map([], |r| {
            Ok(IngestRecord {
                file_name: r.get(0)?,
                format: r.get(1)?,
                rows_read: r.get::<_, i64>(2)? as u64,
                rows_inserted: r.get::<_, i64>(3)? as u64,
                rows_unchanged: r.get::<_, i64>(4)? as u64,
                rows_skipped: r.get::<_, i64>(5)? as u64,
                at: r.get(6)?,
            })
        })?;
        Ok(rows.collect::<rusqlite::Result<_>>()?)
    }

    fn replace_cells(&mut self, cells: &[CellRecord]) -> Result<ReplaceCellsStats> {
        // Validate: unique labels, positive sides, known sensors, each sensor in one cell.
        let mut labels = HashSet::new();
        let mut owner: HashMap<&str, CellIndex> = HashMap::new();
        for c in cells {
            if !labels.insert(c.index) {
                return Err(StoreError::Invalid {
                    what: "cell list",
                    detail: format!("cell {} listed twice", c.index),
                });
            }
            if !(c.cell_size_m.is_finite() && c.cell_size_m > 0.0) {
                return Err(StoreError::Invalid {
                    what: "cell size",
                    detail: format!("cell {}: {} m must be positive", c.index, c.cell_size_m),
                });
            }
            for s in &c.sensors {
                if let Some(other) = owner.insert(s.as_str(), c.index)
                    && other != c.index
                {
                    return Err(StoreError::Invalid {
                        what: "cell list",
                        detail: format!("sensor {s} is in cells {other} and {}", c.index),
                    });
                }
            }
        }
        let stored = self.cells()?;
        let tx = self.conn.transaction()?;
        let sensor_keys = Self::sensor_ids(&tx)?;
        let mut stats = ReplaceCellsStats::default();
        {
            let normalised = |c: &CellRecord| {
                let mut c = c.clone();
                c.sensors.sort();
                c.sensors.dedup();
                c
            };
            let new_by_label: HashMap<CellIndex, CellRecord> =
                cells.iter().map(|c| (c.index, normalised(c))).collect();
            let mut delete = tx.prepare_cached("DELETE FROM cells WHERE label = ?1")?;
            let mut kept = HashSet::new();
            for old in &stored {
                if new_by_label.get(&old.index) == Some(old) {
                    kept.insert(old.index);
                } else {
                    delete.execute([old.index.to_string()])?;
                    stats.removed += 1;
                }
            }
            let mut insert_cell = tx.prepare_cached(
                "INSERT INTO cells (label, i, j, lat, lon, cell_size_m) VALUES (?1, ?2, ?3, ?4, ?5, ?6)",
            )?;
            let mut insert_member =
                tx.prepare_cached("INSERT INTO cell_sensors (cell, sensor) VALUES (?1, ?2)")?;
            let mut order: Vec<&CellRecord> = new_by_label.values().collect();
            order.sort_by_key(|c| c.index);
            for c in order {
                if kept.contains(&c.index) {
                    continue;
                }
                insert_cell.execute(params![
                    c.index.to_string(),
                    c.index.i,
                    c.index.j,
                    c.centre.lat(),
                    c.centre.lon(),
                    c.cell_size_m
                ])?;
                let cell_key = tx.last_insert_rowid();
                for s in &c.sensors {
                    let sensor_key =
                        sensor_keys
                            .get(s.as_str())
                            .ok_or_else(|| StoreError::Unknown {
                                what: "sensor",
                                name: s.to_string(),
                            })?;
                    insert_member.execute(params![cell_key, sensor_key])?;
                }
                stats.added += 1;
            }
            stats.kept = kept.len();
        }
        tx.commit()?;
        Ok(stats)
    }

    fn cells(&self) -> Result<Vec<CellRecord>> {
        let mut stmt = self.conn.prepare_cached(
            "SELECT c.id, c.label, c.lat, c.lon, c.cell_size_m FROM cells c ORDER BY c.i, c.j",
        )?;
        let mut members = self.conn.prepare_cached(
            "SELECT s.name FROM cell_sensors cs JOIN sensors s ON s.id = cs.sensor
             WHERE cs.cell = ?1 ORDER BY s.name",
        )?;
        let rows = stmt.query_map([], |r| {
            Ok((
                r.get::<_, i64>(0)?,
                r.get::<_, String>(1)?,
                r.get::<_, f64>(2)?,
                r.get::<_, f64>(3)?,
                r.get::<_, f64>(4)?,
            ))
        })?;
        let mut out = Vec::new();
        for row in rows {
            let (id, label, lat, lon, cell_size_m) = row?;
            let names = members.query_map([id], |r| r.get::<_, String>(0))?;
            let mut sensors = Vec::new();
            for n in names {
                sensors.push(parse_sensor("cell_sensors", n?)?);
            }
            out.push(CellRecord {
                index: parse_cell("cells", &label)?,
                centre: parse_latlon("cells", lat, lon)?,
                cell_size_m,
                sensors,
            });
        }
        Ok(out)
    }

    fn cell_metadata(&self) -> Result<Vec<CellMetadata>> {
        let c = &self.conn;
        let mut stmt = c.prepare_cached(
            "SELECT c.id, c.label, md.last_collected, md.pending_bytes, md.expected_energy_j,
                    md.freshness, md.redundancy, md.anomaly, md.uncertainty, md.score,
                    md.computed_at
             FROM cells c LEFT JOIN cell_metadata md ON md.cell = c.id ORDER BY c.i, c.j",
        )?;
        let mut probs = c.prepare_cached(
            "SELECT class, probability FROM cell_class_probabilities WHERE cell = ?1 ORDER BY k",
        )?;
        let mut summaries = c.prepare_cached(
            "SELECT m.name, cs.count, cs.mean, cs.std, cs.min, cs.max, cs.latest_t, cs.latest_value
             FROM cell_summaries cs JOIN modalities m ON m.id = cs.modality
             WHERE cs.cell = ?1 ORDER BY m.name",
        )?;
        let mut correlations = c.prepare_cached(
            "SELECT n.label, m.name, cc.correlation, cc.overlap
             FROM cell_correlations cc JOIN cells n ON n.id = cc.neighbour
                  JOIN modalities m ON m.id = cc.modality
             WHERE cc.cell = ?1 ORDER BY n.i, n.j, m.name",
        )?;
        let mut anomalies = c.prepare_cached(
            "SELECT m.name, ca.t, ca.anomaly, ca.flagged
             FROM cell_anomalies ca JOIN modalities m ON m.id = ca.modality
             WHERE ca.cell = ?1 ORDER BY m.name, ca.t",
        )?;
        type Row = (
            i64,
            String,
            Option<i64>,
            Option<f64>,
            Option<f64>,
            [Option<f64>; 5],
            Option<i64>,
        );
        let rows: Vec<Row> = stmt
            .query_map([], |r| {
                Ok((
                    r.get(0)?,
                    r.get(1)?,
                    r.get(2)?,
                    r.get(3)?,
                    r.get(4)?,
                    [r.get(5)?, r.get(6)?, r.get(7)?, r.get(8)?, r.get(9)?],
                    r.get(10)?,
                ))
            })?
            .collect::<rusqlite::Result<_>>()?;
        let mut out = Vec::with_capacity(rows.len());
        for (id, label, last_collected, pending_bytes, expected_energy_j, terms, computed_at) in
            rows
        {
            let mut md = CellMetadata::new(parse_cell("cells", &label)?);
            md.last_collected = last_collected;
            md.pending_bytes = pending_bytes;
            md.expected_energy_j = expected_energy_j;
            if let ([Some(f), Some(r), Some(a), Some(u), Some(s)], Some(at)) = (terms, computed_at)
            {
                md.scores = Some(CellScores {
                    freshness: f,
                    redundancy: r,
                    anomaly: a,
                    uncertainty: u,
                    score: s,
                    computed_at: at,
                });
            }
            for p in probs.query_map([id], |r| {
                Ok(ClassProbability {
                    class: r.get(0)?,
                    probability: r.get(1)?,
                })
            })? {
                md.class_probabilities.push(p?);
            }
            let srows = summaries.query_map([id], |r| {
                Ok((
                    r.get::<_, String>(0)?,
                    r.get::<_, i64>(1)?,
                    r.get::<_, f64>(2)?,
                    r.get::<_, Option<f64>>(3)?,
                    r.get::<_, f64>(4)?,
                    r.get::<_, f64>(5)?,
                    r.get::<_, i64>(6)?,
                    r.get::<_, f64>(7)?,
                ))
            })?;
            for s in srows {
                let (m, count, mean, std, min, max, latest_t, latest_value) = s?;
                md.summaries.push(ModalitySummary {
                    modality: parse_modality("cell_summaries", &m)?,
                    stats: SeriesStats {
                        count: count as u64,
                        mean,
                        std,
                        min,
                        max,
                        latest_t,
                        latest_value,
                    },
                });
            }
            let crows = correlations.query_map([id], |r| {
                Ok((
                    r.get::<_, String>(0)?,
                    r.get::<_, String>(1)?,
                    r.get::<_, f64>(2)?,
                    r.get::<_, i64>(3)?,
                ))
            })?;
            for c in crows {
                let (n, m, correlation, overlap) = c?;
                md.correlations.push(Correlation {
                    neighbour: parse_cell("cell_correlations", &n)?,
                    modality: parse_modality("cell_correlations", &m)?,
                    correlation,
                    overlap: overlap as u64,
                });
            }
            let arows = anomalies.query_map([id], |r| {
                Ok((
                    r.get::<_, String>(0)?,
                    r.get::<_, i64>(1)?,
                    r.get::<_, f64>(2)?,
                    r.get::<_, bool>(3)?,
                ))
            })?;
            for a in arows {
                let (m, t, anomaly, flagged) = a?;
                md.anomalies.push(AnomalyRecord {
                    modality: parse_modality("cell_anomalies", &m)?,
                    t,
                    anomaly,
                    flagged,
                });
            }
            out.push(md);
        }
        Ok(out)
    }

    fn upsert_cell_metadata(&mut self, metadata: &[CellMetadata]) -> Result<()> {
        validate_metadata(metadata)?;
        let tx = self.conn.transaction()?;
        write_metadata(&tx, metadata)?;
        tx.commit()?;
        Ok(())
    }

    fn refresh_cell_summaries(&mut self, params: &RefreshParams) -> Result<usize> {
        if !(params.bytes_per_reading.is_finite() && params.bytes_per_reading >= 0.0) {
            return Err(StoreError::Invalid {
                what: "bytes per reading",
                detail: format!("{} must be >= 0", params.bytes_per_reading),
            });
        }
        if !(params.default_interval_s.is_finite() && params.default_interval_s > 0.0) {
            return Err(StoreError::Invalid {
                what: "default logging interval",
                detail: format!("{} s must be > 0", params.default_interval_s),
            });
        }
        let tx = self.conn.transaction()?;
        let written;
        {
            // Cell series: mean over the cell's sensors at each t; then two-pass statistics.
            // One scan of the readings in key order (no sort) and the aggregation in memory:
            // several times faster than GROUP BY (cell, modality, t) in SQL on millions of rows.
            let cell_of: HashMap<i64, i64> = {
                let mut stmt = tx.prepare("SELECT sensor, cell FROM cell_sensors")?;
                let rows = stmt.query_map([], |r| Ok((r.get(0)?, r.get(1)?)))?;
                rows.collect::<rusqlite::Result<_>>()?
            };
            // The cells to recompute: all, or those holding a changed sensor.
            let targets: Option<HashSet<i64>> = match &params.changed_sensors {
                None => None,
                Some(changed) => {
                    let ids = Self::sensor_ids(&tx)?;
                    let cells: HashSet<i64> = changed
                        .iter()
                        .filter_map(|s| ids.get(s.as_str()))
                        .filter_map(|id| cell_of.get(id).copied())
                        .collect();
                    // Every cell changed (a first ingest): one sequential scan is faster than
                    // a query per sensor.
                    let all: HashSet<i64> = cell_of.values().copied().collect();
                    (cells.len() < all.len()).then_some(cells)
                }
            };
            let mut slots: HashMap<(i64, i64), HashMap<i64, (f64, u32)>> = HashMap::new();
            let mut add = |sensor: i64, modality: i64, t: i64, value: f64| {
                if let Some(&cell) = cell_of.get(&sensor) {
                    let slot = slots
                        .entry((cell, modality))
                        .or_default()
                        .entry(t)
                        .or_insert((0.0, 0));
                    slot.0 += value;
                    slot.1 += 1;
                }
            };
            match &targets {
                None => {
                    let mut stmt = tx.prepare("SELECT sensor, modality, t, value FROM readings")?;
                    let mut rows = stmt.query([])?;
                    while let Some(r) = rows.next()? {
                        add(r.get(0)?, r.get(1)?, r.get(2)?, r.get(3)?);
                    }
                }
                Some(cells) => {
                    let mut stmt =
                        tx.prepare("SELECT modality, t, value FROM readings WHERE sensor = ?1")?;
                    // Sensors in key order, so that sums are formed in the same order every run.
                    let mut sensors: Vec<i64> = cell_of
                        .iter()
                        .filter(|(_, cell)| cells.contains(cell))
                        .map(|(&s, _)| s)
                        .collect();
                    sensors.sort_unstable();
                    for sensor in sensors {
                        let mut rows = stmt.query([sensor])?;
                        while let Some(r) = rows.next()? {
                            add(sensor, r.get(0)?, r.get(1)?, r.get(2)?);
                        }
                    }
                }
            }
            type Row = (i64, i64, i64, f64, Option<f64>, f64, f64, i64, f64);
            let mut rows: Vec<Row> = slots
                .into_iter()
                .map(|((cell, modality), series)| {
                    let mut points: Vec<(i64, f64)> = series
                        .into_iter()
                        .map(|(t, (sum, n))| (t, sum / f64::from(n)))
                        .collect();
                    points.sort_unstable_by_key(|p| p.0);
                    let n = points.len();
                    let mean = points.iter().map(|p| p.1).sum::<f64>() / n as f64;
                    let ss = points
                        .iter()
                        .map(|p| (p.1 - mean) * (p.1 - mean))
                        .sum::<f64>();
                    let (min, max) = points
                        .iter()
                        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
                            (a.min(p.1), b.max(p.1))
                        });
                    let (latest_t, latest_v) = points[n - 1];
                    (
                        cell,
                        modality,
                        n as i64,
                        mean,
                        Some(ss),
                        min,
                        max,
                        latest_t,
                        latest_v,
                    )
                })
                .collect();
            rows.sort_unstable_by_key(|r| (r.0, r.1));
            match &targets {
                None => {
                    tx.execute("DELETE FROM cell_summaries", [])?;
                }
                Some(cells) => {
                    let mut delete = tx.prepare("DELETE FROM cell_summaries WHERE cell = ?1")?;
                    for cell in cells {
                        delete.execute([cell])?;
                    }
                }
            }
            let mut insert = tx.prepare_cached(
                "INSERT INTO cell_summaries (cell, modality, count, mean, std, min, max, latest_t,
                                             latest_value)
                 VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9)",
            )?;
            for (cell, modality, n, mean, ss, min, max, latest_t, latest_v) in &rows {
                let std = sample_std(*n as u64, *ss);
                insert.execute(params![
                    cell, modality, n, mean, std, min, max, latest_t, latest_v
                ])?;
            }
            written = rows.len();

            // Last collection and pending volume per cell.
            tx.execute(
                "INSERT INTO cell_metadata (cell, last_collected, pending_bytes)
                 WITH series AS (
                     SELECT sensor, modality, COUNT(*) AS n, MIN(t) AS t0, MAX(t) AS t1
                     FROM readings GROUP BY sensor, modality
                 ),
                 per_sensor AS (
                     SELECT se.sensor AS sensor,
                            SUM(MAX(0, ?1 - MAX(se.t1, COALESCE(sc.last_collected, se.t1))) * 1.0
                                / CASE WHEN se.n >= 2 AND se.t1 > se.t0
                                       THEN (se.t1 - se.t0) * 1.0 / (se.n - 1)
                                       ELSE ?2 END) AS pending
                     FROM series se LEFT JOIN sensor_collection sc ON sc.sensor = se.sensor
                     GROUP BY se.sensor
                 )
                 SELECT c.id,
                        (SELECT MAX(sc.last_collected) FROM cell_sensors cs
                         JOIN sensor_collection sc ON sc.sensor = cs.sensor WHERE cs.cell = c.id),
                        (SELECT SUM(ps.pending) FROM cell_sensors cs
                         JOIN per_sensor ps ON ps.sensor = cs.sensor WHERE cs.cell = c.id) * ?3
                 FROM cells c WHERE true
                 ON CONFLICT (cell) DO UPDATE SET
                     last_collected = CASE
                         WHEN excluded.last_collected IS NULL THEN cell_metadata.last_collected
                         WHEN cell_metadata.last_collected IS NULL THEN excluded.last_collected
                         ELSE MAX(excluded.last_collected, cell_metadata.last_collected) END,
                     pending_bytes = excluded.pending_bytes",
                params![
                    params.now,
                    params.default_interval_s,
                    params.bytes_per_reading
                ],
            )?;
        }
        tx.commit()?;
        Ok(written)
    }

    fn set_sensors_collected(&mut self, collected: &[(SensorId, UnixSeconds)]) -> Result<()> {
        let keys = Self::sensor_ids(&self.conn)?;
        let tx = self.conn.transaction()?;
        {
            let mut stmt = tx.prepare_cached(
                "INSERT INTO sensor_collection (sensor, last_collected) VALUES (?1, ?2)
                 ON CONFLICT (sensor) DO UPDATE
                 SET last_collected = MAX(last_collected, excluded.last_collected)",
            )?;
            for (s, t) in collected {
                let key = keys
                    .get(s.as_str())
                    .ok_or_else(|| StoreError::UnknownSensor(s.clone()))?;
                stmt.execute(params![key, t])?;
            }
        }
        tx.commit()?;
        Ok(())
    }

    fn sensor_last_collected(&self) -> Result<Vec<(SensorId, UnixSeconds)>> {
        let mut stmt = self.conn.prepare_cached(
            "SELECT s.name, sc.last_collected FROM sensor_collection sc
             JOIN sensors s ON s.id = sc.sensor ORDER BY s.name",
        )?;
        let rows = stmt.query_map([], |r| Ok((r.get::<_, String>(0)?, r.get(1)?)))?;
        let mut out = Vec::new();
        for row in rows {
            let (name, t) = row?;
            out.push((parse_sensor("sensor_collection", name)?, t));
        }
        Ok(out)
    }

    fn create_mission(&mut self, mission: &NewMission) -> Result<MissionId> {
        finite("mission budget", "budget_j", mission.budget_j)?;
        finite("mission energy", "energy_j", mission.energy_j)?;
        self.conn.execute(
            "INSERT INTO missions (created_at, kind, planned_at, solver, budget_j, energy_j,
                                   status, summary_json)
             VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8)",
            params![
                mission.created_at,
                mission.kind.as_str(),
                mission.planned_at,
                mission.solver,
                mission.budget_j,
                mission.energy_j,
                MissionStatus::Planned.as_str(),
                mission.summary_json
            ],
        )?;
        Ok(MissionId(self.conn.last_insert_rowid()))
    }

    fn record_visits(&mut self, mission: MissionId, visits: &[VisitRecord]) -> Result<()> {
        let mut orders = HashSet::new();
        for v in visits {
            if !orders.insert(v.order) {
                return Err(StoreError::Invalid {
                    what: "visit list",
                    detail: format!("visit order {} used twice in mission {mission}", v.order),
                });
            }
            if let Some(e) = v.energy_j {
                finite("visit energy", &v.cell.to_string(), e)?;
            }
        }
        let tx = self.conn.transaction()?;
        let updated = tx.execute(
            "UPDATE missions SET status = ?2 WHERE id = ?1",
            params![mission.0, MissionStatus::Flown.as_str()],
        )?;
        if updated == 0 {
            return Err(StoreError::Unknown {
                what: "mission",
                name: mission.to_string(),
            });
        }
        tx.execute("DELETE FROM visits WHERE mission = ?1", [mission.0])?;
        {
            let mut stmt = tx.prepare_cached(
                "INSERT INTO visits (mission, position, cell, arrived_at, energy_j)
                 VALUES (?1, ?2, ?3, ?4, ?5)",
            )?;
            for v in visits {
                stmt.execute(params![
                    mission.0,
                    v.order,
                    v.cell.to_string(),
                    v.arrived_at,
                    v.energy_j
                ])?;
            }
        }
        tx.commit()?;
        Ok(())
    }

    fn missions(&self) -> Result<Vec<MissionRecord>> {
        let mut stmt = self.conn.prepare_cached(
            "SELECT id, created_at, kind, planned_at, solver, budget_j, energy_j, status,
                    summary_json
             FROM missions ORDER BY id",
        )?;
        let mut visits = self.conn.prepare_cached(
            "SELECT position, cell, arrived_at, energy_j FROM visits WHERE mission = ?1
             ORDER BY position",
        )?;
        type Row = (i64, i64, String, i64, String, f64, f64, String, String);
        let rows: Vec<Row> = stmt
            .query_map([], |r| {
                Ok((
                    r.get(0)?,
                    r.get(1)?,
                    r.get(2)?,
                    r.get(3)?,
                    r.get(4)?,
                    r.get(5)?,
                    r.get(6)?,
                    r.get(7)?,
                    r.get(8)?,
                ))
            })?
            .collect::<rusqlite::Result<_>>()?;
        let mut out = Vec::with_capacity(rows.len());
        for (id, created_at, kind, planned_at, solver, budget_j, energy_j, status, summary_json) in
            rows
        {
            let kind = MissionKind::parse(&kind).ok_or_else(|| StoreError::Corrupt {
                table: "missions",
                detail: format!("mission {id}: unknown kind {kind:?}"),
            })?;
            let status = MissionStatus::parse(&status).ok_or_else(|| StoreError::Corrupt {
                table: "missions",
                detail: format!("mission {id}: unknown status {status:?}"),
            })?;
            let vrows = visits.query_map([id], |r| {
                Ok((
                    r.get::<_, u32>(0)?,
                    r.get::<_, String>(1)?,
                    r.get::<_, Option<i64>>(2)?,
                    r.get::<_, Option<f64>>(3)?,
                ))
            })?;
            let mut vs = Vec::new();
            for v in vrows {
                let (order, cell, arrived_at, energy_j) = v?;
                vs.push(VisitRecord {
                    order,
                    cell: parse_cell("visits", &cell)?,
                    arrived_at,
                    energy_j,
                });
            }
            out.push(MissionRecord {
                id: MissionId(id),
                mission: NewMission {
                    created_at,
                    kind,
                    planned_at,
                    solver,
                    budget_j,
                    energy_j,
                    summary_json,
                },
                status,
                visits: vs,
            });
        }
        Ok(out)
    }

    fn config_get(&self, key: &str) -> Result<Option<String>> {
        Ok(self
            .conn
            .query_row("SELECT value FROM config WHERE key = ?1", [key], |r| {
                r.get(0)
            })
            .optional()?)
    }

    fn config_set(&mut self, key: &str, value: &str) -> Result<()> {
        self.conn.execute(
            "INSERT INTO config (key, value) VALUES (?1, ?2)
             ON CONFLICT (key) DO UPDATE SET value = excluded.value",
            [key, value],
        )?;
        Ok(())
    }
}

/// Checks every number in `metadata` before anything is written.
fn validate_metadata(metadata: &[CellMetadata]) -> Result<()> {
    let mut cells = HashSet::new();
    for md in metadata {
        let cell = md.cell.to_string();
        if !cells.insert(md.cell) {
            return Err(StoreError::Invalid {
                what: "cell metadata",
                detail: format!("cell {cell} listed twice"),
            });
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
                return Err(StoreError::Invalid {
                    what: "class probability",
                    detail: format!(
                        "cell {cell} class {:?}: {} not in [0, 1]",
                        p.class, p.probability
                    ),
                });
            }
        }
        for c in &md.correlations {
            if !(-1.0..=1.0).contains(&c.correlation) {
                return Err(StoreError::Invalid {
                    what: "correlation",
                    detail: format!(
                        "cell {cell} neighbour {} {}: {} not in [-1, 1]",
                        c.neighbour, c.modality, c.correlation
                    ),
                });
            }
        }
        for a in &md.anomalies {
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
                finite("summary", &format!("{cell} {} {name}", s.modality), v)?;
            }
        }
    }
    Ok(())
}

/// Writes validated metadata inside `tx`.
fn write_metadata(tx: &Transaction<'_>, metadata: &[CellMetadata]) -> Result<()> {
    let cell_keys = SqliteStore::cell_ids(tx)?;
    let modality_keys = SqliteStore::modality_ids(tx)?;
    let cell_key = |c: &CellIndex| {
        cell_keys
            .get(&c.to_string())
            .copied()
            .ok_or_else(|| StoreError::Unknown {
                what: "cell",
                name: c.to_string(),
            })
    };
    let modality_key = |m: &Modality| {
        modality_keys
            .get(m.as_str())
            .copied()
            .ok_or_else(|| StoreError::UnknownModality(m.clone()))
    };
    let mut row = tx.prepare_cached(
        "INSERT OR REPLACE INTO cell_metadata (cell, last_collected, pending_bytes,
             expected_energy_j, freshness, redundancy, anomaly, uncertainty, score, computed_at)
         VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10)",
    )?;
    let mut clear_probs =
        tx.prepare_cached("DELETE FROM cell_class_probabilities WHERE cell = ?1")?;
    let mut prob = tx.prepare_cached(
        "INSERT INTO cell_class_probabilities (cell, k, class, probability) VALUES (?1, ?2, ?3, ?4)",
    )?;
    let mut summary = tx.prepare_cached(
        "INSERT OR REPLACE INTO cell_summaries (cell, modality, count, mean, std, min, max,
             latest_t, latest_value)
         VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9)",
    )?;
    let mut correlation = tx.prepare_cached(
        "INSERT OR REPLACE INTO cell_correlations (cell, neighbour, modality, correlation, overlap)
         VALUES (?1, ?2, ?3, ?4, ?5)",
    )?;
    let mut anomaly = tx.prepare_cached(
        "INSERT OR REPLACE INTO cell_anomalies (cell, modality, t, anomaly, flagged)
         VALUES (?1, ?2, ?3, ?4, ?5)",
    )?;
    for md in metadata {
        let c = cell_key(&md.cell)?;
        let s = md.scores.as_ref();
        row.execute(params![
            c,
            md.last_collected,
            md.pending_bytes,
            md.expected_energy_j,
            s.map(|s| s.freshness),
            s.map(|s| s.redundancy),
            s.map(|s| s.anomaly),
            s.map(|s| s.uncertainty),
            s.map(|s| s.score),
            s.map(|s| s.computed_at)
        ])?;
        clear_probs.execute([c])?;
        for (k, p) in md.class_probabilities.iter().enumerate() {
            prob.execute(params![c, k as i64, p.class, p.probability])?;
        }
        for su in &md.summaries {
            let st = &su.stats;
            summary.execute(params![
                c,
                modality_key(&su.modality)?,
                i64::try_from(st.count).unwrap_or(i64::MAX),
                st.mean,
                st.std,
                st.min,
                st.max,
                st.latest_t,
                st.latest_value
            ])?;
        }
        for co in &md.correlations {
            correlation.execute(params![
                c,
                cell_key(&co.neighbour)?,
                modality_key(&co.modality)?,
                co.correlation,
                i64::try_from(co.overlap).unwrap_or(i64::MAX)
            ])?;
        }
        for a in &md.anomalies {
            anomaly.execute(params![
                c,
                modality_key(&a.modality)?,
                a.t,
                a.anomaly,
                a.flagged
            ])?;
        }
    }
    Ok(())
}
