//! `gleaner replan`: the continuation of a mission in the air with the application layer's
//! [`gleaner_app::replan`], written as flight files and printed (a table or JSON).

use std::path::PathBuf;

use anyhow::Result;
use gleaner_app::{self as app, MissionId};
use gleaner_wire::{convert, text};

use crate::args::{JsonArg, ProjectArg, parse_wind};

// The arguments of `gleaner replan` (no doc comment: the variant's is the help).
#[derive(clap::Args)]
pub struct ReplanArgs {
    #[command(flatten)]
    pub project: ProjectArg,
    /// The mission in flight (planned, not yet recorded).
    #[arg(long)]
    pub mission: i64,
    /// Stops already flown: the aircraft is over this stop, done collecting (1-based in
    /// the mission's order; 0 = airborne over the base).
    #[arg(long)]
    pub after_stop: usize,
    /// Energy left in the battery, J (as the autopilot reports it).
    #[arg(long, value_name = "J")]
    pub energy_left: f64,
    /// Output directory [default: <project>/missions/<id>/replan-after-<K>].
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Planner seed [default: the mission's].
    #[arg(long)]
    pub seed: Option<u64>,
    /// Wall-clock limit of the search, seconds.
    #[arg(long, default_value_t = gleaner_app::REPLAN_TIME_LIMIT_S)]
    pub time_limit: f64,
    /// Iteration cap of the search (deterministic answers).
    #[arg(long, default_value_t = gleaner_app::REPLAN_ITERATIONS)]
    pub iterations: u64,
    /// The wind now as SPEED@FROM (m/s @ degrees from north it blows from, e.g. 8@250),
    /// plus [flight] wind_margin_mps; the continuation and its files are priced in it
    /// [default: the wind the mission was planned in].
    #[arg(long, value_name = "SPEED@FROM", value_parser = parse_wind)]
    pub wind: Option<app::Wind>,
    #[command(flatten)]
    pub json: JsonArg,
}

/// Re-plans the mission, writes the continuation's files; prints it.
pub fn run(args: ReplanArgs) -> Result<()> {
    let p = args.project.open()?;
    let r = app::replan(
        &p,
        &app::ReplanRequest {
            mission: MissionId(args.mission),
            after_stop: args.after_stop,
            energy_left_j: args.energy_left,
            seed: args.seed,
            iterations: Some(args.iterations),
            time_limit_s: Some(args.time_limit),
            wind: args.wind,
            wind_margin_mps: None,
        },
    )?;
    let dir = args.out.unwrap_or_else(|| {
        args.project
            .dir
            .join("missions")
            .join(args.mission.to_string())
            .join(format!("replan-after-{}", args.after_stop))
    });
    let doc = convert::replanned_mission(&r);
    let field = convert::field(&app::field_view(&p)?);
    let set = gleaner_render::files::continuation_files(&field, &doc)?;
    let written = app::write_files(&dir, &set.files)?;
    args.json.emit(&doc, "serialising the continuation", || {
        let mut t = text::replan_table(&doc, &r.dropped);
        t.push_str(&text::written_lines(&written, &set.skipped));
        t
    })
}
