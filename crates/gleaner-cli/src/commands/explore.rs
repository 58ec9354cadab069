//! `gleaner explore`: plans the exploration sorties with the application layer's
//! [`gleaner_app::explore`] and prints them (a table or JSON).

use anyhow::Result;
use gleaner_app as app;

use crate::args::{JsonArg, ProjectArg, clock_now, parse_time, parse_wind};

// The arguments of `gleaner explore` (no doc comment: the variant's is the help).
#[derive(clap::Args)]
pub struct ExploreArgs {
    #[command(flatten)]
    pub project: ProjectArg,
    /// Planning time (RFC 3339 or date, years 1900..=2199) [default: the latest reading;
    /// without readings it must be given].
    #[arg(long, value_parser = parse_time)]
    pub at: Option<i64>,
    #[command(flatten)]
    pub json: JsonArg,
    /// Do not store the sorties.
    #[arg(long)]
    pub dry_run: bool,
    /// Forecast wind at the flight altitude as SPEED@FROM (m/s @ degrees clockwise from
    /// north it blows from, e.g. 6@270) [default: [flight] wind_mps@wind_from_deg, still
    /// air]. The sorties are planned in it plus [flight] wind_margin_mps, as `plan`'s.
    #[arg(long, value_name = "SPEED@FROM", value_parser = parse_wind)]
    pub wind: Option<app::Wind>,
}

/// Plans (and unless a dry run stores) the sorties; prints them.
pub fn run(args: ExploreArgs) -> Result<()> {
    let mut p = args.project.open()?;
    let e = app::explore(
        &mut p,
        &app::ExploreRequest {
            at: args.at,
            dry_run: args.dry_run,
            wind: args.wind,
        },
        clock_now(),
    )?;
    let doc = gleaner_wire::convert::exploration(&e);
    args.json.emit(&doc, "serialising the plan", || {
        gleaner_wire::text::exploration_table(&doc)
    })
}
