//! What the mesher asks of a field.
//!
//! The mesher is written against [`Sampler`] so that it runs the same on a compiled tape
//! ([`TapeSampler`], the product) and on plain closures (the exhaustive sign-pattern tests).
//! A sampler gives the field already clipped to the region (`isoforge_field::clip`:
//! F = max(f, d_box), NaN counted as outside), so a model cut by its region is capped and
//! a corner is inside iff F < 0, strictly.

use std::sync::Mutex;

use isoforge_field::Interval;
use isoforge_field::{BatchEval, ClippedField, GradEval, IntervalEval};

/// A field clipped to the region, as the mesher samples it. `Local` is the field narrowed
/// to one octree cell (a simplified tape); `Evals` is one thread's evaluator state.
pub trait Sampler: Sync {
    /// The field restricted to a region (valid inside the box it was narrowed on).
    type Local: Clone + Send + Sync;
    /// Per-thread evaluators and buffers.
    type Evals: Send;
    /// Fresh evaluators.
    fn evals(&self) -> Self::Evals;
    /// The field over the whole region.
    fn root(&self) -> Self::Local;
    /// An enclosure of F over the box: `inf() >= 0` proves it empty, `sup() < 0` full.
    fn interval(&self, ev: &mut Self::Evals, local: &Self::Local, b: [Interval; 3]) -> Interval;
    /// The field narrowed to the box of the last `interval` call.
    fn narrow(&self, ev: &mut Self::Evals, local: &Self::Local) -> Self::Local;
    /// F at many points.
    fn batch(
        &self,
        ev: &mut Self::Evals,
        local: &Self::Local,
        xs: &[f64],
        ys: &[f64],
        zs: &[f64],
        out: &mut [f64],
    );
    /// F and its gradient at a point: `[F, dF/dx, dF/dy, dF/dz]`; the gradient may be NaN.
    fn grad(&self, ev: &mut Self::Evals, local: &Self::Local, p: [f64; 3]) -> [f64; 4];
}

/// A model's tape clipped to the region, as a [`Sampler`]: intervals prune, choices
/// simplify.
pub struct TapeSampler {
    field: ClippedField,
}

impl TapeSampler {
    /// Wraps a clipped field.
    pub fn new(field: ClippedField) -> Self {
        TapeSampler { field }
    }
}

/// One thread's evaluators for [`TapeSampler`].
pub struct TapeEvals {
    interval: IntervalEval,
    batch: BatchEval,
    grad: GradEval,
}

impl Sampler for TapeSampler {
    type Local = ClippedField;
    type Evals = TapeEvals;
    fn evals(&self) -> TapeEvals {
        TapeEvals {
            interval: IntervalEval::new(),
            batch: BatchEval::new(),
            grad: GradEval::new(),
        }
    }
    fn root(&self) -> ClippedField {
        self.field.clone()
    }
    fn interval(&self, ev: &mut TapeEvals, local: &ClippedField, b: [Interval; 3]) -> Interval {
        local.interval(&mut ev.interval, b)
    }
    fn narrow(&self, ev: &mut TapeEvals, local: &ClippedField) -> ClippedField {
        local.narrow(&ev.interval)
    }
    fn batch(
        &self,
        ev: &mut TapeEvals,
        local: &ClippedField,
        xs: &[f64],
        ys: &[f64],
        zs: &[f64],
        out: &mut [f64],
    ) {
        local.batch(&mut ev.batch, xs, ys, zs, out);
    }
    fn grad(&self, ev: &mut TapeEvals, local: &ClippedField, p: [f64; 3]) -> [f64; 4] {
        let g = local.grad(&mut ev.grad, p);
        [g.v, g.d[0], g.d[1], g.d[2]]
    }
}

/// A stack of evaluators shared by the workers, so that each rayon task borrows one
/// instead of building its own (evaluators hold buffers sized to the tape).
pub struct EvalPool<'s, S: Sampler> {
    sampler: &'s S,
    free: Mutex<Vec<S::Evals>>,
}

impl<'s, S: Sampler> EvalPool<'s, S> {
    /// An empty pool for a sampler.
    pub fn new(sampler: &'s S) -> Self {
        EvalPool {
            sampler,
            free: Mutex::new(Vec::new()),
        }
    }
    /// Borrows evaluators until the guard drops.
    pub fn take(&self) -> PoolGuard<'_, 's, S> {
        let ev = self
            .free
            .lock()
            .ok()
            .and_then(|mut v| v.pop())
            .unwrap_or_else(|| self.sampler.evals());
        PoolGuard {
            pool: self,
            ev: Some(ev),
        }
    }
}

/// Evaluators borrowed from an [`EvalPool`].
pub struct PoolGuard<'p, 's, S: Sampler> {
    pool: &'p EvalPool<'s, S>,
    ev: Option<S::Evals>,
}

impl<S: Sampler> PoolGuard<'_, '_, S> {
    /// The evaluators.
    pub fn get(&mut self) -> &mut S::Evals {
        let sampler = self.pool.sampler;
        self.ev.get_or_insert_with(|| sampler.evals())
    }
}

impl<S: Sampler> Drop for PoolGuard<'_, '_, S> {
    fn drop(&mut self) {
        if let (Some(ev), Ok(mut free)) = (self.ev.take(), self.pool.free.lock()) {
            free.push(ev);
        }
    }
}
