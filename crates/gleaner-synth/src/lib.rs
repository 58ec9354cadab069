//! A built-in, seeded synthetic farm for gleaner: sensors, soil-moisture and soil-temperature
//! readings with storms, drying, spatial correlation, faults and localised events whose ground
//! truth is known — so campaigns, tests and the demo need no data files.
//!
//! - [`SynthConfig`] holds every setting (plain public fields with units, CAF-like defaults);
//!   [`generate`] turns it into a [`SynthFarm`]: the [`gleaner_field::Sensor`]s, every
//!   [`Reading`] (dense in memory, iterable), the [`GroundTruthEvent`]s (irrigation leak,
//!   drying patch, failing sensor) and the random [`FaultRecord`]s (dropout, spike, stuck).
//! - Writers take any `&mut impl std::io::Write`: [`write_sensors_csv`] (`id,lat,lon,elevation_m`),
//!   [`write_readings_csv`] (long format `sensor_id,timestamp,modality,value,unit`, RFC 3339
//!   UTC timestamps, units `m3/m3` and `degC`, missing readings are absent rows),
//!   [`write_ground_truth_csv`] and [`write_faults_csv`].
//! - [`panel_stats`] summarises any daily sensor panel (CAF or synthetic) the same way: it is
//!   how the defaults were calibrated (see "Calibration").
//!
//! ```
//! use gleaner_synth::{SynthConfig, generate, write_readings_csv};
//! let config = SynthConfig { seed: 7, sensor_count: 20, days: 10, ..Default::default() };
//! let farm = generate(&config)?;
//! assert_eq!(farm.sensors().len(), 20);
//! assert_eq!(farm.modalities()[0].modality.as_str(), "vw@30cm");
//! let vw = farm.value(0, 0, 0).expect("first reading present");
//! assert!((0.0..=0.6).contains(&vw)); // m³/m³
//! let mut csv = Vec::new();
//! write_readings_csv(&farm, &mut csv)?;
//! let text = String::from_utf8(csv).unwrap();
//! assert!(text.starts_with("sensor_id,timestamp,modality,value,unit\nSYN00001,2014-01-01T00:00:00Z,vw@30cm,"));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! # Determinism
//!
//! Every random choice comes from ChaCha8 streams keyed by [`SynthConfig::seed`] and a domain
//! (layout, spatial fields, weather, events, per-sensor dynamics and faults); per-sensor work
//! uses the stream numbered by the sensor's index. Generation and CSV formatting run in
//! parallel over sensors (rayon) but the output is byte-identical whatever the thread count.
//! Events draw from their own stream, so a farm with `event_count = 0` is the exact
//! event-free counterfactual of the same seed (the integration tests use this).
//!
//! # Model
//!
//! Time runs on the sampling grid (`interval_s`, default daily); `doy` is the day of year.
//! Sensors sit on a jittered grid over the field rectangle (±40 % of the spacing).
//!
//! **Spatial fields.** Soil texture and sensor offsets vary smoothly: each is a unit-variance
//! Gaussian random field with covariance `exp(-r² / (2 l²))`, `l` =
//! [`SynthConfig::correlation_length_m`], approximated by 48 random Fourier features (O(1) per
//! sensor, so O(N) overall). A sensor parameter is `sqrt(0.7) x field + sqrt(0.3) x nugget`.
//!
//! **Soil water** at each depth `d` (cm), per sensor:
//! - storms are a Poisson process, rate `storms_per_year / 365.25 x (1 + a cos(2 pi (doy -
//!   peak) / 365.25))` (wet Palouse winters, dry summers), exponential depths (mean 7 mm); each
//!   sensor catches a log-normal share of each storm (sd 0.8 in log space);
//! - rain reaches depth `d` through a first-order filter with time constant 1.2, 2, 3, 5, 8
//!   days at 30, 60, 90, 120, 150 cm (lag and damping with depth);
//! - storage `S` gains `gain x inflow` and decays as `exp(-k x ET(doy) x dt)`, where `ET` rises
//!   from 0.08 in mid-January to 1 in mid-July, `k` is the layer's drying rate (log-normal per
//!   sensor, spatially correlated), and `S <= 3` (drainage above field capacity);
//! - `VW = wilt + range x (1 - exp(-S)) + moving anomaly + own anomaly + noise`: an exponential
//!   drying curve towards a sensor-specific wilting baseline `wilt` (spatially correlated);
//!   the moving anomaly is four smooth latent processes (time constant 60 days) loaded through
//!   spatial fields (it makes correlation decay with distance), the own anomaly a smooth
//!   per-sensor process, the noise white (0.0004 m³/m³);
//! - values are clamped to [0.01, 0.58] m³/m³.
//!
//! **Soil temperature** at depth `z` (cm): `T = mean + offset + amp x A0 exp(-z / D) cos(2 pi
//! (doy - warmest) / 365.25 - z / D) + daily wave + weather + noise`, with the daily wave
//! damped and lagged by the daily damping depth `D / sqrt(365.25)` (visible only with
//! sub-daily sampling near the surface), a shared AR(1) weather anomaly (2.2 °C, day-to-day
//! correlation 0.8) low-pass filtered (time constant `0.5 + (z / 25)²` days) and damped
//! (`exp(-z / 70)`) with depth, per-sensor offsets (1.0 °C, spatially correlated) and amplitude
//! factors (4 %); below 1 °C excursions are damped to 30 % (latent heat and snow cover keep the
//! soil near 0 °C). Clamped to [-30, 50] °C.
//!
//! **Events** (ground truth in [`SynthFarm::events`]; kinds cycle leak, dry patch, failing
//! sensor): each starts between 10 % and 60 % of the record and lasts 10-30 % of it. A leak
//! pulls VW at every depth in a disc towards `wilt + 1.2 range` (above field capacity), with the
//! layer's lag, tapered from 1 at the centre to 0.5 at the rim, fading over ~10 days after the
//! end; a dry patch pulls VW towards the wilting baseline (80 %), triples drying and cuts rain
//! by 80 %; a failing sensor drifts (±0.002-0.004 m³/m³ and ±0.02-0.05 °C per day) or freezes,
//! then falls silent at the end. Disc radius: [`SynthConfig::event_radius_m`] or 1.5 x the
//! mean sensor spacing (at least 30 m); the disc is centred near a random sensor, so it always
//! contains one.
//!
//! **Faults** ([`FaultRates`], recorded in [`SynthFarm::faults`]): station dropouts (all
//! modalities missing for a geometric number of steps), single-reading spikes (0.05-0.15
//! m³/m³ or 3-8 °C) and stuck stretches (a modality repeats its last value).
//!
//! # Calibration
//!
//! The defaults were tuned so that the default farm (42 sensors on 870 x 520 m, three years from
//! 2014-01-01, daily) reproduces the Cook Agronomy Farm daily record (Gasch & Brown 2017,
//! doi:10.15482/USDA.ADC/1349683; 42 stations, 2007-04-20 .. 2016-06-16, about 46 % missing).
//! Both are summarised by [`panel_stats`] with [`StatsOptions::default`]: all present values
//! pooled over sensors and days (mean, sd, 1st/99th percentiles); the spread of per-sensor means
//! ("between") and the mean per-sensor sd ("within"); day-to-day changes between consecutive
//! present days (sd "dsd", fraction above 0.02 m³/m³ or 1 °C "big"); and the mean Pearson
//! correlation of pairs of sensors' series over their common days (at least 30) in distance
//! bins 0-100, 100-200, 200-300, 300-450, 450+ m (CAF positions from the UTM coordinates).
//! Synthetic numbers are the average over seeds 1-8
//! (`cargo run --release -p gleaner-synth --example calibrate` prints this table):
//!
//! | modality | source | mean | sd | p01 | p99 | between | within | dsd | big | corr 0-100 m | corr 450+ m |
//! |---|---|---|---|---|---|---|---|---|---|---|---|
//! | vw@30cm | CAF   | 0.260 | 0.075 | 0.115 | 0.458 | 0.035 | 0.063 | 0.0081 | 2.5 % | 0.77 | 0.74 |
//! | vw@30cm | synth | 0.265 | 0.075 | 0.111 | 0.410 | 0.034 | 0.067 | 0.0073 | 1.8 % | 0.81 | 0.74 |
//! | vw@60cm | CAF   | 0.290 | 0.092 | 0.123 | 0.506 | 0.052 | 0.074 | 0.0076 | 1.4 % | 0.75 | 0.69 |
//! | vw@60cm | synth | 0.295 | 0.090 | 0.103 | 0.481 | 0.047 | 0.077 | 0.0063 | 1.5 % | 0.77 | 0.67 |
//! | vw@90cm | CAF   | 0.307 | 0.097 | 0.111 | 0.491 | 0.058 | 0.073 | 0.0075 | 1.0 % | 0.67 | 0.57 |
//! | vw@90cm | synth | 0.310 | 0.091 | 0.114 | 0.505 | 0.049 | 0.076 | 0.0050 | 0.9 % | 0.70 | 0.61 |
//! | t@30cm  | CAF   | 10.21 | 6.72 | 0.87 | 22.68 | 0.71 | 6.68 | 0.454 | 4.3 % | 0.99 | 0.98 |
//! | t@30cm  | synth | 9.80  | 6.66 | 0.29 | 20.95 | 0.67 | 6.63 | 0.397 | 1.3 % | 0.99 | 0.99 |
//! | t@60cm  | CAF   | 10.07 | 5.44 | 2.15 | 20.20 | 0.79 | 5.37 | 0.198 | 0.08 % | 0.99 | 0.98 |
//! | t@60cm  | synth | 9.99  | 5.61 | 1.28 | 18.98 | 0.69 | 5.57 | 0.167 | 0.04 % | 0.99 | 0.99 |
//! | t@90cm  | CAF   | 9.88  | 4.63 | 3.00 | 18.80 | 0.79 | 4.55 | 0.120 | 0.01 % | 0.99 | 0.98 |
//! | t@90cm  | synth | 10.00 | 4.68 | 2.55 | 17.46 | 0.68 | 4.64 | 0.131 | 0.04 % | 0.99 | 0.99 |
//!
//! VW in m³/m³, T in °C. The 99th percentile of day-to-day change magnitudes also matches
//! (CAF 0.034 / 0.026 / 0.020 m³/m³ at 30 / 60 / 90 cm, synthetic 0.031 / 0.025 / 0.019).
//! Known gaps: synthetic day-to-day changes are more alike between sensors than CAF's
//! (correlation of daily changes 0.5-0.6 against CAF's 0.15-0.43: CAF's small changes are
//! dominated by sensor-specific noise at its 0.001 m³/m³ resolution), and single years vary:
//! the sd of VW at 30 cm ranges 0.075-0.105 over seeds 1-8. The integration test
//! `tests/it/calibration.rs` recomputes the CAF statistics from the shared data
//! (`GLEANER_DATA_DIR`, default `../shared/data` beside the workspace) and asserts, for seeds 1
//! and 2, mean within 0.03 m³/m³ (1 °C), sd ratio within 0.8-1.25 (0.85-1.15 for T), dsd and
//! between-sensor sd ratios within 0.6-1.6, big-jump fraction ratio within 0.5-2 (VW), and
//! correlation under 100 m within 0.12 (0.03 for T), not increasing with distance.
//!
//! # Speed
//!
//! 10,000 sensors x 365 days x 2 modalities (7.3 M nominal readings) on two shared cores:
//! generation about 1.1 s and CSV formatting about 0.4 s (criterion medians,
//! `benches/generate.rs`); end to end to a real file, 358 MB of readings written and synced,
//! 2.4-4.2 s (`examples/write_farm.rs`). The target is 10 s.
#![deny(missing_docs)]

mod calibration;
mod config;
mod error;
mod farm;
mod model;
mod random;
mod write;

pub use calibration::{DailyPanel, DistanceBin, PanelStats, StatsOptions, panel_stats};
pub use config::{CAF_SENSOR_COUNT, Climate, DEFAULT_START, FaultRates, MAX_VALUES, SynthConfig};
pub use error::SynthError;
pub use farm::{
    EventKind, FaultKind, FaultRecord, GroundTruthEvent, ModalitySpec, Reading, SynthFarm,
};
pub use model::generate;
pub use write::{
    FAULTS_HEADER, GROUND_TRUTH_HEADER, READINGS_HEADER, SENSORS_HEADER, push_fixed,
    write_faults_csv, write_ground_truth_csv, write_readings_csv, write_sensors_csv,
};
