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
