//! The server under a hostile or careless client: hang-ups, missing tokens, foreign hosts,
//! wrong content types, half-open and idle connections, too many connections, secrets in
//! query strings, and the security headers. Every test synchronises on the server's events
//! (`Watched`), never on time.

use std::io::{Read, Write};
use std::net::TcpStream;
use std::sync::{Arc, Mutex, OnceLock};

use serde_json::json;

use gleaner_server::Event;
use gleaner_server::client::{Client, Part};

use crate::common::{Server, TOKEN, Watched, caf_project, raw_json};

/// A short simulation of the CAF project's last week.
const SIMULATION: &str = r#"{"strategies": ["gleaner", "round-robin"], "start": "2013-12-25", "planner_iterations": 50}"#;

fn status_of(r: &gleaner_server::client::Response) -> (u16, String, Option<String>) {
    let v = r.json().unwrap_or_default();
    (
        r.status,
        v["error"].as_str().unwrap_or("").to_string(),
        v["field"].as_str().map(str::to_string),
    )
}

/// A client that sends a simulation and hangs up while it runs: the planning slot stays
/// taken until the work really ends, the work is cancelled (it stops at its next mission),
/// and then the slot is free for the next request.
#[test]
fn a_client_that_hangs_up_keeps_the_slot_taken_until_its_work_ends() {
    let server = Watched::start(&["simulate"], |_| {});
    let mut s = TcpStream::connect(server.addr).unwrap();
    s.write_all(&raw_json(
        "POST",
        "/api/v1/simulate",
        &server.addr.to_string(),
        "",
        SIMULATION,
    ))
    .unwrap();
    server.next(|e| *e == Event::Started("simulate"));
    drop(s);
    server.next(|e| *e == Event::Abandoned("simulate"));
    // The request is gone; its work is not: the slot is still taken.
    assert!(
        !server.state.planning_idle(),
        "the slot was freed by the hang-up"
    );
    server.release();
    let ended = server.next(|e| {
        matches!(
            e,
            Event::Ended {
                kind: "simulate",
                ..
            }
        )
    });
    assert_eq!(
        ended,
        Event::Ended {
            kind: "simulate",
            cancelled: true
        },
        "the abandoned simulation stopped early"
    );
    assert!(server.state.planning_idle());
    // The next planning request runs.
    let r = Client::new(server.addr)
        .post_json(
            "/api/v1/plan",
            &json!({"solver": "greedy", "dry_run": true}),
            None,
        )
        .unwrap();
    assert_eq!(r.status, 200, "{}", r.text());
}

/// A simulation still running at shutdown is cancelled: its client gets 503 `cancelled` and
/// the server stops without waiting for the campaign.
#[test]
fn shutdown_cancels_a_running_simulation() {
    let mut server = Watched::start(&["simulate"], |_| {});
    let addr = server.addr;
    let client = std::thread::spawn(move || {
        let mut c = Client::new(addr);
        c.request(
            "POST",
            "/api/v1/simulate",
            &[("Content-Type", "application/json")],
            Some(SIMULATION.as_bytes()),
        )
        .unwrap()
    });
    server.next(|e| *e == Event::Started("simulate"));
    server.begin_stop();
    server.next(|e| *e == Event::ShuttingDown);
    server.release();
    let r = client.join().unwrap();
    assert_eq!(r.status, 503, "{}", r.text());
    assert_eq!(status_of(&r).1, "cancelled");
    server.next(|e| {
        *e == Event::Ended {
            kind: "simulate",
            cancelled: true,
        }
    });
    server.join();
}

/// Beyond loopback every computation needs the token, checked before the body is read.
#[test]
fn every_computation_needs_the_token_when_not_loopback_only() {
    let server = Server::start(caf_project(), |c| {
        c.token = Some(gleaner_server::Token::new(TOKEN).unwrap());
        c.anonymous_compute = false;
    });
    let mut c = server.client();
    let dry = json!({"dry_run": true, "solver": "greedy"});
    let computations: [(&str, &str, serde_json::Value); 6] = [
        ("POST", "/api/v1/score", json!({"dry_run": true})),
        ("POST", "/api/v1/plan", dry.clone()),
        (
            "POST",
            "/api/v1/plan/sorties",
            json!({"dry_run": true, "solver": "greedy", "sorties": 2}),
        ),
        ("POST", "/api/v1/explore", json!({"dry_run": true})),
        (
            "POST",
            "/api/v1/simulate",
            json!({"strategies": ["nearest"], "start": "2013-12-30", "planner_iterations": 10}),
        ),
        ("POST", "/api/v1/map.svg", json!({})),
    ];
    for (method, path, body) in &computations {
        let r = c.post_json(path, body, None).unwrap();
        assert_eq!(
            status_of(&r),
            (401, "unauthorized".into(), Some("Authorization".into())),
            "{method} {path}: {}",
            r.text()
        );
        // A bad body without the token: still 401, the body is never looked at.
        let r = c
            .request(
                method,
                path,
                &[("Content-Type", "application/json")],
                Some(b"{not json"),
            )
            .unwrap();
        assert_eq!(r.status, 401, "{path}: {}", r.text());
    }
    for path in [
        "/api/v1/reconstruct?at=2013-12-01",
        "/api/v1/reconstruct?from=2013-11-01&to=2013-12-01",
        "/api/v1/reconstruct/map.svg?at=2013-12-01",
        "/api/v1/reconstruct/map.png?at=2013-12-01",
    ] {
        let r = c.get(path).unwrap();
        assert_eq!(r.status, 401, "{path}: {}", r.text());
    }
    // With the token they run (the quick ones here).
    let auth = format!("Bearer {TOKEN}");
    for (path, body) in [
        ("/api/v1/score", json!({"dry_run": true})),
        ("/api/v1/plan", dry),
    ] {
        let r = c
            .request(
                "POST",
                path,
                &[
                    ("Content-Type", "application/json"),
                    ("Authorization", &auth),
                ],
                Some(body.to_string().as_bytes()),
            )
            .unwrap();
        assert_eq!(r.status, 200, "{path}: {}", r.text());
    }
    for path in [
        "/api/v1/reconstruct?at=2013-12-01",
        "/api/v1/reconstruct?from=2013-11-25&to=2013-12-01",
        "/api/v1/reconstruct/map.svg?at=2013-12-01",
    ] {
        let r = c
            .request("GET", path, &[("Authorization", &auth)], None)
            .unwrap();
        assert_eq!(r.status, 200, "{path}: {}", r.text());
    }
    // Stored data stays readable.
    assert_eq!(c.get("/api/v1/project").unwrap().status, 200);
}

/// On a loopback-only server previews need no token, but a body that is not a dry run is
/// refused for want of the token before its content is judged.
#[test]
fn without_the_token_a_bad_body_is_401_and_a_preview_runs() {
    let server = Server::caf();
    let mut c = server.client();
    for body in [
        &b"{not json"[..],
        b"[]",
        b"{\"dry_run\": false, \"budget\": 3}",
        b"",
    ] {
        let r = c
            .request(
                "POST",
                "/api/v1/plan",
                &[("Content-Type", "application/json")],
                Some(body),
            )
            .unwrap();
        assert_eq!(
            r.status,
            401,
            "{}: {}",
            String::from_utf8_lossy(body),
            r.text()
        );
    }
    // A dry run's own mistakes are 400s naming the field.
    let r = c
        .post_json("/api/v1/plan", &json!({"dry_run": true, "budget": 3}), None)
        .unwrap();
    assert_eq!(
        status_of(&r),
        (400, "bad_request".into(), Some("budget".into()))
    );
    // A wrong token is 401 even where none is needed; the scheme is matched in any case.
    let r = c
        .request(
            "GET",
            "/api/v1/project",
            &[("Authorization", "Bearer wrong-token-0123456789")],
            None,
        )
        .unwrap();
    assert_eq!(r.status, 401);
    let lower = format!("bearer {TOKEN}");
    let r = c
        .request(
            "POST",
            "/api/v1/plan",
            &[
                ("Content-Type", "application/json"),
                ("Authorization", &lower),
            ],
            Some(json!({"solver": "greedy"}).to_string().as_bytes()),
        )
        .unwrap();
    assert_eq!(r.status, 200, "lowercase bearer: {}", r.text());
    // Uploads: the token before the body.
    let r = c
        .post_multipart(
            "/api/v1/ingest",
            &[Part::File(
                "files".into(),
                "a.csv".into(),
                b"garbage".to_vec(),
            )],
            None,
        )
        .unwrap();
    assert_eq!(r.status, 401, "{}", r.text());
}

/// Only `localhost`, IP literals and configured names: a rebound foreign name reads nothing.
#[test]
fn the_host_header_is_checked() {
    let server = Server::start(caf_project(), |c| {
        c.token = Some(gleaner_server::Token::new(TOKEN).unwrap());
        c.allowed_hosts = vec!["farm.example".into()];
    });
    let port = server.addr.port();
    let get = |host: Option<&str>| {
        let head = match host {
            Some(h) => format!("GET /api/v1/project HTTP/1.1\r\nHost: {h}\r\n\r\n"),
            None => "GET /api/v1/project HTTP/1.0\r\n\r\n".to_string(),
        };
        Client::new(server.addr)
            .request_raw(head.as_bytes())
            .unwrap()
    };
    for ok in [
        format!("localhost:{port}"),
        format!("127.0.0.1:{port}"),
        "farm.example".into(),
        format!("FARM.example:{port}"),
    ] {
        assert_eq!(get(Some(&ok)).status, 200, "{ok}");
    }
    for bad in ["evil.example", "evil.example:8080", "127.0.0.1.nip.example"] {
        let r = get(Some(bad));
        assert_eq!(
            status_of(&r),
            (421, "misdirected_request".into(), Some("Host".into())),
            "{bad}: {}",
            r.text()
        );
        let page = Client::new(server.addr)
            .request_raw(format!("GET / HTTP/1.1\r\nHost: {bad}\r\n\r\n").as_bytes())
            .unwrap();
        assert_eq!(page.status, 421, "the page too");
    }
    assert_eq!(get(None).status, 400);
}

/// JSON routes take `application/json` only (415 otherwise); uploads take multipart only.
#[test]
fn json_routes_need_a_json_content_type() {
    let server = Server::caf();
    let mut c = server.client();
    let body = json!({"dry_run": true, "solver": "greedy"}).to_string();
    for (ct, expected) in [
        (Some("text/plain"), 415),
        (Some("application/x-www-form-urlencoded"), 415),
        (Some("multipart/form-data; boundary=x"), 415),
        (None, 415),
        (Some("application/json; charset=utf-8"), 200),
        (Some("Application/JSON"), 200),
    ] {
        let headers: Vec<(&str, &str)> = ct.iter().map(|v| ("Content-Type", *v)).collect();
        let r = c
            .request("POST", "/api/v1/plan", &headers, Some(body.as_bytes()))
            .unwrap();
        assert_eq!(r.status, expected, "{ct:?}: {}", r.text());
        if expected == 415 {
            assert_eq!(
                status_of(&r),
                (
                    415,
                    "unsupported_media_type".into(),
                    Some("Content-Type".into())
                )
            );
        }
    }
    for path in [
        "/api/v1/score",
        "/api/v1/simulate",
        "/api/v1/explore",
        "/api/v1/map.svg",
    ] {
        let r = c
            .request("POST", path, &[("Content-Type", "text/plain")], Some(b"{}"))
            .unwrap();
        assert_eq!(r.status, 415, "{path}");
    }
    let auth = format!("Bearer {TOKEN}");
    let r = c
        .request(
            "POST",
            "/api/v1/ingest",
            &[
                ("Content-Type", "application/json"),
                ("Authorization", &auth),
            ],
            Some(b"{}"),
        )
        .unwrap();
    assert_eq!(r.status, 415, "{}", r.text());
}

/// Reads from `stream` until the server closes it; what it sent first.
fn read_until_closed(stream: &mut TcpStream) -> Vec<u8> {
    // A bound on a stuck server, not a timing assertion.
    stream
        .set_read_timeout(Some(std::time::Duration::from_secs(120)))
        .unwrap();
    let mut all = Vec::new();
    let mut buf = [0u8; 4096];
    loop {
        match stream.read(&mut buf) {
            Ok(0) => return all,
            Ok(n) => all.extend_from_slice(&buf[..n]),
            Err(e) if e.kind() == std::io::ErrorKind::ConnectionReset => return all,
            Err(e) => panic!("the server did not close the connection: {e}"),
        }
    }
}

/// A connection that never finishes its request head is closed after the header-read
/// timeout, and so is a kept-alive connection that sends nothing more (the idle timeout).
/// The test waits for the server to close each connection, never for time to pass; the
/// requests are sent before the server runs, so the timeout cannot beat them.
#[test]
fn half_open_and_idle_connections_are_closed() {
    let dir = caf_project();
    let mut config = gleaner_server::ServerConfig::new(dir.path().join("caf"));
    config.addr = "127.0.0.1:0".parse().unwrap();
    config.header_read_timeout = std::time::Duration::from_millis(50);
    let listener = std::net::TcpListener::bind(config.addr).unwrap();
    let addr = listener.local_addr().unwrap();
    // Connected and written before the server runs, so the bytes are there when it reads.
    let mut silent = TcpStream::connect(addr).unwrap();
    let mut partial = TcpStream::connect(addr).unwrap();
    partial
        .write_all(format!("GET /api/v1/project HTTP/1.1\r\nHost: {addr}\r\nX-Slow: ").as_bytes())
        .unwrap();
    let mut idle = TcpStream::connect(addr).unwrap();
    idle.write_all(format!("GET /favicon.ico HTTP/1.1\r\nHost: {addr}\r\n\r\n").as_bytes())
        .unwrap();
    let _server = Watched::serve(dir, config, listener, &[]);
    assert!(read_until_closed(&mut silent).is_empty());
    assert!(
        read_until_closed(&mut partial).is_empty(),
        "no answer to half a head"
    );
    let answered = String::from_utf8(read_until_closed(&mut idle)).unwrap();
    assert!(answered.starts_with("HTTP/1.1 204"), "{answered}");
}

/// At most `max_connections` are open: the next one waits until one closes.
#[test]
fn connections_are_capped() {
    let server = Watched::start(&[], |c| {
        c.max_connections = 1;
        c.header_read_timeout = std::time::Duration::from_secs(3600);
    });
    let mut first = Client::new(server.addr);
    assert_eq!(first.get("/favicon.ico").unwrap().status, 204);
    server.next(|e| *e == Event::Accepted { open: 1 });
    server.next(|e| *e == Event::AtCapacity);
    let addr = server.addr;
    let second = std::thread::spawn(move || Client::new(addr).get("/favicon.ico").unwrap());
    drop(first);
    server.next(|e| *e == Event::Closed { open: 0 });
    server.next(|e| *e == Event::Accepted { open: 1 });
    assert_eq!(second.join().unwrap().status, 204);
}

/// What the server logs, for the whole test binary.
fn log() -> &'static Arc<Mutex<Vec<u8>>> {
    static LOG: OnceLock<Arc<Mutex<Vec<u8>>>> = OnceLock::new();
    LOG.get_or_init(|| {
        let buf = Arc::new(Mutex::new(Vec::new()));
        let writer = Arc::clone(&buf);
        let subscriber = tracing_subscriber::fmt()
            .with_max_level(tracing::Level::TRACE)
            .with_ansi(false)
            .with_writer(move || LogWriter(Arc::clone(&writer)))
            .finish();
        tracing::subscriber::set_global_default(subscriber).ok();
        buf
    })
}

struct LogWriter(Arc<Mutex<Vec<u8>>>);

impl Write for LogWriter {
    fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
        self.0.lock().unwrap().extend_from_slice(b);
        Ok(b.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// Neither a token put in a query string nor the `Authorization` header reaches the log.
#[test]
fn tokens_never_reach_the_log() {
    let log = log();
    let server = Server::caf();
    let mut c = server.client();
    let secret = "query-secret-5f1c0e9a77";
    assert_eq!(
        c.get(&format!("/api/v1/project?token={secret}"))
            .unwrap()
            .status,
        200
    );
    let r = c
        .get(&format!(
            "/api/v1/reconstruct?at=2013-12-01&access_token={secret}"
        ))
        .unwrap();
    assert_eq!(r.status, 400, "an unknown parameter: {}", r.text());
    let r = c
        .post_json("/api/v1/plan", &json!({"solver": "greedy"}), Some(TOKEN))
        .unwrap();
    assert_eq!(r.status, 200);
    drop(server);
    let text = String::from_utf8_lossy(&log.lock().unwrap()).into_owned();
    assert!(text.contains("token=…"), "the request is logged: {text}");
    assert!(!text.contains(secret), "a query token was logged");
    assert!(!text.contains(TOKEN), "the bearer token was logged");
}

/// `announce` prints a token only when it was drawn here and only to a terminal.
#[test]
fn a_supplied_token_is_never_printed() {
    let addr: std::net::SocketAddr = "127.0.0.1:8080".parse().unwrap();
    let token = gleaner_server::Token::new(TOKEN).unwrap();
    for terminal in [true, false] {
        let text = gleaner_server::announce(addr, Some(&token), false, terminal);
        assert!(!text.contains(TOKEN), "{text}");
        assert!(text.contains("http://127.0.0.1:8080/"));
    }
    let drawn = gleaner_server::announce(addr, Some(&token), true, true);
    assert!(drawn.contains(&format!("#token={TOKEN}")), "{drawn}");
    let piped = gleaner_server::announce(addr, Some(&token), true, false);
    assert!(
        !piped.contains(TOKEN),
        "a drawn token never goes to a log: {piped}"
    );
}

/// Every response, whatever its status, says `nosniff` and carries a content policy.
#[test]
fn every_response_has_the_security_headers() {
    let server = Server::caf();
    let mut c = server.client();
    let mut seen = Vec::new();
    for (method, path, body) in [
        ("GET", "/", None),
        ("GET", "/app.js", None),
        ("GET", "/favicon.ico", None),
        ("GET", "/api/v1/project", None),
        ("GET", "/api/v1/openapi.json", None),
        ("GET", "/api/v1/nothing", None),
        ("DELETE", "/api/v1/project", None),
        ("POST", "/api/v1/ingest", Some(&b""[..])),
        ("GET", "/api/v1/cells/nowhere", None),
    ] {
        let r = c.request(method, path, &[], body).unwrap();
        assert_eq!(
            r.header("x-content-type-options"),
            Some("nosniff"),
            "{method} {path}"
        );
        let csp = r.header("content-security-policy").unwrap_or("");
        assert!(
            csp.contains("default-src") && csp.contains("frame-ancestors 'none'"),
            "{method} {path}: {csp}"
        );
        seen.push(r.status);
    }
    assert_eq!(seen, [200, 200, 204, 200, 200, 404, 405, 401, 400]);
}
