//! Bad scripts fail with a message that says what and where (file:line:column).

use std::path::{Path, PathBuf};

use isoforge_script::{ScriptError, load_file, load_script};

fn bad(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/bad")
        .join(name)
}

/// Loads a bad fixture; its error. (The fixtures whose script is fine but whose region is
/// empty or missing are the region's to refuse: see isoforge-field's region tests.)
fn error_of(name: &str) -> String {
    match load_file(&bad(name), &[]) {
        Ok(_) => panic!("{name} did not fail"),
        Err(ScriptError(msg)) => msg,
    }
}

fn expect(name: &str, location: &str, words: &[&str]) {
    let msg = error_of(name);
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
}

#[test]
fn unknown_function() {
    expect(
        "unknown_function.rhai",
        ":3:1:",
        &["Sphre", "did you mean Sphere?"],
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
}

#[test]
fn deep_recursion() {
    expect(
        "deep_recursion.rhai",
        ":5:1:",
        &["nested", "recursion", "`grow`"],
    );
}

#[test]
fn a_number_is_not_a_shape() {
    expect(
        "number.rhai",
        ":3:",
        &["the model evaluated to a number", "not a shape"],
    );
}

#[test]
fn empty_file() {
    expect("empty.rhai", ":", &["empty"]);
}

#[test]
fn random_bytes() {
    expect("random_bytes.rhai", ":", &["not a text file", "byte 0"]);
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
    assert!(err.0.starts_with("p.rhai:1:"), "{err}");
    assert!(err.0.contains("\"r\" = 9"), "{err}");
    // A parameter the script does not declare is a typo, not silently ignored.
    let err = load_script(Path::new("p.rhai"), src, &[("radius".into(), 3.0)]).unwrap_err();
    assert!(
        err.0.contains("--param radius") && err.0.contains("declares: r"),
        "{err}"
    );
}

#[test]
fn errors_inside_functions_point_inside_them() {
    let src = "fn inner(a) {\n    a + undefined_thing\n}\nfn outer() { inner(1) }\nouter()";
    let err = load_script(Path::new("f.rhai"), src, &[]).unwrap_err().0;
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
    let err = load_script(Path::new("c.rhai"), src, &[]).unwrap_err().0;
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
    let err = load_script(Path::new("n.rhai"), src, &[]).unwrap_err().0;
    assert!(err.starts_with("n.rhai:1:16:"), "{err}");
}

#[test]
fn no_file_access() {
    let err = load_script(Path::new("i.rhai"), "import \"x\" as m;\nSphere(1)", &[])
        .unwrap_err()
        .0;
    assert!(err.starts_with("i.rhai:1:"), "{err}");
    let err = load_script(Path::new("e.rhai"), "eval(\"Sphere(1)\")", &[])
        .unwrap_err()
        .0;
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
    .0;
    assert!(err.contains("between 1 and"), "{err}");
    let err = load_script(
        Path::new("c.rhai"),
        "curve_fol_sphere(|t| [1 / t, 0, 0], 2, [0, 1], 1)",
        &[],
    )
    .unwrap_err()
    .0;
    assert!(err.contains("not finite"), "{err}");
}
