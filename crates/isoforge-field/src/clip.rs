//! A field clipped to its region: what the mesher, the slicer and the renderer evaluate.
//!
//! A model is worked on inside a box, and outside the box counts as outside, so a model
//! cut by its box comes out capped rather than open. The clipped field is
//!
//! ```text
//! F(p) = max(f(p), d(p))    with d = Bounds::distance (negative inside the box)
//! F(p) = +inf               where f(p) is NaN
//! ```
//!
//! and a point is inside iff `F(p) < 0`, strictly. Counting NaN as outside is a choice:
//! a model undefined somewhere (sqrt of a negative, ln of 0) has nothing there to print,
//! and `max` on floats would otherwise let the box's distance hide the NaN.
//!
//! The rules are written once, as the `clip_*` functions below, and [`ClippedField`]
//! applies them to a tape with each evaluator. Fields that are not tapes (the mesher's
//! tests sample plain closures) call the `clip_*` functions themselves.

use inari::Interval;

use crate::bounds::Bounds;
use crate::eval::batch::BatchEval;
use crate::eval::grad::{Grad, GradEval};
use crate::eval::interval::IntervalEval;
use crate::eval::point::PointEval;
use crate::shape::Shape;
use crate::tape::Tape;

/// `F` at a point from `f` there: `max(f, d)`, and `+inf` (outside) where `f` is NaN.
#[inline]
pub fn clip_value(bounds: &Bounds, f: f64, p: [f64; 3]) -> f64 {
    if f.is_nan() {
        f64::INFINITY
    } else {
        f.max(bounds.distance(p))
    }
}

/// An enclosure of `F` over the box `b` from an enclosure `f` of the field there and
/// whether the field may be NaN somewhere in it (as [`IntervalEval::eval_nan`] reports).
///
/// Lower end: `max(f.inf, d.inf)`; a NaN point gives `+inf`, above any lower end. Upper
/// end: `max(f.sup, d.sup)`, or `+inf` where NaN is possible. So `inf() >= 0` means no
/// point of the box is inside, and `sup() < 0` that every point is.
pub fn clip_interval(bounds: &Bounds, f: Interval, may_be_nan: bool, b: [Interval; 3]) -> Interval {
    let (dlo, dhi) = bounds.distance_range(b);
    // An empty enclosure means f is NaN everywhere on the box (no value to bound).
    let nan = may_be_nan || f.is_empty();
    let lo = if f.is_empty() {
        f64::INFINITY
    } else {
        f.inf().max(dlo)
    };
    let hi = if nan { f64::INFINITY } else { f.sup().max(dhi) };
    if lo == f64::INFINITY {
        // All outside; inari has no interval whose lower end is +inf, so give the
        // largest one that still says so.
        return Interval::try_from((f64::MAX, f64::INFINITY)).unwrap_or(Interval::ENTIRE);
    }
    Interval::try_from((lo, hi)).unwrap_or(Interval::ENTIRE)
}

/// `F` and its gradient at `p` from `f`'s: where the box's distance wins (`d >= f`), the
/// value is `d` and the gradient the face's normal; where `f` is NaN, `+inf` and a NaN
/// gradient (no direction is known).
#[inline]
pub fn clip_grad(bounds: &Bounds, g: Grad, p: [f64; 3]) -> Grad {
    if g.v.is_nan() {
        return Grad {
            v: f64::INFINITY,
            d: [f64::NAN; 3],
        };
    }
    let d = bounds.distance(p);
    if d >= g.v {
        Grad {
            v: d,
            d: bounds.face_normal(p),
        }
    } else {
        g
    }
}

/// A model's tape clipped to its region (see the module doc for the rule). Cheap to clone:
/// the tape is shared.
///
/// ```
/// use isoforge_field::{Bounds, ClippedField, PointEval, Shape};
/// let (x, y, z) = (Shape::x(), Shape::y(), Shape::z());
/// let ball = x.square() + y.square() + z.square() - 4.0;
/// let region = Bounds::new([-1.0; 3], [1.0; 3]).unwrap();
/// let field = ClippedField::new(&ball, region);
/// let mut ev = PointEval::new();
/// assert!(field.is_inside(&mut ev, [0.5, 0.0, 0.0]));
/// assert!(!field.is_inside(&mut ev, [1.5, 0.0, 0.0])); // in the ball, out of the box
/// ```
#[derive(Clone, Debug)]
pub struct ClippedField {
    tape: Tape,
    bounds: Bounds,
}

impl ClippedField {
    /// Compiles `shape` and clips it to `bounds`.
    pub fn new(shape: &Shape, bounds: Bounds) -> Self {
        ClippedField::from_tape(Tape::new(shape), bounds)
    }

    /// Clips an already compiled tape to `bounds`.
    pub fn from_tape(tape: Tape, bounds: Bounds) -> Self {
        ClippedField { tape, bounds }
    }

    /// The model's own (unclipped) tape.
    pub fn tape(&self) -> &Tape {
        &self.tape
    }

    /// The region.
    pub fn bounds(&self) -> &Bounds {
        &self.bounds
    }

    /// `F(p)`.
    pub fn point(&self, ev: &mut PointEval, p: [f64; 3]) -> f64 {
        clip_value(&self.bounds, ev.eval(&self.tape, p), p)
    }

    /// True when `p` is inside: `F(p) < 0` (in the box, and the model negative there).
    pub fn is_inside(&self, ev: &mut PointEval, p: [f64; 3]) -> bool {
        self.point(ev, p) < 0.0
    }

    /// `F` at many points: `out[i] = F(xs[i], ys[i], zs[i])` (the shortest slice sets the
    /// count, as in [`BatchEval::eval`]).
    pub fn batch(&self, ev: &mut BatchEval, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        ev.eval(&self.tape, xs, ys, zs, out);
        for (i, v) in out
            .iter_mut()
            .enumerate()
            .take(xs.len().min(ys.len()).min(zs.len()))
        {
            *v = clip_value(&self.bounds, *v, [xs[i], ys[i], zs[i]]);
        }
    }

    /// An enclosure of `F` over a box (see [`clip_interval`]). The evaluator keeps the
    /// min/max choices of the pass for [`ClippedField::narrow`].
    pub fn interval(&self, ev: &mut IntervalEval, b: [Interval; 3]) -> Interval {
        let (dlo, _) = self.bounds.distance_range(b);
        if dlo >= 0.0 {
            // Wholly outside the box: F >= d >= 0 whatever f is, so the tape need not run
            // (the mesher's cube and the slicer's square grid reach past the region).
            ev.forget_choices();
            return Interval::try_from((dlo, f64::INFINITY)).unwrap_or(Interval::ENTIRE);
        }
        let (f, nan) = ev.eval_nan(&self.tape, b);
        clip_interval(&self.bounds, f, nan, b)
    }

    /// `F` and its gradient at `p` (see [`clip_grad`]).
    pub fn grad(&self, ev: &mut GradEval, p: [f64; 3]) -> Grad {
        clip_grad(&self.bounds, ev.eval(&self.tape, p), p)
    }

    /// The field with its tape narrowed ([`Tape::narrow`]) by `ev`'s last
    /// [`ClippedField::interval`] call: equal to `self` everywhere in that call's box.
    pub fn narrow(&self, ev: &IntervalEval) -> ClippedField {
        ClippedField {
            tape: self.tape.narrow(ev),
            bounds: self.bounds,
        }
    }
}
