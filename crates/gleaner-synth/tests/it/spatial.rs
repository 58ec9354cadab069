use gleaner_synth::{FaultRates, StatsOptions, SynthConfig, generate, panel_stats};

/// Mean series correlation per distance bin (0-150, 150-300, 300-600, 600+ m), averaged over
/// three seeds, for each VW depth.
fn correlation_by_distance(correlation_length_m: f64) -> Vec<(String, Vec<f64>)> {
    let options = StatsOptions {
        bin_edges_m: vec![0.0, 150.0, 300.0, 600.0, f64::INFINITY],
        ..StatsOptions::default()
    };
    let mut out: Vec<(String, Vec<f64>)> = Vec::new();
    for seed in [8, 9, 10] {
        let config = SynthConfig {
            seed,
            sensor_count: 100,
            days: 730,
            faults: FaultRates::none(),
            event_count: 0,
            scale_extent_with_sensors: true,
            correlation_length_m,
            ..SynthConfig::default()
        };
        let farm = generate(&config).unwrap();
        for (k, spec) in farm
            .modalities()
            .iter()
            .enumerate()
            .filter(|(_, s)| s.is_water)
        {
            let stats = panel_stats(&farm.daily_panel(k).unwrap(), &options);
            assert!(stats.bins.iter().all(|b| b.pairs > 20), "{:?}", stats.bins);
            if out.len() <= k {
                out.push((spec.modality.to_string(), vec![0.0; stats.bins.len()]));
            }
            for (acc, b) in out[k].1.iter_mut().zip(&stats.bins) {
                *acc += b.mean_corr / 3.0;
            }
        }
    }
    out
}

#[test]
fn series_correlation_decays_with_distance() {
    for (name, corr) in correlation_by_distance(300.0) {
        eprintln!("{name}: {corr:?}");
        assert!(corr[0] > corr[3] + 0.025, "{name}: {corr:?}");
        for w in corr.windows(2) {
            assert!(w[0] >= w[1] - 0.01, "{name}: {corr:?}");
        }
    }
}
