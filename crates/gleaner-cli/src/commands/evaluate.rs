//! `gleaner evaluate peer`: the peer study's one-shot selection protocol on CAF, run by
//! gleaner-eval; this module only translates arguments and writes the files.

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::{Args, ValueEnum};
use gleaner_eval::peer::{self, Dataset, FROZEN_ESTIMATOR, FROZEN_PLANNER, Planner};

/// Which protocol data to run on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum PeerData {
    /// The hold-out: hourly VW 30 cm, Jan-Apr 2015 (the peer's own data).
    Holdout,
    /// The tuning twin: CAF daily VW 30 cm, train 2012, test 2013.
    Tuning,
}

/// Arguments of `gleaner evaluate peer`.
#[derive(Debug, Args)]
pub struct PeerArgs {
    /// Shared data directory [env GLEANER_DATA_DIR, default ../shared/data].
    #[arg(long, env = "GLEANER_DATA_DIR", default_value = "../shared/data")]
    pub data: PathBuf,
    /// Output directory (outcomes.csv, summary.md).
    #[arg(long)]
    pub out: PathBuf,
    /// Data to run on.
    #[arg(long, value_enum, default_value_t = PeerData::Holdout)]
    pub on: PeerData,
    /// Weight of the unshared per-sensor drift in the `information` planner's value (a visited
    /// sensor also removes its own drift over the test: fitted rate × mean horizon × weight;
    /// 0 = none, the registered pipeline).
    #[arg(long, default_value_t = 0.0)]
    pub unshared_weight: f64,
}

/// Runs the protocol; returns the summary text.
pub fn run_peer(args: &PeerArgs) -> Result<String> {
    let dataset = match args.on {
        PeerData::Holdout => Dataset::Hourly2015,
        PeerData::Tuning => Dataset::TuningDaily,
    };
    let (matrix, layouts, results, mut protocol) = peer::load(&args.data, dataset)
        .with_context(|| format!("{} (set GLEANER_DATA_DIR)", args.data.display()))?;
    if !(args.unshared_weight.is_finite() && args.unshared_weight >= 0.0) {
        anyhow::bail!(
            "--unshared-weight {}: expected a number >= 0",
            args.unshared_weight
        );
    }
    protocol.unshared_weight = args.unshared_weight;
    let planners = [Planner::Count, Planner::Information];
    let bar = crate::progress::bar(layouts.len() as u64, "layouts");
    let report = peer::run_protocol(
        &matrix,
        &layouts,
        &results,
        &protocol,
        &peer::PEER_CAPACITIES_J,
        &planners,
        |done, _| bar.set_position(done as u64),
    )?;
    bar.finish_and_clear();
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let mut summary = format!(
        "# gleaner on the peer protocol ({})\n\nFrozen pipeline: planner `{}`, estimator `{}`.\n\n",
        match args.on {
            PeerData::Holdout => "hold-out: hourly VW 30 cm, Jan-Apr 2015",
            PeerData::Tuning => "tuning: CAF daily VW 30 cm, train 2012, test 2013",
        },
        FROZEN_PLANNER.name(),
        FROZEN_ESTIMATOR.name()
    );
    for p in planners {
        summary.push_str(&report.summary(p, FROZEN_ESTIMATOR));
        summary.push('\n');
    }
    let csv = args.out.join("outcomes.csv");
    std::fs::write(&csv, report.outcomes_csv())
        .with_context(|| format!("cannot write {}", csv.display()))?;
    let md = args.out.join("summary.md");
    std::fs::write(&md, &summary).with_context(|| format!("cannot write {}", md.display()))?;
    Ok(summary)
}
