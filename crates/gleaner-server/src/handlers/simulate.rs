//! Campaign simulations of the served project's record, with their reports.

use std::path::PathBuf;

use axum::Json;
use axum::body::Bytes;
use axum::extract::State;
use axum::extract::rejection::BytesRejection;
use gleaner_app as app;

use crate::api::{ReportDoc, SimulateBody, SimulationDoc, WindDayBody, parse_time};
use crate::auth::Computing;
use crate::error::{ApiError, ApiResult, ErrorBody};
use crate::state::{AppState, Changes, Job};

use super::{JsonType, clock_now, energy_preset, json_body};

/// Most missions one simulation request may fly in all (missions × strategies × seeds ×
/// budgets): about a minute of CPU on CAF-sized farms.
pub const MAX_SIMULATED_MISSIONS: usize = 5_000;

/// Replays the served project's own record as a campaign (`gleaner simulate --project`):
/// each strategy flies the same missions from the same history, each run its own in-memory
/// copy; the answer compares them (error after the flights, events caught and how soon,
/// energy, with 95% intervals when the campaign spans 10 weeks or more); with
/// `"report": true` also its report (Markdown and SVG charts, as `gleaner simulate` writes).
/// Reads only; one simulation or planning search at a time.
#[utoipa::path(post, path = "/api/v1/simulate", tag = "data", request_body = SimulateBody,
    responses((status = 200, body = SimulationDoc), (status = 400, body = ErrorBody),
        (status = 413, body = ErrorBody)))]
pub async fn simulate(
    State(s): State<AppState>,
    _: Computing,
    _: JsonType,
    body: Result<Bytes, BytesRejection>,
) -> ApiResult<Json<SimulationDoc>> {
    // The request as given, quoted by the report to reproduce it.
    let request = match &body {
        Ok(bytes) => String::from_utf8_lossy(bytes).trim().to_string(),
        Err(_) => String::new(),
    };
    let b: SimulateBody = json_body(body)?;
    let with_report = b.report;
    let flight = simulated_weather(&b)?;
    let observed = b.winds.is_some();
    let defaults = gleaner_campaign::campaign::ReplayOptions::default();
    let names = b.strategies.unwrap_or_else(|| {
        ["gleaner", "round-robin", "freshness"]
            .map(String::from)
            .to_vec()
    });
    let strategies = gleaner_campaign::campaign::Strategy::parse_list(&names)
        .map_err(|e| ApiError::from(e).in_field("strategies"))?;
    let every_hours = b.every_hours.unwrap_or(defaults.every_s as f64 / 3_600.0);
    if !(every_hours > 0.0 && every_hours <= 8_760.0) {
        return Err(ApiError::bad_request(
            Some("every_hours"),
            format!("expected hours in (0, 8760], got {every_hours}"),
        ));
    }
    let seeds = b.seeds.unwrap_or_else(|| defaults.seeds.clone());
    if seeds.is_empty() || seeds.len() > 10 {
        return Err(ApiError::bad_request(
            Some("seeds"),
            format!("expected 1 to 10 seeds, got {}", seeds.len()),
        ));
    }
    let budgets = b.budgets.unwrap_or_else(|| defaults.budgets.clone());
    if budgets.is_empty() || budgets.len() > 10 || !budgets.iter().all(|&x| x > 0.0 && x <= 10.0) {
        return Err(ApiError::bad_request(
            Some("budgets"),
            "expected 1 to 10 budgets, each in (0, 10]",
        ));
    }
    let planner_iterations = b.planner_iterations.unwrap_or(defaults.planner_iterations);
    if !(1..=10_000).contains(&planner_iterations) {
        return Err(ApiError::bad_request(
            Some("planner_iterations"),
            format!("expected 1..=10000, got {planner_iterations}"),
        ));
    }
    let energy_preset = energy_preset(b.energy_preset.as_deref())?;
    let options = gleaner_campaign::campaign::ReplayOptions {
        history_until: parse_time("history_until", b.history_until.as_deref())?,
        start: parse_time("start", b.start.as_deref())?,
        end: parse_time("end", b.end.as_deref())?,
        every_s: (every_hours * 3_600.0).round() as i64,
        strategies,
        seeds,
        budgets,
        planner_iterations,
        energy_preset,
        flight,
        ..defaults
    };
    let simulation = Job {
        kind: "simulate",
        planning: true,
        writes: Changes::NOTHING,
    };
    let doc = s
        .run_job(simulation, move |p, cancel| {
            let parts = gleaner_campaign::ProjectRecord::read(p)?.into_parts(p.dir());
            let replay = gleaner_campaign::campaign::replay(parts, &options, clock_now())?;
            if observed {
                // Every mission's day must have its wind: a gap names the field.
                replay
                    .request
                    .flight
                    .check(&replay.request.schedule)
                    .map_err(|e| ApiError::from(e).in_field("winds"))?;
            }
            let missions = replay.request.mission_runs();
            if missions > MAX_SIMULATED_MISSIONS {
                return Err(ApiError::bad_request(
                    Some("start"),
                    format!(
                        "{missions} missions in all (missions × strategies × seeds × budgets): \
                         at most {MAX_SIMULATED_MISSIONS} per request; shorten the period or \
                         name fewer strategies (the command line's simulate has no limit)"
                    ),
                ));
            }
            let result =
                gleaner_campaign::campaign::run_campaign(&replay.request, &replay.truth, cancel)?;
            let mut doc = gleaner_campaign::doc::campaign_doc(
                &gleaner_campaign::campaign::campaign_summary(&replay.request, &result),
            );
            if !replay.request.flight.is_still() {
                doc.flights = gleaner_campaign::doc::flights(
                    &gleaner_campaign::campaign::flight_summaries(std::slice::from_ref(&result)),
                );
            }
            let report = match with_report {
                true => Some(report_doc(
                    gleaner_campaign::report::render_report(
                        std::slice::from_ref(&result),
                        &format!("POST /api/v1/simulate {request}"),
                    )
                    .map_err(|e| match e {
                        gleaner_campaign::Error::App(e) => ApiError::from(e),
                        e => ApiError::internal(format!("the campaign's report: {e}")),
                    })?,
                )),
                false => None,
            };
            Ok(SimulationDoc {
                campaign: doc,
                report,
            })
        })
        .await?;
    Ok(Json(doc))
}

/// A rendered campaign report as the API answers it.
fn report_doc(r: gleaner_campaign::report::RenderedReport) -> ReportDoc {
    ReportDoc {
        markdown: r.markdown,
        figures: r
            .figures
            .into_iter()
            .map(|(name, svg)| crate::api::FigureDoc { name, svg })
            .collect(),
    }
}

/// The weather a simulation's flights meet, from its body (as `simulate --wind`, `--gust`,
/// `--leg-gust`, `--weak-battery`, `--weather-seed`, `--margin-quantile`); each value checked
/// on its own so that a refusal names its field.
fn simulated_weather(
    b: &SimulateBody,
) -> ApiResult<gleaner_campaign::campaign_flight::FlightConditions> {
    use gleaner_campaign::campaign_flight::{FlightConditions, WindSource};
    let wind = match (&b.wind, &b.winds) {
        (Some(_), Some(_)) => {
            return Err(ApiError::bad_request(
                Some("winds"),
                "give either `wind` (a drawn wind) or `winds` (observed days), not both",
            ));
        }
        (_, Some(days)) => WindSource::Observed {
            path: PathBuf::from("winds"),
            days: observed_winds(days)?,
        },
        (Some(text), None) => {
            WindSource::parse(text).map_err(|e| ApiError::from(e).in_field("wind"))?
        }
        (None, None) => WindSource::Still,
    };
    let still = FlightConditions::default();
    let gust_sd_mps = b.gust.unwrap_or(wind.default_gust_sd_mps());
    let one = |field: &str, c: FlightConditions| {
        c.check(&[])
            .map_err(|e| ApiError::from(e).in_field(field))
            .map(|_| ())
    };
    one(
        "gust",
        FlightConditions {
            gust_sd_mps,
            ..still.clone()
        },
    )?;
    let leg_gust_sd_mps = b.leg_gust.unwrap_or(0.0);
    one(
        "leg_gust",
        FlightConditions {
            leg_gust_sd_mps,
            ..still.clone()
        },
    )?;
    let battery_weakening = b.weak_battery.unwrap_or(0.0);
    one(
        "weak_battery",
        FlightConditions {
            battery_weakening,
            ..still.clone()
        },
    )?;
    let margin_quantile = Some(
        b.margin_quantile
            .unwrap_or(gleaner_campaign::campaign_flight::DEFAULT_MARGIN_QUANTILE),
    );
    one(
        "margin_quantile",
        FlightConditions {
            margin_quantile,
            ..still
        },
    )?;
    Ok(FlightConditions {
        wind,
        gust_sd_mps,
        battery_weakening,
        seed: b.weather_seed.unwrap_or(1),
        leg_gust_sd_mps,
        margin_quantile,
    })
}

/// Most days of observed wind one simulation request may give.
const MAX_WIND_DAYS: usize = 36_600;

/// A simulation's observed daily winds, checked as `simulate --wind-csv` checks its file;
/// each refusal names the entry's field (`winds[3].speed_mps`).
fn observed_winds(
    days: &[WindDayBody],
) -> ApiResult<Vec<gleaner_campaign::campaign_flight::DailyWind>> {
    use gleaner_app::wind::MAX_WIND_MPS;
    if days.is_empty() || days.len() > MAX_WIND_DAYS {
        return Err(ApiError::bad_request(
            Some("winds"),
            format!(
                "expected 1 to {MAX_WIND_DAYS} days of wind, got {}",
                days.len()
            ),
        ));
    }
    let mut out = Vec::with_capacity(days.len());
    for (k, d) in days.iter().enumerate() {
        let field = |name: &str| format!("winds[{k}].{name}");
        let day = app::parse_timestamp(&d.date)
            .filter(|t| t.rem_euclid(86_400) == 0 && d.date.trim().len() == 10)
            .ok_or_else(|| {
                ApiError::bad_request(
                    Some(&field("date")),
                    format!("expected a date YYYY-MM-DD (UTC), got {:?}", d.date),
                )
            })?;
        let number = |x: f64, name: &str, hi: f64, unit: &str| {
            if x.is_finite() && (0.0..=hi).contains(&x) {
                Ok(x)
            } else {
                Err(ApiError::bad_request(
                    Some(&field(name)),
                    format!("expected a number in [0, {hi}] {unit}, got {x}"),
                ))
            }
        };
        let speed_mps = number(d.speed_mps, "speed_mps", MAX_WIND_MPS, "m/s")?;
        let from_deg = number(d.from_deg, "from_deg", 360.0, "degrees")?;
        out.push(gleaner_campaign::campaign_flight::DailyWind {
            day,
            speed_mps,
            from_deg: if from_deg == 360.0 { 0.0 } else { from_deg },
            line: k,
        });
    }
    out.sort_by_key(|d| (d.day, d.line));
    if let Some(w) = out.windows(2).find(|w| w[0].day == w[1].day) {
        return Err(ApiError::bad_request(
            Some(&format!("winds[{}].date", w[1].line)),
            format!(
                "{}: given twice (also winds[{}])",
                &app::format_rfc3339(w[1].day)[..10],
                w[0].line
            ),
        ));
    }
    Ok(out)
}
