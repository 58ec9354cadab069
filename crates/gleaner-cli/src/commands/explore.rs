//! `gleaner explore`: the exploration phase (SPEC §5 step 3) — as few sorties as possible, each
//! within the battery budget, that together visit every cell. Each sortie is stored as an
//! exploration mission.

use anyhow::{Context, Result};
use gleaner_energy::MissionEnergyModel;
use gleaner_energy::exploration::{ExplorationOptions, plan_exploration};
use gleaner_field::{LocalPoint, UnixSeconds};
use gleaner_ingest::time::format_rfc3339;
use gleaner_store::{MissionKind, NewMission, Store};
use serde::Serialize;

use crate::commands::plan::services;
use crate::commands::score::{self, History};
use crate::project::Project;

/// One sortie in the output.
#[derive(Serialize)]
pub struct SortieJson {
    /// Stored mission id.
    pub mission_id: Option<i64>,
    /// Cell ids in visiting order.
    pub cells: Vec<String>,
    /// Cruise distance base -> cells -> base, m.
    pub distance_m: f64,
    /// Energy, J.
    pub energy_j: f64,
    /// Energy / usable budget.
    pub utilisation: f64,
}

/// The whole exploration plan.
#[derive(Serialize)]
pub struct ExplorationJson {
    /// Planned for, RFC 3339.
    pub planned_at: String,
    /// Cells to visit.
    pub cells: usize,
    /// Usable budget per sortie, J.
    pub budget_j: f64,
    /// A lower bound on the number of sorties.
    pub lower_bound_sorties: usize,
    /// Total energy over all sorties, J.
    pub total_energy_j: f64,
    /// The sorties.
    pub sorties: Vec<SortieJson>,
}

/// Plans the exploration at time `at` (default: the latest reading) and optionally stores it.
pub fn run(project: &mut Project, at: Option<UnixSeconds>, save: bool) -> Result<ExplorationJson> {
    let k = score::knowledge(project, at, History::default())?;
    let t = at
        .or(k.latest)
        .unwrap_or_else(crate::commands::ingest::now_unix);
    let model =
        MissionEnergyModel::new(&project.config.energy.to_core()?).context("[energy] settings")?;
    let svc = services(&model, &k, t)?;
    let centres: Vec<LocalPoint> = k.field.cells().iter().map(|c| c.centre).collect();
    let service_j: Vec<f64> = svc.iter().map(|s| s.energy_j).collect();
    let plan = plan_exploration(
        &model,
        LocalPoint::new(0.0, 0.0),
        &centres,
        &service_j,
        &ExplorationOptions::default(),
    )
    .context("no exploration plan")?;
    let budget = model.usable_budget_j();
    let mut sorties = Vec::new();
    for s in &plan.sorties {
        let cells: Vec<String> = s
            .cells
            .iter()
            .map(|&c| k.field.cells()[c].index.to_string())
            .collect();
        let mut json = SortieJson {
            mission_id: None,
            cells,
            distance_m: s.distance_m,
            energy_j: s.energy_j,
            utilisation: s.energy_j / budget,
        };
        if save {
            let stops: Vec<serde_json::Value> = json
                .cells
                .iter()
                .map(|c| serde_json::json!({ "cell": c }))
                .collect();
            let id = project.store.create_mission(&NewMission {
                created_at: crate::commands::ingest::now_unix(),
                kind: MissionKind::Exploration,
                planned_at: t,
                solver: "exploration".into(),
                budget_j: budget,
                energy_j: s.energy_j,
                summary_json: serde_json::json!({ "stops": stops, "energy_j": s.energy_j })
                    .to_string(),
            })?;
            json.mission_id = Some(id.0);
        }
        sorties.push(json);
    }
    Ok(ExplorationJson {
        planned_at: format_rfc3339(t),
        cells: centres.len(),
        budget_j: budget,
        lower_bound_sorties: plan.lower_bound_sorties,
        total_energy_j: plan.total_energy_j,
        sorties,
    })
}

/// The plan as text.
pub fn table(e: &ExplorationJson) -> String {
    let mut out = format!(
        "exploration of {} cells: {} sorties (lower bound {}), {:.1} J in all, {:.1} J usable per sortie\n",
        e.cells,
        e.sorties.len(),
        e.lower_bound_sorties,
        e.total_energy_j,
        e.budget_j
    );
    for (n, s) in e.sorties.iter().enumerate() {
        out.push_str(&format!(
            "{:>3}{} {:>3} cells {:>8.0} m {:>9.1} J ({:>5.1}%): {}\n",
            n + 1,
            s.mission_id
                .map_or(String::new(), |id| format!(" (mission #{id})")),
            s.cells.len(),
            s.distance_m,
            s.energy_j,
            100.0 * s.utilisation,
            s.cells.join(" ")
        ));
    }
    out
}
