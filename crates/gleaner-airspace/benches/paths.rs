//! All-pairs shortest paths around 20 seeded no-fly polygons for 43 points (a CAF-sized
//! field: base + 42 cells) over an 870 m x 520 m area.
use criterion::{Criterion, criterion_group, criterion_main};
use gleaner_airspace::{Airspace, AirspaceOptions, Coord, Geometry, LineString, Polygon};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn zones(seed: u64) -> Vec<Geometry<f64>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..20)
        .map(|_| {
            let (cx, cy) = (
                rng.random_range(-400.0..400.0),
                rng.random_range(-250.0..250.0),
            );
            let k = rng.random_range(4..8);
            let mut ring: Vec<(f64, f64)> = (0..k)
                .map(|i| {
                    let a = std::f64::consts::TAU * i as f64 / k as f64;
                    let r = rng.random_range(6.0..20.0);
                    (cx + r * a.cos(), cy + r * a.sin())
                })
                .collect();
            ring.push(ring[0]);
            Geometry::Polygon(Polygon::new(LineString::from(ring), vec![]))
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let zones = zones(7);
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let points: Vec<Coord<f64>> = (0..43)
        .map(|_| Coord {
            x: rng.random_range(-430.0..430.0),
            y: rng.random_range(-260.0..260.0),
        })
        .collect();
    c.bench_function("airspace_20_zones_43_points", |b| {
        b.iter(|| {
            let a = Airspace::new(&zones, None, AirspaceOptions::default()).unwrap();
            a.paths(&points)
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
