//! Fixtures: a CAF project (the real network, 2013's daily records) built once per test run
//! and copied for each test, and a server on an ephemeral loopback port.

use std::io::Write as _;
use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use gleaner_app::{self as app, Silent};
use gleaner_server::client::Client;
use gleaner_server::{ServerConfig, Token};

/// The write token of the test servers.
pub const TOKEN: &str = "test-token-0123456789abcdef";

/// The shared data directory (`GLEANER_DATA_DIR`, default `../shared/data`).
pub fn shared_data() -> PathBuf {
    std::env::var_os("GLEANER_DATA_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data"))
}

/// CAF's `MM/DD/YYYY` as (year, month, day).
fn ymd(date: &str) -> Option<(i32, u32, u32)> {
    let mut p = date.split('/');
    let m = p.next()?.parse().ok()?;
    let d = p.next()?.parse().ok()?;
    let y = p.next()?.parse().ok()?;
    Some((y, m, d))
}

/// Copies of the CAF daily files holding only the rows of `year`, in `out`.
fn caf_year(daily: &Path, out: &Path, year: i32) -> Vec<PathBuf> {
    let mut names: Vec<_> = std::fs::read_dir(daily)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    names.sort();
    std::fs::create_dir_all(out).unwrap();
    names
        .into_iter()
        .map(|path| {
            let text = std::fs::read_to_string(&path).unwrap();
            let mut lines = text.lines();
            let mut kept = vec![lines.next().unwrap().to_string()];
            kept.extend(
                lines
                    .filter(|l| {
                        l.split('\t')
                            .nth(1)
                            .and_then(ymd)
                            .is_some_and(|(y, _, _)| y == year)
                    })
                    .map(str::to_string),
            );
            let target = out.join(path.file_name().unwrap());
            std::fs::write(&target, kept.join("\n") + "\n").unwrap();
            target
        })
        .collect()
}

/// The sensors' real VW_30cm readings of January 2014 as a long CSV (what a flight over
/// their cells brought back).
pub fn flight_csv<'a>(sensors: impl IntoIterator<Item = &'a str>) -> Vec<u8> {
    let daily = shared_data().join("caf/Daily");
    let mut out = b"sensor_id,timestamp,modality,value,unit\n".to_vec();
    for sensor in sensors {
        let text = std::fs::read_to_string(daily.join(format!("{sensor}.txt"))).unwrap();
        for line in text.lines().skip(1) {
            let cols: Vec<&str> = line.split('\t').collect();
            let Some((y, m, d)) = ymd(cols[1]) else {
                continue;
            };
            if y == 2014 && m == 1 && cols[2] != "NA" {
                writeln!(
                    out,
                    "{sensor},{y:04}-{m:02}-{d:02},vw@30cm,{},m3/m3",
                    cols[2]
                )
                .unwrap();
            }
        }
    }
    out
}

/// The template project: CAF's 42 stations, 2013 ingested. Built once per test binary.
fn template() -> &'static Path {
    static T: OnceLock<tempfile::TempDir> = OnceLock::new();
    T.get_or_init(|| {
        let data = shared_data();
        let tmp = tempfile::tempdir().unwrap();
        let files = caf_year(&data.join("caf/Daily"), &tmp.path().join("input"), 2013);
        assert_eq!(files.len(), 42, "42 CAF stations in {}", data.display());
        let (mut project, _) = app::init(&app::InitRequest {
            dir: tmp.path().join("caf"),
            sensors: data.join("caf/sensors/CAF_sensor_locations.csv"),
            utm_zone: Some("11N".into()),
            name: Some("caf".into()),
            ..Default::default()
        })
        .unwrap();
        app::ingest(
            &mut project,
            &app::IngestRequest {
                files,
                ..Default::default()
            },
            0,
            &Silent,
        )
        .unwrap();
        tmp
    })
    .path()
}

/// The template's CAF readings files (2013, the 42 stations), as ingested into it.
pub fn template_inputs() -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(template().join("input"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    files
}

/// A fresh copy of the template project (its own database), in its own temporary folder.
pub fn caf_project() -> tempfile::TempDir {
    let tmp = tempfile::tempdir().unwrap();
    let from = template().join("caf");
    let to = tmp.path().join("caf");
    std::fs::create_dir_all(&to).unwrap();
    for e in std::fs::read_dir(&from).unwrap() {
        let e = e.unwrap();
        if e.file_type().unwrap().is_file() {
            std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
        }
    }
    tmp
}

/// A server on an ephemeral loopback port, in its own thread and runtime; stopped (gracefully)
/// and joined on drop.
pub struct Server {
    /// Where it listens.
    pub addr: SocketAddr,
    /// Its project's folder (kept alive as long as the server).
    _dir: tempfile::TempDir,
    stop: Option<tokio::sync::oneshot::Sender<()>>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Server {
    /// Serves a fresh CAF project with the test token.
    pub fn caf() -> Self {
        Self::start(caf_project(), |c| {
            c.token = Some(Token::new(TOKEN).unwrap())
        })
    }

    /// Serves the project in `dir`'s `caf` folder with `configure`'s settings.
    pub fn start(dir: tempfile::TempDir, configure: impl FnOnce(&mut ServerConfig)) -> Self {
        let mut config = ServerConfig::new(dir.path().join("caf"));
        config.addr = "127.0.0.1:0".parse().unwrap();
        configure(&mut config);
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
                gleaner_server::serve(listener, &config, async {
                    stopped.await.ok();
                })
                .await
                .unwrap();
            });
        });
        let addr = addr_rx
            .recv()
            .expect("the server thread reports its address");
        Self {
            addr,
            _dir: dir,
            stop: Some(stop),
            thread: Some(thread),
        }
    }

    /// A new client connection.
    pub fn client(&self) -> Client {
        Client::new(self.addr)
    }

    /// GET `path` and parse the JSON body, asserting 200.
    pub fn get_json(&self, path: &str) -> serde_json::Value {
        let r = self.client().get(path).unwrap();
        assert_eq!(r.status, 200, "GET {path}: {}", r.text());
        r.json().unwrap()
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        if let Some(s) = self.stop.take() {
            s.send(()).ok();
        }
        if let Some(t) = self.thread.take() {
            let panicked = t.join().is_err();
            if panicked && !std::thread::panicking() {
                panic!("the server thread panicked");
            }
        }
    }
}

/// A server whose [`gleaner_server::Event`]s the test receives, in order, and which can hold
/// the work of chosen kinds at its start until the test releases it ([`Watched::release`]).
pub struct Watched {
    /// Where it listens.
    pub addr: SocketAddr,
    /// Its state (to ask whether the planning slot is free).
    pub state: gleaner_server::AppState,
    events: std::sync::mpsc::Receiver<gleaner_server::Event>,
    gate: std::sync::mpsc::Sender<()>,
    _dir: tempfile::TempDir,
    stop: Option<tokio::sync::oneshot::Sender<()>>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Watched {
    /// Serves a fresh CAF project with the test token and `configure`'s settings, holding
    /// the work of the kinds in `held` at its start.
    pub fn start(held: &'static [&'static str], configure: impl FnOnce(&mut ServerConfig)) -> Self {
        let dir = caf_project();
        let mut config = ServerConfig::new(dir.path().join("caf"));
        config.addr = "127.0.0.1:0".parse().unwrap();
        config.token = Some(Token::new(TOKEN).unwrap());
        configure(&mut config);
        let listener = std::net::TcpListener::bind(config.addr).unwrap();
        Self::serve(dir, config, listener, held)
    }

    /// Serves `config` on `listener` (bound by the test, which may already have connected
    /// to it and sent its bytes: they are there when the server first reads).
    pub fn serve(
        dir: tempfile::TempDir,
        config: ServerConfig,
        listener: std::net::TcpListener,
        held: &'static [&'static str],
    ) -> Self {
        let state = gleaner_server::AppState::new(&config).unwrap();
        let (event_tx, events) = std::sync::mpsc::channel();
        let (gate, gate_rx) = std::sync::mpsc::channel::<()>();
        let event_tx = std::sync::Mutex::new(event_tx);
        let gate_rx = std::sync::Mutex::new(gate_rx);
        state.set_hook(std::sync::Arc::new(move |e: &gleaner_server::Event| {
            if let Ok(tx) = event_tx.lock() {
                tx.send(e.clone()).ok();
            }
            if let gleaner_server::Event::Started(kind) = e
                && held.contains(kind)
                && let Ok(rx) = gate_rx.lock()
            {
                rx.recv().ok();
            }
        }));
        let addr = listener.local_addr().unwrap();
        listener.set_nonblocking(true).unwrap();
        let (stop, stopped) = tokio::sync::oneshot::channel::<()>();
        let served = state.clone();
        let thread = std::thread::spawn(move || {
            let rt = tokio::runtime::Builder::new_multi_thread()
                .worker_threads(2)
                .enable_all()
                .build()
                .unwrap();
            rt.block_on(async move {
                let listener = tokio::net::TcpListener::from_std(listener).unwrap();
                gleaner_server::serve_state(listener, &config, served, async {
                    stopped.await.ok();
                })
                .await
                .unwrap();
            });
        });
        Self {
            addr,
            state,
            events,
            gate,
            _dir: dir,
            stop: Some(stop),
            thread: Some(thread),
        }
    }

    /// The next event that `keep` selects (others are skipped).
    pub fn next(&self, keep: impl Fn(&gleaner_server::Event) -> bool) -> gleaner_server::Event {
        loop {
            let e = self.events.recv().expect("the server reports its events");
            if keep(&e) {
                return e;
            }
        }
    }

    /// Every event reported so far, without waiting.
    pub fn so_far(&self) -> Vec<gleaner_server::Event> {
        self.events.try_iter().collect()
    }

    /// Lets one held piece of work go on.
    pub fn release(&self) {
        self.gate.send(()).unwrap();
    }

    /// Starts the shutdown (returns at once).
    pub fn begin_stop(&mut self) {
        if let Some(s) = self.stop.take() {
            s.send(()).ok();
        }
    }

    /// Waits until the server has stopped.
    pub fn join(&mut self) {
        self.begin_stop();
        if let Some(t) = self.thread.take() {
            t.join().expect("the server thread ends without panicking");
        }
    }
}

impl Drop for Watched {
    fn drop(&mut self) {
        // Whatever is still held must end for the server to stop.
        for _ in 0..4 {
            self.gate.send(()).ok();
        }
        self.begin_stop();
        if let Some(t) = self.thread.take() {
            let panicked = t.join().is_err();
            if panicked && !std::thread::panicking() {
                panic!("the server thread panicked");
            }
        }
    }
}

/// A whole HTTP/1.1 request with a JSON body, as raw bytes.
pub fn raw_json(method: &str, path: &str, host: &str, extra: &str, body: &str) -> Vec<u8> {
    format!(
        "{method} {path} HTTP/1.1\r\nHost: {host}\r\nContent-Type: application/json\r\n{extra}Content-Length: {}\r\n\r\n{body}",
        body.len()
    )
    .into_bytes()
}
