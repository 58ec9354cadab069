//! `gleaner migrate`: copies a project's data into another database (SQLite file <->
//! PostgreSQL project) with the application layer's [`gleaner_app::migrate`].

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use clap::Args;
use gleaner_app::{self as app, Progress, Project, Settings};

/// `gleaner migrate` arguments.
#[derive(Args)]
pub struct MigrateArgs {
    /// Project directory.
    #[arg(long = "project", value_name = "PROJECT", default_value = ".")]
    pub dir: PathBuf,
    /// The source database instead of the project's `database` setting.
    #[arg(long, value_name = "FILE_OR_URL")]
    pub database: Option<String>,
    /// The target: `postgres://user:password@host:port/db[#schema]` (the schema defaults to
    /// the project's name) or an SQLite file (relative to the project directory). It must be
    /// empty; it is created when missing.
    #[arg(long, value_name = "FILE_OR_URL")]
    pub to: String,
    /// Afterwards, point the project's `database` setting at the target.
    #[arg(long)]
    pub switch: bool,
}

/// Runs the copy; returns the report line.
pub fn run(args: &MigrateArgs, progress: &dyn Progress) -> Result<String> {
    let source = Project::open_with(&args.dir, args.database.as_deref())?;
    let settings = source.settings().clone();
    let target = app::database(&args.dir, &settings, Some(&args.to))?;
    let from = app::database(&args.dir, &settings, args.database.as_deref())?;
    if target == from {
        bail!("the target {target} is the project's own database");
    }
    let mut store = target
        .open()
        .with_context(|| format!("opening the target {target}"))?;
    let outcome = app::migrate(source.store(), &mut store, progress)?;
    let mut line = format!(
        "copied {} sensors, {} modalities, {} readings, {} ingests, {} cells, {} missions, {} settings and blobs from {from} to {target}",
        outcome.sensors,
        outcome.modalities,
        outcome.readings,
        outcome.ingests,
        outcome.cells,
        outcome.missions,
        outcome.config_and_blobs,
    );
    if args.switch {
        let mut settings: Settings = settings;
        settings.project.database = PathBuf::from(&args.to);
        settings.save(&args.dir)?;
        line.push_str(&format!("\nthe project now uses {target}"));
    }
    Ok(line)
}
