//! Mission management over HTTP: paging the history, cancelling and deleting missions.

use serde_json::{Value, json};

use gleaner_server::client::{Part, Response};

use crate::common::{Server, TOKEN};

fn plan(server: &Server) -> i64 {
    let r = server
        .client()
        .post_json(
            "/api/v1/plan",
            &json!({"solver": "greedy", "seed": 1}),
            Some(TOKEN),
        )
        .unwrap();
    assert_eq!(r.status, 200, "{}", r.text());
    r.json().unwrap()["mission_id"].as_i64().unwrap()
}

fn reason(r: &Response) -> String {
    let v: Value = r
        .json()
        .unwrap_or_else(|_| panic!("not JSON: {}", r.text()));
    v["reason"].as_str().unwrap().to_string()
}

fn ids(page: &Value) -> Vec<i64> {
    page["missions"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["mission_id"].as_i64().unwrap())
        .collect()
}

#[test]
fn missions_page_cancel_and_delete_with_their_refusals() {
    let server = Server::caf();
    let m: Vec<i64> = (0..4).map(|_| plan(&server)).collect();
    let mut c = server.client();

    // Paging: newest first, a `next` cursor until the oldest, no repeat, no gap.
    let first = server.get_json("/api/v1/missions/page?limit=3");
    assert_eq!(ids(&first), [m[3], m[2], m[1]]);
    assert_eq!(first["next"], json!(m[1]));
    let second = server.get_json(&format!("/api/v1/missions/page?limit=3&before={}", m[1]));
    assert_eq!((ids(&second), &second["next"]), (vec![m[0]], &Value::Null));
    for bad in ["limit=0", "limit=501", "before=0", "colour=red", "limit=x"] {
        let r = c.get(&format!("/api/v1/missions/page?{bad}")).unwrap();
        assert_eq!(r.status, 400, "{bad}: {}", r.text());
    }

    // Writes need the token.
    let path = format!("/api/v1/missions/{}/cancel", m[0]);
    let r = c.post_json(&path, &json!({}), None).unwrap();
    assert_eq!(r.status, 401, "{}", r.text());
    let r = c
        .request("DELETE", &format!("/api/v1/missions/{}", m[0]), &[], None)
        .unwrap();
    assert_eq!(r.status, 401, "{}", r.text());

    // Cancel: kept in the history as cancelled; a second cancel, a record and an export 409.
    let r = c.post_json(&path, &json!({}), Some(TOKEN)).unwrap();
    assert_eq!(r.status, 200, "{}", r.text());
    assert_eq!(r.json().unwrap()["status"], "cancelled");
    let stored = server.get_json(&format!("/api/v1/missions/{}", m[0]));
    assert_eq!(stored["status"], "cancelled");
    let r = c.post_json(&path, &json!({}), Some(TOKEN)).unwrap();
    assert_eq!(r.status, 409, "{}", r.text());
    assert!(reason(&r).contains("already cancelled"), "{}", r.text());
    let r = c
        .post_multipart(
            &format!("/api/v1/missions/{}/record", m[0]),
            &[Part::Text("at".into(), "2014-02-01T00:00:00Z".into())],
            Some(TOKEN),
        )
        .unwrap();
    assert_eq!(r.status, 409, "{}", r.text());
    assert!(reason(&r).contains("was cancelled"), "{}", r.text());
    let r = c
        .get(&format!("/api/v1/missions/{}/files/mission.plan", m[0]))
        .unwrap();
    assert_eq!(r.status, 409, "{}", r.text());

    // A flown mission is neither cancelled nor deleted.
    let r = c
        .post_multipart(
            &format!("/api/v1/missions/{}/record", m[1]),
            &[Part::Text("at".into(), "2014-02-01T00:00:00Z".into())],
            Some(TOKEN),
        )
        .unwrap();
    assert_eq!(r.status, 200, "{}", r.text());
    let bearer = format!("Bearer {TOKEN}");
    let auth = [("Authorization", bearer.as_str())];
    let r = c
        .post_json(
            &format!("/api/v1/missions/{}/cancel", m[1]),
            &json!({}),
            Some(TOKEN),
        )
        .unwrap();
    assert_eq!(r.status, 409, "{}", r.text());
    let r = c
        .request("DELETE", &format!("/api/v1/missions/{}", m[1]), &auth, None)
        .unwrap();
    assert_eq!(r.status, 409, "{}", r.text());
    assert!(reason(&r).contains("recorded as flown"), "{}", r.text());

    // Delete a cancelled and a planned mission; then they are gone (404).
    for id in [m[0], m[2]] {
        let r = c
            .request("DELETE", &format!("/api/v1/missions/{id}"), &auth, None)
            .unwrap();
        assert_eq!(r.status, 204, "{}", r.text());
        let r = c.get(&format!("/api/v1/missions/{id}")).unwrap();
        assert_eq!(r.status, 404, "{}", r.text());
    }
    let all = server.get_json("/api/v1/missions/page");
    assert_eq!(ids(&all), [m[3], m[1]]);
    let r = c
        .request("DELETE", &format!("/api/v1/missions/{}", m[0]), &auth, None)
        .unwrap();
    assert_eq!(r.status, 404, "{}", r.text());
}
