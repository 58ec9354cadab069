//! `gleaner export` and `map-exploration`: writes a mission's files — GeoJSON, QGroundControl
//! `.plan`, QGC WPL 110, DJI WPML (`mission.kmz`), and the mission figure (SVG and PNG) — made
//! by `gleaner_render::files` from the application layer's checked export.

use std::path::PathBuf;

use anyhow::Result;
use gleaner_app::MissionId;
use gleaner_render::files;
use gleaner_wire::{WpmlOptions, convert, text};

use crate::args::ProjectArg;
use crate::output::out;

// The arguments of `gleaner export` (no doc comment: the variant's is the help).
#[derive(clap::Args)]
pub struct ExportArgs {
    #[command(flatten)]
    pub project: ProjectArg,
    /// The mission's id (printed by `gleaner plan`).
    #[arg(long)]
    pub mission: i64,
    /// Output directory [default: <project>/missions/<id>].
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// mission.kmz: DJI's aircraft enumeration value (wpml:droneEnumValue; 77 = Mavic 3
    /// Enterprise series).
    #[arg(long, default_value_t = 77)]
    pub dji_drone: u32,
    /// mission.kmz: DJI's aircraft sub-type (wpml:droneSubEnumValue; for 77: 0 = M3E,
    /// 1 = M3T, 2 = M3M).
    #[arg(long, default_value_t = 0)]
    pub dji_drone_sub: u32,
    /// mission.kmz: DJI's payload enumeration value (wpml:payloadEnumValue; 66 = M3E camera).
    #[arg(long, default_value_t = 66)]
    pub dji_payload: u32,
}

// The arguments of `gleaner map-exploration` (no doc comment: the variant's is the help).
#[derive(clap::Args)]
pub struct MapExplorationArgs {
    #[command(flatten)]
    pub project: ProjectArg,
    /// Output directory [default: <project>/missions].
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// Writes the mission's files; prints their names.
pub fn run(args: ExportArgs) -> Result<()> {
    let p = args.project.open()?;
    let export = gleaner_app::export(&p, MissionId(args.mission))?;
    let dir = args.out.unwrap_or_else(|| {
        args.project
            .dir
            .join("missions")
            .join(args.mission.to_string())
    });
    let wpml = WpmlOptions {
        drone_enum: args.dji_drone,
        drone_sub_enum: args.dji_drone_sub,
        payload_enum: args.dji_payload,
    };
    let doc = convert::export_mission(&export);
    let set = files::mission_files(&convert::field(&export.field), &doc, wpml)?;
    out(&text::written_lines(
        &gleaner_app::write_files(&dir, &set.files)?,
        &set.skipped,
    ))
}

/// Draws the exploration overview: every exploration sortie of the project on one map;
/// prints the files' names.
pub fn map_exploration(args: MapExplorationArgs) -> Result<()> {
    let p = args.project.open()?;
    let dir = args
        .out
        .unwrap_or_else(|| args.project.dir.join("missions"));
    let sorties = convert::routed_missions(&gleaner_app::exploration_sorties(&p)?);
    anyhow::ensure!(
        !sorties.is_empty(),
        "no exploration sorties in this project (run `gleaner explore`)"
    );
    let field = convert::field(&gleaner_app::field_view(&p)?);
    let set = files::exploration_files(&field, &sorties)?;
    out(&text::written_lines(
        &gleaner_app::write_files(&dir, &set.files)?,
        &[],
    ))
}
