//! Generates a synthetic farm and writes the project's CSV files into a folder, timing each
//! stage: `cargo run --release -p gleaner-synth --example write_farm -- OUT_DIR [SENSORS] [DAYS]`.
//! Defaults: 10,000 sensors, 365 days, modalities vw@30cm and t@30cm.

use std::fs::File;
use std::io::BufWriter;
use std::path::PathBuf;
use std::time::Instant;

use gleaner_synth::{
    SynthConfig, generate, write_faults_csv, write_ground_truth_csv, write_readings_csv,
    write_sensors_csv,
};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let dir = PathBuf::from(
        args.next()
            .ok_or("usage: write_farm OUT_DIR [SENSORS] [DAYS]")?,
    );
    let sensor_count = args
        .next()
        .map(|s| s.parse())
        .transpose()?
        .unwrap_or(10_000);
    let days = args.next().map(|s| s.parse()).transpose()?.unwrap_or(365);
    std::fs::create_dir_all(&dir)?;
    let config = SynthConfig {
        seed: 42,
        sensor_count,
        days,
        vw_depths_cm: vec![30],
        t_depths_cm: vec![30],
        scale_extent_with_sensors: true,
        ..SynthConfig::default()
    };
    let t0 = Instant::now();
    let farm = generate(&config)?;
    let t1 = Instant::now();
    write_sensors_csv(
        &farm,
        &mut BufWriter::new(File::create(dir.join("sensors.csv"))?),
    )?;
    let mut readings = BufWriter::with_capacity(1 << 20, File::create(dir.join("readings.csv"))?);
    write_readings_csv(&farm, &mut readings)?;
    readings.into_inner()?.sync_all()?;
    write_ground_truth_csv(&farm, &mut File::create(dir.join("ground_truth.csv"))?)?;
    write_faults_csv(&farm, &mut File::create(dir.join("faults.csv"))?)?;
    let t2 = Instant::now();
    let bytes = std::fs::metadata(dir.join("readings.csv"))?.len();
    println!(
        "{} sensors x {} days: {} readings, generate {:.2} s, write {:.2} s ({:.0} MB readings.csv), total {:.2} s",
        sensor_count,
        days,
        farm.reading_count(),
        (t1 - t0).as_secs_f64(),
        (t2 - t1).as_secs_f64(),
        bytes as f64 / 1e6,
        (t2 - t0).as_secs_f64()
    );
    Ok(())
}
