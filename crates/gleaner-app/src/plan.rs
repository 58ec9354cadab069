//! Planning: scores (from the utility engine, or a file) + the energy model -> a route and the
//! mission of docs/method.md §6, stored with its stops and energy breakdown in one transaction.

use std::path::{Path, PathBuf};

use gleaner_energy::{
    CellService, MissionEnergy, MissionEnergyModel, flight_point, flight_position,
};
use gleaner_field::{LatLon, LocalPoint, UnixSeconds};
use gleaner_mission::{
    Candidate, Detours, MissionPlan, PlanOptions, Planner, plan_sorties_routed,
    plan_sorties_valued_routed,
};
use gleaner_store::{
    EnergyBreakdown, FlightProfile, MissionId, MissionKind, NewMission, StopRecord, Store,
    StoreWrite,
};

use gleaner_scoring::Project;
use gleaner_scoring::cell_csv;
use gleaner_scoring::{self as score, Objective, ScoreRequest, Scoring, parse_planner};
use gleaner_scoring::{AppError, Result};
use gleaner_scoring::{History, Knowledge, Settings};

/// What to plan.
#[derive(Debug, Clone, Default)]
pub struct PlanRequest {
    /// Mission time t, seconds [default: the latest known reading].
    pub at: Option<UnixSeconds>,
    /// Which stored readings count as collected.
    pub history: History,
    /// Per-cell scores from a CSV (`cell_id,score`) instead of the utility engine.
    pub scores: Option<PathBuf>,
    /// Per-cell scores in field order, given directly (a campaign strategy's own utility)
    /// instead of the utility engine; takes precedence over `scores`.
    pub cell_scores: Option<Vec<f64>>,
    /// Planner [default: the project's `[planner] solver`].
    pub planner: Option<Planner>,
    /// Planner time limit, seconds [default: the project's], in [0, 86400].
    pub time_limit_s: Option<f64>,
    /// Seed [default: the project's].
    pub seed: Option<u64>,
    /// Iteration cap, for results that do not depend on the machine's speed.
    pub max_iterations: Option<u64>,
    /// Plan only; write nothing.
    pub dry_run: bool,
    /// Sorties this mission day (battery swaps) [default 1], in 1..=MAX_SORTIES: disjoint
    /// routes from the base, each within the budget, planned together by the team orienteering
    /// solver; each is stored as its own mission.
    pub sorties: Option<usize>,
    /// What the route maximises [default: the project's `[planner] objective`].
    pub objective: Option<Objective>,
    /// The forecast wind (m/s, and the direction it blows from) [default: the project's
    /// `[flight] wind_mps` and `wind_from_deg`]; `[flight] wind_margin_mps` is added to it.
    pub wind: Option<gleaner_energy::Wind>,
}

/// Most sorties one `plan` may ask for.
pub const MAX_SORTIES: usize = 20;

/// A sortie after the first, when several are planned.
#[derive(Debug, Clone)]
pub struct ExtraSortie {
    /// Its id, unless a dry run.
    pub id: Option<MissionId>,
    /// The sortie as stored.
    pub mission: NewMission,
    /// The turn points of its legs around no-fly zones (see [`PlannedMission::via`]).
    pub via: Vec<Vec<LatLon>>,
    /// Its legs' wind and the strongest wind it stands (see [`PlannedMission::wind`]).
    pub wind: crate::wind::RouteWind,
}

/// The headline numbers of a comparison plan.
#[derive(Debug, Clone, PartialEq)]
pub struct Baseline {
    /// Planner.
    pub planner: Planner,
    /// Cells visited.
    pub cells: usize,
    /// Sum of S.
    pub total_score: f64,
    /// Energy, J.
    pub energy_j: f64,
}

/// A planned mission.
pub struct PlannedMission {
    /// Its id, unless a dry run.
    pub id: Option<MissionId>,
    /// The mission as stored (stops, energy breakdown, flight profile).
    pub mission: NewMission,
    /// The scoring behind it (absent when scores came from a file).
    pub scoring: Option<Scoring>,
    /// Cells with S > 0 the planner chose from.
    pub candidates: usize,
    /// The paper's greedy heuristic on the same instance.
    pub greedy: Baseline,
    /// Planner seed and time limit used.
    pub seed: u64,
    /// Time limit, seconds.
    pub time_limit_s: f64,
    /// Sorties 2..=K when several were asked for (`mission` is sortie 1); empty otherwise.
    pub extra_sorties: Vec<ExtraSortie>,
    /// The turn points of each leg around the no-fly zones, WGS84 on the files' 1e-7° grid:
    /// one list per stop (the leg arriving there) and one for the return leg; empty lists
    /// for straight legs, no lists without zones.
    pub via: Vec<Vec<LatLon>>,
    /// Cells the flight cannot reach (a centre inside a buffered no-fly zone, outside the
    /// geofence, or cut off from the base): never planned.
    pub unreachable: Vec<crate::airspace::Unreachable>,
    /// The wind it was planned in (forecast, margin, the wind its legs are priced in), each
    /// leg's head-, tail- and cross-wind, and the strongest wind from the forecast's
    /// direction at which it stays within the budget.
    pub wind: crate::wind::RouteWind,
}

/// Largest magnitude of a user-given score (the utility engine's scores are a few units).
pub const MAX_SCORE: f64 = 1e6;

fn read_scores(path: &Path, k: &Knowledge) -> Result<Vec<f64>> {
    let labels = k.cell_labels();
    let mut scores: Vec<Option<f64>> = vec![None; labels.len()];
    for row in cell_csv::read(path)? {
        let at = |what: &str| AppError::Invalid(format!("{}:{}: {what}", path.display(), row.line));
        let [score] = row.values[..] else {
            return Err(at("expected `cell_id,score`"));
        };
        if score.abs() > MAX_SCORE {
            return Err(at(&format!(
                "column `score`: {} outside the allowed -{MAX_SCORE}..={MAX_SCORE}",
                gleaner_ingest::number(score)
            )));
        }
        let pos = labels.iter().position(|l| *l == row.cell).ok_or_else(|| {
            at(&format!(
                "column `cell_id`: unknown cell: {:?}",
                gleaner_ingest::shorten(&row.cell)
            ))
        })?;
        if scores[pos].replace(score).is_some() {
            return Err(at(&format!(
                "column `cell_id`: cell {:?} listed twice",
                row.cell
            )));
        }
    }
    // Cells the file leaves out score 0: never worth a detour.
    Ok(scores.into_iter().map(|s| s.unwrap_or(0.0)).collect())
}

/// Scores given instead of the utility engine's.
enum Given<'a> {
    File(&'a PathBuf),
    Values(&'a Vec<f64>),
}

/// The energy model of the project's `[energy]` settings, flying the speed and altitude the
/// flight files command (the cruise speed rounded to `gleaner_energy::SPEED_STEP_MPS`, the
/// altitude to `ALTITUDE_STEP_M`): every plan prices the values the files will carry.
pub fn energy_model<S: Store>(project: &Project<S>) -> Result<MissionEnergyModel> {
    flight_model(&project.settings().energy, "[energy] settings")
}

/// The flight-file model (see [`energy_model`]) of an `[energy]` section.
pub(crate) fn flight_model(
    energy: &gleaner_scoring::settings::EnergySection,
    context: &'static str,
) -> Result<MissionEnergyModel> {
    let mut config = energy.to_core()?;
    // The altitude the files command (rounded to 0.25 m): the climb and descent are priced there.
    config.link.altitude_m = gleaner_energy::flight_altitude_m(config.link.altitude_m);
    MissionEnergyModel::new(&config)
        .and_then(|m| m.for_flight())
        .map_err(|e| AppError::core(context, e))
}

/// Where the flight files put the base and each cell's centre: the positions rounded to the
/// files' 1e-7 degrees (`gleaner_energy::flight_position`), WGS84, and the same points in
/// the field's local frame (m), which the planner prices.
pub(crate) struct FlightPoints {
    /// The base (home) in the local frame, m.
    pub base: LocalPoint,
    /// Each cell's rounded centre, WGS84, in field order.
    pub positions: Vec<LatLon>,
    /// Each cell's rounded centre in the local frame, m, in field order.
    pub centres: Vec<LocalPoint>,
}

impl FlightPoints {
    /// The rounded base and cell centres of `field`.
    pub(crate) fn of(field: &gleaner_field::Field) -> Self {
        let frame = field.frame();
        let positions: Vec<LatLon> = field
            .cells()
            .iter()
            .map(|c| flight_position(frame.inverse(c.centre)))
            .collect();
        Self {
            base: flight_point(frame, field.base()),
            centres: positions.iter().map(|&p| frame.forward(p)).collect(),
            positions,
        }
    }
}

/// How the aircraft flies missions of this project: base, altitudes, cruise speed.
pub fn flight_profile<S: Store>(
    project: &Project<S>,
    model: &MissionEnergyModel,
) -> Result<FlightProfile> {
    Ok(FlightProfile {
        base: project.settings().base()?,
        base_alt_m: project.settings().field.base_alt_m,
        altitude_m: model.link().altitude_m,
        cruise_speed_mps: model.cruise_speed_mps(),
        wind_mps: model.wind().speed_mps,
        wind_from_deg: model.wind().from_deg,
    })
}

/// Per-cell collection service at time `t` from the sensors' backlog: the data logged since
/// each sensor's last collection, or since its first reading.
pub(crate) fn services(
    model: &MissionEnergyModel,
    k: &Knowledge,
    t: UnixSeconds,
) -> Result<Vec<CellService>> {
    let elapsed: Vec<f64> = (0..k.sensors.len())
        .map(|s| {
            let since = k.last_collected[s]
                .or(k.first_reading[s])
                .unwrap_or(t - 86_400);
            (t - since).max(0) as f64
        })
        .collect();
    let services = model
        .field_services(&k.field, &elapsed)
        .map_err(|e| AppError::core("collection times", e))?;
    // Hover for the hold the files command (rounded up): the planner prices that. A stop holds
    // at least one hold step, so a file tells its stops from a detour's turn points (0 s).
    Ok(services
        .into_iter()
        .map(|s| {
            let s = model.flight_service(s);
            if s.hover_s < gleaner_energy::HOLD_STEP_S {
                model.flight_service(CellService {
                    hover_s: gleaner_energy::HOLD_STEP_S,
                    ..s
                })
            } else {
                s
            }
        })
        .collect())
}

/// The stops of a route with the energy model's breakdown; each stop's centre is where the
/// files put it (`points.positions`).
pub(crate) fn stops(
    k: &Knowledge,
    points: &FlightPoints,
    order: &[usize],
    energy: &MissionEnergy,
    services: &[CellService],
    scores: &[f64],
    terms: Option<&[gleaner_utility::CellTerms]>,
) -> Vec<StopRecord> {
    order
        .iter()
        .enumerate()
        .map(|(n, &c)| {
            let cell = &k.field.cells()[c];
            StopRecord {
                order: n as u32,
                cell: cell.index,
                centre: points.positions[c],
                score: scores.get(c).copied().unwrap_or(0.0),
                terms: terms.map(|t| [t[c].f, t[c].r, t[c].a, t[c].u]),
                leg_distance_m: energy.legs[n].distance_m,
                leg_energy_j: energy.legs[n].energy_j,
                collection_s: services[c].collection_s,
                hover_s: energy.cells[n].hover_s,
                hover_j: energy.cells[n].hover_j,
                comm_j: energy.cells[n].comm_j,
            }
        })
        .collect()
}

/// The project's airspace over `points`: the legs around the zones (base first, then every
/// cell in field order) and the cells they leave unreachable; `None` without zones.
pub(crate) fn routing<S: Store>(
    project: &Project<S>,
    k: &Knowledge,
    points: &FlightPoints,
) -> Result<
    Option<(
        crate::airspace::ProjectAirspace,
        Detours,
        Vec<crate::airspace::Unreachable>,
    )>,
> {
    let Some(airspace) = crate::airspace::of_project(project)? else {
        return Ok(None);
    };
    let mut nodes = Vec::with_capacity(points.centres.len() + 1);
    nodes.push(points.base);
    nodes.extend_from_slice(&points.centres);
    let detours = airspace.detours(&nodes);
    let unreachable = crate::airspace::unreachable_cells(
        &airspace,
        &k.cell_labels(),
        points.base,
        &points.centres,
        &detours,
    )?;
    Ok(Some((airspace, detours, unreachable)))
}

/// The turn points of a plan's legs as WGS84 positions on the files' grid.
pub(crate) fn via_positions(
    frame: &gleaner_field::TransverseMercator,
    via: &[Vec<LocalPoint>],
) -> Vec<Vec<LatLon>> {
    via.iter()
        .map(|leg| {
            leg.iter()
                .map(|&p| flight_position(frame.inverse(p)))
                .collect()
        })
        .collect()
}

/// The store's energy breakdown of a route.
pub(crate) fn breakdown(e: &MissionEnergy) -> EnergyBreakdown {
    EnergyBreakdown {
        travel_j: e.travel_j,
        hover_j: e.hover_j,
        comm_j: e.comm_j,
        return_j: e.return_j,
        total_j: e.total_j,
        budget_j: e.budget_j,
        distance_m: e.distance_m,
        flight_time_s: e.flight_time_s,
    }
}

/// The use case: scores the cells (or reads scores), plans the route, and unless a dry run
/// stores the scoring, each cell's expected collection energy, and the
/// mission with its stops — one transaction. The planned route is re-checked by the energy
/// model; a route the budget cannot carry is never returned. `clock_now` (seconds) is
/// recorded as the mission's creation time.
pub fn plan<S: Store>(
    project: &mut Project<S>,
    request: &PlanRequest,
    clock_now: UnixSeconds,
) -> Result<PlannedMission> {
    plan_with_preset(project, request, None, clock_now)
}

/// [`plan`] with the battery budget of another energy preset (`paper`, `large-pack`) in
/// place of `[energy] preset`; fields set in `[energy]` still override the preset's values.
/// `None` is [`plan`].
pub fn plan_with_preset<S: Store>(
    project: &mut Project<S>,
    request: &PlanRequest,
    energy_preset: Option<&str>,
    clock_now: UnixSeconds,
) -> Result<PlannedMission> {
    let run = |project: &mut Project<S>| {
        plan_scored(
            project,
            request,
            energy_preset,
            (None, None),
            true,
            clock_now,
        )
    };
    // A stored plan is computed from the store as it is when it is written: nothing is
    // recorded or planned by another process between its scoring and its write.
    match request.dry_run {
        true => run(project),
        false => project.exclusive(run),
    }
}

/// [`plan_with_preset`] with the utility engine's scoring already computed: `scoring` must be
/// what [`score::compute`] returns for this project's store as it is now, at `request.at`,
/// with `request.history` and no user probabilities (a campaign's pre-flight scoring of the
/// same mission), so planning with it equals planning without it; refused when its time is not
/// `request.at`. Ignored when the request gives its own scores.
///
/// A sortie that visits no cell is never stored: sorties 2..=K the day does not need are
/// left out of the result, and a plan in which no sortie visits a cell (every S <= 0, or no
/// cell within the battery's reach) is refused unless a dry run — or, with `!refuse_empty`
/// (a campaign's mission day), stores only the scoring and returns the empty mission
/// without an id.
pub fn plan_scored<S: Store>(
    project: &mut Project<S>,
    request: &PlanRequest,
    energy_preset: Option<&str>,
    (scored, dynamic): (Option<Scoring>, Option<&gleaner_kriging::DynamicModel>),
    refuse_empty: bool,
    clock_now: UnixSeconds,
) -> Result<PlannedMission> {
    gleaner_scoring::when::check("mission time", request.at)?;
    if let Some(s) = &scored
        && request.at.is_some_and(|at| at != s.t)
    {
        return Err(AppError::Invalid(format!(
            "a scoring at {} given to plan a mission at {:?}",
            s.t, request.at
        )));
    }
    let settings = project.settings().clone();
    let (planner, time_limit_s, seed) = planner_choice(&settings, request)?;
    let prizes = cell_prizes(project, request, scored, &settings)?;
    let (t, scores) = (prizes.t, &prizes.scores);
    let k = prizes.knowledge()?;
    let (model, plan_wind) = planning_model(project, energy_preset, request.wind)?;
    let profile = flight_profile(project, &model)?;
    let services = services(&model, k, t)?;
    let points = FlightPoints::of(&k.field);
    let routed = routing(project, k, &points)?;
    let detours = routed.as_ref().map(|(_, d, _)| d);
    let unreachable = routed.as_ref().map(|r| r.2.clone()).unwrap_or_default();
    let mut fitted = None;
    let objective = request.objective.unwrap_or(settings.planner.objective);
    let information = information_objective(
        project,
        request,
        (k, t, scores),
        objective,
        (dynamic, &mut fitted),
    )?;
    let anomaly_form = match (&information, objective) {
        (Some(_), Objective::Hybrid) => format!(
            "{}; routed by score and information (dynamic field model, weight {})",
            prizes.anomaly_form, settings.planner.information_weight
        ),
        (Some(_), _) => format!(
            "{}; routed by information (dynamic field model)",
            prizes.anomaly_form
        ),
        (None, _) => prizes.anomaly_form.clone(),
    };
    let singletons: Vec<f64> = match &information {
        Some(info) => info.singletons(),
        None => scores.clone(),
    };
    let candidates = candidates(&points, &singletons, &services);
    let options = PlanOptions {
        planner,
        seed,
        max_iterations: request.max_iterations,
        ..PlanOptions::default()
    }
    .with_time_limit_secs(time_limit_s)
    .map_err(|e| AppError::core("planner", e))?;
    let base = points.base;
    let sorties = request.sorties.unwrap_or(1);
    if !(1..=MAX_SORTIES).contains(&sorties) {
        return Err(AppError::Invalid(format!(
            "sorties = {sorties}: allowed 1..={MAX_SORTIES}"
        )));
    }
    let routes = Routes {
        model: &model,
        base,
        candidates: &candidates,
        detours,
    };
    let (mut plans, empty) = routes.sorties(&options, sorties, information.as_ref())?;
    let refuse = refuse_empty && !request.dry_run;
    let plan = first_sortie(&mut plans, empty, refuse, k.field.cells().len())?;
    let greedy = routes.greedy(&options)?;
    check_feasible(&plan)?;
    for p in &plans {
        check_feasible(p)?;
    }
    let parts = MissionParts {
        created_at: clock_now,
        planned_at: t,
        solver: planner.name(),
        seed,
        weights: prizes.weights,
        anomaly_form,
        profile,
        knowledge: k,
        points: &points,
        services: &services,
        scores,
        terms: prizes.scoring.as_ref().map(|s| s.terms.as_slice()),
    };
    let mission = parts.mission(&plan);
    let frame = &k.field.frame().clone();
    let first_via = via_positions(frame, &plan.via);
    let extra_sorties: Vec<ExtraSortie> = plans
        .iter()
        .map(|p| {
            Ok(ExtraSortie {
                id: None,
                mission: parts.mission(p),
                via: via_positions(frame, &p.via),
                wind: routes.wind(&plan_wind, p)?,
            })
        })
        .collect::<Result<_>>()?;
    let wind = routes.wind(&plan_wind, &plan)?;
    let Prizes {
        file_knowledge,
        scoring,
        ..
    } = prizes;
    let mut planned = PlannedMission {
        id: None,
        mission,
        scoring,
        candidates: plan.considered,
        greedy: Baseline {
            planner: Planner::Greedy,
            cells: greedy.order.len(),
            total_score: greedy.total_score,
            energy_j: greedy.energy.total_j,
        },
        seed,
        time_limit_s,
        extra_sorties,
        via: first_via,
        unreachable,
        wind,
    };
    if !request.dry_run {
        store_planned(project, &mut planned, &services, file_knowledge.as_ref())?;
    }
    Ok(planned)
}

/// The plan's first sortie, taken out of `plans` (the sorties that visit a cell); without
/// one, the first of `empty` unless `refuse` (a stored plan), which then refuses the plan.
fn first_sortie(
    plans: &mut Vec<MissionPlan>,
    empty: Vec<MissionPlan>,
    refuse: bool,
    cells: usize,
) -> Result<MissionPlan> {
    if !plans.is_empty() {
        return Ok(plans.remove(0));
    }
    if refuse {
        return Err(AppError::Invalid(format!(
            "no cell to visit: of {cells} cells none scores S > 0 within the battery's reach; \
             nothing was stored (a dry run shows the empty plan)"
        )));
    }
    empty
        .into_iter()
        .next()
        .ok_or_else(|| AppError::Invalid("the planner returned no sortie".into()))
}

/// The energy model a plan prices its routes with (the project's, or `energy_preset`'s with
/// the project's `[energy]` fields over it), legs and hovers in the forecast wind plus the
/// margin (still air: the model as it was, to the bit); and that wind.
fn planning_model<S: Store>(
    project: &Project<S>,
    energy_preset: Option<&str>,
    wind: Option<gleaner_energy::Wind>,
) -> Result<(MissionEnergyModel, crate::wind::PlanWind)> {
    let settings = project.settings();
    let model = match energy_preset {
        None => energy_model(project)?,
        Some(preset) => {
            let mut energy = settings.energy.clone();
            energy.preset = preset.to_string();
            flight_model(&energy, "energy preset")?
        }
    };
    let plan_wind = crate::wind::PlanWind::of(&settings.flight, wind)?;
    Ok((model.with_wind_up_to(plan_wind.planned), plan_wind))
}

/// The cells as the planner's candidates: each rounded centre (m) with its prize and hover
/// time (s).
fn candidates(points: &FlightPoints, prizes: &[f64], services: &[CellService]) -> Vec<Candidate> {
    points
        .centres
        .iter()
        .zip(prizes)
        .zip(services)
        .map(|((&centre, &score), svc)| Candidate {
            centre,
            score,
            hover_s: svc.hover_s,
        })
        .collect()
}

/// The planner, its time limit (s, in [0, 86400]) and its seed: the request's, else the
/// project's `[planner]`.
fn planner_choice(settings: &Settings, request: &PlanRequest) -> Result<(Planner, f64, u64)> {
    let planner = match request.planner {
        Some(p) => p,
        None => parse_planner(&settings.planner.solver)?,
    };
    let time_limit_s = request
        .time_limit_s
        .unwrap_or(settings.planner.time_limit_s);
    if !(time_limit_s.is_finite() && (0.0..=86_400.0).contains(&time_limit_s)) {
        return Err(AppError::Invalid(format!(
            "time limit {} s: expected a number of seconds in [0, 86400]",
            gleaner_ingest::number(time_limit_s)
        )));
    }
    let seed = request.seed.unwrap_or(settings.planner.seed);
    Ok((planner, time_limit_s, seed))
}

/// Each cell's worth to the planner at the mission time: given scores (a file, or values)
/// or the utility engine's S (+ η·V).
struct Prizes {
    /// What is known at t, when the scores were given (else it is the scoring's).
    file_knowledge: Option<Knowledge>,
    /// The utility engine's scoring, when it scored.
    scoring: Option<Scoring>,
    /// Per cell, in field order.
    scores: Vec<f64>,
    /// The mission time t.
    t: UnixSeconds,
    /// The anomaly term's form (or where the scores came from), as stored with the mission.
    anomaly_form: String,
    /// The weights of S (zeros for given scores).
    weights: [f64; 4],
}

impl Prizes {
    /// What is known at the mission time.
    fn knowledge(&self) -> Result<&Knowledge> {
        self.scoring
            .as_ref()
            .map(|s| &s.knowledge)
            .or(self.file_knowledge.as_ref())
            .ok_or_else(|| AppError::Invalid("nothing known at the mission time".into()))
    }
}

/// The request's scores, or the utility engine's (`scored` when the caller computed them).
fn cell_prizes<S: Store>(
    project: &Project<S>,
    request: &PlanRequest,
    scored: Option<Scoring>,
    settings: &Settings,
) -> Result<Prizes> {
    let given = match (&request.cell_scores, &request.scores) {
        (Some(v), _) => Some(Given::Values(v)),
        (None, Some(p)) => Some(Given::File(p)),
        (None, None) => None,
    };
    if let Some(given) = given {
        let k = gleaner_scoring::state::collection_knowledge(project, request.at, request.history)?;
        let t = gleaner_scoring::when::mission_time(request.at, k.latest)?;
        let (scores, form) = match given {
            Given::File(path) => (read_scores(path, &k)?, "n/a (scores from file)"),
            Given::Values(v) => {
                if v.len() != k.field.cells().len() {
                    return Err(AppError::Invalid(format!(
                        "{} cell scores given for {} cells",
                        v.len(),
                        k.field.cells().len()
                    )));
                }
                (v.clone(), "n/a (scores given)")
            }
        };
        return Ok(Prizes {
            file_knowledge: Some(k),
            scoring: None,
            scores,
            t,
            anomaly_form: form.to_string(),
            weights: [0.0; 4],
        });
    }
    let mut scoring = match scored {
        Some(scoring) => scoring,
        None => score::compute(
            project,
            &ScoreRequest {
                at: request.at,
                history: request.history,
                probabilities: None,
                dry_run: true,
            },
        )?,
    };
    let mut scores: Vec<f64> = scoring.terms.iter().map(|c| c.s).collect();
    let mut form = scoring.anomaly_form.clone();
    let eta = settings.utility.variance_weight;
    if eta > 0.0 {
        // gleaner's variance-reduction term: the planner routes by S + η·V.
        match gleaner_scoring::variance_gains(project, &scoring.knowledge, scoring.t)? {
            Ok(v) => {
                for (s, v) in scores.iter_mut().zip(&v) {
                    *s += eta * v;
                }
                form = format!("{form}; S + {eta}·V (variance reduction)");
            }
            Err(why) => scoring.warnings.push(why),
        }
    }
    Ok(Prizes {
        file_knowledge: None,
        t: scoring.t,
        weights: scoring.weights,
        scoring: Some(scoring),
        scores,
        anomaly_form: form,
    })
}

/// The information objective (`information`, `hybrid`): the dynamic field model's filter at
/// t over what is known, the model fitted on it (into `fitted`) unless the caller (a
/// campaign) hands its own; `None` when the route maximises the score.
fn information_objective<'m, S: Store>(
    project: &Project<S>,
    request: &PlanRequest,
    (k, t, scores): (&Knowledge, UnixSeconds, &[f64]),
    objective: Objective,
    (dynamic, fitted): (
        Option<&'m gleaner_kriging::DynamicModel>,
        &'m mut Option<gleaner_kriging::DynamicModel>,
    ),
) -> Result<Option<gleaner_scoring::CellInformation<'m>>> {
    if matches!(objective, Objective::Score) {
        return Ok(None);
    }
    let settings = project.settings();
    let name = score::condition_modality(settings, &k.modalities).ok_or_else(|| {
        AppError::Invalid(
            "the information objective needs a soil-moisture modality; plan by score".into(),
        )
    })?;
    let modality = gleaner_field::Modality::new(&name)
        .map_err(|e| AppError::Invalid(format!("modality {name:?}: {e}")))?;
    let model: &'m gleaner_kriging::DynamicModel = match dynamic {
        Some(m) => m,
        None => {
            let known = t.min(request.history.until);
            let model = gleaner_scoring::fit_dynamic_model(project, &modality, known, None)?
                .ok_or_else(|| gleaner_scoring::unfit_dynamic(&modality, "plan by score"))?;
            fitted.insert(model)
        }
    };
    let info =
        gleaner_scoring::CellInformation::at(project, k, request.history, &modality, model, t)?;
    Ok(Some(match objective {
        Objective::Hybrid => info.blended(scores, settings.planner.information_weight),
        _ => info,
    }))
}

/// The routes of one plan: the energy model, the base, the candidate cells and the detours
/// around no-fly zones.
struct Routes<'a> {
    model: &'a MissionEnergyModel,
    base: LocalPoint,
    candidates: &'a [Candidate],
    detours: Option<&'a Detours>,
}

impl Routes<'_> {
    /// The day's sorties by the score or by `information`, split into those that visit a
    /// cell and those that do not.
    fn sorties(
        &self,
        options: &PlanOptions,
        sorties: usize,
        information: Option<&gleaner_scoring::CellInformation>,
    ) -> Result<(Vec<MissionPlan>, Vec<MissionPlan>)> {
        let (model, base, candidates, detours) =
            (self.model, self.base, self.candidates, self.detours);
        let planned = match information {
            None => plan_sorties_routed(model, base, candidates, options, sorties, detours),
            Some(info) => plan_sorties_valued_routed(
                model,
                base,
                candidates,
                |cells| info.value(cells),
                options,
                sorties,
                detours,
            )
            .map(|mut plans| {
                // Each sortie's worth is what it adds to the ones before it.
                let mut before: Vec<usize> = Vec::new();
                for p in &mut plans {
                    let v0 = info.value(&before);
                    before.extend(&p.order);
                    p.total_score = info.value(&before) - v0;
                }
                plans
            }),
        };
        Ok(planned
            .map_err(|e| AppError::core("planner", e))?
            .into_iter()
            .partition(|p| !p.order.is_empty()))
    }

    /// The paper's greedy route over the same candidates (the baseline a plan is shown
    /// against).
    fn greedy(&self, options: &PlanOptions) -> Result<MissionPlan> {
        Ok(plan_sorties_routed(
            self.model,
            self.base,
            self.candidates,
            &PlanOptions {
                planner: Planner::Greedy,
                ..*options
            },
            1,
            self.detours,
        )
        .map_err(|e| AppError::core("planner", e))?
        .remove(0))
    }

    /// A route's wind: the plan's, each leg's, and the strongest it stands.
    fn wind(
        &self,
        plan_wind: &crate::wind::PlanWind,
        plan: &MissionPlan,
    ) -> Result<crate::wind::RouteWind> {
        let visits: Vec<gleaner_energy::CellVisit> = plan
            .order
            .iter()
            .map(|&k| gleaner_energy::CellVisit {
                centre: self.candidates[k].centre,
                hover_s: self.candidates[k].hover_s,
            })
            .collect();
        let strongest = if visits.is_empty() {
            None
        } else {
            crate::wind::strongest(
                self.model,
                self.base,
                &visits,
                &plan.via,
                (plan_wind.forecast.from_deg, plan_wind.planned.speed_mps),
            )?
        };
        Ok(crate::wind::RouteWind {
            wind: *plan_wind,
            legs: plan.energy.legs.clone(),
            strongest,
        })
    }
}

/// What every sortie of one plan shares, to make each its mission.
struct MissionParts<'a> {
    created_at: UnixSeconds,
    planned_at: UnixSeconds,
    solver: &'static str,
    seed: u64,
    weights: [f64; 4],
    anomaly_form: String,
    profile: FlightProfile,
    knowledge: &'a Knowledge,
    points: &'a FlightPoints,
    services: &'a [CellService],
    scores: &'a [f64],
    terms: Option<&'a [gleaner_utility::CellTerms]>,
}

impl MissionParts<'_> {
    /// The mission of one sortie's route.
    fn mission(&self, plan: &MissionPlan) -> NewMission {
        NewMission {
            created_at: self.created_at,
            kind: MissionKind::Adaptive,
            planned_at: self.planned_at,
            solver: self.solver.to_string(),
            seed: self.seed,
            weights: self.weights,
            anomaly_form: self.anomaly_form.clone(),
            total_score: plan.total_score,
            profile: self.profile,
            energy: breakdown(&plan.energy),
            return_distance_m: if plan.order.is_empty() {
                0.0
            } else {
                plan.energy.legs.last().map_or(0.0, |l| l.distance_m)
            },
            stops: stops(
                self.knowledge,
                self.points,
                &plan.order,
                &plan.energy,
                self.services,
                self.scores,
                self.terms,
            ),
        }
    }
}

/// Stores the plan's scoring and every sortie with stops in one transaction: all stored or
/// none; sets their ids.
fn store_planned<S: Store>(
    project: &mut Project<S>,
    planned: &mut PlannedMission,
    services: &[CellService],
    file_knowledge: Option<&Knowledge>,
) -> Result<()> {
    let known = planned
        .scoring
        .as_ref()
        .map(|s| &s.knowledge)
        .or(file_knowledge)
        .ok_or_else(|| AppError::Invalid("nothing known at the mission time".into()))?;
    project.check_stored_grid(&known.field)?;
    let rows = match &planned.scoring {
        Some(s) => {
            let energy: Vec<f64> = services.iter().map(|svc| svc.energy_j).collect();
            score::metadata_rows(project, s, Some(&energy))
        }
        None => Vec::new(),
    };
    let mission = &planned.mission;
    let extra = &planned.extra_sorties;
    let (id, extra_ids) = project.store_mut().write(|tx| {
        if !rows.is_empty() {
            score::write_scoring(tx, rows)?;
        }
        let id = if mission.stops.is_empty() {
            None
        } else {
            Some(tx.create_mission(mission)?)
        };
        let mut extra_ids = Vec::with_capacity(extra.len());
        for e in extra {
            extra_ids.push(tx.create_mission(&e.mission)?);
        }
        Ok::<_, AppError>((id, extra_ids))
    })?;
    planned.id = id;
    for (e, id) in planned.extra_sorties.iter_mut().zip(extra_ids) {
        e.id = Some(id);
    }
    Ok(())
}

/// Refuses a route the energy model says the budget cannot carry.
fn check_feasible(plan: &MissionPlan) -> Result<()> {
    let e = &plan.energy;
    if !(e.feasible && e.total_j <= e.budget_j && e.total_j.is_finite()) {
        return Err(AppError::Core {
            context: "planner",
            message: format!(
                "the route needs {:.1} J but only {:.1} J are usable; refusing it",
                e.total_j, e.budget_j
            ),
        });
    }
    Ok(())
}
