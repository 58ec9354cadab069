//! The columnar batch that every reader produces, and the options and report around it.

use std::collections::{HashMap, HashSet};

use gleaner_field::{Modality, SensorId, UnixSeconds};

use crate::Problem;

/// What to do with a bad row.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum OnError {
    /// Stop at the first bad row; nothing is ingested (the default).
    #[default]
    Fail,
    /// Skip bad rows, count them and report them.
    Skip,
}

/// Settings shared by the readers.
#[derive(Debug, Clone, Default)]
pub struct IngestOptions {
    /// Bad-row policy.
    pub on_error: OnError,
    /// Sensors the project knows; a reading for any other sensor is a bad row. `None` accepts
    /// every sensor id.
    pub known_sensors: Option<HashSet<String>>,
    /// Plausible value ranges (defaults by unit, see [`crate::limits::default_range`]); a
    /// value outside its modality's range is a bad row.
    pub value_limits: crate::limits::ValueLimits,
}

/// A modality with the unit the file gave for it, if any.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ModalityInfo {
    /// The modality, e.g. `vw@30cm`.
    pub modality: Modality,
    /// Its unit, e.g. `m3/m3`.
    pub unit: Option<String>,
}

/// One reading: indices into [`Readings::sensors`] and [`Readings::modalities`], a time in
/// seconds since the epoch (UTC), the value in the modality's unit, and the source line.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Row {
    /// Index into [`Readings::sensors`].
    pub sensor: u32,
    /// Index into [`Readings::modalities`].
    pub modality: u32,
    /// Time, seconds since 1970-01-01T00:00:00Z.
    pub t: UnixSeconds,
    /// Value, in the modality's unit.
    pub value: f64,
    /// 1-based line in the source file (for error messages).
    pub line: u32,
}

/// A batch of readings. Invariant: every row's indices are in range; after
/// `dedup` no two rows share (sensor, modality, t).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Readings {
    /// Sensor table.
    pub sensors: Vec<SensorId>,
    /// Modality table.
    pub modalities: Vec<ModalityInfo>,
    /// The readings.
    pub rows: Vec<Row>,
}

/// A skipped row, kept for the report.
#[derive(Debug, Clone, PartialEq)]
pub struct SkippedRow {
    /// 1-based line.
    pub line: u64,
    /// Why, formatted like the error it would have been.
    pub reason: String,
}

/// What a reader did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct IngestReport {
    /// Data rows read (excluding the header).
    pub rows_read: u64,
    /// Readings produced.
    pub readings: u64,
    /// Values marked missing (`NA` or empty), which produce no reading.
    pub missing: u64,
    /// Identical duplicate readings dropped.
    pub duplicates: u64,
    /// Rows skipped under [`OnError::Skip`].
    pub skipped: u64,
    /// The first skipped rows (at most [`IngestReport::MAX_KEPT`]).
    pub skipped_rows: Vec<SkippedRow>,
}

impl IngestReport {
    /// How many skipped rows are kept in [`IngestReport::skipped_rows`].
    pub const MAX_KEPT: usize = 20;

    pub(crate) fn skip(&mut self, line: u64, reason: String) {
        self.skipped += 1;
        if self.skipped_rows.len() < Self::MAX_KEPT {
            self.skipped_rows.push(SkippedRow { line, reason });
        }
    }

    /// Adds another report's counts to this one.
    pub fn merge(&mut self, other: &IngestReport) {
        self.rows_read += other.rows_read;
        self.readings += other.readings;
        self.missing += other.missing;
        self.duplicates += other.duplicates;
        for s in &other.skipped_rows {
            if self.skipped_rows.len() < Self::MAX_KEPT {
                self.skipped_rows.push(s.clone());
            }
        }
        self.skipped += other.skipped;
    }
}

/// Whether the options allow readings of sensor `id`.
pub(crate) fn known(options: &IngestOptions, id: &str) -> bool {
    options
        .known_sensors
        .as_ref()
        .is_none_or(|k| k.contains(id))
}

/// Interns sensors and modalities while a reader runs.
#[derive(Default)]
pub(crate) struct Interner {
    sensors: HashMap<Box<str>, u32>,
    /// The last sensor looked up by [`Interner::known_sensor`]: rows usually come grouped by
    /// sensor, so this skips the hash lookup.
    last: Option<(Box<str>, u32)>,
    modalities: HashMap<Modality, u32>,
    /// Per modality index: its plausible value range and what the range is for, computed on
    /// first use (reset when the modality's unit becomes known).
    ranges: Vec<Option<(f64, f64, String)>>,
    pub(crate) out: Readings,
}

impl Interner {
    pub(crate) fn sensor(&mut self, id: &str) -> Option<u32> {
        if let Some(&k) = self.sensors.get(id) {
            return Some(k);
        }
        let sid = SensorId::new(id).ok()?;
        let k = self.out.sensors.len() as u32;
        self.out.sensors.push(sid);
        self.sensors.insert(id.into(), k);
        Some(k)
    }

    /// Interns a sensor the options allow: [`Problem::UnknownSensor`] for one the project does
    /// not know, [`Problem::BadSensorId`] for an invalid id.
    pub(crate) fn known_sensor(
        &mut self,
        id: &str,
        options: &IngestOptions,
    ) -> Result<u32, Problem> {
        if let Some((last, k)) = &self.last
            && &**last == id
        {
            return Ok(*k);
        }
        if !known(options, id) {
            return Err(Problem::UnknownSensor);
        }
        let k = self.sensor(id).ok_or(Problem::BadSensorId)?;
        self.last = Some((id.into(), k));
        Ok(k)
    }

    /// Interns a modality; `Err(expected unit)` when the unit differs from an earlier one.
    pub(crate) fn modality(&mut self, m: Modality, unit: Option<&str>) -> Result<u32, String> {
        if let Some(&k) = self.modalities.get(&m) {
            let info = &mut self.out.modalities[k as usize];
            match (&info.unit, unit) {
                (Some(a), Some(b)) if a != b => return Err(a.clone()),
                (None, Some(b)) => {
                    info.unit = Some(b.to_string());
                    if let Some(r) = self.ranges.get_mut(k as usize) {
                        *r = None;
                    }
                }
                _ => {}
            }
            return Ok(k);
        }
        let k = self.out.modalities.len() as u32;
        self.out.modalities.push(ModalityInfo {
            modality: m.clone(),
            unit: unit.map(str::to_string),
        });
        self.modalities.insert(m, k);
        Ok(k)
    }

    /// Checks a value of modality `k` against its plausible range.
    pub(crate) fn check_value(
        &mut self,
        k: u32,
        value: f64,
        limits: &crate::limits::ValueLimits,
    ) -> Result<(), Problem> {
        let i = k as usize;
        if self.ranges.len() <= i {
            self.ranges.resize(i + 1, None);
        }
        let (lo, hi, _) = self.ranges[i].get_or_insert_with(|| {
            let info = &self.out.modalities[i];
            limits.range(info.modality.quantity(), info.unit.as_deref())
        });
        if (*lo..=*hi).contains(&value) {
            return Ok(());
        }
        let (min, max, unit) = self.ranges[i].clone().unwrap_or_default();
        Err(Problem::OutOfRange { unit, min, max })
    }
}

impl Readings {
    /// Sorts rows by (sensor, modality, t, line) and removes duplicates: identical values are
    /// dropped (counted in `duplicates`); a conflicting value is returned as
    /// `Err((kept_row, conflicting_row))` under [`OnError::Fail`] and skipped (the earlier line
    /// kept) under [`OnError::Skip`].
    pub(crate) fn dedup(
        &mut self,
        on_error: OnError,
        report: &mut IngestReport,
    ) -> Result<(), (Row, Row)> {
        self.rows
            .sort_unstable_by_key(|r| (r.sensor, r.modality, r.t, r.line));
        let mut out: Vec<Row> = Vec::with_capacity(self.rows.len());
        for r in self.rows.drain(..) {
            if let Some(last) = out.last()
                && (last.sensor, last.modality, last.t) == (r.sensor, r.modality, r.t)
            {
                if last.value.to_bits() == r.value.to_bits() {
                    report.duplicates += 1;
                    continue;
                }
                match on_error {
                    OnError::Fail => return Err((*last, r)),
                    OnError::Skip => {
                        report.skip(
                            u64::from(r.line),
                            format!(
                                "conflicting duplicate of line {} ({} vs {})",
                                last.line, last.value, r.value
                            ),
                        );
                        continue;
                    }
                }
            }
            out.push(r);
        }
        self.rows = out;
        Ok(())
    }

    /// Appends `other`, re-indexing its sensors and modalities into this batch's tables.
    /// Rows from different files may then duplicate each other; the store resolves that.
    pub fn append(&mut self, other: Readings) {
        let mut sensors: HashMap<SensorId, u32> = self
            .sensors
            .iter()
            .cloned()
            .enumerate()
            .map(|(k, s)| (s, k as u32))
            .collect();
        let smap: Vec<u32> = other
            .sensors
            .into_iter()
            .map(|s| {
                let n = self.sensors.len() as u32;
                *sensors.entry(s.clone()).or_insert_with(|| {
                    self.sensors.push(s);
                    n
                })
            })
            .collect();
        let mmap: Vec<u32> = other
            .modalities
            .into_iter()
            .map(|m| {
                match self
                    .modalities
                    .iter()
                    .position(|x| x.modality == m.modality)
                {
                    Some(k) => {
                        if self.modalities[k].unit.is_none() {
                            self.modalities[k].unit = m.unit;
                        }
                        k as u32
                    }
                    None => {
                        self.modalities.push(m);
                        (self.modalities.len() - 1) as u32
                    }
                }
            })
            .collect();
        self.rows.extend(other.rows.into_iter().map(|r| Row {
            sensor: smap[r.sensor as usize],
            modality: mmap[r.modality as usize],
            ..r
        }));
    }
}
