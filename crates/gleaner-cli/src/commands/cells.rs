//! `gleaner cells`: the cell table with its metadata, as text or JSON.

use anyhow::Result;

use crate::args::{JsonArg, ProjectArg};

use gleaner_wire::docs::CellRowDoc;

/// How to order the table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum SortKey {
    /// By grid index (column, then row).
    Label,
    /// Most sensors first.
    Sensors,
    /// Highest score first (cells never scored last).
    Score,
    /// Longest since last collection first (never collected first).
    Stale,
}

/// Sorts rows in place.
pub fn sort(rows: &mut [CellRowDoc], key: SortKey) {
    match key {
        SortKey::Label => rows.sort_by_key(|r| (r.i, r.j)),
        SortKey::Sensors => rows.sort_by(|a, b| {
            b.sensors
                .len()
                .cmp(&a.sensors.len())
                .then((a.i, a.j).cmp(&(b.i, b.j)))
        }),
        SortKey::Score => rows.sort_by(|a, b| {
            let sa = a.scores.as_ref().map_or(f64::NEG_INFINITY, |s| s.score);
            let sb = b.scores.as_ref().map_or(f64::NEG_INFINITY, |s| s.score);
            sb.total_cmp(&sa).then((a.i, a.j).cmp(&(b.i, b.j)))
        }),
        SortKey::Stale => rows.sort_by(|a, b| {
            a.last_collected
                .cmp(&b.last_collected)
                .then((a.i, a.j).cmp(&(b.i, b.j)))
        }),
    }
}

// The arguments of `gleaner cells` (no doc comment: the variant's is the help).
#[derive(clap::Args)]
pub struct CellsArgs {
    #[command(flatten)]
    pub project: ProjectArg,
    #[command(flatten)]
    pub json: JsonArg,
    /// Order of the rows.
    #[arg(long, value_enum, default_value_t = SortKey::Label)]
    pub sort: SortKey,
}

/// Prints the cell table (or JSON).
pub fn run(args: CellsArgs) -> Result<()> {
    let p = args.project.open()?;
    let view = gleaner_app::field_view(&p)?;
    let mut rows: Vec<_> = view
        .cells
        .iter()
        .map(|c| gleaner_wire::convert::cell_row(c, view.cell_size_m))
        .collect();
    sort(&mut rows, args.sort);
    if args.json.json {
        return args.json.emit(&rows, "serialising cells", String::new);
    }
    let counts = gleaner_app::cell_reading_counts(&p)?;
    args.json.emit(&rows, "serialising cells", || {
        gleaner_wire::text::cells_table(&rows, &counts)
    })
}
