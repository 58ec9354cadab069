//! The strategies a campaign compares and the utility terms their ablations drop.

use gleaner_app::settings::Settings;
use gleaner_app::{AppError, Result};
use gleaner_mission::Planner;

/// A utility term, for ablations.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Term {
    /// Freshness F (alpha).
    Freshness,
    /// Anomaly A (beta).
    Anomaly,
    /// Model uncertainty U (gamma).
    Uncertainty,
    /// Redundancy R (delta).
    Redundancy,
}

/// How a run chooses the cells of each mission.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Strategy {
    /// Every cell, in as many sorties as it takes (the exploration plan at each mission).
    Exhaustive,
    /// Longest-unvisited first: score = days since the cell's last collection.
    RoundRobin,
    /// S with freshness only (alpha = 1, the other weights 0), default planner.
    Freshness,
    /// Uniform random scores in (0, 1], seeded, default planner.
    Random,
    /// Every cell worth the same, the paper's greedy insertion: the nearest cells first.
    Nearest,
    /// The paper's method: its S (docs/method.md §2 at the paper's values,
    /// [`gleaner_app::settings::UtilitySection::paper`], whatever the project's), its greedy planner.
    Paper,
    /// gleaner's method: the project's utility settings made gleaner's
    /// ([`gleaner_app::settings::UtilitySection::gleaner`]: gated S with the drift freshness, the
    /// bounded anomaly, γ = δ = 0; plus η·V when `[utility] variance_weight` is set), the
    /// default planner.
    Gleaner,
    /// gleaner's method with one utility term switched off (with α = 0 the gated S is 0
    /// everywhere: nothing is worth a flight).
    Without(Term),
    /// Expected reduction of the field's posterior variance (greedy marginal gains of the
    /// kriging model fitted on the history), default planner.
    Variance,
    /// The information objective (docs/method.md §7): the route whose readings remove the
    /// most posterior variance of the dynamic field model (fitted on the history, run as a
    /// filter over what is known at each mission), summed over every sensor; marginal-gain
    /// orienteering ([`gleaner_app::Objective::Information`]).
    Information,
    /// The oracle's flyable twin: each cell worth its sensors' *predicted* squared error
    /// before the flight — the campaign estimator's variance from what is known, nothing
    /// clairvoyant — routed by the default planner.
    Expected,
    /// gleaner's earlier method ([`gleaner_app::settings::UtilitySection::gated`]: gated S with a
    /// 14-day freshness half-life and the bounded anomaly, the project's γ and δ), the
    /// default planner.
    Gated,
    /// gleaner's score and the information objective together
    /// ([`gleaner_app::Objective::Hybrid`]): gleaner's utility settings, a route worth its
    /// cells' share of the total S blended with the share of the dynamic field model's
    /// posterior variance its readings remove (`[planner] information_weight`), marginal-gain
    /// orienteering.
    Hybrid,
    /// A clairvoyant yardstick, not a strategy a UAV could fly: each cell is worth the squared
    /// error its sensors' pre-flight model-based estimates have against the values the flight
    /// will bring back (the truth stamped T − period, (m³/m³)² ×10⁶ for soil water), routed by
    /// the default planner. What choosing cells could buy at the budget if one knew the
    /// answer (up to the planner, and to the neighbours' estimates a visit also improves); never
    /// among [`Strategy::ALL`] nor counted as a same-energy competitor.
    Oracle,
}

impl Strategy {
    /// Every strategy, ablations included, in report order.
    pub const ALL: [Strategy; 16] = [
        Strategy::Gleaner,
        Strategy::Paper,
        Strategy::Variance,
        Strategy::Information,
        Strategy::Freshness,
        Strategy::RoundRobin,
        Strategy::Random,
        Strategy::Nearest,
        Strategy::Exhaustive,
        Strategy::Without(Term::Freshness),
        Strategy::Without(Term::Anomaly),
        Strategy::Without(Term::Uncertainty),
        Strategy::Without(Term::Redundancy),
        Strategy::Gated,
        Strategy::Expected,
        Strategy::Hybrid,
    ];

    /// The main strategies (`main`): gleaner, paper, variance, information, freshness,
    /// round-robin, random, nearest, exhaustive — the first nine of [`Strategy::ALL`], no
    /// ablations.
    pub const MAIN: &'static [Strategy] = Self::ALL.as_slice().split_at(9).0;

    /// Yardsticks run only when named: they see the truth (see [`Strategy::Oracle`]).
    pub const YARDSTICKS: [Strategy; 1] = [Strategy::Oracle];

    /// Whether the strategy sees the truth (a yardstick, not a competitor).
    pub fn is_yardstick(self) -> bool {
        Self::YARDSTICKS.contains(&self)
    }

    /// The strategy's name in outputs and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Strategy::Exhaustive => "exhaustive",
            Strategy::RoundRobin => "round-robin",
            Strategy::Freshness => "freshness",
            Strategy::Random => "random",
            Strategy::Nearest => "nearest",
            Strategy::Paper => "paper",
            Strategy::Gleaner => "gleaner",
            Strategy::Without(Term::Freshness) => "no-freshness",
            Strategy::Without(Term::Anomaly) => "no-anomaly",
            Strategy::Without(Term::Uncertainty) => "no-uncertainty",
            Strategy::Without(Term::Redundancy) => "no-redundancy",
            Strategy::Variance => "variance",
            Strategy::Information => "information",
            Strategy::Hybrid => "hybrid",
            Strategy::Expected => "expected-error",
            Strategy::Gated => "gated",
            Strategy::Oracle => "oracle",
        }
    }

    /// Parses a name of [`Strategy::name`].
    pub fn parse(name: &str) -> Result<Self> {
        Self::ALL
            .iter()
            .chain(&Self::YARDSTICKS)
            .copied()
            .find(|s| s.name() == name)
            .ok_or_else(|| {
                AppError::Invalid(format!(
                    "unknown strategy {name:?}: expected one of {}, or the yardstick {}",
                    Self::ALL.map(Strategy::name).join(", "),
                    Self::YARDSTICKS.map(Strategy::name).join(", ")
                ))
            })
    }

    /// Strategies by name, in order, duplicates next to each other dropped: `all` is
    /// [`Strategy::ALL`], `main` [`Strategy::MAIN`].
    pub fn parse_list<S: AsRef<str>>(names: &[S]) -> Result<Vec<Self>> {
        let mut out = Vec::new();
        for n in names {
            match n.as_ref() {
                "all" => out.extend(Self::ALL),
                "main" => out.extend_from_slice(Self::MAIN),
                other => out.push(Self::parse(other)?),
            }
        }
        out.dedup();
        if out.is_empty() {
            return Err(AppError::Invalid("no strategy named".into()));
        }
        Ok(out)
    }

    /// The run's settings: the campaign's with this strategy's weights and planner.
    pub(super) fn settings(self, base: &Settings) -> Settings {
        let mut s = base.clone();
        match self {
            Strategy::Paper => s.utility = s.utility.paper(),
            Strategy::Gleaner | Strategy::Without(_) | Strategy::Hybrid => {
                s.utility = s.utility.gleaner()
            }
            Strategy::Gated => s.utility = s.utility.gated(),
            _ => {}
        }
        let u = &mut s.utility;
        match self {
            Strategy::Freshness => {
                (u.alpha, u.beta, u.gamma, u.delta) = (1.0, 0.0, 0.0, 0.0);
                u.variance_weight = 0.0;
            }
            Strategy::Without(Term::Freshness) => u.alpha = 0.0,
            Strategy::Without(Term::Anomaly) => u.beta = 0.0,
            Strategy::Without(Term::Uncertainty) => u.gamma = 0.0,
            Strategy::Without(Term::Redundancy) => u.delta = 0.0,
            _ => {}
        }
        s
    }

    /// A rough rank of a run's cost (higher: longer), for scheduling the longest runs first:
    /// exhaustive flies several sorties per mission and records each; the drift freshness
    /// reads and scores its window at every scoring; given scores skip the utility engine's
    /// second scoring. Only the order of the runs depends on it, never a result.
    pub(super) fn expected_cost(self) -> u8 {
        match self {
            Strategy::Exhaustive => 4,
            Strategy::Gleaner | Strategy::Without(_) | Strategy::Hybrid => 3,
            Strategy::Freshness | Strategy::Gated | Strategy::Paper | Strategy::Information => 2,
            Strategy::Variance
            | Strategy::RoundRobin
            | Strategy::Random
            | Strategy::Oracle
            | Strategy::Expected => 1,
            Strategy::Nearest => 0,
        }
    }

    pub(super) fn planner(self) -> Planner {
        match self {
            Strategy::Paper | Strategy::Nearest => Planner::Greedy,
            _ => Planner::Default,
        }
    }

    /// How a run of this strategy chooses its cells besides its settings: the strategy itself
    /// when [`run_one`] gives the planner its own per-cell scores or explores (exhaustive);
    /// `None` when the utility engine scores by the run's settings alone. Two runs with the
    /// same selection and the same settings ([`run_settings`]) compute the same results.
    pub(super) fn selection(self) -> Option<Strategy> {
        match self {
            Strategy::Exhaustive
            | Strategy::RoundRobin
            | Strategy::Random
            | Strategy::Nearest
            | Strategy::Variance
            | Strategy::Information
            | Strategy::Hybrid
            | Strategy::Expected
            | Strategy::Oracle => Some(self),
            Strategy::Freshness
            | Strategy::Paper
            | Strategy::Gleaner
            | Strategy::Without(_)
            | Strategy::Gated => None,
        }
    }
}
