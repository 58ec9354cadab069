//! A scoring, a plan and a record racing each other (released together by a barrier) all
//! succeed and leave the store consistent; reads are answered while a plan runs.

use std::sync::{Arc, Barrier};

use serde_json::json;

use gleaner_server::client::Part;

use crate::common::{Server, TOKEN, flight_csv};

#[test]
fn scoring_planning_and_recording_race_and_leave_the_store_consistent() {
    let server = Server::caf();
    let mut c = server.client();
    let first = c
        .post_json(
            "/api/v1/plan",
            &json!({"solver": "greedy", "seed": 1}),
            Some(TOKEN),
        )
        .unwrap();
    assert_eq!(first.status, 200, "{}", first.text());
    let first = first.json().unwrap();
    let mid = first["mission_id"].as_i64().unwrap();
    let cell = first["stops"][0]["cell"].as_str().unwrap().to_string();
    let sensors: Vec<String> =
        server.get_json(&format!("/api/v1/cells/{cell}?days=0"))["cell"]["sensors"]
            .as_array()
            .unwrap()
            .iter()
            .map(|s| s.as_str().unwrap().to_string())
            .collect();
    let flight = flight_csv(sensors.iter().map(String::as_str));
    let before = server.get_json("/api/v1/project")["readings"]
        .as_u64()
        .unwrap();

    let barrier = Arc::new(Barrier::new(4));
    let addr = server.addr;
    let spawn = |job: Box<dyn FnOnce() -> gleaner_server::client::Response + Send>| {
        let b = Arc::clone(&barrier);
        std::thread::spawn(move || {
            b.wait();
            job()
        })
    };
    let score = spawn(Box::new(move || {
        gleaner_server::client::Client::new(addr)
            .post_json("/api/v1/score", &json!({"at": "2014-02-01"}), Some(TOKEN))
            .unwrap()
    }));
    let plan = spawn(Box::new(move || {
        gleaner_server::client::Client::new(addr)
            .post_json(
                "/api/v1/plan",
                &json!({"at": "2014-02-01", "seed": 2, "iterations": 2000, "time_limit_s": 30}),
                Some(TOKEN),
            )
            .unwrap()
    }));
    let parts = vec![
        Part::Text("at".into(), "2014-02-01".into()),
        Part::Text("cells".into(), cell.clone()),
        Part::File("files".into(), "flight.csv".into(), flight),
    ];
    let record = spawn(Box::new(move || {
        gleaner_server::client::Client::new(addr)
            .post_multipart(
                &format!("/api/v1/missions/{mid}/record"),
                &parts,
                Some(TOKEN),
            )
            .unwrap()
    }));
    // Reads while the three run: answered, and consistent with one state or the other.
    barrier.wait();
    let mut reader = server.client();
    for _ in 0..20 {
        let r = reader.get("/api/v1/missions").unwrap();
        assert_eq!(r.status, 200, "{}", r.text());
        let n = r.json().unwrap().as_array().unwrap().len();
        assert!(n == 1 || n == 2, "{n} missions");
    }
    let (score, plan, record) = (
        score.join().unwrap(),
        plan.join().unwrap(),
        record.join().unwrap(),
    );
    assert_eq!(score.status, 200, "score: {}", score.text());
    assert_eq!(plan.status, 200, "plan: {}", plan.text());
    assert_eq!(record.status, 200, "record: {}", record.text());

    // The store has each use case whole.
    let missions = server.get_json("/api/v1/missions");
    let missions = missions.as_array().unwrap();
    assert_eq!(missions.len(), 2);
    assert_eq!(missions[0]["mission_id"], mid);
    assert_eq!(missions[0]["status"], "flown");
    assert_eq!(missions[0]["flown_at"], "2014-02-01T00:00:00Z");
    let planned = plan.json().unwrap();
    assert_eq!(missions[1]["mission_id"], planned["mission_id"]);
    assert_eq!(missions[1]["stops"], planned["stops"]);
    assert_eq!(missions[1]["energy"], planned["energy"]);
    let inserted = record.json().unwrap()["readings_inserted"]
        .as_u64()
        .unwrap();
    assert!(inserted > 0);
    assert_eq!(
        server.get_json("/api/v1/project")["readings"]
            .as_u64()
            .unwrap(),
        before + inserted
    );
    let detail = server.get_json(&format!("/api/v1/cells/{cell}"));
    assert_eq!(detail["cell"]["last_collected"], "2014-02-01T00:00:00Z");
    let cells = server.get_json("/api/v1/cells");
    for c in cells.as_array().unwrap() {
        let s = &c["scores"];
        assert!(s.is_object(), "every cell scored: {c}");
        let sum = s["freshness"].as_f64().unwrap();
        assert!((0.0..=1.0).contains(&sum));
    }
}
