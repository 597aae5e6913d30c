//! Curve followers: copies of a shape placed along a parametric curve and united.
//!
//! `n` copies go at t = a + i·(b−a)/n, i = 0..n−1. The sphere needs no orientation; the
//! cylinder and the box are turned so their z axis follows the curve's tangent, in the
//! curve's rotation-minimizing frame ([`crate::frame`]) so that consecutive copies do not
//! twist about the curve. The curve is sampled here, once, while the graph is built: the
//! resulting shape is plain arithmetic and never calls back into the closure.

use glam::DVec3;
use isoforge_field::Shape;

use crate::classic::{cube, cyl, sphere, translate, union_all};
use crate::frame::{Frame, rotation_minimizing_frames};

/// The most copies one curve follower may place: each is a separate subgraph, and a
/// million of them would exhaust memory long before anything was meshed.
pub const MAX_PLACEMENTS: usize = 100_000;

/// Intermediate points per placement for carrying the frame, up to this many curve
/// samples in all: double reflection is second-order accurate, and 16 steps between
/// copies keep the frame's drift on a helix turn below 1e-3 rad.
const FRAME_SAMPLES: usize = 4096;

/// Why a curve follower could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CurveError {
    /// `n` was zero or too large.
    #[error("the number of copies must be between 1 and {MAX_PLACEMENTS}, not {0}")]
    Count(i64),
    /// The parameter range is not two finite numbers.
    #[error("the parameter range [{0}, {1}] must be two finite numbers")]
    Range(f64, f64),
    /// The curve gave a point that is not finite.
    #[error("the curve gives a point that is not finite at t = {t}: [{}, {}, {}]", p[0], p[1], p[2])]
    NotFinite {
        /// The parameter.
        t: f64,
        /// What the curve returned.
        p: [f64; 3],
    },
}

/// The parameters of the `n` copies: a + i·(b−a)/n, i = 0..n−1.
pub fn placements(n: i64, [a, b]: [f64; 2]) -> Result<Vec<f64>, CurveError> {
    if n < 1 || n as u64 > MAX_PLACEMENTS as u64 {
        return Err(CurveError::Count(n));
    }
    if !a.is_finite() || !b.is_finite() {
        return Err(CurveError::Range(a, b));
    }
    Ok((0..n).map(|i| a + i as f64 * (b - a) / n as f64).collect())
}

fn check_point(t: f64, p: [f64; 3]) -> Result<[f64; 3], CurveError> {
    if p.iter().all(|c| c.is_finite()) {
        Ok(p)
    } else {
        Err(CurveError::NotFinite { t, p })
    }
}

/// `curve_fol_sphere(f, n, [a, b], radius)`: spheres of `radius` centred on the curve.
pub fn curve_fol_sphere(
    f: impl Fn(f64) -> [f64; 3],
    n: i64,
    range: [f64; 2],
    radius: impl Into<Shape>,
) -> Result<Shape, CurveError> {
    let ball = sphere(radius);
    let copies = placements(n, range)?
        .into_iter()
        .map(|t| Ok(translate(&ball, check_point(t, f(t))?)))
        .collect::<Result<Vec<_>, CurveError>>()?;
    Ok(union_all(&copies).unwrap_or(ball))
}

/// `curve_fol_cyl(f, n, [a, b], [c, d, e])` (alias `curve_fol_cyyl`): the cylinder
/// `Cyl(c, d, e)` placed along the curve with its axis on the tangent.
pub fn curve_fol_cyl(
    f: impl Fn(f64) -> [f64; 3],
    n: i64,
    range: [f64; 2],
    [c, d, e]: [f64; 3],
) -> Result<Shape, CurveError> {
    curve_follow(f, n, range, &cyl(c, d, e))
}

/// `curve_fol_box(f, n, [a, b], size)`: the cube `Cube(size)` placed along the curve with
/// its z axis on the tangent.
pub fn curve_fol_box(
    f: impl Fn(f64) -> [f64; 3],
    n: i64,
    range: [f64; 2],
    size: f64,
) -> Result<Shape, CurveError> {
    curve_follow(f, n, range, &cube(size))
}

/// Any shape placed along the curve with its z axis on the tangent, in the
/// rotation-minimizing frame, `n` copies united.
pub fn curve_follow(
    f: impl Fn(f64) -> [f64; 3],
    n: i64,
    range: [f64; 2],
    shape: &Shape,
) -> Result<Shape, CurveError> {
    let params = placements(n, range)?;
    for &t in &params {
        check_point(t, f(t))?;
    }
    let span = (range[1] - range[0]).abs();
    // Small against one placement's step, large against f64 rounding of t.
    let h = 1e-5 * (span / params.len() as f64).max(1e-3 * (1.0 + range[0].abs()));
    let substeps = (FRAME_SAMPLES / params.len()).clamp(1, 16);
    let frames = rotation_minimizing_frames(&f, &params, substeps, h);
    let copies: Vec<Shape> = frames.iter().map(|fr| place(shape, fr)).collect();
    Ok(union_all(&copies).unwrap_or_else(|| shape.clone()))
}

/// `shape` with its own x, y, z axes on the frame's r, s, t at the frame's origin: the
/// point p is looked up at ((p−o)·r, (p−o)·s, (p−o)·t).
pub fn place(shape: &Shape, fr: &Frame) -> Shape {
    let d = [
        Shape::x() - fr.origin.x,
        Shape::y() - fr.origin.y,
        Shape::z() - fr.origin.z,
    ];
    let along = |axis: DVec3| &d[0] * axis.x + &d[1] * axis.y + &d[2] * axis.z;
    shape.remap(&along(fr.r), &along(fr.s), &along(fr.t))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::at;
    use std::f64::consts::TAU;

    #[test]
    fn placements_are_a_plus_i_step() {
        assert_eq!(
            placements(4, [0.0, 1.0]).unwrap(),
            vec![0.0, 0.25, 0.5, 0.75]
        );
        assert_eq!(placements(0, [0.0, 1.0]), Err(CurveError::Count(0)));
        assert_eq!(placements(-3, [0.0, 1.0]), Err(CurveError::Count(-3)));
        assert!(matches!(
            placements(2, [0.0, f64::NAN]),
            Err(CurveError::Range(..))
        ));
    }

    #[test]
    fn spheres_sit_on_the_curve() {
        let f = |t: f64| [4.0 * t.sin(), 4.0 * t.cos(), 0.0];
        let s = curve_fol_sphere(f, 7, [0.0, TAU], 2.0).unwrap();
        for i in 0..7 {
            let p = f(i as f64 * TAU / 7.0);
            assert!(
                (at(&s, p) + 4.0).abs() < 1e-9,
                "centre {i} is at depth -r^2"
            );
        }
        assert!(at(&s, [0.0, 0.0, 0.0]) > 0.0, "the ring has a hole");
        assert!(at(&s, [0.0, 0.0, 2.5]) > 0.0);
    }

    #[test]
    fn a_non_finite_curve_is_an_error() {
        let f = |t: f64| [1.0 / t, 0.0, 0.0];
        let err = curve_fol_sphere(f, 2, [0.0, 1.0], 1.0).unwrap_err();
        assert!(matches!(err, CurveError::NotFinite { t, .. } if t == 0.0));
    }

    #[test]
    fn cylinders_follow_the_tangent() {
        // Along the x axis, the cylinder's own z axis becomes x: long in x, thin in y and z.
        let s = curve_fol_cyl(|t| [t, 0.0, 0.0], 1, [0.0, 1.0], [0.01, 0.01, 4.0]).unwrap();
        assert!(at(&s, [1.9, 0.0, 0.0]) < 0.0);
        assert!(at(&s, [0.0, 0.0, 1.9]) > 0.0);
        assert!(at(&s, [0.0, 1.9, 0.0]) > 0.0);
        // The fixture: t -> [t, t^2, t], three copies.
        let s = curve_fol_cyl(|t| [t, t * t, t], 3, [0.0, 1.0], [1.0, 1.0, 1.0]).unwrap();
        assert!(at(&s, [0.0, 0.0, 0.0]) < 0.0);
        assert!(at(&s, [1.0 / 3.0, 1.0 / 9.0, 1.0 / 3.0]) < 0.0);
        assert!(at(&s, [5.0, 5.0, 5.0]) > 0.0);
    }

    #[test]
    fn boxes_do_not_twist_along_a_helix() {
        // Thin flat plates (long in the frame's r direction) along a helix: in an RMF the
        // plate's r axis turns only as the curve turns, so consecutive plates line up.
        let helix = |t: f64| [2.0 * t.cos(), 2.0 * t.sin(), 0.5 * t];
        let params = placements(24, [0.0, TAU]).unwrap();
        let frames = rotation_minimizing_frames(&helix, &params, 16, 1e-5);
        for w in frames.windows(2) {
            let turn = w[0].r.dot(w[1].r);
            assert!(turn > 0.9, "frame jumped between copies: {turn}");
        }
        let s = curve_fol_box(helix, 24, [0.0, TAU], 0.5).unwrap();
        for fr in &frames {
            assert!(at(&s, fr.origin.to_array()) < 0.0);
        }
    }
}
