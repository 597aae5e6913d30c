//! Tapes: a graph flattened to SSA instructions with allocated registers, and their
//! simplification by the choices an interval pass recorded.

use crate::context::{Context, NodeId};
use crate::shape::Shape;

/// Which side of a min or max matters on a region.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub enum Choice {
    /// Only the left argument can win: the right branch may be dropped.
    Left,
    /// Only the right argument can win.
    Right,
    /// Either may win (or it is unknown).
    Both,
}

/// An evaluable program. Cheap to clone (shared).
#[derive(Clone)]
pub struct Tape {}

impl Tape {
    /// Compiles a shape (dedupe, fold, flatten, allocate registers).
    pub fn new(shape: &Shape) -> Tape {
        let mut ctx = Context::new();
        let root = ctx.import(shape);
        Tape::from_context(&ctx, root)
    }
    /// Compiles the graph below `root` in a context.
    pub fn from_context(ctx: &Context, root: NodeId) -> Tape {
        let _ = (ctx, root);
        todo!("isoforge-field helper")
    }
    /// The number of instructions.
    pub fn len(&self) -> usize {
        todo!("isoforge-field helper")
    }
    /// True for a tape with no instructions (never: a tape has at least its output).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// The number of min and max instructions; an [`crate::IntervalEval`] records this many
    /// choices.
    pub fn choice_count(&self) -> usize {
        todo!("isoforge-field helper")
    }
    /// A shorter tape that gives the same values wherever `choices` hold (on the region the
    /// interval pass that produced them covered).
    pub fn simplify(&self, choices: &[Choice]) -> Tape {
        let _ = choices;
        todo!("isoforge-field helper")
    }
}
