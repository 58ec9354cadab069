//! `gleaner score`: the scoring as a table (or JSON).

use std::path::PathBuf;

use anyhow::Result;
use gleaner_app as app;

use crate::args::{JsonArg, ProjectArg, WhenArgs};
use crate::output::warn;

use gleaner_wire::docs::{ScoreRowDoc, ScoringDoc};

/// How to order scored cells.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum ScoreSort {
    /// Highest S first (the default).
    #[default]
    #[value(name = "s")]
    Score,
    /// Highest F first.
    #[value(name = "f")]
    Freshness,
    /// Highest R first.
    #[value(name = "r")]
    Redundancy,
    /// Highest A first.
    #[value(name = "a")]
    Anomaly,
    /// Highest U first.
    #[value(name = "u")]
    Uncertainty,
    /// By cell id.
    Cell,
}

/// Sorts the document's cells (ties by cell id).
pub fn sort(doc: &mut ScoringDoc, key: ScoreSort) {
    let value = |c: &ScoreRowDoc| match key {
        ScoreSort::Score | ScoreSort::Cell => c.s,
        ScoreSort::Freshness => c.f,
        ScoreSort::Redundancy => c.r,
        ScoreSort::Anomaly => c.a,
        ScoreSort::Uncertainty => c.u,
    };
    if key == ScoreSort::Cell {
        doc.cells.sort_by(|a, b| a.cell.cmp(&b.cell));
    } else {
        doc.cells
            .sort_by(|a, b| value(b).total_cmp(&value(a)).then(a.cell.cmp(&b.cell)));
    }
}

// The arguments of `gleaner score` (no doc comment: the variant's is the help).
#[derive(clap::Args)]
pub struct ScoreArgs {
    #[command(flatten)]
    pub project: ProjectArg,
    #[command(flatten)]
    pub when: WhenArgs,
    /// Per-cell class probabilities from your own model, instead of the built-in one.
    #[arg(long)]
    pub probabilities: Option<PathBuf>,
    #[command(flatten)]
    pub json: JsonArg,
    /// Rows of the table.
    #[arg(long, default_value_t = 20)]
    pub limit: usize,
    /// Order of the rows (largest first; `cell` by id).
    #[arg(long, value_enum, default_value_t = ScoreSort::Score)]
    pub sort: ScoreSort,
}

/// Scores the cells; prints the table (or JSON).
pub fn run(args: ScoreArgs) -> Result<()> {
    let mut p = args.project.open()?;
    let scoring = app::score(
        &mut p,
        &app::ScoreRequest {
            at: args.when.at,
            history: args.when.history(),
            probabilities: args.probabilities,
            dry_run: false,
        },
    )?;
    warn(&scoring);
    let mut doc = gleaner_wire::convert::scoring(&scoring);
    sort(&mut doc, args.sort);
    args.json.emit(&doc, "serialising scores", || {
        gleaner_wire::text::scoring_table(&doc, args.limit)
    })
}
