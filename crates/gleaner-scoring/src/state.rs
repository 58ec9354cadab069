//! The persisted utility state: what makes `score` cost O(cells × neighbours) instead of
//! O(history).
//!
//! One store blob ([`BLOB_KEY`]) holds, next to gleaner-utility's [`IncrementalState`] (the
//! statistics behind A and R, 32 grid steps of recent slots and at least the last 5 points of
//! every cell series):
//! - fingerprints of the field (sensors, cells, neighbours) and of the settings the state and
//!   the condition model depend on, and the store's reading count when it was written;
//! - the modality names, per sensor its first and latest reading, per sensor and modality its
//!   first and last reading time and a histogram of the gaps between consecutive readings
//!   (so the sampling grid of [`knowledge`](crate::knowledge()) — origin: the earliest
//!   reading, step: the median gap — is known without reading the history);
//! - the condition model behind U, trained on the whole class-modality history with label
//!   times before the newest reading (exactly what the full path trains when scoring at the
//!   newest reading), or the warning its training gave. With a refit cadence
//!   (`utility.condition_refit_growth` > 0, the default 0.05) it is one model trained on every
//!   label up to the newest reading at its fit, kept (with the class-modality reading counts
//!   at the fit and since) until the readings added since exceed that fraction of those it was
//!   trained on; a refit starts Newton's method from it (same optimum, fewer iterations).
//!
//! Kept up to date inside the transaction of every ingest and recorded flight: the readings
//! that are new to the store are added to the statistics (O(new readings × neighbours)) and
//! the condition model is refit on the class modality's history (O(that modality's history);
//! refitting at write time keeps scoring exact and cheap). The state is rebuilt from all
//! stored readings instead when the blob is missing or unreadable, a fingerprint or the grid
//! changes, a new modality appears, readings arrive inside a series' span (not after its last
//! or before its first reading) or older than the retention horizon, or the reading count
//! does not add up. When the state cannot be built (no sensors, no readings) an empty blob is
//! written, which scoring treats as missing.
//!
//! [`fast_scoring`] answers the common scoring request from the blob: everything stored counts
//! (`History::default()`), no user probabilities, the all-history window, and `at` (if given)
//! at or after the newest reading. If `at` is after the newest reading while some
//! class-modality point lies exactly at the newest reading, the model the full path would
//! train differs (it would see that point's label): the full path is taken.

use std::collections::{BTreeMap, HashMap, HashSet};

use gleaner_field::{Field, Modality, Sensor, SensorId, UnixSeconds};
use gleaner_ingest::Readings;
use gleaner_store::{ReadingBatch, StoreRead, StoreWrite};
use gleaner_utility::{
    ConditionConfig, ConditionModel, HistoryWindow, IncrementalState, OwnedSeries, Reading, Series,
    TimeGrid,
};

use crate::codec::{Fnv, In, Out};
use crate::condition::{
    NO_MODALITY, ScoreRequest, Scoring, condition_modality, condition_output, fit_condition_from,
    neighbour_lists,
};
use crate::error::{AppError, Result};
use crate::knowledge::{Columns, Knowledge, cell_series_of, columns};
use crate::project::Project;
use crate::settings::Settings;
use crate::{History, Store};

/// The store blob holding the persisted state.
pub(crate) const BLOB_KEY: &str = "utility.incremental";
/// Magic of the blob (8 bytes), followed by [`VERSION`] as a little-endian `u32`.
const MAGIC: &[u8; 8] = b"GLNAPPST";
/// Blob format version; a blob of another version is rebuilt.
const VERSION: u32 = 2;
/// Grid slots kept in the state, in grid steps (32 days of daily data).
const RETENTION_STEPS: i64 = 32;

/// A trained condition model, or the warning its training gave (U = 0).
type Fit = std::result::Result<ConditionModel, String>;

/// The condition model part of the state (one per state: its size does not matter).
#[derive(Debug, Clone)]
#[allow(clippy::large_enum_variant)]
enum ConditionState {
    /// No soil-moisture modality: U = 0 with [`NO_MODALITY`].
    NoModality,
    /// The configured modality has no readings: scoring fails (full path).
    Unusable,
    /// Trained on the class modality.
    Fitted(ConditionFit),
}

/// A condition model trained on the class modality `modality` when the newest reading was
/// `fitted_to` (s).
#[derive(Debug, Clone)]
struct ConditionFit {
    modality: String,
    fitted_to: UnixSeconds,
    /// Class-modality readings in the store at the fit.
    trained: u64,
    /// Class-modality readings added since (the refit cadence, see
    /// [`Settings`]' `utility.condition_refit_growth`).
    pending: u64,
    /// Labels before `fitted_to`: what scoring at t = `fitted_to` trains.
    at_latest: Fit,
    /// Labels at or before `fitted_to`: what scoring at a later t trains; `None` when
    /// no class-modality point lies at `fitted_to` (then it is `at_latest`).
    after_latest: Option<Fit>,
}

fn put_fit(o: &mut Out, fit: &Fit) {
    match fit {
        Ok(model) => {
            o.u8(1);
            o.bytes(&model.to_bytes());
        }
        Err(warning) => {
            o.u8(0);
            o.bytes(warning.as_bytes());
        }
    }
}

fn get_fit(i: &mut In<'_>) -> Option<Fit> {
    match i.u8()? {
        0 => Some(Err(i.string()?)),
        1 => Some(Ok(ConditionModel::from_bytes(i.bytes()?).ok()?)),
        _ => None,
    }
}

/// Everything persisted (see the module docs).
#[derive(Debug, Clone)]
pub struct Persisted {
    field_fp: u64,
    settings_fp: u64,
    reading_count: u64,
    modalities: Vec<String>,
    /// Per sensor: first and latest reading, s.
    first_reading: Vec<Option<UnixSeconds>>,
    last_reading: Vec<Option<UnixSeconds>>,
    /// Per sensor × modality (sensor-major): first and last reading, s.
    span: Vec<Option<(UnixSeconds, UnixSeconds)>>,
    /// Gap between consecutive readings of a series (s) -> how many.
    gaps: BTreeMap<i64, u64>,
    latest: Option<UnixSeconds>,
    condition: ConditionState,
    state: IncrementalState,
}

// ---------------------------------------------------------------------------------------
// Fingerprints

fn field_fingerprint(sensors: &[Sensor], field: &Field) -> u64 {
    let mut h = Fnv::new();
    h.u64(sensors.len() as u64);
    for s in sensors {
        h.str(s.id.as_str());
    }
    let neighbours = neighbour_lists(field);
    h.u64(field.cells().len() as u64);
    for (cell, nbs) in field.cells().iter().zip(&neighbours) {
        h.u64(cell.index.i as u64);
        h.u64(cell.index.j as u64);
        h.u64(cell.sensors.len() as u64);
        for &s in &cell.sensors {
            h.u64(s as u64);
        }
        h.u64(nbs.len() as u64);
        for &j in nbs {
            h.u64(j as u64);
        }
    }
    h.0
}

fn settings_fingerprint(settings: &Settings) -> u64 {
    let u = &settings.utility;
    let mut h = Fnv::new();
    h.str(&format!(
        "{:?}|{}|{:?}|{RETENTION_STEPS}|{:?}",
        u.condition_modality,
        u.condition_classes,
        u.condition_thresholds,
        ConditionConfig::default()
    ));
    h.0
}

impl Persisted {
    /// The blob: [`MAGIC`], [`VERSION`], then the fields in declaration order (little-endian;
    /// lists as a u64 count then the elements; the state and the model as length-prefixed
    /// bytes of their own formats).
    fn to_bytes(&self) -> Vec<u8> {
        let mut o = Out(MAGIC.to_vec());
        o.0.extend_from_slice(&VERSION.to_le_bytes());
        o.u64(self.field_fp);
        o.u64(self.settings_fp);
        o.u64(self.reading_count);
        o.u64(self.modalities.len() as u64);
        for m in &self.modalities {
            o.bytes(m.as_bytes());
        }
        o.u64(self.first_reading.len() as u64);
        for (f, l) in self.first_reading.iter().zip(&self.last_reading) {
            o.opt(*f);
            o.opt(*l);
        }
        o.u64(self.span.len() as u64);
        for s in &self.span {
            o.opt(s.map(|s| s.0));
            o.opt(s.map(|s| s.1));
        }
        o.u64(self.gaps.len() as u64);
        for (&g, &n) in &self.gaps {
            o.i64(g);
            o.u64(n);
        }
        o.opt(self.latest);
        match &self.condition {
            ConditionState::NoModality => o.u8(0),
            ConditionState::Unusable => o.u8(1),
            ConditionState::Fitted(f) => {
                o.u8(2);
                o.bytes(f.modality.as_bytes());
                o.i64(f.fitted_to);
                o.u64(f.trained);
                o.u64(f.pending);
                put_fit(&mut o, &f.at_latest);
                match &f.after_latest {
                    None => o.u8(0),
                    Some(fit) => {
                        o.u8(1);
                        put_fit(&mut o, fit);
                    }
                }
            }
        }
        o.bytes(&self.state.to_bytes());
        o.0
    }

    /// Decodes [`to_bytes`](Self::to_bytes); `None` for anything else (another version, a
    /// truncated or corrupt blob, the empty "no state" blob).
    fn from_bytes(b: &[u8]) -> Option<Self> {
        let mut i = In(b);
        if i.take(8)? != MAGIC || u32::from_le_bytes(i.take(4)?.try_into().ok()?) != VERSION {
            return None;
        }
        let field_fp = i.u64()?;
        let settings_fp = i.u64()?;
        let reading_count = i.u64()?;
        let nm = i.count(8)?;
        let modalities = (0..nm).map(|_| i.string()).collect::<Option<Vec<_>>>()?;
        let ns = i.count(2)?;
        let mut first_reading = Vec::with_capacity(ns);
        let mut last_reading = Vec::with_capacity(ns);
        for _ in 0..ns {
            first_reading.push(i.opt()?);
            last_reading.push(i.opt()?);
        }
        let nspan = i.count(2)?;
        let mut span = Vec::with_capacity(nspan);
        for _ in 0..nspan {
            span.push(match (i.opt()?, i.opt()?) {
                (Some(a), Some(b)) => Some((a, b)),
                (None, None) => None,
                _ => return None,
            });
        }
        let ng = i.count(16)?;
        let mut gaps = BTreeMap::new();
        for _ in 0..ng {
            gaps.insert(i.i64()?, i.u64()?);
        }
        let latest = i.opt()?;
        let condition = match i.u8()? {
            0 => ConditionState::NoModality,
            1 => ConditionState::Unusable,
            2 => ConditionState::Fitted(ConditionFit {
                modality: i.string()?,
                fitted_to: i.i64()?,
                trained: i.u64()?,
                pending: i.u64()?,
                at_latest: get_fit(&mut i)?,
                after_latest: match i.u8()? {
                    0 => None,
                    1 => Some(get_fit(&mut i)?),
                    _ => return None,
                },
            }),
            _ => return None,
        };
        let state = IncrementalState::from_bytes(i.bytes()?).ok()?;
        let consistent = i.0.is_empty()
            && Some(span.len()) == ns.checked_mul(nm)
            && state.n_modalities() == nm
            && last_reading.len() == ns;
        consistent.then_some(Self {
            field_fp,
            settings_fp,
            reading_count,
            modalities,
            first_reading,
            last_reading,
            span,
            gaps,
            latest,
            condition,
            state,
        })
    }
}

// ---------------------------------------------------------------------------------------
// Building and updating

/// The sensors (sorted by id) and the field from a store and the settings; `None` when there
/// are no sensors or the grid cannot be built (the state is then not kept).
fn field_of<R: StoreRead>(store: &R, settings: &Settings) -> Result<Option<(Vec<Sensor>, Field)>> {
    let sensors: Vec<Sensor> = crate::project::sensors_of(store)?;
    if sensors.is_empty() {
        return Ok(None);
    }
    let Ok(base) = settings.base() else {
        return Ok(None);
    };
    Ok(Field::build(&sensors, base, &settings.field_config())
        .ok()
        .map(|f| (sensors, f)))
}

/// The sampling step of the gap histogram: the median gap, as `knowledge` computes it.
fn median_gap(gaps: &BTreeMap<i64, u64>) -> i64 {
    let total: u64 = gaps.values().sum();
    if total == 0 {
        return 86_400;
    }
    let mid = total / 2;
    let mut seen = 0;
    for (&g, &n) in gaps {
        seen += n;
        if seen > mid {
            return g;
        }
    }
    86_400
}

fn grid_of(p: &Persisted) -> TimeGrid {
    let origin = p.span.iter().flatten().map(|s| s.0).min().unwrap_or(0);
    TimeGrid {
        origin,
        step_s: median_gap(&p.gaps).max(1),
    }
}

/// Trains the condition model (labels before `latest`) from the class modality's series,
/// Newton's method warm-started from `previous` when given; `trained`: the class modality's
/// readings in the store.
fn condition_state(
    settings: &Settings,
    modalities: &[String],
    field: &Field,
    class_series: impl FnOnce(usize) -> Vec<OwnedSeries>,
    latest: UnixSeconds,
    trained: impl FnOnce(usize) -> u64,
    previous: Option<&ConditionModel>,
) -> ConditionState {
    let Some(name) = condition_modality(settings, modalities) else {
        return ConditionState::NoModality;
    };
    let Some(m) = modalities.iter().position(|x| *x == name) else {
        return ConditionState::Unusable;
    };
    let series = class_series(m);
    let cells: Vec<Series<'_>> = series.iter().map(OwnedSeries::as_series).collect();
    let neighbours = neighbour_lists(field);
    let point_at_latest = cells.iter().any(|s| s.times.last() == Some(&latest));
    if settings.utility.condition_refit_growth > 0.0 {
        // With a refit cadence the model is kept for later times anyway: one fit on every
        // label up to and including the newest reading (known data), used for every t.
        let at_latest = fit_condition_from(
            settings,
            &cells,
            &neighbours,
            latest.saturating_add(1),
            previous,
        );
        return ConditionState::Fitted(ConditionFit {
            modality: name,
            fitted_to: latest,
            trained: trained(m),
            pending: 0,
            at_latest,
            after_latest: None,
        });
    }
    let at_latest = fit_condition_from(settings, &cells, &neighbours, latest, previous);
    let after_latest = point_at_latest.then(|| {
        fit_condition_from(
            settings,
            &cells,
            &neighbours,
            latest.saturating_add(1),
            at_latest.as_ref().ok().or(previous),
        )
    });
    ConditionState::Fitted(ConditionFit {
        modality: name,
        fitted_to: latest,
        trained: trained(m),
        pending: 0,
        at_latest,
        after_latest,
    })
}

fn new_state(field: &Field, nm: usize, grid: TimeGrid) -> Option<IncrementalState> {
    let per_cell: Vec<usize> = field.cells().iter().map(|c| c.sensors.len()).collect();
    let mut state = IncrementalState::new(&per_cell, &neighbour_lists(field), nm, grid).ok()?;
    state.set_retention(Some(RETENTION_STEPS.saturating_mul(grid.step_s)));
    state.set_min_points(ConditionConfig::default().trend_points);
    Some(state)
}

/// Per sensor position: (cell, position within the cell).
fn places(field: &Field, n_sensors: usize) -> Vec<(usize, usize)> {
    let mut place = vec![(0, 0); n_sensors];
    for (c, cell) in field.cells().iter().enumerate() {
        for (k, &s) in cell.sensors.iter().enumerate() {
            if let Some(p) = place.get_mut(s) {
                *p = (c, k);
            }
        }
    }
    place
}

/// Every reading of `batch` as columns, none held back by a collection time or window.
fn all_columns(sensors: &[Sensor], batch: &ReadingBatch, grid: Option<TimeGrid>) -> Columns {
    let none = vec![None; sensors.len()];
    columns(
        sensors,
        batch,
        &none,
        UnixSeconds::MAX,
        UnixSeconds::MAX,
        grid,
    )
}

/// Builds the state from every stored reading. O(history).
fn rebuild<R: StoreRead>(store: &R, settings: &Settings) -> Result<Option<Persisted>> {
    rebuild_keeping(store, settings, None)
}

/// [`rebuild`] after a write the incremental update could not take (e.g. readings older than
/// the retention horizon): `carry` is the condition model of the state before the write and
/// the class-modality readings the write added. The refit cadence applies as in `update`: the
/// model is kept while those readings stay within `condition_refit_growth`, else refit from it.
fn rebuild_keeping<R: StoreRead>(
    store: &R,
    settings: &Settings,
    carry: Option<(ConditionState, u64)>,
) -> Result<Option<Persisted>> {
    let Some((sensors, field)) = field_of(store, settings)? else {
        return Ok(None);
    };
    let batch = store.readings_for(None, UnixSeconds::MIN..=UnixSeconds::MAX)?;
    let c = all_columns(&sensors, &batch, None);
    drop(batch);
    let Some(latest) = c.latest else {
        return Ok(None);
    };
    let nm = c.modalities.len();
    let Some(mut state) = new_state(&field, nm, c.grid) else {
        return Ok(None);
    };
    let place = places(&field, sensors.len());
    let mut readings = Vec::new();
    let mut span = vec![None; sensors.len() * nm];
    let mut gaps = BTreeMap::new();
    for (k, (times, values)) in c.times.iter().zip(&c.values).enumerate() {
        let (s, m) = (k / nm.max(1), k % nm.max(1));
        let (cell, sensor) = place[s];
        for (&time, &value) in times.iter().zip(values) {
            readings.push(Reading {
                cell,
                sensor,
                modality: m,
                time,
                value,
            });
        }
        for w in times.windows(2) {
            if w[1] > w[0] {
                *gaps.entry(w[1] - w[0]).or_insert(0) += 1;
            }
        }
        if let (Some(&a), Some(&b)) = (times.first(), times.last()) {
            span[k] = Some((a, b));
        }
    }
    if state.add_readings(&readings).is_err() {
        return Ok(None);
    }
    drop(readings);
    state.trim();
    let class_name = condition_modality(settings, &c.modalities);
    let growth = settings.utility.condition_refit_growth;
    let mut previous = None;
    let mut kept = None;
    if let Some((ConditionState::Fitted(f), added)) = carry
        && class_name.as_deref() == Some(f.modality.as_str())
    {
        let pending = f.pending + added;
        if growth > 0.0 && (pending as f64) <= growth * (f.trained as f64) && f.fitted_to <= latest
        {
            kept = Some(ConditionState::Fitted(ConditionFit { pending, ..f }));
        } else {
            previous = f.after_latest.and_then(Result::ok).or(f.at_latest.ok());
        }
    }
    let condition = match kept {
        Some(kept) => kept,
        None => condition_state(
            settings,
            &c.modalities,
            &field,
            |m| {
                cell_series_of(&field, &c, Some(m))
                    .into_iter()
                    .map(|mut v| v.pop().unwrap_or_default())
                    .collect()
            },
            latest,
            |m| {
                c.times
                    .iter()
                    .skip(m)
                    .step_by(nm.max(1))
                    .map(|t| t.len() as u64)
                    .sum()
            },
            previous.as_ref(),
        ),
    };
    let last_reading = c.last_collected.clone();
    Ok(Some(Persisted {
        field_fp: field_fingerprint(&sensors, &field),
        settings_fp: settings_fingerprint(settings),
        reading_count: store.reading_count()?,
        modalities: c.modalities,
        first_reading: c.first_reading,
        last_reading,
        span,
        gaps,
        latest: Some(latest),
        condition,
        state,
    }))
}

/// Marks the persisted state stale (an empty blob): the next `score` rebuilds it.
pub fn invalidate<W: StoreWrite>(tx: &mut W) -> Result<()> {
    write_blob(tx, None)
}

fn write_blob<W: StoreWrite>(tx: &mut W, p: Option<&Persisted>) -> Result<()> {
    let bytes = p.map(Persisted::to_bytes).unwrap_or_default();
    tx.blob_put(BLOB_KEY, &bytes)?;
    Ok(())
}

/// A new reading: sensor id, modality name, time (s), value.
pub type Row = (SensorId, String, UnixSeconds, f64);

/// What to do after the readings are inserted.
pub enum Plan {
    /// Rebuild from the store.
    Rebuild,
    /// Add these readings (new to the store) to the persisted state.
    Update(Box<Persisted>, Vec<Row>),
}

impl Plan {
    /// The readings new to the store, when the plan computed them (an update).
    pub fn new_rows(&self) -> Option<&[Row]> {
        match self {
            Plan::Rebuild => None,
            Plan::Update(_, rows) => Some(rows),
        }
    }
}

/// Before inserting `files` (each parsed file's readings): loads the state and works out which readings are new to the
/// store (the first of several with the same key; one already stored is not). Costs in
/// proportion to the stored readings of the batch's sensors within its time span.
pub fn before_insert<R: StoreRead>(tx: &R, files: &[&Readings]) -> Result<Plan> {
    let Some(p) = tx
        .blob_get(BLOB_KEY)?
        .and_then(|b| Persisted::from_bytes(&b))
    else {
        return Ok(Plan::Rebuild);
    };
    Ok(Plan::Update(Box::new(p), new_rows(tx, files)?))
}

/// The readings of `files` that are not yet in the store (one per sensor, modality and
/// time, in the files' order): what an insert will add. Reads the stored readings of those
/// sensors between the parsed readings' first and last time (s) only.
pub fn new_rows<R: StoreRead>(tx: &R, files: &[&Readings]) -> Result<Vec<Row>> {
    let mut seen: HashSet<(SensorId, String, UnixSeconds)> = HashSet::new();
    let mut rows: Vec<Row> = Vec::new();
    for readings in files {
        for r in &readings.rows {
            let (Some(s), Some(m)) = (
                readings.sensors.get(r.sensor as usize),
                readings.modalities.get(r.modality as usize),
            ) else {
                continue;
            };
            let name = m.modality.to_string();
            if seen.insert((s.clone(), name.clone(), r.t)) {
                rows.push((s.clone(), name, r.t, r.value));
            }
        }
    }
    if rows.is_empty() {
        return Ok(rows);
    }
    let mut ids: Vec<SensorId> = rows.iter().map(|r| r.0.clone()).collect();
    ids.sort();
    ids.dedup();
    let lo = rows.iter().map(|r| r.2).min().unwrap_or(0);
    let hi = rows.iter().map(|r| r.2).max().unwrap_or(0);
    let stored = tx.readings_of_sensors(&ids, lo..=hi)?;
    let existing: HashSet<(SensorId, String, UnixSeconds)> = stored
        .rows
        .iter()
        .filter_map(|r| {
            Some((
                stored.sensors.get(r.sensor as usize)?.clone(),
                stored.modalities.get(r.modality as usize)?.to_string(),
                r.t,
            ))
        })
        .collect();
    rows.retain(|r| !existing.contains(&(r.0.clone(), r.1.clone(), r.2)));
    Ok(rows)
}

/// After inserting: brings the persisted state up to date (see the module docs), in the
/// caller's transaction.
pub fn after_insert<W: StoreWrite>(tx: &mut W, plan: Plan, settings: &Settings) -> Result<()> {
    let mut carry = None;
    let updated = match plan {
        Plan::Rebuild => None,
        Plan::Update(p, rows) => {
            if rows.is_empty() && is_current(&*tx, &p, settings)? {
                return Ok(());
            }
            if let ConditionState::Fitted(f) = &p.condition {
                let added = rows.iter().filter(|r| r.1 == f.modality).count() as u64;
                carry = Some((p.condition.clone(), added));
            }
            update(tx, *p, &rows, settings)?
        }
    };
    match updated {
        Some(p) => write_blob(tx, Some(&p)),
        None => {
            let p = rebuild_keeping(&*tx, settings, carry)?;
            write_blob(tx, p.as_ref())
        }
    }
}

/// Whether `p` describes the store as it is: same field, same settings, same reading count.
fn is_current<R: StoreRead>(store: &R, p: &Persisted, settings: &Settings) -> Result<bool> {
    let Some((sensors, field)) = field_of(store, settings)? else {
        return Ok(false);
    };
    Ok(p.field_fp == field_fingerprint(&sensors, &field)
        && p.settings_fp == settings_fingerprint(settings)
        && p.first_reading.len() == sensors.len()
        && store.reading_count()? == p.reading_count)
}

/// The persisted state rebuilt from the store, not yet written back (see [`rebuilt_if_stale`]).
pub(crate) struct Rebuilt {
    /// The state (`None`: nothing to build it from, e.g. no readings).
    pub(crate) state: Option<Persisted>,
    /// Its encoding, as [`write_blob`] would store it.
    bytes: Vec<u8>,
    /// The store's reading count it describes.
    reading_count: Option<u64>,
}

/// Outside any transaction: the state rebuilt from the store when the persisted one is
/// missing or does not describe the store (e.g. after the grid settings changed, or a database
/// written before the state existed), else `None`. O(history) then; a few queries otherwise. Written back by [`keep_rebuilt`]
/// in the transaction of the use case that needed it, so a refused use case writes nothing.
pub(crate) fn rebuilt_if_stale<R: StoreRead>(
    store: &R,
    settings: &Settings,
) -> Result<Option<Rebuilt>> {
    let current = match store
        .blob_get(BLOB_KEY)?
        .and_then(|b| Persisted::from_bytes(&b))
    {
        Some(p) => is_current(store, &p, settings)?,
        None => false,
    };
    if current {
        return Ok(None);
    }
    let state = rebuild(store, settings)?;
    let bytes = state.as_ref().map(Persisted::to_bytes).unwrap_or_default();
    let reading_count = state.as_ref().map(|p| p.reading_count);
    Ok(Some(Rebuilt {
        state,
        bytes,
        reading_count,
    }))
}

/// Inside the use case's write transaction: stores a state [`rebuilt_if_stale`] built, unless
/// another process has changed the readings since (then the next scoring rebuilds it).
pub(crate) fn keep_rebuilt<W: StoreWrite>(tx: &mut W, rebuilt: &Rebuilt) -> Result<()> {
    let unchanged = match rebuilt.reading_count {
        Some(n) => tx.reading_count()? == n,
        None => true,
    };
    if unchanged {
        tx.blob_put(BLOB_KEY, &rebuilt.bytes)?;
    }
    Ok(())
}

/// The incremental update; `None` when a rebuild is needed.
fn update<W: StoreWrite>(
    tx: &mut W,
    mut p: Persisted,
    rows: &[Row],
    settings: &Settings,
) -> Result<Option<Persisted>> {
    let Some((sensors, field)) = field_of(&*tx, settings)? else {
        return Ok(None);
    };
    if p.field_fp != field_fingerprint(&sensors, &field)
        || p.settings_fp != settings_fingerprint(settings)
        || p.first_reading.len() != sensors.len()
        || tx.reading_count()? != p.reading_count + rows.len() as u64
        || rows.is_empty()
    {
        return Ok(None);
    }
    let nm = p.modalities.len();
    let index: HashMap<&str, usize> = sensors
        .iter()
        .enumerate()
        .map(|(k, s)| (s.id.as_str(), k))
        .collect();
    let place = places(&field, sensors.len());
    // Per series: its new times and values, in time order.
    let mut by_series: BTreeMap<usize, Vec<(UnixSeconds, f64)>> = BTreeMap::new();
    for (id, modality, t, v) in rows {
        let (Some(&s), Ok(m)) = (index.get(id.as_str()), p.modalities.binary_search(modality))
        else {
            return Ok(None);
        };
        by_series.entry(s * nm + m).or_default().push((*t, *v));
    }
    let mut readings = Vec::with_capacity(rows.len());
    for (&k, points) in &mut by_series {
        points.sort_by_key(|x| x.0);
        let (s, m) = (k / nm, k % nm);
        let (first, last) = (points[0].0, points[points.len() - 1].0);
        let mut add_gap = |g: i64| {
            if g > 0 {
                *p.gaps.entry(g).or_insert(0) += 1;
            }
        };
        for w in points.windows(2) {
            add_gap(w[1].0 - w[0].0);
        }
        p.span[k] = match p.span[k] {
            None => Some((first, last)),
            Some((a, b)) if first > b => {
                add_gap(first - b);
                Some((a, last))
            }
            Some((a, b)) if last < a => {
                add_gap(a - last);
                Some((first, b))
            }
            Some(_) => return Ok(None),
        };
        let (cell, sensor) = place[s];
        readings.extend(points.iter().map(|&(time, value)| Reading {
            cell,
            sensor,
            modality: m,
            time,
            value,
        }));
        p.first_reading[s] = Some(p.first_reading[s].map_or(first, |f| f.min(first)));
        p.last_reading[s] = p.last_reading[s].max(Some(last));
        p.latest = p.latest.max(Some(last));
    }
    let grid = grid_of(&p);
    if grid != p.state.grid() || p.state.add_readings(&readings).is_err() {
        return Ok(None);
    }
    p.state.trim();
    p.reading_count += rows.len() as u64;
    let Some(latest) = p.latest else {
        return Ok(None);
    };
    // The refit cadence: keep the last fit while the class modality's readings added since
    // stay within `condition_refit_growth` of those it was trained on.
    let growth = settings.utility.condition_refit_growth;
    let class_name = condition_modality(settings, &p.modalities);
    let mut previous = None;
    if let ConditionState::Fitted(f) = &mut p.condition
        && class_name.as_deref() == Some(f.modality.as_str())
    {
        let added = rows.iter().filter(|r| r.1 == f.modality).count() as u64;
        f.pending += added;
        if growth > 0.0 && (f.pending as f64) <= growth * (f.trained as f64) {
            return Ok(Some(p));
        }
        previous = f
            .after_latest
            .as_ref()
            .and_then(|f| f.as_ref().ok())
            .or(f.at_latest.as_ref().ok())
            .cloned();
    }
    // Refit the condition model on the class modality's whole history.
    let mut class_error = None;
    let class_readings = std::cell::Cell::new(0u64);
    p.condition = condition_state(
        settings,
        &p.modalities,
        &field,
        |m| {
            let Ok(modality) = Modality::new(&p.modalities[m]) else {
                return vec![OwnedSeries::default(); field.cells().len()];
            };
            match tx.readings_for(Some(&modality), UnixSeconds::MIN..=UnixSeconds::MAX) {
                Ok(batch) => {
                    class_readings.set(batch.rows.len() as u64);
                    let c = all_columns(&sensors, &batch, Some(grid));
                    let Some(m) = c.modalities.iter().position(|x| *x == p.modalities[m]) else {
                        return vec![OwnedSeries::default(); field.cells().len()];
                    };
                    cell_series_of(&field, &c, Some(m))
                        .into_iter()
                        .map(|mut v| v.pop().unwrap_or_default())
                        .collect()
                }
                Err(e) => {
                    class_error = Some(e);
                    Vec::new()
                }
            }
        },
        latest,
        |_| class_readings.get(),
        previous.as_ref(),
    );
    if let Some(e) = class_error {
        return Err(e.into());
    }
    Ok(Some(p))
}

// ---------------------------------------------------------------------------------------
// Scoring

/// The scoring from the persisted state, or `None` when the request or the state does not
/// allow it (see the module docs).
pub(crate) fn fast_scoring<S: Store>(
    project: &Project<S>,
    request: &ScoreRequest,
) -> Result<Option<Scoring>> {
    if request.probabilities.is_some() || request.history != History::default() {
        return Ok(None);
    }
    let Some(p) = project
        .store()
        .blob_get(BLOB_KEY)?
        .and_then(|b| Persisted::from_bytes(&b))
    else {
        return Ok(None);
    };
    fast_scoring_from(project, request, p)
}

/// [`fast_scoring`] from the state `p` (the stored one, or one just rebuilt).
pub(crate) fn fast_scoring_from<S: Store>(
    project: &Project<S>,
    request: &ScoreRequest,
    p: Persisted,
) -> Result<Option<Scoring>> {
    if request.probabilities.is_some() || request.history != History::default() {
        return Ok(None);
    }
    let store = project.store();
    let settings = project.settings();
    let Some(latest) = p.latest else {
        return Ok(None);
    };
    let t = request.at.unwrap_or(latest);
    if t < latest || p.settings_fp != settings_fingerprint(settings) {
        return Ok(None);
    }
    let (sensors, field) = project.field()?;
    let per_cell_ok = field.cells().iter().enumerate().all(|(c, cell)| {
        c < p.state.n_cells() && p.state.last_collected(c).len() == cell.sensors.len()
    });
    if p.field_fp != field_fingerprint(&sensors, &field)
        || p.first_reading.len() != sensors.len()
        || p.state.n_cells() != field.cells().len()
        || !per_cell_ok
        || p.state.neighbours() != neighbour_lists(&field).as_slice()
        || store.reading_count()? != p.reading_count
    {
        return Ok(None);
    }
    let config = settings.utility.to_core(&p.modalities)?;
    // The neighbour-relative anomaly needs the neighbours' history: the full path.
    if config.window != HistoryWindow::All
        || config.anomaly_reference != gleaner_utility::AnomalyReference::OwnHistory
    {
        return Ok(None);
    }
    let mut warnings = Vec::new();
    let mut state = p.state;
    let condition = match &p.condition {
        ConditionState::NoModality => {
            warnings.push(NO_MODALITY.to_string());
            None
        }
        ConditionState::Unusable => return Ok(None),
        ConditionState::Fitted(f) => {
            let Ok(m) = p.modalities.binary_search(&f.modality) else {
                return Ok(None);
            };
            // An earlier fit is one the refit cadence kept (see `update`).
            if f.fitted_to > latest {
                return Ok(None);
            }
            // At a later t the full path also trains on the labels at the newest reading.
            let fit = match &f.after_latest {
                Some(fit) if t > f.fitted_to => fit,
                _ => &f.at_latest,
            };
            match fit {
                Ok(model) => {
                    let recent = state.recent_series(m);
                    let cells: Vec<Series<'_>> =
                        recent.iter().map(OwnedSeries::as_series).collect();
                    let probabilities = model.predict_proba(&cells, &neighbour_lists(&field), t);
                    Some(condition_output(f.modality.clone(), model, probabilities))
                }
                Err(warning) => {
                    warnings.push(warning.clone());
                    None
                }
            }
        }
    };
    // A sensor's last collection: the later of its recorded collection (at or before t) and
    // its latest reading (all readings are at or before t).
    let index: HashMap<&str, usize> = sensors
        .iter()
        .enumerate()
        .map(|(k, s)| (s.id.as_str(), k))
        .collect();
    let mut last_collected = p.last_reading.clone();
    let t_max = request.at.unwrap_or(UnixSeconds::MAX);
    for (id, at) in store.sensor_last_collected()? {
        if let Some(&s) = index.get(id.as_str())
            && at <= t_max
        {
            last_collected[s] = last_collected[s].max(Some(at));
        }
    }
    for (c, cell) in field.cells().iter().enumerate() {
        let last: Vec<Option<UnixSeconds>> =
            cell.sensors.iter().map(|&s| last_collected[s]).collect();
        state
            .set_last_collected(c, &last)
            .map_err(|e| AppError::core("scoring", e))?;
    }
    let probabilities = condition
        .as_ref()
        .map_or_else(Vec::new, |c| c.probabilities.clone());
    let terms = state
        .score(t, &config, &probabilities)
        .map_err(|e| AppError::core("scoring", e))?;
    let nm = p.modalities.len();
    let series = (0..field.cells().len())
        .map(|c| (0..nm).map(|m| state.cell_series(c, m)).collect())
        .collect();
    let u = &settings.utility;
    Ok(Some(Scoring {
        t,
        knowledge: Knowledge {
            sensors,
            field,
            modalities: p.modalities,
            series,
            last_collected,
            first_reading: p.first_reading,
            latest: Some(latest),
        },
        terms,
        condition,
        weights: [u.alpha, u.beta, u.gamma, u.delta],
        anomaly_form: config.anomaly_form.label(),
        warnings,
        incremental: Some(state),
    }))
}

/// What planning without scores needs (the field, the sensors, their last collections and
/// first readings, the newest reading): from the persisted state when it describes the store
/// (see [`fast_scoring`]), else from the history ([`knowledge`](crate::knowledge())). From
/// the state, the series hold only the retained recent points: callers must not use them.
pub fn collection_knowledge<S: Store>(
    project: &Project<S>,
    at: Option<UnixSeconds>,
    history: History,
) -> Result<Knowledge> {
    if history == History::default() {
        let request = ScoreRequest {
            at,
            dry_run: true,
            ..ScoreRequest::default()
        };
        if let Some(scoring) = fast_scoring(project, &request)? {
            return Ok(scoring.knowledge);
        }
    }
    crate::knowledge(project, at, history)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn sample() -> Persisted {
        let grid = TimeGrid {
            origin: 86_400,
            step_s: 86_400,
        };
        let mut state =
            IncrementalState::new(&[1, 2], &[vec![1], vec![0]], 2, grid).expect("valid state");
        state.set_retention(Some(RETENTION_STEPS * 86_400));
        for d in 1..40i64 {
            for (cell, sensor) in [(0, 0), (1, 0), (1, 1)] {
                for modality in 0..2 {
                    let value =
                        0.2 + 0.01 * ((d * 7 + cell as i64 * 3 + modality as i64) % 11) as f64;
                    state
                        .add_reading(Reading {
                            cell,
                            sensor,
                            modality,
                            time: d * 86_400,
                            value,
                        })
                        .expect("valid reading");
                }
            }
        }
        state.trim();
        Persisted {
            field_fp: 1,
            settings_fp: 2,
            reading_count: 234,
            modalities: vec!["t@30cm".into(), "vw@30cm".into()],
            first_reading: vec![Some(86_400); 3],
            last_reading: vec![Some(39 * 86_400); 3],
            span: vec![Some((86_400, 39 * 86_400)); 6],
            gaps: BTreeMap::from([(86_400, 228)]),
            latest: Some(39 * 86_400),
            condition: ConditionState::Fitted(ConditionFit {
                modality: "vw@30cm".into(),
                fitted_to: 39 * 86_400,
                trained: 78,
                pending: 0,
                at_latest: Err("no condition model (too little data); U = 0".into()),
                after_latest: None,
            }),
            state,
        }
    }

    #[test]
    fn blob_round_trip_and_corruption() {
        let p = sample();
        let bytes = p.to_bytes();
        let back = Persisted::from_bytes(&bytes).expect("decodes");
        assert_eq!(back.to_bytes(), bytes, "deterministic round trip");
        assert_eq!(back.state, p.state);
        assert_eq!(median_gap(&back.gaps), 86_400);
        assert_eq!(grid_of(&back), p.state.grid());
        for n in 0..bytes.len() {
            assert!(Persisted::from_bytes(&bytes[..n]).is_none(), "prefix {n}");
        }
        assert!(
            Persisted::from_bytes(&[]).is_none(),
            "the empty 'no state' blob"
        );
        for k in 0..bytes.len() {
            let mut b = bytes.clone();
            b[k] ^= 0x5a;
            let _ = Persisted::from_bytes(&b);
        }
    }

    proptest! {
        #[test]
        fn arbitrary_blobs_never_panic(body in proptest::collection::vec(any::<u8>(), 0..400)) {
            let mut bytes = MAGIC.to_vec();
            bytes.extend_from_slice(&VERSION.to_le_bytes());
            bytes.extend_from_slice(&body);
            let _ = Persisted::from_bytes(&bytes);
            let _ = Persisted::from_bytes(&body);
        }
    }

    #[test]
    fn median_gap_is_the_upper_median() {
        // As `knowledge`: the element at index len/2 of the sorted gaps.
        let gaps = BTreeMap::from([(10, 1), (20, 1), (30, 1), (40, 1)]);
        assert_eq!(median_gap(&gaps), 30);
        assert_eq!(median_gap(&BTreeMap::from([(5, 3), (7, 1)])), 5);
        assert_eq!(median_gap(&BTreeMap::new()), 86_400);
    }
}
