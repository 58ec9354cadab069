//! `gleaner migrate`: copies a project's data into another database (SQLite file <->
//! PostgreSQL project) with the application layer's [`gleaner_app::migrate`].

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use gleaner_app::{self as app, Progress};

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
pub fn run(args: MigrateArgs, progress: &dyn Progress) -> Result<String> {
    let m = app::migrate_project(
        &app::MigrateProjectRequest {
            dir: args.dir,
            database: args.database,
            to: args.to,
            switch: args.switch,
        },
        progress,
    )?;
    Ok(gleaner_wire::text::migration_lines(&m))
}
