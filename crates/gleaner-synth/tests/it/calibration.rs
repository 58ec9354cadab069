//! The default synthetic farm stays within documented tolerances of the CAF daily record
//! (2012-01-01 .. 2013-12-31, the window of `docs/synth-calibration.md`), every statistic
//! computed by the same code (`network_stats`) on both. The tolerances are the ones listed in
//! the crate docs ("Calibration").

use gleaner_synth::{NetworkStats, SynthConfig, generate, network_stats};

use crate::caf;

fn caf_stats() -> NetworkStats {
    let dir = caf::data_dir();
    let panel = caf::caf_network(&dir, (2012, 1, 1), (2013, 12, 31)).unwrap_or_else(|e| {
        panic!(
            "CAF data under {} (set GLEANER_DATA_DIR): {e}",
            dir.display()
        )
    });
    assert_eq!(panel.positions.len(), 42);
    network_stats(&panel)
}

fn inside(what: &str, got: f64, lo: f64, hi: f64) {
    assert!(
        got.is_finite() && (lo..=hi).contains(&got),
        "{what}: {got} outside [{lo}, {hi}]"
    );
}

#[test]
fn caf_targets_are_what_the_calibration_page_says() {
    // Guards the CAF side of the table: the loader and the statistics on real data.
    let c = caf_stats();
    assert_eq!((c.wettest_month, c.driest_month), (4, 9));
    inside("CAF winter rises", c.rise_winter, 0.03, 0.04);
    inside("CAF summer rises", c.rise_summer, 0.0, 0.005);
    inside("CAF depth lag", c.depth_lag_days as f64, 25.0, 35.0);
    inside("CAF missing", c.missing_fraction, 0.2, 0.25);
    inside("CAF lowest T 30 cm", c.t30_min, 0.0, 0.5);
    inside("CAF |z| > 3", c.z_false_alarm_fraction, 0.005, 0.015);
}

#[test]
fn default_farm_matches_caf_within_tolerances() {
    let caf = caf_stats();
    for seed in [1, 2] {
        let farm = generate(&SynthConfig {
            seed,
            days: 730,
            ..SynthConfig::default()
        })
        .unwrap();
        let s = network_stats(&farm.network_panel());
        let at = |what: &str| format!("seed {seed}: {what}");
        // Seasons: wettest within a month of April, driest within a month of September.
        inside(&at("wettest month"), f64::from(s.wettest_month), 3.0, 5.0);
        inside(&at("driest month"), f64::from(s.driest_month), 8.0, 10.0);
        // Rain seasonality: winter rises within a factor 2 of CAF's, summer ones rare.
        inside(
            &at("winter rises"),
            s.rise_winter,
            0.5 * caf.rise_winter,
            2.0 * caf.rise_winter,
        );
        inside(&at("summer rises"), s.rise_summer, 0.0, 0.01);
        assert!(
            s.rise_winter > 3.0 * s.rise_summer,
            "{}",
            at("rise seasonality")
        );
        // Drainage: most of a rise is gone within a week.
        inside(&at("7-day retention"), s.retention_7d, 0.25, 0.65);
        // Depth: 90 cm trails 30 cm by about a month; their daily changes barely correlate.
        inside(&at("depth lag"), s.depth_lag_days as f64, 20.0, 45.0);
        inside(&at("depth change corr"), s.depth_change_corr, 0.05, 0.3);
        // Synchrony of daily changes between stations < 100 m apart: within 0.1 of CAF.
        inside(
            &at("sync 30 cm"),
            s.sync_30,
            caf.sync_30 - 0.1,
            caf.sync_30 + 0.1,
        );
        inside(
            &at("sync 90 cm"),
            s.sync_90,
            caf.sync_90 - 0.1,
            caf.sync_90 + 0.1,
        );
        // Faults: CAF-like missing share, and many gaps hit single depths.
        inside(&at("missing"), s.missing_fraction, 0.15, 0.32);
        inside(&at("partial gaps"), s.partial_gap_fraction, 0.35, 0.75);
        // Frost: the soil at 30 cm stays above 0 °C.
        inside(&at("lowest T 30 cm"), s.t30_min, 0.0, 2.0);
        // Own-history |z| > 3 without events: within 1.5 points of CAF.
        inside(
            &at("|z| > 3 days"),
            s.z_false_alarm_fraction,
            0.0,
            caf.z_false_alarm_fraction + 0.015,
        );
        // What already matched: distributions, autocorrelation, spatial structure.
        for c in &caf.per_modality {
            let m = s
                .per_modality
                .iter()
                .find(|m| m.name == c.name)
                .unwrap_or_else(|| panic!("{} missing", c.name));
            let water = c.name.starts_with("vw");
            let what = |x: &str| at(&format!("{} {x}", c.name));
            let mean_tol = if water { 0.04 } else { 1.0 };
            inside(&what("mean"), m.mean, c.mean - mean_tol, c.mean + mean_tol);
            let (lo, hi) = if water { (0.75, 1.25) } else { (0.9, 1.1) };
            inside(&what("sd ratio"), m.std / c.std, lo, hi);
            // Soil water's change sd is set by a few jumps (CAF's excess kurtosis 100-1300):
            // its shape is checked by the per-depth fidelity bands below instead.
            if !water {
                inside(&what("dsd ratio"), m.change_std / c.change_std, 0.7, 1.4);
            }
            inside(&what("acf1"), m.acf1, c.acf1 - 0.02, c.acf1 + 0.02);
            inside(&what("acf7"), m.acf7, c.acf7 - 0.06, c.acf7 + 0.06);
            // Deep levels are more alike between distant stations than at CAF (a known gap).
            let corr_tol = if water { 0.18 } else { 0.03 };
            inside(
                &what("corr < 100 m"),
                m.corr_near,
                c.corr_near - corr_tol,
                c.corr_near + corr_tol,
            );
        }
    }
}

/// Known misses of the per-depth bands (docs/synth-calibration.md, "Known gaps"): the 60 cm
/// layer dries more gently than CAF's and repeats itself less.
const KNOWN_GAPS: [(&str, &str); 4] = [
    ("vw@60cm", "daily change p05"),
    ("vw@60cm", "stuck runs (>= 7 days)"),
    ("vw@60cm", "change corr. < 100 m"),
    ("vw@150cm", "change corr. 600-800 m"),
];

#[test]
fn every_depth_is_caf_like_in_both_seed_ranges() {
    let dir = caf::data_dir();
    let panel = caf::caf_network_columns(&dir, (2012, 1, 1), (2013, 12, 31), &caf::ALL_COLUMNS)
        .unwrap_or_else(|e| panic!("CAF data under {}: {e}", dir.display()));
    let target = gleaner_synth::fidelity_stats(&panel);
    for seed in [2, 101] {
        let farm = generate(&SynthConfig {
            seed,
            days: 730,
            vw_depths_cm: vec![30, 60, 90, 120, 150],
            t_depths_cm: vec![30, 60, 90, 120, 150],
            ..SynthConfig::default()
        })
        .unwrap();
        let stats = gleaner_synth::fidelity_stats(&farm.network_panel());
        let checks = gleaner_synth::fidelity_checks(&target, &stats);
        assert!(checks.len() > 100, "{}", checks.len());
        let failed: Vec<String> = checks
            .iter()
            .filter(|c| !c.passes())
            .filter(|c| !KNOWN_GAPS.contains(&(c.modality.as_str(), c.statistic)))
            .map(|c| {
                format!(
                    "{} {}: {} outside [{}, {}]",
                    c.modality, c.statistic, c.synth, c.lo, c.hi
                )
            })
            .collect();
        assert!(failed.is_empty(), "seed {seed}: {failed:#?}");
        // The headline statistics, stated directly: 90 cm mostly still, a delayed front.
        let d90 = stats.depth("vw@90cm").unwrap();
        assert!(d90.changes.zero_share > 0.4, "{:?}", d90.changes);
        assert!(d90.changes.excess_kurtosis > 100.0, "{:?}", d90.changes);
        assert!(stats.network_down_days > 10, "{}", stats.network_down_days);
        assert!((20..=35).contains(&stats.front_lag_days));
    }
}
