//! The demo's lifecycle (`gleaner demo`): a synthetic farm or the CAF network → `init` →
//! exploration sorties, each flown in simulation and recorded → adaptive missions, one a day,
//! each planned, exported (its files under `missions/<id>`), flown and recorded → a
//! rescoring. It returns what happened as typed data, the missions' exports at the moment
//! they were planned or flown, and [`story::story`] tells it as text.

use std::path::{Path, PathBuf};

use gleaner_app::{
    self as app, AnyStore, Exploration, InitOutcome, MissionExport, MissionId, MissionRecord,
    PlannedMission, Progress, Project, RecordOutcome, Scoring,
};
use gleaner_field::UnixSeconds;

use crate::datasets::{farm_config, write_farm};
use crate::{Error, Result, Truth, fly};

pub mod story;

/// Adaptive missions flown after the exploration.
pub const MISSIONS: i64 = 5;
const DAY: i64 = 86_400;

/// What the demo runs on.
#[derive(Debug, Clone)]
pub struct DemoRequest {
    /// The working directory; the files an earlier demo wrote there are replaced.
    pub dir: PathBuf,
    /// Plan by gleaner's method (else the paper's S).
    pub gleaner_method: bool,
    /// Seed of the synthetic farm and of the planner.
    pub seed: u64,
    /// Sensors of the synthetic farm.
    pub sensors: usize,
    /// Days of the synthetic farm's record.
    pub days: u32,
    /// The shared data directory: run on the real CAF network instead.
    pub data: Option<PathBuf>,
}

/// The farm the demo ran on.
#[derive(Debug, Clone)]
pub enum DemoFarm {
    /// A seeded synthetic farm, its files under `dir`.
    Synthetic {
        /// Its files' directory.
        dir: PathBuf,
        /// Readings it logs.
        readings: u64,
        /// Ground-truth events.
        events: usize,
    },
    /// The CAF network's daily files.
    Caf {
        /// Daily files read.
        files: usize,
    },
}

/// One flown mission: its id, its export (before the flight for an adaptive mission, after
/// it for an exploration sortie), its files and what the flight brought back.
pub struct DemoFlight {
    /// The mission.
    pub id: MissionId,
    /// The mission as exported.
    pub export: MissionExport,
    /// Its files as written (`gleaner_render::files::mission_files`), under
    /// `missions/<id>` of the demo's directory.
    pub files: Vec<PathBuf>,
    /// The recorded flight.
    pub record: RecordOutcome,
}

/// What the demo did.
pub struct Demo {
    /// The project, after the demo.
    pub project: Project<AnyStore>,
    /// The farm.
    pub farm: DemoFarm,
    /// The project's creation.
    pub init: InitOutcome,
    /// Readings the sensors log (the ground truth), none collected at first.
    pub truth_readings: usize,
    /// The exploration, planned at the first mission day less one day.
    pub exploration: Exploration,
    /// Its sorties, flown.
    pub sorties: Vec<DemoFlight>,
    /// The adaptive missions, one a day, with their plans.
    pub missions: Vec<(PlannedMission, DemoFlight)>,
    /// The first adaptive mission scored when planned (its index in `missions`, whose
    /// scoring is the one before it), the scoring after the campaign and that mission as
    /// stored.
    pub rescored: Option<(usize, Scoring, MissionRecord)>,
    /// The exploration overview's files (`missions/exploration.svg`, `.png`).
    pub overview: Vec<PathBuf>,
}

/// Removes what an earlier demo run wrote in `dir` (and nothing else).
fn clean(dir: &Path) -> Result<()> {
    for name in [
        "gleaner.toml",
        "gleaner.db",
        "gleaner.db-wal",
        "gleaner.db-shm",
        "gleaner.db-lock",
    ] {
        let p = dir.join(name);
        if p.exists() {
            std::fs::remove_file(&p).map_err(|e| Error::file(&p, format!("cannot remove: {e}")))?;
        }
    }
    let missions = dir.join("missions");
    if missions.exists() {
        std::fs::remove_dir_all(&missions)
            .map_err(|e| Error::file(&missions, format!("cannot remove: {e}")))?;
    }
    Ok(())
}

/// A new project from `init` and the ground truth its sensors log: every reading of `files`.
fn project_and_truth(
    init: &app::InitRequest,
    files: Vec<PathBuf>,
    format: app::Format,
    progress: &dyn Progress,
) -> Result<(Project<AnyStore>, InitOutcome, Truth)> {
    let (project, outcome) = app::init(init)?;
    let request = app::IngestRequest {
        files,
        format,
        ..Default::default()
    };
    let truth = Truth::from_files(&project, &request, DAY, progress)?;
    Ok((project, outcome, truth))
}

/// The farm: a project on it, its ground truth and the exploration time (s). A synthetic
/// farm explores `MISSIONS` days before its record ends; CAF on 2014-03-01.
#[allow(clippy::type_complexity)]
fn farm(
    r: &DemoRequest,
    progress: &dyn Progress,
) -> Result<(DemoFarm, Project<AnyStore>, InitOutcome, Truth, UnixSeconds)> {
    let init = |name: &str, sensors: PathBuf| app::InitRequest {
        dir: r.dir.clone(),
        sensors,
        name: Some(name.into()),
        force: true,
        gleaner_method: r.gleaner_method,
        ..Default::default()
    };
    match &r.data {
        None => {
            let data = r.dir.join("data");
            let config = farm_config(r.seed, r.sensors, r.days, 3, false);
            let (synth, sensors, readings) = write_farm(&config, &data)?;
            let request = app::InitRequest {
                base: Some(synth.base()),
                cell_size_m: Some(app::DEFAULT_CELL_SIZE_M),
                ..init("demo", sensors)
            };
            let (p, o, truth) =
                project_and_truth(&request, vec![readings], app::Format::Long, progress)?;
            let end = synth.times().last().copied().unwrap_or_default();
            let farm = DemoFarm::Synthetic {
                dir: data,
                readings: synth.reading_count() as u64,
                events: synth.events().len(),
            };
            Ok((farm, p, o, truth, end - MISSIONS * DAY))
        }
        Some(data) => {
            let caf = data.join("caf");
            let daily_dir = caf.join("Daily");
            let mut daily: Vec<PathBuf> = std::fs::read_dir(&daily_dir)
                .map_err(|e| Error::file(&daily_dir, format!("cannot list: {e}")))?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|x| x == "txt"))
                .collect();
            daily.sort();
            let request = app::InitRequest {
                utm_zone: Some("11N".into()),
                ..init(
                    "caf-demo",
                    caf.join("sensors").join("CAF_sensor_locations.csv"),
                )
            };
            let files = daily.len();
            let (p, o, truth) =
                project_and_truth(&request, daily, app::Format::CafDaily, progress)?;
            let t0 = app::parse_timestamp("2014-03-01").unwrap_or_default();
            Ok((DemoFarm::Caf { files }, p, o, truth, t0))
        }
    }
}

/// Writes the files of `export` into `dir/<id>`; returns their paths.
fn write_mission_files(export: &MissionExport, dir: &Path) -> Result<Vec<PathBuf>> {
    let doc = gleaner_wire::convert::export_mission(export);
    let field = gleaner_wire::convert::field(&export.field);
    let set = gleaner_render::files::mission_files(&field, &doc, Default::default())?;
    let dir = dir.join(export.mission.id.to_string());
    Ok(app::write_files(&dir, &set.files)?)
}

/// Writes the exploration overview of `project`'s sorties into `dir`; returns its paths.
fn write_overview(project: &Project<AnyStore>, dir: &Path) -> Result<Vec<PathBuf>> {
    let sorties = gleaner_wire::convert::routed_missions(&app::exploration_sorties(project)?);
    let field = gleaner_wire::convert::field(&app::field_view(project)?);
    let set = gleaner_render::files::exploration_files(&field, &sorties)?;
    Ok(app::write_files(dir, &set.files)?)
}

/// A stored mission's id, or the error that it was not stored.
fn stored(id: Option<MissionId>) -> Result<MissionId> {
    id.ok_or_else(|| app::AppError::Invalid("the demo's mission was not stored".into()).into())
}

/// Runs the demo in `request.dir`; `clock_now` (s) is provenance only.
pub fn demo(
    request: &DemoRequest,
    clock_now: UnixSeconds,
    progress: &dyn Progress,
) -> Result<Demo> {
    std::fs::create_dir_all(&request.dir)
        .map_err(|e| Error::file(&request.dir, format!("cannot create: {e}")))?;
    clean(&request.dir)?;
    let (farm, mut project, init, truth, t0) = farm(request, progress)?;
    // Exploration: every cell once, in as few sorties as the battery allows.
    let exploration = app::explore(
        &mut project,
        &app::ExploreRequest {
            at: Some(t0),
            dry_run: false,
            wind: None,
        },
        clock_now,
    )?;
    let missions_dir = request.dir.join("missions");
    let mut sorties = Vec::new();
    for (id, _) in &exploration.sorties {
        let id = stored(*id)?;
        let record = fly(&mut project, &truth, id, t0, clock_now)?;
        let export = app::export(&project, id)?;
        let files = write_mission_files(&export, &missions_dir)?;
        sorties.push(DemoFlight {
            id,
            export,
            files,
            record,
        });
    }
    // Adaptive missions, one a day.
    let mut missions = Vec::new();
    let mut first: Option<(usize, MissionId)> = None;
    for k in 1..=MISSIONS {
        let t = t0 + k * DAY;
        let planned = app::plan(
            &mut project,
            &app::PlanRequest {
                at: Some(t),
                time_limit_s: Some(2.0),
                seed: Some(request.seed),
                max_iterations: Some(3_000),
                ..Default::default()
            },
            clock_now,
        )?;
        let id = stored(planned.id)?;
        if first.is_none() && planned.scoring.is_some() {
            first = Some((missions.len(), id));
        }
        let export = app::export(&project, id)?;
        let files = write_mission_files(&export, &missions_dir)?;
        let record = fly(&mut project, &truth, id, t, clock_now)?;
        let flight = DemoFlight {
            id,
            export,
            files,
            record,
        };
        missions.push((planned, flight));
    }
    // The first mission's cells after their collection: fresh again.
    let rescored = match first {
        Some((k, id)) => {
            let after = app::score(
                &mut project,
                &app::ScoreRequest {
                    at: Some(t0 + (MISSIONS + 1) * DAY),
                    ..Default::default()
                },
            )?;
            Some((k, after, app::mission(&project, id)?))
        }
        None => None,
    };
    let overview = write_overview(&project, &missions_dir)?;
    Ok(Demo {
        overview,
        project,
        farm,
        init,
        truth_readings: truth.len(),
        exploration,
        sorties,
        missions,
        rescored,
    })
}
