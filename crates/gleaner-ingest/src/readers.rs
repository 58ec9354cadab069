//! The file readers.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use gleaner_field::{
    LatLon, LocalPoint, Modality, Sensor, SensorId, TransverseMercator, UnixSeconds,
};

use crate::limits::{MAX_YEAR, MIN_YEAR, ValueLimits, plausible_time};
use crate::readings::{Interner, Row, known};
use crate::time::{format_rfc3339, parse_clock, parse_date, parse_timestamp, parse_us_date};
use crate::{IngestError, IngestOptions, IngestReport, OnError, Problem, Readings, default_unit};

/// Why `-` is refused as a file name (unless a file of that name exists).
pub const STDIN_NOT_READ: &str = "standard input (`-`) is not read: save the data to a file \
                                  and give its path (a file is read twice: to detect its \
                                  format, then to parse it)";

/// Whether `path` is `-` meaning standard input: no file of that name exists.
pub fn is_stdin(path: &Path) -> bool {
    path == Path::new("-") && !path.exists()
}

/// Reads the whole file, strips a UTF-8 byte-order mark. Only regular files are read: a pipe,
/// FIFO or device is refused before it is opened (opening a FIFO blocks until a writer comes,
/// and a pipe can be read once only, while detection and parsing read a file twice).
pub(crate) fn read_file(path: &Path) -> Result<Vec<u8>, IngestError> {
    if is_stdin(path) {
        return Err(IngestError::Options {
            path: path.to_path_buf(),
            message: STDIN_NOT_READ.into(),
        });
    }
    let meta = std::fs::metadata(path).map_err(|source| IngestError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    if !meta.is_file() {
        return Err(IngestError::Options {
            path: path.to_path_buf(),
            message: "not a regular file: give the data as a file (pipes, FIFOs and devices \
                      are not read)"
                .into(),
        });
    }
    let mut bytes = std::fs::read(path).map_err(|source| IngestError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    if bytes.starts_with(&[0xEF, 0xBB, 0xBF]) {
        bytes.drain(..3);
    }
    Ok(bytes)
}

/// A CSV/TSV table: header and a record iterator with 1-based line numbers.
///
/// Line numbers are counted here from the record's byte offset, with `\r\n`, `\n` and a lone
/// `\r` each ending one line: the `csv` crate's own count falls one short per CRLF line.
pub(crate) struct Table<'a> {
    path: PathBuf,
    pub(crate) header: Vec<String>,
    reader: csv::Reader<&'a [u8]>,
    pub(crate) record: csv::ByteRecord,
    lines: LineCounter<'a>,
}

/// Counts physical lines up to a byte offset, incrementally (offsets must not decrease).
struct LineCounter<'a> {
    bytes: &'a [u8],
    /// Bytes before this offset have been counted.
    scanned: usize,
    /// Line breaks before `scanned`.
    breaks: u64,
    /// The byte before `scanned` is `\r` (so a `\n` there completes a CRLF already counted).
    after_cr: bool,
}

impl<'a> LineCounter<'a> {
    fn new(bytes: &'a [u8]) -> Self {
        Self {
            bytes,
            scanned: 0,
            breaks: 0,
            after_cr: false,
        }
    }

    /// The 1-based line on which a record starting at byte `offset` begins (line terminators
    /// at `offset` itself, which the record reader may not have consumed yet, are skipped).
    fn line_at(&mut self, offset: usize) -> u64 {
        let mut start = offset.min(self.bytes.len());
        while start < self.bytes.len() && matches!(self.bytes[start], b'\r' | b'\n') {
            start += 1;
        }
        if start < self.scanned {
            // Offsets never go back; tolerate it by recounting from the beginning.
            *self = Self::new(self.bytes);
        }
        for &b in &self.bytes[self.scanned..start] {
            match b {
                b'\r' => self.breaks += 1,
                b'\n' if !self.after_cr => self.breaks += 1,
                _ => {}
            }
            self.after_cr = b == b'\r';
        }
        self.scanned = start;
        self.breaks + 1
    }
}

impl<'a> Table<'a> {
    pub(crate) fn open(path: &Path, bytes: &'a [u8], delimiter: u8) -> Result<Self, IngestError> {
        let mut reader = csv::ReaderBuilder::new()
            .delimiter(delimiter)
            .has_headers(false)
            .flexible(true)
            .from_reader(bytes);
        let mut record = csv::ByteRecord::new();
        let got = reader
            .read_byte_record(&mut record)
            .map_err(|e| csv_error(path, e))?;
        if !got || (record.len() == 1 && record[0].is_empty()) {
            return Err(IngestError::Empty {
                path: path.to_path_buf(),
            });
        }
        let header: Vec<String> = record
            .iter()
            .map(|f| String::from_utf8_lossy(f).trim().to_string())
            .collect();
        for (k, name) in header.iter().enumerate() {
            if name.is_empty() {
                continue;
            }
            if let Some(first) = header[..k]
                .iter()
                .position(|h| h.eq_ignore_ascii_case(name))
            {
                return Err(IngestError::Field {
                    path: path.to_path_buf(),
                    line: 1,
                    column: format!("#{}", k + 1),
                    value: name.clone(),
                    problem: Problem::DuplicateColumn {
                        first_column: first + 1,
                    },
                });
            }
        }
        Ok(Self {
            path: path.to_path_buf(),
            header,
            reader,
            record,
            lines: LineCounter::new(bytes),
        })
    }

    /// Index of the first column whose name matches one of `names` (case-insensitive).
    pub(crate) fn find(&self, names: &[&str]) -> Option<usize> {
        names
            .iter()
            .find_map(|n| self.header.iter().position(|h| h.eq_ignore_ascii_case(n)))
    }

    pub(crate) fn require(&self, names: &[&str]) -> Result<usize, IngestError> {
        self.find(names).ok_or_else(|| IngestError::MissingColumn {
            path: self.path.clone(),
            column: names.join("|"),
            found: self.header.join(", "),
        })
    }

    /// Advances to the next non-blank record; returns its line number.
    pub(crate) fn next(&mut self) -> Result<Option<u64>, IngestError> {
        loop {
            let got = self
                .reader
                .read_byte_record(&mut self.record)
                .map_err(|e| csv_error(&self.path, e))?;
            if !got {
                return Ok(None);
            }
            if self.record.len() == 1 && self.record[0].iter().all(u8::is_ascii_whitespace) {
                continue;
            }
            let offset = self.record.position().map_or(0, |p| p.byte());
            return Ok(Some(
                self.lines
                    .line_at(usize::try_from(offset).unwrap_or(usize::MAX)),
            ));
        }
    }

    /// Advances to the next data row with as many fields as the header, counting every row
    /// read; a row with another number of fields goes to the policy (error or counted skip).
    pub(crate) fn next_row(
        &mut self,
        policy: &Policy<'_>,
        report: &mut IngestReport,
    ) -> Result<Option<u64>, IngestError> {
        while let Some(line) = self.next()? {
            report.rows_read += 1;
            if self.record.len() == self.header.len() {
                return Ok(Some(line));
            }
            let found = self.record.len().to_string();
            policy.bad(report, line, "*", &found, Problem::FieldCount)?;
        }
        Ok(None)
    }

    pub(crate) fn field(&self, k: usize) -> Result<&str, Problem> {
        std::str::from_utf8(self.record.get(k).unwrap_or_default())
            .map(str::trim)
            .map_err(|_| Problem::NotUtf8)
    }

    /// Field `k` as text, or (when it is not UTF-8) its bytes shown lossily for the error.
    pub(crate) fn text(&self, k: usize) -> Result<&str, String> {
        let raw = self.record.get(k).unwrap_or_default();
        std::str::from_utf8(raw)
            .map(str::trim)
            .map_err(|_| String::from_utf8_lossy(raw).into_owned())
    }
}

fn csv_error(path: &Path, e: csv::Error) -> IngestError {
    match e.into_kind() {
        csv::ErrorKind::Io(source) => IngestError::Io {
            path: path.to_path_buf(),
            source,
        },
        other => IngestError::Options {
            path: path.to_path_buf(),
            message: format!("malformed CSV: {other:?}"),
        },
    }
}

/// Applies the bad-row policy: an error under `Fail`, a counted skip under `Skip`.
pub(crate) struct Policy<'p> {
    pub(crate) path: &'p Path,
    pub(crate) on_error: OnError,
    /// Plausible value ranges.
    pub(crate) limits: &'p ValueLimits,
}

/// The built-in ranges, for readers without [`IngestOptions`].
static DEFAULT_LIMITS: ValueLimits = ValueLimits {
    overrides: std::collections::BTreeMap::new(),
};

impl<'p> Policy<'p> {
    pub(crate) fn new(path: &'p Path, on_error: OnError) -> Self {
        Self {
            path,
            on_error,
            limits: &DEFAULT_LIMITS,
        }
    }

    /// The policy of a readings reader: its bad-row policy and value limits.
    pub(crate) fn for_readings(path: &'p Path, options: &'p IngestOptions) -> Self {
        Self {
            path,
            on_error: options.on_error,
            limits: &options.value_limits,
        }
    }

    /// Checks a reading's time and value: `Ok(false)` when the row was skipped.
    pub(crate) fn check_reading(
        &self,
        interner: &mut Interner,
        report: &mut IngestReport,
        (line, column): (u64, &str),
        modality: u32,
        value: (f64, &str),
    ) -> Result<bool, IngestError> {
        match interner.check_value(modality, value.0, self.limits) {
            Ok(()) => Ok(true),
            Err(p) => self.bad(report, line, column, value.1, p).map(|()| false),
        }
    }

    /// Checks a row's time is plausible: `Ok(false)` when the row was skipped.
    pub(crate) fn check_time(
        &self,
        report: &mut IngestReport,
        (line, column): (u64, &str),
        t: UnixSeconds,
        text: &str,
    ) -> Result<bool, IngestError> {
        if plausible_time(t) {
            return Ok(true);
        }
        let problem = Problem::ImplausibleTime {
            min_year: MIN_YEAR,
            max_year: MAX_YEAR,
        };
        self.bad(report, line, column, text, problem)
            .map(|()| false)
    }

    pub(crate) fn bad(
        &self,
        report: &mut IngestReport,
        line: u64,
        column: &str,
        value: &str,
        problem: Problem,
    ) -> Result<(), IngestError> {
        let err = IngestError::Field {
            path: self.path.to_path_buf(),
            line,
            column: column.to_string(),
            value: value.to_string(),
            problem,
        };
        match self.on_error {
            OnError::Fail => Err(err),
            OnError::Skip => {
                report.skip(line, err.to_string());
                Ok(())
            }
        }
    }

    /// Pushes the values of one row of a file with a column per (sensor, modality): `cells` gives
    /// each value column's index, sensor, modality and text (or why it cannot be read). A missing
    /// value is counted; an unreadable one goes to the bad-row policy.
    pub(crate) fn push_values<'a>(
        &self,
        interner: &mut Interner,
        report: &mut IngestReport,
        names: &[String],
        (line, t): (u64, UnixSeconds),
        cells: impl IntoIterator<Item = (usize, u32, u32, Result<&'a str, String>)>,
    ) -> Result<(), IngestError> {
        for (c, sensor, modality, text) in cells {
            let text = match text {
                Ok(text) => text,
                Err(lossy) => {
                    self.bad(report, line, &names[c], &lossy, Problem::NotUtf8)?;
                    continue;
                }
            };
            if is_missing(text) {
                report.missing += 1;
                continue;
            }
            match parse_value(text) {
                Ok(value)
                    if !self.check_reading(
                        interner,
                        report,
                        (line, &names[c]),
                        modality,
                        (value, text),
                    )? => {}
                Ok(value) => interner.out.rows.push(Row {
                    sensor,
                    modality,
                    t,
                    value,
                    line: line as u32,
                }),
                Err(p) => self.bad(report, line, &names[c], text, p)?,
            }
        }
        Ok(())
    }
}

fn is_missing(s: &str) -> bool {
    s.is_empty() || s.eq_ignore_ascii_case("na")
}

fn parse_value(s: &str) -> Result<f64, Problem> {
    let v: f64 = s.parse().map_err(|_| Problem::NotANumber)?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(Problem::NotFinite)
    }
}

/// Sorts, removes duplicates, and turns a conflicting duplicate into an error; the readings
/// with the finished report.
pub(crate) fn finish(
    mut interner: Interner,
    policy: &Policy<'_>,
    mut report: IngestReport,
    value_column: &str,
) -> Result<(Readings, IngestReport), IngestError> {
    let mut out = std::mem::take(&mut interner.out);
    if let Err((first, second)) = out.dedup(policy.on_error, &mut report) {
        return Err(IngestError::Field {
            path: policy.path.to_path_buf(),
            line: u64::from(second.line),
            column: value_column.to_string(),
            value: second.value.to_string(),
            problem: Problem::ConflictingDuplicate {
                first_line: u64::from(first.line),
                first_value: first.value.to_string(),
            },
        });
    }
    report.readings = out.rows.len() as u64;
    Ok((out, report))
}

/// Reads gleaner's generic long readings CSV: a header with `sensor_id`, `timestamp`,
/// `modality`, `value` and optionally `unit` (any order, case-insensitive; `sensor` and `time`
/// are accepted aliases). Timestamps are RFC 3339 (offsets honoured, no offset = UTC) or dates
/// (`YYYY-MM-DD`, midnight UTC). Values `NA` or empty are missing and produce no reading; `NaN`
/// and infinities are errors.
pub fn read_long_csv(
    path: &Path,
    options: &IngestOptions,
) -> Result<(Readings, IngestReport), IngestError> {
    let bytes = read_file(path)?;
    let mut table = Table::open(path, &bytes, b',')?;
    let c_sensor = table.require(&["sensor_id", "sensor"])?;
    let c_time = table.require(&["timestamp", "time"])?;
    let c_mod = table.require(&["modality"])?;
    let c_value = table.require(&["value"])?;
    let c_unit = table.find(&["unit"]);
    let names = table.header.clone();
    let policy = Policy::for_readings(path, options);
    let mut report = IngestReport::default();
    let mut interner = Interner::default();
    // Rows are usually grouped by sensor and modality: cache the last lookups.
    let mut modality_cache: HashMap<(String, String), u32> = HashMap::new();
    while let Some(line) = table.next_row(&policy, &mut report)? {
        macro_rules! field {
            ($k:expr) => {
                match table.text($k) {
                    Ok(s) => s,
                    Err(lossy) => {
                        policy.bad(&mut report, line, &names[$k], &lossy, Problem::NotUtf8)?;
                        continue;
                    }
                }
            };
        }
        let value_s = field!(c_value);
        if is_missing(value_s) {
            report.missing += 1;
            continue;
        }
        let sensor_s = field!(c_sensor);
        let sensor = match interner.known_sensor(sensor_s, options) {
            Ok(k) => k,
            Err(p) => {
                policy.bad(&mut report, line, &names[c_sensor], sensor_s, p)?;
                continue;
            }
        };
        let time_s = field!(c_time);
        let Some(t) = parse_timestamp(time_s) else {
            policy.bad(
                &mut report,
                line,
                &names[c_time],
                time_s,
                Problem::BadTimestamp,
            )?;
            continue;
        };
        if !policy.check_time(&mut report, (line, &names[c_time]), t, time_s)? {
            continue;
        }
        let mod_s = field!(c_mod);
        let unit_s = match c_unit {
            Some(c) => field!(c),
            None => "",
        };
        let modality = match modality_cache.get(&(mod_s.to_string(), unit_s.to_string())) {
            Some(&k) => k,
            None => {
                let Ok(m) = Modality::new(mod_s) else {
                    policy.bad(
                        &mut report,
                        line,
                        &names[c_mod],
                        mod_s,
                        Problem::BadModality,
                    )?;
                    continue;
                };
                let unit = (!unit_s.is_empty()).then_some(unit_s);
                match interner.modality(m, unit) {
                    Ok(k) => {
                        modality_cache.insert((mod_s.to_string(), unit_s.to_string()), k);
                        k
                    }
                    Err(expected) => {
                        let col = c_unit.map_or("unit", |c| names[c].as_str());
                        policy.bad(
                            &mut report,
                            line,
                            col,
                            unit_s,
                            Problem::UnitMismatch { expected },
                        )?;
                        continue;
                    }
                }
            }
        };
        let value = match parse_value(value_s) {
            Ok(v) => v,
            Err(p) => {
                policy.bad(&mut report, line, &names[c_value], value_s, p)?;
                continue;
            }
        };
        if !policy.check_reading(
            &mut interner,
            &mut report,
            (line, &names[c_value]),
            modality,
            (value, value_s),
        )? {
            continue;
        }
        interner.out.rows.push(Row {
            sensor,
            modality,
            t,
            value,
            line: line as u32,
        });
    }
    finish(interner, &policy, report, &names[c_value])
}

/// Settings for [`read_wide_csv`].
#[derive(Debug, Clone)]
pub struct WideOptions {
    /// The modality every sensor column holds, e.g. `vw@30cm`.
    pub modality: Modality,
    /// Its unit; defaults to [`default_unit`] of the quantity.
    pub unit: Option<String>,
    /// Field delimiter (default `,`).
    pub delimiter: u8,
    /// Offset of the file's clock from UTC, seconds (e.g. −28 800 for PST); default 0.
    pub utc_offset_s: i64,
}

impl WideOptions {
    /// Comma-separated, UTC, unit from the quantity.
    pub fn new(modality: Modality) -> Self {
        Self {
            modality,
            unit: None,
            delimiter: b',',
            utc_offset_s: 0,
        }
    }
}

/// Reads a wide table: time columns, then one column per sensor whose header is the sensor id.
/// Time is either one `timestamp`/`datetime` column (RFC 3339 or date) or a `date` column
/// (`YYYY-MM-DD` or `MM/DD/YYYY`) with an optional `time` column (`H:MM[:SS]`), read in the
/// file's clock ([`WideOptions::utc_offset_s`]). A sensor column the project does not know is
/// an error on line 1 (skipped as a whole under [`OnError::Skip`]).
pub fn read_wide_csv(
    path: &Path,
    wide: &WideOptions,
    options: &IngestOptions,
) -> Result<(Readings, IngestReport), IngestError> {
    let bytes = read_file(path)?;
    let mut table = Table::open(path, &bytes, wide.delimiter)?;
    let c_stamp = table.find(&["timestamp", "datetime"]);
    let (c_date, c_clock) = match c_stamp {
        Some(_) => (None, None),
        None => (
            Some(table.require(&["timestamp", "datetime", "date"])?),
            table.find(&["time"]),
        ),
    };
    let names = table.header.clone();
    let policy = Policy::for_readings(path, options);
    let mut report = IngestReport::default();
    let mut interner = Interner::default();
    let unit = wide
        .unit
        .clone()
        .or_else(|| default_unit(wide.modality.quantity()).map(str::to_string));
    let modality = interner
        .modality(wide.modality.clone(), unit.as_deref())
        .map_err(|_| IngestError::Options {
            path: path.to_path_buf(),
            message: "inconsistent unit".into(),
        })?;
    let time_cols = [c_stamp, c_date, c_clock];
    let mut columns: Vec<(usize, u32)> = Vec::new();
    for (k, name) in names.iter().enumerate() {
        if time_cols.contains(&Some(k)) {
            continue;
        }
        if !known(options, name) {
            policy.bad(&mut report, 1, name, name, Problem::UnknownSensor)?;
            continue;
        }
        match interner.sensor(name) {
            Some(s) => columns.push((k, s)),
            None => policy.bad(&mut report, 1, name, name, Problem::BadSensorId)?,
        }
    }
    while let Some(line) = table.next_row(&policy, &mut report)? {
        let t = if let Some(c) = c_stamp {
            let s = match table.text(c) {
                Ok(s) => s,
                Err(lossy) => {
                    policy.bad(&mut report, line, &names[c], &lossy, Problem::NotUtf8)?;
                    continue;
                }
            };
            match parse_timestamp(s) {
                Some(t) => t,
                None => {
                    policy.bad(&mut report, line, &names[c], s, Problem::BadTimestamp)?;
                    continue;
                }
            }
        } else {
            let cd = c_date.unwrap_or(0);
            let ds = match table.text(cd) {
                Ok(s) => s,
                Err(lossy) => {
                    policy.bad(&mut report, line, &names[cd], &lossy, Problem::NotUtf8)?;
                    continue;
                }
            };
            let Some(day) = parse_date(ds) else {
                policy.bad(&mut report, line, &names[cd], ds, Problem::BadTimestamp)?;
                continue;
            };
            let secs = match c_clock {
                Some(cc) => {
                    let cs = match table.text(cc) {
                        Ok(s) => s,
                        Err(lossy) => {
                            policy.bad(&mut report, line, &names[cc], &lossy, Problem::NotUtf8)?;
                            continue;
                        }
                    };
                    match parse_clock(cs) {
                        Some(s) => s,
                        None => {
                            policy.bad(&mut report, line, &names[cc], cs, Problem::BadTimestamp)?;
                            continue;
                        }
                    }
                }
                None => 0,
            };
            day + secs - wide.utc_offset_s
        };
        let time_column = &names[c_stamp.or(c_date).unwrap_or(0)];
        if !policy.check_time(&mut report, (line, time_column), t, &format_rfc3339(t))? {
            continue;
        }
        let cells = columns
            .iter()
            .map(|&(c, sensor)| (c, sensor, modality, table.text(c)));
        policy.push_values(&mut interner, &mut report, &names, (line, t), cells)?;
    }
    finish(interner, &policy, report, wide.modality.as_str())
}

/// Parses a CAF-style quantity column header `VW_30cm` / `T_150cm` to a modality.
fn caf_modality(header: &str) -> Option<Modality> {
    let (q, d) = header.split_once('_')?;
    let depth: u32 = d.strip_suffix("cm")?.parse().ok()?;
    Modality::at_depth(&q.to_ascii_lowercase(), Some(depth)).ok()
}

/// Reads a CAF daily file (`caf/Daily/CAFnnn.txt`): tab-separated, columns `Location`, `Date`
/// (`MM/DD/YYYY`, read as midnight UTC of that date) and one column per quantity and depth
/// (`VW_30cm` .. `T_150cm`), each its own modality (`vw@30cm` in m3/m3, `t@30cm` in degC).
/// `NA` is missing.
pub fn read_caf_daily(
    path: &Path,
    options: &IngestOptions,
) -> Result<(Readings, IngestReport), IngestError> {
    let bytes = read_file(path)?;
    let mut table = Table::open(path, &bytes, b'\t')?;
    let c_loc = table.require(&["Location"])?;
    let c_date = table.require(&["Date"])?;
    let names = table.header.clone();
    let policy = Policy::for_readings(path, options);
    let mut report = IngestReport::default();
    let mut interner = Interner::default();
    let mut columns: Vec<(usize, u32)> = Vec::new();
    for (k, name) in names.iter().enumerate() {
        if k == c_loc || k == c_date {
            continue;
        }
        let Some(m) = caf_modality(name) else {
            return Err(IngestError::Field {
                path: path.to_path_buf(),
                line: 1,
                column: name.clone(),
                value: name.clone(),
                problem: Problem::BadModality,
            });
        };
        let unit = default_unit(m.quantity());
        let id = interner
            .modality(m, unit)
            .map_err(|_| IngestError::Options {
                path: path.to_path_buf(),
                message: format!("column `{name}` repeated"),
            })?;
        columns.push((k, id));
    }
    while let Some(line) = table.next_row(&policy, &mut report)? {
        let loc = match table.text(c_loc) {
            Ok(s) => s,
            Err(lossy) => {
                policy.bad(&mut report, line, &names[c_loc], &lossy, Problem::NotUtf8)?;
                continue;
            }
        };
        let sensor = match interner.known_sensor(loc, options) {
            Ok(k) => k,
            Err(p) => {
                policy.bad(&mut report, line, &names[c_loc], loc, p)?;
                continue;
            }
        };
        let ds = match table.text(c_date) {
            Ok(s) => s,
            Err(lossy) => {
                policy.bad(&mut report, line, &names[c_date], &lossy, Problem::NotUtf8)?;
                continue;
            }
        };
        let Some(t) = parse_us_date(ds) else {
            policy.bad(&mut report, line, &names[c_date], ds, Problem::BadTimestamp)?;
            continue;
        };
        if !policy.check_time(&mut report, (line, &names[c_date]), t, ds)? {
            continue;
        }
        let cells = columns
            .iter()
            .map(|&(c, modality)| (c, sensor, modality, table.text(c)));
        policy.push_values(&mut interner, &mut report, &names, (line, t), cells)?;
    }
    finish(interner, &policy, report, "value")
}

/// Settings for [`read_sensors_csv`].
#[derive(Debug, Clone, Default)]
pub struct SensorsOptions {
    /// Read positions from `easting`/`northing` (metres) in this UTM zone (zone, northern
    /// hemisphere?) instead of `lat`/`lon`. CAF is `(11, true)` (NAD83 / UTM 11N, EPSG:26911).
    pub utm: Option<(u8, bool)>,
    /// Bad-row policy.
    pub on_error: OnError,
}

/// A sensor read from a file, with the line it came from.
#[derive(Debug, Clone, PartialEq)]
pub struct SensorInput {
    /// The sensor.
    pub sensor: Sensor,
    /// 1-based line.
    pub line: u64,
}

/// Reads a sensors table: `id` (or `sensor_id`, `location`, `name`), then either `lat`/`lon`
/// (WGS84 degrees; `lat_deg`, `latitude`, `lon_deg`, `lng`, `longitude` accepted) or, with
/// [`SensorsOptions::utm`], `easting`/`northing` metres (`easting_m`, `northing_m`); optional
/// `elevation_m` (`elevation`). Duplicate ids are errors.
pub fn read_sensors_csv(
    path: &Path,
    options: &SensorsOptions,
) -> Result<(Vec<SensorInput>, IngestReport), IngestError> {
    let bytes = read_file(path)?;
    let delimiter = if bytes
        .split(|&b| b == b'\n')
        .next()
        .is_some_and(|h| h.contains(&b'\t'))
    {
        b'\t'
    } else {
        b','
    };
    let mut table = Table::open(path, &bytes, delimiter)?;
    let c_id = table.require(&["id", "sensor_id", "location", "name"])?;
    let (c_x, c_y, utm) = match options.utm {
        Some((zone, north)) => {
            let tm = TransverseMercator::utm(zone, north).map_err(|e| IngestError::Options {
                path: path.to_path_buf(),
                message: e.to_string(),
            })?;
            (
                table.require(&["easting", "easting_m", "x"])?,
                table.require(&["northing", "northing_m", "y"])?,
                Some(tm),
            )
        }
        None => (
            table.require(&["lat", "lat_deg", "latitude"])?,
            table.require(&["lon", "lon_deg", "lng", "longitude"])?,
            None,
        ),
    };
    let c_elev = table.find(&["elevation_m", "elevation", "elev"]);
    let names = table.header.clone();
    let policy = Policy::new(path, options.on_error);
    let mut report = IngestReport::default();
    let mut out: Vec<SensorInput> = Vec::new();
    let mut seen: HashMap<String, u64> = HashMap::new();
    while let Some(line) = table.next_row(&policy, &mut report)? {
        let id_s = match table.text(c_id) {
            Ok(s) => s,
            Err(lossy) => {
                policy.bad(&mut report, line, &names[c_id], &lossy, Problem::NotUtf8)?;
                continue;
            }
        };
        let Ok(id) = SensorId::new(id_s) else {
            policy.bad(&mut report, line, &names[c_id], id_s, Problem::BadSensorId)?;
            continue;
        };
        if let Some(&first_line) = seen.get(id_s) {
            policy.bad(
                &mut report,
                line,
                &names[c_id],
                id_s,
                Problem::DuplicateSensor { first_line },
            )?;
            continue;
        }
        let mut coord = |c: usize| -> Result<Option<f64>, IngestError> {
            let s = table.field(c).unwrap_or("");
            match parse_value(s) {
                Ok(v) => Ok(Some(v)),
                Err(p) => policy
                    .bad(&mut report, line, &names[c], s, p)
                    .map(|()| None),
            }
        };
        let (Some(x), Some(y)) = (coord(c_x)?, coord(c_y)?) else {
            continue;
        };
        let position = match &utm {
            Some(tm) => utm_position(tm, x, y),
            None => LatLon::new(x, y).map_err(|_| ()),
        };
        let Ok(position) = position else {
            let v = format!("{x}, {y}");
            policy.bad(
                &mut report,
                line,
                &format!("{}/{}", names[c_x], names[c_y]),
                &v,
                Problem::BadPosition,
            )?;
            continue;
        };
        let elevation_m = match c_elev {
            Some(c) => {
                let s = table.field(c).unwrap_or("");
                if is_missing(s) {
                    None
                } else {
                    match parse_value(s) {
                        Ok(v) if (MIN_ELEVATION_M..=MAX_ELEVATION_M).contains(&v) => Some(v),
                        Ok(_) => {
                            let problem = Problem::Elevation {
                                min: MIN_ELEVATION_M,
                                max: MAX_ELEVATION_M,
                            };
                            policy.bad(&mut report, line, &names[c], s, problem)?;
                            continue;
                        }
                        Err(p) => {
                            policy.bad(&mut report, line, &names[c], s, p)?;
                            continue;
                        }
                    }
                }
            }
            None => None,
        };
        seen.insert(id_s.to_string(), line);
        out.push(SensorInput {
            sensor: Sensor {
                id,
                position,
                elevation_m,
            },
            line,
        });
    }
    report.readings = out.len() as u64;
    Ok((out, report))
}

/// Lowest plausible sensor elevation, metres (the Dead Sea shore is at −430 m).
const MIN_ELEVATION_M: f64 = -500.0;
/// Highest plausible sensor elevation, metres.
const MAX_ELEVATION_M: f64 = 9_000.0;

/// A UTM easting/northing (metres) as WGS84, refused unless the easting is within 0..=1e6 m
/// and the northing within 0..=1e7 m (the grid's own ranges, false origins included) and the
/// position maps back to itself within 1 m: an easting of 1e12 m gives NaN degrees.
fn utm_position(tm: &TransverseMercator, x: f64, y: f64) -> Result<LatLon, ()> {
    if !((0.0..=1e6).contains(&x) && (0.0..=1e7).contains(&y)) {
        return Err(());
    }
    let p = tm.inverse(LocalPoint::new(x, y));
    let p = LatLon::new(p.lat(), p.lon()).map_err(|_| ())?;
    let back = tm.forward(p);
    if (back.e - x).hypot(back.n - y) <= 1.0 {
        Ok(p)
    } else {
        Err(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn line_counter_hand_checked() {
        let text = b"h\r\na\nb\rc\r\n\r\nd";
        let mut c = LineCounter::new(text);
        assert_eq!(c.line_at(0), 1);
        assert_eq!(c.line_at(3), 2); // a
        assert_eq!(c.line_at(5), 3); // b
        assert_eq!(c.line_at(7), 4); // c
        // A reader may report the offset of the "\n" of a CRLF: still the next line.
        assert_eq!(c.line_at(12), 6); // d, after an empty line
        let mut c = LineCounter::new(text);
        assert_eq!(c.line_at(9), 6); // "\n\r\nd": skips to d
        assert_eq!(c.line_at(2), 2); // going back recounts
    }

    proptest! {
        #[test]
        fn lines_start_where_expected(
            lines in prop::collection::vec(("[a-z,]{1,6}", 0usize..3), 1..30)
        ) {
            let mut text = Vec::new();
            let mut starts = Vec::new();
            for (body, eol) in &lines {
                starts.push(text.len());
                text.extend_from_slice(body.as_bytes());
                text.extend_from_slice([&b"\n"[..], b"\r\n", b"\r"][*eol]);
            }
            let mut c = LineCounter::new(&text);
            for (k, &s) in starts.iter().enumerate() {
                prop_assert_eq!(c.line_at(s), k as u64 + 1);
            }
        }
    }
}
