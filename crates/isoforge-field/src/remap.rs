//! Memoized substitution of x, y and z: how transforms are built.

use std::collections::HashMap;

use crate::shape::{Shape, ShapeNode, Var};

/// Rebuilds `shape` with x, y, z replaced. Each shared node is rebuilt once, so shared
/// subgraphs stay shared in the result. Iterative (an explicit stack), so arbitrarily deep
/// graphs do not overflow the call stack.
pub fn remap(shape: &Shape, x: &Shape, y: &Shape, z: &Shape) -> Shape {
    let mut memo: HashMap<usize, Shape> = HashMap::new();
    let mut stack: Vec<(Shape, bool)> = vec![(shape.clone(), false)];
    while let Some((s, expanded)) = stack.pop() {
        if memo.contains_key(&s.id()) {
            continue;
        }
        let kids: Vec<&Shape> = match s.node() {
            ShapeNode::Var(_) | ShapeNode::Const(_) => vec![],
            ShapeNode::Unary(_, a) => vec![a],
            ShapeNode::Binary(_, a, b) => vec![a, b],
            ShapeNode::Custom(_, i) => i.iter().collect(),
        };
        if !expanded && !kids.is_empty() {
            let pending: Vec<Shape> = kids
                .into_iter()
                .filter(|k| !memo.contains_key(&k.id()))
                .cloned()
                .collect();
            stack.push((s.clone(), true));
            stack.extend(pending.into_iter().map(|k| (k, false)));
            continue;
        }
        let get = |c: &Shape| memo[&c.id()].clone();
        let out = match s.node() {
            ShapeNode::Var(Var::X) => x.clone(),
            ShapeNode::Var(Var::Y) => y.clone(),
            ShapeNode::Var(Var::Z) => z.clone(),
            ShapeNode::Const(_) => s.clone(),
            ShapeNode::Unary(op, a) => get(a).unary(*op),
            ShapeNode::Binary(op, a, b) => get(a).binary(*op, &get(b)),
            ShapeNode::Custom(field, inputs) => {
                let inputs = inputs.clone().map(|i| get(&i));
                Shape(std::sync::Arc::new(ShapeNode::Custom(
                    field.clone(),
                    inputs,
                )))
            }
        };
        memo.insert(s.id(), out);
    }
    memo[&shape.id()].clone()
}
