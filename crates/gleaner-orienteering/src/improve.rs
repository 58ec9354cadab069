//! Improvement of given routes with the solver's own local-search moves, without choosing
//! which nodes to visit: for callers that already know the node set (a covering tour, routes
//! split from a giant tour) and only want them shorter.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::engine::{Ctx, State};
use crate::error::SolutionError;
use crate::problem::Problem;
use crate::solution::{Solution, evaluate};

/// Settings of [`improve_routes`].
#[derive(Debug, Clone, PartialEq)]
pub struct ImproveOptions {
    /// Length of the candidate-neighbour lists (k nearest nodes) of 2-opt and Or-opt
    /// (default 12).
    pub neighbours: usize,
    /// Move single nodes between routes (relocation, and exchange of two nodes) while that
    /// lowers the total cost and every route stays within the budget (default true). Routes
    /// may end up empty.
    pub between_routes: bool,
    /// Double-bridge kicks per route after the local search, each followed by 2-opt and
    /// Or-opt and kept only when the route gets cheaper (default 0: none). Routes of fewer
    /// than 8 interior nodes are never kicked.
    pub kicks: usize,
    /// Seed of the kicks' random choices.
    pub seed: u64,
    /// Maximum rounds of (tour improvement, moves between routes) (default 100).
    pub max_rounds: usize,
}

impl Default for ImproveOptions {
    fn default() -> ImproveOptions {
        ImproveOptions {
            neighbours: 12,
            between_routes: true,
            kicks: 0,
            seed: 0,
            max_rounds: 100,
        }
    }
}

/// Shortens `routes` over `problem`'s travel costs with the moves of the default solver,
/// keeping the set of visited nodes: 2-opt and Or-opt (segments of 1-3 nodes, both
/// orientations) within each route, then, with several routes and
/// [`ImproveOptions::between_routes`], relocation and exchange of single nodes between
/// routes, repeated until nothing improves; then the optional double-bridge kicks.
///
/// Each route runs from [`Problem::start`] to [`Problem::end`] (a closed tour through all
/// nodes is `[s, .., s]` with `start = end = s`). Rewards play no part (they are unchanged);
/// service costs count towards each route's budget, so nodes only move between routes when
/// the receiving route can pay for them. The total cost never increases; the result is
/// re-validated by [`evaluate`]. Deterministic for a given `options.seed`.
///
/// # Errors
/// The [`SolutionError`] of [`evaluate`] when `routes` are not a valid solution of `problem`
/// (wrong endpoints, repeated nodes, a route over budget, more routes than vehicles).
///
/// ```
/// use gleaner_orienteering::{ImproveOptions, Metric, Problem, improve_routes};
/// // Corners of a 10 x 10 square visited in a crossing order from node 0.
/// let points = [[0.0, 0.0], [10.0, 10.0], [10.0, 0.0], [0.0, 10.0]];
/// let problem = Problem::from_points(&points, Metric::Euclidean, vec![0.0; 4], 100.0)?;
/// let better = improve_routes(&problem, &[vec![0, 1, 2, 3, 0]], &ImproveOptions::default())?;
/// assert!((better.costs[0] - 40.0).abs() < 1e-9); // the square's perimeter
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn improve_routes(
    problem: &Problem,
    routes: &[Vec<usize>],
    options: &ImproveOptions,
) -> Result<Solution, SolutionError> {
    let ctx = Ctx::new(problem, options.neighbours.max(1), true);
    improve_routes_in(&ctx, problem, routes, options)
}

/// [`improve_routes`] over a context built once by the caller
/// (`Ctx::new(problem, options.neighbours.max(1), true)`), for callers that shorten many
/// routes of one problem: the context depends on nothing else, so the same result.
pub(crate) fn improve_routes_in(
    ctx: &Ctx<'_>,
    problem: &Problem,
    routes: &[Vec<usize>],
    options: &ImproveOptions,
) -> Result<Solution, SolutionError> {
    let given = evaluate(problem, routes)?;
    let mut state = State::from_routes(problem, &given.routes);
    for _ in 0..options.max_rounds {
        state.improve_tours(ctx);
        let moved = options.between_routes && state.routes.len() > 1 && state.relocate(ctx);
        if !moved {
            break;
        }
    }
    if options.kicks > 0 {
        let mut rng = ChaCha8Rng::seed_from_u64(options.seed);
        for r in 0..state.routes.len() {
            state.kick_tour(ctx, r, options.kicks, &mut rng);
        }
    }
    state.resync(problem);
    let mut improved = evaluate(problem, &state.routes)?;
    improved.routes.truncate(given.routes.len());
    improved.costs.truncate(given.routes.len());
    if improved.total_cost() > given.total_cost() {
        // Cannot happen (every move is improving); kept as a guarantee.
        return Ok(given);
    }
    Ok(improved)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::problem::Metric;
    use crate::solution::route_cost;

    fn circle(n: usize) -> Vec<[f64; 2]> {
        (0..n)
            .map(|i| {
                let a = 2.0 * std::f64::consts::PI * i as f64 / n as f64;
                [500.0 * a.cos(), 500.0 * a.sin()]
            })
            .collect()
    }

    #[test]
    fn untangles_a_scrambled_circle() {
        // The optimal closed tour through points on a circle is the polygon.
        let n = 40;
        let pts = circle(n);
        let p = Problem::from_points(&pts, Metric::Euclidean, vec![1.0; n], 1e6).unwrap();
        let mut tour: Vec<usize> = (0..n).map(|i| (i * 17) % n).collect();
        tour.push(0);
        let before = route_cost(&p, &tour);
        let s = improve_routes(&p, &[tour], &ImproveOptions::default()).unwrap();
        let polygon = n as f64 * 2.0 * 500.0 * (std::f64::consts::PI / n as f64).sin();
        assert!(before > polygon);
        assert!((s.costs[0] - polygon).abs() < 1e-6, "{}", s.costs[0]);
        let mut seen = s.routes[0][1..n].to_vec();
        seen.sort_unstable();
        assert_eq!(seen, (1..n).collect::<Vec<_>>());
    }

    #[test]
    fn relocation_regroups_crossed_routes() {
        // Two nodes east and two west of the depot, assigned crosswise (routes of 2,020 and
        // 2,180); all four in one route would cost 2,200, over the budget.
        let pts = [
            [0.0, 0.0],
            [500.0, 0.0],
            [-500.0, 0.0],
            [540.0, 0.0],
            [-540.0, 0.0],
        ];
        let p = Problem::from_points(&pts, Metric::Euclidean, vec![0.0; 5], 2_190.0)
            .unwrap()
            .with_service_costs(vec![0.0, 10.0, 10.0, 10.0, 10.0])
            .unwrap()
            .with_vehicles(2)
            .unwrap();
        let crossed = [vec![0, 1, 2, 0], vec![0, 3, 4, 0]];
        let s = improve_routes(&p, &crossed, &ImproveOptions::default()).unwrap();
        let mut sides: Vec<Vec<usize>> = s
            .routes
            .iter()
            .map(|r| {
                let mut r = r[1..r.len() - 1].to_vec();
                r.sort_unstable();
                r
            })
            .collect();
        sides.sort();
        assert_eq!(sides, vec![vec![1, 3], vec![2, 4]]);
        assert!((s.total_cost() - (2.0 * 1080.0 + 40.0)).abs() < 1e-9);
    }

    #[test]
    fn invalid_routes_are_rejected() {
        let pts = [[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]];
        let p = Problem::from_points(&pts, Metric::Euclidean, vec![0.0; 3], 10.0).unwrap();
        let o = ImproveOptions::default();
        assert!(improve_routes(&p, &[vec![0, 1, 1, 0]], &o).is_err());
        assert!(improve_routes(&p, &[vec![1, 2, 0]], &o).is_err());
        assert!(improve_routes(&p, &[vec![0, 1, 0], vec![0, 2, 0]], &o).is_err());
    }
}
