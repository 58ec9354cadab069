//! Exact solver: dynamic programming over subsets of the rewarded nodes (Held-Karp style).

use crate::error::SolveError;
use crate::problem::Problem;
use crate::solution::{Solution, evaluate};

/// Largest number of candidate nodes (non-terminal, positive reward) for one vehicle.
pub const EXACT_MAX_NODES: usize = 18;
/// Largest number of candidate nodes when there are several vehicles.
pub const EXACT_MAX_NODES_TEAM: usize = 14;

/// Solves the problem to proven optimality.
///
/// Only nodes with positive reward are considered (nodes of zero reward could only help as
/// shortcuts, which never happens when costs obey the triangle inequality). For every subset
/// S of candidates and last node j it computes the cheapest path start -> S -> j (travel plus
/// service, budget unit); a subset is feasible when closing to the end node fits the budget.
/// With several vehicles the best combination of disjoint feasible subsets is found by a
/// subset convolution. Memory: 2^c · c · 8 bytes for c candidates (37 MB at c = 18).
///
/// Errors: [`SolveError::TooLargeForExact`] when there are more than [`EXACT_MAX_NODES`]
/// (one vehicle) or [`EXACT_MAX_NODES_TEAM`] (several) candidates.
pub fn exact(problem: &Problem) -> Result<Solution, SolveError> {
    let p = problem;
    let cands: Vec<usize> = (0..p.len())
        .filter(|&v| !p.is_terminal(v) && p.reward(v) > 0.0)
        .collect();
    let c = cands.len();
    let max = if p.vehicles() == 1 {
        EXACT_MAX_NODES
    } else {
        EXACT_MAX_NODES_TEAM
    };
    if c > max {
        return Err(SolveError::TooLargeForExact { got: c, max });
    }
    let (s, e) = (p.start(), p.end());
    let limit = p.budget() + p.tolerance();
    let base = p.empty_route_cost() - p.cost(s, e);
    let full = 1usize << c;
    let mut dp = vec![f64::INFINITY; full * c.max(1)];
    for j in 0..c {
        dp[(1 << j) * c + j] = base + p.cost(s, cands[j]) + p.service(cands[j]);
    }
    // closed[S]: cheapest complete route over exactly S (budget unit), last[S]: its last node.
    let mut closed = vec![f64::INFINITY; full];
    let mut last = vec![usize::MAX; full];
    closed[0] = p.empty_route_cost();
    for set in 1..full {
        for j in 0..c {
            let here = dp[set * c + j];
            if set & (1 << j) == 0 || here > limit {
                continue;
            }
            let done = here + p.cost(cands[j], e);
            if done < closed[set] {
                closed[set] = done;
                last[set] = j;
            }
            for k in 0..c {
                if set & (1 << k) != 0 {
                    continue;
                }
                let next = here + p.cost(cands[j], cands[k]) + p.service(cands[k]);
                let slot = &mut dp[(set | (1 << k)) * c + k];
                if next < *slot {
                    *slot = next;
                }
            }
        }
    }
    let reward_of = |set: usize| -> f64 {
        (0..c)
            .filter(|&j| set & (1 << j) != 0)
            .map(|j| p.reward(cands[j]))
            .sum()
    };
    let mut value = vec![f64::NEG_INFINITY; full];
    for set in 0..full {
        if closed[set] <= limit {
            value[set] = reward_of(set);
        }
    }
    // Choose the subsets: one per vehicle, disjoint.
    let mut chosen: Vec<usize> = Vec::new();
    if p.vehicles() == 1 {
        let mut best = 0usize;
        for set in 0..full {
            if value[set] > value[best] || (value[set] == value[best] && closed[set] < closed[best])
            {
                best = set;
            }
        }
        chosen.push(best);
    } else {
        chosen = choose_disjoint(&value, c, p.vehicles());
    }
    // Rebuild each route backwards through dp.
    let mut routes = Vec::new();
    for set in chosen {
        let seq = if set == 0 {
            Vec::new()
        } else {
            rebuild(p, &cands, &dp, last[set], set)
        };
        let mut route = vec![s];
        route.extend(seq);
        route.push(e);
        routes.push(route);
    }
    // Reconstruction is exact by construction; evaluation guards against rounding.
    Ok(evaluate(p, &routes).unwrap_or_else(|_| Solution::empty(p)))
}

/// The best `vehicles` disjoint feasible subsets by a subset convolution over `value` (each
/// subset's reward, −∞ when infeasible; 2^c entries): the chosen subsets (empty ones left out
/// but the last).
fn choose_disjoint(value: &[f64], c: usize, vehicles: usize) -> Vec<usize> {
    let full = value.len();
    let mut chosen = Vec::new();
    // g[k][U]: best reward of k disjoint feasible subsets within U.
    let mut layers: Vec<Vec<f64>> = vec![value.to_vec()];
    // Make layer 1 monotone over supersets (best feasible subset within U).
    let mut arg1: Vec<usize> = (0..full).collect();
    for bit in 0..c {
        for set in 0..full {
            if set & (1 << bit) != 0 {
                let sub = set ^ (1 << bit);
                if layers[0][sub] > layers[0][set] {
                    layers[0][set] = layers[0][sub];
                    arg1[set] = arg1[sub];
                }
            }
        }
    }
    let mut args: Vec<Vec<usize>> = vec![arg1];
    for _ in 1..vehicles.min(c.max(1)) {
        let prev = layers.last().cloned().unwrap_or_default();
        let mut cur = prev.clone();
        let mut arg = vec![0usize; full];
        for u in 0..full {
            let mut sub = u;
            loop {
                if value[sub] > f64::NEG_INFINITY {
                    let v = value[sub] + prev[u ^ sub];
                    if v > cur[u] {
                        cur[u] = v;
                        arg[u] = sub;
                    }
                }
                if sub == 0 {
                    break;
                }
                sub = (sub - 1) & u;
            }
        }
        layers.push(cur);
        args.push(arg);
    }
    let mut u = full - 1;
    for layer in (1..layers.len()).rev() {
        let sub = args[layer][u];
        if layers[layer][u] > layers[layer - 1][u] && sub != 0 {
            chosen.push(sub);
            u ^= sub;
        }
    }
    chosen.push(args[0][u]);
    chosen
}

/// The candidates of the cheapest path over `set` ending at candidate index `last`, in visit
/// order, traced backwards through `dp` (path costs by subset and last node).
fn rebuild(p: &Problem, cands: &[usize], dp: &[f64], last: usize, set: usize) -> Vec<usize> {
    let c = cands.len();
    let mut seq = Vec::new();
    let mut cur_set = set;
    let mut j = last;
    seq.push(cands[j]);
    while cur_set.count_ones() > 1 {
        let prev_set = cur_set ^ (1 << j);
        let target = dp[cur_set * c + j] - p.service(cands[j]);
        let mut pick = usize::MAX;
        let mut err = f64::INFINITY;
        for i in 0..c {
            if prev_set & (1 << i) == 0 {
                continue;
            }
            let d = (dp[prev_set * c + i] + p.cost(cands[i], cands[j]) - target).abs();
            if d < err {
                err = d;
                pick = i;
            }
        }
        j = pick;
        cur_set = prev_set;
        seq.push(cands[j]);
    }
    seq.reverse();
    seq
}
