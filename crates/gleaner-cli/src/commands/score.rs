//! `gleaner score`: the scoring as a table (or JSON).

use std::path::PathBuf;

use anyhow::Result;
use gleaner_app as app;

use crate::{JsonArg, ProjectArg, WhenArgs, warn};

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

/// The table: header lines with the weights, then one line per cell.
pub fn table(doc: &ScoringDoc, limit: usize) -> String {
    let mut out =
        format!(
            "scored at {}  S = {}·F + {}·A + {}·U − {}·R  (anomaly: {}{})\n",
            doc.t,
            doc.weights[0],
            doc.weights[1],
            doc.weights[2],
            doc.weights[3],
            doc.anomaly_form,
            doc.condition.as_ref().map_or(
                String::from(", no condition model: U = 0"),
                |c| format!(", U from {}: {}", c.modality, c.classes.join("/"))
            )
        );
    out.push_str(&format!(
        "{:<10} {:>7} {:>6} {:>6} {:>8} {:>6} {:>8}  {}\n",
        "cell", "sensors", "F", "R", "A", "U", "S", "driver"
    ));
    for c in doc.cells.iter().take(limit) {
        out.push_str(&format!(
            "{:<10} {:>7} {:>6.3} {:>6.3} {:>8.3} {:>6.3} {:>8.3}  {}\n",
            c.cell, c.sensors, c.f, c.r, c.a, c.u, c.s, c.driver
        ));
    }
    out
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
    args.json
        .emit(&doc, "serialising scores", || table(&doc, args.limit))
}
