//! Bad scripts fail cleanly: exit status 1, a message naming the file (and the line where
//! there is one), and no output file left behind.

use std::path::PathBuf;

use crate::{fixtures, isoforge};

/// Each bad fixture, with the `:line:` its message must name (empty where the problem has
/// no line: an empty or binary file, or a model whose region is wrong).
const BAD: [(&str, &str); 12] = [
    ("syntax_error.rhai", ":2:"),
    ("unknown_function.rhai", ":3:"),
    ("wrong_argument_type.rhai", ":3:"),
    ("endless_loop.rhai", ":4:"),
    ("deep_recursion.rhai", ":5:"),
    ("number.rhai", ":3:"),
    ("empty.rhai", ""),
    ("empty_region.rhai", ""),
    ("empty_model.rhai", ""),
    ("unbounded.rhai", ""),
    ("random_bytes.rhai", ""),
    ("param_out_of_range.rhai", ":2:"),
];

fn bad(name: &str) -> PathBuf {
    fixtures().join("bad").join(name)
}

/// Runs `isoforge <command> BAD <extra>` for every bad fixture; checks the failure.
fn fails_cleanly(command: &str, extra: impl Fn(&std::path::Path) -> Vec<String>) {
    let dir = tempfile::tempdir().unwrap();
    for (name, line) in BAD {
        let path = bad(name);
        let out_file = dir.path().join(format!("{name}.out"));
        let mut args = vec![command.to_string(), path.display().to_string()];
        args.extend(extra(&out_file));
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let out = isoforge(&args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{command} {name}: {err}");
        let located = format!("{}{line}", path.display());
        assert!(
            err.contains(&located),
            "{command} {name}: expected {located:?} in: {err}"
        );
        assert!(!err.contains("panicked"), "{command} {name}: {err}");
        assert!(
            !out_file.exists(),
            "{command} {name} left {}",
            out_file.display()
        );
        let leftovers: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert!(
            leftovers.is_empty(),
            "{command} {name} left files: {leftovers:?}"
        );
    }
}

#[test]
fn info_rejects_every_bad_script() {
    fails_cleanly("info", |_| vec![]);
}

#[test]
fn mesh_rejects_every_bad_script_and_writes_nothing() {
    fails_cleanly("mesh", |out| vec!["-o".into(), out.display().to_string()]);
}

/// Runs `isoforge info BAD extra..`; the error text, after checking it failed cleanly.
fn info_error(name: &str, extra: &[&str]) -> String {
    let path = bad(name).display().to_string();
    let mut args = vec!["info", path.as_str()];
    args.extend_from_slice(extra);
    let out = isoforge(&args);
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(1), "{name}: {err}");
    assert!(!err.contains("panicked"), "{name}: {err}");
    err
}

#[test]
fn a_script_keeping_too_much_memory_is_stopped() {
    // The limit lowered to 64 MiB, so that the test stops after about 64 strings.
    let err = info_error("memory_hog.rhai", &["--script-memory", "64"]);
    assert!(err.contains("memory_hog.rhai:8:"), "{err}");
    assert!(err.contains("more than 64 MiB of memory"), "{err}");
}

#[test]
fn a_script_running_too_long_is_stopped() {
    let err = info_error("copying_loop.rhai", &["--script-timeout", "1"]);
    assert!(err.contains("copying_loop.rhai:7:"), "{err}");
    assert!(err.contains("ran longer than 1 s"), "{err}");
}

#[test]
fn a_string_past_the_size_limit_is_refused() {
    let err = info_error("huge_string.rhai", &[]);
    assert!(err.contains("huge_string.rhai:3:"), "{err}");
    assert!(
        err.contains("a string larger than the limit of 1048576 bytes"),
        "{err}"
    );
}

#[test]
fn script_limits_must_be_positive() {
    let model = fixtures().join("classic/heart.rhai").display().to_string();
    for flag in [["--script-timeout", "0"], ["--script-memory", "0"]] {
        let out = isoforge(&["info", &model, flag[0], flag[1]]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{flag:?}: {err}");
        assert!(err.contains(flag[0]), "{flag:?}: {err}");
    }
}
