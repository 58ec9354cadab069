//! The orienteering problem instance: costs, rewards, service costs, endpoints, budget.

use std::sync::Arc;

use crate::error::ProblemError;

/// Tolerance (relative to the matrix scale) under which `c[i][j]` and `c[j][i]` count as equal.
const SYMMETRY_TOLERANCE: f64 = 1e-9;

/// A planar metric used by [`Problem::from_points`]; coordinates and costs share one unit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Metric {
    /// Straight-line (L2) distance.
    Euclidean,
    /// Manhattan (L1) distance.
    Manhattan,
    /// Chebyshev (L-infinity) distance.
    Chebyshev,
}

impl Metric {
    /// Distance between two points `[x, y]` (same unit as the coordinates).
    pub fn distance(self, a: [f64; 2], b: [f64; 2]) -> f64 {
        let dx = (a[0] - b[0]).abs();
        let dy = (a[1] - b[1]).abs();
        match self {
            Metric::Euclidean => (dx * dx + dy * dy).sqrt(),
            Metric::Manhattan => dx + dy,
            Metric::Chebyshev => dx.max(dy),
        }
    }
}

/// A directed travel cost that depends only on the displacement between two points: `f(dx,
/// dy)` for going from `p_i` to `p_j = p_i + (dx, dy)` (same unit as the budget). See
/// [`Problem::from_displacement_costs`].
pub type DisplacementCost = Arc<dyn Fn(f64, f64) -> f64 + Send + Sync>;

/// Travel costs: a dense matrix, or points, a metric and a cost per unit of distance
/// evaluated on demand (so 10,000-node instances do not need an 800 MB matrix), or points
/// and a directed cost of the displacement.
#[derive(Clone)]
enum Costs {
    Dense(Vec<f64>),
    /// Points, metric, cost per unit of distance (1 for [`Problem::from_points`]), and for
    /// up to [`TABULATED_NODES`] nodes every pair's cost computed once (row-major): the same
    /// expression's value, so the same bits as evaluating it on demand.
    Points(Vec<[f64; 2]>, Metric, f64, Option<Vec<f64>>),
    /// Points and a directed cost of the displacement `f(p_j − p_i)`, tabulated like
    /// `Points` for up to [`TABULATED_NODES`] nodes.
    Displacement(Vec<[f64; 2]>, DisplacementCost, Option<Vec<f64>>),
}

impl std::fmt::Debug for Costs {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Costs::Dense(m) => f.debug_tuple("Dense").field(&m.len()).finish(),
            Costs::Points(p, metric, scale, table) => f
                .debug_tuple("Points")
                .field(&p.len())
                .field(metric)
                .field(scale)
                .field(&table.is_some())
                .finish(),
            Costs::Displacement(p, _, table) => f
                .debug_tuple("Displacement")
                .field(&p.len())
                .field(&table.is_some())
                .finish(),
        }
    }
}

/// `f(p_j − p_i)`: the cost of a displacement problem, the one expression both its table and
/// the on-demand evaluation use.
#[inline]
fn displacement_cost(points: &[[f64; 2]], f: &DisplacementCost, i: usize, j: usize) -> f64 {
    f(points[j][0] - points[i][0], points[j][1] - points[i][1])
}

/// Largest number of nodes whose point costs are tabulated (n² values: 8 MiB at 1,024).
const TABULATED_NODES: usize = 1_024;

/// `scale · metric.distance(p_i, p_j)`: the cost of a points problem, the one expression
/// both the table and the on-demand evaluation use.
#[inline]
fn point_cost(points: &[[f64; 2]], metric: Metric, scale: f64, i: usize, j: usize) -> f64 {
    scale * metric.distance(points[i], points[j])
}

/// The points of a points problem: one per reward, finite, at least one.
fn check_points(points: &[[f64; 2]], nodes: usize) -> Result<(), ProblemError> {
    if points.len() != nodes {
        return Err(ProblemError::LengthMismatch {
            what: "points",
            len: points.len(),
            nodes,
        });
    }
    for (node, p) in points.iter().enumerate() {
        if !p[0].is_finite() || !p[1].is_finite() {
            return Err(ProblemError::BadPoint { node });
        }
    }
    if points.is_empty() {
        return Err(ProblemError::Empty);
    }
    Ok(())
}

/// A validated (team) orienteering problem.
///
/// Costs are in any consistent unit (metres, seconds, joules...): the travel cost matrix, the
/// node service costs and the budget share it. A route starts at [`Problem::start`], ends at
/// [`Problem::end`] (equal for a closed tour), and its cost is the travel along its legs plus
/// the service cost of every node on it (start and end included, counted once each when
/// equal). Each of the [`Problem::vehicles`] routes must cost at most the budget; a node's
/// reward is collected at most once overall (start and end included).
#[derive(Debug, Clone)]
pub struct Problem {
    n: usize,
    cost: Costs,
    reward: Vec<f64>,
    service: Vec<f64>,
    start: usize,
    end: usize,
    budget: f64,
    vehicles: usize,
    /// `cost(i, j) == cost(j, i)` for every pair (within 1e-9 relative for a matrix).
    symmetric: bool,
}

/// Checks a dense row-major cost matrix for `n` nodes: at least one node, `n²` entries, each
/// finite and >= 0 (the first bad one in row-major order is reported). Returns the largest
/// entry (budget unit).
fn check_matrix(cost: &[f64], n: usize) -> Result<f64, ProblemError> {
    if n == 0 {
        return Err(ProblemError::Empty);
    }
    if cost.len() != n * n {
        return Err(ProblemError::MatrixSize {
            len: cost.len(),
            nodes: n,
        });
    }
    let mut scale = 0.0f64;
    for (k, &c) in cost.iter().enumerate() {
        if !c.is_finite() || c < 0.0 {
            return Err(ProblemError::BadCost {
                from: k / n,
                to: k % n,
                value: c,
            });
        }
        scale = scale.max(c);
    }
    Ok(scale)
}

impl Problem {
    /// Builds a single-vehicle closed-tour problem (start = end = node 0, no service costs)
    /// from a dense row-major `n × n` symmetric cost matrix, the node rewards and the budget
    /// (same unit as the costs).
    ///
    /// Errors: matrix size not `n²`, non-finite or negative entries, asymmetry beyond a
    /// relative tolerance of 1e-9, negative or non-finite rewards or budget, no nodes.
    pub fn new(cost: Vec<f64>, rewards: Vec<f64>, budget: f64) -> Result<Problem, ProblemError> {
        let n = rewards.len();
        let scale = check_matrix(&cost, n)?;
        let tol = SYMMETRY_TOLERANCE * scale.max(1.0);
        for i in 0..n {
            for j in (i + 1)..n {
                let (a, b) = (cost[i * n + j], cost[j * n + i]);
                if (a - b).abs() > tol {
                    return Err(ProblemError::Asymmetric {
                        from: i,
                        to: j,
                        forward: a,
                        backward: b,
                    });
                }
            }
        }
        Problem::assemble(n, Costs::Dense(cost), rewards, budget)
    }

    /// Builds a problem like [`Problem::new`] from a dense row-major `n × n` cost matrix that
    /// need not be symmetric: entry `i·n + j` is the cost of going from `i` to `j` (a
    /// directed instance, e.g. travel in a wind). Every solver reads the costs in the
    /// direction of travel; reversing part of a route changes its cost, and the moves that
    /// reverse segments account for it.
    ///
    /// Errors: as [`Problem::new`] but for the symmetry check.
    pub fn new_directed(
        cost: Vec<f64>,
        rewards: Vec<f64>,
        budget: f64,
    ) -> Result<Problem, ProblemError> {
        let n = rewards.len();
        check_matrix(&cost, n)?;
        let mut p = Problem::assemble(n, Costs::Dense(cost), rewards, budget)?;
        p.symmetric = false;
        Ok(p)
    }

    /// Builds a directed problem from planar points `[x, y]` and a cost of the displacement:
    /// going from `p_i` to `p_j` costs `cost(x_j − x_i, y_j − y_i)` (budget unit), which may
    /// differ from the way back (a steady wind, a slope, a current). Like
    /// [`Problem::from_scaled_points`] the costs are tabulated once for up to 1,024 nodes and
    /// evaluated on demand above, the same value either way. `cost` must return a finite
    /// value >= 0 for any displacement between the points and 0 for (0, 0); the tabulated
    /// entries are checked. Costs are not assumed to satisfy the triangle inequality.
    ///
    /// Errors: as [`Problem::from_points`]; [`ProblemError::BadCost`] for a tabulated entry
    /// that is negative or not finite, or a cost of (0, 0) that is not 0.
    pub fn from_displacement_costs(
        points: &[[f64; 2]],
        cost: DisplacementCost,
        rewards: Vec<f64>,
        budget: f64,
    ) -> Result<Problem, ProblemError> {
        check_points(points, rewards.len())?;
        let zero = cost(0.0, 0.0);
        if zero != 0.0 {
            return Err(ProblemError::BadCost {
                from: 0,
                to: 0,
                value: zero,
            });
        }
        let n = points.len();
        let table: Option<Vec<f64>> = (n <= TABULATED_NODES).then(|| {
            (0..n * n)
                .map(|ij| displacement_cost(points, &cost, ij / n, ij % n))
                .collect()
        });
        if let Some((k, &c)) = table
            .iter()
            .flatten()
            .enumerate()
            .find(|(_, c)| !c.is_finite() || **c < 0.0)
        {
            return Err(ProblemError::BadCost {
                from: k / n,
                to: k % n,
                value: c,
            });
        }
        let mut p = Problem::assemble(
            n,
            Costs::Displacement(points.to_vec(), cost, table),
            rewards,
            budget,
        )?;
        p.symmetric = false;
        Ok(p)
    }

    /// True when going from `i` to `j` costs what going back does, for every pair
    /// ([`Problem::new`], points and a metric); false for a directed instance
    /// ([`Problem::new_directed`], [`Problem::from_displacement_costs`]), whatever its values.
    pub fn is_symmetric(&self) -> bool {
        self.symmetric
    }

    fn assemble(
        n: usize,
        cost: Costs,
        rewards: Vec<f64>,
        budget: f64,
    ) -> Result<Problem, ProblemError> {
        for (node, &r) in rewards.iter().enumerate() {
            if !r.is_finite() || r < 0.0 {
                return Err(ProblemError::BadReward { node, value: r });
            }
        }
        if !budget.is_finite() || budget < 0.0 {
            return Err(ProblemError::BadBudget { value: budget });
        }
        let p = Problem {
            n,
            cost,
            reward: rewards,
            service: vec![0.0; n],
            start: 0,
            end: 0,
            budget,
            vehicles: 1,
            symmetric: true,
        };
        p.check_budget()?;
        Ok(p)
    }

    /// Builds a problem like [`Problem::new`] from planar points `[x, y]` and a [`Metric`];
    /// costs (in the coordinates' unit) are evaluated on demand rather than stored, which is
    /// exactly equivalent to the matrix `metric.distance(p_i, p_j)`.
    pub fn from_points(
        points: &[[f64; 2]],
        metric: Metric,
        rewards: Vec<f64>,
        budget: f64,
    ) -> Result<Problem, ProblemError> {
        Problem::from_scaled_points(points, metric, 1.0, rewards, budget)
    }

    /// Builds a problem like [`Problem::from_points`] whose travel cost is `cost_per_unit`
    /// times the metric distance (e.g. joules per metre of flight when the coordinates are
    /// metres and the budget is in joules): the cost from `i` to `j` is exactly
    /// `cost_per_unit * metric.distance(p_i, p_j)`: tabulated once for up to 1,024 nodes,
    /// evaluated on demand above (the same value either way, to the bit).
    ///
    /// Errors: as [`Problem::from_points`], and [`ProblemError::BadCostScale`] for a
    /// `cost_per_unit` that is negative or not finite.
    pub fn from_scaled_points(
        points: &[[f64; 2]],
        metric: Metric,
        cost_per_unit: f64,
        rewards: Vec<f64>,
        budget: f64,
    ) -> Result<Problem, ProblemError> {
        if !cost_per_unit.is_finite() || cost_per_unit < 0.0 {
            return Err(ProblemError::BadCostScale {
                value: cost_per_unit,
            });
        }
        check_points(points, rewards.len())?;
        let n = points.len();
        let table = (n <= TABULATED_NODES).then(|| {
            (0..n * n)
                .map(|ij| point_cost(points, metric, cost_per_unit, ij / n, ij % n))
                .collect()
        });
        Problem::assemble(
            n,
            Costs::Points(points.to_vec(), metric, cost_per_unit, table),
            rewards,
            budget,
        )
    }

    /// Sets per-node service costs (same unit as the budget, each finite and >= 0), paid
    /// whenever the node is on a route.
    pub fn with_service_costs(mut self, service: Vec<f64>) -> Result<Problem, ProblemError> {
        if service.len() != self.n {
            return Err(ProblemError::LengthMismatch {
                what: "service costs",
                len: service.len(),
                nodes: self.n,
            });
        }
        for (node, &s) in service.iter().enumerate() {
            if !s.is_finite() || s < 0.0 {
                return Err(ProblemError::BadService { node, value: s });
            }
        }
        self.service = service;
        self.check_budget()?;
        Ok(self)
    }

    /// Sets the start and end nodes (equal for a closed tour).
    pub fn with_endpoints(mut self, start: usize, end: usize) -> Result<Problem, ProblemError> {
        for node in [start, end] {
            if node >= self.n {
                return Err(ProblemError::NodeOutOfRange {
                    node,
                    nodes: self.n,
                });
            }
        }
        self.start = start;
        self.end = end;
        self.check_budget()?;
        Ok(self)
    }

    /// Sets the number of vehicles (routes), at least 1: team orienteering.
    pub fn with_vehicles(mut self, vehicles: usize) -> Result<Problem, ProblemError> {
        if vehicles == 0 {
            return Err(ProblemError::NoVehicles);
        }
        self.vehicles = vehicles;
        Ok(self)
    }

    /// Replaces the budget (same unit as the costs, finite and >= 0).
    pub fn with_budget(mut self, budget: f64) -> Result<Problem, ProblemError> {
        if !budget.is_finite() || budget < 0.0 {
            return Err(ProblemError::BadBudget { value: budget });
        }
        self.budget = budget;
        self.check_budget()?;
        Ok(self)
    }

    /// The budget must at least pay for the empty route start -> end; otherwise the problem
    /// is infeasible and construction fails with [`ProblemError::Infeasible`].
    fn check_budget(&self) -> Result<(), ProblemError> {
        let minimum = self.empty_route_cost();
        if minimum > self.budget + self.tolerance() {
            return Err(ProblemError::Infeasible {
                minimum,
                budget: self.budget,
            });
        }
        Ok(())
    }

    /// Cost of the route that goes straight from start to end (service costs included).
    pub fn empty_route_cost(&self) -> f64 {
        let mut c = self.cost(self.start, self.end) + self.service[self.start];
        if self.end != self.start {
            c += self.service[self.end];
        }
        c
    }

    /// Absolute feasibility tolerance: 1e-9 relative to the budget (at least 1e-9).
    pub fn tolerance(&self) -> f64 {
        1e-9 * self.budget.abs().max(1.0)
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.n
    }

    /// Always false: a problem has at least one node.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// Travel cost from `i` to `j` (budget unit). Panics if out of range.
    #[inline]
    pub fn cost(&self, i: usize, j: usize) -> f64 {
        match &self.cost {
            Costs::Dense(m) => m[i * self.n + j],
            Costs::Points(_, _, _, Some(table)) => table[i * self.n + j],
            Costs::Points(p, metric, scale, None) => point_cost(p, *metric, *scale, i, j),
            Costs::Displacement(_, _, Some(table)) => table[i * self.n + j],
            Costs::Displacement(p, f, None) => displacement_cost(p, f, i, j),
        }
    }

    /// Every pair's travel cost (budget unit), row-major (`len()` × `len()`), when the
    /// problem keeps them in a table (a cost matrix, or points with at most
    /// [`TABULATED_NODES`] nodes): entry `i·n + j` is [`Problem::cost`]`(i, j)`.
    pub fn cost_table(&self) -> Option<&[f64]> {
        match &self.cost {
            Costs::Dense(m) => Some(m),
            Costs::Points(_, _, _, table) | Costs::Displacement(_, _, table) => table.as_deref(),
        }
    }

    /// The planar points and metric when the problem was built by [`Problem::from_points`]
    /// or [`Problem::from_scaled_points`].
    pub fn points(&self) -> Option<(&[[f64; 2]], Metric)> {
        match &self.cost {
            Costs::Dense(_) | Costs::Displacement(..) => None,
            Costs::Points(p, m, _, _) => Some((p, *m)),
        }
    }

    /// Cost per unit of distance of a problem built from points (1 for
    /// [`Problem::from_points`]); `None` for a cost matrix.
    pub fn cost_per_unit(&self) -> Option<f64> {
        match &self.cost {
            Costs::Dense(_) | Costs::Displacement(..) => None,
            Costs::Points(_, _, scale, _) => Some(*scale),
        }
    }

    /// True when the travel costs are known to satisfy the triangle inequality (points and a
    /// metric, up to floating-point rounding); a cost matrix is not assumed to.
    pub fn is_metric(&self) -> bool {
        matches!(self.cost, Costs::Points(..))
    }

    /// Reward of node `i`.
    #[inline]
    pub fn reward(&self, i: usize) -> f64 {
        self.reward[i]
    }

    /// All rewards.
    pub fn rewards(&self) -> &[f64] {
        &self.reward
    }

    /// Service cost of node `i` (budget unit).
    #[inline]
    pub fn service(&self, i: usize) -> f64 {
        self.service[i]
    }

    /// All service costs.
    pub fn service_costs(&self) -> &[f64] {
        &self.service
    }

    /// Start node of every route.
    pub fn start(&self) -> usize {
        self.start
    }

    /// End node of every route.
    pub fn end(&self) -> usize {
        self.end
    }

    /// Budget per route (cost unit).
    pub fn budget(&self) -> f64 {
        self.budget
    }

    /// Number of vehicles (routes).
    pub fn vehicles(&self) -> usize {
        self.vehicles
    }

    /// True when `i` is the start or the end node.
    #[inline]
    pub fn is_terminal(&self, i: usize) -> bool {
        i == self.start || i == self.end
    }

    /// Non-terminal nodes of positive reward that some feasible route may visit, ascending;
    /// every other node is on no feasible route.
    ///
    /// A route through `v` costs at least `d(start, v) + d(v, end) + service(v)` plus the
    /// terminals' service costs, where `d` is the shortest-path cost (service costs of other
    /// nodes are >= 0). Nodes whose bound exceeds the budget (plus [`Problem::tolerance`]) can
    /// never be visited and are left out, so the search scales with what the budget reaches
    /// rather than with the instance. For points and a metric `d` is the direct cost (triangle
    /// inequality; the tolerance absorbs rounding); for a cost matrix, which need not satisfy
    /// it, `d` comes from Dijkstra's algorithm over the matrix (O(n²), like reading it once).
    pub fn reachable_candidates(&self) -> Vec<usize> {
        let p = self;
        let n = p.len();
        let (s, e) = (p.start(), p.end());
        let (from_start, to_end) = if p.is_metric() {
            (
                (0..n).map(|v| p.cost(s, v)).collect::<Vec<f64>>(),
                (0..n).map(|v| p.cost(v, e)).collect::<Vec<f64>>(),
            )
        } else {
            let ds = p.shortest_costs(s, false);
            let de = if e == s && p.symmetric {
                ds.clone()
            } else {
                // Into the end: over the reversed arcs when the costs are directed.
                p.shortest_costs(e, !p.symmetric)
            };
            (ds, de)
        };
        let terminals = p.empty_route_cost() - p.cost(s, e);
        let limit = p.budget() + p.tolerance();
        (0..n)
            .filter(|&v| !p.is_terminal(v) && p.reward(v) > 0.0)
            .filter(|&v| terminals + from_start[v] + to_end[v] + p.service(v) <= limit)
            .collect()
    }

    /// Shortest-path travel cost from `source` to every node (`into`: from every node to
    /// `source`, over the reversed arcs) over the cost matrix: Dijkstra's algorithm with an
    /// array, O(n²).
    fn shortest_costs(&self, source: usize, into: bool) -> Vec<f64> {
        let p = self;
        let n = p.len();
        let arc = |u: usize, v: usize| if into { p.cost(v, u) } else { p.cost(u, v) };
        let mut dist: Vec<f64> = (0..n).map(|v| arc(source, v)).collect();
        dist[source] = 0.0;
        let mut done = vec![false; n];
        done[source] = true;
        for _ in 1..n {
            let mut u = usize::MAX;
            for v in 0..n {
                if !done[v] && (u == usize::MAX || dist[v] < dist[u]) {
                    u = v;
                }
            }
            if u == usize::MAX {
                break;
            }
            done[u] = true;
            for v in 0..n {
                if !done[v] {
                    let via = dist[u] + arc(u, v);
                    if via < dist[v] {
                        dist[v] = via;
                    }
                }
            }
        }
        dist
    }

    /// Reward collected by the terminals (start, and end if different): always collected.
    pub fn terminal_reward(&self) -> f64 {
        let mut r = self.reward[self.start];
        if self.end != self.start {
            r += self.reward[self.end];
        }
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Builds a 3-node problem from a matrix and checks the outcome.
    fn check(cost: Vec<f64>, rewards: Vec<f64>, budget: f64, expected: Result<(), ProblemError>) {
        let got = Problem::new(cost, rewards, budget).map(|_| ());
        assert_eq!(got, expected);
    }

    #[test]
    fn validation() {
        let ok = vec![0.0, 1.0, 2.0, 1.0, 0.0, 1.5, 2.0, 1.5, 0.0];
        check(ok.clone(), vec![0.0, 1.0, 1.0], 3.0, Ok(()));
        check(
            vec![0.0; 4],
            vec![0.0, 1.0, 1.0],
            3.0,
            Err(ProblemError::MatrixSize { len: 4, nodes: 3 }),
        );
        let mut asym = ok.clone();
        asym[1] = 1.1;
        check(
            asym,
            vec![0.0, 1.0, 1.0],
            3.0,
            Err(ProblemError::Asymmetric {
                from: 0,
                to: 1,
                forward: 1.1,
                backward: 1.0,
            }),
        );
        let mut neg = ok.clone();
        neg[5] = -1.0;
        check(
            neg,
            vec![0.0, 1.0, 1.0],
            3.0,
            Err(ProblemError::BadCost {
                from: 1,
                to: 2,
                value: -1.0,
            }),
        );
        let mut nan = ok.clone();
        nan[0] = f64::NAN;
        assert!(matches!(
            Problem::new(nan, vec![0.0; 3], 1.0),
            Err(ProblemError::BadCost { .. })
        ));
        check(
            ok.clone(),
            vec![0.0, -1.0, 1.0],
            3.0,
            Err(ProblemError::BadReward {
                node: 1,
                value: -1.0,
            }),
        );
        check(
            ok.clone(),
            vec![0.0, 1.0, 1.0],
            f64::INFINITY,
            Err(ProblemError::BadBudget {
                value: f64::INFINITY,
            }),
        );
        check(vec![], vec![], 1.0, Err(ProblemError::Empty));
    }

    #[test]
    fn endpoints_service_and_infeasible_budget() {
        let p = Problem::from_points(
            &[[0.0, 0.0], [3.0, 4.0], [6.0, 8.0]],
            Metric::Euclidean,
            vec![0.0, 1.0, 0.0],
            10.0,
        )
        .unwrap();
        assert_eq!(
            p.clone().with_endpoints(0, 3).unwrap_err(),
            ProblemError::NodeOutOfRange { node: 3, nodes: 3 }
        );
        // start 0 -> end 2 costs 10, exactly the budget: allowed.
        let p2 = p.clone().with_endpoints(0, 2).unwrap();
        assert_eq!(p2.empty_route_cost(), 10.0);
        // Service at the end pushes the empty route over the budget.
        let err = p2.with_service_costs(vec![0.0, 0.0, 0.5]).unwrap_err();
        assert_eq!(
            err,
            ProblemError::Infeasible {
                minimum: 10.5,
                budget: 10.0
            }
        );
        assert_eq!(
            p.clone().with_vehicles(0).unwrap_err(),
            ProblemError::NoVehicles
        );
        assert!(matches!(
            p.with_service_costs(vec![1.0]),
            Err(ProblemError::LengthMismatch { .. })
        ));
    }

    #[test]
    fn metrics() {
        let (a, b) = ([0.0, 0.0], [3.0, -4.0]);
        assert_eq!(Metric::Euclidean.distance(a, b), 5.0);
        assert_eq!(Metric::Manhattan.distance(a, b), 7.0);
        assert_eq!(Metric::Chebyshev.distance(a, b), 4.0);
    }

    proptest::proptest! {
        /// A tabulated points problem's costs are the on-demand expression's, to the bit,
        /// for every pair and metric.
        #[test]
        fn tabulated_costs_are_the_on_demand_costs(
            pts in proptest::collection::vec((-1e4f64..1e4, -1e4f64..1e4), 1..30),
            scale in 0.0f64..50.0,
            metric in 0usize..3,
        ) {
            let points: Vec<[f64; 2]> = pts.iter().map(|&(x, y)| [x, y]).collect();
            let metric = [Metric::Euclidean, Metric::Manhattan, Metric::Chebyshev][metric];
            let n = points.len();
            let p = Problem::from_scaled_points(&points, metric, scale, vec![1.0; n], 1e9)
                .unwrap();
            proptest::prop_assert!(matches!(p.cost, Costs::Points(_, _, _, Some(_))));
            for i in 0..n {
                for j in 0..n {
                    let direct = scale * metric.distance(points[i], points[j]);
                    proptest::prop_assert_eq!(p.cost(i, j).to_bits(), direct.to_bits());
                }
            }
        }
    }

    /// Above the table's size the costs are evaluated on demand (no n² matrix).
    #[test]
    fn large_points_problems_are_not_tabulated() {
        let n = TABULATED_NODES + 1;
        let points: Vec<[f64; 2]> = (0..n).map(|i| [i as f64, 0.5 * i as f64]).collect();
        let p = Problem::from_points(&points, Metric::Euclidean, vec![1.0; n], 1e9).unwrap();
        assert!(matches!(p.cost, Costs::Points(_, _, _, None)));
        assert_eq!(
            p.cost(3, 7),
            Metric::Euclidean.distance(points[3], points[7])
        );
    }
}
