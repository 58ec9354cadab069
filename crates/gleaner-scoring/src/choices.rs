//! Choices named in requests, parsed by `FromStr`, each spelled once: the reconstruction's
//! estimator and the planning objective (the energy preset is
//! [`EnergyPreset`](crate::settings::EnergyPreset), next to the settings it names).

use std::str::FromStr;

use gleaner_kriging::Mean;

use gleaner_mission::Planner;

use crate::error::{AppError, Result};

/// Parses a planner name: `default`, `greedy` or `exact`.
pub fn parse_planner(name: &str) -> Result<Planner> {
    Ok(match name {
        "default" => Planner::Default,
        "greedy" => Planner::Greedy,
        "exact" => Planner::Exact,
        other => {
            return Err(AppError::Invalid(format!(
                "unknown solver {other:?}: expected default, greedy or exact"
            )));
        }
    })
}

/// What the planner maximises (docs/method.md §4, §7).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Objective {
    /// The sum of the visited cells' scores (S, or the scores given).
    #[default]
    Score,
    /// The information the route's readings bring: the expected reduction of the dynamic
    /// field model's posterior variance over every sensor of the condition modality, as a
    /// share of the field's total (non-additive: planned with marginal gains). Cells are
    /// eligible when their reading would reduce it; S is still computed and reported.
    Information,
    /// Both: a route is worth `(1 − w)·ΣS/ΣS_all + w·I` with `I` the information share above,
    /// `ΣS/ΣS_all` its cells' share of the field's total score and `w` the `[planner]
    /// information_weight` (non-additive through `I`: planned with marginal gains).
    Hybrid,
}

/// The model-based estimate of a reconstruction.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Estimator {
    /// Kriging of changes ([`gleaner_kriging::estimate_change`]): each sensor's last known
    /// reading plus its change since, estimated from the changes its neighbours are known to
    /// have made over (part of) that interval; exactly the last value carried forward when no
    /// neighbour's change is known. A sensor never read gets the kriging of levels (ordinary).
    /// The default: the dynamic model did not beat it on the tuning years (docs/evaluation/).
    #[default]
    Changes,
    /// Space-time kriging of levels (residuals from each sensor's mean) from every sensor's
    /// latest known reading: ordinary ([`Mean::Unknown`]) or simple ([`Mean::Known`]).
    Levels(Mean),
    /// The dynamic field model ([`gleaner_kriging::DynamicModel`]): a learned, shrunk
    /// covariance of levels between sensors with AR(1) dynamics of the deviations, run as a
    /// Kalman filter over every reading known in the window [`dynamic_window_s`](crate::dynamic_window_s) before the
    /// estimation time. Where the model cannot be fitted ([`Estimator::resolve`](Estimator::resolve)) kriging of
    /// changes answers instead.
    Dynamic,
}

impl Estimator {
    /// Every estimator, in the order they are listed.
    pub const ALL: [Self; 4] = [
        Self::Dynamic,
        Self::Changes,
        Self::Levels(Mean::Unknown),
        Self::Levels(Mean::Known),
    ];

    /// Its name in requests and documents: `dynamic` (the dynamic field model), `changes`
    /// (kriging of changes), `levels` (ordinary kriging of levels) or `simple` (simple kriging
    /// of levels).
    pub fn name(self) -> &'static str {
        match self {
            Self::Dynamic => "dynamic",
            Self::Changes => "changes",
            Self::Levels(Mean::Unknown) => "levels",
            Self::Levels(Mean::Known) => "simple",
        }
    }
}

impl FromStr for Estimator {
    type Err = AppError;

    fn from_str(s: &str) -> Result<Self, AppError> {
        Self::ALL
            .into_iter()
            .find(|e| e.name() == s)
            .ok_or_else(|| {
                AppError::Invalid(format!(
                    "estimator {:?}: expected dynamic, changes, levels or simple",
                    gleaner_ingest::shorten(s)
                ))
            })
    }
}

impl Objective {
    /// Every objective, the default first.
    pub const ALL: [Self; 3] = [Self::Score, Self::Information, Self::Hybrid];

    /// Its name in settings and requests: `score`, `information` or `hybrid`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Score => "score",
            Self::Information => "information",
            Self::Hybrid => "hybrid",
        }
    }
}

impl FromStr for Objective {
    type Err = AppError;

    fn from_str(s: &str) -> Result<Self, AppError> {
        Self::ALL
            .into_iter()
            .find(|o| o.name() == s)
            .ok_or_else(|| {
                AppError::Invalid(format!(
                    "objective {:?}: expected score, information or hybrid",
                    gleaner_ingest::shorten(s)
                ))
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::settings::EnergyPreset;

    #[test]
    fn every_choice_parses_back_from_its_name_and_others_are_refused() {
        for e in Estimator::ALL {
            assert_eq!(e.name().parse::<Estimator>().expect("estimator"), e);
        }
        for p in EnergyPreset::ALL {
            assert_eq!(p.name().parse::<EnergyPreset>().expect("preset"), p);
        }
        for o in Objective::ALL {
            assert_eq!(o.name().parse::<Objective>().expect("objective"), o);
        }
        assert!("entropy".parse::<Objective>().is_err());
        let e = "kriging"
            .parse::<Estimator>()
            .expect_err("unknown")
            .to_string();
        assert!(
            e.contains("expected dynamic, changes, levels or simple"),
            "{e}"
        );
        let p = "huge"
            .parse::<EnergyPreset>()
            .expect_err("unknown")
            .to_string();
        assert!(p.contains("expected paper or large-pack"), "{p}");
    }
}
