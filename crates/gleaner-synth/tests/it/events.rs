use gleaner_synth::{EventKind, FaultRates, SynthConfig, SynthFarm, generate};

fn config(seed: u64, event_count: usize) -> SynthConfig {
    SynthConfig {
        seed,
        sensor_count: 200,
        days: 365,
        faults: FaultRates::none(),
        event_count,
        ..SynthConfig::default()
    }
}

fn step_of(farm: &SynthFarm, t: i64) -> usize {
    farm.times()
        .iter()
        .position(|&x| x >= t)
        .unwrap_or(farm.times().len())
}

/// Mean of `modality` over `sensors` and steps `range` (present values only).
fn mean(
    farm: &SynthFarm,
    sensors: &[usize],
    modality: usize,
    range: std::ops::Range<usize>,
) -> f64 {
    let (mut sum, mut n) = (0.0, 0);
    for &s in sensors {
        for &v in &farm.series(s, modality)[range.clone()] {
            if !v.is_nan() {
                sum += f64::from(v);
                n += 1;
            }
        }
    }
    sum / f64::from(n.max(1))
}

/// Difference in differences of `modality` for the event's patch against the rest of the
/// field: (inside, second half of the event - inside, before) - (same outside), m³/m³.
fn patch_effect(farm: &SynthFarm, event: usize, modality: usize) -> f64 {
    let e = &farm.events()[event];
    let (start, end) = (step_of(farm, e.start), step_of(farm, e.end));
    let during = (start + end) / 2..end;
    let before = start.saturating_sub(30)..start;
    let outside: Vec<usize> = (0..farm.sensors().len())
        .filter(|i| !e.affected.contains(i))
        .collect();
    let inside_change = mean(farm, &e.affected, modality, during.clone())
        - mean(farm, &e.affected, modality, before.clone());
    let outside_change =
        mean(farm, &outside, modality, during) - mean(farm, &outside, modality, before);
    inside_change - outside_change
}

#[test]
fn leak_patch_is_wetter_and_dry_patch_drier_during_the_event() {
    for seed in [1, 2, 3] {
        let farm = generate(&config(seed, 3)).unwrap();
        assert_eq!(farm.events()[0].kind, EventKind::Leak);
        assert_eq!(farm.events()[1].kind, EventKind::DryPatch);
        for name in ["vw@30cm", "vw@90cm"] {
            let m = farm.modality_index(name).unwrap();
            let leak = patch_effect(&farm, 0, m);
            assert!(leak > 0.03, "seed {seed} {name}: leak effect {leak}");
            let dry = patch_effect(&farm, 1, m);
            assert!(dry < -0.01, "seed {seed} {name}: dry-patch effect {dry}");
        }
    }
}

#[test]
fn events_change_only_the_affected_sensors() {
    let with = generate(&config(4, 3)).unwrap();
    let without = generate(&config(4, 0)).unwrap();
    let affected: Vec<usize> = with
        .events()
        .iter()
        .flat_map(|e| e.affected.clone())
        .collect();
    let m = with.modality_index("vw@30cm").unwrap();
    for s in 0..with.sensors().len() {
        let same = with.series(s, m) == without.series(s, m);
        assert_eq!(same, !affected.contains(&s), "sensor {s}");
    }
    // The leak wets every affected sensor during its second half.
    let leak = &with.events()[0];
    let (a, b) = (step_of(&with, leak.start), step_of(&with, leak.end));
    for &s in &leak.affected {
        let d = mean(&with, &[s], m, (a + b) / 2..b) - mean(&without, &[s], m, (a + b) / 2..b);
        assert!(d > 0.01, "sensor {s}: leak adds only {d}");
    }
}

#[test]
fn failing_sensor_drifts_or_sticks_then_falls_silent_until_replaced() {
    let mut seen = [false; 2];
    for seed in 0..12 {
        let with = generate(&config(seed, 3)).unwrap();
        let without = generate(&config(seed, 0)).unwrap();
        let e = &with.events()[2];
        assert_eq!(e.affected.len(), 1);
        assert_eq!(e.radius_m, 0.0);
        let s = e.affected[0];
        let (a, b) = (step_of(&with, e.start), step_of(&with, e.end));
        // Silent for 30 days after the end, then replaced: true values again.
        let replaced = (b + 30).min(with.times().len());
        for m in 0..with.modalities().len() {
            let series = with.series(s, m);
            assert!(
                series[b..replaced].iter().all(|v| v.is_nan()),
                "silent after the end"
            );
            let clean = without.series(s, m);
            assert!(
                series[replaced..]
                    .iter()
                    .zip(&clean[replaced..])
                    .all(|(a, b)| with.modalities()[m].is_water
                        || (a.is_nan() && b.is_nan())
                        || (a - b).abs() < 1e-6),
                "replaced sensor reports the field again"
            );
            match e.kind {
                EventKind::SensorStuck => {
                    seen[0] = true;
                    assert!(series[a..b].iter().all(|&v| v == series[a]));
                }
                EventKind::SensorDrift if !with.modalities()[m].is_water => {
                    // Temperature is untouched by leak and dry patches, so the difference to
                    // the event-free farm is the drift alone.
                    let diff = |t: usize| f64::from(series[t]) - f64::from(without.series(s, m)[t]);
                    // Linear drift of at least 0.02 degC per day (events last 7 days or more).
                    let early = diff(a + 1).abs();
                    let late = diff(a + 5).abs();
                    assert!(late > early + 4.0 * 0.019, "drift {early} -> {late}");
                }
                EventKind::SensorDrift => {
                    seen[1] = true;
                    assert_ne!(series[a..b], without.series(s, m)[a..b]);
                }
                other => panic!("event 3 is a failing sensor, got {other:?}"),
            }
        }
    }
    assert_eq!(
        seen,
        [true, true],
        "both failure modes occur over the seeds"
    );
}
