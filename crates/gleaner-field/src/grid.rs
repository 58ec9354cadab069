//! The square cell grid over the field, the non-empty cells and their neighbours (docs/method.md §1).

use std::collections::HashMap;
use std::fmt;

use crate::{FieldError, LatLon, LocalPoint, Sensor, Short, TransverseMercator};

/// Index of a grid cell: `i` columns east and `j` rows north of the cell whose south-west
/// corner is the base station.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct CellIndex {
    /// Column, counted eastwards (may be negative).
    pub i: i32,
    /// Row, counted northwards (may be negative).
    pub j: i32,
}

impl fmt::Display for CellIndex {
    /// The cell's stable label, e.g. `x12y-3`; used as the cell id in files and the database.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "x{}y{}", self.i, self.j)
    }
}

impl CellIndex {
    /// Parses a label written by [`fmt::Display`] (`x12y-3`).
    pub fn parse(label: &str) -> Option<Self> {
        let rest = label.strip_prefix('x')?;
        let (i, j) = rest.split_once('y')?;
        Some(Self {
            i: i.parse().ok()?,
            j: j.parse().ok()?,
        })
    }
}

/// Position of a cell in [`Field::cells`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct CellId(pub u32);

impl CellId {
    /// The position as a `usize`, for indexing.
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// A non-empty grid cell.
#[derive(Debug, Clone, PartialEq)]
pub struct Cell {
    /// Grid position.
    pub index: CellIndex,
    /// Centre in the local frame, metres.
    pub centre: LocalPoint,
    /// The cell's sensors, as positions in the sensor slice the field was built from,
    /// ascending.
    pub sensors: Vec<usize>,
}

/// How the grid and the neighbour sets are built.
#[derive(Debug, Clone, PartialEq)]
pub struct FieldConfig {
    /// Side of a square cell, metres (the UAV's ground coverage).
    pub cell_size_m: f64,
    /// For a cell with no non-empty 8-neighbour: how many nearest non-empty cells to use
    /// instead (docs/method.md §1; default 3).
    pub fallback_k: usize,
    /// ... and within what centre-to-centre distance, metres (default 200 m).
    pub fallback_radius_m: f64,
}

impl FieldConfig {
    /// Defaults with the given cell side in metres.
    pub fn with_cell_size(cell_size_m: f64) -> Self {
        Self {
            cell_size_m,
            fallback_k: 3,
            fallback_radius_m: 200.0,
        }
    }
}

impl Default for FieldConfig {
    /// 40 m cells (the paper scenario), k = 3 within 200 m.
    fn default() -> Self {
        Self::with_cell_size(40.0)
    }
}

/// Cell side, metres, from altitude `altitude_m` and the antenna's half-angle `half_angle_deg`:
/// coverage radius r = h·tan(θ), side = r·√2 so the square lies inside the coverage disc.
pub fn cell_size_from_half_angle(altitude_m: f64, half_angle_deg: f64) -> Result<f64, FieldError> {
    if !(altitude_m > 0.0 && half_angle_deg > 0.0 && half_angle_deg < 90.0) {
        return Err(FieldError::Coverage(format!(
            "need altitude > 0 m and 0 < half-angle < 90 deg, got {} m, {} deg",
            Short(altitude_m),
            Short(half_angle_deg)
        )));
    }
    Ok(altitude_m * half_angle_deg.to_radians().tan() * std::f64::consts::SQRT_2)
}

/// Cell side, metres, from altitude `altitude_m` and slant link range `range_m`: coverage radius
/// r = √(range² − h²), side = r·√2.
pub fn cell_size_from_link_range(altitude_m: f64, range_m: f64) -> Result<f64, FieldError> {
    if !(altitude_m >= 0.0 && range_m > altitude_m && range_m.is_finite()) {
        return Err(FieldError::Coverage(format!(
            "link range {} m must exceed altitude {} m",
            Short(range_m),
            Short(altitude_m)
        )));
    }
    Ok((range_m * range_m - altitude_m * altitude_m).sqrt() * std::f64::consts::SQRT_2)
}

/// Neighbour lists, one per cell, as [`CellId`]s in ascending order.
pub type Neighbours = Vec<Vec<CellId>>;

/// A field: the local frame centred on the base station, the sensors' local positions, the
/// non-empty cells (sorted by column then row) and each cell's neighbours.
///
/// Invariants: every sensor is in exactly one cell; every cell has at least one sensor; a cell
/// is never its own neighbour; neighbour lists are sorted and free of duplicates.
#[derive(Debug, Clone)]
pub struct Field {
    frame: TransverseMercator,
    base: LatLon,
    config: FieldConfig,
    sensor_points: Vec<LocalPoint>,
    sensor_cell: Vec<CellId>,
    cells: Vec<Cell>,
    by_index: HashMap<CellIndex, CellId>,
    neighbours: Neighbours,
}

impl Field {
    /// Grids `sensors` around the base station `base`. Fails on an invalid cell size, no sensors
    /// or a duplicate sensor id.
    pub fn build(
        sensors: &[Sensor],
        base: LatLon,
        config: &FieldConfig,
    ) -> Result<Self, FieldError> {
        let size = config.cell_size_m;
        if !(size.is_finite() && size > 0.0) {
            return Err(FieldError::InvalidCellSize(size));
        }
        if sensors.is_empty() {
            return Err(FieldError::NoSensors);
        }
        let mut seen = std::collections::HashSet::with_capacity(sensors.len());
        for s in sensors {
            if !seen.insert(s.id.as_str()) {
                return Err(FieldError::DuplicateSensor(s.id.to_string()));
            }
        }
        let frame = TransverseMercator::local(base);
        let sensor_points: Vec<LocalPoint> =
            sensors.iter().map(|s| frame.forward(s.position)).collect();
        let index_of = |p: &LocalPoint| CellIndex {
            i: (p.e / size).floor() as i32,
            j: (p.n / size).floor() as i32,
        };
        let mut members: HashMap<CellIndex, Vec<usize>> = HashMap::new();
        for (k, p) in sensor_points.iter().enumerate() {
            members.entry(index_of(p)).or_default().push(k);
        }
        let mut indices: Vec<CellIndex> = members.keys().copied().collect();
        indices.sort_unstable();
        let by_index: HashMap<CellIndex, CellId> = indices
            .iter()
            .enumerate()
            .map(|(k, ix)| (*ix, CellId(k as u32)))
            .collect();
        let mut sensor_cell = vec![CellId(0); sensors.len()];
        let cells: Vec<Cell> = indices
            .iter()
            .map(|ix| {
                let sensors = members.remove(ix).unwrap_or_default();
                for &s in &sensors {
                    sensor_cell[s] = by_index[ix];
                }
                Cell {
                    index: *ix,
                    centre: LocalPoint::new(
                        (f64::from(ix.i) + 0.5) * size,
                        (f64::from(ix.j) + 0.5) * size,
                    ),
                    sensors,
                }
            })
            .collect();
        let neighbours = compute_neighbours(&cells, &by_index, config);
        Ok(Self {
            frame,
            base,
            config: config.clone(),
            sensor_points,
            sensor_cell,
            cells,
            by_index,
            neighbours,
        })
    }

    /// The local frame (metres east/north of the base station).
    pub fn frame(&self) -> &TransverseMercator {
        &self.frame
    }
    /// The base station's WGS84 position; it is (0, 0) in the local frame.
    pub fn base(&self) -> LatLon {
        self.base
    }
    /// The configuration the field was built with.
    pub fn config(&self) -> &FieldConfig {
        &self.config
    }
    /// Cell side, metres.
    pub fn cell_size_m(&self) -> f64 {
        self.config.cell_size_m
    }
    /// The non-empty cells, sorted by (i, j).
    pub fn cells(&self) -> &[Cell] {
        &self.cells
    }
    /// Each sensor's local position, metres, in input order.
    pub fn sensor_points(&self) -> &[LocalPoint] {
        &self.sensor_points
    }
    /// The cell holding sensor number `sensor` (its position in the input slice).
    pub fn cell_of_sensor(&self, sensor: usize) -> CellId {
        self.sensor_cell[sensor]
    }
    /// The non-empty cell at a grid index, if any.
    pub fn cell_at(&self, index: CellIndex) -> Option<CellId> {
        self.by_index.get(&index).copied()
    }
    /// The neighbours of `cell` (docs/method.md §1), ascending.
    pub fn neighbours(&self, cell: CellId) -> &[CellId] {
        &self.neighbours[cell.index()]
    }
    /// All neighbour lists, indexed by cell.
    pub fn all_neighbours(&self) -> &Neighbours {
        &self.neighbours
    }
    /// The corners of `cell` in the local frame, metres, counter-clockwise from south-west.
    pub fn cell_corners(&self, cell: CellId) -> [LocalPoint; 4] {
        let s = self.config.cell_size_m;
        let ix = self.cells[cell.index()].index;
        let (e0, n0) = (f64::from(ix.i) * s, f64::from(ix.j) * s);
        [
            LocalPoint::new(e0, n0),
            LocalPoint::new(e0 + s, n0),
            LocalPoint::new(e0 + s, n0 + s),
            LocalPoint::new(e0, n0 + s),
        ]
    }
}

fn compute_neighbours(
    cells: &[Cell],
    by_index: &HashMap<CellIndex, CellId>,
    config: &FieldConfig,
) -> Neighbours {
    let size = config.cell_size_m;
    let rings = (config.fallback_radius_m / size).ceil().max(0.0) as i32 + 1;
    cells
        .iter()
        .enumerate()
        .map(|(k, c)| {
            let mut near: Vec<CellId> = Vec::with_capacity(8);
            for dj in -1..=1 {
                for di in -1..=1 {
                    if di == 0 && dj == 0 {
                        continue;
                    }
                    let ix = CellIndex {
                        i: c.index.i + di,
                        j: c.index.j + dj,
                    };
                    if let Some(&id) = by_index.get(&ix) {
                        near.push(id);
                    }
                }
            }
            if near.is_empty() && config.fallback_k > 0 {
                // k nearest non-empty cells within the radius: scan square rings outwards
                // (ring r covers Chebyshev distance r), which bounds the search by the radius.
                let mut found: Vec<(f64, CellId)> = Vec::new();
                for r in 2..=rings {
                    for dj in -r..=r {
                        for di in -r..=r {
                            if di.abs().max(dj.abs()) != r {
                                continue;
                            }
                            let ix = CellIndex {
                                i: c.index.i + di,
                                j: c.index.j + dj,
                            };
                            if let Some(&id) = by_index.get(&ix) {
                                let d = c.centre.distance(&cells[id.index()].centre);
                                if d <= config.fallback_radius_m && id.index() != k {
                                    found.push((d, id));
                                }
                            }
                        }
                    }
                    // Every cell in ring r+1 is at least r·size away; stop once k are closer.
                    let bound = f64::from(r) * size;
                    if found.iter().filter(|(d, _)| *d <= bound).count() >= config.fallback_k {
                        break;
                    }
                }
                found.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                near = found
                    .into_iter()
                    .take(config.fallback_k)
                    .map(|(_, id)| id)
                    .collect();
            }
            near.sort_unstable();
            near
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::SensorId;
    use proptest::prelude::*;

    fn field_from_local(points: &[(f64, f64)], config: &FieldConfig) -> Field {
        let base = LatLon::new(46.78, -117.08).unwrap();
        let frame = TransverseMercator::local(base);
        let sensors: Vec<Sensor> = points
            .iter()
            .enumerate()
            .map(|(k, (e, n))| {
                Sensor::new(
                    SensorId::new(format!("s{k}")).unwrap(),
                    frame.inverse(LocalPoint::new(*e, *n)),
                )
            })
            .collect();
        Field::build(&sensors, base, config).unwrap()
    }

    #[test]
    fn sensors_share_cells_and_neighbours_are_8_connected() {
        let f = field_from_local(
            &[
                (5.0, 5.0),
                (30.0, 30.0),
                (45.0, 5.0),
                (85.0, 85.0),
                (500.0, 500.0),
            ],
            &FieldConfig::with_cell_size(40.0),
        );
        let labels: Vec<String> = f.cells().iter().map(|c| c.index.to_string()).collect();
        assert_eq!(labels, ["x0y0", "x1y0", "x2y2", "x12y12"]);
        assert_eq!(f.cells()[0].sensors, vec![0, 1]);
        assert_eq!(f.neighbours(CellId(0)), &[CellId(1)]);
        assert_eq!(f.neighbours(CellId(1)), &[CellId(0)]);
        // x2y2 touches no non-empty cell: its 3 nearest within 200 m are x1y0 and x0y0.
        assert_eq!(f.neighbours(CellId(2)), &[CellId(0), CellId(1)]);
        // x12y12 is 400+ m from everything: beyond the 200 m fallback radius.
        assert!(f.neighbours(CellId(3)).is_empty());
    }

    #[test]
    fn isolated_cell_falls_back_to_k_nearest_within_radius() {
        let f = field_from_local(
            &[
                (20.0, 20.0),
                (100.0, 20.0),
                (20.0, 140.0),
                (180.0, 20.0),
                (20.0, 400.0),
            ],
            &FieldConfig::with_cell_size(40.0),
        );
        // cell 0 at x0y0: non-empty cells at x2y0 (80 m), x0y3 (120 m), x4y0 (160 m).
        let n0: Vec<String> = f
            .neighbours(CellId(0))
            .iter()
            .map(|c| f.cells()[c.index()].index.to_string())
            .collect();
        assert_eq!(n0, ["x0y3", "x2y0", "x4y0"]);
    }

    #[test]
    fn derived_cell_sizes() {
        let s = cell_size_from_half_angle(30.0, 45.0).unwrap();
        assert!((s - 30.0 * std::f64::consts::SQRT_2).abs() < 1e-9);
        let s = cell_size_from_link_range(30.0, 50.0).unwrap();
        assert!((s - 40.0 * std::f64::consts::SQRT_2).abs() < 1e-9);
        assert!(cell_size_from_link_range(60.0, 50.0).is_err());
    }

    #[test]
    fn label_round_trip() {
        let ix = CellIndex { i: 12, j: -3 };
        assert_eq!(CellIndex::parse(&ix.to_string()), Some(ix));
        assert_eq!(CellIndex::parse("y1x2"), None);
    }

    proptest! {
        #[test]
        fn every_sensor_in_its_cell_and_neighbours_symmetric_for_8(
            pts in proptest::collection::vec((-2000.0f64..2000.0, -2000.0f64..2000.0), 1..60)
        ) {
            let f = field_from_local(&pts, &FieldConfig::with_cell_size(40.0));
            let total: usize = f.cells().iter().map(|c| c.sensors.len()).sum();
            prop_assert_eq!(total, pts.len());
            for (k, p) in f.sensor_points().iter().enumerate() {
                let c = &f.cells()[f.cell_of_sensor(k).index()];
                prop_assert!((p.e - c.centre.e).abs() <= 20.0 + 1e-6);
                prop_assert!((p.n - c.centre.n).abs() <= 20.0 + 1e-6);
            }
            for (k, ns) in f.all_neighbours().iter().enumerate() {
                prop_assert!(!ns.contains(&CellId(k as u32)));
                prop_assert!(ns.windows(2).all(|w| w[0] < w[1]));
            }
        }
    }
}
