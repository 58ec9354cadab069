//! Exploration (docs/method.md §5 step 3): as few sorties as possible, each within the battery, that
//! together visit every cell; each sortie is a mission like any other, with typed stops and
//! its energy breakdown, all stored in one transaction.

use gleaner_energy::CellVisit;
use gleaner_energy::MissionEnergyModel;
use gleaner_field::LatLon;
use gleaner_field::{LocalPoint, UnixSeconds};
use gleaner_mission::Detours;
use gleaner_mission::exploration::{
    ExplorationError, ExplorationOptions, ExplorationPlan, plan_exploration,
    plan_exploration_routed,
};
use gleaner_store::{MissionId, MissionKind, NewMission, Store, StoreWrite};

use crate::plan::{
    FlightPoints, breakdown, energy_model, flight_profile, routing, services, stops, via_positions,
};
use gleaner_scoring::History;
use gleaner_scoring::Project;
use gleaner_scoring::{AppError, Result};

/// What to explore.
#[derive(Debug, Clone, Default)]
pub struct ExploreRequest {
    /// Planning time, seconds [default: the latest reading; refused without either].
    pub at: Option<UnixSeconds>,
    /// Plan only; write nothing.
    pub dry_run: bool,
    /// The forecast wind (m/s, and the direction it blows from) [default: the project's
    /// `[flight] wind_mps` and `wind_from_deg`]; `[flight] wind_margin_mps` is added to it,
    /// as for `plan`.
    pub wind: Option<gleaner_energy::Wind>,
}

/// The exploration plan.
#[derive(Debug, Clone)]
pub struct Exploration {
    /// Planned for, seconds since the Unix epoch.
    pub planned_at: UnixSeconds,
    /// Cells to visit.
    pub cells: usize,
    /// Usable budget per sortie, J.
    pub budget_j: f64,
    /// A lower bound on the number of sorties any plan needs.
    pub lower_bound_sorties: usize,
    /// Total energy over all sorties, J.
    pub total_energy_j: f64,
    /// The sorties as missions, with their ids unless a dry run.
    pub sorties: Vec<(Option<MissionId>, NewMission)>,
    /// Per sortie, the turn points of its legs around no-fly zones (WGS84, the files' grid;
    /// one list per stop and one for the return leg; none without zones).
    pub via: Vec<Vec<Vec<LatLon>>>,
    /// Cells the flight cannot reach (inside a buffered no-fly zone, outside the geofence, or
    /// cut off): left out of the sorties.
    pub unreachable: Vec<crate::airspace::Unreachable>,
    /// The wind the sorties were planned in (forecast, margin, the wind the legs are priced
    /// in).
    pub wind: crate::wind::PlanWind,
}

/// Budget margins an exploration in wind tries, in order, until every sortie passes the
/// energy model's re-check in the wind: `k/8` of the margin that always suffices (see
/// [`exploration_margins`]), k = 0..=8.
const WIND_MARGIN_STEPS: usize = 8;

/// The relative budget margins (in [0, 1)) the exploration planner is given, in order. The
/// planner prices legs by their length at the still-air energy per metre; in wind a metre
/// costs at most `r` times that (r = [`MissionEnergyModel::worst_energy_per_metre_j`] over
/// the still-air figure), so a margin of 1 − 1/r always gives sorties within the budget in
/// the wind. Tried from the smallest. Still air: the default margin alone.
fn exploration_margins(model: &MissionEnergyModel) -> Vec<f64> {
    let default = ExplorationOptions::default().budget_margin;
    if !model.wind_applies() {
        return vec![default];
    }
    let r = model.worst_energy_per_metre_j() / model.energy_per_metre_j();
    let sufficient = (1.0 - 1.0 / r).clamp(0.0, 0.99);
    (0..=WIND_MARGIN_STEPS)
        .map(|k| (sufficient * k as f64 / WIND_MARGIN_STEPS as f64).max(default))
        .collect()
}

/// The use case: plans the exploration sorties and, unless a dry run, stores them as
/// exploration missions in one transaction. Every sortie is re-checked by the energy model.
pub fn explore<S: Store>(
    project: &mut Project<S>,
    request: &ExploreRequest,
    clock_now: UnixSeconds,
) -> Result<Exploration> {
    let run = |project: &mut Project<S>| {
        explore_with(project, request, clock_now, &mut ExplorationMemo::default())
    };
    match request.dry_run {
        true => run(project),
        false => project.exclusive(run),
    }
}

/// The last exploration plan and the exact inputs it was planned from. The plan is a pure
/// function of the energy model, the base, the cell centres, the cells' service energies and
/// the options, so a memo with the same inputs (compared bit for bit; the model and options
/// by their `Debug` text, every float to the last bit) gives the plan the planner would
/// compute again. A campaign's exhaustive run keeps one: once every sensor is collected
/// daily, the service energies repeat and so does the tour.
#[derive(Debug, Default)]
pub struct ExplorationMemo {
    last: Option<(String, Vec<u64>, ExplorationPlan)>,
}

impl ExplorationMemo {
    /// `plan_exploration` of these inputs: the kept plan when they equal the last ones.
    fn plan(
        &mut self,
        model: &MissionEnergyModel,
        base: LocalPoint,
        centres: &[LocalPoint],
        service_j: &[f64],
        options: &ExplorationOptions,
    ) -> std::result::Result<ExplorationPlan, ExplorationError> {
        let text = format!("{model:?} {options:?}");
        let bits: Vec<u64> = [base.e, base.n]
            .into_iter()
            .chain(centres.iter().flat_map(|c| [c.e, c.n]))
            .chain(service_j.iter().copied())
            .map(f64::to_bits)
            .collect();
        if let Some((t, b, plan)) = &self.last
            && *t == text
            && *b == bits
        {
            return Ok(plan.clone());
        }
        let plan = plan_exploration(model, base, centres, service_j, options)?;
        self.last = Some((text, bits, plan.clone()));
        Ok(plan)
    }
}

/// [`explore`] with a memo of the last plan (see [`ExplorationMemo`]): the same result.
pub fn explore_with<S: Store>(
    project: &mut Project<S>,
    request: &ExploreRequest,
    clock_now: UnixSeconds,
    memo: &mut ExplorationMemo,
) -> Result<Exploration> {
    let k = gleaner_scoring::state::collection_knowledge(project, request.at, History::default())?;
    let t = gleaner_scoring::when::mission_time(request.at, k.latest)?;
    // Legs and hovers priced in the forecast wind plus the margin, as `plan` prices them
    // (still air: the model as it is).
    let plan_wind = crate::wind::PlanWind::of(&project.settings().flight, request.wind)?;
    let still = energy_model(project)?;
    let model = if plan_wind.planned.is_calm() {
        still
    } else {
        still.with_wind_up_to(plan_wind.planned)
    };
    let profile = flight_profile(project, &model)?;
    let svc = services(&model, &k, t)?;
    let points = FlightPoints::of(&k.field);
    let centres = &points.centres;
    let service_j: Vec<f64> = svc.iter().map(|s| s.energy_j).collect();
    let base = points.base;
    let routed = routing(project, &k, &points)?;
    let (detours, unreachable) = match &routed {
        None => (None, Vec::new()),
        Some((_, all, unreachable)) => (Some(all), unreachable.clone()),
    };
    let plan_with = |options: &ExplorationOptions| match &routed {
        None => memo.plan(&model, base, centres, &service_j, options),
        Some((_, all, _)) => {
            // The reachable cells only, with their legs; cell indices mapped back after.
            let keep: Vec<usize> = (0..centres.len())
                .filter(|&c| all.reachable(c + 1))
                .collect();
            let nodes: Vec<usize> = std::iter::once(0)
                .chain(keep.iter().map(|&c| c + 1))
                .collect();
            let mut pts = vec![base];
            pts.extend(keep.iter().map(|&c| centres[c]));
            let sub = Detours::new(&pts, |i, j| Some(all.via(nodes[i], nodes[j]).to_vec()));
            let kept_centres: Vec<_> = keep.iter().map(|&c| centres[c]).collect();
            let kept_service: Vec<f64> = keep.iter().map(|&c| service_j[c]).collect();
            let mut plan = plan_exploration_routed(
                &model,
                base,
                &kept_centres,
                &kept_service,
                options,
                Some(&sub),
            )?;
            for s in &mut plan.sorties {
                for c in &mut s.cells {
                    *c = keep[*c];
                }
            }
            Ok(plan)
        }
    };
    let plan = within_budget(&model, plan_with)?;
    let zeros = vec![0.0; centres.len()];
    let mut sorties = Vec::with_capacity(plan.sorties.len());
    let mut vias = Vec::with_capacity(plan.sorties.len());
    for s in &plan.sorties {
        let visits: Vec<CellVisit> = s
            .cells
            .iter()
            .map(|&c| CellVisit {
                centre: centres[c],
                hover_s: svc[c].hover_s,
            })
            .collect();
        let via = detours.map(|d| d.route_via(&s.cells)).unwrap_or_default();
        let energy = model
            .breakdown_paths(base, &visits, &via)
            .map_err(|e| AppError::core("exploration", e))?;
        vias.push(via_positions(k.field.frame(), &via));
        if !energy.feasible {
            return Err(AppError::Core {
                context: "exploration",
                message: format!(
                    "a sortie needs {:.1} J of {:.1} J usable; refusing it",
                    energy.total_j, energy.budget_j
                ),
            });
        }
        sorties.push((
            None,
            NewMission {
                created_at: clock_now,
                kind: MissionKind::Exploration,
                planned_at: t,
                solver: "exploration".into(),
                seed: 0,
                weights: [0.0; 4],
                anomaly_form: "n/a".into(),
                total_score: 0.0,
                profile,
                energy: breakdown(&energy),
                return_distance_m: if s.cells.is_empty() {
                    0.0
                } else {
                    energy.legs.last().map_or(0.0, |l| l.distance_m)
                },
                stops: stops(&k, &points, &s.cells, &energy, &svc, &zeros, None),
            },
        ));
    }
    if !request.dry_run {
        project.check_stored_grid(&k.field)?;
        store_sorties(project, &mut sorties)?;
    }
    Ok(Exploration {
        planned_at: t,
        cells: centres.len(),
        budget_j: model.usable_budget_j(),
        lower_bound_sorties: plan.lower_bound_sorties,
        total_energy_j: plan.total_energy_j,
        sorties,
        via: vias,
        unreachable,
        wind: plan_wind,
    })
}

/// The first exploration plan within the battery: in wind the planner's length-based split
/// may leave a sortie over the budget in the wind, so a larger margin then, up to one that
/// always suffices.
fn within_budget(
    model: &MissionEnergyModel,
    mut plan_with: impl FnMut(
        &ExplorationOptions,
    ) -> std::result::Result<ExplorationPlan, ExplorationError>,
) -> Result<ExplorationPlan> {
    let margins = exploration_margins(model);
    for (k, &budget_margin) in margins.iter().enumerate() {
        let options = ExplorationOptions {
            budget_margin,
            ..ExplorationOptions::default()
        };
        match plan_with(&options) {
            Ok(plan) => return Ok(plan),
            Err(ExplorationError::Infeasible { .. }) if k + 1 < margins.len() => continue,
            Err(e) => return Err(AppError::core("exploration", e)),
        }
    }
    Err(AppError::Core {
        context: "exploration",
        message: "no budget margin gave sorties within the battery".into(),
    })
}

/// Stores the sorties as missions in one transaction; sets their ids.
fn store_sorties<S: Store>(
    project: &mut Project<S>,
    sorties: &mut [(Option<MissionId>, NewMission)],
) -> Result<()> {
    let ids = project.store_mut().write(|tx| {
        sorties
            .iter()
            .map(|(_, m)| tx.create_mission(m))
            .collect::<std::result::Result<Vec<_>, _>>()
            .map_err(AppError::from)
    })?;
    for ((id, _), new) in sorties.iter_mut().zip(ids) {
        *id = Some(new);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use gleaner_energy::EnergyConfig;

    /// Exploration in wind: every sortie is priced in the forecast plus the margin and
    /// within the battery there, every cell is visited, the profile carries that wind; a
    /// calm forecast is still air.
    #[test]
    fn explores_in_the_forecast_wind_plus_the_margin() {
        let mut p = crate::test_farm::ingested_synth_project(&gleaner_synth::SynthConfig {
            seed: 5,
            sensor_count: 40,
            days: 20,
            vw_depths_cm: vec![30],
            t_depths_cm: vec![],
            ..gleaner_synth::SynthConfig::default()
        });
        let at = p.farm.times()[0] + 10 * 86_400;
        let ask = |wind| ExploreRequest {
            at: Some(at),
            dry_run: true,
            wind,
        };
        let still = explore(&mut p.project, &ask(None), 0).unwrap();
        let calm = explore(&mut p.project, &ask(Some(gleaner_energy::Wind::CALM)), 0).unwrap();
        assert_eq!(
            format!("{:?}", still.sorties),
            format!("{:?}", calm.sorties)
        );
        assert!(still.wind.planned.is_calm());
        let forecast = gleaner_energy::Wind::new(9.0, 250.0).unwrap();
        let windy = explore(&mut p.project, &ask(Some(forecast)), 0).unwrap();
        assert_eq!(windy.wind.forecast, forecast);
        let margin = p.project.settings().flight.wind_margin_mps;
        assert_eq!(windy.wind.planned.speed_mps, 9.0 + margin);
        // Priced otherwise: legs cost more, hovers less (induced power falls with airspeed).
        assert_ne!(windy.total_energy_j, still.total_energy_j);
        let covered: usize = windy.sorties.iter().map(|(_, m)| m.stops.len()).sum();
        assert_eq!(covered, windy.cells);
        let model = energy_model(&p.project)
            .unwrap()
            .with_wind_up_to(windy.wind.planned);
        let (_, field) = p.project.field().unwrap();
        let base = FlightPoints::of(&field).base;
        for (_, m) in &windy.sorties {
            assert_eq!(m.profile.wind_mps, 9.0 + margin);
            assert_eq!(m.profile.wind_from_deg, 250.0);
            assert!(m.energy.total_j <= m.energy.budget_j, "{:?}", m.energy);
            // Re-priced in the wind from the stops: the stored total.
            let visits: Vec<CellVisit> = m
                .stops
                .iter()
                .map(|s| CellVisit {
                    centre: field.frame().forward(s.centre),
                    hover_s: s.hover_s,
                })
                .collect();
            let e = model.breakdown(base, &visits).unwrap();
            assert!((e.total_j - m.energy.total_j).abs() < 1e-6 * e.total_j);
        }
    }

    /// The memo gives what the planner computes, for repeated and for changed inputs (one
    /// service energy one ulp larger is already a new plan's inputs).
    #[test]
    fn memo_plans_are_the_planners_plans() {
        let model = MissionEnergyModel::new(&EnergyConfig::paper()).unwrap();
        let centres: Vec<LocalPoint> = (0..30)
            .map(|i| LocalPoint::new(40.0 * (i % 6) as f64 - 90.0, 35.0 * (i / 6) as f64))
            .collect();
        let mut service: Vec<f64> = (0..30).map(|i| 150.0 + 7.0 * (i % 5) as f64).collect();
        let base = LocalPoint::new(0.0, 0.0);
        let options = ExplorationOptions::default();
        let mut memo = ExplorationMemo::default();
        let direct = plan_exploration(&model, base, &centres, &service, &options).unwrap();
        for _ in 0..2 {
            let memo_plan = memo
                .plan(&model, base, &centres, &service, &options)
                .unwrap();
            assert_eq!(memo_plan, direct);
        }
        service[7] = f64::from_bits(service[7].to_bits() + 1);
        let changed = plan_exploration(&model, base, &centres, &service, &options).unwrap();
        let memo_plan = memo
            .plan(&model, base, &centres, &service, &options)
            .unwrap();
        assert_eq!(memo_plan, changed);
        let (_, bits, _) = memo.last.as_ref().unwrap();
        assert_eq!(bits[2 + 60 + 7], service[7].to_bits(), "planned again");
        service[7] += 50.0;
        let changed = plan_exploration(&model, base, &centres, &service, &options).unwrap();
        let memo_plan = memo
            .plan(&model, base, &centres, &service, &options)
            .unwrap();
        assert_eq!(memo_plan, changed);
        assert_ne!(changed.total_energy_j, direct.total_energy_j);
    }
}
