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
//! Read models: [`field_view`] (the cell table), [`missions`], [`mission`], [`cell_detail`]
//! (one cell's weighted terms, rank and recent series).
//!
//! Units: times are seconds since 1970-01-01T00:00:00Z (UTC); positions WGS84 ([`LatLon`],
//! lat then lon); lengths metres; energies joules; data volumes bytes.
//!
//! [`LatLon`]: gleaner_field::LatLon
#![deny(missing_docs)]

pub mod airspace;
pub mod cell_csv;
mod cell_detail;
mod choices;
mod drift;
mod error;
mod explore;
mod information;
mod ingest;
mod init;
mod knowledge;
mod migrate;
pub mod missions;
mod plan;
mod progress;
mod project;
mod reconstruct;
mod reconstruct_map;
mod record;
mod replan;
mod score;
pub mod settings;
pub mod shortcuts;
mod state;
mod summaries;
#[cfg(test)]
mod test_farm;
mod value;
mod view;
mod when;
pub mod wind;

pub use cell_detail::{CellDetail, Contributions, SeriesPoint, cell_detail};
pub use error::{AppError, Result};
pub use explore::{Exploration, ExploreRequest, explore};
pub use ingest::{Format, IngestOutcome, IngestRequest, batch_of, detect, ingest};
pub use init::{
    DEFAULT_CELL_SIZE_M, InitOutcome, InitRequest, init, init_store, init_store_with,
    read_sensors_file, relative_to,
};
pub use knowledge::{History, Knowledge, knowledge};
pub use migrate::{MigrateOutcome, migrate};
pub use missions::{MissionPage, cancel_mission, delete_mission, missions_page};
pub use plan::{
    Baseline, ExtraSortie, MAX_SORTIES, Objective, PlanRequest, PlannedMission, energy_model,
    flight_profile, parse_planner, plan, plan_with_preset,
};
pub use progress::{Progress, Silent};
pub use project::{Project, database};
pub use reconstruct::{
    DEFAULT_NEIGHBOURS, Estimator, MAX_SERIES_TIMES, ReconstructRequest, ReconstructSeriesRequest,
    Reconstruction, ReconstructionSeries, SensorEstimate, Z90, dynamic_fit_options,
    dynamic_window_s, reconstruct, reconstruct_series,
};
pub use reconstruct_map::{MapCell, ReconstructMapRequest, ReconstructionMap, reconstruct_map};
pub use record::{RecordOutcome, RecordRequest, record_flight};
pub use replan::{REPLAN_ITERATIONS, REPLAN_TIME_LIMIT_S, Replan, ReplanRequest, replan};
pub use score::{Condition, ScoreRequest, Scoring, compute, compute_full, driver, score};
pub use settings::{EnergyPreset, Settings};
pub use summaries::{pending_bytes, series_summary};
pub use view::{
    CellView, FieldView, MissionExport, cell_reading_counts, check_flyable, export,
    export_energy_model, field_view, mission, missions, newest_reading,
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
