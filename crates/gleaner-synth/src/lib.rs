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
//!   storm_peak_doy) / 365.25))` (wet Palouse winters, dry summers), exponential depths (mean
//!   7 mm); each sensor catches a log-normal share of each storm (sd 0.8 in log space); at the
//!   peak of the growing season 80 % of the rain is intercepted or evaporates before it soaks
//!   in (`x (1 - 0.8 ET(doy))`);
//! - the growing season `ET(doy) = 0.05 + 0.95 exp(-(doy - et_peak_doy)² / (2 x 45²))` drives
//!   water uptake, lagged by 0, 15, 30, 40, 50 days at 30, 60, 90, 120, 150 cm (roots reach
//!   deeper layers later);
//! - a **slow store** `B` in [0, 1] (the seasonal wetness) fills with the rain reaching the
//!   layer through a first-order filter (time constant 1.2, 12, 30, 40, 50 days with depth),
//!   `B += gain x inflow x (1 - B)`, and dries as `B x exp(-k x ET)`; with the defaults it
//!   fills through the winter and peaks in April, then dries to its low in September, and the
//!   90 cm layer trails 30 cm by about a month;
//! - a **fast pulse** `P` (the wetting front) gains 0.00125 m³/m³ per mm at 30 cm (less with
//!   depth, arriving with time constant 0.7, 3, 10 ... days) and drains with time constant 3,
//!   4, 5 ... days, so a rain's rise is mostly gone within a week;
//! - `VW = wilt + range x B + P + moving anomaly + own anomaly + noise + shared artefact`:
//!   `wilt` and `range` are spatially correlated per sensor; the moving anomaly is four smooth
//!   latent processes (time constant 60 days) loaded through spatial fields (it makes
//!   correlation decay with distance); the own anomaly a smooth per-sensor process (time
//!   constant 20 days); the noise white per sensor (0.003-0.0045 m³/m³) and the artefact
//!   white but shared by the whole field on a given day (0.0015-0.0028 m³/m³, e.g. the probes'
//!   temperature sensitivity), which sets how alike neighbours' daily changes are;
//! - values are clamped to [0.01, 0.58] m³/m³.
//!
//! **Soil temperature** at depth `z` (cm): `T = mean + offset + amp x A0 exp(-z / D) cos(2 pi
//! (doy - warmest) / 365.25 - z / D) + daily wave + weather + noise`, with the daily wave
//! damped and lagged by the daily damping depth `D / sqrt(365.25)` (visible only with
//! sub-daily sampling near the surface), a shared AR(1) weather anomaly (2.2 °C, day-to-day
//! correlation 0.8) low-pass filtered (time constant `0.5 + (z / 25)²` days) and damped
//! (`exp(-z / 70)`) with depth, per-sensor offsets (0.8 °C, spatially correlated) and amplitude
//! factors (4 %); below 1.5 °C the value approaches 0 °C without reaching it (`1.5 exp((T -
//! 1.5) / 1.5)`: latent heat and snow cover keep the soil at 30 cm above freezing, as at CAF).
//! Clamped to [-30, 50] °C.
//!
//! **Events** (ground truth in [`SynthFarm::events`]; kinds cycle leak, dry patch, failing
//! sensor; default 12 per farm): each lasts [`SynthConfig::event_duration_days`] (default 7-28
//! days, uniform) and starts uniformly between 5 % of the record and the latest start that ends
//! it by 95 %. A leak raises VW at every depth in a disc by 0.10-0.19 m³/m³ (drawn per event),
//! a dry patch lowers it by as much (but not below the wilting baseline minus 0.03 m³/m³);
//! both are tapered from 1 at the centre to 0.5 at the rim, arrive with time constant 1, 2, 4,
//! 6, 8 days at 30 ... 150 cm, and fade over ~10 days after the end, so an event is a
//! transient a missed visit can miss. A failing sensor drifts (±0.002-0.004 m³/m³ and
//! ±0.02-0.05 °C per day) or freezes, falls silent at the end and is replaced 30 days later
//! (it then reports the field again). Disc radius: [`SynthConfig::event_radius_m`] or the mean
//! sensor spacing (at least 30 m); the disc is centred near a random sensor, so it always
//! contains one, and it usually covers one to three stations.
//!
//! **Faults** ([`FaultRates`], recorded in [`SynthFarm::faults`]): station dropouts (all
//! modalities missing for a geometric number of steps, default mean 60), single-probe dropouts
//! (one modality missing, default mean 90 steps; a [`FaultKind::Dropout`] with `modality =
//! Some(m)`), single-reading spikes (0.05-0.15 m³/m³ or 3-8 °C, temperature spikes never below
//! the frost floor) and stuck stretches (a modality repeats its last value). With the defaults
//! about 22 % of values are missing and about half the station-days with a gap lose only some
//! depths, as at CAF.
//!
//! # Calibration
//!
//! The defaults are calibrated against the Cook Agronomy Farm daily record (Gasch & Brown
//! 2017, doi:10.15482/USDA.ADC/1349683) over 2012-01-01 .. 2013-12-31 (42 stations, its
//! well-covered span), against a default farm of 730 days. [`network_stats`] computes every
//! statistic by the same code on both (a [`NetworkPanel`] holds either; [`SynthFarm::network_panel`]
//! builds the synthetic one and masks station-days touched by ground-truth events, which CAF
//! cannot know about): the seasonal cycle ([`monthly_cycle`]: wettest April, driest September),
//! the share of day-to-day rises > 0.02 m³/m³ at 30 cm in winter and summer
//! ([`seasonal_rise_fractions`]), the share of a rise left after 7 days
//! ([`drainage_retention`]), the lag of 90 cm behind 30 cm ([`depth_lag`]) and the correlation of
//! their daily changes ([`change_correlation`]), the correlation of daily changes between
//! stations < 100 m apart ([`panel_stats`]), the missing share and the share of gap days that
//! hit only some depths ([`missing_structure`]), the lowest soil temperature at 30 cm, the
//! share of days with own-history |z| > 3 ([`z_exceedance_fraction`]), and per modality the
//! distribution, lag-1/lag-7 autocorrelation ([`autocorrelation`]) and spatial correlation.
//!
//! The side-by-side table for seeds 1-3 is `docs/synth-calibration.md`, the output of
//! `cargo run --release -p gleaner-synth --example calibrate -- --seeds 1,2,3`. The
//! integration test `tests/it/calibration.rs` recomputes the CAF side from the shared data
//! (`GLEANER_DATA_DIR`, default `../shared/data` beside the workspace) and asserts, for seeds 1
//! and 2: wettest month March-May and driest August-October; winter rises within a factor 2
//! of CAF's, summer rises under 1 % and less than a third of the winter's; 7-day retention
//! 0.25-0.65; depth lag 20-45 days and depth change correlation 0.05-0.3; synchrony at 30 and
//! 90 cm within 0.1 of CAF's; 15-32 % missing with 35-75 % of gap days partial; soil at 30 cm
//! never below 0 °C; own-history |z| > 3 on at most CAF's share + 1.5 points of event-free
//! days; and per modality the mean within 0.04 m³/m³ (1 °C), sd ratio 0.75-1.25 (0.9-1.1 for
//! T), change-sd ratio 0.7-1.4, lag-1 autocorrelation within 0.02, lag-7 within 0.06 and the
//! correlation under 100 m within 0.12 (0.03 for T).
//!
//! Known gaps: the 60 and 90 cm layers are smoother week to week than CAF's (lag-7
//! autocorrelation 0.97 against 0.94) and their correlation decays less with distance (0.78
//! at 450+ m against CAF's 0.66 at 60 cm); single years vary a lot between seeds, as real
//! years do.
//!
//! [`detection`](crate::score_detection) judges anomaly measures against the ground truth: the
//! paper's own-history z-score ([`own_z`]) and a neighbour-relative one ([`neighbour_z`]); the
//! comparison is in the same page.
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
mod detection;
mod error;
mod farm;
mod fidelity;
mod model;
mod network;
mod random;
mod write;

pub use calibration::{DailyPanel, DistanceBin, PanelStats, StatsOptions, panel_stats};
pub use config::{CAF_SENSOR_COUNT, Climate, DEFAULT_START, FaultRates, MAX_VALUES, SynthConfig};
pub use detection::{
    DayTruth, DetectionScore, nearest_neighbours, neighbour_residuals, neighbour_z, own_history_z,
    own_z, score_detection,
};
pub use error::SynthError;
pub use farm::{
    EventKind, FaultKind, FaultRecord, GroundTruthEvent, ModalitySpec, Reading, SynthFarm,
};
pub use fidelity::{
    ChangeShape, DISTANCE_BANDS_M, DepthFidelity, FRONT_LAGS_DAYS, FRONT_WINDOW_DAYS,
    FidelityCheck, FidelityStats, GapShape, STUCK_MIN_DAYS, change_correlation_by_distance,
    change_shape, fidelity_checks, fidelity_stats, gap_shape, lagged_window_change_correlation,
    mean_and_amplitude, network_down_days, peak_in, stuck_share,
};
pub use model::generate;
pub use network::{
    ModalityStats, NetworkPanel, NetworkStats, PanelModality, autocorrelation, change_correlation,
    depth_lag, drainage_retention, extreme_months, missing_structure, month_of_day, monthly_cycle,
    network_stats, seasonal_rise_fractions, z_exceedance_fraction,
};
pub use write::{
    FAULTS_HEADER, FarmFiles, GROUND_TRUTH_HEADER, READINGS_HEADER, SENSORS_HEADER, WriteError,
    push_fixed, write_farm_files, write_faults_csv, write_ground_truth_csv, write_readings_csv,
    write_sensors_csv,
};
