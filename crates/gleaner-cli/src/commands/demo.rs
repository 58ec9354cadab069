//! `gleaner demo`: the main job on built-in data — a synthetic farm, a project, an ingest, the
//! cell table, scoring, a planned mission (against the paper's greedy), the recorded flight and
//! the rescoring that follows it.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use crate::commands::{cells, export, ingest, init, plan, record, score, synth};
use crate::project::Project;

/// Settings from the command line.
pub struct DemoArgs {
    /// Working directory (created; the files the demo writes there are replaced).
    pub dir: PathBuf,
    /// Seed of the synthetic farm.
    pub seed: u64,
    /// Number of sensors.
    pub sensors: usize,
    /// Number of days of history.
    pub days: u32,
}

/// Removes what an earlier demo run wrote in `dir` (and nothing else).
fn clean(dir: &Path) -> Result<()> {
    for name in [
        "gleaner.toml",
        "gleaner.db",
        "gleaner.db-wal",
        "gleaner.db-shm",
    ] {
        let p = dir.join(name);
        if p.exists() {
            std::fs::remove_file(&p).with_context(|| format!("{}: cannot remove", p.display()))?;
        }
    }
    Ok(())
}

/// Runs the demo; returns its report.
pub fn run(args: &DemoArgs) -> Result<String> {
    let mut out = String::new();
    clean(&args.dir)?;
    let data_dir = args.dir.join("data");
    let (farm, files) = synth::run(&synth::SynthArgs {
        out: data_dir,
        seed: args.seed,
        sensors: args.sensors,
        days: args.days,
        interval_s: 86_400,
        events: 3,
        correlation_length_m: 500.0,
        no_faults: false,
        scale_extent: false,
        vw_depths_cm: vec![30, 60, 90],
        t_depths_cm: vec![30],
    })?;
    writeln!(
        out,
        "1. synthetic farm (seed {}): {} sensors, {} days, {} readings, {} ground-truth events -> {}",
        args.seed,
        args.sensors,
        args.days,
        farm.reading_count(),
        farm.events().len(),
        files
            .readings
            .parent()
            .map_or_else(String::new, |p| p.display().to_string())
    )?;
    let base = farm.base();
    let summary = init::run(&init::InitArgs {
        dir: args.dir.clone(),
        sensors: files.sensors.clone(),
        utm_zone: None,
        hubbard_brook: false,
        base: Some((base.lat(), base.lon())),
        cell_size_m: Some(init::DEFAULT_CELL_SIZE_M),
        coverage: None,
        name: Some("demo".into()),
        force: true,
    })?;
    writeln!(out, "2. {summary}")?;
    let mut project = Project::open(&args.dir)?;
    let outcome = ingest::run(
        &mut project,
        &ingest::IngestArgs {
            files: vec![files.readings.clone()],
            format: ingest::Format::Long,
            modality: None,
            unit: None,
            utc_offset_h: 0.0,
            on_error: gleaner_ingest::OnError::Fail,
            metadata: None,
            now: None,
        },
    )?;
    writeln!(out, "3. {outcome}")?;
    let mut rows = cells::cell_rows(&project)?;
    cells::sort(&mut rows, cells::SortKey::Sensors);
    writeln!(
        out,
        "4. cell table ({} cells; the 5 with most sensors):",
        rows.len()
    )?;
    out.push_str(&cells::table(&rows[..rows.len().min(5)]));

    // The exploration flew until 30 days before the end of the record; the mission is planned
    // 10 days later, from what was collected by then.
    let end = farm.times().last().copied().unwrap_or_default();
    let history = score::History {
        from: i64::MIN,
        until: end - 30 * 86_400,
    };
    let t = end - 20 * 86_400;
    let scoring = score::score(&project, Some(t), history, None)?;
    score::store_scores(&mut project, &scoring)?;
    let doc = score::to_json(&project, &scoring);
    writeln!(
        out,
        "5. scores (history until {}, the 8 best cells):",
        gleaner_ingest::time::format_rfc3339(history.until)
    )?;
    out.push_str(&score::table(&doc, 8));
    let plan_args = plan::PlanArgs {
        at: Some(t),
        history,
        scores: None,
        planner: gleaner_mission::Planner::Default,
        time_limit_s: 2.0,
        seed: args.seed,
        save: true,
    };
    let planned = plan::run(&mut project, &plan_args)?;
    let mission = plan::to_json(&project, &planned, &plan_args);
    writeln!(out, "6. {}", plan::table(&mission).trim_end())?;
    let id = planned.mission_id.context("the mission was stored")?;
    let files = export::run(&project, &args.dir, id, None)?;
    writeln!(
        out,
        "   mission files: {}, {}, {}, {}",
        files.geojson.display(),
        files.plan.display(),
        files.waypoints.display(),
        files.map.display()
    )?;
    let recorded = record::run(
        &mut project,
        &record::RecordArgs {
            mission: id,
            at: Some(t),
            cells: None,
            files: Vec::new(),
            ingest: None,
        },
    )?;
    writeln!(out, "7. {recorded}")?;
    let after = score::score(&project, Some(t + 86_400), history, None)?;
    score::store_scores(&mut project, &after)?;
    let after_doc = score::to_json(&project, &after);
    writeln!(
        out,
        "8. a day later the visited cells are fresh again (before -> after):"
    )?;
    for stop in mission.stops.iter().take(5) {
        let before = doc.cells.iter().find(|c| c.cell == stop.cell);
        let now = after_doc.cells.iter().find(|c| c.cell == stop.cell);
        if let (Some(b), Some(a)) = (before, now) {
            writeln!(
                out,
                "   {:<10} F {:.3} -> {:.3}   U {:.3} -> {:.3}   S {:.3} -> {:.3}",
                stop.cell, b.f, a.f, b.u, a.u, b.s, a.s
            )?;
        }
    }
    Ok(out)
}
