//! gleaner's scoring machinery over a project's store: what the application layer
//! (`gleaner-app`) scores, plans and reconstructs with.
//!
//! A [`Project`] is the project's settings (`gleaner.toml`, [`settings`]) and its store. Over
//! it this crate computes what is known at a mission time ([`knowledge`]), the cells'
//! utility scores F, R, A, U and S ([`compute`], fast from the persisted utility state
//! [`state`] and the cell summaries [`summaries`], else from the history), gleaner's drift
//! freshness, the variance-reduction term V ([`variance_gains`]), the information objective
//! ([`CellInformation`]) and every sensor's estimated value ([`reconstruct`],
//! [`reconstruct_map`]). The use cases that write — `score`, `ingest`, `plan`, `record` —
//! live in `gleaner-app` and call [`score()`], [`state`] and [`summaries`] inside their own
//! transaction.
//!
//! Nothing here parses arguments, prints, reads the wall clock or knows SQL; errors are one
//! typed [`AppError`] (the application layer's, re-exported there).
//!
//! Units: times are seconds since 1970-01-01T00:00:00Z (UTC); positions WGS84 (lat then lon);
//! lengths metres; energies joules; data volumes bytes.
#![deny(missing_docs)]

pub mod cell_csv;
mod choices;
mod codec;
mod condition;
mod drift;
mod dynamic;
mod error;
mod information;
mod knowledge;
mod kriging_inputs;
mod project;
mod reconstruct;
mod reconstruct_map;
mod score;
pub mod settings;
pub mod state;
pub mod summaries;
mod value;
pub mod when;

pub use choices::{Estimator, Objective, parse_planner};
pub use condition::{Condition, ScoreRequest, Scoring, condition_modality, driver};
pub use dynamic::{dynamic_fit_options, dynamic_window_s};
pub use error::{AppError, Result};
pub use information::CellInformation;
pub use knowledge::{History, Knowledge, knowledge, sampling_step};
pub use kriging_inputs::Z90;
pub use project::{Project, database};
pub use reconstruct::{
    DEFAULT_NEIGHBOURS, EstimateReads, MAX_SERIES_TIMES, Models, ReconstructRequest,
    ReconstructSeriesRequest, Reconstruction, ReconstructionSeries, SensorEstimate, estimate_with,
    fit_dynamic_model, fit_models, reconstruct, reconstruct_series, target_modality, unfit_dynamic,
};
pub use reconstruct_map::{MapCell, ReconstructMapRequest, ReconstructionMap, reconstruct_map};
pub use score::{compute, compute_full, metadata_rows, score, write_scoring};
pub use settings::{EnergyPreset, Settings};
pub use value::variance_gains;

pub use gleaner_store::Store;
