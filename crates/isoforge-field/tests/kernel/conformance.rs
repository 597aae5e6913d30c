//! One conformance suite run against all four evaluators and against simplified tapes:
//! every operation, on awkward inputs (NaN, ±inf, ±0, huge, tiny), compared with the
//! reference walk of the shape tree.

use isoforge_field::{BatchEval, GradEval, IntervalEval, PointEval, Shape, Tape};

use crate::common::*;

/// Every operation on x (and on x, y), plus a few compositions and the custom node.
fn expressions() -> Vec<Shape> {
    let (x, y, z) = (Shape::x(), Shape::y(), Shape::z());
    let mut out = Vec::new();
    for op in UNARY {
        out.push(x.unary(op));
    }
    for op in BINARY {
        out.push(x.binary(op, &y));
        out.push(x.binary(op, &Shape::constant(2.5)));
        out.push(Shape::constant(-1.5).binary(op, &y));
    }
    out.push((x.square() + y.square() + z.square()).sqrt() - 1.0);
    out.push(x.min(&y).max(&(-&z)).min(&(x.clone() * 0.5)));
    out.push(x.sin() * y.cos() + y.sin() * z.cos() + z.sin() * x.cos());
    out.push(paraboloid());
    out.push(paraboloid().remap(&(x.clone() * 2.0), &y.sin(), &(z.clone() - 1.0)));
    out.push((x.clone() - 0.0) * 1.0 + (-0.0));
    out
}

/// Grid of awkward points: every pair of awkward values for (x, y), z cycling.
fn points() -> Vec<[f64; 3]> {
    let mut out = Vec::new();
    for (i, &a) in AWKWARD.iter().enumerate() {
        for (j, &b) in AWKWARD.iter().enumerate() {
            out.push([a, b, AWKWARD[(i + 3 * j) % AWKWARD.len()]]);
        }
    }
    out
}

#[test]
fn all_evaluators_agree_with_the_reference() {
    let pts = points();
    let xs: Vec<f64> = pts.iter().map(|p| p[0]).collect();
    let ys: Vec<f64> = pts.iter().map(|p| p[1]).collect();
    let zs: Vec<f64> = pts.iter().map(|p| p[2]).collect();
    let (mut pe, mut be, mut ge, mut ie) = (
        PointEval::new(),
        BatchEval::new(),
        GradEval::new(),
        IntervalEval::new(),
    );
    let mut batch = vec![0.0; pts.len()];
    let mut checked_intervals = 0;
    for s in expressions() {
        let tape = Tape::new(&s);
        be.eval(&tape, &xs, &ys, &zs, &mut batch);
        for (k, &p) in pts.iter().enumerate() {
            let want = reference(&s, p);
            let got = pe.eval(&tape, p);
            assert!(same(got, want), "point {s:?} at {p:?}: {got} != {want}");
            assert!(
                same(batch[k], want),
                "batch {s:?} at {p:?}: {} != {want}",
                batch[k]
            );
            let g = ge.eval(&tape, p);
            assert!(
                same(g.v, want),
                "grad value {s:?} at {p:?}: {} != {want}",
                g.v
            );
            if let Some(b) = point_box(p) {
                checked_intervals += 1;
                let i = ie.eval(&tape, b);
                assert!(
                    encloses(i, want),
                    "interval {s:?} at {p:?}: {i:?} misses {want}"
                );
                // The tape simplified on this one-point box gives the same value there.
                let short = tape.simplify(ie.choices());
                assert!(short.len() <= tape.len());
                let v = pe.eval(&short, p);
                assert!(
                    want.is_nan() || same(v, want),
                    "simplified {s:?} at {p:?}: {v} != {want}"
                );
                let i2 = ie.eval(&short, b);
                assert!(encloses(i2, want), "simplified interval {s:?} at {p:?}");
            }
        }
    }
    assert!(checked_intervals > 1000);
}

#[test]
fn evaluators_reuse_buffers_across_tapes_of_different_sizes() {
    let (x, y) = (Shape::x(), Shape::y());
    let big = (0..50).fold(x.clone(), |acc, i| acc.min(&(&y - i as f64).square()));
    let small = x.clone() + 1.0;
    let (tb, ts) = (Tape::new(&big), Tape::new(&small));
    let mut pe = PointEval::new();
    for _ in 0..3 {
        assert_eq!(pe.eval(&ts, [1.0, 0.0, 0.0]), 2.0);
        assert_eq!(pe.eval(&tb, [100.0, 0.0, 0.0]), 0.0);
    }
    // Batch with a count that is not a multiple of the block size.
    let n = 1000;
    let xs: Vec<f64> = (0..n).map(|i| i as f64 * 0.01).collect();
    let mut out = vec![0.0; n];
    let mut be = BatchEval::new();
    be.eval(&tb, &xs, &xs, &xs, &mut out);
    for i in 0..n {
        assert!(same(out[i], pe.eval(&tb, [xs[i], xs[i], xs[i]])));
    }
    be.eval(&ts, &xs, &xs, &xs, &mut out);
    assert_eq!(out[999], xs[999] + 1.0);
}

#[test]
fn constant_and_variable_only_tapes() {
    let mut pe = PointEval::new();
    let mut ie = IntervalEval::new();
    let c = Tape::new(&Shape::constant(-2.0));
    assert_eq!(pe.eval(&c, [5.0, 5.0, 5.0]), -2.0);
    let b = point_box([1.0, 2.0, 3.0]).unwrap();
    assert_eq!(ie.eval(&c, b).sup(), -2.0);
    let z = Tape::new(&Shape::z());
    assert_eq!(pe.eval(&z, [1.0, 2.0, 3.0]), 3.0);
    let mut ge = GradEval::new();
    assert_eq!(ge.eval(&z, [1.0, 2.0, 3.0]).d, [0.0, 0.0, 1.0]);
}
