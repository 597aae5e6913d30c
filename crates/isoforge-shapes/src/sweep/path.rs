//! `path_sweep`: a profile carried along a 3D path, as one custom field node.
//!
//! The path is a list of stations ([`super::frames`]); between two stations the profile's
//! plane turns with the linearly blended tangent, so the planes sweep continuously
//! through space with no gap or seam at a station (both segments meeting there give the
//! same plane), and a closed path has no seam at all.
//!
//! A point p lies in the plane of segment i at fraction u when
//! `(p − c(u)) · t(u) = 0`, with `c` and `t` blended linearly: a quadratic in u, solved
//! exactly. Each such plane that p lies in gives p's coordinates in the profile there;
//! the field is the smallest profile value over all of them. That is the union of every
//! cross-section, so a sweep that overlaps itself (a knot whose strands touch, a bend
//! tighter than the profile) is one clean solid instead of an invalid polyhedron.
//!
//! Open paths get flat end caps: a short straight extension past each end, cut by the
//! end's plane, so the caps have the right normal for the mesher.

use std::sync::Arc;

use glam::{DVec2, DVec3};
use isoforge_field::{CustomField, Interval, Shape, Tape};

use super::SweepError;
use super::frames::{FrameOptions, Station, stations};
use crate::bound::{around, finite_box, widened};
use crate::bvh::{Box3, Bvh};
use crate::profile::Profile;

pub use super::frames::PathMethod;

/// The options of [`path_sweep`] (BOSL2's names and defaults).
#[derive(Clone, Debug, PartialEq)]
pub struct PathSweep {
    /// How the profile turns about the path.
    pub method: PathMethod,
    /// The normal for `incremental` (start) or `manual`.
    pub normal: Option<[f64; 3]>,
    /// Total twist, degrees, spread along the path by length.
    pub twist: f64,
    /// The profile's scale at the end of an open path.
    pub scale: f64,
    /// The path is a loop.
    pub closed: bool,
    /// The profile's rotational symmetry (a closed path's twist may be a multiple of
    /// 360/symmetry).
    pub symmetry: u32,
}

impl Default for PathSweep {
    fn default() -> Self {
        PathSweep {
            method: PathMethod::Incremental,
            normal: None,
            twist: 0.0,
            scale: 1.0,
            closed: false,
            symmetry: 1,
        }
    }
}

/// The most points a path may have.
pub const MAX_PATH_POINTS: usize = 200_000;

/// Samples a path closure over s in [0, 1] finely enough for its chords to stay within
/// `1e-5` of the path's size of the curve (checked at each chord's middle), from 64
/// samples up to [`MAX_CLOSURE_SAMPLES`]. A closed curve's point at s = 1 (the start
/// again) is dropped.
pub fn sample_curve(f: &dyn Fn(f64) -> [f64; 3], closed: bool) -> Result<Vec<DVec3>, SweepError> {
    let at = |s: f64| -> Result<DVec3, SweepError> {
        let p = f(s);
        if p.iter().all(|c| c.is_finite()) {
            Ok(DVec3::from(p))
        } else {
            Err(SweepError::Path(format!(
                "the path closure gives a point that is not finite at s = {s}: [{}, {}, {}]",
                p[0], p[1], p[2]
            )))
        }
    };
    let mut params: Vec<f64> = (0..=INITIAL_SAMPLES)
        .map(|i| i as f64 / INITIAL_SAMPLES as f64)
        .collect();
    let mut points: Vec<DVec3> = params.iter().map(|&s| at(s)).collect::<Result<_, _>>()?;
    let size = Box3::around(points.iter().copied());
    let tolerance = CHORD_TOLERANCE * (size.max - size.min).length().max(1e-9);
    loop {
        let mut next_params = Vec::with_capacity(params.len() * 2);
        let mut next_points = Vec::with_capacity(points.len() * 2);
        let mut split = false;
        for i in 0..params.len() - 1 {
            next_params.push(params[i]);
            next_points.push(points[i]);
            let mid_s = 0.5 * (params[i] + params[i + 1]);
            let mid = at(mid_s)?;
            let chord_mid = 0.5 * (points[i] + points[i + 1]);
            if mid.distance(chord_mid) > tolerance
                && params.len() + next_params.len() < MAX_CLOSURE_SAMPLES
            {
                next_params.push(mid_s);
                next_points.push(mid);
                split = true;
            }
        }
        next_params.push(params[params.len() - 1]);
        next_points.push(points[points.len() - 1]);
        params = next_params;
        points = next_points;
        if !split || params.len() >= MAX_CLOSURE_SAMPLES {
            break;
        }
    }
    if closed {
        points.pop();
    }
    Ok(points)
}

/// Samples a closure starts from: enough to see every turn of a knot.
const INITIAL_SAMPLES: usize = 64;
/// Chord error allowed, relative to the path's size: a circle's swept volume then differs
/// from the exact torus by under 1e-4 (measured: 4e-5 at 1e-5 on the torus test).
const CHORD_TOLERANCE: f64 = 1e-5;
/// The most samples taken from a closure.
pub const MAX_CLOSURE_SAMPLES: usize = 8192;

/// `path_sweep(profile, path, #{..})`: the profile swept along the path of points.
pub fn path_sweep(
    profile: &Profile,
    path: &[DVec3],
    opts: &PathSweep,
) -> Result<Shape, SweepError> {
    if path.len() > MAX_PATH_POINTS {
        return Err(SweepError::Path(format!(
            "the path has {} points; at most {MAX_PATH_POINTS} are allowed",
            path.len()
        )));
    }
    for (i, p) in path.iter().enumerate() {
        if !p.is_finite() {
            return Err(SweepError::Path(format!("path point {i} is not finite")));
        }
    }
    let frame_opts = FrameOptions {
        method: opts.method,
        normal: opts.normal.map(DVec3::from),
        twist: opts.twist,
        scale: opts.scale,
        closed: opts.closed,
        symmetry: opts.symmetry,
    };
    let stations = stations(path, &frame_opts)?;
    Ok(Shape::custom(Arc::new(PathField::new(
        profile,
        &stations,
        opts.closed,
    ))))
}

/// Which end a segment caps.
#[derive(Copy, Clone, Debug, PartialEq)]
enum Cap {
    None,
    /// The extension before the start: cut by the first station's plane.
    Start,
    /// The extension after the end: cut by the last station's plane.
    End,
}

#[derive(Clone, Debug)]
struct Segment {
    a: Station,
    b: Station,
    cap: Cap,
    /// How fast the profile's plane turns along the segment, radians per mm (bending,
    /// spin and twist together), and how fast its scale changes relative to itself.
    turn_rate: f64,
    scale_rate: f64,
}

/// The field of a path sweep.
pub struct PathField {
    profile: Tape,
    segments: Vec<Segment>,
    bvh: Bvh,
    /// The farthest a point of any cross-section is from its station.
    reach: f64,
    /// The profile's slope bound.
    lipschitz: f64,
}

impl PathField {
    fn new(profile: &Profile, stations: &[Station], closed: bool) -> PathField {
        let max_scale = stations.iter().map(|s| s.scale).fold(0.0, f64::max);
        let reach = profile.reach() * max_scale;
        let n = stations.len();
        let mut segments = Vec::with_capacity(n + 2);
        let count = if closed { n } else { n - 1 };
        for i in 0..count {
            segments.push(make_segment(stations[i], stations[(i + 1) % n], Cap::None));
        }
        if !closed {
            // Straight extensions past the ends, as long as the profile is wide, so every
            // point near a cap lies in some plane.
            let ext = reach.max(1e-6) * 1.5;
            let first = stations[0];
            let mut before = first;
            before.origin -= first.tangent * ext;
            before.s -= ext;
            segments.insert(0, make_segment(before, first, Cap::Start));
            let last = stations[n - 1];
            let mut after = last;
            after.origin += last.tangent * ext;
            after.s += ext;
            segments.push(make_segment(last, after, Cap::End));
        }
        let boxes = segments
            .iter()
            .map(|s| Box3::around([s.a.origin, s.b.origin]))
            .collect();
        PathField {
            profile: Tape::new(profile.shape()),
            segments,
            bvh: Bvh::new(boxes),
            reach,
            lipschitz: profile.lipschitz(),
        }
    }

    fn profile_value(&self, q: DVec2) -> f64 {
        crate::evals::with_evals(|ev| ev.point.eval(&self.profile, [q.x, q.y, 0.0]))
    }

    /// The profile value at `p` in segment `seg`'s plane at fraction `u`.
    fn in_plane(&self, seg: &Segment, u: f64, p: DVec3) -> f64 {
        let (a, b) = (&seg.a, &seg.b);
        let c = a.origin.lerp(b.origin, u);
        let t = a.tangent.lerp(b.tangent, u).normalize_or_zero();
        let y0 = a.y_axis.lerp(b.y_axis, u);
        let y = (y0 - t * y0.dot(t)).normalize_or_zero();
        let x = y.cross(t);
        let local = p - c;
        let (px, py) = (local.dot(x), local.dot(y));
        let twist = a.twist + (b.twist - a.twist) * u;
        let scale = a.scale + (b.scale - a.scale) * u;
        let (s, co) = twist.sin_cos();
        // Undo the profile's counter-clockwise twist, then its scale.
        let q = DVec2::new(px * co + py * s, -px * s + py * co) / scale;
        let mut v = self.profile_value(q) * scale;
        match seg.cap {
            Cap::None => {}
            Cap::Start => v = v.max((b.origin - p).dot(b.tangent)),
            Cap::End => v = v.max((p - a.origin).dot(a.tangent)),
        }
        v
    }

    /// The fractions u in [0, 1] at which `p` lies in the segment's plane.
    fn roots(seg: &Segment, p: DVec3) -> ([f64; 2], usize) {
        let q = p - seg.a.origin;
        let d = seg.b.origin - seg.a.origin;
        let dt = seg.b.tangent - seg.a.tangent;
        // (q − u d)·(ta + u dt) = 0  →  qa u² + qb u + qc = 0.
        let qa = -d.dot(dt);
        let qb = q.dot(dt) - d.dot(seg.a.tangent);
        let qc = q.dot(seg.a.tangent);
        let mut out = [0.0; 2];
        let mut n = 0;
        let mut push = |u: f64| {
            if (-1e-9..=1.0 + 1e-9).contains(&u) && n < 2 {
                out[n] = u.clamp(0.0, 1.0);
                n += 1;
            }
        };
        let scale = qb.abs().max(qc.abs()).max(1e-300);
        if qa.abs() <= 1e-12 * scale {
            if qb != 0.0 {
                push(-qc / qb);
            }
        } else {
            let disc = qb * qb - 4.0 * qa * qc;
            if disc >= 0.0 {
                let sq = disc.sqrt();
                // The stable pair: no cancellation between qb and the root.
                let k = -0.5 * (qb + qb.signum() * sq);
                if k != 0.0 {
                    push(k / qa);
                    push(qc / k);
                } else {
                    push(0.0);
                }
            }
        }
        (out, n)
    }

    /// The field at `p`, and whether any plane held it within reach.
    fn evaluate(&self, p: DVec3) -> f64 {
        let mut best = f64::INFINITY;
        let reach = self.reach * 1.5 + 1e-9;
        self.bvh.near_point(p, reach, &mut |i| {
            let seg = &self.segments[i];
            let (us, n) = Self::roots(seg, p);
            for &u in &us[..n] {
                best = best.min(self.in_plane(seg, u, p));
            }
        });
        if best.is_finite() {
            return best;
        }
        // In no plane near the path: outside, by at least the distance to the path less
        // the profile's reach.
        let gap = self.bvh.box_gap(&Box3 { min: p, max: p }).max(0.0);
        ((gap - self.reach) / self.lipschitz).max(FAR_FLOOR * (1.0 + self.reach))
    }
}

/// The smallest value given to a point that lies in no cross-section's plane (relative
/// to the profile's reach): positive, so such points are outside.
const FAR_FLOOR: f64 = 1e-3;

/// Safety factor on the slope estimate of the sweep near its path: the estimate comes
/// from the discrete path (turning angles between stations), which understates the true
/// curvature between them by a little.
const SLOPE_SAFETY: f64 = 2.0;

fn make_segment(a: Station, b: Station, cap: Cap) -> Segment {
    let len = a.origin.distance(b.origin).max(1e-12);
    // The angle the whole frame turns through: from the rotation between the two frames.
    let m = |s: &Station| glam::DMat3::from_cols(s.x_axis, s.y_axis, s.tangent);
    let rel = m(&b) * m(&a).transpose();
    let trace = rel.x_axis.x + rel.y_axis.y + rel.z_axis.z;
    let frame_turn = ((trace - 1.0) * 0.5).clamp(-1.0, 1.0).acos();
    let twist = (b.twist - a.twist).abs();
    let scale_rate = (b.scale - a.scale).abs() / a.scale.min(b.scale).max(1e-12) / len;
    Segment {
        a,
        b,
        cap,
        turn_rate: (frame_turn + twist) / len,
        scale_rate,
    }
}

impl CustomField for PathField {
    fn name(&self) -> &str {
        "path_sweep"
    }

    fn value(&self, p: [f64; 3]) -> f64 {
        self.evaluate(DVec3::from(p))
    }

    fn interval(&self, b: [Interval; 3]) -> Interval {
        let Some((c, h)) = finite_box(b) else {
            return Interval::ENTIRE;
        };
        let bx = Box3 {
            min: c - h,
            max: c + h,
        };
        let gap = self.bvh.box_gap(&bx);
        // Every value is at least (distance from the path − reach) / slope.
        let floor = (gap - self.reach) / self.lipschitz;
        if gap > self.reach * 1.5 {
            return widened(floor, f64::INFINITY);
        }
        let r = h.length();
        // Near the path: the value at the centre moves at most `slope` per mm, where the
        // slope grows with how fast the cross-sections turn at this distance from the
        // path, unless they turn so fast here that they fold (then no upper bound).
        let extent = self.reach + 2.0 * r;
        let (mut turn, mut grow) = (0.0f64, 0.0f64);
        self.bvh.near_box(&bx, extent, &mut |i| {
            turn = turn.max(self.segments[i].turn_rate);
            grow = grow.max(self.segments[i].scale_rate);
        });
        let fold = turn * extent;
        if r > 0.5 * self.reach || fold >= 0.5 {
            return widened(floor, f64::INFINITY);
        }
        let slope = SLOPE_SAFETY * self.lipschitz * (1.0 + (turn + grow) * extent) / (1.0 - fold);
        let near = around(self.evaluate(c), slope, r);
        if near.is_empty() || near == Interval::ENTIRE {
            return widened(floor, f64::INFINITY);
        }
        widened(near.inf().max(floor), near.sup())
    }

    fn gradient(&self, p: [f64; 3]) -> [f64; 4] {
        let p = DVec3::from(p);
        let v = self.evaluate(p);
        // Central differences: the field is piecewise smooth and this is only asked for
        // at surface crossings, a few per cell.
        let h = 1e-6 * (1.0 + self.reach);
        let d = |e: DVec3| (self.evaluate(p + e * h) - self.evaluate(p - e * h)) / (2.0 * h);
        [v, d(DVec3::X), d(DVec3::Y), d(DVec3::Z)]
    }
}
