//! Smoke test: the four shared benchmark models parse, evaluate and simplify.
use isoforge_field::*;

#[test]
fn models_parse_and_evaluate() {
    for m in ["bear", "colonnade", "prospero", "tanglecube"] {
        let text = std::fs::read_to_string(format!("/work/shared/models/{m}.vm")).unwrap();
        let s = vm::parse_vm(&text).unwrap();
        let t = Tape::new(&s);
        let mut p = PointEval::new();
        let mut iv = IntervalEval::new();
        let v = p.eval(&t, [0.1, 0.2, 0.3]);
        let b = Interval::try_from((-1.0, 1.0)).unwrap();
        let i = iv.eval(&t, [b, b, b]);
        let small = Interval::try_from((0.09, 0.11)).unwrap();
        let i2 = iv.eval(
            &t,
            [
                small,
                Interval::try_from((0.19, 0.21)).unwrap(),
                Interval::try_from((0.29, 0.31)).unwrap(),
            ],
        );
        let simp = t.simplify(iv.choices());
        let v2 = p.eval(&simp, [0.1, 0.2, 0.3]);
        println!(
            "{m}: len {} regs {} choices {} v {v} i {:?} i2 {:?} simplified len {} v2 {v2}",
            t.len(),
            t.register_count(),
            t.choice_count(),
            (i.inf(), i.sup()),
            (i2.inf(), i2.sup()),
            simp.len()
        );
        assert!(i2.inf() <= v && v <= i2.sup());
        assert_eq!(v, v2);
    }
}
