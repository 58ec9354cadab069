//! A campaign's request and results: what a run reads and what it brings back (data only).

use gleaner_app::InitRequest;
use gleaner_app::settings::Settings;
use gleaner_field::{CellIndex, Sensor, SensorId, UnixSeconds};
use gleaner_kriging::{Covariance, IncrementModel};

use super::strategy::Strategy;
use crate::campaign_flight::{FlightConditions, FlightDay};

/// An anomaly event to catch: sensors, and the readings' times it covers.
#[derive(Debug, Clone, PartialEq)]
pub struct TruthEvent {
    /// Identifier.
    pub id: String,
    /// The affected sensors (caught when any of them is collected with an event reading).
    pub sensors: Vec<SensorId>,
    /// First affected reading's time, seconds.
    pub start: UnixSeconds,
    /// End (exclusive), seconds: the first reading time no longer in the event.
    pub end: UnixSeconds,
}

/// A campaign to run.
#[derive(Debug, Clone)]
pub struct CampaignRequest {
    /// The dataset's name in outputs.
    pub label: String,
    /// The sensors (as for `init`; its directory is not used).
    pub init: InitRequest,
    /// The sensors themselves (e.g. a project's own, `simulate --project`), used instead of
    /// reading `init.sensors` when given.
    pub sensors: Option<Vec<Sensor>>,
    /// The settings every run starts from (grid, utility, energy at 100% budget, planner).
    pub settings: Settings,
    /// Readings available by this time (t + period <= it) are the history every run starts
    /// with, seconds.
    pub history_until: UnixSeconds,
    /// Readings before this time are left out of the history, seconds [default: none].
    pub history_from: Option<UnixSeconds>,
    /// Mission times, seconds, ascending, after `history_until`.
    pub schedule: Vec<UnixSeconds>,
    /// Strategies.
    pub strategies: Vec<Strategy>,
    /// Replicate seeds (planner and random choices).
    pub seeds: Vec<u64>,
    /// Battery capacities as fractions of the settings' (1 = the paper's budget).
    pub budgets: Vec<f64>,
    /// The evaluated modality [default: the condition modality].
    pub modality: Option<String>,
    /// Ground-truth events (synthetic farms) [default: the real-data rule (`rule_events`) with `event_z`].
    pub events: Option<Vec<TruthEvent>>,
    /// |z| threshold of the real-data event rule.
    pub event_z: f64,
    /// Planner iteration cap (results independent of the machine's speed).
    pub planner_iterations: u64,
    /// Sorties per mission of the planned strategies (battery swaps, each within the budget,
    /// planned together by `plan`'s team solver), in 1..=[`gleaner_app::MAX_SORTIES`];
    /// exhaustive collection flies as many as it takes whatever this says.
    pub sorties: usize,
    /// Observations per kriging estimate.
    pub neighbours: usize,
    /// The reconstruction's model-based estimator (the `kriged` metrics): kriging of changes
    /// (the default), the dynamic field model or kriging of levels.
    pub estimator: gleaner_app::Estimator,
    /// Runs in parallel (threads; 0 = rayon's default).
    pub jobs: usize,
    /// Provenance time stamped on missions, seconds.
    pub clock_now: UnixSeconds,
    /// The wind and batteries the flights meet [default: still air, full batteries: flown
    /// as planned]; every run meets the same.
    pub flight: FlightConditions,
}

/// One mission's metrics (after its flights were recorded).
#[derive(Debug, Clone, PartialEq)]
pub struct MissionMetrics {
    /// Mission number, from 0.
    pub index: usize,
    /// Mission time T, seconds.
    pub t: UnixSeconds,
    /// Sorties flown.
    pub sorties: usize,
    /// Cells visited.
    pub cells: usize,
    /// Energy of all sorties, J.
    pub energy_j: f64,
    /// Usable budget per sortie, J.
    pub budget_j: f64,
    /// Root-mean-square error of last value carried forward, the modality's unit.
    pub rmse_carried: f64,
    /// Mean absolute error of last value carried forward.
    pub mae_carried: f64,
    /// Root-mean-square error of the kriging estimate.
    pub rmse_kriged: f64,
    /// Mean absolute error of the kriging estimate.
    pub mae_kriged: f64,
    /// Mean kriging variance, the unit squared.
    pub mean_variance: f64,
    /// Share of the sensors *estimated* (not read at T − period: their estimate is not their
    /// own reading) whose true value lies in the estimator's 90% interval, estimate ±
    /// 1.645·sd; None when none was estimated (or results of an older version). A calibrated
    /// model covers 90%.
    pub coverage90: Option<f64>,
    /// Root-mean-square error of last value carried forward from what was known before this
    /// mission's flights (after the previous mission's), against the same truth: the error the
    /// operator lived with between the two missions, at its largest. NaN when not measured
    /// (results files of an older version).
    pub rmse_carried_before: f64,
    /// The same for the kriging estimate.
    pub rmse_kriged_before: f64,
    /// Sensors with a true value at T − period (those evaluated).
    pub evaluated: usize,
    /// Mean time since each sensor's last collection, seconds.
    pub staleness_mean_s: f64,
    /// Largest time since a sensor's last collection, seconds.
    pub staleness_max_s: f64,
    /// Share of cells whose class the condition model predicted right before the flight.
    pub classifier_accuracy: Option<f64>,
    /// Readings dropped by full buffers, brought to light by this mission's collections.
    pub lost_readings: u64,
    /// Events first caught at this mission.
    pub events_caught: usize,
    /// How its sorties flew: wind, batteries, re-plans, energy against the battery (`None`
    /// in results files written before flights were simulated).
    pub flight: Option<FlightDay>,
}

/// A run's identity.
#[derive(Debug, Clone, PartialEq)]
pub struct RunKey {
    /// Strategy.
    pub strategy: Strategy,
    /// Replicate seed.
    pub seed: u64,
    /// Budget as a fraction of the settings' battery.
    pub budget: f64,
}

/// One run's results.
#[derive(Debug, Clone)]
pub struct RunResult {
    /// Which run.
    pub key: RunKey,
    /// One per scheduled mission.
    pub missions: Vec<MissionMetrics>,
    /// Per campaign event (same order as [`CampaignResult::events`]): when it was caught
    /// (the mission time), seconds.
    pub caught: Vec<Option<UnixSeconds>>,
    /// Every cell visited, with the utility terms the planner's scoring gave it before the
    /// flight (diagnostics: which terms drove the choice, revisit counts). Empty when the
    /// results were read back from files that do not hold it.
    pub visits: Vec<Visit>,
}

/// One visited cell of one mission, with its pre-flight utility terms (the project's weights
/// and forms, whatever the strategy chose by).
#[derive(Debug, Clone, PartialEq)]
pub struct Visit {
    /// Mission number, from 0.
    pub index: usize,
    /// The cell.
    pub cell: CellIndex,
    /// Days since the cell was last collected (its stalest sensor), at the mission time.
    pub age_days: f64,
    /// Freshness F, in [0, 1].
    pub f: f64,
    /// Anomaly as scored (raw or bounded).
    pub a: f64,
    /// Uncertainty U, in [0, 1].
    pub u: f64,
    /// Redundancy R, in [0, 1].
    pub r: f64,
    /// Score S with the project's weights.
    pub s: f64,
}

/// A campaign's results.
#[derive(Debug, Clone)]
pub struct CampaignResult {
    /// The dataset's name.
    pub label: String,
    /// The evaluated modality.
    pub modality: String,
    /// The logging period, seconds.
    pub period_s: i64,
    /// The field model fitted on the history.
    pub covariance: Covariance,
    /// The model of changes fitted on the history (`None` in results written before it).
    pub changes: Option<IncrementModel>,
    /// The estimator every run was judged by, resolved against the fitted models (`None` in
    /// results written before it was recorded).
    pub estimator: Option<gleaner_app::Estimator>,
    /// Events that became available during the campaign.
    pub events: Vec<TruthEvent>,
    /// One per (strategy, seed, budget), in that order.
    pub runs: Vec<RunResult>,
}
