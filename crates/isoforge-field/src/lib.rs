//! The isoforge field kernel: a model is a function f(x, y, z), negative inside.
//!
//! A [`Shape`] is built with ordinary operators; [`Tape::new`] dedupes it (hash-consing in a
//! [`Context`]), folds constants and flattens it into SSA instructions with allocated
//! registers. Four evaluators run on a tape: [`PointEval`] (f64), [`BatchEval`] (many points
//! a call), [`IntervalEval`] (rigorous enclosures over a box, recording which side of every
//! min and max won) and [`GradEval`] (value and partial derivatives). [`Tape::simplify`] drops
//! the branches an interval pass proved irrelevant, so children of an octree cell are
//! evaluated with a shorter tape.
//!
//! ```
//! use isoforge_field::{Shape, Tape, PointEval, IntervalEval, Interval};
//! let (x, y, z) = (Shape::x(), Shape::y(), Shape::z());
//! let sphere = x.square() + y.square() + z.square() - 1.0;
//! let tape = Tape::new(&sphere);
//! assert_eq!(PointEval::new().eval(&tape, [0.0, 0.0, 0.0]), -1.0);
//! let far = Interval::try_from((2.0, 3.0)).unwrap();
//! assert!(IntervalEval::new().eval(&tape, [far, far, far]).inf() > 0.0);
//! ```

pub mod bounds;
pub mod context;
pub mod custom;
pub mod eval;
pub mod op;
pub mod remap;
pub mod shape;
pub mod tape;
pub mod vm;

pub use bounds::Bounds;
pub use context::{Context, NodeId};
pub use custom::CustomField;
pub use eval::batch::BatchEval;
pub use eval::grad::{Grad, GradEval};
pub use eval::interval::IntervalEval;
pub use eval::point::PointEval;
pub use inari::Interval;
pub use op::{BinaryOp, UnaryOp};
pub use shape::{Shape, ShapeNode, Var};
pub use tape::{Choice, Tape};
