//! A mission's file set and the maps as files' bytes, for the CLI's `export`, `replan`,
//! `map-exploration` and `reconstruct --map`, the demo and the HTTP API's downloads alike:
//! the flight files (`gleaner-wire`, each read back and priced by its writer), the
//! `gleaner.mission` document and the figures. Pure: the caller writes or serves the bytes.

use gleaner_wire::docs::ReconstructionMapDoc;
use gleaner_wire::{ExportError, FieldDoc, MissionDoc, WpmlOptions};

use crate::{FULL_WIDTH_MM, FigureOptions, RenderError};

/// Width of a mission's or the exploration's PNG map, px.
pub const MAP_PNG_WIDTH_PX: u32 = 1600;

/// The reconstruction map's PNG resolution, dots per inch (at [`FULL_WIDTH_MM`]).
pub const RECONSTRUCTION_PNG_DPI: f64 = 300.0;

/// Why a file could not be made.
#[derive(Debug, thiserror::Error)]
pub enum FileError {
    /// A flight file refused the mission (not safe to fly as planned).
    #[error(transparent)]
    Export(#[from] ExportError),
    /// A figure could not be drawn.
    #[error(transparent)]
    Render(#[from] RenderError),
    /// The `gleaner.mission` document could not be serialised.
    #[error("serialising the mission: {0}")]
    Json(#[from] serde_json::Error),
}

/// Files by name, in a fixed order, and those not made with the reason.
#[derive(Debug, Clone, Default)]
pub struct FileSet {
    /// Each file's name and bytes.
    pub files: Vec<(&'static str, Vec<u8>)>,
    /// Files not made, each `name: reason` (a format that cannot carry this mission).
    pub skipped: Vec<String>,
}

/// An image format, SVG text or PNG.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ImageFormat {
    /// SVG text.
    Svg,
    /// PNG.
    Png,
}

impl ImageFormat {
    /// The format a file name's extension (`.svg`, `.png`, in any case) names.
    pub fn of_name(name: &std::path::Path) -> Option<Self> {
        match name
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref()
        {
            Some("svg") => Some(Self::Svg),
            Some("png") => Some(Self::Png),
            _ => None,
        }
    }
}

/// One file of a mission by its name (`mission.plan`, `mission.waypoints`, `mission.kmz` for
/// the aircraft `wpml`, `mission.geojson`, `mission.json`, `mission.svg`, `mission.png`);
/// `None` for another name.
pub fn mission_file(
    name: &str,
    field: &FieldDoc,
    doc: &MissionDoc,
    wpml: WpmlOptions,
) -> Option<Result<Vec<u8>, FileError>> {
    let svg = || crate::mission_figure_svg(field, doc, &FigureOptions::default());
    let bytes = |r: Result<String, ExportError>| Ok(r?.into_bytes());
    Some(match name {
        "mission.plan" => bytes(gleaner_wire::qgc_plan(doc)),
        "mission.waypoints" => bytes(gleaner_wire::wpl(doc)),
        "mission.kmz" => gleaner_wire::wpml_kmz(doc, wpml).map_err(FileError::from),
        "mission.geojson" => bytes(gleaner_wire::geojson(field, doc)),
        "mission.json" => serde_json::to_vec_pretty(doc).map_err(FileError::from),
        "mission.svg" => svg().map(String::into_bytes).map_err(FileError::from),
        "mission.png" => svg()
            .and_then(|s| crate::svg_to_png(&s, MAP_PNG_WIDTH_PX))
            .map_err(FileError::from),
        _ => return None,
    })
}

/// The files of an exported mission, in this order: `mission.geojson`, `mission.plan`,
/// `mission.waypoints`, `mission.kmz` (DJI WPML for the aircraft `wpml`; skipped with the
/// reason when the altitude is below or the commanded speed above what WPML allows),
/// `mission.json`, `mission.svg` and `mission.png` (1600 px wide).
pub fn mission_files(
    field: &FieldDoc,
    doc: &MissionDoc,
    wpml: WpmlOptions,
) -> Result<FileSet, FileError> {
    let mut set = flight_files(field, doc)?;
    let speed = gleaner_wire::commanded_speed_mps(doc.profile.cruise_speed_mps);
    let altitude = gleaner_wire::commanded_altitude_m(doc.profile.altitude_m);
    if altitude < gleaner_wire::wpml::MIN_WPML_HEIGHT_M {
        set.skipped.push(format!(
            "mission.kmz: the flight altitude {altitude} m is below DJI WPML's {} m",
            gleaner_wire::wpml::MIN_WPML_HEIGHT_M
        ));
    } else if speed <= gleaner_wire::wpml::MAX_WPML_SPEED_MPS {
        set.files
            .push(("mission.kmz", gleaner_wire::wpml_kmz(doc, wpml)?));
    } else {
        set.skipped.push(format!(
            "mission.kmz: the commanded speed {speed} m/s exceeds DJI WPML's {} m/s",
            gleaner_wire::wpml::MAX_WPML_SPEED_MPS
        ));
    }
    set.files
        .push(("mission.json", serde_json::to_vec_pretty(doc)?));
    let svg = crate::mission_figure_svg(field, doc, &FigureOptions::default())?;
    let png = crate::svg_to_png(&svg, MAP_PNG_WIDTH_PX)?;
    set.files.push(("mission.svg", svg.into_bytes()));
    set.files.push(("mission.png", png));
    Ok(set)
}

/// The files of a continuation re-planned in the air: `mission.geojson`, `mission.plan`,
/// `mission.waypoints` (no take-off: a 0 s first waypoint where the aircraft is) and
/// `mission.json`; no DJI archive (a wayline mission takes off by itself) and no figure.
pub fn continuation_files(field: &FieldDoc, doc: &MissionDoc) -> Result<FileSet, FileError> {
    let mut set = flight_files(field, doc)?;
    set.files
        .push(("mission.json", serde_json::to_vec_pretty(doc)?));
    set.skipped.push(
        "mission.kmz: a DJI wayline mission takes off by itself; upload the .plan or the WPL"
            .into(),
    );
    Ok(set)
}

/// `mission.geojson`, `mission.plan` and `mission.waypoints`.
fn flight_files(field: &FieldDoc, doc: &MissionDoc) -> Result<FileSet, FileError> {
    Ok(FileSet {
        files: vec![
            (
                "mission.geojson",
                gleaner_wire::geojson(field, doc)?.into_bytes(),
            ),
            ("mission.plan", gleaner_wire::qgc_plan(doc)?.into_bytes()),
            ("mission.waypoints", gleaner_wire::wpl(doc)?.into_bytes()),
        ],
        skipped: Vec::new(),
    })
}

/// The exploration overview, every sortie on one map: `exploration.svg` and
/// `exploration.png` (1600 px wide).
pub fn exploration_files(field: &FieldDoc, sorties: &[MissionDoc]) -> Result<FileSet, RenderError> {
    let svg = crate::exploration_map_svg(field, sorties, &FigureOptions::default())?;
    let png = crate::svg_to_png(&svg, MAP_PNG_WIDTH_PX)?;
    Ok(FileSet {
        files: vec![
            ("exploration.svg", svg.into_bytes()),
            ("exploration.png", png),
        ],
        skipped: Vec::new(),
    })
}

/// The reconstruction map at the full page width ([`FULL_WIDTH_MM`]) as SVG text or a PNG
/// at [`RECONSTRUCTION_PNG_DPI`].
pub fn reconstruction_map_file(
    doc: &ReconstructionMapDoc,
    format: ImageFormat,
) -> Result<Vec<u8>, RenderError> {
    let opts = FigureOptions {
        width_mm: FULL_WIDTH_MM,
        ..Default::default()
    };
    let svg = crate::reconstruction_map_svg(doc, &opts)?;
    Ok(match format {
        ImageFormat::Svg => svg.into_bytes(),
        ImageFormat::Png => crate::svg_to_png(
            &svg,
            crate::png_width_px(FULL_WIDTH_MM, RECONSTRUCTION_PNG_DPI),
        )?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use gleaner_wire::samples;

    #[test]
    fn a_mission_file_set_is_each_named_file() {
        let (field, doc) = (samples::field(), samples::adaptive_mission());
        let set = mission_files(&field, &doc, WpmlOptions::default()).unwrap();
        let names: Vec<_> = set.files.iter().map(|f| f.0).collect();
        assert_eq!(
            names,
            [
                "mission.geojson",
                "mission.plan",
                "mission.waypoints",
                "mission.kmz",
                "mission.json",
                "mission.svg",
                "mission.png"
            ]
        );
        assert!(set.skipped.is_empty());
        for (name, bytes) in &set.files {
            let one = mission_file(name, &field, &doc, WpmlOptions::default());
            assert_eq!(&one.unwrap().unwrap(), bytes, "{name}");
        }
        assert!(mission_file("../etc/passwd", &field, &doc, WpmlOptions::default()).is_none());
    }

    #[test]
    fn a_continuation_has_no_take_off_archive_and_no_figure() {
        let set = continuation_files(&samples::field(), &samples::continuation()).unwrap();
        let names: Vec<_> = set.files.iter().map(|f| f.0).collect();
        assert_eq!(
            names,
            [
                "mission.geojson",
                "mission.plan",
                "mission.waypoints",
                "mission.json"
            ]
        );
        assert_eq!(set.skipped.len(), 1);
    }

    #[test]
    fn image_formats_by_extension() {
        use std::path::Path;
        assert_eq!(
            ImageFormat::of_name(Path::new("a.SVG")),
            Some(ImageFormat::Svg)
        );
        assert_eq!(
            ImageFormat::of_name(Path::new("a.png")),
            Some(ImageFormat::Png)
        );
        assert_eq!(ImageFormat::of_name(Path::new("a.pdf")), None);
    }
}
