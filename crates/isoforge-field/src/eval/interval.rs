//! The interval evaluator: rigorous enclosures over a box, and the min/max choices that
//! drive tape simplification.

use inari::Interval;

use crate::tape::{Choice, Tape};

/// Evaluates a tape over a box. Reuse one per thread.
#[derive(Default)]
pub struct IntervalEval {}

impl IntervalEval {
    /// A new evaluator.
    pub fn new() -> Self {
        todo!("isoforge-field helper")
    }
    /// An interval that encloses f over the box. Where f may be undefined (NaN) somewhere
    /// in the box the result is `Interval::ENTIRE`, never a false all-negative or
    /// all-positive answer.
    pub fn eval(&mut self, tape: &Tape, b: [Interval; 3]) -> Interval {
        let _ = (tape, b);
        todo!("isoforge-field helper")
    }
    /// The choices of the last `eval`, one per min/max of its tape, in tape order.
    pub fn choices(&self) -> &[Choice] {
        todo!("isoforge-field helper")
    }
}
