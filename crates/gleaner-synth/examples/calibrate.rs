//! Prints the calibration statistics of the CAF daily data next to those of a synthetic farm
//! with the default settings (42 sensors, three years from 2014).
//!
//! `cargo run --release -p gleaner-synth --example calibrate` (set `GLEANER_DATA_DIR` if the
//! shared data is not at `../shared/data` beside the workspace).

#[path = "../tests/common/caf.rs"]
mod caf;

use gleaner_synth::{PanelStats, StatsOptions, SynthConfig, generate, panel_stats};

fn row(label: &str, s: &PanelStats) {
    let bins: Vec<String> = s
        .bins
        .iter()
        .map(|b| format!("{:.2}/{:.2}", b.mean_corr, b.mean_change_corr))
        .collect();
    println!(
        "{label:<14} n={:>6} mean={:.4} sd={:.4} p01={:.3} p99={:.3} between={:.4} within={:.4} dsd={:.4} big={:.4} |d|q={:.4}/{:.4}/{:.4} corr/dcorr {}",
        s.count,
        s.mean,
        s.std,
        s.p01,
        s.p99,
        s.between_sensor_std,
        s.within_sensor_std,
        s.change_std,
        s.big_jump_fraction,
        s.change_abs_quantiles[0],
        s.change_abs_quantiles[1],
        s.change_abs_quantiles[2],
        bins.join(" ")
    );
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let seed = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(1);
    let columns = [
        "VW_30cm", "VW_60cm", "VW_90cm", "T_30cm", "T_60cm", "T_90cm",
    ];
    let names = [
        "vw@30cm", "vw@60cm", "vw@90cm", "t@30cm", "t@60cm", "t@90cm",
    ];
    let caf = caf::caf_panels(&caf::data_dir(), &columns)?;
    let config = SynthConfig {
        seed,
        days: 3 * 365,
        t_depths_cm: vec![30, 60, 90],
        ..SynthConfig::default()
    };
    let farm = generate(&config)?;
    println!(
        "bins (m): 0-100 100-200 200-300 300-450 450+; big jump: |daily change| > 0.02 m3/m3 (VW), 1 degC (T)"
    );
    for (k, name) in names.iter().enumerate() {
        let options = StatsOptions {
            big_jump: if k < 3 { 0.02 } else { 1.0 },
            ..StatsOptions::default()
        };
        row(&format!("CAF {name}"), &panel_stats(&caf[k], &options));
        let m = farm.modality_index(name).ok_or("modality missing")?;
        let panel = farm.daily_panel(m).ok_or("modality missing")?;
        row(&format!("synth {name}"), &panel_stats(&panel, &options));
    }
    Ok(())
}
