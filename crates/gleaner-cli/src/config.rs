//! The project file `gleaner.toml`: the serialisable counterpart of the core configuration
//! types, converted explicitly. Only this module knows the TOML layout.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use gleaner_field::{FieldConfig, LatLon};
use serde::{Deserialize, Serialize};

/// File name of the project configuration inside a project directory.
pub const CONFIG_FILE: &str = "gleaner.toml";

/// `gleaner.toml`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ProjectFile {
    /// `[project]`
    pub project: ProjectSection,
    /// `[field]`
    pub field: FieldSection,
    /// `[sensors]`
    pub sensors: SensorsSection,
    /// `[ingest]`
    #[serde(default)]
    pub ingest: IngestSection,
}

/// `[project]`: name and database.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ProjectSection {
    /// A display name.
    pub name: String,
    /// SQLite database file, relative to the project directory.
    pub database: PathBuf,
}

/// `[field]`: base station and grid.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FieldSection {
    /// Base station latitude, WGS84 degrees.
    pub base_lat: f64,
    /// Base station longitude, WGS84 degrees.
    pub base_lon: f64,
    /// Base station altitude, metres.
    #[serde(default)]
    pub base_alt_m: f64,
    /// Cell side, metres (the UAV's ground coverage).
    pub cell_size_m: f64,
    /// Neighbour fallback: k nearest non-empty cells for a cell with no 8-neighbour.
    #[serde(default = "default_k")]
    pub neighbour_k: usize,
    /// Neighbour fallback radius, metres.
    #[serde(default = "default_radius")]
    pub neighbour_radius_m: f64,
}

fn default_k() -> usize {
    3
}
fn default_radius() -> f64 {
    200.0
}

/// `[sensors]`: where the sensor table came from.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SensorsSection {
    /// The sensors file given to `init`, as given.
    pub file: String,
    /// Its UTM zone when positions were read as easting/northing (e.g. `11N`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub utm_zone: Option<String>,
}

/// `[ingest]`: how pending data volume is estimated.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct IngestSection {
    /// Bytes one reading of one modality takes in a sensor's log (default 16).
    pub bytes_per_reading: f64,
    /// Logging interval, seconds, assumed when a series has fewer than 2 readings (default 86 400).
    pub default_interval_s: f64,
}

impl Default for IngestSection {
    fn default() -> Self {
        Self {
            bytes_per_reading: 16.0,
            default_interval_s: 86_400.0,
        }
    }
}

impl ProjectFile {
    /// Reads and validates `dir/gleaner.toml`.
    pub fn load(dir: &Path) -> Result<Self> {
        let path = dir.join(CONFIG_FILE);
        let text = std::fs::read_to_string(&path).with_context(|| {
            format!(
                "{}: cannot read the project file (run `gleaner init` first, or pass --project)",
                path.display()
            )
        })?;
        let file: Self = toml::from_str(&text)
            .with_context(|| format!("{}: invalid project file", path.display()))?;
        file.validate()
            .with_context(|| format!("{}: invalid setting", path.display()))?;
        Ok(file)
    }

    /// Writes `dir/gleaner.toml`.
    pub fn save(&self, dir: &Path) -> Result<()> {
        let path = dir.join(CONFIG_FILE);
        let text = format!(
            "# gleaner project file. Units: degrees (WGS84), metres, seconds, bytes.\n{}",
            toml::to_string_pretty(self)?
        );
        std::fs::write(&path, text).with_context(|| format!("{}: cannot write", path.display()))
    }

    fn validate(&self) -> Result<()> {
        self.base()?;
        if !(self.field.cell_size_m.is_finite() && self.field.cell_size_m > 0.0) {
            bail!(
                "field.cell_size_m = {} must be a positive number of metres",
                self.field.cell_size_m
            );
        }
        if !(self.ingest.bytes_per_reading > 0.0 && self.ingest.default_interval_s > 0.0) {
            bail!("ingest.bytes_per_reading and ingest.default_interval_s must be positive");
        }
        Ok(())
    }

    /// The base station position.
    pub fn base(&self) -> Result<LatLon> {
        LatLon::new(self.field.base_lat, self.field.base_lon)
            .with_context(|| "field.base_lat / field.base_lon")
    }

    /// The core grid configuration.
    pub fn field_config(&self) -> FieldConfig {
        FieldConfig {
            cell_size_m: self.field.cell_size_m,
            fallback_k: self.field.neighbour_k,
            fallback_radius_m: self.field.neighbour_radius_m,
        }
    }
}

/// Parses a UTM zone such as `11N` or `33s` into (zone, northern hemisphere).
pub fn parse_utm_zone(s: &str) -> Result<(u8, bool)> {
    let s = s.trim();
    let (digits, hemi) = s.split_at(s.len().saturating_sub(1));
    let north = match hemi {
        "N" | "n" => true,
        "S" | "s" => false,
        _ => bail!("invalid UTM zone {s:?}: expected e.g. `11N` or `33S`"),
    };
    let zone: u8 = digits
        .parse()
        .ok()
        .filter(|z| (1..=60).contains(z))
        .with_context(|| format!("invalid UTM zone {s:?}: zone must be 1..=60"))?;
    Ok((zone, north))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn utm_zones() {
        assert_eq!(parse_utm_zone("11N").unwrap(), (11, true));
        assert_eq!(parse_utm_zone("33s").unwrap(), (33, false));
        assert!(parse_utm_zone("61N").is_err());
        assert!(parse_utm_zone("11").is_err());
    }
}
