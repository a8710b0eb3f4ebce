//! End to end in a real browser: start the server, open the page in
//! headless Chromium through chromedriver (W3C WebDriver), wait for frames,
//! drag the view with the mouse and check that the camera and the picture
//! changed. Needs Debian's `chromium` and `chromium-driver` (`.ci/run`
//! installs them); without them the test fails and says so, unless
//! RAYKIT_SKIP_BROWSER_TEST=1 asks to skip it (printed, never silent).

mod support;

use serde_json::{json, Value};
use std::net::SocketAddr;
use std::os::unix::process::CommandExt;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};
use support::*;

/// The W3C WebDriver web element identifier key.
const ELEMENT: &str = "element-6066-11e4-a52e-4f735466cecf";

fn find(names: &[&str]) -> Option<String> {
    let path = std::env::var_os("PATH")?;
    names.iter().find_map(|n| {
        std::env::split_paths(&path)
            .map(|d| d.join(n))
            .find(|p| p.is_file())
            .map(|p| p.to_string_lossy().into_owned())
    })
}

struct Driver {
    child: Child,
    addr: SocketAddr,
    session: String,
}

impl Drop for Driver {
    /// Kill chromedriver's whole process group, so the browser it started
    /// does not outlive a failed test.
    fn drop(&mut self) {
        let group = format!("-{}", self.child.id());
        let _ = Command::new("kill").args(["-KILL", "--", &group]).status();
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Driver {
    async fn call(&self, method: &str, path: &str, body: Value) -> Value {
        let path = format!("/session/{}{path}", self.session);
        webdriver(self.addr, method, &path, body).await
    }

    async fn script(&self, js: &str) -> Value {
        self.call("POST", "/execute/sync", json!({"script": js, "args": []}))
            .await
    }
}

async fn webdriver(addr: SocketAddr, method: &str, path: &str, body: Value) -> Value {
    let body = if method == "GET" || method == "DELETE" {
        String::new()
    } else {
        body.to_string()
    };
    let (status, _, out) = http_to(addr, method, path, "", &body).await;
    let v: Value = serde_json::from_slice(&out).unwrap_or(Value::Null);
    assert_eq!(status, 200, "WebDriver {method} {path}: {v}");
    v["value"].clone()
}

/// Luminance of the canvas scaled to 32×18, for comparing pictures.
const THUMBNAIL: &str = "const c = document.getElementById('view');
    const t = document.createElement('canvas'); t.width = 32; t.height = 18;
    const x = t.getContext('2d'); x.drawImage(c, 0, 0, 32, 18);
    const d = x.getImageData(0, 0, 32, 18).data; const out = [];
    for (let i = 0; i < d.length; i += 4) out.push(0.3 * d[i] + 0.59 * d[i + 1] + 0.11 * d[i + 2]);
    return out;";

fn thumbnail(v: &Value) -> Vec<f64> {
    v.as_array()
        .expect("thumbnail array")
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn dragging_in_headless_chromium_changes_the_view() {
    let (Some(chromium), Some(chromedriver)) = (
        find(&["chromium", "chromium-browser", "google-chrome"]),
        find(&["chromedriver"]),
    ) else {
        if std::env::var("RAYKIT_SKIP_BROWSER_TEST").is_ok_and(|v| v == "1") {
            eprintln!("SKIPPED dragging_in_headless_chromium_changes_the_view: chromium or chromedriver not on PATH (RAYKIT_SKIP_BROWSER_TEST=1)");
            return;
        }
        panic!("this test needs headless Chromium and chromedriver: apt-get install -y chromium chromium-driver (or set RAYKIT_SKIP_BROWSER_TEST=1 to skip it, reported)");
    };
    // With a token, as a LAN deployment would run: the page must pass it on.
    let mut c = config();
    c.token = Some("browser-test".into());
    let server = server(c).await;

    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let child = Command::new(&chromedriver)
        .arg(format!("--port={port}"))
        .process_group(0)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("chromedriver starts");
    let addr: SocketAddr = format!("127.0.0.1:{port}").parse().unwrap();
    let start = Instant::now();
    while tokio::net::TcpStream::connect(addr).await.is_err() {
        assert!(
            start.elapsed() < Duration::from_secs(20),
            "chromedriver did not listen"
        );
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    let caps = json!({"capabilities": {"alwaysMatch": {"browserName": "chrome",
        "goog:chromeOptions": {"binary": chromium, "args": ["--headless", "--no-sandbox",
            "--disable-gpu", "--disable-dev-shm-usage", "--window-size=800,600"]}}}});
    let created = webdriver(addr, "POST", "/session", caps).await;
    let mut driver = Driver {
        child,
        addr,
        session: created["sessionId"]
            .as_str()
            .expect("session id")
            .to_string(),
    };

    let url = format!("http://{}/?token=browser-test", server.addr());
    driver.call("POST", "/url", json!({"url": url})).await;
    let wait_for = async |driver: &Driver, what: &str, js: &str| {
        let start = Instant::now();
        loop {
            let v = driver.script(js).await;
            if v.as_bool() == Some(true) {
                return;
            }
            assert!(
                start.elapsed() < Duration::from_secs(30),
                "timed out waiting for {what}"
            );
            tokio::time::sleep(Duration::from_millis(100)).await;
        }
    };
    // Wait until the view has refined (nothing more is coming).
    wait_for(&driver, "the refined frame", "return !!(window.raykit && window.raykit.lastHeader && window.raykit.lastHeader.stage === 'refined')").await;
    let before_camera = driver
        .script("return window.raykit.lastHeader.camera")
        .await;
    let before_frames = driver
        .script("return window.raykit.frames")
        .await
        .as_u64()
        .unwrap();
    let before = thumbnail(&driver.script(THUMBNAIL).await);

    let canvas = driver
        .call(
            "POST",
            "/element",
            json!({"using": "css selector", "value": "#view"}),
        )
        .await;
    let id = canvas[ELEMENT]
        .as_str()
        .unwrap_or_else(|| panic!("canvas element: {canvas}"))
        .to_string();
    let mut origin = serde_json::Map::new();
    origin.insert(ELEMENT.to_string(), Value::String(id));
    let drag = json!({"actions": [{"type": "pointer", "id": "mouse", "parameters": {"pointerType": "mouse"},
        "actions": [
            {"type": "pointerMove", "duration": 0, "origin": origin, "x": 0, "y": 0},
            {"type": "pointerDown", "button": 0},
            {"type": "pointerMove", "duration": 250, "origin": "pointer", "x": 60, "y": 10},
            {"type": "pointerMove", "duration": 250, "origin": "pointer", "x": 60, "y": 10},
            {"type": "pointerUp", "button": 0}]}]});
    driver.call("POST", "/actions", drag).await;
    wait_for(&driver, "a frame after the drag",
        &format!("const h = window.raykit.lastHeader; return window.raykit.frames > {before_frames} && h.input_seq > 0 && h.stage === 'refined'")).await;
    let after_camera = driver
        .script("return window.raykit.lastHeader.camera")
        .await;
    let after = thumbnail(&driver.script(THUMBNAIL).await);
    assert_ne!(
        before_camera["eye"], after_camera["eye"],
        "the drag did not move the camera"
    );
    assert_eq!(
        before_camera["target"], after_camera["target"],
        "an orbit keeps the target"
    );
    let diff = before
        .iter()
        .zip(&after)
        .map(|(a, b)| (a - b).abs())
        .sum::<f64>()
        / before.len() as f64;
    eprintln!("mean luminance change after the drag: {diff:.1} / 255");
    assert!(diff > 2.0, "the picture did not change ({diff})");
    // The server saw the browser's inputs and no errors.
    let errors = driver.script("return window.raykit.errors").await;
    assert_eq!(errors, json!([]), "client errors");
    let sample = &server.state().samples()[0];
    assert!(
        sample.inputs > 0 && sample.errors == 0,
        "inputs {} errors {}",
        sample.inputs,
        sample.errors
    );

    webdriver(
        addr,
        "DELETE",
        &format!("/session/{}", driver.session),
        Value::Null,
    )
    .await;
    driver.session.clear();
    drop(driver);
    server.shutdown().await.unwrap();
}
