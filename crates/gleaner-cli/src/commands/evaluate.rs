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
}

impl PeerData {
    /// The year of a rolling-window data set.
    fn windows_year(self) -> Option<i32> {
        match self {
            PeerData::TuningWindows => Some(2013),
            PeerData::Windows2014 => Some(2014),
            PeerData::Windows2015 => Some(2015),
            PeerData::Windows2016 => Some(2016),
            PeerData::Holdout | PeerData::Tuning | PeerData::HubbardBrook => None,
        }
    }

    fn title(self) -> String {
        match self {
            PeerData::Holdout => "hold-out: hourly VW 30 cm, Jan-Apr 2015".into(),
            PeerData::Tuning => "tuning: CAF daily VW 30 cm, train 2012, test 2013".into(),
            PeerData::TuningWindows => {
                "tuning: CAF daily VW 30 cm, 21-day windows through 2013".into()
            }
            PeerData::HubbardBrook => "hold-out: Hubbard Brook hourly water content".into(),
            d => format!(
                "hold-out: CAF daily VW 30 cm, 21-day windows through {}",
                d.windows_year().unwrap_or_default()
            ),
        }
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

/// Runs the protocol; returns the summary text.
pub fn run_peer(args: &PeerArgs) -> Result<String> {
    let context = || format!("{} (set GLEANER_DATA_DIR)", args.data.display());
    if args.on == PeerData::HubbardBrook {
        return run_hubbard_brook(args);
    }
    let (matrix, layouts, results, mut protocols) = match args.on.windows_year() {
        Some(year) => peer::load_windows(&args.data, year).with_context(context)?,
        None => {
            let dataset = match args.on {
                PeerData::Holdout => Dataset::Hourly2015,
                _ => Dataset::TuningDaily,
            };
            let (m, l, r, p) = peer::load(&args.data, dataset).with_context(context)?;
            (m, l, r, vec![p])
        }
    };
    if !(args.unshared_weight.is_finite() && args.unshared_weight >= 0.0) {
        anyhow::bail!(
            "--unshared-weight {}: expected a number >= 0",
            args.unshared_weight
        );
    }
    for p in &mut protocols {
        p.unshared_weight = args.unshared_weight;
    }
    let planners = [Planner::Count, Planner::Information];
    let total = (layouts.len() * protocols.len()) as u64;
    let bar = crate::progress::bar(total, "layouts");
    let (report, each) = peer::run_windows(
        &matrix,
        &layouts,
        &results,
        &protocols,
        &peer::PEER_CAPACITIES_J,
        &planners,
        |done, _| bar.set_position(done as u64),
    )?;
    bar.finish_and_clear();
    let mut summary = start_output(args)?;
    for p in planners {
        summary.push_str(&report.summary(p, FROZEN_ESTIMATOR));
        summary.push('\n');
    }
    if each.len() > 1 {
        let windows = peer::window_means(
            &matrix,
            &protocols,
            &each,
            &planners,
            FROZEN_ESTIMATOR,
            (8e3, 32e3),
        );
        let mut table = String::from("window_start,planner,mean_error_8_32kJ\n");
        for w in &windows {
            for (p, m) in &w.means {
                let m = m.map_or("inf".to_string(), |x| x.to_string());
                let day = gleaner_field::time::format_rfc3339(w.start);
                table.push_str(&format!("{},{},{m}\n", &day[..10], p.name()));
            }
        }
        let path = args.out.join("windows.csv");
        std::fs::write(&path, table).with_context(|| format!("cannot write {}", path.display()))?;
        if let Some((d, lo, hi, n)) =
            peer::paired_difference(&windows, Planner::Count, Planner::Information)
        {
            summary.push_str(&format!(
                "Paired over {n} windows, `count` − `information` (mean 8–32 kJ, ×10⁻³): {:.3} [{:.3}, {:.3}] (95%, Student's t).\n",
                d * 1e3,
                lo * 1e3,
                hi * 1e3
            ));
        }
    }
    let csv = args.out.join("outcomes.csv");
    std::fs::write(&csv, report.outcomes_csv())
        .with_context(|| format!("cannot write {}", csv.display()))?;
    let md = args.out.join("summary.md");
    std::fs::write(&md, &summary).with_context(|| format!("cannot write {}", md.display()))?;
    Ok(summary)
}

/// `--on hubbard-brook`: both depths, one summary.
fn run_hubbard_brook(args: &PeerArgs) -> Result<String> {
    use gleaner_eval::hubbard::{self, Depth};
    if args.unshared_weight != 0.0 {
        anyhow::bail!("--unshared-weight is not used with --on hubbard-brook");
    }
    let dir = args.data.join("hubbard_brook");
    let mut summary = start_output(args)?;
    for depth in Depth::ALL {
        let data = hubbard::load(&dir, depth)
            .with_context(|| format!("{} (set GLEANER_DATA_DIR)", dir.display()))?;
        let bar = crate::progress::bar(data.protocols.len() as u64, "windows");
        let out = hubbard::run(data, |done, _| bar.set_position(done as u64))?;
        bar.finish_and_clear();
        summary.push_str(&out.summary());
        summary.push('\n');
        let name = match depth {
            Depth::Shallow => "outcomes-shallow.csv",
            Depth::Cm50 => "outcomes-50cm.csv",
        };
        let csv = args.out.join(name);
        std::fs::write(&csv, out.mean.outcomes_csv())
            .with_context(|| format!("cannot write {}", csv.display()))?;
    }
    let md = args.out.join("summary.md");
    std::fs::write(&md, &summary).with_context(|| format!("cannot write {}", md.display()))?;
    Ok(summary)
}

/// Creates the output directory; returns the summary's heading.
fn start_output(args: &PeerArgs) -> Result<String> {
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    Ok(format!(
        "# gleaner on the peer protocol ({})\n\nFrozen pipeline: planner `{}`, estimator `{}`.\n\n",
        args.on.title(),
        FROZEN_PLANNER.name(),
        FROZEN_ESTIMATOR.name()
    ))
}
