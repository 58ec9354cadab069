//! Readers for sensor files, for gleaner.
//!
//! Every reader turns one file into [`Readings`] (a columnar batch: sensor and modality tables
//! plus rows of `(sensor, modality, time, value)`) or [`SensorInput`]s, and reports what it did in
//! an [`IngestReport`]. Formats:
//!
//! - [`read_sensors_csv`]: a sensors table (`id, lat, lon[, elevation_m]`, or projected
//!   `easting, northing` with a UTM zone) — gleaner's generic sensors file and CAF's
//!   `CAF_sensor_locations.csv` alike.
//! - [`read_long_csv`]: gleaner's generic long readings file
//!   (`sensor_id, timestamp, modality, value[, unit]`).
//! - [`read_wide_csv`]: any wide table with time columns and one column per sensor (the CAF
//!   hourly file is one).
//! - [`read_caf_daily`]: the CAF daily files (tab-separated, `Location, Date, VW_30cm, ...`).
//! - [`read_hubbard_brook_sensors`] / [`read_hubbard_brook_logger`]: the Hubbard Brook soil
//!   moisture network's probe metadata and logger files.
//!
//! Bad input is an [`IngestError`] naming the file, the line, the column and the offending value.
//! With [`OnError::Skip`] bad rows are skipped and counted instead, except for structural
//! problems (unreadable or empty file, missing column) which always fail. Within a file, an
//! identical duplicate row is dropped and counted; a conflicting duplicate (same sensor,
//! modality and time, different value) is an error (or, when skipping, the later row is skipped).
//!
//! ```
//! use gleaner_ingest::{read_long_csv, IngestOptions};
//! let dir = tempfile::tempdir().unwrap();
//! let path = dir.path().join("readings.csv");
//! std::fs::write(&path, "sensor_id,timestamp,modality,value,unit\n\
//!     s1,2014-01-01T00:00:00Z,vw@30cm,0.31,m3/m3\n").unwrap();
//! let (readings, report) = read_long_csv(&path, &IngestOptions::default()).unwrap();
//! assert_eq!(readings.rows.len(), 1);
//! assert_eq!(report.skipped, 0);
//! ```
#![deny(missing_docs)]

mod error;
mod hubbard_brook;
pub mod limits;
mod readers;
mod readings;
pub mod time;

pub use error::{IngestError, Problem, SHOWN_CHARS, number, quoted, shorten};
pub use hubbard_brook::{
    HUBBARD_BROOK_UTC_OFFSET_S, HubbardBrookMetadata, hubbard_brook_main_water_depth,
    read_hubbard_brook_logger, read_hubbard_brook_sensors,
};
pub use readers::{
    STDIN_NOT_READ, SensorInput, SensorsOptions, WideOptions, is_stdin, read_caf_daily,
    read_long_csv, read_sensors_csv, read_wide_csv,
};
pub use readings::{IngestOptions, IngestReport, ModalityInfo, OnError, Readings, Row, SkippedRow};

/// The unit gleaner assumes for a quantity when a file does not say: `m3/m3` for volumetric
/// water content (`vw`), `degC` for soil temperature (`t`), none otherwise.
pub fn default_unit(quantity: &str) -> Option<&'static str> {
    match quantity {
        "vw" => Some("m3/m3"),
        "t" => Some("degC"),
        _ => None,
    }
}
