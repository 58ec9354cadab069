//! The peer study's one-shot selection protocol on CAF (see the crate docs).
//!
//! Inputs: the layouts file (`layout,node,label,x_m,y_m`, one row per sensor and a `Depot`
//! row), the peer's results (`experiment,data,method,map,capacity_J,n_selected,tour_len_m,
//! energy_J,mse_sum_over_unvisited,tour`) and a readings matrix of the sensors (rows = times).
//!
//! Protocol ([`Protocol`]): rows `train` give the means, covariances and dynamics; at every
//! row of `test` the chosen sensors' values are known, the others are estimated; the error is
//! the sum over unvisited sensors of the squared error, averaged over the test rows. A tour's
//! energy is `per_metre_j · length + per_visit_j · (n − free_visits)` (the peer's accounting:
//! one visit free), closed from the depot, within the capacity.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::ops::Range;
use std::path::{Path, PathBuf};

use gleaner_kriging::{DynamicFitOptions, DynamicModel, FieldFilter, SensorSeries, Shrinkage};
use gleaner_orienteering::{
    MarginalOptions, Metric, Problem, SolveOptions, SolverKind, solve, solve_marginal,
};

use crate::EvalError;

mod evaluation;
mod files;
mod intervals;

pub use evaluation::{PeerData, PeerEvaluation, evaluate, load_data, summary_heading};
pub use files::{Layout, PeerResult, read_layouts, read_results};
pub(crate) use files::{bad, column, number, read_csv};
pub use intervals::{BACKTEST_ORIGINS, Coverage, backtest_origins, mean_coverage};

/// Readings of the protocol's sensors on a common time grid: `values[t * n + i]`, NaN where
/// sensor i has no reading at `times[t]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Matrix {
    /// Sensor labels (columns).
    pub labels: Vec<String>,
    /// Row times, seconds since the epoch, ascending.
    pub times: Vec<i64>,
    /// Row-major values, the modality's unit.
    pub values: Vec<f64>,
}

impl Matrix {
    /// The matrix of `labels` × every time any of them has a reading of `modality`, from
    /// one or more batches of readings (e.g. one file per station).
    ///
    /// Errors: a label without any reading.
    pub fn from_readings(
        batches: &[gleaner_ingest::Readings],
        modality: &str,
        labels: &[String],
    ) -> Result<Matrix, EvalError> {
        let col: HashMap<&str, usize> = labels
            .iter()
            .enumerate()
            .map(|(i, l)| (l.as_str(), i))
            .collect();
        // (time, column, value) of every wanted reading.
        let mut cells: Vec<(i64, usize, f64)> = Vec::new();
        for readings in batches {
            let Some(m) = readings
                .modalities
                .iter()
                .position(|x| x.modality.as_str() == modality)
            else {
                continue;
            };
            let sensor_col: Vec<Option<usize>> = readings
                .sensors
                .iter()
                .map(|s| col.get(s.as_str()).copied())
                .collect();
            for r in &readings.rows {
                if r.modality as usize == m
                    && let Some(i) = sensor_col[r.sensor as usize]
                {
                    cells.push((r.t, i, r.value));
                }
            }
        }
        let mut times: Vec<i64> = cells.iter().map(|c| c.0).collect();
        times.sort_unstable();
        times.dedup();
        let n = labels.len();
        let mut values = vec![f64::NAN; times.len() * n];
        let mut seen = vec![false; n];
        for (t, i, v) in cells {
            if let Ok(k) = times.binary_search(&t) {
                values[k * n + i] = v;
                seen[i] = true;
            }
        }
        if let Some(i) = seen.iter().position(|s| !s) {
            return Err(EvalError::Data(format!(
                "sensor {} has no reading of {modality}",
                labels[i]
            )));
        }
        Ok(Matrix {
            labels: labels.to_vec(),
            times,
            values,
        })
    }

    /// The index range of the rows with `from <= time < to` (seconds).
    pub fn rows_between(&self, from: i64, to: i64) -> Range<usize> {
        let a = self.times.partition_point(|&t| t < from);
        let b = self.times.partition_point(|&t| t < to);
        a..b
    }

    /// Only the rows where every sensor has a value (the peer's complete-case rows).
    pub fn complete_rows(&self) -> Matrix {
        let n = self.labels.len();
        let mut out = Matrix {
            labels: self.labels.clone(),
            times: Vec::new(),
            values: Vec::new(),
        };
        for (t, row) in self.times.iter().zip(self.values.chunks(n.max(1))) {
            if row.iter().all(|v| v.is_finite()) {
                out.times.push(*t);
                out.values.extend_from_slice(row);
            }
        }
        out
    }

    /// The columns in the order of `labels` (every label must be a column).
    pub fn reorder(&self, labels: &[String]) -> Result<Matrix, EvalError> {
        let n = self.labels.len();
        let idx: Vec<usize> = labels
            .iter()
            .map(|l| {
                self.labels
                    .iter()
                    .position(|x| x == l)
                    .ok_or_else(|| EvalError::Data(format!("sensor {l} is not in the readings")))
            })
            .collect::<Result<_, _>>()?;
        let mut values = Vec::with_capacity(self.times.len() * labels.len());
        for row in self.values.chunks(n.max(1)) {
            values.extend(idx.iter().map(|&i| row[i]));
        }
        Ok(Matrix {
            labels: labels.to_vec(),
            times: self.times.clone(),
            values,
        })
    }

    fn row(&self, t: usize) -> &[f64] {
        let n = self.labels.len();
        &self.values[t * n..(t + 1) * n]
    }
}

/// How the unvisited sensors are estimated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Estimator {
    /// The last training value carried forward.
    Carried,
    /// The Gaussian conditional of levels given the visited sensors now, mean and covariance
    /// from the training rows without shrinkage (the peer's estimator).
    Levels,
    /// gleaner's dynamic field model (shrunk covariance of levels, AR(1) dynamics, Kalman
    /// filter over every reading known).
    Dynamic,
}

impl Estimator {
    /// All, in report order.
    pub const ALL: [Estimator; 3] = [Estimator::Carried, Estimator::Levels, Estimator::Dynamic];

    /// Its name in results files.
    pub fn name(self) -> &'static str {
        match self {
            Estimator::Carried => "carried",
            Estimator::Levels => "levels",
            Estimator::Dynamic => "dynamic",
        }
    }
}

/// How the sensors are chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Planner {
    /// gleaner: the tour whose readings leave the least posterior variance over all sensors
    /// under the dynamic model (information, non-additive), [`solve_marginal`].
    Information,
    /// The tour that visits the most sensors (every sensor worth 1), gleaner's default
    /// orienteering solver.
    Count,
}

impl Planner {
    /// Its name in results files.
    pub fn name(self) -> &'static str {
        match self {
            Planner::Information => "information",
            Planner::Count => "count",
        }
    }
}

/// The protocol's settings.
#[derive(Debug, Clone, PartialEq)]
pub struct Protocol {
    /// Training rows (indices into the matrix).
    pub train: Range<usize>,
    /// Test rows.
    pub test: Range<usize>,
    /// Energy per metre flown, J/m.
    pub per_metre_j: f64,
    /// Energy per sensor visited, J.
    pub per_visit_j: f64,
    /// Visits not charged.
    pub free_visits: usize,
    /// The dynamic model's fit.
    pub fit: DynamicFitOptions,
    /// Seed of the orienteering search (count planner).
    pub seed: u64,
    /// Weight of the unshared per-sensor drift in the information planner's value (0: none):
    /// a visited sensor also removes its own drift variance over the test, its fitted rate
    /// (unit²/s) × the mean time from the last training row to the test rows (s) × this
    /// weight.
    pub unshared_weight: f64,
}

impl Protocol {
    /// The peer's protocol on hourly data: train rows 0..=1000, test rows 1001..=1500,
    /// 10 J/m, 70 J per visit, one visit free; the dynamic model with an hourly step.
    pub fn peer_hourly(fit: DynamicFitOptions) -> Protocol {
        Protocol {
            train: 0..1001,
            test: 1001..1501,
            per_metre_j: 10.0,
            per_visit_j: 70.0,
            free_visits: 1,
            fit,
            seed: 1,
            unshared_weight: 0.0,
        }
    }
}

/// The outcome of one (layout, capacity, planner).
#[derive(Debug, Clone, PartialEq)]
pub struct Outcome {
    /// Layout name.
    pub layout: String,
    /// Capacity, J.
    pub capacity_j: f64,
    /// Planner.
    pub planner: Planner,
    /// Visited sensors (layout indices) in tour order.
    pub tour: Vec<usize>,
    /// Tour length, m.
    pub tour_m: f64,
    /// Energy by the protocol's accounting, J.
    pub energy_j: f64,
    /// Per estimator: the error (sum over unvisited sensors of squared error, averaged over
    /// the test rows; unit²), or infinite when nothing was visited (the peer's convention).
    pub mse: Vec<(Estimator, f64)>,
    /// Share of the unvisited sensors' test values inside the dynamic model's calibrated 90%
    /// interval (`mean ± q·sd`, `q` from the back-test: [`Fitted::interval_multiplier`]).
    pub coverage90: f64,
    /// The same for the Gaussian 90% interval (`mean ± 1.645·sd`).
    pub coverage90_gaussian: f64,
    /// The calibrated interval's multiplier `q` (1.645: the Gaussian one).
    pub multiplier90: f64,
}

/// A fitted protocol over one readings matrix (columns in a layout's label order).
pub struct Fitted {
    matrix: Matrix,
    protocol: Protocol,
    dynamic: DynamicModel,
    peer: DynamicModel,
    /// Each sensor's unshared drift variance over the test, unit² (rate × mean horizon).
    own_drift: Vec<f64>,
    /// The intervals' back-tests: each origin (a training row) with the dynamic model fitted
    /// on the training rows before it only ([`backtest_origins`]).
    backtests: Vec<(usize, DynamicModel)>,
    /// Rows of each back-test stretch: `min(test rows, training rows / 2)`.
    backtest_rows: usize,
    /// Each sensor's training readings (times s, values), in row order: what every fit and
    /// back-test reads.
    train_series: (Vec<Vec<i64>>, Vec<Vec<f64>>),
}

fn series(matrix: &Matrix, rows: Range<usize>) -> (Vec<Vec<i64>>, Vec<Vec<f64>>) {
    let n = matrix.labels.len();
    let mut times = vec![Vec::new(); n];
    let mut values = vec![Vec::new(); n];
    for t in rows {
        for (i, v) in matrix.row(t).iter().enumerate() {
            if v.is_finite() {
                times[i].push(matrix.times[t]);
                values[i].push(*v);
            }
        }
    }
    (times, values)
}

/// The fitting input over per-sensor times (s) and values.
pub(crate) fn sensor_series<'a>(
    times: &'a [Vec<i64>],
    values: &'a [Vec<f64>],
) -> Vec<SensorSeries<'a>> {
    times
        .iter()
        .zip(values)
        .map(|(t, v)| SensorSeries {
            position: [0.0, 0.0],
            times: t,
            values: v,
        })
        .collect()
}

impl Fitted {
    /// Fits the dynamic model and the peer's Gaussian model on the training rows.
    ///
    /// Errors: training or test rows out of the matrix, or a model that cannot be fitted.
    pub fn new(matrix: Matrix, protocol: Protocol) -> Result<Fitted, EvalError> {
        let rows = matrix.times.len();
        if protocol.train.end > rows || protocol.test.end > rows || protocol.train.is_empty() {
            return Err(EvalError::Data(format!(
                "{rows} rows: the protocol needs train rows {:?} and test rows {:?}",
                protocol.train, protocol.test
            )));
        }
        let (times, values) = series(&matrix, protocol.train.clone());
        let input = sensor_series(&times, &values);
        let fit = |o: &DynamicFitOptions| {
            gleaner_kriging::fit_dynamic(&input, o).map_err(|e| EvalError::Data(e.to_string()))
        };
        let dynamic = fit(&protocol.fit)?;
        let peer = fit(&DynamicFitOptions {
            shrinkage: Shrinkage::Fixed(0.0),
            noise_share: 1e-9,
            common_mode: false,
            ..protocol.fit
        })?;
        let rates = gleaner_kriging::fit_own_rates(&input, protocol.fit.step_s.max(1), 30.0)
            .map_err(|e| EvalError::Data(e.to_string()))?;
        let last_train = matrix.times[protocol.train.end - 1] as f64;
        let horizon = if protocol.test.is_empty() {
            0.0
        } else {
            protocol
                .test
                .clone()
                .map(|t| matrix.times[t] as f64 - last_train)
                .sum::<f64>()
                / protocol.test.len() as f64
        };
        let own_drift = rates.iter().map(|r| r * horizon.max(0.0)).collect();
        let backtest_rows = protocol.test.len().min(protocol.train.len() / 2);
        let backtests = backtest_origins(&protocol.train, backtest_rows)
            .into_iter()
            .filter_map(|origin| {
                // The training readings before the origin: a prefix of each sensor's.
                let before = matrix.times[origin];
                let prefix: Vec<SensorSeries<'_>> =
                    input.iter().map(|s| s.before(before)).collect();
                let model = gleaner_kriging::fit_dynamic(&prefix, &protocol.fit).ok()?;
                Some((origin, model))
            })
            .collect();
        drop(input);
        Ok(Fitted {
            matrix,
            protocol,
            dynamic,
            peer,
            own_drift,
            backtests,
            backtest_rows,
            train_series: (times, values),
        })
    }

    /// The dynamic model fitted on the training rows.
    pub fn model(&self) -> &DynamicModel {
        &self.dynamic
    }

    /// The filter after every training reading.
    fn trained_filter(&self) -> FieldFilter<'_> {
        let n = self.matrix.labels.len();
        let first = self.protocol.train.start;
        let mut f = self.dynamic.filter(self.matrix.times[first] as f64);
        for t in self.protocol.train.clone() {
            f.advance(self.matrix.times[t] as f64);
            for i in 0..n {
                f.observe(i, self.matrix.row(t)[i]);
            }
        }
        f
    }

    /// Chooses the tour for `layout` positions at `capacity_j` with `planner`.
    pub fn plan(
        &self,
        positions: &[[f64; 2]],
        capacity_j: f64,
        planner: Planner,
    ) -> Result<(Vec<usize>, f64), EvalError> {
        let n = positions.len();
        let p = &self.protocol;
        let mut points = Vec::with_capacity(n + 1);
        points.push([0.0, 0.0]);
        points.extend_from_slice(positions);
        let mut rewards = vec![1.0; n + 1];
        rewards[0] = 0.0;
        let mut service = vec![p.per_visit_j; n + 1];
        service[0] = 0.0;
        let budget = capacity_j + p.per_visit_j * p.free_visits as f64;
        let problem =
            Problem::from_scaled_points(&points, Metric::Euclidean, p.per_metre_j, rewards, budget)
                .and_then(|q| q.with_service_costs(service))
                .map_err(|e| EvalError::Data(format!("capacity {capacity_j} J: {e}")))?;
        let route = match planner {
            Planner::Information => {
                let model = &self.dynamic;
                let prior: f64 = (0..n).map(|i| model.covariance()[i * n + i]).sum();
                let w = p.unshared_weight;
                let value = |visited: &[usize]| {
                    let sensors: Vec<usize> = visited.iter().map(|v| v - 1).collect();
                    let own: f64 = sensors.iter().filter_map(|&i| self.own_drift.get(i)).sum();
                    prior - model.remaining_variance(&sensors) + w * own
                };
                solve_marginal(&problem, value, &MarginalOptions::default())
                    .solution
                    .routes
                    .remove(0)
            }
            Planner::Count => {
                let options = SolveOptions::default()
                    .with_seed(p.seed)
                    .with_iterations(2_000);
                solve(&problem, SolverKind::Default, &options)
                    .map_err(|e| EvalError::Data(e.to_string()))?
                    .routes
                    .remove(0)
            }
        };
        let length: f64 = route
            .windows(2)
            .map(|w| {
                let (a, b) = (points[w[0]], points[w[1]]);
                ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
            })
            .sum();
        let tour: Vec<usize> = route[1..route.len() - 1].iter().map(|v| v - 1).collect();
        Ok((tour, length))
    }

    /// Scores a choice of visited sensors with every estimator.
    pub fn score(&self, visited: &[usize]) -> (Vec<(Estimator, f64)>, Coverage) {
        let n = self.matrix.labels.len();
        let mut is_visited = vec![false; n];
        for &v in visited {
            if v < n {
                is_visited[v] = true;
            }
        }
        let unvisited: Vec<usize> = (0..n).filter(|&i| !is_visited[i]).collect();
        let test = self.protocol.test.clone();
        let rows = test.len().max(1) as f64;
        if visited.is_empty() {
            let inf = Estimator::ALL.map(|e| (e, f64::INFINITY)).to_vec();
            return (inf, Coverage::default());
        }
        let q = self.interval_multiplier(visited);
        // Last training value of each sensor.
        let mut last = vec![f64::NAN; n];
        for t in self.protocol.train.clone() {
            for (i, v) in self.matrix.row(t).iter().enumerate() {
                if v.is_finite() {
                    last[i] = *v;
                }
            }
        }
        let mut sums = [0.0f64; 3];
        let (mut inside, mut inside_gaussian, mut judged) = (0usize, 0usize, 0usize);
        let mut filter = self.trained_filter();
        for t in test {
            let row = self.matrix.row(t);
            let readings: Vec<(usize, f64)> = visited
                .iter()
                .filter(|&&v| row[v].is_finite())
                .map(|&v| (v, row[v]))
                .collect();
            let levels = self.peer.conditional(&readings);
            filter.advance(self.matrix.times[t] as f64);
            for &(i, v) in &readings {
                filter.observe(i, v);
            }
            for &u in &unvisited {
                let truth = row[u];
                if !truth.is_finite() {
                    continue;
                }
                let carried = if last[u].is_finite() {
                    last[u]
                } else {
                    self.dynamic.means()[u]
                };
                let (mean, var) = filter.estimate(u);
                sums[0] += (carried - truth).powi(2);
                sums[1] += (levels[u].0 - truth).powi(2);
                sums[2] += (mean - truth).powi(2);
                judged += 1;
                let sd = (var + self.dynamic.noise()).sqrt();
                let miss = (truth - mean).abs();
                inside += usize::from(miss <= q * sd);
                inside_gaussian += usize::from(miss <= gleaner_kriging::Z90 * sd);
            }
        }
        let mse = Estimator::ALL
            .iter()
            .zip(sums)
            .map(|(&e, s)| (e, s / rows))
            .collect();
        let share = |k: usize| {
            if judged > 0 {
                k as f64 / judged as f64
            } else {
                f64::NAN
            }
        };
        let coverage = Coverage {
            calibrated: share(inside),
            gaussian: share(inside_gaussian),
            multiplier: q,
        };
        (mse, coverage)
    }

    /// Plans and scores one (layout, capacity, planner).
    pub fn run(
        &self,
        layout: &Layout,
        capacity_j: f64,
        planner: Planner,
    ) -> Result<Outcome, EvalError> {
        let (tour, tour_m) = self.plan(&layout.positions, capacity_j, planner)?;
        let p = &self.protocol;
        let charged = tour.len().saturating_sub(p.free_visits) as f64;
        let energy_j = p.per_metre_j * tour_m + p.per_visit_j * charged;
        let (mse, coverage) = self.score(&tour);
        Ok(Outcome {
            layout: layout.name.clone(),
            capacity_j,
            planner,
            tour,
            tour_m,
            energy_j,
            mse,
            coverage90: coverage.calibrated,
            coverage90_gaussian: coverage.gaussian,
            multiplier90: coverage.multiplier,
        })
    }
}

/// Every outcome of a protocol run, with the peer's results beside them.
#[derive(Debug, Clone, Default)]
pub struct Report {
    /// gleaner's outcomes.
    pub outcomes: Vec<Outcome>,
    /// The peer's results (for the layouts run).
    pub peer: Vec<PeerResult>,
    /// A line on the data and the model fitted on each layout's columns.
    pub notes: Vec<String>,
}

/// Runs the protocol for every layout, at every capacity the peer reports for it (for a
/// layout the peer has no results for, at `default_capacities`), with each planner.
pub fn run_protocol(
    matrix: &Matrix,
    layouts: &[Layout],
    peer: &[PeerResult],
    protocol: &Protocol,
    default_capacities: &[f64],
    planners: &[Planner],
    mut progress: impl FnMut(usize, usize),
) -> Result<Report, EvalError> {
    let mut report = Report::default();
    let total = layouts.len();
    for (k, layout) in layouts.iter().enumerate() {
        progress(k, total);
        let m = matrix.reorder(&layout.labels)?;
        let fitted = Fitted::new(m, protocol.clone())?;
        let model = fitted.model();
        report.notes.push(format!(
            "{}: {} sensors, phi {:.6} per {} s, shrinkage {:.3}",
            layout.name,
            layout.labels.len(),
            model.phi(),
            model.step_s(),
            model.shrinkage()
        ));
        let mut caps: Vec<f64> = peer
            .iter()
            .filter(|r| r.layout == layout.name)
            .map(|r| r.capacity_j)
            .collect();
        caps.sort_by(f64::total_cmp);
        caps.dedup();
        if caps.is_empty() {
            caps = default_capacities.to_vec();
        }
        for &cap in &caps {
            for &planner in planners {
                report.outcomes.push(fitted.run(layout, cap, planner)?);
            }
        }
        report
            .peer
            .extend(peer.iter().filter(|r| r.layout == layout.name).cloned());
    }
    progress(total, total);
    Ok(report)
}

impl Report {
    /// The outcomes as CSV: one row per (layout, capacity, planner, estimator).
    pub fn outcomes_csv(&self) -> String {
        let mut s = String::from(
            "layout,capacity_J,planner,estimator,n_selected,tour_len_m,energy_J,mse_sum_over_unvisited,coverage90,coverage90_gaussian,q90,tour\n",
        );
        for o in &self.outcomes {
            let tour: Vec<String> = o.tour.iter().map(|v| v.to_string()).collect();
            for (e, mse) in &o.mse {
                let _ = writeln!(
                    s,
                    "{},{},{},{},{},{:.3},{:.3},{},{:.4},{:.4},{:.4},{}",
                    o.layout,
                    o.capacity_j,
                    o.planner.name(),
                    e.name(),
                    o.tour.len(),
                    o.tour_m,
                    o.energy_j,
                    mse,
                    o.coverage90,
                    o.coverage90_gaussian,
                    o.multiplier90,
                    tour.join(" ")
                );
            }
        }
        s
    }

    fn mse(&self, layout: &str, cap: f64, planner: Planner, e: Estimator) -> Option<f64> {
        self.outcomes
            .iter()
            .find(|o| o.layout == layout && o.capacity_j == cap && o.planner == planner)
            .and_then(|o| o.mse.iter().find(|(x, _)| *x == e).map(|(_, v)| *v))
    }

    /// The mean error of (`planner`, `estimator`) over the random layouts (`map_*`) and the
    /// capacities in `from_j..=to_j` (J) they were run at, unit²; `None` when there is none or
    /// one is infinite.
    pub fn mean_error(
        &self,
        planner: Planner,
        estimator: Estimator,
        from_j: f64,
        to_j: f64,
    ) -> Option<f64> {
        let v: Vec<f64> = self
            .outcomes
            .iter()
            .filter(|o| {
                o.planner == planner
                    && o.layout.starts_with("map_")
                    && (from_j..=to_j).contains(&o.capacity_j)
            })
            .filter_map(|o| o.mse.iter().find(|(e, _)| *e == estimator).map(|x| x.1))
            .collect();
        (!v.is_empty() && v.iter().all(|x| x.is_finite()))
            .then(|| v.iter().sum::<f64>() / v.len() as f64)
    }

    fn peer_mse(&self, layout: &str, cap: f64, method: &str) -> Option<f64> {
        self.peer
            .iter()
            .find(|r| r.layout == layout && r.capacity_j == cap && r.method == method)
            .map(|r| r.mse)
    }

    /// A Markdown summary: per capacity, the mean over the layouts the peer reports of each
    /// (planner, estimator) error and of the peer's methods; the share of (layout, capacity)
    /// pairs where gleaner's pipeline (`planner`, `estimator`) is at or below the peer's
    /// `mysolu`; coverage of the 90% intervals.
    pub fn summary(&self, planner: Planner, estimator: Estimator) -> String {
        let mut s = String::new();
        // Without the peer's results (a data set they did not run), the random layouts and
        // the capacities gleaner ran.
        let from_outcomes = self.peer.is_empty();
        let mut layouts: Vec<String> = if from_outcomes {
            self.outcomes
                .iter()
                .filter(|o| o.layout.starts_with("map_"))
                .map(|o| o.layout.clone())
                .collect()
        } else {
            self.peer.iter().map(|r| r.layout.clone()).collect()
        };
        layouts.sort();
        layouts.dedup();
        let mut caps: Vec<f64> = if from_outcomes {
            self.outcomes
                .iter()
                .filter(|o| layouts.contains(&o.layout))
                .map(|o| o.capacity_j)
                .collect()
        } else {
            self.peer.iter().map(|r| r.capacity_j).collect()
        };
        caps.sort_by(f64::total_cmp);
        caps.dedup();
        let methods: &[&str] = if from_outcomes {
            &[]
        } else {
            &["mysolu", "baseline_ml", "baseline_fs"]
        };
        let _ = writeln!(
            s,
            "Mean over {} layouts of the summed squared error over unvisited sensors, ×10⁻³ (m³/m³)²; gleaner = planner `{}`, columns = its estimators:\n",
            layouts.len(),
            planner.name()
        );
        let mut head = String::from("| capacity kJ |");
        for e in Estimator::ALL {
            let _ = write!(head, " gleaner {} |", e.name());
        }
        for m in methods {
            let _ = write!(head, " peer {m} |");
        }
        let _ = writeln!(s, "{head}");
        let _ = writeln!(
            s,
            "|{}",
            "---|".repeat(1 + Estimator::ALL.len() + methods.len())
        );
        let (mut wins, mut pairs) = (0usize, 0usize);
        for &cap in &caps {
            let mean = |f: &dyn Fn(&str) -> Option<f64>| -> Option<f64> {
                let v: Vec<f64> = layouts.iter().filter_map(|l| f(l)).collect();
                (v.len() == layouts.len() && v.iter().all(|x| x.is_finite()))
                    .then(|| v.iter().sum::<f64>() / v.len() as f64)
            };
            let fmt = |v: Option<f64>| v.map_or("–".to_string(), |x| format!("{:.3}", x * 1e3));
            let mut line = format!("| {:.0} |", cap / 1e3);
            for e in Estimator::ALL {
                let v = mean(&|l: &str| self.mse(l, cap, planner, e));
                let _ = write!(line, " {} |", fmt(v));
            }
            for m in methods {
                let v = mean(&|l: &str| self.peer_mse(l, cap, m));
                let _ = write!(line, " {} |", fmt(v));
            }
            let _ = writeln!(s, "{line}");
            for l in &layouts {
                if let (Some(g), Some(p)) = (
                    self.mse(l, cap, planner, estimator),
                    self.peer_mse(l, cap, "mysolu"),
                ) && p.is_finite()
                {
                    pairs += 1;
                    if g <= p {
                        wins += 1;
                    }
                }
            }
        }
        if pairs > 0 {
            let _ = writeln!(
                s,
                "\ngleaner (`{}` + `{}`) at or below the peer's `mysolu` at {wins} of {pairs} (layout, capacity) pairs where the peer visits a sensor ({:.0}%).",
                planner.name(),
                estimator.name(),
                100.0 * wins as f64 / pairs.max(1) as f64
            );
        }
        if let Some(m) = self.mean_error(planner, estimator, 8e3, 32e3) {
            let _ = writeln!(
                s,
                "\nMean of `{}` + `{}` over those layouts and the capacities from 8 to 32 kJ: {:.3}.",
                planner.name(),
                estimator.name(),
                m * 1e3
            );
        }
        for (name, pick) in [
            (
                "calibrated",
                (|o: &Outcome| o.coverage90) as fn(&Outcome) -> f64,
            ),
            ("Gaussian", |o: &Outcome| o.coverage90_gaussian),
        ] {
            let mut c: Vec<f64> = self
                .outcomes
                .iter()
                .filter(|o| o.planner == planner)
                .map(pick)
                .filter(|c| c.is_finite())
                .collect();
            if c.is_empty() {
                continue;
            }
            c.sort_by(f64::total_cmp);
            let _ = writeln!(
                s,
                "Coverage of the dynamic model's {name} 90% intervals over unvisited test values: mean {:.1}%, median {:.1}% (min {:.1}%, max {:.1}%) over {} runs.",
                100.0 * c.iter().sum::<f64>() / c.len() as f64,
                100.0 * c[c.len() / 2],
                100.0 * c[0],
                100.0 * c[c.len() - 1],
                c.len()
            );
        }
        for n in &self.notes {
            let _ = writeln!(s, "- {n}");
        }
        s
    }
}

/// Files of the peer protocol under a data directory: (layouts, results, hourly readings).
pub fn peer_files(data: &Path) -> (PathBuf, PathBuf, PathBuf) {
    (
        data.join("peers/taoxu-caf/peer_taoxu_caf_maps.csv"),
        data.join("peers/taoxu-caf/peer_taoxu_caf_results.csv"),
        data.join("caf/derived/water_content_2015_Jan_April_32_sensors.csv"),
    )
}

/// The capacities the peer reports, J (0 to 42 kJ by 2 kJ): also used for the real CAF
/// layout, which the peer has no results for.
pub const PEER_CAPACITIES_J: [f64; 22] = [
    0.0, 2e3, 4e3, 6e3, 8e3, 10e3, 12e3, 14e3, 16e3, 18e3, 20e3, 22e3, 24e3, 26e3, 28e3, 30e3,
    32e3, 34e3, 36e3, 38e3, 40e3, 42e3,
];

/// Which data a protocol run uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dataset {
    /// The peer's own: hourly VW at 30 cm, Jan–Apr 2015, complete-case rows, train rows
    /// 0..=1000, test rows 1001..=1500 (a hold-out: never tuned on).
    Hourly2015,
    /// Tuning data with the same layouts and capacities: CAF daily VW at 30 cm of the same
    /// sensors, train 2012, test the first 250 days of 2013 (every reading, gaps kept).
    TuningDaily,
}

/// Rolling windows at the peer's horizon on CAF daily VW at 30 cm (every reading, gaps kept):
/// test windows of [`WINDOW_TEST_DAYS`] days (the peer's 500 test hours ≈ 20.8 days) one after
/// another from 1 January of a year, each trained on the [`WINDOW_TRAIN_DAYS`] days before it.
/// The year 2013 is tuning data; later years are hold-outs.
pub const WINDOW_TEST_DAYS: i64 = 21;
/// Training span of each rolling window, days.
pub const WINDOW_TRAIN_DAYS: i64 = 365;
/// A window is kept when it has at least this many test rows and 4× as many training rows.
pub const WINDOW_MIN_TEST_ROWS: usize = 10;

/// The rolling-window protocols of `year` (see [`WINDOW_TEST_DAYS`]) over `matrix` (rows =
/// days), each a copy of `base` with its own train and test rows; windows run from 1 January
/// while a whole window fits before 1 January of the next year and before the data's end.
pub fn window_protocols(matrix: &Matrix, base: &Protocol, year: i32) -> Vec<Protocol> {
    let day = 86_400i64;
    let jan1 = |y: i32| gleaner_field::time::days_from_civil(i64::from(y), 1, 1);
    let (Some(start), Some(end)) = (jan1(year), jan1(year + 1)) else {
        return Vec::new();
    };
    let (start, end) = (start * day, end * day);
    let last = matrix.times.last().copied().unwrap_or(i64::MIN);
    let mut out = Vec::new();
    let mut s = start;
    while s + WINDOW_TEST_DAYS * day <= end && s + WINDOW_TEST_DAYS * day <= last + day {
        let train = matrix.rows_between(s - WINDOW_TRAIN_DAYS * day, s);
        let test = matrix.rows_between(s, s + WINDOW_TEST_DAYS * day);
        if test.len() >= WINDOW_MIN_TEST_ROWS && train.len() >= 4 * WINDOW_MIN_TEST_ROWS {
            out.push(Protocol {
                train,
                test,
                ..base.clone()
            });
        }
        s += WINDOW_TEST_DAYS * day;
    }
    out
}

/// Runs [`run_protocol`] once per window and averages: each (layout, capacity, planner)'s
/// error and coverage are the means over the windows where they are finite; its tour, length
/// and energy are the first window's. Returns the mean report and each window's. With several
/// windows the peer's results are dropped from the reports (they ran other data); with one
/// protocol this is [`run_protocol`].
pub fn run_windows(
    matrix: &Matrix,
    layouts: &[Layout],
    peer: &[PeerResult],
    protocols: &[Protocol],
    default_capacities: &[f64],
    planners: &[Planner],
    mut progress: impl FnMut(usize, usize),
) -> Result<(Report, Vec<Report>), EvalError> {
    if let [one] = protocols {
        let r = run_protocol(
            matrix,
            layouts,
            peer,
            one,
            default_capacities,
            planners,
            progress,
        )?;
        return Ok((r.clone(), vec![r]));
    }
    let total = protocols.len() * layouts.len();
    let mut each = Vec::with_capacity(protocols.len());
    for (w, p) in protocols.iter().enumerate() {
        let mut r = run_protocol(
            matrix,
            layouts,
            peer,
            p,
            default_capacities,
            planners,
            |k, _| progress(w * layouts.len() + k, total),
        )?;
        // The peer ran other data: their errors are not comparable with these windows'.
        r.peer.clear();
        each.push(r);
    }
    progress(total, total);
    let Some(first) = each.first() else {
        return Err(EvalError::Data("no window has enough rows".into()));
    };
    let mut mean = first.clone();
    for (k, o) in mean.outcomes.iter_mut().enumerate() {
        for (e, v) in o.mse.iter_mut() {
            let xs: Vec<f64> = each
                .iter()
                .filter_map(|r| r.outcomes.get(k))
                .filter_map(|x| x.mse.iter().find(|(f, _)| f == e).map(|(_, v)| *v))
                .filter(|v| v.is_finite())
                .collect();
            *v = if xs.is_empty() {
                f64::INFINITY
            } else {
                xs.iter().sum::<f64>() / xs.len() as f64
            };
        }
        let mean_of = |pick: fn(&Outcome) -> f64| {
            let cs: Vec<f64> = each
                .iter()
                .filter_map(|r| r.outcomes.get(k))
                .map(pick)
                .filter(|c| c.is_finite())
                .collect();
            if cs.is_empty() {
                f64::NAN
            } else {
                cs.iter().sum::<f64>() / cs.len() as f64
            }
        };
        o.coverage90 = mean_of(|x| x.coverage90);
        o.coverage90_gaussian = mean_of(|x| x.coverage90_gaussian);
        o.multiplier90 = mean_of(|x| x.multiplier90);
    }
    mean.notes = vec![format!(
        "{} windows of {WINDOW_TEST_DAYS} test days, each trained on the {WINDOW_TRAIN_DAYS} days before it",
        protocols.len()
    )];
    Ok((mean, each))
}

/// The registered settings of gleaner's pipeline on this protocol (second registration,
/// `docs/evaluation/peer-registration-v2.md`): the dynamic model with automatic shrinkage,
/// reading noise 0.1% of the variance, lags up to 14 days (chosen on [`Dataset::TuningDaily`]);
/// the tour with the least posterior variance over every sensor, chosen on the rolling windows
/// of both tuning years pooled (2012 and 2013). The first registration's tour, the one visiting
/// the most sensors ([`Planner::Count`]), is still reported beside it.
pub const FROZEN_PLANNER: Planner = Planner::Information;
/// The frozen estimator (see [`FROZEN_PLANNER`]).
pub const FROZEN_ESTIMATOR: Estimator = Estimator::Dynamic;

/// Loads a protocol's data under `data` (the shared data directory): the matrix, the five
/// random layouts and the real CAF layout, the peer's results, the protocol.
pub fn load(
    data: &Path,
    dataset: Dataset,
) -> Result<(Matrix, Vec<Layout>, Vec<PeerResult>, Protocol), EvalError> {
    use gleaner_ingest::{IngestOptions, WideOptions, read_wide_csv};
    let (maps, results, hourly) = peer_files(data);
    let layouts = read_layouts(&maps)?;
    let peer = read_results(&results)?;
    let labels = layouts[0].labels.clone();
    let vw30 =
        gleaner_field::Modality::new("vw@30cm").map_err(|e| EvalError::Data(e.to_string()))?;
    match dataset {
        Dataset::Hourly2015 => {
            let (r, _) =
                read_wide_csv(&hourly, &WideOptions::new(vw30), &IngestOptions::default())?;
            let m = Matrix::from_readings(&[r], "vw@30cm", &labels)?.complete_rows();
            let protocol = Protocol::peer_hourly(frozen_fit(3_600));
            Ok((m, layouts, peer, protocol))
        }
        Dataset::TuningDaily => {
            let m = daily_matrix(data, &labels)?;
            // 2012-01-01 and 2013-01-01, 00:00 UTC.
            let (y2012, y2013) = (1_325_376_000, 1_356_998_400);
            let protocol = Protocol {
                train: m.rows_between(y2012, y2013),
                test: m.rows_between(y2013, y2013 + 250 * 86_400),
                ..Protocol::peer_hourly(frozen_fit(86_400))
            };
            Ok((m, layouts, peer, protocol))
        }
    }
}

/// The frozen fit of the dynamic model on this protocol with a time step of `step_s` seconds:
/// automatic shrinkage, reading noise 0.1% of the variance, lags up to 14 days.
pub(crate) fn frozen_fit(step_s: i64) -> DynamicFitOptions {
    DynamicFitOptions {
        max_lag_s: 14 * 86_400,
        shrinkage: Shrinkage::Auto,
        noise_share: 1e-3,
        step_s,
        ..DynamicFitOptions::default()
    }
}

/// CAF daily VW at 30 cm of `labels` (one file per station under `caf/Daily/`, rows that do
/// not parse skipped, gaps kept as NaN).
fn daily_matrix(data: &Path, labels: &[String]) -> Result<Matrix, EvalError> {
    use gleaner_ingest::{IngestOptions, OnError, read_caf_daily};
    let options = IngestOptions {
        on_error: OnError::Skip,
        ..IngestOptions::default()
    };
    let mut batches = Vec::new();
    for l in labels {
        let (r, _) = read_caf_daily(&data.join(format!("caf/Daily/{l}.txt")), &options)?;
        batches.push(r);
    }
    Matrix::from_readings(&batches, "vw@30cm", labels)
}

/// One window's mean error of each planner (see [`Report::mean_error`]) over the capacities
/// `from_j..=to_j` (J), for the windows' table and the paired comparison.
#[derive(Debug, Clone, PartialEq)]
pub struct WindowMeans {
    /// The window's first test time, seconds since the epoch.
    pub start: i64,
    /// Per planner, the mean error (unit²), `None` when one was infinite.
    pub means: Vec<(Planner, Option<f64>)>,
}

/// Each window's [`WindowMeans`] for `estimator`.
pub fn window_means(
    matrix: &Matrix,
    protocols: &[Protocol],
    each: &[Report],
    planners: &[Planner],
    estimator: Estimator,
    (from_j, to_j): (f64, f64),
) -> Vec<WindowMeans> {
    protocols
        .iter()
        .zip(each)
        .map(|(p, r)| WindowMeans {
            start: matrix.times.get(p.test.start).copied().unwrap_or_default(),
            means: planners
                .iter()
                .map(|&k| (k, r.mean_error(k, estimator, from_j, to_j)))
                .collect(),
        })
        .collect()
}

/// The paired difference `a − b` of two planners' window means: (mean, 95% interval low,
/// high, windows) with Student's t over the windows where both are finite; `None` with fewer
/// than two such windows.
pub fn paired_difference(
    windows: &[WindowMeans],
    a: Planner,
    b: Planner,
) -> Option<(f64, f64, f64, usize)> {
    let get = |w: &WindowMeans, k: Planner| w.means.iter().find(|m| m.0 == k).and_then(|m| m.1);
    let d: Vec<f64> = windows
        .iter()
        .filter_map(|w| Some(get(w, a)? - get(w, b)?))
        .collect();
    mean_interval(&d)
}

/// The mean of `d` and its 95% Student-t interval: (mean, low, high, n); `None` with fewer
/// than two values.
pub fn mean_interval(d: &[f64]) -> Option<(f64, f64, f64, usize)> {
    use statrs::distribution::{ContinuousCDF, StudentsT};
    let n = d.len();
    if n < 2 {
        return None;
    }
    let mean = d.iter().sum::<f64>() / n as f64;
    let var = d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
    let t = StudentsT::new(0.0, 1.0, (n - 1) as f64)
        .ok()?
        .inverse_cdf(0.975);
    let half = t * (var / n as f64).sqrt();
    Some((mean, mean - half, mean + half, n))
}

/// A rolling-window data set: the matrix, the layouts, the peer's results, one protocol per
/// window.
pub type WindowsData = (Matrix, Vec<Layout>, Vec<PeerResult>, Vec<Protocol>);

/// Loads the rolling-window protocol of `year` ([`window_protocols`]) on CAF daily VW at 30 cm:
/// the matrix, the layouts, the peer's results (their capacities are the ones run) and one
/// protocol per window, with the same fit and energy accounting as the peer protocol.
pub fn load_windows(data: &Path, year: i32) -> Result<WindowsData, EvalError> {
    let (maps, results, _) = peer_files(data);
    let layouts = read_layouts(&maps)?;
    let peer = read_results(&results)?;
    let labels = layouts[0].labels.clone();
    let m = daily_matrix(data, &labels)?;
    let base = Protocol::peer_hourly(frozen_fit(86_400));
    let windows = window_protocols(&m, &base, year);
    if windows.is_empty() {
        return Err(EvalError::Data(format!(
            "no {WINDOW_TEST_DAYS}-day window of {year} has enough readings"
        )));
    }
    Ok((m, layouts, peer, windows))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn toy_matrix() -> Matrix {
        // Three sensors: 0 and 1 move together (1 with a small part of its own), 2 on its own.
        let n = 3;
        let mut values = Vec::new();
        let mut times = Vec::new();
        for t in 0..400 {
            let a = (t as f64 / 20.0).sin() * 0.02;
            let b = (t as f64 / 7.0).cos() * 0.01;
            let own = (t as f64 / 3.0).sin() * 0.003;
            values.extend_from_slice(&[0.3 + a, 0.25 + 0.9 * a + own, 0.2 + b]);
            times.push(t as i64 * 3600);
        }
        assert_eq!(values.len(), 400 * n);
        Matrix {
            labels: vec!["A".into(), "B".into(), "C".into()],
            times,
            values,
        }
    }

    fn protocol() -> Protocol {
        Protocol {
            train: 0..200,
            test: 200..400,
            fit: DynamicFitOptions {
                step_s: 3600,
                max_lag_s: 48 * 3600,
                shrinkage: Shrinkage::Fixed(0.0),
                ..DynamicFitOptions::default()
            },
            ..Protocol::peer_hourly(DynamicFitOptions::default())
        }
    }

    /// The calibrated interval's multiplier comes from the back-test on the last half of the
    /// training rows (100 rows, 2 unvisited sensors: 200 errors), scoring reports it, and the
    /// calibrated coverage is the share of test values within `q·sd`.
    #[test]
    fn calibrated_intervals_take_the_backtests_multiplier() {
        let fitted = Fitted::new(toy_matrix(), protocol()).unwrap();
        assert_eq!(fitted.backtest_rows, 100);
        let origins: Vec<usize> = fitted.backtests.iter().map(|b| b.0).collect();
        assert_eq!(origins, vec![100]);
        let q = fitted.interval_multiplier(&[0]);
        assert!(q.is_finite() && q >= gleaner_kriging::Z90);
        let (_, c) = fitted.score(&[0]);
        assert_eq!(c.multiplier, q);
        assert!((0.0..=1.0).contains(&c.calibrated) && (0.0..=1.0).contains(&c.gaussian));
        assert!(c.calibrated >= c.gaussian);
        // Everything visited: no error to back-test, the Gaussian multiplier.
        assert_eq!(fitted.interval_multiplier(&[0, 1, 2]), gleaner_kriging::Z90);
    }

    /// The unshared drift over the test: each sensor's fitted rate times the mean time from
    /// the last training row to the test rows.
    #[test]
    fn unshared_drift_is_rate_times_the_mean_horizon() {
        let fitted = Fitted::new(toy_matrix(), protocol()).unwrap();
        let (times, values) = series(&fitted.matrix, fitted.protocol.train.clone());
        let input: Vec<SensorSeries<'_>> = times
            .iter()
            .zip(&values)
            .map(|(t, v)| SensorSeries {
                position: [0.0, 0.0],
                times: t,
                values: v,
            })
            .collect();
        let rates = gleaner_kriging::fit_own_rates(&input, 3600, 30.0).unwrap();
        // Test rows 200..400 at one hour: the mean horizon is 100.5 hours.
        let horizon = 100.5 * 3600.0;
        for (d, r) in fitted.own_drift.iter().zip(&rates) {
            assert!(
                (d - r * horizon).abs() <= 1e-12 * d.abs().max(1e-300),
                "{d} vs {r}"
            );
        }
        assert!(fitted.own_drift.iter().any(|&d| d > 0.0));
    }

    fn daily_matrix_between(from: i64, to: i64) -> Matrix {
        let times: Vec<i64> = (from..to).step_by(86_400).collect();
        Matrix {
            labels: vec!["A".into()],
            values: vec![0.3; times.len()],
            times,
        }
    }

    #[test]
    fn rolling_windows_tile_the_year_and_stop_at_the_data_end() {
        // 2012-01-01 .. 2014-01-10 daily: 2013 holds 17 whole 21-day windows.
        let (y2012, y2013) = (1_325_376_000, 1_356_998_400);
        let m = daily_matrix_between(y2012, y2013 + 375 * 86_400);
        let base = protocol();
        let w = window_protocols(&m, &base, 2013);
        assert_eq!(w.len(), 17);
        for (k, p) in w.iter().enumerate() {
            assert_eq!(p.test.len(), 21, "window {k}");
            assert_eq!(p.train.len(), 365, "window {k}");
            assert_eq!(p.train.end, p.test.start);
            assert_eq!(m.times[p.test.start], y2013 + 21 * 86_400 * k as i64);
            assert_eq!(p.fit, base.fit);
        }
        // Data ending 2013-03-01: windows from 1 Jan and 22 Jan; the third would end 5 Mar.
        let short = daily_matrix_between(y2012, y2013 + 60 * 86_400);
        assert_eq!(window_protocols(&short, &base, 2013).len(), 2);
        // In the data's first year a window needs 40 training rows: the first two are dropped.
        let first = window_protocols(&m, &base, 2012);
        assert_eq!(first.len(), 15);
        assert_eq!(m.times[first[0].test.start], y2012 + 42 * 86_400);
        assert_eq!(first[0].train, 0..42);
    }

    #[test]
    fn paired_difference_is_students_t_over_the_windows() {
        let w = |start, a: f64, b: Option<f64>| WindowMeans {
            start,
            means: vec![(Planner::Count, Some(a)), (Planner::Information, b)],
        };
        // Differences 1, 2, 3 (the window without an information mean is left out): mean 2,
        // sd 1, t(0.975; 2 df) = 4.302653.
        let windows = [
            w(0, 2.0, Some(1.0)),
            w(1, 2.0, Some(0.0)),
            w(2, 5.0, None),
            w(3, 4.0, Some(1.0)),
        ];
        let (d, lo, hi, n) =
            paired_difference(&windows, Planner::Count, Planner::Information).unwrap();
        assert_eq!(n, 3);
        assert!((d - 2.0).abs() < 1e-12);
        let half = 4.302_652_729_911_275 / 3f64.sqrt();
        assert!((hi - 2.0 - half).abs() < 1e-6 && (2.0 - lo - half).abs() < 1e-6);
        assert!(paired_difference(&windows[..1], Planner::Count, Planner::Information).is_none());
    }

    #[test]
    fn a_correlated_visit_explains_its_partner() {
        let fitted = Fitted::new(toy_matrix(), protocol()).unwrap();
        let (with_a, _) = fitted.score(&[0]);
        let (with_c, _) = fitted.score(&[2]);
        let get = |v: &[(Estimator, f64)], e| v.iter().find(|x| x.0 == e).unwrap().1;
        // Visiting A tells B (levels and dynamic beat carried forward); visiting C does not.
        assert!(get(&with_a, Estimator::Levels) < 0.5 * get(&with_a, Estimator::Carried));
        assert!(get(&with_a, Estimator::Dynamic) < 0.5 * get(&with_a, Estimator::Carried));
        assert!(get(&with_c, Estimator::Dynamic) > get(&with_a, Estimator::Dynamic));
        let (none, _) = fitted.score(&[]);
        assert!(none.iter().all(|(_, v)| v.is_infinite()));
    }

    #[test]
    fn tours_respect_the_protocols_energy() {
        let fitted = Fitted::new(toy_matrix(), protocol()).unwrap();
        let layout = Layout {
            name: "t".into(),
            labels: vec!["A".into(), "B".into(), "C".into()],
            positions: vec![[100.0, 0.0], [100.0, 10.0], [0.0, 300.0]],
        };
        for planner in [Planner::Information, Planner::Count] {
            for cap in [0.0, 1_000.0, 2_100.0, 8_000.0] {
                let o = fitted.run(&layout, cap, planner).unwrap();
                assert!(
                    o.energy_j <= cap + 1e-6,
                    "{planner:?} {cap}: {}",
                    o.energy_j
                );
            }
        }
        // 7,250 J fits C with A (7,230 J) or B (7,143 J), not all three (7,308 J): information
        // takes C and one of the correlated pair.
        let o = fitted.run(&layout, 7_250.0, Planner::Information).unwrap();
        assert!(o.tour.contains(&2), "{:?}", o.tour);
    }

    #[test]
    fn layouts_and_results_files_are_read_and_bad_ones_named() {
        let dir = std::env::temp_dir().join(format!("gleaner-eval-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let maps = dir.join("maps.csv");
        std::fs::write(
            &maps,
            "layout,node,label,x_m,y_m\nm,0,A,1,2\nm,1,B,3,4\nm,Depot,Depot,0,0\n",
        )
        .unwrap();
        let l = read_layouts(&maps).unwrap();
        assert_eq!(l[0].labels, ["A", "B"]);
        std::fs::write(&maps, "layout,node,label,x_m,y_m\nm,0,A,x,2\n").unwrap();
        let e = read_layouts(&maps).unwrap_err().to_string();
        assert!(e.contains(":2: field `x_m`"), "{e}");
        let res = dir.join("res.csv");
        std::fs::write(
            &res,
            "experiment,data,method,map,capacity_J,n_selected,tour_len_m,energy_J,mse_sum_over_unvisited,tour\ne,d,mysolu,m,0,0,0.0,0.0,inf,\n",
        )
        .unwrap();
        let r = read_results(&res).unwrap();
        assert!(r[0].mse.is_infinite());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
