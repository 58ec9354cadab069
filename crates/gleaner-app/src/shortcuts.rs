//! The few lower-level entry points a long replay needs (the campaign simulator,
//! `gleaner-campaign`), beside the use cases: the same work as a use case, minus reading
//! files or recomputing what the caller already holds. Each is the body of a public use case
//! and gives its result; none bypasses a check or a transaction.
//!
//! | shortcut | is | skips |
//! |---|---|---|
//! | [`parse_files`], [`known_sensors`], [`Parsed`] | `ingest`'s reading and checking of files | storing |
//! | [`ingest_parsed`] | `ingest` of readings already read | reading files |
//! | [`record_parsed`] | `record_flight` of readings already read (a simulated flight's) | reading files |
//! | [`explore_with`], [`ExplorationMemo`] | `explore` keeping the last exploration plan | re-planning the same tour |
//! | [`plan_scored`] | `plan` with the scoring already computed (`compute` at the same time) | scoring twice |
//! | [`fit_models`], [`Models`], [`target_modality`] | `reconstruct`'s model fits and modality choice | — |
//! | [`estimate_with`], [`EstimateReads`] | `reconstruct`'s estimate keeping its store reads | reading them again |
//! | [`prepare_cache`] | builds the cell summaries' cache once | rebuilding it at the first record |
//! | [`condition_modality`] | the modality the condition classes come from | — |
//! | [`sampling_step`] | the median spacing of consecutive readings, s | — |
//!
//! The time arguments are seconds since 1970-01-01T00:00:00Z (UTC).

pub use crate::explore::{ExplorationMemo, explore_with};
pub use crate::ingest::{Parsed, ingest_parsed, known_sensors, parse_files};
pub use crate::plan::plan_scored;
pub use crate::record::record_parsed;
pub use gleaner_scoring::summaries::prepare_cache;
pub use gleaner_scoring::{
    EstimateReads, Models, condition_modality, estimate_with, fit_models, sampling_step,
    target_modality,
};
