//! Orienteering with a set-function objective: the value of a route is `f(visited nodes)`,
//! not a sum of fixed node rewards, so a node's worth depends on what else the route visits
//! (e.g. information: two correlated sites tell less together than apart). For monotone
//! submodular `f` this is submodular orienteering; the search here is marginal-gain
//! insertion plus exchange local search, with every route re-checked against the budget.

use crate::engine::Ctx;
use crate::improve::{ImproveOptions, improve_routes_in};
use crate::problem::Problem;
use crate::solution::{Solution, evaluate};

/// Settings of [`solve_marginal`].
#[derive(Debug, Clone, PartialEq)]
pub struct MarginalOptions {
    /// Rounds of exchange local search (each tries every visited × unvisited pair once).
    pub max_rounds: usize,
    /// Route improvement (2-opt, Or-opt) after each insertion or exchange.
    pub improve: ImproveOptions,
}

impl Default for MarginalOptions {
    /// 20 exchange rounds, the default route improvement.
    fn default() -> Self {
        Self {
            max_rounds: 20,
            improve: ImproveOptions::default(),
        }
    }
}

/// A route chosen by [`solve_marginal`] and its objective value.
#[derive(Debug, Clone)]
pub struct MarginalSolution {
    /// The route `[start, .., end]` with its cost (rewards as in the problem).
    pub solution: Solution,
    /// `f` of the visited nodes (terminals excluded).
    pub value: f64,
}

/// Maximises `f(visited)` over single routes within `problem`'s budget.
///
/// Eligible nodes are those with a positive reward in `problem` (the rewards only say which
/// nodes may be visited), terminals excluded; `f` gets the visited eligible nodes in route
/// order and must be finite. Search: two greedy constructions — largest marginal gain per
/// extra cost at the cheapest insertion position, and largest marginal gain — each followed
/// by route shortening and exchange local search (remove one visited node, insert one or
/// more unvisited ones, keep the change when `f` grows and the route fits), the better kept.
/// Deterministic. The route is re-validated by [`evaluate`].
pub fn solve_marginal<F: FnMut(&[usize]) -> f64>(
    problem: &Problem,
    mut f: F,
    options: &MarginalOptions,
) -> MarginalSolution {
    let reachable = problem.reachable_candidates();
    // Route shortening's context (candidates, neighbour lists), built once: it depends only
    // on the problem and the neighbour count.
    let ctx = Ctx::new(problem, options.improve.neighbours.max(1), true);
    let s = Search {
        problem,
        ctx: &ctx,
        options,
    };
    let empty = vec![problem.start(), problem.end()];
    let mut best: Option<(Vec<usize>, f64)> = None;
    for by_ratio in [true, false] {
        let mut route = empty.clone();
        grow(&s, &mut route, &reachable, &mut f, by_ratio);
        exchange(&s, &mut route, &reachable, &mut f);
        let value = f(interior(&route));
        if best
            .as_ref()
            .is_none_or(|(_, v)| value > *v + 1e-12 * v.abs())
        {
            best = Some((route, value));
        }
    }
    let (route, value) = best.unwrap_or((empty, 0.0));
    let solution = evaluate(problem, &[route]).expect("every route kept fits the budget");
    MarginalSolution { solution, value }
}

fn interior(route: &[usize]) -> &[usize] {
    &route[1..route.len() - 1]
}

fn cost(problem: &Problem, route: &[usize]) -> f64 {
    let mut c: f64 = route.windows(2).map(|w| problem.cost(w[0], w[1])).sum();
    for (k, &v) in route.iter().enumerate() {
        if k + 1 == route.len() && v == route[0] {
            break; // a closed tour pays its depot once
        }
        c += problem.service(v);
    }
    c
}

/// Cheapest insertion of `v`: (position, extra cost).
fn cheapest(problem: &Problem, route: &[usize], v: usize) -> (usize, f64) {
    let mut best = (1, f64::INFINITY);
    for k in 1..route.len() {
        let (a, b) = (route[k - 1], route[k]);
        let d = problem.cost(a, v) + problem.cost(v, b) - problem.cost(a, b) + problem.service(v);
        if d < best.1 {
            best = (k, d);
        }
    }
    best
}

/// What every step of the search shares: the problem, route shortening's context, options.
struct Search<'a> {
    problem: &'a Problem,
    ctx: &'a Ctx<'a>,
    options: &'a MarginalOptions,
}

fn shorten(search: &Search<'_>, route: &mut Vec<usize>) {
    if let Ok(s) = improve_routes_in(
        search.ctx,
        search.problem,
        std::slice::from_ref(route),
        &search.options.improve,
    ) && let Some(r) = s.routes.into_iter().next()
    {
        *route = r;
    }
}

/// Greedy insertion until nothing with a positive gain fits.
fn grow<F: FnMut(&[usize]) -> f64>(
    search: &Search<'_>,
    route: &mut Vec<usize>,
    candidates: &[usize],
    f: &mut F,
    by_ratio: bool,
) {
    let problem = search.problem;
    let limit = problem.budget() + problem.tolerance();
    loop {
        let used = cost(problem, route);
        let base = f(interior(route));
        let mut pick: Option<(usize, usize, f64)> = None;
        let mut trial = Vec::with_capacity(route.len() + 1);
        for &v in candidates {
            if route.contains(&v) {
                continue;
            }
            let (pos, extra) = cheapest(problem, route, v);
            if used + extra > limit {
                continue;
            }
            trial.clear();
            trial.extend_from_slice(route);
            trial.insert(pos, v);
            let gain = f(interior(&trial)) - base;
            if gain.is_nan() || gain <= 0.0 {
                continue;
            }
            let score = if by_ratio {
                gain / extra.max(1e-12)
            } else {
                gain
            };
            if pick.is_none_or(|(_, _, s)| score > s) {
                pick = Some((v, pos, score));
            }
        }
        let Some((v, pos, _)) = pick else { break };
        route.insert(pos, v);
        shorten(search, route);
    }
}

/// Exchange local search: drop one visited node, refill greedily by gain per cost; keep
/// when the value grows.
fn exchange<F: FnMut(&[usize]) -> f64>(
    search: &Search<'_>,
    route: &mut Vec<usize>,
    candidates: &[usize],
    f: &mut F,
) {
    let (problem, options) = (search.problem, search.options);
    let limit = problem.budget() + problem.tolerance();
    for _ in 0..options.max_rounds {
        let current = f(interior(route));
        let mut improved = false;
        'outer: for k in 1..route.len() - 1 {
            let removed = route[k];
            for &w in candidates {
                if route.contains(&w) {
                    continue;
                }
                let mut trial = route.clone();
                trial.remove(k);
                let (pos, extra) = cheapest(problem, &trial, w);
                if cost(problem, &trial) + extra > limit {
                    continue;
                }
                trial.insert(pos, w);
                shorten(search, &mut trial);
                let others: Vec<usize> = candidates
                    .iter()
                    .copied()
                    .filter(|&c| c != removed)
                    .collect();
                grow(search, &mut trial, &others, f, true);
                let value = f(interior(&trial));
                if value > current + 1e-12 * current.abs().max(1e-300) {
                    *route = trial;
                    improved = true;
                    break 'outer;
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
    use crate::problem::Metric;

    #[test]
    fn additive_objective_matches_the_exact_optimum() {
        // With f = sum of rewards, the set-function search must find what exact finds here.
        let points: Vec<[f64; 2]> = (0..12)
            .map(|i| {
                let a = i as f64 * 0.9;
                [30.0 * a.cos() + i as f64, 30.0 * a.sin()]
            })
            .collect();
        let rewards: Vec<f64> = (0..12)
            .map(|i| if i == 0 { 0.0 } else { 1.0 + (i % 4) as f64 })
            .collect();
        let p = Problem::from_points(&points, Metric::Euclidean, rewards.clone(), 120.0).unwrap();
        let exact = crate::exact(&p).unwrap();
        let got = solve_marginal(
            &p,
            |s| s.iter().map(|&v| rewards[v]).sum(),
            &MarginalOptions::default(),
        );
        assert!(got.solution.costs[0] <= 120.0 + 1e-9);
        assert!(
            (got.value - exact.reward).abs() < 1e-9,
            "{} vs {}",
            got.value,
            exact.reward
        );
    }

    #[test]
    fn redundant_nodes_are_not_both_taken() {
        // Nodes 1 and 2 sit together and tell the same (f counts the pair once); node 3 is
        // farther but new: with budget for two sites, the route takes one of 1/2 and 3.
        let points = [[0.0, 0.0], [10.0, 0.0], [10.0, 1.0], [0.0, 15.0]];
        let p = Problem::from_points(&points, Metric::Euclidean, vec![0.0, 1.0, 1.0, 1.0], 50.0)
            .unwrap();
        let f = |s: &[usize]| {
            let a = s.iter().any(|&v| v == 1 || v == 2) as u8 as f64;
            let b = s.contains(&3) as u8 as f64;
            a + b
        };
        let got = solve_marginal(&p, f, &MarginalOptions::default());
        assert_eq!(got.value, 2.0);
        assert!(got.solution.routes[0].contains(&3));
    }
}
