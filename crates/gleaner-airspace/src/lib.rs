//! Where a flight may go, and the shortest way there.
//!
//! An [`Airspace`] is built from *no-fly zones* (polygons, lines or points the flight must keep
//! away from) and an optional *geofence* (polygons the flight must stay inside), all in one
//! planar metre frame: `x` = east, `y` = north, metres (any local projection; the caller
//! projects). Every zone is grown by a safety buffer (`buffer_m`, m) and the geofence shrunk by
//! it, with [`geo`]'s `Buffer` (mitred corners, so a rectangle stays four corners); overlapping
//! zones merge into one keep-out region.
//!
//! A point is *free* when it lies strictly outside every buffered zone and strictly inside the
//! shrunk geofence ([`Airspace::blocked`] says why not). A segment between two free points is
//! *clear* when it touches no boundary of those regions ([`Airspace::segment_clear`], `geo`'s
//! robust `Intersects` on every boundary segment, culled by bounding boxes).
//!
//! Shortest paths bend only at corners of the obstacles, so the *turn points* are the convex
//! corners of the zones grown by `buffer_m + clearance_m` (and the reflex corners of the
//! geofence shrunk as much): strictly free, `clearance_m` (default 0.5 m) off the buffered
//! boundary, so a path through them never grazes it. [`Airspace::paths`] computes, for a set of
//! points, every pair's shortest path over the visibility graph of the turn points and the
//! two endpoints (the straight segment when it is clear; otherwise Dijkstra from one end over
//! the turn points) as the list of intermediate turn points. A pair's path is computed from
//! its lexicographically smaller end and reversed for the other direction, so the matrix is
//! symmetric and the path between two points never depends on which other points were asked
//! for: [`Airspace::paths`] of `[a, b]` gives the same path as any larger set holding `a` and
//! `b`.
//!
//! Invariants (tested, proptest over random polygons and points): a path's segments are all
//! clear (it never enters a buffered zone nor leaves the shrunk geofence); it is no shorter
//! than the straight line; it *is* the straight line when that is clear.
//!
//! ```
//! use gleaner_airspace::{Airspace, AirspaceOptions, Coord, Geometry};
//! use geo::{Rect, coord};
//! // A 20 m x 20 m building between two points 100 m apart.
//! let building = Geometry::Polygon(Rect::new(coord! {x: 40.0, y: -10.0}, coord! {x: 60.0, y: 10.0}).to_polygon());
//! let airspace = Airspace::new(&[building], None, AirspaceOptions { buffer_m: 5.0, ..Default::default() }).unwrap();
//! let (a, b) = (Coord { x: 0.0, y: 0.0 }, Coord { x: 100.0, y: 0.0 });
//! let paths = airspace.paths(&[a, b]);
//! let via = paths.via(0, 1).unwrap();
//! assert_eq!(via.len(), 2); // around two corners of the buffered building
//! assert!(paths.length_m(0, 1).unwrap() > 100.0);
//! ```
#![deny(missing_docs)]

use std::sync::OnceLock;

pub mod fixture;

use geo::{
    BoundingRect, Contains, Intersects, Line, Rect,
    algorithm::buffer::{Buffer, BufferStyle, LineJoin},
};
pub use geo::{Coord, Geometry, LineString, MultiPolygon, Polygon};
use thiserror::Error;

/// How much room the flight keeps from the zones.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AirspaceOptions {
    /// Safety buffer, m: every no-fly zone is grown by it and the geofence shrunk by it
    /// (>= 0, finite).
    pub buffer_m: f64,
    /// Extra room of the turn points beyond the buffer, m (> 0, finite; default 0.5 m): a path
    /// passes the buffered boundary at least this far off at its corners, so rounding the
    /// turn points (e.g. to 1e-7° in a flight file, <= 5.6 mm) keeps them free.
    pub clearance_m: f64,
}

impl Default for AirspaceOptions {
    /// 5 m buffer, 0.5 m clearance.
    fn default() -> Self {
        Self {
            buffer_m: 5.0,
            clearance_m: 0.5,
        }
    }
}

/// Why an airspace cannot be built.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum AirspaceError {
    /// A buffer or clearance that is negative, zero where it must be positive, or not finite.
    #[error("{name} = {value}: expected {expected}")]
    InvalidOption {
        /// The option.
        name: &'static str,
        /// Its value.
        value: f64,
        /// What is allowed.
        expected: &'static str,
    },
    /// A no-fly zone with a non-finite coordinate, or one that buffers to nothing (a line or
    /// point with a zero buffer, an empty polygon).
    #[error("no-fly zone {zone}: {reason}")]
    InvalidZone {
        /// Position of the zone in the input.
        zone: usize,
        /// What is wrong.
        reason: String,
    },
    /// A geofence with a non-finite coordinate, or one that the buffer shrinks to nothing.
    #[error("geofence: {reason}")]
    InvalidGeofence {
        /// What is wrong.
        reason: String,
    },
}

/// Why a point is not free.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Blocked {
    /// Inside (or on the boundary of) no-fly zone `zone` grown by the buffer (index into the
    /// zones given to [`Airspace::new`]).
    NoFly {
        /// Position of the zone in the input.
        zone: usize,
    },
    /// Outside (or on the boundary of) the geofence shrunk by the buffer.
    OutsideGeofence,
}

/// One boundary ring's segments with their bounding box, for culling.
#[derive(Debug, Clone)]
struct Ring {
    bbox: Rect<f64>,
    segments: Vec<Line<f64>>,
}

/// The keep-out and keep-in regions, the turn points, and the visibility among turn points.
#[derive(Debug)]
pub struct Airspace {
    options: AirspaceOptions,
    /// Each input zone grown by the buffer (for telling which zone blocks a point).
    zones: Vec<MultiPolygon<f64>>,
    /// The geofence shrunk by the buffer.
    keep_in: Option<MultiPolygon<f64>>,
    /// Boundary rings of the merged keep-out region and of the keep-in region.
    rings: Vec<Ring>,
    /// Turn points, m.
    turns: Vec<Coord<f64>>,
    /// Visibility among turn points: for each, (other turn point, distance m), computed once.
    graph: OnceLock<Vec<Vec<(usize, f64)>>>,
}

/// Euclidean distance, m.
fn dist(a: Coord<f64>, b: Coord<f64>) -> f64 {
    (a.x - b.x).hypot(a.y - b.y)
}

fn finite_geometry(g: &Geometry<f64>) -> bool {
    use geo::CoordsIter;
    g.coords_iter().all(|c| c.x.is_finite() && c.y.is_finite())
}

fn mitred(distance: f64) -> BufferStyle<f64> {
    // Mitred corners keep a polygon's corner count; sharper corners than the limit are
    // bevelled (two corners) rather than spiked far out.
    BufferStyle::new(distance).line_join(LineJoin::Miter(MITER_LIMIT))
}

/// The miter limit handed to `geo`'s buffer: the sharpest corner angle still mitred, rad
/// (sharper corners are bevelled: two corners instead of a far spike).
const MITER_LIMIT: f64 = 0.5;

/// Signed area of a closed ring (positive = counter-clockwise), m².
fn signed_area(ring: &LineString<f64>) -> f64 {
    ring.0
        .windows(2)
        .map(|w| w[0].x * w[1].y - w[1].x * w[0].y)
        .sum::<f64>()
        / 2.0
}

/// The convex corners of the obstacle bounded by `ring` (`obstacle_left_when_ccw`: the
/// obstacle is the ring's inside for an exterior of a keep-out polygon or a hole of a keep-in
/// one), in ring order.
fn corners(ring: &LineString<f64>, obstacle_inside: bool, out: &mut Vec<Coord<f64>>) {
    let mut pts: Vec<Coord<f64>> = ring.0.clone();
    if pts.len() > 1 && pts.first() == pts.last() {
        pts.pop();
    }
    let n = pts.len();
    if n < 3 {
        out.extend(pts);
        return;
    }
    // Orient so that the obstacle is on the left: counter-clockwise when the obstacle is the
    // ring's inside, clockwise when it is the outside.
    if (signed_area(ring) > 0.0) != obstacle_inside {
        pts.reverse();
    }
    for k in 0..n {
        let (p, v, q) = (pts[(k + n - 1) % n], pts[k], pts[(k + 1) % n]);
        let cross = (v.x - p.x) * (q.y - v.y) - (v.y - p.y) * (q.x - v.x);
        if cross > 0.0 {
            out.push(v);
        }
    }
}

fn rings_of(mp: &MultiPolygon<f64>, out: &mut Vec<Ring>) {
    for poly in mp {
        for ring in std::iter::once(poly.exterior()).chain(poly.interiors()) {
            let segments: Vec<Line<f64>> = ring.lines().collect();
            if let Some(bbox) = ring.bounding_rect() {
                out.push(Ring { bbox, segments });
            }
        }
    }
}

impl Airspace {
    /// Builds the airspace of `no_fly` zones (polygons, multipolygons, lines or points, m) and
    /// an optional `geofence` (m); see the crate docs. No zones and no geofence is an
    /// airspace where every point is free and every path straight.
    ///
    /// # Errors
    /// [`AirspaceError`] for invalid options, non-finite coordinates, a zone that buffers to
    /// nothing (a line or point with a zero buffer) or a geofence the buffer shrinks to
    /// nothing.
    pub fn new(
        no_fly: &[Geometry<f64>],
        geofence: Option<&MultiPolygon<f64>>,
        options: AirspaceOptions,
    ) -> Result<Self, AirspaceError> {
        if !(options.buffer_m.is_finite() && options.buffer_m >= 0.0) {
            return Err(AirspaceError::InvalidOption {
                name: "buffer (m)",
                value: options.buffer_m,
                expected: "a finite number >= 0",
            });
        }
        if !(options.clearance_m.is_finite() && options.clearance_m > 0.0) {
            return Err(AirspaceError::InvalidOption {
                name: "clearance (m)",
                value: options.clearance_m,
                expected: "a finite number > 0",
            });
        }
        let outer = options.buffer_m + options.clearance_m;
        let mut zones = Vec::with_capacity(no_fly.len());
        let mut turn_zones = Vec::with_capacity(no_fly.len());
        for (zone, g) in no_fly.iter().enumerate() {
            if !finite_geometry(g) {
                return Err(AirspaceError::InvalidZone {
                    zone,
                    reason: "a coordinate is not a finite number".into(),
                });
            }
            let grown = if options.buffer_m > 0.0 {
                g.buffer_with_style(mitred(options.buffer_m))
            } else {
                match g {
                    Geometry::Polygon(p) => MultiPolygon(vec![p.clone()]),
                    Geometry::MultiPolygon(mp) => mp.clone(),
                    _ => MultiPolygon(Vec::new()),
                }
            };
            if grown.0.is_empty() {
                return Err(AirspaceError::InvalidZone {
                    zone,
                    reason: "it covers no area (a line or point needs a buffer > 0 m)".into(),
                });
            }
            turn_zones.push(g.buffer_with_style(mitred(outer)));
            zones.push(grown);
        }
        let mut rings = Vec::new();
        // The merged keep-out region: overlapping zones become one, so a boundary inside
        // another zone is no boundary.
        let merged = merge(&zones);
        rings_of(&merged, &mut rings);
        let mut turns = Vec::new();
        for poly in &merge(&turn_zones) {
            corners(poly.exterior(), true, &mut turns);
            for hole in poly.interiors() {
                corners(hole, false, &mut turns);
            }
        }
        let keep_in = match geofence {
            None => None,
            Some(fence) => {
                if !finite_geometry(&Geometry::MultiPolygon(fence.clone())) {
                    return Err(AirspaceError::InvalidGeofence {
                        reason: "a coordinate is not a finite number".into(),
                    });
                }
                let inner = if options.buffer_m > 0.0 {
                    fence.buffer_with_style(mitred(-options.buffer_m))
                } else {
                    merge(std::slice::from_ref(fence))
                };
                if inner.0.is_empty() {
                    return Err(AirspaceError::InvalidGeofence {
                        reason: format!(
                            "nothing is left inside it {} m from its edge",
                            options.buffer_m
                        ),
                    });
                }
                rings_of(&inner, &mut rings);
                for poly in &fence.buffer_with_style(mitred(-outer)) {
                    corners(poly.exterior(), false, &mut turns);
                    for hole in poly.interiors() {
                        corners(hole, true, &mut turns);
                    }
                }
                Some(inner)
            }
        };
        let mut airspace = Self {
            options,
            zones,
            keep_in,
            rings,
            turns: Vec::new(),
            graph: OnceLock::new(),
        };
        turns.retain(|&t| airspace.blocked(t).is_none());
        airspace.turns = turns;
        Ok(airspace)
    }

    /// The options it was built with.
    pub fn options(&self) -> AirspaceOptions {
        self.options
    }

    /// True when nothing restricts the flight (no zone, no geofence): every path is straight.
    pub fn is_open(&self) -> bool {
        self.zones.is_empty() && self.keep_in.is_none()
    }

    /// Each no-fly zone grown by the buffer, m, in input order.
    pub fn buffered_zones(&self) -> &[MultiPolygon<f64>] {
        &self.zones
    }

    /// The geofence shrunk by the buffer, m, if there is one.
    pub fn buffered_geofence(&self) -> Option<&MultiPolygon<f64>> {
        self.keep_in.as_ref()
    }

    /// The turn points (convex corners of the zones grown by buffer + clearance), m.
    pub fn turn_points(&self) -> &[Coord<f64>] {
        &self.turns
    }

    /// Moves every turn point by `f` (e.g. onto the grid a flight file can write) and drops
    /// those that are no longer free. Call before [`Airspace::paths`]: paths then go through
    /// exactly the moved points.
    pub fn map_turn_points(&mut self, mut f: impl FnMut(Coord<f64>) -> Coord<f64>) {
        let moved: Vec<Coord<f64>> = self.turns.iter().map(|&t| f(t)).collect();
        self.turns = moved
            .into_iter()
            .filter(|&t| t.x.is_finite() && t.y.is_finite() && self.blocked(t).is_none())
            .collect();
        self.graph = OnceLock::new();
    }

    /// Why `p` (m) is not free: inside or on a buffered zone (the first, in input order), or
    /// outside or on the shrunk geofence; `None` when it is free.
    pub fn blocked(&self, p: Coord<f64>) -> Option<Blocked> {
        if !(p.x.is_finite() && p.y.is_finite()) {
            return Some(Blocked::OutsideGeofence);
        }
        let point = geo::Point(p);
        for (zone, z) in self.zones.iter().enumerate() {
            if z.intersects(&point) {
                return Some(Blocked::NoFly { zone });
            }
        }
        match &self.keep_in {
            Some(fence) if !fence.contains(&point) => Some(Blocked::OutsideGeofence),
            _ => None,
        }
    }

    /// True when the segment `a`–`b` (m) lies in free space: both ends free and no boundary
    /// of a buffered zone or of the shrunk geofence touched.
    pub fn segment_clear(&self, a: Coord<f64>, b: Coord<f64>) -> bool {
        self.blocked(a).is_none() && self.blocked(b).is_none() && self.crosses_nothing(a, b)
    }

    /// True when `a`–`b` touches no boundary ring (ends assumed free).
    fn crosses_nothing(&self, a: Coord<f64>, b: Coord<f64>) -> bool {
        let line = Line::new(a, b);
        let (lo_x, hi_x) = (a.x.min(b.x), a.x.max(b.x));
        let (lo_y, hi_y) = (a.y.min(b.y), a.y.max(b.y));
        for ring in &self.rings {
            let (min, max) = (ring.bbox.min(), ring.bbox.max());
            if hi_x < min.x || lo_x > max.x || hi_y < min.y || lo_y > max.y {
                continue;
            }
            for s in &ring.segments {
                // Cheap box test before the exact predicate.
                let (s0, s1) = (s.start, s.end);
                if hi_x < s0.x.min(s1.x)
                    || lo_x > s0.x.max(s1.x)
                    || hi_y < s0.y.min(s1.y)
                    || lo_y > s0.y.max(s1.y)
                {
                    continue;
                }
                if line.intersects(s) {
                    return false;
                }
            }
        }
        true
    }

    /// Visibility among the turn points, computed once.
    fn graph(&self) -> &[Vec<(usize, f64)>] {
        self.graph.get_or_init(|| {
            let m = self.turns.len();
            let mut adj = vec![Vec::new(); m];
            for i in 0..m {
                for j in (i + 1)..m {
                    let (a, b) = (self.turns[i], self.turns[j]);
                    if self.crosses_nothing(a, b) {
                        let d = dist(a, b);
                        adj[i].push((j, d));
                        adj[j].push((i, d));
                    }
                }
            }
            adj
        })
    }

    /// Every pair's shortest path among `points` (m); see the crate docs. A point that is not
    /// free has no path to anything (not even itself); two free points the zones separate
    /// have none either.
    pub fn paths(&self, points: &[Coord<f64>]) -> Paths {
        let n = points.len();
        let mut paths = Paths {
            n,
            length: vec![f64::INFINITY; n * n],
            via: vec![None; n * n],
        };
        let free: Vec<bool> = points.iter().map(|&p| self.blocked(p).is_none()).collect();
        if self.is_open() {
            for i in 0..n {
                for j in 0..n {
                    paths.length[i * n + j] = dist(points[i], points[j]);
                    paths.via[i * n + j] = Some(Vec::new());
                }
            }
            return paths;
        }
        // The turn points each point sees, lazily.
        let mut sees: Vec<Option<Vec<(usize, f64)>>> = vec![None; n];
        let see = |k: usize, sees: &mut Vec<Option<Vec<(usize, f64)>>>| {
            if sees[k].is_none() {
                let p = points[k];
                sees[k] = Some(
                    self.turns
                        .iter()
                        .enumerate()
                        .filter(|&(_, &t)| self.crosses_nothing(p, t))
                        .map(|(t, &c)| (t, dist(p, c)))
                        .collect(),
                );
            }
        };
        for i in 0..n {
            if !free[i] {
                continue;
            }
            paths.length[i * n + i] = 0.0;
            paths.via[i * n + i] = Some(Vec::new());
            let mut from_i: Option<(Vec<f64>, Vec<usize>)> = None;
            for j in 0..n {
                if j == i || !free[j] || !canonical_source(points, i, j) {
                    continue;
                }
                let (a, b) = (points[i], points[j]);
                let found = if self.crosses_nothing(a, b) {
                    Some((dist(a, b), Vec::new()))
                } else {
                    if from_i.is_none() {
                        see(i, &mut sees);
                        from_i = Some(self.dijkstra(sees[i].as_deref().unwrap_or(&[])));
                    }
                    see(j, &mut sees);
                    let (d, pred) = from_i.as_ref().expect("computed above");
                    let mut best: Option<(f64, usize)> = None;
                    for &(t, dt) in sees[j].as_deref().unwrap_or(&[]) {
                        let total = d[t] + dt;
                        if total.is_finite() && best.is_none_or(|(b, _)| total < b) {
                            best = Some((total, t));
                        }
                    }
                    best.map(|(total, last)| {
                        let mut via = vec![last];
                        while let Some(&p) = pred.get(*via.last().expect("non-empty")) {
                            if p == usize::MAX {
                                break;
                            }
                            via.push(p);
                        }
                        via.reverse();
                        (total, via.into_iter().map(|t| self.turns[t]).collect())
                    })
                };
                if let Some((length, via)) = found {
                    let mut back: Vec<Coord<f64>> = via.clone();
                    back.reverse();
                    paths.length[i * n + j] = length;
                    paths.length[j * n + i] = length;
                    paths.via[i * n + j] = Some(via);
                    paths.via[j * n + i] = Some(back);
                }
            }
        }
        paths
    }

    /// Dijkstra over the turn points from a source that sees `start` (turn point, distance
    /// m): each turn point's distance (m, infinite when unreachable) and predecessor
    /// (`usize::MAX` for the first turn point after the source). Dense O(m²) selection; ties go
    /// to the lower index, so the result is deterministic.
    fn dijkstra(&self, start: &[(usize, f64)]) -> (Vec<f64>, Vec<usize>) {
        let graph = self.graph();
        let m = self.turns.len();
        let mut d = vec![f64::INFINITY; m];
        let mut pred = vec![usize::MAX; m];
        let mut done = vec![false; m];
        for &(t, dt) in start {
            if dt < d[t] {
                d[t] = dt;
            }
        }
        loop {
            let mut u = usize::MAX;
            let mut best = f64::INFINITY;
            for k in 0..m {
                if !done[k] && d[k] < best {
                    best = d[k];
                    u = k;
                }
            }
            if u == usize::MAX {
                break;
            }
            done[u] = true;
            for &(v, w) in &graph[u] {
                let alt = d[u] + w;
                if !done[v] && alt < d[v] {
                    d[v] = alt;
                    pred[v] = u;
                }
            }
        }
        (d, pred)
    }
}

/// True when `points[i]` is the end a path between `i` and `j` is computed from: the
/// lexicographically smaller (x, then y, then index).
fn canonical_source(points: &[Coord<f64>], i: usize, j: usize) -> bool {
    let (a, b) = (points[i], points[j]);
    a.x.total_cmp(&b.x)
        .then(a.y.total_cmp(&b.y))
        .then(i.cmp(&j))
        .is_lt()
}

/// The union of `parts` (a zero buffer of their union, through `geo`'s boolean ops).
fn merge(parts: &[MultiPolygon<f64>]) -> MultiPolygon<f64> {
    use geo::BooleanOps;
    let mut all = MultiPolygon(Vec::new());
    for p in parts {
        all = all.union(p);
    }
    all
}

/// Every pair's shortest path among a set of points ([`Airspace::paths`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Paths {
    n: usize,
    length: Vec<f64>,
    via: Vec<Option<Vec<Coord<f64>>>>,
}

impl Paths {
    /// Number of points.
    pub fn len(&self) -> usize {
        self.n
    }

    /// True for no points.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// The path's length from point `i` to point `j`, m; `None` when there is no path (a
    /// blocked end, or ends the zones separate). Panics when out of range.
    pub fn length_m(&self, i: usize, j: usize) -> Option<f64> {
        assert!(i < self.n && j < self.n, "({i}, {j}) out of range");
        self.via[i * self.n + j]
            .as_ref()
            .map(|_| self.length[i * self.n + j])
    }

    /// The turn points between point `i` and point `j` in flying order (empty: straight), m;
    /// `None` when there is no path. Panics when out of range.
    pub fn via(&self, i: usize, j: usize) -> Option<&[Coord<f64>]> {
        assert!(i < self.n && j < self.n, "({i}, {j}) out of range");
        self.via[i * self.n + j].as_deref()
    }
}

#[cfg(test)]
mod tests;
