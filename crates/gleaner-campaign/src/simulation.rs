//! `gleaner simulate`'s run: the campaigns of a dataset preset, seeded synthetic farms or a
//! project's own record ([`crate::datasets`]), one after the other, their results written as
//! CSV ([`crate::results`]) and the report ([`crate::report`]) into one directory.

use std::path::{Path, PathBuf};

use gleaner_app::Progress;
use gleaner_field::UnixSeconds;

use crate::campaign::{CampaignResult, Replay, ReplayOptions, run_campaign};
use crate::datasets::{self, Preset, Setup, SyntheticFarm};
use crate::{Error, Result};

/// What a simulation replays.
#[derive(Debug, Clone)]
pub enum Source {
    /// A real dataset with its defaults, from the shared data directory.
    Preset(Preset),
    /// Seeded synthetic farms, one campaign each.
    Synthetic(Vec<SyntheticFarm>),
    /// A project's own record (the project is only read).
    Project(PathBuf),
}

/// A simulation: what it replays, how, and where its files go.
#[derive(Debug, Clone)]
pub struct SimulationRequest {
    /// What it replays.
    pub source: Source,
    /// The replay's options (strategies, seeds, budgets, times, flight conditions).
    pub options: ReplayOptions,
    /// Output directory: results CSV, the report, and the presets' project (`project/`) and
    /// synthetic farms (`farm-SEED/`).
    pub out: PathBuf,
    /// The shared data directory (presets).
    pub data_dir: PathBuf,
    /// Cell side, m [default: init's].
    pub cell_size_m: Option<f64>,
    /// The command line, quoted by the results and report to reproduce them.
    pub command_line: String,
}

/// What a simulation wrote.
#[derive(Debug, Clone)]
pub struct Simulation {
    /// Campaigns run.
    pub campaigns: usize,
    /// Runs over every campaign (strategy × seed × budget each).
    pub runs: usize,
    /// The report written (`report.md` in the output directory).
    pub report: PathBuf,
}

/// Runs `r`'s campaigns and writes their results and report into `r.out` (created if
/// missing); `clock_now` (s) is provenance only.
pub fn simulate(
    r: &SimulationRequest,
    clock_now: UnixSeconds,
    progress: &(dyn Progress + Sync),
) -> Result<Simulation> {
    std::fs::create_dir_all(&r.out)
        .map_err(|e| Error::file(&r.out, format!("cannot create: {e}")))?;
    let mut results: Vec<CampaignResult> = Vec::new();
    let mut run_one = |p: Replay| -> Result<()> {
        results.push(run_campaign(&p.request, &p.truth, progress)?);
        Ok(())
    };
    let project_dir = r.out.join("project");
    let setup = Setup {
        project_dir: &project_dir,
        cell_size_m: r.cell_size_m,
        options: &r.options,
        clock_now,
    };
    match &r.source {
        Source::Project(dir) => {
            run_one(datasets::project_replay(dir, &r.options, clock_now)?)?;
        }
        Source::Preset(p) => run_one(datasets::preset_replay(*p, &r.data_dir, &setup)?)?,
        Source::Synthetic(farms) => {
            for farm in farms {
                run_one(datasets::synthetic_replay(farm, &r.out, &setup)?)?;
            }
        }
    }
    crate::results::write_results(&r.out, &results, &r.command_line)?;
    let report = crate::report::write_report(&r.out)?;
    Ok(Simulation {
        campaigns: results.len(),
        runs: results.iter().map(|c| c.runs.len()).sum(),
        report,
    })
}

/// The summary line of a simulation written into `out`.
pub fn summary_line(s: &Simulation, out: &Path) -> String {
    format!(
        "{} campaign(s), {} runs; results in {}; report {}",
        s.campaigns,
        s.runs,
        out.display(),
        s.report.display()
    )
}
