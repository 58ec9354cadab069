//! The PostgreSQL schema of one project, as an ordered list of migrations.
//!
//! Every project lives in its own schema (namespace) of the database; its tables are the
//! SQLite tables of the same names and meaning (see the crate docs), with PostgreSQL types:
//! `BIGINT` for integers and times (s), `DOUBLE PRECISION` for reals, `BOOLEAN` for flags,
//! `BYTEA` for blobs, identity columns for surrogate keys. Text is ordered with the `"C"`
//! collation wherever order matters, so both backends sort names byte-wise whatever the
//! database's locale.
//!
//! Migration `k` (1-based) brings a project's schema from version `k - 1` to `k`; it runs in
//! one transaction with its `schema_migrations` row, under the project's advisory lock, so a
//! crash leaves a whole version and two processes opening a new project apply each step
//! once. Never edit a released migration: append one. The version numbers are those of the
//! SQLite schema of the same content (PostgreSQL projects start at version 2, SQLite's
//! layout since typed missions), so `schema_version` means the same on both backends.

/// One schema step.
pub(super) struct Migration {
    /// The version it brings the schema to.
    pub version: i64,
    /// What it does, stored in `schema_migrations.description`.
    pub description: &'static str,
    /// The SQL script (run with the project's schema first on the `search_path`).
    pub sql: &'static str,
}

/// All migrations, oldest first.
pub(super) const MIGRATIONS: &[Migration] = &[
    Migration {
        version: 2,
        description: "initial PostgreSQL schema (the SQLite schema of version 2): sensors, modalities, readings, ingests, cells, cell metadata, typed missions with stops and visits, config, blobs",
        sql: r#"
CREATE TABLE sensors (
    id          BIGINT GENERATED ALWAYS AS IDENTITY PRIMARY KEY,
    name        TEXT             NOT NULL UNIQUE,
    lat         DOUBLE PRECISION NOT NULL CHECK (lat BETWEEN -90 AND 90),
    lon         DOUBLE PRECISION NOT NULL CHECK (lon BETWEEN -180 AND 180),
    elevation_m DOUBLE PRECISION,
    source      TEXT             NOT NULL
);

CREATE TABLE modalities (
    id   BIGINT GENERATED ALWAYS AS IDENTITY PRIMARY KEY,
    name TEXT NOT NULL UNIQUE,
    unit TEXT
);

-- sensor and modality are not declared REFERENCES, as in SQLite: insert_readings resolves
-- every name to an existing key first and the store never deletes sensors or modalities.
CREATE TABLE readings (
    sensor   BIGINT           NOT NULL,
    modality BIGINT           NOT NULL,
    t        BIGINT           NOT NULL,
    value    DOUBLE PRECISION NOT NULL,
    PRIMARY KEY (sensor, modality, t)
);

CREATE TABLE ingests (
    id             BIGINT GENERATED ALWAYS AS IDENTITY PRIMARY KEY,
    file_name      TEXT   NOT NULL,
    format         TEXT   NOT NULL,
    rows_read      BIGINT NOT NULL,
    rows_inserted  BIGINT NOT NULL,
    rows_unchanged BIGINT NOT NULL,
    rows_skipped   BIGINT NOT NULL,
    at             BIGINT NOT NULL
);

CREATE TABLE sensor_collection (
    sensor         BIGINT PRIMARY KEY REFERENCES sensors (id) ON DELETE CASCADE,
    last_collected BIGINT NOT NULL
);

CREATE TABLE cells (
    id          BIGINT GENERATED ALWAYS AS IDENTITY PRIMARY KEY,
    label       TEXT             NOT NULL UNIQUE,
    i           BIGINT           NOT NULL,
    j           BIGINT           NOT NULL,
    lat         DOUBLE PRECISION NOT NULL,
    lon         DOUBLE PRECISION NOT NULL,
    cell_size_m DOUBLE PRECISION NOT NULL CHECK (cell_size_m > 0),
    UNIQUE (i, j)
);

CREATE TABLE cell_sensors (
    cell   BIGINT NOT NULL REFERENCES cells (id) ON DELETE CASCADE,
    sensor BIGINT NOT NULL UNIQUE REFERENCES sensors (id) ON DELETE CASCADE,
    PRIMARY KEY (cell, sensor)
);

CREATE TABLE cell_metadata (
    cell              BIGINT PRIMARY KEY REFERENCES cells (id) ON DELETE CASCADE,
    last_collected    BIGINT,
    pending_bytes     DOUBLE PRECISION,
    expected_energy_j DOUBLE PRECISION,
    freshness         DOUBLE PRECISION,
    redundancy        DOUBLE PRECISION,
    anomaly           DOUBLE PRECISION,
    uncertainty       DOUBLE PRECISION,
    score             DOUBLE PRECISION,
    computed_at       BIGINT
);

CREATE TABLE cell_class_probabilities (
    cell        BIGINT           NOT NULL REFERENCES cells (id) ON DELETE CASCADE,
    k           BIGINT           NOT NULL,
    class       TEXT             NOT NULL,
    probability DOUBLE PRECISION NOT NULL CHECK (probability BETWEEN 0 AND 1),
    PRIMARY KEY (cell, k)
);

CREATE TABLE cell_summaries (
    cell         BIGINT           NOT NULL REFERENCES cells (id) ON DELETE CASCADE,
    modality     BIGINT           NOT NULL REFERENCES modalities (id),
    count        BIGINT           NOT NULL,
    mean         DOUBLE PRECISION NOT NULL,
    std          DOUBLE PRECISION,
    min          DOUBLE PRECISION NOT NULL,
    max          DOUBLE PRECISION NOT NULL,
    latest_t     BIGINT           NOT NULL,
    latest_value DOUBLE PRECISION NOT NULL,
    PRIMARY KEY (cell, modality)
);

CREATE TABLE cell_correlations (
    cell        BIGINT           NOT NULL REFERENCES cells (id) ON DELETE CASCADE,
    neighbour   BIGINT           NOT NULL REFERENCES cells (id) ON DELETE CASCADE,
    modality    BIGINT           NOT NULL REFERENCES modalities (id),
    correlation DOUBLE PRECISION NOT NULL CHECK (correlation BETWEEN -1 AND 1),
    overlap     BIGINT           NOT NULL,
    PRIMARY KEY (cell, neighbour, modality)
);
CREATE INDEX cell_correlations_neighbour ON cell_correlations (neighbour);

CREATE TABLE cell_anomalies (
    cell     BIGINT           NOT NULL REFERENCES cells (id) ON DELETE CASCADE,
    modality BIGINT           NOT NULL REFERENCES modalities (id),
    t        BIGINT           NOT NULL,
    anomaly  DOUBLE PRECISION NOT NULL,
    flagged  BOOLEAN          NOT NULL,
    PRIMARY KEY (cell, modality, t)
);

CREATE TABLE missions (
    id                BIGINT GENERATED BY DEFAULT AS IDENTITY PRIMARY KEY,
    created_at        BIGINT           NOT NULL,
    kind              TEXT             NOT NULL CHECK (kind IN ('exploration', 'adaptive')),
    planned_at        BIGINT           NOT NULL,
    solver            TEXT             NOT NULL,
    seed              BIGINT           NOT NULL,
    weight_alpha      DOUBLE PRECISION NOT NULL,
    weight_beta       DOUBLE PRECISION NOT NULL,
    weight_gamma      DOUBLE PRECISION NOT NULL,
    weight_delta      DOUBLE PRECISION NOT NULL,
    anomaly_form      TEXT             NOT NULL,
    total_score       DOUBLE PRECISION NOT NULL,
    base_lat          DOUBLE PRECISION NOT NULL CHECK (base_lat BETWEEN -90 AND 90),
    base_lon          DOUBLE PRECISION NOT NULL CHECK (base_lon BETWEEN -180 AND 180),
    base_alt_m        DOUBLE PRECISION NOT NULL,
    altitude_m        DOUBLE PRECISION NOT NULL,
    cruise_speed_mps  DOUBLE PRECISION NOT NULL,
    travel_j          DOUBLE PRECISION NOT NULL,
    hover_j           DOUBLE PRECISION NOT NULL,
    comm_j            DOUBLE PRECISION NOT NULL,
    return_j          DOUBLE PRECISION NOT NULL,
    total_j           DOUBLE PRECISION NOT NULL,
    budget_j          DOUBLE PRECISION NOT NULL,
    distance_m        DOUBLE PRECISION NOT NULL,
    flight_time_s     DOUBLE PRECISION NOT NULL,
    return_distance_m DOUBLE PRECISION NOT NULL,
    status            TEXT             NOT NULL CHECK (status IN ('planned', 'flown')),
    flown_at          BIGINT,
    summary_json      TEXT,
    CHECK ((status = 'flown') = (flown_at IS NOT NULL))
);

CREATE TABLE mission_stops (
    mission        BIGINT           NOT NULL REFERENCES missions (id) ON DELETE CASCADE,
    position       BIGINT           NOT NULL,
    cell           TEXT             NOT NULL,
    lat            DOUBLE PRECISION NOT NULL CHECK (lat BETWEEN -90 AND 90),
    lon            DOUBLE PRECISION NOT NULL CHECK (lon BETWEEN -180 AND 180),
    score          DOUBLE PRECISION NOT NULL,
    freshness      DOUBLE PRECISION,
    redundancy     DOUBLE PRECISION,
    anomaly        DOUBLE PRECISION,
    uncertainty    DOUBLE PRECISION,
    leg_distance_m DOUBLE PRECISION NOT NULL,
    leg_energy_j   DOUBLE PRECISION NOT NULL,
    collection_s   DOUBLE PRECISION NOT NULL,
    hover_s        DOUBLE PRECISION NOT NULL,
    hover_j        DOUBLE PRECISION NOT NULL,
    comm_j         DOUBLE PRECISION NOT NULL,
    PRIMARY KEY (mission, position)
);

CREATE TABLE visits (
    mission    BIGINT NOT NULL REFERENCES missions (id) ON DELETE CASCADE,
    position   BIGINT NOT NULL,
    cell       TEXT   NOT NULL,
    arrived_at BIGINT,
    energy_j   DOUBLE PRECISION,
    PRIMARY KEY (mission, position)
);

CREATE TABLE config (
    key   TEXT PRIMARY KEY,
    value TEXT NOT NULL
);

CREATE TABLE blobs (
    key   TEXT  PRIMARY KEY,
    value BYTEA NOT NULL
);
"#,
    },
    MIGRATION_3,
    MIGRATION_4,
];

/// Version 4 (as SQLite's): a planned mission can be cancelled; it stays in the history,
/// flagged, and is never recorded or exported.
const MIGRATION_4: Migration = Migration {
    version: 4,
    description: "cancelled missions (missions.cancelled)",
    sql: r#"
ALTER TABLE missions
    ADD COLUMN cancelled BOOLEAN NOT NULL DEFAULT FALSE
        CHECK (NOT cancelled OR status = 'planned');
"#,
};

/// Version 3 (as SQLite's): the steady wind a mission's legs were priced in.
const MIGRATION_3: Migration = Migration {
    version: 3,
    description: "the wind each mission was planned in (missions.wind_mps, wind_from_deg)",
    sql: r#"
ALTER TABLE missions
    ADD COLUMN wind_mps      DOUBLE PRECISION NOT NULL DEFAULT 0 CHECK (wind_mps >= 0),
    ADD COLUMN wind_from_deg DOUBLE PRECISION NOT NULL DEFAULT 0;
"#,
};

/// The latest schema version (the same number as SQLite's latest).
pub(super) fn latest_version() -> i64 {
    MIGRATIONS.last().map_or(0, |m| m.version)
}
