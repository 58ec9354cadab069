//! Seeded random streams and the few distributions the model needs (no extra dependency).
//!
//! Every random choice comes from a ChaCha8 stream keyed by the user's seed and a domain tag;
//! per-sensor work uses the stream numbered by the sensor's index, so the output does not
//! depend on the order in which threads run.

use gleaner_field::LocalPoint;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Domains of randomness: each gets its own key so adding draws to one never shifts another.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Domain {
    Layout = 1,
    Fields = 2,
    Weather = 3,
    Events = 4,
    Sensor = 5,
    Outages = 6,
}

fn splitmix64(mut x: u64) -> u64 {
    x = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    x ^ (x >> 31)
}

/// The random stream `stream` of `domain` for `seed`.
pub(crate) fn stream(seed: u64, domain: Domain, stream: u64) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(splitmix64(seed ^ splitmix64(domain as u64)));
    rng.set_stream(stream);
    rng
}

/// Uniform in [0, 1).
pub(crate) fn uniform(rng: &mut ChaCha8Rng) -> f64 {
    rng.random::<f64>()
}

/// Standard normal (Box-Muller, one value per call).
pub(crate) fn normal(rng: &mut ChaCha8Rng) -> f64 {
    let u1 = 1.0 - uniform(rng); // (0, 1]
    let u2 = uniform(rng);
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// Exponential with the given mean.
pub(crate) fn exponential(rng: &mut ChaCha8Rng, mean: f64) -> f64 {
    -(1.0 - uniform(rng)).ln() * mean
}

/// Poisson with mean `lambda` (Knuth's multiplication method; the model only uses small means).
pub(crate) fn poisson(rng: &mut ChaCha8Rng, lambda: f64) -> u32 {
    if lambda <= 0.0 {
        return 0;
    }
    let limit = (-lambda).exp();
    let mut k = 0;
    let mut p = uniform(rng);
    while p > limit && k < 1000 {
        k += 1;
        p *= uniform(rng);
    }
    k
}

/// Geometric number of steps (at least 1) with the given mean (>= 1).
pub(crate) fn geometric_len(rng: &mut ChaCha8Rng, mean: f64) -> usize {
    if mean <= 1.0 {
        return 1;
    }
    let p = 1.0 / mean;
    let u = 1.0 - uniform(rng);
    1 + (u.ln() / (1.0 - p).ln()).floor().min(1.0e9) as usize
}

/// Number of random Fourier features per spatial field.
const FEATURES: usize = 48;

/// A zero-mean, unit-variance Gaussian random field over the plane with Gaussian covariance
/// `exp(-r^2 / (2 l^2))`, approximated by random Fourier features: evaluation costs
/// O(features) per point, so a field over N sensors is O(N).
///
/// [`SpatialField::exponential`] draws the exponential covariance `exp(-r / l)` instead (its
/// spectral measure is a bivariate Cauchy: rougher fields whose correlation falls linearly at
/// short range). [`SpatialField::standardized_over`] rescales a field to mean 0 and sd 1 over
/// a farm's sensors, so that it describes variation *within* the farm: without it a field
/// whose correlation length exceeds the farm is nearly constant over it, and each seed's farm
/// is shifted as a whole (one seed wetter, another drier).
#[derive(Debug, Clone)]
pub(crate) struct SpatialField {
    /// (omega_e, omega_n, phase) per feature; omega in rad/m.
    features: Vec<(f64, f64, f64)>,
    /// Subtracted from the raw value, then divided by `scale`.
    offset: f64,
    scale: f64,
}

/// Points per block when standardising a field (fixed, so sums do not depend on threads).
const BLOCK: usize = 4096;

impl SpatialField {
    pub(crate) fn new(rng: &mut ChaCha8Rng, correlation_length_m: f64) -> Self {
        let features = (0..FEATURES)
            .map(|_| {
                let we = normal(rng) / correlation_length_m;
                let wn = normal(rng) / correlation_length_m;
                let phase = uniform(rng) * std::f64::consts::TAU;
                (we, wn, phase)
            })
            .collect();
        Self {
            features,
            offset: 0.0,
            scale: 1.0,
        }
    }

    /// A field with covariance `exp(-r / l)`, `l` = `correlation_length_m`.
    pub(crate) fn exponential(rng: &mut ChaCha8Rng, correlation_length_m: f64) -> Self {
        let features = (0..FEATURES)
            .map(|_| {
                // Bivariate Cauchy: a Gaussian direction over |N(0, 1)| (a chi with 1 dof).
                let w = normal(rng).abs().max(1.0e-3) * correlation_length_m;
                let we = normal(rng) / w;
                let wn = normal(rng) / w;
                let phase = uniform(rng) * std::f64::consts::TAU;
                (we, wn, phase)
            })
            .collect();
        Self {
            features,
            offset: 0.0,
            scale: 1.0,
        }
    }

    /// The field rescaled to mean 0 and standard deviation 1 over `points` (only centred with
    /// fewer than three points or a flat field). Deterministic whatever the thread count.
    pub(crate) fn standardized_over(mut self, points: &[LocalPoint]) -> Self {
        use rayon::prelude::*;
        if points.is_empty() {
            return self;
        }
        let partial: Vec<(f64, f64)> = points
            .par_chunks(BLOCK)
            .map(|c| {
                c.iter().fold((0.0, 0.0), |(s, q), &p| {
                    let v = self.raw(p);
                    (s + v, q + v * v)
                })
            })
            .collect();
        let (s, q) = partial
            .iter()
            .fold((0.0, 0.0), |(a, b), &(s, q)| (a + s, b + q));
        let n = points.len() as f64;
        let mean = s / n;
        let var = (q / n - mean * mean).max(0.0);
        self.offset = mean;
        if points.len() >= 3 && var > 1.0e-12 {
            self.scale = var.sqrt();
        }
        self
    }

    fn raw(&self, p: LocalPoint) -> f64 {
        let sum: f64 = self
            .features
            .iter()
            .map(|&(we, wn, ph)| (we * p.e + wn * p.n + ph).cos())
            .sum();
        sum * (2.0 / self.features.len() as f64).sqrt()
    }

    pub(crate) fn at(&self, p: LocalPoint) -> f64 {
        (self.raw(p) - self.offset) / self.scale
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distributions_have_expected_means() {
        let mut rng = stream(1, Domain::Weather, 0);
        let n = 20_000;
        let normal_mean: f64 = (0..n).map(|_| normal(&mut rng)).sum::<f64>() / n as f64;
        assert!(normal_mean.abs() < 0.03, "{normal_mean}");
        let exp_mean: f64 = (0..n).map(|_| exponential(&mut rng, 5.0)).sum::<f64>() / n as f64;
        assert!((exp_mean - 5.0).abs() < 0.2, "{exp_mean}");
        let pois_mean: f64 = (0..n)
            .map(|_| f64::from(poisson(&mut rng, 0.3)))
            .sum::<f64>()
            / n as f64;
        assert!((pois_mean - 0.3).abs() < 0.02, "{pois_mean}");
        let geo_mean: f64 = (0..n)
            .map(|_| geometric_len(&mut rng, 10.0) as f64)
            .sum::<f64>()
            / n as f64;
        assert!((geo_mean - 10.0).abs() < 0.5, "{geo_mean}");
    }

    #[test]
    fn streams_differ_by_index_and_seed() {
        let a = uniform(&mut stream(1, Domain::Sensor, 0));
        let b = uniform(&mut stream(1, Domain::Sensor, 1));
        let c = uniform(&mut stream(2, Domain::Sensor, 0));
        let a2 = uniform(&mut stream(1, Domain::Sensor, 0));
        assert_eq!(a, a2);
        assert_ne!(a, b);
        assert_ne!(a, c);
    }

    #[test]
    fn exponential_field_has_exponential_covariance_and_standardizes() {
        let mut rng = stream(4, Domain::Fields, 0);
        let (mut var, mut cov) = (0.0, 0.0);
        let m = 600;
        for _ in 0..m {
            let f = SpatialField::exponential(&mut rng, 100.0);
            let a = f.at(LocalPoint::new(0.0, 0.0));
            let b = f.at(LocalPoint::new(100.0, 0.0));
            var += a * a;
            cov += a * b;
        }
        let (var, cov) = (var / m as f64, cov / m as f64);
        assert!((var - 1.0).abs() < 0.2, "{var}");
        assert!((cov - (-1.0f64).exp()).abs() < 0.12, "{cov}");
        let points: Vec<LocalPoint> = (0..50)
            .map(|i| LocalPoint::new(10.0 * i as f64, 3.0 * i as f64))
            .collect();
        let f = SpatialField::new(&mut rng, 1000.0).standardized_over(&points);
        let v: Vec<f64> = points.iter().map(|&p| f.at(p)).collect();
        let mean = v.iter().sum::<f64>() / 50.0;
        let sd = (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / 50.0).sqrt();
        assert!(mean.abs() < 1e-9 && (sd - 1.0).abs() < 1e-9, "{mean} {sd}");
    }

    #[test]
    fn spatial_field_is_unit_variance_and_correlated() {
        let mut rng = stream(3, Domain::Fields, 0);
        // Average over many independent fields: variance ~1, correlation ~exp(-1/2) at r = l.
        let (mut var, mut cov) = (0.0, 0.0);
        let m = 400;
        for _ in 0..m {
            let f = SpatialField::new(&mut rng, 100.0);
            let a = f.at(LocalPoint::new(10.0, 20.0));
            let b = f.at(LocalPoint::new(110.0, 20.0));
            var += a * a;
            cov += a * b;
        }
        let (var, cov) = (var / m as f64, cov / m as f64);
        assert!((var - 1.0).abs() < 0.2, "{var}");
        assert!((cov - (-0.5f64).exp()).abs() < 0.15, "{cov}");
    }
}
