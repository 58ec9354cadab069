//! Seeded no-fly polygons for tests and benchmarks (deterministic for a seed, no `rand`).

use crate::{Coord, LineString, Polygon};

/// SplitMix64: a tiny seeded generator, enough for fixtures.
struct SplitMix(u64);

impl SplitMix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [lo, hi).
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * ((self.next() >> 11) as f64 / (1u64 << 53) as f64)
    }
}

/// `count` star-shaped polygons (4 to 7 corners, radii `radius_m` = (min, max), m) with
/// centres uniform in the box `min`..`max` (m), each centre at least `keep_away_m` (m) from
/// every point of `avoid` (e.g. the base station). Deterministic for a seed; gives up on a
/// polygon after 1,000 draws (so fewer may come back when the box is crowded).
pub fn seeded_polygons(
    seed: u64,
    count: usize,
    min: Coord<f64>,
    max: Coord<f64>,
    radius_m: (f64, f64),
    avoid: &[Coord<f64>],
    keep_away_m: f64,
) -> Vec<Polygon<f64>> {
    let mut rng = SplitMix(seed);
    let mut out = Vec::with_capacity(count);
    for _ in 0..count {
        for _ in 0..1_000 {
            let c = Coord {
                x: rng.uniform(min.x, max.x),
                y: rng.uniform(min.y, max.y),
            };
            let reach = keep_away_m + radius_m.1;
            if avoid.iter().any(|a| (a.x - c.x).hypot(a.y - c.y) < reach) {
                continue;
            }
            let k = 4 + (rng.next() % 4) as usize;
            let phase = rng.uniform(0.0, std::f64::consts::TAU);
            let mut ring: Vec<(f64, f64)> = (0..k)
                .map(|i| {
                    let a = phase + std::f64::consts::TAU * i as f64 / k as f64;
                    let r = rng.uniform(radius_m.0, radius_m.1);
                    (c.x + r * a.cos(), c.y + r * a.sin())
                })
                .collect();
            ring.push(ring[0]);
            out.push(Polygon::new(LineString::from(ring), vec![]));
            break;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seeded_and_away_from_the_base() {
        let (lo, hi) = (Coord { x: -400.0, y: 0.0 }, Coord { x: 400.0, y: 500.0 });
        let base = [Coord { x: 0.0, y: 0.0 }];
        let a = seeded_polygons(7, 20, lo, hi, (8.0, 20.0), &base, 50.0);
        assert_eq!(a, seeded_polygons(7, 20, lo, hi, (8.0, 20.0), &base, 50.0));
        assert_eq!(a.len(), 20);
        for p in &a {
            for c in p.exterior().coords() {
                assert!(c.x.hypot(c.y) > 50.0);
            }
        }
    }
}
