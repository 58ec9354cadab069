//! Readers for the standard orienteering benchmarks, and a benchmark runner.
//!
//! - [`parse_classic`] reads the Tsiligirides / Chao text format (`Tmax P`, then `x y S` per
//!   point; path from point 1 to point 2; float Euclidean distances).
//! - [`parse_oplib`] reads OPLib (TSPLIB keywords plus `COST_LIMIT` and
//!   `NODE_SCORE_SECTION`; closed tour from the depot; EUC_2D, CEIL_2D, ATT, GEO and
//!   EXPLICIT distances with TSPLIB's integer rounding rules).
//! - Both return an [`OpInstance`]: name, set, size, budget, [`DistanceRule`], raw data, the
//!   generic [`gleaner_orienteering::Problem`] and, when looked up, the target score.
//!   [`OpInstance::validate_route`] re-checks a route with the instance's own distance rule.
//! - [`load_instance`] reads a file and finds its target in `targets.csv` (classic, by set
//!   and budget) or `ea4op_best.csv` (OPLib, by instance name) in the same directory tree.
//! - [`run_benchmark`] solves a list of files and returns [`BenchRow`]s; [`summarize`],
//!   [`format_table`] and [`format_csv`] turn them into a [`BenchSummary`], an aligned text
//!   table and CSV. The library never prints; progress goes through a callback.
//! - Each [`BenchRow`] carries the solver's routes with node ids as numbered in the instance
//!   file (1-based); [`write_routes`] writes them one line per instance
//!   (`instance<TAB>solver<TAB>score<TAB>1 5 3 ... 2`) and [`parse_routes`] reads them back, so
//!   a claimed score can be re-checked ([`OpInstance::route_from_node_ids`],
//!   [`OpInstance::score_routes`]) or with anyone's own tools.
//! - Files larger than [`MAX_NODES`] nodes, and `DIMENSION`s or path counts the file cannot
//!   back, are refused before anything is sized by them.
//!
//! Errors ([`FormatError`]) name the file, the line and the field.
//!
//! ```
//! use gleaner_op_formats::{DistanceRule, parse_oplib};
//! use gleaner_orienteering::{SolveOptions, solve_default};
//! let text = "NAME : tiny\nTYPE : OP\nDIMENSION : 4\nCOST_LIMIT : 20\n\
//!             EDGE_WEIGHT_TYPE : EUC_2D\nNODE_COORD_SECTION\n1 0 0\n2 0 5\n3 5 5\n4 30 0\n\
//!             NODE_SCORE_SECTION\n1 0\n2 3\n3 4\n4 50\nDEPOT_SECTION\n1\n-1\nEOF\n";
//! let inst = parse_oplib("tiny", "demo", text)?;
//! assert_eq!((inst.n, inst.budget, inst.rule), (4, 20.0, DistanceRule::Euc2d));
//! let best = solve_default(&inst.problem, &SolveOptions::default().with_iterations(50));
//! let check = inst.validate_route(&best.routes[0])?;
//! assert_eq!(check.score, 7.0); // node 4 is 60 away and back: over the budget of 20
//! assert_eq!(check.length, 17.0); // 5 + 5 + nint(7.07): EUC_2D rounds each leg
//! # Ok::<(), gleaner_op_formats::FormatError>(())
//! ```
//!
//! Benchmark results of gleaner's default solver on these sets are in `RESULTS.md` next to
//! this crate's manifest; `examples/run_bench.rs` reproduces them.
#![deny(missing_docs)]

mod bench;
mod error;
mod instance;
mod parse;

pub use bench::{
    BenchRow, BenchSummary, RouteRecord, benchmark_files, find_instances, format_csv, format_table,
    load_instance, parse_classic_targets, parse_oplib_best, parse_routes, run_benchmark,
    run_instance, summarize, write_routes,
};
pub use error::FormatError;
pub use instance::{DistanceRule, OpFormat, OpInstance, RouteCheck};
pub use parse::{MAX_NODES, parse_classic, parse_oplib};
