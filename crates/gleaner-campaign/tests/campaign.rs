//! Campaign simulation through the application layer: no strategy sees the future (a
//! synthetic farm whose future is rewritten plans and scores the same until the rewrite
//! becomes available), and an end-to-end campaign on the real CAF network.

use gleaner_app::{self as app, Silent};
use gleaner_campaign::Truth;
use gleaner_campaign::campaign::{
    CampaignRequest, CampaignResult, Strategy, every, run_campaign, summarise,
};

#[allow(dead_code)] // the fixtures this test does not use
#[path = "../../gleaner-app/tests/common/mod.rs"]
mod common;
use common::{caf_files, shared_data};

const DAY: i64 = 86_400;

fn request(
    label: &str,
    project: &app::Project<app::AnyStore>,
    init: app::InitRequest,
    history_until: i64,
    schedule: Vec<i64>,
    strategies: Vec<Strategy>,
) -> CampaignRequest {
    CampaignRequest {
        label: label.into(),
        init,
        sensors: None,
        settings: project.settings().clone(),
        history_until,
        history_from: None,
        schedule,
        strategies,
        seeds: vec![3],
        budgets: vec![1.0],
        modality: None,
        events: None,
        event_z: 3.0,
        planner_iterations: 100,
        sorties: 1,
        neighbours: 16,
        estimator: gleaner_app::Estimator::Changes,
        jobs: 2,
        clock_now: 0,
        flight: Default::default(),
    }
}

#[test]
fn no_strategy_sees_the_future() {
    use gleaner_synth::{SynthConfig, generate, write_readings_csv, write_sensors_csv};
    let farm = generate(&SynthConfig {
        seed: 11,
        sensor_count: 24,
        days: 70,
        vw_depths_cm: vec![30],
        t_depths_cm: vec![30],
        ..SynthConfig::default()
    })
    .unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let sensors = tmp.path().join("sensors.csv");
    write_sensors_csv(&farm, &mut std::fs::File::create(&sensors).unwrap()).unwrap();
    let readings = tmp.path().join("readings.csv");
    write_readings_csv(&farm, &mut std::fs::File::create(&readings).unwrap()).unwrap();
    let init = app::InitRequest {
        dir: tmp.path().join("farm"),
        sensors,
        base: Some(farm.base()),
        ..Default::default()
    };
    let (project, _) = app::init(&init).unwrap();
    let truth = Truth::from_files(
        &project,
        &app::IngestRequest {
            files: vec![readings],
            ..Default::default()
        },
        DAY,
        &Silent,
    )
    .unwrap();
    let t0 = farm.times()[0];
    let history_until = t0 + 50 * DAY;
    let schedule = every(history_until, history_until + 2 * DAY, DAY).unwrap();
    // The oracle yardstick too: it sees what every sensor's buffer holds at T, never later.
    let mut strategies = Strategy::ALL.to_vec();
    strategies.extend(Strategy::YARDSTICKS);
    let mut req = request(
        "synthetic",
        &project,
        init,
        history_until,
        schedule.clone(),
        strategies,
    );
    req.events = Some(Vec::new());
    let before = run_campaign(&req, &truth, &Silent).unwrap();
    // The future of mission 1: every reading not yet available at T_1, rewritten.
    let cut = schedule[1] - DAY;
    let mut changed = truth.readings().clone();
    for r in &mut changed.rows {
        if r.t > cut {
            r.value += 0.2;
        }
    }
    let rewritten = Truth::from_readings(changed, DAY).unwrap();
    let after = run_campaign(&req, &rewritten, &Silent).unwrap();
    let mut differs_later = false;
    for (a, b) in before.runs.iter().zip(&after.runs) {
        assert_eq!(a.key, b.key);
        for k in 0..=1 {
            assert_eq!(
                a.missions[k],
                b.missions[k],
                "{} mission {k} changed with the future",
                a.key.strategy.name()
            );
        }
        differs_later |= a.missions[2] != b.missions[2];
    }
    assert!(differs_later, "the rewrite is seen once it is available");
    for run in &before.runs {
        for m in &run.missions {
            if run.key.strategy != Strategy::Exhaustive {
                assert!(m.sorties <= 1 && m.energy_j <= m.budget_j + 1e-6);
            }
        }
    }
}

/// The strategies of the CAF campaign test, in their keys' order.
const CAF_STRATEGIES: [Strategy; 5] = [
    Strategy::Gleaner,
    Strategy::Nearest,
    Strategy::Exhaustive,
    Strategy::Variance,
    Strategy::Gated,
];

fn caf_campaign(jobs: usize) -> CampaignResult {
    caf_campaign_with(CAF_STRATEGIES.to_vec(), 1, jobs)
}

/// A new CAF project (its sensors, no readings) in `dir`/caf, and the request that made it.
fn caf_project(dir: &std::path::Path) -> (app::InitRequest, app::Project<app::AnyStore>) {
    let init = app::InitRequest {
        dir: dir.join("caf"),
        sensors: shared_data().join("caf/sensors/CAF_sensor_locations.csv"),
        utm_zone: Some("11N".into()),
        ..Default::default()
    };
    let (project, _) = app::init(&init).unwrap();
    (init, project)
}

/// Three daily CAF missions from 2014-04-01 (history: that season) with `strategies`, each
/// mission flying `sorties` batteries, `jobs` runs in parallel.
fn caf_campaign_with(strategies: Vec<Strategy>, sorties: usize, jobs: usize) -> CampaignResult {
    let data = shared_data();
    let tmp = tempfile::tempdir().unwrap();
    let files = caf_files(&data.join("caf/Daily"), &tmp.path().join("in"), 2014..=2014);
    let (init, project) = caf_project(tmp.path());
    let truth = Truth::from_files(
        &project,
        &app::IngestRequest {
            files,
            ..Default::default()
        },
        DAY,
        &Silent,
    )
    .unwrap();
    let start = app::parse_timestamp("2014-04-01").unwrap();
    let mut req = request(
        "caf",
        &project,
        init,
        start,
        every(start, start + 2 * DAY, DAY).unwrap(),
        strategies,
    );
    req.sorties = sorties;
    // One season of history keeps the test quick.
    req.history_from = Some(app::parse_timestamp("2014-01-01").unwrap());
    req.jobs = jobs;
    run_campaign(&req, &truth, &Silent).unwrap()
}

/// Runs are scheduled longest first on a shared queue: the results come back in the keys'
/// order and equal, to the bit, those of one thread running them in order.
#[test]
fn results_do_not_depend_on_the_thread_count() {
    let (one, two) = (caf_campaign(1), caf_campaign(2));
    assert_eq!(one.runs.len(), two.runs.len());
    for (a, b) in one.runs.iter().zip(&two.runs) {
        // Debug text: equal for equal bits, NaN included (NaN != NaN).
        assert_eq!(a.key, b.key);
        assert_eq!(
            format!("{:?}", a.missions),
            format!("{:?}", b.missions),
            "{:?}",
            a.key
        );
        assert_eq!(
            format!("{:?}", a.visits),
            format!("{:?}", b.visits),
            "{:?}",
            a.key
        );
        assert_eq!(a.caught, b.caught, "{:?}", a.key);
    }
    let order: Vec<Strategy> = two.runs.iter().map(|r| r.key.strategy).collect();
    assert_eq!(order, CAF_STRATEGIES.to_vec());
}

#[test]
fn caf_campaign_end_to_end() {
    let result = caf_campaign(2);
    assert_eq!(result.modality, "vw@30cm");
    assert_eq!(result.runs.len(), 5);
    let c = result.covariance;
    assert!(
        c.sill > 0.0 && c.range_m > 0.0 && c.time_scale_s > DAY as f64,
        "{c:?}"
    );
    let run = |s: Strategy| result.runs.iter().find(|r| r.key.strategy == s).unwrap();
    // Exhaustive visits every cell: every sensor's value is then known exactly.
    for m in &run(Strategy::Exhaustive).missions {
        assert!(m.sorties > 1, "more than one battery for 42 cells");
        assert!(m.cells >= 30);
        assert!(m.rmse_carried < 1e-12 && m.rmse_kriged < 1e-9, "{m:?}");
        assert!(m.staleness_max_s == 0.0);
        assert!(m.evaluated > 10);
        // Before its flights it knew the values of a day earlier: not exact (the history
        // every run starts from is complete up to the first mission).
        if m.index > 0 {
            assert!(m.rmse_carried_before > 1e-4, "{m:?}");
            assert!(m.rmse_kriged_before > 1e-4, "{m:?}");
        }
    }
    for r in &result.runs {
        for m in &r.missions {
            // Carrying forward: a visit only ever replaces a sensor's stale value by its
            // true one, so the error after the flights is never above the error before.
            assert!(
                m.rmse_carried <= m.rmse_carried_before + 1e-12,
                "{:?}: {m:?}",
                r.key
            );
        }
    }
    for s in [
        Strategy::Gleaner,
        Strategy::Nearest,
        Strategy::Variance,
        Strategy::Gated,
    ] {
        for m in &run(s).missions {
            assert_eq!(m.sorties, 1);
            assert!(
                m.energy_j <= m.budget_j && m.energy_j > 0.5 * m.budget_j,
                "{m:?}"
            );
            assert!((66_499.0..66_501.0).contains(&m.budget_j));
            assert!(m.cells >= 5 && m.cells < 42);
            assert!(
                m.rmse_kriged.is_finite() && m.rmse_kriged >= 0.0,
                "{s:?}: {m:?}"
            );
            // Nothing stale (the first mission, right after the history): the kriging of
            // changes has nothing to add and returns the carried values exactly.
            if m.staleness_max_s == 0.0 {
                assert_eq!(m.rmse_kriged, m.rmse_carried, "{s:?}: {m:?}");
            }
            assert!(
                m.classifier_accuracy
                    .is_some_and(|a| (0.0..=1.0).contains(&a))
            );
        }
    }
    // Kriging of changes uses the neighbours' known changes: it beats carrying stale values
    // forward on average.
    let g = &run(Strategy::Gleaner).missions;
    let carried: f64 = g.iter().map(|m| m.rmse_carried).sum();
    let kriged: f64 = g.iter().map(|m| m.rmse_kriged).sum();
    assert!(kriged < carried, "kriged {kriged} vs carried {carried}");
    let summary = summarise(std::slice::from_ref(&result), Strategy::Gleaner);
    assert_eq!(summary.len(), 5);
    assert!(summary.iter().all(|s| s.runs == 1));
    assert!(
        summary
            .iter()
            .filter(|s| s.strategy != Strategy::Gleaner)
            .all(|s| s.rmse_vs_reference.is_some())
    );
    // The report in memory (what the server returns) is what `write_report` writes to disk.
    let report =
        gleaner_campaign::report::render_report(std::slice::from_ref(&result), "gleaner test")
            .unwrap();
    assert!(report.markdown.starts_with("# Campaign report: "));
    assert!(report.markdown.contains("gleaner test"));
    assert!(!report.figures.is_empty());
    for (name, svg) in &report.figures {
        assert!(name.ends_with(".svg") && svg.starts_with("<svg"), "{name}");
        assert!(
            report.markdown.contains(&format!("figures/{name}")),
            "{name}"
        );
    }
    let dir = tempfile::tempdir().unwrap();
    gleaner_campaign::results::write_results(
        dir.path(),
        std::slice::from_ref(&result),
        "gleaner test",
    )
    .unwrap();
    let path = gleaner_campaign::report::write_report(dir.path()).unwrap();
    let read_back = gleaner_campaign::results::read_results(dir.path()).unwrap();
    let again = gleaner_campaign::report::render_report(&read_back, "gleaner test").unwrap();
    assert_eq!(std::fs::read_to_string(path).unwrap(), again.markdown);
    for (name, svg) in &again.figures {
        let written = std::fs::read_to_string(dir.path().join("figures").join(name)).unwrap();
        assert_eq!(&written, svg, "{name}");
    }
    assert!(gleaner_campaign::report::render_report(&[], "x").is_err());
}

/// The oracle yardstick (each cell worth its sensors' squared pre-flight error against what
/// the flight brings back) leaves less error after the flights than round-robin at the same
/// budget: its scores are the quantity the error after the flights sums.
#[test]
fn the_oracle_bounds_the_error_a_choice_of_cells_leaves() {
    let result = caf_campaign_with(vec![Strategy::RoundRobin, Strategy::Oracle], 1, 2);
    let run = |s: Strategy| {
        &result
            .runs
            .iter()
            .find(|r| r.key.strategy == s)
            .unwrap()
            .missions
    };
    let (rr, oracle) = (run(Strategy::RoundRobin), run(Strategy::Oracle));
    let sq = |m: &[gleaner_campaign::campaign::MissionMetrics]| -> f64 {
        m.iter().map(|m| m.rmse_kriged.powi(2)).sum()
    };
    for m in oracle {
        assert!(m.energy_j <= m.budget_j && m.sorties == 1, "{m:?}");
    }
    assert!(sq(oracle) < sq(rr), "{} vs {}", sq(oracle), sq(rr));
}

/// `--sorties 2`: every mission of a planned strategy flies two disjoint batteries, each within
/// the budget, so it visits more cells than one battery does (CAF: 42 cells, about 9 per
/// battery) and its error after the flights is lower.
#[test]
fn campaign_missions_fly_several_sorties() {
    let one = caf_campaign_with(vec![Strategy::Gleaner], 1, 2);
    let two = caf_campaign_with(vec![Strategy::Gleaner], 2, 2);
    let (one, two) = (&one.runs[0].missions, &two.runs[0].missions);
    assert_eq!(one.len(), two.len());
    for (a, b) in one.iter().zip(two) {
        assert_eq!((a.sorties, b.sorties), (1, 2), "{b:?}");
        assert!(
            b.energy_j <= 2.0 * b.budget_j && b.energy_j > 1.5 * a.energy_j,
            "{b:?}"
        );
        assert!(b.cells > a.cells + a.cells / 2, "{a:?} {b:?}");
    }
    let mean = |m: &[gleaner_campaign::campaign::MissionMetrics]| {
        m.iter().map(|m| m.rmse_carried).sum::<f64>() / m.len() as f64
    };
    assert!(mean(two) < mean(one), "{} vs {}", mean(two), mean(one));
    // Out of range: refused before anything runs.
    let tmp = tempfile::tempdir().unwrap();
    let (init, project) = caf_project(tmp.path());
    let mut req = request("caf", &project, init, 0, vec![DAY], vec![Strategy::Gleaner]);
    req.sorties = 0;
    let empty = Truth::from_readings(Default::default(), DAY).unwrap();
    let err = run_campaign(&req, &empty, &Silent).unwrap_err();
    assert!(err.to_string().contains("sorties = 0"), "{err}");
}

/// Runs that are the same computation run once and share their results (gleaner's method
/// has γ = δ = 0, so its U and R ablations are gleaner's run): the shared results equal, to
/// the bit, those of the ablation run on its own; other strategies still run their own.
#[test]
fn identical_runs_share_results_equal_to_their_own_runs() {
    use gleaner_campaign::campaign::Term;
    let together = caf_campaign_with(
        vec![
            Strategy::Gleaner,
            Strategy::Without(Term::Redundancy),
            Strategy::Gated,
        ],
        1,
        2,
    );
    let alone = caf_campaign_with(vec![Strategy::Without(Term::Redundancy)], 1, 1);
    let text = |r: &gleaner_campaign::campaign::RunResult| {
        format!("{:?} {:?} {:?}", r.missions, r.visits, r.caught)
    };
    assert_eq!(
        together.runs[1].key.strategy,
        Strategy::Without(Term::Redundancy)
    );
    assert_eq!(text(&together.runs[1]), text(&alone.runs[0]));
    assert_eq!(text(&together.runs[0]), text(&alone.runs[0]));
    assert_ne!(text(&together.runs[2]), text(&together.runs[0]));
}

/// A synthetic farm (seed `seed`, 24 sensors) with its truth and init request: 50 days of
/// history.
fn small_farm(
    seed: u64,
    tmp: &std::path::Path,
) -> (app::InitRequest, app::Project<app::AnyStore>, Truth, i64) {
    use gleaner_synth::{SynthConfig, generate, write_readings_csv, write_sensors_csv};
    let farm = generate(&SynthConfig {
        seed,
        sensor_count: 24,
        days: 70,
        vw_depths_cm: vec![30],
        t_depths_cm: vec![30],
        ..SynthConfig::default()
    })
    .unwrap();
    let sensors = tmp.join("sensors.csv");
    write_sensors_csv(&farm, &mut std::fs::File::create(&sensors).unwrap()).unwrap();
    let readings = tmp.join("readings.csv");
    write_readings_csv(&farm, &mut std::fs::File::create(&readings).unwrap()).unwrap();
    let init = app::InitRequest {
        dir: tmp.join("farm"),
        sensors,
        base: Some(farm.base()),
        ..Default::default()
    };
    let (project, _) = app::init(&init).unwrap();
    let truth = Truth::from_files(
        &project,
        &app::IngestRequest {
            files: vec![readings],
            ..Default::default()
        },
        DAY,
        &Silent,
    )
    .unwrap();
    (init, project, truth, farm.times()[0] + 50 * DAY)
}

/// In random daily winds with forecast errors and weaker batteries, no sortie flies more than
/// its battery gives above the reserve: those that cannot fly the rest re-plan in the air.
/// The same seed gives the same campaign, at any thread count; another weather seed, another.
#[test]
fn campaigns_in_random_winds_never_fly_over_budget() {
    use gleaner_campaign::campaign_flight::{FlightConditions, WindSource};
    let tmp = tempfile::tempdir().unwrap();
    let (init, project, truth, history_until) = small_farm(11, tmp.path());
    let schedule = every(history_until, history_until + 9 * DAY, DAY).unwrap();
    let mut req = request(
        "synthetic",
        &project,
        init,
        history_until,
        schedule,
        vec![Strategy::Gleaner, Strategy::Nearest, Strategy::Exhaustive],
    );
    req.events = Some(Vec::new());
    req.flight = FlightConditions {
        wind: WindSource::Weibull {
            mean_mps: 6.0,
            shape: 2.0,
        },
        gust_sd_mps: 2.5,
        battery_weakening: 0.25,
        seed: 4,
        ..FlightConditions::default()
    };
    let (mut replanned, mut missions, mut dropped) = (0, 0, 0);
    let first = run_campaign(&req, &truth, &Silent).unwrap();
    for run in &first.runs {
        for m in &run.missions {
            let f = m.flight.as_ref().expect("a flight record");
            missions += 1;
            assert_eq!(f.over_budget, 0, "{} {m:?}", run.key.strategy.name());
            assert!(f.max_excess_j <= 0.0, "{f:?}");
            assert!(f.energy_j > 0.0, "{f:?}");
            replanned += f.replanned;
            dropped += f.cells_dropped;
            assert!(f.wind.actual != f.wind.forecast);
        }
    }
    assert_eq!(missions, 30);
    // The test means something: some sorties had to re-plan and dropped stops.
    assert!(replanned > 0 && dropped > 0, "{replanned} {dropped}");
    req.jobs = 1;
    let again = run_campaign(&req, &truth, &Silent).unwrap();
    for (a, b) in first.runs.iter().zip(&again.runs) {
        assert_eq!(a.missions, b.missions);
        assert_eq!(a.visits, b.visits);
    }
    req.flight.seed = 5;
    let other = run_campaign(&req, &truth, &Silent).unwrap();
    assert_ne!(first.runs[0].missions, other.runs[0].missions);
}

/// Gusts leg by leg: every leg meets the day's wind plus its own seeded gust, and the
/// aircraft checks the rest of its route in the day's wind plus a margin for them; no sortie
/// flies over its battery, the flown energies differ from the steady day's, and the same seed
/// gives the same flights.
#[test]
fn leg_by_leg_gusts_change_the_flights_but_never_the_budget() {
    use gleaner_campaign::campaign_flight::{FlightConditions, WindSource};
    let tmp = tempfile::tempdir().unwrap();
    let (init, project, truth, history_until) = small_farm(13, tmp.path());
    let schedule = every(history_until, history_until + 4 * DAY, DAY).unwrap();
    let mut req = request(
        "synthetic",
        &project,
        init,
        history_until,
        schedule,
        vec![Strategy::Gleaner],
    );
    req.events = Some(Vec::new());
    req.flight = FlightConditions {
        wind: WindSource::Weibull {
            mean_mps: 5.0,
            shape: 2.0,
        },
        gust_sd_mps: 1.0,
        seed: 2,
        ..FlightConditions::default()
    };
    let steady = run_campaign(&req, &truth, &Silent).unwrap();
    req.flight.leg_gust_sd_mps = 2.0;
    let gusty = run_campaign(&req, &truth, &Silent).unwrap();
    let flights = |r: &gleaner_campaign::campaign::CampaignResult| {
        r.runs[0]
            .missions
            .iter()
            .map(|m| m.flight.expect("a flight record"))
            .collect::<Vec<_>>()
    };
    let (a, b) = (flights(&steady), flights(&gusty));
    assert_eq!(a.len(), 5);
    for (s, g) in a.iter().zip(&b) {
        // The same day's wind; the gusts come on top.
        assert_eq!(s.wind, g.wind);
        assert_eq!(g.over_budget, 0, "{g:?}");
        assert!(g.max_excess_j <= 0.0, "{g:?}");
    }
    assert!(
        a.iter().zip(&b).any(|(s, g)| s.energy_j != g.energy_j),
        "gusts changed no flight"
    );
    let again = run_campaign(&req, &truth, &Silent).unwrap();
    assert_eq!(flights(&again), b);
}

/// Still air, the default: every mission is flown as planned, its flight record at the
/// planned energy, never re-planned.
#[test]
fn still_air_campaigns_fly_as_planned() {
    let tmp = tempfile::tempdir().unwrap();
    let (init, project, truth, history_until) = small_farm(12, tmp.path());
    let schedule = every(history_until, history_until + 2 * DAY, DAY).unwrap();
    let mut req = request(
        "synthetic",
        &project,
        init,
        history_until,
        schedule,
        vec![Strategy::Gleaner],
    );
    req.events = Some(Vec::new());
    let result = run_campaign(&req, &truth, &Silent).unwrap();
    for m in &result.runs[0].missions {
        let f = m.flight.as_ref().unwrap();
        assert_eq!((f.replanned, f.cells_dropped, f.over_budget), (0, 0, 0));
        assert_eq!(f.energy_j, m.energy_j);
        assert!(f.wind.forecast.is_calm() && f.wind.actual.is_calm());
        assert!(f.max_excess_j <= 0.0);
    }
}
