//! Shared helpers: reference evaluation, a custom field, strategies.

use std::collections::HashMap;
use std::sync::Arc;

use isoforge_field::eval::scalar;
use isoforge_field::{BinaryOp, CustomField, Interval, Shape, ShapeNode, UnaryOp, Var};
use proptest::prelude::*;

/// Evaluates a shape by walking its tree (memoized by node), independent of Context/Tape.
pub fn reference(s: &Shape, p: [f64; 3]) -> f64 {
    fn go(s: &Shape, p: [f64; 3], memo: &mut HashMap<usize, f64>) -> f64 {
        if let Some(v) = memo.get(&s.id()) {
            return *v;
        }
        let v = match s.node() {
            ShapeNode::Var(Var::X) => p[0],
            ShapeNode::Var(Var::Y) => p[1],
            ShapeNode::Var(Var::Z) => p[2],
            ShapeNode::Const(c) => *c,
            ShapeNode::Unary(op, a) => scalar::unary(*op, go(a, p, memo)),
            ShapeNode::Binary(op, a, b) => {
                let a = go(a, p, memo);
                scalar::binary(*op, a, go(b, p, memo))
            }
            ShapeNode::Custom(f, ins) => {
                let q = [
                    go(&ins[0], p, memo),
                    go(&ins[1], p, memo),
                    go(&ins[2], p, memo),
                ];
                f.value(q)
            }
        };
        memo.insert(s.id(), v);
        v
    }
    go(s, p, &mut HashMap::new())
}

/// Equal as bits, or both NaN.
pub fn same(a: f64, b: f64) -> bool {
    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
}

/// True when `v` is inside `i` (infinite values count as inside an interval unbounded on
/// that side; NaN only inside ENTIRE).
pub fn encloses(i: Interval, v: f64) -> bool {
    if v.is_nan() {
        return i.inf() == f64::NEG_INFINITY && i.sup() == f64::INFINITY;
    }
    i.inf() <= v && v <= i.sup()
}

/// A degenerate box at a point, if every coordinate is finite.
pub fn point_box(p: [f64; 3]) -> Option<[Interval; 3]> {
    let i = |v: f64| Interval::try_from((v, v)).ok();
    Some([i(p[0])?, i(p[1])?, i(p[2])?])
}

/// A custom field: a paraboloid `p0^2 + p1^2 - p2` with exact callbacks.
pub struct Paraboloid;

impl CustomField for Paraboloid {
    fn name(&self) -> &str {
        "paraboloid"
    }
    fn value(&self, p: [f64; 3]) -> f64 {
        p[0] * p[0] + p[1] * p[1] - p[2]
    }
    fn interval(&self, b: [Interval; 3]) -> Interval {
        b[0].sqr() + b[1].sqr() - b[2]
    }
    fn gradient(&self, p: [f64; 3]) -> [f64; 4] {
        [self.value(p), 2.0 * p[0], 2.0 * p[1], -1.0]
    }
    fn interval_gradient(&self, b: [Interval; 3]) -> [Interval; 3] {
        let two = Interval::try_from((2.0, 2.0)).expect("point");
        let minus_one = Interval::try_from((-1.0, -1.0)).expect("point");
        [two * b[0], two * b[1], minus_one]
    }
}

/// The shared instance, so hash-consing sees one custom node.
pub fn paraboloid() -> Shape {
    static P: std::sync::LazyLock<Arc<Paraboloid>> =
        std::sync::LazyLock::new(|| Arc::new(Paraboloid));
    Shape::custom(P.clone())
}

pub const UNARY: [UnaryOp; 20] = [
    UnaryOp::Neg,
    UnaryOp::Abs,
    UnaryOp::Recip,
    UnaryOp::Sqrt,
    UnaryOp::Square,
    UnaryOp::Sin,
    UnaryOp::Cos,
    UnaryOp::Tan,
    UnaryOp::Asin,
    UnaryOp::Acos,
    UnaryOp::Atan,
    UnaryOp::Exp,
    UnaryOp::Ln,
    UnaryOp::Floor,
    UnaryOp::Ceil,
    UnaryOp::Round,
    UnaryOp::PowI(3),
    UnaryOp::PowI(-2),
    UnaryOp::PowI(-3),
    UnaryOp::PowI(4),
];

pub const BINARY: [BinaryOp; 9] = [
    BinaryOp::Add,
    BinaryOp::Sub,
    BinaryOp::Mul,
    BinaryOp::Div,
    BinaryOp::Min,
    BinaryOp::Max,
    BinaryOp::Atan2,
    BinaryOp::Pow,
    BinaryOp::Mod,
];

/// Awkward numbers every evaluator must agree on.
pub const AWKWARD: [f64; 16] = [
    f64::NAN,
    f64::INFINITY,
    f64::NEG_INFINITY,
    0.0,
    -0.0,
    1e308,
    -1e308,
    1e-310,
    -1e-310,
    0.5,
    -0.5,
    1.0,
    -1.0,
    std::f64::consts::FRAC_PI_2,
    3.0,
    -7.25,
];

fn leaf() -> impl Strategy<Value = Shape> {
    prop_oneof![
        4 => Just(Shape::x()),
        4 => Just(Shape::y()),
        4 => Just(Shape::z()),
        3 => (-10.0..10.0f64).prop_map(Shape::constant),
        1 => proptest::sample::select(AWKWARD.to_vec()).prop_map(Shape::constant),
        1 => Just(paraboloid()),
    ]
}

/// Random expressions over every operation (and the custom node, sometimes remapped).
pub fn any_shape() -> impl Strategy<Value = Shape> {
    leaf().prop_recursive(6, 48, 3, |inner| {
        prop_oneof![
            2 => (proptest::sample::select(UNARY.to_vec()), inner.clone()).prop_map(|(op, a)| a.unary(op)),
            3 => (proptest::sample::select(BINARY.to_vec()), inner.clone(), inner.clone())
                .prop_map(|(op, a, b)| a.binary(op, &b)),
            1 => (inner.clone(), inner.clone(), inner).prop_map(|(a, b, c)| paraboloid().remap(&a, &b, &c)),
        ]
    })
}

/// Random expressions over smooth operations only (for derivative checks).
pub fn smooth_shape() -> impl Strategy<Value = Shape> {
    let leaf = prop_oneof![
        Just(Shape::x()),
        Just(Shape::y()),
        Just(Shape::z()),
        (-2.0..2.0f64).prop_map(Shape::constant),
    ];
    let unary = [
        UnaryOp::Neg,
        UnaryOp::Square,
        UnaryOp::Sin,
        UnaryOp::Cos,
        UnaryOp::Atan,
        UnaryOp::PowI(3),
        UnaryOp::Abs,
        UnaryOp::Exp,
        UnaryOp::Sqrt,
        UnaryOp::Ln,
    ];
    let binary = [
        BinaryOp::Add,
        BinaryOp::Sub,
        BinaryOp::Mul,
        BinaryOp::Div,
        BinaryOp::Min,
        BinaryOp::Max,
        BinaryOp::Atan2,
        BinaryOp::Pow,
    ];
    leaf.prop_recursive(5, 24, 3, move |inner| {
        prop_oneof![
            (proptest::sample::select(unary.to_vec()), inner.clone())
                .prop_map(|(op, a)| a.unary(op)),
            (
                proptest::sample::select(binary.to_vec()),
                inner.clone(),
                inner.clone()
            )
                .prop_map(|(op, a, b)| a.binary(op, &b)),
            (inner.clone(), inner.clone(), inner)
                .prop_map(|(a, b, c)| paraboloid().remap(&a, &b, &c)),
        ]
    })
}

/// A random box: per axis a centre and a half-width from tiny to wide.
pub fn any_box() -> impl Strategy<Value = [(f64, f64); 3]> {
    let axis = (
        -4.0..4.0f64,
        prop_oneof![Just(0.0), Just(1e-9), 0.0..0.1f64, 0.0..4.0f64],
    )
        .prop_map(|(c, h)| (c - h, c + h));
    [axis.clone(), axis.clone(), axis]
}

/// Intervals of a box.
pub fn intervals(b: &[(f64, f64); 3]) -> [Interval; 3] {
    b.map(|(lo, hi)| Interval::try_from((lo, hi)).expect("valid box"))
}

/// Sample points of a box: its 8 corners, its centre, and points at the given fractions.
pub fn samples(b: &[(f64, f64); 3], fractions: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let mut out = Vec::new();
    for k in 0..8 {
        out.push([0, 1, 2].map(|i| if k >> i & 1 == 0 { b[i].0 } else { b[i].1 }));
    }
    out.push([0, 1, 2].map(|i| 0.5 * (b[i].0 + b[i].1)));
    for f in fractions {
        out.push([0, 1, 2].map(|i| (b[i].0 + f[i] * (b[i].1 - b[i].0)).clamp(b[i].0, b[i].1)));
    }
    out
}

/// `n` proptest cases, unless `PROPTEST_CASES` is set (for long hunts:
/// `PROPTEST_CASES=20000 cargo test -p isoforge-field --release`).
pub fn cases(n: u32) -> ProptestConfig {
    match std::env::var("PROPTEST_CASES") {
        Ok(_) => ProptestConfig::default(),
        Err(_) => ProptestConfig::with_cases(n),
    }
}
