//! The HTML reports opened in a real browser: headless Chromium (Debian's `chromium`), driven
//! over its DevTools protocol on a loopback WebSocket. For a compare report, a suite report and
//! an analysis report it checks that every image loaded (`naturalWidth > 0`, data URIs
//! included), that every link to a file leads to one, that no script error, console error or
//! failed load occurred, and that the page is not blank (text, and a screenshot of more than one colour), and saves the screenshot (into
//! `SPECULA_BROWSER_SHOTS` when set: docs/images holds the three).
//!
//! Where `chromium` is missing the tests fail, unless the runner opts out with
//! `SPECULA_ALLOW_SKIP=browser`.

use std::io::{BufRead, BufReader};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use base64::Engine;
use serde_json::{json, Value};
use tungstenite::{Message, WebSocket};

const CHROMIUM: &str = "chromium";
/// Every technique (the exact methods run in every compare anyway).
const TECHNIQUES: &str = "envmap,pvrr,distance-maps,image-space,c3rc,vertex-tracing";
/// Longest wait for any one answer of the browser.
const PATIENCE: Duration = Duration::from_secs(60);

fn specula() -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_specula"));
    command.env("NODEVICE_SELECT", "1");
    command
}

fn run_ok(mut command: Command) {
    let out = command.output().unwrap();
    assert!(
        out.status.success(),
        "{command:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// A child process killed when dropped, so that a failing test leaves no browser behind.
struct Killed(Child);

impl Drop for Killed {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// A headless Chromium and the DevTools session of its one page.
struct Browser {
    _child: Killed,
    socket: WebSocket<tungstenite::stream::MaybeTlsStream<TcpStream>>,
    session: String,
    next_id: u64,
    /// Script errors, console errors and failed loads, as they arrive.
    errors: Vec<String>,
    /// The names of the events seen since the last `open`.
    events: Vec<String>,
    _profile: tempfile::TempDir,
}

impl Browser {
    /// Starts Chromium, or returns None where it is missing and the runner allowed the skip.
    fn start(test: &str) -> Option<Browser> {
        if Command::new(CHROMIUM).arg("--version").output().is_err() {
            specula_testkit::missing(
                specula_testkit::Requirement::Browser,
                test,
                "`chromium --version` could not be run",
            );
            return None;
        }
        let profile = tempfile::tempdir().unwrap();
        // The flags keep a closed network quiet: no background connections, no updates.
        let child = Command::new(CHROMIUM)
            .args([
                "--headless",
                "--no-sandbox",
                "--disable-gpu",
                "--disable-quic",
                "--no-first-run",
                "--disable-background-networking",
                "--disable-component-update",
                "--disable-sync",
                "--hide-scrollbars",
                "--window-size=1280,960",
                "--remote-debugging-address=127.0.0.1",
                "--remote-debugging-port=0",
            ])
            .arg(format!("--user-data-dir={}", profile.path().display()))
            .arg("about:blank")
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let mut child = Killed(child);
        let endpoint = devtools_endpoint(&mut child.0);
        let (mut socket, _) = tungstenite::connect(endpoint.as_str()).unwrap();
        // A silent browser fails the test after PATIENCE instead of blocking it forever.
        if let tungstenite::stream::MaybeTlsStream::Plain(stream) = socket.get_mut() {
            stream
                .set_read_timeout(Some(Duration::from_secs(1)))
                .unwrap();
        }
        let mut browser = Browser {
            _child: child,
            socket,
            session: String::new(),
            next_id: 0,
            errors: Vec::new(),
            events: Vec::new(),
            _profile: profile,
        };
        let page = browser.first_page();
        let attached = browser.call(
            "Target.attachToTarget",
            json!({ "targetId": page, "flatten": true }),
        );
        browser.session = attached["sessionId"].as_str().unwrap().to_string();
        for domain in ["Page.enable", "Runtime.enable", "Log.enable"] {
            browser.call(domain, json!({}));
        }
        Some(browser)
    }

    /// The first page's target id; the browser may list it a moment after it listens.
    fn first_page(&mut self) -> Value {
        let start = Instant::now();
        loop {
            let targets = self.call("Target.getTargets", json!({}));
            let page = targets["targetInfos"]
                .as_array()
                .and_then(|t| t.iter().find(|t| t["type"] == "page"));
            if let Some(page) = page {
                return page["targetId"].clone();
            }
            assert!(
                start.elapsed() < PATIENCE,
                "Chromium shows no page: {targets}"
            );
            std::thread::sleep(Duration::from_millis(100));
        }
    }

    /// Sends `method` (to the page once attached) and returns its result; events that arrive
    /// meanwhile are read for errors.
    fn call(&mut self, method: &str, params: Value) -> Value {
        self.next_id += 1;
        let id = self.next_id;
        let mut message = json!({ "id": id, "method": method, "params": params });
        if !self.session.is_empty() {
            message["sessionId"] = json!(self.session);
        }
        self.socket
            .send(Message::text(message.to_string()))
            .unwrap();
        let reply = self.until(|m| m["id"] == id, method);
        if let Some(error) = reply.get("error") {
            panic!("{method}: {error}");
        }
        reply["result"].clone()
    }

    /// Reads messages until one satisfies `wanted`, keeping the errors the others report.
    fn until(&mut self, wanted: impl Fn(&Value) -> bool, waiting_for: &str) -> Value {
        let start = Instant::now();
        loop {
            assert!(
                start.elapsed() < PATIENCE,
                "no answer to {waiting_for} in {PATIENCE:?}"
            );
            let text = match self.socket.read() {
                Ok(Message::Text(text)) => text.to_string(),
                Ok(_) => continue,
                Err(tungstenite::Error::Io(e))
                    if matches!(
                        e.kind(),
                        std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                    ) =>
                {
                    continue
                }
                Err(e) => panic!("the DevTools connection, waiting for {waiting_for}: {e}"),
            };
            let message: Value = serde_json::from_str(&text).unwrap();
            if let Some(error) = reported_error(&message) {
                self.errors.push(error);
            }
            if let Some(event) = message["method"].as_str() {
                self.events.push(event.to_string());
            }
            if wanted(&message) {
                return message;
            }
        }
    }

    /// Opens `page` and waits for its load event and for every image to settle.
    fn open(&mut self, page: &Path) {
        let url = format!("file://{}", page.canonicalize().unwrap().display());
        self.events.clear();
        self.call("Page.navigate", json!({ "url": url }));
        // The load event may come before the navigation's reply.
        if !self.events.iter().any(|e| e == "Page.loadEventFired") {
            self.until(|m| m["method"] == "Page.loadEventFired", "the load event");
        }
        self.evaluate(
            "Promise.all(Array.from(document.images).map(i => i.complete ? null : \
             new Promise(r => { i.onload = r; i.onerror = r; })))",
        );
    }

    fn evaluate(&mut self, expression: &str) -> Value {
        let result = self.call(
            "Runtime.evaluate",
            json!({ "expression": expression, "awaitPromise": true, "returnByValue": true }),
        );
        if let Some(exception) = result.get("exceptionDetails") {
            panic!("{expression}: {exception}");
        }
        result["result"]["value"].clone()
    }

    /// The whole page as PNG, or the element with id `element` alone.
    fn screenshot(&mut self, element: Option<&str>) -> image::RgbImage {
        let mut params = json!({ "format": "png", "captureBeyondViewport": true });
        if let Some(id) = element {
            let rect = self.evaluate(&format!(
                "(() => {{ const r = document.getElementById('{id}').getBoundingClientRect(); \
                 return {{ x: r.x + scrollX, y: r.y + scrollY, width: r.width, height: r.height, \
                 scale: 1 }}; }})()"
            ));
            params["clip"] = rect;
        }
        let shot = self.call("Page.captureScreenshot", params);
        let bytes = base64::engine::general_purpose::STANDARD
            .decode(shot["data"].as_str().unwrap())
            .unwrap();
        image::load_from_memory(&bytes).unwrap().to_rgb8()
    }
}

/// Reads `ws://...` from Chromium's "DevTools listening on" line.
fn devtools_endpoint(child: &mut Child) -> String {
    let stderr = child.stderr.take().unwrap();
    let (sender, receiver) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let mut seen = String::new();
        for line in BufReader::new(stderr).lines().map_while(Result::ok) {
            if let Some(at) = line.find("ws://") {
                let _ = sender.send(Ok(line[at..].trim().to_string()));
                return;
            }
            seen.push_str(&line);
            seen.push('\n');
        }
        let _ = sender.send(Err(seen));
    });
    match receiver.recv_timeout(PATIENCE) {
        Ok(Ok(endpoint)) => endpoint,
        Ok(Err(seen)) => panic!("Chromium ended without a DevTools endpoint:\n{seen}"),
        Err(_) => panic!("Chromium gave no DevTools endpoint in {PATIENCE:?}"),
    }
}

/// The error a DevTools event reports: an uncaught exception, a console error, a log entry of
/// level error (a failed image load among them).
fn reported_error(message: &Value) -> Option<String> {
    let params = &message["params"];
    match message["method"].as_str()? {
        "Runtime.exceptionThrown" => Some(format!(
            "script error: {}",
            params["exceptionDetails"]["exception"]["description"]
        )),
        "Runtime.consoleAPICalled"
            if matches!(params["type"].as_str(), Some("error" | "assert")) =>
        {
            Some(format!("console error: {}", params["args"]))
        }
        "Log.entryAdded" if params["entry"]["level"] == "error" => Some(format!(
            "log error: {} {}",
            params["entry"]["text"], params["entry"]["url"]
        )),
        _ => None,
    }
}

/// What a page showed: its images that did not load, its errors, whether it is blank.
#[derive(Debug)]
struct Opened {
    images: usize,
    broken: Vec<String>,
    /// Links to files that do not exist.
    dead_links: Vec<String>,
    errors: Vec<String>,
    text_chars: usize,
    colours: usize,
}

impl Opened {
    fn assert_sound(&self, page: &str, least_images: usize) {
        assert!(
            self.images >= least_images,
            "{page}: {} images, not {least_images}: {self:?}",
            self.images
        );
        assert!(
            self.broken.is_empty(),
            "{page}: images that did not load: {:?}",
            self.broken
        );
        assert!(
            self.dead_links.is_empty(),
            "{page}: links to nothing: {:?}",
            self.dead_links
        );
        assert!(self.errors.is_empty(), "{page}: errors: {:?}", self.errors);
        assert!(
            self.text_chars > 100 && self.colours > 16,
            "{page} looks blank: {self:?}"
        );
    }
}

/// Opens `page` in `browser`, checks what it shows and saves its screenshot as `shot`.
fn open(browser: &mut Browser, page: &Path, shot: &str) -> Opened {
    browser.errors.clear();
    browser.open(page);
    let images = browser.evaluate(
        "Array.from(document.images).map(i => ({ src: i.src.slice(0, 80), \
         loaded: i.complete && i.naturalWidth > 0 }))",
    );
    let images = images.as_array().unwrap();
    let broken = images
        .iter()
        .filter(|i| i["loaded"] != true)
        .map(|i| i["src"].as_str().unwrap_or("").to_string())
        .collect();
    let links = browser.evaluate("Array.from(document.links).map(a => a.href)");
    let dead_links = links
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|l| l.as_str()?.strip_prefix("file://"))
        .map(|link| {
            let path = link.split(['#', '?']).next().unwrap_or(link);
            percent_encoding::percent_decode_str(path)
                .decode_utf8_lossy()
                .into_owned()
        })
        .filter(|path| !Path::new(path).exists())
        .collect();
    let text_chars = browser
        .evaluate("document.body ? document.body.innerText.trim().length : 0")
        .as_u64()
        .unwrap() as usize;
    let png = browser.screenshot(None);
    let colours: std::collections::HashSet<[u8; 3]> = png.pixels().map(|p| p.0).collect();
    let dir = std::env::var_os("SPECULA_BROWSER_SHOTS")
        .map(PathBuf::from)
        .unwrap_or_else(|| page.parent().unwrap().to_path_buf());
    std::fs::create_dir_all(&dir).unwrap();
    png.save(dir.join(shot)).unwrap();
    Opened {
        images: images.len(),
        broken,
        dead_links,
        errors: browser.errors.clone(),
        text_chars,
        colours: colours.len(),
    }
}

#[test]
fn the_reports_open_in_chromium_with_every_image_and_no_error() {
    let test = "the_reports_open_in_chromium_with_every_image_and_no_error";
    let Some(mut browser) = Browser::start(test) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let compare = dir.path().join("compare");
    let suite = dir.path().join("suite");
    let analysis = dir.path().join("analysis");
    let scenes = concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenes/suite");
    let small = ["-W", "96", "-H", "72"];
    let mut command = specula();
    command
        .args(["compare", "door-mirror", "--methods", TECHNIQUES])
        .args(small)
        .arg("--report")
        .arg(&compare);
    run_ok(command);
    let mut command = specula();
    command
        .args(["compare", scenes, "--methods", "envmap"])
        .args(small)
        .arg("--report")
        .arg(&suite);
    run_ok(command);
    let mut command = specula();
    command
        .args([
            "analyze",
            "mirror-view",
            "door-mirror",
            "--mirror",
            "door mirror",
            "--ocular",
        ])
        .args(["--region", "1,2,5,20", "--report"])
        .arg(&analysis);
    run_ok(command);

    // The compare report shows the reference, and each method's image and FLIP map; the
    // suite's table links to each scene's report; the analysis shows its two plots.
    for (folder, shot, least_images) in [
        (
            &compare,
            "report-compare.png",
            1 + 2 * TECHNIQUES.split(',').count(),
        ),
        (&suite, "report-suite.png", 0),
        (&suite.join("glass-lens"), "report-suite-scene.png", 3),
        (&analysis, "report-analysis.png", 2),
    ] {
        let page = folder.join("report.html");
        let opened = open(&mut browser, &page, shot);
        eprintln!("{shot}: {opened:?}");
        opened.assert_sound(&page.display().to_string(), least_images);
    }

    // The compare report's pictures alone: the README's picture.
    browser.open(&compare.join("report.html"));
    let grid = browser.screenshot(Some("figures"));
    assert!(
        grid.width() > 500 && grid.height() > 200,
        "{:?}",
        grid.dimensions()
    );
    if let Some(dir) = std::env::var_os("SPECULA_BROWSER_SHOTS") {
        grid.save(PathBuf::from(dir).join("readme-compare.png"))
            .unwrap();
    }

    // The checks can fail: a report whose image is missing is caught.
    let page = compare.join("report.html");
    let html = std::fs::read_to_string(&page).unwrap();
    let broken = compare.join("broken.html");
    std::fs::write(
        &broken,
        html.replacen("<img src=\"", "<img src=\"missing-", 1),
    )
    .unwrap();
    let opened = open(&mut browser, &broken, "report-broken.png");
    assert_eq!(opened.broken.len(), 1, "{opened:?}");
    assert!(
        opened.errors.iter().any(|e| e.contains("missing-")),
        "the failed load is reported: {opened:?}"
    );
}

/// The reports a user keeps lead with the verdict: an R46 report on the example car, the
/// README's lens example (judged against the compensated order) and a glare report with a
/// display; each opened in Chromium, sound, its verdict on the page; screenshots kept.
#[test]
fn the_verdict_leads_the_regulation_lens_and_glare_reports() {
    let test = "the_verdict_leads_the_regulation_lens_and_glare_reports";
    let Some(mut browser) = Browser::start(test) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let (r46, lens, glare) = (
        dir.path().join("r46"),
        dir.path().join("lens"),
        dir.path().join("glare"),
    );
    let scenes = concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenes");
    let mut command = specula();
    command
        .args(["analyze", "mirror-view"])
        .arg(format!("{scenes}/car-door-mirror.toml"))
        .args(["--mirror", "door mirror", "--regulation", "r46-iii"])
        .args(["--forward", "0,0,-1", "--r-point", "-0.37,0.55,0"])
        .args(["--outermost", "-0.95,0.6,1.5"])
        .args(["--vehicle", "car body", "--vehicle", "A-pillar", "--report"])
        .arg(&r46);
    run_ok(command);
    let mut command = specula();
    command
        .args(["analyze", "lens"])
        .arg(format!("{scenes}/spectacles-wrap.toml"))
        .args(["--lens", "right lens", "--pantoscopic", "10", "--wrap", "5"])
        .args([
            "--compensate",
            "--standard",
            "iso-8980-1",
            "--focimeter",
            "--report",
        ])
        .arg(&lens);
    run_ok(command);
    let mut command = specula();
    command
        .args([
            "analyze",
            "glare",
            "truck-cover",
            "--surface",
            "cover glass",
        ])
        .args(["--source", "side window", "--source-luminance", "8000"])
        .args([
            "--eyebox",
            "0.2,0.1,3,2",
            "--size",
            "96x72",
            "--display",
            "dial",
        ])
        .args(["--symbol-luminance", "300", "--background-luminance", "10"])
        .args(["--min-contrast", "3", "--report"])
        .arg(&glare);
    run_ok(command);
    for (folder, shot, least_images, expected) in [
        (
            &r46,
            "report-r46.png",
            2,
            vec!["FAIL", "4 m wide from 20 m behind", "Why"],
        ),
        (
            &lens,
            "report-lens.png",
            3,
            vec!["FAIL", "ISO 8980-1:2017", "compensated order"],
        ),
        (
            &glare,
            "report-glare.png",
            2,
            vec!["Glare is seen from", "washed out over", "veiling:"],
        ),
    ] {
        let page = folder.join("report.html");
        let opened = open(&mut browser, &page, shot);
        eprintln!("{shot}: {opened:?}");
        opened.assert_sound(&page.display().to_string(), least_images);
        let text = browser.evaluate("document.body.innerText");
        let text = text.as_str().unwrap();
        for words in expected {
            assert!(text.contains(words), "{shot}: '{words}' is not on the page");
        }
        // Where there is a verdict, it comes first, large.
        let banner = browser.evaluate(
            "(() => { const v = document.querySelector('.verdict'); \
             return v ? v.innerText : ''; })()",
        );
        let banner = banner.as_str().unwrap();
        if shot != "report-glare.png" {
            assert!(banner.starts_with("FAIL"), "{shot}: banner '{banner}'");
        }
    }
}
