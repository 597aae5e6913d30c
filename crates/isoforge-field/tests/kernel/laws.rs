//! proptest laws on random expressions and random boxes.

use isoforge_field::{
    BatchEval, Choice, GradEval, IntervalEval, IntervalGradEval, PointEval, Tape,
};
use proptest::prelude::*;

use crate::common::*;

fn fractions() -> impl Strategy<Value = Vec<[f64; 3]>> {
    proptest::collection::vec([0.0..=1.0f64, 0.0..=1.0f64, 0.0..=1.0f64], 8)
}

proptest! {
    #![proptest_config(crate::common::cases(512))]

    /// The interval over a box encloses every point value in it; a NaN point value makes
    /// the interval ENTIRE.
    #[test]
    fn interval_encloses_point_values(s in any_shape(), b in any_box(), f in fractions()) {
        let tape = Tape::new(&s);
        let mut ie = IntervalEval::new();
        let mut pe = PointEval::new();
        let i = ie.eval(&tape, intervals(&b));
        prop_assert_eq!(ie.choices().len(), tape.choice_count());
        for p in samples(&b, &f) {
            let v = pe.eval(&tape, p);
            prop_assert!(encloses(i, v), "{:?} over {:?}: {:?} misses {} at {:?}", s, b, i, v, p);
        }
    }

    /// The interval gradient over a box encloses the value and every partial derivative
    /// the gradient evaluator gives at points of the box (as values are enclosed: an
    /// infinite slope by an interval unbounded on its side, NaN only by `ENTIRE`), and its
    /// value part is the interval evaluator's.
    #[test]
    fn interval_gradient_encloses_point_gradients(s in any_shape(), b in any_box(), f in fractions()) {
        let tape = Tape::new(&s);
        let ig = IntervalGradEval::new().eval(&tape, intervals(&b));
        prop_assert_eq!(ig.v, IntervalEval::new().eval(&tape, intervals(&b)));
        let mut ge = GradEval::new();
        for p in samples(&b, &f) {
            let g = ge.eval(&tape, p);
            prop_assert!(encloses(ig.v, g.v));
            if g.v.is_nan() {
                continue;
            }
            for k in 0..3 {
                let d = g.d[k];
                prop_assert!(encloses(ig.d[k], d), "{:?} over {:?}: d/d{} = {} at {:?} outside {:?}", s, b, k, d, p, ig.d[k]);
            }
            let norm = (g.d[0] * g.d[0] + g.d[1] * g.d[1] + g.d[2] * g.d[2]).sqrt();
            if norm.is_finite() {
                prop_assert!(ig.slope_floor() <= norm && norm <= ig.slope_bound());
            }
        }
    }

    /// Batch equals point, bit for bit (or both NaN), and gradient values equal too.
    #[test]
    fn batch_and_grad_values_equal_point(s in any_shape(), b in any_box(), f in fractions()) {
        let tape = Tape::new(&s);
        let pts = samples(&b, &f);
        let xs: Vec<f64> = pts.iter().map(|p| p[0]).collect();
        let ys: Vec<f64> = pts.iter().map(|p| p[1]).collect();
        let zs: Vec<f64> = pts.iter().map(|p| p[2]).collect();
        let mut out = vec![0.0; pts.len()];
        BatchEval::new().eval(&tape, &xs, &ys, &zs, &mut out);
        let mut pe = PointEval::new();
        let mut ge = GradEval::new();
        for (k, p) in pts.iter().enumerate() {
            let v = pe.eval(&tape, *p);
            prop_assert!(same(out[k], v), "batch {} != point {} at {:?}", out[k], v, p);
            prop_assert!(same(ge.eval(&tape, *p).v, v));
            prop_assert!(same(reference(&s, *p), v), "tape differs from the shape tree");
        }
    }

    /// A tape simplified on a box gives the full tape's value at every non-NaN point of
    /// that box; simplifying again on a sub-box keeps that true.
    #[test]
    fn simplified_tape_equals_full_inside_its_box(
        s in any_shape(), b in any_box(), f in fractions(), sub in [0usize..2, 0usize..2, 0usize..2]
    ) {
        let tape = Tape::new(&s);
        let mut ie = IntervalEval::new();
        let mut pe = PointEval::new();
        ie.eval(&tape, intervals(&b));
        let short = tape.simplify(ie.choices());
        prop_assert!(short.len() <= tape.len());
        let i_short = ie.eval(&short, intervals(&b));
        let pts = samples(&b, &f);
        let xyz: [Vec<f64>; 3] = [0, 1, 2].map(|k| pts.iter().map(|p| p[k]).collect());
        let mut batch = vec![0.0; pts.len()];
        BatchEval::new().eval(&short, &xyz[0], &xyz[1], &xyz[2], &mut batch);
        let mut ge = GradEval::new();
        for (j, p) in pts.into_iter().enumerate() {
            let v = pe.eval(&tape, p);
            if !v.is_nan() {
                let w = pe.eval(&short, p);
                prop_assert!(same(batch[j], w), "batch on the short tape");
                prop_assert!(same(ge.eval(&short, p).v, w), "grad on the short tape");
                prop_assert!(same(v, w), "{:?} over {:?} at {:?}: full {} short {}", s, b, p, v, w);
                prop_assert!(encloses(i_short, v));
            }
        }
        // One octant of the box, with the shorter tape's own choices.
        let child = [0, 1, 2].map(|k| {
            let m = 0.5 * (b[k].0 + b[k].1);
            if sub[k] == 0 { (b[k].0, m) } else { (m, b[k].1) }
        });
        ie.eval(&short, intervals(&child));
        let shorter = short.simplify(ie.choices());
        for p in samples(&child, &f) {
            let v = pe.eval(&tape, p);
            if !v.is_nan() {
                prop_assert!(same(v, pe.eval(&shorter, p)));
            }
        }
    }

    /// Simplifying with every choice `Both` changes nothing.
    #[test]
    fn all_both_is_identity(s in any_shape()) {
        let tape = Tape::new(&s);
        let both = vec![Choice::Both; tape.choice_count()];
        prop_assert!(tape.simplify(&both).ptr_eq(&tape));
    }

    /// The gradient matches central finite differences where the function is smooth
    /// (two step sizes agree, so no kink or jump lies within the step).
    #[test]
    fn gradient_matches_finite_differences(
        s in smooth_shape(), p in [-2.0..2.0f64, -2.0..2.0f64, -2.0..2.0f64]
    ) {
        let tape = Tape::new(&s);
        let mut pe = PointEval::new();
        let g = GradEval::new().eval(&tape, p);
        if !g.v.is_finite() || g.v.abs() > 1e6 {
            return Ok(());
        }
        for k in 0..3 {
            let mut fd = |h: f64| {
                let (mut a, mut b) = (p, p);
                a[k] += h;
                b[k] -= h;
                (pe.eval(&tape, a) - pe.eval(&tape, b)) / (2.0 * h)
            };
            let (d1, d2) = (fd(1e-4), fd(5e-5));
            if !d1.is_finite() || !d2.is_finite() || (d1 - d2).abs() > 1e-5 * (1.0 + d1.abs()) {
                continue; // not smooth here
            }
            let d = g.d[k];
            if !d.is_finite() {
                continue; // allowed where the derivative is undefined (e.g. sqrt at 0)
            }
            prop_assert!(
                (d - d2).abs() <= 1e-4 * (1.0 + d2.abs()),
                "{:?} at {:?}: d/d{} = {} but finite difference {}", s, p, k, d, d2
            );
        }
    }
}
