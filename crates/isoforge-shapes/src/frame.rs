//! Frames along a curve: tangents by central differences and the rotation-minimizing frame
//! by the double reflection method (Wang, Jüttler, Zheng, Liu: "Computation of Rotation
//! Minimizing Frames", ACM TOG 27(1), 2008). A shape carried along a curve in this frame
//! turns with the curve but does not twist about it.

use glam::DVec3;

/// A curve: its point at a parameter.
pub type Curve<'a> = &'a dyn Fn(f64) -> [f64; 3];

fn at(f: Curve, t: f64) -> DVec3 {
    DVec3::from(f(t))
}

/// `a / |a|`, or `None` when `a` is (nearly) zero or not finite. (glam's `try_normalize`
/// accepts lengths down to 1e-308, where the direction is mostly rounding.)
pub fn normalize(a: DVec3) -> Option<DVec3> {
    let n = a.length();
    (n.is_finite() && n > 1e-300).then(|| a * (1.0 / n))
}

/// An orthonormal frame at a point of a curve: `r` and `s` span the normal plane, `t` is
/// the unit tangent, and `r × s = t`.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Frame {
    /// The curve point.
    pub origin: DVec3,
    /// The first normal ("reference") vector.
    pub r: DVec3,
    /// The second normal vector, `t × r`.
    pub s: DVec3,
    /// The unit tangent.
    pub t: DVec3,
}

/// The unit tangent of `f` at `t` by central differences with step `h`.
///
/// Where the derivative vanishes (a cusp, a stationary parameter) the central difference is
/// zero; then wider steps are tried, which pick up the direction the curve leaves in, and
/// `None` is returned only if the curve does not move near `t` at all.
pub fn tangent(f: Curve, t: f64, h: f64) -> Option<DVec3> {
    let mut step = h;
    for _ in 0..6 {
        if let Some(d) = normalize(at(f, t + step) - at(f, t - step)) {
            return Some(d);
        }
        // Central differences cancel at a symmetric turning point; one-sided ones do not.
        if let Some(d) = normalize(at(f, t + step) - at(f, t)) {
            return Some(d);
        }
        step *= 16.0;
    }
    None
}

/// Any unit vector perpendicular to `t`: the cross product with the axis least aligned
/// with `t`, which is never near-parallel to it.
pub fn any_normal(t: DVec3) -> DVec3 {
    let a = t.abs();
    let axis = if a.x <= a.y && a.x <= a.z {
        DVec3::X
    } else if a.y <= a.z {
        DVec3::Y
    } else {
        DVec3::Z
    };
    normalize(t.cross(axis)).unwrap_or(DVec3::X)
}

/// Carries `r` (normal to `t0` at `x0`) to the point `x1` with tangent `t1` by two
/// reflections: first in the plane bisecting x0 x1, then in the plane that maps the
/// reflected tangent onto `t1`. Returns the new normal, orthonormalized against `t1`.
pub fn double_reflection(x0: DVec3, t0: DVec3, r0: DVec3, x1: DVec3, t1: DVec3) -> DVec3 {
    let v1 = x1 - x0;
    let c1 = v1.dot(v1);
    let (r_l, t_l) = if c1 > 1e-300 {
        (
            r0 - v1 * (2.0 / c1 * v1.dot(r0)),
            t0 - v1 * (2.0 / c1 * v1.dot(t0)),
        )
    } else {
        (r0, t0)
    };
    let v2 = t1 - t_l;
    let c2 = v2.dot(v2);
    let r1 = if c2 > 1e-300 {
        r_l - v2 * (2.0 / c2 * v2.dot(r_l))
    } else {
        r_l
    };
    // Rounding drifts r off the normal plane over many steps: project it back.
    normalize(r1 - t1 * r1.dot(t1)).unwrap_or_else(|| any_normal(t1))
}

/// Rotation-minimizing frames of `f` at `params` (in increasing or decreasing order).
///
/// The frame is carried through `substeps` intermediate points between consecutive
/// parameters, since double reflection is exact only in the limit of small steps.
/// Tangents that cannot be found (the curve stands still) repeat the last good one, or the
/// z axis at the start.
pub fn rotation_minimizing_frames(f: Curve, params: &[f64], substeps: usize, h: f64) -> Vec<Frame> {
    let mut frames = Vec::with_capacity(params.len());
    let Some(&first) = params.first() else {
        return frames;
    };
    let mut last_t = first_tangent(f, params, h);
    let mut x = at(f, first);
    let mut r = any_normal(last_t);
    let push = |frames: &mut Vec<Frame>, x: DVec3, r: DVec3, t: DVec3| {
        frames.push(Frame {
            origin: x,
            r,
            s: t.cross(r),
            t,
        })
    };
    push(&mut frames, x, r, last_t);
    for pair in params.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        let substeps = substeps.max(1);
        for k in 1..=substeps {
            let u = a + (b - a) * k as f64 / substeps as f64;
            let x1 = at(f, u);
            let t1 = tangent(f, u, h).unwrap_or(last_t);
            r = double_reflection(x, last_t, r, x1, t1);
            x = x1;
            last_t = t1;
        }
        push(&mut frames, x, r, last_t);
    }
    frames
}

/// The tangent at the first parameter, or the first one found further on, or z.
fn first_tangent(f: Curve, params: &[f64], h: f64) -> DVec3 {
    params
        .iter()
        .find_map(|&t| tangent(f, t, h))
        .unwrap_or(DVec3::Z)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: DVec3, b: [f64; 3], tol: f64) -> bool {
        a.distance(DVec3::from(b)) < tol
    }

    #[test]
    fn tangent_of_a_line_and_a_circle() {
        let line = |t: f64| [t, 2.0 * t, 0.0];
        let d = tangent(&line, 0.3, 1e-4).unwrap();
        assert!(close(d, [1.0 / 5f64.sqrt(), 2.0 / 5f64.sqrt(), 0.0], 1e-9));
        let circle = |t: f64| [t.cos(), t.sin(), 0.0];
        let d = tangent(&circle, 0.0, 1e-4).unwrap();
        assert!(close(d, [0.0, 1.0, 0.0], 1e-6));
    }

    #[test]
    fn tangent_falls_back_at_a_stationary_point() {
        // t^2 has zero derivative at 0 and its central difference cancels there.
        let f = |t: f64| [t * t, 0.0, 0.0];
        let d = tangent(&f, 0.0, 1e-4).unwrap();
        assert!(close(d, [1.0, 0.0, 0.0], 1e-9));
        let still = |_t: f64| [1.0, 2.0, 3.0];
        assert_eq!(tangent(&still, 0.5, 1e-4), None);
    }

    #[test]
    fn frames_are_orthonormal_and_right_handed() {
        let helix = |t: f64| [t.cos(), t.sin(), 0.3 * t];
        let params: Vec<f64> = (0..20).map(|i| i as f64 * 0.5).collect();
        for fr in rotation_minimizing_frames(&helix, &params, 16, 1e-5) {
            assert!((fr.r.length_squared() - 1.0).abs() < 1e-9);
            assert!((fr.t.length_squared() - 1.0).abs() < 1e-9);
            assert!(fr.r.dot(fr.t).abs() < 1e-9);
            assert!(close(fr.r.cross(fr.s), fr.t.to_array(), 1e-9));
        }
    }

    #[test]
    fn a_planar_curve_keeps_its_binormal() {
        // On a plane curve the RMF keeps one normal along the plane's normal (no twist).
        let circle = |t: f64| [2.0 * t.cos(), 2.0 * t.sin(), 0.0];
        let params: Vec<f64> = (0..12).map(|i| i as f64 * 0.5).collect();
        let frames = rotation_minimizing_frames(&circle, &params, 16, 1e-5);
        let z0 = frames[0].r[2];
        for fr in &frames {
            assert!(
                (fr.r[2] - z0).abs() < 1e-6,
                "r drifted out of plane: {fr:?}"
            );
        }
    }

    #[test]
    fn a_straight_line_has_a_constant_frame() {
        let line = |t: f64| [t, t, t];
        let params: Vec<f64> = (0..5).map(f64::from).collect();
        let frames = rotation_minimizing_frames(&line, &params, 8, 1e-5);
        for fr in &frames {
            assert!(close(fr.r, frames[0].r.to_array(), 1e-9));
        }
    }
}
