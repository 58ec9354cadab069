//! Ingest: readings files into the project, all or nothing; re-ingesting changes nothing.

use std::collections::HashSet;
use std::path::{Path, PathBuf};

use gleaner_field::time::format_rfc3339;
use gleaner_field::{Modality, SensorId, UnixSeconds};
use gleaner_ingest::{
    HubbardBrookMetadata, IngestError, IngestOptions, IngestReport, OnError, Readings, WideOptions,
    read_caf_daily, read_hubbard_brook_logger, read_long_csv, read_wide_csv,
};
use gleaner_store::{
    ConflictPolicy, IngestRecord, InsertStats, ModalityRecord, Reading, ReadingBatch, Store,
    StoreError, StoreWrite,
};

use crate::progress::Progress;
use gleaner_scoring::Project;
use gleaner_scoring::state;
use gleaner_scoring::summaries;
use gleaner_scoring::{AppError, Result};

/// A readings file format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Format {
    /// Decide from the file's header.
    #[default]
    Auto,
    /// gleaner's long CSV (`sensor_id,timestamp,modality,value[,unit]`).
    Long,
    /// A wide CSV (time columns + one column per sensor; needs a modality).
    Wide,
    /// A CAF daily file.
    CafDaily,
    /// A Hubbard Brook logger file (`sensor_metadata.csv` beside it, or given).
    HubbardBrook,
}

impl Format {
    /// The name recorded in the provenance table.
    pub fn name(self) -> &'static str {
        match self {
            Format::Auto => "auto",
            Format::Long => "long-csv",
            Format::Wide => "wide-csv",
            Format::CafDaily => "caf-daily",
            Format::HubbardBrook => "hubbard-brook",
        }
    }
}

/// What to ingest and how.
#[derive(Debug, Clone, Default)]
pub struct IngestRequest {
    /// Files to ingest.
    pub files: Vec<PathBuf>,
    /// Their format.
    pub format: Format,
    /// Wide files: the modality of every sensor column (e.g. `vw@30cm`).
    pub modality: Option<String>,
    /// Wide files: the unit of the values.
    pub unit: Option<String>,
    /// Wide files: hours the file's clock is ahead of UTC, in [-14, 14].
    pub utc_offset_h: f64,
    /// Bad-row policy: stop and store nothing, or skip and report.
    pub on_error: OnError,
    /// Hubbard Brook: the probe metadata file [default: `sensor_metadata.csv` beside each file].
    pub metadata: Option<PathBuf>,
    /// The time pending volumes are estimated at, seconds [default: the latest reading].
    pub now: Option<UnixSeconds>,
}

/// What an ingest did.
#[derive(Debug, Clone, Default, PartialEq)]
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
    /// Cells whose summaries were recomputed.
    pub cells_refreshed: usize,
}

/// Files read and parsed, ready to store.
pub struct Parsed {
    /// Per file: path, format, readings, reader counts.
    pub files: Vec<(PathBuf, Format, Readings, IngestReport)>,
    /// Reader counts summed over files.
    pub report: IngestReport,
}

impl Parsed {
    /// Every file's readings, in the files' order.
    pub fn readings(&self) -> Vec<&Readings> {
        self.files.iter().map(|f| &f.2).collect()
    }
    /// Number of readings over all files.
    pub fn len(&self) -> usize {
        self.files.iter().map(|f| f.2.rows.len()).sum()
    }
    /// Whether no file holds a reading.
    pub fn is_empty(&self) -> bool {
        self.files.iter().all(|f| f.2.rows.is_empty())
    }
    /// The latest reading's time, seconds.
    pub fn latest(&self) -> Option<UnixSeconds> {
        self.files
            .iter()
            .flat_map(|f| f.2.rows.iter().map(|r| r.t))
            .max()
    }
    /// Every sensor with a reading, sorted, without duplicates.
    pub fn sensors(&self) -> Vec<SensorId> {
        let mut s: Vec<SensorId> = self
            .files
            .iter()
            .flat_map(|f| {
                let used: HashSet<u32> = f.2.rows.iter().map(|r| r.sensor).collect();
                f.2.sensors
                    .iter()
                    .enumerate()
                    .filter(move |(k, _)| used.contains(&(*k as u32)))
                    .map(|(_, id)| id.clone())
            })
            .collect();
        s.sort();
        s.dedup();
        s
    }
}

/// Decides a file's format from its first line.
pub fn detect(path: &Path) -> Result<Format> {
    use std::io::Read;
    crate::cell_csv::require_regular_file(
        path,
        "not a regular file: give the readings as a file (pipes and devices are not read)",
    )?;
    let mut head = vec![0u8; 4096];
    let n = std::fs::File::open(path)
        .and_then(|mut f| f.read(&mut head))
        .map_err(|e| AppError::io(path, e))?;
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

/// The ids of the project's sensors: readings of any other sensor are refused.
pub fn known_sensors<R: gleaner_store::StoreRead>(store: &R) -> Result<HashSet<String>> {
    Ok(store
        .sensors()?
        .into_iter()
        .map(|s| s.id.to_string())
        .collect())
}

/// Reads and checks every file; stores nothing.
pub fn parse_files(
    request: &IngestRequest,
    known: HashSet<String>,
    value_limits: &gleaner_ingest::limits::ValueLimits,
    progress: &dyn Progress,
) -> Result<Parsed> {
    if request.files.is_empty() {
        return Err(AppError::Invalid("no files to ingest".into()));
    }
    if !(request.utc_offset_h.is_finite() && request.utc_offset_h.abs() <= 14.0) {
        return Err(AppError::Invalid(format!(
            "UTC offset {} h: expected hours in [-14, 14]",
            gleaner_ingest::number(request.utc_offset_h)
        )));
    }
    let options = IngestOptions {
        on_error: request.on_error,
        known_sensors: Some(known),
        value_limits: value_limits.clone(),
    };
    let mut files: Vec<(PathBuf, Format, Readings, IngestReport)> = Vec::new();
    let mut report = IngestReport::default();
    progress.start("reading", Some(request.files.len() as u64));
    for path in &request.files {
        let format = match request.format {
            Format::Auto => detect(path)?,
            f => f,
        };
        let (readings, file_report) = match format {
            Format::CafDaily => read_caf_daily(path, &options)?,
            Format::Long => read_long_csv(path, &options)?,
            Format::HubbardBrook => {
                let meta = match &request.metadata {
                    Some(m) => m.clone(),
                    None => path.with_file_name("sensor_metadata.csv"),
                };
                let metadata = HubbardBrookMetadata::read(&meta)?;
                read_hubbard_brook_logger(path, &metadata, &options)?
            }
            Format::Wide | Format::Auto => {
                let Some(m) = &request.modality else {
                    return Err(AppError::Invalid(format!(
                        "{}: a wide file needs a modality (e.g. --modality vw@30cm)",
                        path.display()
                    )));
                };
                let modality = Modality::new(m)
                    .map_err(|e| AppError::Invalid(format!("modality {m:?}: {e}")))?;
                let mut wide = WideOptions::new(modality);
                wide.unit = request.unit.clone();
                wide.utc_offset_s = (request.utc_offset_h * 3600.0).round() as i64;
                read_wide_csv(path, &wide, &options)?
            }
        };
        for earlier in &files {
            check_units(&earlier.2, &readings, path)?;
        }
        report.merge(&file_report);
        files.push((path.clone(), format, readings, file_report));
        progress.advance(1);
    }
    progress.finish();
    Ok(Parsed { files, report })
}

/// Two files of one ingest must agree on each modality's unit.
fn check_units(all: &Readings, next: &Readings, path: &Path) -> Result<()> {
    for m in &next.modalities {
        if let Some(prev) = all.modalities.iter().find(|p| p.modality == m.modality)
            && let (Some(a), Some(b)) = (&prev.unit, &m.unit)
            && a != b
        {
            return Err(AppError::Invalid(format!(
                "{}: modality {} in {b:?}, but an earlier file of this ingest has it in {a:?}",
                path.display(),
                m.modality
            )));
        }
    }
    Ok(())
}

/// The store's batch of parsed readings: their modalities (with units) and one batch of
/// rows indexing the same sensor and modality tables (values in the modality's unit, times s).
pub fn batch_of(all: &Readings) -> (Vec<ModalityRecord>, ReadingBatch) {
    let modalities = all
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
    (modalities, batch)
}

/// How an insert treats the persisted utility state (see `state.rs`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum StatePolicy {
    /// Bring it up to date in the same transaction (a flight's readings: the next scoring is
    /// fast; the refit cadence decides whether the condition model is refit). The cell
    /// summaries are left to the caller (`record` refreshes every visited cell afterwards).
    Maintain,
    /// Mark it stale when readings were added (a bulk ingest stays as fast as the store
    /// allows; the next `score` rebuilds the state once, O(history)).
    Invalidate,
}

/// Stores parsed readings inside a transaction: modalities, readings, provenance, and the
/// refreshed summaries of the cells whose sensors got readings.
pub(crate) fn store_parsed<W: StoreWrite>(
    tx: &mut W,
    parsed: &Parsed,
    policy: ConflictPolicy,
    at: UnixSeconds,
    now: UnixSeconds,
    settings: &gleaner_scoring::settings::Settings,
    state_policy: StatePolicy,
) -> std::result::Result<(InsertStats, usize, Vec<state::Row>), AppError> {
    let mut stats = InsertStats::default();
    let plan = match state_policy {
        StatePolicy::Maintain => Some(state::before_insert(&*tx, &parsed.readings())?),
        StatePolicy::Invalidate => None,
    };
    // What the insert adds, for the caller's incremental cell summaries (a flight's).
    let added = match &plan {
        Some(plan) => match plan.new_rows() {
            Some(rows) => rows.to_vec(),
            None => state::new_rows(&*tx, &parsed.readings())?,
        },
        None => Vec::new(),
    };
    for (path, format, readings, report) in &parsed.files {
        let (modalities, batch) = batch_of(readings);
        tx.upsert_modalities(&modalities)?;
        let s = tx
            .insert_readings(&batch, policy)
            .map_err(|e| conflict_in_file(e, path, readings))?;
        tx.record_ingest(&IngestRecord {
            file_name: path.display().to_string(),
            format: format.name().to_string(),
            rows_read: report.rows_read,
            rows_inserted: s.inserted,
            rows_unchanged: s.unchanged,
            rows_skipped: report.skipped + s.conflicts.len() as u64,
            at,
        })?;
        stats.inserted += s.inserted;
        stats.unchanged += s.unchanged;
        stats.conflicts.extend(s.conflicts);
    }
    // A flight's readings (`Maintain`): `record` refreshes the visited cells itself once it
    // has marked their sensors collected (a superset of these; the same readings).
    let changed: Vec<SensorId> = if stats.inserted > 0 && state_policy != StatePolicy::Maintain {
        parsed.sensors()
    } else {
        Vec::new()
    };
    let refreshed = summaries::refresh_cells(tx, &changed, now, settings)?;
    if stats.inserted > 0 && state_policy != StatePolicy::Maintain {
        summaries::invalidate_cache(tx)?;
    }
    match plan {
        Some(plan) => state::after_insert(tx, plan, settings)?,
        None if stats.inserted > 0 => state::invalidate(tx)?,
        None => {}
    }
    Ok((stats, refreshed, added))
}

/// How far past the clock a reading may be dated, seconds (a day: a logger's clock running
/// ahead, a local date read as UTC).
pub const FUTURE_TOLERANCE_S: i64 = 86_400;

/// Refuses readings dated more than [`FUTURE_TOLERANCE_S`] after `clock_now`: a sensor cannot
/// have measured the future, and one such reading would move the default mission time there.
/// A clock at or before the epoch is no clock (callers and tests that pass 0): nothing is
/// refused then, and the year range of the readers still applies.
pub(crate) fn refuse_future(parsed: &Parsed, clock_now: UnixSeconds) -> Result<()> {
    if clock_now <= 0 {
        return Ok(());
    }
    let limit = clock_now.saturating_add(FUTURE_TOLERANCE_S);
    for (path, _, readings, _) in &parsed.files {
        if let Some(r) = readings
            .rows
            .iter()
            .filter(|r| r.t > limit)
            .min_by_key(|r| r.line)
        {
            return Err(AppError::Invalid(format!(
                "{}:{}: reading of {} {} dated {}, after the clock ({}); nothing written",
                path.display(),
                r.line,
                readings.sensors[r.sensor as usize],
                readings.modalities[r.modality as usize].modality,
                format_rfc3339(r.t),
                format_rfc3339(clock_now),
            )));
        }
    }
    Ok(())
}

/// A store conflict, told with the file and line of the first conflicting reading and its time
/// as RFC 3339; any other error unchanged.
fn conflict_in_file(e: StoreError, path: &Path, readings: &Readings) -> AppError {
    let StoreError::Conflicts(conflicts) = &e else {
        return e.into();
    };
    let Some(c) = conflicts.first() else {
        return e.into();
    };
    let line = readings
        .rows
        .iter()
        .filter(|r| {
            r.t == c.t
                && readings.sensors[r.sensor as usize] == c.sensor
                && readings.modalities[r.modality as usize].modality == c.modality
        })
        .map(|r| r.line)
        .min();
    let at = line.map_or_else(String::new, |l| format!(":{l}"));
    AppError::Invalid(format!(
        "{} conflicting reading(s), nothing written; first: {} {} at {} ({}{}): the file has \
         {}, the store has {}",
        conflicts.len(),
        c.sensor,
        c.modality,
        format_rfc3339(c.t),
        path.display(),
        at,
        c.incoming,
        c.stored,
    ))
}

/// The use case: reads every file, then stores all readings, their provenance and the
/// refreshed cell summaries in one transaction: a failure anywhere stores nothing.
/// `clock_now` is the wall-clock time (seconds since the epoch): recorded as provenance, and
/// readings dated more than [`FUTURE_TOLERANCE_S`] after it are refused (unless it is 0 or
/// earlier: no clock).
pub fn ingest<S: Store>(
    project: &mut Project<S>,
    request: &IngestRequest,
    clock_now: UnixSeconds,
    progress: &dyn Progress,
) -> Result<IngestOutcome> {
    let limits = project.settings().ingest.value_limits();
    let parsed = parse_files(request, known_sensors(project.store())?, &limits, progress)?;
    refuse_future(&parsed, clock_now)?;
    project.exclusive(|project| ingest_parsed(project, parsed, request, clock_now, progress))
}

/// [`ingest`] with the readings already read (from files, or a simulation's history).
pub fn ingest_parsed<S: Store>(
    project: &mut Project<S>,
    parsed: Parsed,
    request: &IngestRequest,
    clock_now: UnixSeconds,
    progress: &dyn Progress,
) -> Result<IngestOutcome> {
    let policy = match request.on_error {
        OnError::Fail => ConflictPolicy::Fail,
        OnError::Skip => ConflictPolicy::Skip,
    };
    let latest = parsed.latest();
    let now = request.now.or(latest).unwrap_or(clock_now);
    let settings = project.settings().clone();
    progress.start(&format!("storing {} readings", parsed.len()), None);
    let (stats, refreshed, _) = project.store_mut().write(|tx| {
        store_parsed(
            tx,
            &parsed,
            policy,
            clock_now,
            now,
            &settings,
            StatePolicy::Invalidate,
        )
    })?;
    progress.finish();
    Ok(IngestOutcome {
        files: parsed.files.len(),
        report: parsed.report,
        inserted: stats.inserted,
        unchanged: stats.unchanged,
        conflicts: stats.conflicts.len() as u64,
        cells_refreshed: refreshed,
    })
}
