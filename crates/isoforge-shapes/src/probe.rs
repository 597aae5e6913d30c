//! A field wrapped to count how often it is asked: how the benches and tests show that
//! the octree prunes (points and boxes evaluated against a dense grid's corners).
//!
//! The wrapper is a custom node running the field's tape, so the mesher's pruning
//! decisions are the same as for the bare field (the same enclosures); only per-cell
//! tape simplification is lost, which changes speed, never what is visited.

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

use isoforge_field::{CustomField, Interval, Shape, Tape};

use crate::evals::with_evals;

/// How often a [`Probe`] was asked.
#[derive(Debug, Default)]
pub struct Counts {
    /// Point values (single and batched).
    pub points: AtomicU64,
    /// Box enclosures.
    pub boxes: AtomicU64,
    /// Gradients.
    pub gradients: AtomicU64,
}

/// The field of a shape, counting its evaluations.
pub struct Probe {
    tape: Tape,
    counts: Arc<Counts>,
}

/// `shape` as a counting field, and its counters.
pub fn probe(shape: &Shape) -> (Shape, Arc<Counts>) {
    let counts = Arc::new(Counts::default());
    let node = Probe {
        tape: Tape::new(shape),
        counts: counts.clone(),
    };
    (Shape::custom(Arc::new(node)), counts)
}

impl CustomField for Probe {
    fn name(&self) -> &str {
        "probe"
    }
    fn value(&self, p: [f64; 3]) -> f64 {
        self.counts.points.fetch_add(1, Ordering::Relaxed);
        with_evals(|e| e.point.eval(&self.tape, p))
    }
    fn values(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        self.counts
            .points
            .fetch_add(out.len() as u64, Ordering::Relaxed);
        with_evals(|e| e.batch.eval(&self.tape, xs, ys, zs, out));
    }
    fn interval(&self, b: [Interval; 3]) -> Interval {
        self.counts.boxes.fetch_add(1, Ordering::Relaxed);
        with_evals(|e| e.interval.eval(&self.tape, b))
    }
    fn gradient(&self, p: [f64; 3]) -> [f64; 4] {
        self.counts.gradients.fetch_add(1, Ordering::Relaxed);
        let g = with_evals(|e| e.grad.eval(&self.tape, p));
        [g.v, g.d[0], g.d[1], g.d[2]]
    }
    fn interval_gradient(&self, b: [Interval; 3]) -> [Interval; 3] {
        with_evals(|e| e.interval_grad.eval(&self.tape, b)).d
    }
}
