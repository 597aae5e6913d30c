//! The command line's word (issue 9, item 13): exit status 0 / 1 / 2 as the contract says,
//! `--json` prints exactly one JSON object on stdout even when the command fails, messages
//! say a thing once, and `--quiet` silences a script's `print()`.

use super::*;

/// The one JSON object on stdout, parsed; fails the test if stdout holds anything else.
fn json_of(out: &Output) -> serde_json::Value {
    let stdout = String::from_utf8_lossy(&out.stdout);
    let mut lines = stdout.lines().filter(|l| !l.trim().is_empty());
    let first = lines.next().unwrap_or_else(|| panic!("no JSON on stdout"));
    assert!(
        lines.next().is_none(),
        "more than one line on stdout: {stdout}"
    );
    serde_json::from_str(first).unwrap_or_else(|e| panic!("{e}: {first}"))
}

#[test]
fn json_failure_is_one_object_with_the_error() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing.rhai");
    let m = missing.to_str().unwrap();
    let cases: Vec<(Vec<&str>, i32)> = vec![
        (vec!["mesh", m, "--json"], 1),
        (vec!["info", m, "--json"], 1),
        (vec!["render", m, "-o", "x.png", "--json"], 1),
        (vec!["check", "/no/such/mesh.stl", "--json"], 2),
        (vec!["mesh", m, "--depth", "30", "--json"], 2),
        (vec!["mesh", "--json", "--no-such-flag"], 2),
    ];
    for (args, code) in cases {
        let out = isoforge(&args);
        assert_eq!(out.status.code(), Some(code), "{args:?}");
        let v = json_of(&out);
        let error = v["error"]
            .as_str()
            .unwrap_or_else(|| panic!("{args:?}: {v}"));
        assert!(!error.is_empty(), "{args:?}");
        assert_eq!(v["exit_code"], code, "{args:?}: {v}");
    }
}

#[test]
fn json_success_has_no_error_key() {
    let out = isoforge(&[
        "info",
        fixtures().join("classic/heart.rhai").to_str().unwrap(),
        "--json",
    ]);
    assert!(out.status.success());
    assert!(json_of(&out).get("error").is_none());
}

#[test]
fn usage_errors_exit_2() {
    let heart = fixtures().join("classic/heart.rhai");
    let h = heart.to_str().unwrap();
    for args in [
        vec!["info", h, "--bounds", "1,2,3"],
        vec!["info", h, "--bounds", "0,0,0,-1,1,1"],
        vec!["info", h, "--param", "novalue"],
        vec!["info", h, "--param", "a=notanumber"],
        vec!["mesh", h, "--depth", "30"],
        vec!["slice", h, "--set", "no_such_key=1", "-o", "x.gcode"],
        vec!["slice", h, "--set", "layer_height", "-o", "x.gcode"],
    ] {
        let out = isoforge(&args);
        assert_eq!(
            out.status.code(),
            Some(2),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
}

#[test]
fn a_missing_file_is_named_once() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing.rhai");
    for cmd in ["mesh", "info", "render"] {
        let mut args = vec![cmd, missing.to_str().unwrap()];
        if cmd == "render" {
            args.extend(["-o", "x.png"]);
        }
        let out = isoforge(&args);
        assert_eq!(out.status.code(), Some(1), "{cmd}");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(
            stderr.matches("No such file or directory").count(),
            1,
            "{cmd}: {stderr}"
        );
        assert_eq!(stderr.matches("missing.rhai").count(), 1, "{cmd}: {stderr}");
    }
}

#[test]
fn a_huge_model_is_not_called_unbounded_without_a_word_on_size() {
    let dir = tempfile::tempdir().unwrap();
    let big = dir.path().join("big.rhai");
    std::fs::write(&big, "Sphere(1e6)").unwrap();
    let out = isoforge(&["info", big.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("larger than the box searched"), "{stderr}");
    assert!(stderr.contains("--bounds"), "{stderr}");
}

#[test]
fn quiet_silences_a_scripts_print() {
    let dir = tempfile::tempdir().unwrap();
    let script = dir.path().join("chatty.rhai");
    std::fs::write(&script, "print(\"hello from the script\");\nSphere(1)").unwrap();
    let s = script.to_str().unwrap();
    let loud = isoforge(&["info", s]);
    assert!(loud.status.success());
    assert!(String::from_utf8_lossy(&loud.stderr).contains("hello from the script"));
    assert!(!String::from_utf8_lossy(&loud.stdout).contains("hello from the script"));
    let quiet = isoforge(&["info", s, "--quiet"]);
    assert!(quiet.status.success());
    assert!(
        quiet.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&quiet.stderr)
    );
    let json = isoforge(&["info", s, "--json"]);
    assert!(json.status.success());
    json_of(&json);
}

#[test]
fn an_endless_model_file_is_refused_with_bounded_memory() {
    // /dev/zero as a model: read up to the cap, then refused (not read until memory ends).
    let out = isoforge(&["info", "/dev/zero"]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("/dev/zero") && stderr.contains("too large"),
        "{stderr}"
    );
}

#[test]
fn an_endless_mesh_or_gcode_input_is_cut_off_with_a_clear_error() {
    // /dev/zero as a mesh (check) and as G-code (print): at most the cap is taken from a
    // non-file, then a message that names it, not a read until memory runs out.
    let port = tempfile::tempdir().expect("tempdir");
    let port = port.path().join("no-such-port");
    for args in [
        vec!["check", "/dev/zero"],
        vec![
            "print",
            "/dev/zero",
            "--port",
            port.to_str().expect("utf-8"),
        ],
    ] {
        let out = isoforge(&args);
        assert_ne!(out.status.code(), Some(0), "{args:?}");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            stderr.contains("/dev/zero") && stderr.contains("not a regular file"),
            "{args:?}: {stderr}"
        );
    }
}

#[test]
fn a_mesh_or_gcode_where_a_model_goes_says_what_takes_it() {
    let dir = tempfile::tempdir().expect("tempdir");
    let stl = fixtures().join("meshes/cube_binary.stl");
    let gcode = fixtures().join("gcode/square-tube.gcode");
    let png = dir.path().join("x.png");
    let png = png.to_str().expect("utf-8");
    for (args, word) in [
        (vec!["info", stl.to_str().expect("utf-8")], "a mesh"),
        (
            vec!["render", stl.to_str().expect("utf-8"), "-o", png],
            "import_stl",
        ),
        (
            vec!["info", gcode.to_str().expect("utf-8")],
            "isoforge print",
        ),
    ] {
        let out = isoforge(&args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(stderr.contains(word), "{args:?}: {stderr}");
        assert!(
            !stderr.contains("syntax") && !stderr.contains("UTF-8"),
            "{stderr}"
        );
    }
}
