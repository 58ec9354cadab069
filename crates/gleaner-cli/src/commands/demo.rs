//! `gleaner demo`: the whole story on built-in data (a seeded synthetic farm) or on the real
//! CAF network — exploration sorties that visit every cell, then adaptive missions, each
//! planned, exported, flown in simulation, recorded with the readings brought back, and
//! followed by a rescoring. The lifecycle and its report are `gleaner_campaign::demo`.

use std::path::PathBuf;

use anyhow::Result;
use gleaner_campaign::demo::{self, DemoRequest};

use crate::args::clock_now;
use crate::progress::Terminal;

// The arguments of `gleaner demo` (no doc comment: the variant's is the help).
#[derive(clap::Args)]
pub struct DemoArgs {
    /// Working directory; the files the demo writes there are replaced.
    #[arg(long, default_value = "gleaner-demo")]
    pub dir: PathBuf,
    /// The score the demo's project plans by (`gleaner`, the default, or the paper's S).
    #[arg(long, value_enum, default_value_t = crate::args::MethodArg::Gleaner)]
    pub method: crate::args::MethodArg,
    /// Seed of the synthetic farm.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Number of sensors.
    #[arg(long, default_value_t = 60)]
    pub sensors: usize,
    /// Days of history.
    #[arg(long, default_value_t = 180)]
    pub days: u32,
    /// Run on the real CAF network instead (the shared data directory, e.g.
    /// ../shared/data), with the paper's energy preset.
    #[arg(long)]
    pub data: Option<PathBuf>,
}

/// Runs the demo (`gleaner_campaign::demo`, which writes the missions' files); returns its
/// report.
pub fn run(args: &DemoArgs) -> Result<String> {
    let request = DemoRequest {
        dir: args.dir.clone(),
        gleaner_method: matches!(args.method, crate::args::MethodArg::Gleaner),
        seed: args.seed,
        sensors: args.sensors,
        days: args.days,
        data: args.data.clone(),
    };
    let d = demo::demo(&request, clock_now(), &Terminal::default())?;
    Ok(demo::story::story(&d, &request))
}
