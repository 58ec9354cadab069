//! Directed (asymmetric) instances: costs from a displacement (a steady drift, as a wind
//! makes) and random asymmetric matrices. Every solver's routes re-validate, the search alone
//! finds the exact optimum of one route, pruning keeps every node of a feasible route, and
//! the tour improvement ends where no segment reversal and no single-node move would lower
//! the true directed cost (so every move is evaluated in the direction it is flown).

use std::sync::Arc;

use gleaner_orienteering::{
    ImproveOptions, Problem, SolveOptions, evaluate, exact, greedy, improve_routes, route_cost,
    solve_default,
};
use proptest::prelude::*;

/// Cost of a displacement in a drift of `k` (0 <= k < 1) along +x: the distance plus `k`
/// times the displacement against the drift, >= (1 − k)·distance.
fn drift(k: f64) -> gleaner_orienteering::DisplacementCost {
    Arc::new(move |dx: f64, dy: f64| (dx * dx + dy * dy).sqrt() - k * dx)
}

/// A random directed instance of up to `max_n` nodes: points with a drift cost, or a random
/// asymmetric matrix (entries 1-100, no triangle inequality); service costs, start != end
/// possible, 1-2 vehicles.
fn directed_instance(max_n: usize) -> impl Strategy<Value = Problem> {
    (3usize..=max_n)
        .prop_flat_map(|n| {
            (
                prop::collection::vec((0.0f64..100.0, 0.0f64..100.0), n),
                prop::collection::vec(1u32..=100, n * n),
                prop::collection::vec(0u32..20, n),
                prop::collection::vec(0.0f64..15.0, n),
                0..n,
                0..n,
                0.0f64..1.0,
                1usize..=2,
                0.0f64..0.9,
                any::<bool>(),
            )
        })
        .prop_filter_map(
            "infeasible",
            |(pts, matrix, rw, svc, s, e, frac, k, drift_k, points)| {
                let n = rw.len();
                let rewards: Vec<f64> = rw.iter().map(|&r| f64::from(r)).collect();
                let problem = if points {
                    let points: Vec<[f64; 2]> = pts.iter().map(|&(x, y)| [x, y]).collect();
                    Problem::from_displacement_costs(&points, drift(drift_k), rewards, 1e9).ok()?
                } else {
                    let mut cost: Vec<f64> = matrix.iter().map(|&c| f64::from(c)).collect();
                    for i in 0..n {
                        cost[i * n + i] = 0.0;
                    }
                    Problem::new_directed(cost, rewards, 1e9).ok()?
                };
                let direct = problem.cost(s, e) + svc[s] + if e != s { svc[e] } else { 0.0 };
                let budget = direct + frac * 300.0;
                problem
                    .with_budget(budget)
                    .ok()?
                    .with_service_costs(svc)
                    .ok()?
                    .with_endpoints(s, e)
                    .ok()?
                    .with_vehicles(k)
                    .ok()
            },
        )
}

/// Nodes on at least one feasible route (brute force over ordered subsets; n <= 7).
fn on_some_feasible_route(p: &Problem) -> Vec<usize> {
    fn grow(p: &Problem, route: &mut Vec<usize>, used: &mut [bool], found: &mut [bool]) {
        let mut closed = route.clone();
        closed.push(p.end());
        if route_cost(p, &closed) <= p.budget() + p.tolerance() {
            for &v in &route[1..] {
                found[v] = true;
            }
        }
        for v in 0..p.len() {
            if !used[v] && !p.is_terminal(v) {
                used[v] = true;
                route.push(v);
                grow(p, route, used, found);
                route.pop();
                used[v] = false;
            }
        }
    }
    let mut found = vec![false; p.len()];
    let mut used = vec![false; p.len()];
    grow(p, &mut vec![p.start()], &mut used, &mut found);
    (0..p.len())
        .filter(|&v| found[v] && p.reward(v) > 0.0 && !p.is_terminal(v))
        .collect()
}

/// True when the costs satisfy the triangle inequality (within `eps`).
fn triangle(p: &Problem, eps: f64) -> bool {
    let n = p.len();
    (0..n)
        .all(|i| (0..n).all(|j| (0..n).all(|k| p.cost(i, j) <= p.cost(i, k) + p.cost(k, j) + eps)))
}

/// A route obtained from `route` by reversing one interior segment or (`moves`) moving one
/// interior node elsewhere (true directed costs), if cheaper than `route` by more than `eps`.
fn improving_neighbour(p: &Problem, route: &[usize], eps: f64, moves: bool) -> Option<Vec<usize>> {
    let m = route.len();
    let base = route_cost(p, route);
    for lo in 1..m.saturating_sub(1) {
        for hi in lo + 1..m - 1 {
            let mut r = route.to_vec();
            r[lo..=hi].reverse();
            if route_cost(p, &r) < base - eps {
                return Some(r);
            }
        }
    }
    if !moves {
        return None;
    }
    for from in 1..m.saturating_sub(1) {
        for to in 1..m - 1 {
            if to == from {
                continue;
            }
            let mut r = route.to_vec();
            let v = r.remove(from);
            r.insert(to, v);
            if route_cost(p, &r) < base - eps {
                return Some(r);
            }
        }
    }
    None
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// Every solver's routes re-validate on directed costs; the default is never below
    /// greedy; the search alone (exact shortcut off) finds the exact optimum of one route.
    #[test]
    fn directed_solvers_are_feasible_and_optimal(p in directed_instance(12)) {
        prop_assert!(!p.is_symmetric());
        let g = greedy(&p);
        prop_assert!(evaluate(&p, &g.routes).is_ok());
        let opts = SolveOptions { exact_threshold: 0, ..SolveOptions::default() }
            .with_iterations(1000);
        let d = solve_default(&p, &opts);
        let checked = evaluate(&p, &d.routes);
        prop_assert!(checked.is_ok(), "{:?}", checked);
        let checked = checked.unwrap();
        prop_assert!((checked.reward - d.reward).abs() < 1e-9);
        for (c, r) in d.costs.iter().zip(&d.routes) {
            prop_assert!((c - route_cost(&p, r)).abs() <= 1e-9 * (1.0 + c.abs()), "{c} vs {}", route_cost(&p, r));
        }
        prop_assert!(d.reward >= g.reward - 1e-9);
        let x = exact(&p).unwrap();
        prop_assert!(evaluate(&p, &x.routes).is_ok());
        prop_assert!(x.reward >= d.reward - 1e-9);
        // On costs that obey the triangle inequality (a drift, as a wind makes) the search
        // alone finds the optimum of one route; random matrices only bound it.
        if p.vehicles() == 1 && triangle(&p, 1e-9) {
            prop_assert!((d.reward - x.reward).abs() < 1e-9, "ils {} exact {} {:?} {:?}", d.reward, x.reward, d.routes, x.routes);
        }
        let auto = solve_default(&p, &SolveOptions::default().with_iterations(10));
        prop_assert!((auto.reward - x.reward).abs() < 1e-9);
    }

    /// Pruning keeps every node of positive reward on some feasible route (reverse-arc
    /// distances to the end on directed costs).
    #[test]
    fn directed_pruning_keeps_every_node_of_a_feasible_route(p in directed_instance(7)) {
        let kept = p.reachable_candidates();
        for v in on_some_feasible_route(&p) {
            prop_assert!(kept.contains(&v), "node {v} is on a feasible route but pruned: {kept:?}");
        }
    }

    /// Tour improvement of a closed tour through every node, started the wrong way round:
    /// the result keeps the nodes, never costs more, its reported cost is its true directed
    /// cost, and no segment reversal or single-node move would make it cheaper.
    #[test]
    fn directed_tour_improvement_reaches_a_true_local_optimum(p in directed_instance(10), seed in 0u64..3) {
        let n = p.len();
        let mut tour: Vec<usize> = (0..n).collect();
        tour.push(0);
        tour[1..n].reverse();
        // A budget of about the tour's cost: the moves' threshold is 1e-9 of it.
        let loose = p.with_endpoints(0, 0).unwrap().with_vehicles(1).unwrap().with_budget(1e9).unwrap();
        let before = route_cost(&loose, &tour);
        let p = loose.with_budget(before + 1.0).unwrap();
        let o = ImproveOptions { seed, ..ImproveOptions::default() };
        let after = improve_routes(&p, &[tour.clone()], &o).unwrap();
        let r = &after.routes[0];
        let mut nodes = r.clone();
        nodes.sort_unstable();
        nodes.dedup();
        prop_assert_eq!(nodes.len(), n);
        let cost = route_cost(&p, r);
        prop_assert!(cost <= before + 1e-9);
        prop_assert!((after.costs[0] - cost).abs() <= 1e-9 * (1.0 + cost));
        // 2-opt sees every reversal (short routes: all pairs). Or-opt moves a node only when
        // taking it out saves something, which is every improving move when the costs obey
        // the triangle inequality (the drift costs do; the random matrices need not).
        let eps = 1e-9 * (1.0 + cost);
        let moves = triangle(&p, eps);
        prop_assert!(improving_neighbour(&p, r, eps, moves).is_none(), "{r:?} ({cost}) can improve");
    }
}

/// A ring that is cheap one way round (1 per arc) and dear the other (10): started backwards,
/// the tour improvement turns it round — a symmetric reading of the reversal would not see
/// that its inner arcs change too.
#[test]
fn a_backwards_ring_is_turned_round() {
    let n = 6;
    let mut cost = vec![20.0; n * n];
    for i in 0..n {
        cost[i * n + i] = 0.0;
        cost[i * n + (i + 1) % n] = 1.0;
        cost[((i + 1) % n) * n + i] = 10.0;
    }
    let p = Problem::new_directed(cost.clone(), vec![0.0; n], 1e3).unwrap();
    assert!(Problem::new(cost, vec![0.0; n], 1e3).is_err());
    let backwards = vec![0, 5, 4, 3, 2, 1, 0];
    assert_eq!(route_cost(&p, &backwards), 60.0);
    let s = improve_routes(&p, &[backwards], &ImproveOptions::default()).unwrap();
    assert_eq!(s.routes[0], vec![0, 1, 2, 3, 4, 5, 0]);
    assert_eq!(s.costs[0], 6.0);
    // The solver collects every reward it can: the forward ring fits a budget of 6, the
    // backward one would not.
    let q = Problem::new_directed(
        (0..n * n)
            .map(|ij| {
                let (i, j) = (ij / n, ij % n);
                if i == j {
                    0.0
                } else if j == (i + 1) % n {
                    1.0
                } else if i == (j + 1) % n {
                    10.0
                } else {
                    20.0
                }
            })
            .collect(),
        vec![0.0, 1.0, 1.0, 1.0, 1.0, 1.0],
        6.0,
    )
    .unwrap();
    let best = solve_default(&q, &SolveOptions::default().with_iterations(50));
    assert_eq!(best.reward, 5.0);
    assert_eq!(exact(&q).unwrap().reward, 5.0);
}

/// A displacement problem evaluates its cost function in the direction of travel, tabulated
/// or not, and refuses a cost that is negative or not zero at rest.
#[test]
fn displacement_costs_are_directed() {
    let pts = [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0]];
    let p = Problem::from_displacement_costs(&pts, drift(0.5), vec![0.0, 1.0, 1.0], 100.0).unwrap();
    assert_eq!(p.cost(0, 1), 5.0);
    assert_eq!(p.cost(1, 0), 15.0);
    assert!(!p.is_symmetric() && !p.is_metric() && p.points().is_none());
    let neg = Arc::new(|dx: f64, _dy: f64| dx);
    assert!(Problem::from_displacement_costs(&pts, neg, vec![0.0; 3], 100.0).is_err());
    let offset = Arc::new(|_dx: f64, _dy: f64| 1.0);
    assert!(Problem::from_displacement_costs(&pts, offset, vec![0.0; 3], 100.0).is_err());
    // Above 1,024 nodes: on demand, the same values.
    let many: Vec<[f64; 2]> = (0..1_100).map(|i| [i as f64, (i % 7) as f64]).collect();
    let big =
        Problem::from_displacement_costs(&many, drift(0.5), vec![1.0; many.len()], 1e9).unwrap();
    assert_eq!(big.cost(3, 9), drift(0.5)(6.0, 2.0 - 3.0));
    assert!(big.cost(9, 3) > big.cost(3, 9));
}
