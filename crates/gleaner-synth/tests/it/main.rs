//! Integration tests of gleaner-synth (one binary; this file only declares modules).

#[path = "../common/caf.rs"]
mod caf;

mod calibration;
mod determinism;
mod events;
mod faults;
mod shape;
mod snapshot;
mod spatial;

use gleaner_synth::{
    SynthConfig, SynthFarm, write_faults_csv, write_ground_truth_csv, write_readings_csv,
    write_sensors_csv,
};

/// All four CSV files of a farm, as text.
pub fn all_csv(farm: &SynthFarm) -> [String; 4] {
    let mut files: [Vec<u8>; 4] = Default::default();
    write_sensors_csv(farm, &mut files[0]).unwrap();
    write_readings_csv(farm, &mut files[1]).unwrap();
    write_ground_truth_csv(farm, &mut files[2]).unwrap();
    write_faults_csv(farm, &mut files[3]).unwrap();
    files.map(|f| String::from_utf8(f).unwrap())
}

/// A small farm configuration for fast tests.
pub fn small(seed: u64, sensors: usize, days: u32) -> SynthConfig {
    SynthConfig {
        seed,
        sensor_count: sensors,
        days,
        ..SynthConfig::default()
    }
}
