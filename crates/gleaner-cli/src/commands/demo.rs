//! `gleaner demo`: the main job on built-in data — a synthetic farm, a project, an ingest and
//! the cell summary (later steps: scoring, planning, mission files).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use crate::commands::{cells, ingest, init, synth};
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
            now: None,
        },
    )?;
    writeln!(out, "3. {outcome}")?;
    let mut rows = cells::cell_rows(&project)?;
    cells::sort(&mut rows, cells::SortKey::Sensors);
    writeln!(
        out,
        "4. cell table ({} cells; the 10 with most sensors):",
        rows.len()
    )?;
    out.push_str(&cells::table(&rows[..rows.len().min(10)]));
    Ok(out)
}
