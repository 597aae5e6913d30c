//! `offset` and `shell` on any field, through its first-order distance.
//!
//! A field f that is not a distance (the classic `Heart` is a sixth-degree polynomial)
//! still tells how far its surface is to first order: `f / |∇f|` (Taubin's distance
//! estimate), exact wherever |∇f| is constant along the way, i.e. exactly for a distance
//! field, where it equals f. `offset(s, d)` is that estimate minus d, and `shell(s, t)`
//! keeps what lies between the surface and the estimate's level −t.
//!
//! The estimate is a custom node running f's tape in gradient mode. Its enclosure over a
//! box is rigorous: [`isoforge_field::IntervalGradEval`] encloses f and |∇f| on the box,
//! and the quotient of those intervals encloses `f / |∇f|` at every point. Where |∇f| may
//! vanish or be unbounded, the points' values saturate at ±[`MAX_DISTANCE`] with f's sign,
//! and the enclosure reaches there too. So the octree prunes where the estimate is
//! decided (every box whose f-interval and slope bounds settle the sign of `f/|∇f| − d`)
//! and subdivides only near the offset surface.
//!
//! Exact distance fields need none of this: [`offset_exact`] and [`shell_exact`] are
//! plain expressions (`s − d`, `max(s, −s − t)`), used when the caller knows the field is
//! one.

use std::sync::Arc;

use isoforge_field::{CustomField, Interval, Shape, Tape};

use super::{ModernError, finite, positive};
use crate::evals::with_evals;

/// Where the estimate saturates (|∇f| zero, NaN or infinite): far beyond any model.
pub const MAX_DISTANCE: f64 = 1e12;

/// The first-order distance `f / |∇f|` of a field, as a custom node.
pub struct FirstOrderDistance {
    tape: Tape,
}

impl FirstOrderDistance {
    /// The estimate for the field `s`.
    pub fn new(s: &Shape) -> FirstOrderDistance {
        FirstOrderDistance { tape: Tape::new(s) }
    }
}

/// `v / n`, saturated: NaN stays NaN, a zero value stays itself, a slope that is zero,
/// NaN or infinite gives ±MAX_DISTANCE with v's sign, and every result is clamped to
/// ±MAX_DISTANCE.
fn estimate(v: f64, n: f64) -> f64 {
    if v.is_nan() || v == 0.0 {
        return v;
    }
    if !(n > 0.0 && n.is_finite()) {
        return MAX_DISTANCE.copysign(v);
    }
    (v / n).clamp(-MAX_DISTANCE, MAX_DISTANCE)
}

impl CustomField for FirstOrderDistance {
    fn name(&self) -> &str {
        "first_order_distance"
    }

    fn value(&self, p: [f64; 3]) -> f64 {
        with_evals(|e| {
            let g = e.grad.eval(&self.tape, p);
            estimate(g.v, length(g.d))
        })
    }

    fn values(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        with_evals(|e| {
            for (i, o) in out.iter_mut().enumerate() {
                let g = e.grad.eval(&self.tape, [xs[i], ys[i], zs[i]]);
                *o = estimate(g.v, length(g.d));
            }
        })
    }

    fn interval(&self, b: [Interval; 3]) -> Interval {
        with_evals(|e| {
            let ig = e.interval_grad.eval(&self.tape, b);
            if ig.v.is_entire() {
                return Interval::ENTIRE;
            }
            let (lo, hi) = (ig.slope_floor(), ig.slope_bound());
            let slopes = Interval::try_from((lo, hi)).unwrap_or(Interval::ENTIRE);
            let q = ig.v / slopes;
            let (mut qlo, mut qhi) = if q.is_empty() {
                (-MAX_DISTANCE, MAX_DISTANCE)
            } else {
                (q.inf().max(-MAX_DISTANCE), q.sup().min(MAX_DISTANCE))
            };
            // Points whose slope is 0, NaN or infinite saturate with f's sign.
            if lo == 0.0 || !hi.is_finite() {
                if ig.v.sup() > 0.0 {
                    qhi = MAX_DISTANCE;
                }
                if ig.v.inf() < 0.0 {
                    qlo = -MAX_DISTANCE;
                }
            }
            // f = 0 gives 0.
            if ig.v.contains(0.0) {
                qlo = qlo.min(0.0);
                qhi = qhi.max(0.0);
            }
            Interval::try_from((qlo, qhi)).unwrap_or(Interval::ENTIRE)
        })
    }

    /// The estimate on f's tape narrowed to the box: inside a ball that holds one of two
    /// gyroids, say, its points stop paying for the other.
    fn narrow(&self, b: [Interval; 3]) -> Option<Arc<dyn CustomField>> {
        if self.tape.choice_count() == 0 && !self.tape.has_custom_nodes() {
            return None; // one expression (the classic heart): nothing to leave out
        }
        let tape = with_evals(|e| {
            e.interval.eval(&self.tape, b);
            self.tape.narrow(&e.interval)
        });
        (!tape.ptr_eq(&self.tape))
            .then(|| Arc::new(FirstOrderDistance { tape }) as Arc<dyn CustomField>)
    }

    /// The estimate's gradient, `∇f/|∇f| − f·H∇f/|∇f|³` (H the Hessian of f). `H∇f` is
    /// one central difference of ∇f along the gradient's direction: three evaluations of
    /// f's tape in gradient mode, where central differences of the estimate itself took
    /// seven. The late meshing stages ask for a gradient at every point they check, so
    /// on an `offset` of a gyroid this was two thirds of the meshing time.
    fn gradient(&self, p: [f64; 3]) -> [f64; 4] {
        let (v, g) = with_evals(|e| {
            let g = e.grad.eval(&self.tape, p);
            (g.v, g.d)
        });
        let n = length(g);
        let value = estimate(v, n);
        if !(n > 0.0 && n.is_finite() && v.is_finite()) || value.abs() >= MAX_DISTANCE {
            // Saturated (or no slope to go by): the estimate's own differences.
            return self.differences(p, value);
        }
        let u = g.map(|c| c / n);
        let h = step(p);
        let along = |s: f64| {
            with_evals(|e| {
                e.grad
                    .eval(&self.tape, [0, 1, 2].map(|k| p[k] + s * u[k]))
                    .d
            })
        };
        let (ahead, behind) = (along(h), along(-h));
        let k = v / (n * n);
        let d = [0, 1, 2].map(|i| u[i] - k * (ahead[i] - behind[i]) / (2.0 * h));
        if d.iter().all(|c| c.is_finite()) {
            [value, d[0], d[1], d[2]]
        } else {
            self.differences(p, value)
        }
    }
}

impl FirstOrderDistance {
    /// Central differences of the estimate, `value` being its value at `p`.
    fn differences(&self, p: [f64; 3], value: f64) -> [f64; 4] {
        let h = step(p);
        let mut g = [value, 0.0, 0.0, 0.0];
        for k in 0..3 {
            let (mut a, mut b) = (p, p);
            a[k] += h;
            b[k] -= h;
            g[k + 1] = (self.value(a) - self.value(b)) / (2.0 * h);
        }
        g
    }
}

/// The length of a gradient.
fn length(d: [f64; 3]) -> f64 {
    (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
}

/// The difference step at `p`: a millionth of its largest coordinate (or of 1).
fn step(p: [f64; 3]) -> f64 {
    1e-6 * p.iter().fold(1.0f64, |m, c| m.max(c.abs()))
}

/// The first-order distance `f / |∇f|` of `s` (see the module doc).
pub fn first_order_distance(s: &Shape) -> Shape {
    Shape::custom(Arc::new(FirstOrderDistance::new(s)))
}

/// `offset(s, d)` for any field: grown by `d` mm (shrunk for negative `d`), measured by
/// the first-order distance.
pub fn offset(s: &Shape, d: f64) -> Result<Shape, ModernError> {
    let d = finite("the offset distance", d)?;
    Ok(first_order_distance(s) - d)
}

/// `offset(s, d)` for an exact distance field: `s − d`.
pub fn offset_exact(s: &Shape, d: f64) -> Result<Shape, ModernError> {
    let d = finite("the offset distance", d)?;
    Ok(s - d)
}

/// `shell(s, t)` for any field: the outer surface stays, a wall `t` mm thick goes inward.
pub fn shell(s: &Shape, t: f64) -> Result<Shape, ModernError> {
    let t = positive("the wall thickness", t)?;
    Ok(shell_of(&first_order_distance(s), t))
}

/// `shell(s, t)` for an exact distance field: `max(s, −s − t)`.
pub fn shell_exact(s: &Shape, t: f64) -> Result<Shape, ModernError> {
    let t = positive("the wall thickness", t)?;
    Ok(shell_of(s, t))
}

fn shell_of(d: &Shape, t: f64) -> Shape {
    d.max(&(-d - t))
}
