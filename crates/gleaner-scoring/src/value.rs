//! gleaner's own planning term beside the paper's S: the expected reduction of the field's
//! posterior variance from visiting each cell (`[utility] variance_weight`, η).
//!
//! The field model (each sensor's mean; a separable exponential space-time covariance with a
//! temporal nugget, [`gleaner_kriging`]) is fitted on everything known at the mission time
//! for the condition modality; each cell's age is the time since its stalest sensor was
//! last collected. [`gleaner_kriging::variance_reduction`] gives every cell's greedy marginal
//! gain; divided by the largest gain it lies in [0, 1], like F, U and R, and the planner
//! routes by `S + η·V`. V knows what S does not: which cells the others already explain
//! (distance, correlation) and how much a reading of a given age still tells.

use gleaner_field::{Modality, UnixSeconds};
use gleaner_kriging::{MAX_VARIANCE_CELLS, variance_reduction};
use gleaner_store::Store;

use crate::error::Result;
use crate::knowledge::Knowledge;
use crate::project::Project;
use crate::reconstruct::fit_model;

/// Every cell's variance-reduction gain at `t` (seconds), in field order, divided by the
/// largest one (so in [0, 1]); or why it cannot be computed (no soil-moisture modality, too
/// little history to fit the field model, more than [`MAX_VARIANCE_CELLS`] cells), which the
/// caller reports as a warning and plans by S alone.
pub fn variance_gains<S: Store>(
    project: &Project<S>,
    k: &Knowledge,
    t: UnixSeconds,
) -> Result<std::result::Result<Vec<f64>, String>> {
    let cells = k.field.cells();
    if cells.len() > MAX_VARIANCE_CELLS {
        return Ok(Err(format!(
            "{} cells: the variance term handles at most {MAX_VARIANCE_CELLS}; planned by S alone",
            cells.len()
        )));
    }
    let Some(name) = crate::condition::condition_modality(project.settings(), &k.modalities) else {
        return Ok(Err(
            "no soil-moisture modality for the variance term; planned by S alone".into(),
        ));
    };
    let modality = match Modality::new(&name) {
        Ok(m) => m,
        Err(e) => return Ok(Err(format!("modality {name:?}: {e}; planned by S alone"))),
    };
    let model = match fit_model(project, &modality, t) {
        Ok((model, _)) => model,
        Err(e) => return Ok(Err(format!("variance term: {e}; planned by S alone"))),
    };
    let centres: Vec<[f64; 2]> = cells.iter().map(|c| [c.centre.e, c.centre.n]).collect();
    let weights: Vec<f64> = cells.iter().map(|c| c.sensors.len() as f64).collect();
    let ages: Vec<Option<f64>> = cells
        .iter()
        .map(|c| {
            c.sensors
                .iter()
                .filter_map(|&s| k.last_collected.get(s).copied().flatten())
                .min()
                .map(|l| (t - l).max(0) as f64)
        })
        .collect();
    let gains = match variance_reduction(&model.covariance, &centres, &ages, &weights) {
        Ok(g) => g,
        Err(e) => return Ok(Err(format!("variance term: {e}; planned by S alone"))),
    };
    Ok(Ok(normalised(&gains)))
}

/// `gains` divided by the largest (all zeros when none is positive).
pub(crate) fn normalised(gains: &[f64]) -> Vec<f64> {
    let top = gains
        .iter()
        .copied()
        .filter(|g| g.is_finite())
        .fold(0.0f64, f64::max);
    gains
        .iter()
        .map(|g| {
            if top > 0.0 && g.is_finite() {
                (g / top).clamp(0.0, 1.0)
            } else {
                0.0
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::normalised;

    #[test]
    fn gains_are_scaled_into_the_unit_interval() {
        assert_eq!(normalised(&[2.0, 1.0, 0.0]), vec![1.0, 0.5, 0.0]);
        assert_eq!(normalised(&[0.0, 0.0]), vec![0.0, 0.0]);
        assert_eq!(normalised(&[f64::NAN, 4.0]), vec![0.0, 1.0]);
    }
}
