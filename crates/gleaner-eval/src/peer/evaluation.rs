//! The whole evaluation `gleaner evaluate peer` runs: the protocol data loaded, both planners
//! run over every layout, capacity and window, and the summary with the peer's published
//! errors beside gleaner's.

use std::path::Path;

use super::{
    Dataset, FROZEN_ESTIMATOR, FROZEN_PLANNER, PEER_CAPACITIES_J, Planner, WindowsData, load,
    load_windows, paired_difference, run_windows, window_means,
};
use crate::EvalError;

/// Which protocol data to run on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PeerData {
    /// The hold-out: hourly VW 30 cm, Jan-Apr 2015 (the peer's own data).
    Holdout,
    /// The tuning twin: CAF daily VW 30 cm, train 2012, test 2013.
    Tuning,
    /// 21-day windows of CAF daily VW 30 cm through a year, each trained on the 365 days
    /// before it: 2013 is tuning at the hold-out's horizon, later years hold-out windows.
    Windows(i32),
}

impl PeerData {
    /// The data's title in the summary.
    pub fn title(self) -> String {
        match self {
            PeerData::Holdout => "hold-out: hourly VW 30 cm, Jan-Apr 2015".into(),
            PeerData::Tuning => "tuning: CAF daily VW 30 cm, train 2012, test 2013".into(),
            PeerData::Windows(2013) => {
                "tuning: CAF daily VW 30 cm, 21-day windows through 2013".into()
            }
            PeerData::Windows(year) => {
                format!("hold-out: CAF daily VW 30 cm, 21-day windows through {year}")
            }
        }
    }
}

/// Loads the protocol data of `on` from the data directory: the matrix, the layouts, the
/// peer's results and the protocols (one, or one per window).
pub fn load_data(data: &Path, on: PeerData) -> Result<WindowsData, EvalError> {
    match on {
        PeerData::Windows(year) => load_windows(data, year),
        PeerData::Holdout | PeerData::Tuning => {
            let dataset = match on {
                PeerData::Holdout => Dataset::Hourly2015,
                _ => Dataset::TuningDaily,
            };
            let (m, l, r, p) = load(data, dataset)?;
            Ok((m, l, r, vec![p]))
        }
    }
}

/// What the evaluation writes.
#[derive(Debug, Clone, PartialEq)]
pub struct PeerEvaluation {
    /// `summary.md`: both planners' errors with the frozen estimator beside the peer's.
    pub summary: String,
    /// `outcomes.csv`: every layout, capacity, planner and estimator.
    pub outcomes_csv: String,
    /// `windows.csv` with several windows: each window's mean error over 8-32 kJ per planner.
    pub windows_csv: Option<String>,
}

/// The summary's heading: the data's title and the frozen pipeline.
pub fn summary_heading(title: &str) -> String {
    format!(
        "# gleaner on the peer protocol ({title})\n\nFrozen pipeline: planner `{}`, estimator `{}`.\n\n",
        FROZEN_PLANNER.name(),
        FROZEN_ESTIMATOR.name()
    )
}

/// Runs `count` and `information` over the loaded data with the unshared drift weight
/// `unshared_weight` (≥ 0); `progress(done, total)` after each layout and protocol.
pub fn evaluate(
    loaded: WindowsData,
    on: PeerData,
    unshared_weight: f64,
    progress: impl FnMut(usize, usize),
) -> Result<PeerEvaluation, EvalError> {
    let (matrix, layouts, results, mut protocols) = loaded;
    for p in &mut protocols {
        p.unshared_weight = unshared_weight;
    }
    let planners = [Planner::Count, Planner::Information];
    let (report, each) = run_windows(
        &matrix,
        &layouts,
        &results,
        &protocols,
        &PEER_CAPACITIES_J,
        &planners,
        progress,
    )?;
    let mut summary = summary_heading(&on.title());
    for p in planners {
        summary.push_str(&report.summary(p, FROZEN_ESTIMATOR));
        summary.push('\n');
    }
    let mut windows_csv = None;
    if each.len() > 1 {
        let windows = window_means(
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
        windows_csv = Some(table);
        if let Some((d, lo, hi, n)) =
            paired_difference(&windows, Planner::Count, Planner::Information)
        {
            summary.push_str(&format!(
                "Paired over {n} windows, `count` − `information` (mean 8–32 kJ, ×10⁻³): {:.3} [{:.3}, {:.3}] (95%, Student's t).\n",
                d * 1e3,
                lo * 1e3,
                hi * 1e3
            ));
        }
    }
    Ok(PeerEvaluation {
        summary,
        outcomes_csv: report.outcomes_csv(),
        windows_csv,
    })
}
