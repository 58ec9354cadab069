//! Orienteering and team orienteering solvers.
//!
//! TODO docs
#![deny(missing_docs)]

mod engine;
mod error;
mod exact;
mod problem;
mod solution;
mod solve;

pub use error::{ProblemError, SolutionError, SolveError};
pub use exact::{EXACT_MAX_NODES, EXACT_MAX_NODES_TEAM, exact};
pub use problem::{Metric, Problem};
pub use solution::{Solution, evaluate, route_cost};
pub use solve::{SolveOptions, SolverKind, greedy, solve, solve_default};
