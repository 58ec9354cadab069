//! Runs the peer protocol with its settings overridden from the environment, for choosing
//! settings on the tuning data (`gleaner evaluate peer` is the user-facing form):
//! `cargo run --release -p gleaner-eval --example peer -- hourly|tuning|windowsYEAR DATA [OUT.csv]`
//! with `SHRINK` (auto or an intensity), `NOISE` (share of the variance), `LAG_H` (hours), `COMMON` (1: a common level),
//! `UW` (the information planner's unshared-drift weight).
use std::path::PathBuf;

use gleaner_eval::peer::{self, Dataset, Estimator, Planner};
use gleaner_kriging::Shrinkage;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let which = args.get(1).map_or("tuning", String::as_str);
    let data = PathBuf::from(args.get(2).map_or("../shared/data", String::as_str));
    let windows_year: Option<i32> = which.strip_prefix("windows").map(str::parse).transpose()?;
    let (matrix, layouts, results, mut protocols) = match windows_year {
        Some(year) => peer::load_windows(&data, year)?,
        None => {
            let dataset = match which {
                "hourly" => Dataset::Hourly2015,
                _ => Dataset::TuningDaily,
            };
            let (m, l, r, p) = peer::load(&data, dataset)?;
            (m, l, r, vec![p])
        }
    };
    for protocol in &mut protocols {
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
        if let Ok(x) = std::env::var("UW") {
            protocol.unshared_weight = x.parse()?;
        }
    }
    let random: Vec<_> = layouts
        .into_iter()
        .filter(|l| l.name.starts_with("map_"))
        .collect();
    let planners = [Planner::Information, Planner::Count];
    let (report, _) = peer::run_windows(
        &matrix,
        &random,
        &results,
        &protocols,
        &[],
        &planners,
        |done, total| eprint!("\r{done}/{total}"),
    )?;
    eprintln!();
    for p in planners {
        println!("{}", report.summary(p, Estimator::Dynamic));
    }
    if let Some(out) = args.get(3) {
        std::fs::write(out, report.outcomes_csv())?;
    }
    Ok(())
}
