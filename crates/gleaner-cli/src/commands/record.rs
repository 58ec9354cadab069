//! `gleaner record`: records a flown mission with the application layer's
//! [`gleaner_app::record_flight`] and prints the one-line summary.

use std::path::PathBuf;

use anyhow::Result;
use gleaner_app::{self as app, MissionId};

use crate::args::{ProjectArg, clock_now, parse_time};
use crate::output::outln;
use crate::progress::Terminal;

// The arguments of `gleaner record` (no doc comment: the variant's is the help).
#[derive(clap::Args)]
pub struct RecordArgs {
    #[command(flatten)]
    pub project: ProjectArg,
    /// The planned mission's id (printed by `gleaner plan`).
    #[arg(long)]
    pub mission: i64,
    /// Collection time (RFC 3339 or date), not before the mission's planned time [default:
    /// the planned time].
    #[arg(long, value_parser = parse_time)]
    pub at: Option<i64>,
    /// Cells actually visited, comma-separated, in order, each one of the mission's stops
    /// [default: the planned stops].
    #[arg(long, value_delimiter = ',')]
    pub cells: Option<Vec<String>>,
    /// Replace an earlier record of this mission (otherwise recording a mission twice is
    /// refused).
    #[arg(long)]
    pub amend: bool,
    /// Readings files brought back (any format `gleaner ingest` reads); every reading must
    /// come from a sensor in a visited cell and be dated no later than the collection.
    pub files: Vec<PathBuf>,
}

/// Records the flight; prints the summary.
pub fn run(args: RecordArgs, progress: &Terminal) -> Result<()> {
    let mut p = args.project.open()?;
    let outcome = app::record_flight(
        &mut p,
        &app::RecordRequest {
            mission: MissionId(args.mission),
            at: args.at,
            cells: args.cells,
            readings: (!args.files.is_empty()).then(|| app::IngestRequest {
                files: args.files,
                ..Default::default()
            }),
            amend: args.amend,
        },
        clock_now(),
        progress,
    )?;
    outln(&gleaner_wire::text::record_line(&outcome))
}
