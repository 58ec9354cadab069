//! The physics-ish model behind [`generate`]. See the crate docs for the equations and the
//! calibration of the constants below.

use gleaner_field::{LatLon, LocalPoint, Modality, Sensor, SensorId, TransverseMercator};
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use crate::config::SynthConfig;
use crate::farm::{EventKind, FaultKind, FaultRecord, GroundTruthEvent, ModalitySpec, SynthFarm};
use crate::random::{
    Domain, SpatialField, exponential, geometric_len, normal, poisson, stream, uniform,
};
use gleaner_field::time::day_of_year;

/// Depths (cm) at which the per-depth soil-water constants below are given; other depths
/// interpolate linearly and clamp at the ends.
const TABLE_DEPTHS_CM: [f64; 5] = [30.0, 60.0, 90.0, 120.0, 150.0];
/// Mean wilting baseline (dry end) of volumetric water, m³/m³.
const WILT_MEAN: [f64; 5] = [0.17, 0.2, 0.21, 0.225, 0.25];
/// Between-sensor standard deviation of the wilting baseline, m³/m³.
const WILT_SD: [f64; 5] = [0.045, 0.055, 0.06, 0.07, 0.07];
/// Mean range from wilting baseline to field capacity, m³/m³.
const RANGE_MEAN: [f64; 5] = [0.21, 0.27, 0.25, 0.22, 0.2];
/// Between-sensor coefficient of variation (log-normal) of the range, dimensionless.
const RANGE_CV: [f64; 5] = [0.12, 0.14, 0.15, 0.16, 0.16];
/// Drying rate of the slow store at the peak of the growing season, 1/day.
const DRYING_RATE: [f64; 5] = [0.025, 0.045, 0.026, 0.02, 0.016];
/// Slow-store filling per millimetre of rain reaching the layer (times the room left), 1/mm.
const RAIN_GAIN: [f64; 5] = [0.0035, 0.008, 0.008, 0.008, 0.008];
/// Travel time of the wetting front from the surface to the layer's slow store, days (a pure
/// delay: the water that soaks in below the root zone arrives this long after the rain).
const FRONT_DELAY_DAYS: [f64; 5] = [0.0, 11.0, 24.0, 31.0, 38.0];
/// Time constant of the front's arrival once it is there (its sharpness), days.
const INFILTRATION_TAU_DAYS: [f64; 5] = [1.2, 1.0, 1.0, 1.2, 1.5];
/// Log-normal spread of each sensor's front delay (a spatial field, exponential covariance
/// over [`FRONT_CORRELATION_M`]): nearby stations see a front the same day, distant ones days
/// apart, so the correlation of deep daily changes falls with distance.
const FRONT_DELAY_SD: f64 = 0.5;
/// Correlation length of the front-delay field, metres.
const FRONT_CORRELATION_M: f64 = 250.0;
/// Time constant of the rain's arrival as a fast pulse (preferential flow, undelayed), days.
const PULSE_IN_TAU_DAYS: [f64; 5] = [0.7, 1.0, 1.5, 2.0, 2.0];
/// Fast pulse per millimetre of rain, m³/m³ per mm.
const PULSE_GAIN: [f64; 5] = [0.00125, 0.0002, 0.00004, 0.00003, 0.00002];
/// Time constant of the fast pulse's drainage, days.
const PULSE_TAU_DAYS: [f64; 5] = [3.0, 4.0, 5.0, 6.0, 6.0];
/// Lag of the growing season's water uptake behind its peak at 30 cm, days.
const ET_LAG_DAYS: [f64; 5] = [0.0, 15.0, 30.0, 40.0, 50.0];
/// Time constant of a leak's or dry patch's arrival at the layer, days.
const EVENT_TAU_DAYS: [f64; 5] = [1.0, 2.0, 4.0, 6.0, 8.0];
/// White measurement noise of a daily volumetric water value, m³/m³ (a daily mean of many
/// readings: below the sensor's resolution step, so deep layers repeat their value on most
/// days, as at CAF).
const VW_NOISE: [f64; 5] = [0.0002, 0.0001, 0.0001, 0.0001, 0.0001];
/// Field-wide white measurement artefact of volumetric water (shared by every station on a
/// given day, e.g. the probes' temperature sensitivity), m³/m³.
const VW_COMMON_NOISE: [f64; 5] = [0.0006, 0.00045, 0.0, 0.0, 0.0];
/// Resolution step of a volumetric water value, m³/m³ (CAF reports 0.001).
pub(crate) const VW_RESOLUTION: f64 = 0.001;
/// Resolution step of a soil temperature value, °C (CAF reports 0.01).
pub(crate) const T_RESOLUTION: f64 = 0.01;
/// Amplitude of the spatially correlated moving anomaly, m³/m³.
const ANOMALY_SD: [f64; 5] = [0.02, 0.02, 0.025, 0.025, 0.025];
/// Time constant of a further low-pass of the moving anomaly at the layer, days (0: none):
/// deep layers follow it slowly, so it shapes their levels (correlation falling with
/// distance) without moving them on most days.
const ANOMALY_FILTER_DAYS: [f64; 5] = [0.0, 60.0, 120.0, 150.0, 180.0];
/// Amplitude of each sensor's own slow anomaly, m³/m³.
const LOCAL_SD: [f64; 5] = [0.025, 0.025, 0.025, 0.025, 0.025];
/// Log-normal spread of each sensor's response to a storm (infiltration, interception).
const STORM_RESPONSE_SD: f64 = 0.8;
/// Soil temperatures below this knee approach 0 °C without reaching it: `T = knee x exp((T -
/// knee) / knee)` (latent heat of freezing and snow cover keep the soil at 30 cm just above
/// 0 °C, as at CAF), °C.
const T_FREEZE_KNEE_C: f64 = 1.5;
/// Share of rain lost to interception and evaporation at the peak of the growing season.
const RAIN_INTERCEPTION: f64 = 0.8;
/// Share of a sensor parameter's variance that is spatially structured (the rest is nugget).
const SPATIAL_SHARE: f64 = 0.7;
/// Time constant of the moving anomaly, days.
const ANOMALY_TAU_DAYS: f64 = 60.0;
/// Time constant of each sensor's own slow anomaly, days (slower with depth).
const LOCAL_TAU_DAYS: [f64; 5] = [20.0, 90.0, 200.0, 250.0, 300.0];
/// Percolation below the top layer scales as the topsoil's wetness to this power: deep
/// layers are recharged in the wet season, hardly in summer.
const PERCOLATION_POWER: f64 = 1.0;
/// Number of latent processes in the moving anomaly.
const ANOMALY_FIELDS: usize = 4;
/// A failed sensor stays silent this long after its event ends before it is replaced (it then
/// reports the true values again), days.
const REPLACEMENT_DAYS: f64 = 30.0;
/// Spin-up before the first reading, days (daily steps).
const SPIN_UP_DAYS: usize = 400;
/// Seasonal evapotranspiration factor: `ET_FLOOR + (1 - ET_FLOOR) x exp(-((doy - peak) /
/// ET_WIDTH_DAYS)² / 2)` (wrapped around the year), a growing season peaking at
/// [`crate::Climate::et_peak_doy`].
const ET_FLOOR: f64 = 0.05;
/// Half-width (one standard deviation) of the growing season, days.
const ET_WIDTH_DAYS: f64 = 45.0;

/// Weather anomaly of soil temperature at the surface: AR(1) standard deviation, °C.
const T_WEATHER_SD: f64 = 2.2;
/// Its day-to-day autocorrelation.
const T_WEATHER_RHO: f64 = 0.8;
/// Damping depth of the weather anomaly, cm.
const T_WEATHER_DAMPING_CM: f64 = 70.0;
/// Between-sensor standard deviation of the mean soil temperature, °C.
const T_OFFSET_SD: f64 = 0.8;
/// Between-sensor coefficient of variation of the annual amplitude.
const T_AMPLITUDE_CV: f64 = 0.04;
/// White measurement noise of a daily soil temperature, °C (each probe's own day-to-day
/// scatter: it is what keeps deep stations' daily changes from being perfectly alike).
const T_NOISE_SD: f64 = 0.02;

/// Physical clamp of volumetric water content, m³/m³ (inside [0, 0.6] even as f32).
const VW_RANGE: (f64, f64) = (0.01, 0.58);
/// Physical clamp of soil temperature, °C.
const T_RANGE: (f64, f64) = (-30.0, 50.0);

fn interp(table: &[f64; 5], depth_cm: f64) -> f64 {
    let d = depth_cm.clamp(TABLE_DEPTHS_CM[0], TABLE_DEPTHS_CM[4]);
    for i in 0..4 {
        let (a, b) = (TABLE_DEPTHS_CM[i], TABLE_DEPTHS_CM[i + 1]);
        if d <= b {
            let w = (d - a) / (b - a);
            return table[i] + w * (table[i + 1] - table[i]);
        }
    }
    table[4]
}

/// Irwin-Hall approximation of a standard normal (sum of four uniforms): cheap noise.
fn fast_normal(rng: &mut ChaCha8Rng) -> f64 {
    let s: f64 = (0..4).map(|_| rng.random::<f64>()).sum();
    (s - 2.0) * 3.0f64.sqrt()
}

fn round_to(v: f64, decimals: u32) -> f64 {
    let k = 10f64.powi(decimals as i32);
    (v * k).round() / k
}

/// A smooth, zero-mean, unit-variance random process: an AR(1) with time constant tau passed
/// through a first-order low-pass with the same tau, so its day-to-day changes are small
/// (of order dt / tau rather than sqrt(dt / tau)).
#[derive(Debug, Clone, Copy)]
struct SmoothProcess {
    rho: f64,
    kick: f64,
    scale: f64,
    x: f64,
    y: f64,
}

impl SmoothProcess {
    fn new(dt_days: f64, tau_days: f64, first_noise: f64) -> Self {
        let rho = (-dt_days / tau_days).exp();
        // Var(y) = (1 + rho^2) / (1 + rho)^2 for unit-variance x.
        let scale = (1.0 + rho) / (1.0 + rho * rho).sqrt();
        Self {
            rho,
            kick: (1.0 - rho * rho).sqrt(),
            scale,
            x: first_noise,
            y: first_noise / scale,
        }
    }

    fn value(&self) -> f64 {
        self.y * self.scale
    }

    fn step(&mut self, noise: f64) -> f64 {
        self.x = self.rho * self.x + self.kick * noise;
        self.y = self.rho * self.y + (1.0 - self.rho) * self.x;
        self.value()
    }
}

/// Effects of one event on one sensor.
#[derive(Debug, Clone, Copy)]
struct EventEffect {
    kind: EventKind,
    start_step: usize,
    end_step: usize,
    /// Taper in (0, 1]: 1 at the centre.
    weight: f64,
    /// Drift of VW, m³/m³ per day, and of T, °C per day (SensorDrift only).
    drift_vw: f64,
    /// Offset of a leak (up) or dry patch (down) at full strength, m³/m³.
    amp_vw: f64,
    drift_t: f64,
}

/// The shared drivers and fields every sensor's simulation reads.
struct Context<'a> {
    config: &'a SynthConfig,
    steps: usize,
    dt_days: f64,
    /// Growing-season water uptake factor per VW depth and step (and per spin-up day), in
    /// [ET_FLOOR, 1]; `et_surface` is the same at the surface (interception of rain).
    et: Vec<Vec<f64>>,
    et_surface: Vec<f64>,
    spin_up_et: Vec<Vec<f64>>,
    spin_up_et_surface: Vec<f64>,
    rain_mm: Vec<f64>,
    spin_up_rain_mm: Vec<f64>,
    /// ANOMALY_FIELDS x steps, unit variance.
    anomaly: Vec<f64>,
    /// Field-wide white measurement artefact per step, unit variance.
    common: Vec<f64>,
    /// Per temperature depth: deterministic part + shared weather anomaly, °C (without the
    /// sensor's offset and amplitude factor), split so each sensor can scale the annual wave.
    t_annual: Vec<Vec<f64>>,
    t_rest: Vec<Vec<f64>>,
    wilt_field: SpatialField,
    range_field: SpatialField,
    drying_field: SpatialField,
    gain_field: SpatialField,
    t_field: SpatialField,
    anomaly_fields: Vec<SpatialField>,
    front_field: SpatialField,
    effects: Vec<Vec<EventEffect>>,
    /// Network-wide outages, `[start, end)` steps.
    outages: Vec<(usize, usize)>,
    modalities: &'a [ModalitySpec],
}

fn et_factor(config: &SynthConfig, doy: f64) -> f64 {
    let d = (doy - config.climate.et_peak_doy + 182.625).rem_euclid(365.25) - 182.625;
    ET_FLOOR + (1.0 - ET_FLOOR) * (-0.5 * (d / ET_WIDTH_DAYS).powi(2)).exp()
}

fn storm_rate_per_day(config: &SynthConfig, doy: f64) -> f64 {
    let c = &config.climate;
    let season = (std::f64::consts::TAU * (doy - c.storm_peak_doy) / 365.25).cos();
    (c.storms_per_year / 365.25) * (1.0 + c.storm_seasonality * season)
}

fn rain_series(config: &SynthConfig, rng: &mut ChaCha8Rng, doys: &[f64], dt_days: f64) -> Vec<f64> {
    doys.iter()
        .map(|&doy| {
            let n = poisson(rng, storm_rate_per_day(config, doy) * dt_days);
            (0..n)
                .map(|_| exponential(rng, config.climate.storm_mean_mm))
                .sum()
        })
        .collect()
}

/// Generates a synthetic farm. Deterministic: the same configuration gives the same farm,
/// whatever the number of threads.
///
/// Cost is O(sensors x steps x modalities) (plus O(sensors x events) to find the sensors each
/// event touches), parallel over sensors.
pub fn generate(config: &SynthConfig) -> Result<SynthFarm, crate::SynthError> {
    config.validate()?;
    let steps = config.steps();
    let dt_days = config.interval_s as f64 / 86_400.0;
    let n = config.sensor_count;

    let modalities = modality_specs(config)?;
    let times: Vec<i64> = (0..steps as i64)
        .map(|i| config.start + i * config.interval_s)
        .collect();
    let doys: Vec<f64> = times.iter().map(|&t| day_of_year(t)).collect();

    // Layout: a jittered grid over the extent, centred on the field centre.
    let frame = TransverseMercator::local(config.centre);
    let [w, h] = config.effective_extent_m();
    let nx = ((n as f64 * w / h).sqrt().round() as usize).clamp(1, n);
    let ny = n.div_ceil(nx);
    let (dx, dy) = (w / nx as f64, h / ny as f64);
    let local: Vec<LocalPoint> = match &config.layout {
        Some(layout) => layout.iter().map(|(_, p)| frame.forward(*p)).collect(),
        None => grid_layout(config, n, [w, h], [nx, ny], [dx, dy]),
    };

    // Static spatial fields, drawn in a fixed order.
    let mut frng = stream(config.seed, Domain::Fields, 0);
    let l = config.correlation_length_m;
    // Standardised over the farm's own sensors: the fields describe variation within the
    // farm, so every seed's farm has the calibrated mean and spread (no wet or dry seeds).
    let field = |rng: &mut ChaCha8Rng, l: f64| SpatialField::new(rng, l).standardized_over(&local);
    let wilt_field = field(&mut frng, l);
    let range_field = field(&mut frng, l);
    let drying_field = field(&mut frng, l);
    let gain_field = field(&mut frng, l);
    let t_field = field(&mut frng, l);
    let elevation_field = SpatialField::new(&mut frng, 2.0 * l);
    let anomaly_fields: Vec<SpatialField> =
        (0..ANOMALY_FIELDS).map(|_| field(&mut frng, l)).collect();
    let front_field =
        SpatialField::exponential(&mut frng, FRONT_CORRELATION_M).standardized_over(&local);

    let sensors = sensors_at(config, &local, &frame, &elevation_field)?;

    // Shared weather.
    let mut wrng = stream(config.seed, Domain::Weather, 0);
    let rain_mm = rain_series(config, &mut wrng, &doys, dt_days);
    let start_doy = day_of_year(config.start);
    let spin_doys: Vec<f64> = (0..SPIN_UP_DAYS)
        .map(|k| (start_doy - (SPIN_UP_DAYS - k) as f64).rem_euclid(365.25))
        .collect();
    let spin_up_rain_mm = rain_series(config, &mut wrng, &spin_doys, 1.0);
    let et_at = |doys: &[f64], lag: f64| -> Vec<f64> {
        doys.iter().map(|&d| et_factor(config, d - lag)).collect()
    };
    let et: Vec<Vec<f64>> = config
        .vw_depths_cm
        .iter()
        .map(|&d| et_at(&doys, interp(&ET_LAG_DAYS, f64::from(d))))
        .collect();
    let spin_up_et: Vec<Vec<f64>> = config
        .vw_depths_cm
        .iter()
        .map(|&d| et_at(&spin_doys, interp(&ET_LAG_DAYS, f64::from(d))))
        .collect();
    let et_surface = et_at(&doys, 0.0);
    let spin_up_et_surface = et_at(&spin_doys, 0.0);
    let anomaly = anomaly_series(&mut wrng, dt_days, steps);
    let (t_annual, t_rest) = temperature_drivers(config, &mut wrng, &times, &doys, dt_days);
    let common: Vec<f64> = (0..steps).map(|_| normal(&mut wrng)).collect();

    let (events, effects) = place_events(config, &sensors, &local, &frame, &times);
    let outages = network_outages(config, steps);

    let ctx = Context {
        config,
        steps,
        dt_days,
        et,
        et_surface,
        spin_up_et,
        spin_up_et_surface,
        rain_mm,
        spin_up_rain_mm,
        anomaly,
        common,
        t_annual,
        t_rest,
        wilt_field,
        range_field,
        drying_field,
        gain_field,
        t_field,
        anomaly_fields,
        front_field,
        effects,
        outages,
        modalities: &modalities,
    };

    let stride = modalities.len() * steps;
    let mut values = vec![f32::NAN; n * stride];
    let faults: Vec<FaultRecord> = if stride == 0 {
        Vec::new()
    } else {
        values
            .par_chunks_mut(stride)
            .enumerate()
            .map(|(i, out)| simulate_sensor(&ctx, i, local[i], out))
            .collect::<Vec<_>>()
            .into_iter()
            .flatten()
            .collect()
    };

    Ok(SynthFarm {
        sensors,
        local,
        frame,
        base: config.base,
        modalities,
        times,
        values,
        events,
        faults,
    })
}

/// The farm's modalities: soil moisture (water) at each depth first, then soil temperature.
fn modality_specs(config: &SynthConfig) -> Result<Vec<ModalitySpec>, crate::SynthError> {
    let mut modalities = Vec::new();
    // Soil moisture (water) first, then soil temperature.
    for (depths, quantity, unit, is_water, decimals) in [
        (&config.vw_depths_cm, "vw", "m3/m3", true, 3),
        (&config.t_depths_cm, "t", "degC", false, 2),
    ] {
        for &d in depths {
            modalities.push(ModalitySpec {
                modality: Modality::at_depth(quantity, Some(d))?,
                unit,
                decimals,
                depth_cm: d,
                is_water,
            });
        }
    }
    Ok(modalities)
}

/// A jittered grid of `n` stations over the extent `[w, h]` (m, centred on the field
/// centre): `nx` columns of `dx` by `dy` cells, each station's jitter from its own stream.
fn grid_layout(
    config: &SynthConfig,
    n: usize,
    [w, h]: [f64; 2],
    [nx, _ny]: [usize; 2],
    [dx, dy]: [f64; 2],
) -> Vec<LocalPoint> {
    (0..n)
        .into_par_iter()
        .map(|i| {
            let mut rng = stream(config.seed, Domain::Layout, i as u64);
            let (col, row) = ((i % nx) as f64, (i / nx) as f64);
            let je = 0.8 * (uniform(&mut rng) - 0.5);
            let jn = 0.8 * (uniform(&mut rng) - 0.5);
            LocalPoint::new(
                -w / 2.0 + (col + 0.5 + je) * dx,
                -h / 2.0 + (row + 0.5 + jn) * dy,
            )
        })
        .collect()
}

/// The stations at `local` (m): the layout's ids or `SYN00001`.., WGS84 positions, elevations
/// from `elevation_field` (m).
fn sensors_at(
    config: &SynthConfig,
    local: &[LocalPoint],
    frame: &TransverseMercator,
    elevation_field: &SpatialField,
) -> Result<Vec<Sensor>, crate::SynthError> {
    let n = config.sensor_count;
    let width = n.to_string().len().max(5);
    local
        .par_iter()
        .enumerate()
        .map(|(i, p)| -> Result<Sensor, crate::SynthError> {
            let id = match &config.layout {
                Some(layout) => layout[i].0.clone(),
                None => SensorId::new(format!("SYN{:0width$}", i + 1))?,
            };
            let ll = frame.inverse(*p);
            let mut s = Sensor::new(id, LatLon::new(ll.lat(), ll.lon())?);
            s.elevation_m = Some(round_to(785.0 + 12.0 * elevation_field.at(*p), 2));
            Ok(s)
        })
        .collect::<Result<_, _>>()
}

/// The shared anomaly processes, `steps` values each, field by field, drawn from `wrng`.
fn anomaly_series(wrng: &mut ChaCha8Rng, dt_days: f64, steps: usize) -> Vec<f64> {
    let mut anomaly = vec![0.0; ANOMALY_FIELDS * steps];
    for k in 0..ANOMALY_FIELDS {
        let mut z = SmoothProcess::new(dt_days, ANOMALY_TAU_DAYS, normal(wrng));
        for t in 0..steps {
            anomaly[k * steps + t] = if t == 0 {
                z.value()
            } else {
                z.step(normal(wrng))
            };
        }
    }
    anomaly
}

/// Shared soil-temperature drivers per temperature depth: the annual wave (to be scaled by
/// each sensor's amplitude factor) and the rest (mean, daily wave, weather anomaly), °C.
fn temperature_drivers(
    config: &SynthConfig,
    rng: &mut ChaCha8Rng,
    times: &[i64],
    doys: &[f64],
    dt_days: f64,
) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
    use std::f64::consts::TAU;
    let c = &config.climate;
    let steps = times.len();
    // Surface weather anomaly, AR(1) with the daily autocorrelation T_WEATHER_RHO.
    let rho = T_WEATHER_RHO.powf(dt_days);
    let mut weather = Vec::with_capacity(steps);
    let mut w = T_WEATHER_SD * normal(rng);
    for t in 0..steps {
        if t > 0 {
            w = rho * w + T_WEATHER_SD * (1.0 - rho * rho).sqrt() * normal(rng);
        }
        weather.push(w);
    }
    let d_year = c.annual_damping_depth_cm;
    let d_day = d_year / 365.25f64.sqrt();
    let lon = config.centre.lon();
    let mut annual = Vec::new();
    let mut rest = Vec::new();
    for &z in &config.t_depths_cm {
        let z = f64::from(z);
        let amp_year = c.surface_annual_amplitude_c * (-z / d_year).exp();
        let amp_day = c.surface_daily_amplitude_c * (-z / d_day).exp();
        // The weather anomaly reaches depth z low-pass filtered (diffusion time ~ z^2).
        let tau = 0.5 + (z / 25.0).powi(2);
        let alpha = 1.0 - (-dt_days / tau).exp();
        let damp = (-z / T_WEATHER_DAMPING_CM).exp();
        let mut filtered = weather[0];
        let mut a = Vec::with_capacity(steps);
        let mut r = Vec::with_capacity(steps);
        for t in 0..steps {
            filtered += alpha * (weather[t] - filtered);
            let year_phase = TAU * (doys[t] - c.warmest_doy) / 365.25 - z / d_year;
            let solar_hour =
                (times[t].rem_euclid(86_400) as f64 / 3600.0 + lon / 15.0).rem_euclid(24.0);
            let day_phase = TAU * (solar_hour - 15.0) / 24.0 - z / d_day;
            a.push(amp_year * year_phase.cos());
            r.push(c.mean_soil_temp_c + amp_day * day_phase.cos() + damp * filtered);
        }
        annual.push(a);
        rest.push(r);
    }
    (annual, rest)
}

/// Places the localised events and returns their ground truth and per-sensor effects.
fn place_events(
    config: &SynthConfig,
    sensors: &[Sensor],
    local: &[LocalPoint],
    frame: &TransverseMercator,
    times: &[i64],
) -> (Vec<GroundTruthEvent>, Vec<Vec<EventEffect>>) {
    let n = sensors.len();
    let steps = times.len();
    let mut effects = vec![Vec::new(); n];
    let mut events = Vec::with_capacity(config.event_count);
    let mut rng = stream(config.seed, Domain::Events, 0);
    let [w, h] = config.effective_extent_m();
    let spacing = (w * h / n as f64).sqrt();
    let radius = config.event_radius_m.unwrap_or_else(|| spacing.max(30.0));
    let per_day = 86_400.0 / config.interval_s as f64;
    let [d_min, d_max] = config.event_duration_days;
    let step_time = |s: usize| {
        times
            .get(s)
            .copied()
            .unwrap_or(config.start + s as i64 * config.interval_s)
    };
    for e in 0..config.event_count {
        let days = d_min + (d_max - d_min) * uniform(&mut rng);
        let length = ((days * per_day).round() as usize).max(1);
        let first = (0.05 * steps as f64) as usize;
        let last = ((0.95 * steps as f64) as usize)
            .saturating_sub(length)
            .max(first);
        let start_step = (first + (uniform(&mut rng) * (last - first) as f64) as usize).min(steps);
        let end_step = (start_step + length).min(steps);
        let centre_sensor = rng.random_range(0..n);
        let kind = match e % 3 {
            0 => EventKind::Leak,
            1 => EventKind::DryPatch,
            _ if uniform(&mut rng) < 0.5 => EventKind::SensorDrift,
            _ => EventKind::SensorStuck,
        };
        let sign = if uniform(&mut rng) < 0.5 { -1.0 } else { 1.0 };
        let drift_vw = sign * (0.002 + 0.002 * uniform(&mut rng));
        let drift_t = sign * (0.02 + 0.03 * uniform(&mut rng));
        let amp_vw = 0.10 + 0.09 * uniform(&mut rng);
        let (centre, radius_m, affected) = match kind {
            EventKind::Leak | EventKind::DryPatch => {
                let angle = uniform(&mut rng) * std::f64::consts::TAU;
                let off = radius / 3.0 * uniform(&mut rng);
                let c = LocalPoint::new(
                    local[centre_sensor].e + off * angle.cos(),
                    local[centre_sensor].n + off * angle.sin(),
                );
                let affected: Vec<(usize, f64)> = local
                    .iter()
                    .enumerate()
                    .filter_map(|(i, p)| {
                        let r = p.distance(&c) / radius;
                        (r < 1.0).then_some((i, 1.0 - 0.5 * r * r))
                    })
                    .collect();
                (c, radius, affected)
            }
            _ => (local[centre_sensor], 0.0, vec![(centre_sensor, 1.0)]),
        };
        for &(i, weight) in &affected {
            effects[i].push(EventEffect {
                kind,
                start_step,
                end_step,
                weight,
                drift_vw,
                drift_t,
                amp_vw,
            });
        }
        let ll = frame.inverse(centre);
        events.push(GroundTruthEvent {
            id: format!("E{:03}", e + 1),
            kind,
            start: step_time(start_step),
            end: step_time(end_step),
            centre: LatLon::new(ll.lat(), ll.lon()).unwrap_or(config.centre),
            radius_m,
            affected: affected.into_iter().map(|(i, _)| i).collect(),
        });
    }
    (events, effects)
}

/// Per-depth soil-water state of one sensor.
struct WaterLayer {
    wilt: f64,
    range: f64,
    drying: f64,
    gain: f64,
    alpha: f64,
    spin_alpha: f64,
    pulse_alpha: f64,
    spin_pulse_alpha: f64,
    pulse_gain: f64,
    pulse_decay: f64,
    spin_pulse_decay: f64,
    event_alpha: f64,
    noise: f64,
    common_noise: f64,
    anomaly_sd: f64,
    /// Low-pass rate of the moving anomaly (1 = none) and its state.
    anomaly_alpha: f64,
    anomaly_state: f64,
    local_sd: f64,
    /// Slow store (seasonal wetness), in [0, 1].
    store: f64,
    inflow: f64,
    /// Fast pulse (wetting front draining within days), m³/m³, and its inflow, mm/day.
    pulse: f64,
    pulse_inflow: f64,
    local: SmoothProcess,
    /// True below the top layer: fed by the delayed, wetness-gated percolation rather than
    /// by the rain itself.
    percolates: bool,
    /// The wetting front on its way to the layer (daily during the spin-up, then per step).
    front: DelayLine,
    /// Front delay of this sensor at this depth, days.
    front_delay_days: f64,
    /// Leak / dry-patch offsets, m³/m³ (>= 0).
    leak: f64,
    dry: f64,
}

/// A pure delay of a fixed number of steps (a ring buffer; zero steps passes values through).
#[derive(Debug, Clone)]
struct DelayLine {
    buf: Vec<f64>,
    pos: usize,
}

impl DelayLine {
    fn new(steps: usize) -> Self {
        Self {
            buf: vec![0.0; steps],
            pos: 0,
        }
    }

    /// Pushes `x` and returns the value pushed `steps` steps ago (0 before that).
    fn step(&mut self, x: f64) -> f64 {
        if self.buf.is_empty() {
            return x;
        }
        let out = std::mem::replace(&mut self.buf[self.pos], x);
        self.pos = (self.pos + 1) % self.buf.len();
        out
    }

    /// The same history on a grid `steps_per_old` times finer, `steps` long: each new slot
    /// takes the old slot covering its time (rates, so no rescaling).
    fn resampled(&self, steps: usize, steps_per_old: usize) -> DelayLine {
        let old = self.buf.len();
        // Oldest first.
        let seq: Vec<f64> = (0..old).map(|k| self.buf[(self.pos + k) % old]).collect();
        let buf = (0..steps)
            .map(|k| {
                // Slot k (oldest first) is (steps - k) new steps ago.
                let ago_old = (steps - k).div_ceil(steps_per_old.max(1));
                if old == 0 || ago_old > old {
                    0.0
                } else {
                    seq[old - ago_old]
                }
            })
            .collect();
        DelayLine { buf, pos: 0 }
    }
}

/// The topsoil's wetness, in [0, 1]: a slow store with the mean 30 cm parameters, used only
/// to gate the percolation that recharges the deeper layers.
#[derive(Debug, Clone, Copy)]
struct Topsoil {
    store: f64,
    inflow: f64,
}

impl Topsoil {
    fn step(&mut self, rain: f64, et: f64, dt: f64, alpha: f64) {
        self.inflow += alpha * (rain / dt - self.inflow);
        let fill = (RAIN_GAIN[0] * self.inflow * dt).min(1.0);
        self.store = (self.store * (-DRYING_RATE[0] * et * dt).exp()) * (1.0 - fill) + fill;
    }

    /// Water percolating below the top layer out of `rain` mm.
    fn percolation(&self, rain: f64) -> f64 {
        rain * self.store.powf(PERCOLATION_POWER)
    }
}

impl WaterLayer {
    /// One step of `dt` days with `rain` mm reaching the surface and `percolation` mm
    /// leaving the topsoil (per step) and uptake factor `et`; `alphas` are the layer's (slow,
    /// pulse) arrival rates and `decay` the pulse's survival for this step length.
    fn water_step(
        &mut self,
        rain: f64,
        percolation: f64,
        et: f64,
        dt: f64,
        alphas: (f64, f64),
        decay: f64,
    ) {
        let feed = if self.percolates { percolation } else { rain };
        let arriving = self.front.step(feed / dt);
        self.inflow += alphas.0 * (arriving - self.inflow);
        self.pulse_inflow += alphas.1 * (rain / dt - self.pulse_inflow);
        let fill = (self.gain * self.inflow * dt).min(1.0);
        self.store = (self.store * (-self.drying * et * dt).exp()) * (1.0 - fill) + fill;
        self.pulse = self.pulse * decay + self.pulse_gain * self.pulse_inflow * dt;
    }
}

fn mix(field: f64, rng: &mut ChaCha8Rng) -> f64 {
    SPATIAL_SHARE.sqrt() * field + (1.0 - SPATIAL_SHARE).sqrt() * normal(rng)
}

/// Simulates one sensor into `out` (modalities x steps) and returns its fault records.
fn simulate_sensor(
    ctx: &Context<'_>,
    index: usize,
    p: LocalPoint,
    out: &mut [f32],
) -> Vec<FaultRecord> {
    let config = ctx.config;
    let steps = ctx.steps;
    let dt = ctx.dt_days;
    let mut rng = stream(config.seed, Domain::Sensor, index as u64);

    // Static parameters from the spatial fields plus nugget.
    let f_wilt = ctx.wilt_field.at(p);
    let f_range = ctx.range_field.at(p);
    let f_dry = ctx.drying_field.at(p);
    let f_gain = ctx.gain_field.at(p);
    let f_t = ctx.t_field.at(p);
    let f_front = ctx.front_field.at(p);
    let loadings: Vec<f64> = ctx
        .anomaly_fields
        .iter()
        .map(|f| f.at(p) / (ANOMALY_FIELDS as f64).sqrt())
        .collect();
    let mut layers = water_layers(
        config,
        dt,
        [f_wilt, f_range, f_dry, f_gain, f_front],
        &mut rng,
    );
    let t_offset = T_OFFSET_SD * mix(f_t, &mut rng);
    let t_amp = 1.0 + T_AMPLITUDE_CV * normal(&mut rng);

    // Spin-up, daily steps, no events, the field's mean storm response.
    let (mut topsoil, top_alpha) = spin_up(ctx, &mut layers);

    let effects = &ctx.effects[index];
    let n_vw = layers.len();
    for t in 0..steps {
        // Event offsets at this step, m³/m³.
        let mut leak_target = 0.0f64;
        let mut dry_target = 0.0f64;
        for e in effects {
            let active = t >= e.start_step && t < e.end_step;
            match e.kind {
                EventKind::Leak if active => leak_target = leak_target.max(e.weight * e.amp_vw),
                EventKind::DryPatch if active => dry_target = dry_target.max(e.weight * e.amp_vw),
                _ => {}
            }
        }
        let anomaly: f64 = loadings
            .iter()
            .enumerate()
            .map(|(k, l)| l * ctx.anomaly[k * steps + t])
            .sum();
        // Each sensor catches its own share of a storm (log-normal, mean 1).
        let storm_response = if ctx.rain_mm[t] > 0.0 {
            (STORM_RESPONSE_SD * normal(&mut rng) - 0.5 * STORM_RESPONSE_SD * STORM_RESPONSE_SD)
                .exp()
        } else {
            1.0
        };
        let rain = ctx.rain_mm[t] * storm_response * (1.0 - RAIN_INTERCEPTION * ctx.et_surface[t]);
        let percolation = topsoil.percolation(rain);
        topsoil.step(rain, ctx.et_surface[t], dt, top_alpha);
        // Leak water and drying patches arrive with the layer's own lag; they fade over
        // about ten days after the event ends.
        let fade = 1.0 - (-dt / 10.0).exp();
        for (j, layer) in layers.iter_mut().enumerate() {
            let onset = layer.event_alpha;
            let rate = |target: f64, state: f64| if target > state { onset } else { fade };
            layer.leak += rate(leak_target, layer.leak) * (leak_target - layer.leak);
            layer.dry += rate(dry_target, layer.dry) * (dry_target - layer.dry);
            let alphas = (layer.alpha, layer.pulse_alpha);
            let decay = layer.pulse_decay;
            layer.water_step(rain, percolation, ctx.et[j][t], dt, alphas, decay);
            layer.anomaly_state = if layer.anomaly_state.is_nan() {
                anomaly
            } else {
                layer.anomaly_state + layer.anomaly_alpha * (anomaly - layer.anomaly_state)
            };
            let local = layer.local.step(fast_normal(&mut rng));
            let wet = layer.store;
            let mut v = layer.wilt
                + layer.range * wet
                + layer.pulse
                + layer.anomaly_sd * layer.anomaly_state * (0.3 + wet)
                + layer.local_sd * local
                + layer.noise * fast_normal(&mut rng)
                + layer.common_noise * ctx.common[t];
            v += layer.leak;
            if layer.dry > 0.0 {
                v = (v - layer.dry).max((layer.wilt - 0.03).min(v));
            }
            out[j * steps + t] = v.clamp(VW_RANGE.0, VW_RANGE.1) as f32;
        }
        for (k, _) in config.t_depths_cm.iter().enumerate() {
            let mut v = t_offset
                + t_amp * ctx.t_annual[k][t]
                + ctx.t_rest[k][t]
                + T_NOISE_SD * fast_normal(&mut rng);
            if v < T_FREEZE_KNEE_C {
                v = T_FREEZE_KNEE_C * ((v - T_FREEZE_KNEE_C) / T_FREEZE_KNEE_C).exp();
            }
            out[(n_vw + k) * steps + t] = v.clamp(T_RANGE.0, T_RANGE.1) as f32;
        }
    }

    failing_sensor_events(ctx, effects, out);

    let faults = apply_faults(
        config,
        index,
        ctx.modalities,
        &ctx.outages,
        out,
        steps,
        &mut rng,
    );

    quantise(ctx, out);
    faults
}

/// A sensor's soil-water layers, one per `vw_depths_cm`, from the spatial fields at its
/// position (`[wilt, range, drying, gain, front]`) plus nugget drawn from `rng`; `dt` the
/// sampling step, days.
fn water_layers(
    config: &SynthConfig,
    dt: f64,
    [f_wilt, f_range, f_dry, f_gain, f_front]: [f64; 5],
    rng: &mut ChaCha8Rng,
) -> Vec<WaterLayer> {
    config
        .vw_depths_cm
        .iter()
        .map(|&d| {
            let d = f64::from(d);
            let tau = interp(&INFILTRATION_TAU_DAYS, d);
            let front_delay_days = interp(&FRONT_DELAY_DAYS, d) * (FRONT_DELAY_SD * f_front).exp();
            let pulse_in = interp(&PULSE_IN_TAU_DAYS, d);
            let pulse_tau = interp(&PULSE_TAU_DAYS, d);
            let gain = (0.3 * mix(f_gain, rng)).exp();
            WaterLayer {
                wilt: interp(&WILT_MEAN, d) + interp(&WILT_SD, d) * mix(f_wilt, rng),
                range: interp(&RANGE_MEAN, d) * (interp(&RANGE_CV, d) * mix(f_range, rng)).exp(),
                drying: interp(&DRYING_RATE, d) * (0.5 * mix(f_dry, rng)).exp(),
                gain: interp(&RAIN_GAIN, d) * gain,
                alpha: 1.0 - (-dt / tau).exp(),
                spin_alpha: 1.0 - (-1.0 / tau).exp(),
                pulse_alpha: 1.0 - (-dt / pulse_in).exp(),
                spin_pulse_alpha: 1.0 - (-1.0 / pulse_in).exp(),
                pulse_gain: interp(&PULSE_GAIN, d) * gain,
                pulse_decay: (-dt / pulse_tau).exp(),
                spin_pulse_decay: (-1.0 / pulse_tau).exp(),
                event_alpha: 1.0 - (-dt / interp(&EVENT_TAU_DAYS, d)).exp(),
                noise: interp(&VW_NOISE, d),
                common_noise: interp(&VW_COMMON_NOISE, d),
                anomaly_sd: interp(&ANOMALY_SD, d),
                anomaly_alpha: match interp(&ANOMALY_FILTER_DAYS, d) {
                    tau if tau > 0.0 => 1.0 - (-dt / tau).exp(),
                    _ => 1.0,
                },
                anomaly_state: f64::NAN,
                local_sd: interp(&LOCAL_SD, d),
                store: 0.5,
                inflow: 0.0,
                pulse: 0.0,
                pulse_inflow: 0.0,
                local: SmoothProcess::new(dt, interp(&LOCAL_TAU_DAYS, d), normal(rng)),
                percolates: d > TABLE_DEPTHS_CM[0],
                front: DelayLine::new(front_delay_days.round() as usize),
                front_delay_days,
                leak: 0.0,
                dry: 0.0,
            }
        })
        .collect()
}

/// The spin-up: daily steps before the record, no events, the field's mean storm response;
/// the fronts still on their way moved onto the sampling grid. Returns the topsoil and its
/// infiltration rate per sampling step.
fn spin_up(ctx: &Context<'_>, layers: &mut [WaterLayer]) -> (Topsoil, f64) {
    let dt = ctx.dt_days;
    let mut topsoil = Topsoil {
        store: 0.5,
        inflow: 0.0,
    };
    let top_tau = INFILTRATION_TAU_DAYS[0];
    let (spin_top_alpha, top_alpha) = (1.0 - (-1.0 / top_tau).exp(), 1.0 - (-dt / top_tau).exp());
    for k in 0..ctx.spin_up_rain_mm.len() {
        let rain = ctx.spin_up_rain_mm[k] * (1.0 - RAIN_INTERCEPTION * ctx.spin_up_et_surface[k]);
        let percolation = topsoil.percolation(rain);
        topsoil.step(rain, ctx.spin_up_et_surface[k], 1.0, spin_top_alpha);
        for (j, layer) in layers.iter_mut().enumerate() {
            let alphas = (layer.spin_alpha, layer.spin_pulse_alpha);
            let decay = layer.spin_pulse_decay;
            layer.water_step(rain, percolation, ctx.spin_up_et[j][k], 1.0, alphas, decay);
        }
    }
    // The fronts still on their way, moved onto the sampling grid.
    let per_day = (1.0 / dt).round().max(1.0) as usize;
    for layer in layers.iter_mut() {
        let steps = (layer.front_delay_days / dt).round() as usize;
        layer.front = layer.front.resampled(steps, per_day);
    }

    (topsoil, top_alpha)
}

/// Failing-sensor events: a drifting sensor's values drift, a stuck one's freeze; both are
/// missing from the event's end until the sensor is replaced.
fn failing_sensor_events(ctx: &Context<'_>, effects: &[EventEffect], out: &mut [f32]) {
    let (steps, dt) = (ctx.steps, ctx.dt_days);
    for e in effects {
        if !matches!(e.kind, EventKind::SensorDrift | EventKind::SensorStuck) {
            continue;
        }
        for (m, spec) in ctx.modalities.iter().enumerate() {
            let series = &mut out[m * steps..(m + 1) * steps];
            let frozen = series.get(e.start_step).copied().unwrap_or(f32::NAN);
            let replaced = e.end_step + (REPLACEMENT_DAYS / dt).round() as usize;
            for (t, v) in series.iter_mut().enumerate().skip(e.start_step) {
                if t >= replaced {
                    break;
                } else if t >= e.end_step {
                    *v = f32::NAN;
                } else if e.kind == EventKind::SensorStuck {
                    *v = frozen;
                } else {
                    let days = (t - e.start_step) as f64 * dt;
                    let (drift, (lo, hi)) = if spec.is_water {
                        (e.drift_vw, VW_RANGE)
                    } else {
                        (e.drift_t, T_RANGE)
                    };
                    *v = (f64::from(*v) + drift * days).clamp(lo, hi) as f32;
                }
            }
        }
    }
}

/// The sensor's resolution step: values are multiples of it (CAF: 0.001 m³/m³, 0.01 °C).
fn quantise(ctx: &Context<'_>, out: &mut [f32]) {
    let steps = ctx.steps;
    for (m, spec) in ctx.modalities.iter().enumerate() {
        let step = if spec.is_water {
            VW_RESOLUTION
        } else {
            T_RESOLUTION
        };
        for v in &mut out[m * steps..(m + 1) * steps] {
            if !v.is_nan() {
                let q = (f64::from(*v) / step).round() * step;
                *v = round_to(q, spec.decimals) as f32;
            }
        }
    }
}

/// The network-wide outages, `[start, end)` sampling steps: drawn day by day (a new one can
/// start only after the last has ended), from their own random stream.
fn network_outages(config: &SynthConfig, steps: usize) -> Vec<(usize, usize)> {
    let f = &config.faults;
    let mut out = Vec::new();
    if f.outage_per_day <= 0.0 || f.outage_share <= 0.0 {
        return out;
    }
    let per_day = (86_400 / config.interval_s.max(1)) as usize;
    let mut rng = stream(config.seed, Domain::Outages, 0);
    let mut day = 0usize;
    while day < config.days as usize {
        if uniform(&mut rng) < f.outage_per_day {
            let len = geometric_len(&mut rng, f.outage_mean_days);
            out.push((day * per_day, ((day + len) * per_day).min(steps)));
            day += len;
        } else {
            day += 1;
        }
    }
    out
}

/// Applies network outages, random dropouts, stuck stretches and spikes in place; returns
/// what was done.
fn apply_faults(
    config: &SynthConfig,
    sensor: usize,
    modalities: &[ModalitySpec],
    outages: &[(usize, usize)],
    out: &mut [f32],
    steps: usize,
    rng: &mut ChaCha8Rng,
) -> Vec<FaultRecord> {
    let f = &config.faults;
    let mut records = Vec::new();
    let time_at = |s: usize| config.start + s as i64 * config.interval_s;
    // The outages this station takes part in, one draw each, in order.
    let mut silent = vec![false; if outages.is_empty() { 0 } else { steps }];
    for &(a, b) in outages {
        if uniform(rng) < f.outage_share {
            records.push(FaultRecord {
                sensor,
                kind: FaultKind::Dropout,
                modality: None,
                start: time_at(a),
                end: time_at(b),
            });
            silent[a..b].iter_mut().for_each(|x| *x = true);
        }
    }
    let mods = modalities.len();
    let mut dropout_left = 0usize;
    let mut probe_left = vec![0usize; mods];
    let mut stuck_left = vec![0usize; mods];
    // Last value each modality reported: what a stuck sensor repeats.
    let mut last_reported = vec![f32::NAN; mods];
    for t in 0..steps {
        if dropout_left == 0 && uniform(rng) < f.dropout_per_step {
            let len = geometric_len(rng, f.dropout_mean_steps).min(steps - t);
            records.push(FaultRecord {
                sensor,
                kind: FaultKind::Dropout,
                modality: None,
                start: time_at(t),
                end: time_at(t + len),
            });
            dropout_left = len;
        }
        for (m, spec) in modalities.iter().enumerate() {
            let at = m * steps + t;
            if f.probe_dropout_per_step > 0.0
                && dropout_left == 0
                && probe_left[m] == 0
                && uniform(rng) < f.probe_dropout_per_step
            {
                let len = geometric_len(rng, f.probe_dropout_mean_steps).min(steps - t);
                records.push(FaultRecord {
                    sensor,
                    kind: FaultKind::Dropout,
                    modality: Some(m),
                    start: time_at(t),
                    end: time_at(t + len),
                });
                probe_left[m] = len;
            }
            // Stuck stretches hit soil water only (CAF's temperatures hardly repeat).
            if stuck_left[m] == 0 && t > 0 && uniform(rng) < f.stuck_per_step && spec.is_water {
                let len = geometric_len(rng, f.stuck_mean_steps).min(steps - t);
                records.push(FaultRecord {
                    sensor,
                    kind: FaultKind::Stuck,
                    modality: Some(m),
                    start: time_at(t),
                    end: time_at(t + len),
                });
                stuck_left[m] = len;
            }
            // Spikes hit soil water only (CAF's temperatures show none).
            let spike = uniform(rng) < f.spike_per_reading && spec.is_water;
            if stuck_left[m] > 0 {
                stuck_left[m] -= 1;
                // A reading that is missing anyway (a dead sensor) stays missing.
                if !out[at].is_nan() && !last_reported[m].is_nan() {
                    out[at] = last_reported[m];
                }
            } else if spike && dropout_left == 0 && !out[at].is_nan() {
                let mut up = uniform(rng) < 0.5;
                let (size, (lo, hi)) = if spec.is_water {
                    (0.05 + 0.10 * uniform(rng), VW_RANGE)
                } else {
                    (0.5 + 1.0 * uniform(rng), T_RANGE)
                };
                // Soil temperature spikes do not cross 0 °C (the frost floor): they go up.
                if !spec.is_water && f64::from(out[at]) - size < T_FREEZE_KNEE_C {
                    up = true;
                }
                let v = f64::from(out[at]) + if up { size } else { -size };
                out[at] = v.clamp(lo, hi) as f32;
                records.push(FaultRecord {
                    sensor,
                    kind: FaultKind::Spike,
                    modality: Some(m),
                    start: time_at(t),
                    end: time_at(t + 1),
                });
            }
            if dropout_left > 0 || probe_left[m] > 0 || silent.get(t).copied().unwrap_or(false) {
                out[at] = f32::NAN;
            } else if !out[at].is_nan() {
                last_reported[m] = out[at];
            }
            probe_left[m] = probe_left[m].saturating_sub(1);
        }
        dropout_left = dropout_left.saturating_sub(1);
    }
    records
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_farm_laid_on_a_layout_keeps_its_stations_ids_and_positions() {
        let layout: Vec<(SensorId, LatLon)> = [
            ("CAF003", 46.7825, -117.0852),
            ("CAF007", 46.7811, -117.0790),
            ("CAF009", 46.7790, -117.0821),
        ]
        .iter()
        .map(|&(id, lat, lon)| (SensorId::new(id).unwrap(), LatLon::new(lat, lon).unwrap()))
        .collect();
        let config = SynthConfig {
            seed: 3,
            days: 20,
            ..SynthConfig::default()
        }
        .on_layout(layout.clone())
        .unwrap();
        assert_eq!(config.sensor_count, 3);
        let farm = generate(&config).unwrap();
        assert_eq!(farm.sensors().len(), 3);
        for (s, (id, p)) in farm.sensors().iter().zip(&layout) {
            assert_eq!(&s.id, id);
            assert!((s.position.lat() - p.lat()).abs() < 1e-7, "{s:?}");
            assert!((s.position.lon() - p.lon()).abs() < 1e-7, "{s:?}");
        }
        assert!(farm.reading_count() > 0);
        // Deterministic, and a mismatched count or a repeated id is refused.
        assert_eq!(
            generate(&config).unwrap().reading_count(),
            farm.reading_count()
        );
        let mut wrong = config.clone();
        wrong.sensor_count = 4;
        assert!(generate(&wrong).is_err());
        let twice = vec![layout[0].clone(), layout[0].clone()];
        assert!(generate(&SynthConfig::default().on_layout(twice).unwrap()).is_err());
        assert!(SynthConfig::default().on_layout(Vec::new()).is_err());
    }

    #[test]
    fn interp_clamps_and_interpolates() {
        let table = [1.0, 2.0, 3.0, 4.0, 5.0];
        assert_eq!(interp(&table, 10.0), 1.0);
        assert_eq!(interp(&table, 45.0), 1.5);
        assert_eq!(interp(&table, 150.0), 5.0);
        assert_eq!(interp(&table, 400.0), 5.0);
    }

    #[test]
    fn storm_rate_peaks_in_winter() {
        let c = SynthConfig::default();
        assert!(storm_rate_per_day(&c, 30.0) > 3.0 * storm_rate_per_day(&c, 210.0));
        let peak = c.climate.et_peak_doy;
        assert!(et_factor(&c, peak) > 0.99 && et_factor(&c, 15.0) < 0.1);
        // Southern hemisphere: the same seasons half a year later.
        let south = SynthConfig {
            climate: c.climate.shifted(182.625),
            ..c.clone()
        };
        let later = (peak + 182.625).rem_euclid(365.25);
        assert!((et_factor(&south, later) - et_factor(&c, peak)).abs() < 1e-9);
        assert!((storm_rate_per_day(&south, 210.625) - storm_rate_per_day(&c, 28.0)).abs() < 1e-9);
    }
}
