//! Many farms on one server, and replicas over one PostgreSQL (`gleaner serve --farms`): a
//! farm token opens its own farm only, with its scope; two servers over the same farms
//! directory serialise plans and records on a farm in the database (distinct mission ids,
//! nothing lost, nothing doubled).
//!
//! The farm `north` lives in PostgreSQL (`GLEANER_TEST_PG_URL`: these tests fail without a
//! server, like the store's), `south` in SQLite. `GLEANER_REPLICA_WRITES` (default 40) sets
//! how many writes the replica test makes: it is also the benchmark of BENCHMARKS.md with
//! 1,000 (`scripts/bench-replicas.sh`).

use std::collections::{BTreeMap, BTreeSet};
use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Barrier};

use gleaner_app::{self as app, Silent};
use gleaner_server::client::{Client, Part, Response};
use gleaner_server::{Scope, ServerConfig};
use serde_json::{Value, json};

use crate::common::{caf_project, flight_csv, shared_data, template_inputs};

fn pg_url() -> String {
    std::env::var("GLEANER_TEST_PG_URL").expect(
        "GLEANER_TEST_PG_URL names a PostgreSQL server for these tests (scripts/pg-cluster.sh starts one)",
    )
}

/// A farms directory: `north` (CAF 2013 in a fresh PostgreSQL schema) and `south` (an SQLite
/// copy of the CAF project), with a write and a read token for north and a write token for
/// south. The schema is dropped on drop.
struct Farms {
    dir: tempfile::TempDir,
    schema: String,
    north_write: String,
    north_read: String,
    south_write: String,
}

impl Farms {
    fn new(tag: &str) -> Self {
        let dir = tempfile::tempdir().unwrap();
        let schema = format!(
            "farms_{tag}_{}_{}",
            std::process::id(),
            std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .unwrap()
                .as_nanos()
                % 1_000_000_000
        );
        let data = shared_data();
        let (mut north, _) = app::init(&app::InitRequest {
            dir: dir.path().join("north"),
            sensors: data.join("caf/sensors/CAF_sensor_locations.csv"),
            utm_zone: Some("11N".into()),
            name: Some("north".into()),
            database: Some(format!("{}#{schema}", pg_url())),
            ..Default::default()
        })
        .unwrap();
        app::ingest(
            &mut north,
            &app::IngestRequest {
                files: template_inputs(),
                ..Default::default()
            },
            0,
            &Silent,
        )
        .unwrap();
        drop(north);
        let caf = caf_project();
        copy_dir(&caf.path().join("caf"), &dir.path().join("south"));
        let mut lines = vec!["# farm scope sha256(token)".to_string()];
        let mut token = |farm: &str, scope: Scope| {
            let (t, line) = gleaner_server::farms::new_token_line(farm, scope).unwrap();
            lines.push(line);
            t.reveal().to_string()
        };
        let north_write = token("north", Scope::Write);
        let north_read = token("north", Scope::Read);
        let south_write = token("south", Scope::Write);
        std::fs::write(dir.path().join("tokens"), lines.join("\n") + "\n").unwrap();
        Self {
            dir,
            schema,
            north_write,
            north_read,
            south_write,
        }
    }

    fn path(&self) -> &Path {
        self.dir.path()
    }
}

impl Drop for Farms {
    fn drop(&mut self) {
        let _ = app::PgStore::drop_project(&pg_url(), &self.schema);
    }
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        if e.file_type().unwrap().is_file() {
            std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
        }
    }
}

/// A farms server (one replica) on an ephemeral loopback port; stopped and joined on drop.
struct Replica {
    addr: SocketAddr,
    stop: Option<tokio::sync::oneshot::Sender<()>>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Replica {
    fn start(farms: &Path) -> Self {
        let mut config = ServerConfig::new(PathBuf::new());
        config.farms = Some(farms.to_path_buf());
        config.addr = "127.0.0.1:0".parse().unwrap();
        config.max_connections = 1024;
        let opened = gleaner_server::Farms::open(&config).unwrap();
        let (addr_tx, addr_rx) = std::sync::mpsc::channel();
        let (stop, stopped) = tokio::sync::oneshot::channel::<()>();
        let thread = std::thread::spawn(move || {
            let rt = tokio::runtime::Builder::new_multi_thread()
                .worker_threads(2)
                .enable_all()
                .build()
                .unwrap();
            rt.block_on(async move {
                let listener = tokio::net::TcpListener::bind(config.addr).await.unwrap();
                addr_tx.send(listener.local_addr().unwrap()).unwrap();
                gleaner_server::serve_farms(listener, &config, opened, async {
                    stopped.await.ok();
                })
                .await
                .unwrap();
            });
        });
        let addr = addr_rx.recv().expect("the replica reports its address");
        Self {
            addr,
            stop: Some(stop),
            thread: Some(thread),
        }
    }
}

impl Drop for Replica {
    fn drop(&mut self) {
        if let Some(s) = self.stop.take() {
            s.send(()).ok();
        }
        if let Some(t) = self.thread.take() {
            let panicked = t.join().is_err();
            if panicked && !std::thread::panicking() {
                panic!("the replica's thread panicked");
            }
        }
    }
}

/// One request on a fresh connection (never re-sent: a write is made at most once).
fn get(addr: SocketAddr, path: &str, token: Option<&str>) -> Response {
    let auth = token.map(|t| format!("Bearer {t}"));
    let headers: Vec<(&str, &str)> = auth
        .as_deref()
        .map(|a| vec![("Authorization", a)])
        .unwrap_or_default();
    Client::new(addr)
        .request("GET", path, &headers, None)
        .unwrap()
}

fn post(addr: SocketAddr, path: &str, body: &Value, token: Option<&str>) -> Response {
    Client::with_read_timeout(addr, PATIENCE)
        .post_json(path, body, token)
        .unwrap()
}

/// How long a write may wait for its answer: writes on one farm are serialised, so with a
/// thousand in flight the last waits for all the others (a bound on a stuck server, not a
/// timing assertion).
const PATIENCE: std::time::Duration = std::time::Duration::from_secs(3600);

fn ok_json(r: &Response, what: &str) -> Value {
    assert_eq!(r.status, 200, "{what}: {}", r.text());
    r.json().unwrap()
}

#[test]
fn a_farm_token_opens_its_own_farm_only_and_read_scope_cannot_write() {
    let farms = Farms::new("access");
    let server = Replica::start(farms.path());
    let a = server.addr;
    let (nw, nr, sw) = (
        farms.north_write.as_str(),
        farms.north_read.as_str(),
        farms.south_write.as_str(),
    );

    // Each token reads its own farm.
    let north = ok_json(&get(a, "/api/v1/farms/north/project", Some(nw)), "north");
    assert_eq!(north["name"], "north");
    assert_eq!(north["sensors"], 42);
    let south = ok_json(&get(a, "/api/v1/farms/south/project", Some(sw)), "south");
    assert_eq!(south["name"], "caf");
    ok_json(&get(a, "/api/v1/farms/north/cells", Some(nr)), "read scope");
    let listed = ok_json(&get(a, "/api/v1/farms", Some(nr)), "farms");
    assert_eq!(listed, json!([{"farm": "north", "scope": "read"}]));

    // Another farm's token gets exactly what a farm that does not exist gets.
    let other = get(a, "/api/v1/farms/south/project", Some(nw));
    let missing = get(a, "/api/v1/farms/nowhere/project", Some(nw));
    assert_eq!(other.status, 404, "{}", other.text());
    assert_eq!((missing.status, missing.text()), (404, other.text()));
    for (path, body) in [
        ("/api/v1/farms/south/plan", json!({"solver": "greedy"})),
        ("/api/v1/farms/south/score", json!({"dry_run": true})),
    ] {
        let r = post(a, path, &body, Some(nw));
        assert_eq!((r.status, r.text()), (404, other.text()), "{path}");
    }
    let upload = Client::new(a)
        .post_multipart(
            "/api/v1/farms/south/ingest",
            &[Part::File("files".into(), "x.csv".into(), b"x".to_vec())],
            Some(nw),
        )
        .unwrap();
    assert_eq!((upload.status, upload.text()), (404, other.text()));

    // Without a token, or with one that is no farm's: 401 whether the farm exists or not.
    for path in [
        "/api/v1/farms/north/project",
        "/api/v1/farms/nowhere/project",
    ] {
        assert_eq!(get(a, path, None).status, 401, "{path}");
        assert_eq!(
            get(a, path, Some("0123456789abcdef0123456789abcdef")).status,
            401
        );
    }
    let basic = Client::new(a)
        .request(
            "GET",
            "/api/v1/farms/north/project",
            &[("Authorization", "Basic abc")],
            None,
        )
        .unwrap();
    assert_eq!(basic.status, 401);
    assert_eq!(get(a, "/api/v1/farms", None).status, 401);

    // Read scope: reads and previews, never a write (403, nothing stored).
    let preview = post(
        a,
        "/api/v1/farms/north/plan",
        &json!({"solver": "greedy", "at": "2014-01-05", "dry_run": true}),
        Some(nr),
    );
    let preview = ok_json(&preview, "a read token's preview");
    assert!(preview["mission_id"].is_null());
    for (path, body) in [
        (
            "/api/v1/farms/north/plan",
            json!({"solver": "greedy", "at": "2014-01-05"}),
        ),
        ("/api/v1/farms/north/plan", json!({})),
        ("/api/v1/farms/north/score", json!({"at": "2014-01-05"})),
        ("/api/v1/farms/north/explore", json!({"at": "2014-01-05"})),
    ] {
        let r = post(a, path, &body, Some(nr));
        assert_eq!(r.status, 403, "{path} {body}: {}", r.text());
    }
    let r = Client::new(a)
        .post_multipart(
            "/api/v1/farms/north/ingest",
            &[Part::File("files".into(), "x.csv".into(), b"x".to_vec())],
            Some(nr),
        )
        .unwrap();
    assert_eq!(r.status, 403, "{}", r.text());
    let missions = ok_json(
        &get(a, "/api/v1/farms/north/missions", Some(nr)),
        "missions",
    );
    assert_eq!(missions.as_array().unwrap().len(), 0, "nothing was stored");

    // The write token writes; the mission is the farm's own.
    let planned = post(
        a,
        "/api/v1/farms/north/plan",
        &json!({"solver": "greedy", "at": "2014-01-05"}),
        Some(nw),
    );
    let planned = ok_json(&planned, "a write token's plan");
    let id = planned["mission_id"].as_i64().unwrap();
    let one = ok_json(
        &get(a, &format!("/api/v1/farms/north/missions/{id}"), Some(nr)),
        "the mission",
    );
    assert_eq!(one["mission_id"], id);
    let south_missions = ok_json(&get(a, "/api/v1/farms/south/missions", Some(sw)), "south");
    assert_eq!(south_missions.as_array().unwrap().len(), 0);
    let file = get(
        a,
        &format!("/api/v1/farms/north/missions/{id}/files/mission.plan"),
        Some(nr),
    );
    assert_eq!(file.status, 200);

    // The single-project routes are not a farms server's.
    assert_eq!(get(a, "/api/v1/project", Some(nw)).status, 404);
}

#[test]
fn the_farms_openapi_document_lists_every_farm_route() {
    let single = gleaner_server::openapi();
    let doc: Value =
        serde_json::from_str(&gleaner_server::farms_openapi().to_json().unwrap()).unwrap();
    assert!(doc["openapi"].as_str().unwrap().starts_with("3.1"));
    let paths = doc["paths"].as_object().unwrap();
    for (path, item) in &single.paths.paths {
        let farm_path = format!(
            "/api/v1/farms/{{farm}}{}",
            path.strip_prefix("/api/v1").unwrap()
        );
        let farm_item = &paths[&farm_path];
        assert!(farm_item.is_object(), "{farm_path} is missing");
        let params = farm_item["parameters"].as_array().unwrap();
        assert!(
            params
                .iter()
                .any(|p| p["name"] == "farm" && p["in"] == "path" && p["required"] == true),
            "{farm_path}"
        );
        let methods: BTreeSet<&String> = farm_item
            .as_object()
            .unwrap()
            .keys()
            .filter(|k| *k != "parameters")
            .collect();
        assert_eq!(
            methods.len(),
            [&item.get, &item.post, &item.delete]
                .iter()
                .filter(|o| o.is_some())
                .count(),
            "{farm_path}"
        );
        for m in methods {
            let op = &farm_item[m];
            assert_eq!(op["security"], json!([{"bearer": []}]), "{m} {farm_path}");
            for code in ["401", "403", "404"] {
                assert!(op["responses"][code].is_object(), "{m} {farm_path} {code}");
            }
        }
    }
    assert!(paths["/api/v1/farms"]["get"].is_object());
    assert!(paths["/api/v1/openapi.json"]["get"].is_object());
    assert_eq!(paths.len(), single.paths.paths.len() + 2);
    assert!(doc["components"]["schemas"]["FarmDoc"].is_object());
    // Operation ids stay unique.
    let ids: Vec<&str> = paths
        .values()
        .flat_map(|i| i.as_object().unwrap().values())
        .filter_map(|op| op["operationId"].as_str())
        .collect();
    let unique: BTreeSet<&str> = ids.iter().copied().collect();
    assert_eq!(ids.len(), unique.len());
    // The server serves it.
    let farms = Farms::new("openapi");
    let server = Replica::start(farms.path());
    let served = ok_json(&get(server.addr, "/api/v1/openapi.json", None), "openapi");
    assert_eq!(served, doc);
}

/// Waits (a bounded number of polls of pg_locks, no sleeps) until someone waits for the
/// farm's lock.
fn until_waiting(project: &app::Project<app::AnyStore>) {
    let app::AnyStore::Postgres(store) = project.store() else {
        panic!("north is a PostgreSQL farm");
    };
    let mut polls = 0;
    while store.lock_waiters().unwrap() == 0 {
        polls += 1;
        assert!(
            polls < 1_000_000,
            "no writer ever waited for the farm's lock"
        );
    }
}

fn stops(mission: &Value) -> Vec<String> {
    mission["stops"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["cell"].as_str().unwrap().to_string())
        .collect()
}

/// The farm's exclusion held by another process (the test's own connection, as another
/// replica or a CLI command would hold it) holds up a plan through one replica and a record
/// through the other from their first read: each is seen waiting for the farm's advisory
/// lock and stores nothing meanwhile; the plan is computed from what the holder wrote while
/// it waited (a flight recorded over the cells it would otherwise have chosen), exactly as a
/// dry run planned afterwards.
#[test]
fn plans_and_records_wait_for_the_farms_lock_held_elsewhere() {
    use app::{Store as _, StoreRead as _};
    let farms = Farms::new("held");
    let replicas = [Replica::start(farms.path()), Replica::start(farms.path())];
    let token = farms.north_write.clone();
    let plan_body = |at: &str, dry_run: bool| json!({"solver": "greedy", "seed": 3, "at": at, "dry_run": dry_run});
    let first = ok_json(
        &post(
            replicas[0].addr,
            "/api/v1/farms/north/plan",
            &plan_body("2014-02-01", false),
            Some(&token),
        ),
        "the first plan",
    );
    let first_id = first["mission_id"].as_i64().unwrap();
    let before = ok_json(
        &post(
            replicas[0].addr,
            "/api/v1/farms/north/plan",
            &plan_body("2014-02-02", true),
            Some(&token),
        ),
        "a preview",
    );
    assert_eq!(stops(&before), stops(&first), "the same cells a day later");

    let mut holder = app::Project::open(&farms.path().join("north")).unwrap();
    holder.store().lock_project().unwrap();
    let (addr, t, body) = (
        replicas[0].addr,
        token.clone(),
        plan_body("2014-02-02", false),
    );
    let plan = std::thread::spawn(move || post(addr, "/api/v1/farms/north/plan", &body, Some(&t)));
    until_waiting(&holder);
    assert_eq!(
        holder.store().missions().unwrap().len(),
        1,
        "the plan waits"
    );
    // Meanwhile the holder records the first mission's flight over its cells.
    app::record_flight(
        &mut holder,
        &app::RecordRequest {
            mission: app::MissionId(first_id),
            at: Some(1_391_256_000), // 2014-02-01T12:00Z
            cells: Some(stops(&first)),
            readings: None,
            amend: false,
        },
        0,
        &Silent,
    )
    .unwrap();
    holder.store().unlock_project();
    let planned = ok_json(&plan.join().unwrap(), "the plan after the lock");
    let after = ok_json(
        &post(
            replicas[1].addr,
            "/api/v1/farms/north/plan",
            &plan_body("2014-02-02", true),
            Some(&token),
        ),
        "a preview after",
    );
    assert_eq!(
        stops(&planned),
        stops(&after),
        "planned from the store as it is now"
    );
    assert_ne!(
        stops(&planned),
        stops(&first),
        "not from the store before the flight"
    );

    holder.store().lock_project().unwrap();
    let id = planned["mission_id"].as_i64().unwrap();
    let (addr, t, cells) = (replicas[1].addr, token.clone(), stops(&planned).join(","));
    let record = std::thread::spawn(move || {
        Client::new(addr)
            .post_multipart(
                &format!("/api/v1/farms/north/missions/{id}/record"),
                &[
                    Part::Text("at".into(), "2014-02-02".into()),
                    Part::Text("cells".into(), cells),
                ],
                Some(&t),
            )
            .unwrap()
    });
    until_waiting(&holder);
    let m = holder.store().mission(app::MissionId(id)).unwrap().unwrap();
    assert_eq!(m.status, app::MissionStatus::Planned, "the record waits");
    holder.store().unlock_project();
    ok_json(&record.join().unwrap(), "the record after the lock");
    let m = holder.store().mission(app::MissionId(id)).unwrap().unwrap();
    assert_eq!(m.status, app::MissionStatus::Flown);
    drop(holder);
}

/// The sensors of every cell of a farm, by cell id.
fn sensors_by_cell(addr: SocketAddr, token: &str) -> BTreeMap<String, Vec<String>> {
    let cells = ok_json(
        &get(addr, "/api/v1/farms/north/cells", Some(token)),
        "cells",
    );
    cells
        .as_array()
        .unwrap()
        .iter()
        .map(|c| {
            let sensors = c["sensors"]
                .as_array()
                .unwrap()
                .iter()
                .map(|s| s.as_str().unwrap().to_string())
                .collect();
            (c["cell"].as_str().unwrap().to_string(), sensors)
        })
        .collect()
}

/// What one plan-then-record pair did.
#[derive(Debug)]
struct Pair {
    mission: i64,
    inserted: u64,
    unchanged: u64,
    /// Seconds from the request to its answer: the plan's, the record's.
    latency: [f64; 2],
}

/// Two replicas over one PostgreSQL farm, `GLEANER_REPLICA_WRITES` writes (default 40) made
/// at once: half plans, each recorded through the other replica with the readings its
/// cells' sensors logged in January 2014. Every write succeeds, every plan gets its own
/// mission id, every mission is stored and recorded once, and the farm holds exactly the
/// readings the records report as new.
#[test]
fn replicas_over_one_postgres_serialise_plans_and_records() {
    let writes: usize = std::env::var("GLEANER_REPLICA_WRITES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(40);
    let pairs = (writes / 2).max(1);
    let farms = Farms::new("replicas");
    let replicas = [Replica::start(farms.path()), Replica::start(farms.path())];
    let addrs = [replicas[0].addr, replicas[1].addr];
    let token = farms.north_write.clone();
    let before = ok_json(
        &get(addrs[0], "/api/v1/farms/north/project", Some(&token)),
        "project",
    );
    let readings_before = before["readings"].as_u64().unwrap();
    let cells = Arc::new(sensors_by_cell(addrs[0], &token));
    let flights: Arc<BTreeMap<String, Vec<u8>>> = Arc::new(
        cells
            .iter()
            .map(|(c, s)| (c.clone(), flight_csv(s.iter().map(String::as_str))))
            .collect(),
    );

    let barrier = Arc::new(Barrier::new(pairs + 1));
    let started = std::time::Instant::now();
    let threads: Vec<_> = (0..pairs)
        .map(|i| {
            let (barrier, token, flights) =
                (Arc::clone(&barrier), token.clone(), Arc::clone(&flights));
            let (plan_on, record_on) = (addrs[i % 2], addrs[(i + 1) % 2]);
            std::thread::spawn(move || {
                // Each plan at its own hour of February 2014, after every stored reading.
                let at = 1_391_212_800 + 3600 * i as i64;
                let at_text = format!("@{at}");
                barrier.wait();
                let t0 = std::time::Instant::now();
                let r = post(
                    plan_on,
                    "/api/v1/farms/north/plan",
                    &json!({"solver": "greedy", "at": unix_rfc3339(at), "seed": i}),
                    Some(&token),
                );
                assert_eq!(r.status, 200, "plan {i}: {}", r.text());
                let planned = r.json().unwrap();
                let plan_s = t0.elapsed().as_secs_f64();
                let mission = planned["mission_id"].as_i64().unwrap();
                let stops: Vec<String> = planned["stops"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|s| s["cell"].as_str().unwrap().to_string())
                    .collect();
                let mut csv = b"sensor_id,timestamp,modality,value,unit\n".to_vec();
                for s in &stops {
                    csv.extend(flights[s].split(|b| *b == b'\n').skip(1).flat_map(|l| {
                        let mut l = l.to_vec();
                        if !l.is_empty() {
                            l.push(b'\n');
                        }
                        l
                    }));
                }
                let parts = vec![
                    Part::Text("at".into(), unix_rfc3339(at)),
                    Part::Text("cells".into(), stops.join(",")),
                    Part::File("files".into(), format!("flight-{i}.csv"), csv),
                ];
                let t1 = std::time::Instant::now();
                let r = Client::with_read_timeout(record_on, PATIENCE)
                    .post_multipart(
                        &format!("/api/v1/farms/north/missions/{mission}/record"),
                        &parts,
                        Some(&token),
                    )
                    .unwrap();
                assert_eq!(r.status, 200, "record {i} ({at_text}): {}", r.text());
                let recorded = r.json().unwrap();
                Pair {
                    latency: [plan_s, t1.elapsed().as_secs_f64()],
                    mission,
                    inserted: recorded["readings_inserted"].as_u64().unwrap(),
                    unchanged: recorded["readings_unchanged"].as_u64().unwrap(),
                }
            })
        })
        .collect();
    barrier.wait();
    let done: Vec<Pair> = threads.into_iter().map(|t| t.join().unwrap()).collect();
    let elapsed = started.elapsed();

    let ids: BTreeSet<i64> = done.iter().map(|p| p.mission).collect();
    assert_eq!(ids.len(), pairs, "every plan has its own mission id");
    let stored = ok_json(
        &get(addrs[1], "/api/v1/farms/north/missions", Some(&token)),
        "missions",
    );
    let stored = stored.as_array().unwrap();
    let stored_ids: BTreeSet<i64> = stored
        .iter()
        .map(|m| m["mission_id"].as_i64().unwrap())
        .collect();
    assert_eq!(stored_ids, ids, "every mission stored, none twice");
    for m in stored {
        assert_eq!(m["status"], "flown", "mission {}", m["mission_id"]);
    }
    // Cached reads of a replica may be one refresh late: the store itself is the judge.
    let project = app::Project::open(&farms.path().join("north")).unwrap();
    use app::StoreRead as _;
    let readings_after = project.store().reading_count().unwrap();
    let inserted: u64 = done.iter().map(|p| p.inserted).sum();
    assert_eq!(
        readings_after,
        readings_before + inserted,
        "the farm holds exactly the readings the records stored"
    );
    let unchanged: u64 = done.iter().map(|p| p.unchanged).sum();
    assert_eq!(project.store().missions().unwrap().len(), pairs);
    let quantiles = |k: usize| {
        let mut l: Vec<f64> = done.iter().map(|p| p.latency[k]).collect();
        l.sort_by(f64::total_cmp);
        let q = |f: f64| l[((l.len() - 1) as f64 * f).round() as usize];
        format!(
            "p50 {:.2} s, p99 {:.2} s, max {:.2} s",
            q(0.5),
            q(0.99),
            q(1.0)
        )
    };
    eprintln!("replicas: plans {}; records {}", quantiles(0), quantiles(1));
    eprintln!(
        "replicas: {} writes ({pairs} plans + {pairs} records) over 2 replicas in {:.1} s: {:.1} writes/s; {} distinct mission ids, 0 lost, 0 duplicated; {inserted} readings stored, {unchanged} already there",
        2 * pairs,
        elapsed.as_secs_f64(),
        (2 * pairs) as f64 / elapsed.as_secs_f64(),
        ids.len(),
    );
}

/// RFC 3339 text of a time, s.
fn unix_rfc3339(t: i64) -> String {
    app::format_rfc3339(t)
}
