//! The peer protocol on Hubbard Brook hourly data: a hold-out no setting was chosen on
//! (registered in `docs/evaluation/peer-hubbard-brook-preregistration.md`).
//!
//! The 12 sites of the USDA Forest Soil Moisture Monitoring Network at Hubbard Brook (NH),
//! hourly water content, as one-shot selection problems at the peer's horizon: windows of
//! 1,001 training and 500 test complete-case rows, tiled by 500 rows; the sites' positions in
//! the local east/north frame about their centroid, the depot there; the peer's energy
//! accounting (J per metre plus J per visit, one visit free) at capacities that are shares of
//! the energy of a tour through every site.
//!
//! Units: positions metres, energies J, times seconds, water content m³/m³ (errors in its
//! square).

use std::collections::{BTreeMap, HashMap};
use std::fmt::Write as _;
use std::path::Path;

use gleaner_field::{LatLon, TransverseMercator};
use gleaner_ingest::{HubbardBrookMetadata, IngestOptions, OnError, read_hubbard_brook_logger};

use crate::EvalError;
use crate::peer::{
    Estimator, Layout, Matrix, Planner, Protocol, Report, WindowMeans, frozen_fit, mean_interval,
    paired_difference, run_windows,
};

/// Which water content of the sites.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Depth {
    /// At each site the shallowest depth with a water-content probe (10–20 cm).
    Shallow,
    /// At 50 cm (the sites that have it).
    Cm50,
}

impl Depth {
    /// Both, in report order.
    pub const ALL: [Depth; 2] = [Depth::Shallow, Depth::Cm50];

    /// Its name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Depth::Shallow => "shallow (10-20 cm)",
            Depth::Cm50 => "50 cm",
        }
    }
}

/// Training rows of a window (the peer's).
pub const TRAIN_ROWS: usize = 1001;
/// Test rows of a window (the peer's).
pub const TEST_ROWS: usize = 500;
/// Shares of the every-site tour's energy run as capacities.
pub const CAPACITY_SHARES: [f64; 7] = [0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8];
/// Layout name in the outcomes.
pub const LAYOUT: &str = "hubbard_brook";

/// One water-content probe of the metadata: site, WGS84 position (degrees), logger, port,
/// depth (cm).
#[derive(Debug, Clone, PartialEq)]
struct Probe {
    site: String,
    lat: f64,
    lon: f64,
    logger: String,
    port: String,
    depth_cm: u32,
}

fn probes(path: &Path) -> Result<Vec<Probe>, EvalError> {
    let (header, rows) = crate::peer::read_csv(path)?;
    let col = |name: &str| crate::peer::column(path, &header, name);
    let [c_site, c_lat, c_lon, c_logger, c_port, c_meas, c_depth] = [
        col("siteID")?,
        col("lat")?,
        col("lon")?,
        col("logger")?,
        col("port")?,
        col("meas")?,
        col("depth_cm")?,
    ];
    let mut out = Vec::new();
    for (line, row) in rows {
        if !row[c_meas].eq_ignore_ascii_case("vwc") {
            continue;
        }
        let depth = crate::peer::number(path, line, "depth_cm", &row[c_depth])?;
        if !(0.0..=1000.0).contains(&depth) || depth.fract() != 0.0 {
            return Err(crate::peer::bad(
                path,
                line,
                "depth_cm",
                "not a whole number of cm",
            ));
        }
        out.push(Probe {
            site: row[c_site].clone(),
            lat: crate::peer::number(path, line, "lat", &row[c_lat])?,
            lon: crate::peer::number(path, line, "lon", &row[c_lon])?,
            logger: row[c_logger].clone(),
            port: row[c_port].clone(),
            depth_cm: depth as u32,
        });
    }
    Ok(out)
}

/// The probes that make each site's series of `depth`: site -> its probes, sites in name
/// order (a site without a probe of `depth` is left out).
fn chosen(probes: &[Probe], depth: Depth) -> BTreeMap<String, Vec<Probe>> {
    let mut by_site: BTreeMap<String, Vec<Probe>> = BTreeMap::new();
    for p in probes {
        by_site.entry(p.site.clone()).or_default().push(p.clone());
    }
    by_site
        .into_iter()
        .filter_map(|(site, ps)| {
            let want = match depth {
                Depth::Shallow => ps.iter().map(|p| p.depth_cm).min()?,
                Depth::Cm50 => 50,
            };
            let keep: Vec<Probe> = ps.into_iter().filter(|p| p.depth_cm == want).collect();
            (!keep.is_empty()).then_some((site, keep))
        })
        .collect()
}

/// What a site's series measures: the probes' water content or their soil temperature.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Quantity {
    /// Volumetric water content, m³/m³ (values outside 0–1 are missing).
    WaterContent,
    /// Soil temperature of the same probes, °C (values outside −50…60 °C are missing).
    Temperature,
}

impl Quantity {
    /// Its name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Quantity::WaterContent => "water content",
            Quantity::Temperature => "soil temperature",
        }
    }

    /// The modality's quantity code (`vw@15cm`, `t@15cm`).
    fn code(self) -> &'static str {
        match self {
            Quantity::WaterContent => "vw",
            Quantity::Temperature => "t",
        }
    }

    /// Whether `x` (the quantity's unit) is physically possible.
    fn valid(self, x: f64) -> bool {
        match self {
            Quantity::WaterContent => (0.0..=1.0).contains(&x),
            Quantity::Temperature => (-50.0..=60.0).contains(&x),
        }
    }

    /// The factor errors are reported with, the unit they are then in, and its short form
    /// for differences.
    fn error_unit(self) -> (f64, &'static str, &'static str) {
        match self {
            Quantity::WaterContent => (1e3, "×10⁻³ (m³/m³)²", "×10⁻³"),
            Quantity::Temperature => (1.0, "°C²", "°C²"),
        }
    }
}

/// One data set of the protocol: a quantity at a depth, over every complete hour of the
/// sites that have the depth, or (`late`) only over the hours after the last of those, with
/// the sites that have a value in at least half of the later hours.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Series {
    /// What is measured.
    pub quantity: Quantity,
    /// At which depth.
    pub depth: Depth,
    /// Only the hours after every site's last complete hour.
    pub late: bool,
}

impl Series {
    /// Water content at `depth` over every complete hour (the first registration).
    pub fn water(depth: Depth) -> Series {
        Series {
            quantity: Quantity::WaterContent,
            depth,
            late: false,
        }
    }

    /// A file-name stem: `water-shallow`, `temperature-50cm`, `water-late-shallow`, …
    pub fn stem(self) -> String {
        let q = match self.quantity {
            Quantity::WaterContent => "water",
            Quantity::Temperature => "temperature",
        };
        let d = match self.depth {
            Depth::Shallow => "shallow",
            Depth::Cm50 => "50cm",
        };
        if self.late {
            format!("{q}-late-{d}")
        } else {
            format!("{q}-{d}")
        }
    }
}

/// Which registration's data sets to run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Registration {
    /// Water content, shallow and 50 cm, every complete hour
    /// (`peer-hubbard-brook-preregistration.md`).
    First,
    /// Water content in the hours after the first's data ended, shallow and 50 cm, and soil
    /// temperature over every complete hour, shallow and 50 cm
    /// (`peer-hubbard-brook-2-preregistration.md`).
    Second,
}

impl Registration {
    /// Its data sets, in report order.
    pub fn series(self) -> Vec<Series> {
        match self {
            Registration::First => Depth::ALL.map(Series::water).to_vec(),
            Registration::Second => {
                let late = Depth::ALL.map(|depth| Series {
                    late: true,
                    ..Series::water(depth)
                });
                let temperature = Depth::ALL.map(|depth| Series {
                    quantity: Quantity::Temperature,
                    ..Series::water(depth)
                });
                late.into_iter().chain(temperature).collect()
            }
        }
    }

    /// The summary's heading.
    fn title(self) -> &'static str {
        match self {
            Registration::First => "hold-out: Hubbard Brook hourly water content",
            Registration::Second => {
                "hold-out: Hubbard Brook, later hours' water content and soil temperature"
            }
        }
    }
}

/// A loaded Hubbard Brook protocol: the complete-case matrix (columns = sites), the layout,
/// one protocol per window, the capacities (J) and the every-site tour's energy (J).
#[derive(Debug, Clone)]
pub struct HubbardBrook {
    /// The data set.
    pub series: Series,
    /// Complete-case rows, one column per site (site names).
    pub matrix: Matrix,
    /// The sites about their centroid, depot at the centroid.
    pub layout: Layout,
    /// One protocol per window.
    pub protocols: Vec<Protocol>,
    /// Energy of the tour through every site, J.
    pub all_sites_j: f64,
    /// The capacities run, J.
    pub capacities: Vec<f64>,
    /// Loggers of chosen probes listed in the metadata whose file is not in the directory.
    pub missing_loggers: Vec<String>,
    /// For a late series: the last complete hour of every site (s), after which its rows lie.
    pub after: Option<i64>,
}

/// Loads the water content at `depth` over every complete hour ([`load_series`]).
pub fn load(dir: &Path, depth: Depth) -> Result<HubbardBrook, EvalError> {
    load_series(dir, Series::water(depth))
}

/// The sites' probes, their series (one column per site) and the loggers without a file.
type SiteSeries = (BTreeMap<String, Vec<Probe>>, Matrix, Vec<String>);

/// Every site's hourly series of `series` (replicate probes averaged over those with a value
/// at the hour), one column per site, NaN where a site has none; the sites' probes and the
/// listed loggers without a file.
fn read_sites(dir: &Path, series: Series) -> Result<SiteSeries, EvalError> {
    let (quantity, depth) = (series.quantity, series.depth);
    let meta_path = dir.join("sensor_metadata.csv");
    let sites = chosen(&probes(&meta_path)?, depth);
    if sites.is_empty() {
        return Err(EvalError::Data(format!(
            "{}: no water-content probe at {}",
            meta_path.display(),
            depth.name()
        )));
    }
    let metadata = HubbardBrookMetadata::read(&meta_path)?;
    let options = IngestOptions {
        on_error: OnError::Skip,
        ..IngestOptions::default()
    };
    // (logger:pPORT, modality) -> site column.
    let labels: Vec<String> = sites.keys().cloned().collect();
    let mut want: HashMap<(String, String), usize> = HashMap::new();
    let mut loggers: Vec<String> = Vec::new();
    for (k, ps) in sites.values().enumerate() {
        for p in ps {
            want.insert(
                (
                    format!("{}:p{}", p.logger, p.port),
                    format!("{}@{}cm", quantity.code(), p.depth_cm),
                ),
                k,
            );
            if !loggers.contains(&p.logger) {
                loggers.push(p.logger.clone());
            }
        }
    }
    loggers.sort();
    // (time, site) -> (sum, count) of the site's probes with a value.
    let mut cells: BTreeMap<(i64, usize), (f64, u32)> = BTreeMap::new();
    let mut seen = vec![false; labels.len()];
    let mut missing_loggers = Vec::new();
    for logger in &loggers {
        let path = dir.join(format!("{logger}.csv"));
        if !path.exists() {
            // A logger listed in the metadata without a file: its sites' series are what the
            // other loggers hold (a site with none is an error below).
            missing_loggers.push(logger.clone());
            continue;
        }
        let (readings, _) = read_hubbard_brook_logger(&path, &metadata, &options)?;
        for r in &readings.rows {
            let sensor = readings.sensors[r.sensor as usize].as_str().to_string();
            let modality = readings.modalities[r.modality as usize]
                .modality
                .as_str()
                .to_string();
            if let Some(&k) = want.get(&(sensor, modality))
                && quantity.valid(r.value)
            {
                let c = cells.entry((r.t, k)).or_insert((0.0, 0));
                c.0 += r.value;
                c.1 += 1;
                seen[k] = true;
            }
        }
    }
    let n = labels.len();
    if let Some(k) = seen.iter().position(|s| !s) {
        return Err(EvalError::Data(format!(
            "{}: site {} has no {} at {}",
            dir.display(),
            labels[k],
            quantity.name(),
            depth.name()
        )));
    }
    let mut times: Vec<i64> = cells.keys().map(|&(t, _)| t).collect();
    times.dedup();
    let mut values = vec![f64::NAN; times.len() * n];
    for (&(t, k), &(sum, count)) in &cells {
        if let Ok(row) = times.binary_search(&t) {
            values[row * n + k] = sum / f64::from(count);
        }
    }
    let matrix = Matrix {
        labels,
        times,
        values,
    };
    Ok((sites, matrix, missing_loggers))
}

/// The rows of `raw` after its last complete row, with the sites that have a value in at
/// least half of those rows: the kept sites' columns and their complete rows; `None` when
/// no row follows. Also returns the last complete row's time (s).
fn late_rows(raw: &Matrix) -> Option<(Vec<usize>, Matrix, i64)> {
    let cut = *raw.complete_rows().times.last()?;
    let n = raw.labels.len();
    let first = raw.times.partition_point(|&t| t <= cut);
    let rows = raw.times.len() - first;
    if rows == 0 {
        return None;
    }
    let kept: Vec<usize> = (0..n)
        .filter(|&k| {
            let have = (first..raw.times.len())
                .filter(|&r| raw.values[r * n + k].is_finite())
                .count();
            2 * have >= rows
        })
        .collect();
    let mut values = Vec::with_capacity(rows * kept.len());
    for r in first..raw.times.len() {
        values.extend(kept.iter().map(|&k| raw.values[r * n + k]));
    }
    let matrix = Matrix {
        labels: kept.iter().map(|&k| raw.labels[k].clone()).collect(),
        times: raw.times[first..].to_vec(),
        values,
    }
    .complete_rows();
    Some((kept, matrix, cut))
}

/// Loads the protocol of `series` from the Hubbard Brook directory `dir` (its
/// `sensor_metadata.csv` and one `<logger>.csv` per logger).
///
/// Errors: unreadable files, a site without any value, fewer than one window of complete
/// rows.
pub fn load_series(dir: &Path, series: Series) -> Result<HubbardBrook, EvalError> {
    let depth = series.depth;
    let (mut sites, raw, missing_loggers) = read_sites(dir, series)?;
    let (matrix, after) = if series.late {
        let Some((kept, matrix, cut)) = late_rows(&raw) else {
            return Err(EvalError::Data(format!(
                "{}: no hours of {} at {} after the last complete one",
                dir.display(),
                series.quantity.name(),
                depth.name()
            )));
        };
        let names: Vec<String> = sites.keys().cloned().collect();
        let keep: Vec<&String> = kept.iter().map(|&k| &names[k]).collect();
        sites.retain(|name, _| keep.contains(&name));
        (matrix, Some(cut))
    } else {
        (raw.complete_rows(), None)
    };
    let n = matrix.labels.len();
    let layout = site_layout(&sites)?;
    let base = Protocol::peer_hourly(frozen_fit(3_600));
    let protocols = tiled_windows(matrix.times.len(), &base);
    let Some(first) = protocols.first() else {
        return Err(EvalError::Data(format!(
            "{}: {} complete hours at {}, fewer than one window of {}",
            dir.display(),
            matrix.times.len(),
            depth.name(),
            TRAIN_ROWS + TEST_ROWS
        )));
    };
    // The every-site tour: the count planner with no limit (every site is worth one, so the
    // data do not enter it).
    let fitted = crate::peer::Fitted::new(matrix.clone(), first.clone())?;
    let all = fitted.run(&layout, 1e12, Planner::Count)?;
    if all.tour.len() != n {
        return Err(EvalError::Data(format!(
            "the unlimited tour visits {} of {n} sites",
            all.tour.len()
        )));
    }
    let capacities = CAPACITY_SHARES.iter().map(|s| s * all.energy_j).collect();
    Ok(HubbardBrook {
        series,
        matrix,
        layout,
        protocols,
        all_sites_j: all.energy_j,
        capacities,
        missing_loggers,
        after,
    })
}

/// Window k trains on rows `500k .. 500k + 1001` and tests on the next 500, while the data
/// last (test sets do not overlap).
pub fn tiled_windows(rows: usize, base: &Protocol) -> Vec<Protocol> {
    let mut out = Vec::new();
    let mut start = 0;
    while start + TRAIN_ROWS + TEST_ROWS <= rows {
        out.push(Protocol {
            train: start..start + TRAIN_ROWS,
            test: start + TRAIN_ROWS..start + TRAIN_ROWS + TEST_ROWS,
            ..base.clone()
        });
        start += TEST_ROWS;
    }
    out
}

/// The sites in the local Transverse Mercator frame about the centroid of their WGS84
/// positions (east/north metres), the depot at the centroid. A site's position is its first
/// probe's.
fn site_layout(sites: &BTreeMap<String, Vec<Probe>>) -> Result<Layout, EvalError> {
    let pos: Vec<(f64, f64)> = sites.values().map(|ps| (ps[0].lat, ps[0].lon)).collect();
    let k = pos.len() as f64;
    let (lat0, lon0) = (
        pos.iter().map(|p| p.0).sum::<f64>() / k,
        pos.iter().map(|p| p.1).sum::<f64>() / k,
    );
    let latlon = |lat: f64, lon: f64| {
        LatLon::new(lat, lon).map_err(|e| EvalError::Data(format!("site at {lat}, {lon}: {e}")))
    };
    let frame = TransverseMercator::local(latlon(lat0, lon0)?);
    let positions = pos
        .iter()
        .map(|&(lat, lon)| {
            let p = frame.forward(latlon(lat, lon)?);
            Ok([p.e, p.n])
        })
        .collect::<Result<Vec<_>, EvalError>>()?;
    Ok(Layout {
        name: LAYOUT.into(),
        labels: sites.keys().cloned().collect(),
        positions,
    })
}

/// What a run gives: the mean report, each window's, and each window's mean error per
/// (planner, estimator) over the capacities.
#[derive(Debug, Clone)]
pub struct Outcome {
    /// The loaded protocol.
    pub data: HubbardBrook,
    /// Means over the windows.
    pub mean: Report,
    /// Each window's report.
    pub each: Vec<Report>,
}

/// The planners run, registered one first.
pub const PLANNERS: [Planner; 2] = [Planner::Information, Planner::Count];

/// Runs every window with both planners.
pub fn run(data: HubbardBrook, progress: impl FnMut(usize, usize)) -> Result<Outcome, EvalError> {
    let (mean, each) = run_windows(
        &data.matrix,
        std::slice::from_ref(&data.layout),
        &[],
        &data.protocols,
        &data.capacities,
        &PLANNERS,
        progress,
    )?;
    Ok(Outcome { data, mean, each })
}

/// What `gleaner evaluate peer --on hubbard-brook` (or `hubbard-brook-2`) writes.
#[derive(Debug, Clone, PartialEq)]
pub struct HubbardEvaluation {
    /// `summary.md`: every data set's summary under the registration's heading.
    pub summary: String,
    /// Each data set's outcomes CSV with its file name (the first registration's
    /// `outcomes-shallow.csv`, `outcomes-50cm.csv`; the second's `outcomes-<stem>.csv`).
    pub outcomes: Vec<(String, String)>,
}

/// Loads and runs every data set of `registration` from the Hubbard Brook directory `dir`;
/// `progress(done, total)` after each window of a data set.
pub fn evaluate(
    dir: &Path,
    registration: Registration,
    mut progress: impl FnMut(usize, usize),
) -> Result<HubbardEvaluation, EvalError> {
    let mut summary = crate::peer::summary_heading(registration.title());
    let mut outcomes = Vec::new();
    for series in registration.series() {
        let out = run(load_series(dir, series)?, &mut progress)?;
        summary.push_str(&out.summary());
        summary.push('\n');
        let name = match (registration, series.depth) {
            (Registration::First, Depth::Shallow) => "outcomes-shallow.csv".to_string(),
            (Registration::First, Depth::Cm50) => "outcomes-50cm.csv".to_string(),
            (Registration::Second, _) => format!("outcomes-{}.csv", series.stem()),
        };
        outcomes.push((name, out.mean.outcomes_csv()));
    }
    Ok(HubbardEvaluation { summary, outcomes })
}

/// The mean error of (`planner`, `estimator`) over a report's capacities, unit²; `None` when
/// one is infinite (nothing visited) or there is none.
pub fn mean_over_capacities(r: &Report, planner: Planner, estimator: Estimator) -> Option<f64> {
    let v: Vec<f64> = r
        .outcomes
        .iter()
        .filter(|o| o.planner == planner)
        .filter_map(|o| o.mse.iter().find(|(e, _)| *e == estimator).map(|x| x.1))
        .collect();
    (!v.is_empty() && v.iter().all(|x| x.is_finite()))
        .then(|| v.iter().sum::<f64>() / v.len() as f64)
}

impl Outcome {
    /// Each window's mean over the capacities for `estimator`.
    pub fn window_means(&self, estimator: Estimator) -> Vec<WindowMeans> {
        self.data
            .protocols
            .iter()
            .zip(&self.each)
            .map(|(p, r)| WindowMeans {
                start: self
                    .data
                    .matrix
                    .times
                    .get(p.test.start)
                    .copied()
                    .unwrap_or_default(),
                means: PLANNERS
                    .iter()
                    .map(|&k| (k, mean_over_capacities(r, k, estimator)))
                    .collect(),
            })
            .collect()
    }

    /// The mean over the windows and capacities of a 90% coverage of the unvisited sites'
    /// test values under `planner`'s tours: the calibrated interval's with
    /// `|o| o.coverage90`, the Gaussian one's (`mean ± 1.645·sd`) with
    /// `|o| o.coverage90_gaussian`.
    pub fn coverage(&self, planner: Planner, pick: fn(&crate::peer::Outcome) -> f64) -> f64 {
        crate::peer::mean_coverage(
            self.each.iter().flat_map(|r| r.outcomes.iter()),
            planner,
            pick,
        )
    }

    /// A Markdown summary: the data, per capacity the mean over the windows of each
    /// (planner, estimator), the paired differences `count − information` per estimator,
    /// the coverage, and the registration's verdict.
    pub fn summary(&self) -> String {
        let d = &self.data;
        let mut s = String::new();
        let first = d.matrix.times.first().copied().unwrap_or_default();
        let last = d.matrix.times.last().copied().unwrap_or_default();
        let (scale, unit, short) = d.series.quantity.error_unit();
        let after = d.after.map_or(String::new(), |t| {
            format!(", hours after {}", gleaner_field::time::format_rfc3339(t))
        });
        let _ = writeln!(
            s,
            "### Hubbard Brook, {} {}{after}\n\n{} sites, {} complete hours ({} .. {}), {} windows; every-site tour {:.0} J; capacities {}.{}\n",
            d.series.quantity.name(),
            d.series.depth.name(),
            d.layout.labels.len(),
            d.matrix.times.len(),
            gleaner_field::time::format_rfc3339(first),
            gleaner_field::time::format_rfc3339(last),
            d.protocols.len(),
            d.all_sites_j,
            d.capacities
                .iter()
                .map(|c| format!("{c:.0}"))
                .collect::<Vec<_>>()
                .join(", "),
            if d.missing_loggers.is_empty() {
                String::new()
            } else {
                format!(
                    " Loggers in the metadata without a file: {}.",
                    d.missing_loggers.join(", ")
                )
            }
        );
        let _ = writeln!(
            s,
            "| capacity J | share | visited info / count | information: dynamic | levels | carried | count: dynamic | levels | carried |\n|---:|---:|---|---:|---:|---:|---:|---:|---:|"
        );
        for (k, &cap) in d.capacities.iter().enumerate() {
            let get = |p: Planner| {
                self.mean
                    .outcomes
                    .iter()
                    .find(|o| o.planner == p && o.capacity_j == cap)
            };
            let cells = |p: Planner| -> String {
                let Some(o) = get(p) else {
                    return "– | – | –".into();
                };
                Estimator::ALL
                    .iter()
                    .rev()
                    .map(|&e| {
                        o.mse
                            .iter()
                            .find(|x| x.0 == e)
                            .map_or("–".into(), |x| format!("{:.3}", x.1 * scale))
                    })
                    .collect::<Vec<_>>()
                    .join(" | ")
            };
            let visited = |p: Planner| get(p).map_or(0, |o| o.tour.len());
            let _ = writeln!(
                s,
                "| {cap:.0} | {:.1} | {} / {} | {} | {} |",
                CAPACITY_SHARES[k],
                visited(Planner::Information),
                visited(Planner::Count),
                cells(Planner::Information),
                cells(Planner::Count)
            );
        }
        let _ = writeln!(
            s,
            "\n(mean over the windows of the summed squared error over unvisited sites, {unit}; visited: first window's tours)\n"
        );
        for e in Estimator::ALL.iter().rev() {
            let w = self.window_means(*e);
            match paired_difference(&w, Planner::Count, Planner::Information) {
                Some((m, lo, hi, n)) => {
                    let _ = writeln!(
                        s,
                        "- {}: count − information {:+.3} [{:+.3}, {:+.3}] {} over {n} windows",
                        e.name(),
                        m * scale,
                        lo * scale,
                        hi * scale,
                        short
                    );
                }
                None => {
                    let _ = writeln!(
                        s,
                        "- {}: fewer than two windows with finite means",
                        e.name()
                    );
                }
            }
        }
        // The registered estimator against the others on the registered tours.
        let info = |e: Estimator| -> Vec<Option<f64>> {
            self.window_means(e)
                .iter()
                .map(|w| {
                    w.means
                        .iter()
                        .find(|m| m.0 == Planner::Information)
                        .and_then(|m| m.1)
                })
                .collect()
        };
        let dynamic = info(Estimator::Dynamic);
        for other in [Estimator::Levels, Estimator::Carried] {
            let d: Vec<f64> = info(other)
                .iter()
                .zip(&dynamic)
                .filter_map(|(o, x)| Some((*o)? - (*x)?))
                .collect();
            if let Some((m, lo, hi, n)) = mean_interval(&d) {
                let _ = writeln!(
                    s,
                    "- information's tours: {} − dynamic {:+.3} [{:+.3}, {:+.3}] {} over {n} windows",
                    other.name(),
                    m * scale,
                    lo * scale,
                    hi * scale,
                    short
                );
            }
        }
        let verdict = match paired_difference(
            &self.window_means(Estimator::Dynamic),
            Planner::Count,
            Planner::Information,
        ) {
            Some((_, lo, _, _)) if lo > 0.0 => "supported (the interval lies above 0)",
            Some((_, _, hi, _)) if hi < 0.0 => "contradicted (the interval lies below 0)",
            Some(_) => "inconclusive (the interval contains 0)",
            None => "not decidable (fewer than two windows)",
        };
        let _ = writeln!(
            s,
            "- calibrated 90% intervals (dynamic model, back-test multiplier) cover {:.1}% of the unvisited sites' test values under information's tours, {:.1}% under count's (Gaussian intervals: {:.1}%, {:.1}%)\n- registration: {verdict}",
            100.0 * self.coverage(Planner::Information, |o| o.coverage90),
            100.0 * self.coverage(Planner::Count, |o| o.coverage90),
            100.0 * self.coverage(Planner::Information, |o| o.coverage90_gaussian),
            100.0 * self.coverage(Planner::Count, |o| o.coverage90_gaussian)
        );
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn probe(site: &str, logger: &str, port: &str, depth_cm: u32) -> Probe {
        Probe {
            site: site.into(),
            lat: 43.9,
            lon: -71.7,
            logger: logger.into(),
            port: port.into(),
            depth_cm,
        }
    }

    #[test]
    fn shallow_takes_each_sites_shallowest_probes_and_50_cm_skips_sites_without() {
        let ps = [
            probe("A", "z1", "2", 15),
            probe("A", "z1", "4", 50),
            probe("A", "z1", "5", 50),
            probe("B", "z2", "1", 10),
            probe("B", "z2", "3", 90),
            probe("C", "z3", "1", 15),
            probe("C", "z3", "2", 15),
            probe("C", "z4", "1", 15),
        ];
        let shallow = chosen(&ps, Depth::Shallow);
        assert_eq!(shallow.keys().collect::<Vec<_>>(), ["A", "B", "C"]);
        assert_eq!(shallow["B"][0].depth_cm, 10);
        // A replaced logger's probes join the site's series.
        assert_eq!(shallow["C"].len(), 3);
        let deep = chosen(&ps, Depth::Cm50);
        assert_eq!(deep.keys().collect::<Vec<_>>(), ["A"]);
        assert_eq!(deep["A"].len(), 2);
    }

    #[test]
    fn windows_tile_by_the_test_rows_and_stop_at_the_end() {
        let base = Protocol::peer_hourly(frozen_fit(3_600));
        assert!(tiled_windows(1500, &base).is_empty());
        let w = tiled_windows(2600, &base);
        // Starts 0, 500, 1000 (1000 + 1501 = 2501 <= 2600); 1500 + 1501 > 2600.
        assert_eq!(w.len(), 3);
        assert_eq!(w[0].train, 0..1001);
        assert_eq!(w[0].test, 1001..1501);
        assert_eq!(w[2].train, 1000..2001);
        assert_eq!(w[2].test, 2001..2501);
        for pair in w.windows(2) {
            assert_eq!(pair[0].test.end, pair[1].test.start);
        }
    }

    /// A directory like the network's: site A (logger z1) with a 15 cm probe and two 50 cm
    /// replicates, site B (logger z2, 10 cm, and z3 listed without a file), `hours` hourly
    /// rows; returns the directory.
    /// `tag` keeps the directories of tests running at once apart.
    fn fixture(tag: &str, hours: usize) -> std::path::PathBuf {
        let dir =
            std::env::temp_dir().join(format!("gleaner-hb-{}-{tag}-{hours}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(
            dir.join("sensor_metadata.csv"),
            "\u{feff}siteID,lat,lon,logger,port,meas,depth_cm\n\
             A,43.95,-71.72,z1,2,vwc,15\nA,43.95,-71.72,z1,4,vwc,50\nA,43.95,-71.72,z1,5,vwc,50\n\
             A,43.95,-71.72,z1,1,matric,15\nB,43.96,-71.73,z2,1,vwc,10\nB,43.96,-71.73,z3,1,vwc,10\n",
        )
        .unwrap();
        let mut z1 = String::from(
            "timestamp,p2:TEROS_12:Water_Content:m3_per_m3,p4:TEROS_12:Water_Content:m3_per_m3,p5:TEROS_12:Water_Content:m3_per_m3,p2:TEROS_12:Soil_Temperature:degC\n",
        );
        let mut z2 = String::from(
            "timestamp,p1:TEROS_12:Water_Content:m3_per_m3,p1:TEROS_12:Soil_Temperature:degC\n",
        );
        for h in 0..hours {
            let (day, hour) = (1 + h / 24, h % 24);
            let stamp = format!(
                "2024-{:02}-{:02} {hour:02}:00",
                1 + (day - 1) / 28,
                1 + (day - 1) % 28
            );
            let x = (h as f64 / 50.0).sin() * 0.02;
            // Hour 7 of B is out of range (missing), so that row is not complete.
            let b = if h == 7 { 1.5 } else { 0.25 + x };
            let _ = writeln!(
                z1,
                "{stamp},{},{},{},{}",
                0.30 + x,
                0.20 + x,
                0.40 + x,
                12.0 + 100.0 * x
            );
            let _ = writeln!(z2, "{stamp},{b},{}", 11.0 + 100.0 * x);
        }
        std::fs::write(dir.join("z1.csv"), z1).unwrap();
        std::fs::write(dir.join("z2.csv"), z2).unwrap();
        dir
    }

    #[test]
    fn load_averages_replicates_keeps_complete_hours_and_names_missing_loggers() {
        let dir = fixture("water", 1_600);
        let shallow = load(&dir, Depth::Shallow).unwrap();
        assert_eq!(shallow.layout.labels, ["A", "B"]);
        assert_eq!(shallow.missing_loggers, ["z3"]);
        // Hour 7 is dropped (B out of range): 1,599 complete hours, one window.
        assert_eq!(shallow.matrix.times.len(), 1_599);
        assert_eq!(shallow.protocols.len(), 1);
        assert_eq!(shallow.capacities.len(), CAPACITY_SHARES.len());
        assert!((shallow.capacities[0] - 0.2 * shallow.all_sites_j).abs() < 1e-9);
        let deep = load(&dir, Depth::Cm50).unwrap();
        assert_eq!(deep.layout.labels, ["A"]);
        // The two 50 cm replicates' mean: 0.30 + x.
        let x0 = 0.0;
        assert!(
            (deep.matrix.values[0] - (0.30 + x0)).abs() < 1e-12,
            "{}",
            deep.matrix.values[0]
        );
        let out = run(shallow, |_, _| {}).unwrap();
        let summary = out.summary();
        assert!(
            summary.contains("2 sites, 1599 complete hours"),
            "{summary}"
        );
        assert!(summary.contains("without a file: z3"), "{summary}");
        assert!(
            summary.contains("- registration: not decidable"),
            "{summary}"
        );
        // Too few hours for a window: a clear error.
        let short = fixture("water", 1_000);
        let e = load(&short, Depth::Shallow).unwrap_err().to_string();
        assert!(e.contains("fewer than one window"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
        std::fs::remove_dir_all(&short).unwrap();
    }

    /// Soil temperature comes from the same probes, with its own validity range (B's
    /// out-of-range water content at hour 7 does not remove its temperature).
    #[test]
    fn temperature_is_read_from_the_same_probes() {
        let dir = fixture("temperature", 1_600);
        let t = load_series(
            &dir,
            Series {
                quantity: Quantity::Temperature,
                ..Series::water(Depth::Shallow)
            },
        )
        .unwrap();
        assert_eq!(t.layout.labels, ["A", "B"]);
        assert_eq!(t.matrix.times.len(), 1_600);
        assert!(
            (t.matrix.values[0] - 12.0).abs() < 1e-9,
            "{:?}",
            &t.matrix.values[..2]
        );
        assert!(
            (t.matrix.values[1] - 11.0).abs() < 1e-9,
            "{:?}",
            &t.matrix.values[..2]
        );
        let out = run(t, |_, _| {}).unwrap();
        let summary = out.summary();
        assert!(
            summary.contains("### Hubbard Brook, soil temperature shallow"),
            "{summary}"
        );
        assert!(summary.contains(", °C²;"), "{summary}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// The late rows: after the last complete row, the sites with a value in at least half
    /// of them, their complete rows.
    #[test]
    fn late_rows_follow_the_last_complete_row_with_the_sites_still_reporting() {
        let nan = f64::NAN;
        // Sites A, B, C, D over times 0..10: C stops after 4, D reports at 5 and 6 only
        // (2 of the 5 later rows), B misses time 8.
        let mut values = Vec::new();
        for t in 0..10 {
            let c = if t <= 4 { 3.0 } else { nan };
            let d = if t <= 6 { 4.0 } else { nan };
            let b = if t == 8 { nan } else { 2.0 };
            values.extend_from_slice(&[1.0 + t as f64, b, c, d]);
        }
        let raw = Matrix {
            labels: ["A", "B", "C", "D"].map(String::from).to_vec(),
            times: (0..10).collect(),
            values,
        };
        let (kept, m, cut) = late_rows(&raw).unwrap();
        assert_eq!(cut, 4);
        assert_eq!(kept, [0, 1]);
        assert_eq!(m.labels, ["A", "B"]);
        assert_eq!(m.times, [5, 6, 7, 9]);
        assert_eq!(m.values[..2], [6.0, 2.0]);
        // Nothing after the last complete row: none.
        let complete = Matrix {
            labels: vec!["A".into()],
            times: vec![0, 1],
            values: vec![1.0, 2.0],
        };
        assert!(late_rows(&complete).is_none());
    }

    #[test]
    fn registrations_name_their_data_sets() {
        let first: Vec<String> = Registration::First
            .series()
            .iter()
            .map(|s| s.stem())
            .collect();
        assert_eq!(first, ["water-shallow", "water-50cm"]);
        let second: Vec<String> = Registration::Second
            .series()
            .iter()
            .map(|s| s.stem())
            .collect();
        assert_eq!(
            second,
            [
                "water-late-shallow",
                "water-late-50cm",
                "temperature-shallow",
                "temperature-50cm"
            ]
        );
    }

    #[test]
    fn sites_sit_about_their_centroid() {
        let mut sites = BTreeMap::new();
        let mut a = probe("A", "z1", "1", 15);
        a.lat = 43.95;
        let mut b = probe("B", "z2", "1", 15);
        b.lat = 43.97;
        sites.insert("A".into(), vec![a]);
        sites.insert("B".into(), vec![b]);
        let l = site_layout(&sites).unwrap();
        // 0.02° of latitude ≈ 2,223 m; the centroid halves it.
        assert!(
            (l.positions[0][1] + 1111.6).abs() < 2.0,
            "{:?}",
            l.positions
        );
        assert!(
            (l.positions[1][1] - 1111.6).abs() < 2.0,
            "{:?}",
            l.positions
        );
        assert!(l.positions[0][0].abs() < 1e-6);
    }
}
