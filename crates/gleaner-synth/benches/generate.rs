//! Speed target: 10,000 sensors x 365 days x 2 modalities (7.3 M readings) generated and
//! written as CSV in <= 10 s (release).

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use gleaner_synth::{SynthConfig, generate, write_readings_csv};

fn target_config() -> SynthConfig {
    SynthConfig {
        seed: 42,
        sensor_count: 10_000,
        days: 365,
        vw_depths_cm: vec![30],
        t_depths_cm: vec![30],
        scale_extent_with_sensors: true,
        ..SynthConfig::default()
    }
}

fn bench(c: &mut Criterion) {
    let config = target_config();
    let mut group = c.benchmark_group("synth_10k_sensors_365_days_2_modalities");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(20));
    group.bench_function("generate", |b| {
        b.iter(|| black_box(generate(&config).expect("valid config")))
    });
    let farm = generate(&config).expect("valid config");
    group.bench_function("write_readings_csv_to_sink", |b| {
        b.iter(|| write_readings_csv(&farm, &mut std::io::sink()).expect("sink never fails"))
    });
    group.bench_function("generate_and_write_to_vec", |b| {
        b.iter(|| {
            let farm = generate(&config).expect("valid config");
            let mut out = Vec::with_capacity(400 << 20);
            write_readings_csv(&farm, &mut out).expect("vec never fails");
            black_box(out.len())
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
