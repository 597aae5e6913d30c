//! The single-point evaluator.

use crate::tape::Tape;

/// Evaluates a tape at one point. Holds its registers, so reuse one per thread.
#[derive(Default)]
pub struct PointEval {}

impl PointEval {
    /// A new evaluator.
    pub fn new() -> Self {
        todo!("isoforge-field helper")
    }
    /// The field's value at `p`; NaN where it is undefined.
    pub fn eval(&mut self, tape: &Tape, p: [f64; 3]) -> f64 {
        let _ = (tape, p);
        todo!("isoforge-field helper")
    }
}
