//! Legs flown around no-fly zones: the turn points of every leg between the base and the
//! candidates, and each leg's length, for the planner's cost matrix and the energy re-check.

use gleaner_energy::path_length_m;
use gleaner_field::LocalPoint;

/// The legs between every pair of nodes — node 0 the base, node `k + 1` candidate `k` — as
/// polylines: the turn points between the two ends (local frame, m; empty for a straight
/// leg) and the leg's length ([`gleaner_energy::path_length_m`] of start, turn points, end;
/// the function the energy model prices legs with, so the planner's costs and the re-check
/// agree to the last bit). A node with no leg to the base is *unreachable*: its legs are
/// infinite and it is never planned. Two reachable nodes the zones separate otherwise are
/// joined through the base (the legs to and from it, the base as a turn point).
#[derive(Debug, Clone, PartialEq)]
pub struct Detours {
    n: usize,
    via: Vec<Vec<LocalPoint>>,
    length_m: Vec<f64>,
}

impl Detours {
    /// The legs among `points` (the base first, then the candidates in order; local frame,
    /// m) from `via(i, j)`: the turn points from node `i` to node `j` in flying order, `None`
    /// when there is no leg (e.g. `gleaner_airspace::Paths::via`). Only `i != j` is asked.
    pub fn new(
        points: &[LocalPoint],
        mut via: impl FnMut(usize, usize) -> Option<Vec<LocalPoint>>,
    ) -> Self {
        let n = points.len();
        let mut found: Vec<Option<Vec<LocalPoint>>> = vec![None; n * n];
        for i in 0..n {
            found[i * n + i] = Some(Vec::new());
            for j in 0..n {
                if i != j {
                    found[i * n + j] = via(i, j);
                }
            }
        }
        let reachable: Vec<bool> = (0..n)
            .map(|k| k == 0 || (found[k].is_some() && found[k * n].is_some()))
            .collect();
        let mut out = Self {
            n,
            via: vec![Vec::new(); n * n],
            length_m: vec![f64::INFINITY; n * n],
        };
        let mut polyline = Vec::new();
        for i in 0..n {
            for j in 0..n {
                if !(reachable[i] && reachable[j]) {
                    continue;
                }
                let turns = match found[i * n + j].clone() {
                    Some(t) => t,
                    None => {
                        // Through the base: i -> base -> j.
                        let mut t = found_via(&found, n, i, 0);
                        t.push(points[0]);
                        t.extend(found_via(&found, n, 0, j));
                        t
                    }
                };
                polyline.clear();
                polyline.push(points[i]);
                polyline.extend_from_slice(&turns);
                polyline.push(points[j]);
                out.length_m[i * n + j] = if i == j {
                    0.0
                } else {
                    path_length_m(&polyline)
                };
                out.via[i * n + j] = turns;
            }
        }
        out
    }

    /// Straight legs among `points` (no zone).
    pub fn straight(points: &[LocalPoint]) -> Self {
        Self::new(points, |_, _| Some(Vec::new()))
    }

    /// Number of nodes (base + candidates).
    pub fn len(&self) -> usize {
        self.n
    }

    /// True without nodes.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// True when node `k` has a leg to and from the base (the base always does).
    pub fn reachable(&self, k: usize) -> bool {
        k == 0 || self.length_m[k * self.n].is_finite()
    }

    /// The leg's length from node `i` to node `j`, m (infinite when either is unreachable).
    pub fn length_m(&self, i: usize, j: usize) -> f64 {
        self.length_m[i * self.n + j]
    }

    /// The leg's turn points from node `i` to node `j`, in flying order (local frame, m).
    pub fn via(&self, i: usize, j: usize) -> &[LocalPoint] {
        &self.via[i * self.n + j]
    }

    /// The turn points of every leg of the sortie base -> `order` (candidate indices) ->
    /// base, for [`gleaner_energy::MissionEnergyModel::breakdown_paths`]: one entry per
    /// stop and one for the return leg (none for an empty order).
    pub fn route_via(&self, order: &[usize]) -> Vec<Vec<LocalPoint>> {
        if order.is_empty() {
            return Vec::new();
        }
        let mut prev = 0;
        let mut out = Vec::with_capacity(order.len() + 1);
        for &k in order {
            out.push(self.via(prev, k + 1).to_vec());
            prev = k + 1;
        }
        out.push(self.via(prev, 0).to_vec());
        out
    }
}

/// The turn points found from `i` to `j` (empty when none was found).
fn found_via(found: &[Option<Vec<LocalPoint>>], n: usize, i: usize, j: usize) -> Vec<LocalPoint> {
    found[i * n + j].clone().unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn legs_are_path_lengths_and_separated_cells_go_through_the_base() {
        let pts = [
            LocalPoint::new(0.0, 0.0),
            LocalPoint::new(100.0, 0.0),
            LocalPoint::new(0.0, 100.0),
            LocalPoint::new(50.0, 50.0),
        ];
        // 1 and 2 are separated (no leg); 3 is unreachable.
        let d = Detours::new(&pts, |i, j| match (i.min(j), i.max(j)) {
            (_, 3) => None,
            (1, 2) => None,
            (0, 1) => Some(vec![LocalPoint::new(50.0, -10.0)]),
            _ => Some(Vec::new()),
        });
        assert!(d.reachable(1) && d.reachable(2) && !d.reachable(3));
        assert!(d.length_m(0, 3).is_infinite());
        let around = 2.0 * (50.0f64.hypot(10.0));
        assert!((d.length_m(0, 1) - around).abs() < 1e-9);
        assert_eq!(d.length_m(0, 2), 100.0);
        // Through the base.
        assert_eq!(d.via(1, 2).last(), Some(&LocalPoint::new(0.0, 0.0)));
        assert!((d.length_m(1, 2) - (around + 100.0)).abs() < 1e-9);
        assert_eq!(d.route_via(&[0, 1]).len(), 3);
        let s = Detours::straight(&pts);
        assert_eq!(s.length_m(1, 2), 100.0 * 2f64.sqrt());
    }
}
