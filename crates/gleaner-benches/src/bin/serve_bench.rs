//! `serve-bench`: the HTTP server's read throughput and latency, reads while a mission is
//! being planned, and the dashboard's page weight and first paint in headless Chromium.
//!
//! ```text
//! cargo run --release -p gleaner-benches --bin serve-bench -- --project caf
//!     [--requests 20000] [--clients 64] [--workers 2] [--no-browser] [--caf-data DIR]
//! ```
//!
//! The server runs in this process on an ephemeral loopback port with `--workers` runtime
//! threads; `--clients` threads each keep one connection alive and send their share of
//! `--requests` GETs back to back. Every run is bounded by its request count. The project
//! must exist (`gleaner init` + `gleaner ingest`), or, with `--caf-data DIR` (the shared data
//! folder), is made there first: the 42 CAF stations, every daily file ingested, scored at the
//! newest reading. The benchmark plans missions (greedy, stored), so run it on a copy you do
//! not mind gaining missions.

use std::path::PathBuf;
use std::sync::{Arc, Barrier};
use std::time::{Duration, Instant};

use gleaner_server::client::Client;
use gleaner_server::{ServerConfig, Token};

struct Args {
    project: PathBuf,
    requests: usize,
    clients: usize,
    workers: usize,
    browser: bool,
    caf_data: Option<PathBuf>,
}

fn parse_args() -> Result<Args, String> {
    let mut a = Args {
        project: PathBuf::new(),
        requests: 20_000,
        clients: 64,
        workers: 2,
        browser: true,
        caf_data: None,
    };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        let mut value = |name: &str| it.next().ok_or(format!("{name} needs a value"));
        match flag.as_str() {
            "--project" => a.project = PathBuf::from(value("--project")?),
            "--requests" => {
                a.requests = value("--requests")?
                    .parse()
                    .map_err(|e| format!("--requests: {e}"))?
            }
            "--clients" => {
                a.clients = value("--clients")?
                    .parse()
                    .map_err(|e| format!("--clients: {e}"))?
            }
            "--workers" => {
                a.workers = value("--workers")?
                    .parse()
                    .map_err(|e| format!("--workers: {e}"))?
            }
            "--no-browser" => a.browser = false,
            "--caf-data" => a.caf_data = Some(PathBuf::from(value("--caf-data")?)),
            "-h" | "--help" => {
                return Err("usage: serve-bench --project DIR [--requests N] [--clients N] [--workers N] [--no-browser]".into());
            }
            other => return Err(format!("unknown argument {other:?} (see --help)")),
        }
    }
    if a.project.as_os_str().is_empty() {
        return Err("--project DIR is required (a gleaner project with readings)".into());
    }
    if a.clients == 0 || a.requests < a.clients || a.workers == 0 {
        return Err("need --clients >= 1, --requests >= --clients, --workers >= 1".into());
    }
    Ok(a)
}

/// Latency statistics of one run.
struct Stats {
    requests: usize,
    wall: Duration,
    p50: Duration,
    p99: Duration,
    max: Duration,
    errors: usize,
}

impl Stats {
    fn line(&self, what: &str) -> String {
        format!(
            "| {what} | {} | {:.0} | {:.2} | {:.2} | {:.2} | {} |",
            self.requests,
            self.requests as f64 / self.wall.as_secs_f64(),
            ms(self.p50),
            ms(self.p99),
            ms(self.max),
            self.errors
        )
    }
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1000.0
}

/// `requests` GETs of `path` from `clients` keep-alive connections released together.
fn load(addr: std::net::SocketAddr, path: &str, requests: usize, clients: usize) -> Stats {
    let barrier = Arc::new(Barrier::new(clients + 1));
    let per = requests / clients;
    let handles: Vec<_> = (0..clients)
        .map(|_| {
            let b = Arc::clone(&barrier);
            let path = path.to_string();
            std::thread::spawn(move || {
                let mut c = Client::new(addr);
                // Connect before the clock starts.
                let warm = c.get(&path).map(|r| r.status == 200).unwrap_or(false);
                b.wait();
                let mut lat = Vec::with_capacity(per);
                let mut errors = usize::from(!warm);
                for _ in 0..per {
                    let t = Instant::now();
                    match c.get(&path) {
                        Ok(r) if r.status == 200 => {}
                        _ => errors += 1,
                    }
                    lat.push(t.elapsed());
                }
                (lat, errors)
            })
        })
        .collect();
    barrier.wait();
    let start = Instant::now();
    let mut all = Vec::with_capacity(requests);
    let mut errors = 0;
    for h in handles {
        let (lat, e) = h.join().expect("a client thread");
        all.extend(lat);
        errors += e;
    }
    let wall = start.elapsed();
    all.sort();
    let q = |p: f64| all[((all.len() as f64 * p).ceil() as usize).clamp(1, all.len()) - 1];
    Stats {
        requests: all.len(),
        wall,
        p50: q(0.50),
        p99: q(0.99),
        max: *all.last().unwrap(),
        errors,
    }
}

fn main() {
    let args = match parse_args() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("serve-bench: {e}");
            std::process::exit(2);
        }
    };
    if let Err(e) = run(&args) {
        eprintln!("serve-bench: {e}");
        std::process::exit(1);
    }
}

/// The CAF project the figures are measured on, made in `dir` from the shared data folder.
fn make_caf(
    dir: &std::path::Path,
    data: &std::path::Path,
) -> Result<(), Box<dyn std::error::Error>> {
    use gleaner_app as app;
    let caf = data.join("caf");
    let mut files: Vec<PathBuf> = std::fs::read_dir(caf.join("Daily"))?
        .map(|e| e.map(|e| e.path()))
        .collect::<Result<_, _>>()?;
    files.sort();
    eprintln!(
        "making the CAF project in {} ({} daily files)…",
        dir.display(),
        files.len()
    );
    let (mut project, _) = app::init(&app::InitRequest {
        dir: dir.to_path_buf(),
        sensors: caf.join("sensors/CAF_sensor_locations.csv"),
        utm_zone: Some("11N".into()),
        name: Some("caf".into()),
        ..Default::default()
    })?;
    app::ingest(
        &mut project,
        &app::IngestRequest {
            files,
            ..Default::default()
        },
        0,
        &app::Silent,
    )?;
    app::score(
        &mut project,
        &app::ScoreRequest {
            at: None,
            history: app::History {
                from: i64::MIN,
                until: i64::MAX,
            },
            probabilities: None,
            dry_run: false,
        },
    )?;
    Ok(())
}

fn run(args: &Args) -> Result<(), Box<dyn std::error::Error>> {
    if let Some(data) = &args.caf_data
        && !args.project.join("gleaner.toml").exists()
    {
        make_caf(&args.project, data)?;
    }
    let token = Token::random()?;
    let mut config = ServerConfig::new(args.project.clone());
    config.addr = "127.0.0.1:0".parse()?;
    config.token = Some(token.clone());
    let (addr, stop, server) = start_server(config, args.workers)?;
    let mut c = Client::new(addr);

    // A mission to read.
    let id = mission_to_read(&mut c, &token)?;
    let cells = c
        .get("/api/v1/cells")?
        .json()?
        .as_array()
        .map_or(0, Vec::len);
    println!(
        "serve-bench: {} ({cells} cells), {} requests per run, {} clients, {} server worker threads, {} cores",
        args.project.display(),
        args.requests,
        args.clients,
        args.workers,
        std::thread::available_parallelism().map_or(0, |n| n.get())
    );
    println!();
    println!("| run | requests | req/s | p50 ms | p99 ms | max ms | errors |");
    println!("|---|---|---|---|---|---|---|");
    let mission_path = format!("/api/v1/missions/{id}");
    let reads = [
        ("GET /api/v1/project", "/api/v1/project"),
        ("GET /api/v1/cells", "/api/v1/cells"),
        ("GET /api/v1/missions/{id}", mission_path.as_str()),
    ];
    for (what, path) in reads {
        eprintln!("{what}…");
        println!(
            "{}",
            load(addr, path, args.requests, args.clients).line(what)
        );
    }

    // The same reads while missions are planned and saved back to back (greedy: each save
    // is a write that invalidates the cached answers, which are then computed again once).
    for (what, path) in reads {
        reads_while_saving(addr, &token, (what, path), args)?;
    }

    // Reads while a mission is planned (default solver, dry run so nothing is stored).
    eprintln!("GET /api/v1/cells while planning…");
    let planner = std::thread::spawn(move || {
        let t = Instant::now();
        let r = Client::new(addr).post_json(
            "/api/v1/plan",
            &serde_json::json!({"dry_run": true, "solver": "default", "time_limit_s": 60, "iterations": 1_000_000}),
            None,
        );
        (r.map(|r| r.status).unwrap_or(0), t.elapsed())
    });
    let during = load(addr, "/api/v1/cells", args.requests, args.clients);
    let plan_running = !planner.is_finished();
    let (plan_status, plan_time) = planner.join().map_err(|_| "planner thread")?;
    println!(
        "{} plan {} in {:.1} s, {} when the reads ended",
        during.line("GET /api/v1/cells during a plan"),
        plan_status,
        plan_time.as_secs_f64(),
        if plan_running {
            "still running"
        } else {
            "finished"
        }
    );

    // Page weight: everything the dashboard loads to show the field and the latest mission.
    println!();
    page_weight(&mut c)?;
    if args.browser {
        let (fcp, ready) = first_paint(addr)?;
        println!(
            "headless Chromium, median of 5 loads: first contentful paint {fcp:.0} ms, map drawn (cells interactive) {ready:.0} ms after navigation start"
        );
    }
    stop.send(()).ok();
    server.join().map_err(|_| "server thread")??;
    Ok(())
}

/// A running server: its address, the sender that stops it, its thread.
type Server = (
    std::net::SocketAddr,
    tokio::sync::oneshot::Sender<()>,
    std::thread::JoinHandle<Result<(), String>>,
);

/// The server on its own thread and runtime (`workers` threads) at a free loopback port:
/// its address, the sender that stops it, its thread.
fn start_server(
    config: ServerConfig,
    workers: usize,
) -> Result<Server, Box<dyn std::error::Error>> {
    let (addr_tx, addr_rx) = std::sync::mpsc::channel();
    let (stop, stopped) = tokio::sync::oneshot::channel::<()>();
    let server = std::thread::spawn(move || -> Result<(), String> {
        let rt = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(workers)
            .enable_all()
            .build()
            .map_err(|e| e.to_string())?;
        rt.block_on(async move {
            let listener = tokio::net::TcpListener::bind(config.addr)
                .await
                .map_err(|e| e.to_string())?;
            addr_tx
                .send(listener.local_addr().map_err(|e| e.to_string())?)
                .ok();
            gleaner_server::serve(listener, &config, async {
                stopped.await.ok();
            })
            .await
            .map_err(|e| e.to_string())
        })
    });
    let addr = addr_rx
        .recv()
        .map_err(|_| "the server did not start (is --project a gleaner project?)")?;
    Ok((addr, stop, server))
}

/// The project's newest mission, or one planned now (greedy, stored) when it has none.
fn mission_to_read(c: &mut Client, token: &Token) -> Result<i64, Box<dyn std::error::Error>> {
    let missions = c.get("/api/v1/missions")?.json()?;
    Ok(match missions.as_array().and_then(|m| m.last()) {
        Some(m) => m["mission_id"].as_i64().ok_or("bad mission list")?,
        None => {
            eprintln!("planning a mission to read (greedy, stored)…");
            let r = c.post_json(
                "/api/v1/plan",
                &serde_json::json!({"solver": "greedy"}),
                Some(token.reveal()),
            )?;
            if r.status != 200 {
                return Err(format!("planning failed: {}", r.text()).into());
            }
            r.json()?["mission_id"].as_i64().ok_or("no mission id")?
        }
    })
}

/// `path` read by `args.clients` clients while missions are planned and saved back to back;
/// prints the line.
fn reads_while_saving(
    addr: std::net::SocketAddr,
    token: &Token,
    (what, path): (&str, &str),
    args: &Args,
) -> Result<(), Box<dyn std::error::Error>> {
    eprintln!("{what} while plans are saved…");
    let stop = Arc::new(std::sync::atomic::AtomicBool::new(false));
    let saver = {
        let stop = Arc::clone(&stop);
        let token = token.clone();
        std::thread::spawn(move || {
            let mut c = Client::new(addr);
            let mut saved = 0usize;
            while !stop.load(std::sync::atomic::Ordering::Relaxed) {
                match c.post_json(
                    "/api/v1/plan",
                    &serde_json::json!({"solver": "greedy"}),
                    Some(token.reveal()),
                ) {
                    Ok(r) if r.status == 200 => saved += 1,
                    _ => break,
                }
            }
            saved
        })
    };
    let during = load(addr, path, args.requests, args.clients);
    stop.store(true, std::sync::atomic::Ordering::Relaxed);
    let saved = saver.join().map_err(|_| "saver thread")?;
    println!(
        "{} {saved} plans saved meanwhile",
        during.line(&format!("{what} while plans are saved"))
    );
    Ok(())
}

/// Prints the dashboard's page weight: everything it loads to show the field and the latest
/// mission.
fn page_weight(c: &mut Client) -> Result<(), Box<dyn std::error::Error>> {
    let mut total = 0;
    let mut parts = Vec::new();
    for path in [
        "/",
        "/app.js",
        "/app.css",
        "/api/v1/project",
        "/api/v1/field",
        "/api/v1/missions/page?limit=8",
        "/api/v1/map.svg",
    ] {
        let n = c.get(path)?.body.len();
        total += n;
        parts.push(format!("{path} {:.1} kB", n as f64 / 1000.0));
    }
    println!(
        "page weight: {:.1} kB ({})",
        total as f64 / 1000.0,
        parts.join(", ")
    );
    Ok(())
}

/// Median first contentful paint and map-ready times (ms from navigation start) of five
/// dashboard loads in headless Chromium (chromedriver on PATH).
fn first_paint(addr: std::net::SocketAddr) -> Result<(f64, f64), Box<dyn std::error::Error>> {
    use std::io::BufRead as _;
    let port = std::net::TcpListener::bind("127.0.0.1:0")?
        .local_addr()?
        .port();
    let mut driver = std::process::Command::new("chromedriver")
        .arg(format!("--port={port}"))
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::null())
        .spawn()
        .map_err(|e| {
            format!("chromedriver: {e} (run scripts/browser-env.sh, or pass --no-browser)")
        })?;
    let out = driver.stdout.take().ok_or("chromedriver output")?;
    let mut lines = std::io::BufReader::new(out).lines();
    if !lines
        .by_ref()
        .take(50)
        .any(|l| l.unwrap_or_default().contains("started successfully"))
    {
        return Err("chromedriver did not start".into());
    }
    std::thread::spawn(move || for _ in lines {});
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()?;
    let result = rt.block_on(async {
        let mut caps = serde_json::Map::new();
        caps.insert(
            "goog:chromeOptions".into(),
            serde_json::json!({"args": ["--headless=new", "--no-sandbox", "--disable-gpu",
                "--disable-dev-shm-usage", "--window-size=1400,1100"]}),
        );
        let c = fantoccini::ClientBuilder::new(hyper_util::client::legacy::connect::HttpConnector::new())
            .capabilities(caps)
            .connect(&format!("http://127.0.0.1:{port}"))
            .await?;
        let mut fcp = Vec::new();
        let mut ready = Vec::new();
        for _ in 0..5 {
            c.goto(&format!("http://{addr}/")).await?;
            c.wait()
                .at_most(Duration::from_secs(60))
                .for_element(fantoccini::Locator::Css("#map path.cell"))
                .await?;
            let v = c
                .execute(
                    "const p = performance.getEntriesByName('first-contentful-paint')[0]; const m = performance.getEntriesByName('map-ready')[0]; return [p ? p.startTime : -1, m ? m.startTime : -1];",
                    vec![],
                )
                .await?;
            fcp.push(v[0].as_f64().unwrap_or(-1.0));
            ready.push(v[1].as_f64().unwrap_or(-1.0));
        }
        c.close().await.ok();
        let median = |mut v: Vec<f64>| {
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        };
        Ok::<_, Box<dyn std::error::Error>>((median(fcp), median(ready)))
    });
    driver.kill().ok();
    driver.wait().ok();
    result
}
