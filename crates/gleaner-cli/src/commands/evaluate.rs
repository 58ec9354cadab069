//! `gleaner evaluate peer`: the peer study's one-shot selection protocol on CAF, run by
//! gleaner-eval; this module only translates arguments and writes the files.

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::{Args, ValueEnum};
use gleaner_eval::peer;

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
    /// The CAF data of the protocol; `None` for Hubbard Brook (its own pipeline).
    fn data(self) -> Option<peer::PeerData> {
        Some(match self {
            PeerData::Holdout => peer::PeerData::Holdout,
            PeerData::Tuning => peer::PeerData::Tuning,
            PeerData::TuningWindows => peer::PeerData::Windows(2013),
            PeerData::Windows2014 => peer::PeerData::Windows(2014),
            PeerData::Windows2015 => peer::PeerData::Windows(2015),
            PeerData::Windows2016 => peer::PeerData::Windows(2016),
            PeerData::HubbardBrook | PeerData::HubbardBrook2 => return None,
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

/// Runs the protocol (`gleaner_eval::peer::evaluate`), writes its files; returns the summary.
pub fn run_peer(args: &PeerArgs) -> Result<String> {
    let context = || format!("{} (set GLEANER_DATA_DIR)", args.data.display());
    let Some(on) = args.on.data() else {
        return run_hubbard_brook(args);
    };
    let loaded = peer::load_data(&args.data, on).with_context(context)?;
    if !(args.unshared_weight.is_finite() && args.unshared_weight >= 0.0) {
        anyhow::bail!(
            "--unshared-weight {}: expected a number >= 0",
            args.unshared_weight
        );
    }
    let bar = crate::progress::bar((loaded.1.len() * loaded.3.len()) as u64, "layouts");
    let e = peer::evaluate(loaded, on, args.unshared_weight, |done, _| {
        bar.set_position(done as u64)
    })?;
    bar.finish_and_clear();
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let files = [
        ("windows.csv", e.windows_csv.as_deref()),
        ("outcomes.csv", Some(e.outcomes_csv.as_str())),
        ("summary.md", Some(e.summary.as_str())),
    ];
    for (name, text) in files {
        if let Some(text) = text {
            let path = args.out.join(name);
            std::fs::write(&path, text)
                .with_context(|| format!("cannot write {}", path.display()))?;
        }
    }
    Ok(e.summary)
}

/// `--on hubbard-brook` / `hubbard-brook-2`: every data set of the registration, one summary.
fn run_hubbard_brook(args: &PeerArgs) -> Result<String> {
    use gleaner_eval::hubbard::Registration;
    if args.unshared_weight != 0.0 {
        anyhow::bail!("--unshared-weight is not used with --on hubbard-brook");
    }
    let registration = match args.on {
        PeerData::HubbardBrook2 => Registration::Second,
        _ => Registration::First,
    };
    let dir = args.data.join("hubbard_brook");
    let bar = crate::progress::bar(0, "windows");
    let e = gleaner_eval::hubbard::evaluate(&dir, registration, |done, total| {
        bar.set_length(total as u64);
        bar.set_position(done as u64)
    })
    .with_context(|| format!("{} (set GLEANER_DATA_DIR)", dir.display()))?;
    bar.finish_and_clear();
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let files = e
        .outcomes
        .iter()
        .map(|(name, csv)| (name.as_str(), csv.as_str()));
    for (name, text) in files.chain([("summary.md", e.summary.as_str())]) {
        let path = args.out.join(name);
        std::fs::write(&path, text).with_context(|| format!("cannot write {}", path.display()))?;
    }
    Ok(e.summary)
}
