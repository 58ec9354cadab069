//! Field geometry for gleaner.
//!
//! This crate is the pure base of the workspace: it knows positions, sensors, modalities and the
//! square cell grid, and nothing about files, databases or command lines.
//!
//! - [`LatLon`] is a WGS84 position in degrees (note the field order: latitude first; wire
//!   formats such as GeoJSON use `[lon, lat]` and convert explicitly).
//! - [`TransverseMercator`] projects WGS84 to metres: [`TransverseMercator::utm`] gives UTM
//!   zones (so CAF's EPSG:26911 coordinates are accepted), [`TransverseMercator::local`] gives
//!   the local east/north frame, in metres, centred on a reference point, that all planning uses.
//! - [`Sensor`], [`SensorId`] and [`Modality`] describe the network.
//! - [`Field`] cuts the plane into square cells of a given side, keeps the non-empty ones and
//!   their neighbours (docs/method.md §1).
//!
//! ```
//! use gleaner_field::{Field, FieldConfig, LatLon, Sensor, SensorId};
//! let sensors = vec![
//!     Sensor::new(SensorId::new("a").unwrap(), LatLon::new(46.7788, -117.0867).unwrap()),
//!     Sensor::new(SensorId::new("b").unwrap(), LatLon::new(46.7790, -117.0860).unwrap()),
//! ];
//! let base = LatLon::new(46.7785, -117.0870).unwrap();
//! let field = Field::build(&sensors, base, &FieldConfig::with_cell_size(40.0)).unwrap();
//! assert_eq!(field.cells().len(), 2);
//! ```
#![deny(missing_docs)]

mod error;
mod grid;
mod projection;
mod sensor;
pub mod time;

pub use error::{FieldError, Short};
pub use grid::{
    Cell, CellId, CellIndex, Field, FieldConfig, Neighbours, cell_size_from_half_angle,
    cell_size_from_link_range,
};
pub use projection::{LatLon, LocalPoint, TransverseMercator, utm_zone_for};
pub use sensor::{Modality, Sensor, SensorId};

/// A point in time: whole seconds since 1970-01-01T00:00:00Z (UTC). All of gleaner's core uses
/// this one time scale; files with local times are converted at ingest.
pub type UnixSeconds = i64;
