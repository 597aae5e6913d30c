//! Custom nodes: the batch evaluator hands them whole blocks, and the interval gradient
//! carries their slope enclosures through the substitutions around them.

use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

use isoforge_field::{BatchEval, CustomField, Interval, IntervalGradEval, Shape, Tape};

/// The distance from the origin, counting how it is called.
#[derive(Default)]
struct Counted {
    points: AtomicUsize,
    blocks: AtomicUsize,
}

impl CustomField for Counted {
    fn name(&self) -> &str {
        "counted"
    }
    fn value(&self, p: [f64; 3]) -> f64 {
        self.points.fetch_add(1, Ordering::Relaxed);
        (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt()
    }
    fn interval(&self, b: [Interval; 3]) -> Interval {
        (b[0].sqr() + b[1].sqr() + b[2].sqr()).sqrt()
    }
    fn gradient(&self, p: [f64; 3]) -> [f64; 4] {
        let v = self.value(p);
        [v, p[0] / v, p[1] / v, p[2] / v]
    }
    fn values(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        self.blocks.fetch_add(1, Ordering::Relaxed);
        for i in 0..out.len() {
            out[i] = (xs[i] * xs[i] + ys[i] * ys[i] + zs[i] * zs[i]).sqrt();
        }
    }
    fn interval_gradient(&self, _: [Interval; 3]) -> [Interval; 3] {
        let unit = Interval::try_from((-1.0, 1.0)).expect("interval");
        [unit; 3]
    }
}

#[test]
fn batch_hands_custom_nodes_whole_blocks() {
    let field = Arc::new(Counted::default());
    let s = Shape::custom(field.clone()) - 1.0;
    let tape = Tape::new(&s);
    let n = 1000;
    let xs: Vec<f64> = (0..n).map(|i| i as f64 * 0.01).collect();
    let zeros = vec![0.0; n];
    let mut out = vec![0.0; n];
    BatchEval::new().eval(&tape, &xs, &zeros, &zeros, &mut out);
    assert_eq!(field.blocks.load(Ordering::Relaxed), n.div_ceil(256));
    assert_eq!(
        field.points.load(Ordering::Relaxed),
        0,
        "no point-by-point calls"
    );
    for (x, v) in xs.iter().zip(&out) {
        assert_eq!(*v, x - 1.0);
    }
}

#[test]
fn interval_gradient_applies_the_chain_rule_through_a_substitution() {
    let field = Arc::new(Counted::default());
    let (x, y, z) = (Shape::x(), Shape::y(), Shape::z());
    // Evaluated at (2x, y, -z): d/dx spans [-2, 2], d/dy [-1, 1], d/dz [-1, 1].
    let s = Shape::custom(field).remap(&(2.0 * &x), &y, &-z);
    let unit = Interval::try_from((0.0, 1.0)).expect("interval");
    let g = IntervalGradEval::new().eval(&Tape::new(&s), [unit; 3]);
    assert_eq!((g.d[0].inf(), g.d[0].sup()), (-2.0, 2.0));
    assert_eq!((g.d[1].inf(), g.d[1].sup()), (-1.0, 1.0));
    assert_eq!((g.d[2].inf(), g.d[2].sup()), (-1.0, 1.0));
    assert!(g.slope_bound() >= 6f64.sqrt());
    // A node that knows nothing of its slopes leaves them unbounded.
    let plain = Shape::custom(Arc::new(Plain)) * 3.0;
    let g = IntervalGradEval::new().eval(&Tape::new(&plain), [unit; 3]);
    assert!(g.d.iter().all(|d| d.is_entire()));
    assert_eq!(g.slope_bound(), f64::INFINITY);
}

/// A custom node with the default batch and slope callbacks.
struct Plain;

impl CustomField for Plain {
    fn name(&self) -> &str {
        "plain"
    }
    fn value(&self, p: [f64; 3]) -> f64 {
        p[0]
    }
    fn interval(&self, b: [Interval; 3]) -> Interval {
        b[0]
    }
    fn gradient(&self, p: [f64; 3]) -> [f64; 4] {
        [p[0], 1.0, 0.0, 0.0]
    }
}

#[test]
fn default_batch_callback_agrees_with_points() {
    let s = Shape::custom(Arc::new(Plain)) + Shape::y();
    let tape = Tape::new(&s);
    let xs = [1.0, 2.0, 3.0];
    let ys = [0.5, 0.25, 0.0];
    let mut out = [0.0; 3];
    BatchEval::new().eval(&tape, &xs, &ys, &[0.0; 3], &mut out);
    assert_eq!(out, [1.5, 2.25, 3.0]);
}
