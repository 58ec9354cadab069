//! Orienteering (OP) and team orienteering (TOP) solvers.
//!
//! A pure, generic optimisation core: nodes with rewards and service costs, a symmetric travel
//! cost matrix (or planar points and a [`Metric`]) or a directed one ([`Problem::new_directed`],
//! or points and a cost of the displacement, [`Problem::from_displacement_costs`]: going one
//! way may cost more than coming back), start and end nodes, a per-route budget and a number
//! of vehicles. It knows nothing about what the nodes are; costs, service costs
//! and the budget share one unit of the caller's choice (metres, seconds, joules...).
//!
//! - [`Problem`] — a validated instance ([`ProblemError`] for bad input).
//! - [`Solution`] and [`evaluate`] — routes `[start, .., end]`, reward, per-route costs, and
//!   an independent re-check of any routes against a problem ([`SolutionError`]).
//! - [`greedy`] — the paper's ratio-insertion heuristic (baseline).
//! - [`solve_default`] — iterated local search seeded with greedy; never worse than greedy.
//! - [`exact`] — subset dynamic programming, proves optimality for small instances.
//! - [`solve`] with [`SolverKind`] and [`SolveOptions`] — one entry point for all three.
//! - [`improve_routes`] with [`ImproveOptions`] — the same 2-opt / Or-opt / relocation /
//!   exchange moves applied to routes whose node set is already chosen (e.g. a tour through
//!   every node, or routes split from one), making them shorter without changing what they
//!   visit.
//! - [`solve_marginal`] with [`MarginalOptions`] — orienteering with a set-function value
//!   `f(visited)` (non-additive rewards: marginal-gain insertion and exchange search).
//! - [`time_limit_from_secs`] — a checked conversion of a user's time limit in seconds.
//!
//! ```
//! use gleaner_orienteering::{Metric, Problem, SolveOptions, evaluate, greedy, solve_default};
//! // Depot at the origin (closed tour), four sites; costs are distances in metres.
//! let points = [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0], [50.0, 50.0]];
//! let rewards = vec![0.0, 1.0, 2.0, 1.0, 10.0];
//! let problem = Problem::from_points(&points, Metric::Euclidean, rewards, 45.0)?
//!     .with_service_costs(vec![0.0, 1.0, 1.0, 1.0, 1.0])?;
//! let options = SolveOptions::default().with_iterations(100).with_seed(7);
//! let best = solve_default(&problem, &options);
//! assert_eq!(best.routes[0].first(), Some(&0));
//! assert!((best.reward - 4.0).abs() < 1e-9); // the far site (141 m round trip) never fits
//! assert!(best.reward >= greedy(&problem).reward);
//! assert!(evaluate(&problem, &best.routes).is_ok());
//! assert!(best.costs[0] <= 45.0);
//! # Ok::<(), gleaner_orienteering::ProblemError>(())
//! ```
//!
//! # Model
//!
//! A route's cost is its travel cost plus the service cost of every node on it (start and end
//! included; a closed tour pays its depot once). It is feasible when the cost is at most the
//! budget plus a tolerance of 1e-9 relative to the budget. Each node's reward is collected at
//! most once over all routes; the start and end rewards are always collected, once. Nodes of
//! zero reward are never visited. A budget below the cost of the direct start -> end route is
//! rejected when the problem is built ([`ProblemError::Infeasible`]), so every valid problem
//! has at least the empty solution.
//!
//! # Algorithm design
//!
//! - **Greedy** (docs/method.md §4, faithful to the paper): repeatedly insert the feasible node of
//!   largest reward / extra cost at its cheapest insertion position (extra travel + service
//!   cost). Cheapest positions are cached per node and route and updated incrementally
//!   after each insertion (only the broken edge forces a rescan), so a whole construction
//!   costs about O(n·m) for m visited nodes.
//! - **Default: multi-start iterated local search.** Local search = 2-opt and Or-opt (segments
//!   of 1-3, both orientations) driven by k-nearest candidate lists, which shorten the tours
//!   and free budget; ratio insertion of unvisited nodes; replacement of a visited node by an
//!   unvisited one of higher reward (or equal reward at lower cost); repeated until none
//!   applies. Before the iterations, a route is built through every candidate as a first
//!   stop (a sample of 64 above 400 candidates); the best of these seed the elite pool and
//!   the "top anchors". Each iteration perturbs, refills with optionally noisy ratios while
//!   the removed nodes are tabu, and runs the local search. Perturbations (the strength grows
//!   while stalled): remove a random segment or random nodes, or, in 30% of the iterations,
//!   *shift* a route: force a random unvisited node and up to `strength - 1` of its unvisited
//!   nearest neighbours in (budget ignored), then drop the nodes of largest saving per reward
//!   until it fits. The shift moves tours toward unvisited regions; on the clustered OPLib
//!   `pr226-gen1-50` it lifts the score from 122 to 126. Solutions that improve the run's
//!   best are intensified by double-bridge kicks on their tours. Acceptance is
//!   record-to-record (within 2-5% of the run's best). A run ends after
//!   `150 + candidates / 2` non-improving iterations; new runs restart from the overall best,
//!   an elite solution, or a construction through one or two anchors (top or random: on
//!   OPLib `pr107-gen3` this is what finds the far cluster). Instances with at most
//!   [`SolveOptions::exact_threshold`] candidates are solved exactly. Above
//!   [`SolveOptions::full_scan_limit`] candidates, insertion and replacement only look at
//!   edges next to a node's candidate neighbours, so 10,000 nodes are practical.
//! - **Pruning** ([`SolveOptions::prune`], default on): the search only considers
//!   [`Problem::reachable_candidates`], the nodes for which start -> node -> end fits the
//!   budget by shortest-path cost (direct costs for points and a metric; Dijkstra over a cost
//!   matrix, which need not satisfy the triangle inequality). No feasible route is lost, and
//!   the work follows what the budget reaches rather than the instance: 10,000 nodes of
//!   which the budget reaches about 1,000 and a route holds 10 take 0.3 s for 300 iterations
//!   instead of 8.9 s. On metric costs an insertion costs at least the node's service cost,
//!   so insertion skips nodes whose service exceeds every route's slack; replacement skips
//!   routes that hold none of the node's candidate neighbours (large instances). Both
//!   shortcuts leave the result unchanged.
//! - **Exact**: DP over (subset, last node) of the positive-reward nodes (Held-Karp),
//!   then the best feasible subset (or, for several vehicles, the best combination of
//!   disjoint feasible subsets by subset convolution); up to [`EXACT_MAX_NODES`] candidates.
//!
//! - **Directed costs**: every move reads the costs in the direction flown. A reversal
//!   (2-opt, Or-opt's reversed segments) also changes the cost of the arcs inside the reversed
//!   segment; on a directed instance its gain adds that change (prefix sums of the route's arcs
//!   both ways, O(1) per evaluation), and pruning measures the way to the end over the
//!   reversed arcs. Symmetric instances take exactly the code paths they always took. On
//!   drift costs (a steady wind) the search alone still equals the exact optimum of one route
//!   in the property tests (`tests/directed.rs`).
//!
//! Determinism: every random choice comes from `ChaCha8Rng::seed_from_u64(options.seed)`.
//! With `max_iterations` or `max_stall` as the binding limit, results do not depend on the
//! machine; the time limit only stops the search early.
//!
//! # Results (measured; see `gleaner-op-formats/RESULTS.md` for the tables)
//!
//! - Classic sets (Tsiligirides 1-3, Chao 64/66), 1 s each: all 89 at their target, none
//!   infeasible. The paper's greedy reaches 8 of 89 (mean gap 12.8%).
//! - OPLib gen1-3 with n <= 400, 10 s each, one thread: mean gap -0.63% to the EA4OP scores
//!   (negative = better), worst +1.41% (`rd400-gen2-50`), 129 of 135 equal or better, 71
//!   strictly better (before the shift perturbation: -0.54%, worst +3.17% on
//!   `pr226-gen1-50`, 123 and 66). Greedy's mean gap is 24.2%.
//! - Random uniform instances with a depot at the centre, [`SolveOptions::fast`] (greedy, then
//!   local search to a local optimum), criterion medians: 1,000 nodes in 11 ms, 10,000 nodes
//!   in 0.31 s, with about 16% of the nodes visited. An exhaustive check afterwards finds no
//!   feasible insertion and no improving 2-opt move left.
//! - Property tests (n <= 12, service costs, start != end, 1-2 vehicles): default = exact
//!   optimum, greedy = a plain reference implementation.
#![deny(missing_docs)]

mod engine;
mod error;
mod exact;
mod improve;
mod marginal;
mod problem;
mod solution;
mod solve;

pub use error::{ProblemError, SolutionError, SolveError};
pub use exact::{EXACT_MAX_NODES, EXACT_MAX_NODES_TEAM, exact};
pub use improve::{ImproveOptions, improve_routes};
pub use marginal::{MarginalOptions, MarginalSolution, solve_marginal};
pub use problem::{DisplacementCost, Metric, Problem};
pub use solution::{Solution, evaluate, route_cost};
pub use solve::{SolveOptions, SolverKind, greedy, solve, solve_default, time_limit_from_secs};
