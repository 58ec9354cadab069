//! placeholder docs
#![deny(missing_docs)]

mod calibration;
mod config;
mod error;
mod farm;
mod model;
mod random;
mod time;
mod write;

pub use calibration::{DailyPanel, DistanceBin, PanelStats, StatsOptions, panel_stats};
pub use config::{CAF_SENSOR_COUNT, Climate, DEFAULT_START, FaultRates, SynthConfig};
pub use error::SynthError;
pub use farm::{
    EventKind, FaultKind, FaultRecord, GroundTruthEvent, ModalitySpec, Reading, SynthFarm,
};
pub use model::generate;
pub use write::{
    FAULTS_HEADER, GROUND_TRUTH_HEADER, READINGS_HEADER, SENSORS_HEADER, push_fixed,
    write_faults_csv, write_ground_truth_csv, write_readings_csv, write_sensors_csv,
};
