//! Solutions and their independent re-validation.

use crate::error::SolutionError;
use crate::problem::Problem;

/// A feasible set of routes with its reward and per-route costs.
///
/// Every route lists its nodes in visiting order, starting with the problem's start node and
/// ending with its end node (both present even when equal, so a closed tour from 0 that
/// visits nothing is `[0, 0]`). Costs are in the problem's budget unit.
#[derive(Debug, Clone, PartialEq)]
pub struct Solution {
    /// Node sequences, one per vehicle used (always `vehicles` routes, some possibly empty).
    pub routes: Vec<Vec<usize>>,
    /// Total reward collected (terminals counted once).
    pub reward: f64,
    /// Cost of each route: travel + service (budget unit).
    pub costs: Vec<f64>,
}

impl Solution {
    /// The solution that visits nothing: every route goes straight from start to end.
    pub fn empty(problem: &Problem) -> Solution {
        Solution {
            routes: vec![vec![problem.start(), problem.end()]; problem.vehicles()],
            reward: problem.terminal_reward(),
            costs: vec![problem.empty_route_cost(); problem.vehicles()],
        }
    }

    /// Total cost over all routes (budget unit).
    pub fn total_cost(&self) -> f64 {
        self.costs.iter().sum()
    }

    /// Number of nodes visited, excluding start and end.
    pub fn visited(&self) -> usize {
        self.routes.iter().map(|r| r.len().saturating_sub(2)).sum()
    }
}

/// Cost of one route (travel + service of every node on it, budget unit). Does not validate.
/// A closed tour `[s, .., s]` pays the service of `s` once.
pub fn route_cost(problem: &Problem, route: &[usize]) -> f64 {
    if route.is_empty() {
        return 0.0;
    }
    let mut c = 0.0;
    for w in route.windows(2) {
        c += problem.cost(w[0], w[1]);
    }
    let last = route.len() - 1;
    for (k, &v) in route.iter().enumerate() {
        if k == last && last > 0 && v == route[0] {
            continue;
        }
        c += problem.service(v);
    }
    c
}

/// Re-validates `routes` against `problem` and returns the evaluated [`Solution`].
///
/// Checks: at most `vehicles` routes, each from start to end, node indices in range, no node
/// visited twice overall (terminals only at the ends of routes), each route's cost within the
/// budget plus [`Problem::tolerance`]. Missing routes are filled with empty ones.
pub fn evaluate(problem: &Problem, routes: &[Vec<usize>]) -> Result<Solution, SolutionError> {
    if routes.len() > problem.vehicles() {
        return Err(SolutionError::TooManyRoutes {
            routes: routes.len(),
            vehicles: problem.vehicles(),
        });
    }
    let n = problem.len();
    let mut seen = vec![false; n];
    let mut reward = problem.terminal_reward();
    let mut costs = Vec::with_capacity(problem.vehicles());
    let mut out = Vec::with_capacity(problem.vehicles());
    for (ri, route) in routes.iter().enumerate() {
        let first = route.first().copied();
        let last = route.last().copied();
        if route.len() < 2 || first != Some(problem.start()) || last != Some(problem.end()) {
            return Err(SolutionError::BadEndpoints {
                route: ri,
                start: problem.start(),
                end: problem.end(),
                first,
                last,
            });
        }
        for &v in &route[1..route.len() - 1] {
            if v >= n {
                return Err(SolutionError::NodeOutOfRange {
                    route: ri,
                    node: v,
                    nodes: n,
                });
            }
            if seen[v] || problem.is_terminal(v) {
                return Err(SolutionError::Duplicate { route: ri, node: v });
            }
            seen[v] = true;
            reward += problem.reward(v);
        }
        let c = route_cost(problem, route);
        if c > problem.budget() + problem.tolerance() {
            return Err(SolutionError::OverBudget {
                route: ri,
                cost: c,
                budget: problem.budget(),
            });
        }
        costs.push(c);
        out.push(route.clone());
    }
    while out.len() < problem.vehicles() {
        out.push(vec![problem.start(), problem.end()]);
        costs.push(problem.empty_route_cost());
    }
    Ok(Solution {
        routes: out,
        reward,
        costs,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::problem::Metric;

    fn problem() -> Problem {
        // Square of side 1: 0 (0,0), 1 (1,0), 2 (1,1), 3 (0,1); closed tour at 0.
        Problem::from_points(
            &[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
            Metric::Euclidean,
            vec![5.0, 1.0, 2.0, 3.0],
            4.5,
        )
        .unwrap()
        .with_service_costs(vec![0.25, 0.0, 0.0, 0.0])
        .unwrap()
    }

    fn check(routes: &[Vec<usize>], expected: Result<(f64, f64), SolutionError>) {
        let p = problem();
        let got = evaluate(&p, routes).map(|s| (s.reward, s.total_cost()));
        assert_eq!(got, expected);
    }

    #[test]
    fn evaluation() {
        check(&[vec![0, 1, 2, 3, 0]], Ok((11.0, 4.25)));
        check(&[], Ok((5.0, 0.25)));
        check(&[vec![0, 1, 0]], Ok((6.0, 2.25)));
        check(
            &[vec![0, 1, 1, 0]],
            Err(SolutionError::Duplicate { route: 0, node: 1 }),
        );
        check(
            &[vec![1, 0]],
            Err(SolutionError::BadEndpoints {
                route: 0,
                start: 0,
                end: 0,
                first: Some(1),
                last: Some(0),
            }),
        );
        check(
            &[vec![0, 9, 0]],
            Err(SolutionError::NodeOutOfRange {
                route: 0,
                node: 9,
                nodes: 4,
            }),
        );
        check(
            &[vec![0, 0], vec![0, 0]],
            Err(SolutionError::TooManyRoutes {
                routes: 2,
                vehicles: 1,
            }),
        );
        let p = problem().with_budget(4.0).unwrap();
        assert_eq!(
            evaluate(&p, &[vec![0, 1, 2, 3, 0]]),
            Err(SolutionError::OverBudget {
                route: 0,
                cost: 4.25,
                budget: 4.0
            })
        );
    }
}
