//! Typed errors.

use thiserror::Error;

/// Invalid problem data.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ProblemError {
    /// No nodes at all.
    #[error("a problem needs at least one node")]
    Empty,
    /// The cost matrix does not have `n²` entries.
    #[error("cost matrix has {len} entries, expected {nodes}² for {nodes} nodes")]
    MatrixSize {
        /// Entries given.
        len: usize,
        /// Number of nodes.
        nodes: usize,
    },
    /// A per-node vector has the wrong length.
    #[error("{what} has {len} entries, expected {nodes}")]
    LengthMismatch {
        /// Which vector.
        what: &'static str,
        /// Entries given.
        len: usize,
        /// Number of nodes.
        nodes: usize,
    },
    /// A travel cost is negative or not finite.
    #[error("cost from node {from} to node {to} is {value}; costs must be finite and >= 0")]
    BadCost {
        /// Row.
        from: usize,
        /// Column.
        to: usize,
        /// The value.
        value: f64,
    },
    /// The matrix is not symmetric.
    #[error(
        "cost matrix is asymmetric: c[{from}][{to}] = {forward} but c[{to}][{from}] = {backward}"
    )]
    Asymmetric {
        /// Row.
        from: usize,
        /// Column.
        to: usize,
        /// `c[from][to]`.
        forward: f64,
        /// `c[to][from]`.
        backward: f64,
    },
    /// A point has a non-finite coordinate.
    #[error("point of node {node} has a non-finite coordinate")]
    BadPoint {
        /// The node.
        node: usize,
    },
    /// The cost per unit of distance of [`crate::Problem::from_scaled_points`] is negative or
    /// not finite.
    #[error("cost per unit of distance is {value}; it must be finite and >= 0")]
    BadCostScale {
        /// The value given.
        value: f64,
    },
    /// A reward is negative or not finite.
    #[error("reward of node {node} is {value}; rewards must be finite and >= 0")]
    BadReward {
        /// The node.
        node: usize,
        /// The value.
        value: f64,
    },
    /// A service cost is negative or not finite.
    #[error("service cost of node {node} is {value}; service costs must be finite and >= 0")]
    BadService {
        /// The node.
        node: usize,
        /// The value.
        value: f64,
    },
    /// The budget is negative or not finite.
    #[error("budget is {value}; it must be finite and >= 0")]
    BadBudget {
        /// The value.
        value: f64,
    },
    /// Start or end out of range.
    #[error("node {node} is out of range for {nodes} nodes")]
    NodeOutOfRange {
        /// The node.
        node: usize,
        /// Number of nodes.
        nodes: usize,
    },
    /// Zero vehicles.
    #[error("at least one vehicle is needed")]
    NoVehicles,
    /// Even the direct start -> end route exceeds the budget.
    #[error("infeasible: the direct start->end route costs {minimum} but the budget is {budget}")]
    Infeasible {
        /// Cost of the direct route (travel + terminal service).
        minimum: f64,
        /// The budget.
        budget: f64,
    },
}

/// A solution that does not satisfy its problem.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum SolutionError {
    /// More routes than vehicles.
    #[error("{routes} routes but only {vehicles} vehicles")]
    TooManyRoutes {
        /// Routes given.
        routes: usize,
        /// Vehicles available.
        vehicles: usize,
    },
    /// A route does not start at the start node or end at the end node.
    #[error("route {route} must run from node {start} to node {end}, got {first:?} -> {last:?}")]
    BadEndpoints {
        /// Route index.
        route: usize,
        /// Expected start.
        start: usize,
        /// Expected end.
        end: usize,
        /// Actual first node.
        first: Option<usize>,
        /// Actual last node.
        last: Option<usize>,
    },
    /// A node index out of range.
    #[error("route {route} visits node {node}, out of range for {nodes} nodes")]
    NodeOutOfRange {
        /// Route index.
        route: usize,
        /// The node.
        node: usize,
        /// Number of nodes.
        nodes: usize,
    },
    /// A node visited twice (or a terminal visited in the middle of a route).
    #[error("node {node} is visited more than once (route {route})")]
    Duplicate {
        /// Route index.
        route: usize,
        /// The node.
        node: usize,
    },
    /// A route costs more than the budget.
    #[error("route {route} costs {cost}, over the budget {budget}")]
    OverBudget {
        /// Route index.
        route: usize,
        /// Its cost.
        cost: f64,
        /// The budget.
        budget: f64,
    },
}

/// Failure of a solver.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum SolveError {
    /// The exact solver was given too many candidate nodes.
    #[error(
        "exact solver supports at most {max} nodes with positive reward besides start/end, got {got}"
    )]
    TooLargeForExact {
        /// Candidates in the instance.
        got: usize,
        /// Maximum supported.
        max: usize,
    },
    /// A time limit that is not a number of seconds >= 0 (NaN or negative).
    #[error("invalid time limit {seconds} s: expected a number of seconds >= 0")]
    InvalidTimeLimit {
        /// The offending value, seconds.
        seconds: f64,
    },
}
