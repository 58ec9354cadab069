//! Times [`gleaner_synth::generate`] for a year of daily data on 2,000- and 10,000-sensor
//! farms (default modalities: VW at 30/60/90 cm and T at 30 cm; extent scaled to keep CAF's
//! sensor density): median and range of 5 runs each, wall clock, after one warm-up run.
//!
//! `cargo run --release -p gleaner-synth --example generation_time -- [RUNS]`

use std::time::Instant;

use gleaner_synth::{SynthConfig, generate};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let runs: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(5)
        .max(1);
    for sensors in [2_000, 10_000] {
        let config = SynthConfig {
            seed: 42,
            sensor_count: sensors,
            days: 365,
            scale_extent_with_sensors: true,
            ..SynthConfig::default()
        };
        let readings = generate(&config)?.reading_count();
        let mut times: Vec<f64> = (0..runs)
            .map(|_| {
                let start = Instant::now();
                let farm = generate(&config).expect("valid configuration");
                let s = start.elapsed().as_secs_f64();
                std::hint::black_box(farm);
                s
            })
            .collect();
        times.sort_by(f64::total_cmp);
        println!(
            "{sensors} sensors x 365 days x 4 modalities ({readings} readings): median {:.3} s (min {:.3}, max {:.3}, {runs} runs)",
            times[runs / 2],
            times[0],
            times[runs - 1]
        );
    }
    Ok(())
}
