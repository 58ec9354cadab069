//! `gleaner evaluate peer`: the peer study's one-shot selection protocol on CAF, run by
//! gleaner-eval; this module only translates arguments.

use std::path::PathBuf;

use anyhow::Result;
use clap::{Args, ValueEnum};
use gleaner_eval::{PeerRun, peer};

/// Which protocol data to run on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum PeerData {
    /// The hold-out: hourly VW 30 cm, Jan-Apr 2015 (the peer's own data).
    Holdout,
    /// The tuning twin: CAF daily VW 30 cm, train 2012, test 2013.
    Tuning,
    /// Tuning at the hold-out's horizon: CAF daily VW 30 cm, 21-day test windows through
    /// 2013, each trained on the 365 days before it (errors are means over the windows).
    TuningWindows,
    /// Hold-out windows of 2014 (as `tuning-windows`).
    #[value(name = "windows-2014")]
    Windows2014,
    /// Hold-out windows of 2015.
    #[value(name = "windows-2015")]
    Windows2015,
    /// Hold-out windows of 2016 (to the data's end, 16 June).
    #[value(name = "windows-2016")]
    Windows2016,
    /// Hold-out on another network: Hubbard Brook hourly water content (shallow and 50 cm),
    /// windows of 1,001 training and 500 test hours, capacities 0.2-0.8 of the every-site
    /// tour's energy (outcomes-shallow.csv, outcomes-50cm.csv, summary.md).
    HubbardBrook,
    /// The second Hubbard Brook hold-out: water content in the hours after the first one's
    /// data end (the sites with a value in at least half of them) and soil temperature over
    /// every complete hour, shallow and 50 cm each (outcomes-<data set>.csv, summary.md).
    #[value(name = "hubbard-brook-2")]
    HubbardBrook2,
}

impl PeerData {
    /// The evaluation to run.
    fn run(self) -> PeerRun {
        use gleaner_eval::hubbard::Registration;
        PeerRun::Caf(match self {
            PeerData::Holdout => peer::PeerData::Holdout,
            PeerData::Tuning => peer::PeerData::Tuning,
            PeerData::TuningWindows => peer::PeerData::Windows(2013),
            PeerData::Windows2014 => peer::PeerData::Windows(2014),
            PeerData::Windows2015 => peer::PeerData::Windows(2015),
            PeerData::Windows2016 => peer::PeerData::Windows(2016),
            PeerData::HubbardBrook => return PeerRun::Hubbard(Registration::First),
            PeerData::HubbardBrook2 => return PeerRun::Hubbard(Registration::Second),
        })
    }
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

/// Runs the protocol (`gleaner_eval::run_peer`, which writes its files); returns the summary.
pub fn run_peer(args: &PeerArgs) -> Result<String> {
    let run = args.on.run();
    let what = if matches!(run, PeerRun::Caf(_)) {
        "layouts"
    } else {
        "windows"
    };
    let bar = crate::progress::bar(0, what);
    let summary = gleaner_eval::run_peer(
        &args.data,
        &args.out,
        run,
        args.unshared_weight,
        |done, total| {
            bar.set_length(total as u64);
            bar.set_position(done as u64)
        },
    )?;
    bar.finish_and_clear();
    Ok(summary)
}
