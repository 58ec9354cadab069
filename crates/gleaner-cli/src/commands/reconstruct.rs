//! `gleaner reconstruct`: every sensor's estimated value and variance as a table.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use gleaner_app as app;

use crate::args::{ProjectArg, parse_time};
use crate::output::{emit, outln};

use gleaner_app::Estimator;
use gleaner_kriging::Mean;
use gleaner_render::files::{ImageFormat, reconstruction_map_file};
use gleaner_wire::{convert, text};

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
        &convert::reconstruction(&r),
        "reconstruction",
        || text::reconstruction_table(&r),
    )
}

/// `--map`: draws the map into `path`; prints its one-line summary.
fn map(p: &app::Project<app::AnyStore>, args: &ReconstructArgs, path: &Path) -> Result<()> {
    let Some(format) = ImageFormat::of_name(path) else {
        anyhow::bail!(
            "--map {}: the file must end in .svg or .png",
            path.display()
        );
    };
    let m = app::reconstruct_map(
        p,
        &app::ReconstructMapRequest {
            reconstruct: args.request(),
            read_within_s: None,
        },
    )?;
    let bytes = reconstruction_map_file(&convert::reconstruction_map(&m), format)?;
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
        let doc = convert::reconstruction_series(&r);
        println!("{}", serde_json::to_string_pretty(&doc)?);
        return Ok(());
    }
    let csv = text::series_csv(&r);
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
