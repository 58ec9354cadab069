//! The read cache: an answer is computed once per write through the server, however many
//! clients ask for it meanwhile, and a write makes the next answer new: the project, field
//! and cell table are recomputed by the write itself before it answers (no reader waits
//! after it), a mission's answer by its next reader.

use std::time::Duration;

use serde_json::json;

use gleaner_server::Event;
use gleaner_server::client::Client;

use crate::common::{TOKEN, Watched};

#[test]
fn an_answer_is_computed_once_per_change_however_many_ask() {
    // Computations of cached answers are held at their start until released; no answer
    // expires by time during the test.
    let server = Watched::start(&["cache-fill"], |c| c.cache_ttl = Duration::from_secs(3600));
    let addr = server.addr;
    let readers: Vec<_> = (0..8)
        .map(|_| std::thread::spawn(move || Client::new(addr).get("/api/v1/cells").unwrap()))
        .collect();
    // The computation's start and the seven others joining it, in whatever order they come.
    let (mut started, mut joined) = (0, 0);
    while started < 1 || joined < 7 {
        match server.next(|e| matches!(e, Event::Started("cache-fill") | Event::CacheJoined)) {
            Event::CacheJoined => joined += 1,
            _ => started += 1,
        }
    }
    server.release();
    let answers: Vec<_> = readers.into_iter().map(|r| r.join().unwrap()).collect();
    for a in &answers {
        assert_eq!(a.status, 200, "{}", a.text());
        assert_eq!(a.body, answers[0].body);
    }
    let fills = server
        .so_far()
        .into_iter()
        .filter(|e| *e == Event::Started("cache-fill"))
        .count();
    assert_eq!(fills, 0, "one computation for eight readers");

    // A write through the server: the next answer is new, and was computed by the write
    // (before it answered), so no reader computes it or waits for it.
    let project = |server: &Watched| {
        let addr = server.addr;
        let r = std::thread::spawn(move || Client::new(addr).get("/api/v1/project").unwrap());
        server.next(|e| *e == Event::Started("cache-fill"));
        server.release();
        let r = r.join().unwrap();
        assert_eq!(r.status, 200, "{}", r.text());
        r.json().unwrap()
    };
    assert_eq!(project(&server)["missions"], 0);
    let r = Client::new(addr)
        .post_json("/api/v1/plan", &json!({"solver": "greedy"}), Some(TOKEN))
        .unwrap();
    assert_eq!(r.status, 200, "{}", r.text());
    // (A computation would be let through, and seen.)
    server.so_far();
    server.release();
    let after = Client::new(addr).get("/api/v1/project").unwrap();
    assert_eq!(after.json().unwrap()["missions"], 1, "the write's answer");
    let cells = Client::new(addr).get("/api/v1/cells").unwrap();
    assert_eq!(cells.status, 200);
    assert_ne!(cells.body, answers[0].body, "the plan stored new scores");
    assert!(
        !server.so_far().contains(&Event::Started("cache-fill")),
        "computed by a reader after the write"
    );
    // Unchanged since: answered from the cache.
    server.release();
    let again = Client::new(addr).get("/api/v1/project").unwrap();
    assert_eq!(again.json().unwrap()["missions"], 1);
    assert!(
        !server.so_far().contains(&Event::Started("cache-fill")),
        "computed again without a change"
    );
    // A mission's answer too.
    let id = r.json().unwrap()["mission_id"].as_i64().unwrap();
    let path = format!("/api/v1/missions/{id}");
    let first = std::thread::spawn(move || Client::new(addr).get(&path).unwrap());
    server.next(|e| *e == Event::Started("cache-fill"));
    server.release();
    assert_eq!(first.join().unwrap().json().unwrap()["mission_id"], id);
}

/// The cached `/project`, `/field` and `/cells` answers are recomputed by exactly the writes
/// that change what they read, before those writes answer (a read that starts after a write's
/// answer sees it): a stored plan changes the cells' description (it stores its scoring at
/// the mission time and each cell's expected energy) and the missions; a scoring the cells
/// only; a cancellation or deletion the missions only, and keeps `/cells` and `/field`.
#[test]
fn each_write_recomputes_the_answers_it_changes_and_keeps_the_others() {
    let server = Watched::start(&[], |c| c.cache_ttl = Duration::from_secs(3600));
    let addr = server.addr;
    let get = |path: &str| {
        let r = Client::new(addr).get(path).unwrap();
        assert_eq!(r.status, 200, "{path}: {}", r.text());
        r
    };
    // Every cell's stored score time (RFC 3339).
    let score_times = |cells: &serde_json::Value| -> Vec<String> {
        cells
            .as_array()
            .unwrap()
            .iter()
            .filter_map(|c| c["scores"]["computed_at"].as_str().map(String::from))
            .collect()
    };
    let first_cells = get("/api/v1/cells");
    let first_field = get("/api/v1/field");
    assert_eq!(get("/api/v1/project").json().unwrap()["missions"], 0);
    // What a write recomputed, and whether a reader computed anything since.
    let after_write = |server: &Watched| {
        let events = server.so_far();
        let mut refilled: Vec<String> = events
            .iter()
            .filter_map(|e| match e {
                Event::Refilled(k) => Some(k.clone()),
                _ => None,
            })
            .collect();
        refilled.sort();
        refilled
    };
    let no_reader_computed = |server: &Watched| {
        assert!(
            !server.so_far().contains(&Event::Started("cache-fill")),
            "a reader computed an answer after the write"
        );
    };
    server.so_far();

    // A stored plan at a time of its own: its scoring shows in /cells at once.
    let r = Client::new(addr)
        .post_json(
            "/api/v1/plan",
            &json!({"solver": "greedy", "at": "2013-12-20"}),
            Some(TOKEN),
        )
        .unwrap();
    assert_eq!(r.status, 200, "{}", r.text());
    let id = r.json().unwrap()["mission_id"].as_i64().unwrap();
    assert_eq!(after_write(&server), ["cells", "field", "project"]);
    let cells = get("/api/v1/cells");
    let times = score_times(&cells.json().unwrap());
    assert!(!times.is_empty());
    assert!(
        times.iter().all(|t| t == "2013-12-20T00:00:00Z"),
        "the plan's scoring: {times:?}"
    );
    assert_ne!(cells.body, first_cells.body);
    assert_ne!(get("/api/v1/field").body, first_field.body);
    assert_eq!(get("/api/v1/project").json().unwrap()["missions"], 1);
    no_reader_computed(&server);

    // Cancelling it changes the missions only: /cells and /field are kept as they are.
    let (cells_before, field_before) = (cells.body.clone(), get("/api/v1/field").body);
    let r = Client::new(addr)
        .request(
            "POST",
            &format!("/api/v1/missions/{id}/cancel"),
            &[("authorization", &format!("Bearer {TOKEN}"))],
            None,
        )
        .unwrap();
    assert_eq!(r.status, 200, "{}", r.text());
    assert_eq!(after_write(&server), ["project"]);
    assert_eq!(get("/api/v1/cells").body, cells_before);
    assert_eq!(get("/api/v1/field").body, field_before);
    let status = get(&format!("/api/v1/missions/{id}")).json().unwrap()["status"].clone();
    assert_eq!(status, "cancelled");
    // Deleting it: the project's mission count at once.
    let r = Client::new(addr)
        .request(
            "DELETE",
            &format!("/api/v1/missions/{id}"),
            &[("authorization", &format!("Bearer {TOKEN}"))],
            None,
        )
        .unwrap();
    assert_eq!(r.status, 204, "{}", r.text());
    assert_eq!(after_write(&server), ["project"]);
    assert_eq!(get("/api/v1/project").json().unwrap()["missions"], 0);
    assert_eq!(get("/api/v1/cells").body, cells_before);

    // A scoring at another time: the cells' description, not the project.
    let r = Client::new(addr)
        .post_json("/api/v1/score", &json!({"at": "2013-12-24"}), Some(TOKEN))
        .unwrap();
    assert_eq!(r.status, 200, "{}", r.text());
    assert_eq!(after_write(&server), ["cells", "field"]);
    let times = score_times(&get("/api/v1/cells").json().unwrap());
    assert!(
        !times.is_empty() && times.iter().all(|t| t == "2013-12-24T00:00:00Z"),
        "the new scoring: {times:?}"
    );
    no_reader_computed(&server);
}
