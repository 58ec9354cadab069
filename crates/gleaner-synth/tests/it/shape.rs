use gleaner_synth::{FaultRates, SynthConfig, SynthError, generate};
use proptest::prelude::*;

use crate::{all_csv, small};

fn assert_physical(farm: &gleaner_synth::SynthFarm) {
    for r in farm.readings() {
        let spec = &farm.modalities()[r.modality];
        assert!(r.value.is_finite());
        if spec.is_water {
            assert!((0.0..=0.6).contains(&r.value), "VW {}", r.value);
        } else {
            assert!((-30.0..=50.0).contains(&r.value), "T {}", r.value);
        }
    }
}

#[test]
fn without_faults_every_reading_is_present_and_physical() {
    let config = SynthConfig {
        faults: FaultRates::none(),
        event_count: 0,
        ..small(3, 25, 40)
    };
    let farm = generate(&config).unwrap();
    assert_eq!(farm.sensors().len(), 25);
    assert_eq!(farm.times().len(), 40);
    assert_eq!(farm.modalities().len(), 4);
    assert_eq!(farm.reading_count(), 25 * 40 * 4);
    assert_physical(&farm);
    let [sensors, readings, truth, faults] = all_csv(&farm);
    assert_eq!(sensors.lines().count(), 1 + 25);
    assert_eq!(readings.lines().count(), 1 + 25 * 40 * 4);
    assert_eq!(truth.lines().count(), 1);
    assert_eq!(faults.lines().count(), 1);
    for line in readings.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        assert_eq!(f.len(), 5, "{line}");
        let v: f64 = f[3].parse().unwrap();
        assert!(v.is_finite());
        assert!(matches!(f[4], "m3/m3" | "degC"), "{line}");
        assert_eq!(f[1].len(), 20, "{line}");
    }
}

#[test]
fn with_default_faults_values_stay_physical_and_missing_rows_are_absent() {
    let farm = generate(&small(4, 60, 200)).unwrap();
    assert_physical(&farm);
    let n = farm.reading_count();
    assert!(n < 60 * 200 * 4, "some readings are missing");
    let readings = &all_csv(&farm)[1];
    assert_eq!(readings.lines().count(), 1 + n);
    assert!(!readings.contains("NaN"));
}

#[test]
fn in_memory_readings_match_the_csv_rows() {
    let farm = generate(&small(9, 15, 50)).unwrap();
    let readings = &all_csv(&farm)[1];
    let mut rows = readings.lines().skip(1);
    let mut count = 0;
    for r in farm.readings() {
        let row = rows.next().expect("a row per reading");
        let f: Vec<&str> = row.split(',').collect();
        assert_eq!(f[0], farm.sensors()[r.sensor].id.as_str());
        assert_eq!(f[2], farm.modalities()[r.modality].modality.as_str());
        let v: f64 = f[3].parse().unwrap();
        assert!((v - r.value).abs() < 1e-6, "{row} vs {}", r.value);
        count += 1;
    }
    assert!(rows.next().is_none());
    assert_eq!(count, farm.reading_count());
}

#[test]
fn hourly_sampling_has_a_daily_temperature_cycle() {
    let config = SynthConfig {
        interval_s: 3600,
        t_depths_cm: vec![5],
        vw_depths_cm: vec![30],
        faults: FaultRates::none(),
        event_count: 0,
        ..small(6, 5, 4)
    };
    let farm = generate(&config).unwrap();
    assert_eq!(farm.times().len(), 96);
    assert_eq!(farm.times()[1] - farm.times()[0], 3600);
    let t = farm.modality_index("t@5cm").unwrap();
    let day: Vec<f32> = farm.series(0, t)[24..48].to_vec();
    let max = day.iter().copied().fold(f32::MIN, f32::max);
    let min = day.iter().copied().fold(f32::MAX, f32::min);
    assert!(max - min > 2.0, "daily range at 5 cm {min}..{max}");
    assert_physical(&farm);
}

fn check_invalid(mutate: impl FnOnce(&mut SynthConfig), expected_name: &str) {
    let mut config = SynthConfig::default();
    mutate(&mut config);
    match generate(&config) {
        Err(SynthError::InvalidSetting { name, .. }) => assert_eq!(name, expected_name),
        Err(SynthError::InvalidDepths { name, .. }) => assert_eq!(name, expected_name),
        other => panic!("expected an error on {expected_name}, got {other:?}"),
    }
}

#[test]
fn invalid_settings_are_rejected_with_their_name() {
    check_invalid(|c| c.sensor_count = 0, "sensor_count");
    check_invalid(|c| c.days = 0, "days");
    check_invalid(|c| c.interval_s = 7000, "interval_s");
    check_invalid(|c| c.extent_m[1] = f64::NAN, "extent_m[1]");
    check_invalid(|c| c.correlation_length_m = 0.0, "correlation_length_m");
    check_invalid(|c| c.vw_depths_cm = vec![30, 30], "vw_depths_cm");
    check_invalid(|c| c.t_depths_cm = vec![0], "t_depths_cm");
    check_invalid(
        |c| c.faults.spike_per_reading = 1.0,
        "faults.spike_per_reading",
    );
    check_invalid(
        |c| c.faults.dropout_mean_steps = 0.5,
        "faults.dropout_mean_steps",
    );
    check_invalid(|c| c.event_radius_m = Some(-1.0), "event_radius_m");
    check_invalid(
        |c| c.climate.storm_seasonality = 2.0,
        "climate.storm_seasonality",
    );
    check_invalid(|c| c.start = i64::MAX - 10, "start");
    check_invalid(
        |c| {
            c.sensor_count = 10_000_000;
            c.days = 1000;
        },
        "sensor_count x modalities x steps",
    );
}

#[test]
fn extent_scales_at_constant_density_when_asked() {
    let config = SynthConfig {
        sensor_count: 42 * 4,
        scale_extent_with_sensors: true,
        ..SynthConfig::default()
    };
    let [w, h] = config.effective_extent_m();
    assert!((w - 1740.0).abs() < 1e-9 && (h - 1040.0).abs() < 1e-9);
    let farm = generate(&SynthConfig { days: 2, ..config }).unwrap();
    let max_e = farm
        .local_positions()
        .iter()
        .map(|p| p.e.abs())
        .fold(0.0, f64::max);
    assert!(max_e > 700.0 && max_e <= 870.0, "{max_e}");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]
    #[test]
    fn any_small_farm_is_physical(
        seed in any::<u64>(), sensors in 1usize..20, days in 1u32..20, hourly in any::<bool>(),
        events in 0usize..5,
    ) {
        let config = SynthConfig {
            interval_s: if hourly { 3600 } else { 86_400 },
            event_count: events,
            ..small(seed, sensors, days)
        };
        let farm = generate(&config).unwrap();
        let steps = farm.times().len();
        prop_assert!(farm.reading_count() <= sensors * steps * farm.modalities().len());
        assert_physical(&farm);
        prop_assert_eq!(farm.events().len(), events);
        for e in farm.events() {
            prop_assert!(!e.affected.is_empty());
            prop_assert!(e.affected.iter().all(|&i| i < sensors));
            prop_assert!(e.start <= e.end);
        }
    }
}
