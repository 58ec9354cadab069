//! The SQLite schema as an ordered list of migrations.
//!
//! Migration `k` (1-based) brings the schema from version `k - 1` to `k`. Each runs in its own
//! transaction together with its row in `schema_migrations` and `PRAGMA user_version` (the
//! SQLite store's `migrate`; PostgreSQL's its own), so a crash leaves the database at a whole
//! version. Never edit a released migration: append one.

/// One schema step.
pub(crate) struct Migration {
    /// What it does, stored in `schema_migrations.description`.
    pub description: &'static str,
    /// The SQL script.
    pub sql: &'static str,
}

/// All migrations, oldest first. The schema version is the number applied.
pub(crate) const MIGRATIONS: &[Migration] = &[
    Migration {
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
    },
    Migration {
        description: "typed missions (profile, energy breakdown, flown_at) with their stops; blobs",
        sql: MIGRATION_2,
    },
    Migration {
        description: "the wind each mission was planned in (missions.wind_mps, wind_from_deg)",
        sql: MIGRATION_3,
    },
    Migration {
        description: "cancelled missions (missions.cancelled)",
        sql: MIGRATION_4,
    },
];

/// Version 4: a planned mission can be cancelled: it stays in the history, flagged, and is
/// never recorded or exported (`cancelled` is 0 or 1, and 1 only on a planned mission).
const MIGRATION_4: &str = r#"
ALTER TABLE missions ADD COLUMN cancelled INTEGER NOT NULL DEFAULT 0
    CHECK (cancelled IN (0, 1) AND (cancelled = 0 OR status = 'planned'));
"#;

/// Version 3: the steady wind a mission's legs were priced in (m/s, and the direction it
/// blows from, degrees from north); missions planned before are still-air plans (0, 0).
const MIGRATION_3: &str = r#"
ALTER TABLE missions ADD COLUMN wind_mps      REAL NOT NULL DEFAULT 0 CHECK (wind_mps >= 0);
ALTER TABLE missions ADD COLUMN wind_from_deg REAL NOT NULL DEFAULT 0;
"#;

/// Version 2: typed missions with their stops, and blobs.
///
/// SQLite cannot add NOT NULL columns or relax NOT NULL in place, so `missions` is recreated
/// and its rows copied (and `visits` with it: its foreign key must point at the new table, and
/// dropping the old `missions` with `visits` still attached would cascade-delete the visits).
/// A legacy row's fields are taken from its `summary_json` where the old planner wrote them
/// (adaptive missions: seed, weights, anomaly form, base, speed, energy breakdown, stops),
/// otherwise defaulted: zero energies, distances and speed, the sensors' mean position as base,
/// altitudes 0 m, anomaly form `n/a`; exploration stops take their cell's centre when the cell
/// still exists. A legacy flown mission gets its latest visit arrival, else its planned time,
/// as `flown_at`. New rows leave `summary_json` NULL.
const MIGRATION_2: &str = r#"
CREATE TABLE missions_v2 (
    id                INTEGER PRIMARY KEY,
    created_at        INTEGER NOT NULL,
    kind              TEXT    NOT NULL CHECK (kind IN ('exploration', 'adaptive')),
    planned_at        INTEGER NOT NULL,
    solver            TEXT    NOT NULL,
    seed              INTEGER NOT NULL,
    weight_alpha      REAL    NOT NULL,
    weight_beta       REAL    NOT NULL,
    weight_gamma      REAL    NOT NULL,
    weight_delta      REAL    NOT NULL,
    anomaly_form      TEXT    NOT NULL,
    total_score       REAL    NOT NULL,
    base_lat          REAL    NOT NULL CHECK (base_lat BETWEEN -90 AND 90),
    base_lon          REAL    NOT NULL CHECK (base_lon BETWEEN -180 AND 180),
    base_alt_m        REAL    NOT NULL,
    altitude_m        REAL    NOT NULL,
    cruise_speed_mps  REAL    NOT NULL,
    travel_j          REAL    NOT NULL,
    hover_j           REAL    NOT NULL,
    comm_j            REAL    NOT NULL,
    return_j          REAL    NOT NULL,
    total_j           REAL    NOT NULL,
    budget_j          REAL    NOT NULL,
    distance_m        REAL    NOT NULL,
    flight_time_s     REAL    NOT NULL,
    return_distance_m REAL    NOT NULL,
    status            TEXT    NOT NULL CHECK (status IN ('planned', 'flown')),
    flown_at          INTEGER,
    summary_json      TEXT,
    CHECK ((status = 'flown') = (flown_at IS NOT NULL))
);

INSERT INTO missions_v2
SELECT m.id, m.created_at, m.kind, m.planned_at, m.solver,
       COALESCE(CAST(json_extract(m.js, '$.seed') AS INTEGER), 0),
       COALESCE(json_extract(m.js, '$.weights[0]'), 0.0),
       COALESCE(json_extract(m.js, '$.weights[1]'), 0.0),
       COALESCE(json_extract(m.js, '$.weights[2]'), 0.0),
       COALESCE(json_extract(m.js, '$.weights[3]'), 0.0),
       COALESCE(json_extract(m.js, '$.anomaly_form'), 'n/a'),
       COALESCE(json_extract(m.js, '$.total_score'), 0.0),
       COALESCE(json_extract(m.js, '$.base_lon_lat[1]'), (SELECT AVG(lat) FROM sensors), 0.0),
       COALESCE(json_extract(m.js, '$.base_lon_lat[0]'), (SELECT AVG(lon) FROM sensors), 0.0),
       0.0,
       0.0,
       COALESCE(json_extract(m.js, '$.cruise_speed_mps'), 0.0),
       COALESCE(json_extract(m.js, '$.energy.travel_j'), 0.0),
       COALESCE(json_extract(m.js, '$.energy.hover_j'), 0.0),
       COALESCE(json_extract(m.js, '$.energy.comm_j'), 0.0),
       COALESCE(json_extract(m.js, '$.energy.return_j'), 0.0),
       m.energy_j,
       m.budget_j,
       COALESCE(json_extract(m.js, '$.energy.distance_m'), 0.0),
       COALESCE(json_extract(m.js, '$.energy.flight_time_s'), 0.0),
       COALESCE(json_extract(m.js, '$.return_distance_m'), 0.0),
       m.status,
       CASE WHEN m.status = 'flown'
            THEN COALESCE((SELECT MAX(v.arrived_at) FROM visits v WHERE v.mission = m.id),
                          m.planned_at)
       END,
       m.summary_json
FROM (SELECT *, CASE WHEN json_valid(summary_json) THEN summary_json ELSE '{}' END AS js
      FROM missions) m
ORDER BY m.id;

CREATE TABLE visits_v2 (
    mission    INTEGER NOT NULL REFERENCES missions_v2 (id) ON DELETE CASCADE,
    position   INTEGER NOT NULL,
    cell       TEXT    NOT NULL,
    arrived_at INTEGER,
    energy_j   REAL,
    PRIMARY KEY (mission, position)
) WITHOUT ROWID;
INSERT INTO visits_v2 SELECT mission, position, cell, arrived_at, energy_j FROM visits;

CREATE TABLE mission_stops (
    mission        INTEGER NOT NULL REFERENCES missions_v2 (id) ON DELETE CASCADE,
    position       INTEGER NOT NULL,
    cell           TEXT    NOT NULL,
    lat            REAL    NOT NULL CHECK (lat BETWEEN -90 AND 90),
    lon            REAL    NOT NULL CHECK (lon BETWEEN -180 AND 180),
    score          REAL    NOT NULL,
    freshness      REAL,
    redundancy     REAL,
    anomaly        REAL,
    uncertainty    REAL,
    leg_distance_m REAL    NOT NULL,
    leg_energy_j   REAL    NOT NULL,
    collection_s   REAL    NOT NULL,
    hover_s        REAL    NOT NULL,
    hover_j        REAL    NOT NULL,
    comm_j         REAL    NOT NULL,
    PRIMARY KEY (mission, position)
) WITHOUT ROWID;

INSERT INTO mission_stops
SELECT st.id, st.position, st.label,
       COALESCE(json_extract(st.v, '$.centre_lon_lat[1]'),
                (SELECT c.lat FROM cells c WHERE c.label = st.label), st.base_lat),
       COALESCE(json_extract(st.v, '$.centre_lon_lat[0]'),
                (SELECT c.lon FROM cells c WHERE c.label = st.label), st.base_lon),
       COALESCE(json_extract(st.v, '$.s'), 0.0),
       json_extract(st.v, '$.terms[0]'),
       json_extract(st.v, '$.terms[1]'),
       json_extract(st.v, '$.terms[2]'),
       json_extract(st.v, '$.terms[3]'),
       COALESCE(json_extract(st.v, '$.leg_distance_m'), 0.0),
       COALESCE(json_extract(st.v, '$.leg_energy_j'), 0.0),
       COALESCE(json_extract(st.v, '$.collection_s'), 0.0),
       COALESCE(json_extract(st.v, '$.hover_s'), 0.0),
       COALESCE(json_extract(st.v, '$.hover_j'), 0.0),
       COALESCE(json_extract(st.v, '$.comm_j'), 0.0)
FROM (SELECT m.id AS id, m.base_lat AS base_lat, m.base_lon AS base_lon,
             CAST(s.key AS INTEGER) AS position, json_extract(s.value, '$.cell') AS label,
             s.value AS v
      FROM missions_v2 m,
           json_each(CASE WHEN json_valid(m.summary_json) THEN m.summary_json ELSE '{}' END,
                     '$.stops') s) st
WHERE st.label IS NOT NULL
ORDER BY st.id, st.position;

DROP TABLE visits;
DROP TABLE missions;
ALTER TABLE missions_v2 RENAME TO missions;
ALTER TABLE visits_v2 RENAME TO visits;

CREATE TABLE blobs (
    key   TEXT PRIMARY KEY,
    value BLOB NOT NULL
) WITHOUT ROWID;
"#;

/// The schema version this build writes.
pub(crate) fn latest_version() -> i64 {
    MIGRATIONS.len() as i64
}
