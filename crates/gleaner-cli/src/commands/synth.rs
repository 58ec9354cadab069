//! `gleaner synth`: writes a seeded synthetic farm in the generic format.

use std::path::PathBuf;

use anyhow::{Context, Result};
use gleaner_synth::{FaultRates, SynthConfig, generate, write_farm_files};

// The arguments of `gleaner synth` (no doc comment: the variant's is the help). Everything
// else takes `SynthConfig`'s defaults, which are calibrated to the CAF network.
#[derive(clap::Args)]
pub struct SynthArgs {
    /// Output directory (sensors.csv, readings.csv, ground_truth.csv, faults.csv).
    #[arg(long)]
    pub out: PathBuf,
    /// Seed: the same seed gives byte-identical files.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Number of sensor stations.
    #[arg(long, default_value_t = 42)]
    pub sensors: usize,
    /// Days of record.
    #[arg(long, default_value_t = 365)]
    pub days: u32,
    /// Sampling interval, seconds (a divisor of 86400).
    #[arg(long, default_value_t = 86_400)]
    pub interval_s: i64,
    /// Number of localised ground-truth events (leak, drying patch, failing sensor; each
    /// lasts 7-28 days).
    #[arg(long, default_value_t = SynthConfig::default().event_count)]
    pub events: usize,
    /// Correlation length of the spatial fields, metres.
    #[arg(long = "correlation-length", default_value_t = 500.0)]
    pub correlation_length_m: f64,
    /// No sensor faults (dropouts, spikes, stuck values).
    #[arg(long)]
    pub no_faults: bool,
    /// Grow the field with the sensor count to keep CAF's sensor density.
    #[arg(long)]
    pub scale_extent: bool,
    /// Soil-moisture depths, cm, comma-separated (modalities vw@<d>cm); empty ('') for none.
    #[arg(long = "vw-depths", value_parser = parse_depths, default_value = "30,60,90")]
    pub vw_depths_cm: Depths,
    /// Soil-temperature depths, cm, comma-separated (modalities t@<d>cm); empty ('') for none.
    #[arg(long = "t-depths", value_parser = parse_depths, default_value = "30")]
    pub t_depths_cm: Depths,
    /// Lay the farm on a real network's stations: a sensors file as `init` reads it (id and
    /// lat/lon, or UTM easting/northing with --utm-zone); its ids and positions replace the
    /// jittered grid and --sensors.
    #[arg(long)]
    pub layout: Option<PathBuf>,
    /// UTM zone of --layout's coordinates (e.g. 11N for CAF's own sensors file).
    #[arg(long, requires = "layout")]
    pub utm_zone: Option<String>,
}

/// A list of depths, cm (`--vw-depths`, `--t-depths`): possibly empty.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Depths(pub Vec<u32>);

/// `30,60,90` -> [30, 60, 90]; an empty (or blank) list means no depth.
fn parse_depths(s: &str) -> Result<Depths, String> {
    if s.trim().is_empty() {
        return Ok(Depths(Vec::new()));
    }
    s.split(',')
        .map(|d| {
            d.trim().parse::<u32>().map_err(|_| {
                let d: String = d.chars().take(20).collect();
                format!("depth {d:?}: expected whole centimetres, e.g. 30,60,90 (or '' for none)")
            })
        })
        .collect::<Result<_, _>>()
        .map(Depths)
}

/// The core configuration for these settings.
pub fn config(args: &SynthArgs) -> SynthConfig {
    SynthConfig {
        seed: args.seed,
        sensor_count: args.sensors,
        days: args.days,
        interval_s: args.interval_s,
        event_count: args.events,
        correlation_length_m: args.correlation_length_m,
        faults: if args.no_faults {
            FaultRates::none()
        } else {
            FaultRates::default()
        },
        scale_extent_with_sensors: args.scale_extent,
        vw_depths_cm: args.vw_depths_cm.0.clone(),
        t_depths_cm: args.t_depths_cm.0.clone(),
        ..SynthConfig::default()
    }
}

/// Generates the farm and writes its four files (`gleaner_synth::write_farm_files`); returns
/// the summary line.
pub fn run(args: &SynthArgs) -> Result<String> {
    let mut config = config(args);
    if let Some(path) = &args.layout {
        let sensors = gleaner_app::read_sensors_file(path, args.utm_zone.as_deref())?;
        config = config
            .on_layout(sensors.into_iter().map(|s| (s.id, s.position)).collect())
            .with_context(|| format!("{}: cannot lay a farm on it", path.display()))?;
    }
    let farm = generate(&config).context("invalid synthetic farm settings")?;
    write_farm_files(&farm, &args.out)?;
    Ok(format!(
        "wrote {} sensors, {} readings, {} events to {}",
        farm.sensors().len(),
        farm.reading_count(),
        farm.events().len(),
        args.out.display()
    ))
}
