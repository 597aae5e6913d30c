//! Bad scripts fail with an error of the right kind, whose message says what and where
//! (file:line:column).

use std::path::{Path, PathBuf};

use isoforge_field::{RegionError, ensure_not_empty, find_bounds};
use isoforge_script::{RuntimeCause, ScriptError, load_file, load_script};

fn bad(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/bad")
        .join(name)
}

/// A loading error or a region error.
#[derive(Debug)]
enum Failure {
    Script(ScriptError),
    Region(RegionError),
}

impl std::fmt::Display for Failure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Failure::Script(e) => write!(f, "{e}"),
            Failure::Region(e) => write!(f, "{e}"),
        }
    }
}

/// Loads a bad fixture and settles its region as `isoforge info` does; the first error.
fn failure_of(name: &str) -> Failure {
    let path = bad(name);
    let m = match load_file(&path, &[]) {
        Ok(m) => m,
        Err(e) => return Failure::Script(e),
    };
    let result = match m.bounds {
        Some(b) => ensure_not_empty(&m.shape, &b),
        None => find_bounds(&m.shape).map(|_| ()),
    };
    match result {
        Ok(()) => panic!("{name} did not fail"),
        Err(e) => Failure::Region(e),
    }
}

/// The script error of a bad fixture (it must fail while loading).
fn script_error(name: &str) -> ScriptError {
    match failure_of(name) {
        Failure::Script(e) => e,
        other => panic!("{name}: expected a script error, got {other}"),
    }
}

fn expect(name: &str, location: &str, words: &[&str]) {
    let msg = failure_of(name).to_string();
    let path = bad(name).display().to_string();
    assert!(
        msg.starts_with(&format!("{path}{location}")),
        "{name}: expected {path}{location}, got: {msg}"
    );
    for w in words {
        assert!(msg.contains(w), "{name}: {w:?} not in: {msg}");
    }
}

#[test]
fn syntax_error() {
    expect("syntax_error.rhai", ":2:", &["syntax error"]);
    let e = script_error("syntax_error.rhai");
    assert!(
        matches!(&e, ScriptError::Syntax { at, .. } if at.line == Some(2)),
        "{e:?}"
    );
}

#[test]
fn unknown_function() {
    expect(
        "unknown_function.rhai",
        ":3:1:",
        &["Sphre", "did you mean Sphere?"],
    );
    let e = script_error("unknown_function.rhai");
    assert!(
        matches!(
            e.runtime_cause(),
            Some(RuntimeCause::UnknownFunction {
                suggestion: Some("Sphere"),
                ..
            })
        ),
        "{e:?}"
    );
}

#[test]
fn wrong_argument_type() {
    expect(
        "wrong_argument_type.rhai",
        ":3:1:",
        &["Sphere", "number", "string"],
    );
}

#[test]
fn endless_loop() {
    expect("endless_loop.rhai", ":", &["operations", "endless loop"]);
    let e = script_error("endless_loop.rhai");
    assert!(
        matches!(
            e.runtime_cause(),
            Some(RuntimeCause::TooManyOperations { limit }) if *limit == isoforge_script::MAX_OPERATIONS
        ),
        "{e:?}"
    );
}

#[test]
fn deep_recursion() {
    expect(
        "deep_recursion.rhai",
        ":5:1:",
        &["nested", "recursion", "`grow`"],
    );
    let e = script_error("deep_recursion.rhai");
    assert!(
        matches!(
            e.runtime_cause(),
            Some(RuntimeCause::TooDeep { function: Some(f), .. }) if f == "grow"
        ),
        "{e:?}"
    );
}

#[test]
fn a_number_is_not_a_shape() {
    expect(
        "number.rhai",
        ":3:",
        &["the model evaluated to a number", "not a shape"],
    );
    let e = script_error("number.rhai");
    assert!(
        matches!(&e, ScriptError::NotAShape { at, .. } if at.line == Some(3)),
        "{e:?}"
    );
}

#[test]
fn empty_file() {
    expect("empty.rhai", ":", &["empty"]);
    assert!(matches!(
        script_error("empty.rhai"),
        ScriptError::Empty { .. }
    ));
}

#[test]
fn random_bytes() {
    expect("random_bytes.rhai", ":", &["not a text file", "byte 0"]);
    assert!(matches!(
        script_error("random_bytes.rhai"),
        ScriptError::NotText { byte: 0, .. }
    ));
}

#[test]
fn param_out_of_range() {
    expect(
        "param_out_of_range.rhai",
        ":2:",
        &["param \"r\"", "outside its range"],
    );
    // An override out of range names the parameter too.
    let src = "let r = param(\"r\", 2, 1, 5);\nSphere(r)";
    let err = load_script(Path::new("p.rhai"), src, &[("r".into(), 9.0)]).unwrap_err();
    assert!(err.to_string().starts_with("p.rhai:1:"), "{err}");
    assert!(err.to_string().contains("\"r\" = 9"), "{err}");
    assert!(
        matches!(
            err.runtime_cause(),
            Some(RuntimeCause::ParamOutOfRange { name, value, min, max })
                if name == "r" && *value == 9.0 && *min == 1.0 && *max == 5.0
        ),
        "{err:?}"
    );
    // A parameter the script does not declare is a typo, not silently ignored.
    let err = load_script(Path::new("p.rhai"), src, &[("radius".into(), 3.0)]).unwrap_err();
    assert!(
        err.to_string().contains("\"radius\"") && err.to_string().contains("declares: r"),
        "{err}"
    );
    assert!(
        matches!(&err, ScriptError::UnknownParams { unknown, declared, .. }
            if unknown == &["radius"] && declared == &["r"]),
        "{err:?}"
    );
    // Library messages name no command-line flag: the CLI adds those.
    assert!(!err.to_string().contains("--"), "{err}");
}

#[test]
fn empty_region_and_empty_model() {
    let f = failure_of("empty_region.rhai");
    assert!(f.to_string().contains("empty in its region"), "{f}");
    assert!(
        matches!(f, Failure::Region(RegionError::EmptyRegion { .. })),
        "{f:?}"
    );
    let f = failure_of("empty_model.rhai");
    assert!(f.to_string().contains("the model is empty"), "{f}");
    assert!(
        matches!(f, Failure::Region(RegionError::Empty { .. })),
        "{f:?}"
    );
}

#[test]
fn unbounded_model() {
    let f = failure_of("unbounded.rhai");
    let msg = f.to_string();
    // The library says what is wrong; the CLI adds how to give a region.
    assert!(msg.contains("not bounded"), "{msg}");
    assert!(!msg.contains("--bounds"), "{msg}");
    assert!(
        matches!(f, Failure::Region(RegionError::Unbounded { .. })),
        "{f:?}"
    );
}

#[test]
fn errors_inside_functions_point_inside_them() {
    let src = "fn inner(a) {\n    a + undefined_thing\n}\nfn outer() { inner(1) }\nouter()";
    let e = load_script(Path::new("f.rhai"), src, &[]).unwrap_err();
    match &e {
        ScriptError::Runtime { at, calls, .. } => {
            assert_eq!((at.line, at.column), (Some(2), Some(9)), "{e}");
            let names: Vec<_> = calls.iter().map(|c| c.function.as_deref()).collect();
            assert_eq!(
                names,
                [Some("inner"), Some("outer")],
                "innermost first: {e}"
            );
        }
        other => panic!("expected a runtime error, got {other:?}"),
    }
    let err = e.to_string();
    assert!(err.starts_with("f.rhai:2:9:"), "{err}");
    assert!(
        err.contains("function `inner` called at f.rhai:4:"),
        "{err}"
    );
    assert!(
        err.contains("function `outer` called at f.rhai:5:1"),
        "{err}"
    );
    // Wrong type inside a closure given to a curve follower.
    let src = "let f = |t| [t, \"no\", 0];\ncurve_fol_sphere(f, 3, [0, 1], 1)";
    let err = load_script(Path::new("c.rhai"), src, &[])
        .unwrap_err()
        .to_string();
    assert!(err.starts_with("c.rhai:2:1:"), "{err}");
    assert!(
        err.contains("[x, y, z]") || err.contains("3 numbers"),
        "{err}"
    );
}

#[test]
fn columns_are_those_the_user_wrote() {
    // The notation pass rewrites `-x^2` to `-(x**2)`; the column must still be the original.
    let src = "let a = -x^2 + nope;\na";
    let err = load_script(Path::new("n.rhai"), src, &[])
        .unwrap_err()
        .to_string();
    assert!(err.starts_with("n.rhai:1:16:"), "{err}");
}

#[test]
fn no_file_access() {
    let err = load_script(Path::new("i.rhai"), "import \"x\" as m;\nSphere(1)", &[])
        .unwrap_err()
        .to_string();
    assert!(err.starts_with("i.rhai:1:"), "{err}");
    let err = load_script(Path::new("e.rhai"), "eval(\"Sphere(1)\")", &[])
        .unwrap_err()
        .to_string();
    assert!(err.starts_with("e.rhai:1:"), "{err}");
}

#[test]
fn curve_follower_limits() {
    let err = load_script(
        Path::new("c.rhai"),
        "curve_fol_sphere(|t| [t, 0, 0], 0, [0, 1], 1)",
        &[],
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("between 1 and"), "{err}");
    let err = load_script(
        Path::new("c.rhai"),
        "curve_fol_sphere(|t| [1 / t, 0, 0], 2, [0, 1], 1)",
        &[],
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("not finite"), "{err}");
}
