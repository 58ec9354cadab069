//! Exploration (SPEC §5 step 3): as few sorties as possible, each within the battery, that
//! together visit every cell; each sortie is a mission like any other, with typed stops and
//! its energy breakdown, all stored in one transaction.

use gleaner_energy::CellVisit;
use gleaner_field::{LocalPoint, UnixSeconds};
use gleaner_mission::exploration::{ExplorationOptions, plan_exploration};
use gleaner_store::{MissionId, MissionKind, NewMission, Store, StoreWrite};

use crate::error::{AppError, Result};
use crate::knowledge::History;
use crate::plan::{breakdown, energy_model, flight_profile, services, stops};
use crate::project::Project;

/// What to explore.
#[derive(Debug, Clone, Default)]
pub struct ExploreRequest {
    /// Planning time, seconds [default: the latest reading, else the clock].
    pub at: Option<UnixSeconds>,
    /// Plan only; write nothing.
    pub dry_run: bool,
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
}

/// The use case: plans the exploration sorties and, unless a dry run, stores them as
/// exploration missions in one transaction. Every sortie is re-checked by the energy model.
pub fn explore<S: Store>(
    project: &mut Project<S>,
    request: &ExploreRequest,
    clock_now: UnixSeconds,
) -> Result<Exploration> {
    let k = crate::state::collection_knowledge(project, request.at, History::default())?;
    let t = request.at.or(k.latest).unwrap_or(clock_now);
    let model = energy_model(project)?;
    let profile = flight_profile(project, &model)?;
    let svc = services(&model, &k, t)?;
    let centres: Vec<LocalPoint> = k.field.cells().iter().map(|c| c.centre).collect();
    let service_j: Vec<f64> = svc.iter().map(|s| s.energy_j).collect();
    let base = LocalPoint::new(0.0, 0.0);
    let plan = plan_exploration(
        &model,
        base,
        &centres,
        &service_j,
        &ExplorationOptions::default(),
    )
    .map_err(|e| AppError::core("exploration", e))?;
    let zeros = vec![0.0; centres.len()];
    let mut sorties = Vec::with_capacity(plan.sorties.len());
    for s in &plan.sorties {
        let visits: Vec<CellVisit> = s
            .cells
            .iter()
            .map(|&c| CellVisit {
                centre: centres[c],
                hover_s: svc[c].hover_s,
            })
            .collect();
        let energy = model
            .breakdown(base, &visits)
            .map_err(|e| AppError::core("exploration", e))?;
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
                stops: stops(&k, &s.cells, &energy, &svc, &zeros, None),
            },
        ));
    }
    if !request.dry_run {
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
    }
    Ok(Exploration {
        planned_at: t,
        cells: centres.len(),
        budget_j: model.usable_budget_j(),
        lower_bound_sorties: plan.lower_bound_sorties,
        total_energy_j: plan.total_energy_j,
        sorties,
    })
}
