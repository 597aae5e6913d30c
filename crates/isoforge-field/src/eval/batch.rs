//! The batch evaluator: many points a call, structure of arrays.

use crate::tape::Tape;

/// Evaluates a tape at many points (any count; worked through in blocks sized for
/// vectorized loops). Reuse one per thread: it holds its buffers.
#[derive(Default)]
pub struct BatchEval {}

impl BatchEval {
    /// A new evaluator.
    pub fn new() -> Self {
        todo!("isoforge-field helper")
    }
    /// Writes f(xs[i], ys[i], zs[i]) to `out[i]`. All four slices have the same length.
    pub fn eval(&mut self, tape: &Tape, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        let _ = (tape, xs, ys, zs, out);
        todo!("isoforge-field helper")
    }
}
