//! gleaner's application layer: every use case of the mission lifecycle, over any
//! [`gleaner_store::Store`].
//!
//! This crate plays the role rust-analyzer's `ide` crate plays: adapters (the CLI, the HTTP
//! server, the campaign simulator `gleaner-campaign`) call these functions and translate their plain typed
//! results into text, JSON or files. Nothing here parses arguments, prints, reads the wall
//! clock or knows SQL: the clock comes in as an argument (`clock_now`, seconds since the Unix
//! epoch, recorded as provenance only, never used for results), progress goes out through
//! [`Progress`], and errors are one typed [`AppError`].
//!
//! The use cases, each one transaction when it writes (a failure writes nothing):
//!
//! | use case | reads | writes |
//! |---|---|---|
//! | [`init()`] / [`init_store`] | a sensors file | sensors, cells, `gleaner.toml` |
//! | [`ingest()`] | readings files | modalities, readings, provenance, changed cells' summaries, the persisted utility state |
//! | [`score()`] (and [`compute`]) | what is known at t (in the common case: the persisted utility state only) | the cell metadata table |
//! | [`plan()`] | scores (or a scores file), the energy model | scoring, expected energies, the mission with its stops |
//! | [`explore()`] | the grid, the energy model | one exploration mission per sortie |
//! | [`export()`] | a mission | nothing (checks it is safe to fly) |
//! | [`record_flight`] | a mission, visited cells, readings files | readings, collections, visits, summaries, the persisted utility state |
//! | [`migrate()`] | every table of one store | every table of another, empty one (SQLite <-> PostgreSQL) |
//! | [`migrate_project`] | a project's database | [`migrate()`] into another; with `switch` the `database` setting |
//!
//! The persisted utility state (the statistics behind A and R and the condition model behind
//! U, one store blob kept up to date inside the ingest and record transactions) lets
//! [`compute`] score the common request — all history, the built-in model, `at` at or after
//! the newest reading — in O(cells × neighbours) instead of O(history); [`compute_full`]
//! always reads the history. Both give the same scores within 1e-9 relative.
//!
//! Evaluation: [`reconstruct`] estimates every sensor's current value (last value carried
//! forward, and space-time kriging with its variance) from what is known; the campaign
//! simulator (`gleaner-campaign`) replays a dataset as a campaign of missions per strategy
//! through these same use cases and the few [`shortcuts`] a long replay needs.
//!
//! Read models: [`field_view`] (the cell table), [`missions`], [`mission`],
//! [`exploration_sorties`] (with their routes around no-fly zones), [`cell_detail`]
//! (one cell's weighted terms, rank and recent series).
//!
//! Units: times are seconds since 1970-01-01T00:00:00Z (UTC); positions WGS84 ([`LatLon`],
//! lat then lon); lengths metres; energies joules; data volumes bytes.
//!
//! [`LatLon`]: gleaner_field::LatLon
#![deny(missing_docs)]

pub mod airspace;
mod cell_detail;
pub mod crash_test;
mod explore;
mod ingest;
mod init;
mod migrate;
pub mod missions;
mod plan;
mod progress;
mod record;
mod replan;
#[cfg(test)]
mod scoring_tests;
pub mod shortcuts;
#[cfg(test)]
mod test_farm;
mod view;
pub mod wind;

pub use cell_detail::{CellDetail, Contributions, SeriesPoint, cell_detail};
pub use explore::{Exploration, ExploreRequest, explore};
pub use ingest::{Format, IngestOutcome, IngestRequest, batch_of, detect, ingest};
pub use init::{
    DEFAULT_CELL_SIZE_M, InitOutcome, InitRequest, init, init_store, init_store_with,
    read_sensors_file, relative_to,
};
pub use migrate::{
    MigrateOutcome, MigrateProjectRequest, ProjectMigration, migrate, migrate_project,
};
pub use missions::{MissionPage, cancel_mission, delete_mission, missions_page};
pub use plan::{
    Baseline, ExtraSortie, MAX_SORTIES, PlanRequest, PlannedMission, energy_model, flight_profile,
    plan, plan_with_preset,
};
pub use progress::{Progress, Silent};
pub use record::{RecordOutcome, RecordRequest, record_flight};
pub use replan::{REPLAN_ITERATIONS, REPLAN_TIME_LIMIT_S, Replan, ReplanRequest, replan};
pub use view::{
    CellView, FieldView, MissionExport, RoutedMission, cell_reading_counts, check_flyable,
    exploration_sorties, export, export_energy_model, field_view, mission, missions,
    newest_reading, write_files,
};

// The scoring machinery (`gleaner-scoring`): the project, its settings and errors, what is
// known at t, scoring and reconstruction, as the adapters name them.
/// Per-cell CSV inputs (`plan --scores`, `score --probabilities`) and header-line tables.
pub use gleaner_scoring::cell_csv;
/// `gleaner.toml`: its sections, defaults and checks.
pub use gleaner_scoring::settings;
pub use gleaner_scoring::summaries::{pending_bytes, series_summary};
pub use gleaner_scoring::{
    AppError, Condition, DEFAULT_NEIGHBOURS, EnergyPreset, Estimator, History, Knowledge,
    MAX_SERIES_TIMES, MapCell, Objective, Project, ReconstructMapRequest, ReconstructRequest,
    ReconstructSeriesRequest, Reconstruction, ReconstructionMap, ReconstructionSeries, Result,
    ScoreRequest, Scoring, SensorEstimate, Settings, Z90, compute, compute_full, database, driver,
    dynamic_fit_options, dynamic_window_s, knowledge, parse_planner, reconstruct, reconstruct_map,
    reconstruct_series, score,
};

pub use gleaner_energy::Wind;
/// Re-exported so adapters name one crate for the lifecycle's data.
pub use gleaner_ingest::OnError;
pub use gleaner_ingest::time::{format_rfc3339, parse_timestamp};
pub use gleaner_mission::Planner;
pub use gleaner_store::{
    AnyStore, CellMetadata, CellScores, Database, EnergyBreakdown, FlightProfile, MissionId,
    MissionKind, MissionRecord, MissionStatus, NewMission, PgStore, SqliteStore, StopRecord, Store,
    StoreError, StoreRead, StoreWrite, VisitRecord,
};
