//! Configuration of the utility score (docs/method.md §2).

use crate::UtilityError;
use gleaner_field::UnixSeconds;

/// Seconds in a day.
pub const DAY_S: f64 = 86_400.0;

/// Which past data the redundancy and anomaly terms look at.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum HistoryWindow {
    /// Every point at or before the scoring time t (the default).
    #[default]
    All,
    /// Only points in [t − seconds, t]; `seconds` in s, > 0.
    Last {
        /// Window length, s.
        seconds: i64,
    },
}

impl HistoryWindow {
    /// The first timestamp (s) inside the window when scoring at `t` (s).
    pub fn start(self, t: UnixSeconds) -> UnixSeconds {
        match self {
            HistoryWindow::All => UnixSeconds::MIN,
            HistoryWindow::Last { seconds } => t.saturating_sub(seconds),
        }
    }
}

/// Per-modality weights (omega for redundancy, phi for anomaly).
#[derive(Debug, Clone, PartialEq, Default)]
pub enum ModalityWeights {
    /// Equal weights over the modalities a cell has (the default).
    #[default]
    Equal,
    /// One non-negative weight per modality position; for each cell they are renormalised to
    /// sum to 1 over the modalities the cell has (dimensionless).
    Given(Vec<f64>),
}

impl ModalityWeights {
    /// The weights of modalities flagged in `present`, renormalised to sum to 1 (entries for
    /// absent modalities are 0). All zero if no modality is present or all present weights are 0.
    pub fn normalised(&self, present: &[bool]) -> Vec<f64> {
        let raw: Vec<f64> = present
            .iter()
            .enumerate()
            .map(|(m, &p)| match (p, self) {
                (false, _) => 0.0,
                (true, ModalityWeights::Equal) => 1.0,
                (true, ModalityWeights::Given(w)) => w.get(m).copied().unwrap_or(0.0),
            })
            .collect();
        let total: f64 = raw.iter().sum();
        if total > 0.0 {
            raw.iter().map(|w| w / total).collect()
        } else {
            vec![0.0; present.len()]
        }
    }

    /// Weighted sum of per-modality terms (`None` = the cell lacks the modality), with the
    /// weights renormalised over the present modalities.
    pub fn combine(&self, terms: &[Option<f64>]) -> f64 {
        let present: Vec<bool> = terms.iter().map(Option::is_some).collect();
        let w = self.normalised(&present);
        terms
            .iter()
            .zip(&w)
            .map(|(t, w)| t.unwrap_or(0.0) * w)
            .sum()
    }

    fn validate(&self, name: &str, n_modalities: usize) -> Result<(), UtilityError> {
        if let ModalityWeights::Given(w) = self {
            if w.len() != n_modalities {
                return Err(UtilityError::Config(format!(
                    "{name}: {} weights for {n_modalities} modalities",
                    w.len()
                )));
            }
            if let Some(bad) = w.iter().find(|x| !(x.is_finite() && **x >= 0.0)) {
                return Err(UtilityError::Config(format!(
                    "{name}: weight {bad} is not a finite non-negative number"
                )));
            }
        }
        Ok(())
    }
}

/// How the anomaly term enters the score.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum AnomalyForm {
    /// A_i as defined (>= 0, unbounded, in standard deviations): the paper's form, the default.
    #[default]
    Raw,
    /// 1 − exp(−A_i/kappa), in [0, 1); kappa > 0 in standard deviations.
    Bounded {
        /// Scale, standard deviations.
        kappa: f64,
    },
}

impl AnomalyForm {
    /// Applies the form to a raw anomaly value.
    pub fn apply(self, a: f64) -> f64 {
        match self {
            AnomalyForm::Raw => a,
            AnomalyForm::Bounded { kappa } => -(-a / kappa).exp_m1(),
        }
    }

    /// A short label for outputs: `raw` or `bounded(kappa=…)`.
    pub fn label(self) -> String {
        match self {
            AnomalyForm::Raw => "raw".to_string(),
            AnomalyForm::Bounded { kappa } => format!("bounded(kappa={kappa})"),
        }
    }
}

/// How the four terms combine into S.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ScoreForm {
    /// S = alpha·F + beta·A + gamma·U − delta·R (docs/method.md §2, the paper's; the default).
    #[default]
    Additive,
    /// S = alpha·F·max(0, 1 + beta·A + gamma·U − delta·R): freshness gated by the cell's
    /// value per unit of staleness. A just-collected cell (F = 0) is worth nothing however
    /// anomalous, uncertain or unique it is, and a cell that matters twice as much is
    /// revisited about twice as often once F grows about linearly with age (a long
    /// half-life). In the additive form the static part of S (A, U, R change little after a
    /// visit) outweighs F's range of [0, 1], and the same cells win every mission
    /// (docs/method-improvement.md). alpha = 0 makes every cell worth 0 in this form.
    Gated,
}

impl ScoreForm {
    /// A short label for outputs: `additive` or `gated`.
    pub fn label(self) -> &'static str {
        match self {
            ScoreForm::Additive => "additive",
            ScoreForm::Gated => "gated",
        }
    }
}

/// What the anomaly A_i^m measures the latest value against.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum AnomalyReference {
    /// The cell's own past: `|x̂(t*) − mu| / (sigma + epsilon)` over the cell series (docs/method.md §2,
    /// the paper's form; the default).
    #[default]
    OwnHistory,
    /// The cell's neighbours: the residual `r(t) = x̂_i(t) − median_j x̂_j(t)` over the
    /// neighbour cells `j` that have a value at `t` (at least `min_neighbours` of them), then
    /// the same z-score on the residual series: its latest point against the mean and sd of
    /// its earlier points. Weather moves a cell and its neighbours together and cancels; a
    /// local event (a leak, a dry patch) does not. Computed from the history (not from the
    /// incremental state).
    Neighbours {
        /// Fewest neighbours with a value at a timestamp for the residual to exist (>= 1).
        min_neighbours: usize,
    },
}

impl AnomalyReference {
    /// A short label for outputs: `own-history` or `neighbours(min=…)`.
    pub fn label(self) -> String {
        match self {
            AnomalyReference::OwnHistory => "own-history".to_string(),
            AnomalyReference::Neighbours { min_neighbours } => {
                format!("neighbours(min={min_neighbours})")
            }
        }
    }
}

/// Every parameter of S_i = alpha·F_i + beta·A_i + gamma·U_i − delta·R_i.
///
/// Defaults (docs/method.md §2): all weights 1, freshness half-life 3 days (259,200 s), all history,
/// `min_overlap` 10, `epsilon` 1e-6, equal modality weights, raw anomaly.
#[derive(Debug, Clone, PartialEq)]
pub struct UtilityConfig {
    /// Weight of freshness F (dimensionless, default 1).
    pub alpha: f64,
    /// Weight of anomaly A (dimensionless, default 1).
    pub beta: f64,
    /// Weight of model uncertainty U (dimensionless, default 1).
    pub gamma: f64,
    /// Weight of redundancy R (dimensionless, default 1; subtracted).
    pub delta: f64,
    /// Freshness half-life, s (default 3 days = 259,200 s); lambda = ln 2 / half-life.
    pub freshness_half_life_s: f64,
    /// History window for R and A (default all history).
    pub window: HistoryWindow,
    /// Fewest common timestamps for a correlation to count (default 10).
    pub min_overlap: usize,
    /// Added to the standard deviation in A, in the modality's unit (default 1e-6, > 0).
    pub epsilon: f64,
    /// omega: modality weights of the redundancy (default equal).
    pub redundancy_weights: ModalityWeights,
    /// phi: modality weights of the anomaly (default equal).
    pub anomaly_weights: ModalityWeights,
    /// Raw or bounded anomaly in the score (default raw).
    pub anomaly_form: AnomalyForm,
    /// What the anomaly compares the latest value with (default the cell's own history).
    pub anomaly_reference: AnomalyReference,
    /// How the terms combine into S (default additive, the paper's).
    pub score_form: ScoreForm,
}

impl Default for UtilityConfig {
    fn default() -> Self {
        Self {
            alpha: 1.0,
            beta: 1.0,
            gamma: 1.0,
            delta: 1.0,
            freshness_half_life_s: 3.0 * DAY_S,
            window: HistoryWindow::All,
            min_overlap: 10,
            epsilon: 1e-6,
            redundancy_weights: ModalityWeights::Equal,
            anomaly_weights: ModalityWeights::Equal,
            anomaly_form: AnomalyForm::Raw,
            anomaly_reference: AnomalyReference::OwnHistory,
            score_form: ScoreForm::Additive,
        }
    }
}

impl UtilityConfig {
    /// The freshness decay rate lambda = ln 2 / half-life, in 1/s.
    pub fn lambda_per_s(&self) -> f64 {
        std::f64::consts::LN_2 / self.freshness_half_life_s
    }

    /// Checks every parameter for `n_modalities` modalities.
    pub fn validate(&self, n_modalities: usize) -> Result<(), UtilityError> {
        for (name, w) in [
            ("alpha", self.alpha),
            ("beta", self.beta),
            ("gamma", self.gamma),
            ("delta", self.delta),
        ] {
            if !w.is_finite() {
                return Err(UtilityError::Config(format!("{name} = {w} is not finite")));
            }
        }
        if !(self.freshness_half_life_s.is_finite() && self.freshness_half_life_s > 0.0) {
            return Err(UtilityError::Config(format!(
                "freshness half-life {} s must be positive",
                self.freshness_half_life_s
            )));
        }
        if let HistoryWindow::Last { seconds } = self.window
            && seconds <= 0
        {
            return Err(UtilityError::Config(format!(
                "history window {seconds} s must be positive"
            )));
        }
        if self.min_overlap < 2 {
            return Err(UtilityError::Config(format!(
                "min_overlap {} must be at least 2",
                self.min_overlap
            )));
        }
        if !(self.epsilon.is_finite() && self.epsilon > 0.0) {
            return Err(UtilityError::Config(format!(
                "epsilon {} must be finite and positive",
                self.epsilon
            )));
        }
        if let AnomalyForm::Bounded { kappa } = self.anomaly_form
            && !(kappa.is_finite() && kappa > 0.0)
        {
            return Err(UtilityError::Config(format!(
                "kappa {kappa} must be positive"
            )));
        }
        if let AnomalyReference::Neighbours { min_neighbours: 0 } = self.anomaly_reference {
            return Err(UtilityError::Config(
                "anomaly reference: min_neighbours must be at least 1".to_string(),
            ));
        }
        self.redundancy_weights.validate("omega", n_modalities)?;
        self.anomaly_weights.validate("phi", n_modalities)?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_renormalise_over_present_modalities() {
        assert_eq!(
            ModalityWeights::Equal.normalised(&[true, false, true]),
            vec![0.5, 0.0, 0.5]
        );
        let w = ModalityWeights::Given(vec![1.0, 2.0, 3.0]);
        assert_eq!(w.normalised(&[false, true, true]), vec![0.0, 0.4, 0.6]);
        assert_eq!(w.normalised(&[false, false, false]), vec![0.0; 3]);
        assert!((w.combine(&[Some(1.0), None, Some(2.0)]) - 1.75).abs() < 1e-12);
    }

    #[test]
    fn lambda_and_forms() {
        let c = UtilityConfig::default();
        assert!((c.lambda_per_s() - std::f64::consts::LN_2 / 259_200.0).abs() < 1e-20);
        let b = AnomalyForm::Bounded { kappa: 2.0 };
        assert!((b.apply(2.0) - (1.0 - (-1.0f64).exp())).abs() < 1e-12);
        assert_eq!(AnomalyForm::Raw.apply(7.5), 7.5);
        assert_eq!(b.label(), "bounded(kappa=2)");
    }

    #[test]
    fn invalid_configurations_are_rejected() {
        let bad = [
            UtilityConfig {
                freshness_half_life_s: 0.0,
                ..Default::default()
            },
            UtilityConfig {
                alpha: f64::NAN,
                ..Default::default()
            },
            UtilityConfig {
                min_overlap: 1,
                ..Default::default()
            },
            UtilityConfig {
                epsilon: 0.0,
                ..Default::default()
            },
            UtilityConfig {
                window: HistoryWindow::Last { seconds: 0 },
                ..Default::default()
            },
            UtilityConfig {
                anomaly_form: AnomalyForm::Bounded { kappa: -1.0 },
                ..Default::default()
            },
            UtilityConfig {
                redundancy_weights: ModalityWeights::Given(vec![1.0]),
                ..Default::default()
            },
            UtilityConfig {
                anomaly_weights: ModalityWeights::Given(vec![1.0, -1.0]),
                ..Default::default()
            },
        ];
        for c in bad {
            assert!(c.validate(2).is_err(), "{c:?} accepted");
        }
        assert!(UtilityConfig::default().validate(2).is_ok());
    }
}
