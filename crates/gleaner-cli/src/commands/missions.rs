//! `gleaner missions`, `cancel`, `delete`: the mission history (a table or the
//! `gleaner.mission` documents) and its two changes.

use anyhow::Result;
use gleaner_app::{self as app, MissionId};
use gleaner_wire::text;

use crate::args::ProjectArg;
use crate::output::{emit, out, outln};

// The arguments of `gleaner missions` (no doc comment: the variant's is the help).
#[derive(clap::Args)]
pub struct MissionsArgs {
    #[command(flatten)]
    pub project: ProjectArg,
    /// Show this mission with its stops and energy breakdown.
    #[arg(long, conflicts_with_all = ["limit", "before"])]
    pub mission: Option<i64>,
    /// List one page of at most this many missions (1 to 500), newest first [default with
    /// --before: 20].
    #[arg(long)]
    pub limit: Option<usize>,
    /// List only missions with an id below this one (the next page's cursor).
    #[arg(long)]
    pub before: Option<i64>,
    /// Print JSON (the `gleaner.mission` document) instead of text.
    #[arg(long)]
    pub json: bool,
}

// The arguments of `gleaner cancel` (no doc comment: the variant's is the help).
#[derive(clap::Args)]
pub struct CancelArgs {
    #[command(flatten)]
    pub project: ProjectArg,
    /// The mission to cancel.
    #[arg(long)]
    pub mission: i64,
}

// The arguments of `gleaner delete` (no doc comment: the variant's is the help).
#[derive(clap::Args)]
pub struct DeleteArgs {
    #[command(flatten)]
    pub project: ProjectArg,
    /// The mission to delete.
    #[arg(long)]
    pub mission: i64,
}

/// Lists the missions (all, or one page), or shows one.
pub fn run(args: MissionsArgs) -> Result<()> {
    let p = args.project.open()?;
    if args.limit.is_some() || args.before.is_some() {
        let page = app::missions_page(&p, args.before.map(MissionId), args.limit.unwrap_or(20))?;
        if args.json {
            let docs: Vec<_> = page
                .missions
                .iter()
                .map(gleaner_wire::convert::stored_mission)
                .collect();
            let doc = serde_json::json!({"missions": docs, "next": page.next.map(|m| m.0)});
            return emit(true, &doc, "serialising missions", String::new);
        }
        out(&text::missions_table(&page.missions))?;
        return match page.next {
            Some(n) => outln(&format!("next page: --before {n}")),
            None => outln("no older missions"),
        };
    }
    match args.mission {
        Some(id) => {
            let m = app::mission(&p, MissionId(id))?;
            let doc = gleaner_wire::convert::stored_mission(&m);
            emit(args.json, &doc, "serialising the mission", || {
                text::mission_table(&doc)
            })
        }
        None => {
            let all = app::missions(&p)?;
            let docs: Vec<_> = all
                .iter()
                .map(gleaner_wire::convert::stored_mission)
                .collect();
            emit(args.json, &docs, "serialising missions", || {
                text::missions_table(&all)
            })
        }
    }
}

/// Cancels a planned mission.
pub fn cancel(args: CancelArgs) -> Result<()> {
    let mut p = args.project.open()?;
    let m = app::cancel_mission(&mut p, MissionId(args.mission))?;
    outln(&format!(
        "cancelled mission #{}: it stays in the history and can no longer be recorded or exported",
        m.id
    ))
}

/// Deletes a mission never flown.
pub fn delete(args: DeleteArgs) -> Result<()> {
    let mut p = args.project.open()?;
    app::delete_mission(&mut p, MissionId(args.mission))?;
    outln(&format!("deleted mission #{}", args.mission))
}
