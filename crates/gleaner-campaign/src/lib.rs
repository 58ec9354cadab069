//! gleaner's campaign simulator, above the application layer: a dataset stands for everything
//! the sensors logged (the ground truth, [`Truth`]); a campaign replays it as missions, one run
//! per strategy, seed and battery budget, each against its own store and through the same
//! use cases the CLI and the server call (`score`, `plan`, `explore`, a simulated flight →
//! `record_flight`), then evaluates what each strategy brought back.
//!
//! - [`campaign`]: requests, strategies, runs, metrics and their intervals (`summarise`).
//! - [`campaign_flight`]: a campaign's daily wind, forecast error and batteries; the
//!   simulated flight that re-plans in the air.
//! - [`simulate`]: [`Truth`] (what is available when), [`fly`] (a mission flown in
//!   simulation, recorded like a real flight).
//! - [`replay`]: [`ProjectRecord`], a project's own record as a dataset.
//! - [`simulation`]: `gleaner simulate`'s run: a dataset's campaigns, their results and
//!   report written into one directory.
//! - [`results`]: the results format (CSV files a simulation writes and the report reads).
//! - [`report`]: the campaign report, Markdown with SVG charts.
//! - [`doc`]: a campaign's summary as the `gleaner.campaign` document.
//!
//! It reaches the application layer only through `gleaner_app`'s public API, and the few
//! shortcuts a long replay needs through [`gleaner_app::shortcuts`].
//!
//! Units: times are seconds since 1970-01-01T00:00:00Z (UTC); energies joules; wind m/s.
#![deny(missing_docs)]

pub mod campaign;
pub mod campaign_flight;
pub mod datasets;
pub mod demo;
pub mod doc;
mod error;
pub mod replay;
pub mod report;
pub mod results;
mod seed;
pub mod simulate;
pub mod simulation;

pub use error::{Error, Result};

pub use replay::{ProjectRecord, REPLAY_DEFAULT_DAYS};
pub use simulate::{Truth, fly, fly_buffered};

impl std::str::FromStr for campaign::Strategy {
    type Err = gleaner_app::AppError;

    /// [`campaign::Strategy::parse`].
    fn from_str(s: &str) -> Result<Self, gleaner_app::AppError> {
        campaign::Strategy::parse(s)
    }
}

#[cfg(test)]
mod tests {
    use super::campaign::Strategy;

    #[test]
    fn every_strategy_parses_back_from_its_name_and_others_are_refused() {
        for s in Strategy::ALL.iter().chain(&Strategy::YARDSTICKS) {
            assert_eq!(s.name().parse::<Strategy>().expect("strategy"), *s);
        }
        assert!("best".parse::<Strategy>().is_err());
    }
}
