//! Runs the peer protocol with its settings overridden from the environment, for choosing
//! settings on the tuning data (`gleaner evaluate peer` is the user-facing form):
//! `cargo run --release -p gleaner-eval --example peer -- hourly|tuning DATA [OUT.csv]`
//! with `SHRINK` (auto or an intensity), `NOISE` (share of the variance), `LAG_H` (hours), `COMMON` (1: a common level).
use std::path::PathBuf;

use gleaner_eval::peer::{self, Dataset, Estimator, Planner};
use gleaner_kriging::Shrinkage;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let dataset = match args.get(1).map_or("tuning", String::as_str) {
        "hourly" => Dataset::Hourly2015,
        _ => Dataset::TuningDaily,
    };
    let data = PathBuf::from(args.get(2).map_or("../shared/data", String::as_str));
    let (matrix, layouts, results, mut protocol) = peer::load(&data, dataset)?;
    if let Ok(x) = std::env::var("SHRINK") {
        protocol.fit.shrinkage = if x == "auto" {
            Shrinkage::Auto
        } else {
            Shrinkage::Fixed(x.parse()?)
        };
    }
    if let Ok(x) = std::env::var("NOISE") {
        protocol.fit.noise_share = x.parse()?;
    }
    if let Ok(x) = std::env::var("COMMON") {
        protocol.fit.common_mode = x == "1";
    }
    if let Ok(x) = std::env::var("LAG_H") {
        protocol.fit.max_lag_s = x.parse::<i64>()? * 3600;
    }
    let random: Vec<_> = layouts
        .into_iter()
        .filter(|l| l.name.starts_with("map_"))
        .collect();
    let planners = [Planner::Information, Planner::Count];
    let report = peer::run_protocol(
        &matrix,
        &random,
        &results,
        &protocol,
        &[],
        &planners,
        |_, _| {},
    )?;
    for p in planners {
        println!("{}", report.summary(p, Estimator::Dynamic));
    }
    if let Some(out) = args.get(3) {
        std::fs::write(out, report.outcomes_csv())?;
    }
    Ok(())
}
