//! The `.vm` reader: the four shared models, logic ops, and malformed input.

use std::collections::HashMap;

use isoforge_field::eval::scalar;
use isoforge_field::vm::parse_vm;
use isoforge_field::{Interval, IntervalEval, PointEval, Tape};
use proptest::prelude::*;

use crate::common::{encloses, same};

fn model(name: &str) -> String {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/vm/");
    std::fs::read_to_string(format!("{path}{name}.vm"))
        .or_else(|_| std::fs::read_to_string(format!("/work/shared/models/{name}.vm")))
        .expect("model file")
}

/// An independent interpreter of the text: evaluates line by line with f64.
fn interpret(text: &str, p: [f64; 3]) -> f64 {
    let mut vals: HashMap<&str, f64> = HashMap::new();
    let mut last = f64::NAN;
    for line in text.lines() {
        let w: Vec<&str> = line.split_whitespace().collect();
        if w.is_empty() || w[0].starts_with('#') {
            continue;
        }
        let a = |i: usize| vals[w[i]];
        let v = match w[1] {
            "const" => w[2].parse().unwrap(),
            "var-x" => p[0],
            "var-y" => p[1],
            "var-z" => p[2],
            "add" => a(2) + a(3),
            "sub" => a(2) - a(3),
            "mul" => a(2) * a(3),
            "div" => a(2) / a(3),
            "min" => scalar::min(a(2), a(3)),
            "max" => scalar::max(a(2), a(3)),
            "neg" => -a(2),
            "square" => a(2) * a(2),
            "sqrt" => a(2).sqrt(),
            "abs" => a(2).abs(),
            "exp" => a(2).exp(),
            "ln" => a(2).ln(),
            "sin" => a(2).sin(),
            "cos" => a(2).cos(),
            op => panic!("interpreter lacks {op}"),
        };
        vals.insert(w[0], v);
        last = v;
    }
    last
}

#[test]
fn all_four_models_parse() {
    for (name, min_len) in [
        ("bear", 500),
        ("colonnade", 600),
        ("prospero", 6000),
        ("tanglecube", 15),
    ] {
        let s = parse_vm(&model(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
        let t = Tape::new(&s);
        assert!(t.len() >= min_len, "{name}: {} instructions", t.len());
    }
}

#[test]
fn bear_colonnade_and_tanglecube_evaluate_like_the_text() {
    let mut pe = PointEval::new();
    let mut ie = IntervalEval::new();
    for (name, scale) in [
        ("bear", 1.0),
        ("colonnade", 1.0),
        ("tanglecube", 3.0),
        ("prospero", 1.0),
    ] {
        let text = model(name);
        let t = Tape::new(&parse_vm(&text).unwrap());
        let (mut inside, mut outside) = (0, 0);
        for i in 0..400usize {
            // A scrambled grid over [-1, 1]^3, scaled to the model.
            let p = [0, 1, 2].map(|k| ((i * [7, 37, 101][k] + 13 * k) % 29) as f64 / 14.0 - 1.0);
            let p = p.map(|v| v * scale);
            let want = interpret(&text, p);
            let got = pe.eval(&t, p);
            assert!(same(got, want), "{name} at {p:?}: {got} != {want}");
            inside += (got < 0.0) as usize;
            outside += (got > 0.0) as usize;
            let b = p.map(|v| Interval::try_from((v - 0.01, v + 0.01)).unwrap());
            assert!(encloses(ie.eval(&t, b), got));
        }
        assert!(
            inside > 0 && outside > 0,
            "{name}: {inside} inside, {outside} outside"
        );
    }
}

#[test]
fn logic_ops() {
    let text = "a var-x\nb var-y\nc compare a b\nd not a\n";
    let t = Tape::new(&parse_vm(text).unwrap());
    let mut pe = PointEval::new();
    assert_eq!(pe.eval(&t, [0.0, 0.0, 0.0]), 1.0);
    assert_eq!(pe.eval(&t, [3.0, 0.0, 0.0]), 0.0);
    assert_eq!(pe.eval(&t, [-1e-300, 0.0, 0.0]), 0.0);
    let t = Tape::new(&parse_vm("a var-x\nb var-y\nc compare a b").unwrap());
    for (x, y, want) in [
        (1.0, 2.0, -1.0),
        (2.0, 1.0, 1.0),
        (1.5, 1.5, 0.0),
        (1e-300, 0.0, 1.0),
        (-1e300, 1e300, -1.0),
    ] {
        assert_eq!(pe.eval(&t, [x, y, 0.0]), want, "compare({x}, {y})");
    }
    let err = parse_vm("a var-x\nb var-y\nc and a b\n").unwrap_err();
    assert_eq!(err.line, 3);
}

#[test]
fn errors_name_the_line() {
    let cases = [
        ("a var-x\nb add a c\n", 2, "not defined"),
        ("a var-x\n\n# c\nb frob a\n", 4, "unknown opcode"),
        ("a const banana\n", 1, "not a number"),
        ("a var-x\nb add a\n", 2, "takes 2"),
        ("lonely\n", 1, "expected"),
        ("# only a comment\n", 1, "no operations"),
    ];
    for (text, line, msg) in cases {
        let e = parse_vm(text).unwrap_err();
        assert_eq!(e.line, line, "{text:?}");
        assert!(e.to_string().contains(msg), "{e}");
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]
    /// Random lines never panic the reader, and whatever parses evaluates.
    #[test]
    fn random_lines_never_panic(lines in proptest::collection::vec(
        (
            prop_oneof![Just("_0".to_string()), Just("_1".to_string()), Just("a".to_string()), Just("#".to_string()), "[a-z_0-9]{0,4}"],
            prop_oneof![
                proptest::sample::select(vec!["const", "var-x", "add", "sqrt", "min", "compare", "not", "and"])
                    .prop_map(String::from),
                "[a-z-]{0,6}",
            ],
            proptest::collection::vec(prop_oneof![
                proptest::sample::select(vec!["_0", "_1", "a", "1.5", "nan", "-inf"]).prop_map(String::from),
                "\\PC{0,5}",
            ], 0..4),
        ),
        0..12,
    )) {
        let text: String = lines
            .iter()
            .map(|(n, o, a)| format!("{n} {o} {}\n", a.join(" ")))
            .collect();
        if let Ok(s) = parse_vm(&text) {
            let t = Tape::new(&s);
            let _ = PointEval::new().eval(&t, [0.5, -0.5, 0.25]);
        }
    }
}
