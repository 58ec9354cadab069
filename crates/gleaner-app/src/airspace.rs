//! The project's airspace: `[field] geofence` (a GeoJSON file of the polygons the flight stays
//! inside), `[field] no_fly` (a GeoJSON file of zones the flight keeps out of: buildings, power
//! lines, tree rows, neighbours) and `[field] no_fly_buffer_m` (m), read here (the only IO),
//! projected into the field's local frame (east/north metres around the base) and handed to
//! `gleaner_airspace` for buffering and shortest paths.
//!
//! GeoJSON positions are WGS84 `[lon, lat]` degrees (RFC 7946); a file holds a geometry, a
//! Feature or a FeatureCollection. The geofence's features must be Polygons or MultiPolygons
//! (their union is the allowed area); no-fly features may also be LineStrings (a power
//! line), Points and their Multi- forms, which the buffer turns into areas. Errors name the
//! file, the feature (by index, from 0) and the field at fault; no input panics.
//!
//! Turn points are put where the flight files can write them (1e-7°, as
//! `gleaner_energy::flight_point` does for cell centres) before any path is computed, so the
//! planner prices exactly the detours the files command.

use std::path::{Path, PathBuf};

use gleaner_airspace::{Airspace, AirspaceOptions, Blocked, Coord, Geometry, MultiPolygon};
use gleaner_energy::flight_point;
use gleaner_field::{LatLon, LocalPoint, TransverseMercator};
use gleaner_mission::Detours;

use gleaner_scoring::Project;
use gleaner_scoring::settings::FieldSection;
use gleaner_scoring::{AppError, Result};

/// The largest zone file read, bytes (a farm's zones are kilobytes).
pub const MAX_ZONE_FILE_BYTES: u64 = 16 << 20;

/// What a zone is to the flight.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ZoneKind {
    /// The flight stays inside (QGroundControl's inclusion fence).
    Geofence,
    /// The flight keeps out (QGroundControl's exclusion fence).
    NoFly,
}

impl ZoneKind {
    /// `geofence` or `no-fly`, as written in documents.
    pub fn name(self) -> &'static str {
        match self {
            ZoneKind::Geofence => "geofence",
            ZoneKind::NoFly => "no-fly",
        }
    }
}

/// One zone as the settings' file gives it, WGS84.
#[derive(Debug, Clone, PartialEq)]
pub struct ZoneView {
    /// Geofence or no-fly zone.
    pub kind: ZoneKind,
    /// The feature's `name` property, if any.
    pub name: Option<String>,
    /// Position of the feature in its file, from 0.
    pub feature: usize,
    /// Polygons, each a list of rings (exterior first, then holes), each ring closed, of
    /// `[lon, lat]` WGS84 degrees. Empty for a line or point zone.
    pub polygons: Vec<Vec<Vec<[f64; 2]>>>,
    /// Lines (a no-fly line or the point of a point zone), `[lon, lat]` WGS84 degrees.
    pub lines: Vec<Vec<[f64; 2]>>,
}

/// A cell (or the base) the flight cannot reach, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct Unreachable {
    /// The cell's label (`x12y-3`).
    pub cell: String,
    /// Why: inside no-fly zone k (buffered), outside the geofence (shrunk), or cut off.
    pub reason: String,
}

/// The project's airspace in the field's frame, with the zones as given (for the files and
/// the maps).
#[derive(Debug)]
pub struct ProjectAirspace {
    airspace: Airspace,
    frame: TransverseMercator,
    /// The zones as given, geofence first, WGS84.
    pub zones: Vec<ZoneView>,
    /// The buffer, m.
    pub buffer_m: f64,
    no_fly_file: Option<PathBuf>,
}

/// The zones of a `[field]` section (files relative to `dir`) in `frame`, or `None` when neither a
/// geofence nor no-fly zones are set.
///
/// # Errors
/// A file that cannot be read or is not GeoJSON of the kinds allowed, naming the file, the
/// feature and the field; a zone the buffer cannot handle.
pub fn load(
    f: &FieldSection,
    dir: &Path,
    frame: &TransverseMercator,
) -> Result<Option<ProjectAirspace>> {
    if f.geofence.is_none() && f.no_fly.is_none() {
        return Ok(None);
    }
    let resolve = |p: &str| {
        let p = Path::new(p);
        if p.is_absolute() {
            p.to_path_buf()
        } else {
            dir.join(p)
        }
    };
    let mut zones = Vec::new();
    let mut fence: Option<MultiPolygon<f64>> = None;
    if let Some(file) = &f.geofence {
        let path = resolve(file);
        for (view, geometry) in read_zones(&path, ZoneKind::Geofence)? {
            let local = to_local(frame, &geometry);
            let polygons = match local {
                Geometry::Polygon(p) => vec![p],
                Geometry::MultiPolygon(mp) => mp.0,
                _ => Vec::new(),
            };
            fence
                .get_or_insert_with(|| MultiPolygon(Vec::new()))
                .0
                .extend(polygons);
            zones.push(view);
        }
        if fence.is_none() {
            return Err(AppError::Invalid(format!(
                "{}: no geofence polygon (field.geofence)",
                path.display()
            )));
        }
    }
    let mut no_fly = Vec::new();
    let no_fly_file = f.no_fly.as_deref().map(resolve);
    if let Some(path) = &no_fly_file {
        for (view, geometry) in read_zones(path, ZoneKind::NoFly)? {
            no_fly.push(to_local(frame, &geometry));
            zones.push(view);
        }
    }
    let options = AirspaceOptions {
        buffer_m: f.no_fly_buffer_m,
        ..AirspaceOptions::default()
    };
    let mut airspace = Airspace::new(&no_fly, fence.as_ref(), options).map_err(|e| {
        let which = match &e {
            gleaner_airspace::AirspaceError::InvalidZone { zone, .. } => {
                let file = no_fly_file
                    .as_ref()
                    .map_or_else(String::new, |p| p.display().to_string());
                format!("{file}: feature {zone}")
            }
            gleaner_airspace::AirspaceError::InvalidGeofence { .. } => f
                .geofence
                .as_deref()
                .map_or_else(String::new, |p| resolve(p).display().to_string()),
            _ => "field.no_fly_buffer_m".to_string(),
        };
        AppError::Invalid(format!("{which}: {e}"))
    })?;
    // Turn points where the files can write them: rounded to 1e-7° and projected back.
    airspace.map_turn_points(|c| {
        let p = frame.inverse(LocalPoint::new(c.x, c.y));
        let q = flight_point(frame, p);
        Coord { x: q.e, y: q.n }
    });
    Ok(Some(ProjectAirspace {
        airspace,
        frame: frame.clone(),
        zones,
        buffer_m: f.no_fly_buffer_m,
        no_fly_file,
    }))
}

/// [`load`] for a project, in its field's frame (the base at the origin).
///
/// # Errors
/// As [`load`].
pub fn of_project<S: gleaner_store::Store>(
    project: &Project<S>,
) -> Result<Option<ProjectAirspace>> {
    let base = project.settings().base()?;
    load(
        &project.settings().field,
        project.dir(),
        &TransverseMercator::local(base),
    )
}

impl ProjectAirspace {
    /// Why a point (local frame, m) cannot be flown to, in words; `None` when it is free.
    pub fn blocked(&self, p: LocalPoint) -> Option<String> {
        self.airspace
            .blocked(Coord { x: p.e, y: p.n })
            .map(|b| match b {
                Blocked::NoFly { zone } => {
                    let view = self
                        .zones
                        .iter()
                        .filter(|z| z.kind == ZoneKind::NoFly)
                        .nth(zone);
                    let name = view
                        .and_then(|z| z.name.clone())
                        .map_or_else(String::new, |n| format!(" ({n:?})"));
                    format!(
                        "inside no-fly zone {zone}{name} of {} (with its {} m buffer)",
                        self.no_fly_file
                            .as_ref()
                            .map_or_else(String::new, |p| p.display().to_string()),
                        gleaner_ingest::number(self.buffer_m)
                    )
                }
                Blocked::OutsideGeofence => format!(
                    "outside the geofence (or within its {} m buffer of the edge)",
                    gleaner_ingest::number(self.buffer_m)
                ),
            })
    }

    /// The legs among `points` (the base first; local frame, m) around the zones, for the
    /// planner ([`Detours`]).
    pub fn detours(&self, points: &[LocalPoint]) -> Detours {
        let coords: Vec<Coord<f64>> = points.iter().map(|p| Coord { x: p.e, y: p.n }).collect();
        let paths = self.airspace.paths(&coords);
        Detours::new(points, |i, j| {
            paths
                .via(i, j)
                .map(|v| v.iter().map(|c| LocalPoint::new(c.x, c.y)).collect())
        })
    }

    /// The turn points of the legs of a flown sequence `points` (base, stops..., base; local
    /// frame, m) as WGS84 positions (on the files' 1e-7° grid, as planned): one list per
    /// leg. `None` when a leg has no path (a stop inside a zone, or cut off).
    /// As in [`Detours`], two stops the zones separate are joined through the base
    /// (`points[0]`).
    pub fn legs_via(&self, points: &[LocalPoint]) -> Option<Vec<Vec<LatLon>>> {
        let base = *points.first()?;
        let pair = |a: LocalPoint, b: LocalPoint| -> Option<Vec<Coord<f64>>> {
            let pair = [Coord { x: a.e, y: a.n }, Coord { x: b.e, y: b.n }];
            self.airspace.paths(&pair).via(0, 1).map(<[_]>::to_vec)
        };
        let mut out = Vec::with_capacity(points.len().saturating_sub(1));
        for w in points.windows(2) {
            let via = match pair(w[0], w[1]) {
                Some(v) => v,
                None => {
                    let mut v = pair(w[0], base)?;
                    v.push(Coord {
                        x: base.e,
                        y: base.n,
                    });
                    v.extend(pair(base, w[1])?);
                    v
                }
            };
            out.push(
                via.iter()
                    .map(|c| {
                        gleaner_energy::flight_position(
                            self.frame.inverse(LocalPoint::new(c.x, c.y)),
                        )
                    })
                    .collect(),
            );
        }
        Some(out)
    }

    /// The turn points of every leg of the stored mission `m` (one list per stop, one for the
    /// return leg), recomputed from the zones as they are now.
    ///
    /// # Errors
    /// [`AppError::Invalid`] when a stop now lies in a zone, or a leg has no path: plan again.
    pub fn mission_via(&self, m: &gleaner_store::MissionRecord) -> Result<Vec<Vec<LatLon>>> {
        if m.mission.stops.is_empty() {
            return Ok(Vec::new());
        }
        let base = flight_point(&self.frame, m.mission.profile.base);
        let mut points = vec![base];
        for s in &m.mission.stops {
            let c = self.frame.forward(s.centre);
            if let Some(why) = self.blocked(c) {
                return Err(AppError::Invalid(format!(
                    "mission #{}: stop {} (cell {}) is {why}; plan it again",
                    m.id,
                    s.order + 1,
                    s.cell
                )));
            }
            points.push(c);
        }
        points.push(base);
        self.legs_via(&points).ok_or_else(|| {
            AppError::Invalid(format!(
                "mission #{}: a leg has no path around the zones; plan it again",
                m.id
            ))
        })
    }

    /// The underlying airspace (local frame, m).
    pub fn airspace(&self) -> &Airspace {
        &self.airspace
    }
}

/// The turn points of a stored mission's legs for its maps (see
/// [`ProjectAirspace::mission_via`]); empty without zones, or when they cannot be computed
/// (a stop now in a zone: the export refuses such a mission, a map draws it straight).
pub fn stored_via<S: gleaner_store::Store>(
    project: &Project<S>,
    m: &gleaner_store::MissionRecord,
) -> Vec<Vec<LatLon>> {
    match of_project(project) {
        Ok(Some(a)) => a.mission_via(m).unwrap_or_default(),
        _ => Vec::new(),
    }
}

/// The cells of `field` (and the base) the flight cannot reach under `airspace`: their centre
/// (at `centres`, local frame, m) blocked, or cut off from the base (`detours` over base +
/// centres). Errors when the base itself is blocked: nothing can be flown.
///
/// # Errors
/// [`AppError::Invalid`] when the base lies in a zone or outside the geofence.
pub fn unreachable_cells(
    airspace: &ProjectAirspace,
    labels: &[String],
    base: LocalPoint,
    centres: &[LocalPoint],
    detours: &Detours,
) -> Result<Vec<Unreachable>> {
    if let Some(why) = airspace.blocked(base) {
        return Err(AppError::Invalid(format!(
            "the base station is {why}: no flight can take off; move the base \
             (field.base_lat, field.base_lon) or the zones"
        )));
    }
    let mut out = Vec::new();
    for (k, c) in centres.iter().enumerate() {
        if detours.reachable(k + 1) {
            continue;
        }
        let reason = airspace
            .blocked(*c)
            .unwrap_or_else(|| "cut off from the base by the zones".to_string());
        out.push(Unreachable {
            cell: labels.get(k).cloned().unwrap_or_default(),
            reason,
        });
    }
    Ok(out)
}

/// The rectangle from (`e0`, `n0`) to (`e1`, `n1`), local frame, m (a geofence fixture).
pub fn rectangle(e0: f64, n0: f64, e1: f64, n1: f64) -> geo::Polygon<f64> {
    geo::Rect::new(geo::coord! {x: e0, y: n0}, geo::coord! {x: e1, y: n1}).to_polygon()
}

/// Polygons in `frame` (local east/north metres) as a GeoJSON FeatureCollection of Polygons
/// in WGS84 `[lon, lat]` degrees (rounded to 1e-7°), one Feature per polygon with its
/// `name` (`zone k`): the file `[field] no_fly` or `geofence` reads.
pub fn polygons_geojson(frame: &TransverseMercator, polygons: &[geo::Polygon<f64>]) -> String {
    let features: Vec<String> = polygons
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let ring = |r: &geo::LineString<f64>| {
                let pts: Vec<String> = r
                    .coords()
                    .map(|c| {
                        let q = gleaner_energy::flight_position(
                            frame.inverse(LocalPoint::new(c.x, c.y)),
                        );
                        format!("[{:.7},{:.7}]", q.lon(), q.lat())
                    })
                    .collect();
                format!("[{}]", pts.join(","))
            };
            let rings: Vec<String> = std::iter::once(p.exterior())
                .chain(p.interiors())
                .map(ring)
                .collect();
            format!(
                r#"{{"type":"Feature","properties":{{"name":"zone {k}"}},"geometry":{{"type":"Polygon","coordinates":[{}]}}}}"#,
                rings.join(",")
            )
        })
        .collect();
    format!(
        "{{\"type\":\"FeatureCollection\",\"features\":[\n{}\n]}}\n",
        features.join(",\n")
    )
}

/// `count` seeded no-fly polygons (4 to 7 corners, 8 to 25 m across from their centre) over
/// the box of `points` (local frame, m; e.g. the cell centres) grown by 20 m, each at least
/// 60 m from `base` (m), as a GeoJSON file's text ([`polygons_geojson`]): the fixture of the
/// zone tests and benchmarks. Deterministic for a seed.
pub fn seeded_no_fly_geojson(
    frame: &TransverseMercator,
    seed: u64,
    count: usize,
    points: &[LocalPoint],
    base: LocalPoint,
) -> String {
    let (mut lo, mut hi) = (
        Coord {
            x: base.e,
            y: base.n,
        },
        Coord {
            x: base.e,
            y: base.n,
        },
    );
    for p in points {
        lo.x = lo.x.min(p.e);
        lo.y = lo.y.min(p.n);
        hi.x = hi.x.max(p.e);
        hi.y = hi.y.max(p.n);
    }
    let grow = 20.0;
    let polygons = gleaner_airspace::fixture::seeded_polygons(
        seed,
        count,
        Coord {
            x: lo.x - grow,
            y: lo.y - grow,
        },
        Coord {
            x: hi.x + grow,
            y: hi.y + grow,
        },
        (8.0, 25.0),
        &[Coord {
            x: base.e,
            y: base.n,
        }],
        60.0,
    );
    polygons_geojson(frame, &polygons)
}

/// A geometry in WGS84 `[lon, lat]` projected into `frame` (x = east, y = north, m).
fn to_local(frame: &TransverseMercator, g: &Geometry<f64>) -> Geometry<f64> {
    use geo::MapCoords;
    g.map_coords(|c| {
        // Positions were checked on reading; an invalid one cannot reach here.
        let p =
            LatLon::new(c.y, c.x).map_or(LocalPoint::new(f64::NAN, f64::NAN), |p| frame.forward(p));
        Coord { x: p.e, y: p.n }
    })
}

/// Reads a zone file: every geometry with its view, in file order.
fn read_zones(path: &Path, kind: ZoneKind) -> Result<Vec<(ZoneView, Geometry<f64>)>> {
    let at = |what: String| AppError::Invalid(format!("{}: {what}", path.display()));
    let meta = std::fs::metadata(path).map_err(|e| at(format!("cannot read: {e}")))?;
    if !meta.is_file() {
        return Err(at("not a regular file".into()));
    }
    if meta.len() > MAX_ZONE_FILE_BYTES {
        return Err(at(format!(
            "{} bytes, more than the {MAX_ZONE_FILE_BYTES} allowed for a zone file",
            meta.len()
        )));
    }
    let text = std::fs::read_to_string(path).map_err(|e| at(format!("cannot read: {e}")))?;
    let doc: geojson::GeoJson = text
        .parse()
        .map_err(|e: geojson::Error| at(format!("not GeoJSON: {}", short(&e.to_string()))))?;
    let features: Vec<(Option<String>, Option<geojson::Geometry>)> = match doc {
        geojson::GeoJson::Geometry(g) => vec![(None, Some(g))],
        geojson::GeoJson::Feature(f) => vec![(name_of(&f), f.geometry)],
        geojson::GeoJson::FeatureCollection(fc) => fc
            .features
            .into_iter()
            .map(|f| (name_of(&f), f.geometry))
            .collect(),
    };
    if features.is_empty() {
        return Err(at("no feature".into()));
    }
    let mut out = Vec::with_capacity(features.len());
    for (feature, (name, geometry)) in features.into_iter().enumerate() {
        let here = |what: String| at(format!("feature {feature}: {what}"));
        let Some(geometry) = geometry else {
            return Err(here("`geometry` is null".into()));
        };
        let (view, g) = convert(&geometry.value, kind, feature, name)
            .map_err(|what| here(format!("`geometry`: {what}")))?;
        out.push((view, g));
    }
    Ok(out)
}

fn name_of(f: &geojson::Feature) -> Option<String> {
    f.properties
        .as_ref()
        .and_then(|p| p.get("name"))
        .and_then(|v| v.as_str())
        .map(|s| gleaner_ingest::shorten(s).to_string())
}

fn short(s: &str) -> String {
    gleaner_ingest::shorten(s).to_string()
}

/// One position `[lon, lat]` checked: two or three finite numbers in range.
fn position(p: &geojson::Position, at: &str) -> std::result::Result<[f64; 2], String> {
    let s = p.as_slice();
    if !(2..=3).contains(&s.len()) {
        return Err(format!("{at}: {} numbers, expected [lon, lat]", s.len()));
    }
    let (lon, lat) = (s[0], s[1]);
    if !(lon.is_finite() && (-180.0..=180.0).contains(&lon)) {
        return Err(format!("{at}: longitude {lon} outside -180..=180"));
    }
    if !(lat.is_finite() && (-90.0..=90.0).contains(&lat)) {
        return Err(format!("{at}: latitude {lat} outside -90..=90"));
    }
    Ok([lon, lat])
}

fn line(ps: &[geojson::Position], at: &str) -> std::result::Result<Vec<[f64; 2]>, String> {
    ps.iter()
        .enumerate()
        .map(|(k, p)| position(p, &format!("{at}[{k}]")))
        .collect()
}

fn ring(ps: &[geojson::Position], at: &str) -> std::result::Result<Vec<[f64; 2]>, String> {
    let r = line(ps, at)?;
    if r.len() < 4 {
        return Err(format!(
            "{at}: a ring of {} positions; RFC 7946 needs at least 4",
            r.len()
        ));
    }
    if r.first() != r.last() {
        return Err(format!(
            "{at}: the ring is not closed (first position != last)"
        ));
    }
    Ok(r)
}

fn polygon(
    rings: &[Vec<geojson::Position>],
    at: &str,
) -> std::result::Result<Vec<Vec<[f64; 2]>>, String> {
    if rings.is_empty() {
        return Err(format!("{at}: a polygon without rings"));
    }
    rings
        .iter()
        .enumerate()
        .map(|(k, r)| ring(r, &format!("{at}[{k}]")))
        .collect()
}

fn geo_polygon(rings: &[Vec<[f64; 2]>]) -> geo::Polygon<f64> {
    let ls = |r: &Vec<[f64; 2]>| {
        geo::LineString::from(r.iter().map(|&[x, y]| (x, y)).collect::<Vec<_>>())
    };
    geo::Polygon::new(ls(&rings[0]), rings[1..].iter().map(ls).collect())
}

fn geo_line(l: &[[f64; 2]]) -> geo::LineString<f64> {
    geo::LineString::from(l.iter().map(|&[x, y]| (x, y)).collect::<Vec<_>>())
}

/// A GeoJSON geometry as a zone of `kind`: its view and its `geo` geometry (lon/lat).
fn convert(
    value: &geojson::GeometryValue,
    kind: ZoneKind,
    feature: usize,
    name: Option<String>,
) -> std::result::Result<(ZoneView, Geometry<f64>), String> {
    use geojson::GeometryValue as V;
    let mut view = ZoneView {
        kind,
        name,
        feature,
        polygons: Vec::new(),
        lines: Vec::new(),
    };
    let areas_only = || {
        format!(
            "a {} cannot be a geofence: expected a Polygon or MultiPolygon",
            value.type_name()
        )
    };
    let g = match value {
        V::Polygon { coordinates } => {
            let p = polygon(coordinates, "coordinates")?;
            let g = geo_polygon(&p);
            view.polygons.push(p);
            Geometry::Polygon(g)
        }
        V::MultiPolygon { coordinates } => {
            if coordinates.is_empty() {
                return Err("coordinates: an empty MultiPolygon".into());
            }
            let mut parts = Vec::new();
            for (k, c) in coordinates.iter().enumerate() {
                let p = polygon(c, &format!("coordinates[{k}]"))?;
                parts.push(geo_polygon(&p));
                view.polygons.push(p);
            }
            Geometry::MultiPolygon(MultiPolygon(parts))
        }
        _ if kind == ZoneKind::Geofence => return Err(areas_only()),
        V::LineString { coordinates } => {
            let l = line(coordinates, "coordinates")?;
            if l.len() < 2 {
                return Err("coordinates: a LineString needs 2 positions".into());
            }
            let g = geo_line(&l);
            view.lines.push(l);
            Geometry::LineString(g)
        }
        V::MultiLineString { coordinates } => {
            let mut parts = Vec::new();
            for (k, c) in coordinates.iter().enumerate() {
                let l = line(c, &format!("coordinates[{k}]"))?;
                if l.len() < 2 {
                    return Err(format!("coordinates[{k}]: a LineString needs 2 positions"));
                }
                parts.push(geo_line(&l));
                view.lines.push(l);
            }
            if parts.is_empty() {
                return Err("coordinates: an empty MultiLineString".into());
            }
            Geometry::MultiLineString(geo::MultiLineString(parts))
        }
        V::Point { coordinates } => {
            let p = position(coordinates, "coordinates")?;
            view.lines.push(vec![p]);
            Geometry::Point(geo::Point::new(p[0], p[1]))
        }
        V::MultiPoint { coordinates } => {
            let l = line(coordinates, "coordinates")?;
            if l.is_empty() {
                return Err("coordinates: an empty MultiPoint".into());
            }
            let g = geo::MultiPoint(l.iter().map(|&[x, y]| geo::Point::new(x, y)).collect());
            view.lines.extend(l.into_iter().map(|p| vec![p]));
            Geometry::MultiPoint(g)
        }
        V::GeometryCollection { .. } => {
            return Err("a GeometryCollection: give each zone as its own feature".into());
        }
    };
    Ok((view, g))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(dir: &Path, name: &str, text: &str) -> String {
        std::fs::write(dir.join(name), text).unwrap();
        name.to_string()
    }

    fn settings_with(geofence: Option<String>, no_fly: Option<String>) -> FieldSection {
        FieldSection {
            base_lat: 46.78,
            base_lon: -117.08,
            base_alt_m: 0.0,
            cell_size_m: 40.0,
            neighbour_k: 4,
            neighbour_radius_m: 200.0,
            geofence,
            no_fly,
            no_fly_buffer_m: 5.0,
        }
    }

    #[test]
    fn bad_geojson_names_the_file_the_feature_and_the_field() {
        let dir = tempfile::tempdir().unwrap();
        let frame = TransverseMercator::local(LatLon::new(46.78, -117.08).unwrap());
        let cases = [
            ("{", "not GeoJSON"),
            (
                r#"{"type":"FeatureCollection","features":[{"type":"Feature","properties":{},"geometry":{"type":"Polygon","coordinates":[[[-117.08,46.78],[-117.07,46.78],[-117.07,46.79],[-117.08,46.78]]]}},{"type":"Feature","properties":{},"geometry":{"type":"Polygon","coordinates":[[[-117.08,46.78],[-117.07,96.78],[-117.07,46.79],[-117.08,46.78]]]}}]}"#,
                "feature 1: `geometry`: coordinates[0][1]: latitude 96.78 outside -90..=90",
            ),
            (
                r#"{"type":"Polygon","coordinates":[[[-117.08,46.78],[-117.07,46.78],[-117.07,46.79]]]}"#,
                "feature 0: `geometry`: coordinates[0]: a ring of 3 positions",
            ),
            (
                r#"{"type":"Feature","properties":null,"geometry":null}"#,
                "feature 0: `geometry` is null",
            ),
            (
                r#"{"type":"FeatureCollection","features":[]}"#,
                "no feature",
            ),
        ];
        for (text, expected) in cases {
            let name = write(dir.path(), "zones.geojson", text);
            let e = load(&settings_with(None, Some(name)), dir.path(), &frame).unwrap_err();
            let msg = e.to_string();
            assert!(
                msg.contains("zones.geojson") && msg.contains(expected),
                "{msg}"
            );
        }
        let line = r#"{"type":"LineString","coordinates":[[-117.08,46.78],[-117.07,46.78]]}"#;
        let name = write(dir.path(), "fence.geojson", line);
        let e = load(&settings_with(Some(name), None), dir.path(), &frame).unwrap_err();
        assert!(e.to_string().contains("cannot be a geofence"), "{e}");
        let e = load(
            &settings_with(Some("missing.geojson".into()), None),
            dir.path(),
            &frame,
        )
        .unwrap_err();
        assert!(
            e.to_string().contains("missing.geojson: cannot read"),
            "{e}"
        );
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]
        /// No zone file panics the reader or the airspace: arbitrary bytes, and valid
        /// polygons with arbitrary (also huge, tiny, degenerate) coordinates.
        #[test]
        fn no_zone_file_panics(
            bytes in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..300),
            coords in proptest::collection::vec((-200.0f64..200.0, -100.0f64..100.0), 0..8),
        ) {
            let dir = tempfile::tempdir().unwrap();
            let frame = TransverseMercator::local(LatLon::new(46.78, -117.08).unwrap());
            std::fs::write(dir.path().join("a.geojson"), &bytes).unwrap();
            let _ = load(&settings_with(Some("a.geojson".into()), Some("a.geojson".into())), dir.path(), &frame);
            let ring: Vec<String> = coords
                .iter()
                .chain(coords.first())
                .map(|(x, y)| format!("[{x},{y}]"))
                .collect();
            let text = format!(
                r#"{{"type":"Polygon","coordinates":[[{}]]}}"#,
                ring.join(",")
            );
            std::fs::write(dir.path().join("b.geojson"), text).unwrap();
            let _ = load(&settings_with(Some("b.geojson".into()), Some("b.geojson".into())), dir.path(), &frame);
        }
    }

    #[test]
    fn a_line_zone_blocks_its_buffer_and_legs_go_around() {
        let dir = tempfile::tempdir().unwrap();
        let base = LatLon::new(46.78, -117.08).unwrap();
        let frame = TransverseMercator::local(base);
        // A power line 100 m east of the base, 200 m long north-south.
        let a = frame.inverse(LocalPoint::new(100.0, -100.0));
        let b = frame.inverse(LocalPoint::new(100.0, 100.0));
        let text = format!(
            r#"{{"type":"Feature","properties":{{"name":"power line"}},"geometry":{{"type":"LineString","coordinates":[[{},{}],[{},{}]]}}}}"#,
            a.lon(),
            a.lat(),
            b.lon(),
            b.lat()
        );
        let name = write(dir.path(), "lines.geojson", &text);
        let air = load(&settings_with(None, Some(name)), dir.path(), &frame)
            .unwrap()
            .unwrap();
        let why = air.blocked(LocalPoint::new(102.0, 0.0)).unwrap();
        assert!(why.contains("no-fly zone 0 (\"power line\")"), "{why}");
        let pts = [LocalPoint::new(0.0, 0.0), LocalPoint::new(200.0, 0.0)];
        let d = air.detours(&pts);
        assert!(!d.via(0, 1).is_empty());
        assert!(d.length_m(0, 1) > 200.0);
        let legs = air.legs_via(&pts).unwrap();
        assert_eq!(legs[0].len(), d.via(0, 1).len());
    }
}
