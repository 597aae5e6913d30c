//! `isoforge studio` as a server: who is let in, what it reads and writes, and what it
//! refuses to listen on. (The page itself is tested in a browser: `studio_browser`.)

use crate::isoforge;
use crate::studio_process::StudioProcess;

fn folder_with_model() -> tempfile::TempDir {
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(
        dir.path().join("ball.rhai"),
        "bounds([-2, -2, -2], [2, 2, 2]);\nSphere(param(\"r\", 1, 0.5, 1.5))\n",
    )
    .expect("model");
    dir
}

#[test]
fn requests_without_the_token_are_refused() {
    let dir = folder_with_model();
    let studio = StudioProcess::start(&dir.path().join("ball.rhai"));
    for target in [
        "/",
        "/api/session",
        "/api/file?name=ball.rhai",
        "/assets/studio.js",
    ] {
        let (status, _) = studio.request("GET", target, &[], "");
        assert_eq!(status, 403, "{target} without a token");
        let wrong = format!(
            "{target}{}token=00000000000000000000000000000000",
            if target.contains('?') { "&" } else { "?" }
        );
        assert_eq!(studio.request("GET", &wrong, &[], "").0, 403, "{wrong}");
    }
    // With it: the page (by the cookie the first load sets) and the API.
    let cookie = format!(
        "isoforge_studio_{}={}",
        studio.authority.rsplit(':').next().unwrap(),
        studio.token
    );
    let (status, body) = studio.request(
        "GET",
        "/api/file?name=ball.rhai",
        &[("cookie", &cookie)],
        "",
    );
    assert_eq!(status, 200, "{body}");
    assert!(body.contains("Sphere(param"), "{body}");
    let (status, _) = studio.request("GET", &format!("/?token={}", studio.token), &[], "");
    assert_eq!(status, 303, "the token is traded for a cookie");
    // The token is no use through a foreign host name (DNS rebinding) or from another site.
    let (status, _) = studio.request(
        "GET",
        "/api/session",
        &[("cookie", &cookie), ("host", "evil.example")],
        "",
    );
    assert_eq!(status, 421);
    let (status, _) = studio.request(
        "PUT",
        "/api/file",
        &[
            ("cookie", &cookie),
            ("origin", "http://evil.example"),
            ("content-type", "application/json"),
        ],
        r#"{"name":"ball.rhai","text":"Sphere(9)","force":true}"#,
    );
    assert_eq!(status, 403);
    assert!(
        std::fs::read_to_string(dir.path().join("ball.rhai"))
            .unwrap()
            .contains("param")
    );
}

#[test]
fn paths_outside_the_models_folder_are_refused() {
    let dir = folder_with_model();
    let outside = tempfile::tempdir().expect("temp dir");
    std::fs::write(outside.path().join("secret.rhai"), "Sphere(1) // secret").unwrap();
    std::os::unix::fs::symlink(
        outside.path().join("secret.rhai"),
        dir.path().join("link.rhai"),
    )
    .unwrap();
    let studio = StudioProcess::start(&dir.path().join("ball.rhai"));
    let cookie = format!(
        "isoforge_studio_{}={}",
        studio.authority.rsplit(':').next().unwrap(),
        studio.token
    );
    let auth = [
        ("cookie", cookie.as_str()),
        ("content-type", "application/json"),
    ];
    let secret = outside.path().join("secret.rhai");
    let secret = secret.to_str().unwrap();
    let escaping = [
        "../secret.rhai".to_string(),
        "..%2Fsecret.rhai".to_string(),
        secret.to_string(),
        "link.rhai".to_string(),
        "sub/ball.rhai".to_string(),
    ];
    for name in &escaping {
        let (status, body) = studio.request("GET", &format!("/api/file?name={name}"), &auth, "");
        assert_eq!(status, 403, "read {name}: {body}");
        assert!(!body.contains("// secret"), "{body}");
        let save =
            serde_json::json!({"name": name, "text": "Sphere(2)", "force": true}).to_string();
        let (status, body) = studio.request("PUT", "/api/file", &auth, &save);
        assert_eq!(status, 403, "write {name}: {body}");
        let preview = serde_json::json!({"name": name, "text": "Sphere(1)", "depth": 4, "job": 1})
            .to_string();
        assert_eq!(
            studio.request("POST", "/api/preview", &auth, &preview).0,
            403,
            "{name}"
        );
    }
    assert_eq!(
        std::fs::read_to_string(outside.path().join("secret.rhai")).unwrap(),
        "Sphere(1) // secret"
    );
    // Only models open in the editor: not the folder's other files.
    std::fs::write(dir.path().join("notes.txt"), "n").unwrap();
    assert_eq!(
        studio
            .request("GET", "/api/file?name=notes.txt", &auth, "")
            .0,
        403
    );
    // A serial "port" that is not one is refused before anything is opened.
    let print = serde_json::json!({"file": "ball.gcode", "port": "/etc/passwd"}).to_string();
    let (status, body) = studio.request("POST", "/api/print", &auth, &print);
    assert_eq!(status, 403, "{body}");
}

#[test]
fn a_saved_script_is_written_whole_into_the_folder() {
    let dir = folder_with_model();
    let studio = StudioProcess::start(&dir.path().join("ball.rhai"));
    let cookie = format!(
        "isoforge_studio_{}={}",
        studio.authority.rsplit(':').next().unwrap(),
        studio.token
    );
    let auth = [
        ("cookie", cookie.as_str()),
        ("content-type", "application/json"),
    ];
    let (_, body) = studio.request("GET", "/api/file?name=ball.rhai", &auth, "");
    let version = serde_json::from_str::<serde_json::Value>(&body).unwrap()["version"].clone();
    let save = serde_json::json!({"name": "ball.rhai", "text": "Sphere(1.25)\n", "base": version})
        .to_string();
    let (status, body) = studio.request("PUT", "/api/file", &auth, &save);
    assert_eq!(status, 200, "{body}");
    assert_eq!(
        std::fs::read_to_string(dir.path().join("ball.rhai")).unwrap(),
        "Sphere(1.25)\n"
    );
    // Saving over a version the page never saw (another editor changed it) is a conflict.
    let (status, _) = studio.request("PUT", "/api/file", &auth, &save);
    assert_eq!(status, 409);
    let leftovers: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .filter_map(Result::ok)
        .map(|e| e.file_name())
        .collect();
    assert_eq!(leftovers.len(), 1, "{leftovers:?}");
}

#[test]
fn a_remote_address_needs_allow_remote() {
    let dir = folder_with_model();
    let model = dir.path().join("ball.rhai");
    let out = isoforge(&["studio", model.to_str().unwrap(), "--host", "0.0.0.0"]);
    assert_eq!(out.status.code(), Some(2), "{out:?}");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--allow-remote"), "{err}");
}

#[test]
fn a_missing_model_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let out = isoforge(&["studio", dir.path().join("none.rhai").to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1), "{out:?}");
    assert!(String::from_utf8_lossy(&out.stderr).contains("no such file"));
}

/// Calls the API with the session cookie; the body as JSON.
fn api(
    studio: &StudioProcess,
    method: &str,
    target: &str,
    body: &serde_json::Value,
) -> (u16, serde_json::Value) {
    let cookie = format!(
        "isoforge_studio_{}={}",
        studio.authority.rsplit(':').next().unwrap(),
        studio.token
    );
    let text = if body.is_null() {
        String::new()
    } else {
        body.to_string()
    };
    let (status, reply) = studio.request(
        method,
        target,
        &[("cookie", &cookie), ("content-type", "application/json")],
        &text,
    );
    (
        status,
        serde_json::from_str(&reply).unwrap_or(serde_json::Value::Null),
    )
}

fn wait_for_state(studio: &StudioProcess, states: &[&str]) -> serde_json::Value {
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(120);
    loop {
        let (_, r) = api(studio, "GET", "/api/print", &serde_json::Value::Null);
        let state = r["status"]["state"].as_str().unwrap_or("").to_string();
        if states.contains(&state.as_str()) {
            return r["status"].clone();
        }
        assert!(std::time::Instant::now() < deadline, "still {state}: {r}");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
}

#[test]
fn a_cancelled_print_resumes_from_its_journal() {
    let dir = folder_with_model();
    let studio = StudioProcess::start(&dir.path().join("ball.rhai"));
    let text = std::fs::read_to_string(dir.path().join("ball.rhai")).unwrap();
    let (status, sliced) = api(
        &studio,
        "POST",
        "/api/slice",
        &serde_json::json!({"name": "ball.rhai", "text": text, "params": [["r", 1.5]], "profile": "builtin:generic_marlin_220.toml"}),
    );
    assert_eq!(status, 200, "{sliced}");
    assert_eq!(sliced["file"], "ball.gcode");
    let (_, fake) = api(&studio, "POST", "/api/fake-printer", &serde_json::json!({}));
    let port = fake["path"]
        .as_str()
        .expect("the fake printer's path")
        .to_string();
    let (_, ports) = api(&studio, "GET", "/api/ports", &serde_json::Value::Null);
    assert!(
        ports
            .as_array()
            .unwrap()
            .iter()
            .any(|p| p["path"] == port.as_str() && p["kind"] == "fake")
    );
    let start = serde_json::json!({"file": "ball.gcode", "port": port});
    let (status, r) = api(&studio, "POST", "/api/print", &start);
    assert_eq!(status, 200, "{r}");
    // Paused while the fake printer heats up (a quarter of a second), then cancelled.
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(60);
    while api(&studio, "GET", "/api/print", &serde_json::Value::Null).1["status"]["executed"] == 0 {
        assert!(std::time::Instant::now() < deadline, "nothing executed");
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    let (status, _) = api(&studio, "POST", "/api/print/pause", &serde_json::json!({}));
    assert_eq!(status, 200);
    wait_for_state(&studio, &["paused"]);
    let (status, _) = api(&studio, "POST", "/api/print/cancel", &serde_json::json!({}));
    assert_eq!(status, 200);
    let cancelled = wait_for_state(&studio, &["cancelled", "completed", "failed"]);
    assert_eq!(cancelled["state"], "cancelled", "{cancelled}");
    let done_before = cancelled["executed"].as_u64().unwrap();
    let total = cancelled["total"].as_u64().unwrap();
    assert!(done_before > 0 && done_before < total, "{cancelled}");
    // A fresh start would lose the unfinished job: refused until asked to restart.
    let (status, r) = api(&studio, "POST", "/api/print", &start);
    assert_eq!(status, 409, "{r}");
    let (_, r) = api(
        &studio,
        "GET",
        "/api/print?file=ball.gcode",
        &serde_json::Value::Null,
    );
    assert_eq!(r["resumable"], true);
    let resume = serde_json::json!({"file": "ball.gcode", "port": port, "resume": true});
    let (status, r) = api(&studio, "POST", "/api/print", &resume);
    assert_eq!(status, 200, "{r}");
    assert!(
        r["status"]["resume_plan"]
            .as_str()
            .is_some_and(|p| !p.is_empty()),
        "{r}"
    );
    let done = wait_for_state(&studio, &["completed", "cancelled", "failed"]);
    assert_eq!(done["state"], "completed", "{done}");
    assert_eq!(done["executed"], total);
    // What the printer ran: the file's first commands up to the cancel, then (after the
    // cancel sequence and the resume's heat-up and moves) the rest of the file, each once.
    let (_, executed) = api(
        &studio,
        "GET",
        "/api/fake-printer/executed",
        &serde_json::Value::Null,
    );
    let ran: Vec<String> = executed
        .as_array()
        .unwrap()
        .iter()
        .filter(|e| e["line"].is_u64())
        .filter_map(|e| e["command"].as_str().map(str::to_string))
        .filter(|c| !c.starts_with("M110"))
        .collect();
    let file: Vec<String> = isoforge_host::gcode::read_file(&dir.path().join("ball.gcode"))
        .unwrap()
        .commands
        .into_iter()
        .map(|c| c.text)
        .collect();
    let k = done_before as usize;
    assert_eq!(ran[..k], file[..k]);
    assert!(
        ran.ends_with(&file[k..]),
        "the resumed run is not the rest of the file"
    );
    assert!(
        ran.len() < file.len() + k + 40,
        "{} commands ran for a {}-command file",
        ran.len(),
        file.len()
    );
    let journal = std::fs::read_to_string(dir.path().join("ball.gcode.journal")).unwrap();
    assert!(journal.contains("\"completed\""), "{journal}");
}
