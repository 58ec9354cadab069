//! Integration tests on the real benchmark files in the shared data directory
//! (`GLEANER_DATA_DIR`, default `../shared/data` next to the workspace).

use std::path::{Path, PathBuf};

use gleaner_op_formats::{
    DistanceRule, find_instances, format_csv, format_table, load_instance, run_benchmark, summarize,
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
