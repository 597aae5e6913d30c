//! Where the profile of a path sweep stands at each point of the path: the stations.
//!
//! A path is a list of points. At each point the profile's plane is normal to the path's
//! tangent (central differences, as BOSL2's `path_tangents`), and the profile is turned in
//! that plane by one of BOSL2's three methods:
//! - `incremental`: carried from point to point by the smallest rotation (the rotation-
//!   minimizing frame, by double reflection); a closed path's leftover turn is spread
//!   evenly along it so the ends meet without a seam;
//! - `natural`: the Frenet frame, the profile's x axis towards the centre of curvature;
//! - `manual`: the profile's y axis along a given vector projected into the plane.
//!
//! Twist and scale are then spread along the path by length.

use std::f64::consts::TAU;

use glam::DVec3;

use super::SweepError;
use crate::frame::{any_normal, double_reflection, normalize};

/// How the profile is turned about the path (BOSL2's `method`).
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum PathMethod {
    /// The rotation-minimizing frame (BOSL2's default).
    Incremental,
    /// The Frenet frame.
    Natural,
    /// A fixed normal vector.
    Manual,
}

/// The profile's placement at one path point.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Station {
    /// The point.
    pub origin: DVec3,
    /// The unit tangent (the profile plane's normal).
    pub tangent: DVec3,
    /// The profile's x axis.
    pub x_axis: DVec3,
    /// The profile's y axis (`x_axis × y_axis = tangent`).
    pub y_axis: DVec3,
    /// How far the profile is turned in its plane here, radians (counter-clockwise).
    pub twist: f64,
    /// The profile's scale here.
    pub scale: f64,
    /// Arc length from the start.
    pub s: f64,
}

/// What is asked of the stations.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameOptions {
    /// The method.
    pub method: PathMethod,
    /// The starting normal (`incremental`) or the normal (`manual`); `None` for BOSL2's
    /// default: up if the path starts within 45 degrees of the xy plane, else back (+y).
    pub normal: Option<DVec3>,
    /// Total twist along the path, degrees.
    pub twist: f64,
    /// The profile's scale at the end (1 at the start); must be 1 on a closed path.
    pub scale: f64,
    /// The last point joins the first.
    pub closed: bool,
    /// Rotational symmetry of the profile: a closed path may then close with a turn of a
    /// multiple of 360/symmetry degrees instead of 360.
    pub symmetry: u32,
}

impl Default for FrameOptions {
    fn default() -> Self {
        FrameOptions {
            method: PathMethod::Incremental,
            normal: None,
            twist: 0.0,
            scale: 1.0,
            closed: false,
            symmetry: 1,
        }
    }
}

fn fail(msg: impl Into<String>) -> SweepError {
    SweepError::Path(msg.into())
}

/// Drops repeated points (a closed path given with its first point repeated at the end
/// loses that too).
pub fn clean_path(points: &[DVec3], closed: bool) -> Vec<DVec3> {
    let scale = points
        .iter()
        .map(|p| p.abs().max_element())
        .fold(1.0, f64::max);
    let same = |a: DVec3, b: DVec3| a.distance(b) <= 1e-12 * scale;
    let mut out: Vec<DVec3> = Vec::with_capacity(points.len());
    for &p in points {
        if out.last().is_none_or(|&q| !same(p, q)) {
            out.push(p);
        }
    }
    if closed {
        while out.len() > 1 && same(out[0], out[out.len() - 1]) {
            out.pop();
        }
    }
    out
}

/// Unit tangents by central differences (one-sided at an open path's ends).
fn tangents(pts: &[DVec3], closed: bool) -> Result<Vec<DVec3>, SweepError> {
    let n = pts.len();
    (0..n)
        .map(|i| {
            let (prev, next) = if closed {
                (pts[(i + n - 1) % n], pts[(i + 1) % n])
            } else {
                (pts[i.saturating_sub(1)], pts[(i + 1).min(n - 1)])
            };
            normalize(next - prev)
                .ok_or_else(|| fail(format!("the path has no direction at point {i}")))
        })
        .collect()
}

/// The stations of a path.
pub fn stations(points: &[DVec3], opts: &FrameOptions) -> Result<Vec<Station>, SweepError> {
    let pts = clean_path(points, opts.closed);
    let need = if opts.closed { 3 } else { 2 };
    if pts.len() < need {
        return Err(fail(format!(
            "the path needs at least {need} distinct points, it has {}",
            pts.len()
        )));
    }
    if opts.closed && opts.scale != 1.0 {
        return Err(fail(
            "a closed path cannot scale its profile (the ends must meet)",
        ));
    }
    if !opts.scale.is_finite() || opts.scale <= 0.0 {
        return Err(SweepError::NotPositive {
            what: "the scale",
            value: opts.scale,
        });
    }
    if !opts.twist.is_finite() {
        return Err(SweepError::NotFinite {
            what: "the twist",
            value: opts.twist,
        });
    }
    let symmetry = opts.symmetry.max(1);
    let step = 360.0 / f64::from(symmetry);
    if opts.closed && (opts.twist / step - (opts.twist / step).round()).abs() > 1e-9 {
        return Err(fail(format!(
            "on a closed path the twist must be a multiple of {step} degrees (360 / symmetry), not {}",
            opts.twist
        )));
    }
    let n = pts.len();
    let tangents = tangents(&pts, opts.closed)?;
    let mut s = vec![0.0; n];
    for i in 1..n {
        s[i] = s[i - 1] + pts[i].distance(pts[i - 1]);
    }
    let length = if opts.closed {
        s[n - 1] + pts[n - 1].distance(pts[0])
    } else {
        s[n - 1]
    };
    let y_axes = match opts.method {
        PathMethod::Incremental => incremental(&pts, &tangents, opts, &s, length, symmetry)?,
        PathMethod::Natural => natural(&tangents, opts.closed)?,
        PathMethod::Manual => manual(&tangents, opts.normal)?,
    };
    Ok((0..n)
        .map(|i| {
            let f = if length > 0.0 { s[i] / length } else { 0.0 };
            let t = tangents[i];
            let y = y_axes[i];
            Station {
                origin: pts[i],
                tangent: t,
                x_axis: y.cross(t),
                y_axis: y,
                twist: opts.twist.to_radians() * f,
                scale: 1.0 + (opts.scale - 1.0) * f,
                s: s[i],
            }
        })
        .collect())
}

/// BOSL2's default starting normal: up, unless the path starts steeper than 45 degrees.
fn default_normal(t0: DVec3) -> DVec3 {
    if t0.z.abs() <= std::f64::consts::FRAC_1_SQRT_2 {
        DVec3::Z
    } else {
        DVec3::Y
    }
}

fn project(n: DVec3, t: DVec3, at: usize) -> Result<DVec3, SweepError> {
    normalize(n - t * n.dot(t)).ok_or_else(|| {
        fail(format!(
            "the normal [{}, {}, {}] is parallel to the path at point {at}",
            n.x, n.y, n.z
        ))
    })
}

fn incremental(
    pts: &[DVec3],
    tangents: &[DVec3],
    opts: &FrameOptions,
    s: &[f64],
    length: f64,
    symmetry: u32,
) -> Result<Vec<DVec3>, SweepError> {
    let n = pts.len();
    let start = opts.normal.unwrap_or_else(|| default_normal(tangents[0]));
    let mut y = vec![project(start, tangents[0], 0)?];
    for i in 1..n {
        let next = double_reflection(pts[i - 1], tangents[i - 1], y[i - 1], pts[i], tangents[i]);
        y.push(next);
    }
    if opts.closed {
        // Carried once around, the frame comes back turned by some angle about the first
        // tangent; turn every station back by its share of it, by length.
        let back = double_reflection(pts[n - 1], tangents[n - 1], y[n - 1], pts[0], tangents[0]);
        let t0 = tangents[0];
        let mut gap = y[0].cross(back).dot(t0).atan2(y[0].dot(back));
        // A profile with n-fold symmetry only needs to come back to within 360/n.
        let unit = TAU / f64::from(symmetry);
        gap -= unit * (gap / unit).round();
        for i in 0..n {
            let a = -gap * s[i] / length;
            y[i] = rotate_about(y[i], tangents[i], a);
        }
    }
    Ok(y)
}

/// `v` turned by `angle` about the unit axis `k` (Rodrigues).
pub fn rotate_about(v: DVec3, k: DVec3, angle: f64) -> DVec3 {
    let (s, c) = angle.sin_cos();
    v * c + k.cross(v) * s + k * k.dot(v) * (1.0 - c)
}

fn natural(tangents: &[DVec3], closed: bool) -> Result<Vec<DVec3>, SweepError> {
    let n = tangents.len();
    (0..n)
        .map(|i| {
            let (prev, next) = if closed {
                (tangents[(i + n - 1) % n], tangents[(i + 1) % n])
            } else {
                (tangents[i.saturating_sub(1)], tangents[(i + 1).min(n - 1)])
            };
            let t = tangents[i];
            let bend = next - prev;
            let curvature = bend - t * bend.dot(t);
            if curvature.length() < 1e-9 {
                return Err(fail(format!(
                    "method \"natural\" needs a curving path, but it is straight at point {i} (use \"incremental\" or \"manual\")"
                )));
            }
            // x towards the centre of curvature; y = t × x makes x × y = t.
            let x = curvature.normalize();
            Ok(t.cross(x))
        })
        .collect()
}

fn manual(tangents: &[DVec3], normal: Option<DVec3>) -> Result<Vec<DVec3>, SweepError> {
    let normal = match normal {
        Some(v) => v,
        None => default_normal(tangents[0]),
    };
    tangents
        .iter()
        .enumerate()
        .map(|(i, &t)| project(normal, t, i))
        .collect()
}

/// A normal for a tangent when nothing better is known.
pub fn fallback_normal(t: DVec3) -> DVec3 {
    any_normal(t)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn circle(n: usize, r: f64) -> Vec<DVec3> {
        (0..n)
            .map(|i| {
                let a = i as f64 * TAU / n as f64;
                DVec3::new(r * a.cos(), r * a.sin(), 0.0)
            })
            .collect()
    }

    #[test]
    fn frames_are_orthonormal_and_right_handed() {
        let helix: Vec<DVec3> = (0..200)
            .map(|i| {
                let a = i as f64 * 0.05;
                DVec3::new(a.cos(), a.sin(), 0.2 * a)
            })
            .collect();
        for method in [
            PathMethod::Incremental,
            PathMethod::Natural,
            PathMethod::Manual,
        ] {
            let opts = FrameOptions {
                method,
                ..Default::default()
            };
            for st in stations(&helix, &opts).unwrap() {
                assert!((st.x_axis.length() - 1.0).abs() < 1e-9);
                assert!((st.y_axis.length() - 1.0).abs() < 1e-9);
                assert!(st.x_axis.dot(st.tangent).abs() < 1e-9);
                assert!(
                    st.x_axis.cross(st.y_axis).distance(st.tangent) < 1e-9,
                    "{method:?}"
                );
            }
        }
    }

    #[test]
    fn a_closed_incremental_path_meets_itself() {
        // A tilted, wobbly loop: the RMF comes back turned, and the correction closes it.
        let pts: Vec<DVec3> = (0..300)
            .map(|i| {
                let a = i as f64 * TAU / 300.0;
                DVec3::new(3.0 * a.cos(), 2.0 * a.sin(), (3.0 * a).sin())
            })
            .collect();
        let opts = FrameOptions {
            closed: true,
            ..Default::default()
        };
        let st = stations(&pts, &opts).unwrap();
        let last = st.last().unwrap();
        let carried = double_reflection(
            last.origin,
            last.tangent,
            last.y_axis,
            st[0].origin,
            st[0].tangent,
        );
        assert!(
            carried.distance(st[0].y_axis) < 1e-6,
            "seam: {carried} vs {}",
            st[0].y_axis
        );
    }

    #[test]
    fn natural_points_x_at_the_centre() {
        let st = stations(
            &circle(64, 5.0),
            &FrameOptions {
                method: PathMethod::Natural,
                closed: true,
                ..Default::default()
            },
        )
        .unwrap();
        for s in &st {
            assert!(s.x_axis.dot(-s.origin.normalize()) > 0.999);
        }
        let straight = [DVec3::ZERO, DVec3::X, DVec3::X * 2.0];
        assert!(
            stations(
                &straight,
                &FrameOptions {
                    method: PathMethod::Natural,
                    ..Default::default()
                }
            )
            .is_err()
        );
    }

    #[test]
    fn options_are_checked() {
        let loop_ = circle(16, 1.0);
        let bad_twist = FrameOptions {
            closed: true,
            twist: 90.0,
            ..Default::default()
        };
        assert!(stations(&loop_, &bad_twist).is_err());
        let ok = FrameOptions {
            symmetry: 4,
            ..bad_twist
        };
        assert!(stations(&loop_, &ok).is_ok());
        let manual_parallel = FrameOptions {
            method: PathMethod::Manual,
            normal: Some(DVec3::X),
            ..Default::default()
        };
        assert!(stations(&[DVec3::ZERO, DVec3::X], &manual_parallel).is_err());
        assert!(stations(&[DVec3::ZERO], &FrameOptions::default()).is_err());
    }
}
