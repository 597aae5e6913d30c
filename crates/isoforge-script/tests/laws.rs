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

    /// Every classic fixture, cut anywhere or with one byte changed: a model or a located
    /// error, never a panic (mutations keep most of a real script, so they reach further
    /// than random text).
    #[test]
    fn mutated_fixtures_load_or_fail(which in 0usize..64, at in any::<usize>(), byte in any::<u8>(), cut in any::<bool>()) {
        let files = classic_fixtures();
        let (name, text) = &files[which % files.len()];
        let mut bytes = text.clone().into_bytes();
        let at = at % bytes.len().max(1);
        if cut {
            bytes.truncate(at);
        } else if let Some(b) = bytes.get_mut(at) {
            *b = byte;
        }
        let Ok(src) = String::from_utf8(bytes) else { return Ok(()); };
        if let Err(e) = load_script(Path::new(name), &src, &[]) {
            prop_assert!(e.to_string().starts_with(name.as_str()), "{}", e);
        }
    }
}

/// The classic fixtures' names and texts.
fn classic_fixtures() -> Vec<(String, String)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/classic");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .expect("fixtures/classic")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "rhai"))
        .map(|p| {
            let name = p
                .file_name()
                .unwrap_or_default()
                .to_string_lossy()
                .into_owned();
            (name, std::fs::read_to_string(&p).expect("text"))
        })
        .collect();
    files.sort();
    files
}
