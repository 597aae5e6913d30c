//! `Shape`: a cheap, shareable handle to an expression graph, with operator overloading.
//!
//! Shapes are immutable trees of `Arc` nodes; shared subgraphs stay shared (cloning a
//! `Shape` clones a pointer). They are turned into a hash-consed [`crate::Context`] and then
//! a [`crate::Tape`] for evaluation. Constants are folded as shapes are built.

use std::fmt;
use std::ops::{Add, Div, Mul, Neg, Sub};
use std::sync::Arc;

use crate::custom::CustomField;
use crate::op::{BinaryOp, UnaryOp};

/// One of the three coordinates.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub enum Var {
    /// x
    X,
    /// y
    Y,
    /// z
    Z,
}

/// A node of a shape's expression tree.
pub enum ShapeNode {
    /// A coordinate.
    Var(Var),
    /// A number.
    Const(f64),
    /// An operation on one shape.
    Unary(UnaryOp, Shape),
    /// An operation on two shapes.
    Binary(BinaryOp, Shape, Shape),
    /// A field given by callbacks, evaluated at the point given by three input shapes
    /// (x, y, z unless the shape was remapped).
    Custom(Arc<dyn CustomField>, [Shape; 3]),
}

impl ShapeNode {
    /// Moves the children that this node alone owns into `out`, leaving cheap placeholders,
    /// so they can be dropped from a loop instead of by recursion.
    fn take_unique_children(&mut self, out: &mut Vec<Shape>) {
        let mut take = |s: &mut Shape| {
            // A shared child is only decremented when dropped: no recursion to avoid.
            if Arc::strong_count(&s.0) == 1 {
                out.push(std::mem::replace(s, placeholder()));
            }
        };
        match self {
            ShapeNode::Var(_) | ShapeNode::Const(_) => {}
            ShapeNode::Unary(_, a) => take(a),
            ShapeNode::Binary(_, a, b) => {
                take(a);
                take(b)
            }
            ShapeNode::Custom(_, ins) => ins.iter_mut().for_each(take),
        }
    }
}

/// A shared constant node put in place of children taken out for iterative dropping.
fn placeholder() -> Shape {
    static P: std::sync::LazyLock<Shape> =
        std::sync::LazyLock::new(|| Shape(Arc::new(ShapeNode::Const(0.0))));
    P.clone()
}

impl Drop for ShapeNode {
    /// Drops a deep chain (a 100,000-long min chain, say) without one stack frame per
    /// level: children owned only by this node are unlinked and dropped from a loop.
    fn drop(&mut self) {
        let mut stack = Vec::new();
        self.take_unique_children(&mut stack);
        while let Some(s) = stack.pop() {
            if let Some(mut node) = Arc::into_inner(s.0) {
                node.take_unique_children(&mut stack);
                // `node` now has only placeholder or shared children: dropping it is flat.
            }
        }
    }
}

/// A field f(x, y, z): negative inside, positive outside. Cheap to clone.
#[derive(Clone)]
pub struct Shape(pub(crate) Arc<ShapeNode>);

impl fmt::Debug for Shape {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.node() {
            ShapeNode::Var(v) => write!(f, "{v:?}"),
            ShapeNode::Const(c) => write!(f, "{c}"),
            ShapeNode::Unary(op, a) => write!(f, "{op:?}({a:?})"),
            ShapeNode::Binary(op, a, b) => write!(f, "{op:?}({a:?}, {b:?})"),
            ShapeNode::Custom(c, _) => write!(f, "{}(..)", c.name()),
        }
    }
}

impl Shape {
    fn new(node: ShapeNode) -> Self {
        Shape(Arc::new(node))
    }
    /// The x coordinate.
    pub fn x() -> Self {
        Self::new(ShapeNode::Var(Var::X))
    }
    /// The y coordinate.
    pub fn y() -> Self {
        Self::new(ShapeNode::Var(Var::Y))
    }
    /// The z coordinate.
    pub fn z() -> Self {
        Self::new(ShapeNode::Var(Var::Z))
    }
    /// A constant field.
    pub fn constant(v: f64) -> Self {
        Self::new(ShapeNode::Const(v))
    }
    /// A field given by callbacks, evaluated at (x, y, z).
    pub fn custom(field: Arc<dyn CustomField>) -> Self {
        Self::new(ShapeNode::Custom(field, [Self::x(), Self::y(), Self::z()]))
    }
    /// The node at the root of this shape.
    pub fn node(&self) -> &ShapeNode {
        &self.0
    }
    /// The value, if this shape is a constant.
    pub fn as_constant(&self) -> Option<f64> {
        match self.node() {
            ShapeNode::Const(c) => Some(*c),
            _ => None,
        }
    }
    /// An address that identifies this node (shared subgraphs have the same one).
    pub fn id(&self) -> usize {
        Arc::as_ptr(&self.0) as *const () as usize
    }

    /// Applies a unary operation, folding constants.
    pub fn unary(&self, op: UnaryOp) -> Self {
        if let Some(a) = self.as_constant() {
            return Self::constant(crate::eval::scalar::unary(op, a));
        }
        Self::new(ShapeNode::Unary(op, self.clone()))
    }
    /// Applies a binary operation, folding constants.
    pub fn binary(&self, op: BinaryOp, other: &Shape) -> Self {
        if let (Some(a), Some(b)) = (self.as_constant(), other.as_constant()) {
            return Self::constant(crate::eval::scalar::binary(op, a, b));
        }
        Self::new(ShapeNode::Binary(op, self.clone(), other.clone()))
    }

    /// `|self|`
    pub fn abs(&self) -> Self {
        self.unary(UnaryOp::Abs)
    }
    /// `sqrt(self)`
    pub fn sqrt(&self) -> Self {
        self.unary(UnaryOp::Sqrt)
    }
    /// `self * self`
    pub fn square(&self) -> Self {
        self.unary(UnaryOp::Square)
    }
    /// `1 / self`
    pub fn recip(&self) -> Self {
        self.unary(UnaryOp::Recip)
    }
    /// `sin(self)`
    pub fn sin(&self) -> Self {
        self.unary(UnaryOp::Sin)
    }
    /// `cos(self)`
    pub fn cos(&self) -> Self {
        self.unary(UnaryOp::Cos)
    }
    /// `tan(self)`
    pub fn tan(&self) -> Self {
        self.unary(UnaryOp::Tan)
    }
    /// `asin(self)`
    pub fn asin(&self) -> Self {
        self.unary(UnaryOp::Asin)
    }
    /// `acos(self)`
    pub fn acos(&self) -> Self {
        self.unary(UnaryOp::Acos)
    }
    /// `atan(self)`
    pub fn atan(&self) -> Self {
        self.unary(UnaryOp::Atan)
    }
    /// `e^self`
    pub fn exp(&self) -> Self {
        self.unary(UnaryOp::Exp)
    }
    /// `ln(self)`
    pub fn ln(&self) -> Self {
        self.unary(UnaryOp::Ln)
    }
    /// Rounds towards -inf.
    pub fn floor(&self) -> Self {
        self.unary(UnaryOp::Floor)
    }
    /// Rounds towards +inf.
    pub fn ceil(&self) -> Self {
        self.unary(UnaryOp::Ceil)
    }
    /// Rounds to the nearest whole number.
    pub fn round(&self) -> Self {
        self.unary(UnaryOp::Round)
    }
    /// `self^n` for a whole number n.
    pub fn powi(&self, n: i32) -> Self {
        match n {
            0 => Self::constant(1.0),
            1 => self.clone(),
            2 => self.square(),
            _ => self.unary(UnaryOp::PowI(n)),
        }
    }
    /// `self^e`; a whole-number constant exponent becomes [`Shape::powi`].
    pub fn pow(&self, e: &Shape) -> Self {
        if let Some(c) = e.as_constant()
            && c.fract() == 0.0
            && c.abs() <= 1024.0
        {
            return self.powi(c as i32);
        }
        self.binary(BinaryOp::Pow, e)
    }
    /// The smaller of the two.
    pub fn min(&self, other: &Shape) -> Self {
        self.binary(BinaryOp::Min, other)
    }
    /// The larger of the two.
    pub fn max(&self, other: &Shape) -> Self {
        self.binary(BinaryOp::Max, other)
    }
    /// `atan2(self, other)`: the angle of the point (other, self).
    pub fn atan2(&self, other: &Shape) -> Self {
        self.binary(BinaryOp::Atan2, other)
    }
    /// `self mod other`, with the sign of `other`.
    pub fn modulo(&self, other: &Shape) -> Self {
        self.binary(BinaryOp::Mod, other)
    }

    /// Substitutes x, y and z (a transform). Shared subgraphs stay shared.
    pub fn remap(&self, x: &Shape, y: &Shape, z: &Shape) -> Shape {
        crate::remap::remap(self, x, y, z)
    }
}

impl From<f64> for Shape {
    fn from(v: f64) -> Self {
        Shape::constant(v)
    }
}

macro_rules! binary_operator {
    ($trait:ident, $method:ident, $op:expr) => {
        impl $trait<Shape> for Shape {
            type Output = Shape;
            fn $method(self, rhs: Shape) -> Shape {
                self.binary($op, &rhs)
            }
        }
        impl $trait<&Shape> for &Shape {
            type Output = Shape;
            fn $method(self, rhs: &Shape) -> Shape {
                self.binary($op, rhs)
            }
        }
        impl $trait<&Shape> for Shape {
            type Output = Shape;
            fn $method(self, rhs: &Shape) -> Shape {
                self.binary($op, rhs)
            }
        }
        impl $trait<Shape> for &Shape {
            type Output = Shape;
            fn $method(self, rhs: Shape) -> Shape {
                self.binary($op, &rhs)
            }
        }
        impl $trait<f64> for Shape {
            type Output = Shape;
            fn $method(self, rhs: f64) -> Shape {
                self.binary($op, &Shape::constant(rhs))
            }
        }
        impl $trait<f64> for &Shape {
            type Output = Shape;
            fn $method(self, rhs: f64) -> Shape {
                self.binary($op, &Shape::constant(rhs))
            }
        }
        impl $trait<Shape> for f64 {
            type Output = Shape;
            fn $method(self, rhs: Shape) -> Shape {
                Shape::constant(self).binary($op, &rhs)
            }
        }
        impl $trait<&Shape> for f64 {
            type Output = Shape;
            fn $method(self, rhs: &Shape) -> Shape {
                Shape::constant(self).binary($op, rhs)
            }
        }
    };
}

binary_operator!(Add, add, BinaryOp::Add);
binary_operator!(Sub, sub, BinaryOp::Sub);
binary_operator!(Mul, mul, BinaryOp::Mul);
binary_operator!(Div, div, BinaryOp::Div);

impl Neg for Shape {
    type Output = Shape;
    fn neg(self) -> Shape {
        self.unary(UnaryOp::Neg)
    }
}

impl Neg for &Shape {
    type Output = Shape;
    fn neg(self) -> Shape {
        self.unary(UnaryOp::Neg)
    }
}
