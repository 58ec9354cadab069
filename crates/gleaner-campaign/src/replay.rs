//! A project's own record as a campaign's dataset (`gleaner simulate --project`,
//! `POST /api/v1/simulate`).

use gleaner_app::{Project, Result};
use gleaner_field::UnixSeconds;
use gleaner_store::Store;

use crate::simulate::Truth;

/// Days of missions a project replay runs by default: the last 30 days of its record.
pub const REPLAY_DEFAULT_DAYS: i64 = 30;

/// A project's own record as a campaign's dataset (`gleaner simulate --project`): its sensors
/// and settings as they are, every stored reading as the truth, and the default period: the
/// last [`REPLAY_DEFAULT_DAYS`] days of the record as missions, everything before as history.
/// The project itself is only read: each run of the campaign is its own in-memory project.
pub struct ProjectRecord {
    /// The project's name (the campaign's label).
    pub name: String,
    /// The project's sensors, WGS84.
    pub sensors: Vec<gleaner_field::Sensor>,
    /// The project's settings (grid, base, energy, planner; the strategies set the utility).
    pub settings: gleaner_app::settings::Settings,
    /// Every stored reading; its period is the sampling step.
    pub truth: Truth,
    /// Default end of the history and first mission, s: the last reading's availability
    /// minus [`REPLAY_DEFAULT_DAYS`] days.
    pub history_until: UnixSeconds,
    /// Default last mission, s: when the last reading becomes available (its time plus the
    /// period).
    pub end: UnixSeconds,
}

impl ProjectRecord {
    /// The record as a campaign's dataset, the runs' project directory `dir` (the project's:
    /// nothing is written there). A first mission given without an end of the history moves
    /// the history's end there.
    pub fn into_parts(self, dir: &std::path::Path) -> crate::campaign::DatasetParts {
        crate::campaign::DatasetParts {
            label: self.name,
            init: gleaner_app::InitRequest {
                dir: dir.to_path_buf(),
                ..gleaner_app::InitRequest::default()
            },
            sensors: Some(self.sensors),
            settings: self.settings,
            truth: self.truth,
            history_until: self.history_until,
            history_from: None,
            end: self.end,
            history_follows_start: true,
            events: None,
        }
    }

    /// Reads `project`'s sensors, settings and readings.
    pub fn read<S: Store>(project: &Project<S>) -> Result<Self> {
        let (sensors, _) = project.field()?;
        let truth = Truth::from_store(project)?;
        let (_, last) = truth.span().unwrap_or((0, 0));
        let end = last.saturating_add(truth.period_s);
        Ok(Self {
            name: project.settings().project.name.clone(),
            sensors,
            settings: project.settings().clone(),
            history_until: end.saturating_sub(REPLAY_DEFAULT_DAYS * 86_400),
            end,
            truth,
        })
    }
}
