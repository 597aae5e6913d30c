//! The studio's page in a real browser: it shows the model, re-meshes on typing and on a
//! slider, places syntax errors, downloads the same STL `isoforge mesh` writes, reloads a
//! file changed on disk, and prints to the fake printer with every line executed once.

use std::path::Path;

use fantoccini::Locator;
use fantoccini::key::Key;
use isoforge_host::gcode;
use serde_json::Value;

use crate::browser::{Browser, copy_into, model_share, pixels, run};
use crate::studio_process::StudioProcess;
use crate::{fixtures, isoforge};

/// The page has shown the newest edit's preview, coarse and fine, and nothing is pending.
const SETTLED: &str = "window.studio && document.body.dataset.ready === '1' \
    && !studio.typingPending && studio.doneJob === studio.job && !studio.coarseBusy && !studio.fine \
    && (document.body.dataset.previewJob == studio.job || !document.getElementById('problem').hidden)";

async fn settle(b: &Browser) {
    b.wait_until("the preview", SETTLED, 120).await;
}

async fn number(b: &Browser, expression: &str) -> f64 {
    match b.js(&format!("return Number({expression});")).await {
        Value::Number(n) => n.as_f64().expect("a number"),
        other => panic!("{expression} is {other}"),
    }
}

async fn triangles(b: &Browser) -> f64 {
    number(b, "document.getElementById('fact-triangles').dataset.value").await
}

async fn volume(b: &Browser) -> f64 {
    number(b, "document.getElementById('fact-volume').dataset.value").await
}

/// Replaces the editor's text by typing it, as a person would.
async fn type_script(b: &Browser, text: &str) {
    let editor = b.client.find(Locator::Id("editor")).await.expect("editor");
    editor.clear().await.expect("clear");
    editor.send_keys(text).await.expect("typing");
}

fn ball_folder() -> tempfile::TempDir {
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(
        dir.path().join("ball.rhai"),
        "// a ball with a knob\nbounds([-3, -3, -3], [3, 3, 3]);\nlet r = param(\"r\", 1.5, 0.5, 2.5);\nSphere(r)\n",
    )
    .expect("model");
    dir
}

/// The share of pixels that differ between two screenshots of the same size.
fn changed_share(a: &[u8], b: &[u8]) -> f64 {
    let (_, _, pa) = pixels(a);
    let (_, _, pb) = pixels(b);
    assert_eq!(pa.len(), pb.len());
    let changed = pa
        .iter()
        .zip(&pb)
        .filter(|(x, y)| x.iter().zip(y.iter()).any(|(u, v)| u.abs_diff(*v) > 24))
        .count();
    changed as f64 / pa.len() as f64
}

#[test]
fn the_page_shows_a_classic_model() {
    run(async {
        let dir = tempfile::tempdir().expect("temp dir");
        let model = copy_into(&fixtures().join("classic/heart.rhai"), dir.path());
        let studio = StudioProcess::start(&model);
        let b = Browser::start().await;
        b.client.goto(&studio.url).await.expect("page");
        settle(&b).await;
        let shot = b.screenshot("#view").await;
        let share = model_share(&shot);
        assert!(
            share > 0.02,
            "the view shows no model: {share:.4} of its pixels are the model's colour"
        );
        assert!(triangles(&b).await > 1000.0);
        let closed = b
            .js("return document.getElementById('fact-closed').textContent")
            .await;
        assert_eq!(closed, "closed, manifold");
        // The heart has no part thinner than the cells at either depth.
        let thin = b
            .js("return document.getElementById('fact-thin').textContent")
            .await;
        assert_eq!(thin, "none");
        // The README's picture is made here, with the layer view open beside the model.
        if let Some(out) = std::env::var_os("ISOFORGE_STUDIO_SCREENSHOT") {
            b.client
                .find(Locator::Id("slice"))
                .await
                .unwrap()
                .click()
                .await
                .unwrap();
            b.wait_until(
                "the layer view",
                "!document.getElementById('layers-box').hidden",
                120,
            )
            .await;
            tokio::time::sleep(std::time::Duration::from_millis(500)).await;
            std::fs::write(out, b.client.screenshot().await.expect("screenshot")).expect("write");
        }
        b.close().await;
    });
}

#[test]
fn typing_a_change_remeshes_the_preview() {
    run(async {
        let dir = tempfile::tempdir().expect("temp dir");
        let model = copy_into(&fixtures().join("classic/heart.rhai"), dir.path());
        let studio = StudioProcess::start(&model);
        let b = Browser::start().await;
        b.client.goto(&studio.url).await.expect("page");
        settle(&b).await;
        let before = (triangles(&b).await, b.screenshot("#view").await);
        type_script(
            &b,
            "bounds([-1.5, -1.5, -1.5], [1.5, 1.5, 1.5]);\nSphere(1.2)",
        )
        .await;
        settle(&b).await;
        let after = (triangles(&b).await, b.screenshot("#view").await);
        assert_ne!(before.0, after.0, "the triangle count did not change");
        let changed = changed_share(&before.1, &after.1);
        assert!(changed > 0.01, "the view hardly changed: {changed:.4}");
        let v = volume(&b).await;
        let sphere = 4.0 / 3.0 * std::f64::consts::PI * 1.2f64.powi(3);
        assert!(
            (v - sphere).abs() < 0.02 * sphere,
            "volume {v}, a sphere of 1.2 has {sphere}"
        );
        // Typed, not saved: the file on disk is the fixture still.
        let disk = std::fs::read_to_string(&model).unwrap();
        assert!(disk.contains("Heart("), "{disk}");
        b.close().await;
    });
}

#[test]
fn a_syntax_error_is_shown_at_its_line() {
    run(async {
        let dir = ball_folder();
        let studio = StudioProcess::start(&dir.path().join("ball.rhai"));
        let b = Browser::start().await;
        b.client.goto(&studio.url).await.expect("page");
        settle(&b).await;
        type_script(
            &b,
            "bounds([-2, -2, -2], [2, 2, 2]);\nlet a = 1;\nlet b = ;\nSphere(a)",
        )
        .await;
        settle(&b).await;
        let line = b
            .js("return document.getElementById('problem').dataset.line")
            .await;
        assert_eq!(line, "3", "the error is not placed at line 3");
        let text = b
            .js("return document.getElementById('problem').textContent")
            .await;
        assert!(
            text.as_str().unwrap_or("").starts_with("line 3, column"),
            "{text}"
        );
        let marked = b
            .js("return [...document.querySelectorAll('#gutter .err')].map(e => e.textContent)")
            .await;
        assert_eq!(marked, serde_json::json!(["3"]));
        // Fixed, the mark goes and the model is back.
        type_script(&b, "bounds([-2, -2, -2], [2, 2, 2]);\nSphere(1)").await;
        settle(&b).await;
        assert_eq!(
            b.js("return document.getElementById('problem').hidden")
                .await,
            Value::Bool(true)
        );
        assert_eq!(
            b.js("return document.querySelectorAll('#gutter .err').length")
                .await,
            0
        );
        b.close().await;
    });
}

/// Presses a key on the slider of parameter `name`, `times` times.
async fn nudge(b: &Browser, name: &str, key: Key, times: usize) {
    let slider = b
        .client
        .find(Locator::Css(&format!(
            "input[type=range][aria-label='{name}']"
        )))
        .await
        .expect("the parameter's slider");
    let keys: String = std::iter::repeat_n(char::from(key), times).collect();
    slider.send_keys(&keys).await.expect("keys");
}

#[test]
fn moving_a_slider_changes_the_mesh() {
    run(async {
        let dir = ball_folder();
        let studio = StudioProcess::start(&dir.path().join("ball.rhai"));
        let b = Browser::start().await;
        b.client.goto(&studio.url).await.expect("page");
        settle(&b).await;
        let v0 = volume(&b).await;
        let shot0 = b.screenshot("#view").await;
        nudge(&b, "r", Key::Right, 30).await;
        settle(&b).await;
        let r = number(
            &b,
            "document.querySelector(\"input[type=range][aria-label='r']\").value",
        )
        .await;
        assert!((r - 1.8).abs() < 1e-9, "slider at {r}");
        let v1 = volume(&b).await;
        let expected = (1.8f64 / 1.5).powi(3);
        assert!(
            (v1 / v0 - expected).abs() < 0.03,
            "volume {v0} -> {v1}, expected x{expected}"
        );
        let changed = changed_share(&shot0, &b.screenshot("#view").await);
        assert!(changed > 0.005, "the view hardly changed: {changed:.4}");
        // The number box follows the slider.
        let shown = number(
            &b,
            "document.querySelector(\"input[type=number][aria-label='r value']\").value",
        )
        .await;
        assert_eq!(shown, r);
        b.close().await;
    });
}

#[test]
fn the_downloaded_stl_is_what_isoforge_mesh_writes() {
    run(async {
        let dir = ball_folder();
        let model = dir.path().join("ball.rhai");
        let studio = StudioProcess::start(&model);
        let b = Browser::start().await;
        b.client.goto(&studio.url).await.expect("page");
        settle(&b).await;
        nudge(&b, "r", Key::Left, 7).await;
        b.client
            .find(Locator::Id("fine-depth"))
            .await
            .expect("depth")
            .select_by_value("7")
            .await
            .expect("select");
        settle(&b).await;
        let r = b
            .js("return document.querySelector(\"input[type=range][aria-label='r']\").value")
            .await;
        let r = r.as_str().expect("a value").to_string();
        assert_eq!(r, "1.43");
        b.client
            .find(Locator::Id("export"))
            .await
            .unwrap()
            .click()
            .await
            .unwrap();
        let downloaded = b.downloaded("stl").await;
        let ours = dir.path().join("cli.stl");
        let out = isoforge(&[
            "mesh",
            model.to_str().unwrap(),
            "--param",
            &format!("r={r}"),
            "--depth",
            "7",
            "-o",
            ours.to_str().unwrap(),
        ]);
        assert!(out.status.success(), "{out:?}");
        let (a, c) = (
            std::fs::read(&downloaded).unwrap(),
            std::fs::read(&ours).unwrap(),
        );
        assert!(a.len() > 84, "an empty STL");
        assert!(
            a == c,
            "the download ({} bytes) differs from isoforge mesh's ({} bytes)",
            a.len(),
            c.len()
        );
        b.close().await;
    });
}

#[test]
fn a_change_on_disk_is_reloaded() {
    run(async {
        let dir = ball_folder();
        let model = dir.path().join("ball.rhai");
        let studio = StudioProcess::start(&model);
        let b = Browser::start().await;
        b.client.goto(&studio.url).await.expect("page");
        settle(&b).await;
        let t0 = triangles(&b).await;
        std::fs::write(&model, "bounds([-3, -3, -3], [3, 3, 3]);\nCube(2)\n").unwrap();
        b.wait_until(
            "the new text",
            "document.getElementById('editor').value.includes('Cube(2)')",
            30,
        )
        .await;
        settle(&b).await;
        assert_eq!(
            b.js("return document.getElementById('problem').hidden")
                .await,
            Value::Bool(true)
        );
        assert_ne!(triangles(&b).await, t0);
        let v = volume(&b).await;
        assert!((v - 8.0).abs() < 0.05, "a 2 mm cube has 8 mm³, not {v}");
        // A reloaded page is not taken for an older edit: it gets its preview.
        b.client.refresh().await.expect("reload");
        settle(&b).await;
        assert_eq!(
            b.js("return document.getElementById('problem').hidden")
                .await,
            Value::Bool(true)
        );
        assert!((volume(&b).await - 8.0).abs() < 0.05);
        b.close().await;
    });
}

/// Numbered commands the fake printer executed, M110 (line-number resets) aside.
fn executed_job(executed: &Value) -> Vec<(u64, String)> {
    executed
        .as_array()
        .expect("a list")
        .iter()
        .filter_map(|e| Some((e["line"].as_u64()?, e["command"].as_str()?.to_string())))
        .filter(|(_, c)| !c.starts_with("M110"))
        .collect()
}

#[test]
fn printing_to_the_fake_printer_runs_every_line_once() {
    run(async {
        let dir = ball_folder();
        let studio = StudioProcess::start(&dir.path().join("ball.rhai"));
        let b = Browser::start().await;
        b.client.goto(&studio.url).await.expect("page");
        settle(&b).await;
        b.client
            .find(Locator::Id("fake-start"))
            .await
            .unwrap()
            .click()
            .await
            .unwrap();
        b.wait_until("the fake printer's port", "document.getElementById('port').selectedOptions[0]?.textContent.includes('fake printer')", 30).await;
        b.client
            .find(Locator::Id("print-start"))
            .await
            .unwrap()
            .click()
            .await
            .unwrap();
        b.wait_until("the print to end", "['completed','failed','cancelled'].includes(document.getElementById('print-state').dataset.state)", 180).await;
        let state = b
            .js("return document.getElementById('print-state').textContent")
            .await;
        assert!(
            state
                .as_str()
                .unwrap_or("")
                .starts_with("completed: 100.0%"),
            "{state}"
        );
        assert_eq!(
            b.js("return document.getElementById('print-progress').value")
                .await,
            100
        );
        // Printing sliced it first: the layer view scrubs through the layers.
        assert!(number(&b, "document.getElementById('layers').dataset.extrusions").await > 0.0);
        let scrub = b.client.find(Locator::Id("layer")).await.unwrap();
        scrub
            .send_keys(&char::from(Key::Home).to_string())
            .await
            .unwrap();
        assert_eq!(
            number(&b, "document.getElementById('layers').dataset.layer").await,
            0.0
        );
        scrub
            .send_keys(&char::from(Key::End).to_string())
            .await
            .unwrap();
        let last = number(&b, "document.getElementById('layers').dataset.layer").await;
        assert_eq!(
            last,
            number(&b, "document.getElementById('layer').max").await
        );
        // What the printer executed is the file, line by line, each line once.
        let executed = b
            .js("return fetch('/api/fake-printer/executed').then(r => r.json())")
            .await;
        let job = executed_job(&executed);
        let gcode_file = dir.path().join("ball.gcode");
        let program = gcode::read_file(&gcode_file).expect("the sliced file");
        let want: Vec<&str> = program.commands.iter().map(|c| c.text.as_str()).collect();
        let got: Vec<&str> = job.iter().map(|(_, c)| c.as_str()).collect();
        assert_eq!(
            got.len(),
            want.len(),
            "executed {} of {} commands",
            got.len(),
            want.len()
        );
        assert!(got == want, "the executed commands differ from the file");
        let mut lines: Vec<u64> = job.iter().map(|(n, _)| *n).collect();
        lines.dedup();
        assert_eq!(lines.len(), job.len(), "a line executed twice");
        // The same journal as `isoforge print`, finished.
        let journal =
            std::fs::read_to_string(dir.path().join("ball.gcode.journal")).expect("journal");
        assert!(journal.contains("\"completed\""), "{journal}");
        assert!(!Path::new(&dir.path().join("ball.stl")).exists());
        b.close().await;
    });
}

/// A classic model with one knob: the script's last expression scaled by `param("scale")`,
/// so a slider re-runs the script and re-meshes a changed shape, as any knob does.
fn with_scale_knob(text: &str) -> String {
    let cut = text.rfind(';').expect("a statement before the model");
    format!(
        "{}\nScaleXYZ({}, param(\"scale\", 1.0, 0.5, 1.0))\n",
        &text[..=cut],
        text[cut + 1..].trim()
    )
}

/// The preview latency bench (tools/studio-latency.sh runs it in release): for every
/// classic model, the time from a slider's input event to the coarse preview on screen,
/// measured in the page with performance marks (`edit-N` to the frame after the draw).
/// Two ways: the slider moved from rest (the fine preview done before each move), and
/// dragged (a move every 60 ms, the fine previews cancelled). The slider is set by script
/// (one input event per position, as a drag makes), not by keys, to move it by whole
/// percents.
#[test]
#[ignore = "a benchmark: tools/studio-latency.sh runs it in release"]
fn preview_latency() {
    run(async {
        let mut report = String::from(
            "| model | coarse triangles | from rest: median / max ms | of which request / mesh / upload / frames (median ms) | dragged: median / max ms |\n| --- | ---: | ---: | ---: | ---: |\n",
        );
        let b = Browser::start().await;
        let mut names: Vec<_> = std::fs::read_dir(fixtures().join("classic"))
            .unwrap()
            .filter_map(Result::ok)
            .map(|e| e.path())
            .filter(|p| p.extension().is_some_and(|e| e == "rhai"))
            .filter(|p| {
                // ISOFORGE_LATENCY_MODELS=heart,spaceship picks some.
                std::env::var("ISOFORGE_LATENCY_MODELS").map_or(true, |only| {
                    only.split(',')
                        .any(|n| p.file_stem().is_some_and(|s| s.to_string_lossy() == n))
                })
            })
            .collect();
        names.sort();
        for path in names {
            let name = path.file_stem().unwrap().to_string_lossy().to_string();
            let dir = tempfile::tempdir().unwrap();
            let model = dir.path().join(format!("{name}.rhai"));
            std::fs::write(
                &model,
                with_scale_knob(&std::fs::read_to_string(&path).unwrap()),
            )
            .unwrap();
            let studio = StudioProcess::start(&model);
            b.client.goto(&studio.url).await.expect("page");
            settle(&b).await;
            let set = |v: f64| {
                format!(
                    "const s = document.querySelector(\"input[type=range][aria-label='scale']\"); \
                     s.value = {v}; s.dispatchEvent(new Event('input')); return studio.latencies.length;"
                )
            };
            let mut rest = Vec::new();
            let mut parts: [Vec<f64>; 4] = Default::default();
            for i in 1..=8 {
                let before = b
                    .js(&set(1.0 - 0.01 * f64::from(i)))
                    .await
                    .as_u64()
                    .unwrap();
                b.wait_until(
                    "the coarse preview",
                    &format!("studio.latencies.length > {before}"),
                    60,
                )
                .await;
                settle(&b).await;
                let last = "studio.latencies[studio.latencies.length - 1]";
                rest.push(number(&b, &format!("{last}.ms")).await);
                for (k, field) in ["requestMs", "meshMs", "uploadMs", "frameMs"]
                    .iter()
                    .enumerate()
                {
                    parts[k].push(number(&b, &format!("{last}.{field}")).await);
                }
            }
            let triangles = number(
                &b,
                "studio.latencies[studio.latencies.length - 1].triangles",
            )
            .await;
            let before = number(&b, "studio.latencies.length").await as usize;
            for i in 1..=8 {
                b.js(&set(0.9 - 0.01 * f64::from(i))).await;
                tokio::time::sleep(std::time::Duration::from_millis(60)).await;
            }
            settle(&b).await;
            let all = b.js("return studio.latencies.map(l => l.ms)").await;
            let dragged: Vec<f64> = all.as_array().unwrap()[before..]
                .iter()
                .filter_map(Value::as_f64)
                .collect();
            let stats = |v: &[f64]| {
                let mut s = v.to_vec();
                s.sort_by(f64::total_cmp);
                (s[s.len() / 2], s[s.len() - 1])
            };
            let (rm, rx) = stats(&rest);
            let (dm, dx) = stats(&dragged);
            let p: Vec<String> = parts.iter().map(|v| format!("{:.0}", stats(v).0)).collect();
            let row = format!(
                "| {name} | {triangles} | {rm:.0} / {rx:.0} | {} | {dm:.0} / {dx:.0} |\n",
                p.join(" / ")
            );
            print!("{row}");
            report.push_str(&row);
            drop(studio);
        }
        b.close().await;
        println!("\n{report}");
        if let Some(out) = std::env::var_os("ISOFORGE_LATENCY_OUT") {
            std::fs::write(out, report).expect("write the report");
        }
    });
}
