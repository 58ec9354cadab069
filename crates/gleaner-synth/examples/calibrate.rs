//! Prints the calibration statistics of the CAF daily data next to those of synthetic farms
//! with the default settings (42 sensors, three years from 2014), averaged over seeds.
//!
//! `cargo run --release -p gleaner-synth --example calibrate -- [SEEDS]` (default 8 seeds;
//! set `GLEANER_DATA_DIR` if the shared data is not at `../shared/data` beside the workspace).

#[path = "../tests/common/caf.rs"]
mod caf;

use gleaner_synth::{PanelStats, StatsOptions, SynthConfig, generate, panel_stats};

/// The statistics printed, in order.
fn numbers(s: &PanelStats) -> Vec<f64> {
    let mut v = vec![
        s.mean,
        s.std,
        s.p01,
        s.p99,
        s.between_sensor_std,
        s.within_sensor_std,
        s.change_std,
        s.big_jump_fraction,
        s.change_abs_quantiles[1],
        s.change_abs_quantiles[2],
    ];
    v.extend(s.bins.iter().map(|b| b.mean_corr));
    v.extend(s.bins.iter().map(|b| b.mean_change_corr));
    v
}

fn row(label: &str, v: &[f64]) {
    let fmt = |xs: &[f64]| {
        xs.iter()
            .map(|x| format!("{x:.2}"))
            .collect::<Vec<_>>()
            .join(" ")
    };
    println!(
        "{label:<16} mean={:.4} sd={:.4} p01={:.3} p99={:.3} between={:.4} within={:.4} dsd={:.4} big={:.4} |d|p90={:.4} p99={:.4} corr {} | dcorr {}",
        v[0],
        v[1],
        v[2],
        v[3],
        v[4],
        v[5],
        v[6],
        v[7],
        v[8],
        v[9],
        fmt(&v[10..15]),
        fmt(&v[15..20]),
    );
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let seeds: u64 = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(8);
    let columns = [
        "VW_30cm", "VW_60cm", "VW_90cm", "T_30cm", "T_60cm", "T_90cm",
    ];
    let names = [
        "vw@30cm", "vw@60cm", "vw@90cm", "t@30cm", "t@60cm", "t@90cm",
    ];
    let caf = caf::caf_panels(&caf::data_dir(), &columns)?;
    let farms = (1..=seeds)
        .map(|seed| {
            generate(&SynthConfig {
                seed,
                days: 3 * 365,
                t_depths_cm: vec![30, 60, 90],
                ..SynthConfig::default()
            })
        })
        .collect::<Result<Vec<_>, _>>()?;
    println!(
        "distance bins (m): 0-100 100-200 200-300 300-450 450+; big jump: |daily change| > 0.02 m3/m3 (VW), 1 degC (T); synthetic rows average {seeds} seeds"
    );
    for (k, name) in names.iter().enumerate() {
        let options = StatsOptions {
            big_jump: if k < 3 { 0.02 } else { 1.0 },
            ..StatsOptions::default()
        };
        row(
            &format!("CAF {name}"),
            &numbers(&panel_stats(&caf[k], &options)),
        );
        let mut sum = vec![0.0; 20];
        for farm in &farms {
            let m = farm.modality_index(name).ok_or("modality missing")?;
            let panel = farm.daily_panel(m).ok_or("modality missing")?;
            for (a, b) in sum.iter_mut().zip(numbers(&panel_stats(&panel, &options))) {
                *a += b / seeds as f64;
            }
        }
        row(&format!("synth {name}"), &sum);
    }
    Ok(())
}
