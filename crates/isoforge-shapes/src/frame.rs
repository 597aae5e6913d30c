//! Frames along a curve: tangents by central differences and the rotation-minimizing frame
//! by the double reflection method (Wang, Jüttler, Zheng, Liu: "Computation of Rotation
//! Minimizing Frames", ACM TOG 27(1), 2008). A shape carried along a curve in this frame
//! turns with the curve but does not twist about it.

/// A 3-vector.
pub type Vec3 = [f64; 3];

fn sub(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn scale(a: Vec3, k: f64) -> Vec3 {
    [a[0] * k, a[1] * k, a[2] * k]
}

/// The dot product.
pub fn dot(a: Vec3, b: Vec3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The cross product.
pub fn cross(a: Vec3, b: Vec3) -> Vec3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn norm(a: Vec3) -> f64 {
    dot(a, a).sqrt()
}

/// `a / |a|`, or `None` when `a` is (nearly) zero or not finite.
pub fn normalize(a: Vec3) -> Option<Vec3> {
    let n = norm(a);
    (n.is_finite() && n > 1e-300).then(|| scale(a, 1.0 / n))
}

/// An orthonormal frame at a point of a curve: `r` and `s` span the normal plane, `t` is
/// the unit tangent, and `r × s = t`.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Frame {
    /// The curve point.
    pub origin: Vec3,
    /// The first normal ("reference") vector.
    pub r: Vec3,
    /// The second normal vector, `t × r`.
    pub s: Vec3,
    /// The unit tangent.
    pub t: Vec3,
}

/// The unit tangent of `f` at `t` by central differences with step `h`.
///
/// Where the derivative vanishes (a cusp, a stationary parameter) the central difference is
/// zero; then wider steps are tried, which pick up the direction the curve leaves in, and
/// `None` is returned only if the curve does not move near `t` at all.
pub fn tangent(f: &dyn Fn(f64) -> Vec3, t: f64, h: f64) -> Option<Vec3> {
    let mut step = h;
    for _ in 0..6 {
        if let Some(d) = normalize(sub(f(t + step), f(t - step))) {
            return Some(d);
        }
        // Central differences cancel at a symmetric turning point; one-sided ones do not.
        if let Some(d) = normalize(sub(f(t + step), f(t))) {
            return Some(d);
        }
        step *= 16.0;
    }
    None
}

/// Any unit vector perpendicular to `t`: the cross product with the axis least aligned
/// with `t`, which is never near-parallel to it.
pub fn any_normal(t: Vec3) -> Vec3 {
    let a = t.map(f64::abs);
    let axis = if a[0] <= a[1] && a[0] <= a[2] {
        [1.0, 0.0, 0.0]
    } else if a[1] <= a[2] {
        [0.0, 1.0, 0.0]
    } else {
        [0.0, 0.0, 1.0]
    };
    normalize(cross(t, axis)).unwrap_or([1.0, 0.0, 0.0])
}

/// Carries `r` (normal to `t0` at `x0`) to the point `x1` with tangent `t1` by two
/// reflections: first in the plane bisecting x0 x1, then in the plane that maps the
/// reflected tangent onto `t1`. Returns the new normal, orthonormalized against `t1`.
pub fn double_reflection(x0: Vec3, t0: Vec3, r0: Vec3, x1: Vec3, t1: Vec3) -> Vec3 {
    let v1 = sub(x1, x0);
    let c1 = dot(v1, v1);
    let (r_l, t_l) = if c1 > 1e-300 {
        (
            sub(r0, scale(v1, 2.0 / c1 * dot(v1, r0))),
            sub(t0, scale(v1, 2.0 / c1 * dot(v1, t0))),
        )
    } else {
        (r0, t0)
    };
    let v2 = sub(t1, t_l);
    let c2 = dot(v2, v2);
    let r1 = if c2 > 1e-300 {
        sub(r_l, scale(v2, 2.0 / c2 * dot(v2, r_l)))
    } else {
        r_l
    };
    // Rounding drifts r off the normal plane over many steps: project it back.
    normalize(sub(r1, scale(t1, dot(r1, t1)))).unwrap_or_else(|| any_normal(t1))
}

/// Rotation-minimizing frames of `f` at `params` (in increasing or decreasing order).
///
/// The frame is carried through `substeps` intermediate points between consecutive
/// parameters, since double reflection is exact only in the limit of small steps.
/// Tangents that cannot be found (the curve stands still) repeat the last good one, or the
/// z axis at the start.
pub fn rotation_minimizing_frames(
    f: &dyn Fn(f64) -> Vec3,
    params: &[f64],
    substeps: usize,
    h: f64,
) -> Vec<Frame> {
    let mut frames = Vec::with_capacity(params.len());
    let Some(&first) = params.first() else {
        return frames;
    };
    let mut last_t = first_tangent(f, params, h);
    let mut x = f(first);
    let mut r = any_normal(last_t);
    let push = |frames: &mut Vec<Frame>, x: Vec3, r: Vec3, t: Vec3| {
        frames.push(Frame {
            origin: x,
            r,
            s: cross(t, r),
            t,
        })
    };
    push(&mut frames, x, r, last_t);
    for pair in params.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        let substeps = substeps.max(1);
        for k in 1..=substeps {
            let u = a + (b - a) * k as f64 / substeps as f64;
            let x1 = f(u);
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
fn first_tangent(f: &dyn Fn(f64) -> Vec3, params: &[f64], h: f64) -> Vec3 {
    params
        .iter()
        .find_map(|&t| tangent(f, t, h))
        .unwrap_or([0.0, 0.0, 1.0])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Vec3, b: Vec3, tol: f64) -> bool {
        norm(sub(a, b)) < tol
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
            assert!((dot(fr.r, fr.r) - 1.0).abs() < 1e-9);
            assert!((dot(fr.t, fr.t) - 1.0).abs() < 1e-9);
            assert!(dot(fr.r, fr.t).abs() < 1e-9);
            assert!(close(cross(fr.r, fr.s), fr.t, 1e-9));
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
            assert!(close(fr.r, frames[0].r, 1e-9));
        }
    }
}
