//! Every endpoint and every error code, against a server on an ephemeral loopback port over
//! a CAF project.

use serde_json::{Value, json};

use gleaner_server::client::Part;
use gleaner_server::handlers::MISSION_FILES;

use crate::common::{Server, TOKEN, caf_project, flight_csv};

/// Every API route (method, path as in the OpenAPI document).
const ROUTES: [(&str, &str); 24] = [
    ("get", "/api/v1/openapi.json"),
    ("get", "/api/v1/project"),
    ("get", "/api/v1/field"),
    ("get", "/api/v1/cells"),
    ("get", "/api/v1/cells/{cell}"),
    ("post", "/api/v1/score"),
    ("get", "/api/v1/reconstruct"),
    ("get", "/api/v1/reconstruct/map.svg"),
    ("get", "/api/v1/reconstruct/map.png"),
    ("post", "/api/v1/simulate"),
    ("get", "/api/v1/missions"),
    ("get", "/api/v1/missions/page"),
    ("get", "/api/v1/missions/{id}"),
    ("delete", "/api/v1/missions/{id}"),
    ("post", "/api/v1/missions/{id}/cancel"),
    ("post", "/api/v1/plan"),
    ("post", "/api/v1/plan/sorties"),
    ("post", "/api/v1/explore"),
    ("get", "/api/v1/missions/{id}/files/{name}"),
    ("get", "/api/v1/map.svg"),
    ("post", "/api/v1/map.svg"),
    ("post", "/api/v1/ingest"),
    ("post", "/api/v1/missions/{id}/record"),
    ("post", "/api/v1/missions/{id}/replan"),
];

fn error(r: &gleaner_server::client::Response) -> (String, Option<String>, String) {
    let v = r
        .json()
        .unwrap_or_else(|_| panic!("not JSON: {}", r.text()));
    (
        v["error"].as_str().unwrap().to_string(),
        v["field"].as_str().map(str::to_string),
        v["reason"].as_str().unwrap().to_string(),
    )
}

/// A quick, machine-independent plan request.
fn plan_body(dry_run: bool) -> Value {
    json!({"solver": "greedy", "seed": 1, "dry_run": dry_run})
}

#[test]
fn openapi_lists_every_route_and_every_route_answers() {
    let server = Server::caf();
    let doc = server.get_json("/api/v1/openapi.json");
    assert!(doc["openapi"].as_str().unwrap().starts_with("3."));
    let paths = doc["paths"].as_object().unwrap();
    let mut documented: Vec<(String, String)> = paths
        .iter()
        .flat_map(|(p, ops)| {
            ops.as_object()
                .unwrap()
                .keys()
                .map(move |m| (m.clone(), p.clone()))
        })
        .collect();
    documented.sort();
    let mut expected: Vec<(String, String)> = ROUTES
        .iter()
        .map(|(m, p)| (m.to_string(), p.to_string()))
        .collect();
    expected.sort();
    assert_eq!(documented, expected);
    assert!(doc["components"]["schemas"]["MissionDoc"].is_object());
    assert!(doc["components"]["securitySchemes"]["bearer"].is_object());
    // Each route exists on the server (an empty request gets anything but 404/405 for the
    // route itself).
    let mut c = server.client();
    for (method, path) in ROUTES {
        let concrete = path
            .replace("{cell}", "x0y0")
            .replace("{id}", "1")
            .replace("{name}", "mission.plan");
        let r = c
            .request(&method.to_uppercase(), &concrete, &[], Some(b""))
            .unwrap();
        assert_ne!(r.status, 405, "{method} {path}");
        if r.status == 404 {
            let (_, field, _) = error(&r);
            assert!(
                field.is_some(),
                "{method} {path} is not routed: {}",
                r.text()
            );
        }
    }
}

#[test]
fn reconstructs_every_sensor_and_refuses_bad_queries_naming_the_field() {
    let server = Server::caf();
    let doc = server.get_json("/api/v1/reconstruct?at=2013-12-01&estimator=changes");
    assert_eq!(doc["format"], "gleaner.reconstruction");
    assert_eq!(doc["version"], 1);
    assert_eq!(doc["modality"], "vw@30cm");
    assert_eq!(doc["estimator"], "changes");
    assert_eq!(doc["at"], "2013-12-01T00:00:00Z");
    assert_eq!(doc["step_s"], 86_400);
    let sensors = doc["sensors"].as_array().unwrap();
    assert_eq!(sensors.len(), 42);
    // Soil moisture, m³/m³: every estimate a water content, every sd finite and >= 0, nothing
    // read after `at`; a sensor read at `at` itself has no change to estimate: its estimate
    // is its reading, with no variance.
    let mut read_at_t = 0;
    for x in sensors {
        let v = x["estimate"].as_f64().unwrap();
        assert!((0.0..=0.7).contains(&v), "{x}");
        assert!(x["sd"].as_f64().unwrap() >= 0.0, "{x}");
        let last = x["last_reading"].as_str().unwrap();
        assert!(last <= "2013-12-01T00:00:00Z", "{x}");
        if last == "2013-12-01T00:00:00Z" {
            read_at_t += 1;
            assert_eq!(x["estimate"], x["carried"], "{x}");
            assert_eq!(x["sd"], 0.0, "{x}");
        }
    }
    assert!(read_at_t > 0);
    // The estimators differ; the default is kriging of changes.
    let default = server.get_json("/api/v1/reconstruct?at=2013-12-01");
    assert_eq!(default, doc);
    let dynamic = server.get_json("/api/v1/reconstruct?at=2013-12-01&estimator=dynamic");
    assert_eq!(dynamic["estimator"], "dynamic");
    assert_eq!(dynamic["sensors"].as_array().unwrap().len(), 42);
    assert_ne!(dynamic["sensors"], doc["sensors"]);
    let levels = server.get_json("/api/v1/reconstruct?at=2013-12-01&estimator=levels&neighbours=8");
    assert_eq!(levels["estimator"], "levels");
    assert_eq!(levels["sensors"].as_array().unwrap().len(), 42);
    assert_ne!(levels["sensors"], doc["sensors"]);

    let mut c = server.client();
    for (query, field) in [
        ("estimator=best", Some("estimator")),
        ("at=yesterday", Some("at")),
        ("neighbours=0", Some("neighbours")),
        ("neighbours=-1", Some("neighbours")),
        ("colour=red", Some("colour")),
        ("modality=vw@", Some("modality")),
    ] {
        let r = c
            .request("GET", &format!("/api/v1/reconstruct?{query}"), &[], None)
            .unwrap();
        assert_eq!(r.status, 400, "{query}: {}", r.text());
        let (code, f, reason) = error(&r);
        assert_eq!(code, "bad_request", "{query}");
        assert!(!reason.is_empty());
        if field.is_some() {
            assert_eq!(f.as_deref(), field, "{query}: {reason}");
        }
    }
}

/// `GET /api/v1/reconstruct` over a range: every time's mean, sd and 90% interval, the same
/// values at its end as the reconstruction at that time, one cell's columns on request;
/// ranges too long, reversed or half given are refused naming the field.
#[test]
fn reconstructs_a_range_and_refuses_bad_ranges_naming_the_field() {
    let server = Server::caf();
    let doc = server.get_json(
        "/api/v1/reconstruct?from=2013-11-01&to=2013-12-01&every_hours=6&estimator=changes",
    );
    assert_eq!(doc["format"], "gleaner.reconstruction-series");
    assert_eq!(doc["version"], 1);
    assert_eq!(doc["estimator"], "changes");
    assert_eq!(doc["unit"], "m3/m3");
    assert!(doc["model"].is_null());
    let times = doc["times"].as_array().unwrap();
    assert_eq!(times.len(), 30 * 4 + 1);
    assert_eq!(times[0], "2013-11-01T00:00:00Z");
    assert_eq!(times[120], "2013-12-01T00:00:00Z");
    assert_eq!(doc["sensors"].as_array().unwrap().len(), 42);
    for key in ["mean", "sd", "lo90", "hi90"] {
        let rows = doc[key].as_array().unwrap();
        assert_eq!(rows.len(), 121, "{key}");
        assert!(
            rows.iter().all(|r| r.as_array().unwrap().len() == 42),
            "{key}"
        );
    }
    // Intervals centred on the mean; under the kriging of changes each time's half-widths
    // are one calibrated multiple of the sd for every sensor estimated from a reading (the
    // Gaussian 1.645 for a sensor never read).
    for t in 0..121 {
        let mut multiples: Vec<f64> = Vec::new();
        for s in 0..42 {
            let (m, sd) = (
                doc["mean"][t][s].as_f64().unwrap(),
                doc["sd"][t][s].as_f64().unwrap(),
            );
            let (lo, hi) = (
                doc["lo90"][t][s].as_f64().unwrap(),
                doc["hi90"][t][s].as_f64().unwrap(),
            );
            assert!(sd >= 0.0 && lo <= m && m <= hi, "{t} {s}");
            assert!(((hi - m) - (m - lo)).abs() < 1e-9, "{t} {s}");
            if sd > 1e-6 {
                multiples.push((hi - lo) / (2.0 * sd));
            }
        }
        let z90 = 1.644_853_626_951_472_2;
        let calibrated: Vec<f64> = multiples
            .into_iter()
            .filter(|x| (x - z90).abs() > 1e-9)
            .collect();
        if let Some(&q) = calibrated.first() {
            assert!(q > 0.0 && q.is_finite());
            assert!(
                calibrated.iter().all(|x| (x - q).abs() < 1e-6 * q.max(1.0)),
                "{t}: {calibrated:?}"
            );
        }
    }
    // Its last time is the reconstruction at that time.
    let at = server.get_json("/api/v1/reconstruct?at=2013-12-01&estimator=changes");
    for (s, x) in at["sensors"].as_array().unwrap().iter().enumerate() {
        assert_eq!(doc["sensors"][s]["sensor"], x["sensor"]);
        assert_eq!(doc["mean"][120][s], x["estimate"], "{x}");
    }
    // The default estimator is kriging of changes; the dynamic model carries its parameters.
    let default =
        server.get_json("/api/v1/reconstruct?from=2013-11-01&to=2013-12-01&every_hours=6");
    assert_eq!(default, doc);
    let dynamic =
        server.get_json("/api/v1/reconstruct?from=2013-11-25&to=2013-12-01&estimator=dynamic");
    assert_eq!(dynamic["estimator"], "dynamic");
    assert_eq!(dynamic["times"].as_array().unwrap().len(), 7);
    assert!(dynamic["model"]["phi"].as_f64().unwrap() > 0.0);
    // One cell: its sensors' columns only, the same numbers.
    let field = server.get_json("/api/v1/cells");
    let cell = &field[0];
    let id = cell["cell"].as_str().unwrap();
    let one = server.get_json(&format!(
        "/api/v1/reconstruct?from=2013-11-01&to=2013-12-01&every_hours=6&cell={id}"
    ));
    let sensors: Vec<&str> = cell["sensors"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    let got: Vec<&str> = one["sensors"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v["sensor"].as_str().unwrap())
        .collect();
    assert_eq!(got, sensors);
    let k = doc["sensors"]
        .as_array()
        .unwrap()
        .iter()
        .position(|v| v["sensor"] == sensors[0])
        .unwrap();
    assert_eq!(one["mean"][60][0], doc["mean"][60][k]);

    let mut c = server.client();
    for (query, status, field) in [
        ("from=2013-01-01&to=2013-12-31&every_hours=1", 400, "to"),
        ("from=2013-12-01&to=2013-11-01", 400, "to"),
        ("from=2013-11-01", 400, "to"),
        ("to=2013-11-01", 400, "from"),
        (
            "from=2013-11-01&to=2013-12-01&every_hours=0",
            400,
            "every_hours",
        ),
        (
            "from=2013-11-01&to=2013-12-01&every_hours=-6",
            400,
            "every_hours",
        ),
        (
            "from=2013-11-01&to=2013-12-01&every_hours=nan",
            400,
            "every_hours",
        ),
        (
            "from=2013-11-01&to=2013-12-01&every_hours=six",
            400,
            "every_hours",
        ),
        ("from=1900-01-01&to=2013-12-01", 400, "from"),
        ("from=2013-11-01&to=2013-12-01&at=2013-11-05", 400, "at"),
        ("from=2013-11-01&to=2013-12-01&cell=somewhere", 400, "cell"),
        ("from=2013-11-01&to=2013-12-01&cell=x999y999", 404, "cell"),
        (
            "from=2013-11-01&to=2013-12-01&estimator=best",
            400,
            "estimator",
        ),
        (
            "from=2013-11-01&to=2013-12-01&modality=nothing@1cm",
            400,
            "modality",
        ),
        // Before the project's first reading.
        ("from=2001-01-01&to=2001-02-01", 400, "to"),
    ] {
        let r = c
            .request("GET", &format!("/api/v1/reconstruct?{query}"), &[], None)
            .unwrap();
        assert_eq!(r.status, status, "{query}: {}", r.text());
        let (_, f, reason) = error(&r);
        assert_eq!(f.as_deref(), Some(field), "{query}: {reason}");
    }
    // Too many steps: the message says how many and what the limit is.
    let r = c
        .get("/api/v1/reconstruct?from=2013-01-01&to=2013-12-31&every_hours=1")
        .unwrap();
    let (_, _, reason) = error(&r);
    assert!(
        reason.contains("8737") && reason.contains("1000"),
        "{reason}"
    );
}

/// `GET /api/v1/reconstruct/map.svg` and `.png`: the two-panel figure of the estimate and
/// its uncertainty at a time, with its media type; bad queries name their field.
#[test]
fn draws_the_reconstruction_map_as_svg_and_png() {
    let server = Server::caf();
    let mut c = server.client();
    let r = c
        .get("/api/v1/reconstruct/map.svg?at=2013-12-01&estimator=changes")
        .unwrap();
    assert_eq!(r.status, 200, "{}", r.text());
    assert_eq!(r.header("content-type"), Some("image/svg+xml"));
    let svg = r.text();
    assert!(svg.starts_with("<svg") && svg.contains("2013-12-01 00:00 UTC"));
    assert!(svg.contains("kriging of changes") && svg.contains("VW (m\u{b3}/m\u{b3})"));
    assert_eq!(svg.matches(r#"id="value-cell-"#).count(), 42);
    assert_eq!(svg.matches(r#"id="sd-cell-"#).count(), 42);
    let marked = svg.matches(r#"class="sensor-read""#).count()
        + svg.matches(r#"class="sensor-estimated""#).count();
    assert_eq!(marked, 2 * 42);
    assert!(svg.matches(r#"class="sensor-read""#).count() > 0);
    // The same figure as the default estimator's, and deterministic.
    let again = c.get("/api/v1/reconstruct/map.svg?at=2013-12-01").unwrap();
    assert_eq!(again.text(), svg);
    let png = c
        .get("/api/v1/reconstruct/map.png?at=2013-12-01&estimator=dynamic")
        .unwrap();
    assert_eq!(png.status, 200, "{}", png.text());
    assert_eq!(png.header("content-type"), Some("image/png"));
    assert_eq!(&png.body[1..4], b"PNG");
    assert_eq!(
        u32::from_be_bytes(png.body[16..20].try_into().unwrap()),
        2102
    );
    for (query, field) in [
        ("at=yesterday", "at"),
        ("estimator=best", "estimator"),
        ("neighbours=0", "neighbours"),
        ("from=2013-11-01", "from"),
        ("modality=nothing@1cm", "modality"),
    ] {
        for ext in ["svg", "png"] {
            let r = c
                .get(&format!("/api/v1/reconstruct/map.{ext}?{query}"))
                .unwrap();
            assert_eq!(r.status, 400, "{ext} {query}: {}", r.text());
            let (_, f, reason) = error(&r);
            assert_eq!(f.as_deref(), Some(field), "{ext} {query}: {reason}");
        }
    }
    // Declared with their media types.
    let doc = server.get_json("/api/v1/openapi.json");
    let paths = &doc["paths"];
    assert!(
        paths["/api/v1/reconstruct/map.svg"]["get"]["responses"]["200"]["content"]["image/svg+xml"]
            .is_object()
    );
    assert!(
        paths["/api/v1/reconstruct/map.png"]["get"]["responses"]["200"]["content"]["image/png"]
            .is_object()
    );
    let answer = &paths["/api/v1/reconstruct"]["get"]["responses"]["200"]["content"]["application/json"]
        ["schema"];
    assert!(answer.to_string().contains("ReconstructAnswer"), "{answer}");
    let names: Vec<&str> = paths["/api/v1/reconstruct"]["get"]["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["name"].as_str().unwrap())
        .collect();
    for name in [
        "at",
        "from",
        "to",
        "every_hours",
        "cell",
        "modality",
        "estimator",
    ] {
        assert!(names.contains(&name), "{name}: {names:?}");
    }
}

/// `POST /api/v1/simulate` replays the served project's own record: the same missions for
/// every strategy, deterministic, the project only read; bad requests name their field.
#[test]
fn simulates_the_projects_recent_past_and_refuses_bad_requests_naming_the_field() {
    let server = Server::caf();
    let before = server.get_json("/api/v1/project");
    let mut c = server.client();
    let body = json!({
        "strategies": ["gleaner", "round-robin"],
        "start": "2013-12-25",
        "planner_iterations": 50
    });
    let post = |c: &mut gleaner_server::client::Client, body: &Value| {
        c.request(
            "POST",
            "/api/v1/simulate",
            &[("content-type", "application/json")],
            Some(body.to_string().as_bytes()),
        )
        .unwrap()
    };
    let r = post(&mut c, &body);
    assert_eq!(r.status, 200, "{}", r.text());
    let doc: Value = r.json().unwrap();
    assert_eq!(doc["format"], "gleaner.campaign");
    assert_eq!(doc["label"], "caf");
    assert_eq!(doc["modality"], "vw@30cm");
    assert_eq!(doc["period_s"], 86_400);
    // The history runs to the first mission; the last is when the last reading (stamped
    // 2013-12-31) becomes available.
    assert_eq!(doc["history_until"], "2013-12-25T00:00:00Z");
    assert_eq!(doc["first_mission"], "2013-12-25T00:00:00Z");
    assert_eq!(doc["last_mission"], "2014-01-01T00:00:00Z");
    assert_eq!(doc["missions"], 8);
    assert_eq!(doc["reference"], "gleaner");
    let strategies = doc["strategies"].as_array().unwrap();
    assert_eq!(strategies.len(), 2);
    for (x, name) in strategies.iter().zip(["gleaner", "round-robin"]) {
        assert_eq!(x["strategy"], name);
        assert_eq!(x["budget"], 1.0);
        // m³/m³ after the flights; the paper's battery: 66.5 kJ usable per mission.
        let rmse = x["metrics"]["rmse_kriged"]["mean"].as_f64().unwrap();
        assert!(rmse > 0.0 && rmse < 0.05, "{x}");
        let energy = x["metrics"]["energy_kj"]["mean"].as_f64().unwrap();
        assert!(energy > 30.0 && energy <= 66.5, "{x}");
        assert!(x["events_caught"].as_u64().unwrap() <= x["events"].as_u64().unwrap());
    }
    assert_eq!(strategies[0]["rmse_vs_reference"], Value::Null);
    assert!(strategies[1]["rmse_vs_reference"]["mean"].is_f64());
    // Deterministic, and the project is only read.
    let again: Value = post(&mut c, &body).json().unwrap();
    assert_eq!(again, doc);
    let after = server.get_json("/api/v1/project");
    assert_eq!(after["readings"], before["readings"]);
    assert_eq!(
        server.get_json("/api/v1/missions"),
        json!([]),
        "no mission stored"
    );

    for (bad, field) in [
        (json!({"strategies": ["best"]}), Some("strategies")),
        (json!({"every_hours": 0}), Some("every_hours")),
        (json!({"seeds": []}), Some("seeds")),
        (json!({"budgets": [0.0]}), Some("budgets")),
        (json!({"planner_iterations": 0}), Some("planner_iterations")),
        (json!({"energy_preset": "huge"}), Some("energy_preset")),
        (json!({"start": "soon"}), Some("start")),
        (
            json!({"strategies": ["all"], "start": "2012-01-01"}),
            Some("start"),
        ),
        (json!({"colour": "red"}), Some("colour")),
    ] {
        let r = post(&mut c, &bad);
        assert_eq!(r.status, 400, "{bad}: {}", r.text());
        let (code, f, reason) = error(&r);
        assert_eq!(code, "bad_request", "{bad}");
        assert!(!reason.is_empty());
        assert_eq!(f.as_deref(), field, "{bad}: {reason}");
    }
}

/// `POST /api/v1/simulate` with `"report": true`: the campaign document as without it, plus
/// the report `gleaner simulate` writes: Markdown with a row per strategy (its error as the
/// document says) and the charts it links, each a valid SVG document.
#[test]
fn simulates_with_the_campaign_report() {
    let server = Server::caf();
    let mut c = server.client();
    let post = |c: &mut gleaner_server::client::Client, body: &Value| {
        let r = c.post_json("/api/v1/simulate", body, None).unwrap();
        assert_eq!(r.status, 200, "{body}: {}", r.text());
        let v: Value = r.json().unwrap();
        v
    };
    let mut body = json!({
        "strategies": ["gleaner", "round-robin"],
        "start": "2013-12-25",
        "planner_iterations": 50
    });
    let plain = post(&mut c, &body);
    assert!(plain.get("report").is_none(), "no report unless asked");
    body["report"] = json!(true);
    let mut doc = post(&mut c, &body);
    let report = doc
        .as_object_mut()
        .unwrap()
        .remove("report")
        .expect("the report");
    assert_eq!(
        doc, plain,
        "the campaign document is the same with its report"
    );

    let markdown = report["markdown"].as_str().unwrap();
    assert!(markdown.starts_with("# Campaign report: caf"), "{markdown}");
    assert!(
        markdown.contains("POST /api/v1/simulate {"),
        "the request to reproduce it"
    );
    // The strategies' table: one row each, with the document's kriging RMSE (×1000).
    for x in doc["strategies"].as_array().unwrap() {
        let name = x["strategy"].as_str().unwrap();
        let rmse = x["metrics"]["rmse_kriged"]["mean"].as_f64().unwrap();
        let row = markdown
            .lines()
            .find(|l| l.starts_with(&format!("| {name} | ")))
            .unwrap_or_else(|| panic!("no row of {name}: {markdown}"));
        let cells: Vec<&str> = row.split('|').map(str::trim).collect();
        assert_eq!(cells[3], format!("{:.2}", rmse * 1000.0), "{row}");
    }
    let figures = report["figures"].as_array().unwrap();
    assert!(!figures.is_empty());
    let mut names = Vec::new();
    for f in figures {
        let name = f["name"].as_str().unwrap();
        let svg = f["svg"].as_str().unwrap();
        assert!(name.ends_with(".svg"), "{name}");
        assert!(
            markdown.contains(&format!("](figures/{name})")),
            "{name} linked"
        );
        let tree = gleaner_render::parse_svg(svg).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(
            tree.size().width() > 0.0 && tree.root().has_children(),
            "{name}"
        );
        names.push(name);
    }
    assert!(names.contains(&"rmse_intervals.svg"), "{names:?}");

    // The OpenAPI document names the field and the answer's report.
    let api = server.get_json("/api/v1/openapi.json");
    let schemas = &api["components"]["schemas"];
    assert!(schemas["SimulateBody"]["properties"]["report"].is_object());
    assert!(schemas["ReportDoc"]["properties"]["figures"].is_object());
    let answer = api["paths"]["/api/v1/simulate"]["post"]["responses"]["200"].to_string();
    assert!(answer.contains("SimulationDoc"), "{answer}");
}

/// `POST /api/v1/simulate` in wind (`wind`, `gust`, `leg_gust`, `weak_battery`,
/// `weather_seed`, `margin_quantile`, as the command line's flags): the answer tells how the
/// sorties flew, none over its battery; the same weather seed gives the same answer; a bad
/// value names its field; the OpenAPI document lists the fields.
#[test]
fn simulates_in_wind_and_names_bad_weather_fields() {
    let server = Server::caf();
    let mut c = server.client();
    let post = |c: &mut gleaner_server::client::Client, body: &Value| {
        c.request(
            "POST",
            "/api/v1/simulate",
            &[("content-type", "application/json")],
            Some(body.to_string().as_bytes()),
        )
        .unwrap()
    };
    let still = json!({
        "strategies": ["gleaner"],
        "start": "2013-12-28",
        "planner_iterations": 50
    });
    let r = post(&mut c, &still);
    assert_eq!(r.status, 200, "{}", r.text());
    let calm: Value = r.json().unwrap();
    assert!(
        calm.get("flights").is_none(),
        "still air: no flights section"
    );
    let mut body = still.clone();
    for (k, v) in [
        ("wind", json!("weibull:6")),
        ("gust", json!(1.5)),
        ("leg_gust", json!(0.5)),
        ("weak_battery", json!(0.1)),
        ("weather_seed", json!(3)),
        ("margin_quantile", json!(0.9)),
    ] {
        body[k] = v;
    }
    let r = post(&mut c, &body);
    assert_eq!(r.status, 200, "{}", r.text());
    let doc: Value = r.json().unwrap();
    let flights = doc["flights"].as_array().expect("flights");
    assert_eq!(flights.len(), 1);
    let f = &flights[0];
    assert_eq!(f["strategy"], "gleaner");
    assert_eq!(f["missions"], doc["missions"]);
    assert_eq!(f["over_budget"], 0, "{f}");
    assert!(f["max_excess_j"].as_f64().unwrap() <= 0.0, "{f}");
    assert!(f["mean_forecast_mps"].as_f64().unwrap() > 0.0, "{f}");
    let again: Value = post(&mut c, &body).json().unwrap();
    assert_eq!(again, doc);
    body["weather_seed"] = json!(4);
    let other: Value = post(&mut c, &body).json().unwrap();
    assert_ne!(other["flights"], doc["flights"]);

    for (bad, field) in [
        (json!({"wind": "gale"}), "wind"),
        (json!({"wind": "weibull:50"}), "wind"),
        (json!({"gust": -1}), "gust"),
        (json!({"leg_gust": 11}), "leg_gust"),
        (json!({"weak_battery": 0.9}), "weak_battery"),
        (json!({"margin_quantile": 0.2}), "margin_quantile"),
        (json!({"weather_seed": -1}), "weather_seed"),
    ] {
        let r = post(&mut c, &bad);
        assert_eq!(r.status, 400, "{bad}: {}", r.text());
        let (code, f, reason) = error(&r);
        assert_eq!(code, "bad_request", "{bad}");
        assert_eq!(f.as_deref(), Some(field), "{bad}: {reason}");
    }

    let api = server.get_json("/api/v1/openapi.json");
    let schemas = &api["components"]["schemas"];
    for field in [
        "wind",
        "gust",
        "leg_gust",
        "weak_battery",
        "weather_seed",
        "margin_quantile",
    ] {
        assert!(
            schemas["SimulateBody"]["properties"][field].is_object(),
            "{field}"
        );
    }
    assert!(schemas["ExploreBody"]["properties"]["wind"].is_object());
    assert!(schemas["CampaignDoc"]["properties"]["flights"].is_object());
    assert!(schemas["FlightSummaryDoc"].is_object());
}

/// `POST /api/v1/simulate` in observed daily winds (`winds`, as the command line's
/// `--wind-csv`): each mission is planned for its day's wind, the answer's flights say so;
/// a gap in the days, `wind` beside `winds`, or a bad entry is a 400 naming the field.
#[test]
fn simulates_in_observed_winds_and_names_bad_entries() {
    let server = Server::caf();
    let mut c = server.client();
    let post = |c: &mut gleaner_server::client::Client, body: &Value| {
        c.request(
            "POST",
            "/api/v1/simulate",
            &[("content-type", "application/json")],
            Some(body.to_string().as_bytes()),
        )
        .unwrap()
    };
    // 2013-12-20 .. 2014-01-05 at 5 m/s from the west, every mission day among them.
    let days: Vec<Value> = (0..17)
        .map(|k| {
            let t = gleaner_app::parse_timestamp("2013-12-20").unwrap() + k * 86_400;
            json!({"date": &gleaner_app::format_rfc3339(t)[..10], "speed_mps": 5.0, "from_deg": 270})
        })
        .collect();
    let body = json!({
        "strategies": ["gleaner"],
        "start": "2013-12-28",
        "planner_iterations": 50,
        "winds": days,
    });
    let r = post(&mut c, &body);
    assert_eq!(r.status, 200, "{}", r.text());
    let doc: Value = r.json().unwrap();
    let f = &doc["flights"][0];
    assert_eq!(f["missions"], doc["missions"], "{f}");
    assert!(doc["missions"].as_u64().unwrap() >= 4, "{doc}");
    // Every mission was planned for its day's 5 m/s.
    assert!(
        (f["mean_forecast_mps"].as_f64().unwrap() - 5.0).abs() < 1e-9,
        "{f}"
    );
    assert_eq!(f["over_budget"], 0, "{f}");
    let again: Value = post(&mut c, &body).json().unwrap();
    assert_eq!(again, doc, "the same winds, the same answer");

    let with = |edit: &dyn Fn(&mut Value)| {
        let mut b = body.clone();
        edit(&mut b);
        b
    };
    let cases: Vec<(Value, &str)> = vec![
        // 2013-12-30 missing: a mission day without its wind.
        (
            with(&|b| {
                b["winds"].as_array_mut().unwrap().remove(10);
            }),
            "winds",
        ),
        (with(&|b| b["wind"] = json!("weibull:4")), "winds"),
        (with(&|b| b["winds"] = json!([])), "winds"),
        (
            with(&|b| b["winds"][1]["date"] = json!("2013-13-01")),
            "winds[1].date",
        ),
        (
            with(&|b| b["winds"][1]["date"] = json!("2013-12-21T06:00:00Z")),
            "winds[1].date",
        ),
        (
            with(&|b| b["winds"][0]["speed_mps"] = json!(99)),
            "winds[0].speed_mps",
        ),
        (
            with(&|b| b["winds"][2]["from_deg"] = json!(-1)),
            "winds[2].from_deg",
        ),
        (
            with(&|b| b["winds"][3]["date"] = json!("2013-12-20")),
            "winds[3].date",
        ),
        (with(&|b| b["winds"][0]["gust"] = json!(1)), "winds"),
    ];
    for (bad, field) in cases {
        let r = post(&mut c, &bad);
        assert_eq!(r.status, 400, "{field}: {}", r.text());
        let (code, f, reason) = error(&r);
        assert_eq!(code, "bad_request", "{field}");
        assert_eq!(f.as_deref(), Some(field), "{reason}");
    }
    let api = server.get_json("/api/v1/openapi.json");
    let schemas = &api["components"]["schemas"];
    assert!(schemas["SimulateBody"]["properties"]["winds"].is_object());
    assert!(schemas["WindDayBody"]["properties"]["speed_mps"].is_object());
}

/// A plan previewed in a forecast wind (the dashboard's 6 m/s from the west) says the
/// strongest wind it stands, scanned up from the wind it was priced in: a route planned in
/// wind may be over the battery in still air (hovering in wind is cheaper), which is said,
/// not taken for "stands no wind".
#[test]
fn a_windy_plan_says_the_strongest_wind_it_stands() {
    let server = Server::caf();
    let mut c = server.client();
    let body = json!({"dry_run": true, "seed": 1, "iterations": 500, "time_limit_s": 5,
        "wind": {"speed_mps": 6, "from_deg": 270}});
    let r = c.post_json("/api/v1/plan", &body, None).unwrap();
    assert_eq!(r.status, 200, "{}", r.text());
    let m: Value = r.json().unwrap();
    let w = &m["wind"];
    assert_eq!(w["planned_mps"], 8.0, "{w}");
    let strongest = w["strongest_feasible_mps"]
        .as_f64()
        .expect("strongest wind");
    assert!((8.0..=40.0).contains(&strongest), "{w}");
    let still = json!({"dry_run": true, "seed": 1, "iterations": 500, "time_limit_s": 5,
        "wind": {"speed_mps": 0, "from_deg": 270}});
    let calm: Value = c
        .post_json("/api/v1/plan", &still, None)
        .unwrap()
        .json()
        .unwrap();
    assert!(
        calm["wind"].get("over_budget_in_still_air").is_none(),
        "a still-air plan is within budget in still air"
    );
}

/// `POST /api/v1/explore` with a forecast wind plans every sortie in it plus the margin.
#[test]
fn explores_in_the_forecast_wind() {
    let server = Server::caf();
    let mut c = server.client();
    let r = c
        .post_json("/api/v1/explore", &json!({"dry_run": true}), None)
        .unwrap();
    assert_eq!(r.status, 200, "{}", r.text());
    let still: Value = r.json().unwrap();
    let r = c
        .post_json(
            "/api/v1/explore",
            &json!({"dry_run": true, "wind": {"speed_mps": 8, "from_deg": 270}}),
            None,
        )
        .unwrap();
    assert_eq!(r.status, 200, "{}", r.text());
    let windy: Value = r.json().unwrap();
    // Priced otherwise (legs dearer, hovers cheaper), every cell still visited.
    assert_ne!(windy["total_energy_j"], still["total_energy_j"]);
    let stops = |d: &Value| {
        d["sorties"]
            .as_array()
            .unwrap()
            .iter()
            .map(|s| s["stops"].as_array().unwrap().len())
            .sum::<usize>()
    };
    assert_eq!(stops(&windy), stops(&still));
    for s in windy["sorties"].as_array().unwrap() {
        // The forecast plus `[flight] wind_margin_mps` (2 m/s by default).
        assert_eq!(s["profile"]["wind_mps"], 10.0, "{}", s["profile"]);
        assert_eq!(s["profile"]["wind_from_deg"], 270.0);
        let e = &s["energy"];
        assert!(
            e["total_j"].as_f64().unwrap() <= e["budget_j"].as_f64().unwrap(),
            "{e}"
        );
    }
    let r = c
        .post_json(
            "/api/v1/explore",
            &json!({"dry_run": true, "wind": {"speed_mps": 99, "from_deg": 270}}),
            None,
        )
        .unwrap();
    assert_eq!(r.status, 400, "{}", r.text());
    assert_eq!(error(&r).1.as_deref(), Some("wind"));
}

#[test]
fn reads_project_field_cells_cell_and_map() {
    let server = Server::caf();
    let project = server.get_json("/api/v1/project");
    assert_eq!(project["name"], "caf");
    assert_eq!(project["sensors"], 42);
    assert!(project["readings"].as_u64().unwrap() > 50_000);
    assert!(
        project["latest_reading"]
            .as_str()
            .unwrap()
            .starts_with("2013-12")
    );
    assert_eq!(project["writable"], true);
    assert_eq!(project["basemap_url"], Value::Null);

    let field = server.get_json("/api/v1/field");
    assert_eq!(field["format"], "gleaner.field");
    let n = field["cells"].as_array().unwrap().len();
    assert!((30..=42).contains(&n), "{n} cells");
    let cells = server.get_json("/api/v1/cells");
    assert_eq!(cells.as_array().unwrap().len(), n);

    let id = field["cells"][0]["cell"].as_str().unwrap().to_string();
    let detail = server.get_json(&format!("/api/v1/cells/{id}?days=10"));
    assert_eq!(detail["cell"]["cell"], id);
    assert_eq!(detail["rank"], Value::Null, "not scored yet");
    let series = detail["series"].as_array().unwrap();
    assert!(!series.is_empty());
    for s in series {
        let t = s["t"].as_array().unwrap();
        assert_eq!(t.len(), s["values"].as_array().unwrap().len());
        let first = t[0].as_i64().unwrap();
        let last = t[t.len() - 1].as_i64().unwrap();
        assert!(last - first <= 10 * 86_400, "10 days of series");
    }

    // The map: one cell shape per cell of /field, in the same order.
    let r = server.client().get("/api/v1/map.svg").unwrap();
    assert_eq!(r.status, 200);
    assert_eq!(r.header("content-type"), Some("image/svg+xml"));
    let svg = r.text();
    assert_eq!(svg.matches("<path id=\"cell-").count(), n);
    assert!(svg.contains(&format!("<title>{id} ")));

    assert_eq!(server.get_json("/api/v1/missions"), json!([]));

    // The dashboard is served by the same binary, with a strict content policy.
    let r = server.client().get("/").unwrap();
    assert_eq!(r.status, 200);
    assert!(r.text().contains("<script src=\"/app.js\""));
    assert!(
        r.header("content-security-policy")
            .unwrap()
            .contains("default-src 'self'")
    );
    for asset in ["/app.js", "/app.css"] {
        assert_eq!(server.client().get(asset).unwrap().status, 200, "{asset}");
    }
}

#[test]
fn several_sorties_share_the_cells_each_within_one_battery() {
    let server = Server::caf();
    let mut c = server.client();
    let body = |sorties: i64, dry_run: bool| json!({"solver": "greedy", "seed": 1, "sorties": sorties, "dry_run": dry_run});
    // The single-mission route points to this one for several sorties.
    let r = c.post_json("/api/v1/plan", &body(2, true), None).unwrap();
    assert_eq!(r.status, 400, "{}", r.text());
    assert_eq!(error(&r).1.as_deref(), Some("sorties"));
    for bad in [0, 21] {
        let r = c
            .post_json("/api/v1/plan/sorties", &body(bad, true), None)
            .unwrap();
        assert_eq!(r.status, 400, "sorties {bad}: {}", r.text());
        assert!(error(&r).2.contains("sorties"), "{}", r.text());
    }
    // A dry run: three sorties, no cell twice, each within its battery, nothing stored.
    let r = c
        .post_json("/api/v1/plan/sorties", &body(3, true), None)
        .unwrap();
    assert_eq!(r.status, 200, "{}", r.text());
    let docs = r.json().unwrap();
    let docs = docs.as_array().unwrap();
    assert_eq!(docs.len(), 3);
    let mut cells: Vec<String> = Vec::new();
    for d in docs {
        assert_eq!(d["status"], "dry-run");
        let e = &d["energy"];
        assert!(e["total_j"].as_f64().unwrap() <= e["budget_j"].as_f64().unwrap() + 1e-6);
        for stop in d["stops"].as_array().unwrap() {
            cells.push(stop["cell"].as_str().unwrap().to_string());
        }
    }
    let n = cells.len();
    cells.sort();
    cells.dedup();
    assert_eq!(cells.len(), n, "a cell in two sorties");
    assert!(
        n > docs[0]["stops"].as_array().unwrap().len(),
        "the others add cells"
    );
    assert_eq!(server.get_json("/api/v1/missions"), json!([]));
    // Stored: a token is needed; then three missions with the previewed routes.
    let r = c
        .post_json("/api/v1/plan/sorties", &body(3, false), None)
        .unwrap();
    assert_eq!(r.status, 401, "{}", r.text());
    let r = c
        .post_json("/api/v1/plan/sorties", &body(3, false), Some(TOKEN))
        .unwrap();
    assert_eq!(r.status, 200, "{}", r.text());
    let saved = r.json().unwrap();
    let saved = saved.as_array().unwrap();
    assert_eq!(saved.len(), 3);
    for (s, d) in saved.iter().zip(docs) {
        assert_eq!(
            s["stops"], d["stops"],
            "the saved routes are the previewed ones"
        );
        let id = s["mission_id"].as_i64().unwrap();
        let stored = server.get_json(&format!("/api/v1/missions/{id}"));
        assert_eq!(stored["stops"], s["stops"]);
    }
    assert_eq!(
        server
            .get_json("/api/v1/missions")
            .as_array()
            .unwrap()
            .len(),
        3
    );
}

#[test]
fn score_plan_export_record_lifecycle() {
    let server = Server::caf();
    let mut c = server.client();

    // Scoring: a dry run needs no token and stores nothing; a stored one needs it.
    let r = c
        .post_json(
            "/api/v1/score",
            &json!({"at": "2014-01-01", "dry_run": true}),
            None,
        )
        .unwrap();
    assert_eq!(r.status, 200, "{}", r.text());
    assert!(r.json().unwrap()["cells"].as_array().unwrap().len() > 20);
    assert!(server.get_json("/api/v1/cells")[0]["scores"].is_null());
    let r = c
        .post_json("/api/v1/score", &json!({"at": "2014-01-01"}), Some(TOKEN))
        .unwrap();
    assert_eq!(r.status, 200, "{}", r.text());
    assert!(server.get_json("/api/v1/cells")[0]["scores"].is_object());
    let field = server.get_json("/api/v1/field");
    let id = field["cells"][0]["cell"].as_str().unwrap();
    let detail = server.get_json(&format!("/api/v1/cells/{id}"));
    assert!(detail["rank"].as_u64().unwrap() >= 1);
    assert!(
        ["freshness", "anomaly", "uncertainty", "none"]
            .contains(&detail["driver"].as_str().unwrap())
    );
    let k = &detail["contributions"];
    let s = detail["cell"]["scores"]["score"].as_f64().unwrap();
    let sum: f64 = ["freshness", "anomaly", "uncertainty", "redundancy"]
        .iter()
        .map(|t| k[t].as_f64().unwrap())
        .sum();
    assert!((sum - s).abs() < 1e-9, "the weighted terms add up to S");

    // Planning: the dry run is previewed, then saved.
    let dry = c.post_json("/api/v1/plan", &plan_body(true), None).unwrap();
    assert_eq!(dry.status, 200, "{}", dry.text());
    let dry = dry.json().unwrap();
    assert_eq!(dry["status"], "dry-run");
    assert_eq!(server.get_json("/api/v1/missions"), json!([]));
    let r = c.post_json("/api/v1/map.svg", &dry, None).unwrap();
    assert_eq!(r.status, 200, "{}", r.text());
    assert!(r.text().contains("id=\"route\""));
    let saved = c
        .post_json("/api/v1/plan", &plan_body(false), Some(TOKEN))
        .unwrap();
    assert_eq!(saved.status, 200, "{}", saved.text());
    let saved = saved.json().unwrap();
    let mid = saved["mission_id"].as_i64().unwrap();
    assert_eq!(
        saved["stops"], dry["stops"],
        "the saved route is the previewed one"
    );
    let stored = server.get_json(&format!("/api/v1/missions/{mid}"));
    assert_eq!(stored["energy"], saved["energy"]);
    assert_eq!(
        server
            .get_json("/api/v1/missions")
            .as_array()
            .unwrap()
            .len(),
        1
    );

    // Downloads: every file, as an attachment of its type.
    for (name, media, _) in MISSION_FILES {
        let r = c
            .get(&format!("/api/v1/missions/{mid}/files/{name}"))
            .unwrap();
        assert_eq!(r.status, 200, "{name}: {}", r.text());
        assert_eq!(r.header("content-type"), Some(media), "{name}");
        // Named with the file's own extension (QGroundControl lists only `.plan` files).
        assert_eq!(
            r.header("content-disposition"),
            Some(format!("attachment; filename=\"mission-{mid}.{}\"", &name[8..]).as_str()),
            "{name}"
        );
        match name {
            "mission.plan" => {
                assert_eq!(r.json().unwrap()["fileType"], "Plan");
            }
            "mission.waypoints" => assert!(r.text().starts_with("QGC WPL 110")),
            "mission.kmz" => {
                let kmz = gleaner_wire::parse_wpml_kmz(&r.body).expect("a WPML archive");
                assert!(!kmz.waylines.waypoints.is_empty());
            }
            "mission.geojson" => assert_eq!(r.json().unwrap()["type"], "FeatureCollection"),
            "mission.json" => assert_eq!(r.json().unwrap()["mission_id"], mid),
            "mission.svg" => assert!(r.text().contains("<svg")),
            _ => assert_eq!(&r.body[1..4], b"PNG"),
        }
    }
    // Re-planning in the air after the first stop with 25 kJ left: a continuation within
    // the energy left less the reserve, its .plan without a take-off; too little for the way
    // home is refused with the advice to land.
    let path = format!("/api/v1/missions/{mid}/replan");
    let r = c
        .post_json(
            &path,
            &json!({"after_stop": 1, "energy_left_j": 25000.0, "iterations": 200}),
            None,
        )
        .unwrap();
    assert_eq!(r.status, 200, "{}", r.text());
    let rp = r.json().unwrap();
    assert_eq!(rp["mission"]["status"], "continuation");
    assert_eq!(rp["mission"]["continuation"]["after_stop"], 1);
    let e = &rp["mission"]["energy"];
    let budget = e["budget_j"].as_f64().unwrap();
    assert!(
        budget < 25000.0 && e["total_j"].as_f64().unwrap() <= budget,
        "{e}"
    );
    let kept = rp["mission"]["stops"].as_array().unwrap().len();
    let dropped = rp["dropped"].as_array().unwrap().len();
    assert_eq!(kept + dropped, saved["stops"].as_array().unwrap().len() - 1);
    let flight = gleaner_wire::parse_qgc_plan(rp["plan"].as_str().unwrap()).unwrap();
    assert!(flight.airborne);
    assert_eq!(flight.waypoints.len(), kept + 1);
    assert!(rp["waypoints"].as_str().unwrap().starts_with("QGC WPL 110"));
    let r = c
        .post_json(
            &path,
            &json!({"after_stop": 1, "energy_left_j": 3600.0}),
            None,
        )
        .unwrap();
    assert_eq!(r.status, 400, "{}", r.text());
    assert!(error(&r).2.contains("land now"), "{}", r.text());
    let r = c
        .post_json(
            &path,
            &json!({"after_stop": 99, "energy_left_j": 3e4}),
            None,
        )
        .unwrap();
    assert_eq!(r.status, 400, "{}", r.text());
    let svg = c.get(&format!("/api/v1/map.svg?mission={mid}")).unwrap();
    assert_eq!(svg.status, 200);
    let svg = svg.text();
    assert!(svg.contains("<text"), "the map has its labels");
    assert!(
        svg.contains(&format!("Mission {mid}")),
        "the map is the mission's"
    );

    // Recording the flight with the readings brought back.
    let sensors: Vec<String> = stored["stops"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|s| {
            let cell = s["cell"].as_str().unwrap();
            let cells = server.get_json(&format!("/api/v1/cells/{cell}?days=0"));
            cells["cell"]["sensors"]
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_str().unwrap().to_string())
                .collect::<Vec<_>>()
        })
        .collect();
    let flight = flight_csv(sensors.iter().map(String::as_str));
    let before = server.get_json("/api/v1/project")["readings"]
        .as_u64()
        .unwrap();
    let parts = [
        Part::Text("at".into(), "2014-02-01T00:00:00Z".into()),
        Part::File("files".into(), "flight.csv".into(), flight.clone()),
    ];
    let r = c
        .post_multipart(
            &format!("/api/v1/missions/{mid}/record"),
            &parts,
            Some(TOKEN),
        )
        .unwrap();
    assert_eq!(r.status, 200, "{}", r.text());
    let rec = r.json().unwrap();
    let inserted = rec["readings_inserted"].as_u64().unwrap();
    assert!(inserted > 0);
    assert_eq!(
        server.get_json("/api/v1/project")["readings"]
            .as_u64()
            .unwrap(),
        before + inserted
    );
    assert_eq!(
        server.get_json(&format!("/api/v1/missions/{mid}"))["status"],
        "flown"
    );
    // 409 on a second record, unless amending.
    let again = c
        .post_multipart(
            &format!("/api/v1/missions/{mid}/record"),
            &parts,
            Some(TOKEN),
        )
        .unwrap();
    assert_eq!(again.status, 409, "{}", again.text());
    assert_eq!(error(&again).0, "conflict");
    let mut amend = parts.to_vec();
    amend.push(Part::Text("amend".into(), "true".into()));
    let r = c
        .post_multipart(
            &format!("/api/v1/missions/{mid}/record"),
            &amend,
            Some(TOKEN),
        )
        .unwrap();
    assert_eq!(r.status, 200, "{}", r.text());
    assert_eq!(r.json().unwrap()["amended"], true);

    // Exploration: a dry run stores nothing; a saved one stores every sortie.
    let r = c
        .post_json("/api/v1/explore", &json!({"dry_run": true}), None)
        .unwrap();
    assert_eq!(r.status, 200, "{}", r.text());
    let sorties = r.json().unwrap()["sorties"].as_array().unwrap().len();
    assert!(sorties >= 1);
    assert_eq!(
        server
            .get_json("/api/v1/missions")
            .as_array()
            .unwrap()
            .len(),
        1
    );
    let r = c
        .post_json("/api/v1/explore", &json!({}), Some(TOKEN))
        .unwrap();
    assert_eq!(r.status, 200, "{}", r.text());
    assert_eq!(
        server
            .get_json("/api/v1/missions")
            .as_array()
            .unwrap()
            .len(),
        1 + sorties
    );
}

#[test]
fn ingest_is_all_or_nothing() {
    let server = Server::caf();
    let mut c = server.client();
    let readings = || {
        server.get_json("/api/v1/project")["readings"]
            .as_u64()
            .unwrap()
    };
    let before = readings();
    let good = flight_csv(["CAF003"]);
    let mut bad = good.clone();
    bad.extend_from_slice(b"CAF003,2014-01-40,vw@30cm,0.2,m3/m3\n");
    // The first file is fine, the second fails half-way: nothing of either is stored.
    let r = c
        .post_multipart(
            "/api/v1/ingest",
            &[
                Part::File("files".into(), "good.csv".into(), good.clone()),
                Part::File("files".into(), "../../bad.csv".into(), bad),
            ],
            Some(TOKEN),
        )
        .unwrap();
    assert_eq!(r.status, 400, "{}", r.text());
    let (code, field, reason) = error(&r);
    assert_eq!(
        (code.as_str(), field.as_deref()),
        ("bad_request", Some("files"))
    );
    assert!(
        reason.starts_with("bad.csv:33: "),
        "the client's file and line: {reason}"
    );
    assert!(!reason.contains("/tmp"), "no server path: {reason}");
    assert_eq!(readings(), before);

    // The good file alone is stored; a second upload of it changes nothing.
    let parts = [Part::File("files".into(), "good.csv".into(), good)];
    let r = c
        .post_multipart("/api/v1/ingest", &parts, Some(TOKEN))
        .unwrap();
    assert_eq!(r.status, 200, "{}", r.text());
    let n = r.json().unwrap()["inserted"].as_u64().unwrap();
    assert_eq!(n, 31);
    assert_eq!(readings(), before + n);
    let r = c
        .post_multipart("/api/v1/ingest", &parts, Some(TOKEN))
        .unwrap();
    assert_eq!(r.json().unwrap()["unchanged"], 31);
    assert_eq!(readings(), before + n);
}

#[test]
fn every_error_code() {
    let server = Server::caf();
    let mut c = server.client();
    // 400: a bad value, naming its field.
    let r = c
        .post_json(
            "/api/v1/score",
            &json!({"at": "yesterday", "dry_run": true}),
            None,
        )
        .unwrap();
    assert_eq!(r.status, 400);
    assert_eq!(error(&r).1.as_deref(), Some("at"));
    let r = c
        .post_json("/api/v1/plan", &json!({"dry_run": true, "budget": 3}), None)
        .unwrap();
    assert_eq!(r.status, 400);
    assert_eq!(error(&r).1.as_deref(), Some("budget"));
    let r = c
        .post_json(
            "/api/v1/plan",
            &json!({"dry_run": true, "seed": "one"}),
            None,
        )
        .unwrap();
    assert_eq!(r.status, 400);
    assert_eq!(error(&r).1.as_deref(), Some("seed"));
    let r = c
        .post_json(
            "/api/v1/plan",
            &json!({"dry_run": true, "solver": "magic"}),
            None,
        )
        .unwrap();
    assert_eq!((r.status, error(&r).1.as_deref()), (400, Some("solver")));
    let r = c
        .post_json(
            "/api/v1/plan",
            &json!({"dry_run": true, "time_limit_s": 1e9}),
            None,
        )
        .unwrap();
    assert_eq!(
        (r.status, error(&r).1.as_deref()),
        (400, Some("time_limit_s"))
    );
    let r = c
        .post_json(
            "/api/v1/plan",
            &json!({"dry_run": true, "energy_preset": "huge"}),
            None,
        )
        .unwrap();
    assert_eq!(
        (r.status, error(&r).1.as_deref()),
        (400, Some("energy_preset"))
    );
    let r = c.get("/api/v1/missions/abc").unwrap();
    assert_eq!((r.status, error(&r).1.as_deref()), (400, Some("mission")));
    let r = c.get("/api/v1/cells/nowhere").unwrap();
    assert_eq!((r.status, error(&r).1.as_deref()), (400, Some("cell")));
    let r = c.get("/api/v1/cells/x0y0?days=-1").unwrap();
    assert_eq!((r.status, error(&r).1.as_deref()), (400, Some("days")));
    let auth = format!("Bearer {TOKEN}");
    let r = c
        .request(
            "POST",
            "/api/v1/score",
            &[
                ("Content-Type", "application/json"),
                ("Authorization", &auth),
            ],
            Some(b"{not json"),
        )
        .unwrap();
    assert_eq!(r.status, 400);
    assert_eq!(
        (error(&r).0.as_str(), error(&r).1.as_deref()),
        ("bad_request", Some("body"))
    );

    // 404: missions, cells, files, routes.
    let r = c.get("/api/v1/missions/999").unwrap();
    assert_eq!((r.status, error(&r).0.as_str()), (404, "not_found"));
    let r = c.get("/api/v1/cells/x999y999").unwrap();
    assert_eq!((r.status, error(&r).1.as_deref()), (404, Some("cell")));
    let r = c
        .get("/api/v1/missions/1/files/..%2F..%2Fgleaner.db")
        .unwrap();
    assert_eq!((r.status, error(&r).1.as_deref()), (404, Some("name")));
    let r = c.get("/api/v1/nothing").unwrap();
    assert_eq!((r.status, error(&r).0.as_str()), (404, "not_found"));
    let r = c.get("/../gleaner.toml").unwrap();
    assert_eq!(r.status, 404);

    // 401: writes without the token or with another one; 403 on a read-only server.
    let r = c
        .post_json("/api/v1/plan", &plan_body(false), None)
        .unwrap();
    assert_eq!((r.status, error(&r).0.as_str()), (401, "unauthorized"));
    assert_eq!(r.header("www-authenticate"), Some("Bearer"));
    let r = c
        .post_json(
            "/api/v1/plan",
            &plan_body(false),
            Some("not-the-token-at-all"),
        )
        .unwrap();
    assert_eq!(r.status, 401);
    let r = c
        .post_multipart(
            "/api/v1/ingest",
            &[Part::File(
                "files".into(),
                "a.csv".into(),
                flight_csv(["CAF003"]),
            )],
            Some("wrong-token-0123456789"),
        )
        .unwrap();
    assert_eq!(r.status, 401);
    assert_eq!(
        server.get_json("/api/v1/missions"),
        json!([]),
        "nothing written"
    );
    let r = c
        .post_json("/api/v1/plan", &plan_body(false), Some(TOKEN))
        .unwrap();
    assert_eq!(r.status, 200, "the right token is accepted: {}", r.text());

    // 409: recording a flown mission again (also in the lifecycle test).
    let mid = r.json().unwrap()["mission_id"].as_i64().unwrap();
    for expected in [200, 409] {
        let r = c
            .post_multipart(&format!("/api/v1/missions/{mid}/record"), &[], Some(TOKEN))
            .unwrap();
        assert_eq!(r.status, expected, "{}", r.text());
    }

    // 413: a JSON body over 1 MiB.
    let big = json!({"at": "x".repeat(2 << 20)});
    let r = c.post_json("/api/v1/score", &big, None).unwrap();
    assert_eq!((r.status, error(&r).0.as_str()), (413, "payload_too_large"));

    let read_only = Server::start(caf_project(), |_| {});
    let r = read_only
        .client()
        .post_json("/api/v1/plan", &plan_body(false), Some(TOKEN))
        .unwrap();
    assert_eq!((r.status, error(&r).0.as_str()), (403, "forbidden"));
}

#[test]
fn uploads_over_the_limit_are_refused_and_store_nothing() {
    let server = Server::start(caf_project(), |c| {
        c.token = Some(gleaner_server::Token::new(TOKEN).unwrap());
        c.max_upload_bytes = 4096;
    });
    let before = server.get_json("/api/v1/project")["readings"]
        .as_u64()
        .unwrap();
    let good = flight_csv(["CAF003"]);
    assert!(good.len() < 4096);
    let mut big = good.clone();
    while big.len() < 64 << 10 {
        big.extend_from_slice(b"CAF003,2014-01-01,vw@30cm,0.2,m3/m3\n");
    }
    let r = server
        .client()
        .post_multipart(
            "/api/v1/ingest",
            &[
                Part::File("files".into(), "good.csv".into(), good),
                Part::File("files".into(), "big.csv".into(), big),
            ],
            Some(TOKEN),
        )
        .unwrap();
    assert_eq!(r.status, 413, "{}", r.text());
    assert_eq!(error(&r).1.as_deref(), Some("files"));
    assert_eq!(
        server.get_json("/api/v1/project")["readings"]
            .as_u64()
            .unwrap(),
        before
    );
}

#[test]
fn configuration_is_checked() {
    let mut config = gleaner_server::ServerConfig::new("p".into());
    assert!(config.check().is_ok());
    config.addr = "0.0.0.0:8080".parse().unwrap();
    let e = config.check().unwrap_err().to_string();
    assert!(e.contains("needs a token"), "{e}");
    config.token = Some(gleaner_server::Token::new(TOKEN).unwrap());
    assert!(config.check().is_ok());
    config.cors_origins = vec!["*".into()];
    assert!(config.check().is_err());
    config.cors_origins = vec!["http://localhost:3000".into()];
    config.basemap_url = Some("https://tiles.example/{z}/{x}/{y}.png".into());
    assert!(config.check().is_ok());
    config.basemap_url = Some("javascript:alert(1)".into());
    assert!(config.check().is_err());
}

#[test]
fn cors_is_off_unless_configured() {
    let server = Server::caf();
    let origin = [("Origin", "http://elsewhere.example")];
    let r = server
        .client()
        .request("GET", "/api/v1/project", &origin, None)
        .unwrap();
    assert_eq!(r.header("access-control-allow-origin"), None);
    let server = Server::start(caf_project(), |c| {
        c.cors_origins = vec!["http://elsewhere.example".into()];
    });
    let r = server
        .client()
        .request("GET", "/api/v1/project", &origin, None)
        .unwrap();
    assert_eq!(
        r.header("access-control-allow-origin"),
        Some("http://elsewhere.example")
    );
}
