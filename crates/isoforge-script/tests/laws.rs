//! Property tests: scripts never panic, whatever their text, and found bounds enclose
//! the model.

use std::path::Path;

use isoforge_field::Shape;
use isoforge_script::{find_bounds, load_script};
use isoforge_shapes::classic::{sphere, translate};
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

    #[test]
    fn found_bounds_enclose_a_sphere(
        c in prop::array::uniform3(-50.0f64..50.0),
        r in 0.05f64..20.0,
    ) {
        let s: Shape = translate(&sphere(r), c);
        let b = find_bounds(&s).unwrap();
        for (i, ci) in c.iter().enumerate() {
            prop_assert!(b.min[i] <= ci - r && b.max[i] >= ci + r, "{b:?}");
            // Tight: padding is a few percent, plus what the cells add.
            prop_assert!(b.min[i] >= ci - 1.2 * r && b.max[i] <= ci + 1.2 * r, "{b:?}");
        }
    }
}
