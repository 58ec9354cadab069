//! The datasets `simulate` replays, each prepared as a [`Replay`]: a preset is where its files
//! are and how to read them (CAF daily, CAF hourly, Hubbard Brook); a synthetic farm is
//! generated from its seed and written as small files; a project's own record is read as is.
//! The adapters choose a dataset and the replay options; everything else happens here.

use std::path::{Path, PathBuf};

use gleaner_app::{self as app, Format, IngestRequest, InitRequest, Project};
use gleaner_field::UnixSeconds;
use gleaner_synth::{FaultRates, SynthConfig, SynthFarm, generate};

use crate::campaign::{DatasetParts, Replay, ReplayOptions, TruthEvent, replay};
use crate::{Error, ProjectRecord, Result, Truth};

/// A real dataset with its defaults.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Preset {
    /// CAF daily files (42 stations; VW and T at 5 depths): history 2011-2013, missions every
    /// day of 2014.
    CafDaily,
    /// The CAF hourly subset (32 stations, VW 30 cm, Jan-Apr 2015, timestamps read as UTC):
    /// history January, missions daily Feb 1 - Apr 21.
    CafHourly,
    /// Hubbard Brook (12 loggers, hourly; `large-pack` battery): history to 2024-06-30,
    /// missions daily 2024-07-01 .. 2025-06-30.
    HubbardBrook,
}

/// Where a dataset's project is made and how the replay runs.
pub struct Setup<'a> {
    /// The project directory of a preset (made by `init` unless it holds a `gleaner.toml`).
    pub project_dir: &'a Path,
    /// The cell size, m [default: init's].
    pub cell_size_m: Option<f64>,
    /// The replay's options.
    pub options: &'a ReplayOptions,
    /// The wall clock, seconds (provenance only).
    pub clock_now: UnixSeconds,
}

/// A seeded synthetic farm (daily readings, CAF-like, VW at 30/60/90 cm and T at 30 cm) with
/// ground-truth events.
#[derive(Clone, Debug)]
pub struct SyntheticFarm {
    /// The farm's seed.
    pub seed: u64,
    /// Sensors.
    pub sensors: usize,
    /// Days of readings.
    pub days: u32,
    /// Ground-truth events.
    pub events: usize,
    /// Scale the field's extent with the sensor count (constant density).
    pub scale_extent: bool,
    /// Days of history before the missions start.
    pub history_days: u32,
}

/// A midnight (UTC) given as `YYYY-MM-DD`, seconds.
fn day(s: &str) -> i64 {
    app::parse_timestamp(s).unwrap_or(0)
}

/// The readings files of `dir` whose names `keep` accepts, sorted; at least one.
fn files_in(dir: &Path, keep: impl Fn(&str) -> bool) -> Result<Vec<PathBuf>> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| Error::file(dir, format!("cannot list: {e}")))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.file_name().and_then(|n| n.to_str()).is_some_and(&keep))
        .collect();
    v.sort();
    if v.is_empty() {
        return Err(Error::file(dir, "no readings files"));
    }
    Ok(v)
}

/// A dataset's replay: its project (made by `init` from `init` unless one is there), its
/// readings as the truth, and the defaults `(history_until, history_from, end)` (s).
#[allow(clippy::too_many_arguments)]
fn prepare(
    setup: &Setup<'_>,
    project_dir: &Path,
    label: &str,
    init: InitRequest,
    readings: IngestRequest,
    period_s: i64,
    (history_until, history_from, end): (i64, Option<i64>, i64),
    preset: &str,
    events: Option<Vec<TruthEvent>>,
) -> Result<Replay> {
    let project = if project_dir.join("gleaner.toml").exists() {
        Project::open(project_dir)?
    } else {
        app::init(&InitRequest {
            dir: project_dir.to_path_buf(),
            cell_size_m: setup.cell_size_m,
            name: Some(label.to_string()),
            ..init.clone()
        })?
        .0
    };
    let mut settings = project.settings().clone();
    settings.energy.preset = preset.to_string();
    let truth = Truth::from_files(&project, &readings, period_s, &app::Silent)?;
    let parts = DatasetParts {
        label: label.to_string(),
        init: InitRequest {
            dir: project_dir.to_path_buf(),
            ..init
        },
        sensors: None,
        settings,
        truth,
        history_until,
        history_from,
        end,
        history_follows_start: false,
        events,
    };
    Ok(replay(parts, setup.options, setup.clock_now)?)
}

/// The replay of a real dataset whose files are under `data` (the shared data directory).
pub fn preset_replay(preset: Preset, data: &Path, setup: &Setup<'_>) -> Result<Replay> {
    let caf_sensors = || InitRequest {
        sensors: data.join("caf/sensors/CAF_sensor_locations.csv"),
        utm_zone: Some("11N".into()),
        ..InitRequest::default()
    };
    let dir = setup.project_dir;
    match preset {
        Preset::CafDaily => prepare(
            setup,
            dir,
            "caf-daily",
            caf_sensors(),
            IngestRequest {
                files: files_in(&data.join("caf/Daily"), |n| n.ends_with(".txt"))?,
                format: Format::CafDaily,
                ..IngestRequest::default()
            },
            86_400,
            (
                day("2014-01-01"),
                Some(day("2011-01-01")),
                day("2014-12-31"),
            ),
            "paper",
            None,
        ),
        Preset::CafHourly => prepare(
            setup,
            dir,
            "caf-hourly",
            caf_sensors(),
            IngestRequest {
                files: vec![data.join("caf/derived/water_content_2015_Jan_April_32_sensors.csv")],
                format: Format::Wide,
                modality: Some("vw@30cm".into()),
                unit: Some("m3/m3".into()),
                ..IngestRequest::default()
            },
            3_600,
            (day("2015-02-01"), None, day("2015-04-21")),
            "paper",
            None,
        ),
        Preset::HubbardBrook => {
            let hb = data.join("hubbard_brook");
            prepare(
                setup,
                dir,
                "hubbard-brook",
                InitRequest {
                    sensors: hb.join("sensor_metadata.csv"),
                    hubbard_brook: true,
                    ..InitRequest::default()
                },
                IngestRequest {
                    files: files_in(&hb, |n| n.starts_with("z6-") && n.ends_with(".csv"))?,
                    format: Format::HubbardBrook,
                    ..IngestRequest::default()
                },
                3_600,
                (day("2024-07-01"), None, day("2025-06-30")),
                "large-pack",
                None,
            )
        }
    }
}

/// A CAF-like farm's settings: daily readings, VW at 30/60/90 cm and T at 30 cm, the default
/// faults, a 500 m correlation length.
pub(crate) fn farm_config(
    seed: u64,
    sensors: usize,
    days: u32,
    events: usize,
    scale_extent: bool,
) -> SynthConfig {
    SynthConfig {
        seed,
        sensor_count: sensors,
        days,
        interval_s: 86_400,
        event_count: events,
        correlation_length_m: 500.0,
        faults: FaultRates::default(),
        scale_extent_with_sensors: scale_extent,
        vw_depths_cm: vec![30, 60, 90],
        t_depths_cm: vec![30],
        ..SynthConfig::default()
    }
}

/// Generates the farm of `config` and writes its sensors, readings, ground truth and faults
/// into `dir`; returns the farm and its sensors and readings files.
pub(crate) fn write_farm(
    config: &SynthConfig,
    dir: &Path,
) -> Result<(SynthFarm, PathBuf, PathBuf)> {
    let synth = generate(config)
        .map_err(|e| app::AppError::Invalid(format!("invalid synthetic farm settings: {e}")))?;
    let files = gleaner_synth::write_farm_files(&synth, dir)
        .map_err(|e| Error::file(&e.path, format!("cannot {}: {}", e.what, e.source)))?;
    let (sensors, readings) = (files.sensors, files.readings);
    Ok((synth, sensors, readings))
}

/// The synthetic farm of one seed: its sensors, readings, ground truth and faults written
/// under `dir/farm-SEED/` (the readings file removed once read), its project under
/// `dir/farm-SEED/project`, its events as the truth's.
pub fn synthetic_replay(farm: &SyntheticFarm, dir: &Path, setup: &Setup<'_>) -> Result<Replay> {
    let seed = farm.seed;
    let farm_dir = dir.join(format!("farm-{seed}"));
    let config = farm_config(
        seed,
        farm.sensors,
        farm.days,
        farm.events,
        farm.scale_extent,
    );
    let (synth, sensors, readings) = write_farm(&config, &farm_dir)?;
    let events: Vec<TruthEvent> = synth
        .events()
        .iter()
        .map(|e| TruthEvent {
            id: e.id.clone(),
            sensors: e
                .affected
                .iter()
                .map(|&s| synth.sensors()[s].id.clone())
                .collect(),
            start: e.start,
            end: e.end,
        })
        .collect();
    let t0 = synth.times().first().copied().unwrap_or(0);
    let t_end = synth.times().last().copied().unwrap_or(0);
    let until = t0 + i64::from(farm.history_days) * 86_400;
    let prepared = prepare(
        setup,
        &farm_dir.join("project"),
        &format!("synthetic-{seed}"),
        InitRequest {
            sensors,
            ..InitRequest::default()
        },
        IngestRequest {
            files: vec![readings.clone()],
            ..IngestRequest::default()
        },
        86_400,
        (until, None, t_end),
        "paper",
        Some(events),
    )?;
    // The readings are in memory now; keep only the small files.
    std::fs::remove_file(&readings).ok();
    Ok(prepared)
}

/// A project's own record (`simulate --project`): its settings, sensors and readings; the
/// project is only read.
pub fn project_replay(
    dir: &Path,
    options: &ReplayOptions,
    clock_now: UnixSeconds,
) -> Result<Replay> {
    let project = Project::open(dir)?;
    let parts = ProjectRecord::read(&project)?.into_parts(dir);
    Ok(replay(parts, options, clock_now)?)
}
