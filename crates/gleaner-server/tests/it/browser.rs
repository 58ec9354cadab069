//! The dashboard in a real headless Chromium (Debian's `chromium` and `chromium-driver`,
//! installed by `scripts/browser-env.sh`), driven over WebDriver. Fails (never skips) when the
//! browser is missing. The flows:
//!
//! - On a CAF project: one shape per cell, a cell's estimated series with its 90% band, the
//!   estimated field map, a mission planned through the form, its route drawn and its energy
//!   total equal to the API's, the `.plan` downloaded, and a screenshot.
//! - The missions panel: pages through the history, cancels one mission and deletes another
//!   after the page's confirmation, shows a refused change as an error; the API agrees after.
//! - A phone (375 × 812 px): every tap target at least 44 px in its smaller dimension (the
//!   map's cells included), every text at least 12 px as drawn, no sideways scrolling.
//! - A farms server: the farm picker lists the farms of the tokens given, and switching
//!   shows each farm's cells and missions.
//!
//! The browser tests run one at a time (one Chromium on the machine at once).

use std::future::Future;
use std::io::{BufRead, BufReader};
use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::Mutex;
use std::time::Duration;

use fantoccini::{ClientBuilder, Locator};
use serde_json::{Value, json};

use crate::common::{Server, TOKEN};

/// Where a test's screenshot goes: `GLEANER_SCREENSHOT` (the main flow's), or the tests'
/// target folder.
fn screenshot_path(name: &str) -> PathBuf {
    match std::env::var_os("GLEANER_SCREENSHOT") {
        Some(p) if name == "dashboard.png" => PathBuf::from(p),
        _ => Path::new(env!("CARGO_TARGET_TMPDIR")).join(name),
    }
}

/// A bound on a stuck browser, not a timing assertion.
const WAIT: Duration = Duration::from_secs(60);

/// One browser test at a time.
static BROWSER: Mutex<()> = Mutex::new(());

fn which(name: &str) -> Option<PathBuf> {
    std::env::var_os("PATH").and_then(|paths| {
        std::env::split_paths(&paths)
            .map(|p| p.join(name))
            .find(|p| p.is_file())
    })
}

/// chromedriver on a free loopback port, stopped on drop.
struct Driver {
    child: Child,
    port: u16,
}

impl Driver {
    fn start() -> Self {
        let driver = which("chromedriver").unwrap_or_else(|| {
            panic!("chromedriver is missing: run scripts/browser-env.sh (apt-get install chromium chromium-driver)")
        });
        assert!(
            which("chromium").is_some(),
            "chromium is missing: run scripts/browser-env.sh (apt-get install chromium chromium-driver)"
        );
        // A free port: bind 0, read it, release it for chromedriver.
        let port = std::net::TcpListener::bind("127.0.0.1:0")
            .unwrap()
            .local_addr()
            .unwrap()
            .port();
        let mut child = Command::new(driver)
            .arg(format!("--port={port}"))
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("chromedriver starts");
        // Explicit synchronisation: chromedriver says when it listens.
        let out = child.stdout.take().unwrap();
        let mut lines = BufReader::new(out).lines();
        let mut ready = false;
        for line in lines.by_ref().take(50) {
            if line.unwrap_or_default().contains("started successfully") {
                ready = true;
                break;
            }
        }
        assert!(ready, "chromedriver did not report that it started");
        // Keep draining its output so it never blocks on a full pipe.
        std::thread::spawn(move || for _ in lines {});
        Self { child, port }
    }
}

impl Drop for Driver {
    fn drop(&mut self) {
        self.child.kill().ok();
        self.child.wait().ok();
    }
}

type Res = Result<(), Box<dyn std::error::Error>>;

/// Runs `drive` in a new headless Chromium whose window is `width` × `height` CSS px and
/// whose downloads go to `downloads`, then saves a screenshot as `shot` (whatever the outcome)
/// and fails the test if `drive` failed.
fn in_browser<F, Fut>((width, height): (u32, u32), downloads: &Path, shot: &str, drive: F)
where
    F: FnOnce(fantoccini::Client) -> Fut,
    Fut: Future<Output = Res>,
{
    let _one = BROWSER.lock().unwrap_or_else(|p| p.into_inner());
    let driver = Driver::start();
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .unwrap();
    rt.block_on(async {
        let mut options = json!({
            "binary": which("chromium").unwrap(),
            "args": ["--headless=new", "--no-sandbox", "--disable-gpu",
                     "--disable-dev-shm-usage", format!("--window-size={width},{height}"),
                     "--hide-scrollbars", "--no-first-run", "--no-default-browser-check"],
            "prefs": {
                "download.default_directory": downloads,
                "download.prompt_for_download": false
            }
        });
        // Chromium's windows are at least 500 px wide: a phone is emulated (a touch screen
        // whose viewport the page's `<meta name="viewport">` sets).
        if width < 500 {
            options["mobileEmulation"] = json!({
                "deviceMetrics": {"width": width, "height": height, "pixelRatio": 2.0,
                                  "touch": true, "mobile": true}
            });
        }
        let mut caps = serde_json::Map::new();
        caps.insert("goog:chromeOptions".into(), options);
        let connector = hyper_util::client::legacy::connect::HttpConnector::new();
        let c = ClientBuilder::new(connector)
            .capabilities(caps)
            .connect(&format!("http://127.0.0.1:{}", driver.port))
            .await
            .expect("a WebDriver session");
        let result = drive(c.clone()).await;
        let png = c.screenshot().await;
        c.close().await.ok();
        if let Ok(png) = png {
            let path = screenshot_path(shot);
            std::fs::create_dir_all(path.parent().unwrap()).ok();
            std::fs::write(&path, png).unwrap();
        }
        result.unwrap();
    });
}

/// Evaluates the JavaScript expression `cond` until it is true; each round trip to the
/// browser paces the check, the count bounds it.
async fn until(c: &fantoccini::Client, cond: &str) -> Res {
    let script = format!("return !!({cond});");
    for _ in 0..3000 {
        if c.execute(&script, vec![]).await? == json!(true) {
            return Ok(());
        }
    }
    Err(format!("never true in the page: {cond}").into())
}

/// The mission ids the missions panel lists, top to bottom.
async fn listed(c: &fantoccini::Client) -> Result<Vec<i64>, fantoccini::error::CmdError> {
    let v = c
        .execute(
            "return [...document.querySelectorAll('#missions li.mission')].map(li => +li.dataset.mission)",
            vec![],
        )
        .await?;
    Ok(v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_i64().unwrap())
        .collect())
}

/// The ids of a page of the API's mission history.
fn page_ids(page: &Value) -> Vec<i64> {
    page["missions"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["mission_id"].as_i64().unwrap())
        .collect()
}

/// Plans and saves a mission through the API (the greedy planner: quick).
fn plan(addr: SocketAddr, prefix: &str, token: &str) -> i64 {
    let r = gleaner_server::client::Client::new(addr)
        .post_json(
            &format!("{prefix}/plan"),
            &json!({"solver": "greedy", "seed": 1}),
            Some(token),
        )
        .unwrap();
    assert_eq!(r.status, 200, "{}", r.text());
    r.json().unwrap()["mission_id"].as_i64().unwrap()
}

#[test]
fn dashboard_in_headless_chromium() {
    let server = Server::caf();
    let downloads = tempfile::tempdir().unwrap();
    let (server, dl) = (&server, downloads.path());
    in_browser((1400, 1560), dl, "dashboard.png", |c| async move {
        drive(&c, server, dl).await
    });
}

async fn drive(c: &fantoccini::Client, server: &Server, downloads: &Path) -> Res {
    let field = server.get_json("/api/v1/field");
    let n_cells = field["cells"].as_array().unwrap().len();
    let wait = WAIT;

    c.goto(&format!("http://{}/#token={TOKEN}", server.addr))
        .await?;
    c.wait()
        .at_most(wait)
        .for_element(Locator::Css("#map path.cell"))
        .await?;
    // The token moved from the address into the session, out of the URL.
    assert!(!c.current_url().await?.as_str().contains("token"));
    let shapes = c.find_all(Locator::Css("#map path.cell")).await?;
    assert_eq!(shapes.len(), n_cells, "one shape per cell");

    // Click a cell: its panel explains its rank and shows its series.
    shapes[0].click().await?;
    c.wait()
        .at_most(wait)
        .for_element(Locator::Css("#cell-body svg.spark"))
        .await?;

    // ... and its sensors' estimated series over the last 30 days at 6-hour steps: per
    // sensor one chart with the 90% band, the mean line through every time, the readings
    // as dots, dated x ticks and a y axis in m³/m³.
    c.wait()
        .at_most(wait)
        .for_element(Locator::Css("#estimate-chart svg.estimate path.band"))
        .await?;
    let cell = &field["cells"][0];
    let cell_id = cell["cell"].as_str().unwrap();
    let project = server.get_json("/api/v1/project");
    let latest = project["latest_reading"].as_str().unwrap().to_string();
    let to = gleaner_app::parse_timestamp(&latest).unwrap();
    let from = to - 30 * 86_400;
    let detail = server.get_json(&format!("/api/v1/cells/{cell_id}?days=31"));
    let sensors: Vec<String> = detail["cell"]["sensors"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap().to_string())
        .collect();
    let charts = c
        .find_all(Locator::Css("#estimate-chart svg.estimate"))
        .await?;
    assert_eq!(
        charts.len(),
        sensors.len(),
        "one chart per sensor of {cell_id}"
    );
    for chart in &charts {
        let sensor = chart.attr("data-sensor").await?.unwrap();
        assert!(sensors.contains(&sensor), "{sensor}");
        let count = |css: &'static str| {
            let chart = chart.clone();
            async move { chart.find_all(Locator::Css(css)).await.map(|v| v.len()) }
        };
        assert_eq!(count("path.band").await?, 1);
        assert_eq!(count("polyline.mean").await?, 1);
        let points = chart
            .find(Locator::Css("polyline.mean"))
            .await?
            .attr("points")
            .await?
            .unwrap();
        assert_eq!(points.split(' ').count(), 30 * 4 + 1, "a point per 6 h");
        let band = chart
            .find(Locator::Css("path.band"))
            .await?
            .attr("d")
            .await?
            .unwrap();
        assert_eq!(
            band.matches('L').count() + 1,
            2 * (30 * 4 + 1),
            "both edges"
        );
        let readings = detail["series"]
            .as_array()
            .unwrap()
            .iter()
            .find(|s| s["sensor"] == sensor.as_str() && s["modality"] == "vw@30cm")
            .map_or(0, |s| {
                s["t"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .filter(|t| (from..=to).contains(&t.as_i64().unwrap()))
                    .count()
            });
        assert!(readings > 0, "CAF reports daily");
        assert_eq!(
            count("circle.reading").await?,
            readings,
            "a dot per reading"
        );
        assert!(
            count(".x-axis text").await? >= 4,
            "dated ticks and the axis title"
        );
        assert!(count(".y-axis text").await? >= 3);
        let y_texts = chart.find_all(Locator::Css(".y-axis text")).await?;
        let y_title = y_texts.last().unwrap().html(true).await?;
        assert_eq!(y_title, "VW (m³/m³)");
    }

    // The estimated field map: both panels, one shape per cell in each.
    c.find(Locator::Id("field-map-button"))
        .await?
        .click()
        .await?;
    c.wait()
        .at_most(wait)
        .for_element(Locator::Css("#field-map svg #panel-sd"))
        .await?;
    for key in ["value", "sd"] {
        let cells = c
            .find_all(Locator::Css(&format!("#field-map path[id^='{key}-cell-']")))
            .await?;
        assert_eq!(cells.len(), n_cells, "{key} panel");
    }

    // One file picker: the native input stays hidden inside its "choose files" label.
    let pickers = c
        .execute(
            "return [...document.querySelectorAll('#upload-panel input[type=file]')].filter(i => getComputedStyle(i).display !== 'none').length",
            vec![],
        )
        .await?;
    assert_eq!(
        pickers,
        json!(0),
        "the native file input is shown besides the link"
    );

    // Compare strategies in a daily wind: the form's weather goes with the simulation, and
    // the page shows how the sorties flew (over budget, re-planned), as the API answers it.
    let sim = c.form(Locator::Id("simulate-form")).await?;
    sim.set_by_name("strategies", "gleaner").await?;
    sim.set_by_name("start", "2013-12-28").await?;
    sim.set_by_name("planner_iterations", "50").await?;
    sim.set_by_name("weather", "weibull").await?;
    sim.set_by_name("wind_mean_mps", "6").await?;
    sim.set_by_name("gust", "1.5").await?;
    c.find(Locator::Id("simulate")).await?.click().await?;
    c.wait()
        .at_most(wait)
        .for_element(Locator::Css(
            "#simulate-result #sim-flights tr[data-strategy='gleaner']",
        ))
        .await?;
    let body = json!({"strategies": ["gleaner"], "start": "2013-12-28", "planner_iterations": 50,
        "wind": "weibull:6", "gust": 1.5});
    let r = server
        .client()
        .post_json("/api/v1/simulate", &body, None)
        .unwrap();
    assert_eq!(r.status, 200, "{}", r.text());
    let doc: Value = r.json().unwrap();
    let f = &doc["flights"][0];
    for (css, key) in [
        ("td.over-budget", "over_budget"),
        ("td.replanned", "replanned"),
        ("td.dropped", "cells_dropped"),
    ] {
        let shown = c
            .find(Locator::Css(&format!(
                "#sim-flights tr[data-strategy='gleaner'] {css}"
            )))
            .await?
            .text()
            .await?;
        assert_eq!(shown, f[key].to_string(), "{key}");
    }
    let rows = c
        .find_all(Locator::Css("#sim-strategies tr[data-strategy]"))
        .await?;
    assert_eq!(rows.len(), 1, "one strategy");
    // Still air: no flights table.
    sim.set_by_name("weather", "").await?;
    c.find(Locator::Id("simulate")).await?.click().await?;
    until(
        c,
        "document.querySelector('#simulate-result #sim-strategies') && !document.querySelector('#simulate-result #sim-flights') && !document.getElementById('simulate').disabled",
    )
    .await?;
    // The report's charts (asked for by default): each drawn as an image (the SVG decoded by
    // the browser), as many as the API's report holds, and the Markdown to download.
    until(
        c,
        "[...document.querySelectorAll('#sim-report img')].length > 0 && [...document.querySelectorAll('#sim-report img')].every(i => i.complete && i.naturalWidth > 0)",
    )
    .await?;
    let body = json!({"strategies": ["gleaner"], "start": "2013-12-28", "planner_iterations": 50,
        "report": true});
    let r = server
        .client()
        .post_json("/api/v1/simulate", &body, None)
        .unwrap();
    assert_eq!(r.status, 200, "{}", r.text());
    let doc: Value = r.json().unwrap();
    let shown = c
        .execute(
            "return [...document.querySelectorAll('#sim-report figure')].map(f => f.dataset.name)",
            vec![],
        )
        .await?;
    let names: Vec<Value> = doc["report"]["figures"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["name"].clone())
        .collect();
    assert_eq!(shown, Value::Array(names), "the report's charts, in order");
    let md = c
        .execute(
            "return document.getElementById('sim-report-md').getAttribute('download')",
            vec![],
        )
        .await?;
    assert_eq!(md, json!("report.md"));

    // Plan through the form: preview, then save.
    let form = c.form(Locator::Id("plan-form")).await?;
    form.set_by_name("seed", "1").await?;
    form.set_by_name("iterations", "500").await?;
    form.set_by_name("time_limit_s", "5").await?;
    c.find(Locator::Id("preview")).await?.click().await?;
    c.wait()
        .at_most(wait)
        .for_element(Locator::Css("#plan-result #energy-total"))
        .await?;
    // A preview that fails leaves nothing to save (not the previous preview).
    form.set_by_name("at", "1900-01-01").await?;
    c.find(Locator::Id("preview")).await?.click().await?;
    c.wait()
        .at_most(wait)
        .for_element(Locator::Css("#plan-result p.error"))
        .await?;
    assert!(
        !c.find(Locator::Id("save")).await?.is_enabled().await?,
        "Save is enabled after a failed preview"
    );
    assert_eq!(server.get_json("/api/v1/missions"), json!([]));
    // A forecast wind goes with the plan; the preview says what it was priced in (the
    // forecast plus the project's 2 m/s margin).
    form.set_by_name("at", "").await?;
    form.set_by_name("wind_mps", "6").await?;
    form.set_by_name("wind_from_deg", "270").await?;
    c.find(Locator::Id("preview")).await?.click().await?;
    c.wait()
        .at_most(wait)
        .for_element(Locator::Css("#plan-result #wind-summary"))
        .await?;
    let said = c.find(Locator::Id("wind-summary")).await?.text().await?;
    assert!(said.contains("Wind 6 m/s from 270°"), "{said}");
    assert!(said.contains("priced at 8 m/s with the margin"), "{said}");
    // The strongest wind it stands, scanned up from the 8 m/s it was priced in (a windy
    // route may be over the battery in still air: said too, when it is).
    assert!(said.contains("stays within the battery up to"), "{said}");
    form.set_by_name("wind_mps", "").await?;
    form.set_by_name("wind_from_deg", "").await?;
    c.find(Locator::Id("preview")).await?.click().await?;
    // The still-air preview has replaced the windy one before it is saved.
    until(
        c,
        "(document.getElementById('wind-summary') || {}).textContent?.startsWith('Still air')",
    )
    .await?;
    c.find(Locator::Id("save")).await?.click().await?;
    c.wait()
        .at_most(wait)
        .for_element(Locator::Id("saved"))
        .await?;
    c.wait()
        .at_most(wait)
        .for_element(Locator::Css("#missions li.mission.current"))
        .await?;

    // The route is drawn on the map, one marker per stop.
    let missions = server.get_json("/api/v1/missions");
    let m = &missions[0];
    let id = m["mission_id"].as_i64().unwrap();
    let stops = m["stops"].as_array().unwrap().len();
    assert!(stops > 0);
    let route = c.find_all(Locator::Css("#map #route *")).await?;
    assert!(!route.is_empty(), "the route is drawn");
    let markers = c.find_all(Locator::Css("#map #stops circle")).await?;
    assert_eq!(markers.len(), stops, "one marker per stop");
    // The energy total on the page is the API's.
    let shown = c
        .find(Locator::Id("energy-total"))
        .await?
        .attr("data-joules")
        .await?
        .unwrap();
    let api = server.get_json(&format!("/api/v1/missions/{id}"))["energy"]["total_j"]
        .as_f64()
        .unwrap();
    assert_eq!(shown.parse::<f64>()?, api);
    let text = c.find(Locator::Id("energy-total")).await?.text().await?;
    assert_eq!(text, format!("{:.2} kJ", api / 1000.0));

    // Download the .plan through its button.
    c.find(Locator::Id("dl-plan")).await?.click().await?;
    let file = downloads.join(format!("mission-{id}.plan"));
    let mut plan = None;
    // Each round trip to the browser paces the check; the count bounds it.
    for _ in 0..2000 {
        if let Ok(text) = std::fs::read_to_string(&file)
            && let Ok(v) = serde_json::from_str::<serde_json::Value>(&text)
        {
            plan = Some(v);
            break;
        }
        c.title().await?;
    }
    let plan = plan.ok_or("the .plan was not downloaded")?;
    assert_eq!(plan["fileType"], "Plan");
    let items = plan["mission"]["items"].as_array().unwrap();
    assert!(
        items.len() >= stops,
        "{} items for {stops} stops",
        items.len()
    );

    // Colour by another term: the cells change colour, the S colour bar is hidden.
    let before = shapes_fill(c).await?;
    c.find(Locator::Css("#colour-by option[value='f']"))
        .await?
        .click()
        .await?;
    assert_ne!(shapes_fill(c).await?, before);
    Ok(())
}

async fn shapes_fill(c: &fantoccini::Client) -> Result<String, fantoccini::error::CmdError> {
    let v = c
        .execute(
            "return [...document.querySelectorAll('#map path.cell')].map(p => getComputedStyle(p).fill).join(';')",
            vec![],
        )
        .await?;
    Ok(v.as_str().unwrap_or("").to_string())
}

/// The missions panel: newest first, 8 a page; "Older" and "Newer" page through the history;
/// Cancel and Delete ask on the page first ("No" changes nothing); a change the server
/// refuses is shown in the panel; the API's state afterwards is the page's.
#[test]
fn missions_panel_pages_cancels_and_deletes() {
    let server = Server::caf();
    let ids: Vec<i64> = (0..11)
        .map(|_| plan(server.addr, "/api/v1", TOKEN))
        .collect();
    let downloads = tempfile::tempdir().unwrap();
    let (server, ids) = (&server, &ids);
    in_browser(
        (1400, 1200),
        downloads.path(),
        "missions.png",
        |c| async move { drive_missions(&c, server, ids).await },
    );
}

async fn drive_missions(c: &fantoccini::Client, server: &Server, ids: &[i64]) -> Res {
    c.goto(&format!("http://{}/#token={TOKEN}", server.addr))
        .await?;
    c.wait()
        .at_most(WAIT)
        .for_element(Locator::Css("#missions li.mission"))
        .await?;
    // The first page is the API's first page: the 8 newest, newest first.
    let first = server.get_json("/api/v1/missions/page?limit=8");
    assert_eq!(listed(c).await?, page_ids(&first));
    assert_eq!(
        page_ids(&first),
        ids[3..].iter().rev().copied().collect::<Vec<_>>()
    );
    assert!(
        !c.find(Locator::Id("missions-newer"))
            .await?
            .is_enabled()
            .await?
    );
    let range = c.find(Locator::Id("missions-range")).await?.text().await?;
    assert!(range.contains("11 in all"), "{range}");
    // Every mission is planned: each has its status, a Cancel and a Delete.
    let statuses = c
        .execute(
            "return [...document.querySelectorAll('#missions li.mission .status')].map(s => s.textContent)",
            vec![],
        )
        .await?;
    assert_eq!(statuses, json!(vec!["planned"; 8]));
    assert_eq!(
        c.find_all(Locator::Css("#missions button.cancel"))
            .await?
            .len(),
        8
    );

    // Older: the last three; then nothing older.
    c.find(Locator::Id("missions-older")).await?.click().await?;
    let oldest = format!("#missions li[data-mission='{}']", ids[0]);
    c.wait()
        .at_most(WAIT)
        .for_element(Locator::Css(&oldest))
        .await?;
    let second = server.get_json(&format!(
        "/api/v1/missions/page?limit=8&before={}",
        first["next"].as_i64().unwrap()
    ));
    assert_eq!(listed(c).await?, page_ids(&second));
    assert_eq!(listed(c).await?, [ids[2], ids[1], ids[0]]);
    assert!(
        !c.find(Locator::Id("missions-older"))
            .await?
            .is_enabled()
            .await?
    );
    assert!(
        c.find(Locator::Id("missions-newer"))
            .await?
            .is_enabled()
            .await?
    );

    // Cancel ids[1]: "No" keeps it planned; "Yes" cancels it.
    let row = |id: i64| format!("#missions li[data-mission='{id}']");
    c.find(Locator::Css(&format!("{} button.cancel", row(ids[1]))))
        .await?
        .click()
        .await?;
    let question = c
        .find(Locator::Id("missions-confirm-text"))
        .await?
        .text()
        .await?;
    assert!(
        question.contains(&format!("Cancel mission #{}", ids[1])),
        "{question}"
    );
    c.find(Locator::Id("confirm-no")).await?.click().await?;
    until(c, "document.getElementById('missions-confirm').hidden").await?;
    let m = server.get_json(&format!("/api/v1/missions/{}", ids[1]));
    assert_eq!(m["status"], "planned", "No changes nothing");
    c.find(Locator::Css(&format!("{} button.cancel", row(ids[1]))))
        .await?
        .click()
        .await?;
    c.find(Locator::Id("confirm-yes")).await?.click().await?;
    c.wait()
        .at_most(WAIT)
        .for_element(Locator::Css(&format!(
            "{}[data-status='cancelled']",
            row(ids[1])
        )))
        .await?;
    let m = server.get_json(&format!("/api/v1/missions/{}", ids[1]));
    assert_eq!(m["status"], "cancelled");
    let cancelled = c.find(Locator::Css(&row(ids[1]))).await?;
    assert_eq!(
        cancelled
            .find(Locator::Css(".status"))
            .await?
            .text()
            .await?,
        "cancelled"
    );
    assert!(
        cancelled
            .find_all(Locator::Css("button.cancel"))
            .await?
            .is_empty(),
        "a cancelled mission cannot be cancelled again"
    );

    // Delete ids[0] (planned) after the confirmation: gone from the page and from the API.
    c.find(Locator::Css(&format!("{} button.delete", row(ids[0]))))
        .await?
        .click()
        .await?;
    let question = c
        .find(Locator::Id("missions-confirm-text"))
        .await?
        .text()
        .await?;
    assert!(
        question.contains(&format!("Delete mission #{}", ids[0])),
        "{question}"
    );
    c.find(Locator::Id("confirm-yes")).await?.click().await?;
    until(c, &format!("!document.querySelector(\"{}\")", row(ids[0]))).await?;
    assert_eq!(listed(c).await?, [ids[2], ids[1]]);
    let r = server
        .client()
        .get(&format!("/api/v1/missions/{}", ids[0]))
        .unwrap();
    assert_eq!(r.status, 404, "{}", r.text());

    // A mission deleted elsewhere meanwhile: the page's delete is refused (404), and says so.
    let r = server
        .client()
        .request(
            "DELETE",
            &format!("/api/v1/missions/{}", ids[2]),
            &[("Authorization", &format!("Bearer {TOKEN}"))],
            None,
        )
        .unwrap();
    assert_eq!(r.status, 204, "{}", r.text());
    c.find(Locator::Css(&format!("{} button.delete", row(ids[2]))))
        .await?
        .click()
        .await?;
    c.find(Locator::Id("confirm-yes")).await?.click().await?;
    until(c, "!document.getElementById('missions-error').hidden").await?;
    let error = c.find(Locator::Id("missions-error")).await?.text().await?;
    assert!(
        error.contains(&format!("Deleting mission #{} failed", ids[2])),
        "{error}"
    );

    // Newer: the first page again, as the API has it now.
    c.find(Locator::Id("missions-newer")).await?.click().await?;
    let newest = format!("#missions li[data-mission='{}']", ids[10]);
    c.wait()
        .at_most(WAIT)
        .for_element(Locator::Css(&newest))
        .await?;
    let now = server.get_json("/api/v1/missions/page?limit=500");
    assert_eq!(page_ids(&now)[..8], listed(c).await?[..]);
    assert_eq!(
        page_ids(&now),
        ids[3..]
            .iter()
            .rev()
            .chain([&ids[1]])
            .copied()
            .collect::<Vec<_>>(),
        "two deleted, one cancelled and kept"
    );
    Ok(())
}

/// What the phone test measures in the page: every visible tap target (buttons, fields,
/// links, the map's cells) whose smaller side is under 44 px, and every visible text drawn
/// under 12 px (an SVG text: its font size times the scale it is drawn at).
const PHONE_CHECK: &str = r##"
const visible = (e) => { const r = e.getBoundingClientRect(); return r.width > 0 && r.height > 0; };
const name = (e) => e.tagName.toLowerCase() + (e.id ? "#" + e.id : "") + (e.className && typeof e.className === "string" ? "." + e.className.split(" ").join(".") : "");
const small = [];
let targets = 0, cells = 0;
for (const e of document.querySelectorAll("button, input:not([type=hidden]), select, a[href], label.link, #map path.cell")) {
  if (!visible(e)) continue;
  targets++;
  if (e.matches("path.cell")) cells++;
  const r = e.getBoundingClientRect();
  if (Math.min(r.width, r.height) < 44) small.push(name(e) + " " + r.width.toFixed(1) + "x" + r.height.toFixed(1));
}
const tiny = [];
let texts = 0, svgTexts = 0;
const walk = document.createTreeWalker(document.body, NodeFilter.SHOW_TEXT);
for (let n = walk.nextNode(); n; n = walk.nextNode()) {
  const e = n.parentElement;
  if (!n.textContent.trim() || !e || !visible(e)) continue;
  let px = parseFloat(getComputedStyle(e).fontSize);
  if (e instanceof SVGElement) {
    const m = e.getScreenCTM();
    px *= m ? Math.hypot(m.a, m.b) : 1;
    svgTexts++;
  }
  texts++;
  if (px < 12 - 1e-6) tiny.push(name(e) + " " + px.toFixed(2) + "px: " + n.textContent.trim().slice(0, 30));
}
return { width: window.innerWidth, scroll_width: document.documentElement.scrollWidth,
         targets, cells, small: small.slice(0, 40), texts, svg_texts: svgTexts, tiny: tiny.slice(0, 40) };
"##;

/// A phone, 375 × 812 px: after opening a cell, the estimated field map, a plan preview and
/// a delete's confirmation, every tap target is at least 44 px in its smaller dimension (the
/// map's cells too: on a narrow screen the map is drawn with tap-size cells and scrolls in
/// its box), every text at least 12 px as drawn, and the page never scrolls sideways.
#[test]
fn phone_layout_has_tap_size_targets_and_readable_text() {
    let server = Server::caf();
    let a = plan(server.addr, "/api/v1", TOKEN);
    plan(server.addr, "/api/v1", TOKEN);
    let r = server
        .client()
        .post_json(
            &format!("/api/v1/missions/{a}/cancel"),
            &json!({}),
            Some(TOKEN),
        )
        .unwrap();
    assert_eq!(r.status, 200, "{}", r.text());
    let downloads = tempfile::tempdir().unwrap();
    let server = &server;
    in_browser((375, 812), downloads.path(), "phone.png", |c| async move {
        drive_phone(&c, server).await
    });
}

async fn drive_phone(c: &fantoccini::Client, server: &Server) -> Res {
    let n_cells = server.get_json("/api/v1/field")["cells"]
        .as_array()
        .unwrap()
        .len();
    c.goto(&format!("http://{}/#token={TOKEN}", server.addr))
        .await?;
    c.wait()
        .at_most(WAIT)
        .for_element(Locator::Css("#map path.cell"))
        .await?;
    c.wait()
        .at_most(WAIT)
        .for_element(Locator::Css("#missions li.mission"))
        .await?;
    assert_eq!(
        c.find(Locator::Id("map-zoom"))
            .await?
            .attr("aria-pressed")
            .await?
            .as_deref(),
        Some("true"),
        "tap-size cells by default on a phone"
    );
    // Open what a user would: a cell's panel with its charts, the field map, a preview.
    let shapes = c.find_all(Locator::Css("#map path.cell")).await?;
    shapes[n_cells / 2].click().await?;
    c.wait()
        .at_most(WAIT)
        .for_element(Locator::Css("#estimate-chart svg.estimate path.band"))
        .await?;
    c.find(Locator::Id("field-map-button"))
        .await?
        .click()
        .await?;
    c.wait()
        .at_most(WAIT)
        .for_element(Locator::Css("#field-map svg #panel-sd"))
        .await?;
    let form = c.form(Locator::Id("plan-form")).await?;
    form.set_by_name("iterations", "200").await?;
    form.set_by_name("seed", "1").await?;
    c.find(Locator::Id("preview")).await?.click().await?;
    c.wait()
        .at_most(WAIT)
        .for_element(Locator::Css("#plan-result #energy-total"))
        .await?;
    c.find(Locator::Css("#missions button.delete"))
        .await?
        .click()
        .await?;
    until(c, "!document.getElementById('missions-confirm').hidden").await?;

    let m = c.execute(PHONE_CHECK, vec![]).await?;
    assert_eq!(m["width"], 375, "the viewport is 375 px wide: {m}");
    assert!(
        m["scroll_width"].as_i64().unwrap() <= 375,
        "the page scrolls sideways: {m}"
    );
    assert_eq!(m["cells"], json!(n_cells), "every cell is a target: {m}");
    assert!(m["targets"].as_i64().unwrap() > n_cells as i64 + 20, "{m}");
    assert!(
        m["svg_texts"].as_i64().unwrap() > 20,
        "the maps' and charts' text: {m}"
    );
    assert_eq!(m["small"], json!([]), "tap targets under 44 px: {m}");
    assert_eq!(m["tiny"], json!([]), "text under 12 px: {m}");

    // "Fit the map" draws the whole field in the box (cells smaller than a tap); the
    // button brings tap-size cells back.
    c.find(Locator::Id("confirm-no")).await?.click().await?;
    c.find(Locator::Id("map-zoom")).await?.click().await?;
    let side = "Math.min(...[...document.querySelectorAll('#map path.cell')].map(p => { const r = p.getBoundingClientRect(); return Math.min(r.width, r.height); }))";
    until(c, &format!("{side} < 44")).await?;
    c.find(Locator::Id("map-zoom")).await?.click().await?;
    until(c, &format!("{side} >= 44")).await?;
    Ok(())
}

/// A farms server over `dir` on an ephemeral loopback port; stopped and joined on drop.
struct FarmsServer {
    addr: SocketAddr,
    stop: Option<tokio::sync::oneshot::Sender<()>>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl FarmsServer {
    fn start(dir: &Path) -> Self {
        let mut config = gleaner_server::ServerConfig::new(PathBuf::new());
        config.farms = Some(dir.to_path_buf());
        config.addr = "127.0.0.1:0".parse().unwrap();
        let farms = gleaner_server::Farms::open(&config).unwrap();
        let listener = std::net::TcpListener::bind(config.addr).unwrap();
        listener.set_nonblocking(true).unwrap();
        let addr = listener.local_addr().unwrap();
        let (stop, stopped) = tokio::sync::oneshot::channel::<()>();
        let thread = std::thread::spawn(move || {
            let rt = tokio::runtime::Builder::new_multi_thread()
                .worker_threads(2)
                .enable_all()
                .build()
                .unwrap();
            rt.block_on(async move {
                let listener = tokio::net::TcpListener::from_std(listener).unwrap();
                gleaner_server::serve_farms(listener, &config, farms, async {
                    stopped.await.ok();
                })
                .await
                .unwrap();
            });
        });
        Self {
            addr,
            stop: Some(stop),
            thread: Some(thread),
        }
    }

    fn get_json(&self, path: &str, token: &str) -> Value {
        let r = gleaner_server::client::Client::new(self.addr)
            .request(
                "GET",
                path,
                &[("Authorization", &format!("Bearer {token}"))],
                None,
            )
            .unwrap();
        assert_eq!(r.status, 200, "GET {path}: {}", r.text());
        r.json().unwrap()
    }
}

impl Drop for FarmsServer {
    fn drop(&mut self) {
        if let Some(s) = self.stop.take() {
            s.send(()).ok();
        }
        if let Some(t) = self.thread.take() {
            t.join().ok();
        }
    }
}

/// Two farms: `north`, the CAF project (42 stations), and `south`, on CAF's first 12
/// stations only (2013's readings of those); a write token for north, a read and a write
/// token for south.
struct TwoFarms {
    dir: tempfile::TempDir,
    north_write: String,
    south_read: String,
    south_write: String,
}

impl TwoFarms {
    fn new() -> Self {
        use gleaner_app::{self as app, Silent};
        use gleaner_server::Scope;
        let dir = tempfile::tempdir().unwrap();
        let caf = crate::common::caf_project();
        std::fs::rename(caf.path().join("caf"), dir.path().join("north")).unwrap();
        let all = std::fs::read_to_string(
            crate::common::shared_data().join("caf/sensors/CAF_sensor_locations.csv"),
        )
        .unwrap();
        let rows: Vec<&str> = all.lines().take(13).collect();
        let sensors = dir.path().join("south-sensors.csv");
        std::fs::write(&sensors, rows.join("\n") + "\n").unwrap();
        let names: Vec<String> = rows[1..]
            .iter()
            .map(|r| format!("{}.txt", r.split(',').next().unwrap()))
            .collect();
        let (mut south, _) = app::init(&app::InitRequest {
            dir: dir.path().join("south"),
            sensors,
            utm_zone: Some("11N".into()),
            name: Some("south".into()),
            ..Default::default()
        })
        .unwrap();
        let files = crate::common::template_inputs()
            .into_iter()
            .filter(|f| names.iter().any(|n| f.ends_with(n)))
            .collect::<Vec<_>>();
        assert_eq!(files.len(), 12);
        app::ingest(
            &mut south,
            &app::IngestRequest {
                files,
                ..Default::default()
            },
            0,
            &Silent,
        )
        .unwrap();
        drop(south);
        let mut lines = Vec::new();
        let mut token = |farm: &str, scope: Scope| {
            let (t, line) = gleaner_server::farms::new_token_line(farm, scope).unwrap();
            lines.push(line);
            t.reveal().to_string()
        };
        let north_write = token("north", Scope::Write);
        let south_read = token("south", Scope::Read);
        let south_write = token("south", Scope::Write);
        std::fs::write(dir.path().join("tokens"), lines.join("\n") + "\n").unwrap();
        Self {
            dir,
            north_write,
            south_read,
            south_write,
        }
    }
}

/// A farms server's dashboard: the picker lists the farms of the tokens given to the page
/// (as `GET /api/v1/farms` names them), opens the first, and switching shows each farm's
/// cells and missions; a farm's downloads carry its token; a read token's cancel is refused
/// (403) and the page says so.
#[test]
fn farms_dashboard_switches_between_farms() {
    let farms = TwoFarms::new();
    let server = FarmsServer::start(farms.dir.path());
    let north: Vec<i64> = (0..3)
        .map(|_| plan(server.addr, "/api/v1/farms/north", &farms.north_write))
        .collect();
    let south = plan(server.addr, "/api/v1/farms/south", &farms.south_write);
    let downloads = tempfile::tempdir().unwrap();
    let (farms, server, dl, north) = (&farms, &server, downloads.path(), &north);
    in_browser((1400, 1200), dl, "farms.png", |c| async move {
        drive_farms(&c, server, farms, dl, north, south).await
    });
}

async fn drive_farms(
    c: &fantoccini::Client,
    server: &FarmsServer,
    farms: &TwoFarms,
    downloads: &Path,
    north: &[i64],
    south: i64,
) -> Res {
    let cells = |farm: &str, token: &str| {
        server.get_json(&format!("/api/v1/farms/{farm}/field"), token)["cells"]
            .as_array()
            .unwrap()
            .len()
    };
    let (n_north, n_south) = (
        cells("north", &farms.north_write),
        cells("south", &farms.south_read),
    );
    assert!(n_south < n_north, "{n_south} < {n_north}");
    // The page is the dashboard, marked as a farms server's.
    let r = gleaner_server::client::Client::new(server.addr)
        .get("/")
        .unwrap();
    assert_eq!(r.status, 200);
    assert!(r.text().contains("<body data-farms>"));

    c.goto(&format!(
        "http://{}/#token={}&token={}",
        server.addr, farms.north_write, farms.south_read
    ))
    .await?;
    c.wait()
        .at_most(WAIT)
        .for_element(Locator::Css("#map path.cell"))
        .await?;
    assert!(!c.current_url().await?.as_str().contains("token"));
    let options = c
        .execute(
            "return [...document.querySelectorAll('#farm option')].map(o => o.textContent)",
            vec![],
        )
        .await?;
    assert_eq!(options, json!(["north (write)", "south (read)"]));
    let shown = |c: &fantoccini::Client| {
        let c = c.clone();
        async move {
            let n = c.find_all(Locator::Css("#map path.cell")).await?.len();
            let name = c.find(Locator::Id("project-name")).await?.text().await?;
            Ok::<_, fantoccini::error::CmdError>((name, n, listed(&c).await?))
        }
    };
    let north_ids: Vec<i64> = north.iter().rev().copied().collect();
    assert_eq!(
        shown(c).await?,
        ("· north (caf)".into(), n_north, north_ids.clone())
    );

    // Switch to south: its cells and its mission.
    c.find(Locator::Css("#farm option[value='south']"))
        .await?
        .click()
        .await?;
    until(
        c,
        &format!(
            "document.getElementById('project-name').textContent === '· south' && document.querySelectorAll('#map path.cell').length === {n_south} && document.querySelector('#missions li.mission')"
        ),
    )
    .await?;
    assert_eq!(shown(c).await?, ("· south".into(), n_south, vec![south]));
    // A read token cannot cancel: 403, shown in the panel; the mission stays planned.
    c.find(Locator::Css("#missions button.cancel"))
        .await?
        .click()
        .await?;
    c.find(Locator::Id("confirm-yes")).await?.click().await?;
    until(c, "!document.getElementById('missions-error').hidden").await?;
    let error = c.find(Locator::Id("missions-error")).await?.text().await?;
    assert!(error.contains("failed"), "{error}");
    let m = server.get_json(
        &format!("/api/v1/farms/south/missions/{south}"),
        &farms.south_read,
    );
    assert_eq!(m["status"], "planned");

    // Back to north: its cells and missions; its .plan is downloaded with its token.
    c.find(Locator::Css("#farm option[value='north']"))
        .await?
        .click()
        .await?;
    until(
        c,
        &format!(
            "document.getElementById('project-name').textContent === '· north (caf)' && document.querySelectorAll('#map path.cell').length === {n_north} && document.querySelectorAll('#missions li.mission').length === {}",
            north.len()
        ),
    )
    .await?;
    assert_eq!(
        shown(c).await?,
        ("· north (caf)".into(), n_north, north_ids)
    );
    c.find(Locator::Id("dl-plan")).await?.click().await?;
    let newest = north[north.len() - 1];
    let file = downloads.join(format!("mission-{newest}.plan"));
    let mut plan = None;
    for _ in 0..2000 {
        if let Ok(text) = std::fs::read_to_string(&file)
            && let Ok(v) = serde_json::from_str::<Value>(&text)
        {
            plan = Some(v);
            break;
        }
        c.title().await?;
    }
    let plan = plan.ok_or("the farm's .plan was not downloaded")?;
    assert_eq!(plan["fileType"], "Plan");
    Ok(())
}
