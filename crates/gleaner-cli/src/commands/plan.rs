//! `gleaner plan`: scores (from the utility engine, or a `--scores` CSV) + the energy model ->
//! a route and the mission summary of SPEC §6, stored as a planned mission.

use std::path::Path;
use std::time::Duration;

use anyhow::{Context, Result, bail};
use gleaner_energy::{CellService, MissionEnergyModel};
use gleaner_field::{LocalPoint, UnixSeconds};
use gleaner_ingest::time::format_rfc3339;
use gleaner_mission::{Candidate, MissionPlan, PlanOptions, Planner, plan_mission};
use gleaner_store::{MissionKind, NewMission, Store};
use gleaner_utility::CellTerms;
use serde::Serialize;

use crate::cell_csv;
use crate::commands::score::{self, History, Knowledge};
use crate::project::Project;

/// Settings from the command line.
pub struct PlanArgs {
    /// Mission time, seconds (default: the latest reading).
    pub at: Option<UnixSeconds>,
    /// Which readings count as collected.
    pub history: History,
    /// Per-cell scores from a CSV (`cell_id,score`) instead of the utility engine.
    pub scores: Option<std::path::PathBuf>,
    /// Planner.
    pub planner: Planner,
    /// Time limit, seconds.
    pub time_limit_s: f64,
    /// Seed.
    pub seed: u64,
    /// Store the mission as planned.
    pub save: bool,
}

/// Parses a planner name.
pub fn parse_planner(name: &str) -> Result<Planner> {
    Ok(match name {
        "default" => Planner::Default,
        "greedy" => Planner::Greedy,
        "exact" => Planner::Exact,
        other => bail!("unknown solver {other:?}: expected default, greedy or exact"),
    })
}

fn read_scores(path: &Path, k: &Knowledge) -> Result<Vec<f64>> {
    let labels: Vec<String> = k
        .field
        .cells()
        .iter()
        .map(|c| c.index.to_string())
        .collect();
    let mut scores: Vec<Option<f64>> = vec![None; labels.len()];
    for row in cell_csv::read(path)? {
        let at = |what: &str| format!("{}:{}: {what}", path.display(), row.line);
        let [score] = row.values[..] else {
            bail!("{}", at("expected `cell_id,score`"));
        };
        let pos = labels
            .iter()
            .position(|l| *l == row.cell)
            .with_context(|| at(&format!("column `cell_id`: unknown cell: {:?}", row.cell)))?;
        if scores[pos].replace(score).is_some() {
            bail!(
                "{}",
                at(&format!(
                    "column `cell_id`: cell {:?} listed twice",
                    row.cell
                ))
            );
        }
    }
    // Cells the file leaves out score 0: never worth a detour.
    Ok(scores.into_iter().map(|s| s.unwrap_or(0.0)).collect())
}

/// Per-cell collection service at time `t` from the sensors' backlog.
pub fn services(
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
    model
        .field_services(&k.field, &elapsed)
        .context("collection times")
}

/// Keeps each cell's expected collection energy (J) and pending data (bytes, from the energy
/// model's backlog) in the cell metadata table; the other fields stay as stored.
fn store_expected_energy(
    project: &mut Project,
    k: &Knowledge,
    services: &[CellService],
) -> Result<()> {
    let mut metadata = project.store.cell_metadata()?;
    for m in &mut metadata {
        m.summaries.clear();
        m.correlations.clear();
        m.anomalies.clear();
        if let Some(c) = k.field.cells().iter().position(|c| c.index == m.cell) {
            m.expected_energy_j = Some(services[c].energy_j);
        }
    }
    project.store.upsert_cell_metadata(&metadata)?;
    Ok(())
}

/// A planned mission with everything needed to report it.
pub struct Planned {
    /// Mission time, seconds.
    pub t: UnixSeconds,
    /// What was known.
    pub knowledge: Knowledge,
    /// Per-cell terms when scored by the utility engine.
    pub terms: Option<Vec<CellTerms>>,
    /// Per-cell S.
    pub scores: Vec<f64>,
    /// Per-cell collection service.
    pub services: Vec<CellService>,
    /// The plan.
    pub plan: MissionPlan,
    /// The paper's greedy heuristic on the same instance, for comparison.
    pub greedy: MissionPlan,
    /// Stored mission id.
    pub mission_id: Option<i64>,
    /// The anomaly form label.
    pub anomaly_form: String,
}

/// Scores, plans and (optionally) stores a mission.
pub fn run(project: &mut Project, args: &PlanArgs) -> Result<Planned> {
    let (knowledge, terms, scores, t, anomaly_form) = match &args.scores {
        Some(path) => {
            let k = score::knowledge(project, args.at, args.history)?;
            let t = args
                .at
                .or(k.latest)
                .context("no readings and no --at: cannot tell the mission time")?;
            let s = read_scores(path, &k)?;
            (k, None, s, t, String::from("n/a (scores from file)"))
        }
        None => {
            let scoring = score::score(project, args.at, args.history, None)?;
            score::store_scores(project, &scoring)?;
            let scores = scoring.cells.iter().map(|c| c.terms.s).collect();
            let terms = scoring.cells.into_iter().map(|c| c.terms).collect();
            (
                scoring.knowledge,
                Some(terms),
                scores,
                scoring.t,
                scoring.anomaly_form,
            )
        }
    };
    let model =
        MissionEnergyModel::new(&project.config.energy.to_core()?).context("[energy] settings")?;
    let services = services(&model, &knowledge, t)?;
    store_expected_energy(project, &knowledge, &services)?;
    let candidates: Vec<Candidate> = knowledge
        .field
        .cells()
        .iter()
        .zip(&scores)
        .zip(&services)
        .map(|((c, &score), svc)| Candidate {
            centre: c.centre,
            score,
            hover_s: svc.hover_s,
        })
        .collect();
    let options = PlanOptions {
        planner: args.planner,
        time_limit: Duration::from_secs_f64(args.time_limit_s.max(0.0)),
        seed: args.seed,
        max_iterations: None,
    };
    let base = LocalPoint::new(0.0, 0.0);
    let plan = plan_mission(&model, base, &candidates, &options)?;
    let greedy = plan_mission(
        &model,
        base,
        &candidates,
        &PlanOptions {
            planner: Planner::Greedy,
            ..options
        },
    )?;
    let mut planned = Planned {
        t,
        knowledge,
        terms,
        scores,
        services,
        plan,
        greedy,
        mission_id: None,
        anomaly_form,
    };
    if args.save {
        let summary = serde_json::to_string(&to_json(project, &planned, args))?;
        let id = project.store.create_mission(&NewMission {
            created_at: crate::commands::ingest::now_unix(),
            kind: MissionKind::Adaptive,
            planned_at: t,
            solver: args.planner.name().to_string(),
            budget_j: planned.plan.energy.budget_j,
            energy_j: planned.plan.energy.total_j,
            summary_json: summary,
        })?;
        planned.mission_id = Some(id.0);
    }
    Ok(planned)
}

/// One visited cell in the mission summary.
#[derive(Serialize)]
pub struct StopJson {
    /// Position in the visiting order, from 1.
    pub order: usize,
    /// Cell id.
    pub cell: String,
    /// Centre `[lon, lat]`, WGS84 degrees.
    pub centre_lon_lat: [f64; 2],
    /// Score S.
    pub s: f64,
    /// Terms F, R, A, U (absent when scores came from a file).
    pub terms: Option<[f64; 4]>,
    /// Leg from the previous stop, metres.
    pub leg_distance_m: f64,
    /// Leg propulsion energy, J.
    pub leg_energy_j: f64,
    /// Upload time, s.
    pub collection_s: f64,
    /// Hover time, s.
    pub hover_s: f64,
    /// Hover energy, J.
    pub hover_j: f64,
    /// Receiver energy, J.
    pub comm_j: f64,
}

/// The energy totals.
#[derive(Serialize)]
pub struct EnergyJson {
    /// E_t: travel base -> ... -> last cell, J.
    pub travel_j: f64,
    /// E_h, J.
    pub hover_j: f64,
    /// E_c, J.
    pub comm_j: f64,
    /// E_r: return leg, J.
    pub return_j: f64,
    /// Total, J.
    pub total_j: f64,
    /// Usable budget, J.
    pub budget_j: f64,
    /// total / budget.
    pub utilisation: f64,
    /// Distance flown, m.
    pub distance_m: f64,
    /// Flight time including hovers, s.
    pub flight_time_s: f64,
}

/// A plan's headline numbers.
#[derive(Serialize)]
pub struct BaselineJson {
    /// Planner.
    pub planner: &'static str,
    /// Cells visited.
    pub cells: usize,
    /// Sum of S.
    pub total_score: f64,
    /// Energy, J.
    pub energy_j: f64,
}

/// The mission summary (SPEC §6) as JSON.
#[derive(Serialize)]
pub struct MissionJson {
    /// Stored mission id.
    pub mission_id: Option<i64>,
    /// Mission time, RFC 3339.
    pub planned_at: String,
    /// Planner.
    pub planner: &'static str,
    /// Seed.
    pub seed: u64,
    /// Time limit, s.
    pub time_limit_s: f64,
    /// Weights alpha, beta, gamma, delta.
    pub weights: [f64; 4],
    /// Anomaly form.
    pub anomaly_form: String,
    /// Base station `[lon, lat]`.
    pub base_lon_lat: [f64; 2],
    /// Cruise speed, m/s.
    pub cruise_speed_mps: f64,
    /// Stops in visiting order.
    pub stops: Vec<StopJson>,
    /// Return leg distance, m.
    pub return_distance_m: f64,
    /// Energy totals.
    pub energy: EnergyJson,
    /// Sum of S over the visited cells.
    pub total_score: f64,
    /// Cells with S > 0.
    pub candidates: usize,
    /// The paper's greedy heuristic on the same instance.
    pub greedy_baseline: BaselineJson,
}

/// The summary document.
pub fn to_json(project: &Project, p: &Planned, args: &PlanArgs) -> MissionJson {
    let u = &project.config.utility;
    let k = &p.knowledge;
    let e = &p.plan.energy;
    let model_speed = if e.flight_time_s > 0.0 {
        let hover: f64 = e.cells.iter().map(|c| c.hover_s).sum();
        e.distance_m / (e.flight_time_s - hover).max(1e-9)
    } else {
        0.0
    };
    let stops = p
        .plan
        .order
        .iter()
        .enumerate()
        .map(|(n, &c)| {
            let cell = &k.field.cells()[c];
            let centre = k.field.frame().inverse(cell.centre);
            StopJson {
                order: n + 1,
                cell: cell.index.to_string(),
                centre_lon_lat: [centre.lon(), centre.lat()],
                s: p.scores[c],
                terms: p.terms.as_ref().map(|t| [t[c].f, t[c].r, t[c].a, t[c].u]),
                leg_distance_m: e.legs[n].distance_m,
                leg_energy_j: e.legs[n].energy_j,
                collection_s: p.services[c].collection_s,
                hover_s: e.cells[n].hover_s,
                hover_j: e.cells[n].hover_j,
                comm_j: e.cells[n].comm_j,
            }
        })
        .collect();
    let base = k.field.base();
    MissionJson {
        mission_id: p.mission_id,
        planned_at: format_rfc3339(p.t),
        planner: p.plan.planner.name(),
        seed: args.seed,
        time_limit_s: args.time_limit_s,
        weights: [u.alpha, u.beta, u.gamma, u.delta],
        anomaly_form: p.anomaly_form.clone(),
        base_lon_lat: [base.lon(), base.lat()],
        cruise_speed_mps: model_speed,
        stops,
        return_distance_m: e.legs.last().map_or(0.0, |l| {
            if p.plan.order.is_empty() {
                0.0
            } else {
                l.distance_m
            }
        }),
        energy: EnergyJson {
            travel_j: e.travel_j,
            hover_j: e.hover_j,
            comm_j: e.comm_j,
            return_j: e.return_j,
            total_j: e.total_j,
            budget_j: e.budget_j,
            utilisation: e.utilisation,
            distance_m: e.distance_m,
            flight_time_s: e.flight_time_s,
        },
        total_score: p.plan.total_score,
        candidates: p.plan.considered,
        greedy_baseline: BaselineJson {
            planner: "greedy",
            cells: p.greedy.order.len(),
            total_score: p.greedy.total_score,
            energy_j: p.greedy.energy.total_j,
        },
    }
}

/// The summary as a readable table.
pub fn table(m: &MissionJson) -> String {
    let mut out = format!(
        "mission{} planned for {} with the {} planner: {} of {} candidate cells, total S = {:.3}\n",
        m.mission_id.map_or(String::new(), |id| format!(" #{id}")),
        m.planned_at,
        m.planner,
        m.stops.len(),
        m.candidates,
        m.total_score
    );
    out.push_str(&format!(
        "{:>3} {:<10} {:>7} {:>6} {:>6} {:>7} {:>6} {:>8} {:>9} {:>7} {:>9} {:>7}\n",
        "#", "cell", "S", "F", "R", "A", "U", "leg_m", "leg_J", "hover_s", "hover_J", "comm_J"
    ));
    for s in &m.stops {
        let t = s.terms.map_or(
            [
                "-".to_string(),
                "-".to_string(),
                "-".to_string(),
                "-".to_string(),
            ],
            |t| {
                [
                    format!("{:.3}", t[0]),
                    format!("{:.3}", t[1]),
                    format!("{:.3}", t[2]),
                    format!("{:.3}", t[3]),
                ]
            },
        );
        out.push_str(&format!(
            "{:>3} {:<10} {:>7.3} {:>6} {:>6} {:>7} {:>6} {:>8.1} {:>9.1} {:>7.1} {:>9.1} {:>7.1}\n",
            s.order, s.cell, s.s, t[0], t[1], t[2], t[3], s.leg_distance_m, s.leg_energy_j, s.hover_s, s.hover_j, s.comm_j
        ));
    }
    let e = &m.energy;
    out.push_str(&format!(
        "return leg {:.1} m\nenergy: E_t {:.1} J + E_h {:.1} J + E_c {:.1} J + E_r {:.1} J = {:.1} J of {:.1} J usable ({:.1}%)\n",
        m.return_distance_m,
        e.travel_j,
        e.hover_j,
        e.comm_j,
        e.return_j,
        e.total_j,
        e.budget_j,
        100.0 * e.utilisation
    ));
    out.push_str(&format!(
        "flight: {:.0} m, {:.0} s; paper's greedy on the same cells: {} cells, total S = {:.3}, {:.1} J\n",
        e.distance_m, e.flight_time_s, m.greedy_baseline.cells, m.greedy_baseline.total_score, m.greedy_baseline.energy_j
    ));
    out.push_str(&format!(
        "weights alpha,beta,gamma,delta = {:?}; anomaly {}\n",
        m.weights, m.anomaly_form
    ));
    out
}
