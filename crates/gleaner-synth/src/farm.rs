//! The generated farm held in memory: sensors, readings, ground truth.

use gleaner_field::{LatLon, LocalPoint, Modality, Sensor, TransverseMercator, UnixSeconds};

/// The kind of a localised ground-truth event.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum EventKind {
    /// An irrigation leak: soil in a disc of the event's radius wets towards saturation at
    /// every depth (the deeper, the later), then dries after the leak is fixed.
    Leak,
    /// A patch drying out (e.g. a compacted or diseased patch with strong uptake): volumetric
    /// water in the disc falls towards the wilting baseline at every depth, and rain helps less.
    DryPatch,
    /// One failing sensor whose readings drift (VW by up to ±0.004 m³/m³ per day, T by up to
    /// ±0.05 °C per day) from the event's start; it falls silent at the end.
    SensorDrift,
    /// One failing sensor whose readings freeze at their value at the event's start; it falls
    /// silent at the end.
    SensorStuck,
}

impl EventKind {
    /// The name used in files: `leak`, `dry_patch`, `sensor_drift`, `sensor_stuck`.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Leak => "leak",
            Self::DryPatch => "dry_patch",
            Self::SensorDrift => "sensor_drift",
            Self::SensorStuck => "sensor_stuck",
        }
    }
}

/// A localised event with its ground truth: where, when and which sensors it touched.
#[derive(Debug, Clone, PartialEq)]
pub struct GroundTruthEvent {
    /// Identifier, `E001`, `E002`, ...
    pub id: String,
    /// What happened.
    pub kind: EventKind,
    /// First affected sampling time, seconds since the Unix epoch.
    pub start: UnixSeconds,
    /// End of the event (exclusive), seconds since the Unix epoch: the first sampling time no
    /// longer driven by it (effects on soil water then fade over days).
    pub end: UnixSeconds,
    /// Centre of the affected disc (the sensor's position for a failing sensor), WGS84.
    pub centre: LatLon,
    /// Radius of the affected disc, metres (0 for a failing sensor).
    pub radius_m: f64,
    /// Indices into [`SynthFarm::sensors`] of the affected sensors, ascending.
    pub affected: Vec<usize>,
}

/// The kind of a random sensor fault.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FaultKind {
    /// The whole station is silent: every modality missing.
    Dropout,
    /// One reading of one modality jumps.
    Spike,
    /// One modality repeats its last value.
    Stuck,
}

impl FaultKind {
    /// The name used in files: `dropout`, `spike`, `stuck`.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Dropout => "dropout",
            Self::Spike => "spike",
            Self::Stuck => "stuck",
        }
    }
}

/// One random fault, recorded so that evaluations can tell faults from signal.
#[derive(Debug, Clone, PartialEq)]
pub struct FaultRecord {
    /// Index into [`SynthFarm::sensors`].
    pub sensor: usize,
    /// What went wrong.
    pub kind: FaultKind,
    /// Index into [`SynthFarm::modalities`]; `None` for a dropout (all modalities).
    pub modality: Option<usize>,
    /// First affected sampling time, seconds since the Unix epoch.
    pub start: UnixSeconds,
    /// End (exclusive), seconds since the Unix epoch.
    pub end: UnixSeconds,
}

/// A modality the farm reports, with its unit and the number of decimals written.
#[derive(Debug, Clone, PartialEq)]
pub struct ModalitySpec {
    /// E.g. `vw@30cm`.
    pub modality: Modality,
    /// `m3/m3` for volumetric water content, `degC` for temperature.
    pub unit: &'static str,
    /// Decimal places in CSV output (4).
    pub decimals: u32,
    /// Depth below the surface, centimetres.
    pub depth_cm: u32,
    /// True for volumetric water content, false for temperature.
    pub is_water: bool,
}

/// One reading: sensor `sensor` reported `value` (in the modality's unit) at `time`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reading {
    /// Index into [`SynthFarm::sensors`].
    pub sensor: usize,
    /// Sampling time, seconds since the Unix epoch.
    pub time: UnixSeconds,
    /// Index into [`SynthFarm::modalities`].
    pub modality: usize,
    /// Value in the modality's unit (m³/m³ or °C).
    pub value: f64,
}

/// A generated farm: the sensors, every reading, and the ground truth of events and faults.
///
/// Readings are held densely, `sensors x modalities x steps` single-precision values (NaN for
/// a missing reading), already rounded to the decimals written to CSV.
#[derive(Debug, Clone)]
pub struct SynthFarm {
    pub(crate) sensors: Vec<Sensor>,
    pub(crate) local: Vec<LocalPoint>,
    pub(crate) frame: TransverseMercator,
    pub(crate) base: LatLon,
    pub(crate) modalities: Vec<ModalitySpec>,
    pub(crate) times: Vec<UnixSeconds>,
    pub(crate) values: Vec<f32>,
    pub(crate) events: Vec<GroundTruthEvent>,
    pub(crate) faults: Vec<FaultRecord>,
}

impl SynthFarm {
    /// The sensors, ids `SYN00001`, `SYN00002`, ... (at least five digits).
    pub fn sensors(&self) -> &[Sensor] {
        &self.sensors
    }
    /// Sensor positions in the local east/north frame of [`Self::frame`], metres.
    pub fn local_positions(&self) -> &[LocalPoint] {
        &self.local
    }
    /// The local frame, centred on the configured field centre.
    pub fn frame(&self) -> &TransverseMercator {
        &self.frame
    }
    /// The base station, WGS84.
    pub fn base(&self) -> LatLon {
        self.base
    }
    /// The reported modalities: VW depths first, then temperature depths, as configured.
    pub fn modalities(&self) -> &[ModalitySpec] {
        &self.modalities
    }
    /// Index of a modality by name (e.g. `vw@30cm`).
    pub fn modality_index(&self, name: &str) -> Option<usize> {
        self.modalities
            .iter()
            .position(|m| m.modality.as_str() == name)
    }
    /// Sampling times, seconds since the Unix epoch, ascending.
    pub fn times(&self) -> &[UnixSeconds] {
        &self.times
    }
    /// Localised events, in id order.
    pub fn events(&self) -> &[GroundTruthEvent] {
        &self.events
    }
    /// Random faults, ordered by sensor, then as generated.
    pub fn faults(&self) -> &[FaultRecord] {
        &self.faults
    }
    /// The full series of `sensor`'s `modality`, one value per sampling time, NaN when
    /// missing. Panics if an index is out of range.
    pub fn series(&self, sensor: usize, modality: usize) -> &[f32] {
        let steps = self.times.len();
        let at = (sensor * self.modalities.len() + modality) * steps;
        &self.values[at..at + steps]
    }
    /// One reading, `None` when missing or out of range.
    pub fn value(&self, sensor: usize, modality: usize, step: usize) -> Option<f64> {
        if sensor >= self.sensors.len() || modality >= self.modalities.len() {
            return None;
        }
        let v = *self.series(sensor, modality).get(step)?;
        (!v.is_nan()).then_some(f64::from(v))
    }
    /// Every present reading, ordered by sensor, then time, then modality (the CSV order).
    pub fn readings(&self) -> impl Iterator<Item = Reading> + '_ {
        let steps = self.times.len();
        let mods = self.modalities.len();
        (0..self.sensors.len()).flat_map(move |s| {
            (0..steps).flat_map(move |t| {
                (0..mods).filter_map(move |m| {
                    let v = self.values[(s * mods + m) * steps + t];
                    (!v.is_nan()).then_some(Reading {
                        sensor: s,
                        time: self.times[t],
                        modality: m,
                        value: f64::from(v),
                    })
                })
            })
        })
    }
    /// Number of present readings.
    pub fn reading_count(&self) -> usize {
        self.values.iter().filter(|v| !v.is_nan()).count()
    }
}
