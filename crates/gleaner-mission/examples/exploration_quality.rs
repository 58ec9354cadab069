//! Exploration quality on fixed instances: sorties, lower bound, total energy, time.
use std::time::Instant;

use gleaner_energy::{EnergyConfig, MissionEnergyModel};
use gleaner_field::LocalPoint;
use gleaner_mission::exploration::{ExplorationOptions, plan_exploration};

fn grid(nx: usize, ny: usize, count: usize) -> Vec<LocalPoint> {
    (0..nx * ny)
        .take(count)
        .map(|i| LocalPoint::new(20.0 + 40.0 * (i % nx) as f64, 20.0 + 40.0 * (i / nx) as f64))
        .collect()
}

struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn caf(cell: f64) -> Vec<LocalPoint> {
    let dir = std::env::var("GLEANER_DATA_DIR").unwrap_or_else(|_| "/work/shared/data".into());
    let text = std::fs::read_to_string(format!("{dir}/caf/sensors/CAF_sensor_locations.csv"))
        .expect("CAF sensors");
    let pts: Vec<(f64, f64)> = text
        .lines()
        .skip(1)
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (f[1].parse().unwrap(), f[2].parse().unwrap())
        })
        .collect();
    let e0 = pts.iter().map(|p| p.0).fold(f64::MAX, f64::min);
    let n0 = pts.iter().map(|p| p.1).fold(f64::MAX, f64::min);
    let mut cells: Vec<(i64, i64)> = pts
        .iter()
        .map(|p| {
            (
                ((p.0 - e0) / cell).floor() as i64,
                ((p.1 - n0) / cell).floor() as i64,
            )
        })
        .collect();
    cells.sort_unstable();
    cells.dedup();
    cells
        .iter()
        .map(|&(i, j)| LocalPoint::new((i as f64 + 0.5) * cell, (j as f64 + 0.5) * cell))
        .collect()
}

fn main() {
    let model = MissionEnergyModel::new(&EnergyConfig::paper()).unwrap();
    // Optional: `cargo run --release --example exploration_quality -- KICKS SEED`.
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut options = ExplorationOptions::default();
    if let Some(k) = args.first() {
        options.tour_kicks = k.parse().expect("KICKS: a count");
    }
    if let Some(s) = args.get(1) {
        options.seed = s.parse().expect("SEED: an integer");
    }
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let mut cases: Vec<(String, LocalPoint, Vec<LocalPoint>, Vec<f64>)> = Vec::new();
    let c = caf(40.0);
    let k = c.len();
    cases.push((
        "caf-40m-corner-30s".into(),
        LocalPoint::new(0.0, 0.0),
        c.clone(),
        vec![30.0; k],
    ));
    cases.push((
        "caf-40m-centre-120s".into(),
        LocalPoint::new(440.0, 260.0),
        c.clone(),
        vec![120.0; k],
    ));
    let hov: Vec<f64> = (0..k).map(|_| 30.0 + 150.0 * rng.next()).collect();
    cases.push((
        "caf-40m-corner-rand".into(),
        LocalPoint::new(0.0, 0.0),
        c,
        hov,
    ));
    let c = grid(10, 10, 100);
    cases.push((
        "grid10-corner-30s".into(),
        LocalPoint::new(-20.0, -20.0),
        c,
        vec![30.0; 100],
    ));
    let c = grid(20, 20, 400);
    let hov: Vec<f64> = (0..400).map(|_| 30.0 + 60.0 * rng.next()).collect();
    cases.push((
        "grid20-centre-rand".into(),
        LocalPoint::new(400.0, 400.0),
        c,
        hov,
    ));
    let c = grid(32, 32, 1000);
    cases.push((
        "grid32-corner-30s".into(),
        LocalPoint::new(0.0, 0.0),
        c.clone(),
        vec![30.0; 1000],
    ));
    cases.push((
        "grid32-centre-30s".into(),
        LocalPoint::new(640.0, 640.0),
        c,
        vec![30.0; 1000],
    ));
    let c: Vec<LocalPoint> = (0..300)
        .map(|_| LocalPoint::new(1200.0 * rng.next() - 600.0, 1200.0 * rng.next() - 600.0))
        .collect();
    let hov: Vec<f64> = (0..300).map(|_| 30.0 + 60.0 * rng.next()).collect();
    cases.push((
        "uniform300-centre".into(),
        LocalPoint::new(0.0, 0.0),
        c,
        hov,
    ));
    println!(
        "{:<22} {:>6} {:>8} {:>6} {:>14} {:>9}",
        "instance", "cells", "sorties", "bound", "total_J", "ms"
    );
    for (name, base, cells, hover) in cases {
        let service: Vec<f64> = hover.iter().map(|&h| model.service_energy_j(h)).collect();
        let t = Instant::now();
        let p = plan_exploration(&model, base, &cells, &service, &options).unwrap();
        let ms = t.elapsed().as_secs_f64() * 1e3;
        println!(
            "{:<22} {:>6} {:>8} {:>6} {:>14.1} {:>10.1} {:>9.1}",
            name,
            cells.len(),
            p.sorties.len(),
            p.lower_bound_sorties,
            p.total_energy_j,
            p.giant_tour_m,
            ms
        );
    }
}
