//! Property tests on random instances (n <= 12, service costs, start != end, 1-2 vehicles;
//! non-metric cost matrices with a planted shortcut; 30-80 nodes for the large-instance paths):
//! every solver's routes re-validate, default >= greedy, the default solver equals the exact
//! optimum, and so does the iterated local search alone (exact shortcut disabled) for one
//! vehicle. (For two vehicles the search alone occasionally stays 1 short of the optimum
//! within 1,000 iterations, which is why the default solves such small teams exactly.) Pruning
//! keeps every node of a feasible route, and the pruned search scores at least as much as the
//! unpruned one.

use gleaner_orienteering::{
    ImproveOptions, Metric, Problem, SolveOptions, evaluate, exact, greedy, improve_routes,
    route_cost, solve_default,
};
use proptest::prelude::*;

/// A random Euclidean instance with up to 12 nodes, service costs and possibly start != end.
fn instance() -> impl Strategy<Value = Problem> {
    (3usize..=12)
        .prop_flat_map(|n| {
            (
                prop::collection::vec((0.0f64..100.0, 0.0f64..100.0), n),
                prop::collection::vec(0u32..20, n),
                prop::collection::vec(0.0f64..15.0, n),
                0..n,
                0..n,
                0.0f64..1.0,
                1usize..=2,
            )
        })
        .prop_filter_map("infeasible", |(pts, rw, svc, s, e, frac, k)| {
            let points: Vec<[f64; 2]> = pts.iter().map(|&(x, y)| [x, y]).collect();
            let rewards: Vec<f64> = rw.iter().map(|&r| f64::from(r)).collect();
            let direct = Metric::Euclidean.distance(points[s], points[e]) + svc[s] + svc[e];
            let budget = direct + frac * 300.0;
            Problem::from_points(&points, Metric::Euclidean, rewards, budget)
                .ok()?
                .with_service_costs(svc)
                .ok()?
                .with_endpoints(s, e)
                .ok()?
                .with_vehicles(k)
                .ok()
        })
}

/// Plain re-implementation of the paper's greedy (every step rescans every node, route and
/// position), as the reference for the incremental implementation.
fn reference_greedy(p: &Problem) -> Vec<Vec<usize>> {
    let mut routes = vec![vec![p.start(), p.end()]; p.vehicles()];
    let mut costs: Vec<f64> = routes.iter().map(|r| route_cost(p, r)).collect();
    let mut on = vec![false; p.len()];
    loop {
        let mut best: Option<(f64, f64, usize, usize, usize, f64)> = None;
        for (v, _) in on.iter().enumerate().filter(|&(_, &seen)| !seen) {
            if p.is_terminal(v) || p.reward(v) <= 0.0 {
                continue;
            }
            for (r, route) in routes.iter().enumerate() {
                let (mut d, mut at) = (f64::INFINITY, 0);
                for (t, w) in route.windows(2).enumerate() {
                    let x = p.cost(w[0], v) + p.cost(v, w[1]) - p.cost(w[0], w[1]) + p.service(v);
                    if x < d {
                        (d, at) = (x, t + 1);
                    }
                }
                if costs[r] + d > p.budget() + p.tolerance() {
                    continue;
                }
                let ratio = if d <= 1e-12 {
                    f64::INFINITY
                } else {
                    p.reward(v) / d
                };
                let wins = best.is_none_or(|b| {
                    ratio > b.0
                        || (ratio == b.0
                            && (p.reward(v) > b.1
                                || (p.reward(v) == b.1 && (v < b.2 || (v == b.2 && r < b.3)))))
                });
                if wins {
                    best = Some((ratio, p.reward(v), v, r, at, d));
                }
            }
        }
        let Some((_, _, v, r, at, d)) = best else {
            break;
        };
        routes[r].insert(at, v);
        costs[r] += d;
        on[v] = true;
    }
    routes
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn greedy_matches_reference(p in instance()) {
        prop_assert_eq!(greedy(&p).routes, reference_greedy(&p));
    }

    #[test]
    fn solvers_are_feasible_and_ordered(p in instance()) {
        let g = greedy(&p);
        prop_assert!(evaluate(&p, &g.routes).is_ok());
        let opts = SolveOptions { exact_threshold: 0, ..SolveOptions::default() }
            .with_iterations(1000);
        let d = solve_default(&p, &opts);
        let checked = evaluate(&p, &d.routes);
        prop_assert!(checked.is_ok(), "{:?}", checked);
        prop_assert!(d.reward >= g.reward - 1e-9);
        let x = exact(&p).unwrap();
        prop_assert!(evaluate(&p, &x.routes).is_ok());
        prop_assert!((checked.unwrap().reward - d.reward).abs() < 1e-9);
        prop_assert!(x.reward >= d.reward - 1e-9);
        if p.vehicles() == 1 {
            // The search alone (exact shortcut disabled) finds the optimum of one route.
            prop_assert!((d.reward - x.reward).abs() < 1e-9, "ils {} exact {} {:?} {:?}", d.reward, x.reward, d.routes, x.routes);
        }
        let auto = solve_default(&p, &SolveOptions::default().with_iterations(10));
        prop_assert!((auto.reward - x.reward).abs() < 1e-9);
    }

    #[test]
    fn improvement_keeps_the_nodes_and_never_costs_more(p in instance(), kicks in 0usize..3, seed in 0u64..4) {
        // Greedy's routes, each interior reversed and rotated so there is work to do.
        let mut routes = greedy(&p).routes;
        for (k, r) in routes.iter_mut().enumerate() {
            let m = r.len();
            if m > 3 {
                r[1..m - 1].reverse();
                r[1..m - 1].rotate_left(k % (m - 2));
            }
        }
        let Ok(before) = evaluate(&p, &routes) else { return Ok(()); };
        let o = ImproveOptions { kicks, seed, ..ImproveOptions::default() };
        let after = improve_routes(&p, &routes, &o).unwrap();
        let checked = evaluate(&p, &after.routes);
        prop_assert!(checked.is_ok(), "{:?}", checked);
        prop_assert!(after.total_cost() <= before.total_cost() + 1e-9);
        let nodes = |rs: &[Vec<usize>]| {
            let mut v: Vec<usize> = rs.iter().flat_map(|r| r[1..r.len() - 1].to_vec()).collect();
            v.sort_unstable();
            v
        };
        prop_assert_eq!(nodes(&after.routes), nodes(&routes));
        prop_assert_eq!(after.routes.len(), routes.len());
        prop_assert_eq!(&improve_routes(&p, &routes, &o).unwrap(), &after);
    }
}

/// A random instance with up to `max_n` nodes on an explicit symmetric cost matrix whose
/// entries (1-100) need not satisfy the triangle inequality, with a shortcut planted: node
/// `v` is far from the start directly (beyond the budget) but near through node `u`. Service
/// costs, start != end possible. Pruning by direct costs would wrongly drop `v`.
fn non_metric_instance(max_n: usize) -> impl Strategy<Value = Problem> {
    (4usize..=max_n)
        .prop_flat_map(|n| {
            (
                prop::collection::vec(1u32..=100, n * n),
                prop::collection::vec(0u32..20, n),
                prop::collection::vec(0u32..10, n),
                0..n,
                0..n,
                0u32..=150,
                any::<prop::sample::Index>(),
                any::<prop::sample::Index>(),
            )
        })
        .prop_filter_map("infeasible", |(c, rw, svc, s, e, extra, iu, iv)| {
            let n = rw.len();
            let mut cost = vec![0.0; n * n];
            for i in 0..n {
                for j in (i + 1)..n {
                    let x = f64::from(c[i * n + j]);
                    cost[i * n + j] = x;
                    cost[j * n + i] = x;
                }
            }
            let others: Vec<usize> = (0..n).filter(|&x| x != s && x != e).collect();
            if others.len() < 2 {
                return None;
            }
            let u = others[iu.index(others.len())];
            let rest: Vec<usize> = others.iter().copied().filter(|&x| x != u).collect();
            let v = rest[iv.index(rest.len())];
            let service: Vec<f64> = svc.iter().map(|&x| f64::from(x)).collect();
            let direct = cost[s * n + e] + service[s] + if e != s { service[e] } else { 0.0 };
            let budget = direct + f64::from(extra);
            // The shortcut: s - u - v cheap, s - v direct beyond the budget.
            for (a, b, x) in [(s, u, 2.0), (u, v, 2.0), (s, v, budget + 50.0)] {
                cost[a * n + b] = x;
                cost[b * n + a] = x;
            }
            let mut rewards: Vec<f64> = rw.iter().map(|&r| f64::from(r)).collect();
            rewards[v] += 30.0;
            Problem::new(cost, rewards, budget)
                .ok()?
                .with_service_costs(service)
                .ok()?
                .with_endpoints(s, e)
                .ok()
        })
}

/// Nodes on at least one feasible route (brute force over every ordered subset; n <= 7).
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

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// Pruning is sound: every node of positive reward that lies on some feasible route
    /// (brute force) is kept, also when the costs break the triangle inequality (the planted
    /// shortcut), and on Euclidean instances.
    #[test]
    fn pruning_keeps_every_node_of_a_feasible_route(
        p in prop_oneof![non_metric_instance(7), instance().prop_filter("small", |p| p.len() <= 7)]
    ) {
        let kept = p.reachable_candidates();
        for v in on_some_feasible_route(&p) {
            prop_assert!(kept.contains(&v), "node {v} is on a feasible route but pruned: {kept:?}");
        }
    }

    /// The pruned search (the default) never returns an infeasible route, never less than
    /// its greedy start nor more than the exact optimum, and the unpruned search
    /// (`prune: false`) only ever visits nodes pruning kept. Which of the two scores more is
    /// not an invariant: pruning changes the random moves' trajectory, and on non-metric
    /// instances either can stop one unit short of the optimum (seen: 43 against 44).
    /// Pruning's soundness itself is `pruning_keeps_every_node_of_a_feasible_route`.
    #[test]
    fn pruned_search_is_feasible_and_bounded(
        p in prop_oneof![non_metric_instance(10), instance()],
        seed in 0u64..3,
    ) {
        let opts = SolveOptions { exact_threshold: 0, ..SolveOptions::default() }
            .with_iterations(300)
            .with_seed(seed);
        let pruned = solve_default(&p, &opts);
        let checked = evaluate(&p, &pruned.routes);
        prop_assert!(checked.is_ok(), "{:?}", checked);
        prop_assert!(pruned.reward >= greedy(&p).reward - 1e-9);
        let full = solve_default(&p, &SolveOptions { prune: false, ..opts });
        prop_assert!(evaluate(&p, &full.routes).is_ok());
        let kept = p.reachable_candidates();
        for v in full.routes.iter().flatten().filter(|&&v| !p.is_terminal(v) && p.reward(v) > 0.0) {
            prop_assert!(kept.contains(v), "unpruned search visits {v}, which pruning left out");
        }
        let x = exact(&p).unwrap();
        prop_assert!(full.reward <= x.reward + 1e-9);
        prop_assert!(pruned.reward <= x.reward + 1e-9);
    }
}

/// A random Euclidean instance of 30-80 nodes with service costs, a closed tour from a node
/// near the middle and a budget reaching part of the square (some nodes out of reach).
fn medium_instance() -> impl Strategy<Value = Problem> {
    (30usize..=80)
        .prop_flat_map(|n| {
            (
                prop::collection::vec((0.0f64..1000.0, 0.0f64..1000.0), n),
                prop::collection::vec(0u32..20, n),
                prop::collection::vec(0.0f64..60.0, n),
                300.0f64..1500.0,
            )
        })
        .prop_filter_map("infeasible", |(mut pts, rw, svc, budget)| {
            pts[0] = (500.0, 500.0);
            let points: Vec<[f64; 2]> = pts.iter().map(|&(x, y)| [x, y]).collect();
            let rewards: Vec<f64> = rw.iter().map(|&r| f64::from(r)).collect();
            Problem::from_points(&points, Metric::Euclidean, rewards, budget)
                .ok()?
                .with_service_costs(svc)
                .ok()
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(40))]

    /// The large-instance paths (insertion and replacement next to candidate neighbours,
    /// forced here by `full_scan_limit: 0`) with pruning never return an infeasible route nor
    /// less than greedy, and every visited node is a reachable candidate.
    #[test]
    fn restricted_pruned_search_is_feasible(p in medium_instance(), seed in 0u64..3) {
        let opts = SolveOptions { exact_threshold: 0, full_scan_limit: 0, ..SolveOptions::default() }
            .with_iterations(60)
            .with_seed(seed);
        let s = solve_default(&p, &opts);
        let checked = evaluate(&p, &s.routes);
        prop_assert!(checked.is_ok(), "{:?}", checked);
        prop_assert!(s.reward >= greedy(&p).reward - 1e-9);
        let kept = p.reachable_candidates();
        for r in &s.routes {
            for v in &r[1..r.len() - 1] {
                prop_assert!(kept.contains(v));
            }
        }
    }
}
