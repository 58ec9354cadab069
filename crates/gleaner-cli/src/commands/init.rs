//! `gleaner init`: creates a project from a sensors file with the application layer's
//! [`gleaner_app::init`].

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::ValueEnum;
use gleaner_app as app;

use crate::args::{MethodArg, parse_lat_lon};
use crate::output::outln;

// The arguments of `gleaner init` (no doc comment: the variant's is the help).
#[derive(clap::Args)]
pub struct InitArgs {
    /// Project directory (created if missing).
    #[arg(long, default_value = ".")]
    pub dir: PathBuf,
    /// Sensors CSV: `id,lat,lon[,elevation_m]` (WGS84 degrees), or `easting,northing` metres
    /// with --utm-zone (CAF_sensor_locations.csv works as is).
    #[arg(long)]
    pub sensors: PathBuf,
    /// Read positions as UTM easting/northing in this zone, e.g. `11N` (EPSG:26911/32611).
    #[arg(long)]
    pub utm_zone: Option<String>,
    /// The sensors file's layout: `generic` (id,lat,lon...) or `hubbard-brook`
    /// (sensor_metadata.csv: one sensor per logger probe, id `<logger>:p<port>`).
    #[arg(long, value_enum, default_value_t = SensorsFormatArg::Generic)]
    pub sensors_format: SensorsFormatArg,
    /// Base station (take-off and landing) as `LAT,LON` in WGS84 degrees [default: 10 m
    /// south of the middle of the sensors' southern edge].
    #[arg(long, value_parser = parse_lat_lon, allow_hyphen_values = true)]
    pub base: Option<(f64, f64)>,
    /// Base station altitude above mean sea level, metres (the flight files' home
    /// altitude) [default: 0].
    #[arg(long, allow_hyphen_values = true)]
    pub base_alt: Option<f64>,
    /// Cell side in metres (the UAV's ground coverage), at least 0.5 [default: 40].
    #[arg(long)]
    pub cell_size: Option<f64>,
    /// Neighbour fallback radius in metres: a cell with no non-empty adjacent cell takes its
    /// `neighbour_k` nearest non-empty cells within it as neighbours; at most 100 cell sides
    /// [default: 200, or 100 cell sides for cells under 2 m].
    #[arg(long)]
    pub neighbour_radius: Option<f64>,
    /// UAV altitude, metres; with --half-angle derives the cell side (r = h·tan θ, side = r·√2).
    #[arg(long, requires = "half_angle")]
    pub altitude: Option<f64>,
    /// Antenna half-angle, degrees (with --altitude).
    #[arg(long, requires = "altitude")]
    pub half_angle: Option<f64>,
    /// Project name [default: the directory's name].
    #[arg(long)]
    pub name: Option<String>,
    /// Overwrite the settings of an existing project (its database is kept).
    #[arg(long)]
    pub force: bool,
    /// Where to keep the data: an SQLite file relative to the project directory, or a
    /// PostgreSQL database `postgres://user:password@host:port/db[#schema]` (one schema
    /// per project, named after `#` or after the project name) [default: gleaner.db].
    #[arg(long, value_name = "FILE_OR_URL")]
    pub database: Option<String>,
    /// The score the project plans by: `gleaner` (gleaner's method, the default: the gated
    /// score with each sensor's drift as freshness and the bounded anomaly, β = 4,
    /// γ = δ = 0; less error and sooner catches than coverage and far less than the
    /// paper's S on CAF, docs/method.md §2, docs/method-improvement.md) or `paper` (the paper's S exactly,
    /// which loses to random sampling on CAF 2014). Written into `[utility]`.
    #[arg(long, value_enum, default_value_t = MethodArg::Gleaner)]
    pub method: MethodArg,
    /// GeoJSON file of the geofence: a Polygon or MultiPolygon (or Features of them),
    /// `[lon, lat]` WGS84 degrees; every flight stays inside it, `--no-fly-buffer`
    /// metres from its edge (`[field] geofence`).
    #[arg(long, value_name = "GEOJSON")]
    pub geofence: Option<PathBuf>,
    /// GeoJSON file of the no-fly zones: Polygons (buildings, tree rows, neighbours),
    /// LineStrings (power lines) or Points, `[lon, lat]` WGS84 degrees; every leg keeps
    /// `--no-fly-buffer` metres away, flying the shortest way around; cells inside are
    /// reported unreachable (`[field] no_fly`).
    #[arg(long, value_name = "GEOJSON")]
    pub no_fly: Option<PathBuf>,
    /// Safety buffer around the no-fly zones and inside the geofence, metres, 0..=1000
    /// (`[field] no_fly_buffer_m`) [default: 5].
    #[arg(long, value_name = "M")]
    pub no_fly_buffer: Option<f64>,
}

// The sensors file's layout (no doc comments: clap would show them).
#[derive(Clone, Copy, ValueEnum)]
pub enum SensorsFormatArg {
    Generic,
    HubbardBrook,
}

/// Creates the project; prints its summary.
pub fn run(args: InitArgs) -> Result<()> {
    let base = args
        .base
        .map(|(lat, lon)| gleaner_field::LatLon::new(lat, lon).context("--base"))
        .transpose()?;
    let (_, outcome) = app::init(&app::InitRequest {
        dir: args.dir.clone(),
        sensors: args.sensors,
        utm_zone: args.utm_zone,
        hubbard_brook: matches!(args.sensors_format, SensorsFormatArg::HubbardBrook),
        base,
        base_alt_m: args.base_alt,
        cell_size_m: args.cell_size,
        neighbour_radius_m: args.neighbour_radius,
        coverage: args.altitude.zip(args.half_angle),
        name: args.name,
        force: args.force,
        database: args.database,
        gleaner_method: matches!(args.method, MethodArg::Gleaner),
        geofence: args.geofence,
        no_fly: args.no_fly,
        no_fly_buffer_m: args.no_fly_buffer,
    })?;
    outln(&gleaner_wire::text::init_lines(&outcome, &args.dir))
}
