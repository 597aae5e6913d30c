//! What the mesher asks of a field, and the region clip.
//!
//! The mesher is written against [`Sampler`] so that it runs the same on a compiled tape
//! ([`TapeSampler`], the product) and on plain closures (the exhaustive sign-pattern tests).
//! The region is applied here, not in the user's tape: F = max(f, d_box), with d_box > 0
//! outside the box, so a model cut by its region is capped; and NaN counts as outside
//! (a corner is inside iff F < 0, strictly), which `max` on floats would not give.

use std::sync::Mutex;

use isoforge_field::Interval;
use isoforge_field::{BatchEval, Bounds, Choice, GradEval, IntervalEval, Tape};

/// A field the mesher can sample. `Local` is the field narrowed to one octree cell (a
/// simplified tape); `Evals` is one thread's evaluator state.
pub trait Sampler: Sync {
    /// The field restricted to a region (valid inside the box it was narrowed on).
    type Local: Clone + Send + Sync;
    /// Per-thread evaluators and buffers.
    type Evals: Send;
    /// Fresh evaluators.
    fn evals(&self) -> Self::Evals;
    /// The field over the whole region.
    fn root(&self) -> Self::Local;
    /// An enclosure of f over the box. May be `ENTIRE` (e.g. when f may be NaN).
    fn interval(&self, ev: &mut Self::Evals, local: &Self::Local, b: [Interval; 3]) -> Interval;
    /// The field narrowed to the box of the last `interval` call.
    fn narrow(&self, ev: &mut Self::Evals, local: &Self::Local) -> Self::Local;
    /// f at many points.
    fn batch(
        &self,
        ev: &mut Self::Evals,
        local: &Self::Local,
        xs: &[f64],
        ys: &[f64],
        zs: &[f64],
        out: &mut [f64],
    );
    /// f and its gradient at a point: `[f, df/dx, df/dy, df/dz]`, possibly NaN.
    fn grad(&self, ev: &mut Self::Evals, local: &Self::Local, p: [f64; 3]) -> [f64; 4];
}

/// A compiled tape as a [`Sampler`]: intervals prune, choices simplify.
pub struct TapeSampler {
    tape: Tape,
}

impl TapeSampler {
    /// Wraps a tape.
    pub fn new(tape: Tape) -> Self {
        TapeSampler { tape }
    }
}

/// One thread's evaluators for [`TapeSampler`].
pub struct TapeEvals {
    interval: IntervalEval,
    batch: BatchEval,
    grad: GradEval,
}

impl Sampler for TapeSampler {
    type Local = Tape;
    type Evals = TapeEvals;
    fn evals(&self) -> TapeEvals {
        TapeEvals {
            interval: IntervalEval::new(),
            batch: BatchEval::new(),
            grad: GradEval::new(),
        }
    }
    fn root(&self) -> Tape {
        self.tape.clone()
    }
    fn interval(&self, ev: &mut TapeEvals, local: &Tape, b: [Interval; 3]) -> Interval {
        ev.interval.eval(local, b)
    }
    fn narrow(&self, ev: &mut TapeEvals, local: &Tape) -> Tape {
        let choices = ev.interval.choices();
        // Simplifying costs a pass over the tape; skip it when nothing was decided.
        if choices.iter().all(|c| *c == Choice::Both) {
            local.clone()
        } else {
            local.simplify(choices)
        }
    }
    fn batch(
        &self,
        ev: &mut TapeEvals,
        local: &Tape,
        xs: &[f64],
        ys: &[f64],
        zs: &[f64],
        out: &mut [f64],
    ) {
        ev.batch.eval(local, xs, ys, zs, out);
    }
    fn grad(&self, ev: &mut TapeEvals, local: &Tape, p: [f64; 3]) -> [f64; 4] {
        let g = ev.grad.eval(local, p);
        [g.v, g.d[0], g.d[1], g.d[2]]
    }
}

/// The region: distance-like function positive outside the box, and the combination
/// F = max(f, d_box) with NaN counted as outside.
#[derive(Clone, Copy, Debug)]
pub struct Clip {
    /// The box.
    pub bounds: Bounds,
}

impl Clip {
    /// max over axes of (min − p, p − max): negative inside, zero on the box, positive out.
    pub fn dist(&self, p: [f64; 3]) -> f64 {
        let mut d = f64::NEG_INFINITY;
        for (i, &c) in p.iter().enumerate() {
            d = d.max(self.bounds.min[i] - c).max(c - self.bounds.max[i]);
        }
        d
    }

    /// The axis and sign of `dist`'s gradient at `p` (the face it measures to).
    pub fn normal(&self, p: [f64; 3]) -> [f64; 3] {
        let mut best = (f64::NEG_INFINITY, 0, 0.0);
        for (i, &c) in p.iter().enumerate() {
            let lo = self.bounds.min[i] - c;
            let hi = c - self.bounds.max[i];
            if lo > best.0 {
                best = (lo, i, -1.0);
            }
            if hi > best.0 {
                best = (hi, i, 1.0);
            }
        }
        let mut n = [0.0; 3];
        n[best.1] = best.2;
        n
    }

    /// An enclosure of `dist` over a box.
    pub fn interval(&self, b: [Interval; 3]) -> (f64, f64) {
        let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::NEG_INFINITY);
        for (i, iv) in b.iter().enumerate() {
            // min − p over [inf, sup] is [min − sup, min − inf]; p − max likewise.
            lo = lo
                .max(self.bounds.min[i] - iv.sup())
                .max(iv.inf() - self.bounds.max[i]);
            hi = hi
                .max(self.bounds.min[i] - iv.inf())
                .max(iv.sup() - self.bounds.max[i]);
        }
        (lo, hi)
    }

    /// F from f and the point's box distance; NaN becomes +∞ (outside).
    pub fn combine(f: f64, d: f64) -> f64 {
        if f.is_nan() { f64::INFINITY } else { f.max(d) }
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
