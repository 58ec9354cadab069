//! gleaner's farming layer over the generic orienteering solver.
//!
//! [`plan_mission`] takes scored cells ([`Candidate`]: centre in the local frame, score S,
//! hover time) and a [`MissionEnergyModel`], builds an orienteering instance — node 0 is the
//! base station (start and end), every cell with S > 0 is a node whose reward is S and whose
//! service cost is its hover + receiver energy, travel costs are propulsion energies in J
//! (directed in a wind, [`MissionEnergyModel::with_wind`]: the way out and the way back differ), the
//! budget is the usable battery energy less the fixed take-off/landing energy — solves it, and
//! re-checks the chosen route with the energy model's own breakdown ([`MissionPlan::energy`]).
//!
//! Cells with S <= 0 are never worth a detour (docs/method.md §2) and are left out of the instance.
//!
//! [`exploration::plan_exploration`] plans the exploration phase (docs/method.md §5 step 3): the fewest
//! budget-feasible sorties that together visit every cell.
//!
//! [`PlanOptions::with_time_limit_secs`] turns a user's time limit in seconds into the
//! options without panicking on NaN, negative, huge or infinite values.
//!
//! ```
//! use gleaner_energy::{EnergyConfig, MissionEnergyModel};
//! use gleaner_field::LocalPoint;
//! use gleaner_mission::{Candidate, PlanOptions, plan_mission};
//! let model = MissionEnergyModel::new(&EnergyConfig::paper()).unwrap();
//! let cells: Vec<Candidate> = (0..20)
//!     .map(|k| Candidate {
//!         centre: LocalPoint::new(40.0 * k as f64 + 20.0, 20.0),
//!         score: 1.0 + (k % 3) as f64,
//!         hover_s: 30.0,
//!     })
//!     .collect();
//! let plan = plan_mission(&model, LocalPoint::new(0.0, 0.0), &cells, &PlanOptions::default()).unwrap();
//! assert!(plan.energy.feasible);
//! assert!(plan.energy.total_j <= plan.energy.budget_j);
//! ```
#![deny(missing_docs)]

pub mod detours;
pub mod exploration;

pub use detours::Detours;

use std::time::{Duration, Instant};

use gleaner_energy::{CellVisit, EnergyError, MissionEnergy, MissionEnergyModel};
use gleaner_field::LocalPoint;
use gleaner_orienteering::{
    MarginalOptions, Metric, Problem, ProblemError, SolveError, SolveOptions, SolverKind, solve,
    solve_marginal, time_limit_from_secs,
};
use thiserror::Error;

/// A cell that may be visited.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Candidate {
    /// Cell centre in the local frame (base station at the origin), metres.
    pub centre: LocalPoint,
    /// Utility score S (dimensionless); cells with S <= 0 are never planned.
    pub score: f64,
    /// Hover time needed to collect the cell, seconds.
    pub hover_s: f64,
}

/// Which route planner to use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Planner {
    /// The paper's heuristic: repeated best reward / extra-energy insertion.
    Greedy,
    /// gleaner's default: iterated local search seeded with greedy (exact when tiny).
    #[default]
    Default,
    /// Proven optimum by dynamic programming (small instances only).
    Exact,
}

impl Planner {
    /// The planner's name as written in outputs: `greedy`, `default`, `exact`.
    pub fn name(self) -> &'static str {
        match self {
            Planner::Greedy => "greedy",
            Planner::Default => "default",
            Planner::Exact => "exact",
        }
    }
}

/// Planner settings.
#[derive(Debug, Clone, PartialEq)]
pub struct PlanOptions {
    /// Planner.
    pub planner: Planner,
    /// Wall-clock limit, seconds; the best route so far is returned.
    pub time_limit: Duration,
    /// Seed of every random choice.
    pub seed: u64,
    /// Iteration cap for deterministic runs (`None`: until the time or stall limit).
    pub max_iterations: Option<u64>,
}

impl Default for PlanOptions {
    /// Default planner, 5 s, seed 0, no iteration cap.
    fn default() -> Self {
        Self {
            planner: Planner::Default,
            time_limit: Duration::from_secs(5),
            seed: 0,
            max_iterations: None,
        }
    }
}

impl PlanOptions {
    /// Sets the wall-clock limit from a number of seconds as a user writes it, without
    /// panicking on hostile values: values too large for a [`Duration`], `+inf` included,
    /// mean "no limit" (the search then ends on its iteration or stall limit).
    ///
    /// # Errors
    /// [`PlanError::Solve`] with [`SolveError::InvalidTimeLimit`] for NaN or a negative value.
    ///
    /// ```
    /// use gleaner_mission::PlanOptions;
    /// let o = PlanOptions::default().with_time_limit_secs(1.5).unwrap();
    /// assert_eq!(o.time_limit.as_millis(), 1500);
    /// assert!(PlanOptions::default().with_time_limit_secs(f64::INFINITY).is_ok());
    /// assert!(PlanOptions::default().with_time_limit_secs(-2.0).is_err());
    /// ```
    pub fn with_time_limit_secs(mut self, seconds: f64) -> Result<Self, PlanError> {
        self.time_limit = time_limit_from_secs(seconds)?;
        Ok(self)
    }
}

/// A planned mission.
#[derive(Debug, Clone, PartialEq)]
pub struct MissionPlan {
    /// Visiting order, as indices into the candidate slice.
    pub order: Vec<usize>,
    /// Sum of S over the visited cells.
    pub total_score: f64,
    /// The energy model's breakdown of the route (E_t, E_h, E_c, E_r, per leg, per cell).
    pub energy: MissionEnergy,
    /// Candidates with S > 0 that the planner could choose from.
    pub considered: usize,
    /// The planner used.
    pub planner: Planner,
    /// Wall-clock time spent solving, seconds (informational; never affects the result when an
    /// iteration cap is set).
    pub solve_seconds: f64,
    /// The turn points of each leg around no-fly zones (local frame, m), one entry per stop
    /// and one for the return leg: empty entries for straight legs, no entries for straight
    /// routes or an empty order. What [`MissionPlan::energy`] was priced along.
    pub via: Vec<Vec<LocalPoint>>,
}

/// Why a mission could not be planned.
#[derive(Debug, Error)]
pub enum PlanError {
    /// The energy model rejected an input.
    #[error("energy model: {0}")]
    Energy(#[from] EnergyError),
    /// The orienteering instance is invalid.
    #[error("orienteering instance: {0}")]
    Problem(#[from] ProblemError),
    /// The solver failed (e.g. `exact` on too large an instance).
    #[error("route planner: {0}")]
    Solve(#[from] SolveError),
    /// A candidate with a non-finite score or hover time.
    #[error("cell {index}: invalid {what} {value}")]
    InvalidCandidate {
        /// Position in the candidate slice.
        index: usize,
        /// Which field.
        what: &'static str,
        /// Its value.
        value: f64,
    },
    /// Detours over another number of nodes than the base and the candidates.
    #[error("detours over {nodes} nodes for {candidates} candidates and the base")]
    Detours {
        /// Nodes of the detours.
        nodes: usize,
        /// Candidates given.
        candidates: usize,
    },
    /// The solver returned a route the energy model finds infeasible (a bug; reported, never
    /// handed to an operator).
    #[error("planned route needs {total_j:.1} J but only {budget_j:.1} J are usable")]
    Infeasible {
        /// Energy of the route, J.
        total_j: f64,
        /// Usable budget, J.
        budget_j: f64,
    },
}

/// Plans one sortie from `base` (local frame, metres) over `candidates`; see the crate docs.
pub fn plan_mission(
    model: &MissionEnergyModel,
    base: LocalPoint,
    candidates: &[Candidate],
    options: &PlanOptions,
) -> Result<MissionPlan, PlanError> {
    let mut plans = plan_sorties(model, base, candidates, options, 1)?;
    Ok(plans.remove(0))
}

/// Plans `sorties` (>= 1; 0 is taken as 1) disjoint sorties from `base` over `candidates` — one
/// per battery, each within the usable budget — maximising their total score with the team
/// orienteering solver (one vehicle per sortie). Returns one plan per sortie, in the solver's
/// route order; a sortie with nothing worth visiting has an empty order and 0 J. With
/// `sorties == 1` this is [`plan_mission`].
pub fn plan_sorties(
    model: &MissionEnergyModel,
    base: LocalPoint,
    candidates: &[Candidate],
    options: &PlanOptions,
    sorties: usize,
) -> Result<Vec<MissionPlan>, PlanError> {
    plan_sorties_routed(model, base, candidates, options, sorties, None)
}

/// [`plan_sorties`] with legs flown around no-fly zones: `detours` (over the base and
/// `candidates`, in order) gives every leg's polyline; the travel costs are the energy per
/// metre times their lengths (a dense matrix, not assumed metric; in a wind each polyline's
/// energy in the direction flown, a directed matrix), unreachable candidates
/// are left out, and every sortie is re-checked along its polylines
/// ([`MissionEnergyModel::breakdown_paths`]). `None` is [`plan_sorties`].
///
/// # Errors
/// As [`plan_sorties`]; [`PlanError::Detours`] when `detours` is not over base + candidates.
pub fn plan_sorties_routed(
    model: &MissionEnergyModel,
    base: LocalPoint,
    candidates: &[Candidate],
    options: &PlanOptions,
    sorties: usize,
    detours: Option<&Detours>,
) -> Result<Vec<MissionPlan>, PlanError> {
    let sorties = sorties.max(1);
    check_candidates(candidates)?;
    check_detours(candidates, detours)?;
    let chosen: Vec<usize> = (0..candidates.len())
        .filter(|&k| candidates[k].score > 0.0 && detours.is_none_or(|d| d.reachable(k + 1)))
        .collect();
    let started = Instant::now();
    let mut orders: Vec<Vec<usize>> = vec![Vec::new(); sorties];
    if let Some(problem) = instance(model, base, candidates, &chosen, sorties, detours)? {
        let (solve_options, kind) = solver_setup(options);
        let solution = solve(&problem, kind, &solve_options)?;
        for (order, route) in orders.iter_mut().zip(&solution.routes) {
            *order = route
                .iter()
                .filter(|&&node| node != 0)
                .map(|&node| chosen[node - 1])
                .collect();
        }
    }
    finish(
        model,
        base,
        candidates,
        orders,
        chosen.len(),
        options.planner,
        started,
        detours,
    )
}

/// Plans `sorties` disjoint sorties from `base` maximising a *set function* of the visited
/// cells instead of a sum of scores: `value` gets the candidate indices visited so far (in
/// no particular order) and returns their joint worth (e.g. the information they bring
/// together, which is less than the sum of what each brings alone when they are
/// correlated). Candidates with `score > 0` are the eligible cells (their scores are reported
/// as [`MissionPlan::total_score`], they do not steer the search). Sorties are planned one
/// after the other, each maximising the gain over the cells already planned, by
/// [`gleaner_orienteering::solve_marginal`] (marginal-gain insertion and exchange search);
/// deterministic. Every route is re-checked by the energy model.
pub fn plan_sorties_valued<F: FnMut(&[usize]) -> f64>(
    model: &MissionEnergyModel,
    base: LocalPoint,
    candidates: &[Candidate],
    value: F,
    options: &PlanOptions,
    sorties: usize,
) -> Result<Vec<MissionPlan>, PlanError> {
    plan_sorties_valued_routed(model, base, candidates, value, options, sorties, None)
}

/// [`plan_sorties_valued`] with legs flown around no-fly zones (see
/// [`plan_sorties_routed`]). `None` is [`plan_sorties_valued`].
///
/// # Errors
/// As [`plan_sorties_routed`].
pub fn plan_sorties_valued_routed<F: FnMut(&[usize]) -> f64>(
    model: &MissionEnergyModel,
    base: LocalPoint,
    candidates: &[Candidate],
    mut value: F,
    options: &PlanOptions,
    sorties: usize,
    detours: Option<&Detours>,
) -> Result<Vec<MissionPlan>, PlanError> {
    let sorties = sorties.max(1);
    check_candidates(candidates)?;
    check_detours(candidates, detours)?;
    let started = Instant::now();
    let mut orders: Vec<Vec<usize>> = Vec::with_capacity(sorties);
    let mut taken: Vec<usize> = Vec::new();
    let mut considered = 0;
    for _ in 0..sorties {
        let chosen: Vec<usize> = (0..candidates.len())
            .filter(|&k| {
                candidates[k].score > 0.0
                    && !taken.contains(&k)
                    && detours.is_none_or(|d| d.reachable(k + 1))
            })
            .collect();
        considered = considered.max(chosen.len());
        let mut order = Vec::new();
        if let Some(problem) = instance(model, base, candidates, &chosen, 1, detours)? {
            let mut set = taken.clone();
            let base_len = set.len();
            let found = solve_marginal(
                &problem,
                |nodes: &[usize]| {
                    set.truncate(base_len);
                    set.extend(nodes.iter().map(|&node| chosen[node - 1]));
                    let v = value(&set);
                    if v.is_finite() { v } else { 0.0 }
                },
                &MarginalOptions::default(),
            );
            if let Some(route) = found.solution.routes.first() {
                order = route
                    .iter()
                    .filter(|&&node| node != 0)
                    .map(|&node| chosen[node - 1])
                    .collect();
            }
        }
        taken.extend(&order);
        orders.push(order);
    }
    finish(
        model,
        base,
        candidates,
        orders,
        considered,
        options.planner,
        started,
        detours,
    )
}

/// Default wall-clock limit of [`replan`] in the air, seconds (an answer is needed now).
pub const REPLAN_TIME_LIMIT_S: f64 = 1.0;

/// Default iteration cap of [`replan`]'s search: deterministic answers, well within 100 ms
/// on a 42-cell field (BENCHMARKS.md).
pub const REPLAN_ITERATIONS: u64 = 200;

/// Re-plans the rest of a sortie in the air. The aircraft is at `start` (local frame, m, at
/// the flight altitude) with `budget_j` joules it may still spend (the energy left less the
/// reserve); `remaining` are the stops not flown yet (a stop with `score <= 0` is never
/// kept). Returns the best continuation — a subset of `remaining` in a new order, then home
/// to `base` — by the orienteering solver with `start` and `base` as the route's two ends.
/// Its energy ([`MissionPlan::energy`]) is [`MissionEnergyModel::continuation`] over a 0 s
/// first stop at `start` followed by the kept stops (what a continuation file commands:
/// `legs[0]` and `cells[0]` are that 0 m, 0 s first stop; stop `i` of `order` is `legs[i + 1]`
/// and `cells[i + 1]`).
///
/// # Errors
/// [`PlanError::Infeasible`] when even the leg home exceeds the budget (land now); invalid
/// candidates, positions or options as [`plan_mission`].
pub fn replan(
    model: &MissionEnergyModel,
    (start, base): (LocalPoint, LocalPoint),
    remaining: &[Candidate],
    budget_j: f64,
    options: &PlanOptions,
) -> Result<MissionPlan, PlanError> {
    check_candidates(remaining)?;
    let started = Instant::now();
    let here = CellVisit {
        centre: start,
        hover_s: 0.0,
    };
    let home = model.continuation(start, base, &[here], budget_j)?;
    if !home.feasible {
        return Err(PlanError::Infeasible {
            total_j: home.total_j,
            budget_j,
        });
    }
    let chosen: Vec<usize> = (0..remaining.len())
        .filter(|&k| remaining[k].score > 0.0)
        .collect();
    let mut order = Vec::new();
    if !chosen.is_empty() {
        let mut points = vec![[start.e, start.n], [base.e, base.n]];
        points.extend(chosen.iter().map(|&k| {
            let c = remaining[k].centre;
            [c.e, c.n]
        }));
        let (rewards, service) = node_values(model, remaining, &chosen, 2);
        let problem = point_problem(
            model,
            &points,
            rewards,
            (budget_j - model.descent().0).max(0.0),
        )?
        .with_service_costs(service)?
        .with_endpoints(0, 1)?;
        let (solve_options, kind) = solver_setup(options);
        let solution = solve(&problem, kind, &solve_options)?;
        order = solution
            .routes
            .first()
            .map(|route| {
                route
                    .iter()
                    .filter(|&&node| node >= 2)
                    .map(|&node| chosen[node - 2])
                    .collect()
            })
            .unwrap_or_default();
    }
    let visits: Vec<CellVisit> = std::iter::once(here)
        .chain(order.iter().map(|&k| CellVisit {
            centre: remaining[k].centre,
            hover_s: remaining[k].hover_s,
        }))
        .collect();
    let energy = model.continuation(start, base, &visits, budget_j)?;
    if !energy.feasible {
        return Err(PlanError::Infeasible {
            total_j: energy.total_j,
            budget_j,
        });
    }
    Ok(MissionPlan {
        total_score: order.iter().map(|&k| remaining[k].score).sum(),
        order,
        energy,
        considered: chosen.len(),
        planner: options.planner,
        solve_seconds: started.elapsed().as_secs_f64(),
        via: Vec::new(),
    })
}

/// The orienteering instance over the `chosen` candidates (node k + 1 is `chosen[k]`, node 0
/// the base, start and end), or None when nothing can be visited.
fn instance(
    model: &MissionEnergyModel,
    base: LocalPoint,
    candidates: &[Candidate],
    chosen: &[usize],
    sorties: usize,
    detours: Option<&Detours>,
) -> Result<Option<Problem>, PlanError> {
    let budget = model.usable_budget_j() - model.sortie_fixed_j();
    if chosen.is_empty() || budget <= 0.0 {
        return Ok(None);
    }
    if let Some(d) = detours {
        // Travel costs along the legs' polylines: energy per metre times their lengths, the
        // products the energy model's breakdown forms leg by leg.
        let nodes: Vec<usize> = std::iter::once(0)
            .chain(chosen.iter().map(|&k| k + 1))
            .collect();
        let epm = model.energy_per_metre_j();
        let mut cost = Vec::with_capacity(nodes.len() * nodes.len());
        if model.wind_applies() {
            // In wind each leg is priced along its polyline in the direction flown, as the
            // breakdown prices it: a directed matrix.
            let at = |node: usize| {
                if node == 0 {
                    base
                } else {
                    candidates[node - 1].centre
                }
            };
            let mut polyline = Vec::new();
            for &a in &nodes {
                for &b in &nodes {
                    polyline.clear();
                    polyline.push(at(a));
                    if a != b {
                        polyline.extend_from_slice(d.via(a, b));
                    }
                    polyline.push(at(b));
                    cost.push(if a == b {
                        0.0
                    } else {
                        model.polyline_energy_j(&polyline)
                    });
                }
            }
        } else {
            for &a in &nodes {
                cost.extend(nodes.iter().map(|&b| epm * d.length_m(a, b)));
            }
        }
        let (rewards, service) = node_values(model, candidates, chosen, 1);
        let problem = if model.wind_applies() {
            Problem::new_directed(cost, rewards, budget)?
        } else {
            Problem::new(cost, rewards, budget)?
        }
        .with_service_costs(service)?
        .with_endpoints(0, 0)?
        .with_vehicles(sorties)?;
        return Ok(Some(problem));
    }
    // Travel costs: energy per metre times the straight-line distance (m), evaluated on
    // demand by the solver (exactly the entries of `travel_cost_matrix`, without its
    // n² memory: 800 MB for 10,000 cells).
    let mut points = Vec::with_capacity(chosen.len() + 1);
    points.push([base.e, base.n]);
    points.extend(chosen.iter().map(|&k| {
        let c = candidates[k].centre;
        [c.e, c.n]
    }));
    let (rewards, service) = node_values(model, candidates, chosen, 1);
    let problem = point_problem(model, &points, rewards, budget)?
        .with_service_costs(service)?
        .with_endpoints(0, 0)?
        .with_vehicles(sorties)?;
    Ok(Some(problem))
}

/// The solver's instance over `points` (local frame, m) with the model's travel energies
/// (J): in still air energy per metre times the straight-line distance, evaluated on demand
/// (exactly the entries of `travel_cost_matrix`, without its n² memory: 800 MB for 10,000
/// cells); in wind ([`MissionEnergyModel::wind_applies`]) the directed energy of each
/// displacement, [`MissionEnergyModel::travel_energy_j`] — the breakdown's leg energies to
/// the bit.
fn point_problem(
    model: &MissionEnergyModel,
    points: &[[f64; 2]],
    rewards: Vec<f64>,
    budget: f64,
) -> Result<Problem, ProblemError> {
    if model.wind_applies() {
        let m = model.clone();
        let origin = LocalPoint::new(0.0, 0.0);
        let cost = move |de: f64, dn: f64| m.travel_energy_j(origin, LocalPoint::new(de, dn));
        return Problem::from_displacement_costs(
            points,
            std::sync::Arc::new(cost),
            rewards,
            budget,
        );
    }
    Problem::from_scaled_points(
        points,
        Metric::Euclidean,
        model.energy_per_metre_j(),
        rewards,
        budget,
    )
}

/// Detours over the base and every candidate, if any.
fn check_detours(candidates: &[Candidate], detours: Option<&Detours>) -> Result<(), PlanError> {
    match detours {
        Some(d) if d.len() != candidates.len() + 1 => Err(PlanError::Detours {
            nodes: d.len(),
            candidates: candidates.len(),
        }),
        _ => Ok(()),
    }
}

/// The rewards (S) and service energies (J) of `ends` leading end nodes (0 and 0 J: the base,
/// or the aircraft and the base) followed by the `chosen` candidates.
fn node_values(
    model: &MissionEnergyModel,
    candidates: &[Candidate],
    chosen: &[usize],
    ends: usize,
) -> (Vec<f64>, Vec<f64>) {
    let mut rewards = vec![0.0; ends];
    rewards.extend(chosen.iter().map(|&k| candidates[k].score));
    let mut service = vec![0.0; ends];
    service.extend(
        chosen
            .iter()
            .map(|&k| model.service_energy_j(candidates[k].hover_s)),
    );
    (rewards, service)
}

/// The solver's options and kind for `options`.
fn solver_setup(options: &PlanOptions) -> (SolveOptions, SolverKind) {
    let mut solve_options = SolveOptions::default()
        .with_time_limit(options.time_limit)
        .with_seed(options.seed);
    solve_options.max_iterations = options.max_iterations;
    let kind = match options.planner {
        Planner::Greedy => SolverKind::Greedy,
        Planner::Default => SolverKind::Default,
        Planner::Exact => SolverKind::Exact,
    };
    (solve_options, kind)
}

/// Finite scores and finite non-negative hover times, or the first offender.
fn check_candidates(candidates: &[Candidate]) -> Result<(), PlanError> {
    for (index, c) in candidates.iter().enumerate() {
        if !c.score.is_finite() {
            return Err(PlanError::InvalidCandidate {
                index,
                what: "score",
                value: c.score,
            });
        }
        if !(c.hover_s.is_finite() && c.hover_s >= 0.0) {
            return Err(PlanError::InvalidCandidate {
                index,
                what: "hover time (s)",
                value: c.hover_s,
            });
        }
    }
    Ok(())
}

/// The plans of the solver's `orders`, each re-checked by the energy model's breakdown.
#[allow(clippy::too_many_arguments)]
fn finish(
    model: &MissionEnergyModel,
    base: LocalPoint,
    candidates: &[Candidate],
    orders: Vec<Vec<usize>>,
    considered: usize,
    planner: Planner,
    started: Instant,
    detours: Option<&Detours>,
) -> Result<Vec<MissionPlan>, PlanError> {
    let solve_seconds = started.elapsed().as_secs_f64();
    let mut plans = Vec::with_capacity(orders.len());
    for order in orders {
        let visits: Vec<CellVisit> = order
            .iter()
            .map(|&k| CellVisit {
                centre: candidates[k].centre,
                hover_s: candidates[k].hover_s,
            })
            .collect();
        let via = detours.map(|d| d.route_via(&order)).unwrap_or_default();
        let energy = model.breakdown_paths(base, &visits, &via)?;
        if !energy.feasible {
            return Err(PlanError::Infeasible {
                total_j: energy.total_j,
                budget_j: energy.budget_j,
            });
        }
        plans.push(MissionPlan {
            total_score: order.iter().map(|&k| candidates[k].score).sum(),
            order,
            energy,
            considered,
            planner,
            solve_seconds,
            via,
        });
    }
    Ok(plans)
}

#[cfg(test)]
mod tests {
    use super::*;
    use gleaner_energy::EnergyConfig;
    use proptest::prelude::*;

    fn model() -> MissionEnergyModel {
        MissionEnergyModel::new(&EnergyConfig::paper()).expect("paper preset is valid")
    }

    /// A candidate at (`e`, `n`) m with a 30 s hover.
    fn cell(e: f64, n: f64, score: f64) -> Candidate {
        Candidate {
            centre: LocalPoint::new(e, n),
            score,
            hover_s: 30.0,
        }
    }

    #[test]
    fn a_set_value_skips_redundant_cells_and_sorties_do_not_repeat_cells() {
        // Cells 0 and 1 are twins (together worth what one is), cell 2 is far off; a budget
        // that fits about two of the three: the valued planner takes one twin and cell 2.
        let cells = [
            cell(100.0, 0.0, 1.0),
            cell(110.0, 0.0, 1.0),
            cell(-400.0, 0.0, 1.0),
        ];
        let value = |set: &[usize]| {
            let twins = set.iter().any(|&k| k < 2) as u8 as f64;
            twins + set.contains(&2) as u8 as f64
        };
        let plans = plan_sorties_valued(
            &model(),
            LocalPoint::default(),
            &cells,
            value,
            &opts(Planner::Default),
            2,
        )
        .unwrap();
        assert_eq!(plans.len(), 2);
        let mut first = plans[0].order.clone();
        first.sort_unstable();
        assert!(first.contains(&2), "{first:?}");
        assert_eq!(first.iter().filter(|&&k| k < 2).count(), 1, "{first:?}");
        for p in &plans {
            assert!(p.energy.feasible);
            assert!(p.order.iter().all(|k| !first.contains(k)) || std::ptr::eq(p, &plans[0]));
        }
        // Nothing eligible: empty sorties, 0 J of cells.
        let none = [cell(100.0, 0.0, 0.0)];
        let plans = plan_sorties_valued(
            &model(),
            LocalPoint::default(),
            &none,
            value,
            &opts(Planner::Default),
            1,
        )
        .unwrap();
        assert!(plans[0].order.is_empty());
    }

    /// [`plan_mission`] from the origin with the paper model and [`opts`].
    fn plan(cells: &[Candidate], planner: Planner) -> Result<MissionPlan, PlanError> {
        plan_mission(&model(), LocalPoint::default(), cells, &opts(planner))
    }

    fn opts(planner: Planner) -> PlanOptions {
        PlanOptions {
            planner,
            max_iterations: Some(300),
            time_limit: Duration::from_secs(30),
            seed: 1,
        }
    }

    /// 40 cells on a 40 m grid, scores varying, for the several-sorties tests.
    fn grid40() -> Vec<Candidate> {
        (0..40)
            .map(|k| {
                cell(
                    40.0 * f64::from(k % 8) + 20.0,
                    40.0 * f64::from(k / 8) + 20.0,
                    1.0 + f64::from((k * 7) % 5),
                )
            })
            .collect()
    }

    #[test]
    fn one_sortie_is_the_single_sortie_plan() {
        let cells = grid40();
        let one = plan_sorties(
            &model(),
            LocalPoint::default(),
            &cells,
            &opts(Planner::Default),
            1,
        )
        .unwrap();
        let single = plan(&cells, Planner::Default).unwrap();
        assert_eq!(one.len(), 1);
        assert_eq!(one[0].order, single.order);
        assert_eq!(one[0].energy, single.energy);
    }

    #[test]
    fn two_sorties_are_disjoint_within_budget_and_collect_more() {
        let cells = grid40();
        let m = model();
        let two = plan_sorties(
            &m,
            LocalPoint::default(),
            &cells,
            &opts(Planner::Default),
            2,
        )
        .unwrap();
        let single = plan(&cells, Planner::Default).unwrap();
        assert_eq!(two.len(), 2);
        let mut seen = std::collections::HashSet::new();
        for p in &two {
            assert!(p.energy.feasible && p.energy.total_j <= m.usable_budget_j());
            assert!(!p.order.is_empty());
            for &c in &p.order {
                assert!(seen.insert(c), "cell {c} visited twice");
            }
        }
        let total: f64 = two.iter().map(|p| p.total_score).sum();
        assert!(
            total >= single.total_score,
            "{total} < {}",
            single.total_score
        );
        // The paper battery fits at most 13 such cells, so a second battery must add cells.
        assert!(seen.len() > single.order.len());
    }

    #[test]
    fn detours_are_priced_and_unreachable_cells_never_planned() {
        let cells = grid40();
        let m = model();
        let mut pts = vec![LocalPoint::default()];
        pts.extend(cells.iter().map(|c| c.centre));
        // Cell 3 is unreachable; legs touching cell 5 turn 25 m south of their midpoint.
        let d = Detours::new(&pts, |i, j| {
            if i == 4 || j == 4 {
                None
            } else if i == 6 || j == 6 {
                let (a, b) = (pts[i], pts[j]);
                Some(vec![LocalPoint::new(
                    0.5 * (a.e + b.e),
                    0.5 * (a.n + b.n) - 25.0,
                )])
            } else {
                Some(Vec::new())
            }
        });
        let plans = plan_sorties_routed(
            &m,
            LocalPoint::default(),
            &cells,
            &opts(Planner::Default),
            2,
            Some(&d),
        )
        .unwrap();
        let straight = Detours::straight(&pts);
        let plain = plan_sorties(
            &m,
            LocalPoint::default(),
            &cells,
            &opts(Planner::Default),
            2,
        )
        .unwrap();
        let same = plan_sorties_routed(
            &m,
            LocalPoint::default(),
            &cells,
            &opts(Planner::Default),
            2,
            Some(&straight),
        )
        .unwrap();
        assert_eq!(
            plain.iter().map(|p| p.total_score).sum::<f64>(),
            same.iter().map(|p| p.total_score).sum::<f64>()
        );
        for p in &plans {
            assert!(!p.order.contains(&3));
            assert!(p.energy.feasible);
            assert_eq!(p.via.len(), p.order.len() + 1);
            // The breakdown priced the polylines: leg distances are the detours' lengths.
            let mut prev = 0;
            for (k, &c) in p.order.iter().enumerate() {
                assert_eq!(p.energy.legs[k].distance_m, d.length_m(prev, c + 1));
                prev = c + 1;
            }
        }
        let e = plan_sorties_routed(
            &m,
            LocalPoint::default(),
            &cells[1..],
            &opts(Planner::Default),
            1,
            Some(&d),
        )
        .unwrap_err();
        assert!(e.to_string().contains("detours over 41 nodes"), "{e}");
    }

    #[test]
    fn nonpositive_scores_are_never_planned() {
        let cells = [
            cell(20.0, 20.0, 0.0),
            cell(60.0, 20.0, -1.0),
            cell(100.0, 20.0, 0.5),
        ];
        let plan = plan(&cells, Planner::Default).unwrap();
        assert_eq!(plan.order, vec![2]);
        assert_eq!(plan.considered, 1);
    }

    #[test]
    fn the_paper_budget_fits_eleven_to_thirteen_30_s_hovers() {
        // 30 s hovers at 168.5 W cost 5,055 J each: 66,500 J allows at most 13 with no travel.
        let cells: Vec<Candidate> = (0..40)
            .map(|k| {
                cell(
                    40.0 * f64::from(k % 8) + 20.0,
                    40.0 * f64::from(k / 8) + 20.0,
                    1.0,
                )
            })
            .collect();
        let plan = plan(&cells, Planner::Default).unwrap();
        assert!(
            (11..=13).contains(&plan.order.len()),
            "{}",
            plan.order.len()
        );
        assert!(plan.energy.utilisation > 0.9);
    }

    #[test]
    fn invalid_candidates_are_errors() {
        let cells = [cell(1.0, 1.0, f64::NAN)];
        let e = plan(&cells, Planner::Greedy).unwrap_err();
        assert!(e.to_string().contains("cell 0: invalid score NaN"), "{e}");
    }

    #[test]
    fn hostile_time_limits_are_errors_or_no_limit() {
        for bad in [f64::NAN, -1.0, f64::NEG_INFINITY] {
            let e = PlanOptions::default()
                .with_time_limit_secs(bad)
                .unwrap_err();
            assert!(e.to_string().contains("invalid time limit"), "{e}");
        }
        let cells: Vec<Candidate> = (0..15)
            .map(|k| cell(40.0 * f64::from(k) + 20.0, 20.0, 1.0))
            .collect();
        for huge in [f64::INFINITY, 1e20, f64::MAX] {
            let o = opts(Planner::Default).with_time_limit_secs(huge).unwrap();
            assert_eq!(o.time_limit, Duration::MAX);
            let plan = plan_mission(&model(), LocalPoint::default(), &cells, &o).unwrap();
            assert!(plan.energy.feasible);
        }
    }

    /// In the air at the 5th of 10 stops: ample energy keeps every remaining stop, little
    /// keeps some, too little for the leg home is refused; the priced continuation starts at
    /// the aircraft with a 0 s stop and ends at the base.
    #[test]
    fn a_replan_keeps_what_the_energy_left_carries() {
        let m = model();
        let stops: Vec<Candidate> = (0..10)
            .map(|k| cell(60.0 * f64::from(k) + 40.0, 120.0, 1.0 + f64::from(k % 3)))
            .collect();
        let here = stops[4].centre;
        let rest = &stops[5..];
        let ends = (here, LocalPoint::default());
        let ample = replan(&m, ends, rest, 60_000.0, &opts(Planner::Default)).unwrap();
        let mut kept = ample.order.clone();
        kept.sort_unstable();
        assert_eq!(kept, vec![0, 1, 2, 3, 4]);
        assert!(ample.energy.feasible && ample.energy.total_j <= 60_000.0);
        assert_eq!(ample.energy.legs[0].distance_m, 0.0);
        assert_eq!(ample.energy.cells[0].hover_s, 0.0);
        assert_eq!(ample.energy.legs.len(), ample.order.len() + 2);
        // Enough for the way home and about two stops: fewer, still feasible.
        let home = replan(&m, ends, &[], 1e9, &opts(Planner::Default)).unwrap();
        let short = home.energy.total_j + 2.5 * m.service_energy_j(30.0);
        let few = replan(&m, ends, rest, short, &opts(Planner::Default)).unwrap();
        assert!(
            !few.order.is_empty() && few.order.len() < 5,
            "{:?}",
            few.order
        );
        assert!(few.energy.total_j <= short);
        assert!(few.total_score <= ample.total_score);
        // Not even the leg home.
        let err = replan(
            &m,
            ends,
            rest,
            0.5 * home.energy.total_j,
            &opts(Planner::Default),
        );
        assert!(matches!(err, Err(PlanError::Infeasible { .. })));
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]
        #[test]
        fn routes_fit_the_battery_and_default_beats_greedy(
            cells in proptest::collection::vec((0.0f64..800.0, 0.0f64..500.0, -0.5f64..3.0, 30.0f64..90.0), 1..40)
        ) {
            let cands: Vec<Candidate> = cells
                .iter()
                .map(|&(e, n, score, hover_s)| Candidate { centre: LocalPoint::new(e, n), score, hover_s })
                .collect();
            let m = model();
            let g = plan_mission(&m, LocalPoint::default(), &cands, &opts(Planner::Greedy)).unwrap();
            let d = plan_mission(&m, LocalPoint::default(), &cands, &opts(Planner::Default)).unwrap();
            for p in [&g, &d] {
                prop_assert!(p.energy.total_j <= p.energy.budget_j * (1.0 + 1e-9));
                prop_assert!(p.order.iter().all(|&k| cands[k].score > 0.0));
            }
            prop_assert!(d.total_score >= g.total_score - 1e-9);
        }

        /// In a wind every sortie (straight legs, or around obstacles) is re-priced in that
        /// wind and fits; a calm wind plans exactly what still air plans.
        #[test]
        fn routes_in_wind_fit_and_calm_is_still_air(
            cells in proptest::collection::vec((0.0f64..800.0, 0.0f64..500.0, -0.5f64..3.0, 30.0f64..90.0), 1..30),
            speed in 0.5f64..12.0,
            from in 0.0f64..360.0,
            planner in prop_oneof![Just(Planner::Greedy), Just(Planner::Default)],
            routed in any::<bool>(),
        ) {
            let cands: Vec<Candidate> = cells
                .iter()
                .map(|&(e, n, score, hover_s)| Candidate { centre: LocalPoint::new(e, n), score, hover_s })
                .collect();
            let base = LocalPoint::default();
            let mut nodes = vec![base];
            nodes.extend(cands.iter().map(|c| c.centre));
            // A detour: every leg through a turn point 10 m east of its midpoint.
            let detours = Detours::new(&nodes, |i, j| {
                let (a, b) = (nodes[i], nodes[j]);
                Some(vec![LocalPoint::new((a.e + b.e) / 2.0 + 10.0, (a.n + b.n) / 2.0)])
            });
            let d = routed.then_some(&detours);
            let still = model();
            let windy = still.with_wind(gleaner_energy::Wind::new(speed, from).unwrap());
            let calm = still.with_wind(gleaner_energy::Wind { speed_mps: 0.0, from_deg: from });
            let o = opts(planner);
            let w = plan_sorties_routed(&windy, base, &cands, &o, 2, d).unwrap();
            for p in &w {
                let visits: Vec<CellVisit> = p.order.iter().map(|&k| CellVisit { centre: cands[k].centre, hover_s: cands[k].hover_s }).collect();
                let again = windy.breakdown_paths(base, &visits, &p.via).unwrap();
                prop_assert_eq!(again.total_j, p.energy.total_j);
                prop_assert!(again.feasible && again.total_j <= again.budget_j);
            }
            let a = plan_sorties_routed(&still, base, &cands, &o, 2, d).unwrap();
            let b = plan_sorties_routed(&calm, base, &cands, &o, 2, d).unwrap();
            for (x, y) in a.iter().zip(&b) {
                prop_assert_eq!(&x.order, &y.order);
                prop_assert_eq!(x.energy.total_j.to_bits(), y.energy.total_j.to_bits());
            }
        }

        #[test]
        fn a_replan_never_exceeds_the_energy_left(
            cells in proptest::collection::vec((0.0f64..800.0, 0.0f64..500.0, -0.5f64..3.0, 30.0f64..90.0), 0..30),
            at in (0.0f64..800.0, 0.0f64..500.0),
            left in 0.0f64..70_000.0,
            wind in (0.0f64..10.0, 0.0f64..360.0),
        ) {
            let cands: Vec<Candidate> = cells
                .iter()
                .map(|&(e, n, score, hover_s)| Candidate { centre: LocalPoint::new(e, n), score, hover_s })
                .collect();
            // Still air or a wind (directed costs from the aircraft to the base).
            let m = model().with_wind(gleaner_energy::Wind::new(wind.0, wind.1).unwrap());
            let start = LocalPoint::new(at.0, at.1);
            match replan(&m, (start, LocalPoint::default()), &cands, left, &opts(Planner::Default)) {
                Ok(p) => {
                    prop_assert!(p.energy.feasible && p.energy.total_j <= left);
                    prop_assert!(p.order.iter().all(|&k| cands[k].score > 0.0));
                    let mut seen = p.order.clone();
                    seen.sort_unstable();
                    seen.dedup();
                    prop_assert_eq!(seen.len(), p.order.len());
                }
                Err(PlanError::Infeasible { total_j, .. }) => prop_assert!(total_j > left),
                Err(e) => prop_assert!(false, "{e}"),
            }
        }
    }
}
