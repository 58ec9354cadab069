//! Re-planning in the air: the best continuation of a planned mission from the stop the
//! aircraft is over, with the energy it has left.

use gleaner_energy::{FlightEnergyModel, flight_point, flight_position};
use gleaner_field::{CellIndex, LatLon};
use gleaner_mission::{Candidate, PlanOptions, Planner, replan as plan_continuation};
use gleaner_store::{MissionId, MissionRecord, MissionStatus, NewMission, StopRecord, Store};

use crate::plan::breakdown;
use gleaner_scoring::Project;
use gleaner_scoring::{AppError, Result};

/// What to re-plan.
#[derive(Debug, Clone, PartialEq)]
pub struct ReplanRequest {
    /// The mission in flight (stored, not yet recorded as flown).
    pub mission: MissionId,
    /// Stops already flown: the aircraft is over stop `after_stop` (1-based, in the
    /// mission's order), done collecting there; 0 = over the base, airborne.
    pub after_stop: usize,
    /// Energy left in the battery, J (as the autopilot reports it; the reserve is kept).
    pub energy_left_j: f64,
    /// Planner seed [default: the mission's].
    pub seed: Option<u64>,
    /// Iteration cap of the search [default: [`REPLAN_ITERATIONS`]].
    pub iterations: Option<u64>,
    /// Wall-clock limit, seconds [default: 1 s].
    pub time_limit_s: Option<f64>,
    /// The wind now (m/s, and the direction it blows from), to which `[flight]
    /// wind_margin_mps` is added [default: the wind the mission was planned in, as stored].
    pub wind: Option<gleaner_energy::Wind>,
    /// Added to `wind`'s speed, m/s (>= 0) [default: `[flight] wind_margin_mps`]; a
    /// simulated flight passes the margin of the gusts still to come. Ignored without `wind`.
    pub wind_margin_mps: Option<f64>,
}

/// A continuation: the stops kept, in their new order, from where the aircraft is.
#[derive(Debug, Clone, PartialEq)]
pub struct Replan {
    /// The mission it continues.
    pub parent: MissionId,
    /// Stops flown before it (see [`ReplanRequest::after_stop`]).
    pub after_stop: usize,
    /// Where the aircraft is: the flown stop's centre (the base for 0), WGS84.
    pub start: LatLon,
    /// Energy left, J, as given.
    pub energy_left_j: f64,
    /// The battery's reserve, J (capacity × reserve fraction), kept for landing.
    pub reserve_j: f64,
    /// The continuation as a mission: the kept stops (orders from 0, legs from `start`,
    /// the first stop's leg from the aircraft), its energy against `energy_left_j −
    /// reserve_j` (`energy.budget_j`), the parent's profile, kind, time and weights.
    pub mission: NewMission,
    /// The remaining stops dropped, in the parent's order.
    pub dropped: Vec<CellIndex>,
    /// The energy model the continuation's flight files are priced with.
    pub energy: FlightEnergyModel,
    /// Time spent planning, seconds.
    pub solve_seconds: f64,
    /// The continuation's wind: the legs' components and the strongest wind it stands.
    pub wind: crate::wind::RouteWind,
}

pub use gleaner_mission::{REPLAN_ITERATIONS, REPLAN_TIME_LIMIT_S};

/// The use case: the best continuation of mission `request.mission` after `after_stop`
/// stops with `energy_left_j` joules left — the remaining stops dropped and reordered so
/// the aircraft still reaches the base with the battery's reserve, priced by the energy model
/// exactly as its continuation files command it (no take-off or climb; a 0 s first waypoint
/// where the aircraft is). Writes nothing: the flight is recorded against the mission itself
/// (the continuation's stops are the mission's).
///
/// Errors: a project with a geofence or no-fly zones (the continuation's legs are straight
/// lines), an unknown mission, one already recorded as flown, `after_stop` beyond its stops,
/// an energy left that is not a finite positive number or exceeds the battery, not enough
/// energy for the leg home with the reserve (land now), invalid `[energy]` settings.
pub fn replan<S: Store>(project: &Project<S>, request: &ReplanRequest) -> Result<Replan> {
    let parent = replannable(project, request)?;
    let stops = &parent.mission.stops;
    let (left, reserve_j) = energy_left(project, request)?;
    // Priced by the very model the files' writers recompute with, at the mission's speed and
    // altitude (what its files command).
    let stored = crate::view::export_energy_model(project, &parent)?;
    let plan_wind = replan_wind(project, request, &stored)?;
    let export = gleaner_energy::FlightEnergyModel {
        wind: plan_wind.planned,
        ..stored
    };
    let mut profile = parent.mission.profile;
    profile.wind_mps = plan_wind.planned.speed_mps;
    profile.wind_from_deg = plan_wind.planned.from_deg;
    let profile = &profile;
    let model = export
        .model(profile.cruise_speed_mps, profile.altitude_m)
        .map_err(|e| AppError::core("energy model", e))?;
    let (_, field) = project.field()?;
    let frame = field.frame();
    let base = flight_point(frame, field.base());
    let start_pos = match request.after_stop {
        0 => flight_position(field.base()),
        k => stops[k - 1].centre,
    };
    let remaining: &[StopRecord] = &stops[request.after_stop..];
    // Exploration stops carry no score: each counts the same.
    let unscored = remaining.iter().all(|s| s.score <= 0.0);
    let candidates: Vec<Candidate> = remaining
        .iter()
        .map(|s| Candidate {
            centre: frame.forward(s.centre),
            score: if unscored { 1.0 } else { s.score },
            hover_s: s.hover_s,
        })
        .collect();
    let options = PlanOptions {
        planner: Planner::Default,
        seed: request.seed.unwrap_or(parent.mission.seed),
        max_iterations: Some(request.iterations.unwrap_or(REPLAN_ITERATIONS)),
        ..PlanOptions::default()
    }
    .with_time_limit_secs(request.time_limit_s.unwrap_or(REPLAN_TIME_LIMIT_S))
    .map_err(|e| AppError::Invalid(format!("time limit: {e}")))?;
    let budget_j = left - reserve_j;
    let start_local = frame.forward(start_pos);
    let plan = plan_continuation(&model, (start_local, base), &candidates, budget_j, &options)
        .map_err(|e| match e {
            gleaner_mission::PlanError::Infeasible { total_j, .. } => AppError::Invalid(format!(
                "{left:.1} J left with a {reserve_j:.1} J reserve leaves {budget_j:.1} J, but the \
             way home alone needs {total_j:.1} J: return to launch and land now"
            )),
            other => AppError::core("re-planning", other),
        })?;
    let (kept, dropped) = kept_and_dropped(&plan, remaining);
    let visits: Vec<gleaner_energy::CellVisit> = std::iter::once(gleaner_energy::CellVisit {
        centre: start_local,
        hover_s: 0.0,
    })
    .chain(plan.order.iter().map(|&k| gleaner_energy::CellVisit {
        centre: candidates[k].centre,
        hover_s: candidates[k].hover_s,
    }))
    .collect();
    let wind = crate::wind::RouteWind {
        wind: plan_wind,
        legs: plan.energy.legs.clone(),
        strongest: crate::wind::strongest_continuation(
            &model,
            (start_local, base),
            &visits,
            budget_j,
            (plan_wind.forecast.from_deg, plan_wind.planned.speed_mps),
        )?,
    };
    let mission = NewMission {
        solver: "replan".into(),
        seed: options.seed,
        total_score: kept.iter().map(|s| s.score).sum(),
        energy: breakdown(&plan.energy),
        return_distance_m: plan.energy.legs.last().map_or(0.0, |l| l.distance_m),
        stops: kept,
        profile: *profile,
        ..parent.mission.clone()
    };
    Ok(Replan {
        parent: parent.id,
        after_stop: request.after_stop,
        start: start_pos,
        energy_left_j: left,
        reserve_j,
        mission,
        dropped,
        energy: export,
        solve_seconds: plan.solve_seconds,
        wind,
    })
}

/// The mission to re-plan: planned (neither cancelled nor flown), in a project without
/// geofence or no-fly zones, with `after_stop` within its stops.
fn replannable<S: Store>(project: &Project<S>, request: &ReplanRequest) -> Result<MissionRecord> {
    let parent: MissionRecord = crate::view::mission(project, request.mission)?;
    crate::missions::refuse_cancelled(&parent, "re-planned")?;
    if parent.status == MissionStatus::Flown {
        return Err(AppError::Invalid(format!(
            "mission #{} was already recorded as flown: nothing to re-plan",
            parent.id
        )));
    }
    let field_settings = &project.settings().field;
    if field_settings.geofence.is_some() || field_settings.no_fly.is_some() {
        // The continuation's legs are straight: never hand over one that may cross a zone.
        return Err(AppError::Invalid(
            "re-planning in the air does not route around no-fly zones yet, and this project \
             sets [field] geofence or no_fly: fly the planned mission or return to launch"
                .into(),
        ));
    }
    let stops = &parent.mission.stops;
    if request.after_stop > stops.len() {
        return Err(AppError::Invalid(format!(
            "mission #{} has {} stops: --after-stop {} is beyond them (0 = over the base)",
            parent.id,
            stops.len(),
            request.after_stop
        )));
    }
    Ok(parent)
}

/// The energy left (J, checked: positive, at most the battery's capacity) and the battery's
/// reserve, J.
fn energy_left<S: Store>(project: &Project<S>, request: &ReplanRequest) -> Result<(f64, f64)> {
    let config = project.settings().energy.to_core()?;
    let (capacity_j, reserve_fraction) =
        (config.battery.capacity_j, config.battery.reserve_fraction);
    let left = request.energy_left_j;
    if !(left.is_finite() && left > 0.0 && left <= capacity_j) {
        return Err(AppError::Invalid(format!(
            "energy left {left} J: must be a positive number of joules, at most the battery's \
             {capacity_j:.1} J"
        )));
    }
    Ok((left, capacity_j * reserve_fraction))
}

/// The wind now, if given (plus the margin), else the one the mission was planned in.
fn replan_wind<S: Store>(
    project: &Project<S>,
    request: &ReplanRequest,
    stored: &FlightEnergyModel,
) -> Result<crate::wind::PlanWind> {
    Ok(match request.wind {
        Some(w) => {
            let mut flight = project.settings().flight;
            if let Some(m) = request.wind_margin_mps {
                flight.wind_margin_mps = m;
            }
            crate::wind::PlanWind::of(&flight, Some(w))?
        }
        None => crate::wind::PlanWind {
            forecast: stored.wind,
            margin_mps: 0.0,
            planned: stored.wind,
        },
    })
}

/// The continuation's stops, re-priced leg by leg, and the remaining cells it drops.
fn kept_and_dropped(
    plan: &gleaner_mission::MissionPlan,
    remaining: &[StopRecord],
) -> (Vec<StopRecord>, Vec<CellIndex>) {
    let kept: Vec<StopRecord> = plan
        .order
        .iter()
        .enumerate()
        .map(|(n, &k)| {
            let (leg, cell) = (&plan.energy.legs[n + 1], &plan.energy.cells[n + 1]);
            StopRecord {
                order: n as u32,
                leg_distance_m: leg.distance_m,
                leg_energy_j: leg.energy_j,
                hover_s: cell.hover_s,
                hover_j: cell.hover_j,
                comm_j: cell.comm_j,
                ..remaining[k].clone()
            }
        })
        .collect();
    let dropped: Vec<CellIndex> = (0..remaining.len())
        .filter(|k| !plan.order.contains(k))
        .map(|k| remaining[k].cell)
        .collect();
    (kept, dropped)
}
