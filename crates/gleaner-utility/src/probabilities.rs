//! Validation of class probabilities supplied by the user's own model (docs/method.md §2: a file of
//! cell id -> p_1..p_K; parsing the file is the caller's job).

use std::collections::HashMap;

use crate::UtilityError;

/// Largest accepted deviation of a distribution's sum from 1.
pub const PROBABILITY_SUM_TOLERANCE: f64 = 1e-6;

/// Checks one distribution: `k` entries (K >= 2), each finite and >= 0, summing to 1 within
/// [`PROBABILITY_SUM_TOLERANCE`]. Returns the reason on failure.
pub(crate) fn check_distribution(p: &[f64], k: usize) -> Result<(), String> {
    if k < 2 {
        return Err(format!("need at least 2 classes, got {k}"));
    }
    if p.len() != k {
        return Err(format!(
            "{} probabilities, expected {k} like the other cells",
            p.len()
        ));
    }
    if let Some((c, v)) = p
        .iter()
        .enumerate()
        .find(|(_, v)| !(v.is_finite() && **v >= 0.0))
    {
        return Err(format!("probability of class {} is {v}", c + 1));
    }
    let sum: f64 = p.iter().sum();
    if (sum - 1.0).abs() > PROBABILITY_SUM_TOLERANCE {
        return Err(format!(
            "probabilities sum to {sum}, not 1 (tolerance 1e-6)"
        ));
    }
    Ok(())
}

/// Validates user-supplied per-cell class probabilities against the field's cell ids and
/// returns them in the order of `cell_ids`.
///
/// Checks: every row's cell is known and appears once; every cell in `cell_ids` has a row; the
/// same K >= 2 everywhere; entries finite and non-negative; each row sums to 1 within 1e-6.
/// Errors name the offending cell.
///
/// ```
/// use gleaner_utility::validate_probabilities;
/// let ids = ["x0y0".to_string(), "x1y0".to_string()];
/// let rows = vec![("x1y0".to_string(), vec![0.2, 0.8]), ("x0y0".to_string(), vec![1.0, 0.0])];
/// let p = validate_probabilities(&ids, &rows).unwrap();
/// assert_eq!(p[0], vec![1.0, 0.0]);
/// let bad = vec![("x0y0".to_string(), vec![0.5, 0.6]), ("x1y0".to_string(), vec![0.5, 0.5])];
/// assert!(validate_probabilities(&ids, &bad).unwrap_err().to_string().contains("x0y0"));
/// ```
pub fn validate_probabilities(
    cell_ids: &[String],
    rows: &[(String, Vec<f64>)],
) -> Result<Vec<Vec<f64>>, UtilityError> {
    let position: HashMap<&str, usize> = cell_ids
        .iter()
        .enumerate()
        .map(|(k, id)| (id.as_str(), k))
        .collect();
    let mut out: Vec<Option<Vec<f64>>> = vec![None; cell_ids.len()];
    let k = rows.first().map_or(0, |r| r.1.len());
    for (id, p) in rows {
        let err = |reason: String| UtilityError::Probabilities {
            cell: id.clone(),
            reason,
        };
        let Some(&pos) = position.get(id.as_str()) else {
            return Err(err("unknown cell".to_string()));
        };
        if out[pos].is_some() {
            return Err(err("listed more than once".to_string()));
        }
        check_distribution(p, k).map_err(err)?;
        out[pos] = Some(p.clone());
    }
    out.into_iter()
        .zip(cell_ids)
        .map(|(p, id)| {
            p.ok_or_else(|| UtilityError::Probabilities {
                cell: id.clone(),
                reason: "no probabilities given for this cell".to_string(),
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(rows: &[(&str, &[f64])], expected_error: Option<&str>) {
        let ids: Vec<String> = ["a", "b"].iter().map(|s| s.to_string()).collect();
        let rows: Vec<(String, Vec<f64>)> = rows
            .iter()
            .map(|(c, p)| (c.to_string(), p.to_vec()))
            .collect();
        match (validate_probabilities(&ids, &rows), expected_error) {
            (Ok(p), None) => assert_eq!(p.len(), 2),
            (Err(e), Some(want)) => assert!(e.to_string().contains(want), "{e} lacks {want:?}"),
            (got, want) => panic!("got {got:?}, wanted error {want:?}"),
        }
    }

    #[test]
    fn validation() {
        check(&[("a", &[0.5, 0.5]), ("b", &[0.0, 1.0])], None);
        check(&[("a", &[0.5, 0.5 + 1e-7]), ("b", &[0.0, 1.0])], None);
        check(&[("a", &[0.5, 0.5])], Some("cell b: no probabilities"));
        check(
            &[("a", &[0.5, 0.5]), ("c", &[0.5, 0.5])],
            Some("cell c: unknown"),
        );
        check(
            &[("a", &[0.5, 0.5]), ("a", &[0.5, 0.5])],
            Some("cell a: listed more than once"),
        );
        check(
            &[("a", &[0.5, 0.5]), ("b", &[0.2, 0.3, 0.5])],
            Some("cell b: 3 probabilities, expected 2"),
        );
        check(
            &[("a", &[1.5, -0.5]), ("b", &[0.5, 0.5])],
            Some("cell a: probability of class 2 is -0.5"),
        );
        check(
            &[("a", &[0.5, 0.4]), ("b", &[0.5, 0.5])],
            Some("cell a: probabilities sum to 0.9"),
        );
        check(
            &[("a", &[f64::NAN, 1.0]), ("b", &[0.5, 0.5])],
            Some("cell a: probability of class 1 is NaN"),
        );
        check(
            &[("a", &[1.0]), ("b", &[1.0])],
            Some("cell a: need at least 2 classes"),
        );
    }
}
