//! Fixtures shared by gleaner's cross-crate benchmarks (`cargo bench -p gleaner-benches`).
//!
//! The benchmarks themselves live in `benches/`; this library only builds their inputs, with a
//! fixed seed so that every run measures the same work. [`fuzz`] is the mutation fuzzer of every
//! reader of untrusted input, run by the `gleaner-fuzz` binary.
#![deny(missing_docs)]

pub mod fuzz;

use gleaner_field::{LatLon, LocalPoint, Sensor, SensorId, TransverseMercator};

/// A tiny deterministic generator (SplitMix64) so fixtures need no extra dependency.
#[derive(Debug, Clone)]
pub struct SplitMix(u64);

impl SplitMix {
    /// A generator from a seed.
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }
    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// The base station used by the fixtures (near the Cook Agronomy Farm), WGS84 degrees.
pub fn base() -> LatLon {
    LatLon::new(46.78, -117.08).expect("valid constant")
}

/// `n` sensors placed uniformly at random in a `side_m` x `side_m` square whose south-west
/// corner is the base station, metres.
pub fn random_sensors(n: usize, side_m: f64, seed: u64) -> Vec<Sensor> {
    let frame = TransverseMercator::local(base());
    let mut rng = SplitMix::new(seed);
    (0..n)
        .map(|k| {
            let p = LocalPoint::new(rng.unit() * side_m, rng.unit() * side_m);
            Sensor::new(
                SensorId::new(format!("S{k:05}")).expect("valid id"),
                frame.inverse(p),
            )
        })
        .collect()
}
