//! The defects found by trying the server as a new user would: each with the request that
//! showed it.

use serde_json::{Value, json};

use gleaner_server::client::Part;
use gleaner_server::handlers::MISSION_FILES;

use crate::common::{Server, TOKEN};

fn error(r: &gleaner_server::client::Response) -> (u16, String, Option<String>, String) {
    let v = r
        .json()
        .unwrap_or_else(|_| panic!("not JSON: {} {}", r.status, r.text()));
    (
        r.status,
        v["error"].as_str().unwrap_or("").to_string(),
        v["field"].as_str().map(str::to_string),
        v["reason"].as_str().unwrap_or("").to_string(),
    )
}

/// The OpenAPI document lists itself and each download's own media type.
#[test]
fn openapi_lists_itself_and_the_downloads_media_types() {
    let server = Server::caf();
    let doc = server.get_json("/api/v1/openapi.json");
    assert!(doc["paths"]["/api/v1/openapi.json"]["get"].is_object());
    let content =
        &doc["paths"]["/api/v1/missions/{id}/files/{name}"]["get"]["responses"]["200"]["content"];
    let mut declared: Vec<&str> = content
        .as_object()
        .unwrap()
        .keys()
        .map(String::as_str)
        .collect();
    declared.sort();
    let mut served: Vec<&str> = MISSION_FILES.iter().map(|f| f.1).collect();
    served.sort();
    served.dedup();
    assert_eq!(declared, served);
    assert!(content.get("application/octet-stream").is_none());
}

/// The header's "latest reading" is the newest stored reading, also right after an upload.
#[test]
fn the_latest_reading_is_the_newest_stored_one() {
    let server = Server::caf();
    assert_eq!(
        server.get_json("/api/v1/project")["latest_reading"],
        "2013-12-31T00:00:00Z"
    );
    let r = server
        .client()
        .post_multipart(
            "/api/v1/ingest",
            &[Part::File(
                "files".into(),
                "jan.csv".into(),
                b"sensor_id,timestamp,modality,value,unit\nCAF003,2014-01-05T06:30:00Z,vw@30cm,0.31,m3/m3\n"
                    .to_vec(),
            )],
            Some(TOKEN),
        )
        .unwrap();
    assert_eq!(r.status, 200, "{}", r.text());
    assert_eq!(
        server.get_json("/api/v1/project")["latest_reading"],
        "2014-01-05T06:30:00Z",
        "the cached answer was refreshed by the write"
    );
}

/// A flight recorded without a collection time is dated by the newest reading it brought
/// back, so readings taken later on the planned day are not refused.
#[test]
fn recording_without_a_time_takes_the_newest_reading_brought_back() {
    let server = Server::caf();
    let mut c = server.client();
    let plan = c
        .post_json(
            "/api/v1/plan",
            &json!({"at": "2014-01-02", "solver": "greedy", "seed": 1}),
            Some(TOKEN),
        )
        .unwrap();
    assert_eq!(plan.status, 200, "{}", plan.text());
    let plan = plan.json().unwrap();
    let mid = plan["mission_id"].as_i64().unwrap();
    assert_eq!(plan["planned_at"], "2014-01-02T00:00:00Z");
    let cell = plan["stops"][0]["cell"].as_str().unwrap();
    let sensor = server.get_json(&format!("/api/v1/cells/{cell}?days=0"))["cell"]["sensors"][0]
        .as_str()
        .unwrap()
        .to_string();
    let csv = format!(
        "sensor_id,timestamp,modality,value,unit\n{sensor},2014-01-02T09:15:00Z,vw@30cm,0.3,m3/m3\n"
    );
    let r = c
        .post_multipart(
            &format!("/api/v1/missions/{mid}/record"),
            &[Part::File(
                "files".into(),
                "flight.csv".into(),
                csv.into_bytes(),
            )],
            Some(TOKEN),
        )
        .unwrap();
    assert_eq!(r.status, 200, "{}", r.text());
    assert_eq!(r.json().unwrap()["at"], "2014-01-02T09:15:00Z");
    // Without readings, the planned time.
    let again = c
        .post_json(
            "/api/v1/plan",
            &json!({"at": "2014-01-03", "solver": "greedy", "seed": 1}),
            Some(TOKEN),
        )
        .unwrap()
        .json()
        .unwrap();
    let id = again["mission_id"].as_i64().unwrap();
    let r = c
        .post_multipart(&format!("/api/v1/missions/{id}/record"), &[], Some(TOKEN))
        .unwrap();
    assert_eq!(r.json().unwrap()["at"], "2014-01-03T00:00:00Z");
}

/// Errors name the API's fields, never the command line's flags.
#[test]
fn errors_name_api_fields_not_cli_flags() {
    let server = Server::caf();
    let mut c = server.client();
    let mid = c
        .post_json("/api/v1/plan", &json!({"solver": "greedy"}), Some(TOKEN))
        .unwrap()
        .json()
        .unwrap()["mission_id"]
        .as_i64()
        .unwrap();
    let path = format!("/api/v1/missions/{mid}/record");
    assert_eq!(
        c.post_multipart(&path, &[], Some(TOKEN)).unwrap().status,
        200
    );
    let (status, code, field, reason) = error(&c.post_multipart(&path, &[], Some(TOKEN)).unwrap());
    assert_eq!(
        (status, code.as_str(), field.as_deref()),
        (409, "conflict", Some("amend"))
    );
    assert!(
        reason.contains("`amend`") && !reason.contains("--"),
        "{reason}"
    );

    let wide = b"timestamp,CAF003\n2014-01-01,0.3\n".to_vec();
    let r = c
        .post_multipart(
            "/api/v1/ingest",
            &[
                Part::Text("format".into(), "wide-csv".into()),
                Part::File("files".into(), "wide.csv".into(), wide),
            ],
            Some(TOKEN),
        )
        .unwrap();
    let (status, _, field, reason) = error(&r);
    assert_eq!(
        (status, field.as_deref()),
        (400, Some("modality")),
        "{reason}"
    );
    assert!(!reason.contains("--"), "{reason}");
}

/// Every 400 names a field (never null, never `?`), and nonsense values are refused.
#[test]
fn every_400_names_its_field_and_nonsense_is_refused() {
    let server = Server::caf();
    let mut c = server.client();
    let cases: Vec<(&str, &str, Value, &str)> = vec![
        (
            "POST",
            "/api/v1/plan",
            json!({"dry_run": true, "history_from": "2013-06-01", "history_until": "2013-05-01"}),
            "history_from",
        ),
        (
            "POST",
            "/api/v1/plan",
            json!({"dry_run": true, "at": "2013-06-01", "history_from": "2013-07-01"}),
            "history_from",
        ),
        (
            "POST",
            "/api/v1/plan",
            json!({"dry_run": true, "at": "1900-01-01"}),
            "at",
        ),
        (
            "POST",
            "/api/v1/plan",
            json!({"dry_run": true, "at": "2999-01-01"}),
            "at",
        ),
        (
            "POST",
            "/api/v1/plan",
            json!({"dry_run": true, "iterations": 0}),
            "iterations",
        ),
        (
            "POST",
            "/api/v1/plan",
            json!({"dry_run": true, "seed": -1}),
            "seed",
        ),
        (
            "POST",
            "/api/v1/score",
            json!({"dry_run": true, "history_from": "2013-06-01", "history_until": "2013-05-01"}),
            "history_from",
        ),
        (
            "POST",
            "/api/v1/score",
            json!({"dry_run": true, "at": "1900-01-01"}),
            "at",
        ),
        (
            "POST",
            "/api/v1/simulate",
            json!({"seeds": [1, "x"]}),
            "seeds",
        ),
        (
            "POST",
            "/api/v1/simulate",
            json!({"start": "1900-01-01"}),
            "start",
        ),
        (
            "POST",
            "/api/v1/explore",
            json!({"dry_run": true, "at": "1900-01-01"}),
            "at",
        ),
        (
            "POST",
            "/api/v1/map.svg",
            json!({"format": "gleaner.mission"}),
            "version",
        ),
        (
            "POST",
            "/api/v1/plan",
            json!({"dry_run": true, "at": 5}),
            "at",
        ),
    ];
    for (method, path, body, field) in cases {
        let r = c
            .request(
                method,
                path,
                &[("Content-Type", "application/json")],
                Some(body.to_string().as_bytes()),
            )
            .unwrap();
        let (status, _, f, reason) = error(&r);
        assert_eq!(status, 400, "{path} {body}: {reason}");
        assert_eq!(f.as_deref(), Some(field), "{path} {body}: {reason}");
    }
    for (path, field) in [
        ("/api/v1/reconstruct?neighbours=-1", "neighbours"),
        ("/api/v1/reconstruct?at=1900-01-01", "at"),
        ("/api/v1/reconstruct?modality=nothing@1cm", "modality"),
        ("/api/v1/cells/x0y0?days=many", "days"),
        ("/api/v1/map.svg?mission=one", "mission"),
    ] {
        let (status, _, f, reason) = error(&c.get(path).unwrap());
        assert_eq!(
            (status, f.as_deref()),
            (400, Some(field)),
            "{path}: {reason}"
        );
    }
}

/// A 405 has the JSON error body and the `Allow` header; the favicon is answered.
#[test]
fn method_not_allowed_is_json_and_the_favicon_is_served() {
    let server = Server::caf();
    let mut c = server.client();
    let r = c.request("PUT", "/api/v1/missions/1", &[], None).unwrap();
    let (status, code, field, _) = error(&r);
    assert_eq!(
        (status, code.as_str(), field.as_deref()),
        (405, "method_not_allowed", Some("method"))
    );
    assert!(
        r.header("allow").is_some_and(|a| a.contains("GET")),
        "{:?}",
        r.headers
    );
    assert_eq!(r.header("content-type"), Some("application/json"));
    assert_eq!(c.get("/favicon.ico").unwrap().status, 204);
    let icon = c.get("/favicon.svg").unwrap();
    assert_eq!(
        (icon.status, icon.header("content-type")),
        (200, Some("image/svg+xml"))
    );
    assert!(
        server
            .client()
            .get("/")
            .unwrap()
            .text()
            .contains("href=\"/favicon.svg\"")
    );
}
