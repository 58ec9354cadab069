//! Everything the energy model needs, as one plain configuration value with presets.

use crate::error::{EnergyError, non_negative, positive};
use crate::link::{DataLogging, HoverConfig, LinkConfig};
use crate::propulsion::{Airframe, PowerModel, PowerParameters};

/// Where the power curve comes from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PowerSource {
    /// Derive P0, Pi, v0 from the airframe's physical parameters.
    Airframe(Airframe),
    /// Use P0, Pi, v0, U_tip, d0·rho·s·A (and W) as given.
    Parameters(PowerParameters),
}

impl Default for PowerSource {
    fn default() -> Self {
        Self::Airframe(Airframe::default())
    }
}

impl PowerSource {
    /// The validated power curve.
    ///
    /// # Errors
    /// [`EnergyError::InvalidParameter`] for an invalid airframe or parameter set.
    pub fn power_model(&self) -> Result<PowerModel, EnergyError> {
        match self {
            Self::Airframe(a) => PowerModel::from_airframe(a),
            Self::Parameters(p) => PowerModel::from_parameters(*p),
        }
    }
}

/// The horizontal cruise speed between cells.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum CruiseSpeed {
    /// argmin P(V): the paper scenario's choice (default; 10.21 m/s for the default airframe).
    #[default]
    MaxEndurance,
    /// argmin P(V)/V: the least energy per metre (18.29 m/s for the default airframe).
    MaxRange,
    /// A fixed speed, m/s (> 0).
    Fixed(f64),
}

/// The battery and the share of it that planning may use.
///
/// Default: 70,000 J with a 5% reserve, so 66,500 J usable (the paper's budget).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Battery {
    /// Energy stored in a full pack, J.
    pub capacity_j: f64,
    /// Fraction of the capacity never planned (landing margin, ageing, wind), in [0, 1).
    pub reserve_fraction: f64,
}

impl Default for Battery {
    fn default() -> Self {
        Self {
            capacity_j: 70_000.0,
            reserve_fraction: 0.05,
        }
    }
}

impl Battery {
    /// A pack of `watt_hours` Wh (1 Wh = 3,600 J) with `reserve_fraction` kept in reserve.
    pub fn from_watt_hours(watt_hours: f64, reserve_fraction: f64) -> Self {
        Self {
            capacity_j: watt_hours * 3600.0,
            reserve_fraction,
        }
    }

    /// Usable budget B_usable = capacity·(1 − reserve), J.
    pub fn usable_j(&self) -> f64 {
        self.capacity_j * (1.0 - self.reserve_fraction)
    }

    /// Checks capacity > 0 and reserve in [0, 1).
    ///
    /// # Errors
    /// [`EnergyError::InvalidParameter`] naming the offending value.
    pub fn validate(&self) -> Result<(), EnergyError> {
        positive("battery capacity (J)", self.capacity_j)?;
        if !(self.reserve_fraction >= 0.0 && self.reserve_fraction < 1.0) {
            return Err(EnergyError::InvalidParameter {
                name: "battery reserve fraction",
                value: self.reserve_fraction,
                expected: "a number in [0, 1)",
            });
        }
        Ok(())
    }
}

/// Optional climb at take-off and descent at landing (docs/method.md §3: off by default).
///
/// A simple conservative model, not part of Zeng et al. 2019: climbing to the flight altitude h
/// at vertical speed v_c costs (P(0) + W·v_c)·h/v_c = P(0)·h/v_c + W·h (hover power plus the
/// potential energy gained); descending at v_d costs P(0)·h/v_d (no energy recovered). h is
/// [`LinkConfig::altitude_m`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VerticalConfig {
    /// Climb rate after take-off, m/s (default 2.5 m/s).
    pub climb_speed_mps: f64,
    /// Descent rate before landing, m/s (default 1.5 m/s).
    pub descent_speed_mps: f64,
}

impl Default for VerticalConfig {
    fn default() -> Self {
        Self {
            climb_speed_mps: 2.5,
            descent_speed_mps: 1.5,
        }
    }
}

/// Cell side of the paper scenario, metres.
pub const PAPER_CELL_SIZE_M: f64 = 40.0;

/// Every parameter of the mission energy model, with units. Plain fields, so an outer layer
/// can map it from a configuration file; [`crate::MissionEnergyModel::new`] validates it.
///
/// [`EnergyConfig::default`] is [`EnergyConfig::paper`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EnergyConfig {
    /// The propulsion power curve.
    pub power: PowerSource,
    /// Horizontal cruise speed between cells.
    pub cruise: CruiseSpeed,
    /// Battery capacity and reserve.
    pub battery: Battery,
    /// Radio link used while hovering (includes the flight altitude).
    pub link: LinkConfig,
    /// Default sensor logging (reading interval, size, buffer) for pending-data estimates.
    pub logging: DataLogging,
    /// Hover-time rule.
    pub hover: HoverConfig,
    /// Receiver / processing power P_rx while hovering at a cell, W (default 0.5 W).
    pub rx_power_w: f64,
    /// Climb and descent energy; `None` (default) leaves it out.
    pub vertical: Option<VerticalConfig>,
    /// A plain linear model instead of the physical one, for comparison with other studies
    /// (`None`, the default: the rotary-wing model).
    pub linear: Option<LinearEnergy>,
}

/// A plain linear energy model: a constant energy per metre flown and per cell visited
/// (whatever the hover time), replacing P(V)/V and (P(0) + P_rx)·hover_s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinearEnergy {
    /// Energy per metre flown, J/m.
    pub j_per_m: f64,
    /// Energy per cell visited (hover and collection), J.
    pub j_per_cell: f64,
}

impl Default for EnergyConfig {
    fn default() -> Self {
        Self::paper()
    }
}

impl EnergyConfig {
    /// The paper scenario (docs/method.md §3): Table I airframe, cruise at the maximum-endurance speed,
    /// 70,000 J pack with 5% reserve (66,500 J usable), hover = max(30 s, 30 s + t_comm),
    /// altitude 30 m, P_rx 0.5 W, no climb/descent energy. Cells are [`PAPER_CELL_SIZE_M`].
    pub fn paper() -> Self {
        Self {
            power: PowerSource::default(),
            cruise: CruiseSpeed::MaxEndurance,
            battery: Battery::default(),
            link: LinkConfig::default(),
            logging: DataLogging::default(),
            hover: HoverConfig {
                overhead_s: 30.0,
                min_hover_s: 30.0,
            },
            rx_power_w: 0.5,
            vertical: None,
            linear: None,
        }
    }

    /// The paper scenario with a larger pack: 77 Wh = 277,200 J with a 20% reserve
    /// (221,760 J usable), e.g. a 4S 5,200 mAh LiPo, same airframe.
    pub fn large_pack() -> Self {
        Self {
            battery: Battery::from_watt_hours(77.0, 0.20),
            ..Self::paper()
        }
    }

    /// Checks every part of the configuration.
    ///
    /// # Errors
    /// [`EnergyError::InvalidParameter`] naming the first offending parameter.
    pub fn validate(&self) -> Result<(), EnergyError> {
        self.power.power_model()?;
        if let CruiseSpeed::Fixed(v) = self.cruise {
            positive("fixed cruise speed (m/s)", v)?;
        }
        self.battery.validate()?;
        self.link.validate()?;
        self.logging.validate()?;
        self.hover.validate()?;
        non_negative("receiver power P_rx (W)", self.rx_power_w)?;
        if let Some(l) = &self.linear {
            positive("linear energy per metre (J/m)", l.j_per_m)?;
            non_negative("linear energy per cell (J)", l.j_per_cell)?;
        }
        if let Some(v) = &self.vertical {
            positive("climb speed (m/s)", v.climb_speed_mps)?;
            positive("descent speed (m/s)", v.descent_speed_mps)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets() {
        assert_eq!(EnergyConfig::default(), EnergyConfig::paper());
        assert!((EnergyConfig::paper().battery.usable_j() - 66_500.0).abs() < 1e-9);
        let big = EnergyConfig::large_pack();
        assert!((big.battery.capacity_j - 277_200.0).abs() < 1e-9);
        assert!((big.battery.usable_j() - 221_760.0).abs() < 1e-9);
        assert!(EnergyConfig::paper().validate().is_ok());
        assert!(big.validate().is_ok());
    }

    #[test]
    fn invalid_configs() {
        let c = EnergyConfig {
            cruise: CruiseSpeed::Fixed(0.0),
            ..EnergyConfig::paper()
        };
        assert!(c.validate().is_err());
        let c = EnergyConfig {
            battery: Battery {
                capacity_j: 1.0,
                reserve_fraction: 1.0,
            },
            ..EnergyConfig::paper()
        };
        assert!(c.validate().unwrap_err().to_string().contains("reserve"));
        let c = EnergyConfig {
            rx_power_w: -0.5,
            ..EnergyConfig::paper()
        };
        assert!(c.validate().is_err());
    }
}
