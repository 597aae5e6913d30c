//! A real browser for the studio's tests: Debian's headless Chromium driven through its
//! chromedriver (WebDriver, which chromedriver carries out over the DevTools protocol),
//! with software WebGL (SwiftShader), a fresh profile and a download folder of its own.
//! `.ci/run` installs both packages (tools/install-browser.sh). The browser tests run one
//! at a time: two Chromiums on two cores would only slow each other down.

use std::net::TcpListener;
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::{Mutex, PoisonError};
use std::time::{Duration, Instant};

use fantoccini::{Client, ClientBuilder, Locator};
use hyper_util::client::legacy::connect::HttpConnector;
use serde_json::{Value, json};

static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

/// The browser and driver binaries (Debian's paths unless the environment says otherwise).
fn binaries() -> (PathBuf, PathBuf) {
    let chromium = std::env::var_os("ISOFORGE_CHROMIUM")
        .map_or_else(|| PathBuf::from("/usr/bin/chromium"), PathBuf::from);
    let driver = std::env::var_os("ISOFORGE_CHROMEDRIVER")
        .map_or_else(|| PathBuf::from("/usr/bin/chromedriver"), PathBuf::from);
    assert!(
        chromium.exists() && driver.exists(),
        "the studio's browser tests need chromium and chromedriver: run tools/install-browser.sh \
         (apt-get install chromium chromium-driver)"
    );
    (chromium, driver)
}

fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .map(|a| a.port())
        .expect("a free port")
}

/// A headless Chromium session.
pub struct Browser {
    pub client: Client,
    driver: Child,
    _profile: tempfile::TempDir,
    pub downloads: tempfile::TempDir,
}

impl Browser {
    pub async fn start() -> Browser {
        let (chromium, driver_bin) = binaries();
        let port = free_port();
        // Its own process group, so the browsers it starts go with it (see `Drop`).
        let driver = Command::new(driver_bin)
            .process_group(0)
            .arg(format!("--port={port}"))
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("chromedriver starts");
        let profile = tempfile::tempdir().expect("profile dir");
        let downloads = tempfile::tempdir().expect("download dir");
        let caps = json!({
            "browserName": "chrome",
            "goog:chromeOptions": {
                "binary": chromium,
                "args": [
                    "--headless",
                    "--no-sandbox",
                    "--use-angle=swiftshader",
                    "--enable-unsafe-swiftshader",
                    "--disable-background-networking",
                    "--disable-component-update",
                    "--disable-sync",
                    "--no-first-run",
                    "--disable-dev-shm-usage",
                    format!("--user-data-dir={}", profile.path().display()),
                    "--window-size=1400,900",
                ],
                "prefs": {
                    "download.default_directory": downloads.path(),
                    "download.prompt_for_download": false,
                },
            },
        });
        let caps = match caps {
            Value::Object(map) => map,
            _ => unreachable!(),
        };
        let url = format!("http://127.0.0.1:{port}");
        let deadline = Instant::now() + Duration::from_secs(30);
        let client = loop {
            match ClientBuilder::new(HttpConnector::new())
                .capabilities(caps.clone())
                .connect(&url)
                .await
            {
                Ok(c) => break c,
                Err(e) if Instant::now() < deadline => {
                    let _ = e;
                    tokio::time::sleep(Duration::from_millis(200)).await;
                }
                Err(e) => panic!("cannot start a browser session: {e}"),
            }
        };
        Browser {
            client,
            driver,
            _profile: profile,
            downloads,
        }
    }

    /// Runs JavaScript in the page and returns its value.
    pub async fn js(&self, script: &str) -> Value {
        self.client
            .execute(script, vec![])
            .await
            .unwrap_or_else(|e| panic!("{script}: {e}"))
    }

    /// Waits until a JavaScript expression is truthy, up to `seconds`.
    pub async fn wait_until(&self, what: &str, expression: &str, seconds: u64) -> Value {
        let deadline = Instant::now() + Duration::from_secs(seconds);
        loop {
            let v = self.js(&format!("return ({expression});")).await;
            let truthy = match &v {
                Value::Null => false,
                Value::Bool(b) => *b,
                Value::Number(n) => n.as_f64() != Some(0.0),
                Value::String(s) => !s.is_empty(),
                _ => true,
            };
            if truthy {
                return v;
            }
            if Instant::now() > deadline {
                let problem = self.js("return document.getElementById('problem').textContent + ' | ' + document.getElementById('busy').textContent").await;
                panic!("timed out waiting for {what} ({expression}); page says: {problem}");
            }
            tokio::time::sleep(Duration::from_millis(50)).await;
        }
    }

    /// A PNG screenshot of one element.
    pub async fn screenshot(&self, css: &str) -> Vec<u8> {
        self.client
            .find(Locator::Css(css))
            .await
            .expect("element")
            .screenshot()
            .await
            .expect("screenshot")
    }

    /// Waits for a finished download with this extension and returns its path.
    pub async fn downloaded(&self, extension: &str) -> PathBuf {
        let deadline = Instant::now() + Duration::from_secs(60);
        loop {
            let found = std::fs::read_dir(self.downloads.path())
                .expect("downloads")
                .filter_map(Result::ok)
                .map(|e| e.path())
                .find(|p| p.extension().is_some_and(|e| e == extension));
            if let Some(p) = found {
                return p;
            }
            assert!(Instant::now() < deadline, "no .{extension} downloaded");
            tokio::time::sleep(Duration::from_millis(100)).await;
        }
    }

    pub async fn close(self) {
        let _ = self.client.clone().close().await;
    }
}

impl Drop for Browser {
    /// Ends chromedriver and every browser process it started (its process group), also
    /// when a test fails half-way.
    fn drop(&mut self) {
        let _ = Command::new("kill")
            .args(["-KILL", "--", &format!("-{}", self.driver.id())])
            .status();
        let _ = self.driver.wait();
    }
}

/// Decodes a PNG into RGBA pixels.
pub fn pixels(png_bytes: &[u8]) -> (usize, usize, Vec<[u8; 4]>) {
    let mut decoder = png::Decoder::new(std::io::Cursor::new(png_bytes));
    decoder.set_transformations(png::Transformations::normalize_to_color8());
    let mut reader = decoder.read_info().expect("png");
    let mut buf = vec![0; reader.output_buffer_size().expect("size")];
    let info = reader.next_frame(&mut buf).expect("frame");
    let channels = info.color_type.samples();
    let px = buf[..info.buffer_size()]
        .chunks(channels)
        .map(|c| match channels {
            4 => [c[0], c[1], c[2], c[3]],
            3 => [c[0], c[1], c[2], 255],
            _ => [c[0], c[0], c[0], 255],
        })
        .collect();
    (info.width as usize, info.height as usize, px)
}

/// The share of pixels in the model's colour (orange shading: red well above blue), as
/// opposed to the background, the plate and its grid (greys and blue-greys).
pub fn model_share(png_bytes: &[u8]) -> f64 {
    let (_, _, px) = pixels(png_bytes);
    let model = px
        .iter()
        .filter(|p| i32::from(p[0]) - i32::from(p[2]) > 40)
        .count();
    model as f64 / px.len() as f64
}

/// Runs one browser test's body on a runtime of its own, one test at a time.
pub fn run<F: std::future::Future<Output = ()>>(body: F) {
    let _turn = ONE_AT_A_TIME.lock().unwrap_or_else(PoisonError::into_inner);
    tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .expect("runtime")
        .block_on(body)
}

/// Copies a file into a folder and returns the copy's path.
pub fn copy_into(file: &Path, folder: &Path) -> PathBuf {
    let to = folder.join(file.file_name().expect("a file name"));
    std::fs::copy(file, &to).expect("copy");
    to
}
