//! `gleaner reconstruct`: every sensor's estimated value and variance as a table.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use gleaner_app as app;

use crate::{ProjectArg, emit, outln, parse_time};

use gleaner_app::{Estimator, Reconstruction, ReconstructionSeries, format_rfc3339};
use gleaner_kriging::Mean;

/// The reconstruction as a text table (values in the modality's unit, sd its square root).
pub fn table(r: &Reconstruction) -> String {
    let mut out = String::new();
    let c = r.model.covariance;
    let _ = writeln!(
        out,
        "{} at {}: field model sill {:.3e}, nugget {:.3e}, range {:.0} m, time scale {:.1} d",
        r.modality,
        format_rfc3339(r.at),
        c.sill,
        c.nugget,
        c.range_m,
        c.time_scale_s / 86_400.0
    );
    let m = r.changes;
    let _ = writeln!(
        out,
        "model of changes: shared variogram {:.3e} + {:.3e}·(1 − exp(−h/{:.1} d)), range {:.0} m; \
         own {:.3e} + {:.3e}·(1 − exp(−h/{:.1} d))",
        m.shared.nugget,
        m.shared.partial,
        m.shared.scale_s / 86_400.0,
        m.range_m,
        m.own.nugget,
        m.own.partial,
        m.own.scale_s / 86_400.0
    );
    let _ = writeln!(
        out,
        "estimate (\"kriged\"): {}",
        match r.estimator {
            Estimator::Changes => "kriging of changes (last value + neighbours' known changes)",
            Estimator::Levels(Mean::Unknown) => "ordinary kriging of levels",
            Estimator::Levels(Mean::Known) => "simple kriging of levels",
            Estimator::Dynamic =>
                "dynamic field model (learned covariance of levels, AR(1) dynamics, Kalman filter)",
        }
    );
    let _ = writeln!(
        out,
        "{:<16} {:<21} {:>10} {:>10} {:>10}",
        "sensor", "last reading", "carried", "kriged", "sd"
    );
    for s in &r.sensors {
        let _ = writeln!(
            out,
            "{:<16} {:<21} {:>10.4} {:>10.4} {:>10.4}",
            s.sensor.as_str(),
            s.last_time.map_or("never".into(), format_rfc3339),
            s.carried,
            s.kriged,
            s.variance.sqrt()
        );
    }
    out
}

/// A range reconstruction as CSV: `time,sensor,mean,sd,lo90,hi90` (RFC 3339 times; the
/// modality's unit), one row per time and sensor.
pub fn series_csv(r: &ReconstructionSeries) -> String {
    let mut out = String::from("time,sensor,mean,sd,lo90,hi90\n");
    let n = r.sensors.len();
    for (t, &time) in r.times.iter().enumerate() {
        let stamp = format_rfc3339(time);
        for (s, (id, _)) in r.sensors.iter().enumerate() {
            let k = t * n + s;
            let (lo, hi) = r.interval90(t, s);
            let _ = writeln!(
                out,
                "{stamp},{},{:.6},{:.6},{:.6},{:.6}",
                id.as_str(),
                r.mean[k],
                r.variance[k].sqrt(),
                lo,
                hi
            );
        }
    }
    out
}

/// What `--map` writes, by the file's extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MapFile {
    /// `.svg`: the figure as SVG text.
    Svg,
    /// `.png`: the figure rasterised at 300 dpi.
    Png,
}

impl MapFile {
    /// The kind of `path` (`.svg` or `.png`, in any case).
    pub fn of(path: &std::path::Path) -> anyhow::Result<Self> {
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref()
        {
            Some("svg") => Ok(Self::Svg),
            Some("png") => Ok(Self::Png),
            _ => anyhow::bail!(
                "--map {}: the file must end in .svg or .png",
                path.display()
            ),
        }
    }
}

/// The map's PNG resolution, dots per inch.
pub const MAP_PNG_DPI: f64 = 300.0;

/// The reconstruction map as the file's bytes.
pub fn map_file(
    doc: &gleaner_wire::docs::ReconstructionMapDoc,
    kind: MapFile,
) -> anyhow::Result<Vec<u8>> {
    let opts = gleaner_render::FigureOptions {
        width_mm: gleaner_render::FULL_WIDTH_MM,
        ..Default::default()
    };
    let svg = gleaner_render::reconstruction_map_svg(doc, &opts)?;
    Ok(match kind {
        MapFile::Svg => svg.into_bytes(),
        MapFile::Png => gleaner_render::svg_to_png(
            &svg,
            gleaner_render::png_width_px(gleaner_render::FULL_WIDTH_MM, MAP_PNG_DPI),
        )?,
    })
}

// The arguments of `gleaner reconstruct` (no doc comment: the variant's is the help).
#[derive(clap::Args)]
pub struct ReconstructArgs {
    #[command(flatten)]
    pub project: ProjectArg,
    /// Estimation time (RFC 3339 or date) [default: the latest reading].
    #[arg(long, value_parser = parse_time)]
    pub at: Option<i64>,
    /// Modality [default: vw@30cm, else the first vw@...].
    #[arg(long)]
    pub modality: Option<String>,
    /// Observations per estimate.
    #[arg(long, default_value_t = app::DEFAULT_NEIGHBOURS)]
    pub neighbours: usize,
    /// Simple kriging of levels towards each sensor's long-run mean instead of kriging
    /// of changes.
    #[arg(long, conflicts_with = "levels")]
    pub simple: bool,
    /// Ordinary kriging of levels (from every sensor's latest reading) instead of kriging
    /// of changes.
    #[arg(long, conflicts_with = "simple")]
    pub levels: bool,
    /// The dynamic field model (a learned, shrunk covariance of levels between sensors
    /// with AR(1) dynamics, a Kalman filter over the readings known) instead of kriging
    /// of changes.
    #[arg(long, conflicts_with_all = ["simple", "levels"])]
    pub dynamic: bool,
    /// Reconstruct over a range instead of at one time: the first estimation time
    /// (RFC 3339 or date; needs --to).
    #[arg(long, value_parser = parse_time, requires = "to", conflicts_with_all = ["at", "map"])]
    pub from: Option<i64>,
    /// The range's last estimation time (RFC 3339 or date).
    #[arg(long, value_parser = parse_time, requires = "from")]
    pub to: Option<i64>,
    /// Spacing of the range's estimation times, hours.
    #[arg(long, default_value_t = 24.0, requires = "from")]
    pub every_hours: f64,
    /// Write the range's CSV (time, sensor, mean, sd, lo90, hi90) to this file instead of
    /// standard output (`-`: standard output).
    #[arg(long, requires = "from")]
    pub out: Option<PathBuf>,
    /// Print the `gleaner.reconstruction` JSON document (as `GET /api/v1/reconstruct`)
    /// instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Draw the map of the estimate and its uncertainty at --at into this file: SVG or
    /// PNG by its extension (`.svg`, `.png`).
    #[arg(long, value_name = "FILE", conflicts_with = "json")]
    pub map: Option<PathBuf>,
}

impl ReconstructArgs {
    fn estimator(&self) -> Estimator {
        if self.dynamic {
            Estimator::Dynamic
        } else if self.simple {
            Estimator::Levels(Mean::Known)
        } else if self.levels {
            Estimator::Levels(Mean::Unknown)
        } else {
            Estimator::Changes
        }
    }

    fn request(&self) -> app::ReconstructRequest {
        app::ReconstructRequest {
            at: self.at,
            modality: self.modality.clone(),
            neighbours: Some(self.neighbours),
            estimator: self.estimator(),
        }
    }
}

/// Reconstructs at one time (a table, JSON or a map) or over a range (CSV or JSON).
pub fn run(args: ReconstructArgs) -> Result<()> {
    let p = args.project.open()?;
    if let Some(path) = &args.map {
        return map(&p, &args, path);
    }
    if let (Some(from), Some(to)) = (args.from, args.to) {
        return series(&p, &args, from, to);
    }
    let r = app::reconstruct(&p, &args.request())?;
    emit(
        args.json,
        &gleaner_wire::convert::reconstruction(&r),
        "reconstruction",
        || table(&r),
    )
}

/// `--map`: draws the map into `path`; prints its one-line summary.
fn map(p: &app::Project<app::AnyStore>, args: &ReconstructArgs, path: &Path) -> Result<()> {
    let kind = MapFile::of(path)?;
    let m = app::reconstruct_map(
        p,
        &app::ReconstructMapRequest {
            reconstruct: args.request(),
            read_within_s: None,
        },
    )?;
    let bytes = map_file(&gleaner_wire::convert::reconstruction_map(&m), kind)?;
    std::fs::write(path, bytes).with_context(|| format!("cannot write {}", path.display()))?;
    outln(&format!(
        "{}: {} at {} ({}), {} cells, {} of {} sensors read within {} s",
        path.display(),
        m.reconstruction.modality,
        app::format_rfc3339(m.reconstruction.at),
        m.reconstruction.estimator.name(),
        m.cells.len(),
        m.read.iter().filter(|&&r| r).count(),
        m.read.len(),
        m.read_within_s
    ))
}

/// `--from`/`--to`: the range as CSV (to `--out` or standard output) or JSON.
fn series(
    p: &app::Project<app::AnyStore>,
    args: &ReconstructArgs,
    from: i64,
    to: i64,
) -> Result<()> {
    let every_hours = args.every_hours;
    if !(every_hours.is_finite() && every_hours > 0.0 && every_hours <= 24.0 * 3660.0) {
        anyhow::bail!("--every-hours must be a positive number of hours (at most 10 years)");
    }
    let r = app::reconstruct_series(
        p,
        &app::ReconstructSeriesRequest {
            from,
            to,
            every_s: ((every_hours * 3600.0).round() as i64).max(1),
            modality: args.modality.clone(),
            estimator: args.estimator(),
            neighbours: Some(args.neighbours),
            cell: None,
        },
    )?;
    if args.json {
        let doc = gleaner_wire::convert::reconstruction_series(&r);
        println!("{}", serde_json::to_string_pretty(&doc)?);
        return Ok(());
    }
    let csv = series_csv(&r);
    match args.out.as_deref() {
        Some(path) if path != Path::new("-") => {
            std::fs::write(path, csv)
                .with_context(|| format!("cannot write {}", path.display()))?;
            println!(
                "{}: {} times × {} sensors",
                path.display(),
                r.times.len(),
                r.sensors.len()
            );
        }
        _ => print!("{csv}"),
    }
    Ok(())
}
