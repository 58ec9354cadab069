//! Text presentation, the CLI's output format beside the JSON documents: aligned tables and
//! one-line summaries made from the documents and the application layer's results. Pure: the
//! caller prints. Energies J, distances m, times s (RFC 3339 text, UTC), positions WGS84.

mod mission;
mod project;

pub use mission::{
    energy_line, exploration_table, mission_table, paper_line, replan_table, sorties_table,
    thousands, unreachable_lines, wind_lines,
};
pub use project::{
    cells_table, crash_report, ingest_line, init_lines, migration_lines, missions_table,
    reconstruction_table, record_line, scoring_table, series_csv, written_lines,
};
