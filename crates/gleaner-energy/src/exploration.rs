//! Exploration phase (SPEC §5 step 3): visit every cell in as few budget-feasible sorties as
//! possible.
//!
//! Route-first, cluster-second: a short closed tour through all cells (nearest neighbour,
//! then 2-opt over each cell's nearest neighbours), then the optimal split of that giant tour
//! into consecutive sorties B -> ... -> B (Beasley 1983's split, solved by dynamic
//! programming on the tour positions), minimising first the number of sorties, then their total
//! energy. Every rotation, in both directions, of that tour and of a polar sweep around the base
//! is split and the best kept. Each sortie's order is then improved by 2-opt (which only lowers
//! its energy), and sorties are emptied where all their cells fit into the others (cheapest
//! feasible insertion). Then, for a few rounds, cells are moved or swapped between sorties
//! while that lowers the total energy, and emptying sorties is tried again. (Tried and dropped
//! as not better on grid fields: a cheapest-insertion construction seeded by the farthest
//! cell, and pricing split segments by cheapest insertion instead of tour order.)
//!
//! On a 32 x 32 grid of 40 m cells with 30 s hovers (paper preset) this gives 147 sorties from
//! a corner base (lower bound 129) and 108 from the centre (lower bound 97).
//!
//! Sortie energy = fixed (climb/descent) + cruise energy of its legs + the cells' service
//! energies, exactly as [`MissionEnergyModel::breakdown`] computes it.
//!
//! ```
//! use gleaner_energy::exploration::{ExplorationOptions, plan_exploration};
//! use gleaner_energy::{EnergyConfig, MissionEnergyModel};
//! use gleaner_field::LocalPoint;
//!
//! let model = MissionEnergyModel::new(&EnergyConfig::paper()).unwrap();
//! // 30 cells of 40 m in a row; each hover costs 30 s at P(0) + P_rx.
//! let cells: Vec<LocalPoint> = (0..30).map(|i| LocalPoint::new(20.0 + 40.0 * i as f64, 20.0)).collect();
//! let service = vec![model.service_energy_j(30.0); cells.len()];
//! let plan = plan_exploration(&model, LocalPoint::new(0.0, 0.0), &cells, &service, &ExplorationOptions::default()).unwrap();
//! assert!(plan.sorties.len() >= plan.lower_bound_sorties);
//! assert!(plan.sorties.iter().all(|s| s.energy_j <= model.usable_budget_j()));
//! ```

use gleaner_field::LocalPoint;

use crate::error::{EnergyError, non_negative};
use crate::mission::{MissionEnergyModel, distance_m};

/// Tuning of the exploration planner.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExplorationOptions {
    /// Candidate neighbours per cell in the 2-opt of the giant tour (default 12).
    pub neighbours: usize,
    /// Maximum 2-opt passes over the giant tour (default 200).
    pub max_two_opt_passes: usize,
    /// Relative safety margin on the budget, so that float rounding never makes a planned
    /// sortie infeasible when re-checked (default 1e-9: sorties use at most
    /// budget·(1 − 1e-9)).
    pub budget_margin: f64,
    /// After the split, try to empty whole sorties by moving their cells into the others at
    /// the cheapest feasible position (default true).
    pub eliminate_sorties: bool,
    /// Rounds of inter-sortie improvement (move or swap single cells between sorties while
    /// that lowers the energy, then try to empty sorties again); 0 disables it (default 50).
    pub max_improvement_rounds: usize,
}

impl Default for ExplorationOptions {
    fn default() -> Self {
        Self {
            neighbours: 12,
            max_two_opt_passes: 200,
            budget_margin: 1e-9,
            eliminate_sorties: true,
            max_improvement_rounds: 50,
        }
    }
}

/// One sortie of the exploration phase.
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
    /// fixed_j + travel_j + service_j, J.
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

/// Plans the fewest budget-feasible sorties from `base` that together visit every cell of
/// `cells` (centres, local metres) with service energies `service_j` (J), then the least total
/// energy for that number of sorties (for the tour found; the split is optimal for it).
///
/// # Errors
/// [`EnergyError::LengthMismatch`] if the slices differ in length;
/// [`EnergyError::InvalidParameter`] for a non-finite position or a negative / non-finite
/// service energy or invalid options; [`EnergyError::CellUnreachable`] if some cell cannot be
/// served even alone.
pub fn plan_exploration(
    model: &MissionEnergyModel,
    base: LocalPoint,
    cells: &[LocalPoint],
    service_j: &[f64],
    options: &ExplorationOptions,
) -> Result<ExplorationPlan, EnergyError> {
    if cells.len() != service_j.len() {
        return Err(EnergyError::LengthMismatch {
            what: "cell centres vs service energies",
            left: cells.len(),
            right: service_j.len(),
        });
    }
    for p in cells.iter().chain(std::iter::once(&base)) {
        crate::error::finite("cell or base easting (m)", p.e)?;
        crate::error::finite("cell or base northing (m)", p.n)?;
    }
    for &s in service_j {
        non_negative("cell service energy (J)", s)?;
    }
    if !(options.budget_margin >= 0.0 && options.budget_margin < 1.0) {
        return Err(EnergyError::InvalidParameter {
            name: "budget margin",
            value: options.budget_margin,
            expected: "a number in [0, 1)",
        });
    }
    let n = cells.len();
    let fixed_j = model.sortie_fixed_j();
    let budget = model.usable_budget_j() * (1.0 - options.budget_margin);
    let epm = model.energy_per_metre_j();
    let to_base: Vec<f64> = cells.iter().map(|c| epm * distance_m(c, &base)).collect();
    for i in 0..n {
        let alone = fixed_j + 2.0 * to_base[i] + service_j[i];
        if alone > budget {
            return Err(EnergyError::CellUnreachable {
                cell: i,
                energy_j: alone,
                budget_j: model.usable_budget_j(),
            });
        }
    }
    let lower_bound_sorties = sortie_lower_bound(&to_base, service_j, budget - fixed_j);
    let tour = giant_tour(cells, options);
    let giant_tour_m = cycle_length(cells, &tour);
    let sweep = sweep_order(cells, base);

    let cost = SplitCost {
        cells,
        epm,
        to_base: &to_base,
        service_j,
        fixed_j,
        budget,
    };
    let mut best: Option<(usize, f64, Vec<Vec<usize>>)> = None;
    let mut sequence = Vec::with_capacity(n);
    for candidate in [&tour, &sweep] {
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
    let mut groups = best.map(|b| b.2).unwrap_or_default();
    for g in &mut groups {
        improve_sortie(cells, base, g);
    }
    if options.eliminate_sorties {
        groups = eliminate_sorties(&cost, base, groups);
    }
    for _ in 0..options.max_improvement_rounds {
        let moved = relocate_cells(&cost, base, &mut groups, options.max_two_opt_passes);
        let before = groups.len();
        if options.eliminate_sorties {
            groups = eliminate_sorties(&cost, base, groups);
        }
        if !moved && groups.len() == before {
            break;
        }
    }
    let sorties: Vec<Sortie> = groups
        .into_iter()
        .filter(|g| !g.is_empty())
        .map(|mut g| {
            improve_sortie(cells, base, &mut g);
            let distance_m = path_length(cells, base, &g);
            let travel_j = epm * distance_m;
            let service: f64 = g.iter().map(|&c| service_j[c]).sum();
            Sortie {
                cells: g,
                distance_m,
                travel_j,
                service_j: service,
                fixed_j,
                energy_j: fixed_j + travel_j + service,
            }
        })
        .collect();
    let total_energy_j = sorties.iter().map(|s| s.energy_j).sum();
    Ok(ExplorationPlan {
        sorties,
        lower_bound_sorties,
        total_energy_j,
        giant_tour_m,
    })
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

/// Moves single cells to the cheapest feasible position in another sortie, or else swaps them
/// with a cell of another sortie, while that lowers the total energy (best move per cell, at
/// most `max_passes` passes over all cells); a sortie left empty is dropped. Returns whether
/// anything moved.
fn relocate_cells(
    cost: &SplitCost<'_>,
    base: LocalPoint,
    groups: &mut Vec<Vec<usize>>,
    max_passes: usize,
) -> bool {
    let at = |g: &[usize], pos: usize| -> LocalPoint {
        // Path position pos in 0..=len+1, with 0 and len+1 the base.
        if pos == 0 || pos > g.len() {
            base
        } else {
            cost.cells[g[pos - 1]]
        }
    };
    let mut energies: Vec<f64> = groups
        .iter()
        .map(|g| sortie_energy(cost, base, g))
        .collect();
    let mut any = false;
    for _ in 0..max_passes {
        let mut moved = false;
        let mut a = 0;
        while a < groups.len() {
            let mut i = 0;
            while i < groups[a].len() {
                let c = groups[a][i];
                let p = cost.cells[c];
                let (prev, next) = (at(&groups[a], i), at(&groups[a], i + 2));
                let gain = cost.epm
                    * (distance_m(&prev, &p) + distance_m(&p, &next) - distance_m(&prev, &next));
                let mut best: Option<(f64, usize, usize)> = None;
                for (b, g) in groups.iter().enumerate() {
                    if b == a {
                        continue;
                    }
                    for pos in 0..=g.len() {
                        let (u, v) = (at(g, pos), at(g, pos + 1));
                        let ins = cost.epm
                            * (distance_m(&u, &p) + distance_m(&p, &v) - distance_m(&u, &v));
                        if ins < gain - 1e-9 * (1.0 + gain)
                            && energies[b] + ins + cost.service_j[c] <= cost.budget
                            && best.is_none_or(|x| ins < x.0)
                        {
                            best = Some((ins, b, pos));
                        }
                    }
                }
                let Some((_, b, pos)) = best else {
                    if swap_best(cost, base, groups, &mut energies, a, i) {
                        moved = true;
                    }
                    i += 1;
                    continue;
                };
                groups[b].insert(pos, c);
                let exact = sortie_energy(cost, base, &groups[b]);
                if exact > cost.budget {
                    // Float rounding: undo.
                    groups[b].remove(pos);
                    i += 1;
                    continue;
                }
                energies[b] = exact;
                groups[a].remove(i);
                energies[a] = sortie_energy(cost, base, &groups[a]);
                moved = true;
            }
            if groups[a].is_empty() {
                groups.remove(a);
                energies.remove(a);
            } else {
                a += 1;
            }
        }
        any |= moved;
        if !moved {
            break;
        }
    }
    if any {
        for g in groups.iter_mut() {
            improve_sortie(cost.cells, base, g);
        }
    }
    any
}

/// Exchanges cell `groups[a][i]` with the cell of another sortie (each taking the other's
/// position) that lowers the total energy most while both sorties stay within budget.
/// Returns whether a swap was made.
fn swap_best(
    cost: &SplitCost<'_>,
    base: LocalPoint,
    groups: &mut [Vec<usize>],
    energies: &mut [f64],
    a: usize,
    i: usize,
) -> bool {
    let at = |g: &[usize], pos: usize| -> LocalPoint {
        if pos == 0 || pos > g.len() {
            base
        } else {
            cost.cells[g[pos - 1]]
        }
    };
    // Energy change of sortie g when the cell at index k is replaced by cell `by`.
    let replace = |g: &[usize], k: usize, by: usize| -> f64 {
        let (u, v) = (at(g, k), at(g, k + 2));
        let (old, new) = (cost.cells[g[k]], cost.cells[by]);
        cost.epm
            * (distance_m(&u, &new) + distance_m(&new, &v)
                - distance_m(&u, &old)
                - distance_m(&old, &v))
            + cost.service_j[by]
            - cost.service_j[g[k]]
    };
    let c = groups[a][i];
    let mut best: Option<(f64, usize, usize)> = None;
    for (b, g) in groups.iter().enumerate() {
        if b == a {
            continue;
        }
        for (k, &d) in g.iter().enumerate() {
            let da = replace(&groups[a], i, d);
            let db = replace(g, k, c);
            let total = da + db;
            if total < -1e-9 * (1.0 + energies[a] + energies[b])
                && energies[a] + da <= cost.budget
                && energies[b] + db <= cost.budget
                && best.is_none_or(|x| total < x.0)
            {
                best = Some((total, b, k));
            }
        }
    }
    let Some((_, b, k)) = best else { return false };
    let d = groups[b][k];
    groups[a][i] = d;
    groups[b][k] = c;
    let (ea, eb) = (
        sortie_energy(cost, base, &groups[a]),
        sortie_energy(cost, base, &groups[b]),
    );
    if ea > cost.budget || eb > cost.budget {
        // Float rounding: undo.
        groups[a][i] = c;
        groups[b][k] = d;
        return false;
    }
    energies[a] = ea;
    energies[b] = eb;
    true
}

/// Energy of the sortie base -> order -> base, J.
fn sortie_energy(cost: &SplitCost<'_>, base: LocalPoint, order: &[usize]) -> f64 {
    if order.is_empty() {
        return 0.0;
    }
    let service: f64 = order.iter().map(|&c| cost.service_j[c]).sum();
    cost.fixed_j + cost.epm * path_length(cost.cells, base, order) + service
}

/// Repeatedly tries to empty a sortie (fewest cells first) by inserting each of its cells,
/// farthest first, at the cheapest feasible position of another sortie; commits when all fit.
fn eliminate_sorties(
    cost: &SplitCost<'_>,
    base: LocalPoint,
    mut groups: Vec<Vec<usize>>,
) -> Vec<Vec<usize>> {
    let at = |c: Option<usize>| c.map_or(base, |c| cost.cells[c]);
    loop {
        let energies: Vec<f64> = groups
            .iter()
            .map(|g| sortie_energy(cost, base, g))
            .collect();
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
                let p = cost.cells[c];
                let mut best: Option<(f64, usize, usize)> = None;
                for (k, g) in trial.iter().enumerate() {
                    if k == r || g.is_empty() {
                        continue;
                    }
                    for pos in 0..=g.len() {
                        let prev = at(pos.checked_sub(1).map(|q| g[q]));
                        let next = at(g.get(pos).copied());
                        let delta = cost.epm
                            * (distance_m(&prev, &p) + distance_m(&p, &next)
                                - distance_m(&prev, &next))
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
                trial_energy[k] = sortie_energy(cost, base, &trial[k]);
                if trial_energy[k] > cost.budget {
                    continue 'attempt;
                }
            }
            trial.remove(r);
            done = Some(trial);
            break;
        }
        match done {
            Some(mut g) => {
                for order in &mut g {
                    improve_sortie(cost.cells, base, order);
                }
                groups = g;
            }
            None => return groups,
        }
    }
}

/// Everything the split DP needs, in J.
struct SplitCost<'a> {
    cells: &'a [LocalPoint],
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
                    path += self.epm * distance_m(&self.cells[seq[j - 1]], &self.cells[seq[j]]);
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

fn cycle_length(cells: &[LocalPoint], tour: &[usize]) -> f64 {
    let n = tour.len();
    (0..n)
        .map(|k| distance_m(&cells[tour[k]], &cells[tour[(k + 1) % n]]))
        .sum()
}

fn path_length(cells: &[LocalPoint], base: LocalPoint, order: &[usize]) -> f64 {
    let mut previous = base;
    let mut total = 0.0;
    for &c in order {
        total += distance_m(&previous, &cells[c]);
        previous = cells[c];
    }
    total + distance_m(&previous, &base)
}

/// A closed tour through all cells: nearest neighbour from cell 0, then neighbour-list 2-opt.
fn giant_tour(cells: &[LocalPoint], options: &ExplorationOptions) -> Vec<usize> {
    let n = cells.len();
    if n < 4 {
        return (0..n).collect();
    }
    let d = |a: usize, b: usize| distance_m(&cells[a], &cells[b]);
    // Nearest neighbour construction.
    let mut tour = Vec::with_capacity(n);
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
    // Candidate lists: the k nearest other cells of each cell.
    let k = options.neighbours.clamp(1, n - 1);
    let near: Vec<Vec<usize>> = (0..n)
        .map(|a| {
            let mut others: Vec<usize> = (0..n).filter(|&b| b != a).collect();
            others.select_nth_unstable_by(k - 1, |&x, &y| {
                d(a, x).total_cmp(&d(a, y)).then(x.cmp(&y))
            });
            others.truncate(k);
            others.sort_by(|&x, &y| d(a, x).total_cmp(&d(a, y)).then(x.cmp(&y)));
            others
        })
        .collect();
    let mut pos = vec![0usize; n];
    for (p, &c) in tour.iter().enumerate() {
        pos[c] = p;
    }
    for _ in 0..options.max_two_opt_passes {
        let mut improved = false;
        for p in 0..n {
            let a = tour[p];
            let b = tour[(p + 1) % n];
            let dab = d(a, b);
            for &c in &near[a] {
                let dac = d(a, c);
                if dac >= dab {
                    break;
                }
                let q = pos[c];
                let dd = tour[(q + 1) % n];
                if c == b || dd == a {
                    continue;
                }
                let gain = dab + d(c, dd) - dac - d(b, dd);
                if gain > 1e-10 * (1.0 + dab) {
                    // Edges (a,b) at p and (c,dd) at q become (a,c) and (b,dd): reverse the
                    // tour between them.
                    let (lo, hi) = if p < q { (p, q) } else { (q, p) };
                    tour[lo + 1..=hi].reverse();
                    for (r, &city) in tour.iter().enumerate().take(hi + 1).skip(lo + 1) {
                        pos[city] = r;
                    }
                    improved = true;
                    break;
                }
            }
        }
        if !improved {
            break;
        }
    }
    tour
}

/// 2-opt on one sortie's path with both ends fixed at the base, to a local optimum.
fn improve_sortie(cells: &[LocalPoint], base: LocalPoint, order: &mut [usize]) {
    let m = order.len();
    if m < 2 {
        return;
    }
    let at = |order: &[usize], k: usize| -> LocalPoint {
        if k == 0 || k == m + 1 {
            base
        } else {
            cells[order[k - 1]]
        }
    };
    // Path positions 0..=m+1 with 0 and m+1 the base; reverse positions i+1..=j.
    for _ in 0..100 {
        let mut improved = false;
        for i in 0..m {
            for j in (i + 2)..=m {
                let (a, b) = (at(order, i), at(order, i + 1));
                let (c, dd) = (at(order, j), at(order, j + 1));
                let gain = distance_m(&a, &b) + distance_m(&c, &dd)
                    - distance_m(&a, &c)
                    - distance_m(&b, &dd);
                if gain > 1e-10 * (1.0 + distance_m(&a, &b)) {
                    order[i..j].reverse();
                    improved = true;
                }
            }
        }
        if !improved {
            break;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::{EnergyConfig, VerticalConfig};
    use crate::mission::CellVisit;
    use proptest::prelude::*;

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
        let m = MissionEnergyModel::new(&EnergyConfig::paper()).unwrap();
        let p = plan(&m, LocalPoint::new(0.0, 0.0), &[], &[]);
        assert!(p.sorties.is_empty() && p.lower_bound_sorties == 0 && p.total_energy_j == 0.0);
    }

    #[test]
    fn small_field_fits_one_sortie() {
        let m = MissionEnergyModel::new(&EnergyConfig::paper()).unwrap();
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
        let m = MissionEnergyModel::new(&EnergyConfig::paper()).unwrap();
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
        let m = MissionEnergyModel::new(&EnergyConfig::paper()).unwrap();
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
            matches!(err, EnergyError::CellUnreachable { cell: 1, .. }),
            "{err}"
        );
    }

    #[test]
    fn bad_inputs_are_rejected() {
        let m = MissionEnergyModel::new(&EnergyConfig::paper()).unwrap();
        let base = LocalPoint::new(0.0, 0.0);
        let o = ExplorationOptions::default();
        assert!(plan_exploration(&m, base, &[base], &[], &o).is_err());
        assert!(plan_exploration(&m, base, &[base], &[-1.0], &o).is_err());
        assert!(plan_exploration(&m, base, &[LocalPoint::new(f64::NAN, 0.0)], &[1.0], &o).is_err());
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
    fn two_opt_untangles_points_on_a_circle() {
        // 40 points on a circle of radius 500 m in scrambled order: the optimal tour is the
        // polygon, and 2-opt reaches it from any tour without crossings.
        let n = 40;
        let cells: Vec<LocalPoint> = (0..n)
            .map(|i| {
                let a = 2.0 * std::f64::consts::PI * ((i * 17) % n) as f64 / n as f64;
                LocalPoint::new(500.0 * a.cos(), 500.0 * a.sin())
            })
            .collect();
        let tour = giant_tour(&cells, &ExplorationOptions::default());
        let mut sorted = tour.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..n).collect::<Vec<_>>());
        let polygon = n as f64 * 2.0 * 500.0 * (std::f64::consts::PI / n as f64).sin();
        assert!(
            (cycle_length(&cells, &tour) - polygon).abs() < 1e-6,
            "{}",
            cycle_length(&cells, &tour)
        );
    }

    #[test]
    fn elimination_merges_sorties_that_fit_together() {
        let m = MissionEnergyModel::new(&EnergyConfig::paper()).unwrap();
        let cells = [
            LocalPoint::new(100.0, 0.0),
            LocalPoint::new(140.0, 0.0),
            LocalPoint::new(180.0, 0.0),
        ];
        let to_base: Vec<f64> = cells.iter().map(|c| m.energy_per_metre_j() * c.e).collect();
        let service = [m.service_energy_j(30.0); 3];
        let cost = SplitCost {
            cells: &cells,
            epm: m.energy_per_metre_j(),
            to_base: &to_base,
            service_j: &service,
            fixed_j: 0.0,
            budget: m.usable_budget_j(),
        };
        let base = LocalPoint::new(0.0, 0.0);
        let merged = eliminate_sorties(&cost, base, vec![vec![1], vec![0], vec![2]]);
        assert_eq!(merged.len(), 1);
        let mut cells_visited = merged[0].clone();
        cells_visited.sort_unstable();
        assert_eq!(cells_visited, vec![0, 1, 2]);
        // Collinear cells: any out-and-back order flies 2 x 180 m.
        assert!((path_length(&cells, base, &merged[0]) - 360.0).abs() < 1e-9);
    }

    #[test]
    fn relocation_regroups_crossed_sorties() {
        // Two cells east and two west, assigned crosswise: moving cells between the sorties
        // must end with one sortie per side.
        let m = MissionEnergyModel::new(&EnergyConfig::paper()).unwrap();
        let cells = [
            LocalPoint::new(500.0, 0.0),
            LocalPoint::new(-500.0, 0.0),
            LocalPoint::new(540.0, 0.0),
            LocalPoint::new(-540.0, 0.0),
        ];
        let to_base: Vec<f64> = cells
            .iter()
            .map(|c| m.energy_per_metre_j() * c.e.abs())
            .collect();
        let service = [m.service_energy_j(30.0); 4];
        let cost = SplitCost {
            cells: &cells,
            epm: m.energy_per_metre_j(),
            to_base: &to_base,
            service_j: &service,
            fixed_j: 0.0,
            // Crossed sorties fit (34.8 kJ, 36.8 kJ), three cells never do (>= 41.8 kJ).
            budget: 37_000.0,
        };
        let base = LocalPoint::new(0.0, 0.0);
        let mut groups = vec![vec![0, 1], vec![2, 3]];
        assert!(
            groups
                .iter()
                .all(|g| sortie_energy(&cost, base, g) <= cost.budget)
        );
        let before: f64 = groups.iter().map(|g| sortie_energy(&cost, base, g)).sum();
        assert!(relocate_cells(&cost, base, &mut groups, 10));
        let after: f64 = groups.iter().map(|g| sortie_energy(&cost, base, g)).sum();
        assert!(after < before);
        let mut sides: Vec<Vec<usize>> = groups
            .iter()
            .map(|g| {
                let mut g = g.clone();
                g.sort_unstable();
                g
            })
            .collect();
        sides.sort();
        assert_eq!(sides, vec![vec![0, 2], vec![1, 3]]);
        assert!(
            groups
                .iter()
                .all(|g| sortie_energy(&cost, base, g) <= cost.budget)
        );
    }

    #[test]
    fn deterministic() {
        let m = MissionEnergyModel::new(&EnergyConfig::paper()).unwrap();
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
