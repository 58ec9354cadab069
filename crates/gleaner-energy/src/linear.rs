//! The plain linear energy model, for comparison with studies that cost a sortie as
//! `j_per_m · distance + j_per_cell · cells`: J per metre flown plus J per cell visited, with
//! no propulsion curve, no hover-time dependence and no climb/descent term.
//!
//! [`MissionEnergyModel::with_linear`](crate::MissionEnergyModel::with_linear) plugs it into the
//! mission model so that every planner and breakdown uses these costs.

use gleaner_field::LocalPoint;

use crate::error::{EnergyError, non_negative};
use crate::mission::distance_m;

/// Largest accepted coefficient, J/m or J/cell (a 1 GJ battery would be spent in one metre).
pub const LINEAR_MAX_J: f64 = 1e9;

/// Linear sortie energy: `j_per_m` J per metre flown plus `j_per_cell` J per cell visited.
///
/// ```
/// use gleaner_energy::LinearEnergy;
/// let l = LinearEnergy { j_per_m: 10.0, j_per_cell: 5_000.0 };
/// assert_eq!(l.route_energy_j(1_200.0, 3), 27_000.0); // J
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinearEnergy {
    /// Energy per metre flown, J/m (≥ 0).
    pub j_per_m: f64,
    /// Energy per cell visited (hover and collection together), J (≥ 0).
    pub j_per_cell: f64,
}

impl LinearEnergy {
    /// Checks both coefficients are finite, ≥ 0 and ≤ [`LINEAR_MAX_J`].
    ///
    /// # Errors
    /// [`EnergyError::InvalidParameter`] naming the offending coefficient.
    pub fn validate(&self) -> Result<(), EnergyError> {
        for (name, v) in [
            ("linear energy per metre (J/m)", self.j_per_m),
            ("linear energy per cell (J)", self.j_per_cell),
        ] {
            non_negative(name, v)?;
            if v > LINEAR_MAX_J {
                return Err(EnergyError::InvalidParameter {
                    name,
                    value: v,
                    expected: "at most 1e9",
                });
            }
        }
        Ok(())
    }

    /// Travel energy of `distance_m` metres, J.
    pub fn travel_j(&self, distance_m: f64) -> f64 {
        self.j_per_m * distance_m
    }

    /// Energy of a sortie flying `distance_m` metres and visiting `cells` cells, J.
    pub fn route_energy_j(&self, distance_m: f64, cells: usize) -> f64 {
        self.travel_j(distance_m) + self.j_per_cell * cells as f64
    }

    /// Length of the closed tour `base` -> `stops[0]` -> ... -> `stops[k-1]` -> `base`, metres
    /// (0 for no stops).
    pub fn tour_length_m(base: LocalPoint, stops: &[LocalPoint]) -> f64 {
        if stops.is_empty() {
            return 0.0;
        }
        let mut previous = base;
        let mut total = 0.0;
        for &p in stops.iter().chain(std::iter::once(&base)) {
            total += distance_m(&previous, &p);
            previous = p;
        }
        total
    }

    /// Energy of the closed tour from `base` through `stops` and back, J.
    pub fn tour_energy_j(&self, base: LocalPoint, stops: &[LocalPoint]) -> f64 {
        self.route_energy_j(Self::tour_length_m(base, stops), stops.len())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    const L: LinearEnergy = LinearEnergy {
        j_per_m: 12.5,
        j_per_cell: 4_000.0,
    };

    #[test]
    fn hand_computed_values() {
        // 3-4-5 triangle: base (0,0) -> (30,0) -> (30,40) -> base = 30 + 40 + 50 = 120 m.
        let stops = [LocalPoint::new(30.0, 0.0), LocalPoint::new(30.0, 40.0)];
        let base = LocalPoint::new(0.0, 0.0);
        assert_eq!(LinearEnergy::tour_length_m(base, &stops), 120.0);
        // 12.5 J/m · 120 m + 2 · 4000 J = 1500 + 8000 = 9500 J.
        assert_eq!(L.tour_energy_j(base, &stops), 9_500.0);
        assert_eq!(L.route_energy_j(0.0, 0), 0.0);
        assert_eq!(L.travel_j(8.0), 100.0);
        assert_eq!(L.tour_energy_j(base, &[]), 0.0);
    }

    #[test]
    fn validation_names_the_coefficient() {
        assert!(L.validate().is_ok());
        let bad = LinearEnergy { j_per_m: -1.0, ..L };
        let msg = bad.validate().unwrap_err().to_string();
        assert!(msg.contains("per metre"), "{msg}");
        let bad = LinearEnergy {
            j_per_cell: f64::NAN,
            ..L
        };
        let msg = bad.validate().unwrap_err().to_string();
        assert!(msg.contains("per cell"), "{msg}");
        let bad = LinearEnergy {
            j_per_cell: 2e9,
            ..L
        };
        assert!(bad.validate().is_err());
    }

    proptest! {
        /// Energy never decreases when the route gets longer or visits more cells.
        #[test]
        fn monotone_in_route_length(
            j_per_m in 0.0..1e3f64,
            j_per_cell in 0.0..1e5f64,
            d in 0.0..1e5f64,
            extra in 0.0..1e5f64,
            cells in 0usize..50,
            more in 0usize..5,
        ) {
            let l = LinearEnergy { j_per_m, j_per_cell };
            prop_assert!(l.route_energy_j(d + extra, cells) >= l.route_energy_j(d, cells));
            prop_assert!(l.route_energy_j(d, cells + more) >= l.route_energy_j(d, cells));
        }

        /// Appending a stop to a tour never lowers its energy (triangle inequality).
        #[test]
        fn appending_a_stop_never_lowers_energy(
            pts in proptest::collection::vec((-1e3..1e3f64, -1e3..1e3f64), 0..8),
            extra in (-1e3..1e3f64, -1e3..1e3f64),
        ) {
            let base = LocalPoint::new(0.0, 0.0);
            let stops: Vec<LocalPoint> = pts.iter().map(|&(e, n)| LocalPoint::new(e, n)).collect();
            let mut longer = stops.clone();
            longer.push(LocalPoint::new(extra.0, extra.1));
            prop_assert!(L.tour_energy_j(base, &longer) + 1e-6 >= L.tour_energy_j(base, &stops));
        }
    }
}
