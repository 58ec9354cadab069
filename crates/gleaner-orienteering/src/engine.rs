//! Shared search state and move operators (insertion, 2-opt, Or-opt, swap, removal).
//!
//! Routes are node vectors `[start, .., end]`; `route_of` and `pos` give, for every visited
//! non-terminal node, its route and index. Route costs are maintained incrementally and
//! recomputed exactly by [`State::resync`].

use rand::Rng;
use rand_chacha::ChaCha8Rng;

use crate::problem::Problem;
use crate::solution::route_cost;

/// `route_of` value of a node that is not on any route.
pub(crate) const FREE: u32 = u32::MAX;
/// `route_of` value of the start and end nodes.
pub(crate) const TERMINAL: u32 = u32::MAX - 1;

/// Routes up to this length (nodes) use exhaustive 2-opt rather than candidate lists.
const FULL_TWO_OPT: usize = 24;

/// Read-only context: the problem, the candidate nodes and the k-nearest-neighbour lists.
pub(crate) struct Ctx<'a> {
    pub p: &'a Problem,
    /// Non-terminal nodes with positive reward, ascending.
    pub cands: Vec<usize>,
    /// `k` nearest nodes of each node (by travel cost, ascending), flattened.
    knn: Vec<u32>,
    k: usize,
    /// Improvement threshold (cost unit).
    pub eps: f64,
    /// Evaluate insertions only next to a node's neighbours (large instances); otherwise at
    /// every edge (exact cheapest insertion).
    pub restricted: bool,
    /// `cands` by reward, largest first (ties: lower index first), sorted once.
    by_reward: Vec<usize>,
    /// Travel costs satisfy the triangle inequality, so an insertion costs at least the
    /// node's service cost: nodes whose service exceeds a route's slack are skipped.
    metric: bool,
    /// Costs are the same both ways: reversing a segment keeps its inner cost. When false
    /// (a directed instance) every reversing move adds the change of the reversed inner
    /// arcs to its gain.
    symmetric: bool,
    /// Every pair's travel cost, row-major (`n` × `n`), when the problem keeps them in a
    /// table: [`Ctx::c`] reads it directly (the same values as [`Problem::cost`]).
    table: Option<&'a [f64]>,
    /// Node count (the table's row length).
    n: usize,
}

/// Prefix sums of a route's arc costs both ways: `fwd[k]` is the cost of the route's first
/// `k` arcs as flown, `bwd[k]` of the same arcs flown backwards (budget unit). Reversing the
/// segment `route[lo..=hi]` changes its inner cost by `(bwd[hi] − bwd[lo]) − (fwd[hi] −
/// fwd[lo])` — 0 on a symmetric instance.
#[derive(Default)]
struct Arcs {
    fwd: Vec<f64>,
    bwd: Vec<f64>,
}

impl Arcs {
    fn build(&mut self, ctx: &Ctx, route: &[usize]) {
        self.fwd.clear();
        self.bwd.clear();
        let (mut f, mut b) = (0.0, 0.0);
        self.fwd.push(f);
        self.bwd.push(b);
        for w in route.windows(2) {
            f += ctx.c(w[0], w[1]);
            b += ctx.c(w[1], w[0]);
            self.fwd.push(f);
            self.bwd.push(b);
        }
    }

    /// Change of the inner cost of `route[lo..=hi]` when it is reversed.
    #[inline]
    fn reversal(&self, lo: usize, hi: usize) -> f64 {
        (self.bwd[hi] - self.bwd[lo]) - (self.fwd[hi] - self.fwd[lo])
    }
}

impl<'a> Ctx<'a> {
    /// Context over the candidates: with `prune`, only the nodes some feasible route can
    /// visit ([`Problem::reachable_candidates`]); without, every non-terminal node of
    /// positive reward (the reference path).
    pub fn new(p: &'a Problem, k: usize, prune: bool) -> Ctx<'a> {
        let n = p.len();
        let cands: Vec<usize> = if prune {
            p.reachable_candidates()
        } else {
            (0..n)
                .filter(|&v| !p.is_terminal(v) && p.reward(v) > 0.0)
                .collect()
        };
        let k = k.min(n.saturating_sub(1)).max(1);
        let knn = neighbour_lists(p, k);
        let eps = 1e-9 * p.budget().abs().max(1e-3);
        let mut by_reward = cands.clone();
        by_reward.sort_by(|&a, &b| p.reward(b).total_cmp(&p.reward(a)).then(a.cmp(&b)));
        Ctx {
            p,
            cands,
            knn,
            k,
            eps,
            restricted: false,
            by_reward,
            metric: p.is_metric(),
            symmetric: p.is_symmetric(),
            table: p.cost_table(),
            n,
        }
    }

    #[inline]
    pub fn neighbours(&self, v: usize) -> &[u32] {
        &self.knn[v * self.k..(v + 1) * self.k]
    }

    #[inline]
    pub fn c(&self, i: usize, j: usize) -> f64 {
        match self.table {
            Some(t) => t[i * self.n + j],
            None => self.p.cost(i, j),
        }
    }

    /// False when `v` provably fits in no route of `state` (metric costs: an insertion costs
    /// at least the service cost, up to rounding far below the tolerance).
    #[inline]
    fn may_fit(&self, state: &State, v: usize) -> bool {
        if !self.metric {
            return true;
        }
        let room = self.p.budget() + 2.0 * self.p.tolerance();
        state.cost.iter().any(|&c| self.p.service(v) <= room - c)
    }

    /// Gain (negative: cheaper) of reversing `route[lo..=hi]` (1 <= lo < hi < len − 1) on a
    /// directed instance: the two new boundary arcs less the two old, plus the reversed
    /// inner arcs' change (`arcs` built over `route`).
    #[inline]
    fn reversal_gain(&self, route: &[usize], arcs: &Arcs, lo: usize, hi: usize) -> f64 {
        let (x, y) = (route[lo - 1], route[hi + 1]);
        let (first, last) = (route[lo], route[hi]);
        self.c(x, last) + self.c(first, y) - self.c(x, first) - self.c(last, y)
            + arcs.reversal(lo, hi)
    }

    #[inline]
    pub fn insert_delta(&self, a: usize, v: usize, b: usize) -> f64 {
        self.c(a, v) + self.c(v, b) - self.c(a, b) + self.p.service(v)
    }
}

/// k nearest neighbours of every node. Grid buckets for planar problems, brute force else.
fn neighbour_lists(p: &Problem, k: usize) -> Vec<u32> {
    let n = p.len();
    let mut out = vec![0u32; n * k];
    if n <= 1 {
        return out;
    }
    let mut buf: Vec<(f64, u32)> = Vec::with_capacity(n);
    if let (Some((pts, _)), true) = (p.points(), n > 2000) {
        // Uniform grid; every metric offered is >= the Chebyshev distance, so a ring at
        // Chebyshev cell distance r holds points at least (r - 1) * cell away.
        let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
        for q in pts {
            x0 = x0.min(q[0]);
            y0 = y0.min(q[1]);
            x1 = x1.max(q[0]);
            y1 = y1.max(q[1]);
        }
        // Costs are `scale` times the metric distance.
        let scale = p.cost_per_unit().unwrap_or(1.0);
        let g = ((n as f64 / 2.0).sqrt().ceil() as usize).max(1);
        let cell = ((x1 - x0).max(y1 - y0) / g as f64).max(1e-12);
        let idx = |v: f64, lo: f64| (((v - lo) / cell) as usize).min(g - 1);
        let mut buckets: Vec<Vec<u32>> = vec![Vec::new(); g * g];
        for (i, q) in pts.iter().enumerate() {
            buckets[idx(q[1], y0) * g + idx(q[0], x0)].push(i as u32);
        }
        for i in 0..n {
            let (cx, cy) = (idx(pts[i][0], x0) as i64, idx(pts[i][1], y0) as i64);
            buf.clear();
            let mut r: i64 = 0;
            loop {
                for yy in (cy - r)..=(cy + r) {
                    for xx in (cx - r)..=(cx + r) {
                        if (yy - cy).abs() != r && (xx - cx).abs() != r {
                            continue;
                        }
                        if yy < 0 || xx < 0 || yy >= g as i64 || xx >= g as i64 {
                            continue;
                        }
                        for &j in &buckets[yy as usize * g + xx as usize] {
                            if j as usize != i {
                                buf.push((p.cost(i, j as usize), j));
                            }
                        }
                    }
                }
                let enough = buf.len() >= k;
                if enough {
                    buf.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                    if buf[k - 1].0 <= scale * r as f64 * cell {
                        break;
                    }
                }
                if r as usize > g {
                    buf.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                    break;
                }
                r += 1;
            }
            for t in 0..k {
                out[i * k + t] = buf[t].1;
            }
        }
        return out;
    }
    for i in 0..n {
        buf.clear();
        buf.extend((0..n).filter(|&j| j != i).map(|j| (p.cost(i, j), j as u32)));
        if k < buf.len() {
            buf.select_nth_unstable_by(k - 1, |a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            buf.truncate(k);
        }
        buf.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        for t in 0..k {
            out[i * k + t] = buf[t].1;
        }
    }
    out
}

/// Routes under construction / search.
pub(crate) struct State {
    pub routes: Vec<Vec<usize>>,
    pub cost: Vec<f64>,
    pub route_of: Vec<u32>,
    pub pos: Vec<u32>,
    pub reward: f64,
}

/// Field by field, so that `clone_from` reuses the target's buffers (the search copies its
/// current solution every iteration).
impl Clone for State {
    fn clone(&self) -> State {
        State {
            routes: self.routes.clone(),
            cost: self.cost.clone(),
            route_of: self.route_of.clone(),
            pos: self.pos.clone(),
            reward: self.reward,
        }
    }

    fn clone_from(&mut self, source: &State) {
        self.routes.clone_from(&source.routes);
        self.cost.clone_from(&source.cost);
        self.route_of.clone_from(&source.route_of);
        self.pos.clone_from(&source.pos);
        self.reward = source.reward;
    }
}

/// Cached cheapest insertion of a free node into one route: edge `(a, b)`, extra cost.
#[derive(Clone, Copy)]
struct Slot {
    /// Extra cost; a lower bound when `stale`.
    delta: f64,
    a: usize,
    b: usize,
    /// The edge was broken by an insertion and the true cheapest position not yet rescanned.
    stale: bool,
}

impl State {
    pub fn empty(p: &Problem) -> State {
        let mut route_of = vec![FREE; p.len()];
        route_of[p.start()] = TERMINAL;
        route_of[p.end()] = TERMINAL;
        State {
            routes: vec![vec![p.start(), p.end()]; p.vehicles()],
            cost: vec![p.empty_route_cost(); p.vehicles()],
            route_of,
            pos: vec![0; p.len()],
            reward: p.terminal_reward(),
        }
    }

    /// Builds a state from valid routes.
    pub fn from_routes(p: &Problem, routes: &[Vec<usize>]) -> State {
        let mut s = State::empty(p);
        for (r, route) in routes.iter().enumerate().take(p.vehicles()) {
            s.routes[r] = route.clone();
            for &v in &route[1..route.len() - 1] {
                s.reward += p.reward(v);
            }
            s.refresh(r, 0);
        }
        s.resync(p);
        s
    }

    /// Recomputes route costs exactly (removes floating-point drift).
    pub fn resync(&mut self, p: &Problem) {
        for r in 0..self.routes.len() {
            self.cost[r] = route_cost(p, &self.routes[r]);
        }
    }

    /// Updates `pos`/`route_of` of route `r` from index `from` on.
    fn refresh(&mut self, r: usize, from: usize) {
        let route = &self.routes[r];
        let last = route.len() - 1;
        for (i, &v) in route.iter().enumerate().skip(from.max(1)) {
            if i == last {
                break;
            }
            self.pos[v] = i as u32;
            self.route_of[v] = r as u32;
        }
    }

    fn refresh_range(&mut self, r: usize, lo: usize, hi: usize) {
        let route = &self.routes[r];
        for (i, &v) in route.iter().enumerate().take(hi + 1).skip(lo) {
            self.pos[v] = i as u32;
        }
    }

    /// Inserts `v` into route `r` at index `idx` (before the node now at `idx`).
    pub fn insert(&mut self, ctx: &Ctx, r: usize, idx: usize, v: usize) {
        let route = &self.routes[r];
        let d = ctx.insert_delta(route[idx - 1], v, route[idx]);
        self.cost[r] += d;
        self.reward += ctx.p.reward(v);
        self.routes[r].insert(idx, v);
        self.refresh(r, idx);
    }

    /// Removes the node at index `idx` of route `r`.
    pub fn remove_at(&mut self, ctx: &Ctx, r: usize, idx: usize) -> usize {
        let route = &self.routes[r];
        let (a, v, b) = (route[idx - 1], route[idx], route[idx + 1]);
        self.cost[r] -= ctx.insert_delta(a, v, b);
        self.reward -= ctx.p.reward(v);
        self.routes[r].remove(idx);
        self.route_of[v] = FREE;
        self.refresh(r, idx);
        v
    }

    #[inline]
    fn fits(&self, ctx: &Ctx, r: usize, delta: f64) -> bool {
        self.cost[r] + delta <= ctx.p.budget() + ctx.p.tolerance()
    }

    fn cheapest_in(&self, ctx: &Ctx, r: usize, v: usize) -> Slot {
        let route = &self.routes[r];
        let mut best = Slot {
            delta: f64::INFINITY,
            a: route[0],
            b: route[1],
            stale: false,
        };
        if ctx.restricted && route.len() > 16 {
            // Edges next to the node's routed neighbours, plus the two terminal edges.
            let m = route.len();
            let mut consider = |a: usize, b: usize| {
                let d = ctx.insert_delta(a, v, b);
                if d < best.delta {
                    best = Slot {
                        delta: d,
                        a,
                        b,
                        stale: false,
                    };
                }
            };
            consider(route[0], route[1]);
            consider(route[m - 2], route[m - 1]);
            for &x in ctx.neighbours(v) {
                let x = x as usize;
                if self.route_of[x] == r as u32 {
                    let i = self.pos[x] as usize;
                    consider(route[i - 1], x);
                    consider(x, route[i + 1]);
                }
            }
            return best;
        }
        for w in route.windows(2) {
            let d = ctx.insert_delta(w[0], v, w[1]);
            if d < best.delta {
                best = Slot {
                    delta: d,
                    a: w[0],
                    b: w[1],
                    stale: false,
                };
            }
        }
        best
    }

    /// Index of `a` in route `r` when `(a, b)` is still an edge of it.
    fn edge_index(&self, r: usize, a: usize, b: usize) -> Option<usize> {
        let route = &self.routes[r];
        let i = if a == route[0] {
            0
        } else if self.route_of[a] == r as u32 {
            self.pos[a] as usize
        } else {
            return None;
        };
        (i + 1 < route.len() && route[i + 1] == b).then_some(i)
    }

    /// Greedy ratio insertion: repeatedly inserts the free candidate (not in `forbidden`)
    /// with the largest reward / extra cost at its cheapest position, until nothing fits.
    /// `noise` in [0, 1) randomises the ratios (GRASP); 0 is the deterministic rule.
    /// Returns the number of nodes inserted.
    pub fn fill(
        &mut self,
        ctx: &Ctx,
        forbidden: &[usize],
        noise: f64,
        rng: &mut ChaCha8Rng,
    ) -> usize {
        let nr = self.routes.len();
        // Nodes that fit nowhere now never will in this call (route costs only grow).
        let mut free: Vec<usize> = ctx
            .cands
            .iter()
            .copied()
            .filter(|&v| {
                self.route_of[v] == FREE && !forbidden.contains(&v) && ctx.may_fit(self, v)
            })
            .collect();
        let mut slots: Vec<Slot> = Vec::with_capacity(free.len() * nr);
        for &v in &free {
            for r in 0..nr {
                slots.push(self.cheapest_in(ctx, r, v));
            }
        }
        let mut inserted = 0;
        loop {
            // Select the best feasible (node, route).
            let mut best: Option<(usize, usize)> = None;
            let mut best_key = (f64::NEG_INFINITY, f64::NEG_INFINITY);
            for (fi, &v) in free.iter().enumerate() {
                let rw = ctx.p.reward(v);
                for r in 0..nr {
                    let s = slots[fi * nr + r];
                    if !self.fits(ctx, r, s.delta) {
                        continue;
                    }
                    let mut ratio = if s.delta <= 1e-12 {
                        f64::INFINITY
                    } else {
                        rw / s.delta
                    };
                    if noise > 0.0 && ratio.is_finite() {
                        ratio *= 1.0 + noise * (2.0 * rng.random::<f64>() - 1.0);
                    }
                    // Ties: larger reward, then lower node index, then lower route. The key
                    // is a total order, so a stale bound never ties with the winner.
                    let wins = match best {
                        None => true,
                        Some((bf, br)) => {
                            ratio > best_key.0
                                || (ratio == best_key.0
                                    && (rw > best_key.1
                                        || (rw == best_key.1
                                            && (v < free[bf] || (v == free[bf] && r < br)))))
                        }
                    };
                    if wins {
                        best_key = (ratio, rw);
                        best = Some((fi, r));
                    }
                }
            }
            let Some((fi, r)) = best else { break };
            if slots[fi * nr + r].stale {
                // Its bound won: compute the true cheapest position and select again.
                slots[fi * nr + r] = self.cheapest_in(ctx, r, free[fi]);
                continue;
            }
            let v = free[fi];
            let s = slots[fi * nr + r];
            let idx = self.edge_index(r, s.a, s.b).map_or(1, |i| i + 1);
            self.insert(ctx, r, idx, v);
            inserted += 1;
            free.swap_remove(fi);
            for t in 0..nr {
                slots.swap(fi * nr + t, free.len() * nr + t);
            }
            slots.truncate(free.len() * nr);
            // Update the caches of route r.
            let (a, b) = (s.a, s.b);
            for (fj, &w) in free.iter().enumerate() {
                let slot = &mut slots[fj * nr + r];
                // A broken best edge leaves its old cost as a lower bound (every other old
                // edge costs at least as much); the two new edges are evaluated exactly, and
                // one that beats the bound is the true cheapest position.
                if slot.a == a && slot.b == b {
                    slot.stale = true;
                }
                let d1 = ctx.insert_delta(a, w, v);
                let d2 = ctx.insert_delta(v, w, b);
                if d1 <= d2 && d1 < slot.delta {
                    *slot = Slot {
                        delta: d1,
                        a,
                        b: v,
                        stale: false,
                    };
                } else if d2 < d1 && d2 < slot.delta {
                    *slot = Slot {
                        delta: d2,
                        a: v,
                        b,
                        stale: false,
                    };
                }
            }
        }
        inserted
    }

    /// 2-opt on route `r`, first improvement, in passes until one finds no improving move:
    /// over all position pairs on routes of up to `FULL_TWO_OPT` positions (catches long-range
    /// moves that candidate lists miss on clustered instances), along the neighbour lists on
    /// longer ones. Returns true when the route got cheaper.
    pub fn two_opt(&mut self, ctx: &Ctx, r: usize) -> bool {
        let full = self.routes[r].len() <= FULL_TWO_OPT;
        let mut arcs = Arcs::default();
        let mut any = false;
        loop {
            if !ctx.symmetric {
                arcs.build(ctx, &self.routes[r]);
            }
            let improved = if full {
                self.two_opt_full_pass(ctx, r, &mut arcs)
            } else {
                self.two_opt_pass(ctx, r, &mut arcs)
            };
            if !improved {
                return any;
            }
            any = true;
        }
    }

    /// One pass of 2-opt along the neighbour lists; true when it moved.
    fn two_opt_pass(&mut self, ctx: &Ctx, r: usize, arcs: &mut Arcs) -> bool {
        let ru = r as u32;
        let mut improved = false;
        let m = self.routes[r].len();
        let mut i = 0;
        while i < m {
            let a = self.routes[r][i];
            for &c in ctx.neighbours(a) {
                let c = c as usize;
                if self.route_of[c] != ru {
                    continue;
                }
                let j = self.pos[c] as usize;
                let dac = ctx.c(a, c);
                let route = &self.routes[r];
                let mut moved = None;
                // Successor variant: new edges (a, c), (a+, c+).
                if i + 1 < m && j + 1 < m && j != i + 1 && j != i {
                    let (lo, hi) = if i < j { (i + 1, j) } else { (j + 1, i) };
                    let g = if ctx.symmetric {
                        let (an, cn) = (route[i + 1], route[j + 1]);
                        dac + ctx.c(an, cn) - ctx.c(a, an) - ctx.c(c, cn)
                    } else {
                        ctx.reversal_gain(route, arcs, lo, hi)
                    };
                    if g < -ctx.eps {
                        moved = Some((g, (lo, hi)));
                    }
                }
                // Predecessor variant: new edges (a, c), (a-, c-).
                if moved.is_none() && i > 0 && j > 0 && j + 1 != i && j != i + 1 {
                    let (lo, hi) = if i < j { (i, j - 1) } else { (j, i - 1) };
                    let g = if ctx.symmetric {
                        let (ap, cp) = (route[i - 1], route[j - 1]);
                        dac + ctx.c(ap, cp) - ctx.c(ap, a) - ctx.c(cp, c)
                    } else {
                        ctx.reversal_gain(route, arcs, lo, hi)
                    };
                    if g < -ctx.eps {
                        moved = Some((g, (lo, hi)));
                    }
                }
                if let Some((g, (lo, hi))) = moved {
                    self.reverse_segment(ctx, r, (lo, hi), g, arcs);
                    improved = true;
                    break;
                }
            }
            i += 1;
        }
        improved
    }

    /// The 2-opt move: reverses `routes[r][lo..=hi]`, whose cost changes by `gain` (m or the
    /// instance's cost unit; < 0 is cheaper), and keeps positions, cost and (asymmetric
    /// costs) the route's prefix sums `arcs` in step.
    fn reverse_segment(
        &mut self,
        ctx: &Ctx,
        r: usize,
        (lo, hi): (usize, usize),
        gain: f64,
        arcs: &mut Arcs,
    ) {
        self.routes[r][lo..=hi].reverse();
        self.refresh_range(r, lo, hi);
        self.cost[r] += gain;
        if !ctx.symmetric {
            arcs.build(ctx, &self.routes[r]);
        }
    }

    /// One pass of 2-opt over all position pairs; true when it moved.
    fn two_opt_full_pass(&mut self, ctx: &Ctx, r: usize, arcs: &mut Arcs) -> bool {
        let mut improved = false;
        let m = self.routes[r].len();
        for i in 0..m.saturating_sub(3) {
            let route = &self.routes[r];
            let (a, an) = (route[i], route[i + 1]);
            let dan = ctx.c(a, an);
            let mut found = None;
            for j in (i + 2)..(m - 1) {
                let g = if ctx.symmetric {
                    let (c, cn) = (route[j], route[j + 1]);
                    ctx.c(a, c) + ctx.c(an, cn) - dan - ctx.c(c, cn)
                } else {
                    ctx.reversal_gain(route, arcs, i + 1, j)
                };
                if g < -ctx.eps {
                    found = Some((g, j));
                    break;
                }
            }
            if let Some((g, j)) = found {
                self.reverse_segment(ctx, r, (i + 1, j), g, arcs);
                improved = true;
            }
        }
        improved
    }

    /// Or-opt on route `r`: moves segments of 1..=3 nodes (either orientation) next to a
    /// neighbour of their ends. Returns true when the route got cheaper.
    pub fn or_opt(&mut self, ctx: &Ctx, r: usize) -> bool {
        let mut any = false;
        let ru = r as u32;
        loop {
            let mut improved = false;
            let m = self.routes[r].len();
            for len in 1..=3usize {
                let mut i = 1;
                while i + len < m {
                    let route = &self.routes[r];
                    let (p, q) = (route[i - 1], route[i + len]);
                    let (s0, sl) = (route[i], route[i + len - 1]);
                    let removal = ctx.c(p, s0) + ctx.c(sl, q) - ctx.c(p, q);
                    if removal <= ctx.eps {
                        i += 1;
                        continue;
                    }
                    // Directed: what flying the segment backwards adds to its inner arcs.
                    let inner = if ctx.symmetric {
                        0.0
                    } else {
                        route[i..i + len]
                            .windows(2)
                            .map(|w| ctx.c(w[1], w[0]) - ctx.c(w[0], w[1]))
                            .sum()
                    };
                    let mut found: Option<(f64, usize, bool)> = None;
                    for &end in [s0, sl].iter() {
                        for &x in ctx.neighbours(end) {
                            let x = x as usize;
                            let j = if x == route[0] {
                                0
                            } else if self.route_of[x] == ru {
                                self.pos[x] as usize
                            } else if x == route[m - 1] {
                                m - 1
                            } else {
                                continue;
                            };
                            for t in [j.wrapping_sub(1), j] {
                                if t >= m - 1 || (t + 1 >= i && t < i + len) {
                                    continue;
                                }
                                let (u, w) = (route[t], route[t + 1]);
                                let base = ctx.c(u, w);
                                let fwd = ctx.c(u, s0) + ctx.c(sl, w) - base;
                                let rev = ctx.c(u, sl) + ctx.c(s0, w) - base + inner;
                                let (ins, reversed) =
                                    if rev < fwd { (rev, true) } else { (fwd, false) };
                                let g = ins - removal;
                                if g < -ctx.eps && found.is_none_or(|f| g < f.0) {
                                    found = Some((g, t, reversed));
                                }
                            }
                        }
                    }
                    if let Some((g, t, reversed)) = found {
                        let route = &mut self.routes[r];
                        let (lo, hi);
                        if t >= i + len {
                            route[i..=t].rotate_left(len);
                            if reversed {
                                route[t + 1 - len..=t].reverse();
                            }
                            (lo, hi) = (i, t);
                        } else {
                            route[t + 1..i + len].rotate_right(len);
                            if reversed {
                                route[t + 1..t + 1 + len].reverse();
                            }
                            (lo, hi) = (t + 1, i + len - 1);
                        }
                        self.refresh_range(r, lo, hi);
                        self.cost[r] += g;
                        any = true;
                        improved = true;
                        continue;
                    }
                    i += 1;
                }
            }
            if !improved {
                break;
            }
        }
        any
    }

    /// Tour improvement of route `r`: 2-opt and Or-opt until neither improves.
    pub fn improve_tour(&mut self, ctx: &Ctx, r: usize) {
        loop {
            let a = self.two_opt(ctx, r);
            let b = self.or_opt(ctx, r);
            if !a && !b {
                break;
            }
        }
    }

    /// [`Self::improve_tour`] of every route.
    pub fn improve_tours(&mut self, ctx: &Ctx) {
        for r in 0..self.routes.len() {
            self.improve_tour(ctx, r);
        }
    }

    /// Replacement moves: a free candidate `u` takes the place of a visited node `v` (put
    /// where `v` was, or at one of the three cheapest edges of the route not touching `v`)
    /// when that gains reward, or keeps the reward and saves cost. Returns true on any move.
    pub fn swap(&mut self, ctx: &Ctx, scan_all: bool) -> bool {
        let mut any = false;
        let nr = self.routes.len();
        // Largest rewards first (the order sorted once in the context).
        let free: Vec<usize> = ctx
            .by_reward
            .iter()
            .copied()
            .filter(|&v| self.route_of[v] == FREE)
            .collect();
        for &u in &free {
            if self.route_of[u] != FREE {
                continue;
            }
            let ru_reward = ctx.p.reward(u);
            let mut best: Option<(f64, f64, usize, usize, usize)> = None; // (gain, dcost, r, idx_v, ins_a)
            for r in 0..nr {
                let route = &self.routes[r];
                if route.len() <= 2 {
                    continue;
                }
                // Without a full scan only `u`'s routed neighbours can be replaced: none on
                // this route, no move (skip the edge scan).
                if !scan_all
                    && !ctx
                        .neighbours(u)
                        .iter()
                        .any(|&x| self.route_of[x as usize] == r as u32)
                {
                    continue;
                }
                // Three cheapest insertion edges (by index of their first node).
                let mut top = [(f64::INFINITY, usize::MAX); 3];
                let mut edges = |t: usize| {
                    if top.iter().any(|e| e.1 == t) {
                        return;
                    }
                    let d = ctx.insert_delta(route[t], u, route[t + 1]);
                    if d < top[2].0 {
                        top[2] = (d, t);
                        if top[2].0 < top[1].0 {
                            top.swap(1, 2);
                            if top[1].0 < top[0].0 {
                                top.swap(0, 1);
                            }
                        }
                    }
                };
                if ctx.restricted && route.len() > 16 {
                    edges(0);
                    edges(route.len() - 2);
                    for &x in ctx.neighbours(u) {
                        let x = x as usize;
                        if self.route_of[x] == r as u32 {
                            let i = self.pos[x] as usize;
                            edges(i - 1);
                            edges(i);
                        }
                    }
                } else {
                    for t in 0..route.len() - 1 {
                        edges(t);
                    }
                }
                let consider = |vi: usize, best: &mut Option<(f64, f64, usize, usize, usize)>| {
                    let v = route[vi];
                    let gain = ru_reward - ctx.p.reward(v);
                    if gain < 0.0 {
                        return;
                    }
                    let (vp, vn) = (route[vi - 1], route[vi + 1]);
                    let rem = ctx.c(vp, vn) - ctx.c(vp, v) - ctx.c(v, vn) - ctx.p.service(v);
                    let mut ins = ctx.insert_delta(vp, u, vn);
                    let mut at = usize::MAX; // MAX: in place of v
                    for &(d, t) in &top {
                        if t != usize::MAX && t + 1 != vi && t != vi && d < ins {
                            ins = d;
                            at = t;
                        }
                    }
                    let dcost = rem + ins;
                    if self.cost[r] + dcost > ctx.p.budget() + ctx.p.tolerance() {
                        return;
                    }
                    if gain == 0.0 && dcost >= -ctx.eps {
                        return;
                    }
                    let better = match best {
                        None => true,
                        Some((bg, bd, ..)) => gain > *bg || (gain == *bg && dcost < *bd),
                    };
                    if better {
                        *best = Some((gain, dcost, r, vi, at));
                    }
                };
                if scan_all {
                    for vi in 1..route.len() - 1 {
                        consider(vi, &mut best);
                    }
                } else {
                    for &x in ctx.neighbours(u) {
                        let x = x as usize;
                        if self.route_of[x] == r as u32 {
                            consider(self.pos[x] as usize, &mut best);
                        }
                    }
                }
            }
            if let Some((_, _, r, vi, at)) = best {
                let v = self.routes[r][vi];
                if at == usize::MAX {
                    self.routes[r][vi] = u;
                    self.route_of[v] = FREE;
                    self.route_of[u] = r as u32;
                    self.pos[u] = vi as u32;
                    self.reward += ctx.p.reward(u) - ctx.p.reward(v);
                    self.cost[r] = route_cost(ctx.p, &self.routes[r]);
                } else {
                    // Insert after index `at` first, then remove v (its index may shift).
                    self.insert(ctx, r, at + 1, u);
                    let vi = self.pos[v] as usize;
                    self.remove_at(ctx, r, vi);
                }
                any = true;
            }
        }
        any
    }

    /// Shortens route `r` by iterated 2-opt/Or-opt with double-bridge kicks (`kicks`
    /// attempts, each kept only if the route gets cheaper). Returns true when it did.
    pub fn kick_tour(&mut self, ctx: &Ctx, r: usize, kicks: usize, rng: &mut ChaCha8Rng) -> bool {
        let mut any = false;
        for _ in 0..kicks {
            let m = self.routes[r].len();
            if m < 10 {
                return any;
            }
            let saved = self.routes[r].clone();
            let saved_cost = self.cost[r];
            // Interior indices 1..m-1; cut into A | B | C | D and reorder A C B D.
            let mut cuts = [
                rng.random_range(1..m - 1),
                rng.random_range(1..m - 1),
                rng.random_range(1..m - 1),
            ];
            cuts.sort_unstable();
            let [a, b, c] = cuts;
            if a == b || b == c {
                continue;
            }
            self.routes[r][a..c].rotate_left(b - a);
            self.refresh(r, 1);
            self.cost[r] = route_cost(ctx.p, &self.routes[r]);
            self.improve_tour(ctx, r);
            if self.cost[r] < saved_cost - ctx.eps {
                any = true;
            } else {
                self.routes[r] = saved;
                self.cost[r] = saved_cost;
                self.refresh(r, 1);
            }
        }
        any
    }

    /// Team moves: relocates a visited node to another route when that lowers the total
    /// cost (the receiving route staying within budget). Returns true on any move.
    pub fn relocate(&mut self, ctx: &Ctx) -> bool {
        let nr = self.routes.len();
        let mut any = false;
        for r in 0..nr {
            let mut i = 1;
            while i + 1 < self.routes[r].len() {
                let route = &self.routes[r];
                let (a, v, b) = (route[i - 1], route[i], route[i + 1]);
                let saving = ctx.insert_delta(a, v, b);
                let mut target: Option<(f64, usize, usize)> = None;
                for r2 in (0..nr).filter(|&r2| r2 != r) {
                    let slot = self.cheapest_in(ctx, r2, v);
                    if slot.delta < saving - ctx.eps
                        && self.fits(ctx, r2, slot.delta)
                        && target.is_none_or(|t| slot.delta < t.0)
                        && let Some(e) = self.edge_index(r2, slot.a, slot.b)
                    {
                        target = Some((slot.delta, r2, e + 1));
                    }
                }
                if let Some((_, r2, idx)) = target {
                    self.remove_at(ctx, r, i);
                    self.insert(ctx, r2, idx, v);
                    any = true;
                    continue;
                }
                i += 1;
            }
        }
        // Exchange of two nodes between routes, each taking the other's place.
        let visited: usize = self.routes.iter().map(|x| x.len() - 2).sum();
        if visited > 2000 {
            return any;
        }
        for r in 0..nr {
            for r2 in (r + 1)..nr {
                for i in 1..self.routes[r].len() - 1 {
                    for j in 1..self.routes[r2].len() - 1 {
                        let (x, y) = (&self.routes[r], &self.routes[r2]);
                        let (a, v, b) = (x[i - 1], x[i], x[i + 1]);
                        let (c, w, d) = (y[j - 1], y[j], y[j + 1]);
                        let d1 = ctx.insert_delta(a, w, b) - ctx.insert_delta(a, v, b);
                        let d2 = ctx.insert_delta(c, v, d) - ctx.insert_delta(c, w, d);
                        if d1 + d2 < -ctx.eps && self.fits(ctx, r, d1) && self.fits(ctx, r2, d2) {
                            self.routes[r][i] = w;
                            self.routes[r2][j] = v;
                            self.route_of[w] = r as u32;
                            self.pos[w] = i as u32;
                            self.route_of[v] = r2 as u32;
                            self.pos[v] = j as u32;
                            self.cost[r] += d1;
                            self.cost[r2] += d2;
                            any = true;
                        }
                    }
                }
            }
        }
        any
    }

    /// Full local search: tour improvement, insertion and replacement until stable.
    pub fn local_search(&mut self, ctx: &Ctx, rng: &mut ChaCha8Rng, scan_all: bool) {
        loop {
            self.improve_tours(ctx);
            let ins = self.fill(ctx, &[], 0.0, rng);
            let sw = self.swap(ctx, scan_all);
            let moved = self.routes.len() > 1 && self.relocate(ctx);
            if ins == 0 && !sw && !moved {
                break;
            }
        }
        self.resync(ctx.p);
    }

    /// The iterated local search's kick: with probability 0.3 a `shift` toward a free region,
    /// else a `remove` of a segment or of random nodes, both of about `strength` nodes. The
    /// nodes dropped from the routes are returned in `out` (cleared first).
    pub fn kick(&mut self, ctx: &Ctx, rng: &mut ChaCha8Rng, strength: usize, out: &mut Vec<usize>) {
        out.clear();
        if rng.random_bool(0.3) {
            self.shift(ctx, rng, strength, out);
        } else {
            self.remove(ctx, rng, strength, out);
        }
    }

    /// Shift perturbation: forces a random free candidate and up to `strength - 1` of its
    /// free nearest neighbours into a random route (cheapest positions, budget ignored),
    /// shortens that route, then drops the visited nodes of largest saving per reward (the
    /// forced ones last) until the route fits again. Moves a tour toward unvisited regions.
    /// The dropped nodes are pushed to `out` (to be kept out of the next refill).
    fn shift(&mut self, ctx: &Ctx, rng: &mut ChaCha8Rng, strength: usize, out: &mut Vec<usize>) {
        let free: Vec<usize> = ctx
            .cands
            .iter()
            .copied()
            .filter(|&v| self.route_of[v] == FREE)
            .collect();
        if free.is_empty() {
            return;
        }
        let r = rng.random_range(0..self.routes.len());
        let u = free[rng.random_range(0..free.len())];
        let want = strength.clamp(1, ctx.k + 1);
        let mut forced = vec![u];
        for &x in ctx.neighbours(u) {
            if forced.len() >= want {
                break;
            }
            let x = x as usize;
            if self.route_of[x] == FREE && ctx.p.reward(x) > 0.0 {
                forced.push(x);
            }
        }
        for &v in &forced {
            let slot = self.cheapest_in(ctx, r, v);
            let idx = self.edge_index(r, slot.a, slot.b).map_or(1, |i| i + 1);
            self.insert(ctx, r, idx, v);
        }
        self.improve_tour(ctx, r);
        while !self.fits(ctx, r, 0.0) && self.routes[r].len() > 2 {
            let route = &self.routes[r];
            let mut pick: Option<(bool, f64, usize)> = None;
            for i in 1..route.len() - 1 {
                let v = route[i];
                let keep = forced.contains(&v);
                let score =
                    ctx.insert_delta(route[i - 1], v, route[i + 1]) / ctx.p.reward(v).max(1e-12);
                let wins = match pick {
                    None => true,
                    Some((k, s, _)) => (!keep && k) || (keep == k && score > s),
                };
                if wins {
                    pick = Some((keep, score, i));
                }
            }
            let Some((_, _, i)) = pick else { break };
            out.push(self.remove_at(ctx, r, i));
        }
    }

    /// Removal perturbation: removes a random segment of up to `strength` nodes from a random
    /// non-empty route, or `strength` random visited nodes; pushes the removed nodes to `out`.
    fn remove(&mut self, ctx: &Ctx, rng: &mut ChaCha8Rng, strength: usize, out: &mut Vec<usize>) {
        let nonempty: Vec<usize> = (0..self.routes.len())
            .filter(|&r| self.routes[r].len() > 2)
            .collect();
        if nonempty.is_empty() {
            return;
        }
        if nonempty.len() > 1 && rng.random_bool(0.5) {
            // Team perturbation: random nodes from any route.
            for _ in 0..strength.max(2) {
                let r = rng.random_range(0..self.routes.len());
                let m = self.routes[r].len() - 2;
                if m > 0 {
                    let idx = rng.random_range(1..=m);
                    let v = self.remove_at(ctx, r, idx);
                    // Half of the time the node is forced into another route (cheapest
                    // position, if it fits) rather than dropped.
                    let r2 = rng.random_range(0..self.routes.len());
                    if r2 != r && rng.random_bool(0.5) {
                        let slot = self.cheapest_in(ctx, r2, v);
                        if self.fits(ctx, r2, slot.delta)
                            && let Some(e) = self.edge_index(r2, slot.a, slot.b)
                        {
                            self.insert(ctx, r2, e + 1, v);
                            continue;
                        }
                    }
                    out.push(v);
                }
            }
            return;
        }
        let r = nonempty[rng.random_range(0..nonempty.len())];
        let m = self.routes[r].len() - 2;
        let k = strength.clamp(1, m);
        if rng.random_bool(0.5) {
            let len = rng.random_range(1..=k);
            let start = rng.random_range(1..=m + 1 - len);
            for _ in 0..len {
                out.push(self.remove_at(ctx, r, start));
            }
        } else {
            for _ in 0..k {
                let m = self.routes[r].len() - 2;
                if m == 0 {
                    break;
                }
                let idx = rng.random_range(1..=m);
                out.push(self.remove_at(ctx, r, idx));
            }
        }
    }
}
