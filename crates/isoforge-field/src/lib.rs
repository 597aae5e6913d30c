//! The isoforge field kernel: a model is a function f(x, y, z), negative inside.
//!
//! A [`Shape`] is built with ordinary operators; [`Tape::new`] dedupes it (hash-consing in a
//! [`Context`]), folds constants and flattens it into SSA instructions with allocated
//! registers. Four evaluators run on a tape: [`PointEval`] (f64), [`BatchEval`] (many points
//! a call), [`IntervalEval`] (rigorous enclosures over a box, recording which side of every
//! min and max won), [`GradEval`] (value and partial derivatives) and [`IntervalGradEval`]
//! (enclosures of the value and the partial derivatives over a box). [`Tape::simplify`] drops
//! the branches an interval pass proved irrelevant, so children of an octree cell are
//! evaluated with a shorter tape.
//!
//! Interval results always enclose the point values; where a point may be NaN (sqrt of a
//! negative, 0 * inf, ...) the interval is `ENTIRE`. The enclosures inari lacks without
//! `gmp` (sin, cos, tan, asin, acos, atan, atan2, exp, ln, powi, pow, mod) are in
//! [`eval::enclose`]. [`vm::parse_vm`] reads the `.vm` benchmark models.
//!
//! A model is worked on inside a region, a [`Bounds`] box: [`find_bounds`] finds one by
//! interval pruning (and [`ensure_not_empty`] checks a given one), and [`ClippedField`] is
//! the model clipped to it, outside the box and NaN counted as outside. The mesher, the
//! slicer and the renderer all evaluate a `ClippedField`, so "inside" means one thing.
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
pub mod clip;
pub mod context;
pub mod custom;
pub mod eval;
pub mod op;
pub mod region;
pub mod remap;
pub mod shape;
pub mod tape;
pub mod vm;

pub use bounds::Bounds;
pub use clip::{ClippedField, clip_grad, clip_interval, clip_value};
pub use context::{Context, NodeId};
pub use custom::CustomField;
pub use eval::batch::BatchEval;
pub use eval::grad::{Grad, GradEval};
pub use eval::interval::IntervalEval;
pub use eval::interval_grad::{IntervalGrad, IntervalGradEval};
pub use eval::point::PointEval;
pub use inari::Interval;
pub use op::{BinaryOp, UnaryOp};
pub use region::{RegionError, SEARCH_HALF_SIDE, ensure_not_empty, find_bounds, region_is_empty};
pub use shape::{Shape, ShapeNode, Var};
pub use tape::{Choice, Tape};
pub use vm::{VmError, parse_vm};
