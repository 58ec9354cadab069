//! `gleaner plan`: plans with the application layer's [`gleaner_app::plan_with_preset`] and
//! prints the mission (or the day's sorties) as a table or JSON.

use std::path::PathBuf;

use anyhow::Result;
use gleaner_app as app;
use gleaner_wire::text;

use crate::args::{JsonArg, ProjectArg, WhenArgs, clock_now, parse_wind};
use crate::output::warn;

// The arguments of `gleaner plan` (no doc comment: the variant's is the help).
#[derive(clap::Args)]
pub struct PlanArgs {
    #[command(flatten)]
    pub project: ProjectArg,
    #[command(flatten)]
    pub when: WhenArgs,
    /// Per-cell scores (CSV `cell_id,score` with a header) instead of the utility engine;
    /// cells left out score 0.
    #[arg(long)]
    pub scores: Option<PathBuf>,
    /// Route planner: default (iterated local search), greedy (the paper's), exact.
    #[arg(long)]
    pub solver: Option<String>,
    /// Planner time limit, seconds [default: [planner] time_limit_s, 5].
    #[arg(long)]
    pub time_limit: Option<f64>,
    /// Seed of the planner [default: [planner] seed, 0].
    #[arg(long)]
    pub seed: Option<u64>,
    /// Stop the search after this many iterations, so the route does not depend on the
    /// machine's speed (the time limit still applies).
    #[arg(long)]
    pub iterations: Option<u64>,
    #[command(flatten)]
    pub json: JsonArg,
    /// Do not store the mission.
    #[arg(long)]
    pub dry_run: bool,
    /// Sorties this mission day (battery swaps), 1..=20: disjoint routes from the base, each
    /// within the budget, planned together to maximise total S; each is stored as its own
    /// mission (export/record each by its id). With K > 1, --json prints an array.
    #[arg(long, default_value_t = 1)]
    pub sorties: usize,
    /// Plan with this energy preset's battery instead of `[energy] preset` (`paper`,
    /// `large-pack`); fields set in `[energy]` still override the preset's values.
    #[arg(long)]
    pub energy_preset: Option<app::EnergyPreset>,
    /// What the route maximises: `score` (the sum of the visited cells' S) or
    /// `information` (the expected reduction of the dynamic field model's posterior
    /// variance over the whole field, non-additive: correlated cells share information)
    /// or `hybrid` (the route's share of the total S and its information share, blended
    /// by [planner] information_weight, default 0.5) [default: [planner] objective,
    /// score].
    #[arg(long)]
    pub objective: Option<app::Objective>,
    /// Forecast wind at the flight altitude as SPEED@FROM: m/s @ degrees clockwise from
    /// north the wind blows from (e.g. 6@270, a 6 m/s west wind) [default: [flight]
    /// wind_mps@wind_from_deg, still air]. Legs are priced at the airspeed that holds
    /// their track at the planned ground speed, in this wind plus [flight]
    /// wind_margin_mps (2 m/s); the plan prints the strongest wind it stands.
    #[arg(long, value_name = "SPEED@FROM", value_parser = parse_wind)]
    pub wind: Option<app::Wind>,
}

/// Plans the mission (or the day's sorties); prints its summary (or JSON).
pub fn run(args: PlanArgs) -> Result<()> {
    let mut p = args.project.open()?;
    let planned = app::plan_with_preset(
        &mut p,
        &app::PlanRequest {
            at: args.when.at,
            history: args.when.history(),
            scores: args.scores,
            cell_scores: None,
            planner: args.solver.as_deref().map(app::parse_planner).transpose()?,
            time_limit_s: args.time_limit,
            seed: args.seed,
            max_iterations: args.iterations,
            dry_run: args.dry_run,
            sorties: Some(args.sorties),
            objective: args.objective,
            wind: args.wind,
        },
        args.energy_preset.map(app::EnergyPreset::name),
        clock_now(),
    )?;
    if let Some(s) = &planned.scoring {
        warn(s);
    }
    let doc = gleaner_wire::convert::planned_mission(&planned);
    if planned.extra_sorties.is_empty() {
        return args.json.emit(&doc, "serialising the mission", || {
            text::mission_table(&doc)
        });
    }
    let mut docs = vec![doc];
    docs.extend(planned.extra_sorties.iter().map(|e| {
        let mut doc = gleaner_wire::convert::extra_sortie(e);
        // The sorties of one day are chosen together from the same cells.
        doc.candidates = Some(planned.candidates);
        doc
    }));
    args.json.emit(&docs, "serialising the sorties", || {
        text::sorties_table(&docs)
    })
}
