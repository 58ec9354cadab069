//! `gleaner ingest`: readings files into the project database, all or nothing.

use std::collections::HashSet;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use gleaner_field::Modality;
use gleaner_ingest::{
    HubbardBrookMetadata, IngestError, IngestOptions, IngestReport, OnError, Readings, WideOptions,
    read_caf_daily, read_hubbard_brook_logger, read_long_csv, read_wide_csv,
};
use gleaner_store::{
    ConflictPolicy, IngestRecord, ModalityRecord, Reading, ReadingBatch, RefreshParams, Store,
};

use crate::progress;
use crate::project::Project;

/// A readings file format.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// Decide from the file's header.
    Auto,
    /// gleaner's long CSV.
    Long,
    /// A wide CSV (time columns + one column per sensor).
    Wide,
    /// A CAF daily file.
    CafDaily,
    /// A Hubbard Brook logger file (`sensor_metadata.csv` beside it, or `--metadata`).
    HubbardBrook,
}

impl Format {
    fn name(self) -> &'static str {
        match self {
            Format::Auto => "auto",
            Format::Long => "long-csv",
            Format::Wide => "wide-csv",
            Format::CafDaily => "caf-daily",
            Format::HubbardBrook => "hubbard-brook",
        }
    }
}

/// Settings from the command line.
pub struct IngestArgs {
    /// Files to ingest.
    pub files: Vec<PathBuf>,
    /// Their format.
    pub format: Format,
    /// For wide files: the modality of every sensor column.
    pub modality: Option<String>,
    /// For wide files: its unit.
    pub unit: Option<String>,
    /// For wide files: hours the file's clock is ahead of UTC.
    pub utc_offset_h: f64,
    /// Bad-row policy.
    pub on_error: OnError,
    /// Hubbard Brook: the probe metadata file [default: `sensor_metadata.csv` beside each file].
    pub metadata: Option<PathBuf>,
    /// The mission time "now" for pending-volume estimates, seconds since the epoch; default:
    /// the latest reading.
    pub now: Option<i64>,
}

/// What an ingest did, for the summary line and tests.
#[derive(Debug, Default)]
pub struct IngestOutcome {
    /// Files read.
    pub files: usize,
    /// Reader counts, summed over files.
    pub report: IngestReport,
    /// Readings newly stored.
    pub inserted: u64,
    /// Readings already stored identically.
    pub unchanged: u64,
    /// Readings that conflicted with stored values and were skipped.
    pub conflicts: u64,
}

impl std::fmt::Display for IngestOutcome {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let r = &self.report;
        write!(
            f,
            "ingested {} file(s): {} rows read, {} readings ({} new, {} already stored), {} missing values, {} duplicate rows, {} rows skipped, {} conflicts kept as stored",
            self.files,
            r.rows_read,
            r.readings,
            self.inserted,
            self.unchanged,
            r.missing,
            r.duplicates,
            r.skipped,
            self.conflicts
        )?;
        for s in &r.skipped_rows {
            write!(f, "\n  skipped: {}", s.reason)?;
        }
        Ok(())
    }
}

fn detect(path: &Path) -> Result<Format> {
    let mut head = vec![0u8; 4096];
    let n = {
        use std::io::Read;
        let mut f = std::fs::File::open(path)
            .with_context(|| format!("{}: cannot read", path.display()))?;
        f.read(&mut head)
            .with_context(|| format!("{}: cannot read", path.display()))?
    };
    let first = String::from_utf8_lossy(&head[..n]);
    let first = first
        .trim_start_matches('\u{feff}')
        .lines()
        .next()
        .unwrap_or("")
        .to_ascii_lowercase();
    if first.starts_with("location\tdate") {
        Ok(Format::CafDaily)
    } else if first.starts_with("timestamp,p1:") {
        Ok(Format::HubbardBrook)
    } else if first.split(',').any(|c| c.trim() == "modality") {
        Ok(Format::Long)
    } else if !first.is_empty() {
        Ok(Format::Wide)
    } else {
        Err(IngestError::Empty {
            path: path.to_path_buf(),
        }
        .into())
    }
}

/// Reads every file, then stores all readings in one transaction: a failure anywhere stores
/// nothing.
pub fn run(project: &mut Project, args: &IngestArgs) -> Result<IngestOutcome> {
    if args.files.is_empty() {
        bail!("no files to ingest");
    }
    let known: HashSet<String> = project
        .store
        .sensors()?
        .into_iter()
        .map(|s| s.id.to_string())
        .collect();
    let options = IngestOptions {
        on_error: args.on_error,
        known_sensors: Some(known),
    };
    let pb = progress::bar(args.files.len() as u64, "reading");
    let mut all = Readings::default();
    let mut outcome = IngestOutcome::default();
    let mut provenance = Vec::new();
    for path in &args.files {
        let format = match args.format {
            Format::Auto => detect(path)?,
            f => f,
        };
        let (readings, report) = match format {
            Format::CafDaily => read_caf_daily(path, &options)?,
            Format::Long => read_long_csv(path, &options)?,
            Format::HubbardBrook => {
                let meta = match &args.metadata {
                    Some(m) => m.clone(),
                    None => path.with_file_name("sensor_metadata.csv"),
                };
                let metadata = HubbardBrookMetadata::read(&meta).with_context(|| {
                    format!(
                        "{}: probe metadata for this logger file (--metadata)",
                        path.display()
                    )
                })?;
                read_hubbard_brook_logger(path, &metadata, &options)?
            }
            Format::Wide | Format::Auto => {
                let Some(m) = &args.modality else {
                    bail!(
                        "{}: a wide file needs --modality (e.g. --modality vw@30cm)",
                        path.display()
                    );
                };
                let mut wide = WideOptions::new(Modality::new(m).context("--modality")?);
                wide.unit = args.unit.clone();
                wide.utc_offset_s = (args.utc_offset_h * 3600.0).round() as i64;
                read_wide_csv(path, &wide, &options)?
            }
        };
        pb.set_message(
            path.file_name()
                .map_or_else(String::new, |n| n.to_string_lossy().into_owned()),
        );
        provenance.push((path.clone(), format, report.clone()));
        outcome.report.merge(&report);
        all.append(readings);
        pb.inc(1);
    }
    pb.finish_and_clear();
    outcome.files = args.files.len();
    store_readings(project, &all, args, &provenance, &mut outcome)?;
    Ok(outcome)
}

fn store_readings(
    project: &mut Project,
    all: &Readings,
    args: &IngestArgs,
    provenance: &[(PathBuf, Format, IngestReport)],
    outcome: &mut IngestOutcome,
) -> Result<()> {
    let modalities: Vec<ModalityRecord> = all
        .modalities
        .iter()
        .map(|m| ModalityRecord {
            modality: m.modality.clone(),
            unit: m.unit.clone(),
        })
        .collect();
    let batch = ReadingBatch {
        sensors: all.sensors.clone(),
        modalities: all.modalities.iter().map(|m| m.modality.clone()).collect(),
        rows: all
            .rows
            .iter()
            .map(|r| Reading {
                sensor: r.sensor,
                modality: r.modality,
                t: r.t,
                value: r.value,
            })
            .collect(),
    };
    let policy = match args.on_error {
        OnError::Fail => ConflictPolicy::Fail,
        OnError::Skip => ConflictPolicy::Skip,
    };
    let at = now_unix();
    let records: Vec<IngestRecord> = provenance
        .iter()
        .map(|(path, format, report)| IngestRecord {
            file_name: path.display().to_string(),
            format: format.name().to_string(),
            rows_read: report.rows_read,
            rows_inserted: 0,
            rows_unchanged: 0,
            rows_skipped: report.skipped,
            at,
        })
        .collect();
    let spin = progress::spinner(&format!("storing {} readings", batch.rows.len()));
    let stats = project
        .store
        .ingest(&modalities, &batch, policy, &records)
        .context("storing the readings (nothing was stored)")?;
    spin.set_message("updating cell summaries");
    outcome.inserted = stats.inserted;
    outcome.unchanged = stats.unchanged;
    outcome.conflicts = stats.conflicts.len() as u64;
    let latest = all.rows.iter().map(|r| r.t).max();
    let now = args.now.or(latest).unwrap_or(at);
    project.store.refresh_cell_summaries(&RefreshParams {
        now,
        bytes_per_reading: project.config.ingest.bytes_per_reading,
        default_interval_s: project.config.ingest.default_interval_s,
        // Only the cells of sensors with readings in this ingest change.
        changed_sensors: Some(all.sensors.clone()),
    })?;
    spin.finish_and_clear();
    Ok(())
}

/// The wall clock, seconds since the epoch (for provenance only; never for results).
pub fn now_unix() -> i64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs() as i64)
}
