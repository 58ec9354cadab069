//! Exploration phase (docs/method.md §5 step 3): visit every cell in as few budget-feasible sorties as
//! possible.
//!
//! Route-first, cluster-second:
//!
//! 1. A short closed tour through all cells (the "giant tour"): nearest neighbour from cell 0,
//!    then the generic solver's tour improvement ([`gleaner_orienteering::improve_routes`]:
//!    2-opt and Or-opt on candidate-neighbour lists, then seeded double-bridge kicks).
//! 2. The optimal split of that tour into consecutive sorties B -> ... -> B (Beasley 1983's
//!    split, dynamic programming on the tour positions), minimising first the number of
//!    sorties, then their total energy. Every rotation, in both directions, of the giant tour
//!    and of a polar sweep around the base is split and the best kept.
//! 3. The sorties are improved as routes of a team orienteering instance (node 0 = base,
//!    travel costs = cruise energy, service costs = the cells' service energies, budget =
//!    usable budget less the fixed climb/descent energy) by the same generic moves: 2-opt and
//!    Or-opt within each sortie, relocation and exchange of cells between sorties while that
//!    lowers the total energy and every sortie stays within budget.
//! 4. Sorties are emptied where all their cells fit into the others (cheapest feasible
//!    insertion, farthest cell first); steps 3-4 repeat while that removes sorties.
//!
//! Every sortie is finally re-checked with [`MissionEnergyModel::breakdown`] and its figures
//! ([`Sortie::distance_m`], [`Sortie::energy_j`]...) are the model's own. Deterministic for a
//! given [`ExplorationOptions::seed`].
//!
//! Measured on the paper preset (30 s hovers, 40 m cells): a 32 x 32 grid (1,000 cells) needs
//! 142 sorties from a corner base (lower bound 125) and 106 from the centre (lower bound 94);
//! see `examples/exploration_quality.rs` and `BENCHMARKS.md`.
//!
//! ```
//! use gleaner_energy::{EnergyConfig, MissionEnergyModel};
//! use gleaner_field::LocalPoint;
//! use gleaner_mission::exploration::{ExplorationOptions, plan_exploration};
//!
//! let model = MissionEnergyModel::new(&EnergyConfig::paper()).unwrap();
//! // 30 cells of 40 m in a row; each hover costs 30 s at P(0) + P_rx.
//! let cells: Vec<LocalPoint> = (0..30).map(|i| LocalPoint::new(20.0 + 40.0 * i as f64, 20.0)).collect();
//! let service = vec![model.service_energy_j(30.0); cells.len()];
//! let plan = plan_exploration(&model, LocalPoint::new(0.0, 0.0), &cells, &service, &ExplorationOptions::default()).unwrap();
//! assert!(plan.sorties.len() >= plan.lower_bound_sorties);
//! assert!(plan.sorties.iter().all(|s| s.energy_j <= model.usable_budget_j()));
//! let mut visited: Vec<usize> = plan.sorties.iter().flat_map(|s| s.cells.clone()).collect();
//! visited.sort_unstable();
//! assert_eq!(visited, (0..30).collect::<Vec<_>>());
//! ```

use gleaner_energy::{CellVisit, EnergyError, MissionEnergyModel};
use gleaner_field::LocalPoint;

use crate::Detours;
use gleaner_orienteering::{
    ImproveOptions, Metric, Problem, ProblemError, SolutionError, improve_routes,
};
use thiserror::Error;

/// Tuning of the exploration planner.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExplorationOptions {
    /// Candidate neighbours per cell in 2-opt and Or-opt (default 12).
    pub neighbours: usize,
    /// Double-bridge kicks on the giant tour, each kept only when it shortens the tour
    /// (default 200; 0 disables them).
    pub tour_kicks: usize,
    /// Seed of the kicks' random choices (default 0).
    pub seed: u64,
    /// Relative safety margin on the budget, so that float rounding never makes a planned
    /// sortie infeasible when re-checked: sorties use at most usable budget·(1 − margin)
    /// (default 1e-9; must lie in [0, 1)).
    pub budget_margin: f64,
    /// After the split, try to empty whole sorties by moving their cells into the others at
    /// the cheapest feasible position (default true).
    pub eliminate_sorties: bool,
    /// Moving cells between sorties: 0 disables relocation and exchange of cells between
    /// sorties; otherwise the maximum number of further (empty sorties, re-optimise) rounds
    /// after the first (default 50).
    pub max_improvement_rounds: usize,
}

impl Default for ExplorationOptions {
    fn default() -> Self {
        Self {
            neighbours: 12,
            tour_kicks: 200,
            seed: 0,
            budget_margin: 1e-9,
            eliminate_sorties: true,
            max_improvement_rounds: 50,
        }
    }
}

/// One sortie of the exploration phase, with the energy model's own figures.
#[derive(Debug, Clone, PartialEq)]
pub struct Sortie {
    /// Cells in visiting order, as indices into the input slices.
    pub cells: Vec<usize>,
    /// Cruise distance B -> cells -> B, metres.
    pub distance_m: f64,
    /// Cruise energy including the return leg, J.
    pub travel_j: f64,
    /// Sum of the cells' service energies, J.
    pub service_j: f64,
    /// Climb and descent energy ([`MissionEnergyModel::sortie_fixed_j`]), J.
    pub fixed_j: f64,
    /// fixed_j + travel_j + service_j: the total of [`MissionEnergyModel::breakdown`], J.
    pub energy_j: f64,
}

/// The exploration plan: sorties that together visit every cell exactly once.
#[derive(Debug, Clone, PartialEq)]
pub struct ExplorationPlan {
    /// The sorties; each is an independent flight from the base and back, in no particular
    /// order of priority.
    pub sorties: Vec<Sortie>,
    /// A lower bound on the number of sorties any plan needs (0 without cells), with
    /// capacity = budget − fixed energy per sortie: the larger of
    /// ceil(sum over cells of service / (capacity − 2·one-way travel energy)) and, over distance
    /// thresholds tau, ceil(service of the cells at least tau away / (capacity − 2·tau)).
    pub lower_bound_sorties: usize,
    /// Sum of the sorties' energies, J.
    pub total_energy_j: f64,
    /// Length of the giant tour through all cells (cells only, closed), metres.
    pub giant_tour_m: f64,
}

/// Why an exploration could not be planned.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ExplorationError {
    /// An input the energy model rejects: slices of different lengths, a non-finite
    /// position, a negative or non-finite service energy, or an invalid option.
    #[error("{0}")]
    Energy(#[from] EnergyError),
    /// A cell that cannot be served even by a sortie that visits it alone.
    #[error(
        "cell {cell} cannot be visited within the budget: a sortie to it alone needs {energy_j} J, usable budget is {budget_j} J"
    )]
    CellUnreachable {
        /// Position of the cell in the input slice.
        cell: usize,
        /// Energy of the single-cell sortie B -> cell -> B, J.
        energy_j: f64,
        /// Usable budget, J.
        budget_j: f64,
    },
    /// The tour-improvement instance could not be built (a bug; reported, never hidden).
    #[error("tour improvement: {0}")]
    Problem(#[from] ProblemError),
    /// The tour improvement rejected its routes (a bug; reported, never hidden).
    #[error("tour improvement: {0}")]
    Routes(#[from] SolutionError),
    /// A planned sortie that the energy model finds over budget (a bug; reported, never
    /// handed to an operator).
    #[error("sortie {sortie} needs {total_j} J but only {budget_j} J are usable")]
    Infeasible {
        /// Position of the sortie in the plan.
        sortie: usize,
        /// Its energy according to [`MissionEnergyModel::breakdown`], J.
        total_j: f64,
        /// Usable budget, J.
        budget_j: f64,
    },
}

fn invalid(name: &'static str, value: f64, expected: &'static str) -> ExplorationError {
    ExplorationError::Energy(EnergyError::InvalidParameter {
        name,
        value,
        expected,
    })
}

/// Straight-line distance, metres: the same formula as the energy model's.
fn distance_m(a: &LocalPoint, b: &LocalPoint) -> f64 {
    let (de, dn) = (a.e - b.e, a.n - b.n);
    (de * de + dn * dn).sqrt()
}

/// Leg lengths between the base (`None`) and the cells (`Some(c)`), m: straight, or along
/// the detours' polylines.
struct Legs<'a> {
    base: LocalPoint,
    cells: &'a [LocalPoint],
    detours: Option<&'a Detours>,
}

impl Legs<'_> {
    fn at(&self, c: Option<usize>) -> LocalPoint {
        c.map_or(self.base, |c| self.cells[c])
    }

    /// The leg from `a` to `b`, m.
    fn d(&self, a: Option<usize>, b: Option<usize>) -> f64 {
        match self.detours {
            None => distance_m(&self.at(a), &self.at(b)),
            Some(d) => d.length_m(a.map_or(0, |c| c + 1), b.map_or(0, |c| c + 1)),
        }
    }
}

/// Plans the fewest budget-feasible sorties from `base` that together visit every cell of
/// `centres` (cell centres, local frame, metres) with service energies `service_j` (hover +
/// receiver energy per cell, J, e.g. [`MissionEnergyModel::service_energy_j`]), then the least
/// total energy for that number of sorties. See the module docs for the method.
///
/// # Errors
/// [`ExplorationError::Energy`] with [`EnergyError::LengthMismatch`] if the slices differ in
/// length, or [`EnergyError::InvalidParameter`] for a non-finite position, a negative /
/// non-finite service energy or an invalid option; [`ExplorationError::CellUnreachable`] if
/// some cell cannot be served even alone. The other variants report bugs.
pub fn plan_exploration(
    model: &MissionEnergyModel,
    base: LocalPoint,
    centres: &[LocalPoint],
    service_j: &[f64],
    options: &ExplorationOptions,
) -> Result<ExplorationPlan, ExplorationError> {
    plan_exploration_routed(model, base, centres, service_j, options, None)
}

/// [`plan_exploration`] with legs flown around no-fly zones: `detours` over the base and
/// `centres` (in order) gives every leg's polyline, whose length every step of the method
/// uses in place of the straight line, and every sortie is re-checked along its polylines
/// ([`MissionEnergyModel::breakdown_paths`]). A cell `detours` marks unreachable is a
/// [`ExplorationError::CellUnreachable`]: leave such cells out. `None` is
/// [`plan_exploration`].
///
/// # Errors
/// As [`plan_exploration`]; [`EnergyError::LengthMismatch`] for detours over another number
/// of nodes than base + cells.
pub fn plan_exploration_routed(
    model: &MissionEnergyModel,
    base: LocalPoint,
    centres: &[LocalPoint],
    service_j: &[f64],
    options: &ExplorationOptions,
    detours: Option<&Detours>,
) -> Result<ExplorationPlan, ExplorationError> {
    check_inputs(base, centres, service_j, options, detours)?;
    let cells = centres;
    let legs = Legs {
        base,
        cells,
        detours,
    };
    let n = cells.len();
    let fixed_j = model.sortie_fixed_j();
    let epm = model.energy_per_metre_j();
    // Travel + service capacity of a sortie, J. The orienteering routes may exceed their
    // budget by its tolerance (1e-9 relative), so they get a budget that much lower.
    let capacity = model.usable_budget_j() * (1.0 - options.budget_margin) - fixed_j;
    let route_budget = (capacity - 1e-9 * capacity.max(1.0)).max(0.0);
    let budget = fixed_j + route_budget;
    let to_base: Vec<f64> = (0..n).map(|c| epm * legs.d(Some(c), None)).collect();
    for i in 0..n {
        let alone = fixed_j + 2.0 * to_base[i] + service_j[i];
        if alone.is_nan() || alone > budget {
            return Err(ExplorationError::CellUnreachable {
                cell: i,
                energy_j: alone,
                budget_j: model.usable_budget_j(),
            });
        }
    }
    let lower_bound_sorties = sortie_lower_bound(&to_base, service_j, budget - fixed_j);
    let tour = giant_tour(&legs, options)?;
    let giant_tour_m = cycle_length(&legs, &tour);
    let sweep = sweep_order(cells, base);

    let cost = SplitCost {
        legs: &legs,
        epm,
        to_base: &to_base,
        service_j,
        fixed_j,
        budget,
    };
    let mut groups = best_split(&cost, [&tour, &sweep], n);
    // The sorties as a team orienteering instance in J: node 0 = base, node c + 1 = cell c.
    let sorties_problem = sorties_problem(&legs, service_j, epm, route_budget, groups.len())?;
    let improve = ImproveOptions {
        neighbours: options.neighbours,
        between_routes: options.max_improvement_rounds > 0,
        ..ImproveOptions::default()
    };
    let improve_sorties = |groups: Vec<Vec<usize>>| -> Result<Vec<Vec<usize>>, ExplorationError> {
        let Some(problem) = &sorties_problem else {
            return Ok(groups);
        };
        let routes: Vec<Vec<usize>> = groups
            .iter()
            .map(|g| {
                std::iter::once(0)
                    .chain(g.iter().map(|&c| c + 1))
                    .chain(std::iter::once(0))
                    .collect()
            })
            .collect();
        let improved = improve_routes(problem, &routes, &improve)?;
        Ok(improved
            .routes
            .iter()
            .map(|r| {
                r[1..r.len() - 1]
                    .iter()
                    .map(|&v| v - 1)
                    .collect::<Vec<usize>>()
            })
            .filter(|g| !g.is_empty())
            .collect())
    };
    groups = improve_sorties(groups)?;
    if options.eliminate_sorties {
        for _ in 0..=options.max_improvement_rounds {
            let before = groups.len();
            groups = eliminate_sorties(&cost, groups);
            if groups.len() == before {
                break;
            }
            // Re-optimise the sorties that received cells.
            groups = improve_sorties(groups)?;
        }
    }
    let sorties = priced_sorties(model, &legs, service_j, groups)?;
    let total_energy_j = sorties.iter().map(|s| s.energy_j).sum();
    Ok(ExplorationPlan {
        sorties,
        lower_bound_sorties,
        total_energy_j,
        giant_tour_m,
    })
}

/// Refuses detours over another number of nodes than base + cells, a service energy per
/// cell missing, a coordinate or service energy that is not finite (or negative), a budget
/// margin outside [0, 1).
fn check_inputs(
    base: LocalPoint,
    cells: &[LocalPoint],
    service_j: &[f64],
    options: &ExplorationOptions,
    detours: Option<&Detours>,
) -> Result<(), ExplorationError> {
    if let Some(d) = detours
        && d.len() != cells.len() + 1
    {
        return Err(EnergyError::LengthMismatch {
            what: "detour nodes vs base + cells",
            left: d.len(),
            right: cells.len() + 1,
        }
        .into());
    }
    if cells.len() != service_j.len() {
        return Err(EnergyError::LengthMismatch {
            what: "cell centres vs service energies",
            left: cells.len(),
            right: service_j.len(),
        }
        .into());
    }
    for p in cells.iter().chain(std::iter::once(&base)) {
        if !(p.e.is_finite() && p.n.is_finite()) {
            let bad = if p.e.is_finite() { p.n } else { p.e };
            return Err(invalid(
                "cell or base coordinate (m)",
                bad,
                "a finite number",
            ));
        }
    }
    for &s in service_j {
        if !(s.is_finite() && s >= 0.0) {
            return Err(invalid(
                "cell service energy (J)",
                s,
                "a finite number >= 0",
            ));
        }
    }
    if !(options.budget_margin >= 0.0 && options.budget_margin < 1.0) {
        return Err(invalid(
            "budget margin",
            options.budget_margin,
            "a number in [0, 1)",
        ));
    }
    Ok(())
}

/// The fewest sorties (then the least energy) over every rotation of each candidate order,
/// forwards and backwards, split by [`SplitCost::split`].
fn best_split(cost: &SplitCost<'_>, candidates: [&Vec<usize>; 2], n: usize) -> Vec<Vec<usize>> {
    let mut best: Option<(usize, f64, Vec<Vec<usize>>)> = None;
    let mut sequence = Vec::with_capacity(n);
    for candidate in candidates {
        for reversed in [false, true] {
            for start in 0..n.max(1) {
                sequence.clear();
                for k in 0..n {
                    let at = if reversed {
                        (start + n - k) % n
                    } else {
                        (start + k) % n
                    };
                    sequence.push(candidate[at]);
                }
                let (count, energy, groups) = cost.split(&sequence);
                let better = match &best {
                    None => true,
                    Some((c, e, _)) => count < *c || (count == *c && energy < *e),
                };
                if better {
                    best = Some((count, energy, groups));
                }
            }
        }
    }
    best.map(|b| b.2).unwrap_or_default()
}

/// The sorties as a team orienteering instance in J for `vehicles` sorties (node 0 = base,
/// node c + 1 = cell c; legs along the detours when given); `None` without cells.
fn sorties_problem(
    legs: &Legs<'_>,
    service_j: &[f64],
    epm: f64,
    route_budget: f64,
    vehicles: usize,
) -> Result<Option<Problem>, ExplorationError> {
    let (base, cells, detours, n) = (legs.base, legs.cells, legs.detours, legs.cells.len());
    if n > 0 {
        let mut service = Vec::with_capacity(n + 1);
        service.push(0.0);
        service.extend_from_slice(service_j);
        let problem = match detours {
            None => {
                let points: Vec<[f64; 2]> = std::iter::once(base)
                    .chain(cells.iter().copied())
                    .map(|p| [epm * p.e, epm * p.n])
                    .collect();
                Problem::from_points(&points, Metric::Euclidean, vec![0.0; n + 1], route_budget)?
            }
            Some(d) => {
                let cost: Vec<f64> = (0..=n)
                    .flat_map(|a| (0..=n).map(move |b| epm * d.length_m(a, b)))
                    .collect();
                Problem::new(cost, vec![0.0; n + 1], route_budget)?
            }
        };
        Ok(Some(
            problem
                .with_service_costs(service)?
                .with_vehicles(vehicles.max(1))?,
        ))
    } else {
        Ok(None)
    }
}

/// Each group of cells as a sortie, re-checked by the energy model with the hover times
/// behind the service energies (and along the detours); refuses one over the budget.
fn priced_sorties(
    model: &MissionEnergyModel,
    legs: &Legs<'_>,
    service_j: &[f64],
    groups: Vec<Vec<usize>>,
) -> Result<Vec<Sortie>, ExplorationError> {
    let (base, cells, detours) = (legs.base, legs.cells, legs.detours);
    let per_joule_of_service = model.hover_power_w() + model.rx_power_w();
    let mut sorties = Vec::with_capacity(groups.len());
    for (k, g) in groups.into_iter().filter(|g| !g.is_empty()).enumerate() {
        // The energy model's own re-check, with the hover times behind the service energies.
        let visits: Vec<CellVisit> = g
            .iter()
            .map(|&c| CellVisit {
                centre: cells[c],
                hover_s: service_j[c] / per_joule_of_service,
            })
            .collect();
        let via = detours.map(|d| d.route_via(&g)).unwrap_or_default();
        let e = model.breakdown_paths(base, &visits, &via)?;
        if !e.feasible {
            return Err(ExplorationError::Infeasible {
                sortie: k,
                total_j: e.total_j,
                budget_j: e.budget_j,
            });
        }
        sorties.push(Sortie {
            cells: g,
            distance_m: e.distance_m,
            travel_j: e.travel_j - e.vertical_j + e.return_j,
            service_j: e.hover_j + e.comm_j,
            fixed_j: e.vertical_j,
            energy_j: e.total_j,
        });
    }
    Ok(sorties)
}

/// A closed tour through all cells: nearest neighbour from cell 0, then the generic tour
/// improvement (2-opt, Or-opt, double-bridge kicks) with cell `tour[0]` held in place.
fn giant_tour(
    legs: &Legs<'_>,
    options: &ExplorationOptions,
) -> Result<Vec<usize>, ExplorationError> {
    let cells = legs.cells;
    let n = cells.len();
    if n < 4 {
        return Ok((0..n).collect());
    }
    let d = |a: usize, b: usize| legs.d(Some(a), Some(b));
    let mut tour = Vec::with_capacity(n + 1);
    let mut used = vec![false; n];
    let mut current = 0;
    used[0] = true;
    tour.push(0);
    for _ in 1..n {
        let mut next = usize::MAX;
        let mut best = f64::INFINITY;
        for (c, &u) in used.iter().enumerate() {
            if !u && d(current, c) < best {
                best = d(current, c);
                next = c;
            }
        }
        used[next] = true;
        tour.push(next);
        current = next;
    }
    tour.push(0);
    // Any budget at least the tour's length will do; it only sets the improvement threshold
    // (1e-9 relative).
    let length = cycle_length(legs, &tour[..n]);
    let problem = match legs.detours {
        None => {
            let points: Vec<[f64; 2]> = cells.iter().map(|c| [c.e, c.n]).collect();
            Problem::from_points(&points, Metric::Euclidean, vec![0.0; n], 0.0)?
        }
        Some(_) => {
            let cost: Vec<f64> = (0..n).flat_map(|a| (0..n).map(move |b| d(a, b))).collect();
            Problem::new(cost, vec![0.0; n], 0.0)?
        }
    }
    .with_budget(length * (1.0 + 1e-6) + 1.0)?;
    let improve = ImproveOptions {
        neighbours: options.neighbours,
        between_routes: false,
        kicks: options.tour_kicks,
        seed: options.seed,
        ..ImproveOptions::default()
    };
    let improved = improve_routes(&problem, &[tour], &improve)?;
    let mut tour = improved.routes[0].clone();
    tour.pop();
    Ok(tour)
}

/// A lower bound on the number of sorties, the larger of two valid bounds (`capacity_j` is
/// the budget minus the fixed energy per sortie, J):
///
/// - per cell: a sortie S flies at least 2·to_base(c) for each of its cells c, so
///   service(S) <= capacity − 2·to_base(c) and sum over c in S of
///   service(c)/(capacity − 2·to_base(c)) <= 1; summing over all cells bounds the count;
/// - per threshold tau: the sorties serving cells at least tau away have at most
///   capacity − 2·tau each for service and must serve all those cells.
fn sortie_lower_bound(to_base: &[f64], service_j: &[f64], capacity_j: f64) -> usize {
    if to_base.is_empty() {
        return 0;
    }
    // A tiny relative slack keeps float rounding from overstating a bound.
    let up = |x: f64| ((x * (1.0 - 1e-12)).ceil() as usize).max(1);
    let per_cell: f64 = to_base
        .iter()
        .zip(service_j)
        .map(|(&d, &s)| {
            let room = capacity_j - 2.0 * d;
            if s > 0.0 && room > 0.0 { s / room } else { 0.0 }
        })
        .sum();
    let mut order: Vec<usize> = (0..to_base.len()).collect();
    order.sort_by(|&a, &b| to_base[b].total_cmp(&to_base[a]));
    let mut served = 0.0;
    let mut bound = up(per_cell);
    for &c in &order {
        served += service_j[c];
        let room = capacity_j - 2.0 * to_base[c];
        if room > 0.0 {
            bound = bound.max(up(served / room));
        }
    }
    bound
}

/// Cells sorted by polar angle around the base (then by distance): a sweep order whose
/// splits are radial petals.
fn sweep_order(cells: &[LocalPoint], base: LocalPoint) -> Vec<usize> {
    let key = |c: &LocalPoint| ((c.n - base.n).atan2(c.e - base.e), distance_m(c, &base));
    let mut order: Vec<usize> = (0..cells.len()).collect();
    order.sort_by(|&a, &b| {
        let (ka, kb) = (key(&cells[a]), key(&cells[b]));
        ka.0.total_cmp(&kb.0)
            .then(ka.1.total_cmp(&kb.1))
            .then(a.cmp(&b))
    });
    order
}

/// Energy of the sortie base -> order -> base, J.
fn sortie_energy(cost: &SplitCost<'_>, order: &[usize]) -> f64 {
    if order.is_empty() {
        return 0.0;
    }
    let service: f64 = order.iter().map(|&c| cost.service_j[c]).sum();
    cost.fixed_j + cost.epm * path_length(cost.legs, order) + service
}

/// Repeatedly tries to empty a sortie (fewest cells first) by inserting each of its cells,
/// farthest first, at the cheapest feasible position of another sortie; commits when all fit.
fn eliminate_sorties(cost: &SplitCost<'_>, mut groups: Vec<Vec<usize>>) -> Vec<Vec<usize>> {
    let d = |a: Option<usize>, b: Option<usize>| cost.legs.d(a, b);
    loop {
        let energies: Vec<f64> = groups.iter().map(|g| sortie_energy(cost, g)).collect();
        let mut candidates: Vec<usize> = (0..groups.len()).collect();
        candidates.sort_by(|&a, &b| {
            groups[a]
                .len()
                .cmp(&groups[b].len())
                .then(energies[a].total_cmp(&energies[b]))
        });
        let mut done = None;
        'attempt: for &r in &candidates {
            let mut trial = groups.clone();
            let mut trial_energy = energies.clone();
            let mut moving = std::mem::take(&mut trial[r]);
            moving.sort_by(|&a, &b| cost.to_base[b].total_cmp(&cost.to_base[a]).then(a.cmp(&b)));
            for &c in &moving {
                let mut best: Option<(f64, usize, usize)> = None;
                for (k, g) in trial.iter().enumerate() {
                    if k == r || g.is_empty() {
                        continue;
                    }
                    for pos in 0..=g.len() {
                        let prev = pos.checked_sub(1).map(|q| g[q]);
                        let next = g.get(pos).copied();
                        let delta = cost.epm
                            * (d(prev, Some(c)) + d(Some(c), next) - d(prev, next))
                            + cost.service_j[c];
                        if trial_energy[k] + delta <= cost.budget
                            && best.is_none_or(|b| delta < b.0)
                        {
                            best = Some((delta, k, pos));
                        }
                    }
                }
                let Some((_, k, pos)) = best else {
                    continue 'attempt;
                };
                trial[k].insert(pos, c);
                // Recompute exactly rather than accumulate deltas, so feasibility is exact.
                trial_energy[k] = sortie_energy(cost, &trial[k]);
                if trial_energy[k] > cost.budget {
                    continue 'attempt;
                }
            }
            trial.remove(r);
            done = Some(trial);
            break;
        }
        match done {
            Some(g) => groups = g,
            None => return groups,
        }
    }
}

/// Everything the split DP needs, in J.
struct SplitCost<'a> {
    legs: &'a Legs<'a>,
    epm: f64,
    to_base: &'a [f64],
    service_j: &'a [f64],
    fixed_j: f64,
    budget: f64,
}

impl SplitCost<'_> {
    /// Optimal split of `seq` into consecutive feasible sorties: (count, energy, groups).
    fn split(&self, seq: &[usize]) -> (usize, f64, Vec<Vec<usize>>) {
        let m = seq.len();
        let mut count = vec![usize::MAX; m + 1];
        let mut energy = vec![f64::INFINITY; m + 1];
        let mut pred = vec![0usize; m + 1];
        count[0] = 0;
        energy[0] = 0.0;
        for i in 0..m {
            if count[i] == usize::MAX {
                continue;
            }
            let mut path = 0.0;
            let mut service = 0.0;
            for j in i..m {
                if j > i {
                    path += self.epm * self.legs.d(Some(seq[j - 1]), Some(seq[j]));
                }
                service += self.service_j[seq[j]];
                let sortie =
                    self.fixed_j + self.to_base[seq[i]] + path + self.to_base[seq[j]] + service;
                // Monotone in j (triangle inequality, service >= 0): stop at the first overflow.
                if sortie > self.budget {
                    break;
                }
                let (c, e) = (count[i] + 1, energy[i] + sortie);
                if c < count[j + 1] || (c == count[j + 1] && e < energy[j + 1]) {
                    count[j + 1] = c;
                    energy[j + 1] = e;
                    pred[j + 1] = i;
                }
            }
        }
        let mut groups = Vec::new();
        let mut j = m;
        while j > 0 {
            let i = pred[j];
            groups.push(seq[i..j].to_vec());
            j = i;
        }
        groups.reverse();
        (count[m], energy[m], groups)
    }
}

fn cycle_length(legs: &Legs<'_>, tour: &[usize]) -> f64 {
    let n = tour.len();
    (0..n)
        .map(|k| legs.d(Some(tour[k]), Some(tour[(k + 1) % n])))
        .sum()
}

fn path_length(legs: &Legs<'_>, order: &[usize]) -> f64 {
    let mut previous = None;
    let mut total = 0.0;
    for &c in order {
        total += legs.d(previous, Some(c));
        previous = Some(c);
    }
    total + legs.d(previous, None)
}

#[cfg(test)]
mod tests {
    use super::*;
    use gleaner_energy::{EnergyConfig, VerticalConfig};
    use proptest::prelude::*;

    /// The energy model of the paper preset.
    fn paper() -> MissionEnergyModel {
        MissionEnergyModel::new(&EnergyConfig::paper()).unwrap()
    }

    fn grid(nx: usize, ny: usize) -> Vec<LocalPoint> {
        (0..nx * ny)
            .map(|i| LocalPoint::new(20.0 + 40.0 * (i % nx) as f64, 20.0 + 40.0 * (i / nx) as f64))
            .collect()
    }

    /// Checks every cell is visited exactly once, every sortie re-checks feasible with
    /// [`MissionEnergyModel::breakdown`] and the reported energies match it.
    fn check_plan(
        model: &MissionEnergyModel,
        base: LocalPoint,
        cells: &[LocalPoint],
        hover_s: &[f64],
        plan: &ExplorationPlan,
    ) {
        let mut seen = vec![0; cells.len()];
        for s in &plan.sorties {
            assert!(!s.cells.is_empty());
            for &c in &s.cells {
                seen[c] += 1;
            }
            let visits: Vec<CellVisit> = s
                .cells
                .iter()
                .map(|&c| CellVisit {
                    centre: cells[c],
                    hover_s: hover_s[c],
                })
                .collect();
            let e = model.breakdown(base, &visits).unwrap();
            assert!(
                e.feasible,
                "sortie of {} J over budget {}",
                e.total_j, e.budget_j
            );
            assert!(
                (e.total_j - s.energy_j).abs() <= 1e-9 * e.total_j,
                "{} vs {}",
                e.total_j,
                s.energy_j
            );
        }
        assert!(seen.iter().all(|&k| k == 1), "visit counts {seen:?}");
        assert!(plan.sorties.len() >= plan.lower_bound_sorties);
        let total: f64 = plan.sorties.iter().map(|s| s.energy_j).sum();
        assert!((total - plan.total_energy_j).abs() <= 1e-9 * (1.0 + total));
    }

    fn plan(
        model: &MissionEnergyModel,
        base: LocalPoint,
        cells: &[LocalPoint],
        hover_s: &[f64],
    ) -> ExplorationPlan {
        let service: Vec<f64> = hover_s.iter().map(|&h| model.service_energy_j(h)).collect();
        plan_exploration(model, base, cells, &service, &ExplorationOptions::default()).unwrap()
    }

    #[test]
    fn empty_field_needs_no_sortie() {
        let m = paper();
        let p = plan(&m, LocalPoint::new(0.0, 0.0), &[], &[]);
        assert!(p.sorties.is_empty() && p.lower_bound_sorties == 0 && p.total_energy_j == 0.0);
    }

    #[test]
    fn small_field_fits_one_sortie() {
        let m = paper();
        let cells = grid(3, 3);
        let hover = vec![30.0; 9];
        let p = plan(&m, LocalPoint::new(0.0, 0.0), &cells, &hover);
        assert_eq!(p.sorties.len(), 1);
        check_plan(&m, LocalPoint::new(0.0, 0.0), &cells, &hover, &p);
        // From the corner base: 28.28 m out, 8 legs of 40 m, and a return of at most
        // sqrt(20² + 100²) = 101.98 m (the optimum is 428.0 m, e.g. a serpentine ending at
        // (20, 100)).
        assert!(
            p.sorties[0].distance_m <= 28.2843 + 320.0 + 101.981,
            "{}",
            p.sorties[0].distance_m
        );
    }

    #[test]
    fn paper_field_meets_lower_bound_closely() {
        // 10 x 10 cells of 40 m, 30 s hovers: each sortie serves about 12 cells.
        let m = paper();
        let cells = grid(10, 10);
        let hover = vec![30.0; 100];
        let base = LocalPoint::new(-20.0, -20.0);
        let p = plan(&m, base, &cells, &hover);
        check_plan(&m, base, &cells, &hover, &p);
        assert!(
            p.sorties.len() <= p.lower_bound_sorties + 2,
            "{} vs bound {}",
            p.sorties.len(),
            p.lower_bound_sorties
        );
    }

    #[test]
    fn unreachable_cell_is_reported() {
        let m = paper();
        let cells = [LocalPoint::new(10.0, 0.0), LocalPoint::new(5_000.0, 0.0)];
        let service = [m.service_energy_j(30.0); 2];
        let err = plan_exploration(
            &m,
            LocalPoint::new(0.0, 0.0),
            &cells,
            &service,
            &ExplorationOptions::default(),
        )
        .unwrap_err();
        assert!(
            matches!(err, ExplorationError::CellUnreachable { cell: 1, .. }),
            "{err}"
        );
    }

    #[test]
    fn bad_inputs_are_rejected() {
        let m = paper();
        let base = LocalPoint::new(0.0, 0.0);
        let o = ExplorationOptions::default();
        assert!(plan_exploration(&m, base, &[base], &[], &o).is_err());
        assert!(plan_exploration(&m, base, &[base], &[-1.0], &o).is_err());
        assert!(plan_exploration(&m, base, &[LocalPoint::new(f64::NAN, 0.0)], &[1.0], &o).is_err());
    }

    #[test]
    fn hostile_numbers_are_errors_not_panics() {
        let m = paper();
        let base = LocalPoint::new(0.0, 0.0);
        let o = ExplorationOptions::default();
        let far = [LocalPoint::new(1e300, -1e300), LocalPoint::new(10.0, 0.0)];
        assert!(matches!(
            plan_exploration(&m, base, &far, &[1.0, 1.0], &o),
            Err(ExplorationError::CellUnreachable { cell: 0, .. })
        ));
        let near = [LocalPoint::new(10.0, 0.0)];
        for s in [f64::INFINITY, f64::NAN, -0.5] {
            assert!(matches!(
                plan_exploration(&m, base, &near, &[s], &o),
                Err(ExplorationError::Energy(_))
            ));
        }
        assert!(matches!(
            plan_exploration(&m, base, &near, &[f64::MAX], &o),
            Err(ExplorationError::CellUnreachable { .. })
        ));
        // Everything 1,000 km from the origin, base included: a normal plan.
        let shifted: Vec<LocalPoint> = grid(3, 3)
            .iter()
            .map(|p| LocalPoint::new(p.e + 1e6, p.n - 1e6))
            .collect();
        let b = LocalPoint::new(1e6, -1e6);
        let p = plan_exploration(&m, b, &shifted, &[m.service_energy_j(30.0); 9], &o).unwrap();
        check_plan(&m, b, &shifted, &[30.0; 9], &p);
        for margin in [f64::NAN, -1e-3, 1.0, f64::INFINITY] {
            let o = ExplorationOptions {
                budget_margin: margin,
                ..ExplorationOptions::default()
            };
            assert!(plan_exploration(&m, base, &near, &[1.0], &o).is_err());
        }
    }

    #[test]
    fn lower_bound_hand_checked() {
        // Capacity 100 J. Cells at one-way 40, 10, 0 J with service 10, 50, 30 J.
        // tau = 40: 10 / 20 -> 1; tau = 10: 60 / 80 -> 1; tau = 0: 90 / 100 -> 1;
        // per cell: 10/20 + 50/80 + 30/100 = 1.425 -> 2.
        assert_eq!(
            sortie_lower_bound(&[40.0, 10.0, 0.0], &[10.0, 50.0, 30.0], 100.0),
            2
        );
        // Per cell 5/20 + 20/80 + 30/100 = 0.8 and every threshold gives 1.
        assert_eq!(
            sortie_lower_bound(&[40.0, 10.0, 0.0], &[5.0, 20.0, 30.0], 100.0),
            1
        );
        // Far cells dominate: two cells 45 J away with 8 J service each need 2 sorties (room 10).
        assert_eq!(
            sortie_lower_bound(&[45.0, 45.0, 0.0], &[8.0, 8.0, 1.0], 100.0),
            2
        );
        assert_eq!(sortie_lower_bound(&[], &[], 100.0), 0);
    }

    #[test]
    fn giant_tour_untangles_points_on_a_circle() {
        // 40 points on a circle of radius 500 m in scrambled order: the optimal tour is the
        // polygon, and 2-opt reaches it from any tour (a tour with a crossing is not 2-opt
        // optimal).
        let n = 40;
        let cells: Vec<LocalPoint> = (0..n)
            .map(|i| {
                let a = 2.0 * std::f64::consts::PI * ((i * 17) % n) as f64 / n as f64;
                LocalPoint::new(500.0 * a.cos(), 500.0 * a.sin())
            })
            .collect();
        let legs = Legs {
            base: LocalPoint::new(0.0, 0.0),
            cells: &cells,
            detours: None,
        };
        let tour = giant_tour(&legs, &ExplorationOptions::default()).unwrap();
        let mut sorted = tour.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..n).collect::<Vec<_>>());
        let polygon = n as f64 * 2.0 * 500.0 * (std::f64::consts::PI / n as f64).sin();
        assert!(
            (cycle_length(&legs, &tour) - polygon).abs() < 1e-6,
            "{}",
            cycle_length(&legs, &tour)
        );
    }

    #[test]
    fn elimination_merges_sorties_that_fit_together() {
        let m = paper();
        let cells = [
            LocalPoint::new(100.0, 0.0),
            LocalPoint::new(140.0, 0.0),
            LocalPoint::new(180.0, 0.0),
        ];
        let to_base: Vec<f64> = cells.iter().map(|c| m.energy_per_metre_j() * c.e).collect();
        let service = [m.service_energy_j(30.0); 3];
        let base = LocalPoint::new(0.0, 0.0);
        let legs = Legs {
            base,
            cells: &cells,
            detours: None,
        };
        let cost = SplitCost {
            legs: &legs,
            epm: m.energy_per_metre_j(),
            to_base: &to_base,
            service_j: &service,
            fixed_j: 0.0,
            budget: m.usable_budget_j(),
        };
        let merged = eliminate_sorties(&cost, vec![vec![1], vec![0], vec![2]]);
        assert_eq!(merged.len(), 1);
        let mut cells_visited = merged[0].clone();
        cells_visited.sort_unstable();
        assert_eq!(cells_visited, vec![0, 1, 2]);
        // Collinear cells: any out-and-back order flies 2 x 180 m.
        assert!((path_length(&legs, &merged[0]) - 360.0).abs() < 1e-9);
    }

    #[test]
    fn straight_detours_plan_the_same_sorties_and_blocked_legs_are_longer() {
        let m = paper();
        let cells = grid(6, 4);
        let service = vec![m.service_energy_j(30.0); cells.len()];
        let base = LocalPoint::new(0.0, 0.0);
        let mut pts = vec![base];
        pts.extend(cells.iter().copied());
        let straight = Detours::straight(&pts);
        let o = ExplorationOptions::default();
        let plain = plan_exploration(&m, base, &cells, &service, &o).unwrap();
        let routed =
            plan_exploration_routed(&m, base, &cells, &service, &o, Some(&straight)).unwrap();
        assert_eq!(plain.sorties.len(), routed.sorties.len());
        assert!(
            (plain.total_energy_j - routed.total_energy_j).abs() <= 1e-6 * plain.total_energy_j
        );
        // Every leg to cell 0 detours 30 m north: the plan flies them and prices them.
        let detour = Detours::new(&pts, |i, j| {
            Some(if i == 1 || j == 1 {
                vec![LocalPoint::new(
                    0.5 * (pts[i].e + pts[j].e),
                    30.0 + pts[i].n.max(pts[j].n),
                )]
            } else {
                Vec::new()
            })
        });
        let p = plan_exploration_routed(&m, base, &cells, &service, &o, Some(&detour)).unwrap();
        assert!(p.total_energy_j > plain.total_energy_j);
        let mut seen: Vec<usize> = p.sorties.iter().flat_map(|s| s.cells.clone()).collect();
        seen.sort_unstable();
        assert_eq!(seen, (0..cells.len()).collect::<Vec<_>>());
        let err = plan_exploration_routed(&m, base, &cells[1..], &service[1..], &o, Some(&detour));
        assert!(err.is_err(), "detours over the wrong node count");
    }

    #[test]
    fn deterministic() {
        let m = paper();
        let cells = grid(7, 5);
        let hover = vec![45.0; 35];
        let a = plan(&m, LocalPoint::new(0.0, 0.0), &cells, &hover);
        let b = plan(&m, LocalPoint::new(0.0, 0.0), &cells, &hover);
        assert_eq!(a, b);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        #[test]
        fn every_cell_once_every_sortie_feasible(
            pts in prop::collection::vec((-600.0f64..600.0, -600.0f64..600.0, 0.0f64..120.0), 0..60),
            vertical in any::<bool>(),
        ) {
            let cfg = EnergyConfig { vertical: vertical.then(VerticalConfig::default), ..EnergyConfig::paper() };
            let m = MissionEnergyModel::new(&cfg).unwrap();
            let cells: Vec<LocalPoint> = pts.iter().map(|&(e, n, _)| LocalPoint::new(e, n)).collect();
            let hover: Vec<f64> = pts.iter().map(|&(_, _, h)| h).collect();
            let base = LocalPoint::new(0.0, 0.0);
            let p = plan(&m, base, &cells, &hover);
            check_plan(&m, base, &cells, &hover, &p);
        }
    }
}
