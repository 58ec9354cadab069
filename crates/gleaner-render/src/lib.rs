//! gleaner's figures: the mission map (the paper's Figure 1), the exploration overview, and
//! SVG to PNG with a bundled font.
//!
//! - [`mission_figure_svg`]: one mission over the field — cells coloured by the utility S with
//!   a colour bar and the formula with its weights, sensors, the route with direction arrows
//!   and visiting order, the dashed return leg, the base, coordinate ticks, a north arrow, a
//!   scale bar, a legend and the energy breakdown in kJ.
//! - [`exploration_map_svg`]: the exploration sorties on one map, one colour per sortie.
//! - [`reconstruction_map_svg`]: an estimated field and its uncertainty at one time, two
//!   panels side by side (viridis for the value, reversed magma for the posterior sd, each
//!   with a colour bar in the modality's unit), sensors read then told from those only
//!   estimated, the field's outline, scale bar and north arrow.
//! - [`line_chart_svg`] and [`interval_chart_svg`]: campaign report charts (a metric per
//!   strategy over time or budget; means with 95% intervals).
//! - [`files`]: a mission's file set (flight files, document, map) and the maps as files'
//!   bytes, for every adapter.
//! - [`svg_to_png`]: rasterises either with resvg, loading only the bundled DejaVu Sans
//!   ([`FONT_FAMILY`]), so output is the same on every machine; [`outline_text`] turns the
//!   text of a figure into outlines of that font for a vector file that needs no fonts.
//!
//! Inputs are the wire documents ([`FieldDoc`], [`MissionDoc`], [`ReconstructionMapDoc`]);
//! positions are WGS84 `[lon, lat]` degrees, projected here onto a local equirectangular
//! frame centred on the field's base station (metres east and north; north is up). That is accurate to well under
//! a pixel over a farm (a few km). Figures are sized in millimetres and laid out in points
//! (1 pt = 1/72 in) with the real advance widths of the bundled font; output is deterministic
//! (same input, same bytes).
//!
//! ```
//! use gleaner_render::{FigureOptions, example, mission_figure_svg, svg_to_png};
//!
//! let (field, mission) = (example::field(), example::mission());
//! let svg = mission_figure_svg(&field, &mission, &FigureOptions::default()).unwrap();
//! assert!(svg.contains("Mission 7"));
//! let png = svg_to_png(&svg, 400).unwrap();
//! assert_eq!(&png[1..4], b"PNG");
//! ```
#![deny(missing_docs)]

mod chart;
mod colour;
pub mod example;
mod exploration;
mod figure;
pub mod files;
mod font;
mod frame;
mod png;
mod reconstruction;
mod svg;
mod ticks;

pub use chart::{
    IntervalChart, IntervalRow, Line, LineChart, XAxis, interval_chart_svg, line_chart_svg,
};
pub use exploration::exploration_map_svg;
pub use figure::mission_figure_svg;
pub use files::{FileError, FileSet, ImageFormat};
pub use font::FONT_FAMILY;
pub use png::{MAX_PNG_SIDE_PX, outline_text, parse_svg, svg_to_png};
pub use reconstruction::reconstruction_map_svg;

/// The SVG parser used by [`parse_svg`] (resvg's), for inspecting parsed figures.
pub use resvg::usvg;

#[doc(no_inline)]
pub use gleaner_wire::docs::ReconstructionMapDoc;
#[doc(no_inline)]
pub use gleaner_wire::{FieldDoc, MissionDoc};

/// The full page width of a two-column paper, mm: the reconstruction map's usual width.
pub const FULL_WIDTH_MM: f64 = 178.0;

/// The PNG width, px, of a figure `width_mm` wide printed at `dpi` dots per inch (at least 1,
/// at most [`MAX_PNG_SIDE_PX`]).
pub fn png_width_px(width_mm: f64, dpi: f64) -> u32 {
    let px = (width_mm / 25.4 * dpi).round();
    if px.is_finite() {
        px.clamp(1.0, f64::from(MAX_PNG_SIDE_PX)) as u32
    } else {
        1
    }
}

/// What the map's coordinate ticks show.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Coordinates {
    /// Metres east and north of the base station.
    #[default]
    LocalMetres,
    /// WGS84 longitude and latitude, degrees.
    Degrees,
}

/// Size, type and labelling of a figure.
#[derive(Debug, Clone, PartialEq)]
pub struct FigureOptions {
    /// Width of the figure as printed, mm (85 ≈ one column of a two-column paper, 178 ≈ the
    /// full page width). The layout is made for this width: text keeps `font_pt` at it.
    pub width_mm: f64,
    /// Body text size at `width_mm`, pt (the title is 1 pt larger). At least 4.
    pub font_pt: f64,
    /// The map's coordinate ticks.
    pub coordinates: Coordinates,
    /// Title in place of the automatic one (mission id, kind and time); `Some("")` for
    /// none, e.g. when the paper's caption says it.
    pub title: Option<String>,
    /// Tallest the map itself may be, as a fraction of the figure width (a tall field is
    /// drawn narrower instead).
    pub max_map_aspect: f64,
}

impl Default for FigureOptions {
    fn default() -> Self {
        Self {
            width_mm: 85.0,
            font_pt: 7.0,
            coordinates: Coordinates::LocalMetres,
            title: None,
            max_map_aspect: 0.8,
        }
    }
}

/// Why a figure could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RenderError {
    /// A number in the input is NaN or infinite.
    #[error("{what} is not a finite number ({value})")]
    NonFinite {
        /// Which number (`cell x3y1 ring point 2 longitude`).
        what: String,
        /// Its value.
        value: f64,
    },
    /// A number in the input is outside the range a figure can use.
    #[error("{what} = {value} is out of range: {expected}")]
    OutOfRange {
        /// Which number.
        what: String,
        /// Its value.
        value: f64,
        /// The range it must be in.
        expected: &'static str,
    },
    /// An option is unusable.
    #[error("option {name} = {value} is invalid: {expected}")]
    InvalidOption {
        /// The option's field name in [`FigureOptions`] or the argument name.
        name: &'static str,
        /// Its value.
        value: f64,
        /// What it must be.
        expected: &'static str,
    },
    /// The SVG text could not be parsed.
    #[error("SVG cannot be parsed: {0}")]
    Svg(String),
    /// The PNG could not be produced.
    #[error("PNG cannot be produced: {0}")]
    Png(String),
}
