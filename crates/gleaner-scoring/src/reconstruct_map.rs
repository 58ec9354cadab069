//! The map of a reconstruction (docs/method.md §7): every cell's estimated value of one
//! modality at a time with its uncertainty, the sensors that were read near that time told
//! from those only estimated, and the field's outline — plain data for a figure.

use std::collections::{BTreeMap, HashMap};

use gleaner_field::{CellId, CellIndex, LatLon, LocalPoint, SensorId};
use gleaner_store::Store;

use crate::error::{AppError, Result};
use crate::project::Project;
use crate::reconstruct::{
    ReconstructRequest, Reconstruction, modality_unit, reconstruct, target_modality,
};

/// What to map.
#[derive(Debug, Clone, Default)]
pub struct ReconstructMapRequest {
    /// The reconstruction (time, modality, neighbours, estimator) as [`reconstruct`].
    pub reconstruct: ReconstructRequest,
    /// A sensor counts as read at the time when its latest known reading is at most this
    /// long before it, seconds, >= 0 [default: the modality's sampling step].
    pub read_within_s: Option<i64>,
}

/// One cell of the map.
#[derive(Debug, Clone, PartialEq)]
pub struct MapCell {
    /// Grid index (`x12y-3`).
    pub index: CellIndex,
    /// The square's corners, WGS84, counter-clockwise from south-west.
    pub corners: [LatLon; 4],
    /// Its sensors, as positions in [`Reconstruction::sensors`], ascending.
    pub sensors: Vec<usize>,
    /// The mean of its sensors' estimates, the modality's unit.
    pub mean: f64,
    /// Its uncertainty: the root mean of its sensors' variances (the typical posterior
    /// standard deviation of a sensor in it), the modality's unit.
    pub sd: f64,
}

/// A reconstruction laid on the field.
#[derive(Debug, Clone)]
pub struct ReconstructionMap {
    /// Project name.
    pub project: String,
    /// The reconstruction mapped (time, modality, estimator, every sensor's estimate).
    pub reconstruction: Reconstruction,
    /// The modality's unit as stored (e.g. `m3/m3`), if known.
    pub unit: Option<String>,
    /// Base station, WGS84.
    pub base: LatLon,
    /// Cell side, m.
    pub cell_size_m: f64,
    /// The cells, in the field's order (by grid index).
    pub cells: Vec<MapCell>,
    /// Per sensor of [`Reconstruction::sensors`]: whether it was read at the time (its
    /// latest known reading at most `read_within_s` before it).
    pub read: Vec<bool>,
    /// The tolerance behind `read`, seconds.
    pub read_within_s: i64,
    /// The field's outline: the boundary of the union of its cells as closed rings (first
    /// point repeated last), WGS84.
    pub outline: Vec<Vec<LatLon>>,
}

/// The use case: reconstructs the modality at the time (as [`reconstruct`]) and lays the
/// estimates on the cells. Writes nothing.
///
/// Errors: those of [`reconstruct`], and a negative `read_within_s`.
pub fn reconstruct_map<S: Store>(
    project: &Project<S>,
    request: &ReconstructMapRequest,
) -> Result<ReconstructionMap> {
    if let Some(w) = request.read_within_s
        && w < 0
    {
        return Err(AppError::Invalid(format!(
            "the read tolerance must be at least 0 s, got {w} s"
        )));
    }
    let reconstruction = reconstruct(project, &request.reconstruct)?;
    let modality = target_modality(project, Some(&reconstruction.modality))?;
    let unit = modality_unit(project, &modality)?;
    let (sensors, field) = project.field()?;
    let frame = field.frame();
    let position: HashMap<&SensorId, usize> = reconstruction
        .sensors
        .iter()
        .enumerate()
        .map(|(k, s)| (&s.sensor, k))
        .collect();
    let cells: Vec<MapCell> = field
        .cells()
        .iter()
        .enumerate()
        .map(|(c, cell)| {
            let mut members: Vec<usize> = cell
                .sensors
                .iter()
                .filter_map(|&s| position.get(&sensors[s].id).copied())
                .collect();
            members.sort_unstable();
            let n = members.len().max(1) as f64;
            let mean = members
                .iter()
                .map(|&k| reconstruction.sensors[k].kriged)
                .sum::<f64>()
                / n;
            let var = members
                .iter()
                .map(|&k| reconstruction.sensors[k].variance.max(0.0))
                .sum::<f64>()
                / n;
            MapCell {
                index: cell.index,
                corners: field
                    .cell_corners(CellId(c as u32))
                    .map(|p| frame.inverse(p)),
                sensors: members,
                mean,
                sd: var.sqrt(),
            }
        })
        .collect();
    let read_within_s = request
        .read_within_s
        .unwrap_or(reconstruction.step_s)
        .max(0);
    let at = reconstruction.at;
    let read = reconstruction
        .sensors
        .iter()
        .map(|s| {
            s.last_time
                .is_some_and(|t| t <= at && at.saturating_sub(t) <= read_within_s)
        })
        .collect();
    let size = field.cell_size_m();
    let indices: Vec<CellIndex> = field.cells().iter().map(|c| c.index).collect();
    let outline = outline(&indices)
        .into_iter()
        .map(|ring| {
            ring.into_iter()
                .map(|(i, j)| {
                    frame.inverse(LocalPoint::new(f64::from(i) * size, f64::from(j) * size))
                })
                .collect()
        })
        .collect();
    let settings = project.settings();
    Ok(ReconstructionMap {
        project: settings.project.name.clone(),
        reconstruction,
        unit,
        base: settings.base()?,
        cell_size_m: size,
        cells,
        read,
        read_within_s,
        outline,
    })
}

/// A lattice point: cell corner (i, j) is the south-west corner of cell (i, j).
type Corner = (i32, i32);

/// The boundary of the union of the cells as closed rings of lattice corners (first corner
/// repeated last), each running counter-clockwise around the cells (holes clockwise). Every
/// boundary edge is in exactly one ring; rings are deterministic (they start at the smallest
/// unused edge).
pub(crate) fn outline(cells: &[CellIndex]) -> Vec<Vec<Corner>> {
    let present: std::collections::HashSet<(i32, i32)> = cells.iter().map(|c| (c.i, c.j)).collect();
    // Directed boundary edges, the cell on their left.
    let mut out_edges: BTreeMap<Corner, Vec<Corner>> = BTreeMap::new();
    for &(i, j) in &present {
        let sides = [
            ((i, j - 1), (i, j), (i + 1, j)),         // south
            ((i + 1, j), (i + 1, j), (i + 1, j + 1)), // east
            ((i, j + 1), (i + 1, j + 1), (i, j + 1)), // north
            ((i - 1, j), (i, j + 1), (i, j)),         // west
        ];
        for (other, a, b) in sides {
            if !present.contains(&other) {
                out_edges.entry(a).or_default().push(b);
            }
        }
    }
    for ends in out_edges.values_mut() {
        ends.sort_unstable();
    }
    let mut rings = Vec::new();
    while let Some((&start, _)) = out_edges.iter().find(|(_, e)| !e.is_empty()) {
        let mut ring = vec![start];
        let mut at = start;
        // Each corner has as many boundary edges out as in, so the walk returns to its start.
        while let Some(ends) = out_edges.get_mut(&at).filter(|e| !e.is_empty()) {
            let next = ends.remove(0);
            ring.push(next);
            at = next;
            if at == start {
                break;
            }
        }
        rings.push(ring);
    }
    rings
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ix(i: i32, j: i32) -> CellIndex {
        CellIndex { i, j }
    }

    #[test]
    fn the_outline_of_one_cell_is_its_square() {
        assert_eq!(
            outline(&[ix(2, 3)]),
            vec![vec![(2, 3), (3, 3), (3, 4), (2, 4), (2, 3)]]
        );
    }

    #[test]
    fn shared_edges_are_not_in_the_outline() {
        // An L of three cells: 8 boundary edges, one ring.
        let rings = outline(&[ix(0, 0), ix(1, 0), ix(0, 1)]);
        assert_eq!(rings.len(), 1);
        assert_eq!(rings[0].len(), 9);
        assert_eq!(rings[0].first(), rings[0].last());
        // Two separate cells: two rings; a ring of 8 cells around a hole: two rings.
        assert_eq!(outline(&[ix(0, 0), ix(5, 5)]).len(), 2);
        let ring: Vec<CellIndex> = (0..3)
            .flat_map(|i| (0..3).map(move |j| ix(i, j)))
            .filter(|c| (c.i, c.j) != (1, 1))
            .collect();
        let rings = outline(&ring);
        assert_eq!(rings.len(), 2);
        let edges: usize = rings.iter().map(|r| r.len() - 1).sum();
        assert_eq!(edges, 12 + 4);
        // Cells touching at a corner only: every edge once, rings closed.
        let rings = outline(&[ix(0, 0), ix(1, 1)]);
        let edges: usize = rings.iter().map(|r| r.len() - 1).sum();
        assert_eq!(edges, 8);
        assert!(rings.iter().all(|r| r.first() == r.last()));
        assert!(outline(&[]).is_empty());
    }
}
