//! Evaluators for custom nodes that run a tape of their own (the first-order distance of
//! `offset` and `shell`, the radius of a tube): one set per thread, taken from a pool and
//! given back, so a node nested inside another node's tape (an offset of an offset) gets
//! its own set instead of finding the outer one borrowed.

use std::cell::RefCell;

use isoforge_field::{BatchEval, GradEval, IntervalEval, IntervalGradEval, PointEval};

/// One of each evaluator.
#[derive(Default)]
pub struct Evals {
    /// Values at a point.
    pub point: PointEval,
    /// Values and gradients at a point.
    pub grad: GradEval,
    /// Enclosures over a box.
    pub interval: IntervalEval,
    /// Enclosures of values and slopes over a box.
    pub interval_grad: IntervalGradEval,
    /// Values at many points.
    pub batch: BatchEval,
}

thread_local! {
    static POOL: RefCell<Vec<Evals>> = const { RefCell::new(Vec::new()) };
}

/// Runs `f` with a set of evaluators of this thread's pool.
pub fn with_evals<R>(f: impl FnOnce(&mut Evals) -> R) -> R {
    let mut evals = POOL
        .with(|p| p.try_borrow_mut().ok().and_then(|mut p| p.pop()))
        .unwrap_or_default();
    let result = f(&mut evals);
    POOL.with(|p| {
        if let Ok(mut p) = p.try_borrow_mut() {
            p.push(evals);
        }
    });
    result
}
