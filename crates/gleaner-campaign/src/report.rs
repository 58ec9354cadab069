//! The campaign report: the results read back ([`crate::results`]), summarised
//! ([`crate::campaign::summarise`]) and written as Markdown (`report.md`) with SVG charts
//! under `figures/`.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use gleaner_app::{AppError, format_rfc3339};
use gleaner_kriging::Variogram;
use gleaner_render::{
    IntervalChart, IntervalRow, Line, LineChart, XAxis, interval_chart_svg, line_chart_svg,
};

use crate::campaign::{
    BLOCK_DAYS, CampaignResult, Interval, METRICS, MIN_BLOCKS, RunKey, RunResult, Strategy,
    Summary, metric, summarise,
};
use crate::error::{Error, Result};
use crate::results::{CAMPAIGN, COMMAND, read_results, write};

/// "Flights": per strategy, the winds met, the sorties that re-planned in the air, the stops
/// they dropped, the data brought back and the energy flown against each battery. Nothing
/// when the files hold no flights.
fn flights_section(md: &mut String, results: &[CampaignResult]) -> Result<()> {
    use crate::campaign::{CALM_DAY_MPS, flight_summaries};
    let rows = flight_summaries(results);
    if rows.is_empty() {
        return Ok(());
    }
    writeln!(md, "## Flights\n")?;
    writeln!(
        md,
        "Each mission is planned for its forecast wind plus the margin and flown in the wind of \
         the day (the forecast plus its error) on its sortie's battery; over each stop a sortie \
         whose energy left cannot fly the rest with the reserve re-plans from there (dropping \
         and reordering the remaining stops). Over budget: missions of which a sortie flew more \
         than its battery could give above the reserve (must be 0); max excess: the largest \
         flown energy less that, over every sortie (< 0: energy to spare).\n"
    )?;
    writeln!(
        md,
        "| strategy | missions | mean forecast (m/s) | re-planned | stops dropped | readings | readings, days < {CALM_DAY_MPS} m/s | over budget | max excess (J) |\n|---|---|---|---|---|---|---|---|---|"
    )?;
    for f in &rows {
        writeln!(
            md,
            "| {} | {} | {:.2} | {} | {} | {} | {} ({} days) | {} | {:.1} |",
            f.strategy.name(),
            f.missions,
            f.mean_forecast_mps,
            f.replanned,
            f.cells_dropped,
            f.readings,
            f.readings_calm_days,
            f.calm_days,
            f.over_budget,
            f.max_excess_j
        )?;
    }
    writeln!(md)?;
    Ok(())
}

fn fmt_iv(i: &Interval, scale: f64, d: usize) -> String {
    if !i.mean.is_finite() {
        return "–".into();
    }
    if i.n <= 1 || !(i.low.is_finite() && i.high.is_finite()) || (i.high - i.low).abs() < 1e-15 {
        return format!("{:.d$}", i.mean * scale);
    }
    format!(
        "{:.d$} [{:.d$}, {:.d$}]",
        i.mean * scale,
        i.low * scale,
        i.high * scale
    )
}

fn get<'a>(s: &'a Summary, name: &str) -> &'a Interval {
    &s.metrics
        .iter()
        .find(|m| m.0 == name)
        .expect("known metric")
        .1
}

/// "Against exhaustive collection": each strategy's energy and error, at every budget, as a
/// share of exhaustive collection's at `main_budget` (its energy is what flying every cell
/// takes; its error does not depend on the battery), with the error measured before the
/// flights (after them exhaustive collection is exact by construction, so only the error lived
/// with between missions compares). Nothing when exhaustive collection was not run at
/// `main_budget` or the files predate the pre-flight errors.
fn exhaustive_section(md: &mut String, summaries: &[Summary], main_budget: f64) -> Result<()> {
    let mean = |s: &Summary, name: &str| get(s, name).mean;
    let Some(ex) = summaries
        .iter()
        .find(|s| s.strategy == Strategy::Exhaustive && s.budget == main_budget)
    else {
        return Ok(());
    };
    let (ex_energy, ex_kriged, ex_carried) = (
        mean(ex, "energy_kj"),
        mean(ex, "rmse_kriged_before"),
        mean(ex, "rmse_carried_before"),
    );
    if !(ex_energy > 0.0 && ex_kriged > 0.0 && ex_carried > 0.0) {
        return Ok(());
    }
    writeln!(md, "## Against exhaustive collection\n")?;
    writeln!(
        md,
        "Exhaustive collection flies every cell at every mission, in as many sorties as it \
         takes ({ex_energy:.1} kJ per mission with the batteries of budget {main_budget}). Right \
         after its flights it knows every value (RMSE 0 by construction), so the errors \
         compared here are those of what was known *before* each mission's flights — the \
         largest error the operator lives with between two missions — as a ratio to exhaustive \
         collection's, beside the energy ratio, at every budget run. Target of the method: \
         ratio ≤ 1.2 at an energy ratio ≤ 1/3.\n"
    )?;
    writeln!(
        md,
        "| strategy | budget | energy / exhaustive | RMSE kriging before | / exhaustive | RMSE carried before | / exhaustive |\n|---|---|---|---|---|---|---|"
    )?;
    let mut rows: Vec<&Summary> = summaries
        .iter()
        .filter(|s| s.strategy != Strategy::Exhaustive || s.budget == main_budget)
        .collect();
    // Strategies in report order, each one's budgets ascending.
    rows.sort_by(|a, b| {
        let rank = |s: &Summary| summaries.iter().position(|x| x.strategy == s.strategy);
        rank(a).cmp(&rank(b)).then(a.budget.total_cmp(&b.budget))
    });
    for s in rows {
        let (e, k, c) = (
            mean(s, "energy_kj"),
            mean(s, "rmse_kriged_before"),
            mean(s, "rmse_carried_before"),
        );
        writeln!(
            md,
            "| {} | {} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} |",
            s.strategy.name(),
            s.budget,
            e / ex_energy,
            k * 1000.0,
            k / ex_kriged,
            c * 1000.0,
            c / ex_carried
        )?;
    }
    writeln!(md)?;
    // Where each strategy run at several budgets comes within 20% (kriging, before the flights).
    let mut lines = Vec::new();
    let mut seen: Vec<Strategy> = Vec::new();
    for s in summaries {
        if s.strategy == Strategy::Exhaustive || seen.contains(&s.strategy) {
            continue;
        }
        seen.push(s.strategy);
        let points: Vec<(f64, f64)> = summaries
            .iter()
            .filter(|x| x.strategy == s.strategy)
            .map(|x| {
                (
                    mean(x, "energy_kj") / ex_energy,
                    mean(x, "rmse_kriged_before") / ex_kriged,
                )
            })
            .collect();
        if points.len() < 2 {
            continue;
        }
        let text = match energy_at_ratio(&points, WITHIN) {
            Crossing::Between(e) => format!("≈ {e:.2} (linear between the budgets run)"),
            Crossing::AtLeast(e) => format!("≤ {e:.2} (already at the smallest budget run)"),
            Crossing::Beyond { energy, ratio } => {
                format!("beyond the budgets run (best: {ratio:.2}× at {energy:.2})")
            }
        };
        lines.push(format!("| {} | {text} |", s.strategy.name()));
    }
    if !lines.is_empty() {
        writeln!(
            md,
            "Energy (as a share of exhaustive collection's) at which each strategy's error before \
             the flights comes within {:.0}% of exhaustive collection's (kriging):\n\n\
             | strategy | energy / exhaustive at {WITHIN}× |\n|---|---|",
            (WITHIN - 1.0) * 100.0
        )?;
        for l in lines {
            writeln!(md, "{l}")?;
        }
        writeln!(md)?;
    }
    Ok(())
}

/// Strategies whose every run (each campaign, seed and budget) has exactly the results of an
/// earlier strategy's run (in the summaries' order), mission by mission and event by event:
/// (the strategy, the earlier one). Floats compare by their printed value (NaN equals NaN).
fn same_runs(results: &[CampaignResult], summaries: &[Summary]) -> Vec<(Strategy, Strategy)> {
    let mut order: Vec<Strategy> = Vec::new();
    for s in summaries {
        if !order.contains(&s.strategy) {
            order.push(s.strategy);
        }
    }
    // Each run once: (campaign, key, its results as text).
    let runs: Vec<(usize, &RunKey, String)> = results
        .iter()
        .enumerate()
        .flat_map(|(c, campaign)| {
            campaign
                .runs
                .iter()
                .map(move |r| (c, &r.key, format!("{:?} {:?}", r.missions, r.caught)))
        })
        .collect();
    let mut out = Vec::new();
    for (k, &b) in order.iter().enumerate() {
        let of_b: Vec<&(usize, &RunKey, String)> =
            runs.iter().filter(|r| r.1.strategy == b).collect();
        if of_b.is_empty() {
            continue;
        }
        let earlier = order[..k].iter().copied().find(|&a| {
            of_b.iter().all(|(c, kb, text)| {
                runs.iter().any(|(ca, ka, ta)| {
                    ca == c
                        && ka.strategy == a
                        && ka.seed == kb.seed
                        && ka.budget == kb.budget
                        && ta == text
                })
            })
        });
        if let Some(a) = earlier {
            out.push((b, a));
        }
    }
    out
}

/// How many of `strategy`'s runs at `budget` differ: runs of one campaign with the same
/// results mission by mission and event by event (a planner deterministic on the case,
/// whatever its seed) count once; runs of different campaigns always differ. Floats compare
/// by their printed value.
fn distinct_runs(results: &[CampaignResult], strategy: Strategy, budget: f64) -> usize {
    let mut seen: Vec<(usize, String)> = Vec::new();
    for (c, campaign) in results.iter().enumerate() {
        for r in &campaign.runs {
            if r.key.strategy != strategy || r.key.budget != budget {
                continue;
            }
            let print = (c, format!("{:?} {:?}", r.missions, r.caught));
            if !seen.contains(&print) {
                seen.push(print);
            }
        }
    }
    seen.len()
}

/// A summary's runs for the table: `n`, or `n (k distinct)` when replicates coincide.
fn runs_cell(results: &[CampaignResult], s: &Summary) -> String {
    let distinct = distinct_runs(results, s.strategy, s.budget);
    if distinct < s.runs {
        format!("{} ({distinct} distinct)", s.runs)
    } else {
        s.runs.to_string()
    }
}

/// The method's target ratio to exhaustive collection's error.
const WITHIN: f64 = 1.2;

/// Where a strategy's error ratio reaches a target, along its budgets.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Crossing {
    /// Reached between two budgets run: the energy ratio interpolated linearly.
    Between(f64),
    /// Already reached at the smallest energy run (this one).
    AtLeast(f64),
    /// Never reached: the smallest ratio and its energy.
    Beyond { energy: f64, ratio: f64 },
}

/// The smallest energy ratio at which `points` ((energy ratio, error ratio) pairs, any order;
/// at least one) reach `target` or less, walking up in energy: linear between the last run
/// above the target and the first at or below it.
fn energy_at_ratio(points: &[(f64, f64)], target: f64) -> Crossing {
    let mut p: Vec<(f64, f64)> = points
        .iter()
        .copied()
        .filter(|(e, r)| e.is_finite() && r.is_finite())
        .collect();
    p.sort_by(|a, b| a.0.total_cmp(&b.0));
    for (k, &(e, r)) in p.iter().enumerate() {
        if r <= target {
            if k == 0 {
                return Crossing::AtLeast(e);
            }
            let (e0, r0) = p[k - 1];
            return Crossing::Between(e0 + (e - e0) * (r0 - target) / (r0 - r));
        }
    }
    let best = p
        .iter()
        .copied()
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap_or((f64::NAN, f64::NAN));
    Crossing::Beyond {
        energy: best.0,
        ratio: best.1,
    }
}

/// What a metric is, for tables and chart labels: (title, unit label, scale, decimals).
fn describe(name: &str, unit: &str) -> (&'static str, String, f64, usize) {
    match name {
        "rmse_kriged" => ("RMSE, kriging", format!("{unit} ×1000"), 1000.0, 2),
        "rmse_carried" => (
            "RMSE, last value carried forward",
            format!("{unit} ×1000"),
            1000.0,
            2,
        ),
        "rmse_kriged_before" => (
            "RMSE before the flights, kriging",
            format!("{unit} ×1000"),
            1000.0,
            2,
        ),
        "rmse_carried_before" => (
            "RMSE before the flights, last value carried forward",
            format!("{unit} ×1000"),
            1000.0,
            2,
        ),
        "mae_kriged" => ("MAE, kriging", format!("{unit} ×1000"), 1000.0, 2),
        "mae_carried" => (
            "MAE, last value carried forward",
            format!("{unit} ×1000"),
            1000.0,
            2,
        ),
        "mean_sd" => (
            "kriging standard deviation (mean variance)",
            format!("{unit} ×1000"),
            1000.0,
            2,
        ),
        "coverage90" => (
            "90% interval coverage of the estimated sensors",
            "%".into(),
            100.0,
            1,
        ),
        "staleness_mean_days" => ("mean staleness", "days".into(), 1.0, 2),
        "staleness_max_days" => ("max staleness", "days".into(), 1.0, 1),
        "energy_kj" => ("energy per mission", "kJ".into(), 1.0, 1),
        "utilisation" => ("battery utilisation per sortie", "%".into(), 100.0, 1),
        "cells" => ("cells per mission", "cells".into(), 1.0, 1),
        "classifier_accuracy" => ("condition classifier accuracy", "%".into(), 100.0, 1),
        "lost_readings" => ("readings lost to full buffers", "readings".into(), 1.0, 1),
        _ => ("?", String::new(), 1.0, 2),
    }
}

/// A campaign report in memory: the Markdown text and its charts.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderedReport {
    /// `report.md`'s text; charts are linked as `figures/NAME.svg`.
    pub markdown: String,
    /// Each chart: (file name under `figures/`, SVG document).
    pub figures: Vec<(String, String)>,
}

/// Reads the results in `dir` and writes `report.md` with its charts under `figures/`.
pub fn write_report(dir: &Path) -> Result<PathBuf> {
    let results = read_results(dir)?;
    if results.is_empty() {
        return Err(Error::file(dir, format!("no campaigns in {CAMPAIGN}")));
    }
    let command = std::fs::read_to_string(dir.join(COMMAND)).unwrap_or_default();
    let report = render_report(&results, &command)?;
    let figures = dir.join("figures");
    std::fs::create_dir_all(&figures)
        .map_err(|e| Error::file(&figures, format!("cannot create: {e}")))?;
    for (name, svg) in &report.figures {
        write(&figures.join(name), svg)?;
    }
    let path = dir.join("report.md");
    write(&path, &report.markdown)?;
    Ok(path)
}

/// The report of `results` (at least one campaign) made by `command` (quoted in the report to
/// reproduce it): what `write_report` writes, in memory (the server's simulation report).
///
/// # Errors
/// No campaign in `results`; a chart that cannot be drawn.
pub fn render_report(results: &[CampaignResult], command: &str) -> Result<RenderedReport> {
    if results.is_empty() {
        return Err(Error::App(AppError::Invalid(
            "no campaigns to report".into(),
        )));
    }
    let mut charts: Vec<(String, String)> = Vec::new();
    let summaries = summarise(results, Strategy::Gleaner);
    let unit = "m³/m³";
    let mut budgets: Vec<f64> = summaries.iter().map(|s| s.budget).collect();
    budgets.sort_by(f64::total_cmp);
    budgets.dedup();
    let main_budget = budgets
        .iter()
        .copied()
        .min_by(|a, b| (a - 1.0).abs().total_cmp(&(b - 1.0).abs()))
        .unwrap_or(1.0);
    let mut md = String::new();
    overview_section(&mut md, results, command, &budgets, unit)?;
    let at_main: Vec<&Summary> = summaries
        .iter()
        .filter(|s| s.budget == main_budget)
        .collect();
    strategies_section(&mut md, results, &summaries, (&at_main, main_budget), unit)?;
    charts.push((
        "rmse_intervals.svg".into(),
        rmse_chart(&at_main, main_budget, unit)?,
    ));
    writeln!(
        md,
        "![RMSE with 95% intervals](figures/rmse_intervals.svg)\n"
    )?;
    exhaustive_section(&mut md, &summaries, main_budget)?;
    let strategies: Vec<Strategy> = at_main.iter().map(|s| s.strategy).collect();
    over_campaign_section(
        &mut md,
        &mut charts,
        results,
        (&strategies, main_budget),
        unit,
    )?;
    if budgets.len() > 1 {
        against_budget_section(&mut md, &mut charts, &summaries, &strategies, unit)?;
    }
    flights_section(&mut md, results)?;
    definitions_section(&mut md, results, command)?;
    Ok(RenderedReport {
        markdown: md,
        figures: charts,
    })
}

/// The report's title, the command that reproduces it, and what the campaigns were: missions,
/// the fitted models, events, budgets.
fn overview_section(
    md: &mut String,
    results: &[CampaignResult],
    command: &str,
    budgets: &[f64],
    unit: &str,
) -> Result<()> {
    let modality = &results[0].modality;
    let labels: Vec<&str> = results.iter().map(|r| r.label.as_str()).collect();
    let first = &results[0];
    let missions = first.runs.first().map_or(0, |r| r.missions.len());
    let (t0, t1) = first
        .runs
        .first()
        .and_then(|r| Some((r.missions.first()?.t, r.missions.last()?.t)))
        .unwrap_or((0, 0));
    writeln!(md, "# Campaign report: {}\n", labels.join(", "))?;
    writeln!(md, "Reproduce with:\n\n```\n{}\n```\n", command.trim())?;
    writeln!(
        md,
        "- {} campaign(s); {} missions each, {} .. {}; evaluated modality `{modality}`.",
        results.len(),
        missions,
        format_rfc3339(t0),
        format_rfc3339(t1)
    )?;
    let c = first.covariance;
    writeln!(
        md,
        "- Field model fitted on the history{}: sill {:.3e}, nugget {:.3e} ({unit})², range {:.0} m, time scale {:.1} days, {:.0}% of the variance persisting past one step (temporal nugget {:.0}%).",
        if results.len() > 1 {
            " (first campaign)"
        } else {
            ""
        },
        c.sill,
        c.nugget,
        c.range_m,
        c.time_scale_s / 86_400.0,
        100.0 * c.temporal_share,
        100.0 * (1.0 - c.temporal_share)
    )?;
    if let Some(m) = first.changes {
        // Root mean square changes over a day and a week, the unit ×1000.
        let rms = |v: &Variogram, days: f64| 1000.0 * v.at(days * 86_400.0).sqrt();
        writeln!(
            md,
            "- Model of changes fitted on the history: field-wide part {:.2} / {:.2} ×10⁻³ {unit} \
             r.m.s. over 1 / 7 days, correlated in space with range {:.0} m; each sensor's own \
             part {:.2} / {:.2}; a neighbour's change over the same week explains {:.0}% of \
             the variance of a sensor's 100 m away.",
            rms(&m.shared, 1.0),
            rms(&m.shared, 7.0),
            m.range_m,
            rms(&m.own, 1.0),
            rms(&m.own, 7.0),
            {
                let week = 7.0 * 86_400.0;
                let k = (-100.0 / m.range_m).exp() * m.shared.at(week);
                100.0 * k * k / (m.carried_variance(week) * m.carried_variance(week))
            }
        )?;
    }
    let n_events: usize = results.iter().map(|r| r.events.len()).sum();
    writeln!(
        md,
        "- {n_events} anomaly events became available during the campaign(s) ({}).",
        if first.events.first().is_some_and(|e| e.id.starts_with('Z')) {
            "real-data rule: runs of |z| > threshold of a sensor's one-step change, z against its whole series"
        } else {
            "the synthetic farms' ground truth"
        }
    )?;
    writeln!(
        md,
        "- Budgets (fractions of the preset battery): {}.\n",
        budgets
            .iter()
            .map(|b| format!("{b}"))
            .collect::<Vec<_>>()
            .join(", ")
    )?;
    Ok(())
}

/// The strategies' table at the main budget, and which strategies' runs were identical.
fn strategies_section(
    md: &mut String,
    results: &[CampaignResult],
    summaries: &[Summary],
    (at_main, main_budget): (&[&Summary], f64),
    unit: &str,
) -> Result<()> {
    writeln!(md, "## Strategies at budget {main_budget}\n")?;
    writeln!(
        md,
        "Means over missions with 95% intervals: Student's t over the means of blocks of {} days \
         of missions (runs and campaigns averaged within a block, so replicates of one dataset \
         do not count as independent evidence; `n (k distinct)` runs: only k of the n seeds' \
         campaigns differ, the planner being deterministic on the case), given only with at \
         least {} blocks. RMSE/MAE in \
         {unit} ×1000 against the true reading stamped T − period of every sensor that has one; \
         ΔRMSE is the strategy's kriging RMSE minus gleaner's, paired by mission; Δdelay is the \
         strategy's catch delay minus gleaner's over the events both caught (t over events).\n",
        BLOCK_DAYS, MIN_BLOCKS,
    )?;
    writeln!(
        md,
        "| strategy | runs | RMSE kriging | ΔRMSE vs gleaner | RMSE carried | MAE kriging | 90% coverage % | energy kJ/mission | utilisation % | cells/mission | staleness mean d | staleness max d | events caught | delay d | Δdelay vs gleaner d | classifier % | lost readings |"
    )?;
    writeln!(
        md,
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    )?;
    for s in at_main {
        let (caught, total) = s.events_caught;
        writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {caught}/{total} | {} | {} | {} | {} |",
            s.strategy.name(),
            runs_cell(results, s),
            fmt_iv(get(s, "rmse_kriged"), 1000.0, 2),
            s.rmse_vs_reference
                .as_ref()
                .map_or("–".into(), |i| fmt_iv(i, 1000.0, 2)),
            fmt_iv(get(s, "rmse_carried"), 1000.0, 2),
            fmt_iv(get(s, "mae_kriged"), 1000.0, 2),
            fmt_iv(get(s, "coverage90"), 100.0, 1),
            fmt_iv(get(s, "energy_kj"), 1.0, 1),
            fmt_iv(get(s, "utilisation"), 100.0, 1),
            fmt_iv(get(s, "cells"), 1.0, 1),
            fmt_iv(get(s, "staleness_mean_days"), 1.0, 2),
            fmt_iv(get(s, "staleness_max_days"), 1.0, 1),
            fmt_iv(&s.delay_days, 1.0, 2),
            s.delay_vs_reference
                .as_ref()
                .map_or("–".into(), |i| fmt_iv(i, 1.0, 2)),
            fmt_iv(get(s, "classifier_accuracy"), 100.0, 1),
            fmt_iv(get(s, "lost_readings"), 1.0, 1),
        )?;
    }
    writeln!(md)?;
    let shared = same_runs(results, summaries);
    if !shared.is_empty() {
        let text: Vec<String> = shared
            .iter()
            .map(|(b, a)| format!("`{}` = `{}`", b.name(), a.name()))
            .collect();
        writeln!(
            md,
            "Identical results mission by mission: {}. (Runs with the same settings are \
             computed once: gleaner's method has γ = δ = 0, so its `no-uncertainty` and \
             `no-redundancy` ablations are gleaner's run; different strategies can also choose \
             the same cells at every mission.)\n",
            text.join(", ")
        )?;
    }
    Ok(())
}

/// The chart of the kriging RMSE with its 95% intervals at the main budget (SVG).
fn rmse_chart(at_main: &[&Summary], main_budget: f64, unit: &str) -> Result<String> {
    let rows: Vec<IntervalRow> = at_main
        .iter()
        .map(|s| {
            let i = get(s, "rmse_kriged");
            let (low, high) = if i.low.is_finite() && i.high.is_finite() {
                (i.low, i.high)
            } else {
                (i.mean, i.mean)
            };
            IntervalRow {
                name: s.strategy.name().into(),
                mean: i.mean * 1000.0,
                low: low * 1000.0,
                high: high * 1000.0,
            }
        })
        .filter(|r| r.mean.is_finite())
        .collect();
    Ok(interval_chart_svg(&IntervalChart {
        title: format!("Kriging RMSE at budget {main_budget} (95% intervals)"),
        x_label: format!("RMSE, {unit} ×1000"),
        rows,
    })?)
}

/// The x axis of the charts over a campaign: the missions' times.
const BY_MISSION_TIME: (&str, XAxis) = ("mission time (UTC)", XAxis::Date);

/// The x axis of the charts against the budget, % of the preset battery.
const BY_BUDGET: (&str, XAxis) = ("budget, % of the preset battery", XAxis::Number);

/// A metric's chart: `title`, the x axis (label and kind), the y axis label, the lines.
fn line_chart(
    title: String,
    (x_label, x_axis): (&str, XAxis),
    y_label: String,
    lines: Vec<Line>,
) -> LineChart {
    LineChart {
        title,
        x_label: x_label.into(),
        y_label,
        x_axis,
        lines,
    }
}

/// Draws `chart` as `figures/<file>` and links it in `md` with `alt`, unless no line has a
/// finite point (then nothing).
fn push_chart(
    md: &mut String,
    charts: &mut Vec<(String, String)>,
    chart: LineChart,
    file: String,
    alt: &str,
) -> Result<()> {
    if chart
        .lines
        .iter()
        .all(|l| l.points.iter().all(|p| !p.1.is_finite()))
    {
        return Ok(());
    }
    let svg = line_chart_svg(&chart)?;
    writeln!(md, "![{alt}](figures/{file})\n")?;
    charts.push((file, svg));
    Ok(())
}

/// Each metric over the campaign at the main budget: a line per strategy (charts).
fn over_campaign_section(
    md: &mut String,
    charts: &mut Vec<(String, String)>,
    results: &[CampaignResult],
    (strategies, main_budget): (&[Strategy], f64),
    unit: &str,
) -> Result<()> {
    writeln!(
        md,
        "## Each metric over the campaign (budget {main_budget})\n"
    )?;
    for name in METRICS {
        let (title, ylabel, scale, _) = describe(name, unit);
        let lines: Vec<Line> = strategies
            .iter()
            .map(|&st| {
                // Mean over runs (and campaigns) by mission index; x = the first run's times.
                let runs: Vec<&RunResult> = results
                    .iter()
                    .flat_map(|r| r.runs.iter())
                    .filter(|r| r.key.strategy == st && r.key.budget == main_budget)
                    .collect();
                let n = runs.iter().map(|r| r.missions.len()).min().unwrap_or(0);
                let points = (0..n)
                    .map(|k| {
                        let v: Vec<f64> = runs
                            .iter()
                            .map(|r| metric(&r.missions[k], name))
                            .filter(|v| v.is_finite())
                            .collect();
                        let y = if v.is_empty() {
                            f64::NAN
                        } else {
                            v.iter().sum::<f64>() / v.len() as f64 * scale
                        };
                        (runs[0].missions[k].t as f64, y)
                    })
                    .collect();
                Line {
                    name: st.name().into(),
                    points,
                }
            })
            .collect();
        let chart = line_chart(
            format!("{title} per mission"),
            BY_MISSION_TIME,
            ylabel,
            lines,
        );
        push_chart(
            md,
            charts,
            chart,
            format!("{name}_over_campaign.svg"),
            title,
        )?;
    }
    Ok(())
}

/// Each metric against the budget: a table and a chart per metric.
fn against_budget_section(
    md: &mut String,
    charts: &mut Vec<(String, String)>,
    summaries: &[Summary],
    strategies: &[Strategy],
    unit: &str,
) -> Result<()> {
    writeln!(md, "## Each metric against the budget\n")?;
    writeln!(
        md,
        "| strategy | budget | RMSE kriging | energy kJ/mission | events caught | delay d |\n|---|---|---|---|---|---|"
    )?;
    for s in summaries {
        writeln!(
            md,
            "| {} | {} | {} | {} | {}/{} | {} |",
            s.strategy.name(),
            s.budget,
            fmt_iv(get(s, "rmse_kriged"), 1000.0, 2),
            fmt_iv(get(s, "energy_kj"), 1.0, 1),
            s.events_caught.0,
            s.events_caught.1,
            fmt_iv(&s.delay_days, 1.0, 2)
        )?;
    }
    writeln!(md)?;
    let mut metrics: Vec<&str> = METRICS.to_vec();
    metrics.push("events_caught_share");
    metrics.push("delay_days");
    for name in metrics {
        let (title, ylabel, scale) = match name {
            "events_caught_share" => ("events caught", "%".to_string(), 100.0),
            "delay_days" => ("delay to catch an event", "days".to_string(), 1.0),
            other => {
                let (t, y, s, _) = describe(other, unit);
                (t, y, s)
            }
        };
        let lines: Vec<Line> = strategies
            .iter()
            .map(|&st| Line {
                name: st.name().into(),
                points: summaries
                    .iter()
                    .filter(|s| s.strategy == st)
                    .map(|s| {
                        let y = match name {
                            "events_caught_share" => {
                                s.events_caught.0 as f64 / s.events_caught.1.max(1) as f64
                            }
                            "delay_days" => s.delay_days.mean,
                            other => get(s, other).mean,
                        };
                        (s.budget * 100.0, y * scale)
                    })
                    .collect(),
            })
            .collect();
        let chart = line_chart(
            format!("{title} against the budget"),
            BY_BUDGET,
            ylabel,
            lines,
        );
        let alt = format!("{title} against the budget");
        push_chart(md, charts, chart, format!("{name}_vs_budget.svg"), &alt)?;
    }
    Ok(())
}

/// How the simulation worked and what each metric means; the model-based estimate named as
/// recorded with the results (older results: as named on the command line).
fn definitions_section(md: &mut String, results: &[CampaignResult], command: &str) -> Result<()> {
    writeln!(md, "## Definitions\n")?;
    // The model-based estimate ("kriging" columns) the simulation used.
    // Recorded with the results; older results: named on the command line.
    let recorded = results.iter().find_map(|r| r.estimator);
    let named = |e: &str| match recorded {
        Some(r) => r.name() == e,
        None => {
            command.contains(&format!("--estimator {e}"))
                || command.contains(&format!("--estimator={e}"))
        }
    };
    let old_flag = |f: &str| recorded.is_none() && command.contains(f);
    let model_based = if old_flag("--simple-kriging")
        || old_flag("--level-kriging")
        || named("levels")
        || named("simple")
    {
        format!(
            "kriging = {} kriging of levels (residuals from each sensor's history mean) with a \
             separable exponential space-time covariance and a temporal nugget fitted on the \
             history, from the 16 most correlated latest readings",
            if old_flag("--simple-kriging") || named("simple") {
                "simple"
            } else {
                "ordinary"
            }
        )
    } else if named("dynamic") {
        "kriging = the dynamic field model: each sensor's mean and a covariance of levels between \
         sensors learned from the history (shrunk), AR(1) persistence of the deviations, a Kalman \
         filter over the readings known in the window before the estimate (docs/method.md §7): \
         a sensor read lately is known from its own reading, one not read for long from the \
         sensors read since"
            .to_string()
    } else {
        "kriging = kriging of changes: each sensor's last collected value plus its change since, \
         estimated by simple kriging from the changes its neighbours are known to have made over \
         (part of) that interval (a model of changes fitted on the history: a field-wide part \
         correlated in space, each sensor's own part; exponential variograms with a nugget), \
         from the 16 most informative changes; with no neighbour collected since, exactly the \
         carried value"
            .to_string()
    };
    writeln!(
        md,
        "- Every run is its own project (an in-memory store) driven through gleaner's score, plan, \
         explore and record use cases; the planner knows only the history and what its flights \
         brought back; a reading stamped t is available from t + period on.\n\
         - Strategies: gleaner = gleaner's method (gated S = αF·max(0, 1 + 4A), F from each \
         sensor's own drift — the staleness index of its mean squared change, less the field's \
         mean, over the last year of collected readings —, bounded anomaly, γ = δ = 0) + the \
         default planner; gated = gleaner's first method (gated S with a 14-day freshness \
         half-life and the project's γ, δ); paper = the paper's S (docs/method.md §2 at its values) + the \
         paper's greedy; variance = greedy expected reduction of the level kriging's posterior \
         variance, routed by the default planner; freshness = S with F only; round-robin = days \
         since the last collection; random = seeded uniform scores; nearest = equal scores with \
         greedy insertion; exhaustive = every cell, as many sorties as it takes; no-X = gleaner \
         without term X; oracle (when run) = a clairvoyant yardstick, not a flyable strategy: \
         each cell worth the squared error of its sensors' pre-flight estimates against the \
         values the flight will bring back, default planner.\n\
         - Reconstruction at mission T (after its flights): each sensor's value stamped T − period; \
         carried = its last collected value; {model_based}.\n\
         - An event is caught at the first mission that collects one of its sensors (with an \
         event reading still in the buffer) once its first reading is available; delay = catch \
         time − (start + period).\n\
         - Classifier accuracy: the condition model's most likely class per cell before the \
         flight against the class of the cell's true value (the model's own thresholds).\n\
         - Staleness: mission time minus each sensor's last collection."
    )?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn energy_at_ratio_interpolates_between_the_budgets_around_the_target() {
        // caf-daily-energy's gleaner: 1.48 at 0.35, 1.24 at 0.49, 1.16 at 0.61 (any order).
        let p = [(0.61, 1.16), (0.35, 1.48), (0.49, 1.24), (0.74, 1.07)];
        let Crossing::Between(e) = energy_at_ratio(&p, 1.2) else {
            panic!("expected a crossing")
        };
        assert!((e - 0.55).abs() < 1e-12, "{e}");
        assert_eq!(
            energy_at_ratio(&[(0.3, 1.1), (0.5, 1.0)], 1.2),
            Crossing::AtLeast(0.3)
        );
        assert_eq!(
            energy_at_ratio(&[(0.3, 1.9), (0.5, 1.4), (0.7, 1.5)], 1.2),
            Crossing::Beyond {
                energy: 0.5,
                ratio: 1.4
            }
        );
        // Exactly at the target counts; non-finite points are ignored.
        assert_eq!(
            energy_at_ratio(&[(f64::NAN, 1.0), (0.4, 1.3), (0.6, 1.2)], 1.2),
            Crossing::Between(0.6)
        );
    }
}
