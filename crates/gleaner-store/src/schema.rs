//! The SQLite schema as an ordered list of migrations.
//!
//! Migration `k` (1-based) brings the schema from version `k - 1` to `k`. Each runs in its own
//! transaction together with its row in `schema_migrations` and `PRAGMA user_version`, so a
//! crash leaves the database at a whole version. Never edit a released migration: append one.

use rusqlite::{Connection, OptionalExtension};

use crate::{Result, StoreError};

/// One schema step.
pub(crate) struct Migration {
    /// What it does, stored in `schema_migrations.description`.
    pub description: &'static str,
    /// The SQL script.
    pub sql: &'static str,
}

/// All migrations, oldest first. The schema version is the number applied.
pub(crate) const MIGRATIONS: &[Migration] = &[Migration {
    description: "initial schema: sensors, modalities, readings, ingests, cells, cell metadata, missions, config",
    sql: r#"
CREATE TABLE sensors (
    id          INTEGER PRIMARY KEY,
    name        TEXT    NOT NULL UNIQUE,
    lat         REAL    NOT NULL CHECK (lat BETWEEN -90 AND 90),
    lon         REAL    NOT NULL CHECK (lon BETWEEN -180 AND 180),
    elevation_m REAL,
    source      TEXT    NOT NULL
);

CREATE TABLE modalities (
    id   INTEGER PRIMARY KEY,
    name TEXT    NOT NULL UNIQUE,
    unit TEXT
);

CREATE TABLE readings (
    sensor   INTEGER NOT NULL,
    modality INTEGER NOT NULL,
    t        INTEGER NOT NULL,
    value    REAL    NOT NULL,
    PRIMARY KEY (sensor, modality, t)
) WITHOUT ROWID;

CREATE TABLE ingests (
    id             INTEGER PRIMARY KEY,
    file_name      TEXT    NOT NULL,
    format         TEXT    NOT NULL,
    rows_read      INTEGER NOT NULL,
    rows_inserted  INTEGER NOT NULL,
    rows_unchanged INTEGER NOT NULL,
    rows_skipped   INTEGER NOT NULL,
    at             INTEGER NOT NULL
);

CREATE TABLE sensor_collection (
    sensor         INTEGER PRIMARY KEY REFERENCES sensors (id) ON DELETE CASCADE,
    last_collected INTEGER NOT NULL
);

CREATE TABLE cells (
    id          INTEGER PRIMARY KEY,
    label       TEXT    NOT NULL UNIQUE,
    i           INTEGER NOT NULL,
    j           INTEGER NOT NULL,
    lat         REAL    NOT NULL,
    lon         REAL    NOT NULL,
    cell_size_m REAL    NOT NULL CHECK (cell_size_m > 0),
    UNIQUE (i, j)
);

CREATE TABLE cell_sensors (
    cell   INTEGER NOT NULL REFERENCES cells (id) ON DELETE CASCADE,
    sensor INTEGER NOT NULL UNIQUE REFERENCES sensors (id) ON DELETE CASCADE,
    PRIMARY KEY (cell, sensor)
) WITHOUT ROWID;

CREATE TABLE cell_metadata (
    cell              INTEGER PRIMARY KEY REFERENCES cells (id) ON DELETE CASCADE,
    last_collected    INTEGER,
    pending_bytes     REAL,
    expected_energy_j REAL,
    freshness         REAL,
    redundancy        REAL,
    anomaly           REAL,
    uncertainty       REAL,
    score             REAL,
    computed_at       INTEGER
);

CREATE TABLE cell_class_probabilities (
    cell        INTEGER NOT NULL REFERENCES cells (id) ON DELETE CASCADE,
    k           INTEGER NOT NULL,
    class       TEXT    NOT NULL,
    probability REAL    NOT NULL CHECK (probability BETWEEN 0 AND 1),
    PRIMARY KEY (cell, k)
) WITHOUT ROWID;

CREATE TABLE cell_summaries (
    cell         INTEGER NOT NULL REFERENCES cells (id) ON DELETE CASCADE,
    modality     INTEGER NOT NULL REFERENCES modalities (id),
    count        INTEGER NOT NULL,
    mean         REAL    NOT NULL,
    std          REAL,
    min          REAL    NOT NULL,
    max          REAL    NOT NULL,
    latest_t     INTEGER NOT NULL,
    latest_value REAL    NOT NULL,
    PRIMARY KEY (cell, modality)
) WITHOUT ROWID;

CREATE TABLE cell_correlations (
    cell        INTEGER NOT NULL REFERENCES cells (id) ON DELETE CASCADE,
    neighbour   INTEGER NOT NULL REFERENCES cells (id) ON DELETE CASCADE,
    modality    INTEGER NOT NULL REFERENCES modalities (id),
    correlation REAL    NOT NULL CHECK (correlation BETWEEN -1 AND 1),
    overlap     INTEGER NOT NULL,
    PRIMARY KEY (cell, neighbour, modality)
) WITHOUT ROWID;
CREATE INDEX cell_correlations_neighbour ON cell_correlations (neighbour);

CREATE TABLE cell_anomalies (
    cell     INTEGER NOT NULL REFERENCES cells (id) ON DELETE CASCADE,
    modality INTEGER NOT NULL REFERENCES modalities (id),
    t        INTEGER NOT NULL,
    anomaly  REAL    NOT NULL,
    flagged  INTEGER NOT NULL CHECK (flagged IN (0, 1)),
    PRIMARY KEY (cell, modality, t)
) WITHOUT ROWID;

CREATE TABLE missions (
    id           INTEGER PRIMARY KEY,
    created_at   INTEGER NOT NULL,
    kind         TEXT    NOT NULL CHECK (kind IN ('exploration', 'adaptive')),
    planned_at   INTEGER NOT NULL,
    solver       TEXT    NOT NULL,
    budget_j     REAL    NOT NULL,
    energy_j     REAL    NOT NULL,
    status       TEXT    NOT NULL CHECK (status IN ('planned', 'flown')),
    summary_json TEXT    NOT NULL
);

CREATE TABLE visits (
    mission    INTEGER NOT NULL REFERENCES missions (id) ON DELETE CASCADE,
    position   INTEGER NOT NULL,
    cell       TEXT    NOT NULL,
    arrived_at INTEGER,
    energy_j   REAL,
    PRIMARY KEY (mission, position)
) WITHOUT ROWID;

CREATE TABLE config (
    key   TEXT PRIMARY KEY,
    value TEXT NOT NULL
) WITHOUT ROWID;
"#,
}];

/// The schema version this build writes.
pub(crate) fn latest_version() -> i64 {
    MIGRATIONS.len() as i64
}

/// Brings `conn` to the latest schema, or fails with [`StoreError::SchemaTooNew`] if the
/// database is newer than this build. Returns the version found before migrating.
pub(crate) fn migrate(conn: &mut Connection) -> Result<i64> {
    migrate_with(conn, MIGRATIONS)
}

/// [`migrate`] with an explicit list (tests use longer lists).
pub(crate) fn migrate_with(conn: &mut Connection, migrations: &[Migration]) -> Result<i64> {
    conn.execute_batch(
        "CREATE TABLE IF NOT EXISTS schema_migrations (
             version     INTEGER PRIMARY KEY,
             applied_at  INTEGER NOT NULL,
             description TEXT    NOT NULL
         );",
    )?;
    let supported = migrations.len() as i64;
    let recorded: i64 = conn
        .query_row("SELECT MAX(version) FROM schema_migrations", [], |r| {
            r.get::<_, Option<i64>>(0)
        })
        .optional()?
        .flatten()
        .unwrap_or(0);
    let user_version: i64 = conn.query_row("PRAGMA user_version", [], |r| r.get(0))?;
    let found = recorded.max(user_version);
    if found > supported {
        return Err(StoreError::SchemaTooNew { found, supported });
    }
    for (k, m) in migrations.iter().enumerate().skip(found as usize) {
        let version = k as i64 + 1;
        let tx = conn.transaction()?;
        tx.execute_batch(m.sql)?;
        tx.execute(
            "INSERT INTO schema_migrations (version, applied_at, description)
             VALUES (?1, CAST(strftime('%s', 'now') AS INTEGER), ?2)",
            rusqlite::params![version, m.description],
        )?;
        tx.pragma_update(None, "user_version", version)?;
        tx.commit()?;
    }
    Ok(found)
}
