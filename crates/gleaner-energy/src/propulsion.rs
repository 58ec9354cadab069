//! Rotary-wing propulsion power in level flight (Zeng, Xu & Zhang, "Energy minimization for
//! wireless communication with rotary-wing UAV", IEEE TWC 18(4), 2019, eq. (12)).

use crate::error::{EnergyError, non_negative, positive};
use crate::minimise::{polish_stationary, scan_then_brent};

/// Physical parameters of a rotary-wing UAV (the symbols of Zeng et al. 2019, Table I).
///
/// [`Airframe::default`] is the paper's Table I airframe.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Airframe {
    /// Aircraft weight W, newtons (default 20 N).
    pub weight_n: f64,
    /// Air density rho, kg/m³ (default 1.225 kg/m³).
    pub air_density_kg_m3: f64,
    /// Rotor radius R, metres (default 0.4 m).
    pub rotor_radius_m: f64,
    /// Rotor disc area A, m² (default 0.503 m² = π·0.4²).
    pub rotor_disc_area_m2: f64,
    /// Blade angular velocity Omega, rad/s (default 300 rad/s).
    pub blade_angular_velocity_rad_s: f64,
    /// Tip speed of the rotor blade U_tip, m/s (default 120 m/s = Omega·R).
    pub tip_speed_mps: f64,
    /// Rotor solidity s, dimensionless (default 0.05).
    pub rotor_solidity: f64,
    /// Fuselage drag ratio d0, dimensionless (default 0.6).
    pub fuselage_drag_ratio: f64,
    /// Incremental correction factor to induced power k, dimensionless (default 0.1).
    pub induced_power_correction: f64,
    /// Profile drag coefficient delta_p, dimensionless (default 0.012).
    pub profile_drag_coefficient: f64,
}

impl Default for Airframe {
    fn default() -> Self {
        Self {
            weight_n: 20.0,
            air_density_kg_m3: 1.225,
            rotor_radius_m: 0.4,
            rotor_disc_area_m2: 0.503,
            blade_angular_velocity_rad_s: 300.0,
            tip_speed_mps: 120.0,
            rotor_solidity: 0.05,
            fuselage_drag_ratio: 0.6,
            induced_power_correction: 0.1,
            profile_drag_coefficient: 0.012,
        }
    }
}

impl Airframe {
    /// Checks every parameter: all finite and > 0, except d0 and k which may be 0.
    ///
    /// # Errors
    /// [`EnergyError::InvalidParameter`] naming the first offending parameter.
    pub fn validate(&self) -> Result<(), EnergyError> {
        positive("weight W (N)", self.weight_n)?;
        positive("air density rho (kg/m³)", self.air_density_kg_m3)?;
        positive("rotor radius R (m)", self.rotor_radius_m)?;
        positive("rotor disc area A (m²)", self.rotor_disc_area_m2)?;
        positive(
            "blade angular velocity Omega (rad/s)",
            self.blade_angular_velocity_rad_s,
        )?;
        positive("tip speed U_tip (m/s)", self.tip_speed_mps)?;
        positive("rotor solidity s", self.rotor_solidity)?;
        non_negative("fuselage drag ratio d0", self.fuselage_drag_ratio)?;
        non_negative("induced power correction k", self.induced_power_correction)?;
        positive(
            "profile drag coefficient delta_p",
            self.profile_drag_coefficient,
        )?;
        Ok(())
    }

    /// Blade profile power in hover P0 = (delta_p/8)·rho·s·A·Omega³·R³, watts.
    pub fn blade_profile_power_w(&self) -> f64 {
        self.profile_drag_coefficient / 8.0
            * self.air_density_kg_m3
            * self.rotor_solidity
            * self.rotor_disc_area_m2
            * self.blade_angular_velocity_rad_s.powi(3)
            * self.rotor_radius_m.powi(3)
    }

    /// Induced power in hover Pi = (1+k)·W^(3/2)/sqrt(2·rho·A), watts.
    pub fn induced_power_w(&self) -> f64 {
        (1.0 + self.induced_power_correction) * self.weight_n.powf(1.5)
            / (2.0 * self.air_density_kg_m3 * self.rotor_disc_area_m2).sqrt()
    }

    /// Mean rotor induced velocity in hover v0 = sqrt(W/(2·rho·A)), m/s.
    pub fn mean_induced_velocity_mps(&self) -> f64 {
        (self.weight_n / (2.0 * self.air_density_kg_m3 * self.rotor_disc_area_m2)).sqrt()
    }

    /// Parasite drag factor d0·rho·s·A, kg/m, so that parasite power is ½·(d0·rho·s·A)·V³ W.
    pub fn parasite_drag_factor_kg_m(&self) -> f64 {
        self.fuselage_drag_ratio
            * self.air_density_kg_m3
            * self.rotor_solidity
            * self.rotor_disc_area_m2
    }

    /// The derived power parameters (P0, Pi, v0, U_tip, d0·rho·s·A) of this airframe.
    pub fn power_parameters(&self) -> PowerParameters {
        PowerParameters {
            blade_profile_power_w: self.blade_profile_power_w(),
            induced_power_w: self.induced_power_w(),
            mean_induced_velocity_mps: self.mean_induced_velocity_mps(),
            tip_speed_mps: self.tip_speed_mps,
            parasite_drag_factor_kg_m: self.parasite_drag_factor_kg_m(),
            weight_n: self.weight_n,
        }
    }
}

/// The five numbers that fully determine the level-flight power curve; set them directly to
/// model an airframe whose P0, Pi and v0 were measured rather than derived.
///
/// [`PowerParameters::default`] is derived from [`Airframe::default`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PowerParameters {
    /// Blade profile power in hover P0, watts (> 0).
    pub blade_profile_power_w: f64,
    /// Induced power in hover Pi, watts (>= 0).
    pub induced_power_w: f64,
    /// Mean rotor induced velocity in hover v0, m/s (> 0).
    pub mean_induced_velocity_mps: f64,
    /// Rotor blade tip speed U_tip, m/s (> 0).
    pub tip_speed_mps: f64,
    /// Parasite drag factor d0·rho·s·A, kg/m (>= 0).
    pub parasite_drag_factor_kg_m: f64,
    /// Aircraft weight W, newtons (> 0). Not part of P(V); used only for the optional climb
    /// energy (potential energy W·h).
    pub weight_n: f64,
}

impl Default for PowerParameters {
    fn default() -> Self {
        Airframe::default().power_parameters()
    }
}

/// A speed that minimises an energy criterion, with the power and energy per metre there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OptimalSpeed {
    /// Horizontal speed, m/s.
    pub speed_mps: f64,
    /// Propulsion power at that speed, W.
    pub power_w: f64,
    /// Propulsion energy per metre travelled at that speed, J/m (infinite at 0 m/s).
    pub energy_per_metre_j: f64,
}

/// Absolute tolerance on the optimal speeds before derivative polishing, m/s.
const SPEED_TOL_MPS: f64 = 1e-9;
/// Grid samples scanned before Brent's method (robustness against non-unimodal curves).
const SPEED_SCAN_SAMPLES: usize = 128;

/// A validated level-flight power curve P(V), W, of a rotary-wing UAV:
///
/// P(V) = P0·(1 + 3V²/U_tip²) + Pi·(sqrt(1 + V⁴/(4·v0⁴)) − V²/(2·v0²))^(1/2) + ½·d0·rho·s·A·V³
///
/// ```
/// use gleaner_energy::{Airframe, PowerModel};
/// let model = PowerModel::from_airframe(&Airframe::default()).unwrap();
/// assert!((model.hover_power_w() - 168.484).abs() < 1e-3);
/// let best = model.max_endurance();
/// assert!((best.speed_mps - 10.2117).abs() < 1e-3);
/// ```
///
/// [`PowerModel::default`] is the curve of [`Airframe::default`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PowerModel {
    p: PowerParameters,
}

impl PowerModel {
    /// The power curve of `airframe`.
    ///
    /// # Errors
    /// [`EnergyError::InvalidParameter`] if the airframe does not validate.
    pub fn from_airframe(airframe: &Airframe) -> Result<Self, EnergyError> {
        airframe.validate()?;
        Self::from_parameters(airframe.power_parameters())
    }

    /// The power curve with P0, Pi, v0, U_tip and d0·rho·s·A given directly.
    ///
    /// # Errors
    /// [`EnergyError::InvalidParameter`] unless P0, v0, U_tip, W are finite and > 0 and Pi,
    /// d0·rho·s·A finite and >= 0.
    pub fn from_parameters(p: PowerParameters) -> Result<Self, EnergyError> {
        positive("blade profile power P0 (W)", p.blade_profile_power_w)?;
        non_negative("induced power Pi (W)", p.induced_power_w)?;
        positive(
            "mean induced velocity v0 (m/s)",
            p.mean_induced_velocity_mps,
        )?;
        positive("tip speed U_tip (m/s)", p.tip_speed_mps)?;
        non_negative(
            "parasite drag factor d0·rho·s·A (kg/m)",
            p.parasite_drag_factor_kg_m,
        )?;
        positive("weight W (N)", p.weight_n)?;
        Ok(Self { p })
    }

    /// The parameters of this curve.
    pub fn parameters(&self) -> &PowerParameters {
        &self.p
    }

    /// Blade profile power in hover P0, W.
    pub fn blade_profile_power_w(&self) -> f64 {
        self.p.blade_profile_power_w
    }

    /// Induced power in hover Pi, W.
    pub fn induced_power_w(&self) -> f64 {
        self.p.induced_power_w
    }

    /// Mean rotor induced velocity in hover v0, m/s.
    pub fn mean_induced_velocity_mps(&self) -> f64 {
        self.p.mean_induced_velocity_mps
    }

    /// Aircraft weight W, N.
    pub fn weight_n(&self) -> f64 {
        self.p.weight_n
    }

    /// Propulsion power in level flight at horizontal speed `speed_mps` (m/s), in W. The curve
    /// is symmetric: a negative speed gives the power at its magnitude.
    pub fn power_w(&self, speed_mps: f64) -> f64 {
        let p = &self.p;
        let v2 = speed_mps * speed_mps;
        let blade =
            p.blade_profile_power_w * (1.0 + 3.0 * v2 / (p.tip_speed_mps * p.tip_speed_mps));
        let induced = p.induced_power_w * self.induced_factor(v2);
        let parasite = 0.5 * p.parasite_drag_factor_kg_m * v2 * speed_mps.abs();
        blade + induced + parasite
    }

    /// (sqrt(1 + x²) − x)^(1/2) with x = V²/(2·v0²), computed as 1/sqrt(sqrt(1+x²)+x) to avoid
    /// cancellation at high speed.
    fn induced_factor(&self, v2: f64) -> f64 {
        let v0 = self.p.mean_induced_velocity_mps;
        let x = v2 / (2.0 * v0 * v0);
        1.0 / (x.hypot(1.0) + x).sqrt()
    }

    /// dP/dV at `speed_mps` >= 0, W/(m/s).
    pub fn power_derivative(&self, speed_mps: f64) -> f64 {
        let p = &self.p;
        let v = speed_mps;
        let v0 = p.mean_induced_velocity_mps;
        let x = v * v / (2.0 * v0 * v0);
        let s = x.hypot(1.0);
        let blade = p.blade_profile_power_w * 6.0 * v / (p.tip_speed_mps * p.tip_speed_mps);
        let induced = -p.induced_power_w * 0.5 / ((s + x).sqrt() * s) * v / (v0 * v0);
        let parasite = 1.5 * p.parasite_drag_factor_kg_m * v * v;
        blade + induced + parasite
    }

    /// Hover power P(0) = P0 + Pi, W.
    pub fn hover_power_w(&self) -> f64 {
        self.p.blade_profile_power_w + self.p.induced_power_w
    }

    /// Propulsion energy per metre travelled at `speed_mps` (m/s): P(V)/V, J/m. Infinite at 0.
    pub fn energy_per_metre_j(&self, speed_mps: f64) -> f64 {
        let v = speed_mps.abs();
        if v == 0.0 {
            f64::INFINITY
        } else {
            self.power_w(v) / v
        }
    }

    fn optimal(&self, speed_mps: f64) -> OptimalSpeed {
        OptimalSpeed {
            speed_mps,
            power_w: self.power_w(speed_mps),
            energy_per_metre_j: self.energy_per_metre_j(speed_mps),
        }
    }

    /// The maximum-endurance speed: argmin over V >= 0 of P(V), with P there (the speed that
    /// keeps the UAV airborne longest per joule). Found by a grid scan plus Brent's method on
    /// an interval proven to contain the minimum, then polished on dP/dV = 0.
    pub fn max_endurance(&self) -> OptimalSpeed {
        let p = &self.p;
        // Beyond either bound P(V) > P0 + Pi = P(0), so the minimum lies below both.
        let mut hi = f64::INFINITY;
        if p.parasite_drag_factor_kg_m > 0.0 {
            hi = hi.min((2.0 * p.induced_power_w / p.parasite_drag_factor_kg_m).cbrt());
        }
        hi = hi.min(p.tip_speed_mps * (p.induced_power_w / (3.0 * p.blade_profile_power_w)).sqrt());
        let hi = 1.01 * hi;
        if !(hi > 0.0 && hi.is_finite()) {
            return self.optimal(0.0);
        }
        let speed = match scan_then_brent(
            |v| self.power_w(v),
            0.0,
            hi,
            SPEED_SCAN_SAMPLES,
            SPEED_TOL_MPS,
        ) {
            Ok(m) => m.x,
            Err(_) => 0.0,
        };
        let speed = polish_stationary(|v| self.power_derivative(v), speed, 1e-6 * (1.0 + speed));
        let best = self.optimal(speed.max(0.0));
        // V = 0 is always a stationary point; keep hover if it is really the minimum.
        if self.hover_power_w() < best.power_w {
            self.optimal(0.0)
        } else {
            best
        }
    }

    /// The maximum-range speed: argmin over V > 0 of P(V)/V, with the energy per metre there
    /// (the speed that covers the most distance per joule). Same method as
    /// [`PowerModel::max_endurance`], polished on d(P/V)/dV = 0.
    pub fn max_range(&self) -> OptimalSpeed {
        let p = &self.p;
        let reference = {
            let v = self.max_endurance().speed_mps;
            if v > 0.0 {
                v
            } else {
                p.mean_induced_velocity_mps
            }
        };
        let e_ref = self.energy_per_metre_j(reference);
        // P(V)/V >= P0/V, >= 3·P0·V/U_tip² and >= ½·d0·rho·s·A·V², so outside [lo, hi] the
        // energy per metre exceeds e_ref.
        let lo = p.blade_profile_power_w / e_ref;
        let mut hi = e_ref * p.tip_speed_mps * p.tip_speed_mps / (3.0 * p.blade_profile_power_w);
        if p.parasite_drag_factor_kg_m > 0.0 {
            hi = hi.min((2.0 * e_ref / p.parasite_drag_factor_kg_m).sqrt());
        }
        let (lo, hi) = (0.99 * lo, 1.01 * hi);
        let speed = match scan_then_brent(
            |v| self.energy_per_metre_j(v),
            lo,
            hi,
            SPEED_SCAN_SAMPLES,
            SPEED_TOL_MPS,
        ) {
            Ok(m) => m.x,
            Err(_) => reference,
        };
        let g = |v: f64| self.power_derivative(v) * v - self.power_w(v);
        let speed = polish_stationary(g, speed, 1e-6 * (1.0 + speed));
        self.optimal(speed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn rel_close(a: f64, b: f64, rel: f64) -> bool {
        (a - b).abs() <= rel * b.abs().max(1e-300)
    }

    #[test]
    fn paper_airframe_rounded_values() {
        // docs/method.md §3 values, quoted to 2 decimals.
        let m = PowerModel::default();
        assert!((m.blade_profile_power_w() - 79.86).abs() < 0.005);
        assert!((m.induced_power_w() - 88.63).abs() < 0.005);
        assert!((m.hover_power_w() - 168.48).abs() < 0.005);
        assert!((m.mean_induced_velocity_mps() - 4.03).abs() < 0.005);
        let e = m.max_endurance();
        assert!((e.speed_mps - 10.21).abs() < 0.005);
        assert!((e.power_w - 126.0).abs() < 0.05);
        let r = m.max_range();
        assert!((r.speed_mps - 18.29).abs() < 0.005);
        assert!((r.energy_per_metre_j - 8.83).abs() < 0.005);
    }

    #[test]
    fn derivative_matches_finite_differences() {
        let m = PowerModel::default();
        for v in [0.0, 0.5, 3.0, 10.0, 18.0, 40.0] {
            let h = 1e-5;
            let fd = (m.power_w(v + h) - m.power_w((v - h).abs())) / (2.0 * h);
            assert!(
                (m.power_derivative(v) - fd).abs() < 1e-5 * (1.0 + fd.abs()),
                "v={v}"
            );
        }
    }

    #[test]
    fn direct_parameters_equal_derived() {
        let a = Airframe::default();
        let direct = PowerModel::from_parameters(a.power_parameters()).unwrap();
        assert_eq!(direct, PowerModel::from_airframe(&a).unwrap());
    }

    #[test]
    fn invalid_parameters_are_rejected_with_value() {
        let a = Airframe {
            weight_n: -1.0,
            ..Airframe::default()
        };
        let err = PowerModel::from_airframe(&a).unwrap_err();
        assert!(err.to_string().contains("-1"), "{err}");
        let p = PowerParameters {
            mean_induced_velocity_mps: f64::NAN,
            ..PowerParameters::default()
        };
        assert!(PowerModel::from_parameters(p).is_err());
    }

    #[test]
    fn no_parasite_drag_still_has_optima() {
        let p = PowerParameters {
            parasite_drag_factor_kg_m: 0.0,
            ..PowerParameters::default()
        };
        let m = PowerModel::from_parameters(p).unwrap();
        let e = m.max_endurance();
        let r = m.max_range();
        assert!(e.speed_mps > 0.0 && r.speed_mps > e.speed_mps);
        assert!(m.power_derivative(e.speed_mps).abs() < 1e-6);
    }

    #[test]
    fn zero_induced_power_hovers_cheapest() {
        let p = PowerParameters {
            induced_power_w: 0.0,
            ..PowerParameters::default()
        };
        let m = PowerModel::from_parameters(p).unwrap();
        assert_eq!(m.max_endurance().speed_mps, 0.0);
        assert!(m.max_range().speed_mps > 0.0);
    }

    proptest! {
        #[test]
        fn power_positive_and_optima_are_minima(
            w in 5.0f64..200.0,
            d0 in 0.0f64..2.0,
            k in 0.0f64..0.5,
            v in 0.0f64..60.0,
        ) {
            let a = Airframe { weight_n: w, fuselage_drag_ratio: d0, induced_power_correction: k, ..Airframe::default() };
            let m = PowerModel::from_airframe(&a).unwrap();
            prop_assert!(m.power_w(v) > 0.0);
            let e = m.max_endurance();
            prop_assert!(e.power_w <= m.power_w(v) * (1.0 + 1e-12));
            let r = m.max_range();
            if v > 0.0 {
                prop_assert!(r.energy_per_metre_j <= m.energy_per_metre_j(v) * (1.0 + 1e-12));
            }
            prop_assert!(r.speed_mps >= e.speed_mps);
            prop_assert!(rel_close(r.power_w / r.speed_mps, r.energy_per_metre_j, 1e-12));
        }

        #[test]
        fn explicit_parameters_optima_beat_a_fine_grid(
            p0 in 1.0f64..500.0,
            pi in 0.0f64..500.0,
            v0 in 0.5f64..20.0,
            u_tip in 50.0f64..250.0,
            drag in 0.0f64..0.2,
        ) {
            let p = PowerParameters {
                blade_profile_power_w: p0,
                induced_power_w: pi,
                mean_induced_velocity_mps: v0,
                tip_speed_mps: u_tip,
                parasite_drag_factor_kg_m: drag,
                weight_n: 20.0,
            };
            let m = PowerModel::from_parameters(p).unwrap();
            let e = m.max_endurance();
            let r = m.max_range();
            for i in 1..=2000 {
                let v = 0.05 * i as f64;
                prop_assert!(m.power_w(v) > 0.0);
                prop_assert!(e.power_w <= m.power_w(v) * (1.0 + 1e-12), "P({v}) below P(V_e = {})", e.speed_mps);
                prop_assert!(r.energy_per_metre_j <= m.energy_per_metre_j(v) * (1.0 + 1e-12), "P/V at {v} below {}", r.speed_mps);
            }
        }
    }
}
