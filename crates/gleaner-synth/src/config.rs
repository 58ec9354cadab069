//! The generator's configuration: plain data with documented units and CAF-like defaults.

use gleaner_field::{LatLon, SensorId, TransverseMercator, UnixSeconds};

use crate::SynthError;

/// Number of stations in the Cook Agronomy Farm network (42): the density reference when
/// [`SynthConfig::scale_extent_with_sensors`] is on.
pub const CAF_SENSOR_COUNT: usize = 42;

/// Largest farm [`crate::generate`] accepts, in values (sensors x modalities x steps): 2e9
/// single-precision values, 8 GB of memory.
pub const MAX_VALUES: u64 = 2_000_000_000;

/// 2014-01-01T00:00:00Z, the default start, seconds since the Unix epoch.
pub const DEFAULT_START: UnixSeconds = 1_388_534_400;

/// Everything the generator needs. All fields are public; start from [`Default`] and change
/// what you need:
///
/// ```
/// let config = gleaner_synth::SynthConfig {
///     seed: 7,
///     sensor_count: 100,
///     days: 30,
///     ..Default::default()
/// };
/// assert!(config.validate().is_ok());
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct SynthConfig {
    /// Seed of every random choice; the same seed gives byte-identical output whatever the
    /// number of threads.
    pub seed: u64,
    /// Number of sensor stations (default 42, like CAF). At least 1.
    pub sensor_count: usize,
    /// Length of the record, days (default 365). At least 1.
    pub days: u32,
    /// Time of the first reading, seconds since 1970-01-01T00:00:00Z (default
    /// 2014-01-01T00:00:00Z, [`DEFAULT_START`]).
    pub start: UnixSeconds,
    /// Sampling interval, seconds (default 86 400 s = daily). Between 60 s and 86 400 s and a
    /// divisor of 86 400 s, so that every day has the same sampling times.
    pub interval_s: i64,
    /// Field extent `[east-west, north-south]`, metres (default `[870, 520]`, the CAF field).
    pub extent_m: [f64; 2],
    /// When true, the extent is multiplied by `sqrt(sensor_count / 42)` so that the sensor
    /// density stays that of CAF (about 93 stations per km²). Default false.
    pub scale_extent_with_sensors: bool,
    /// Centre of the field rectangle, WGS84 degrees (default lat 46.7807, lon -117.0820, the
    /// centroid of the CAF stations). The rectangle is axis-aligned in the local east/north frame.
    pub centre: LatLon,
    /// Base station (UAV take-off point), WGS84 degrees (default lat 46.7800, lon -117.0840,
    /// near CAF). Only carried through to the output; it does not shape the data.
    pub base: LatLon,
    /// Depths of the volumetric water content modalities `vw@<d>cm`, centimetres (default
    /// 30, 60, 90). May be empty.
    pub vw_depths_cm: Vec<u32>,
    /// Depths of the soil temperature modalities `t@<d>cm`, centimetres (default 30). May be
    /// empty.
    pub t_depths_cm: Vec<u32>,
    /// Correlation length of the spatial fields (soil texture, sensor offsets, the moving
    /// anomaly field), metres (default 500 m): the `l` of the Gaussian covariance
    /// `exp(-r^2 / (2 l^2))`.
    pub correlation_length_m: f64,
    /// Rates of sensor faults (dropouts, spikes, stuck values).
    pub faults: FaultRates,
    /// Number of localised ground-truth events (default 12). Kinds cycle through irrigation
    /// leak, drying patch and failing sensor (drift or stuck).
    pub event_count: usize,
    /// Shortest and longest duration of an event, days (default `[7, 28]`; uniform between).
    /// Both at least 1 and `[0] <= [1]`. Events start uniformly between 5 % of the record
    /// and the latest start that lets them end by 95 % of it.
    pub event_duration_days: [f64; 2],
    /// Radius of leak and drying patches, metres. `None` (default) chooses
    /// `max(30 m, mean sensor spacing)`, so a patch covers one to a few stations.
    pub event_radius_m: Option<f64>,
    /// Weather and soil-temperature drivers.
    pub climate: Climate,
    /// Lay the farm on these stations (id, WGS84 position) instead of a jittered grid: the
    /// synthetic weather, soils and faults are drawn at a real network's own positions
    /// (e.g. CAF's layout). `sensor_count` and the extent are then taken from the layout and
    /// the field centre is its centroid. Default `None`.
    pub layout: Option<Vec<(SensorId, LatLon)>>,
}

impl Default for SynthConfig {
    fn default() -> Self {
        Self {
            seed: 0,
            sensor_count: CAF_SENSOR_COUNT,
            days: 365,
            start: DEFAULT_START,
            interval_s: 86_400,
            extent_m: [870.0, 520.0],
            scale_extent_with_sensors: false,
            centre: LatLon::new(46.7807, -117.0820).expect("constant position is valid"),
            base: LatLon::new(46.7800, -117.0840).expect("constant position is valid"),
            vw_depths_cm: vec![30, 60, 90],
            t_depths_cm: vec![30],
            correlation_length_m: 500.0,
            faults: FaultRates::default(),
            event_count: 12,
            event_duration_days: [7.0, 28.0],
            event_radius_m: None,
            climate: Climate::default(),
            layout: None,
        }
    }
}

/// Sensor fault rates. A fault never hides a ground-truth event's signal completely, but it
/// can overlap one, as in the field.
#[derive(Debug, Clone, PartialEq)]
pub struct FaultRates {
    /// Probability, per sensor and sampling step, that a dropout (the whole station silent:
    /// every modality missing) starts (default 0.0025 per step). In [0, 1).
    pub dropout_per_step: f64,
    /// Mean length of a dropout, sampling steps (geometric; default 40). At least 1.
    pub dropout_mean_steps: f64,
    /// Probability that a single soil-water reading is a spike (default 0.0001): a jump of
    /// 0.05..0.15 m³/m³, up or down, clamped to the physical range. In [0, 1).
    pub spike_per_reading: f64,
    /// Probability, per sensor, modality and step, that the modality gets stuck (repeats its
    /// last value; soil water only) (default 0.0025 per step). In [0, 1).
    pub stuck_per_step: f64,
    /// Mean length of a stuck stretch, steps (geometric; default 20). At least 1.
    pub stuck_mean_steps: f64,
    /// Probability, per sensor, modality and step, that one modality alone falls silent (a
    /// dead probe at one depth while the station keeps reporting the others; default 0.0015
    /// per step). Recorded as a [`crate::FaultKind::Dropout`] with `modality = Some(m)`. In
    /// [0, 1).
    pub probe_dropout_per_step: f64,
    /// Mean length of a single-probe dropout, steps (geometric; default 45). At least 1.
    pub probe_dropout_mean_steps: f64,
    /// Probability, per day, that a network-wide outage starts (the logger network or its
    /// telemetry down: most stations silent at once; default 0.0035 per day, about 1.3 a
    /// year). Outages are drawn on a daily grid whatever the sampling interval. In [0, 1).
    pub outage_per_day: f64,
    /// Mean length of a network-wide outage, days (geometric; default 22). At least 1.
    pub outage_mean_days: f64,
    /// Probability that a given station goes silent in a network-wide outage (default 0.85;
    /// recorded per station as a [`crate::FaultKind::Dropout`] of the whole station). In [0, 1].
    pub outage_share: f64,
}

impl FaultRates {
    /// No faults at all: every reading present and clean.
    pub fn none() -> Self {
        Self {
            dropout_per_step: 0.0,
            dropout_mean_steps: 1.0,
            spike_per_reading: 0.0,
            stuck_per_step: 0.0,
            stuck_mean_steps: 1.0,
            probe_dropout_per_step: 0.0,
            probe_dropout_mean_steps: 1.0,
            outage_per_day: 0.0,
            outage_mean_days: 1.0,
            outage_share: 0.0,
        }
    }
}

impl Default for FaultRates {
    fn default() -> Self {
        Self {
            dropout_per_step: 0.0025,
            dropout_mean_steps: 40.0,
            spike_per_reading: 0.0001,
            stuck_per_step: 0.0025,
            stuck_mean_steps: 20.0,
            probe_dropout_per_step: 0.0015,
            probe_dropout_mean_steps: 45.0,
            outage_per_day: 0.005,
            outage_mean_days: 25.0,
            outage_share: 0.85,
        }
    }
}

/// Weather and soil-temperature drivers shared by the whole field. Defaults follow the
/// Palouse climate of CAF (wet winters, dry summers) and the CAF calibration (crate docs).
#[derive(Debug, Clone, PartialEq)]
pub struct Climate {
    /// Mean number of storms per year (default 75). Storms are a Poisson process.
    pub storms_per_year: f64,
    /// Relative seasonal amplitude of the storm rate, in [0, 1] (default 0.7): the rate is
    /// `mean x (1 + a cos(2 pi (doy - peak_doy) / 365.25))`.
    pub storm_seasonality: f64,
    /// Day of year of the wettest season (peak storm rate), days since 1 January (default 30,
    /// end of January: with the growing season it makes the soil wettest in April).
    pub storm_peak_doy: f64,
    /// Mean rain per storm, millimetres (exponentially distributed; default 7 mm).
    pub storm_mean_mm: f64,
    /// Mean annual soil temperature, °C (default 10.2).
    pub mean_soil_temp_c: f64,
    /// Amplitude of the annual temperature wave at the surface, °C (default 11.2).
    pub surface_annual_amplitude_c: f64,
    /// Amplitude of the daily temperature wave at the surface, °C (default 8.0); visible only
    /// with sub-daily sampling and in the top few tens of centimetres.
    pub surface_daily_amplitude_c: f64,
    /// Day of year of the warmest surface temperature, days since 1 January (default 200).
    pub warmest_doy: f64,
    /// Annual damping depth of the temperature wave, centimetres (default 165 cm): amplitude
    /// falls as `exp(-z / D)` and the phase lags by `z / D` radians.
    pub annual_damping_depth_cm: f64,
    /// Day of year of peak evapotranspiration (crop water use) at 30 cm, days since 1
    /// January (default 175, late June; deeper layers peak later). With `storm_peak_doy`
    /// and `warmest_doy` it sets the seasonal phase: with the defaults the soil is wettest
    /// in April and driest in September, as at CAF. [`Climate::shifted`] moves all three.
    pub et_peak_doy: f64,
}

impl Climate {
    /// The same climate with every seasonal phase (`storm_peak_doy`, `warmest_doy`,
    /// `et_peak_doy`) moved by `days` (e.g. 182.6 for a southern-hemisphere farm), wrapped
    /// into [0, 365.25).
    pub fn shifted(&self, days: f64) -> Climate {
        let wrap = |d: f64| (d + days).rem_euclid(365.25);
        Climate {
            storm_peak_doy: wrap(self.storm_peak_doy),
            warmest_doy: wrap(self.warmest_doy),
            et_peak_doy: wrap(self.et_peak_doy),
            ..self.clone()
        }
    }
}

impl Default for Climate {
    fn default() -> Self {
        Self {
            storms_per_year: 75.0,
            storm_seasonality: 0.7,
            storm_peak_doy: 30.0,
            storm_mean_mm: 7.0,
            mean_soil_temp_c: 10.2,
            surface_annual_amplitude_c: 11.2,
            surface_daily_amplitude_c: 8.0,
            warmest_doy: 200.0,
            annual_damping_depth_cm: 165.0,
            et_peak_doy: 195.0,
        }
    }
}

fn invalid(name: &'static str, value: impl ToString, reason: &'static str) -> SynthError {
    SynthError::InvalidSetting {
        name,
        value: value.to_string(),
        reason,
    }
}

fn check_probability(name: &'static str, p: f64) -> Result<(), SynthError> {
    if p.is_finite() && (0.0..1.0).contains(&p) {
        Ok(())
    } else {
        Err(invalid(name, p, "must be a probability in [0, 1)"))
    }
}

fn check_at_least(name: &'static str, v: f64, min: f64) -> Result<(), SynthError> {
    if v.is_finite() && v >= min {
        Ok(())
    } else {
        Err(invalid(name, v, "must be finite and not below its minimum"))
    }
}

fn check_depths(name: &'static str, depths: &[u32]) -> Result<(), SynthError> {
    let mut sorted = depths.to_vec();
    sorted.sort_unstable();
    sorted.dedup();
    if sorted.len() != depths.len() || depths.iter().any(|d| !(1..=1000).contains(d)) {
        return Err(SynthError::InvalidDepths {
            name,
            depths: depths.to_vec(),
        });
    }
    Ok(())
}

impl SynthConfig {
    /// Checks every setting; [`crate::generate`] calls this first.
    pub fn validate(&self) -> Result<(), SynthError> {
        self.check_layout()?;
        if self.sensor_count == 0 || self.sensor_count > 10_000_000 {
            return Err(invalid(
                "sensor_count",
                self.sensor_count,
                "must be in 1..=10000000",
            ));
        }
        if self.days == 0 || self.days > 100 * 366 {
            return Err(invalid("days", self.days, "must be in 1..=36600"));
        }
        if !(60..=86_400).contains(&self.interval_s) || 86_400 % self.interval_s != 0 {
            return Err(invalid(
                "interval_s",
                self.interval_s,
                "must be in 60..=86400 s and divide 86400 s",
            ));
        }
        // Keep every timestamp within years 0..=9999 so RFC 3339 output stays four-digit.
        let end = self.start.checked_add(i64::from(self.days) * 86_400);
        if self.start < -62_167_219_200 || end.is_none_or(|e| e > 253_402_300_799) {
            return Err(invalid(
                "start",
                self.start,
                "record must lie within years 0000..=9999",
            ));
        }
        for (name, v) in [
            ("extent_m[0]", self.extent_m[0]),
            ("extent_m[1]", self.extent_m[1]),
        ] {
            if !(v.is_finite() && v > 0.0 && v <= 1.0e6) {
                return Err(invalid(name, v, "must be in (0, 1e6] m"));
            }
        }
        if !(self.correlation_length_m.is_finite() && self.correlation_length_m > 0.0) {
            return Err(invalid(
                "correlation_length_m",
                self.correlation_length_m,
                "must be positive and finite",
            ));
        }
        check_depths("vw_depths_cm", &self.vw_depths_cm)?;
        check_depths("t_depths_cm", &self.t_depths_cm)?;
        if self.vw_depths_cm.len() + self.t_depths_cm.len() > 1000 {
            return Err(invalid(
                "vw_depths_cm + t_depths_cm",
                self.vw_depths_cm.len() + self.t_depths_cm.len(),
                "at most 1000 modalities",
            ));
        }
        let values = (self.sensor_count as u128)
            * (self.vw_depths_cm.len() + self.t_depths_cm.len()) as u128
            * (u128::from(self.days) * 86_400 / self.interval_s as u128);
        if values > MAX_VALUES as u128 {
            return Err(invalid(
                "sensor_count x modalities x steps",
                values,
                "at most 2e9 values (8 GB in memory)",
            ));
        }
        self.check_faults()?;
        self.check_events()?;
        self.check_climate()
    }

    /// A layout: at least one station, as many as `sensor_count`, distinct ids.
    fn check_layout(&self) -> Result<(), SynthError> {
        if let Some(layout) = &self.layout {
            if layout.is_empty() {
                return Err(invalid("layout", 0, "must hold at least one station"));
            }
            if layout.len() != self.sensor_count {
                return Err(invalid(
                    "sensor_count",
                    self.sensor_count,
                    "must equal the layout's station count (see SynthConfig::on_layout)",
                ));
            }
            let mut ids: Vec<&SensorId> = layout.iter().map(|(id, _)| id).collect();
            ids.sort();
            if let Some(w) = ids.windows(2).find(|w| w[0] == w[1]) {
                return Err(invalid(
                    "layout",
                    w[0].as_str(),
                    "station ids must be distinct",
                ));
            }
        }
        Ok(())
    }

    /// The fault rates: probabilities in [0, 1], mean lengths at least 1.
    fn check_faults(&self) -> Result<(), SynthError> {
        let f = &self.faults;
        check_probability("faults.dropout_per_step", f.dropout_per_step)?;
        check_probability("faults.spike_per_reading", f.spike_per_reading)?;
        check_probability("faults.stuck_per_step", f.stuck_per_step)?;
        check_at_least("faults.dropout_mean_steps", f.dropout_mean_steps, 1.0)?;
        check_at_least("faults.stuck_mean_steps", f.stuck_mean_steps, 1.0)?;
        check_probability("faults.probe_dropout_per_step", f.probe_dropout_per_step)?;
        check_at_least(
            "faults.probe_dropout_mean_steps",
            f.probe_dropout_mean_steps,
            1.0,
        )?;
        check_probability("faults.outage_per_day", f.outage_per_day)?;
        check_at_least("faults.outage_mean_days", f.outage_mean_days, 1.0)?;
        if !(f.outage_share.is_finite() && (0.0..=1.0).contains(&f.outage_share)) {
            return Err(invalid(
                "faults.outage_share",
                f.outage_share,
                "must be a probability in [0, 1]",
            ));
        }
        Ok(())
    }

    /// The ground-truth events: at most 10000, durations ascending from 1 day, a positive radius.
    fn check_events(&self) -> Result<(), SynthError> {
        if self.event_count > 10_000 {
            return Err(invalid("event_count", self.event_count, "at most 10000"));
        }
        let [d0, d1] = self.event_duration_days;
        if !(d0.is_finite() && d1.is_finite() && d0 >= 1.0 && d0 <= d1) {
            return Err(invalid(
                "event_duration_days",
                format!("[{d0}, {d1}]"),
                "must be finite, at least 1 day and ascending",
            ));
        }
        if let Some(r) = self.event_radius_m.filter(|r| !(r.is_finite() && *r > 0.0)) {
            return Err(invalid("event_radius_m", r, "must be positive and finite"));
        }
        Ok(())
    }

    /// The climate: storms, seasons and temperatures finite and in range.
    fn check_climate(&self) -> Result<(), SynthError> {
        let c = &self.climate;
        check_at_least("climate.storms_per_year", c.storms_per_year, 0.0)?;
        if c.storms_per_year > 365.0 * 24.0 {
            return Err(invalid(
                "climate.storms_per_year",
                c.storms_per_year,
                "at most one storm per hour on average",
            ));
        }
        if !(c.storm_seasonality.is_finite() && (0.0..=1.0).contains(&c.storm_seasonality)) {
            return Err(invalid(
                "climate.storm_seasonality",
                c.storm_seasonality,
                "must be in [0, 1]",
            ));
        }
        check_at_least("climate.storm_mean_mm", c.storm_mean_mm, 0.0)?;
        check_at_least(
            "climate.annual_damping_depth_cm",
            c.annual_damping_depth_cm,
            1.0,
        )?;
        for (name, v) in [
            ("climate.storm_peak_doy", c.storm_peak_doy),
            ("climate.mean_soil_temp_c", c.mean_soil_temp_c),
            ("climate.warmest_doy", c.warmest_doy),
            ("climate.et_peak_doy", c.et_peak_doy),
        ] {
            if !v.is_finite() {
                return Err(invalid(name, v, "must be finite"));
            }
        }
        for (name, v) in [
            (
                "climate.surface_annual_amplitude_c",
                c.surface_annual_amplitude_c,
            ),
            (
                "climate.surface_daily_amplitude_c",
                c.surface_daily_amplitude_c,
            ),
        ] {
            if !(v.is_finite() && (0.0..=40.0).contains(&v)) {
                return Err(invalid(name, v, "must be in [0, 40] degC"));
            }
        }
        Ok(())
    }

    /// This configuration laid on `layout` (station ids with WGS84 positions, at least one):
    /// [`Self::layout`] set, `sensor_count` its length, the field centre its centroid and the
    /// extent its bounding box in the local frame (at least 1 m a side), so the spatial fields
    /// and the events span the real network.
    pub fn on_layout(mut self, layout: Vec<(SensorId, LatLon)>) -> Result<Self, SynthError> {
        if layout.is_empty() {
            return Err(invalid("layout", 0, "must hold at least one station"));
        }
        let n = layout.len() as f64;
        let lat = layout.iter().map(|(_, p)| p.lat()).sum::<f64>() / n;
        let lon = layout.iter().map(|(_, p)| p.lon()).sum::<f64>() / n;
        let centre = LatLon::new(lat, lon).map_err(|_| SynthError::InvalidSetting {
            name: "layout",
            value: format!("centroid {lat}, {lon}"),
            reason: "its centroid is not a valid position",
        })?;
        let frame = TransverseMercator::local(centre);
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for (_, p) in &layout {
            let q = frame.forward(*p);
            for (k, v) in [q.e, q.n].into_iter().enumerate() {
                lo[k] = lo[k].min(v);
                hi[k] = hi[k].max(v);
            }
        }
        self.extent_m = [0, 1].map(|k| 2.0 * lo[k].abs().max(hi[k].abs()).max(0.5));
        self.centre = centre;
        self.sensor_count = layout.len();
        self.scale_extent_with_sensors = false;
        self.layout = Some(layout);
        Ok(self)
    }

    /// The field extent actually used, `[east-west, north-south]` metres, after the optional
    /// constant-density scaling.
    pub fn effective_extent_m(&self) -> [f64; 2] {
        if self.scale_extent_with_sensors {
            let k = (self.sensor_count as f64 / CAF_SENSOR_COUNT as f64).sqrt();
            [self.extent_m[0] * k, self.extent_m[1] * k]
        } else {
            self.extent_m
        }
    }

    /// Number of sampling steps: `days x 86400 / interval_s`.
    pub fn steps(&self) -> usize {
        (i64::from(self.days) * 86_400 / self.interval_s.max(1)) as usize
    }
}
