//! `gleaner demo`: the whole story on built-in data (a seeded synthetic farm) or on the real
//! CAF network — exploration sorties that visit every cell, then adaptive missions, each
//! planned, exported, flown in simulation, recorded with the readings brought back, and
//! followed by a rescoring. Every step is an application-layer call; this module only
//! chooses the scenario and prints.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use gleaner_app::{self as app, AnyStore, MissionId, Project};

use crate::clock_now;
use crate::commands::{export, plan, synth};
use crate::progress::Terminal;

// The arguments of `gleaner demo` (no doc comment: the variant's is the help).
#[derive(clap::Args)]
pub struct DemoArgs {
    /// Working directory; the files the demo writes there are replaced.
    #[arg(long, default_value = "gleaner-demo")]
    pub dir: PathBuf,
    /// The score the demo's project plans by (`gleaner`, the default, or the paper's S).
    #[arg(long, value_enum, default_value_t = crate::MethodArg::Gleaner)]
    pub method: crate::MethodArg,
    /// Seed of the synthetic farm.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Number of sensors.
    #[arg(long, default_value_t = 60)]
    pub sensors: usize,
    /// Days of history.
    #[arg(long, default_value_t = 180)]
    pub days: u32,
    /// Run on the real CAF network instead (the shared data directory, e.g.
    /// ../shared/data), with the paper's energy preset.
    #[arg(long)]
    pub data: Option<PathBuf>,
}

/// Adaptive missions flown after the exploration.
const MISSIONS: i64 = 5;
const DAY: i64 = 86_400;

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
            std::fs::remove_file(&p).with_context(|| format!("{}: cannot remove", p.display()))?;
        }
    }
    let missions = dir.join("missions");
    if missions.exists() {
        std::fs::remove_dir_all(&missions)
            .with_context(|| format!("{}: cannot remove", missions.display()))?;
    }
    Ok(())
}

/// The paper's line: "selected 8 cells; 55,309.8 J of 66,500 J, 83.2%".
fn paper_line(m: &gleaner_wire::MissionDoc) -> String {
    format!(
        "selected {} cells; {} J of {} J, {:.1}%",
        m.stops.len(),
        thousands(m.energy.total_j),
        thousands(m.energy.budget_j),
        100.0 * m.energy.utilisation
    )
}

/// 55309.8 -> "55,309.8".
fn thousands(x: f64) -> String {
    let s = format!("{x:.1}");
    let (int, frac) = s.split_once('.').unwrap_or((&s, "0"));
    let (sign, digits) = int.strip_prefix('-').map_or(("", int), |d| ("-", d));
    let mut out = String::new();
    for (k, c) in digits.chars().enumerate() {
        if k > 0 && (digits.len() - k) % 3 == 0 {
            out.push(',');
        }
        out.push(c);
    }
    format!("{sign}{out}.{frac}")
}

/// Runs the demo; returns its report.
pub fn run(args: &DemoArgs) -> Result<String> {
    let mut out = String::new();
    std::fs::create_dir_all(&args.dir)
        .with_context(|| format!("{}: cannot create", args.dir.display()))?;
    clean(&args.dir)?;
    let progress = Terminal::default();
    let (mut project, truth, t0) = match &args.data {
        None => synthetic(args, &mut out, &progress)?,
        Some(data) => caf(args, data, &mut out, &progress)?,
    };
    let dir = args.dir.clone();

    // Exploration: every cell once, in as few sorties as the battery allows.
    let exploration = app::explore(
        &mut project,
        &app::ExploreRequest {
            at: Some(t0),
            dry_run: false,
            wind: None,
        },
        clock_now(),
    )?;
    let doc = gleaner_wire::convert::exploration(&exploration);
    writeln!(
        out,
        "3. exploration at {}: {} cells in {} sorties (lower bound {}), {:.1} kJ in all",
        doc.planned_at,
        doc.cells,
        doc.sorties.len(),
        doc.lower_bound_sorties,
        doc.total_energy_j / 1000.0
    )?;
    for (id, _) in &exploration.sorties {
        let id = id.context("the sortie was stored")?;
        let rec = gleaner_campaign::fly(&mut project, &truth, id, t0, clock_now())?;
        let flown = app::export(&project, id)?;
        let files = export::write_files(&flown, &dir.join("missions").join(id.to_string()))?;
        writeln!(
            out,
            "   sortie #{id}: {}; brought back {} readings from {} sensors ({} files)",
            paper_line(&gleaner_wire::convert::stored_mission(&flown.mission)),
            rec.readings_inserted,
            rec.sensors_collected,
            files.files.len()
        )?;
    }
    let map = export::write_exploration_map(&project, &dir.join("missions"))?;
    writeln!(out, "   overview map: {}", map.join(", "))?;

    // Adaptive missions, one a day.
    writeln!(
        out,
        "4. {MISSIONS} adaptive missions, one a day, each planned from what was collected, flown in simulation and recorded:"
    )?;
    let mut first: Option<(MissionId, gleaner_wire::docs::ScoringDoc)> = None;
    for k in 1..=MISSIONS {
        let t = t0 + k * DAY;
        let planned = app::plan(
            &mut project,
            &app::PlanRequest {
                at: Some(t),
                time_limit_s: Some(2.0),
                seed: Some(args.seed),
                max_iterations: Some(3_000),
                ..Default::default()
            },
            clock_now(),
        )?;
        let id = planned.id.context("the mission was stored")?;
        let doc = gleaner_wire::convert::planned_mission(&planned);
        if first.is_none()
            && let Some(s) = &planned.scoring
        {
            first = Some((id, gleaner_wire::convert::scoring(s)));
        }
        let files = export::write_files(
            &app::export(&project, id)?,
            &dir.join("missions").join(id.to_string()),
        )?;
        let rec = gleaner_campaign::fly(&mut project, &truth, id, t, clock_now())?;
        writeln!(
            out,
            "   mission #{id} at {}: {}; total S = {:.3} (paper's greedy {:.3}); brought back {} readings; files in {}",
            doc.planned_at,
            paper_line(&doc),
            doc.total_score,
            doc.greedy_baseline.as_ref().map_or(0.0, |g| g.total_score),
            rec.readings_inserted,
            files
                .files
                .first()
                .and_then(|f| f.parent())
                .map_or(String::new(), |p| p.display().to_string())
        )?;
        if k == 1 {
            writeln!(out, "{}", indent(&plan::table(&doc)))?;
        }
    }

    // The first mission's cells after their collection: fresh again.
    if let Some((id, before)) = first {
        let after = app::score(
            &mut project,
            &app::ScoreRequest {
                at: Some(t0 + (MISSIONS + 1) * DAY),
                ..Default::default()
            },
        )?;
        let after = gleaner_wire::convert::scoring(&after);
        let m = app::mission(&project, id)?;
        writeln!(
            out,
            "5. mission #{id}'s cells, scored before it and after the campaign (F resets when collected):"
        )?;
        for stop in m.mission.stops.iter().take(5) {
            let label = stop.cell.to_string();
            let b = before.cells.iter().find(|c| c.cell == label);
            let a = after.cells.iter().find(|c| c.cell == label);
            if let (Some(b), Some(a)) = (b, a) {
                writeln!(
                    out,
                    "   {label:<10} F {:.3} -> {:.3}   U {:.3} -> {:.3}   S {:.3} -> {:.3}",
                    b.f, a.f, b.u, a.u, b.s, a.s
                )?;
            }
        }
    }
    Ok(out)
}

fn indent(s: &str) -> String {
    s.lines()
        .map(|l| format!("     {l}"))
        .collect::<Vec<_>>()
        .join("\n")
}

/// A seeded synthetic farm: its files, a project, and the ground truth. The exploration flies
/// 6 days before the end of the record.
fn synthetic(
    args: &DemoArgs,
    out: &mut String,
    progress: &Terminal,
) -> Result<(Project<AnyStore>, gleaner_campaign::Truth, i64)> {
    let (farm, files) = synth::run(&synth::SynthArgs {
        out: args.dir.join("data"),
        seed: args.seed,
        sensors: args.sensors,
        days: args.days,
        interval_s: DAY,
        events: 3,
        correlation_length_m: 500.0,
        no_faults: false,
        scale_extent: false,
        vw_depths_cm: synth::Depths(vec![30, 60, 90]),
        t_depths_cm: synth::Depths(vec![30]),
        layout: None,
        utm_zone: None,
    })?;
    writeln!(
        out,
        "1. synthetic farm (seed {}): {} sensors, {} days, {} readings, {} ground-truth events -> {}",
        args.seed,
        args.sensors,
        args.days,
        farm.reading_count(),
        farm.events().len(),
        args.dir.join("data").display()
    )?;
    let base = farm.base();
    let (project, init, truth) = project_and_truth(
        &app::InitRequest {
            dir: args.dir.clone(),
            sensors: files.sensors.clone(),
            base: Some(base),
            cell_size_m: Some(app::DEFAULT_CELL_SIZE_M),
            name: Some("demo".into()),
            force: true,
            gleaner_method: matches!(args.method, crate::MethodArg::Gleaner),
            ..Default::default()
        },
        vec![files.readings.clone()],
        app::Format::Long,
        progress,
    )?;
    writeln!(
        out,
        "2. {}; the sensors log {} readings, none collected yet",
        project_line(&init),
        truth.len()
    )?;
    let end = farm.times().last().copied().unwrap_or_default();
    let t0 = end - MISSIONS * DAY;
    Ok((project, truth, t0))
}

/// A new project from `init`, and the ground truth its sensors log: every reading of `files`
/// (in `format`), none collected yet.
fn project_and_truth(
    init: &app::InitRequest,
    files: Vec<PathBuf>,
    format: app::Format,
    progress: &Terminal,
) -> Result<(Project<AnyStore>, app::InitOutcome, gleaner_campaign::Truth)> {
    let (project, outcome) = app::init(init)?;
    let truth = gleaner_campaign::Truth::from_files(
        &project,
        &app::IngestRequest {
            files,
            format,
            ..Default::default()
        },
        DAY,
        progress,
    )?;
    Ok((project, outcome, truth))
}

/// "project NAME: N sensors in C cells of S m".
fn project_line(init: &app::InitOutcome) -> String {
    format!(
        "project {}: {} sensors in {} cells of {} m",
        init.settings.project.name, init.sensors, init.n_cells, init.settings.field.cell_size_m
    )
}

/// The CAF network (Gasch & Brown 2017): sensors in UTM 11N, daily files as ground truth;
/// the exploration flies on 2014-03-01 and the missions follow it, with the paper preset.
fn caf(
    args: &DemoArgs,
    data: &Path,
    out: &mut String,
    progress: &Terminal,
) -> Result<(Project<AnyStore>, gleaner_campaign::Truth, i64)> {
    let caf = data.join("caf");
    let sensors = caf.join("sensors").join("CAF_sensor_locations.csv");
    let mut daily: Vec<PathBuf> = std::fs::read_dir(caf.join("Daily"))
        .with_context(|| format!("{}: cannot list the CAF daily files", caf.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "txt"))
        .collect();
    daily.sort();
    let (project, init, truth) = project_and_truth(
        &app::InitRequest {
            dir: args.dir.clone(),
            sensors,
            utm_zone: Some("11N".into()),
            name: Some("caf-demo".into()),
            force: true,
            gleaner_method: matches!(args.method, crate::MethodArg::Gleaner),
            ..Default::default()
        },
        daily.clone(),
        app::Format::CafDaily,
        progress,
    )?;
    writeln!(
        out,
        "1. CAF network (doi:10.15482/USDA.ADC/1349683): {} daily files, {} readings",
        daily.len(),
        truth.len()
    )?;
    writeln!(
        out,
        "2. {}, energy preset {}",
        project_line(&init),
        init.settings.energy.preset
    )?;
    let t0 = app::parse_timestamp("2014-03-01").context("demo date")?;
    Ok((project, truth, t0))
}
