//! The results format of a simulation: what `simulate` writes into its output directory (CSV
//! files, one row per campaign, event, mission, sortie flown, event catch and visited cell,
//! plus the command line) and the report reads back into the simulator's plain types.
//! Files written by earlier versions (fewer columns) are still read.

use std::fmt::Write as _;
use std::path::Path;

use gleaner_field::SensorId;
use gleaner_kriging::{Covariance, IncrementModel, Variogram};

use crate::campaign::{CampaignResult, MissionMetrics, RunKey, RunResult, Strategy, TruthEvent};
use crate::error::{Error, Result};

pub(crate) const CAMPAIGN: &str = "campaign.csv";
const MISSIONS: &str = "missions.csv";
const EVENTS: &str = "events.csv";
const CATCHES: &str = "catches.csv";
pub(crate) const COMMAND: &str = "command.txt";
const VISITS: &str = "visits.csv";
const FLIGHTS: &str = "flights.csv";
const FLIGHTS_HEADER: &str = "label,strategy,seed,budget,index,forecast_mps,forecast_from_deg,actual_mps,actual_from_deg,battery_factor,replanned,cells_dropped,readings,energy_j,over_budget,max_excess_j";

const MISSIONS_HEADER: &str = "label,strategy,seed,budget,index,t,sorties,cells,energy_j,budget_j,rmse_carried,mae_carried,rmse_kriged,mae_kriged,mean_variance,evaluated,staleness_mean_s,staleness_max_s,classifier_accuracy,lost_readings,events_caught,rmse_carried_before,rmse_kriged_before,coverage90";
/// Columns of `missions.csv` before the pre-flight errors were added (still read).
const MISSIONS_COLUMNS_V1: usize = 21;
/// Columns of missions.csv before `coverage90`.
const MISSIONS_COLUMNS_V2: usize = 23;

/// Writes `text` to `path`.
pub(crate) fn write(path: &Path, text: &str) -> Result<()> {
    std::fs::write(path, text).map_err(|e| Error::file(path, format!("cannot write: {e}")))
}

/// Writes the campaigns' results as CSV files into `dir`, with the command that made them.
pub fn write_results(dir: &Path, results: &[CampaignResult], command: &str) -> Result<()> {
    let mut campaign = String::from(
        "label,modality,period_s,sill,nugget,range_m,time_scale_s,temporal_share,\
        changes_shared_nugget,changes_shared_partial,changes_shared_scale_s,changes_range_m,\
        changes_own_nugget,changes_own_partial,changes_own_scale_s,estimator\n",
    );
    let mut missions = format!("{MISSIONS_HEADER}\n");
    let mut events = String::from("label,event,sensors,start,end\n");
    let mut catches = String::from("label,strategy,seed,budget,event,caught_at\n");
    let mut visits = String::from("label,strategy,seed,budget,index,cell,age_days,f,a,u,r,s\n");
    let mut flights = format!("{FLIGHTS_HEADER}\n");
    for r in results {
        let c = r.covariance;
        write!(
            campaign,
            "{},{},{},{},{},{},{},{}",
            r.label,
            r.modality,
            r.period_s,
            c.sill,
            c.nugget,
            c.range_m,
            c.time_scale_s,
            c.temporal_share
        )?;
        // The model of changes: 7 more columns (empty when unknown).
        match r.changes {
            Some(m) => write!(
                campaign,
                ",{},{},{},{},{},{},{}",
                m.shared.nugget,
                m.shared.partial,
                m.shared.scale_s,
                m.range_m,
                m.own.nugget,
                m.own.partial,
                m.own.scale_s
            )?,
            None => write!(campaign, ",,,,,,,")?,
        }
        writeln!(
            campaign,
            ",{}",
            r.estimator.map_or("", gleaner_app::Estimator::name)
        )?;
        for e in &r.events {
            let ids: Vec<&str> = e.sensors.iter().map(SensorId::as_str).collect();
            writeln!(
                events,
                "{},{},{},{},{}",
                r.label,
                e.id,
                ids.join(";"),
                e.start,
                e.end
            )?;
        }
        for run in &r.runs {
            let k = &run.key;
            let head = format!("{},{},{},{}", r.label, k.strategy.name(), k.seed, k.budget);
            for m in &run.missions {
                writeln!(
                    missions,
                    "{head},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
                    m.index,
                    m.t,
                    m.sorties,
                    m.cells,
                    m.energy_j,
                    m.budget_j,
                    m.rmse_carried,
                    m.mae_carried,
                    m.rmse_kriged,
                    m.mae_kriged,
                    m.mean_variance,
                    m.evaluated,
                    m.staleness_mean_s,
                    m.staleness_max_s,
                    m.classifier_accuracy
                        .map_or(String::new(), |a| a.to_string()),
                    m.lost_readings,
                    m.events_caught,
                    m.rmse_carried_before,
                    m.rmse_kriged_before,
                    m.coverage90.map_or(String::new(), |c| c.to_string())
                )?;
            }
            for (m, f) in run
                .missions
                .iter()
                .filter_map(|m| Some((m, m.flight.as_ref()?)))
            {
                let w = &f.wind;
                writeln!(
                    flights,
                    "{head},{},{},{},{},{},{},{},{},{},{},{},{}",
                    m.index,
                    w.forecast.speed_mps,
                    w.forecast.from_deg,
                    w.actual.speed_mps,
                    w.actual.from_deg,
                    f.battery_factor,
                    f.replanned,
                    f.cells_dropped,
                    f.readings,
                    f.energy_j,
                    f.over_budget,
                    f.max_excess_j
                )?;
            }
            for v in &run.visits {
                writeln!(
                    visits,
                    "{head},{},{},{},{},{},{},{},{}",
                    v.index, v.cell, v.age_days, v.f, v.a, v.u, v.r, v.s
                )?;
            }
            for (e, c) in r.events.iter().zip(&run.caught) {
                writeln!(
                    catches,
                    "{head},{},{}",
                    e.id,
                    c.map_or(String::new(), |t| t.to_string())
                )?;
            }
        }
    }
    write(&dir.join(CAMPAIGN), &campaign)?;
    write(&dir.join(MISSIONS), &missions)?;
    write(&dir.join(EVENTS), &events)?;
    write(&dir.join(CATCHES), &catches)?;
    write(&dir.join(VISITS), &visits)?;
    write(&dir.join(FLIGHTS), &flights)?;
    write(&dir.join(COMMAND), &format!("{command}\n"))?;
    Ok(())
}

/// Rows of one of our CSV files (header skipped), with a located error on a short row.
fn rows(path: &Path, columns: usize) -> Result<Vec<(usize, Vec<String>)>> {
    rows_of(path, &[columns])
}

/// [`rows`] of a file whose rows may have any of `columns` fields (older versions).
fn rows_of(path: &Path, columns: &[usize]) -> Result<Vec<(usize, Vec<String>)>> {
    let text = std::fs::read_to_string(path).map_err(|e| {
        Error::file(
            path,
            format!("cannot read (run `gleaner simulate` first): {e}"),
        )
    })?;
    let mut out = Vec::new();
    for (n, line) in text.lines().enumerate().skip(1) {
        if line.trim().is_empty() {
            continue;
        }
        let cells: Vec<String> = line.split(',').map(str::to_string).collect();
        if !columns.contains(&cells.len()) {
            let expected: Vec<String> = columns.iter().map(usize::to_string).collect();
            return Err(Error::malformed(
                path,
                n + 1,
                format!("{} fields, expected {}", cells.len(), expected.join(" or ")),
            ));
        }
        out.push((n + 1, cells));
    }
    Ok(out)
}

/// Field `v` of column `column` at `path`:`line`.
fn num<T: std::str::FromStr>(path: &Path, line: usize, column: &str, v: &str) -> Result<T> {
    v.parse().map_err(|_| {
        Error::malformed(
            path,
            line,
            format!("column `{column}`: invalid value {v:?}"),
        )
    })
}

/// Reads the results `write_results` wrote.
pub fn read_results(dir: &Path) -> Result<Vec<CampaignResult>> {
    let mut results = read_campaigns(dir)?;
    read_events(dir, &mut results)?;
    read_missions(dir, &mut results)?;
    read_flights(dir, &mut results)?;
    read_catches(dir, &mut results)?;
    Ok(results)
}

/// The campaign named `label` among `results`, for line `line` of `p`.
fn find(results: &[CampaignResult], label: &str, p: &Path, line: usize) -> Result<usize> {
    results
        .iter()
        .position(|r| r.label == label)
        .ok_or_else(|| Error::malformed(p, line, format!("unknown campaign {label:?}")))
}

/// The campaigns of `campaign.csv`, without their events and runs.
fn read_campaigns(dir: &Path) -> Result<Vec<CampaignResult>> {
    let mut results: Vec<CampaignResult> = Vec::new();
    let p = dir.join(CAMPAIGN);
    // Files written before the temporal nugget have 7 columns (temporal share 1), before the
    // model of changes 8, before the estimator 15.
    let campaign_rows = rows_of(&p, &[16, 15, 8, 7])?;
    for (line, c) in campaign_rows {
        let share = match c.get(7) {
            Some(v) => num(&p, line, "temporal_share", v)?,
            None => 1.0,
        };
        let cov = Covariance::new(
            num(&p, line, "sill", &c[3])?,
            num(&p, line, "nugget", &c[4])?,
            num(&p, line, "range_m", &c[5])?,
            num(&p, line, "time_scale_s", &c[6])?,
        )
        .and_then(|c| c.with_temporal_share(share))
        .map_err(|e| Error::malformed(&p, line, e))?;
        let changes = if c.len() >= 15 && !c[8].is_empty() {
            let f = |k: usize, what: &str| num::<f64>(&p, line, what, &c[k]);
            let v = |k: usize| -> Result<Variogram> {
                Ok(Variogram {
                    nugget: f(k, "changes nugget")?,
                    partial: f(k + 1, "changes partial")?,
                    scale_s: f(k + 2, "changes scale_s")?,
                })
            };
            Some(
                IncrementModel::new(v(8)?, f(11, "changes_range_m")?, v(12)?)
                    .map_err(|e| Error::malformed(&p, line, e))?,
            )
        } else {
            None
        };
        results.push(CampaignResult {
            label: c[0].clone(),
            modality: c[1].clone(),
            period_s: num(&p, line, "period_s", &c[2])?,
            covariance: cov,
            changes,
            estimator: match c.get(15).map(String::as_str) {
                None | Some("") => None,
                Some(name) => Some(
                    name.parse::<gleaner_app::Estimator>()
                        .map_err(|e| Error::malformed(&p, line, format!("estimator: {e}")))?,
                ),
            },
            events: Vec::new(),
            runs: Vec::new(),
        });
    }
    Ok(results)
}

/// The events of `events.csv`, into their campaigns.
fn read_events(dir: &Path, results: &mut [CampaignResult]) -> Result<()> {
    let p = dir.join(EVENTS);
    for (line, c) in rows(&p, 5)? {
        let r = find(results, &c[0], &p, line)?;
        let sensors = c[2]
            .split(';')
            .filter(|s| !s.is_empty())
            .map(|s| SensorId::new(s).map_err(|e| Error::malformed(&p, line, e)))
            .collect::<Result<Vec<_>>>()?;
        results[r].events.push(TruthEvent {
            id: c[1].clone(),
            sensors,
            start: num(&p, line, "start", &c[3])?,
            end: num(&p, line, "end", &c[4])?,
        });
    }
    Ok(())
}

/// The missions of `missions.csv`, into their campaigns' runs.
fn read_missions(dir: &Path, results: &mut [CampaignResult]) -> Result<()> {
    let p = dir.join(MISSIONS);
    for (line, c) in rows_of(
        &p,
        &[
            MISSIONS_HEADER.split(',').count(),
            MISSIONS_COLUMNS_V2,
            MISSIONS_COLUMNS_V1,
        ],
    )? {
        let r = find(results, &c[0], &p, line)?;
        let key = RunKey {
            strategy: Strategy::parse(&c[1]).map_err(|e| Error::malformed(&p, line, e))?,
            seed: num(&p, line, "seed", &c[2])?,
            budget: num(&p, line, "budget", &c[3])?,
        };
        let f = |k: usize, name: &str| num::<f64>(&p, line, name, &c[k]);
        let m = MissionMetrics {
            index: num(&p, line, "index", &c[4])?,
            t: num(&p, line, "t", &c[5])?,
            sorties: num(&p, line, "sorties", &c[6])?,
            cells: num(&p, line, "cells", &c[7])?,
            energy_j: f(8, "energy_j")?,
            budget_j: f(9, "budget_j")?,
            rmse_carried: f(10, "rmse_carried")?,
            mae_carried: f(11, "mae_carried")?,
            rmse_kriged: f(12, "rmse_kriged")?,
            mae_kriged: f(13, "mae_kriged")?,
            mean_variance: f(14, "mean_variance")?,
            coverage90: match c.get(23).map(String::as_str) {
                None | Some("") => None,
                Some(_) => Some(f(23, "coverage90")?),
            },
            evaluated: num(&p, line, "evaluated", &c[15])?,
            staleness_mean_s: f(16, "staleness_mean_s")?,
            staleness_max_s: f(17, "staleness_max_s")?,
            classifier_accuracy: if c[18].is_empty() {
                None
            } else {
                Some(f(18, "classifier_accuracy")?)
            },
            lost_readings: num(&p, line, "lost_readings", &c[19])?,
            events_caught: num(&p, line, "events_caught", &c[20])?,
            rmse_carried_before: if c.len() > 21 {
                f(21, "rmse_carried_before")?
            } else {
                f64::NAN
            },
            rmse_kriged_before: if c.len() > 22 {
                f(22, "rmse_kriged_before")?
            } else {
                f64::NAN
            },
            flight: None,
        };
        let n_events = results[r].events.len();
        let runs = &mut results[r].runs;
        match runs.iter_mut().find(|x| x.key == key) {
            Some(run) => run.missions.push(m),
            None => runs.push(RunResult {
                key,
                missions: vec![m],
                caught: vec![None; n_events],
                visits: Vec::new(),
            }),
        }
    }
    Ok(())
}

/// The flights of `flights.csv`, into their missions.
fn read_flights(dir: &Path, results: &mut [CampaignResult]) -> Result<()> {
    // Flights (files written before flights were simulated have none).
    let p = dir.join(FLIGHTS);
    if p.exists() {
        for (line, c) in rows(&p, FLIGHTS_HEADER.split(',').count())? {
            let r = find(results, &c[0], &p, line)?;
            let strategy = Strategy::parse(&c[1]).map_err(|e| Error::malformed(&p, line, e))?;
            let seed: u64 = num(&p, line, "seed", &c[2])?;
            let budget: f64 = num(&p, line, "budget", &c[3])?;
            let index: usize = num(&p, line, "index", &c[4])?;
            let f = |k: usize, name: &str| num::<f64>(&p, line, name, &c[k]);
            let wind = |k: usize, what: &str| -> Result<gleaner_app::Wind> {
                gleaner_app::Wind::new(f(k, what)?, f(k + 1, what)?)
                    .map_err(|e| Error::malformed(&p, line, format!("{what}: {e}")))
            };
            let day = crate::campaign_flight::FlightDay {
                wind: crate::campaign_flight::DayWind {
                    forecast: wind(5, "forecast")?,
                    actual: wind(7, "actual")?,
                },
                battery_factor: f(9, "battery_factor")?,
                replanned: num(&p, line, "replanned", &c[10])?,
                cells_dropped: num(&p, line, "cells_dropped", &c[11])?,
                readings: num(&p, line, "readings", &c[12])?,
                energy_j: f(13, "energy_j")?,
                over_budget: num(&p, line, "over_budget", &c[14])?,
                max_excess_j: f(15, "max_excess_j")?,
            };
            let mission = results[r]
                .runs
                .iter_mut()
                .find(|x| {
                    x.key.strategy == strategy && x.key.seed == seed && x.key.budget == budget
                })
                .and_then(|run| run.missions.iter_mut().find(|m| m.index == index));
            match mission {
                Some(m) => m.flight = Some(day),
                None => {
                    return Err(Error::malformed(
                        &p,
                        line,
                        format!("no such mission in {MISSIONS}"),
                    ));
                }
            }
        }
    }
    Ok(())
}

/// The catches of `catches.csv`, into their runs.
fn read_catches(dir: &Path, results: &mut [CampaignResult]) -> Result<()> {
    let p = dir.join(CATCHES);
    for (line, c) in rows(&p, 6)? {
        let r = find(results, &c[0], &p, line)?;
        if c[5].is_empty() {
            continue;
        }
        let strategy = Strategy::parse(&c[1]).map_err(|e| Error::malformed(&p, line, e))?;
        let seed: u64 = num(&p, line, "seed", &c[2])?;
        let budget: f64 = num(&p, line, "budget", &c[3])?;
        let at: i64 = num(&p, line, "caught_at", &c[5])?;
        let Some(e) = results[r].events.iter().position(|e| e.id == c[4]) else {
            return Err(Error::malformed(
                &p,
                line,
                format!("unknown event {:?}", c[4]),
            ));
        };
        if let Some(run) = results[r]
            .runs
            .iter_mut()
            .find(|x| x.key.strategy == strategy && x.key.seed == seed && x.key.budget == budget)
        {
            run.caught[e] = Some(at);
        }
    }
    Ok(())
}
