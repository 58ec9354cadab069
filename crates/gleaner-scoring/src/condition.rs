//! What a scoring asks for and gives ([`ScoreRequest`], [`Scoring`], [`Condition`]) and the
//! built-in condition model behind U, shared by the full path (`score.rs`) and the fast path
//! from the persisted utility state (`state.rs`).

use std::path::PathBuf;

use gleaner_field::{Field, UnixSeconds};
use gleaner_utility::{
    CellTerms, ClassThresholds, ConditionConfig, ConditionModel, IncrementalState, Series,
};

use crate::error::AppError;
use crate::knowledge::{History, Knowledge};
use crate::settings::Settings;

/// What to score.
#[derive(Debug, Clone, Default)]
pub struct ScoreRequest {
    /// Mission time t, seconds since the Unix epoch [default: the latest known reading].
    pub at: Option<UnixSeconds>,
    /// Which stored readings count as collected.
    pub history: History,
    /// Per-cell class probabilities from the user's own model (CSV `cell_id,p_1,...,p_K`)
    /// instead of the built-in condition model.
    pub probabilities: Option<PathBuf>,
    /// Compute only; write nothing.
    pub dry_run: bool,
}

/// The condition model's output: class names and one distribution per cell.
#[derive(Debug, Clone)]
pub struct Condition {
    /// The modality the classes come from (`user` for user probabilities).
    pub modality: String,
    /// Class thresholds in the modality's unit (empty for user probabilities).
    pub thresholds: Vec<f64>,
    /// Class names.
    pub classes: Vec<String>,
    /// One distribution per cell, in field order.
    pub probabilities: Vec<Vec<f64>>,
}

/// The result of scoring every cell at t.
pub struct Scoring {
    /// Mission time t, seconds since the Unix epoch.
    pub t: UnixSeconds,
    /// What was known at t.
    pub knowledge: Knowledge,
    /// The terms of every cell, in field order.
    pub terms: Vec<CellTerms>,
    /// The condition model's output, if any.
    pub condition: Option<Condition>,
    /// Weights alpha, beta, gamma, delta.
    pub weights: [f64; 4],
    /// The anomaly form label (`raw` or `bounded(kappa=...)`), followed by `,
    /// neighbours(min=k)` when the neighbour-relative anomaly is in use.
    pub anomaly_form: String,
    /// Things the user should know (e.g. no condition model could be fitted: U = 0).
    pub warnings: Vec<String>,
    /// The persisted statistics the scoring came from (the fast path of [`compute`]); then
    /// `knowledge.series` holds only their retained recent points, and counts, means,
    /// correlations and latest points come from these statistics.
    pub incremental: Option<IncrementalState>,
}

/// The anomaly label of every output: the form, and the reference when it is not the
/// paper's own history (e.g. `raw, neighbours(min=2)`).
pub(crate) fn anomaly_label(config: &gleaner_utility::UtilityConfig) -> String {
    let label = match config.anomaly_reference {
        gleaner_utility::AnomalyReference::OwnHistory => config.anomaly_form.label(),
        r => format!("{}, {}", config.anomaly_form.label(), r.label()),
    };
    match config.score_form {
        gleaner_utility::ScoreForm::Additive => label,
        f => format!("{label}; S {}", f.label()),
    }
}

/// Which weighted term contributes most to S: `freshness`, `anomaly`, `uncertainty` or `none`.
pub fn driver(t: &CellTerms, w: [f64; 4]) -> &'static str {
    let parts = [
        ("freshness", w[0] * t.f),
        ("anomaly", w[1] * t.a),
        ("uncertainty", w[2] * t.u),
    ];
    parts
        .iter()
        .filter(|p| p.1 > 0.0)
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map_or("none", |p| p.0)
}

pub(crate) fn class_names(k: usize) -> Vec<String> {
    if k == 3 {
        vec!["dry".into(), "adequate".into(), "wet".into()]
    } else {
        (1..=k).map(|c| format!("class_{c}")).collect()
    }
}

pub(crate) fn neighbour_lists(field: &Field) -> Vec<Vec<usize>> {
    field
        .all_neighbours()
        .iter()
        .map(|n| n.iter().map(|c| c.index()).collect())
        .collect()
}

/// The modality the condition classes come from: `utility.condition_modality`, else
/// `vw@30cm`, else the first `vw@...` of `modalities` (sorted names); `None` without one.
pub fn condition_modality(settings: &Settings, modalities: &[String]) -> Option<String> {
    match &settings.utility.condition_modality {
        Some(m) => Some(m.clone()),
        None => modalities
            .iter()
            .find(|m| *m == "vw@30cm")
            .or_else(|| modalities.iter().find(|m| m.starts_with("vw@")))
            .cloned(),
    }
}

/// The warning given when there is no soil-moisture modality.
pub(crate) const NO_MODALITY: &str = "no soil-moisture modality: U = 0 for every cell";

/// The error for a configured condition modality without readings.
pub(crate) fn modality_without_readings(name: &str) -> AppError {
    AppError::Invalid(format!(
        "utility.condition_modality = {name:?} has no readings"
    ))
}

/// Fits the built-in condition model on the cells' class-modality series (`cells`, field
/// order) with label times before `t` (s), from the earliest point on; the error becomes the
/// scoring's warning.
pub(crate) fn fit_condition(
    settings: &Settings,
    cells: &[Series<'_>],
    neighbours: &[Vec<usize>],
    t: UnixSeconds,
) -> std::result::Result<ConditionModel, String> {
    fit_condition_from(settings, cells, neighbours, t, None)
}

/// [`fit_condition`], Newton's method warm-started from `start` (the same model to the
/// solver's tolerance, see [`ConditionModel::fit_from`]).
pub(crate) fn fit_condition_from(
    settings: &Settings,
    cells: &[Series<'_>],
    neighbours: &[Vec<usize>],
    t: UnixSeconds,
    start: Option<&ConditionModel>,
) -> std::result::Result<ConditionModel, String> {
    let u = &settings.utility;
    let config = ConditionConfig {
        n_classes: u.condition_classes,
        thresholds: match &u.condition_thresholds {
            Some(th) => ClassThresholds::Fixed(th.clone()),
            None => ClassThresholds::Quantiles,
        },
        ..ConditionConfig::default()
    };
    let from = cells
        .iter()
        .filter_map(|s| s.times.first())
        .min()
        .copied()
        .unwrap_or(t);
    ConditionModel::fit_from(cells, neighbours, from, t, &config, start)
        .map_err(|e| format!("no condition model ({e}); U = 0 for every cell"))
}

/// The scoring's condition output from a fitted model.
pub(crate) fn condition_output(
    name: String,
    model: &ConditionModel,
    probabilities: Vec<Vec<f64>>,
) -> Condition {
    Condition {
        modality: name,
        thresholds: model.thresholds().to_vec(),
        classes: class_names(model.n_classes()),
        probabilities,
    }
}
