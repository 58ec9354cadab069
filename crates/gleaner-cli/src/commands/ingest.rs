//! `gleaner ingest`: stores readings files with the application layer's
//! [`gleaner_app::ingest`] and prints the one-line summary.

use std::path::PathBuf;

use anyhow::Result;
use clap::ValueEnum;
use gleaner_app as app;

use crate::args::{ProjectArg, clock_now};
use crate::output::outln;
use crate::progress::Terminal;

// The arguments of `gleaner ingest` (no doc comment: the variant's is the help).
#[derive(clap::Args)]
pub struct IngestArgs {
    /// Files to ingest.
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
    #[command(flatten)]
    pub project: ProjectArg,
    /// File format.
    #[arg(long, value_enum, default_value_t = FormatArg::Auto)]
    pub format: FormatArg,
    /// Wide files: the modality of every sensor column, e.g. `vw@30cm`.
    #[arg(long)]
    pub modality: Option<String>,
    /// Wide files: the unit of the values, e.g. `m3/m3`.
    #[arg(long)]
    pub unit: Option<String>,
    /// Wide files: hours the file's clock is ahead of UTC (e.g. -8 for PST).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub utc_offset: f64,
    /// What to do with a bad row: stop and store nothing, or skip it and report it.
    #[arg(long, value_enum, default_value_t = OnErrorArg::Fail)]
    pub on_error: OnErrorArg,
    /// Hubbard Brook logger files: the probe metadata [default: sensor_metadata.csv beside
    /// each file].
    #[arg(long)]
    pub metadata: Option<PathBuf>,
}

// A readings file's format (no doc comments: clap would show them).
#[derive(Clone, Copy, ValueEnum)]
pub enum FormatArg {
    Auto,
    LongCsv,
    WideCsv,
    CafDaily,
    HubbardBrook,
}

// What to do with a bad row.
#[derive(Clone, Copy, ValueEnum)]
pub enum OnErrorArg {
    Fail,
    Skip,
}

/// Ingests the files; prints the summary.
pub fn run(args: IngestArgs, progress: &Terminal) -> Result<()> {
    let mut p = args.project.open()?;
    let outcome = app::ingest(
        &mut p,
        &app::IngestRequest {
            files: args.files,
            format: match args.format {
                FormatArg::Auto => app::Format::Auto,
                FormatArg::LongCsv => app::Format::Long,
                FormatArg::WideCsv => app::Format::Wide,
                FormatArg::CafDaily => app::Format::CafDaily,
                FormatArg::HubbardBrook => app::Format::HubbardBrook,
            },
            modality: args.modality,
            unit: args.unit,
            utc_offset_h: args.utc_offset,
            on_error: match args.on_error {
                OnErrorArg::Fail => app::OnError::Fail,
                OnErrorArg::Skip => app::OnError::Skip,
            },
            metadata: args.metadata,
            now: None,
        },
        clock_now(),
        progress,
    )?;
    outln(&gleaner_wire::text::ingest_line(&outcome))
}
