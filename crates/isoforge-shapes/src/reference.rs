//! A plain tree-walking evaluator for this crate's tests: the written formulas are checked
//! against it without depending on the kernel's tapes, so a failure here is the library's.

use std::collections::HashMap;

use isoforge_field::eval::scalar;
use isoforge_field::{Shape, ShapeNode, Var};

/// The value of `s` at `p`, by walking its graph (memoized, so shared nodes cost once).
pub fn at(s: &Shape, p: [f64; 3]) -> f64 {
    walk(s, p, &mut HashMap::new())
}

fn walk(s: &Shape, p: [f64; 3], memo: &mut HashMap<usize, f64>) -> f64 {
    if let Some(v) = memo.get(&s.id()) {
        return *v;
    }
    let v = match s.node() {
        ShapeNode::Var(Var::X) => p[0],
        ShapeNode::Var(Var::Y) => p[1],
        ShapeNode::Var(Var::Z) => p[2],
        ShapeNode::Const(c) => *c,
        ShapeNode::Unary(op, a) => scalar::unary(*op, walk(a, p, memo)),
        ShapeNode::Binary(op, a, b) => {
            let (a, b) = (walk(a, p, memo), walk(b, p, memo));
            scalar::binary(*op, a, b)
        }
        ShapeNode::Custom(field, inputs) => {
            let q = [0, 1, 2].map(|i| walk(&inputs[i], p, memo));
            field.value(q)
        }
    };
    memo.insert(s.id(), v);
    v
}
