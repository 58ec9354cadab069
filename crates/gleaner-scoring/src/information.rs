//! The information objective (docs/method.md §7, "Information"): a route is worth the
//! expected reduction of the dynamic field model's posterior variance that its readings
//! bring, summed over *every* sensor of the condition modality (not only those read), as a
//! share of the field's total posterior variance at the mission time. Correlated cells share
//! information, so the value of a set of cells is not the sum of their values: the planner
//! maximises it with marginal gains ([`gleaner_mission::plan_sorties_valued`]).

use gleaner_field::{Modality, SensorId, UnixSeconds};
use gleaner_kriging::{DynamicModel, FieldFilter};
use gleaner_store::Store;

use crate::dynamic::dynamic_window_s;
use crate::error::{AppError, Result};
use crate::knowledge::{History, Knowledge, known_until};
use crate::project::Project;
use crate::reconstruct::{per_sensor, run_filter};

/// The information a set of cells brings at one time: the filter's posterior given every
/// reading known then, and each cell's sensors as positions in the model.
pub struct CellInformation<'m> {
    filter: FieldFilter<'m>,
    cells: Vec<Vec<usize>>,
    /// The field's total posterior variance before the flight, unit² (> 0).
    total: f64,
    /// The hybrid objective's blend: each cell's share of the field's total score, and the
    /// weight on information ([`CellInformation::blended`]).
    blend: Option<(Vec<f64>, f64)>,
}

impl<'m> CellInformation<'m> {
    /// The filter of `model` (fitted on the project's sensors, in their order) run over the
    /// `modality` readings known at `at` (seconds), from [`dynamic_window_s`] before: those
    /// `history` admits, and a sensor's later ones up to its last recorded collection
    /// (`k.last_collected`, as scoring counts them); `k`'s cells name the sensors a visit
    /// reads.
    pub fn at<S: Store>(
        project: &Project<S>,
        k: &Knowledge,
        history: History,
        modality: &Modality,
        model: &'m DynamicModel,
        at: UnixSeconds,
    ) -> Result<Self> {
        let sensors = project.sensors()?;
        if sensors.len() != model.len() || sensors.len() != k.sensors.len() {
            return Err(AppError::Invalid(format!(
                "the field model has {} sensors, the project {}",
                model.len(),
                sensors.len()
            )));
        }
        let ids: Vec<SensorId> = sensors.iter().map(|s| s.id.clone()).collect();
        if ids.iter().zip(&k.sensors).any(|(a, b)| *a != b.id) {
            return Err(AppError::Invalid(
                "the field model's sensors are not the field's".into(),
            ));
        }
        let start = at.saturating_sub(dynamic_window_s(model)).max(history.from);
        let batch = project.store().readings_for(Some(modality), start..=at)?;
        let mut columns = per_sensor(&ids, &batch);
        for ((times, values), last) in columns.iter_mut().zip(&k.last_collected) {
            let cut = known_until(at, history.until, *last);
            let (kept_t, kept_v): (Vec<UnixSeconds>, Vec<f64>) = times
                .iter()
                .zip(values.iter())
                .filter(|(t, _)| **t <= cut)
                .map(|(t, v)| (*t, *v))
                .unzip();
            (*times, *values) = (kept_t, kept_v);
        }
        let mut filter = None;
        run_filter(model, &columns, start, &[at], |_, f| {
            filter = Some(f.clone())
        });
        let filter = filter.unwrap_or_else(|| model.filter(at as f64));
        let total = filter.total_variance();
        if !(total.is_finite() && total > 0.0) {
            return Err(AppError::Invalid(format!(
                "the field model leaves no {modality} variance to reduce at the mission time"
            )));
        }
        Ok(Self {
            filter,
            cells: k.field.cells().iter().map(|c| c.sensors.clone()).collect(),
            total,
            blend: None,
        })
    }

    /// The hybrid objective's worth: `(1 − weight)·ΣS/ΣS_all + weight·I` with `scores` the
    /// cells' S in field order (negative or non-finite counted as 0) and `weight` in [0, 1];
    /// all scores 0 leaves the information alone.
    pub fn blended(mut self, scores: &[f64], weight: f64) -> Self {
        let clean = |s: f64| if s.is_finite() { s.max(0.0) } else { 0.0 };
        let total: f64 = scores.iter().map(|&s| clean(s)).sum();
        let shares = if total > 0.0 {
            scores.iter().map(|&s| clean(s) / total).collect()
        } else {
            vec![0.0; scores.len()]
        };
        let weight = if total > 0.0 {
            weight.clamp(0.0, 1.0)
        } else {
            1.0
        };
        self.blend = Some((shares, weight));
        self
    }

    /// The route's worth (in [0, 1]) of reading every sensor of `cells` (positions in field
    /// order): the share of the field's posterior variance it would remove, blended with the
    /// cells' share of the total score under the hybrid objective.
    pub fn value(&self, cells: &[usize]) -> f64 {
        let sensors: Vec<usize> = cells
            .iter()
            .filter_map(|&c| self.cells.get(c))
            .flatten()
            .copied()
            .collect();
        let info = (self.filter.information(&sensors) / self.total).clamp(0.0, 1.0);
        match &self.blend {
            None => info,
            Some((shares, w)) => {
                let score: f64 = cells.iter().filter_map(|&c| shares.get(c)).sum();
                (1.0 - w) * score + w * info
            }
        }
    }

    /// Every cell's value alone, in field order.
    pub fn singletons(&self) -> Vec<f64> {
        (0..self.cells.len()).map(|c| self.value(&[c])).collect()
    }
}
