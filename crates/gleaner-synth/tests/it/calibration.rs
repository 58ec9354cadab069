//! The synthetic farm with default settings matches the CAF daily data within stated
//! tolerances (the numbers are documented in the crate docs, "Calibration").

use gleaner_synth::{PanelStats, StatsOptions, SynthConfig, generate, panel_stats};

use crate::caf;

/// Tolerances: absolute for the mean (m³/m³ or °C), ratios synthetic / CAF for spreads.
struct Tolerance {
    mean_abs: f64,
    std_ratio: (f64, f64),
    change_std_ratio: (f64, f64),
    big_jump_ratio: (f64, f64),
    between_ratio: (f64, f64),
    near_corr_abs: f64,
}

const VW: Tolerance = Tolerance {
    mean_abs: 0.03,
    std_ratio: (0.8, 1.25),
    change_std_ratio: (0.6, 1.6),
    big_jump_ratio: (0.5, 2.0),
    between_ratio: (0.6, 1.6),
    near_corr_abs: 0.12,
};

const T: Tolerance = Tolerance {
    mean_abs: 1.0,
    std_ratio: (0.85, 1.15),
    change_std_ratio: (0.6, 1.6),
    big_jump_ratio: (0.0, f64::INFINITY),
    between_ratio: (0.6, 1.6),
    near_corr_abs: 0.03,
};

fn check(name: &str, caf: &PanelStats, synth: &PanelStats, tol: &Tolerance) {
    let ratio = |a: f64, b: f64| a / b;
    let inside = |r: f64, (lo, hi): (f64, f64)| (lo..=hi).contains(&r);
    assert!(
        (synth.mean - caf.mean).abs() <= tol.mean_abs,
        "{name} mean {} vs CAF {}",
        synth.mean,
        caf.mean
    );
    assert!(
        inside(ratio(synth.std, caf.std), tol.std_ratio),
        "{name} std {} vs CAF {}",
        synth.std,
        caf.std
    );
    assert!(
        inside(
            ratio(synth.change_std, caf.change_std),
            tol.change_std_ratio
        ),
        "{name} change std {} vs CAF {}",
        synth.change_std,
        caf.change_std
    );
    assert!(
        inside(
            ratio(synth.big_jump_fraction, caf.big_jump_fraction),
            tol.big_jump_ratio
        ),
        "{name} big-jump fraction {} vs CAF {}",
        synth.big_jump_fraction,
        caf.big_jump_fraction
    );
    assert!(
        inside(
            ratio(synth.between_sensor_std, caf.between_sensor_std),
            tol.between_ratio
        ),
        "{name} between-sensor std {} vs CAF {}",
        synth.between_sensor_std,
        caf.between_sensor_std
    );
    let (c0, s0) = (caf.bins[0].mean_corr, synth.bins[0].mean_corr);
    assert!(
        (s0 - c0).abs() <= tol.near_corr_abs,
        "{name} correlation under 100 m {s0} vs CAF {c0}"
    );
    let last = synth.bins.len() - 1;
    // Temperature series correlate at 0.99+ everywhere, in CAF as here: no trend to check.
    assert!(
        tol.near_corr_abs < 0.1 || synth.bins[0].mean_corr >= synth.bins[last].mean_corr,
        "{name}: synthetic correlation must not grow with distance: {:?}",
        synth.bins
    );
}

#[test]
fn default_farm_matches_caf_statistics() {
    let columns = [
        "VW_30cm", "VW_60cm", "VW_90cm", "T_30cm", "T_60cm", "T_90cm",
    ];
    let names = [
        "vw@30cm", "vw@60cm", "vw@90cm", "t@30cm", "t@60cm", "t@90cm",
    ];
    let dir = caf::data_dir();
    let panels = caf::caf_panels(&dir, &columns).unwrap_or_else(|e| {
        panic!(
            "CAF data under {} (set GLEANER_DATA_DIR): {e}",
            dir.display()
        )
    });
    assert_eq!(panels[0].series.len(), 42);
    for seed in [1, 2] {
        let config = SynthConfig {
            seed,
            days: 3 * 365,
            t_depths_cm: vec![30, 60, 90],
            ..SynthConfig::default()
        };
        let farm = generate(&config).unwrap();
        for (k, name) in names.iter().enumerate() {
            let water = k < 3;
            let options = StatsOptions {
                big_jump: if water { 0.02 } else { 1.0 },
                ..StatsOptions::default()
            };
            let caf_stats = panel_stats(&panels[k], &options);
            let m = farm.modality_index(name).unwrap();
            let synth_stats = panel_stats(&farm.daily_panel(m).unwrap(), &options);
            check(
                &format!("seed {seed} {name}"),
                &caf_stats,
                &synth_stats,
                if water { &VW } else { &T },
            );
        }
    }
}
