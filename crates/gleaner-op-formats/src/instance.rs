//! Benchmark instances, their distance rules and route re-validation.

use gleaner_orienteering::Problem;

use crate::error::FormatError;

/// How the distance between two nodes is computed (TSPLIB section 2, or the classic sets'
/// float Euclidean distance). TSPLIB rules give integer distances.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DistanceRule {
    /// Float Euclidean distance, unrounded (classic Tsiligirides / Chao sets).
    Euclidean,
    /// TSPLIB EUC_2D: Euclidean distance rounded to the nearest integer.
    Euc2d,
    /// TSPLIB CEIL_2D: Euclidean distance rounded up.
    Ceil2d,
    /// TSPLIB ATT: pseudo-Euclidean distance (att48, att532).
    Att,
    /// TSPLIB GEO: great-circle distance in km on a 6378.388 km sphere, coordinates DDD.MM.
    Geo,
    /// TSPLIB EXPLICIT: distances listed in the file.
    Explicit,
}

impl DistanceRule {
    /// Distance between two coordinate pairs (`[x, y]`; for GEO `[lat, lon]` in DDD.MM).
    /// Not meaningful for [`DistanceRule::Explicit`] (returns NaN).
    pub fn distance(self, a: [f64; 2], b: [f64; 2]) -> f64 {
        let (xd, yd) = (a[0] - b[0], a[1] - b[1]);
        match self {
            DistanceRule::Euclidean => xd.hypot(yd),
            DistanceRule::Euc2d => ((xd * xd + yd * yd).sqrt() + 0.5).floor(),
            DistanceRule::Ceil2d => (xd * xd + yd * yd).sqrt().ceil(),
            DistanceRule::Att => {
                let r = ((xd * xd + yd * yd) / 10.0).sqrt();
                let t = r.trunc();
                if t < r { t + 1.0 } else { t }
            }
            DistanceRule::Geo => {
                let (lat_a, lon_a) = (geo_radians(a[0]), geo_radians(a[1]));
                let (lat_b, lon_b) = (geo_radians(b[0]), geo_radians(b[1]));
                let q1 = (lon_a - lon_b).cos();
                let q2 = (lat_a - lat_b).cos();
                let q3 = (lat_a + lat_b).cos();
                let d = 6378.388 * (0.5 * ((1.0 + q1) * q2 - (1.0 - q1) * q3)).acos() + 1.0;
                d.trunc()
            }
            DistanceRule::Explicit => f64::NAN,
        }
    }

    /// The TSPLIB keyword (or `FLOAT_EUC` for the classic sets).
    pub fn name(self) -> &'static str {
        match self {
            DistanceRule::Euclidean => "FLOAT_EUC",
            DistanceRule::Euc2d => "EUC_2D",
            DistanceRule::Ceil2d => "CEIL_2D",
            DistanceRule::Att => "ATT",
            DistanceRule::Geo => "GEO",
            DistanceRule::Explicit => "EXPLICIT",
        }
    }
}

fn geo_radians(v: f64) -> f64 {
    // TSPLIB defines GEO with this truncated value of pi; using the exact constant would
    // change some rounded distances.
    #[allow(clippy::approx_constant)]
    const PI: f64 = 3.141592;
    let deg = v.trunc();
    let min = v - deg;
    PI * (deg + 5.0 * min / 3.0) / 180.0
}

/// Which benchmark family a file belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OpFormat {
    /// Tsiligirides / Chao text format: path from point 1 to point 2.
    Classic,
    /// OPLib (TSPLIB-derived): closed tour from the depot.
    OpLib,
}

/// A parsed benchmark instance.
///
/// Node indices are 0-based (file node k is index k - 1). `problem` is the generic
/// orienteering problem (costs = the instance's distances, rewards = scores, no service
/// costs); `target` is the score to reach (classic `targets.csv` target, OPLib EA4OP best
/// known) when it was looked up.
#[derive(Debug, Clone)]
pub struct OpInstance {
    /// Instance name: the file stem (e.g. `set_64_1_15`, `eil51-gen1-50`).
    pub name: String,
    /// Set name: classic directory (`Tsiligirides_1`, `ChaoSet_64`) or OPLib generation.
    pub set: String,
    /// File family.
    pub format: OpFormat,
    /// Number of nodes.
    pub n: usize,
    /// Distance (cost) limit per route, in the instance's distance unit.
    pub budget: f64,
    /// Distance rule.
    pub rule: DistanceRule,
    /// Coordinates `[x, y]` per node (empty for EXPLICIT instances).
    pub coords: Vec<[f64; 2]>,
    /// Explicit full distance matrix (row-major, only for EXPLICIT instances).
    pub explicit: Option<Vec<f64>>,
    /// Node scores.
    pub scores: Vec<f64>,
    /// Start node (0-based).
    pub start: usize,
    /// End node (0-based; equal to `start` for closed tours).
    pub end: usize,
    /// The generic problem built from this instance.
    pub problem: Problem,
    /// Target / best-known score, when known.
    pub target: Option<f64>,
}

/// Result of [`OpInstance::validate_route`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RouteCheck {
    /// Score collected (start/end once).
    pub score: f64,
    /// Length under the instance's own distance rule.
    pub length: f64,
}

impl OpInstance {
    /// Distance between nodes `i` and `j` (0-based) recomputed from the raw data with the
    /// instance's own rule.
    pub fn distance(&self, i: usize, j: usize) -> f64 {
        match (&self.explicit, self.rule) {
            (Some(m), _) => m[i * self.n + j],
            (None, rule) => rule.distance(self.coords[i], self.coords[j]),
        }
    }

    /// The node id of 0-based index `v` as numbered in the instance file: `v + 1` (classic
    /// files number points 1, 2, ... in file order; OPLib/TSPLIB ids are 1-based).
    pub fn node_id(&self, v: usize) -> usize {
        v + 1
    }

    /// Converts a route written with node ids as numbered in the instance file (1-based)
    /// into 0-based indices.
    ///
    /// # Errors
    /// [`FormatError::Route`] for an id outside 1..=n.
    pub fn route_from_node_ids(&self, ids: &[usize]) -> Result<Vec<usize>, FormatError> {
        ids.iter()
            .map(|&id| {
                if (1..=self.n).contains(&id) {
                    Ok(id - 1)
                } else {
                    Err(FormatError::Route {
                        file: self.name.clone(),
                        message: format!("node id {id} not in 1..={}", self.n),
                    })
                }
            })
            .collect()
    }

    /// Re-checks a whole solution (0-based routes) with the instance's own distance rule —
    /// each route as [`OpInstance::validate_route`], and no node on two routes — and returns
    /// its score (start and end counted once).
    ///
    /// # Errors
    /// [`FormatError::Route`] naming the first violation.
    pub fn score_routes(&self, routes: &[Vec<usize>]) -> Result<f64, FormatError> {
        let mut seen = vec![false; self.n];
        let mut score = 0.0;
        for (r, route) in routes.iter().enumerate() {
            let c = self.validate_route(route)?;
            for &v in &route[1..route.len() - 1] {
                if std::mem::replace(&mut seen[v], true) {
                    return Err(FormatError::Route {
                        file: self.name.clone(),
                        message: format!("node {v} (0-based) on two routes"),
                    });
                }
            }
            score += c.score;
            if r > 0 {
                score -= self.scores[self.start];
                if self.end != self.start {
                    score -= self.scores[self.end];
                }
            }
        }
        Ok(score)
    }

    /// Re-validates one route (0-based nodes, starting at `start`, ending at `end`) with the
    /// instance's own distance rule: endpoints, range, no repeated node, length within the
    /// budget (exact for integer TSPLIB distances, 1e-9 relative for float ones).
    pub fn validate_route(&self, route: &[usize]) -> Result<RouteCheck, FormatError> {
        let bad = |message: String| FormatError::Route {
            file: self.name.clone(),
            message,
        };
        if route.len() < 2 || route[0] != self.start || route[route.len() - 1] != self.end {
            return Err(bad(format!(
                "route must run from node {} to node {} (0-based), got {:?}",
                self.start,
                self.end,
                (route.first(), route.last())
            )));
        }
        let mut seen = vec![false; self.n];
        let mut score = self.scores[self.start];
        if self.end != self.start {
            score += self.scores[self.end];
        }
        seen[self.start] = true;
        seen[self.end] = true;
        for &v in &route[1..route.len() - 1] {
            if v >= self.n {
                return Err(bad(format!("node {v} out of range for {} nodes", self.n)));
            }
            if seen[v] {
                return Err(bad(format!("node {v} visited twice")));
            }
            seen[v] = true;
            score += self.scores[v];
        }
        let length: f64 = route.windows(2).map(|w| self.distance(w[0], w[1])).sum();
        let tol = match self.rule {
            DistanceRule::Euclidean => 1e-9 * self.budget.max(1.0),
            _ => 0.0,
        };
        if length > self.budget + tol {
            return Err(bad(format!(
                "length {length} exceeds the budget {}",
                self.budget
            )));
        }
        Ok(RouteCheck { score, length })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(rule: DistanceRule, a: [f64; 2], b: [f64; 2], expected: f64) {
        assert_eq!(rule.distance(a, b), expected, "{rule:?} {a:?} {b:?}");
    }

    #[test]
    fn distance_rules() {
        check(DistanceRule::Euclidean, [0.0, 0.0], [3.0, 4.0], 5.0);
        check(DistanceRule::Euc2d, [0.0, 0.0], [3.0, 4.4], 5.0); // 5.325 -> 5
        check(DistanceRule::Euc2d, [0.0, 0.0], [3.0, 4.8], 6.0); // 5.660 -> 6
        check(DistanceRule::Ceil2d, [0.0, 0.0], [3.0, 4.4], 6.0);
        check(DistanceRule::Att, [0.0, 0.0], [10.0, 0.0], 4.0); // sqrt(10) = 3.16 -> 4
        check(DistanceRule::Att, [0.0, 0.0], [0.0, 0.0], 0.0);
        // Augsburg (48.23, 10.53) to Berlin (52.31, 13.24): 494 km; Sydney to London 17014 km
        // (values from an independent implementation of the TSPLIB formula).
        check(DistanceRule::Geo, [48.23, 10.53], [52.31, 13.24], 494.0);
        check(DistanceRule::Geo, [-33.52, 151.13], [51.30, -0.07], 17014.0);
        assert!(
            DistanceRule::Explicit
                .distance([0.0, 0.0], [1.0, 1.0])
                .is_nan()
        );
    }
}
