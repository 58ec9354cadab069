//! Prints, as Markdown, the calibration of the default synthetic farm against the CAF daily
//! record (2012-01-01 .. 2013-12-31, 42 stations; synthetic: 730 days, default settings) and
//! the event-detection comparison (own-history z-score vs neighbour-relative z-score) judged
//! against the synthetic ground truth. `docs/synth-calibration.md` is its output.
//!
//! `cargo run --release -p gleaner-synth --example calibrate -- --seeds 1,2,3`
//! (set `GLEANER_DATA_DIR` if the shared data is not at `../shared/data` beside the workspace).

#[path = "../tests/common/caf.rs"]
mod caf;

use gleaner_synth::{
    DayTruth, DetectionScore, EventKind, FidelityStats, NetworkPanel, NetworkStats, SynthConfig,
    fidelity_checks, fidelity_stats, generate, neighbour_z, network_stats, own_z, score_detection,
};

/// CAF's single years inside the tuning window, shown beside the two-year target: the spread
/// that justifies the tolerance bands.
const CAF_YEARS: [i64; 3] = [2011, 2012, 2013];

/// The modalities of the network table (as before the per-depth statistics were added).
const NETWORK_MODALITIES: [&str; 4] = ["vw@30cm", "vw@60cm", "vw@90cm", "t@30cm"];

/// `panel` with only the modalities named in `names`.
fn only(panel: &NetworkPanel, names: &[&str]) -> NetworkPanel {
    NetworkPanel {
        modalities: panel
            .modalities
            .iter()
            .filter(|m| names.contains(&m.name.as_str()))
            .cloned()
            .collect(),
        ..panel.clone()
    }
}

/// Neighbourhood sizes of the neighbour-relative measure compared.
const NEIGHBOURS: [usize; 2] = [3, 8];
/// Earlier values needed before a z-score counts.
const MIN_HISTORY: usize = 30;

/// Parses `--seeds 1,2,3` (calibration table) and `--detection-seeds 1-10` (detection
/// comparison; default: the calibration seeds).
fn parse_args() -> Result<(Vec<u64>, Vec<u64>), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let list = |v: &str| -> Result<Vec<u64>, String> {
        let mut out = Vec::new();
        for part in v.split(',') {
            let part = part.trim();
            let parse = |x: &str| x.parse::<u64>().map_err(|e| format!("seeds {v}: {e}"));
            match part.split_once('-') {
                Some((a, b)) => out.extend(parse(a)?..=parse(b)?),
                None => out.push(parse(part)?),
            }
        }
        if out.is_empty() {
            return Err(format!("seeds {v}: empty list"));
        }
        Ok(out)
    };
    let (mut seeds, mut detection) = (vec![1, 2, 3], None);
    let mut i = 0;
    while i < args.len() {
        let value = args
            .get(i + 1)
            .ok_or(format!("{} needs a list, e.g. 1,2,3 or 1-10", args[i]))?;
        match args[i].as_str() {
            "--seeds" => seeds = list(value)?,
            "--detection-seeds" => detection = Some(list(value)?),
            other => {
                return Err(format!(
                    "unknown argument {other} (expected --seeds LIST, --detection-seeds LIST)"
                ));
            }
        }
        i += 2;
    }
    let detection = detection.unwrap_or_else(|| seeds.clone());
    Ok((seeds, detection))
}

/// The synthetic configuration compared with CAF: every depth CAF has.
fn config(seed: u64) -> SynthConfig {
    SynthConfig {
        seed,
        days: 730,
        vw_depths_cm: vec![30, 60, 90, 120, 150],
        t_depths_cm: vec![30, 60, 90, 120, 150],
        ..SynthConfig::default()
    }
}

fn f(x: f64, decimals: usize) -> String {
    if x.is_nan() {
        "-".to_string()
    } else {
        format!("{x:.decimals$}")
    }
}

fn pct(x: f64) -> String {
    if x.is_nan() {
        "-".to_string()
    } else {
        format!("{:.1} %", 100.0 * x)
    }
}

const MONTHS: [&str; 12] = [
    "Jan", "Feb", "Mar", "Apr", "May", "Jun", "Jul", "Aug", "Sep", "Oct", "Nov", "Dec",
];

/// Rows of the network table: label and the formatted value of one panel's statistics.
type Row = (&'static str, fn(&NetworkStats) -> String);

fn network_rows() -> Vec<Row> {
    vec![
        ("wettest / driest month, VW 30 cm", |s| {
            format!(
                "{} / {}",
                MONTHS[s.wettest_month as usize - 1],
                MONTHS[s.driest_month as usize - 1]
            )
        }),
        ("rises > 0.02 m³/m³ at 30 cm, winter (DJF) days", |s| {
            pct(s.rise_winter)
        }),
        ("rises > 0.02 m³/m³ at 30 cm, summer (JJA) days", |s| {
            pct(s.rise_summer)
        }),
        ("share of a 30 cm rise left after 7 days (median)", |s| {
            format!("{} (n={})", f(s.retention_7d, 2), s.retention_rises)
        }),
        ("lag of 90 cm behind 30 cm, days", |s| {
            s.depth_lag_days.to_string()
        }),
        ("corr. of daily changes, 30 cm vs 90 cm", |s| {
            f(s.depth_change_corr, 2)
        }),
        ("corr. of daily changes, stations < 100 m, 30 cm", |s| {
            f(s.sync_30, 2)
        }),
        ("corr. of daily changes, stations < 100 m, 90 cm", |s| {
            f(s.sync_90, 2)
        }),
        ("missing values (VW 30/60/90, T 30)", |s| {
            pct(s.missing_fraction)
        }),
        ("gap station-days hitting only some VW depths", |s| {
            pct(s.partial_gap_fraction)
        }),
        ("lowest soil temperature at 30 cm, °C", |s| f(s.t30_min, 2)),
        ("days with T 30 cm < 0 °C", |s| pct(s.t30_below_zero)),
        (
            "station-days with own-history \\|z\\| > 3 (VW 30 cm), no event",
            |s| pct(s.z_false_alarm_fraction),
        ),
    ]
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let (seeds, detection_seeds) = parse_args()?;
    let dir = caf::data_dir();
    let caf_all = caf::caf_network_columns(&dir, (2012, 1, 1), (2013, 12, 31), &caf::ALL_COLUMNS)
        .map_err(|e| {
        format!(
            "CAF data under {} (set GLEANER_DATA_DIR): {e}",
            dir.display()
        )
    })?;
    let caf = only(&caf_all, &NETWORK_MODALITIES);
    let caf_stats = network_stats(&caf);
    let farms = seeds
        .iter()
        .map(|&s| generate(&config(s)))
        .collect::<Result<Vec<_>, _>>()?;
    let panels: Vec<NetworkPanel> = farms.iter().map(|f| f.network_panel()).collect();
    let stats: Vec<NetworkStats> = panels
        .iter()
        .map(|p| network_stats(&only(p, &NETWORK_MODALITIES)))
        .collect();
    let seed_list = seeds
        .iter()
        .map(u64::to_string)
        .collect::<Vec<_>>()
        .join(",");

    println!("# Synthetic farm calibration against CAF\n");
    println!(
        "Generated by `cargo run --release -p gleaner-synth --example calibrate -- --seeds {seed_list} --detection-seeds {}`.\n",
        detection_seeds
            .iter()
            .map(u64::to_string)
            .collect::<Vec<_>>()
            .join(",")
    );
    println!(
        "CAF: the Cook Agronomy Farm daily record (Gasch & Brown 2017, doi:10.15482/USDA.ADC/1349683), \
         2012-01-01 .. 2013-12-31, {} stations. Synthetic: `SynthConfig::default()` with `days = 730` \
         (from 2014-01-01) and every CAF depth (VW and T at 30, 60, 90, 120, 150 cm), one column per \
         seed. Every number on both sides comes from the same code (`gleaner_synth::network_stats`, \
         `gleaner_synth::fidelity_stats`); the tables before the per-depth section use VW 30/60/90 cm \
         and T 30 cm.\n",
        caf.positions.len()
    );
    let header = |first: &str| {
        let mut h = format!("| {first} | CAF |");
        let mut sep = "|---|---|".to_string();
        for s in &seeds {
            h.push_str(&format!(" seed {s} |"));
            sep.push_str("---|");
        }
        println!("{h}\n{sep}");
    };
    println!("## Network statistics\n");
    header("statistic");
    for (label, value) in network_rows() {
        let mut line = format!("| {label} | {} |", value(&caf_stats));
        for s in &stats {
            line.push_str(&format!(" {} |", value(s)));
        }
        println!("{line}");
    }
    println!("\n## Monthly cycle of VW at 30 cm (station-demeaned, m³/m³)\n");
    header("month");
    for (k, month) in MONTHS.iter().enumerate() {
        let mut line = format!("| {month} | {} |", f(caf_stats.monthly_vw30[k], 3));
        for s in &stats {
            line.push_str(&format!(" {} |", f(s.monthly_vw30[k], 3)));
        }
        println!("{line}");
    }
    println!("\n## Per-modality statistics\n");
    println!(
        "Mean, sd, 1st/99th percentiles of all values; between = sd of station means; dsd = sd of \
         day-to-day changes; acf1/acf7 = mean lag-1/lag-7 autocorrelation; corr <100 m / 450+ m = mean \
         series correlation of station pairs at those distances.\n"
    );
    let mut h = "| modality | source |".to_string();
    for c in [
        "mean",
        "sd",
        "p01",
        "p99",
        "between",
        "dsd",
        "acf1",
        "acf7",
        "corr <100 m",
        "corr 450+ m",
    ] {
        h.push_str(&format!(" {c} |"));
    }
    println!("{h}\n|---|---|---|---|---|---|---|---|---|---|---|---|");
    for (k, m) in caf_stats.per_modality.iter().enumerate() {
        let d = if m.name.starts_with("vw") { 3 } else { 2 };
        let line = |source: &str, m: &gleaner_synth::ModalityStats| {
            println!(
                "| {} | {source} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
                m.name,
                f(m.mean, d),
                f(m.std, d),
                f(m.p01, d),
                f(m.p99, d),
                f(m.between_sensor_std, d),
                f(m.change_std, d + 1),
                f(m.acf1, 3),
                f(m.acf7, 3),
                f(m.corr_near, 2),
                f(m.corr_far, 2),
            )
        };
        line("CAF", m);
        for (s, st) in seeds.iter().zip(&stats) {
            if let Some(sm) = st.per_modality.iter().find(|x| x.name == m.name) {
                line(&format!("seed {s}"), sm);
            }
        }
        let _ = k;
    }

    fidelity_section(&dir, &caf_all, &seeds, &panels)?;
    detection_section(&detection_seeds, &caf)?;
    Ok(())
}

/// Formats a fidelity value: percentages for shares, else a few significant digits.
fn fv(statistic: &str, x: f64) -> String {
    if x.is_nan() {
        "-".to_string()
    } else if statistic.contains("days with") {
        format!("{x:.0}")
    } else if statistic.starts_with("zero") || statistic.starts_with("stuck") {
        pct(x)
    } else if statistic.contains("kurtosis") {
        format!("{x:.0}")
    } else if x.abs() >= 10.0 {
        format!("{x:.1}")
    } else if x.abs() >= 1.0 {
        format!("{x:.2}")
    } else {
        format!("{x:.3}")
    }
}

/// Prints the per-depth fidelity tables: CAF 2012-13 (the target), CAF's single years, the
/// band and every seed, each synthetic value marked when outside its band.
fn fidelity_section(
    dir: &std::path::Path,
    caf_all: &NetworkPanel,
    seeds: &[u64],
    panels: &[NetworkPanel],
) -> Result<(), Box<dyn std::error::Error>> {
    let caf = fidelity_stats(caf_all);
    let years: Vec<FidelityStats> = CAF_YEARS
        .iter()
        .map(|&y| {
            caf::caf_network_columns(dir, (y, 1, 1), (y, 12, 31), &caf::ALL_COLUMNS)
                .map(|p| fidelity_stats(&p))
        })
        .collect::<Result<_, _>>()?;
    let synth: Vec<FidelityStats> = panels.iter().map(fidelity_stats).collect();
    let checks: Vec<_> = synth.iter().map(|s| fidelity_checks(&caf, s)).collect();
    // CAF's single years against the two-year target (same bands; a year's outage days are
    // scaled to its length).
    let year_checks: Vec<_> = years.iter().map(|y| fidelity_checks(&caf, y)).collect();
    println!("\n## Per-depth fidelity\n");
    println!(
        "Every statistic for every depth, CAF 2012-13 (the target) beside CAF's single years {} \
         (their spread is what the bands allow for) and the synthetic seeds. *band*: the accepted \
         range (`gleaner_synth::fidelity_checks`); a synthetic value outside it is marked ✗ \
         (a single CAF year is checked against the same bands: where one falls outside, the band is \
         tighter than CAF's own year-to-year spread). Definitions are in the notes below.\n",
        CAF_YEARS
            .iter()
            .map(i64::to_string)
            .collect::<Vec<_>>()
            .join(", ")
    );
    let mut h = "| modality | statistic | band | CAF 2012-13 |".to_string();
    let mut sep = "|---|---|---|---|".to_string();
    for y in CAF_YEARS {
        h.push_str(&format!(" CAF {y} |"));
        sep.push_str("---|");
    }
    for s in seeds {
        h.push_str(&format!(" seed {s} |"));
        sep.push_str("---|");
    }
    println!("{h}\n{sep}");
    let mut failures = vec![0usize; seeds.len()];
    for (k, c) in checks.first().map_or(&Vec::new(), |v| v).iter().enumerate() {
        let band = format!("{} .. {}", fv(c.statistic, c.lo), fv(c.statistic, c.hi));
        let mut line = format!(
            "| {} | {} | {band} | {} |",
            c.modality,
            c.statistic,
            fv(c.statistic, c.caf)
        );
        let cell = |x: &gleaner_synth::FidelityCheck| {
            format!(
                " {}{} |",
                fv(x.statistic, x.synth),
                if x.passes() { "" } else { " ✗" }
            )
        };
        for yc in &year_checks {
            match yc
                .iter()
                .find(|x| x.modality == c.modality && x.statistic == c.statistic)
            {
                Some(x) => line.push_str(&cell(x)),
                None => line.push_str(" - |"),
            }
        }
        for (i, sc) in checks.iter().enumerate() {
            let x = &sc[k];
            failures[i] += usize::from(!x.passes());
            line.push_str(&cell(x));
        }
        println!("{line}");
    }
    let n = checks.first().map_or(0, Vec::len);
    println!(
        "\nOutside the band: {} (of {n} checks per seed).\n",
        seeds
            .iter()
            .zip(&failures)
            .map(|(s, f)| format!("seed {s}: {f}"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    println!("Wetting front: correlation of 30 cm and 90 cm 7-day changes by lag (days).\n");
    let lags = [0usize, 5, 10, 15, 20, 25, 28, 30, 35, 45, 60];
    let mut h = "| source |".to_string();
    let mut sep = "|---|".to_string();
    for l in lags {
        h.push_str(&format!(" {l} |"));
        sep.push_str("---|");
    }
    h.push_str(" peak in 20-35 |");
    sep.push_str("---|");
    println!("{h}\n{sep}");
    let row = |name: String, f: &FidelityStats| {
        let mut line = format!("| {name} |");
        for &l in &lags {
            line.push_str(&format!(
                " {} |",
                f.front_curve
                    .get(l)
                    .map_or("-".into(), |r| format!("{r:.2}"))
            ));
        }
        line.push_str(&format!(" {:.2} at {} |", f.front_corr, f.front_lag_days));
        println!("{line}");
    };
    row("CAF 2012-13".into(), &caf);
    for (y, f) in CAF_YEARS.iter().zip(&years) {
        row(format!("CAF {y}"), f);
    }
    for (s, f) in seeds.iter().zip(&synth) {
        row(format!("seed {s}"), f);
    }
    Ok(())
}

/// Prints the detection comparison: per seed and in total, per event kind, for the own-history
/// z-score and the neighbour-relative one (each neighbourhood size), plus CAF's flagged share.
fn detection_section(seeds: &[u64], caf: &NetworkPanel) -> Result<(), Box<dyn std::error::Error>> {
    println!("\n## Event detection against the ground truth\n");
    println!(
        "Synthetic farms: `SynthConfig::default()` with `days = 730`, seeds {}; each has 12 events \
         (leak, dry patch, failing sensor in turn; 7-28 days, 0.10-0.19 m³/m³ over one to three \
         stations). Each station-day of VW at 30 cm is flagged when |z| > 3 (at least \
         {MIN_HISTORY} earlier values). *Own history* is the paper's anomaly on a one-station \
         cell: the day's value against the mean and sd of all the station's earlier values. \
         *Neighbours k* is the station's value minus the median of its k nearest stations that \
         day (at least two reporting), against the mean and sd of that residual's own history \
         (`utility.anomaly_reference = \"neighbours\"` is this measure on cells and their grid \
         neighbours). Event station-days: the active days of leaks and dry patches at their \
         affected stations; quiet: no event (an event's 30-day fading tail and failing sensors \
         until replaced are not scored). Caught: events with at least one flagged station-day; \
         delay: days from the start to the first flag, over caught events.\n",
        seeds
            .iter()
            .map(u64::to_string)
            .collect::<Vec<_>>()
            .join(", ")
    );
    let measures: Vec<String> = std::iter::once("own history".to_string())
        .chain(NEIGHBOURS.iter().map(|k| format!("neighbours k={k}")))
        .collect();
    // [measure][kind: all, leak, dry patch]
    let mut totals = vec![[DetectionScore::default(); 3]; measures.len()];
    let mut per_seed = Vec::new();
    for &seed in seeds {
        let farm = generate(&config(seed))?;
        let m = farm.modality_index("vw@30cm").ok_or("vw@30cm missing")?;
        let series = &farm.network_panel().modalities[m].series;
        let (truth, starts) = farm.day_truth();
        let kind_truth = |kind: EventKind| -> Vec<Vec<DayTruth>> {
            truth
                .iter()
                .map(|row| {
                    row.iter()
                        .map(|&d| match d {
                            DayTruth::Event(e) if farm.events()[e].kind != kind => DayTruth::Ignore,
                            other => other,
                        })
                        .collect()
                })
                .collect()
        };
        let truths = [
            truth.clone(),
            kind_truth(EventKind::Leak),
            kind_truth(EventKind::DryPatch),
        ];
        let zs: Vec<Vec<Vec<f64>>> = std::iter::once(own_z(series, MIN_HISTORY))
            .chain(
                NEIGHBOURS
                    .iter()
                    .map(|&k| neighbour_z(series, farm.local_positions(), k, MIN_HISTORY)),
            )
            .collect();
        let mut row = Vec::new();
        for (mi, z) in zs.iter().enumerate() {
            for (ki, t) in truths.iter().enumerate() {
                let s = score_detection(z, t, &starts, 3.0);
                totals[mi][ki].add(&s);
                if ki == 0 {
                    row.push(s);
                }
            }
        }
        per_seed.push((seed, row));
    }
    println!("### Totals over the seeds\n");
    println!(
        "| measure | events | event station-days flagged | quiet station-days flagged | events caught | mean delay, days |"
    );
    println!("|---|---|---|---|---|---|");
    for (mi, name) in measures.iter().enumerate() {
        for (ki, kind) in ["leaks and dry patches", "leaks", "dry patches"]
            .iter()
            .enumerate()
        {
            let s = &totals[mi][ki];
            println!(
                "| {name} | {kind} | {} of {} ({}) | {} | {} of {} | {} |",
                s.event_hits,
                s.event_days,
                pct(s.detection_rate()),
                if ki == 0 {
                    format!(
                        "{} of {} ({})",
                        s.quiet_hits,
                        s.quiet_days,
                        pct(s.false_alarm_rate())
                    )
                } else {
                    "(same)".to_string()
                },
                s.events_caught,
                s.events,
                f(s.mean_delay_days(), 1)
            );
        }
    }
    println!("\n### Per seed (leaks and dry patches)\n");
    let mut h = "| seed |".to_string();
    let mut sep = "|---|".to_string();
    for name in &measures {
        h.push_str(&format!(
            " {name}: flagged event days / quiet days / caught |"
        ));
        sep.push_str("---|");
    }
    println!("{h}\n{sep}");
    for (seed, row) in &per_seed {
        let mut line = format!("| {seed} |");
        for s in row {
            line.push_str(&format!(
                " {} / {} / {} of {} |",
                pct(s.detection_rate()),
                pct(s.false_alarm_rate()),
                s.events_caught,
                s.events
            ));
        }
        println!("{line}");
    }
    // CAF: no ground truth, so only the share of flagged station-days.
    println!("\n### CAF 2012-13 (no ground truth)\n");
    println!("| measure | station-days of VW at 30 cm flagged |");
    println!("|---|---|");
    let vw30 = &caf.modality("vw@30cm").ok_or("CAF vw@30cm missing")?.series;
    let zs: Vec<Vec<Vec<f64>>> = std::iter::once(own_z(vw30, MIN_HISTORY))
        .chain(
            NEIGHBOURS
                .iter()
                .map(|&k| neighbour_z(vw30, &caf.positions, k, MIN_HISTORY)),
        )
        .collect();
    for (name, z) in measures.iter().zip(&zs) {
        let (mut hit, mut n) = (0usize, 0usize);
        for v in z.iter().flatten().filter(|v| !v.is_nan()) {
            n += 1;
            hit += usize::from(v.abs() > 3.0);
        }
        println!(
            "| {name} | {hit} of {n} ({}) |",
            pct(hit as f64 / n.max(1) as f64)
        );
    }
    Ok(())
}
