//! `gleaner synth`: writes a seeded synthetic farm in the generic format.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use gleaner_synth::{
    FaultRates, SynthConfig, SynthFarm, generate, write_faults_csv, write_ground_truth_csv,
    write_readings_csv, write_sensors_csv,
};

/// The files `synth` writes, inside the output directory.
pub struct SynthFiles {
    /// `sensors.csv`: `id,lat,lon,elevation_m`.
    pub sensors: PathBuf,
    /// `readings.csv`: the long readings format.
    pub readings: PathBuf,
    /// `ground_truth.csv`: the localised events.
    pub ground_truth: PathBuf,
    /// `faults.csv`: injected sensor faults.
    pub faults: PathBuf,
}

impl SynthFiles {
    /// The file names inside `dir`.
    pub fn in_dir(dir: &Path) -> Self {
        Self {
            sensors: dir.join("sensors.csv"),
            readings: dir.join("readings.csv"),
            ground_truth: dir.join("ground_truth.csv"),
            faults: dir.join("faults.csv"),
        }
    }
}

/// Settings from the command line (everything else takes [`SynthConfig`]'s defaults, which are
/// calibrated to the CAF network).
pub struct SynthArgs {
    /// Output directory.
    pub out: PathBuf,
    /// Seed.
    pub seed: u64,
    /// Number of sensors.
    pub sensors: usize,
    /// Number of days.
    pub days: u32,
    /// Sampling interval, seconds.
    pub interval_s: i64,
    /// Number of ground-truth events.
    pub events: usize,
    /// Spatial correlation length, metres.
    pub correlation_length_m: f64,
    /// Turn off sensor faults.
    pub no_faults: bool,
    /// Keep CAF's sensor density by growing the field with the sensor count.
    pub scale_extent: bool,
    /// Depths of the soil-moisture modalities `vw@<d>cm`, centimetres.
    pub vw_depths_cm: Vec<u32>,
    /// Depths of the soil-temperature modalities `t@<d>cm`, centimetres.
    pub t_depths_cm: Vec<u32>,
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
        vw_depths_cm: args.vw_depths_cm.clone(),
        t_depths_cm: args.t_depths_cm.clone(),
        ..SynthConfig::default()
    }
}

fn write_file(
    path: &Path,
    f: impl FnOnce(&mut BufWriter<File>) -> std::io::Result<()>,
) -> Result<()> {
    let file = File::create(path).with_context(|| format!("{}: cannot create", path.display()))?;
    let mut w = BufWriter::with_capacity(1 << 20, file);
    f(&mut w)
        .and_then(|()| w.flush())
        .with_context(|| format!("{}: cannot write", path.display()))
}

/// Generates the farm and writes its four files; returns the farm and the file names.
pub fn run(args: &SynthArgs) -> Result<(SynthFarm, SynthFiles)> {
    let farm = generate(&config(args)).context("invalid synthetic farm settings")?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("{}: cannot create", args.out.display()))?;
    let files = SynthFiles::in_dir(&args.out);
    write_file(&files.sensors, |w| write_sensors_csv(&farm, w))?;
    write_file(&files.readings, |w| write_readings_csv(&farm, w))?;
    write_file(&files.ground_truth, |w| write_ground_truth_csv(&farm, w))?;
    write_file(&files.faults, |w| write_faults_csv(&farm, w))?;
    Ok((farm, files))
}
