//! `Context`: the hash-consed arena a shape is deduplicated into before it becomes a tape.
//!
//! Every node is stored once: inserting an operation whose operands and opcode already exist
//! returns the existing node. Constants are keyed by bit pattern (so `0.0` and `-0.0` stay
//! apart, and NaN constants dedupe), custom nodes by the address of their callbacks.
//! Only identities that can never change a result are applied on insert (see
//! [`Context::binary`] and [`Context::unary`]); everything else is left to evaluation.

use std::collections::HashMap;
use std::sync::Arc;

use crate::custom::CustomField;
use crate::eval::scalar;
use crate::op::{BinaryOp, UnaryOp};
use crate::shape::{Shape, ShapeNode, Var};

/// A node in a [`Context`].
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct NodeId(pub u32);

impl NodeId {
    fn index(self) -> usize {
        self.0 as usize
    }
}

/// One unique node of a [`Context`]. Operands always have smaller ids than the node.
#[derive(Clone)]
pub enum Node {
    /// A coordinate.
    Var(Var),
    /// A number.
    Const(f64),
    /// An operation on one node.
    Unary(UnaryOp, NodeId),
    /// An operation on two nodes.
    Binary(BinaryOp, NodeId, NodeId),
    /// Callbacks evaluated at the point given by three nodes.
    Custom(Arc<dyn CustomField>, [NodeId; 3]),
}

/// The hash key of a node: constants by bits, custom nodes by callback address.
#[derive(Copy, Clone, PartialEq, Eq, Hash)]
enum Key {
    Var(Var),
    Const(u64),
    Unary(UnaryOp, NodeId),
    Binary(BinaryOp, NodeId, NodeId),
    Custom(usize, [NodeId; 3]),
}

/// An arena of unique nodes: inserting an operation that already exists returns the
/// existing node (hash-consing), and operations on constants are folded.
#[derive(Default)]
pub struct Context {
    nodes: Vec<Node>,
    index: HashMap<Key, NodeId>,
    /// `Shape::id()` -> node, so shared subgraphs are imported once. The shapes are kept
    /// alive alongside (`keep`) so an address cannot be reused by another shape while the
    /// memo entry exists.
    imported: HashMap<usize, NodeId>,
    keep: Vec<Shape>,
}

impl Context {
    /// An empty arena.
    pub fn new() -> Self {
        Self::default()
    }

    /// The number of unique nodes.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }
    /// True when there are no nodes.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The node behind an id. Panics on an id from another context (a programming error).
    pub fn node(&self, id: NodeId) -> &Node {
        &self.nodes[id.index()]
    }

    /// The value, if the node is a constant.
    pub fn as_constant(&self, id: NodeId) -> Option<f64> {
        match self.node(id) {
            Node::Const(c) => Some(*c),
            _ => None,
        }
    }

    fn insert(&mut self, key: Key, node: Node) -> NodeId {
        if let Some(id) = self.index.get(&key) {
            return *id;
        }
        let id = NodeId(u32::try_from(self.nodes.len()).unwrap_or(u32::MAX));
        self.nodes.push(node);
        self.index.insert(key, id);
        id
    }

    /// A coordinate node.
    pub fn var(&mut self, v: Var) -> NodeId {
        self.insert(Key::Var(v), Node::Var(v))
    }

    /// A constant node (deduplicated by bit pattern).
    pub fn constant(&mut self, c: f64) -> NodeId {
        self.insert(Key::Const(c.to_bits()), Node::Const(c))
    }

    /// A unary operation, folded when the operand is constant. Identities (bitwise exact):
    /// `--a = a`, `||a|| = |a|`, `|-a| = |a|`.
    pub fn unary(&mut self, op: UnaryOp, a: NodeId) -> NodeId {
        if let Some(c) = self.as_constant(a) {
            return self.constant(scalar::unary(op, c));
        }
        match (op, self.node(a)) {
            // -(-a) is bitwise a (negation only flips the sign bit, NaN included).
            (UnaryOp::Neg, Node::Unary(UnaryOp::Neg, inner)) => return *inner,
            // Taking abs twice changes nothing.
            (UnaryOp::Abs, Node::Unary(UnaryOp::Abs, _)) => return a,
            // |-a| is bitwise |a| (abs clears the sign bit negation flipped).
            (UnaryOp::Abs, Node::Unary(UnaryOp::Neg, inner)) => {
                let inner = *inner;
                return self.unary(UnaryOp::Abs, inner);
            }
            _ => {}
        }
        self.insert(Key::Unary(op, a), Node::Unary(op, a))
    }

    /// A binary operation, folded when both operands are constant.
    ///
    /// Identities applied (each gives a bitwise-identical result for every input, NaN and
    /// signed zeros included): `a - 0`, `a + (-0)`, `(-0) + a`, `a * 1`, `1 * a`, `a / 1`,
    /// `min(a, a)`, `max(a, a)`. Not applied: `a + 0` (turns `-0` into `+0`, which
    /// `atan2` and `1/a` can see) and `a * 0` (NaN and infinity give NaN, not 0).
    /// Additions and multiplications are stored with their operands in id order, so
    /// `a + b` and `b + a` are one node (IEEE addition and multiplication commute).
    pub fn binary(&mut self, op: BinaryOp, a: NodeId, b: NodeId) -> NodeId {
        let (ca, cb) = (self.as_constant(a), self.as_constant(b));
        if let (Some(x), Some(y)) = (ca, cb) {
            return self.constant(scalar::binary(op, x, y));
        }
        let is = |c: Option<f64>, v: f64| c.is_some_and(|c| c.to_bits() == v.to_bits());
        match op {
            BinaryOp::Sub if is(cb, 0.0) => return a,
            BinaryOp::Add if is(cb, -0.0) => return a,
            BinaryOp::Add if is(ca, -0.0) => return b,
            BinaryOp::Mul | BinaryOp::Div if is(cb, 1.0) => return a,
            BinaryOp::Mul if is(ca, 1.0) => return b,
            BinaryOp::Min | BinaryOp::Max if a == b => return a,
            _ => {}
        }
        let (a, b) = match op {
            BinaryOp::Add | BinaryOp::Mul if b < a => (b, a),
            _ => (a, b),
        };
        self.insert(Key::Binary(op, a, b), Node::Binary(op, a, b))
    }

    /// A custom node evaluated at the point given by three nodes.
    pub fn custom(&mut self, field: Arc<dyn CustomField>, inputs: [NodeId; 3]) -> NodeId {
        let key = Key::Custom(Arc::as_ptr(&field) as *const () as usize, inputs);
        self.insert(key, Node::Custom(field, inputs))
    }

    /// Inserts a shape's whole graph; returns its root.
    ///
    /// Iterative (an explicit stack), so graphs many thousands of nodes deep import without
    /// touching the call stack's limit; memoized by [`Shape::id`] so each shared subgraph is
    /// visited once.
    pub fn import(&mut self, shape: &Shape) -> NodeId {
        if let Some(id) = self.imported.get(&shape.id()) {
            return *id;
        }
        // (shape, children pushed?)
        let mut stack: Vec<(Shape, bool)> = vec![(shape.clone(), false)];
        while let Some((s, expanded)) = stack.pop() {
            if self.imported.contains_key(&s.id()) {
                continue;
            }
            if !expanded {
                stack.push((s.clone(), true));
                for child in children(&s) {
                    if !self.imported.contains_key(&child.id()) {
                        stack.push((child.clone(), false));
                    }
                }
                continue;
            }
            let get = |ctx: &Self, c: &Shape| ctx.imported[&c.id()];
            let id = match s.node() {
                ShapeNode::Var(v) => self.var(*v),
                ShapeNode::Const(c) => self.constant(*c),
                ShapeNode::Unary(op, a) => {
                    let a = get(self, a);
                    self.unary(*op, a)
                }
                ShapeNode::Binary(op, a, b) => {
                    let (a, b) = (get(self, a), get(self, b));
                    self.binary(*op, a, b)
                }
                ShapeNode::Custom(field, inputs) => {
                    let ins = [
                        get(self, &inputs[0]),
                        get(self, &inputs[1]),
                        get(self, &inputs[2]),
                    ];
                    self.custom(field.clone(), ins)
                }
            };
            self.imported.insert(s.id(), id);
            self.keep.push(s);
        }
        self.imported[&shape.id()]
    }
}

/// The operands of a shape node.
fn children(s: &Shape) -> Vec<&Shape> {
    match s.node() {
        ShapeNode::Var(_) | ShapeNode::Const(_) => vec![],
        ShapeNode::Unary(_, a) => vec![a],
        ShapeNode::Binary(_, a, b) => vec![a, b],
        ShapeNode::Custom(_, i) => i.iter().collect(),
    }
}
