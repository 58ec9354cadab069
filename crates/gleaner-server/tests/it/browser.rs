//! The dashboard in a real headless Chromium (Debian's `chromium` and `chromium-driver`,
//! installed by `scripts/browser-env.sh`), driven over WebDriver: it opens the dashboard on a
//! CAF project, sees one shape per cell, sees a cell's estimated series with its 90% band
//! and the estimated field map, plans a mission through the form, sees the route drawn and
//! the energy total equal to the API's, downloads the `.plan`, and saves a screenshot. Fails (never skips) when the browser is missing.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::Duration;

use fantoccini::{ClientBuilder, Locator};
use serde_json::json;

use crate::common::{Server, TOKEN};

/// Where the screenshot goes: `GLEANER_SCREENSHOT`, or the test's target folder.
fn screenshot_path() -> PathBuf {
    std::env::var_os("GLEANER_SCREENSHOT")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_TARGET_TMPDIR")).join("dashboard.png"))
}

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

#[test]
fn dashboard_in_headless_chromium() {
    let server = Server::caf();
    let driver = Driver::start();
    let downloads = tempfile::tempdir().unwrap();
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .unwrap();
    rt.block_on(async {
        let mut caps = serde_json::Map::new();
        caps.insert(
            "goog:chromeOptions".into(),
            json!({
                "binary": which("chromium").unwrap(),
                "args": ["--headless=new", "--no-sandbox", "--disable-gpu",
                         "--disable-dev-shm-usage", "--window-size=1400,1560",
                         "--no-first-run", "--no-default-browser-check"],
                "prefs": {
                    "download.default_directory": downloads.path(),
                    "download.prompt_for_download": false
                }
            }),
        );
        let connector = hyper_util::client::legacy::connect::HttpConnector::new();
        let c = ClientBuilder::new(connector)
            .capabilities(caps)
            .connect(&format!("http://127.0.0.1:{}", driver.port))
            .await
            .expect("a WebDriver session");
        let result = drive(&c, &server, downloads.path()).await;
        let shot = c.screenshot().await;
        c.close().await.ok();
        if let Ok(png) = shot {
            let path = screenshot_path();
            std::fs::create_dir_all(path.parent().unwrap()).ok();
            std::fs::write(&path, png).unwrap();
        }
        result.unwrap();
    });
}

type Res = Result<(), Box<dyn std::error::Error>>;

async fn drive(c: &fantoccini::Client, server: &Server, downloads: &Path) -> Res {
    let field = server.get_json("/api/v1/field");
    let n_cells = field["cells"].as_array().unwrap().len();
    let wait = Duration::from_secs(60); // a bound on a stuck browser, not a timing assertion

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
    form.set_by_name("at", "").await?;
    c.find(Locator::Id("preview")).await?.click().await?;
    c.wait()
        .at_most(wait)
        .for_element(Locator::Css("#plan-result #energy-total"))
        .await?;
    c.find(Locator::Id("save")).await?.click().await?;
    c.wait()
        .at_most(wait)
        .for_element(Locator::Id("saved"))
        .await?;
    c.wait()
        .at_most(wait)
        .for_element(Locator::Css("#missions tr.current"))
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
