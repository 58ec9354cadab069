//! `gleaner score`: the utility terms F, R, A, U and the score S of every cell at a mission time,
//! printed and kept in the cell metadata table.

use std::collections::HashMap;
use std::path::Path;

use anyhow::{Context, Result, bail};
use gleaner_field::{Field, Sensor, UnixSeconds};
use gleaner_ingest::time::format_rfc3339;
use gleaner_store::{
    AnomalyRecord, CellMetadata, CellScores, ClassProbability, Correlation, Store,
};
use gleaner_utility::{
    CellInputs, CellTerms, ClassThresholds, ConditionConfig, ConditionModel, OwnedSeries, Series,
    TimeGrid, cell_series, score_cells_parallel, series_correlation, validate_probabilities,
};
use serde::Serialize;

use crate::cell_csv;
use crate::project::Project;

/// What the planner knows at time t: the field and, per cell and modality, the collected
/// cell series; per sensor, the last collection time.
pub struct Knowledge {
    /// The sensors, sorted by id (positions as in `field`).
    pub sensors: Vec<Sensor>,
    /// The grid.
    pub field: Field,
    /// Modality names, sorted.
    pub modalities: Vec<String>,
    /// `series[cell][modality]`: the cell series x̂ on the dataset's time grid.
    pub series: Vec<Vec<OwnedSeries>>,
    /// Per sensor: the later of its recorded collection and its latest reading at or before t
    /// (a reading that is in the database has been collected), seconds.
    pub last_collected: Vec<Option<UnixSeconds>>,
    /// Per sensor: its earliest reading, seconds (the start of its log, for pending volume).
    pub first_reading: Vec<Option<UnixSeconds>>,
    /// The latest reading at or before t, seconds.
    pub latest: Option<UnixSeconds>,
}

/// The median spacing of consecutive readings, seconds (the dataset's sampling interval).
fn sampling_step(times: &[Vec<UnixSeconds>]) -> i64 {
    let mut gaps: Vec<i64> = times
        .iter()
        .flat_map(|t| t.windows(2).map(|w| w[1] - w[0]))
        .filter(|&g| g > 0)
        .collect();
    if gaps.is_empty() {
        return 86_400;
    }
    let mid = gaps.len() / 2;
    *gaps.select_nth_unstable(mid).1
}

/// Which stored readings count as collected: those with times in `from..=until` (seconds).
#[derive(Debug, Clone, Copy)]
pub struct History {
    /// Earliest reading used.
    pub from: UnixSeconds,
    /// Latest reading used.
    pub until: UnixSeconds,
}

impl Default for History {
    fn default() -> Self {
        Self {
            from: UnixSeconds::MIN,
            until: UnixSeconds::MAX,
        }
    }
}

/// Loads everything collected at or before `t` (default: the latest reading), within `history`.
pub fn knowledge(project: &Project, t: Option<UnixSeconds>, history: History) -> Result<Knowledge> {
    let (sensors, field) = project.field()?;
    let index: HashMap<&str, usize> = sensors
        .iter()
        .enumerate()
        .map(|(k, s)| (s.id.as_str(), k))
        .collect();
    let t_max = t.unwrap_or(UnixSeconds::MAX);
    // A reading is known when it lies in the history window, or when a recorded collection of
    // its sensor (at or before t) brought it back.
    let mut collected: Vec<Option<UnixSeconds>> = vec![None; sensors.len()];
    for (id, at) in project.store.sensor_last_collected()? {
        if let Some(&s) = index.get(id.as_str())
            && at <= t_max
        {
            collected[s] = collected[s].max(Some(at));
        }
    }
    let horizon = collected
        .iter()
        .flatten()
        .copied()
        .max()
        .unwrap_or(UnixSeconds::MIN);
    let until = t_max.min(history.until.max(horizon));
    let batch = project.store.readings_for(None, history.from..=until)?;
    let mut modalities: Vec<String> = batch.modalities.iter().map(ToString::to_string).collect();
    modalities.sort();
    modalities.dedup();
    let mpos: Vec<usize> = batch
        .modalities
        .iter()
        .map(|m| modalities.binary_search(&m.to_string()).unwrap_or(0))
        .collect();
    let nm = modalities.len();
    // Per (sensor, modality): times and values, in time order (the store returns them so).
    let mut times: Vec<Vec<UnixSeconds>> = vec![Vec::new(); sensors.len() * nm];
    let mut values: Vec<Vec<f64>> = vec![Vec::new(); sensors.len() * nm];
    let mut last_collected = collected.clone();
    let mut first_reading: Vec<Option<UnixSeconds>> = vec![None; sensors.len()];
    let mut latest = None;
    for r in &batch.rows {
        let Some(&s) = index.get(batch.sensors[r.sensor as usize].as_str()) else {
            continue;
        };
        if r.t > t_max.min(history.until.max(collected[s].unwrap_or(UnixSeconds::MIN))) {
            continue;
        }
        let k = s * nm + mpos[r.modality as usize];
        times[k].push(r.t);
        values[k].push(r.value);
        last_collected[s] = last_collected[s].max(Some(r.t));
        first_reading[s] = Some(first_reading[s].map_or(r.t, |f: i64| f.min(r.t)));
        latest = latest.max(Some(r.t));
    }
    let step = sampling_step(&times);
    let origin = times
        .iter()
        .filter_map(|t| t.first())
        .min()
        .copied()
        .unwrap_or(0);
    let grid = TimeGrid {
        origin,
        step_s: step.max(1),
    };
    let series = field
        .cells()
        .iter()
        .map(|cell| {
            (0..nm)
                .map(|m| {
                    let members: Vec<Series<'_>> = cell
                        .sensors
                        .iter()
                        .map(|&s| Series::new(&times[s * nm + m], &values[s * nm + m]))
                        .collect();
                    cell_series(&members, grid)
                })
                .collect()
        })
        .collect();
    Ok(Knowledge {
        sensors,
        field,
        modalities,
        series,
        last_collected,
        first_reading,
        latest,
    })
}

/// Per-cell class probabilities from a user's CSV: `cell_id,p_1,...,p_K` with a header.
fn read_probabilities(path: &Path, field: &Field) -> Result<Vec<Vec<f64>>> {
    let rows: Vec<(String, Vec<f64>)> = cell_csv::read(path)?
        .into_iter()
        .map(|r| (r.cell, r.values))
        .collect();
    let labels: Vec<String> = field.cells().iter().map(|c| c.index.to_string()).collect();
    let ordered =
        validate_probabilities(&labels, &rows).with_context(|| format!("{}", path.display()))?;
    Ok(ordered)
}

/// The condition model's output: class names and one distribution per cell.
pub struct ConditionOutput {
    /// The modality the classes come from.
    pub modality: String,
    /// Class thresholds in its unit (empty for user probabilities).
    pub thresholds: Vec<f64>,
    /// Class names.
    pub classes: Vec<String>,
    /// One distribution per cell.
    pub probabilities: Vec<Vec<f64>>,
}

fn class_names(k: usize) -> Vec<String> {
    if k == 3 {
        vec!["dry".into(), "adequate".into(), "wet".into()]
    } else {
        (1..=k).map(|c| format!("class_{c}")).collect()
    }
}

/// Trains the built-in condition model on the collected history and predicts every cell at
/// `t`; `None` when there is no suitable modality or too little data.
fn condition(project: &Project, k: &Knowledge, t: UnixSeconds) -> Result<Option<ConditionOutput>> {
    let u = &project.config.utility;
    let name = match &u.condition_modality {
        Some(m) => Some(m.clone()),
        None => k
            .modalities
            .iter()
            .find(|m| *m == "vw@30cm")
            .or_else(|| k.modalities.iter().find(|m| m.starts_with("vw@")))
            .cloned(),
    };
    let Some(name) = name else { return Ok(None) };
    let Some(m) = k.modalities.iter().position(|x| *x == name) else {
        bail!("utility.condition_modality = {name:?} has no readings");
    };
    let cells: Vec<Series<'_>> = k.series.iter().map(|s| s[m].as_series()).collect();
    let neighbours: Vec<Vec<usize>> = k
        .field
        .all_neighbours()
        .iter()
        .map(|n| n.iter().map(|c| c.index()).collect())
        .collect();
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
    match ConditionModel::fit(&cells, &neighbours, from, t, &config) {
        Ok(model) => Ok(Some(ConditionOutput {
            modality: name,
            thresholds: model.thresholds().to_vec(),
            classes: class_names(model.n_classes()),
            probabilities: model.predict_proba(&cells, &neighbours, t),
        })),
        Err(e) => {
            eprintln!("warning: no condition model ({e}); U = 0 for every cell");
            Ok(None)
        }
    }
}

/// A scored cell.
pub struct ScoredCell {
    /// Position in the field.
    pub cell: usize,
    /// The terms.
    pub terms: CellTerms,
}

/// The result of scoring.
pub struct Scoring {
    /// Mission time, seconds.
    pub t: UnixSeconds,
    /// What was known.
    pub knowledge: Knowledge,
    /// One entry per cell, in field order.
    pub cells: Vec<ScoredCell>,
    /// The condition model's output, if any.
    pub condition: Option<ConditionOutput>,
    /// The anomaly form label (`raw` or `bounded(kappa=...)`).
    pub anomaly_form: String,
}

/// Scores every cell at `t` (default: the latest reading), from the stored history.
pub fn score(
    project: &Project,
    at: Option<UnixSeconds>,
    history: History,
    probabilities: Option<&Path>,
) -> Result<Scoring> {
    let k = knowledge(project, at, history)?;
    let Some(t) = at.or(k.latest) else {
        bail!("no readings: ingest some data first");
    };
    let config = project.config.utility.to_core(&k.modalities)?;
    let condition = match probabilities {
        Some(path) => {
            let p = read_probabilities(path, &k.field)?;
            let kk = p.first().map_or(0, Vec::len);
            Some(ConditionOutput {
                modality: "user".into(),
                thresholds: Vec::new(),
                classes: class_names(kk),
                probabilities: p,
            })
        }
        None => condition(project, &k, t)?,
    };
    let neighbours: Vec<Vec<usize>> = k
        .field
        .all_neighbours()
        .iter()
        .map(|n| n.iter().map(|c| c.index()).collect())
        .collect();
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
    let terms = score_cells_parallel(&inputs, t, &config).context("scoring the cells")?;
    drop(inputs);
    Ok(Scoring {
        t,
        cells: terms
            .into_iter()
            .enumerate()
            .map(|(cell, terms)| ScoredCell { cell, terms })
            .collect(),
        knowledge: k,
        condition,
        anomaly_form: config.anomaly_form.label(),
    })
}

/// Writes the terms, class probabilities, neighbour correlations and the anomaly history into
/// the cell metadata table, in one transaction.
pub fn store_scores(project: &mut Project, s: &Scoring) -> Result<()> {
    let k = &s.knowledge;
    let min_overlap = project.config.utility.min_overlap;
    let flag = project.config.utility.anomaly_flag;
    // Scalar fields are replaced on upsert: carry over what scoring does not compute.
    let stored: HashMap<gleaner_field::CellIndex, CellMetadata> = project
        .store
        .cell_metadata()?
        .into_iter()
        .map(|m| (m.cell, m))
        .collect();
    let metadata: Vec<CellMetadata> = s
        .cells
        .iter()
        .map(|c| {
            let cell = &k.field.cells()[c.cell];
            let mut m = CellMetadata::new(cell.index);
            if let Some(old) = stored.get(&cell.index) {
                m.pending_bytes = old.pending_bytes;
                m.expected_energy_j = old.expected_energy_j;
            }
            m.last_collected = cell
                .sensors
                .iter()
                .filter_map(|&x| k.last_collected[x])
                .max();
            m.scores = Some(CellScores {
                freshness: c.terms.f,
                redundancy: c.terms.r,
                anomaly: c.terms.a,
                uncertainty: c.terms.u,
                score: c.terms.s,
                computed_at: s.t,
            });
            if let Some(cond) = &s.condition {
                m.class_probabilities = cond
                    .classes
                    .iter()
                    .zip(&cond.probabilities[c.cell])
                    .map(|(class, &p)| ClassProbability {
                        class: class.clone(),
                        probability: p,
                    })
                    .collect();
            }
            for &nb in k.field.neighbours(gleaner_field::CellId(c.cell as u32)) {
                for (mi, name) in k.modalities.iter().enumerate() {
                    let (a, b) = (
                        k.series[c.cell][mi].as_series(),
                        k.series[nb.index()][mi].as_series(),
                    );
                    if a.is_empty() || b.is_empty() {
                        continue;
                    }
                    let overlap = common_points(a, b);
                    m.correlations.push(Correlation {
                        neighbour: k.field.cells()[nb.index()].index,
                        modality: gleaner_field::Modality::new(name)
                            .expect("stored modality is valid"),
                        correlation: series_correlation(a, b, min_overlap),
                        overlap,
                    });
                }
            }
            for (mi, a) in c.terms.a_by_modality.iter().enumerate() {
                if let (Some(a), Some((t_star, _))) = (a, k.series[c.cell][mi].as_series().last()) {
                    m.anomalies.push(AnomalyRecord {
                        modality: gleaner_field::Modality::new(&k.modalities[mi])
                            .expect("stored modality is valid"),
                        t: t_star,
                        anomaly: *a,
                        flagged: *a >= flag,
                    });
                }
            }
            m
        })
        .collect();
    project.store.upsert_cell_metadata(&metadata)?;
    Ok(())
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

/// One scored cell in the JSON output. Positions are `[lon, lat]`.
#[derive(Serialize)]
pub struct ScoreJson {
    /// Cell id.
    pub cell: String,
    /// Centre `[lon, lat]`, degrees.
    pub centre_lon_lat: [f64; 2],
    /// Number of sensors.
    pub sensors: usize,
    /// Freshness F.
    pub f: f64,
    /// Redundancy R.
    pub r: f64,
    /// Anomaly A as used in S (see `anomaly_form`).
    pub a: f64,
    /// Raw anomaly.
    pub a_raw: f64,
    /// Uncertainty U.
    pub u: f64,
    /// Score S.
    pub s: f64,
    /// The largest term's name: what drives S.
    pub driver: &'static str,
    /// R per modality (null where the cell lacks it).
    pub r_by_modality: HashMap<String, Option<f64>>,
    /// A per modality.
    pub a_by_modality: HashMap<String, Option<f64>>,
    /// Class probabilities.
    pub probabilities: Vec<f64>,
}

/// The whole `score --json` document.
#[derive(Serialize)]
pub struct ScoringJson {
    /// Mission time, RFC 3339.
    pub t: String,
    /// Weights alpha, beta, gamma, delta.
    pub weights: [f64; 4],
    /// `raw` or `bounded(kappa=..)`.
    pub anomaly_form: String,
    /// Condition modality and class names.
    pub condition: Option<(String, Vec<String>, Vec<f64>)>,
    /// Cells, sorted as asked.
    pub cells: Vec<ScoreJson>,
}

/// Which weighted term contributes most to S.
pub fn driver(t: &CellTerms, w: [f64; 4]) -> &'static str {
    let parts = [
        ("freshness", w[0] * t.f),
        ("anomaly", w[1] * t.a),
        ("uncertainty", w[2] * t.u),
    ];
    parts
        .iter()
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map_or("none", |p| p.0)
}

/// How to order scored cells.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ScoreSort {
    /// Highest S first (the default).
    #[default]
    Score,
    /// Highest F first.
    Freshness,
    /// Highest R first.
    Redundancy,
    /// Highest A first.
    Anomaly,
    /// Highest U first.
    Uncertainty,
    /// By cell id.
    Cell,
}

/// Sorts the document's cells (ties by cell id).
pub fn sort(doc: &mut ScoringJson, key: ScoreSort) {
    let value = |c: &ScoreJson| match key {
        ScoreSort::Score | ScoreSort::Cell => c.s,
        ScoreSort::Freshness => c.f,
        ScoreSort::Redundancy => c.r,
        ScoreSort::Anomaly => c.a,
        ScoreSort::Uncertainty => c.u,
    };
    if key == ScoreSort::Cell {
        doc.cells.sort_by(|a, b| a.cell.cmp(&b.cell));
    } else {
        doc.cells
            .sort_by(|a, b| value(b).total_cmp(&value(a)).then(a.cell.cmp(&b.cell)));
    }
}

/// The JSON document, cells sorted by descending S.
pub fn to_json(project: &Project, s: &Scoring) -> ScoringJson {
    let u = &project.config.utility;
    let w = [u.alpha, u.beta, u.gamma, u.delta];
    let k = &s.knowledge;
    let mut cells: Vec<ScoreJson> = s
        .cells
        .iter()
        .map(|c| {
            let cell = &k.field.cells()[c.cell];
            let centre = k.field.frame().inverse(cell.centre);
            ScoreJson {
                cell: cell.index.to_string(),
                centre_lon_lat: [centre.lon(), centre.lat()],
                sensors: cell.sensors.len(),
                f: c.terms.f,
                r: c.terms.r,
                a: c.terms.a,
                a_raw: c.terms.a_raw,
                u: c.terms.u,
                s: c.terms.s,
                driver: driver(&c.terms, w),
                r_by_modality: k
                    .modalities
                    .iter()
                    .cloned()
                    .zip(c.terms.r_by_modality.iter().copied())
                    .collect(),
                a_by_modality: k
                    .modalities
                    .iter()
                    .cloned()
                    .zip(c.terms.a_by_modality.iter().copied())
                    .collect(),
                probabilities: c.terms.probabilities.clone(),
            }
        })
        .collect();
    cells.sort_by(|a, b| b.s.total_cmp(&a.s).then(a.cell.cmp(&b.cell)));
    ScoringJson {
        t: format_rfc3339(s.t),
        weights: w,
        anomaly_form: s.anomaly_form.clone(),
        condition: s
            .condition
            .as_ref()
            .map(|c| (c.modality.clone(), c.classes.clone(), c.thresholds.clone())),
        cells,
    }
}

/// The table: header lines with the weights, then one line per cell.
pub fn table(doc: &ScoringJson, limit: usize) -> String {
    let mut out = format!(
        "scored at {}  S = {}·F + {}·A + {}·U − {}·R  (anomaly: {}{})\n",
        doc.t,
        doc.weights[0],
        doc.weights[1],
        doc.weights[2],
        doc.weights[3],
        doc.anomaly_form,
        doc.condition.as_ref().map_or(
            String::from(", no condition model: U = 0"),
            |(m, c, _)| format!(", U from {m}: {}", c.join("/"))
        )
    );
    out.push_str(&format!(
        "{:<10} {:>7} {:>6} {:>6} {:>8} {:>6} {:>8}  {}\n",
        "cell", "sensors", "F", "R", "A", "U", "S", "driver"
    ));
    for c in doc.cells.iter().take(limit) {
        out.push_str(&format!(
            "{:<10} {:>7} {:>6.3} {:>6.3} {:>8.3} {:>6.3} {:>8.3}  {}\n",
            c.cell, c.sensors, c.f, c.r, c.a, c.u, c.s, c.driver
        ));
    }
    out
}
