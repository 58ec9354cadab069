//! Scoring: the utility terms F, R, A, U and the score S of every cell at a mission time
//! (docs/method.md §2), and the cell metadata they become (docs/method.md §5).

use std::collections::HashMap;

use gleaner_field::{CellId, Modality, UnixSeconds};
use gleaner_store::{
    AnomalyRecord, CellMetadata, CellScores, ClassProbability, Correlation, ModalitySummary,
    SeriesStats, Store, StoreWrite,
};
use gleaner_utility::{
    CellInputs, IncrementalState, OwnedSeries, Series, score_cells_parallel, series_correlation,
    validate_probabilities,
};

use crate::cell_csv;
use crate::condition::{
    Condition, NO_MODALITY, ScoreRequest, Scoring, anomaly_label, class_names, condition_modality,
    condition_output, fit_condition, modality_without_readings, neighbour_lists,
};
use crate::error::{AppError, Result};
use crate::knowledge::{History, Knowledge, knowledge};
use crate::project::Project;
use crate::state;
use crate::summaries;

/// Trains the built-in condition model on the collected history and predicts every cell at
/// `t`; `Ok(None)` with a warning when there is no suitable modality or too little data.
fn condition<S: Store>(
    project: &Project<S>,
    k: &Knowledge,
    t: UnixSeconds,
    warnings: &mut Vec<String>,
) -> Result<Option<Condition>> {
    let Some(name) = condition_modality(project.settings(), &k.modalities) else {
        warnings.push(NO_MODALITY.into());
        return Ok(None);
    };
    let Some(m) = k.modalities.iter().position(|x| *x == name) else {
        return Err(modality_without_readings(&name));
    };
    let cells: Vec<Series<'_>> = k.series.iter().map(|s| s[m].as_series()).collect();
    let neighbours = neighbour_lists(&k.field);
    match fit_condition(project.settings(), &cells, &neighbours, t) {
        Ok(model) => {
            let p = model.predict_proba(&cells, &neighbours, t);
            Ok(Some(condition_output(name, &model, p)))
        }
        Err(warning) => {
            warnings.push(warning);
            Ok(None)
        }
    }
}

/// Scores every cell at the requested time from what is known then. Writes nothing: see
/// [`score`] for the use case that also keeps the result.
///
/// The common case — all history, no user probabilities, the all-history window, and `at`
/// (if given) at or after the newest stored reading — is answered from the persisted utility
/// state (the statistics behind A and R and the condition model kept up to date by ingest and
/// record, see `state.rs`) in O(cells × neighbours × modalities) without reading the history;
/// the result equals [`compute_full`]'s within 1e-9 relative. Anything else, or a missing or
/// stale state, takes the full path.
///
/// With `[utility] freshness_form = "drift"` (gleaner's method) F is then replaced by the
/// cells' drift freshness and S recomputed (`drift.rs`; reads the condition modality's
/// readings of the last `drift_window_days`).
pub fn compute<S: Store>(project: &Project<S>, request: &ScoreRequest) -> Result<Scoring> {
    crate::when::check("mission time", request.at)?;
    let scoring = match state::fast_scoring(project, request)? {
        Some(scoring) => scoring,
        None => compute_history(project, request)?,
    };
    with_freshness_form(project, scoring, &request.history)
}

/// [`compute`] from a state just rebuilt (not yet stored) instead of the stored one.
fn compute_rebuilt<S: Store>(
    project: &Project<S>,
    request: &ScoreRequest,
    rebuilt: Option<state::Persisted>,
) -> Result<Scoring> {
    let fast = match rebuilt {
        Some(p) => state::fast_scoring_from(project, request, p)?,
        None => None,
    };
    let scoring = match fast {
        Some(scoring) => scoring,
        None => compute_history(project, request)?,
    };
    with_freshness_form(project, scoring, &request.history)
}

/// F as `[utility] freshness_form` asks: the half-life's (as computed) or, with `drift`, each
/// cell's drift freshness from the readings `history` knows, S recomputed (`drift.rs`).
fn with_freshness_form<S: Store>(
    project: &Project<S>,
    mut scoring: Scoring,
    history: &History,
) -> Result<Scoring> {
    let u = &project.settings().utility;
    if u.freshness_form == "drift" {
        let k = &scoring.knowledge;
        match condition_modality(project.settings(), &k.modalities) {
            Some(name) => {
                // The condition modality, or every depth of its quantity.
                let quantity = name.split('@').next().unwrap_or(&name);
                let names: Vec<&String> = if u.drift_all_depths {
                    k.modalities
                        .iter()
                        .filter(|m| m.split('@').next() == Some(quantity))
                        .collect()
                } else {
                    vec![&name]
                };
                let mut index = vec![0.0; k.field.cells().len()];
                for name in &names {
                    let modality =
                        Modality::new(name).map_err(|e| AppError::Invalid(e.to_string()))?;
                    let one = crate::drift::drift_index(
                        project,
                        k,
                        &modality,
                        scoring.t,
                        (u.drift_window_days * 86_400.0) as i64,
                        history,
                    )?;
                    for (a, b) in index.iter_mut().zip(&one) {
                        if b.is_finite() {
                            *a += b;
                        }
                    }
                }
                let config = u.to_core(&k.modalities)?;
                crate::drift::apply(&mut scoring.terms, &index, &config)?;
                scoring.anomaly_form = if u.drift_all_depths {
                    format!(
                        "{}; F drift ({quantity} at every depth)",
                        scoring.anomaly_form
                    )
                } else {
                    format!("{}; F drift", scoring.anomaly_form)
                };
            }
            None => scoring.warnings.push(
                "freshness_form = \"drift\" needs a soil-moisture (condition) modality: F from \
                 the half-life"
                    .into(),
            ),
        }
    }
    Ok(scoring)
}

/// [`compute`] from the stored history, never from the persisted state: loads every reading
/// known at t and refits the condition model. O(history).
pub fn compute_full<S: Store>(project: &Project<S>, request: &ScoreRequest) -> Result<Scoring> {
    crate::when::check("mission time", request.at)?;
    with_freshness_form(
        project,
        compute_history(project, request)?,
        &request.history,
    )
}

/// [`compute_full`] before `[utility] freshness_form` is applied.
fn compute_history<S: Store>(project: &Project<S>, request: &ScoreRequest) -> Result<Scoring> {
    let k = knowledge(project, request.at, request.history)?;
    let t = crate::when::mission_time(request.at, k.latest)?;
    let settings = project.settings();
    let config = settings.utility.to_core(&k.modalities)?;
    let mut warnings = Vec::new();
    let condition = match &request.probabilities {
        Some(path) => {
            let rows: Vec<(String, Vec<f64>)> = cell_csv::read(path)?
                .into_iter()
                .map(|r| (gleaner_ingest::shorten(&r.cell).into_owned(), r.values))
                .collect();
            let labels = k.cell_labels();
            let p = validate_probabilities(&labels, &rows)
                .map_err(|e| AppError::Invalid(format!("{}: {e}", path.display())))?;
            let kk = p.first().map_or(0, Vec::len);
            Some(Condition {
                modality: "user".into(),
                thresholds: Vec::new(),
                classes: class_names(kk),
                probabilities: p,
            })
        }
        None => condition(project, &k, t, &mut warnings)?,
    };
    let neighbours = neighbour_lists(&k.field);
    let last: Vec<Vec<Option<UnixSeconds>>> = k
        .field
        .cells()
        .iter()
        .map(|c| c.sensors.iter().map(|&s| k.last_collected[s]).collect())
        .collect();
    let inputs: Vec<CellInputs<'_>> = (0..k.field.cells().len())
        .map(|i| CellInputs {
            last_collected: &last[i],
            series: k.series[i].iter().map(OwnedSeries::as_series).collect(),
            neighbours: &neighbours[i],
            probabilities: condition.as_ref().map_or(&[][..], |c| &c.probabilities[i]),
        })
        .collect();
    let terms =
        score_cells_parallel(&inputs, t, &config).map_err(|e| AppError::core("scoring", e))?;
    drop(inputs);
    let u = &settings.utility;
    Ok(Scoring {
        t,
        knowledge: k,
        terms,
        condition,
        weights: [u.alpha, u.beta, u.gamma, u.delta],
        anomaly_form: anomaly_label(&config),
        warnings,
        incremental: None,
    })
}

/// The use case: scores every cell at t and, unless a dry run, keeps the terms, class
/// probabilities, neighbour correlations, anomaly history and series summaries in the cell
/// metadata table, in one transaction.
///
/// A common request (all history, no user probabilities) whose persisted utility state is
/// stale — after a bulk ingest, a change of grid settings, or a database from before the state
/// existed — first rebuilds the state in memory, then scores from it (the condition model is
/// fitted once, not once for this scoring and again for the state) and stores it with the
/// scoring, in the same transaction: a refused scoring writes nothing, the state included.
pub fn score<S: Store>(project: &mut Project<S>, request: &ScoreRequest) -> Result<Scoring> {
    match request.dry_run {
        true => score_held(project, request),
        // The state rebuilt and the scoring computed are written over the store they read.
        false => project.exclusive(|project| score_held(project, request)),
    }
}

/// [`score`], the project's exclusion held unless a dry run.
fn score_held<S: Store>(project: &mut Project<S>, request: &ScoreRequest) -> Result<Scoring> {
    crate::when::check("mission time", request.at)?;
    if !request.dry_run {
        project.check_stored_grid(&project.field()?.1)?;
    }
    let common = request.probabilities.is_none() && request.history == History::default();
    let mut rebuilt = if !request.dry_run && common {
        state::rebuilt_if_stale(project.store(), project.settings())?
    } else {
        None
    };
    let scoring = match rebuilt.as_mut() {
        Some(r) => compute_rebuilt(project, request, r.state.take())?,
        None => compute(project, request)?,
    };
    if !request.dry_run {
        let rows = metadata_rows(project, &scoring, None);
        project.store_mut().write(|tx| {
            if let Some(r) = &rebuilt {
                state::keep_rebuilt(tx, r)?;
            }
            write_scoring(tx, rows)
        })?;
    }
    Ok(scoring)
}

/// Writes scoring rows, carrying over what scoring does not compute (the pending volume, and an
/// expected energy the caller did not set) from the stored rows.
pub fn write_scoring<W: StoreWrite>(
    tx: &mut W,
    mut rows: Vec<CellMetadata>,
) -> std::result::Result<(), AppError> {
    let stored: HashMap<gleaner_field::CellIndex, CellMetadata> = tx
        .cell_metadata_scalars()?
        .into_iter()
        .map(|m| (m.cell, m))
        .collect();
    for m in &mut rows {
        if let Some(old) = stored.get(&m.cell) {
            m.expected_energy_j = m.expected_energy_j.or(old.expected_energy_j);
            m.pending_bytes = m.pending_bytes.or(old.pending_bytes);
            m.last_collected = m.last_collected.max(old.last_collected);
        }
    }
    tx.upsert_cell_metadata(&rows)?;
    Ok(())
}

/// The cell metadata rows of a scoring: terms, class probabilities, correlations with every
/// neighbour, the latest anomaly per modality, and the series summaries; with
/// `expected_energy_j` (J, one per cell in field order), each cell's expected collection energy.
pub fn metadata_rows<S: Store>(
    project: &Project<S>,
    s: &Scoring,
    expected_energy_j: Option<&[f64]>,
) -> Vec<CellMetadata> {
    let k = &s.knowledge;
    let min_overlap = project.settings().utility.min_overlap;
    let flag = project.settings().utility.anomaly_flag;
    let modalities: Vec<Option<Modality>> =
        k.modalities.iter().map(|m| Modality::new(m).ok()).collect();
    s.terms
        .iter()
        .enumerate()
        .map(|(c, terms)| {
            let cell = &k.field.cells()[c];
            let mut m = CellMetadata::new(cell.index);
            m.expected_energy_j = expected_energy_j.and_then(|e| e.get(c).copied());
            m.last_collected = cell
                .sensors
                .iter()
                .filter_map(|&x| k.last_collected[x])
                .max();
            m.scores = Some(CellScores {
                freshness: terms.f,
                redundancy: terms.r,
                anomaly: terms.a,
                uncertainty: terms.u,
                score: terms.s,
                computed_at: s.t,
            });
            if let Some(cond) = &s.condition {
                m.class_probabilities = cond
                    .classes
                    .iter()
                    .zip(&cond.probabilities[c])
                    .map(|(class, &p)| ClassProbability {
                        class: class.clone(),
                        probability: p,
                    })
                    .collect();
            }
            if let Some(state) = &s.incremental {
                metadata_from_state(s, state, &modalities, c, min_overlap, flag, &mut m);
                return m;
            }
            for &nb in k.field.neighbours(CellId(c as u32)) {
                for (mi, modality) in modalities.iter().enumerate() {
                    let Some(modality) = modality else { continue };
                    let (a, b) = (
                        k.series[c][mi].as_series(),
                        k.series[nb.index()][mi].as_series(),
                    );
                    if a.is_empty() || b.is_empty() {
                        continue;
                    }
                    m.correlations.push(Correlation {
                        neighbour: k.field.cells()[nb.index()].index,
                        modality: modality.clone(),
                        correlation: series_correlation(a, b, min_overlap),
                        overlap: common_points(a, b),
                    });
                }
            }
            for (mi, a) in terms.a_by_modality.iter().enumerate() {
                let latest = k.series[c][mi].as_series().last().map(|p| p.0);
                push_anomaly(&mut m, modalities.get(mi), latest, *a, flag);
            }
            m.summaries = modalities
                .iter()
                .zip(&k.series[c])
                .filter_map(|(modality, series)| {
                    summaries::series_summary(modality.as_ref()?, series.as_series())
                })
                .collect();
            m
        })
        .collect()
}

/// Fills cell `c`'s correlations, anomalies and series summaries from the persisted
/// statistics (what `metadata_rows` computes from the full series otherwise).
fn metadata_from_state(
    s: &Scoring,
    state: &IncrementalState,
    modalities: &[Option<Modality>],
    c: usize,
    min_overlap: usize,
    flag: f64,
    m: &mut CellMetadata,
) {
    let k = &s.knowledge;
    let neighbours = state.neighbours().get(c).map_or(&[][..], Vec::as_slice);
    for (pos, &nb) in neighbours.iter().enumerate() {
        for (mi, modality) in modalities.iter().enumerate() {
            let Some(modality) = modality else { continue };
            if state.series_stats(c, mi).all.count() == 0
                || state.series_stats(nb, mi).all.count() == 0
            {
                continue;
            }
            let pair = state.neighbour_pair(c, pos, mi);
            m.correlations.push(Correlation {
                neighbour: k.field.cells()[nb].index,
                modality: modality.clone(),
                correlation: pair.correlation(min_overlap),
                overlap: pair.count(),
            });
        }
    }
    if let Some(terms) = s.terms.get(c) {
        for (mi, a) in terms.a_by_modality.iter().enumerate() {
            let latest = state.series_stats(c, mi).latest.map(|p| p.0);
            push_anomaly(m, modalities.get(mi), latest, *a, flag);
        }
    }
    m.summaries = modalities
        .iter()
        .enumerate()
        .filter_map(|(mi, modality)| {
            let st = state.series_stats(c, mi);
            let (latest_t, latest_value) = st.latest?;
            let n = st.all.count();
            Some(ModalitySummary {
                modality: modality.clone()?,
                stats: SeriesStats {
                    count: n,
                    mean: st.all.mean(),
                    std: (n >= 2).then(|| st.all.std()),
                    min: st.min,
                    max: st.max,
                    latest_t,
                    latest_value,
                },
            })
        })
        .collect();
}

/// Adds the anomaly of one modality at its latest point (time in seconds) to a cell's anomaly
/// history, flagged when at or above `flag`; nothing when any part is missing.
pub(crate) fn push_anomaly(
    m: &mut CellMetadata,
    modality: Option<&Option<Modality>>,
    latest: Option<UnixSeconds>,
    anomaly: Option<f64>,
    flag: f64,
) {
    if let (Some(Some(modality)), Some(t), Some(a)) = (modality, latest, anomaly) {
        m.anomalies.push(AnomalyRecord {
            modality: modality.clone(),
            t,
            anomaly: a,
            flagged: a >= flag,
        });
    }
}

fn common_points(a: Series<'_>, b: Series<'_>) -> u64 {
    let (mut i, mut j, mut n) = (0, 0, 0u64);
    while i < a.times.len() && j < b.times.len() {
        match a.times[i].cmp(&b.times[j]) {
            std::cmp::Ordering::Less => i += 1,
            std::cmp::Ordering::Greater => j += 1,
            std::cmp::Ordering::Equal => {
                n += 1;
                i += 1;
                j += 1;
            }
        }
    }
    n
}
