//! `isoforge info` end to end: region and where it came from, graph and tape sizes,
//! parameters, `--json`, `--bounds`, `--param`.

use std::process::Output;

use crate::{fixtures, isoforge};
use serde_json::Value;

fn stdout(out: &Output) -> String {
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn info_json(args: &[&str]) -> Value {
    let mut all = vec!["info", "--json"];
    all.extend_from_slice(args);
    let out = isoforge(&all);
    assert!(out.status.success(), "{args:?}: {}", stderr(&out));
    serde_json::from_str(&stdout(&out)).unwrap_or_else(|e| panic!("{e}: {}", stdout(&out)))
}

fn bounds_of(v: &Value) -> [[f64; 3]; 2] {
    let b = &v["bounds"];
    let corner = |c: &Value| [0, 1, 2].map(|i| c[i].as_f64().expect("a number"));
    [corner(&b[0]), corner(&b[1])]
}

#[test]
fn every_classic_and_bench_fixture_has_info() {
    for folder in ["classic", "bench"] {
        let dir = fixtures().join(folder);
        let mut n = 0;
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_none_or(|e| e != "rhai") {
                continue;
            }
            let v = info_json(&[path.to_str().unwrap()]);
            assert_eq!(v["bounds_source"], "script", "{}", path.display());
            assert!(v["nodes"].as_u64().unwrap() > 0);
            assert!(v["tape_length"].as_u64().unwrap() > 0);
            n += 1;
        }
        assert!(n >= 6, "{folder} has its scripts");
    }
}

#[test]
fn declared_bounds_and_sizes() {
    let heart = fixtures().join("classic/heart.rhai");
    let v = info_json(&[heart.to_str().unwrap()]);
    assert_eq!(bounds_of(&v), [[-1.5; 3], [1.5; 3]]);
    assert_eq!(v["bounds_source"], "script");
    assert_eq!(v["params"], serde_json::json!([]));
    // Hash-consing merges shared subexpressions: fewer unique nodes than a tree would have.
    let nodes = v["nodes"].as_u64().unwrap();
    assert!((10..60).contains(&nodes), "heart has {nodes} nodes");
    let text = isoforge(&["info", heart.to_str().unwrap()]);
    assert!(text.status.success());
    let text = stdout(&text);
    assert!(text.contains("declared by the script"), "{text}");
    assert!(
        text.contains("[-1.5, -1.5, -1.5] to [1.5, 1.5, 1.5]"),
        "{text}"
    );
}

#[test]
fn command_line_bounds_win() {
    let heart = fixtures().join("classic/heart.rhai");
    let v = info_json(&[heart.to_str().unwrap(), "--bounds", "-2,-2,-2,2,2,3"]);
    assert_eq!(bounds_of(&v), [[-2.0; 3], [2.0, 2.0, 3.0]]);
    assert_eq!(v["bounds_source"], "command line");
    // A malformed region is a mistake in the call: a usage error.
    let out = isoforge(&["info", heart.to_str().unwrap(), "--bounds", "1,1,1,0,0,0"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("--bounds"), "{}", stderr(&out));
}

#[test]
fn bounds_are_found_when_not_declared() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("ball.rhai");
    std::fs::write(
        &path,
        "// a ball of radius 2 at (3, 0, -1)\nTransZ(TransX(Sphere(2), 3), -1)",
    )
    .unwrap();
    let v = info_json(&[path.to_str().unwrap()]);
    assert_eq!(v["bounds_source"], "found");
    let [lo, hi] = bounds_of(&v);
    let (want_lo, want_hi) = ([1.0, -2.0, -3.0], [5.0, 2.0, 1.0]);
    for i in 0..3 {
        assert!(lo[i] <= want_lo[i] && lo[i] >= want_lo[i] - 1.0, "{lo:?}");
        assert!(hi[i] >= want_hi[i] && hi[i] <= want_hi[i] + 1.0, "{hi:?}");
    }
}

#[test]
fn parameters_are_listed_and_overridden() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("p.rhai");
    std::fs::write(
        &path,
        "let r = param(\"r\", 2, 1, 5);\nlet h = param(\"h\", 0.5);\nbounds([-6,-6,-6],[6,6,6]);\nTransZ(Sphere(r), h)",
    )
    .unwrap();
    let p = path.to_str().unwrap();
    let v = info_json(&[p]);
    assert_eq!(v["params"][0]["name"], "r");
    assert_eq!(v["params"][0]["value"], 2.0);
    assert_eq!(v["params"][0]["min"], 1.0);
    assert_eq!(v["params"][0]["max"], 5.0);
    assert_eq!(v["params"][1]["name"], "h");
    assert_eq!(v["params"][1]["min"], Value::Null);
    let v = info_json(&[p, "--param", "r=4.5", "--param", "h=-1"]);
    assert_eq!(v["params"][0]["value"], 4.5);
    assert_eq!(v["params"][0]["default"], 2.0);
    assert_eq!(v["params"][1]["value"], -1.0);
    let out = isoforge(&["info", p, "--param", "r=9"]);
    assert_eq!(out.status.code(), Some(1));
    let err = stderr(&out);
    assert!(
        err.contains("p.rhai:1:") && err.contains("\"r\" = 9") && err.contains("--param r=9"),
        "{err}"
    );
    // A parameter the script does not declare is a mistake in the call: usage error.
    let out = isoforge(&["info", p, "--param", "radius=3"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("--param radius"), "{}", stderr(&out));
    // So is a malformed --param or --bounds.
    for bad in [
        vec!["--param", "r"],
        vec!["--param", "r=big"],
        vec!["--bounds", "1,2,3"],
        vec!["--bounds", "1,1,1,0,0,0"],
    ] {
        let mut args = vec!["info", p];
        args.extend(bad.iter().copied());
        let out = isoforge(&args);
        assert_eq!(out.status.code(), Some(2), "{bad:?}: {}", stderr(&out));
        assert!(stderr(&out).contains(bad[0]), "{bad:?}: {}", stderr(&out));
    }
    let text = stdout(&isoforge(&["info", p]));
    assert!(text.contains("r = 2 (default 2, range 1 to 5)"), "{text}");
}

#[test]
fn vm_models_take_command_line_bounds() {
    let vm = fixtures().join("vm/colonnade.vm");
    let v = info_json(&[vm.to_str().unwrap(), "--bounds", "-1,-1,-1,1,1,1"]);
    assert!(v["nodes"].as_u64().unwrap() > 100);
    assert!(v["tape_length"].as_u64().unwrap() > 100);
}

#[test]
fn quiet_prints_nothing_and_json_only_json() {
    let heart = fixtures().join("classic/heart.rhai");
    let out = isoforge(&["info", "--quiet", heart.to_str().unwrap()]);
    assert!(out.status.success());
    assert!(out.stdout.is_empty());
    let out = isoforge(&["info", "--json", heart.to_str().unwrap()]);
    let text = stdout(&out);
    assert_eq!(text.trim().lines().count(), 1, "{text}");
}

#[test]
fn a_missing_file_is_an_error_naming_it() {
    let out = isoforge(&["info", "no/such/model.rhai"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(stderr(&out).contains("no/such/model.rhai"));
}
