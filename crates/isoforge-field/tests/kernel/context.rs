//! Hash-consing, folding, identities, memoized remap, and graphs too deep for recursion.

use isoforge_field::{BinaryOp, Context, Interval, IntervalEval, PointEval, Shape, Tape, UnaryOp};
use proptest::prelude::*;

use crate::common::*;

#[test]
fn the_same_expression_built_twice_is_one_node() {
    let build = || {
        let (x, y) = (Shape::x(), Shape::y());
        (x.square() + y.sin() * 2.0).max(&(x - 1.0))
    };
    let mut ctx = Context::new();
    let a = ctx.import(&build());
    let n = ctx.len();
    let b = ctx.import(&build());
    assert_eq!(a, b);
    assert_eq!(ctx.len(), n, "second import added nodes");
}

#[test]
fn commutative_operands_are_normalised() {
    let (x, y) = (Shape::x(), Shape::y());
    let mut ctx = Context::new();
    let a = ctx.import(&(&x + &y));
    let b = ctx.import(&(&y + &x));
    assert_eq!(a, b);
    let c = ctx.import(&(&x * &y));
    let d = ctx.import(&(&y * &x));
    assert_eq!(c, d);
    // Not for non-commutative ones.
    let e = ctx.import(&(&x - &y));
    let f = ctx.import(&(&y - &x));
    assert_ne!(e, f);
}

#[test]
fn exact_identities_only() {
    let mut ctx = Context::new();
    let x = ctx.var(isoforge_field::Var::X);
    let zero = ctx.constant(0.0);
    let nzero = ctx.constant(-0.0);
    let one = ctx.constant(1.0);
    assert_ne!(zero, nzero, "constants are keyed by bits");
    assert_eq!(ctx.binary(BinaryOp::Sub, x, zero), x);
    assert_eq!(ctx.binary(BinaryOp::Add, x, nzero), x);
    assert_eq!(ctx.binary(BinaryOp::Mul, one, x), x);
    assert_eq!(ctx.binary(BinaryOp::Div, x, one), x);
    assert_eq!(ctx.binary(BinaryOp::Min, x, x), x);
    let n = ctx.unary(UnaryOp::Neg, x);
    assert_eq!(ctx.unary(UnaryOp::Neg, n), x);
    // x + 0 would turn -0 into +0 and x * 0 would hide NaN/inf: both kept.
    assert_ne!(ctx.binary(BinaryOp::Add, x, zero), x);
    let m = ctx.binary(BinaryOp::Mul, x, zero);
    assert_ne!(m, zero);
    // Folding: 2 * 3 is the constant 6.
    let two = ctx.constant(2.0);
    let three = ctx.constant(3.0);
    let six = ctx.binary(BinaryOp::Mul, two, three);
    assert_eq!(ctx.as_constant(six), Some(6.0));
    // NaN constants dedupe with themselves.
    let nan1 = ctx.constant(f64::NAN);
    let nan2 = ctx.constant(f64::NAN);
    assert_eq!(nan1, nan2);
}

#[test]
fn x_times_zero_keeps_nan_and_inf() {
    let s = Shape::x() * 0.0;
    let t = Tape::new(&s);
    let mut pe = PointEval::new();
    assert!(pe.eval(&t, [f64::INFINITY, 0.0, 0.0]).is_nan());
    assert_eq!(pe.eval(&t, [5.0, 0.0, 0.0]), 0.0);
}

#[test]
fn shared_subgraphs_are_imported_once() {
    // A diamond chain: each level uses the previous one twice. As a tree it has 2^40
    // nodes; as a DAG 40 levels.
    let mut s = Shape::x();
    for i in 0..40 {
        s = (&s + &s) * (i as f64 + 1.0).recip();
    }
    let mut ctx = Context::new();
    ctx.import(&s);
    assert!(ctx.len() < 200, "{} nodes", ctx.len());
    let t = Tape::new(&s);
    assert!(t.len() < 100);
    let mut pe = PointEval::new();
    assert!(pe.eval(&t, [1.0, 0.0, 0.0]).is_finite());
}

#[test]
fn remap_keeps_sharing() {
    let (x, y, z) = (Shape::x(), Shape::y(), Shape::z());
    let shared = (x.square() + y.square()).sqrt();
    let s = shared.min(&(&shared - 1.0).abs());
    let moved = s.remap(&(&x - 2.0), &(&y * 3.0), &z);
    // The remapped `shared` appears once: both uses point to one node.
    let isoforge_field::ShapeNode::Binary(_, a, b) = moved.node() else {
        panic!("not binary")
    };
    let isoforge_field::ShapeNode::Unary(_, inner) = b.node() else {
        panic!("not abs")
    };
    let isoforge_field::ShapeNode::Binary(_, c, _) = inner.node() else {
        panic!("not sub")
    };
    assert_eq!(a.id(), c.id());
    let mut pe = PointEval::new();
    let v = pe.eval(&Tape::new(&moved), [2.0, 1.0 / 3.0, 0.0]);
    assert_eq!(v, 0.0f64.min(1.0));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    #[test]
    fn hash_consing_is_stable_on_random_shapes(s in any_shape()) {
        let mut ctx = Context::new();
        let a = ctx.import(&s);
        let n = ctx.len();
        // A structurally equal copy (rebuilt through remap with x, y, z themselves; remap
        // folds constants again, so hash-consing must map it to the same node).
        let copy = s.remap(&Shape::x(), &Shape::y(), &Shape::z());
        let b = ctx.import(&copy);
        prop_assert_eq!(a, b);
        prop_assert_eq!(ctx.len(), n);
    }
}

const DEEP: usize = 100_000;

/// A 100,000-deep min chain: import, tape, evaluate, simplify and drop must not recurse.
/// Runs on a thread with a small (256 KiB) stack so recursion would fail loudly.
#[test]
fn deep_chains_do_not_overflow_the_stack() {
    std::thread::Builder::new()
        .stack_size(256 * 1024)
        .spawn(|| {
            let (x, y) = (Shape::x(), Shape::y());
            let mut s = x.clone();
            for i in 0..DEEP {
                s = s.min(&(&y + i as f64));
            }
            let t = Tape::new(&s);
            assert_eq!(t.choice_count(), DEEP);
            let mut pe = PointEval::new();
            assert_eq!(pe.eval(&t, [5.0, 1.0, 0.0]), 1.0);
            let mut ie = IntervalEval::new();
            let b = Interval::try_from((0.0, 0.5)).unwrap();
            let i = ie.eval(&t, [Interval::try_from((10.0, 11.0)).unwrap(), b, b]);
            assert!(i.inf() <= 0.0 && i.sup() >= 0.5);
            let short = t.simplify(ie.choices());
            assert!(short.len() < 10, "{}", short.len());
            let moved = s.remap(&(&x + 1.0), &y, &Shape::z());
            drop(s);
            drop(moved);
            // A unary chain too (one child per level).
            let mut u = x.clone();
            for _ in 0..DEEP {
                u = -u.abs();
            }
            let t = Tape::new(&u);
            assert!(t.len() < 10);
            drop(u);
        })
        .unwrap()
        .join()
        .expect("deep-chain thread panicked (stack overflow?)");
}
