//! Cell utility engine for gleaner (docs/method.md §2). Pure: no IO, no database.
//!
//! Each candidate cell gets a score S_i = alpha·F_i + beta·A_i + gamma·U_i − delta·R_i from
//! four terms:
//!
//! - [`freshness`] F_i: how stale the cell's sensors are (half-life decay, never collected = 1);
//! - [`redundancy`] R_i: how well the neighbours' series already predict the cell's
//!   (positive Pearson correlation over common timestamps, [`series_correlation`]);
//! - [`anomaly`] A_i: how far the latest value lies from the cell's past, in standard deviations;
//! - [`uncertainty`] U_i: the normalised entropy of a class distribution, from the
//!   [`ConditionModel`] (soil moisture dry / adequate / wet) or from the user
//!   ([`validate_probabilities`]).
//!
//! Main types: [`UtilityConfig`] (weights, half-life, window, …), [`CellInputs`] (borrowed
//! per-cell data: last collection times, [`Series`] per modality, neighbours, probabilities),
//! [`CellTerms`] (the terms and S per cell), [`score_cells`] / [`score_cells_parallel`] (from
//! scratch) and [`IncrementalState`] (statistics maintained as readings arrive, so rescoring
//! after a mission is cheap). Cell series are built with [`cell_series`] on a [`TimeGrid`].
//!
//! ```
//! use gleaner_utility::{score_cells, CellInputs, Series, UtilityConfig};
//! let day = 86_400;
//! let times: Vec<i64> = (0..12).map(|d| d * day).collect();
//! let a: Vec<f64> = (0..12).map(|d| 0.30 + 0.001 * d as f64).collect();
//! let b: Vec<f64> = (0..12).map(|d| 0.25 + 0.0012 * d as f64).collect();
//! let (last_a, last_b) = ([Some(11 * day)], [None]);
//! let cells = vec![
//!     CellInputs { last_collected: &last_a, series: vec![Series::new(&times, &a)],
//!                  neighbours: &[1], probabilities: &[] },
//!     CellInputs { last_collected: &last_b, series: vec![Series::new(&times, &b)],
//!                  neighbours: &[0], probabilities: &[] },
//! ];
//! let terms = score_cells(&cells, 12 * day, &UtilityConfig::default()).unwrap();
//! assert_eq!(terms[1].f, 1.0); // never collected
//! assert!((terms[0].r - 1.0).abs() < 1e-9); // perfectly correlated neighbour
//! assert!(terms[1].s > terms[0].s);
//! ```
//!
//! # Decisions where docs/method.md §2 is silent
//!
//! - Scoring at time t uses only points at or before t (and inside the history window);
//!   what a series contains is what has been collected: the caller passes collected data only.
//! - A collection time after t counts as age 0; a cell must have at least one sensor.
//! - Several readings falling in one grid slot (several sensors, or one sensor twice) are
//!   averaged; non-finite readings are missing.
//! - A cell "has" a modality when its series has a point in the window; omega / phi are
//!   renormalised over those, and per-modality outputs are `None` for the others.
//! - Zero variance means a standard deviation below 1e-12 of the mean's magnitude (so rounding
//!   in the mean of a constant series does not fake a correlation).
//! - `epsilon` must be > 0 (A would be 0/0 for a constant past otherwise).
//! - Without a condition model (empty probabilities for every cell) U = 0; a cell with no data
//!   gets uniform probabilities from [`ConditionModel::predict_proba`] (U = 1).
//! - [`IncrementalState`] supports only the all-history window (see its module docs).
//!
//! # Speed
//!
//! Criterion benches in `benches/scoring.rs` (`cargo bench -p gleaner-utility`): 100,000 cells
//! with 8 neighbours and 3 modalities scored from maintained statistics (on a one-thread pool;
//! `IncrementalState::score` spreads the cells over rayon's pool), from
//! scratch over 365 daily points (all cores; complete series and 10% missing days), and the
//! incremental update after a 10-cell mission. From scratch, each neighbour pair is correlated
//! once, over contiguous slices when the two series share their timestamps.
#![deny(missing_docs)]

mod codec;
mod condition;
mod config;
mod drift;
mod engine;
mod error;
mod incremental;
mod probabilities;
mod series;
mod terms;

pub use condition::{
    ClassThresholds, ConditionConfig, ConditionModel, Evaluation, FEATURE_NAMES, TrainingSet,
    class_of, condition_features, quantile_thresholds,
};
pub use config::{
    AnomalyForm, AnomalyReference, DAY_S, HistoryWindow, ModalityWeights, ScoreForm, UtilityConfig,
};
pub use drift::{mean_squared_change, staleness_index};
pub use engine::{CellInputs, CellTerms, score_cells, score_cells_parallel};
pub use error::UtilityError;
pub use incremental::{IncrementalState, PairStats, Reading, RunningStats, SeriesStats};
pub use probabilities::{PROBABILITY_SUM_TOLERANCE, validate_probabilities};
pub use series::{OwnedSeries, Series, TimeGrid, cell_series};
pub use terms::{
    anomaly, freshness, median_of_sorted, neighbour_anomaly, neighbour_residuals, pearson,
    redundancy, score, series_correlation, uncertainty,
};
