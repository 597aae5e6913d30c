//! Rigorous interval enclosures for the operations inari (without `gmp`) lacks.
//!
//! Each function returns `(enclosure, nan)`: an interval that contains every value the
//! f64 point evaluator ([`crate::eval::scalar`]) can return for points of the argument
//! intervals, and whether some of those points may give NaN.
//!
//! Method: split the function into monotonic pieces, evaluate libm at the piece ends, and
//! widen each libm result outward by [`ULPS`] units in the last place. glibc's
//! `sin cos tan asin acos atan exp ln atan2 pow` are accurate to within one ulp, so the
//! true value at an endpoint lies within one ulp of libm's, and a libm result at any inner
//! point lies within one ulp of the true value there: two ulps outward cover both. The
//! point evaluators' own sin and cos (`trig.rs`) are within one ulp of the true value
//! as well (under 0.83 measured), so the same two ulps cover them. Extrema
//! inside the interval (sin and cos at k*pi/2) are found with a safety margin that only
//! ever adds extrema, never misses one. Results are clamped to the function's true range.

use std::f64::consts::{FRAC_2_PI, FRAC_PI_2, PI};

use inari::Interval;

/// How many ulps each libm endpoint result is widened outward.
pub const ULPS: u32 = 2;

/// `[lo, hi]`, or `ENTIRE` if that is not a valid interval (NaN or crossed bounds), which
/// is always a safe enclosure.
pub fn interval(lo: f64, hi: f64) -> Interval {
    if lo.is_nan() || hi.is_nan() || lo > hi {
        return Interval::ENTIRE;
    }
    let lo = if lo == f64::INFINITY { f64::MAX } else { lo };
    let hi = if hi == f64::NEG_INFINITY {
        f64::MIN
    } else {
        hi
    };
    Interval::try_from((lo, hi)).unwrap_or(Interval::ENTIRE)
}

/// `x` moved [`ULPS`] ulps towards -inf.
pub fn down(x: f64) -> f64 {
    (0..ULPS).fold(x, |v, _| v.next_down())
}

/// `x` moved [`ULPS`] ulps towards +inf.
pub fn up(x: f64) -> f64 {
    (0..ULPS).fold(x, |v, _| v.next_up())
}

/// True when the interval's bounds reach an infinity (so a point value may be infinite).
pub fn unbounded(a: Interval) -> bool {
    a.inf() == f64::NEG_INFINITY || a.sup() == f64::INFINITY
}

/// True when 0 lies in the interval.
pub fn has_zero(a: Interval) -> bool {
    a.inf() <= 0.0 && a.sup() >= 0.0
}

/// The integers n with `t_lo <= n * (2/pi)... ` i.e. whose point `n * pi/2` may lie in
/// `[lo, hi]`, given `lo, hi` finite and `hi - lo < 2 pi`. The margin makes the test
/// include every n whose point is in the interval (and perhaps one or two more).
fn quarter_turns(lo: f64, hi: f64) -> impl Iterator<Item = i64> {
    let (tl, th) = (lo * FRAC_2_PI, hi * FRAC_2_PI);
    // FRAC_2_PI and the product each carry at most half an ulp of relative error.
    let e = tl.abs().max(th.abs()) * 1e-15 + 1e-300;
    let (a, b) = (tl - e, th + e);
    let (n0, n1) = (a.ceil() as i64, b.floor() as i64);
    n0..=n1
}

/// sin or cos: `f` is the function, `max_at`/`min_at` the residues mod 4 of the quarter
/// turns where it reaches 1 and -1.
fn sin_cos(a: Interval, f: fn(f64) -> f64, max_at: i64, min_at: i64) -> (Interval, bool) {
    if a.is_empty() {
        return (Interval::ENTIRE, true);
    }
    let full = interval(-1.0, 1.0);
    let (lo, hi) = (a.inf(), a.sup());
    if !lo.is_finite() || !hi.is_finite() {
        // sin(inf) is NaN.
        return (full, true);
    }
    // Beyond 1e15 the quarter-turn test's margin would exceed one turn anyway.
    if hi - lo >= 2.0 * PI || lo.abs().max(hi.abs()) > 1e15 {
        return (full, false);
    }
    let (fl, fh) = (f(lo), f(hi));
    let (mut l, mut h) = (down(fl.min(fh)), up(fl.max(fh)));
    for n in quarter_turns(lo, hi) {
        let r = n.rem_euclid(4);
        if r == max_at {
            h = 1.0;
        }
        if r == min_at {
            l = -1.0;
        }
    }
    (interval(l.max(-1.0), h.min(1.0)), false)
}

/// sin over an interval.
pub fn sin(a: Interval) -> (Interval, bool) {
    sin_cos(a, f64::sin, 1, 3)
}

/// cos over an interval.
pub fn cos(a: Interval) -> (Interval, bool) {
    sin_cos(a, f64::cos, 0, 2)
}

/// tan over an interval: increasing between poles at odd multiples of pi/2; a possible
/// pole inside gives `ENTIRE` (values there are huge, not NaN).
pub fn tan(a: Interval) -> (Interval, bool) {
    if a.is_empty() {
        return (Interval::ENTIRE, true);
    }
    let (lo, hi) = (a.inf(), a.sup());
    if !lo.is_finite() || !hi.is_finite() {
        return (Interval::ENTIRE, true);
    }
    if hi - lo >= PI || lo.abs().max(hi.abs()) > 1e15 {
        return (Interval::ENTIRE, false);
    }
    if quarter_turns(lo, hi).any(|n| n.rem_euclid(2) == 1) {
        return (Interval::ENTIRE, false);
    }
    (interval(down(lo.tan()), up(hi.tan())), false)
}

/// asin: increasing on [-1, 1], NaN outside.
pub fn asin(a: Interval) -> (Interval, bool) {
    if a.is_empty() || a.inf() < -1.0 || a.sup() > 1.0 {
        return (Interval::ENTIRE, true);
    }
    let m = FRAC_PI_2.next_up();
    (
        interval(down(a.inf().asin()).max(-m), up(a.sup().asin()).min(m)),
        false,
    )
}

/// acos: decreasing on [-1, 1], NaN outside.
pub fn acos(a: Interval) -> (Interval, bool) {
    if a.is_empty() || a.inf() < -1.0 || a.sup() > 1.0 {
        return (Interval::ENTIRE, true);
    }
    let m = PI.next_up();
    (
        interval(down(a.sup().acos()).max(0.0), up(a.inf().acos()).min(m)),
        false,
    )
}

/// atan: increasing, range (-pi/2, pi/2).
pub fn atan(a: Interval) -> (Interval, bool) {
    if a.is_empty() {
        return (Interval::ENTIRE, true);
    }
    let m = FRAC_PI_2.next_up();
    (
        interval(down(a.inf().atan()).max(-m), up(a.sup().atan()).min(m)),
        false,
    )
}

/// exp: increasing, positive; overflow gives +inf, which the upper bound then is.
pub fn exp(a: Interval) -> (Interval, bool) {
    if a.is_empty() {
        return (Interval::ENTIRE, true);
    }
    (
        interval(down(a.inf().exp()).max(0.0), up(a.sup().exp())),
        false,
    )
}

/// ln: increasing on (0, inf). An interval reaching 0 or below counts as a domain error
/// (NaN below 0; at 0 the value is -inf).
pub fn ln(a: Interval) -> (Interval, bool) {
    if a.is_empty() || a.inf() <= 0.0 {
        return (Interval::ENTIRE, true);
    }
    (interval(down(a.inf().ln()), up(a.sup().ln())), false)
}

/// Widens a `powi` result: repeated squaring accumulates about one rounding per
/// multiplication, and results in the subnormal range carry absolute, not relative, error.
fn powi_widen(v: f64, n: u32, toward_inf: bool) -> f64 {
    if !v.is_finite() {
        return v;
    }
    let k = 2.0 * (32 - n.leading_zeros()) as f64 + 2.0;
    let slack = v.abs() * k * f64::EPSILON + k * 5e-324;
    if toward_inf {
        up(v + slack)
    } else {
        down(v - slack)
    }
}

/// `a^n` for a whole number n, as computed by `f64::powi`.
pub fn powi(a: Interval, n: i32) -> (Interval, bool) {
    if a.is_empty() {
        return (Interval::ENTIRE, true);
    }
    if n == 0 {
        return (interval(1.0, 1.0), false);
    }
    let (lo, hi) = (a.inf(), a.sup());
    let m = n.unsigned_abs();
    let p = |x: f64| x.powi(n);
    let even = m.is_multiple_of(2);
    let (l, h) = if n > 0 {
        if even {
            let mig = if has_zero(a) {
                0.0
            } else {
                lo.abs().min(hi.abs())
            };
            let mag = lo.abs().max(hi.abs());
            (
                powi_widen(p(mig), m, false).max(0.0),
                powi_widen(p(mag), m, true),
            )
        } else {
            (powi_widen(p(lo), m, false), powi_widen(p(hi), m, true))
        }
    } else if has_zero(a) {
        if !even {
            // A pole inside (and -0 gives -inf, +0 gives +inf).
            return (Interval::ENTIRE, false);
        }
        let mag = lo.abs().max(hi.abs());
        (powi_widen(p(mag), m, false).max(0.0), f64::INFINITY)
    } else if even {
        let (mig, mag) = (lo.abs().min(hi.abs()), lo.abs().max(hi.abs()));
        (
            powi_widen(p(mag), m, false).max(0.0),
            powi_widen(p(mig), m, true),
        )
    } else {
        // Decreasing on each side of the pole.
        (powi_widen(p(hi), m, false), powi_widen(p(lo), m, true))
    };
    (interval(l, h), false)
}

/// `a^b` for real b (`f64::powf`). A base that may be negative counts as a domain error.
///
/// For a >= 0, x^y is monotonic in each argument on each quadrant split at x = 1 and
/// y = 0, so the extremes lie at the box's corners or on those lines, where the value is 1.
pub fn pow(a: Interval, b: Interval) -> (Interval, bool) {
    if a.is_empty() || b.is_empty() || a.inf() < 0.0 {
        return (Interval::ENTIRE, true);
    }
    let mut l = f64::INFINITY;
    let mut h = f64::NEG_INFINITY;
    // inari reports a zero lower bound as -0; the base +0 is what the corner means
    // (the -0 case is handled below).
    let base_lo = if a.inf() == 0.0 { 0.0 } else { a.inf() };
    for x in [base_lo, a.sup()] {
        for y in [b.inf(), b.sup()] {
            let v = x.powf(y);
            l = l.min(v);
            h = h.max(v);
        }
    }
    if (a.inf() <= 1.0 && a.sup() >= 1.0) || has_zero(b) {
        l = l.min(1.0);
        h = h.max(1.0);
    }
    let mut l = (down(l) - 5e-324).max(0.0);
    if a.inf() == 0.0 && b.inf() < 0.0 {
        // (-0)^(negative odd integer) is -inf.
        l = f64::NEG_INFINITY;
    }
    (interval(l, up(h) + 5e-324), false)
}

/// atan2(y, x), the angle of the point (x, y), in [-pi, pi].
///
/// Away from the origin and the branch cut (the negative x axis, where the sign of a zero
/// y picks pi or -pi) the angle is continuous on the box, and its extremes over a convex
/// box lie at the corners.
pub fn atan2(y: Interval, x: Interval) -> (Interval, bool) {
    if y.is_empty() || x.is_empty() {
        return (Interval::ENTIRE, true);
    }
    let m = PI.next_up();
    let full = interval(-m, m);
    if unbounded(x) || unbounded(y) || (x.inf() <= 0.0 && has_zero(y)) {
        return (full, false);
    }
    let mut l = f64::INFINITY;
    let mut h = f64::NEG_INFINITY;
    for yy in [y.inf(), y.sup()] {
        for xx in [x.inf(), x.sup()] {
            let v = yy.atan2(xx);
            l = l.min(v);
            h = h.max(v);
        }
    }
    // Two ulps more than for libm alone: the point evaluators' atan2 (`trig.rs`) is
    // within two ulps of the true value (1.71 the largest measured), libm within one.
    let (l, h) = (down(down(l)), up(up(h)));
    (interval(l.max(-m), h.min(m)), false)
}

/// `a - b * floor(a / b)`, enclosed by composing inari's rigorous operations (each f64
/// step of the point formula rounds to a value inside the matching interval). A divisor
/// that may be 0, or an unbounded operand, may give NaN.
pub fn modulo(a: Interval, b: Interval) -> (Interval, bool) {
    if a.is_empty() || b.is_empty() || has_zero(b) || unbounded(a) || unbounded(b) {
        return (Interval::ENTIRE, true);
    }
    let r = a - b * (a / b).floor();
    if r.is_empty() {
        return (Interval::ENTIRE, true);
    }
    (r, false)
}
