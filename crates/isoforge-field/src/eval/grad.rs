//! The gradient evaluator: value and partial derivatives, forward mode.

use crate::tape::Tape;

/// A field value with its partial derivatives.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Grad {
    /// f
    pub v: f64,
    /// (df/dx, df/dy, df/dz)
    pub d: [f64; 3],
}

/// Evaluates value and gradient at a point. Reuse one per thread.
#[derive(Default)]
pub struct GradEval {}

impl GradEval {
    /// A new evaluator.
    pub fn new() -> Self {
        todo!("isoforge-field helper")
    }
    /// Value and gradient at `p`. Where a derivative is undefined it may be NaN or infinite;
    /// callers must handle that.
    pub fn eval(&mut self, tape: &Tape, p: [f64; 3]) -> Grad {
        let _ = (tape, p);
        todo!("isoforge-field helper")
    }
}
