//! A mutation fuzzer for every reader of untrusted input: the sensors, readings (long, wide,
//! CAF daily, Hubbard Brook), per-cell CSV (scores, probabilities) and flight files, and the
//! project file `gleaner.toml`.
//!
//! Each execution takes a seed input (a corpus file or an earlier generated input), applies a
//! few random mutations (bit flips, interesting bytes and tokens, inserted, deleted, duplicated
//! or spliced ranges, repeated lines) or generates arbitrary bytes, writes them to the target's
//! file and calls the reader under [`std::panic::catch_unwind`]. An `Err` is the expected
//! outcome of bad input; a panic is a bug, and its input is kept. Everything random comes from
//! the seed, so a run is reproducible for a given seed and execution count.

use std::collections::HashSet;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use gleaner_field::Modality;
use gleaner_ingest::{
    HubbardBrookMetadata, IngestOptions, OnError, SensorsOptions, WideOptions, read_caf_daily,
    read_hubbard_brook_logger, read_hubbard_brook_sensors, read_long_csv, read_sensors_csv,
    read_wide_csv,
};

use crate::SplitMix;

/// A parser under test.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Target {
    /// `read_sensors_csv`, lat/lon and UTM 11N.
    Sensors,
    /// `read_long_csv`, every sensor and known sensors only, fail and skip.
    Long,
    /// `read_wide_csv` (`vw@30cm`, comma and tab).
    Wide,
    /// `read_caf_daily`.
    Caf,
    /// `read_hubbard_brook_logger` with a fixed probe table.
    HubbardBrook,
    /// `HubbardBrookMetadata::read` and `read_hubbard_brook_sensors`.
    HubbardBrookMetadata,
    /// The per-cell CSV of `plan --scores` and `score --probabilities`, then the
    /// probabilities' validation.
    CellCsv,
    /// A flight file as `record` reads it: format detection, then the detected reader.
    Flight,
    /// `Settings::load` of a `gleaner.toml`.
    Config,
    /// The orienteering benchmark readers `parse_classic` and `parse_oplib` (`bench op`).
    OpInstance,
}

impl Target {
    /// Every target, in the order `--target all` runs them.
    pub const ALL: [Target; 10] = [
        Target::Sensors,
        Target::Long,
        Target::Wide,
        Target::Caf,
        Target::HubbardBrook,
        Target::HubbardBrookMetadata,
        Target::CellCsv,
        Target::Flight,
        Target::Config,
        Target::OpInstance,
    ];

    /// The target's name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Target::Sensors => "sensors",
            Target::Long => "long",
            Target::Wide => "wide",
            Target::Caf => "caf",
            Target::HubbardBrook => "hubbard-brook",
            Target::HubbardBrookMetadata => "hubbard-brook-metadata",
            Target::CellCsv => "cell-csv",
            Target::Flight => "flight",
            Target::Config => "config",
            Target::OpInstance => "op-instance",
        }
    }

    /// The target named `name`.
    pub fn from_name(name: &str) -> Option<Target> {
        Self::ALL.into_iter().find(|t| t.name() == name)
    }

    /// Folders of the hostile corpus (`crates/gleaner-cli/tests/data/hostile/<folder>`) whose
    /// files seed this target.
    fn corpus_folders(self) -> &'static [&'static str] {
        match self {
            Target::Sensors => &["sensors"],
            Target::Long => &["long", "flight"],
            Target::Wide => &["wide"],
            Target::Caf => &["caf"],
            Target::HubbardBrook => &["hubbard"],
            Target::HubbardBrookMetadata => &["hubbard_metadata", "base"],
            Target::CellCsv => &["scores", "probabilities"],
            Target::Flight => &["flight", "long", "wide", "caf"],
            Target::Config => &["toml"],
            Target::OpInstance => &[],
        }
    }

    /// The file name the input is written to (a logger file's name is its logger id).
    fn file_name(self) -> &'static str {
        match self {
            Target::HubbardBrook => "z9-1.csv",
            Target::Config => "gleaner.toml",
            Target::Caf => "input.txt",
            _ => "input.csv",
        }
    }
}

/// Where the fuzzer finds its seeds and keeps what it finds.
#[derive(Debug, Clone)]
pub struct FuzzConfig {
    /// The parser.
    pub target: Target,
    /// Seed of the random choices.
    pub seed: u64,
    /// Stop after this long (wall clock).
    pub duration: Duration,
    /// Stop after this many executions (whichever comes first).
    pub max_execs: u64,
    /// The repository's root (the corpus is read from its test data).
    pub root: PathBuf,
    /// Inputs that panicked are written here (`<target>-<exec>.bin`).
    pub crashes: PathBuf,
    /// Largest generated input, bytes.
    pub max_len: usize,
    /// Folder for the input file written at every execution (a memory file system such as
    /// `/dev/shm` keeps the run CPU-bound); the system's temporary folder when `None`.
    pub scratch: Option<PathBuf>,
}

/// What a run did.
#[derive(Debug, Clone, Default)]
pub struct FuzzReport {
    /// Executions.
    pub execs: u64,
    /// Inputs the parser accepted (`Ok`).
    pub accepted: u64,
    /// Inputs it refused with an error.
    pub refused: u64,
    /// Panics (each input kept in the crashes folder).
    pub panics: u64,
    /// The first panics' messages and the files holding their inputs.
    pub crashes: Vec<(String, PathBuf)>,
    /// Seeds the run started from.
    pub seeds: usize,
    /// Distinct error messages seen (a rough measure of the paths reached), capped at 100 000.
    pub distinct_errors: usize,
    /// Wall-clock time of the run.
    pub elapsed: Duration,
    /// Slowest single execution.
    pub slowest: Duration,
}

/// Tokens that often matter to these parsers.
const TOKENS: &[&str] = &[
    "NaN",
    "nan",
    "inf",
    "-inf",
    "1e308",
    "-1.7e308",
    "1e-320",
    "0",
    "-0",
    "NA",
    "",
    ",",
    ",,,,,,",
    "\t",
    "\n",
    "\r\n",
    "\r",
    "\"",
    "\"\"",
    "\u{feff}",
    "\u{0}",
    "\u{fffd}",
    "9999-12-31",
    "0000-01-01",
    "2014-02-30",
    "2014-01-01T00:00:00Z",
    "2014-01-01T23:59:60+14:00",
    "12/31/9999",
    "02/29/2015",
    "24:00",
    "99:99:99",
    "vw@30cm",
    "t@1e9m",
    "vw@",
    "@",
    ":",
    "p1:TEROS_12:Water_Content:m3_per_m3",
    "p99:X:Bulk_EC:mS/cm",
    "value",
    "sensor_id",
    "timestamp",
    "modality",
    "unit",
    "Location",
    "Date",
    "VW_30cm",
    "T_150cm",
    "x0y0",
    "x-2147483648y2147483647",
    "18446744073709551615",
    "-9223372036854775808",
    "[field]",
    "[energy]",
    "[utility]",
    "[planner]",
    "[ingest]",
    "= nan",
    "= inf",
    "= -1",
    "= 1e300",
    "= 1000000",
    "= \"\"",
    "= []",
    "= {}",
    "cell_size_m = 0.5\n",
    "neighbour_radius_m = 50\n",
    "condition_classes = 20\n",
    "time_limit_s = 86400\n",
    "value_limits = { vw = [0, 1e15] }\n",
];

/// Arbitrary bytes or one to eight mutations of `seed`.
fn mutate(rng: &mut SplitMix, seed: &[u8], others: &[Vec<u8>], max_len: usize) -> Vec<u8> {
    let pick = |rng: &mut SplitMix, n: usize| (rng.next_u64() % n.max(1) as u64) as usize;
    if rng.unit() < 0.05 {
        let n = pick(rng, 512);
        return (0..n).map(|_| rng.next_u64() as u8).collect();
    }
    let mut data = seed.to_vec();
    let rounds = 1 + pick(rng, 8);
    for _ in 0..rounds {
        let len = data.len();
        match pick(rng, 11) {
            0 if len > 0 => {
                let i = pick(rng, len);
                data[i] ^= 1 << pick(rng, 8);
            }
            1 if len > 0 => {
                let i = pick(rng, len);
                data[i] = b"\0\xff\x7f\x80,\n\r\t\"\\:@-.eE0123456789"[pick(rng, 24)];
            }
            2 => {
                let i = pick(rng, len + 1);
                let token = TOKENS[pick(rng, TOKENS.len())].as_bytes();
                data.splice(i..i, token.iter().copied());
            }
            3 if len > 0 => {
                // Replace a field (between separators) with a token.
                let i = pick(rng, len);
                let is_sep = |b: u8| matches!(b, b',' | b'\t' | b'\n' | b'\r' | b'=');
                let start = data[..i]
                    .iter()
                    .rposition(|&b| is_sep(b))
                    .map_or(0, |p| p + 1);
                let end = data[i..]
                    .iter()
                    .position(|&b| is_sep(b))
                    .map_or(len, |p| i + p);
                let token = TOKENS[pick(rng, TOKENS.len())].as_bytes();
                data.splice(start..end.max(start), token.iter().copied());
            }
            4 if len > 0 => {
                let a = pick(rng, len);
                let b = (a + 1 + pick(rng, 64)).min(len);
                data.drain(a..b);
            }
            5 if len > 0 => {
                let a = pick(rng, len);
                let b = (a + 1 + pick(rng, 256)).min(len);
                let chunk = data[a..b].to_vec();
                let at = pick(rng, len + 1);
                data.splice(at..at, chunk);
            }
            6 if !others.is_empty() => {
                let other = &others[pick(rng, others.len())];
                if !other.is_empty() {
                    let a = pick(rng, other.len());
                    let b = (a + 1 + pick(rng, 512)).min(other.len());
                    let at = pick(rng, len + 1);
                    data.splice(at..at, other[a..b].iter().copied());
                }
            }
            7 => {
                // Repeat one line many times (long files, many duplicates).
                let lines: Vec<&[u8]> = data.split(|&b| b == b'\n').collect();
                if let Some(line) = lines.get(pick(rng, lines.len())) {
                    let mut line = line.to_vec();
                    line.push(b'\n');
                    let times = 1 + pick(rng, 200);
                    let mut extra = Vec::with_capacity(line.len() * times);
                    for _ in 0..times {
                        extra.extend_from_slice(&line);
                    }
                    data.extend(extra);
                }
            }
            8 if len > 0 => data.truncate(pick(rng, len)),
            9 => {
                let i = pick(rng, len + 1);
                let n = 1 + pick(rng, 16);
                let bytes: Vec<u8> = (0..n).map(|_| rng.next_u64() as u8).collect();
                data.splice(i..i, bytes);
            }
            _ => {
                // A long field: a digit or letter run.
                let i = pick(rng, len + 1);
                let c = b"9ax-"[pick(rng, 4)];
                let n = 1 + pick(rng, 4096);
                data.splice(i..i, std::iter::repeat_n(c, n));
            }
        }
        data.truncate(max_len);
    }
    data
}

/// The corpus files that seed `target`, plus the valid test fixtures.
pub fn seeds(target: Target, root: &Path) -> Vec<Vec<u8>> {
    let hostile = root.join("crates/gleaner-cli/tests/data/hostile");
    let mut dirs: Vec<PathBuf> = target
        .corpus_folders()
        .iter()
        .map(|f| hostile.join(f))
        .collect();
    dirs.push(root.join("crates/gleaner-cli/tests/data"));
    dirs.push(root.join("crates/gleaner-ingest/tests/data"));
    let mut out = Vec::new();
    for dir in dirs {
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        let mut files: Vec<PathBuf> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.is_file() && p.extension().is_none_or(|e| e != "expected"))
            .collect();
        files.sort();
        for f in files {
            if let Ok(bytes) = std::fs::read(&f) {
                out.push(bytes);
            }
        }
    }
    if target == Target::OpInstance {
        // The benchmark instances themselves (shared data, not in the repository): the
        // smallest of each set.
        let data = std::env::var_os("GLEANER_DATA_DIR")
            .map(PathBuf::from)
            .unwrap_or_else(|| root.join("../shared/data"));
        for set in ["classic", "oplib/gen1", "oplib/gen2", "oplib/gen3"] {
            let mut files: Vec<(u64, PathBuf)> = walk(&data.join("op").join(set))
                .into_iter()
                .filter_map(|p| Some((std::fs::metadata(&p).ok()?.len(), p)))
                .filter(|(len, _)| *len <= 200_000)
                .collect();
            files.sort();
            for (_, f) in files.into_iter().take(12) {
                if let Ok(bytes) = std::fs::read(&f) {
                    out.push(bytes);
                }
            }
        }
    }
    match target {
        Target::Config => out.push(VALID_TOML.as_bytes().to_vec()),
        Target::CellCsv => out.push(
            b"cell_id,p_dry,p_adequate,p_wet\nx0y0,0.2,0.3,0.5\nx1y0,1,0,0\nx2y0,0.25,0.25,0.5\n"
                .to_vec(),
        ),
        _ => {}
    }
    out
}

/// The files under `dir`, recursively, sorted.
fn walk(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let Ok(entries) = std::fs::read_dir(dir) else {
        return out;
    };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            out.extend(walk(&p));
        } else {
            out.push(p);
        }
    }
    out.sort();
    out
}

/// A valid project file, the config target's main seed.
const VALID_TOML: &str = "[project]\nname = \"f\"\ndatabase = \"gleaner.db\"\n\n[field]\n\
base_lat = 46.78\nbase_lon = -117.0805\nbase_alt_m = 0.0\ncell_size_m = 40.0\nneighbour_k = 3\n\
neighbour_radius_m = 200.0\n\n[sensors]\nfile = \"sensors.csv\"\n\n[ingest]\n\
bytes_per_reading = 16.0\ndefault_interval_s = 86400.0\n\n[utility]\nalpha = 1.0\nbeta = 1.0\n\
gamma = 1.0\ndelta = 1.0\nfreshness_half_life_s = 259200.0\nmin_overlap = 10\nepsilon = 0.000001\n\
anomaly_form = \"bounded\"\nanomaly_kappa = 3.0\nanomaly_flag = 3.0\ncondition_classes = 3\n\
condition_thresholds = [0.2, 0.3]\nredundancy_weights = { \"vw@30cm\" = 1.0 }\n\n[energy]\n\
preset = \"paper\"\ncruise = \"12.5\"\naltitude_m = 30\nreserve_fraction = 0.1\n\n[planner]\n\
solver = \"default\"\ntime_limit_s = 5.0\nseed = 0\n";

/// The probe table the Hubbard Brook logger target reads against.
const HB_METADATA: &str = "siteID,lat,lon,logger,port,unit,depth_cm\n\
HB1,43.9620,-71.7218,z9-1,1,kPa,15\nHB1,43.9620,-71.7218,z9-1,2,m3/m3,15\n\
HB2,43.9625,-71.7210,z9-1,3,m3/m3,50\n";

/// The error of a parse, as text (`None`: accepted).
fn err<T, E: std::fmt::Display>(r: Result<T, E>) -> Option<String> {
    r.err().map(|e| e.to_string())
}

/// Calls the target's parser(s) on the file at `path`: each call's error (`None`: accepted).
fn run_one(target: Target, path: &Path, dir: &Path) -> Vec<Option<String>> {
    let known: HashSet<String> = ["n1", "n2", "n3", "n4", "CAF003", "s1", "s2"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    let every = IngestOptions::default();
    let known_skip = IngestOptions {
        on_error: OnError::Skip,
        known_sensors: Some(known),
        ..IngestOptions::default()
    };
    let vw = || Modality::new("vw@30cm").map_err(|e| e.to_string());
    match target {
        Target::Sensors => {
            let utm = SensorsOptions {
                utm: Some((11, true)),
                on_error: OnError::Skip,
            };
            vec![
                err(read_sensors_csv(path, &SensorsOptions::default())),
                err(read_sensors_csv(path, &utm)),
            ]
        }
        Target::Long => vec![
            err(read_long_csv(path, &every)),
            err(read_long_csv(path, &known_skip)),
        ],
        Target::Wide => {
            let Ok(m) = vw() else {
                return vec![Some("modality".into())];
            };
            let mut wide = WideOptions::new(m);
            let a = err(read_wide_csv(path, &wide, &every));
            wide.delimiter = b'\t';
            wide.utc_offset_s = -8 * 3600;
            vec![a, err(read_wide_csv(path, &wide, &known_skip))]
        }
        Target::Caf => vec![
            err(read_caf_daily(path, &every)),
            err(read_caf_daily(path, &known_skip)),
        ],
        Target::HubbardBrook => {
            let meta = match HubbardBrookMetadata::read(&dir.join("sensor_metadata.csv")) {
                Ok(m) => m,
                Err(e) => return vec![Some(e.to_string())],
            };
            let skip = IngestOptions {
                on_error: OnError::Skip,
                ..IngestOptions::default()
            };
            vec![
                err(read_hubbard_brook_logger(path, &meta, &every)),
                err(read_hubbard_brook_logger(path, &meta, &skip)),
            ]
        }
        Target::HubbardBrookMetadata => vec![
            err(HubbardBrookMetadata::read(path)),
            err(read_hubbard_brook_sensors(path)),
        ],
        Target::CellCsv => match gleaner_app::cell_csv::read(path) {
            Ok(rows) => {
                let labels: Vec<String> = ["x0y0", "x1y0", "x2y0"].map(String::from).to_vec();
                let rows: Vec<(String, Vec<f64>)> =
                    rows.into_iter().map(|r| (r.cell, r.values)).collect();
                vec![err(gleaner_utility::validate_probabilities(&labels, &rows))]
            }
            Err(e) => vec![Some(e.to_string())],
        },
        Target::Flight => {
            let format = match gleaner_app::detect(path) {
                Ok(f) => f,
                Err(e) => return vec![Some(e.to_string())],
            };
            vec![match format {
                gleaner_app::Format::CafDaily => err(read_caf_daily(path, &known_skip)),
                gleaner_app::Format::HubbardBrook => Some("logger file".into()),
                gleaner_app::Format::Wide => match vw() {
                    Ok(m) => err(read_wide_csv(path, &WideOptions::new(m), &known_skip)),
                    Err(e) => Some(e),
                },
                _ => err(read_long_csv(path, &known_skip)),
            }]
        }
        Target::Config => vec![err(gleaner_app::Settings::load(dir))],
        Target::OpInstance => {
            let text = match std::fs::read(path) {
                Ok(b) => String::from_utf8_lossy(&b).into_owned(),
                Err(e) => return vec![Some(e.to_string())],
            };
            vec![
                err(gleaner_op_formats::parse_classic("fuzz", "classic", &text)),
                err(gleaner_op_formats::parse_oplib("fuzz", "gen1", &text)),
            ]
        }
    }
}

/// Runs the fuzzer; `progress` is called about once a second with the report so far.
pub fn fuzz(
    config: &FuzzConfig,
    mut progress: impl FnMut(&FuzzReport),
) -> std::io::Result<FuzzReport> {
    let dir = match &config.scratch {
        Some(s) => tempfile::tempdir_in(s)?,
        None => tempfile::tempdir()?,
    };
    std::fs::write(dir.path().join("sensor_metadata.csv"), HB_METADATA)?;
    let path = dir.path().join(config.target.file_name());
    let mut pool = seeds(config.target, &config.root);
    if pool.is_empty() {
        pool.push(Vec::new());
    }
    let seeds_n = pool.len();
    let mut report = FuzzReport {
        seeds: seeds_n,
        ..FuzzReport::default()
    };
    let mut errors: HashSet<u64> = HashSet::new();
    let mut rng = SplitMix::new(config.seed ^ 0x6C65_616E_6572);
    // Panics are caught and counted; the hook keeps their message instead of printing it.
    let last_panic: Arc<Mutex<String>> = Arc::new(Mutex::new(String::new()));
    let sink = Arc::clone(&last_panic);
    let previous_hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        if let Ok(mut m) = sink.lock() {
            *m = info.to_string();
        }
    }));
    let start = Instant::now();
    let mut last_progress = start;
    while report.execs < config.max_execs && start.elapsed() < config.duration {
        let seed = &pool[(rng.next_u64() % pool.len() as u64) as usize];
        let input = mutate(&mut rng, seed, &pool, config.max_len);
        std::fs::write(&path, &input)?;
        let t0 = Instant::now();
        let outcome = catch_unwind(AssertUnwindSafe(|| {
            run_one(config.target, &path, dir.path())
        }));
        let took = t0.elapsed();
        report.slowest = report.slowest.max(took);
        report.execs += 1;
        match outcome {
            Ok(results) if results.iter().any(Option::is_none) => {
                report.accepted += 1;
                // Accepted inputs are good starting points for deeper mutations.
                if pool.len() < seeds_n + 2_000 {
                    pool.push(input);
                }
            }
            Ok(results) => {
                report.refused += 1;
                // Keep an input that produced a new kind of error: it reached somewhere new.
                if errors.len() < 100_000 {
                    let key = error_key(&results);
                    if errors.insert(key) && pool.len() < seeds_n + 2_000 {
                        pool.push(input);
                    }
                }
            }
            Err(_) => {
                report.panics += 1;
                std::fs::create_dir_all(&config.crashes)?;
                let file =
                    config
                        .crashes
                        .join(format!("{}-{}.bin", config.target.name(), report.execs));
                std::fs::write(&file, &input)?;
                let message = last_panic.lock().map(|m| m.clone()).unwrap_or_default();
                if report.crashes.len() < 20 {
                    report.crashes.push((message, file));
                }
            }
        }
        if last_progress.elapsed() >= Duration::from_secs(1) {
            last_progress = Instant::now();
            report.elapsed = start.elapsed();
            report.distinct_errors = errors.len();
            progress(&report);
        }
    }
    std::panic::set_hook(previous_hook);
    report.elapsed = start.elapsed();
    report.distinct_errors = errors.len();
    Ok(report)
}

/// A hash of the shape of the errors an input produced (digits removed, so line numbers and
/// values do not count as new shapes): refused inputs with a new shape join the pool.
fn error_key(results: &[Option<String>]) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    for message in results.iter().flatten() {
        let shape: String = message
            .chars()
            .filter(|c| !c.is_ascii_digit())
            .take(120)
            .collect();
        shape.hash(&mut h);
    }
    h.finish()
}
