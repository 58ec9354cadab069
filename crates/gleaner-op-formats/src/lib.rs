//! Readers for the standard orienteering benchmarks and a benchmark runner. TODO docs
#![deny(missing_docs)]

mod bench;
mod error;
mod instance;
mod parse;

pub use bench::{
    BenchRow, BenchSummary, find_instances, format_csv, format_table, load_instance,
    parse_classic_targets, parse_oplib_best, run_benchmark, run_instance, summarize,
};
pub use error::FormatError;
pub use instance::{DistanceRule, OpFormat, OpInstance, RouteCheck};
pub use parse::{parse_classic, parse_oplib};
