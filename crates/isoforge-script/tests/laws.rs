//! Property tests: scripts never panic, whatever their text. (That found bounds enclose
//! the model is a law of the region search, tested in isoforge-field.)

use std::path::Path;

use isoforge_script::load_script;
use proptest::prelude::*;

/// Pieces of scripts, valid and not, so random sources reach deep into the parser and the
/// library instead of failing at the first character.
const PIECES: [&str; 40] = [
    "x",
    "y",
    "z",
    "1",
    "2.5",
    "-",
    "+",
    "*",
    "/",
    "^",
    "(",
    ")",
    "[",
    "]",
    ",",
    ";",
    "\n",
    "Sphere(",
    "Cube(",
    "Union(",
    "TransX(",
    "RotateY(",
    "sin(",
    "param(\"a\", 1, 0, 2)",
    "bounds([-1,-1,-1],[1,1,1])",
    "let a = ",
    "a",
    "fn f(q) { q ^ 2 }",
    "f(",
    "|t| [t, t, t]",
    "curve_fol_sphere(",
    "\"s\"",
    "// c\n",
    "/*",
    "*/",
    "PI",
    "E",
    "if true {",
    "}",
    "while false {",
];

fn source() -> impl Strategy<Value = String> {
    prop::collection::vec(prop::sample::select(&PIECES[..]), 0..24).prop_map(|v| v.concat())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(96))]

    #[test]
    fn any_script_loads_or_fails_with_a_located_message(src in source()) {
        match load_script(Path::new("fuzz.rhai"), &src, &[]) {
            Ok(_) => {}
            Err(e) => prop_assert!(e.to_string().starts_with("fuzz.rhai"), "{}", e),
        }
    }

    #[test]
    fn any_text_loads_or_fails(src in "\\PC{0,64}") {
        let _ = load_script(Path::new("t.rhai"), &src, &[]);
    }
}
