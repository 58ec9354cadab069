//! Integration tests on the real benchmark files in the shared data directory
//! (`GLEANER_DATA_DIR`, default `../shared/data` next to the workspace).

use std::path::{Path, PathBuf};

use gleaner_op_formats::{
    DistanceRule, find_instances, format_csv, format_table, load_instance, parse_routes,
    run_benchmark, summarize, write_routes,
};
use gleaner_orienteering::{SolveOptions, SolverKind, solve_default};

fn data_dir() -> PathBuf {
    std::env::var_os("GLEANER_DATA_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/data"))
        })
        .join("op")
}

/// Deterministic options: an iteration cap and a generous time limit.
fn options(iterations: u64) -> SolveOptions {
    SolveOptions::default()
        .with_iterations(iterations)
        .with_time_limit(std::time::Duration::from_secs(60))
}

#[test]
fn every_classic_instance_parses_with_its_target() {
    let files = find_instances(&data_dir().join("classic")).unwrap();
    assert_eq!(files.len(), 89);
    for f in &files {
        let inst = load_instance(f).unwrap();
        assert!(inst.target.is_some(), "no target for {}", inst.name);
        assert_eq!(inst.rule, DistanceRule::Euclidean);
        assert_eq!((inst.start, inst.end), (0, 1));
        assert_eq!(inst.problem.len(), inst.n);
    }
}

#[test]
fn oplib_instances_of_every_distance_rule_parse() {
    let dir = data_dir().join("oplib");
    let check = |file: &str, n: usize, budget: f64, rule: DistanceRule, target: f64| {
        let inst = load_instance(&dir.join(file)).unwrap();
        assert_eq!(
            (inst.n, inst.budget, inst.rule, inst.target),
            (n, budget, rule, Some(target)),
            "{file}"
        );
        assert_eq!((inst.start, inst.end), (0, 0));
    };
    check(
        "gen1/att48-gen1-50.oplib",
        48,
        5314.0,
        DistanceRule::Att,
        31.0,
    );
    check(
        "gen1/eil51-gen1-50.oplib",
        51,
        213.0,
        DistanceRule::Euc2d,
        29.0,
    );
    check(
        "gen2/gr48-gen2-50.oplib",
        48,
        2523.0,
        DistanceRule::Explicit,
        1749.0,
    );
    check(
        "gen3/brazil58-gen3-50.oplib",
        58,
        12698.0,
        DistanceRule::Explicit,
        1702.0,
    );
    check(
        "gen1/gr137-gen1-50.oplib",
        137,
        34927.0,
        DistanceRule::Geo,
        78.0,
    );
    assert_eq!(load_target("gr137-gen3-50"), 3954.0);
    // Explicit matrices are symmetric and agree with the generic problem.
    let inst = load_instance(&dir.join("gen1/brazil58-gen1-50.oplib")).unwrap();
    assert_eq!(inst.distance(0, 1), 2635.0);
    assert_eq!(inst.distance(57, 56), inst.problem.cost(56, 57));
}

fn load_target(name: &str) -> f64 {
    let text = std::fs::read_to_string(data_dir().join("oplib/ea4op_best.csv")).unwrap();
    gleaner_op_formats::parse_oplib_best(&text)
        .unwrap()
        .into_iter()
        .find(|(n, _)| n == name)
        .map(|(_, s)| s)
        .unwrap()
}

/// Solves `file` with an iteration cap and checks feasibility under the instance's own rule
/// and that the target is reached.
fn solve_to_target(file: &Path, iterations: u64) {
    let inst = load_instance(file).unwrap();
    let s = solve_default(&inst.problem, &options(iterations));
    let mut score = 0.0;
    for route in &s.routes {
        score += inst.validate_route(route).unwrap().score;
    }
    let target = inst.target.unwrap();
    assert!(
        score >= target - 1e-9,
        "{}: {score} < target {target}",
        inst.name
    );
}

#[test]
fn small_classic_instances_reach_their_targets() {
    let dir = data_dir().join("classic");
    for f in find_instances(&dir.join("Tsiligirides_2")).unwrap() {
        solve_to_target(&f, 300);
    }
    for name in [
        "tsiligirides_problem_1_budget_30.txt",
        "tsiligirides_problem_1_budget_75.txt",
    ] {
        solve_to_target(&dir.join("Tsiligirides_1").join(name), 1500);
    }
    solve_to_target(&dir.join("ChaoSet_66/set_66_1_050.txt"), 1500);
}

#[test]
fn small_oplib_instances_reach_best_known() {
    let dir = data_dir().join("oplib");
    for f in [
        "gen1/att48-gen1-50.oplib",
        "gen2/eil51-gen2-50.oplib",
        "gen3/gr48-gen3-50.oplib",
    ] {
        solve_to_target(&dir.join(f), 1500);
    }
}

#[test]
fn route_validation_uses_the_instance_rule() {
    let inst = load_instance(&data_dir().join("oplib/gen1/eil51-gen1-50.oplib")).unwrap();
    assert!(inst.validate_route(&[0, 0]).is_ok());
    assert!(inst.validate_route(&[0, 5, 5, 0]).is_err());
    assert!(inst.validate_route(&[1, 0]).is_err());
    assert!(inst.validate_route(&[0, 51, 0]).is_err());
    // Visiting everything is far over the budget.
    let mut all: Vec<usize> = (0..51).collect();
    all.push(0);
    let e = inst.validate_route(&all).unwrap_err();
    assert!(e.to_string().contains("exceeds the budget 213"), "{e}");
}

#[test]
fn runner_rows_summary_and_tables() {
    let dir = data_dir().join("classic/Tsiligirides_2");
    let files: Vec<PathBuf> = find_instances(&dir).unwrap().into_iter().take(3).collect();
    let mut seen = 0;
    let rows = run_benchmark(
        &files,
        SolverKind::Greedy,
        &options(0),
        &mut |k, total, _| {
            seen = k;
            assert_eq!(total, 3);
        },
    )
    .unwrap();
    assert_eq!(seen, 3);
    assert!(
        rows.iter()
            .all(|r| r.feasible && r.target.is_some() && r.n == 21)
    );
    let s = summarize(&rows);
    assert_eq!((s.count, s.with_target, s.infeasible), (3, 3, 0));
    let table = format_table(&rows);
    assert!(table.starts_with("instance"));
    assert!(table.contains("3 instances, 3 with target"));
    let csv = format_csv(&rows);
    assert_eq!(csv.lines().count(), 4);
    assert!(csv.starts_with("instance,set,n,budget,target,ours,gap_pct,seconds,feasible\n"));
}

/// Re-scores routes given with file node ids from the instance's raw data and its own
/// distance rule, without the crate's validation: (score, length of each route).
fn rescore_independently(inst: &gleaner_op_formats::OpInstance, ids: &[usize]) -> (f64, f64) {
    let idx: Vec<usize> = ids.iter().map(|&id| id - 1).collect();
    let mut nodes = idx.clone();
    nodes.sort_unstable();
    nodes.dedup();
    let score = nodes.iter().map(|&v| inst.scores[v]).sum();
    let length = idx
        .windows(2)
        .map(|w| match &inst.explicit {
            Some(m) => m[w[0] * inst.n + w[1]],
            None => inst.rule.distance(inst.coords[w[0]], inst.coords[w[1]]),
        })
        .sum();
    (score, length)
}

#[test]
fn written_routes_re_read_and_re_score_with_the_instance_rule() {
    let dir = data_dir();
    let files = [
        dir.join("classic/Tsiligirides_1/tsiligirides_problem_1_budget_30.txt"),
        dir.join("classic/ChaoSet_66/set_66_1_050.txt"),
        dir.join("oplib/gen1/eil51-gen1-50.oplib"),
        dir.join("oplib/gen2/gr48-gen2-50.oplib"),
        dir.join("oplib/gen1/gr137-gen1-50.oplib"),
    ];
    for solver in [SolverKind::Greedy, SolverKind::Default] {
        let rows = run_benchmark(&files, solver, &options(200), &mut |_, _, _| {}).unwrap();
        let mut out = Vec::new();
        write_routes(&rows, &mut out).unwrap();
        let text = String::from_utf8(out).unwrap();
        assert_eq!(text.lines().count(), files.len());
        let records = parse_routes(&text).unwrap();
        for (file, (row, rec)) in files.iter().zip(rows.iter().zip(&records)) {
            let inst = load_instance(file).unwrap();
            assert!(row.feasible, "{}", row.instance);
            assert_eq!(rec.instance, inst.name);
            assert_eq!(rec.solver, solver.name());
            assert_eq!(rec.score, row.ours);
            assert_eq!(rec.routes, row.routes);
            assert_eq!(rec.routes.len(), 1);
            let ids = &rec.routes[0];
            // Ids as in the file: classic paths run from point 1 to point 2, OPLib tours
            // from depot 1 back to it.
            let ends = if file.extension().is_some_and(|e| e == "oplib") {
                (1, 1)
            } else {
                (1, 2)
            };
            assert_eq!((ids[0], ids[ids.len() - 1]), ends, "{}", inst.name);
            let (score, length) = rescore_independently(&inst, ids);
            assert_eq!(score, rec.score, "{}", inst.name);
            assert!(
                length <= inst.budget * (1.0 + 1e-9),
                "{}: {length} > {}",
                inst.name,
                inst.budget
            );
            // And the crate's own re-check agrees.
            let route = inst.route_from_node_ids(ids).unwrap();
            assert_eq!(inst.score_routes(&[route]).unwrap(), rec.score);
        }
    }
}

#[test]
fn classic_routes_re_score_from_the_raw_file() {
    // Independent of the parser: read `x y S` lines and use float Euclidean distances.
    let file = data_dir().join("classic/ChaoSet_64/set_64_1_50.txt");
    let rows = run_benchmark(
        std::slice::from_ref(&file),
        SolverKind::Default,
        &options(200),
        &mut |_, _, _| {},
    )
    .unwrap();
    let mut out = Vec::new();
    write_routes(&rows, &mut out).unwrap();
    let rec = &parse_routes(std::str::from_utf8(&out).unwrap()).unwrap()[0];
    let text = std::fs::read_to_string(&file).unwrap();
    let mut lines = text.lines().filter(|l| !l.trim().is_empty());
    let budget: f64 = lines
        .next()
        .unwrap()
        .split_whitespace()
        .next()
        .unwrap()
        .parse()
        .unwrap();
    let pts: Vec<[f64; 3]> = lines
        .map(|l| {
            let v: Vec<f64> = l.split_whitespace().map(|t| t.parse().unwrap()).collect();
            [v[0], v[1], v[2]]
        })
        .collect();
    let ids = &rec.routes[0];
    let p = |id: usize| pts[id - 1];
    let length: f64 = ids
        .windows(2)
        .map(|w| (p(w[0])[0] - p(w[1])[0]).hypot(p(w[0])[1] - p(w[1])[1]))
        .sum();
    let score: f64 = ids.iter().map(|&id| p(id)[2]).sum();
    assert!(length <= budget * (1.0 + 1e-9), "{length} > {budget}");
    assert_eq!(score, rec.score);
    assert!(rec.score > 0.0);
}

#[test]
fn routes_files_reject_garbage() {
    assert!(parse_routes("a\tdefault\n").is_err());
    assert!(parse_routes("a\tdefault\tx\t1 2\n").is_err());
    assert!(parse_routes("a\tdefault\t3\t1 -2\n").is_err());
    let ok = parse_routes("\na\tgreedy\t3.5\t1 4 2\t1 3 2\n").unwrap();
    assert_eq!(ok[0].routes, vec![vec![1, 4, 2], vec![1, 3, 2]]);
}
