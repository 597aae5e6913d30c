//! Helpers for the interval callbacks of this crate's custom fields: boxes from the
//! kernel's intervals, and enclosures built from a value at the box's centre.
//!
//! Most custom fields here are distance-like: they change by at most `L` per millimetre
//! moved (`L` is their Lipschitz constant). Then over a box of half-diagonal `r` every
//! value lies in `f(centre) ± L·r`, a rigorous and, for small boxes, tight enclosure; the
//! octree prunes a box as soon as `|f(centre)| > L·r`.

use glam::{DVec2, DVec3};
use isoforge_field::Interval;
use isoforge_field::eval::enclose;

/// Relative widening of computed bounds, for the rounding in the arithmetic that made
/// them: far above the 1e-15 relative error of a few dozen f64 operations, far below any
/// printable size.
const ROUNDING: f64 = 1e-9;

/// `[lo, hi]` widened outward for rounding; `ENTIRE` when not a valid interval.
pub fn widened(lo: f64, hi: f64) -> Interval {
    let pad = |v: f64| ROUNDING * (1.0 + v.abs());
    enclose::interval(lo - pad(lo), hi + pad(hi))
}

/// An enclosure of a field that changes by at most `lipschitz` per millimetre, from its
/// value at the centre of a box of half-diagonal `radius`.
pub fn around(centre_value: f64, lipschitz: f64, radius: f64) -> Interval {
    if !centre_value.is_finite() || !lipschitz.is_finite() || !radius.is_finite() {
        return Interval::ENTIRE;
    }
    let r = lipschitz * radius;
    widened(centre_value - r, centre_value + r)
}

/// A box given as three intervals, as centre and half-sizes; `None` when any side is
/// unbounded, empty or NaN (no finite centre to evaluate at).
pub fn finite_box(b: [Interval; 3]) -> Option<(DVec3, DVec3)> {
    let mut c = [0.0; 3];
    let mut h = [0.0; 3];
    for i in 0..3 {
        let (lo, hi) = (b[i].inf(), b[i].sup());
        if !lo.is_finite() || !hi.is_finite() || lo > hi {
            return None;
        }
        c[i] = 0.5 * (lo + hi);
        h[i] = 0.5 * (hi - lo);
    }
    Some((DVec3::from(c), DVec3::from(h)))
}

/// The first two sides of a box as a 2D box (the plane a profile lives in).
pub fn plane_box(b: [Interval; 3]) -> Option<(DVec2, DVec2)> {
    let (c, h) = finite_box([b[0], b[1], widened(0.0, 0.0)])?;
    Some((c.truncate(), h.truncate()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn around_encloses_a_distance_field() {
        // |x| is 1-Lipschitz: over [2, 4] it lies in 3 ± 1.
        let iv = around(3.0, 1.0, 1.0);
        assert!(iv.inf() <= 2.0 && iv.sup() >= 4.0 && iv.inf() > 1.99);
        assert_eq!(around(f64::NAN, 1.0, 1.0), Interval::ENTIRE);
    }

    #[test]
    fn unbounded_boxes_have_no_centre() {
        let i = |a: f64, b: f64| Interval::try_from((a, b)).unwrap();
        assert!(finite_box([i(0.0, 1.0), i(0.0, 1.0), Interval::ENTIRE]).is_none());
        let (c, h) = finite_box([i(0.0, 2.0), i(-1.0, 1.0), i(4.0, 4.0)]).unwrap();
        assert_eq!(c, DVec3::new(1.0, 0.0, 4.0));
        assert_eq!(h, DVec3::new(1.0, 1.0, 0.0));
    }
}
