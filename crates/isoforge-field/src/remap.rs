//! Memoized substitution of x, y and z: how transforms are built.

use std::collections::HashMap;

use crate::shape::{Shape, ShapeNode, Var};

/// Rebuilds `shape` with x, y, z replaced. Each shared node is rebuilt once, so shared
/// subgraphs stay shared in the result.
pub fn remap(shape: &Shape, x: &Shape, y: &Shape, z: &Shape) -> Shape {
    let mut memo: HashMap<usize, Shape> = HashMap::new();
    remap_node(shape, [x, y, z], &mut memo)
}

fn remap_node(shape: &Shape, xyz: [&Shape; 3], memo: &mut HashMap<usize, Shape>) -> Shape {
    if let Some(done) = memo.get(&shape.id()) {
        return done.clone();
    }
    let out = match shape.node() {
        ShapeNode::Var(Var::X) => xyz[0].clone(),
        ShapeNode::Var(Var::Y) => xyz[1].clone(),
        ShapeNode::Var(Var::Z) => xyz[2].clone(),
        ShapeNode::Const(_) => shape.clone(),
        ShapeNode::Unary(op, a) => remap_node(a, xyz, memo).unary(*op),
        ShapeNode::Binary(op, a, b) => {
            let a = remap_node(a, xyz, memo);
            let b = remap_node(b, xyz, memo);
            a.binary(*op, &b)
        }
        ShapeNode::Custom(field, inputs) => {
            let inputs = inputs.clone().map(|i| remap_node(&i, xyz, memo));
            Shape(std::sync::Arc::new(ShapeNode::Custom(
                field.clone(),
                inputs,
            )))
        }
    };
    memo.insert(shape.id(), out.clone());
    out
}
