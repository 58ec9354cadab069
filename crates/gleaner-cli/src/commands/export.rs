//! `gleaner export`: writes a mission's files — GeoJSON, QGroundControl `.plan`, QGC WPL 110,
//! DJI WPML (`mission.kmz`), and the mission figure (SVG and PNG) — from the application
//! layer's checked export.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use gleaner_app::{MissionExport, MissionId};
use gleaner_wire::WpmlOptions;

use crate::{ProjectArg, out, outln};

/// The files written.
pub struct Exported {
    /// Every file written, in a fixed order.
    pub files: Vec<PathBuf>,
    /// Files not written, each with the reason (a format that cannot carry this mission).
    pub skipped: Vec<String>,
}

impl Exported {
    /// `wrote FILES` and a `not written: REASON` line per file skipped, each line ending in
    /// a newline.
    pub fn lines(&self) -> String {
        let names: Vec<String> = self.files.iter().map(|f| f.display().to_string()).collect();
        let mut t = format!("wrote {}\n", names.join(", "));
        for note in &self.skipped {
            t.push_str(&format!("not written: {note}\n"));
        }
        t
    }
}

fn write(dir: &Path, name: &str, bytes: &[u8], files: &mut Vec<PathBuf>) -> Result<()> {
    let path = dir.join(name);
    std::fs::write(&path, bytes).with_context(|| format!("{}: cannot write", path.display()))?;
    files.push(path);
    Ok(())
}

/// Creates `dir` and writes `mission.geojson`, `mission.plan` and `mission.waypoints` of `doc`
/// (each autopilot file read back and priced by its writer); returns their paths.
fn write_map_and_autopilot_files(
    field: &gleaner_wire::FieldDoc,
    doc: &gleaner_wire::MissionDoc,
    dir: &Path,
) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).with_context(|| format!("{}: cannot create", dir.display()))?;
    let mut files = Vec::new();
    write(
        dir,
        "mission.geojson",
        gleaner_wire::geojson(field, doc)?.as_bytes(),
        &mut files,
    )?;
    write(
        dir,
        "mission.plan",
        gleaner_wire::qgc_plan(doc)?.as_bytes(),
        &mut files,
    )?;
    write(
        dir,
        "mission.waypoints",
        gleaner_wire::wpl(doc)?.as_bytes(),
        &mut files,
    )?;
    Ok(files)
}

/// Writes the files of `export` into `dir` (created if missing), the DJI archive for the
/// default aircraft ([`WpmlOptions::default`]).
pub fn write_files(export: &MissionExport, dir: &Path) -> Result<Exported> {
    write_files_with(export, dir, WpmlOptions::default())
}

/// [`write_files`] declaring `wpml` as the aircraft of `mission.kmz` (DJI WPML).
pub fn write_files_with(export: &MissionExport, dir: &Path, wpml: WpmlOptions) -> Result<Exported> {
    let doc = gleaner_wire::convert::export_mission(export);
    let field = gleaner_wire::convert::field(&export.field);
    let mut files = write_map_and_autopilot_files(&field, &doc, dir)?;
    let mut skipped = Vec::new();
    let speed = gleaner_energy_speed(doc.profile.cruise_speed_mps);
    let altitude = gleaner_wire::commanded_altitude_m(doc.profile.altitude_m);
    if altitude < gleaner_wire::wpml::MIN_WPML_HEIGHT_M {
        skipped.push(format!(
            "mission.kmz: the flight altitude {altitude} m is below DJI WPML's {} m",
            gleaner_wire::wpml::MIN_WPML_HEIGHT_M
        ));
    } else if speed <= gleaner_wire::wpml::MAX_WPML_SPEED_MPS {
        write(
            dir,
            "mission.kmz",
            &gleaner_wire::wpml_kmz(&doc, wpml)?,
            &mut files,
        )?;
    } else {
        skipped.push(format!(
            "mission.kmz: the commanded speed {speed} m/s exceeds DJI WPML's {} m/s",
            gleaner_wire::wpml::MAX_WPML_SPEED_MPS
        ));
    }
    write(
        dir,
        "mission.json",
        serde_json::to_string_pretty(&doc)?.as_bytes(),
        &mut files,
    )?;
    let svg = gleaner_render::mission_figure_svg(&field, &doc, &Default::default())?;
    write(dir, "mission.svg", svg.as_bytes(), &mut files)?;
    let png = gleaner_render::svg_to_png(&svg, 1600)?;
    write(dir, "mission.png", &png, &mut files)?;
    Ok(Exported { files, skipped })
}

/// Writes the files of a continuation re-planned in the air into `dir` (created if missing):
/// `mission.geojson`, `mission.plan`, `mission.waypoints` (no take-off: a 0 s first waypoint
/// where the aircraft is) and `mission.json`; no DJI archive (a wayline mission takes off by
/// itself) and no figure. Each flight file is read back and its energy recomputed against the
/// energy left less the reserve.
pub fn write_replan_files<S: gleaner_app::Store>(
    project: &gleaner_app::Project<S>,
    replan: &gleaner_app::Replan,
    dir: &Path,
) -> Result<Exported> {
    let doc = gleaner_wire::convert::replanned_mission(replan);
    let field = gleaner_wire::convert::field(&gleaner_app::field_view(project)?);
    let mut files = write_map_and_autopilot_files(&field, &doc, dir)?;
    write(
        dir,
        "mission.json",
        serde_json::to_string_pretty(&doc)?.as_bytes(),
        &mut files,
    )?;
    Ok(Exported {
        files,
        skipped: vec![
            "mission.kmz: a DJI wayline mission takes off by itself; upload the .plan or the WPL"
                .into(),
        ],
    })
}

/// The speed the flight files command for a planned `speed_mps`, m/s.
fn gleaner_energy_speed(speed_mps: f64) -> f64 {
    gleaner_wire::commanded_speed_mps(speed_mps)
}

/// Writes the exploration overview (`exploration.svg`, `exploration.png`) into `dir`: every
/// exploration sortie of the project on one map. Returns the paths written.
pub fn write_exploration_map<S: gleaner_app::Store>(
    project: &gleaner_app::Project<S>,
    dir: &Path,
) -> Result<Vec<String>> {
    let sorties: Vec<_> = gleaner_app::missions(project)?
        .iter()
        .filter(|m| gleaner_wire::convert::is_exploration(m))
        .map(|m| {
            let mut doc = gleaner_wire::convert::stored_mission(m);
            gleaner_wire::convert::set_via(
                &mut doc,
                &gleaner_app::airspace::stored_via(project, m),
            );
            doc
        })
        .collect();
    anyhow::ensure!(
        !sorties.is_empty(),
        "no exploration sorties in this project (run `gleaner explore`)"
    );
    let field = gleaner_wire::convert::field(&gleaner_app::field_view(project)?);
    std::fs::create_dir_all(dir).with_context(|| format!("{}: cannot create", dir.display()))?;
    let svg = gleaner_render::exploration_map_svg(&field, &sorties, &Default::default())?;
    let mut files = Vec::new();
    write(dir, "exploration.svg", svg.as_bytes(), &mut files)?;
    write(
        dir,
        "exploration.png",
        &gleaner_render::svg_to_png(&svg, 1600)?,
        &mut files,
    )?;
    Ok(files.iter().map(|f| f.display().to_string()).collect())
}

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
    out(&write_files_with(&export, &dir, wpml)?.lines())
}

/// Draws the exploration overview; prints the files' names.
pub fn map_exploration(args: MapExplorationArgs) -> Result<()> {
    let p = args.project.open()?;
    let dir = args
        .out
        .unwrap_or_else(|| args.project.dir.join("missions"));
    let files = write_exploration_map(&p, &dir)?;
    outln(&format!("wrote {}", files.join(", ")))
}
