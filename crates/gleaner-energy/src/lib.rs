//! Energy model for gleaner (docs/method.md §3): how much battery a data-collection sortie costs.
//!
//! Pure: no IO. The main types:
//!
//! - [`Airframe`] (physical parameters, the paper's Table I by default) and [`PowerModel`], the
//!   rotary-wing level-flight power curve P(V) of Zeng, Xu & Zhang (IEEE TWC 2019), W, with
//!   hover power, the maximum-endurance speed (argmin P) and maximum-range speed
//!   (argmin P/V). P0, Pi and v0 can be given directly through [`PowerParameters`].
//! - [`LinkConfig`], [`DataLogging`], [`SensorBacklog`] and [`HoverConfig`]: OFDMA upload rates,
//!   pending data and the hover time at a cell.
//! - [`EnergyConfig`] (plain fields with units; presets [`EnergyConfig::paper`] and
//!   [`EnergyConfig::large_pack`]) and [`MissionEnergyModel`], which gives the
//!   [`MissionEnergy`] breakdown (E_t, E_h, E_c, E_r, per leg and per cell, budget,
//!   utilisation, feasibility) of a route, and the additive travel / service costs an
//!   orienteering planner needs.
//!
//! Planning (which cells, in which order, in how many sorties) lives in `gleaner-mission`.
//!
//! ```
//! use gleaner_energy::{CellVisit, EnergyConfig, MissionEnergyModel};
//! use gleaner_field::LocalPoint;
//!
//! let model = MissionEnergyModel::new(&EnergyConfig::paper()).unwrap();
//! let power = model.power_model();
//! assert!((power.hover_power_w() - 168.484).abs() < 1e-3); // W
//! assert!((model.cruise_speed_mps() - 10.2117).abs() < 1e-3); // maximum-endurance speed, m/s
//!
//! let base = LocalPoint::new(0.0, 0.0);
//! let route = [CellVisit { centre: LocalPoint::new(60.0, 100.0), hover_s: 30.0 }];
//! let energy = model.breakdown(base, &route).unwrap();
//! let sum = energy.travel_j + energy.hover_j + energy.comm_j + energy.return_j;
//! assert!((energy.total_j - sum).abs() < 1e-9); // J
//! assert!(energy.feasible && energy.budget_j == 66_500.0);
//! ```
#![deny(missing_docs)]

mod air;
mod config;
mod error;
pub mod flight;
mod link;
pub mod minimise;
mod mission;
mod propulsion;
pub mod wind;

pub use config::{
    Battery, CruiseSpeed, EnergyConfig, LinearEnergy, PAPER_CELL_SIZE_M, PowerSource,
    VerticalConfig,
};
pub use error::EnergyError;
pub use flight::{
    ALTITUDE_STEP_M, COORDINATE_STEP_DEG, CommandedFlight, FlightEnergyModel, HOLD_STEP_S,
    SPEED_STEP_MPS, flight_altitude_m, flight_degrees, flight_hold_s, flight_point,
    flight_position, flight_speed_mps,
};
pub use link::{DataLogging, HoverConfig, LinkConfig, SensorBacklog};
pub use mission::{
    CellEnergy, CellService, CellVisit, LegEnergy, MissionEnergy, MissionEnergyModel,
    TravelCostMatrix, UP_TO_SAMPLES, path_length_m,
};
pub use propulsion::{Airframe, OptimalSpeed, PowerModel, PowerParameters};
pub use wind::{
    GustySortie, STRONGEST_WIND_CAP_MPS, STRONGEST_WIND_STEP_MPS, Wind, WindLeg, WindTolerance,
    strongest_wind, strongest_wind_from,
};
