//! One-dimensional minimisation and root refinement used for the optimal speeds.

use crate::error::EnergyError;

/// The result of a one-dimensional minimisation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Minimum {
    /// The minimiser, in the unit of the search variable.
    pub x: f64,
    /// The function value at `x`.
    pub value: f64,
    /// Number of function evaluations used.
    pub evaluations: usize,
}

/// Minimises `f` over `[lo, hi]` with Brent's method (golden-section steps safeguarding
/// parabolic interpolation), stopping when the bracket around the minimum is narrower than
/// about `2·x_tol` (plus a few ulps of `x`).
///
/// `f` should be unimodal on the interval; otherwise a local minimum is returned. Non-finite
/// function values are treated as +infinity. At most 500 iterations are made.
///
/// ```
/// use gleaner_energy::minimise::brent_minimise;
/// let m = brent_minimise(|x| (x - 2.0f64).powi(2) + 1.0, 0.0, 5.0, 1e-9).unwrap();
/// assert!((m.x - 2.0).abs() < 1e-6);
/// assert!((m.value - 1.0).abs() < 1e-12);
/// ```
///
/// # Errors
/// [`EnergyError::InvalidInterval`] if `lo`, `hi` are not finite with `lo < hi`;
/// [`EnergyError::InvalidParameter`] if `x_tol` is not finite and > 0.
pub fn brent_minimise<F: FnMut(f64) -> f64>(
    mut f: F,
    lo: f64,
    hi: f64,
    x_tol: f64,
) -> Result<Minimum, EnergyError> {
    interval(lo, hi)?;
    crate::error::positive("x tolerance", x_tol)?;
    let mut eval = |x: f64| {
        let y = f(x);
        if y.is_nan() { f64::INFINITY } else { y }
    };
    let golden = 0.5 * (3.0 - 5.0f64.sqrt());
    let (mut a, mut b) = (lo, hi);
    let mut x = a + golden * (b - a);
    let (mut w, mut v) = (x, x);
    let mut fx = eval(x);
    let (mut fw, mut fv) = (fx, fx);
    let mut evaluations = 1;
    let mut d: f64 = 0.0;
    let mut e: f64 = 0.0;
    for _ in 0..500 {
        let m = 0.5 * (a + b);
        let tol = x_tol + 4.0 * f64::EPSILON * x.abs();
        let t2 = 2.0 * tol;
        if (x - m).abs() <= t2 - 0.5 * (b - a) {
            break;
        }
        let mut use_golden = true;
        if e.abs() > tol {
            // Parabola through (v, fv), (w, fw), (x, fx).
            let r = (x - w) * (fx - fv);
            let mut q = (x - v) * (fx - fw);
            let mut p = (x - v) * q - (x - w) * r;
            q = 2.0 * (q - r);
            if q > 0.0 {
                p = -p;
            } else {
                q = -q;
            }
            let e_prev = e;
            if p.abs() < (0.5 * q * e_prev).abs() && p > q * (a - x) && p < q * (b - x) {
                e = d;
                d = p / q;
                let u = x + d;
                if (u - a) < t2 || (b - u) < t2 {
                    d = if x < m { tol } else { -tol };
                }
                use_golden = false;
            }
        }
        if use_golden {
            e = if x < m { b - x } else { a - x };
            d = golden * e;
        }
        let u = if d.abs() >= tol {
            x + d
        } else if d > 0.0 {
            x + tol
        } else {
            x - tol
        };
        let fu = eval(u);
        evaluations += 1;
        if fu <= fx {
            if u < x {
                b = x;
            } else {
                a = x;
            }
            v = w;
            fv = fw;
            w = x;
            fw = fx;
            x = u;
            fx = fu;
        } else {
            if u < x {
                a = u;
            } else {
                b = u;
            }
            if fu <= fw || w == x {
                v = w;
                fv = fw;
                w = u;
                fw = fu;
            } else if fu <= fv || v == x || v == w {
                v = u;
                fv = fu;
            }
        }
    }
    Ok(Minimum {
        x,
        value: fx,
        evaluations,
    })
}

/// Checks that `lo`, `hi` are finite with `lo < hi`.
fn interval(lo: f64, hi: f64) -> Result<(), EnergyError> {
    if lo.is_finite() && hi.is_finite() && lo < hi {
        Ok(())
    } else {
        Err(EnergyError::InvalidInterval { lo, hi })
    }
}

/// Minimises `f` over `[lo, hi]` robustly: scans `samples` evenly spaced points (at least 3),
/// then runs [`brent_minimise`] on the two grid intervals around the best sample. This finds
/// the global minimum of any function whose minimum basin is wider than the grid spacing.
///
/// # Errors
/// As [`brent_minimise`].
pub fn scan_then_brent<F: FnMut(f64) -> f64>(
    mut f: F,
    lo: f64,
    hi: f64,
    samples: usize,
    x_tol: f64,
) -> Result<Minimum, EnergyError> {
    interval(lo, hi)?;
    let n = samples.max(3);
    let step = (hi - lo) / (n - 1) as f64;
    let at = |i: usize| if i + 1 == n { hi } else { lo + step * i as f64 };
    let mut best = (0, f64::INFINITY);
    for i in 0..n {
        let y = f(at(i));
        if y < best.1 {
            best = (i, y);
        }
    }
    let a = at(best.0.saturating_sub(1));
    let b = at((best.0 + 1).min(n - 1));
    let mut m = brent_minimise(&mut f, a, b, x_tol)?;
    m.evaluations += n;
    // Brent never evaluates the interval ends; keep a better grid sample if there is one.
    if best.1 < m.value {
        m.x = at(best.0);
        m.value = best.1;
    }
    Ok(m)
}

/// Refines a stationary point of a smooth function from its derivative `g`: if `g` changes sign
/// from negative to positive within `half_width` of `x`, bisects that bracket to full floating
/// point precision and returns the root; otherwise returns `x` unchanged.
pub(crate) fn polish_stationary<G: Fn(f64) -> f64>(g: G, x: f64, half_width: f64) -> f64 {
    let (mut a, mut b) = (x - half_width, x + half_width);
    if !(g(a) < 0.0 && g(b) > 0.0) {
        return x;
    }
    for _ in 0..200 {
        let m = 0.5 * (a + b);
        if m <= a || m >= b {
            break;
        }
        if g(m) < 0.0 {
            a = m;
        } else {
            b = m;
        }
    }
    0.5 * (a + b)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(f: fn(f64) -> f64, lo: f64, hi: f64, expected_x: f64) {
        let m = brent_minimise(f, lo, hi, 1e-9).unwrap();
        assert!(
            (m.x - expected_x).abs() < 1e-6 * (1.0 + expected_x.abs()),
            "brent: got {} expected {}",
            m.x,
            expected_x
        );
        let s = scan_then_brent(f, lo, hi, 50, 1e-9).unwrap();
        assert!(
            (s.x - expected_x).abs() < 1e-6 * (1.0 + expected_x.abs()),
            "scan: got {}",
            s.x
        );
    }

    #[test]
    fn known_minima() {
        check(|x| (x - 2.0).powi(2), 0.0, 5.0, 2.0);
        check(|x| x.cos(), 0.0, 6.0, std::f64::consts::PI);
        check(|x| x + 1.0 / x, 0.1, 10.0, 1.0);
        check(|x| (x - 1e-3).abs(), -1.0, 1.0, 1e-3);
        // Monotone: minimum at the interval end.
        check(|x| x, 0.0, 1.0, 0.0);
        check(|x| -x, 0.0, 1.0, 1.0);
    }

    #[test]
    fn scan_finds_global_minimum_of_multimodal_function() {
        // Local minimum near 1, global near 4.
        let f = |x: f64| (x - 1.0).powi(2) * (x - 4.0).powi(2) + 0.1 * (x - 4.0).powi(2);
        let m = scan_then_brent(f, 0.0, 5.0, 64, 1e-9).unwrap();
        assert!((m.x - 4.0).abs() < 1e-6, "{}", m.x);
    }

    #[test]
    fn rejects_bad_intervals() {
        assert!(brent_minimise(|x| x, 1.0, 1.0, 1e-9).is_err());
        assert!(brent_minimise(|x| x, 0.0, f64::NAN, 1e-9).is_err());
        assert!(brent_minimise(|x| x, 0.0, 1.0, 0.0).is_err());
        assert!(scan_then_brent(|x| x, 2.0, 1.0, 10, 1e-9).is_err());
    }

    #[test]
    fn polish_finds_root_to_full_precision() {
        let g = |x: f64| x - std::f64::consts::E;
        let r = polish_stationary(g, 2.7, 0.1);
        assert!((r - std::f64::consts::E).abs() < 1e-14);
        // No sign change: unchanged.
        assert_eq!(polish_stationary(g, 1.0, 0.1), 1.0);
    }
}
