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
