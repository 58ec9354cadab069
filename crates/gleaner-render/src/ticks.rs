//! Tick values at round numbers and their labels.

/// A step of 1, 2 or 5 times a power of ten, at least `raw` (> 0, finite).
pub(crate) fn nice_step(raw: f64) -> f64 {
    if !(raw.is_finite() && raw > 0.0) {
        return 1.0;
    }
    let mag = 10f64.powf(raw.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|m| m * mag)
        .find(|&s| s >= raw * (1.0 - 1e-9))
        .unwrap_or(10.0 * mag)
}

/// The multiples of `step` in [`lo`, `hi`] (at most 200; none if the inputs are unusable).
pub(crate) fn multiples(lo: f64, hi: f64, step: f64) -> Vec<f64> {
    if !(lo.is_finite() && hi.is_finite() && step.is_finite() && step > 0.0 && hi >= lo) {
        return Vec::new();
    }
    let eps = step * 1e-9;
    let first = ((lo - eps) / step).ceil();
    let last = ((hi + eps) / step).floor();
    if !(first.is_finite() && last.is_finite()) || last - first > 200.0 {
        return Vec::new();
    }
    let mut out = Vec::new();
    let mut k = first;
    while k <= last {
        out.push(k * step);
        k += 1.0;
    }
    out
}

/// Decimals needed to tell multiples of `step` apart.
pub(crate) fn decimals(step: f64) -> usize {
    if !(step.is_finite() && step > 0.0) {
        return 0;
    }
    let d = -(step.log10() + 1e-9).floor();
    d.clamp(0.0, 12.0) as usize
}

/// `v` with `decimals` decimals and a true minus sign (never "−0").
pub(crate) fn label(v: f64, decimals: usize) -> String {
    let s = format!("{v:.decimals$}");
    if s.trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        return s.trim_start_matches('-').to_string();
    }
    match s.strip_prefix('-') {
        Some(rest) => format!("\u{2212}{rest}"),
        None => s,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_are_round() {
        assert_eq!(nice_step(0.13), 0.2);
        assert_eq!(nice_step(170.0), 200.0);
        assert_eq!(nice_step(4.0), 5.0);
        assert_eq!(nice_step(1.0), 1.0);
        assert_eq!(nice_step(f64::NAN), 1.0);
    }

    #[test]
    fn multiples_cover_the_interval() {
        assert_eq!(multiples(-0.05, 0.41, 0.1).len(), 5);
        assert_eq!(multiples(0.0, 1.0, 0.5), vec![0.0, 0.5, 1.0]);
        assert!(multiples(0.0, 1e300, 1e-300).is_empty());
        assert!(multiples(1.0, 0.0, 0.1).is_empty());
    }

    #[test]
    fn labels_use_a_minus_sign() {
        assert_eq!(label(-0.2, decimals(0.1)), "\u{2212}0.2");
        assert_eq!(label(-0.0, 1), "0.0");
        assert_eq!(label(200.0, decimals(100.0)), "200");
        assert_eq!(decimals(0.002), 3);
        assert_eq!(decimals(0.5), 1);
        assert_eq!(decimals(50.0), 0);
    }
}
