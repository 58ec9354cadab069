//! Solver entry points and options.

use std::time::{Duration, Instant};

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::engine::{Ctx, FREE, State};
use crate::error::SolveError;
use crate::exact::{EXACT_MAX_NODES, EXACT_MAX_NODES_TEAM, exact};
use crate::problem::Problem;
use crate::solution::{Solution, evaluate};

/// Search settings shared by the solvers.
///
/// The search is deterministic for a given `seed` as long as it stops on `max_iterations` or
/// `max_stall`; `time_limit` only cuts it short (then the result depends on machine speed).
#[derive(Debug, Clone, PartialEq)]
pub struct SolveOptions {
    /// Wall-clock limit for the whole solve (s). The best solution so far is returned.
    pub time_limit: Duration,
    /// Seed of every random choice.
    pub seed: u64,
    /// Maximum number of perturbation + local search iterations (`None`: until the time
    /// limit or the stall limit).
    pub max_iterations: Option<u64>,
    /// Stop after this many consecutive iterations without a new best (`None`: never).
    pub max_stall: Option<u64>,
    /// Length of the candidate-neighbour lists (k nearest nodes) used by 2-opt, Or-opt and,
    /// on large instances, replacement moves.
    pub neighbours: usize,
    /// The default solver runs [`exact`] instead when the instance has at most this many
    /// candidate nodes (positive reward, not start/end) and the exact solver supports it.
    /// 0 disables it.
    pub exact_threshold: usize,
    /// Instances with more candidate nodes than this evaluate insertions and replacements only
    /// next to each node's candidate neighbours (faster, slightly approximate).
    pub full_scan_limit: usize,
    /// Double-bridge kicks used to shorten the tours of promising solutions (0 disables).
    pub kicks: usize,
    /// Search only the nodes some feasible route can visit
    /// ([`Problem::reachable_candidates`]: start -> node -> end within the budget), so the
    /// work scales with what the budget reaches rather than with the instance (default
    /// true). False searches every candidate: the reference path, for comparisons.
    pub prune: bool,
}

impl Default for SolveOptions {
    fn default() -> SolveOptions {
        SolveOptions {
            time_limit: Duration::from_secs(2),
            seed: 0,
            max_iterations: None,
            max_stall: Some(20_000),
            neighbours: 12,
            exact_threshold: 12,
            kicks: 10,
            full_scan_limit: 200,
            prune: true,
        }
    }
}

impl SolveOptions {
    /// Fast configuration: greedy construction then one local search to a local optimum
    /// (no perturbation), with 12-nearest candidate lists; meant for very large instances.
    pub fn fast() -> SolveOptions {
        SolveOptions {
            max_iterations: Some(0),
            neighbours: 12,
            ..SolveOptions::default()
        }
    }

    /// Sets the iteration cap (deterministic runs).
    pub fn with_iterations(mut self, iterations: u64) -> SolveOptions {
        self.max_iterations = Some(iterations);
        self
    }

    /// Sets the time limit.
    pub fn with_time_limit(mut self, limit: Duration) -> SolveOptions {
        self.time_limit = limit;
        self
    }

    /// Sets the seed.
    pub fn with_seed(mut self, seed: u64) -> SolveOptions {
        self.seed = seed;
        self
    }
}

/// Converts a time limit in seconds, as a user writes it, into a [`Duration`] without
/// panicking on hostile values (unlike [`Duration::from_secs_f64`]): a finite value >= 0 is
/// converted (rounded to the nanosecond), and anything too large for a [`Duration`],
/// `+inf` included, means "no limit" and gives [`Duration::MAX`] (the search then ends on its
/// iteration or stall limit). `-0.0` counts as 0.
///
/// # Errors
/// [`SolveError::InvalidTimeLimit`] for NaN or a negative value.
///
/// ```
/// use std::time::Duration;
/// use gleaner_orienteering::time_limit_from_secs;
/// assert_eq!(time_limit_from_secs(2.5).unwrap(), Duration::from_millis(2500));
/// assert_eq!(time_limit_from_secs(f64::INFINITY).unwrap(), Duration::MAX);
/// assert_eq!(time_limit_from_secs(1e20).unwrap(), Duration::MAX);
/// assert!(time_limit_from_secs(-1.0).is_err() && time_limit_from_secs(f64::NAN).is_err());
/// ```
pub fn time_limit_from_secs(seconds: f64) -> Result<Duration, SolveError> {
    if seconds.is_nan() || seconds < 0.0 {
        return Err(SolveError::InvalidTimeLimit { seconds });
    }
    Ok(Duration::try_from_secs_f64(seconds).unwrap_or(Duration::MAX))
}

/// Which solver to run through [`solve`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SolverKind {
    /// [`greedy`]: the paper's ratio-insertion heuristic.
    Greedy,
    /// [`solve_default`]: iterated local search seeded with greedy.
    Default,
    /// [`exact`]: subset dynamic programming (small instances only).
    Exact,
}

impl std::str::FromStr for SolverKind {
    type Err = String;

    /// `default`, `greedy` or `exact`; anything else is refused, quoting it.
    fn from_str(name: &str) -> Result<Self, String> {
        Ok(match name {
            "default" => Self::Default,
            "greedy" => Self::Greedy,
            "exact" => Self::Exact,
            other => {
                return Err(format!(
                    "unknown solver {other:?}: expected default, greedy or exact"
                ));
            }
        })
    }
}

impl SolverKind {
    /// The solver's name as written in outputs: `greedy`, `default`, `exact`.
    pub fn name(self) -> &'static str {
        match self {
            SolverKind::Greedy => "greedy",
            SolverKind::Default => "default",
            SolverKind::Exact => "exact",
        }
    }
}

/// Runs the chosen solver.
pub fn solve(
    problem: &Problem,
    kind: SolverKind,
    options: &SolveOptions,
) -> Result<Solution, SolveError> {
    match kind {
        SolverKind::Greedy => Ok(greedy(problem)),
        SolverKind::Default => Ok(solve_default(problem, options)),
        SolverKind::Exact => exact(problem),
    }
}

/// The paper's heuristic: starting from empty routes, repeatedly inserts the feasible node
/// with the largest reward / extra cost (extra travel + its service cost, at its cheapest
/// insertion position) until no node fits. Zero extra cost counts as an infinite ratio;
/// ties go to the larger reward, then the lower node index, then the lower route index.
/// Nodes with zero reward are never inserted. Deterministic, no options.
pub fn greedy(problem: &Problem) -> Solution {
    // Pruning cannot change greedy's result: a pruned node never fits anywhere.
    let ctx = Ctx::new(problem, 1, true);
    let mut state = State::empty(problem);
    let mut rng = ChaCha8Rng::seed_from_u64(0);
    state.fill(&ctx, &[], 0.0, &mut rng);
    finish(problem, &state)
}

fn finish(problem: &Problem, state: &State) -> Solution {
    evaluate(problem, &state.routes).unwrap_or_else(|_| Solution::empty(problem))
}

/// Empty routes, route 0 sent through the `anchors` in order (when they fit), then ratio
/// insertion with the given noise.
fn anchored(ctx: &Ctx, anchors: &[usize], noise: f64, rng: &mut ChaCha8Rng) -> Option<State> {
    let p = ctx.p;
    let mut st = State::empty(p);
    for (k, &v) in anchors.iter().enumerate() {
        let route = &st.routes[0];
        let (a, b) = (route[k], route[k + 1]);
        if st.route_of[v] != FREE
            || st.cost[0] + ctx.insert_delta(a, v, b) > p.budget() + p.tolerance()
        {
            return None;
        }
        st.insert(ctx, 0, k + 1, v);
    }
    // Teams: every other route starts through a random node of its own.
    for r in 1..st.routes.len() {
        if ctx.cands.is_empty() {
            break;
        }
        let v = ctx.cands[rng.random_range(0..ctx.cands.len())];
        if st.route_of[v] == FREE
            && st.cost[r] + ctx.insert_delta(p.start(), v, p.end()) <= p.budget() + p.tolerance()
        {
            st.insert(ctx, r, 1, v);
        }
    }
    st.fill(ctx, &[], noise, rng);
    Some(st)
}

/// Lexicographic objective: more reward, then less total cost.
fn better(a: &State, b: &State, eps: f64) -> bool {
    if a.reward > b.reward + 1e-9 * b.reward.abs().max(1.0) {
        return true;
    }
    if a.reward < b.reward - 1e-9 * b.reward.abs().max(1.0) {
        return false;
    }
    a.cost.iter().sum::<f64>() < b.cost.iter().sum::<f64>() - eps
}

/// The default solver: multi-start iterated local search (ILS) seeded with [`greedy`].
///
/// 1. Greedy construction, then local search: 2-opt and Or-opt on candidate lists (shorter
///    tours free budget), ratio insertion of unvisited nodes, replacement of a visited node
///    by an unvisited one of higher reward (or equal reward at lower cost), and for teams
///    relocation/exchange of nodes between routes; repeated until none applies.
/// 2. Anchored constructions: for every candidate node (a sample of 64 above 400), a route
///    sent through it first, then ratio insertion and local search; the best become the
///    elite pool and the "top anchors" (skipped by [`SolveOptions::fast`]).
/// 3. Iterations: perturb (remove a random segment or random nodes, or in 30% of the
///    iterations shift a route toward a random unvisited node and its unvisited neighbours,
///    dropping the nodes of largest saving per reward until it fits; the strength grows
///    while stalled), refill with optionally noisy ratios while the removed nodes are tabu, local
///    search; a new best of the run is intensified with double-bridge kicks on its tours.
///    Record-to-record acceptance within 2-5% of the run's best reward.
/// 4. A run ends after `150 + candidates / 2` iterations without improvement; the next starts
///    from the overall best, an elite solution, or a fresh construction through one or two
///    anchors (top or random) — this is what finds far-away clusters.
///
/// Instances with at most [`SolveOptions::exact_threshold`] candidates are solved exactly.
/// Deterministic for a seed when an iteration or stall limit binds. Never returns less reward
/// than [`greedy`].
pub fn solve_default(problem: &Problem, options: &SolveOptions) -> Solution {
    let started = Instant::now();
    let greedy_solution = greedy(problem);
    let ctx_probe = problem
        .rewards()
        .iter()
        .enumerate()
        .filter(|&(v, &r)| r > 0.0 && !problem.is_terminal(v))
        .count();
    let cap = if problem.vehicles() == 1 {
        EXACT_MAX_NODES
    } else {
        EXACT_MAX_NODES_TEAM
    };
    if ctx_probe <= options.exact_threshold.min(cap)
        && let Ok(s) = exact(problem)
    {
        return s;
    }
    let mut ctx = Ctx::new(problem, options.neighbours.max(2), options.prune);
    let scan_all = ctx.cands.len() <= options.full_scan_limit;
    ctx.restricted = !scan_all;
    let mut rng = ChaCha8Rng::seed_from_u64(options.seed);
    let mut cur = State::from_routes(problem, &greedy_solution.routes);
    cur.local_search(&ctx, &mut rng, scan_all);
    let mut best = cur.clone();
    let (anchors, mut elite) = anchor_pool(&ctx, options, started, &mut rng, scan_all, &mut best);
    cur = best.clone();
    elite.push(best.clone());
    let top_anchors: Vec<usize> = anchors.iter().take(20).map(|a| a.1).collect();
    let mut run_best = cur.clone();
    let run_len = 150 + ctx.cands.len() as u64 / 2;
    let mut run_stall: u64 = 0;
    let mut runs: u64 = 0;
    let mut removed = Vec::new();
    let mut stall: u64 = 0;
    let mut strength: usize = 1;
    let mut iter: u64 = 0;
    // The iteration's candidate: a copy of `cur` into reused buffers.
    let mut cand = cur.clone();
    loop {
        if options.max_iterations.is_some_and(|m| iter >= m)
            || options.max_stall.is_some_and(|m| stall >= m)
            || started.elapsed() >= options.time_limit
        {
            break;
        }
        iter += 1;
        cand.clone_from(&cur);
        let visited: usize = cand.routes.iter().map(|r| r.len() - 2).sum();
        cand.kick(&ctx, &mut rng, strength, &mut removed);
        let noise = if rng.random_bool(0.5) { 0.0 } else { 0.3 };
        cand.fill(&ctx, &removed, noise, &mut rng);
        cand.local_search(&ctx, &mut rng, scan_all);
        if options.kicks > 0
            && (better(&cand, &run_best, ctx.eps)
                || (cand.reward >= run_best.reward - 1e-9 * run_best.reward.abs().max(1.0)
                    && rng.random_bool(0.02)))
        {
            // Promising: intensify by shortening the tours, then refill.
            let mut shortened = false;
            for r in 0..cand.routes.len() {
                shortened |= cand.kick_tour(&ctx, r, options.kicks, &mut rng);
            }
            if shortened {
                cand.local_search(&ctx, &mut rng, scan_all);
            }
        }
        if better(&cand, &best, ctx.eps) {
            best.clone_from(&cand);
            elite.push(best.clone());
            if elite.len() > 8 {
                elite.remove(0);
            }
            stall = 0;
        } else {
            stall += 1;
        }
        if better(&cand, &run_best, ctx.eps) {
            run_best.clone_from(&cand);
            std::mem::swap(&mut cur, &mut cand);
            run_stall = 0;
            strength = 1;
            continue;
        }
        run_stall += 1;
        strength = if strength >= (visited / 3).max(3) {
            1
        } else {
            strength + 1
        };
        // Record-to-record acceptance: stay within a few percent of the run's best reward.
        let slack = if run_stall > run_len / 2 { 0.05 } else { 0.02 };
        if better(&cand, &cur, ctx.eps) || cand.reward >= run_best.reward * (1.0 - slack) {
            std::mem::swap(&mut cur, &mut cand);
        }
        if run_stall >= run_len {
            runs += 1;
            run_stall = 0;
            strength = 1;
            // Restart schedule: overall best, an elite solution, or a fresh construction
            // through one or two anchors (from the best anchors or at random).
            let pick = |top: bool, rng: &mut ChaCha8Rng| {
                if top && !top_anchors.is_empty() {
                    top_anchors[rng.random_range(0..top_anchors.len())]
                } else {
                    ctx.cands[rng.random_range(0..ctx.cands.len())]
                }
            };
            match runs % 6 {
                _ if ctx.cands.is_empty() => cur = best.clone(),
                0 => cur = best.clone(),
                3 => cur = elite[rng.random_range(0..elite.len())].clone(),
                1 => {
                    let a = pick(true, &mut rng);
                    cur = anchored(&ctx, &[a], 0.3, &mut rng).unwrap_or_else(|| best.clone());
                    cur.local_search(&ctx, &mut rng, scan_all);
                }
                k => {
                    let a = pick(k != 4, &mut rng);
                    let b = pick(k == 5, &mut rng);
                    cur = anchored(&ctx, &[a, b], 0.3, &mut rng).unwrap_or_else(|| best.clone());
                    cur.local_search(&ctx, &mut rng, scan_all);
                }
            }
            run_best.clone_from(&cur);
        }
    }
    let result = finish(problem, &best);
    if result.reward + 1e-9 < greedy_solution.reward {
        greedy_solution
    } else {
        result
    }
}

/// The anchored constructions of [`solve_default`]: route 0 first goes to an anchor, then
/// ratio insertion, each followed by a local search; scored for (a sample of) all candidates,
/// improving `best`. Returns the anchors by reward (best first) and up to four distinct
/// elite solutions from the best of them, in the order the search draws them.
fn anchor_pool(
    ctx: &Ctx<'_>,
    options: &SolveOptions,
    started: Instant,
    rng: &mut ChaCha8Rng,
    scan_all: bool,
    best: &mut State,
) -> (Vec<(f64, usize)>, Vec<State>) {
    // Anchored constructions: route 0 first goes to anchor v, then ratio insertion. Scored
    // for (a sample of) all candidates; the best few get a local search and seed the pool.
    let mut anchors: Vec<(f64, usize)> = Vec::new();
    {
        let sample: Vec<usize> = if ctx.cands.len() <= 400 {
            ctx.cands.clone()
        } else {
            (0..64)
                .map(|_| ctx.cands[rng.random_range(0..ctx.cands.len())])
                .collect()
        };
        let search = options.max_iterations.is_none_or(|m| m > 0);
        for &v in sample.iter().filter(|_| search) {
            if started.elapsed() >= options.time_limit / 4 {
                break;
            }
            if let Some(mut st) = anchored(ctx, &[v], 0.0, rng) {
                st.local_search(ctx, rng, scan_all);
                anchors.push((st.reward, v));
                if better(&st, best, ctx.eps) {
                    *best = st;
                }
            }
        }
        anchors.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    }
    let mut elite: Vec<State> = Vec::new();
    let mut last_reward = f64::NAN;
    for &(rw, v) in anchors.iter() {
        if elite.len() >= 4 || started.elapsed() >= options.time_limit / 3 {
            break;
        }
        if rw == last_reward {
            continue;
        }
        last_reward = rw;
        if let Some(mut st) = anchored(ctx, &[v], 0.0, rng) {
            st.local_search(ctx, rng, scan_all);
            if better(&st, best, ctx.eps) {
                *best = st.clone();
            }
            elite.push(st);
        }
    }
    (anchors, elite)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::problem::Metric;

    #[test]
    fn hostile_time_limits_never_panic() {
        for bad in [f64::NAN, -1.0, -1e-300, f64::NEG_INFINITY] {
            assert!(
                matches!(
                    time_limit_from_secs(bad),
                    Err(SolveError::InvalidTimeLimit { .. })
                ),
                "{bad}"
            );
        }
        assert_eq!(time_limit_from_secs(-0.0).unwrap(), Duration::ZERO);
        assert_eq!(time_limit_from_secs(0.0).unwrap(), Duration::ZERO);
        for huge in [f64::INFINITY, 1e20, f64::MAX, 2f64.powi(64)] {
            assert_eq!(time_limit_from_secs(huge).unwrap(), Duration::MAX, "{huge}");
        }
        // A solve with "no limit" ends on its iteration cap.
        let p = line(vec![0.0, 1.0, 1.0, 5.0], 25.0);
        let o = SolveOptions::default()
            .with_time_limit(time_limit_from_secs(f64::INFINITY).unwrap())
            .with_iterations(20);
        let s = solve_default(&p, &o);
        assert!(evaluate(&p, &s.routes).is_ok());
    }

    /// Points on a line at x = 0 (depot), 1, 2, 10 with rewards; closed tour.
    fn line(rewards: Vec<f64>, budget: f64) -> Problem {
        Problem::from_points(
            &[[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [10.0, 0.0]],
            Metric::Euclidean,
            rewards,
            budget,
        )
        .unwrap()
    }

    fn check(p: &Problem, kind: SolverKind, expected_routes: &[Vec<usize>], expected_reward: f64) {
        let s = solve(p, kind, &SolveOptions::default().with_iterations(50)).unwrap();
        assert_eq!(s.routes, expected_routes);
        assert!((s.reward - expected_reward).abs() < 1e-9);
    }

    #[test]
    fn greedy_takes_ratio_order_and_stops() {
        // Ratio of node 1: 1/2, node 2: 3/4 (both fit in 4), node 3: 100/20 does not fit.
        let p = line(vec![0.0, 1.0, 3.0, 100.0], 4.0);
        check(&p, SolverKind::Greedy, &[vec![0, 1, 2, 0]], 4.0);
        // With budget 20, node 3 (ratio 5) is taken first, then 1 and 2 at zero extra cost.
        let p = line(vec![0.0, 1.0, 3.0, 100.0], 20.0);
        check(&p, SolverKind::Greedy, &[vec![0, 1, 2, 3, 0]], 104.0);
    }

    #[test]
    fn greedy_is_beaten_where_ratio_misleads() {
        // Node 1 has the better ratio (1.6 / 2 > 15 / 20); after it, node 2 no longer fits.
        let p = Problem::from_points(
            &[[0.0, 0.0], [0.0, 1.0], [10.0, 0.0]],
            Metric::Euclidean,
            vec![0.0, 1.6, 15.0],
            20.0,
        )
        .unwrap();
        check(&p, SolverKind::Greedy, &[vec![0, 1, 0]], 1.6);
        check(&p, SolverKind::Exact, &[vec![0, 2, 0]], 15.0);
        check(&p, SolverKind::Default, &[vec![0, 2, 0]], 15.0);
        let ils = SolveOptions {
            exact_threshold: 0,
            ..SolveOptions::default()
        }
        .with_iterations(20);
        assert_eq!(solve_default(&p, &ils).reward, 15.0);
    }

    #[test]
    fn path_and_team() {
        let p = line(vec![0.0, 1.0, 3.0, 100.0], 2.0)
            .with_endpoints(0, 2)
            .unwrap();
        check(&p, SolverKind::Exact, &[vec![0, 1, 2]], 4.0);
        check(&p, SolverKind::Default, &[vec![0, 1, 2]], 4.0);
        let p = Problem::from_points(
            &[[0.0, 0.0], [0.0, 3.0], [0.0, -3.0]],
            Metric::Euclidean,
            vec![0.0, 2.0, 5.0],
            6.0,
        )
        .unwrap()
        .with_vehicles(2)
        .unwrap();
        let s = exact(&p).unwrap();
        assert_eq!(s.reward, 7.0);
        assert_eq!(s.routes.len(), 2);
        let d = solve_default(
            &p,
            &SolveOptions {
                exact_threshold: 0,
                ..SolveOptions::default()
            }
            .with_iterations(20),
        );
        assert_eq!(d.reward, 7.0);
    }

    #[test]
    fn zero_extra_cost_is_infinite_ratio() {
        // Node 1 sits on the depot: extra cost 0, taken before the better-reward node 2.
        let p = Problem::from_points(
            &[[0.0, 0.0], [0.0, 0.0], [1.0, 0.0]],
            Metric::Euclidean,
            vec![0.0, 1.0, 10.0],
            2.0,
        )
        .unwrap();
        let g = greedy(&p);
        assert_eq!(g.reward, 11.0);
    }

    #[test]
    fn degenerate_instances() {
        let one = Problem::new(vec![0.0], vec![3.0], 0.0).unwrap();
        for kind in [SolverKind::Greedy, SolverKind::Default, SolverKind::Exact] {
            check(&one, kind, &[vec![0, 0]], 3.0);
        }
        let nothing = line(vec![0.0; 4], 100.0).with_vehicles(3).unwrap();
        let ils = SolveOptions {
            exact_threshold: 0,
            ..SolveOptions::default()
        }
        .with_iterations(5);
        assert_eq!(solve_default(&nothing, &ils).reward, 0.0);
        assert_eq!(solve_default(&nothing, &ils).routes, vec![vec![0, 0]; 3]);
    }

    #[test]
    fn exact_rejects_large() {
        let n = EXACT_MAX_NODES + 2;
        let pts: Vec<[f64; 2]> = (0..n).map(|i| [i as f64, 0.0]).collect();
        let p = Problem::from_points(&pts, Metric::Euclidean, vec![1.0; n], 5.0).unwrap();
        assert_eq!(
            exact(&p).unwrap_err(),
            SolveError::TooLargeForExact {
                got: n - 1,
                max: EXACT_MAX_NODES
            }
        );
    }
}
