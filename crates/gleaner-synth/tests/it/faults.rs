use gleaner_synth::{FaultKind, FaultRates, SynthConfig, generate};

#[test]
fn faults_occur_at_their_configured_rates() {
    let faults = FaultRates {
        dropout_per_step: 0.003,
        dropout_mean_steps: 8.0,
        spike_per_reading: 0.002,
        stuck_per_step: 0.001,
        stuck_mean_steps: 5.0,
        probe_dropout_per_step: 0.0,
        probe_dropout_mean_steps: 1.0,
        ..FaultRates::none()
    };
    let (sensors, steps, mods) = (400usize, 365usize, 4usize);
    let config = SynthConfig {
        seed: 11,
        sensor_count: sensors,
        days: steps as u32,
        event_count: 0,
        faults: faults.clone(),
        ..SynthConfig::default()
    };
    let farm = generate(&config).unwrap();
    let count = |k: FaultKind| farm.faults().iter().filter(|f| f.kind == k).count() as f64;
    let within = |got: f64, expected: f64, tol: f64, what: &str| {
        assert!(
            (got / expected - 1.0).abs() < tol,
            "{what}: {got} against expected {expected:.1}"
        );
    };
    // A new dropout can only start outside one: fraction of time free = 1 / (1 + p x mean).
    let free = 1.0 / (1.0 + faults.dropout_per_step * faults.dropout_mean_steps);
    let cells = (sensors * steps) as f64;
    within(
        count(FaultKind::Dropout),
        cells * faults.dropout_per_step * free,
        0.15,
        "dropouts",
    );
    let missing = 1.0 - farm.reading_count() as f64 / (cells * mods as f64);
    within(missing, 1.0 - free, 0.2, "missing fraction");
    let stuck_free = 1.0 / (1.0 + faults.stuck_per_step * faults.stuck_mean_steps);
    within(
        count(FaultKind::Stuck),
        // Stuck stretches and spikes hit soil water only (three of the four modalities).
        cells * (mods - 1) as f64 * faults.stuck_per_step * stuck_free,
        0.15,
        "stuck stretches",
    );
    within(
        count(FaultKind::Spike),
        farm.reading_count() as f64 * 0.75 * stuck_free * faults.spike_per_reading,
        0.15,
        "spikes",
    );
    // Spikes are visible: the spiked reading stands out from both neighbours.
    let (mut visible, mut checked) = (0, 0);
    for f in farm.faults().iter().filter(|f| f.kind == FaultKind::Spike) {
        let m = f.modality.unwrap();
        let t = ((f.start - config.start) / config.interval_s) as usize;
        let series = farm.series(f.sensor, m);
        if t == 0 || t + 1 >= steps || series[t - 1].is_nan() || series[t + 1].is_nan() {
            continue;
        }
        checked += 1;
        let jump = if farm.modalities()[m].is_water {
            0.03
        } else {
            2.0
        };
        if (series[t] - series[t - 1]).abs() > jump && (series[t] - series[t + 1]).abs() > jump {
            visible += 1;
        }
    }
    assert!(
        checked > 100 && visible as f64 > 0.85 * checked as f64,
        "{visible}/{checked}"
    );
    // Stuck stretches repeat the last reported value exactly.
    let mut checked_stuck = 0;
    for f in farm.faults().iter().filter(|f| f.kind == FaultKind::Stuck) {
        let m = f.modality.unwrap();
        let a = ((f.start - config.start) / config.interval_s) as usize;
        let b = ((f.end - config.start) / config.interval_s) as usize;
        let series = farm.series(f.sensor, m);
        let Some(last) = series[..a].iter().rev().find(|v| !v.is_nan()) else {
            continue;
        };
        checked_stuck += 1;
        for v in &series[a..b] {
            assert!(v.is_nan() || v == last, "stuck at {last}, got {v}");
        }
    }
    assert!(checked_stuck > 100, "{checked_stuck}");
}
