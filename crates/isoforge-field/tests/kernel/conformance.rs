//! One conformance suite, written once and instantiated for every evaluator (as fidget's
//! is): every operation on awkward inputs (NaN, ±inf, ±0, huge, tiny) against the
//! reference walk of the shape tree, the same on simplified tapes, and the NaN and
//! signed-zero rules of `min`, `max` and `modulo` against written-out values.
//!
//! An evaluator joins the suite by implementing [`Evaluator`] (its answers at a list of
//! points) and one line of `conformance!` at the bottom of this file.

use isoforge_field::{
    BatchEval, BinaryOp, GradEval, Interval, IntervalEval, PointEval, Shape, Tape,
};

use crate::common::*;

/// What an evaluator answered at one point.
#[derive(Clone, Copy, Debug)]
pub enum Outcome {
    /// A value, which must equal the true one bit for bit (or both be NaN).
    Value(f64),
    /// An enclosure of the one-point box, which must contain the true value (NaN only in
    /// `ENTIRE`).
    Enclosure(Interval),
    /// The evaluator cannot be asked at this point (an interval cannot sit at infinity).
    Skipped,
}

impl Outcome {
    /// True when this answer is right for a point whose true value is `want`.
    fn agrees(self, want: f64) -> bool {
        match self {
            Outcome::Value(v) => same(v, want),
            Outcome::Enclosure(i) => encloses(i, want),
            Outcome::Skipped => true,
        }
    }
}

/// An evaluator under test.
pub trait Evaluator {
    /// Its name in failure messages.
    const NAME: &'static str;
    /// A fresh evaluator.
    fn new() -> Self;
    /// Its answers at every point of `pts` (in order) with `tape`.
    fn answers(&mut self, tape: &Tape, pts: &[[f64; 3]]) -> Vec<Outcome>;
}

pub struct Point(PointEval);
pub struct Batch(BatchEval);
pub struct GradValue(GradEval);
pub struct IntervalAtPoint(IntervalEval);

impl Evaluator for Point {
    const NAME: &'static str = "point";
    fn new() -> Self {
        Point(PointEval::new())
    }
    fn answers(&mut self, tape: &Tape, pts: &[[f64; 3]]) -> Vec<Outcome> {
        pts.iter()
            .map(|&p| Outcome::Value(self.0.eval(tape, p)))
            .collect()
    }
}

impl Evaluator for Batch {
    const NAME: &'static str = "batch";
    fn new() -> Self {
        Batch(BatchEval::new())
    }
    fn answers(&mut self, tape: &Tape, pts: &[[f64; 3]]) -> Vec<Outcome> {
        let [xs, ys, zs] = [0, 1, 2].map(|k| pts.iter().map(|p| p[k]).collect::<Vec<_>>());
        let mut out = vec![0.0; pts.len()];
        self.0.eval(tape, &xs, &ys, &zs, &mut out);
        out.into_iter().map(Outcome::Value).collect()
    }
}

impl Evaluator for GradValue {
    const NAME: &'static str = "gradient (value)";
    fn new() -> Self {
        GradValue(GradEval::new())
    }
    fn answers(&mut self, tape: &Tape, pts: &[[f64; 3]]) -> Vec<Outcome> {
        pts.iter()
            .map(|&p| Outcome::Value(self.0.eval(tape, p).v))
            .collect()
    }
}

impl Evaluator for IntervalAtPoint {
    const NAME: &'static str = "interval";
    fn new() -> Self {
        IntervalAtPoint(IntervalEval::new())
    }
    fn answers(&mut self, tape: &Tape, pts: &[[f64; 3]]) -> Vec<Outcome> {
        pts.iter()
            .map(|&p| match point_box(p) {
                Some(b) => Outcome::Enclosure(self.0.eval(tape, b)),
                None => Outcome::Skipped,
            })
            .collect()
    }
}

/// Every operation on x (and on x, y), a few compositions, the custom node, a constant
/// and a variable alone.
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
    out.push(Shape::constant(-2.0));
    out.push(z);
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

/// Every expression at every awkward point agrees with the reference walk.
fn agrees_with_the_reference<E: Evaluator>() {
    let pts = points();
    let mut ev = E::new();
    for s in expressions() {
        let tape = Tape::new(&s);
        for (answer, p) in ev.answers(&tape, &pts).into_iter().zip(&pts) {
            let want = reference(&s, *p);
            assert!(
                answer.agrees(want),
                "{} {s:?} at {p:?}: {answer:?}, want {want}",
                E::NAME
            );
        }
    }
}

/// The tape simplified on a one-point box answers the same there (a value that is NaN
/// may come from a branch simplification dropped only for enclosures, so values are
/// compared where defined; enclosures always).
fn agrees_on_simplified_tapes<E: Evaluator>() {
    let mut ev = E::new();
    let mut ie = IntervalEval::new();
    let mut checked = 0;
    for s in expressions() {
        let tape = Tape::new(&s);
        for p in points() {
            let Some(b) = point_box(p) else { continue };
            ie.eval(&tape, b);
            let short = tape.simplify(ie.choices());
            assert!(short.len() <= tape.len());
            let want = reference(&s, p);
            let answer = ev.answers(&short, &[p])[0];
            let skip = want.is_nan() && matches!(answer, Outcome::Value(_));
            assert!(
                skip || answer.agrees(want),
                "{} on the simplified {s:?} at {p:?}: {answer:?}, want {want}",
                E::NAME
            );
            checked += 1;
        }
    }
    assert!(checked > 1000);
}

/// One evaluator over tapes of different sizes in turn (its buffers are reused), with a
/// point count that is no multiple of a batch block.
fn reuses_buffers_across_tapes<E: Evaluator>() {
    let (x, y) = (Shape::x(), Shape::y());
    let big = (0..50).fold(x.clone(), |acc, i| acc.min(&(&y - i as f64).square()));
    let small = x.clone() + 1.0;
    let pts: Vec<[f64; 3]> = (0..1000)
        .map(|i| [i as f64 * 0.01, i as f64 * 0.07 - 20.0, 0.0])
        .collect();
    let mut ev = E::new();
    for s in [&big, &small, &big, &small] {
        let tape = Tape::new(s);
        for (answer, p) in ev.answers(&tape, &pts).into_iter().zip(&pts) {
            let want = reference(s, *p);
            assert!(
                answer.agrees(want),
                "{} at {p:?}: {answer:?}, want {want}",
                E::NAME
            );
        }
    }
}

const NAN: f64 = f64::NAN;
const INF: f64 = f64::INFINITY;

/// `min`, `max` and `modulo` written out: `(op, a, b, a op b)`, where a zero result is
/// compared with its sign.
///
/// The rules we chose, and why:
/// - `min` and `max` propagate NaN: if either side is NaN, so is the result. IEEE
///   `minNum` would return the other side, and a model undefined somewhere would then
///   look defined there (inside or outside at random). The interval evaluator stays
///   consistent by marking a min or max "may be NaN" (so `ENTIRE`) whenever either side
///   may be, and by choosing `Both` there, so simplification never drops the branch
///   that makes a point NaN.
/// - On a tie `min` and `max` return their left operand, so `min(-0, +0)` is `-0` and
///   `min(+0, -0)` is `+0`: a fixed rule lets every evaluator agree bit for bit, where
///   `f64::min` leaves the choice open. (Intervals cannot tell -0 from +0; nothing to
///   keep consistent there.)
/// - `modulo(a, b)` is `a - b * floor(a / b)`, the remainder with the sign of `b` (what
///   a repeating pattern wants: `x mod 2` is in [0, 2) for negative x too), computed as
///   written: `b = ±0`, `a = ±inf` and `b = ±inf` give NaN (`inf * 0`), an exact multiple
///   gives `+0` whatever the signs, and a tiny negative `a` rounds to `b` itself (the
///   interval of a - b·floor(a/b), composed from rigorous steps, still encloses it). The
///   interval evaluator returns `ENTIRE` (may be NaN) for a divisor that may be 0 or an
///   unbounded operand, the cases that can give NaN.
const PINNED: [(BinaryOp, f64, f64, f64); 34] = [
    (BinaryOp::Min, 1.0, 2.0, 1.0),
    (BinaryOp::Min, 2.0, 1.0, 1.0),
    (BinaryOp::Min, -0.0, 0.0, -0.0),
    (BinaryOp::Min, 0.0, -0.0, 0.0),
    (BinaryOp::Min, NAN, 1.0, NAN),
    (BinaryOp::Min, 1.0, NAN, NAN),
    (BinaryOp::Min, NAN, -INF, NAN),
    (BinaryOp::Min, -INF, 1.0, -INF),
    (BinaryOp::Min, INF, 1.0, 1.0),
    (BinaryOp::Min, INF, -INF, -INF),
    (BinaryOp::Max, 1.0, 2.0, 2.0),
    (BinaryOp::Max, -0.0, 0.0, -0.0),
    (BinaryOp::Max, 0.0, -0.0, 0.0),
    (BinaryOp::Max, NAN, 1.0, NAN),
    (BinaryOp::Max, 1.0, NAN, NAN),
    (BinaryOp::Max, -INF, NAN, NAN),
    (BinaryOp::Max, INF, 1.0, INF),
    (BinaryOp::Max, -INF, 1.0, 1.0),
    (BinaryOp::Mod, 5.5, 2.0, 1.5),
    (BinaryOp::Mod, -5.5, 2.0, 0.5),
    (BinaryOp::Mod, 5.5, -2.0, -0.5),
    (BinaryOp::Mod, -5.5, -2.0, -1.5),
    (BinaryOp::Mod, 7.0, 2.5, 2.0),
    (BinaryOp::Mod, -0.0, 2.0, 0.0),
    (BinaryOp::Mod, -4.0, 2.0, 0.0),
    (BinaryOp::Mod, 4.0, -2.0, 0.0),
    (BinaryOp::Mod, -0.0, -2.0, 0.0),
    (BinaryOp::Mod, -1e-310, 1.0, 1.0),
    (BinaryOp::Mod, 5.5, 0.0, NAN),
    (BinaryOp::Mod, -5.5, -0.0, NAN),
    (BinaryOp::Mod, INF, 2.0, NAN),
    (BinaryOp::Mod, 5.5, INF, NAN),
    (BinaryOp::Mod, NAN, 2.0, NAN),
    (BinaryOp::Mod, 2.0, NAN, NAN),
];

/// Every pinned row, with both operands variables and with either one an immediate (the
/// tape's register-immediate forms), through the evaluator.
fn pinned_rules<E: Evaluator>() {
    let (x, y) = (Shape::x(), Shape::y());
    let mut ev = E::new();
    for (op, a, b, want) in PINNED {
        let forms = [
            (x.binary(op, &y), [a, b, 0.0]),
            (x.binary(op, &Shape::constant(b)), [a, 0.0, 0.0]),
            (Shape::constant(a).binary(op, &y), [0.0, b, 0.0]),
        ];
        for (s, p) in forms {
            let answer = ev.answers(&Tape::new(&s), &[p])[0];
            assert!(
                answer.agrees(want),
                "{}: {op:?}({a:?}, {b:?}) as {s:?}: {answer:?}, want {want:?}",
                E::NAME
            );
        }
    }
}

/// The suite for one evaluator: `conformance!(module_name, EvaluatorType);`.
macro_rules! conformance {
    ($name:ident, $eval:ty) => {
        mod $name {
            #[test]
            fn agrees_with_the_reference() {
                super::agrees_with_the_reference::<$eval>();
            }
            #[test]
            fn agrees_on_simplified_tapes() {
                super::agrees_on_simplified_tapes::<$eval>();
            }
            #[test]
            fn reuses_buffers_across_tapes() {
                super::reuses_buffers_across_tapes::<$eval>();
            }
            #[test]
            fn min_max_modulo_follow_the_pinned_rules() {
                super::pinned_rules::<$eval>();
            }
        }
    };
}

conformance!(point, super::Point);
conformance!(batch, super::Batch);
conformance!(grad, super::GradValue);
conformance!(interval, super::IntervalAtPoint);

#[test]
fn tapes_and_evaluators_cross_threads() {
    fn send_sync<T: Send + Sync>() {}
    fn send<T: Send>() {}
    send_sync::<Tape>();
    send_sync::<Shape>();
    send::<PointEval>();
    send::<BatchEval>();
    send::<IntervalEval>();
    send::<GradEval>();
    // One tape shared by threads, each with its own evaluator.
    let t = Tape::new(&(Shape::x().square() + Shape::y().sin()));
    let handles: Vec<_> = (0..2)
        .map(|i| {
            let t = t.clone();
            std::thread::spawn(move || PointEval::new().eval(&t, [i as f64, 0.0, 0.0]))
        })
        .collect();
    let v: Vec<f64> = handles.into_iter().map(|h| h.join().unwrap()).collect();
    assert_eq!(v, vec![0.0, 1.0]);
}

#[test]
fn a_variable_alone_has_a_unit_gradient() {
    let z = Tape::new(&Shape::z());
    assert_eq!(GradEval::new().eval(&z, [1.0, 2.0, 3.0]).d, [0.0, 0.0, 1.0]);
    let c = Tape::new(&Shape::constant(-2.0));
    assert_eq!(GradEval::new().eval(&c, [1.0, 2.0, 3.0]).d, [0.0; 3]);
}
