//! Scoring every cell from scratch (docs/method.md §2): plain in-memory inputs in, terms out.

use rayon::prelude::*;

use crate::probabilities::check_distribution;
use crate::terms::{
    Moments, aligned_correlation, anomaly, freshness, merged_correlation, neighbour_anomaly, score,
    uncertainty,
};
use crate::{AnomalyReference, Series, UtilityConfig, UtilityError};
use gleaner_field::UnixSeconds;

/// Everything the score needs to know about one cell, borrowed from the caller.
///
/// Cells are referred to by their position in the slice given to [`score_cells`] (use
/// [`gleaner_field::CellId::index`] for a field's cells).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct CellInputs<'a> {
    /// Last collection time of each of the cell's sensors, s (`None` = never collected).
    /// At least one sensor.
    pub last_collected: &'a [Option<UnixSeconds>],
    /// The cell series x̂_i^m, one per modality position (same number for every cell; an empty
    /// series means the cell lacks the modality), on the dataset's time grid (see
    /// [`cell_series`](crate::cell_series)). Only collected data belongs here.
    pub series: Vec<Series<'a>>,
    /// Neighbour cells N_i, as positions in the same slice.
    pub neighbours: &'a [usize],
    /// Class probabilities p_i1..p_iK from the condition model or the user (same K >= 2 for
    /// every cell, summing to 1), or empty for every cell when there is no model (U = 0).
    pub probabilities: &'a [f64],
}

/// The terms of one cell's score. Per-modality entries are `None` where the cell lacks the
/// modality (no point in the history window).
#[derive(Debug, Clone, PartialEq)]
pub struct CellTerms {
    /// Freshness F_i, dimensionless in [0, 1].
    pub f: f64,
    /// Redundancy R_i, dimensionless in [0, 1].
    pub r: f64,
    /// Anomaly as used in the score: raw A_i or its bounded form, per
    /// [`UtilityConfig::anomaly_form`].
    pub a: f64,
    /// Raw anomaly A_i, standard deviations, >= 0.
    pub a_raw: f64,
    /// Model uncertainty U_i, dimensionless in [0, 1].
    pub u: f64,
    /// Score S_i = alpha·F + beta·A + gamma·U − delta·R.
    pub s: f64,
    /// R_i^m per modality position.
    pub r_by_modality: Vec<Option<f64>>,
    /// Raw A_i^m per modality position, standard deviations.
    pub a_by_modality: Vec<Option<f64>>,
    /// The class probabilities U was computed from (empty without a model).
    pub probabilities: Vec<f64>,
}

/// Checks the inputs and returns the number of modalities; `parallel` spreads the per-cell
/// checks over rayon's pool (the first bad cell in order is still the one reported).
fn validate(
    cells: &[CellInputs<'_>],
    config: &UtilityConfig,
    parallel: bool,
) -> Result<usize, UtilityError> {
    let n_modalities = cells.first().map_or(0, |c| c.series.len());
    config.validate(n_modalities)?;
    let k = cells.first().map_or(0, |c| c.probabilities.len());
    let check = |i: usize| check_cell(cells, i, n_modalities, k).err();
    let first_error = if parallel {
        (0..cells.len()).into_par_iter().find_map_first(check)
    } else {
        (0..cells.len()).find_map(check)
    };
    match first_error {
        Some(e) => Err(e),
        None => Ok(n_modalities),
    }
}

fn check_cell(
    cells: &[CellInputs<'_>],
    i: usize,
    n_modalities: usize,
    k: usize,
) -> Result<(), UtilityError> {
    let c = &cells[i];
    if c.last_collected.is_empty() {
        return Err(UtilityError::NoSensors(i));
    }
    if c.series.len() != n_modalities {
        return Err(UtilityError::ModalityCount {
            cell: i,
            got: c.series.len(),
            expected: n_modalities,
        });
    }
    for (m, s) in c.series.iter().enumerate() {
        check_series(i, m, *s)?;
    }
    if let Some(&j) = c.neighbours.iter().find(|&&j| j >= cells.len() || j == i) {
        return Err(UtilityError::Neighbour {
            cell: i,
            neighbour: j,
            cells: cells.len(),
        });
    }
    let err = |reason: String| UtilityError::Probabilities {
        cell: format!("#{i}"),
        reason,
    };
    if k == 0 && !c.probabilities.is_empty() {
        return Err(err(format!(
            "{} probabilities but cell #0 has none (give every cell probabilities, or none)",
            c.probabilities.len()
        )));
    }
    if k > 0 {
        check_distribution(c.probabilities, k).map_err(err)?;
    }
    Ok(())
}

/// Checks that a series has equal lengths, strictly increasing times and finite values.
pub(crate) fn check_series(
    cell: usize,
    modality: usize,
    s: Series<'_>,
) -> Result<(), UtilityError> {
    if s.times.len() != s.values.len() {
        return Err(UtilityError::SeriesLength {
            cell,
            modality,
            times: s.times.len(),
            values: s.values.len(),
        });
    }
    if let Some(w) = s.times.windows(2).find(|w| w[1] <= w[0]) {
        return Err(UtilityError::SeriesOrder {
            cell,
            modality,
            time: w[1],
        });
    }
    if let Some(k) = s.values.iter().position(|v| !v.is_finite()) {
        return Err(UtilityError::NonFinite {
            cell,
            modality,
            time: s.times[k],
            value: s.values[k],
        });
    }
    Ok(())
}

/// Moments of every cell's windowed series, cell-major (cell × modality).
fn all_moments(
    cells: &[CellInputs<'_>],
    t: UnixSeconds,
    config: &UtilityConfig,
    parallel: bool,
) -> Vec<Moments> {
    let from = config.window.start(t);
    let one = |c: &CellInputs<'_>| -> Vec<Moments> {
        c.series
            .iter()
            .map(|s| Moments::of(s.between(from, t).values))
            .collect()
    };
    if parallel {
        cells.par_iter().flat_map_iter(one).collect()
    } else {
        cells.iter().flat_map(one).collect()
    }
}

/// Reusable gather buffers of the merge join.
type Buffers = (Vec<f64>, Vec<f64>);

/// Correlation of cell `i` with neighbour `j` for modality `m` over the window.
fn pair_correlation(
    cells: &[CellInputs<'_>],
    moments: &[Moments],
    (i, j, m): (usize, usize, usize),
    t: UnixSeconds,
    config: &UtilityConfig,
    n_modalities: usize,
    buffers: &mut Buffers,
) -> f64 {
    let from = config.window.start(t);
    let own = cells[i].series[m].between(from, t);
    let other = cells[j].series[m].between(from, t);
    if own.times == other.times {
        aligned_correlation(
            own.values,
            moments[i * n_modalities + m],
            other.values,
            moments[j * n_modalities + m],
            config.min_overlap,
        )
    } else {
        merged_correlation(
            own,
            other,
            config.min_overlap,
            &mut buffers.0,
            &mut buffers.1,
        )
    }
}

/// Whether edge (i -> j) is computed by cell i; otherwise j computed the same pair (the
/// correlation is symmetric) and i reads it.
fn owns_edge(cells: &[CellInputs<'_>], i: usize, j: usize) -> bool {
    i < j || !cells[j].neighbours.contains(&i)
}

/// Per cell: the correlations with its neighbours, neighbour-major (k × modality), NaN for
/// edges whose pair is computed by the neighbour.
fn edge_correlations(
    cells: &[CellInputs<'_>],
    moments: &[Moments],
    t: UnixSeconds,
    config: &UtilityConfig,
    n_modalities: usize,
    parallel: bool,
) -> Vec<Vec<f64>> {
    let one = |buffers: &mut Buffers, i: usize| -> Vec<f64> {
        let mut out = Vec::with_capacity(cells[i].neighbours.len() * n_modalities);
        for &j in cells[i].neighbours {
            let owned = owns_edge(cells, i, j);
            for m in 0..n_modalities {
                out.push(if owned {
                    pair_correlation(cells, moments, (i, j, m), t, config, n_modalities, buffers)
                } else {
                    f64::NAN
                });
            }
        }
        out
    };
    if parallel {
        (0..cells.len())
            .into_par_iter()
            .map_init(Buffers::default, one)
            .collect()
    } else {
        let mut buffers = Buffers::default();
        (0..cells.len()).map(|i| one(&mut buffers, i)).collect()
    }
}

/// Terms of cell `i` (inputs already validated; `edges` from [`edge_correlations`]).
fn cell_terms(
    cells: &[CellInputs<'_>],
    edges: &[Vec<f64>],
    i: usize,
    t: UnixSeconds,
    config: &UtilityConfig,
    n_modalities: usize,
) -> CellTerms {
    let cell = &cells[i];
    let from = config.window.start(t);
    let f = freshness(t, cell.last_collected, config.lambda_per_s());
    let mut r_by = Vec::with_capacity(n_modalities);
    let mut a_by = Vec::with_capacity(n_modalities);
    for m in 0..n_modalities {
        let own = cell.series[m].between(from, t);
        if own.is_empty() {
            r_by.push(None);
            a_by.push(None);
            continue;
        }
        let mut total = 0.0;
        for (k, &j) in cell.neighbours.iter().enumerate() {
            let corr = if owns_edge(cells, i, j) {
                edges[i][k * n_modalities + m]
            } else {
                let back = cells[j]
                    .neighbours
                    .iter()
                    .position(|&x| x == i)
                    .unwrap_or(0);
                edges[j][back * n_modalities + m]
            };
            total += corr.max(0.0);
        }
        let r = if cell.neighbours.is_empty() {
            0.0
        } else {
            (total / cell.neighbours.len() as f64).clamp(0.0, 1.0)
        };
        r_by.push(Some(r));
        let a = match config.anomaly_reference {
            AnomalyReference::OwnHistory => anomaly(own, config.epsilon),
            AnomalyReference::Neighbours { min_neighbours } => {
                let nbs: Vec<Series<'_>> = cell
                    .neighbours
                    .iter()
                    .map(|&j| cells[j].series[m].between(from, t))
                    .collect();
                neighbour_anomaly(own, &nbs, min_neighbours, config.epsilon)
            }
        };
        a_by.push(Some(a));
    }
    finish_terms(f, r_by, a_by, cell.probabilities, config)
}

/// Combines per-modality terms, F and the probabilities into [`CellTerms`].
pub(crate) fn finish_terms(
    f: f64,
    r_by_modality: Vec<Option<f64>>,
    a_by_modality: Vec<Option<f64>>,
    probabilities: &[f64],
    config: &UtilityConfig,
) -> CellTerms {
    let r = config
        .redundancy_weights
        .combine(&r_by_modality)
        .clamp(0.0, 1.0);
    let a_raw = config.anomaly_weights.combine(&a_by_modality).max(0.0);
    let a = config.anomaly_form.apply(a_raw);
    let u = uncertainty(probabilities);
    CellTerms {
        f,
        r,
        a,
        a_raw,
        u,
        s: score(f, a, u, r, config),
        r_by_modality,
        a_by_modality,
        probabilities: probabilities.to_vec(),
    }
}

/// Scores every cell at mission time `t` (s) from its full series, on one thread. Only points
/// at or before `t` and inside [`UtilityConfig::window`] are used.
///
/// ```
/// use gleaner_utility::{score_cells, CellInputs, Series, UtilityConfig};
/// let times: Vec<i64> = (0..12).map(|d| d * 86_400).collect();
/// let a: Vec<f64> = (0..12).map(|d| 0.30 + 0.001 * d as f64).collect();
/// let b: Vec<f64> = (0..12).map(|d| 0.25 + 0.002 * (d % 3) as f64).collect();
/// let last = [Some(11 * 86_400)];
/// let cells = vec![
///     CellInputs { last_collected: &last, series: vec![Series::new(&times, &a)],
///                  neighbours: &[1], probabilities: &[0.5, 0.5] },
///     CellInputs { last_collected: &last, series: vec![Series::new(&times, &b)],
///                  neighbours: &[0], probabilities: &[1.0, 0.0] },
/// ];
/// let terms = score_cells(&cells, 12 * 86_400, &UtilityConfig::default()).unwrap();
/// assert!((terms[0].u - 1.0).abs() < 1e-12 && terms[1].u == 0.0);
/// assert!((terms[0].f - (1.0 - 0.5f64.powf(1.0 / 3.0))).abs() < 1e-12);
/// ```
pub fn score_cells(
    cells: &[CellInputs<'_>],
    t: UnixSeconds,
    config: &UtilityConfig,
) -> Result<Vec<CellTerms>, UtilityError> {
    let n_modalities = validate(cells, config, false)?;
    let moments = all_moments(cells, t, config, false);
    let edges = edge_correlations(cells, &moments, t, config, n_modalities, false);
    Ok((0..cells.len())
        .map(|i| cell_terms(cells, &edges, i, t, config, n_modalities))
        .collect())
}

/// [`score_cells`] on all cores (rayon's global pool); same result.
pub fn score_cells_parallel(
    cells: &[CellInputs<'_>],
    t: UnixSeconds,
    config: &UtilityConfig,
) -> Result<Vec<CellTerms>, UtilityError> {
    let n_modalities = validate(cells, config, true)?;
    let moments = all_moments(cells, t, config, true);
    let edges = edge_correlations(cells, &moments, t, config, n_modalities, true);
    Ok((0..cells.len())
        .into_par_iter()
        .map(|i| cell_terms(cells, &edges, i, t, config, n_modalities))
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{AnomalyForm, HistoryWindow};

    const DAY: i64 = 86_400;

    #[test]
    fn window_missing_modality_and_forms() {
        let t: Vec<i64> = (0..30).map(|d| d * DAY).collect();
        let up: Vec<f64> = (0..30).map(|d| d as f64).collect();
        let zig: Vec<f64> = (0..30)
            .map(|d| if d < 15 { d as f64 } else { -(d as f64) })
            .collect();
        let last = [Some(29 * DAY)];
        let cells = vec![
            CellInputs {
                last_collected: &last,
                series: vec![Series::new(&t, &up), Series::new(&t, &up)],
                neighbours: &[1],
                probabilities: &[],
            },
            CellInputs {
                last_collected: &last,
                series: vec![Series::new(&t, &zig), Series::empty()],
                neighbours: &[0],
                probabilities: &[],
            },
        ];
        let all = score_cells(&cells, 29 * DAY, &UtilityConfig::default()).unwrap();
        // Cell 1 lacks modality 1: its terms come from modality 0 alone.
        assert_eq!(all[1].r_by_modality[1], None);
        assert_eq!(all[1].r, all[1].r_by_modality[0].unwrap());
        // Cell 0: modality 1's neighbour lacks it (0), modality 0 correlates weakly positive.
        assert_eq!(all[0].r_by_modality[1], Some(0.0));
        assert!((all[0].r - all[0].r_by_modality[0].unwrap() / 2.0).abs() < 1e-15);
        // The last 14 days only: zig is strictly decreasing there, anti-correlated with up.
        let window = UtilityConfig {
            window: HistoryWindow::Last { seconds: 13 * DAY },
            ..Default::default()
        };
        let w = score_cells(&cells, 29 * DAY, &window).unwrap();
        assert_eq!(w[0].r_by_modality[0], Some(0.0));
        // Anomaly in the window: days 16..29, the latest (29) against days 16..28.
        let want = crate::anomaly(Series::new(&t[16..], &zig[16..]), 1e-6);
        assert_eq!(w[1].a_by_modality[0], Some(want));
        assert!(want > 0.0 && want != all[1].a_by_modality[0].unwrap());
        // Data after t is ignored: scoring at day 9 sees days 0..9 only (fewer than 10 -> R 0).
        let early = score_cells(&cells, 8 * DAY, &UtilityConfig::default()).unwrap();
        assert_eq!(early[0].r, 0.0);
        let bounded = UtilityConfig {
            anomaly_form: AnomalyForm::Bounded { kappa: 3.0 },
            ..Default::default()
        };
        let b = score_cells(&cells, 29 * DAY, &bounded).unwrap();
        assert_eq!(b[1].a_raw, all[1].a_raw);
        assert!((b[1].a - (1.0 - (-all[1].a_raw / 3.0).exp())).abs() < 1e-12);
        assert_eq!(
            score_cells_parallel(&cells, 29 * DAY, &UtilityConfig::default()).unwrap(),
            all
        );
    }

    #[test]
    fn invalid_inputs_name_the_cell() {
        let t = [0, DAY, DAY];
        let v = [1.0, 2.0, 3.0];
        let last = [None];
        let good = CellInputs {
            last_collected: &last,
            series: vec![Series::new(&t[..2], &v[..2])],
            neighbours: &[],
            probabilities: &[],
        };
        let cases: Vec<(CellInputs, &str)> = vec![
            (
                CellInputs {
                    series: vec![Series::new(&t, &v)],
                    ..good.clone()
                },
                "cell 1, modality 0: timestamps not strictly increasing at 86400 s",
            ),
            (
                CellInputs {
                    series: vec![Series::new(&t[..2], &v)],
                    ..good.clone()
                },
                "cell 1, modality 0: 2 times but 3 values",
            ),
            (
                CellInputs {
                    last_collected: &[],
                    ..good.clone()
                },
                "cell 1 has no sensors",
            ),
            (
                CellInputs {
                    neighbours: &[1],
                    ..good.clone()
                },
                "cell 1: invalid neighbour 1",
            ),
            (
                CellInputs {
                    series: vec![],
                    ..good.clone()
                },
                "cell 1: 0 modality series, expected 1",
            ),
            (
                CellInputs {
                    probabilities: &[0.5, 0.5],
                    ..good.clone()
                },
                "cell #1: 2 probabilities but cell #0 has none",
            ),
        ];
        for (bad, want) in cases {
            let e = score_cells(&[good.clone(), bad], DAY, &UtilityConfig::default()).unwrap_err();
            assert!(e.to_string().contains(want), "{e} lacks {want:?}");
        }
        let nan = [f64::NAN, 1.0];
        let bad = CellInputs {
            series: vec![Series::new(&t[..2], &nan)],
            ..good.clone()
        };
        assert!(score_cells_parallel(&[good, bad], DAY, &UtilityConfig::default()).is_err());
    }

    #[test]
    fn neighbour_reference_sees_a_local_jump_that_weather_hides() {
        const DAY: i64 = 86_400;
        let t: Vec<i64> = (0..40).map(|d| d * DAY).collect();
        // A strong shared season (weather) plus small cell-specific wiggles.
        let weather: Vec<f64> = (0..40).map(|d| 0.3 * (d as f64 / 6.0).sin()).collect();
        let wiggle = |k: usize, d: usize| 0.004 * ((d * (k + 2)) % 5) as f64;
        let mut series: Vec<Vec<f64>> = (0..4)
            .map(|k| (0..40).map(|d| weather[d] + wiggle(k, d)).collect())
            .collect();
        // Cell 0 alone gets a 0.1 leak on the last day; cell 3 misses that day.
        series[0][39] += 0.1;
        let t3 = &t[..39];
        let last = [Some(39 * DAY)];
        let nb0 = [1, 2, 3];
        let nb = [0];
        let cells: Vec<CellInputs<'_>> = (0..4)
            .map(|k| CellInputs {
                last_collected: &last,
                series: vec![if k == 3 {
                    Series::new(t3, &series[3][..39])
                } else {
                    Series::new(&t, &series[k])
                }],
                neighbours: if k == 0 { &nb0 } else { &nb },
                probabilities: &[],
            })
            .collect();
        let own = score_cells(&cells, 39 * DAY, &UtilityConfig::default()).unwrap();
        let config = UtilityConfig {
            anomaly_reference: AnomalyReference::Neighbours { min_neighbours: 2 },
            ..Default::default()
        };
        let nbr = score_cells(&cells, 39 * DAY, &config).unwrap();
        let (a_own, a_nb) = (own[0].a_raw, nbr[0].a_raw);
        assert!(a_own < 3.0, "own history hides the jump: {a_own}");
        assert!(a_nb > 10.0, "neighbours reveal it: {a_nb}");
        // By hand: residuals against the median of cells 1, 2 (and 3 before the last day).
        let nbs: Vec<Series<'_>> = nb0.iter().map(|&j| cells[j].series[0]).collect();
        let want = crate::neighbour_anomaly(cells[0].series[0], &nbs, 2, 1e-6);
        assert_eq!(a_nb, want);
        // Too few neighbours on every day: no residual series, A = 0.
        let strict = UtilityConfig {
            anomaly_reference: AnomalyReference::Neighbours { min_neighbours: 4 },
            ..Default::default()
        };
        assert_eq!(
            score_cells(&cells, 39 * DAY, &strict).unwrap()[0].a_raw,
            0.0
        );
        let zero = UtilityConfig {
            anomaly_reference: AnomalyReference::Neighbours { min_neighbours: 0 },
            ..Default::default()
        };
        assert!(score_cells(&cells, 39 * DAY, &zero).is_err());
    }
}
