//! `curve_tube(|s| [x, y, z], |s, theta| r, s0, s1)`: a tube of radius r(s, θ) around a
//! curve, Functy's third function class.
//!
//! Inside or outside is decided by the true closest point of the curve: a hierarchy of
//! the curve's chords (contiguous runs of segments, each box grown by the chords' sag)
//! finds the nearest chord, and Newton's method on the curve's own expression refines it
//! to the nearest curve point. The angle θ is measured in the curve's
//! rotation-minimizing frame (double reflection, Wang et al. 2008), not Functy's Frenet
//! frame: the Frenet normal flips where the curvature vanishes (an inflection, a straight
//! stretch) and is undefined on a straight line, so a tube whose radius depends on θ
//! would tear there; the rotation-minimizing frame turns only as much as the tangent
//! does. On a closed curve that frame comes back turned by the curve's total torsion, so
//! the turn is spread evenly along the curve and θ joins up.
//!
//! Open curves get flat caps at their ends. The value is `|p − c(s)| − r(s, θ)`, the
//! exact distance for a constant radius; its enclosure over a box comes from the
//! distance at the box's centre (the distance to a curve is 1-Lipschitz) and the radius's
//! enclosure over the parameters of the curve points within reach.

use std::cell::RefCell;
use std::f64::consts::PI;
use std::sync::Arc;

use glam::DVec3;
use isoforge_field::{CustomField, Interval, PointEval, Shape, Tape};

use crate::evals::with_evals;
use crate::frame::{normalize, rotation_minimizing_frames};

/// Chords along the curve. The sag of a chord shrinks with the square of its length: at
/// 2048 a trefoil knot's chords sag by about 1e-5 of its size, and Newton's method on the
/// curve takes the rest.
pub const SEGMENTS: usize = 2048;

/// Chords per leaf of the hierarchy.
const LEAF: usize = 4;

/// Why a tube cannot be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TubeError {
    /// The parameter range is not two different finite numbers.
    #[error("the parameter range {0} to {1} must be two different finite numbers")]
    Range(f64, f64),
    /// The curve is not finite somewhere.
    #[error("the curve is not finite at s = {0}")]
    NotFinite(f64),
    /// The curve does not move.
    #[error("the curve stays at one point")]
    Still,
}

/// The curve as three expressions of the parameter (the variable x).
struct Curve {
    coords: [Tape; 3],
}

impl Curve {
    fn point(&self, pe: &mut PointEval, s: f64) -> DVec3 {
        let q = [s, 0.0, 0.0];
        DVec3::new(
            pe.eval(&self.coords[0], q),
            pe.eval(&self.coords[1], q),
            pe.eval(&self.coords[2], q),
        )
    }

    /// The point and the derivative by s.
    fn with_derivative(&self, s: f64) -> (DVec3, DVec3) {
        with_evals(|e| {
            let q = [s, 0.0, 0.0];
            let g = self.coords.each_ref().map(|t| e.grad.eval(t, q));
            (
                DVec3::new(g[0].v, g[1].v, g[2].v),
                DVec3::new(g[0].d[0], g[1].d[0], g[2].d[0]),
            )
        })
    }
}

/// A node of the chord hierarchy: chords `lo..hi`, their box grown by their sag.
#[derive(Clone, Copy, Debug)]
struct Node {
    lo: usize,
    hi: usize,
    min: DVec3,
    max: DVec3,
    /// Children, for an inner node.
    kids: Option<(usize, usize)>,
}

impl Node {
    fn distance(&self, p: DVec3) -> f64 {
        let d = (self.min - p).max(p - self.max).max(DVec3::ZERO);
        d.length()
    }
}

/// The nearest point of the curve found for a query point.
#[derive(Clone, Copy, Debug)]
struct Nearest {
    /// Its parameter.
    s: f64,
    /// The curve point.
    point: DVec3,
    /// The curve's derivative there (for the frame's tangent).
    derivative: DVec3,
    /// The chord it was refined from.
    chord: usize,
    /// The distance to the nearest chord (the polyline's distance).
    chord_distance: f64,
}

/// The tube's field.
pub struct TubeField {
    curve: Curve,
    radius: Tape,
    /// The radius is a number (the field is then an exact distance).
    constant: Option<f64>,
    s0: f64,
    s1: f64,
    closed: bool,
    /// Parameters, points and frame normals at the chord ends.
    params: Vec<f64>,
    points: Vec<DVec3>,
    normals: Vec<DVec3>,
    /// The frame's turn after one lap of a closed curve (spread along it).
    holonomy: f64,
    nodes: Vec<Node>,
    /// The largest sag of a chord (times a safety factor).
    sag: f64,
    /// A length scale for finite differences.
    scale: f64,
    /// How near an end of an open curve its cap plane counts (the largest radius).
    cap_zone: f64,
    /// The ends of an open curve with their caps' outward normals.
    caps: [(DVec3, DVec3); 2],
}

impl TubeField {
    /// Builds a tube around `curve` (three expressions of x, the parameter) with `radius`
    /// (an expression of x = s and y = θ), for s from `s0` to `s1`.
    pub fn new(
        curve: [Shape; 3],
        radius: &Shape,
        s0: f64,
        s1: f64,
    ) -> Result<TubeField, TubeError> {
        if !(s0.is_finite() && s1.is_finite() && s0 != s1) {
            return Err(TubeError::Range(s0, s1));
        }
        let curve = Curve {
            coords: curve.each_ref().map(Tape::new),
        };
        let mut pe = PointEval::new();
        let params: Vec<f64> = (0..=SEGMENTS)
            .map(|i| s0 + (s1 - s0) * i as f64 / SEGMENTS as f64)
            .collect();
        let points: Vec<DVec3> = params.iter().map(|&s| curve.point(&mut pe, s)).collect();
        if let Some((s, _)) = params.iter().zip(&points).find(|(_, p)| !p.is_finite()) {
            return Err(TubeError::NotFinite(*s));
        }
        let (lo, hi) = points.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        );
        let size = (hi - lo).length();
        if size == 0.0 || size.is_nan() {
            return Err(TubeError::Still);
        }
        let closed = points[0].distance(points[SEGMENTS]) <= 1e-9 * size;
        // Frames by double reflection along the chord ends.
        let pe_cell = RefCell::new(PointEval::new());
        let at = |s: f64| curve.point(&mut pe_cell.borrow_mut(), s).to_array();
        let h = 1e-6 * (s1 - s0).abs();
        let frames = rotation_minimizing_frames(&at, &params, 1, h);
        let normals: Vec<DVec3> = frames.iter().map(|f| f.r).collect();
        let holonomy = if closed {
            let (r0, r1, t0) = (frames[0].r, frames[SEGMENTS].r, frames[0].t);
            r0.cross(r1).dot(t0).atan2(r0.dot(r1))
        } else {
            0.0
        };
        // Sag of each chord: how far the curve strays from it, and how far the curve
        // point at an interpolated parameter lies from the chord point there (a search
        // starts from that point), at three inner points.
        let sags: Vec<f64> = (0..SEGMENTS)
            .map(|i| {
                let (a, b) = (points[i], points[i + 1]);
                [0.25, 0.5, 0.75]
                    .iter()
                    .map(|&u| {
                        let q = curve.point(&mut pe, params[i] + u * (params[i + 1] - params[i]));
                        let off_chord = segment_point(q, a, b).distance(q);
                        off_chord.max(q.distance(a + (b - a) * u))
                    })
                    .fold(0.0, f64::max)
            })
            .collect();
        // Inner samples can miss the peak: double it, and a floor for rounding.
        let sag = 2.0 * sags.iter().cloned().fold(0.0, f64::max) + 1e-12 * size;
        let mut nodes = Vec::new();
        build(&mut nodes, &points, &sags, 0, SEGMENTS);
        let constant = radius.as_constant();
        let radius_tape = Tape::new(radius);
        let cap_zone = match constant {
            Some(k) => k.max(0.0),
            None => {
                let span = Interval::try_from((s0.min(s1), s0.max(s1))).unwrap_or(Interval::ENTIRE);
                let angle =
                    Interval::try_from((-PI.next_up(), PI.next_up())).unwrap_or(Interval::ENTIRE);
                let zero = Interval::try_from((0.0, 0.0)).unwrap_or(Interval::ENTIRE);
                let r = isoforge_field::IntervalEval::new().eval(&radius_tape, [span, angle, zero]);
                if r.sup().is_finite() {
                    r.sup().max(0.0)
                } else {
                    size
                }
            }
        };
        Ok(TubeField {
            curve,
            radius: radius_tape,
            constant,
            s0,
            s1,
            closed,
            params,
            points,
            normals,
            holonomy,
            nodes,
            sag,
            scale: size,
            cap_zone,
            caps: [(DVec3::ZERO, DVec3::Z); 2],
        }
        .with_caps())
    }

    /// True when the field is an exact distance (a constant radius).
    pub fn is_distance(&self) -> bool {
        self.constant.is_some()
    }

    /// True when the curve closes on itself.
    pub fn is_closed(&self) -> bool {
        self.closed
    }

    /// The nearest chord to `p`: (index, distance), searching from a known candidate.
    fn nearest_chord(&self, p: DVec3, start: Option<usize>) -> (usize, f64) {
        let mut best = match start {
            Some(i) => (i, chord_distance(p, self.points[i], self.points[i + 1])),
            None => (0, f64::INFINITY),
        };
        let mut stack = vec![0usize];
        while let Some(n) = stack.pop() {
            let node = &self.nodes[n];
            if node.distance(p) >= best.1 {
                continue;
            }
            match node.kids {
                Some((a, b)) => {
                    let (da, db) = (self.nodes[a].distance(p), self.nodes[b].distance(p));
                    // Nearer child last, so it is searched first.
                    if da < db {
                        stack.push(b);
                        stack.push(a);
                    } else {
                        stack.push(a);
                        stack.push(b);
                    }
                }
                None => {
                    for i in node.lo..node.hi {
                        let d = chord_distance(p, self.points[i], self.points[i + 1]);
                        if d < best.1 {
                            best = (i, d);
                        }
                    }
                }
            }
        }
        best
    }

    /// Keeps a parameter on the curve: clamped on an open curve, wrapped on a closed one.
    fn onto_curve(&self, s: f64) -> f64 {
        let (a, b) = if self.s0 < self.s1 {
            (self.s0, self.s1)
        } else {
            (self.s1, self.s0)
        };
        if self.closed {
            let span = b - a;
            a + (s - a).rem_euclid(span)
        } else {
            s.clamp(a, b)
        }
    }

    /// The nearest curve point: the nearest chord, refined by Newton's method on the
    /// squared distance's slope g(s) = (c(s) − p)·c'(s). Its own slope g' is taken by the
    /// secant of the last two steps where that says the distance is at a minimum, else by
    /// the Gauss-Newton estimate |c'|² (first derivatives only). Gauss-Newton alone
    /// converges only linearly, by about the distance over the curve's radius of
    /// curvature a step (0.3 to 0.8 near the trefoil fixture's tube), so it used all 8
    /// steps; the secant's superlinear steps stop in about 4 (trefoil at depth 7: from
    /// 7.8 and 9.4 s to 6.8 and 5.8 s in two release runs on a busy machine).
    fn nearest(&self, p: DVec3, start: Option<usize>) -> Nearest {
        let (i, chord_distance) = self.nearest_chord(p, start);
        let (a, b) = (self.points[i], self.points[i + 1]);
        let ab = b - a;
        let u = if ab.length_squared() > 0.0 {
            ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let mut s = self.params[i] + u * (self.params[i + 1] - self.params[i]);
        let (mut point, mut d1) = self.curve.with_derivative(s);
        let mut best = (p.distance_squared(point), s, point, d1);
        let step_limit = 2.0 * (self.params[1] - self.params[0]).abs();
        // The last step and g before it, for the secant.
        let mut last: Option<(f64, f64)> = None;
        for _ in 0..8 {
            let len2 = d1.length_squared();
            if len2 == 0.0 || len2.is_nan() {
                break;
            }
            let g = (point - p).dot(d1);
            let slope = match last {
                Some((step, g_before)) if step != 0.0 => {
                    let secant = (g - g_before) / step;
                    // Only where the distance curves upward (a minimum) and not far
                    // flatter than Gauss-Newton says; else its step is the safer one.
                    if secant > 0.1 * len2 { secant } else { len2 }
                }
                _ => len2,
            };
            let step = (-g / slope).clamp(-step_limit, step_limit);
            s = self.onto_curve(s + step);
            (point, d1) = self.curve.with_derivative(s);
            let d = p.distance_squared(point);
            if d < best.0 {
                best = (d, s, point, d1);
            }
            if step.abs() <= 1e-13 * (1.0 + s.abs()) {
                break;
            }
            last = Some((step, g));
        }
        Nearest {
            s: best.1,
            point: best.2,
            derivative: best.3,
            chord: i,
            chord_distance,
        }
    }

    /// The frame at parameter s (where the curve's derivative is `d1`), in the chord
    /// `chord`: the stored normal carried to the exact tangent by the smallest turn, less
    /// the spread holonomy.
    fn frame(&self, d1: DVec3, chord: usize, s: f64) -> (DVec3, DVec3, DVec3) {
        let t = normalize(d1).unwrap_or_else(|| {
            normalize(self.points[chord + 1] - self.points[chord]).unwrap_or(DVec3::Z)
        });
        let r0 = self.normals[chord];
        let r = normalize(r0 - t * r0.dot(t)).unwrap_or_else(|| crate::frame::any_normal(t));
        let r = if self.closed && self.holonomy != 0.0 {
            let f = (s - self.s0) / (self.s1 - self.s0);
            let a = -self.holonomy * f;
            r * a.cos() + t.cross(r) * a.sin()
        } else {
            r
        };
        (t, r, t.cross(r))
    }

    fn value_at(&self, p: DVec3, start: Option<usize>) -> (f64, usize) {
        let n = self.nearest(p, start);
        let d = p - n.point;
        let (t, r, s_axis) = self.frame(n.derivative, n.chord, n.s);
        let theta = d.dot(s_axis).atan2(d.dot(r));
        let radius = match self.constant {
            Some(c) => c.max(0.0),
            None => with_evals(|e| e.point.eval(&self.radius, [n.s, theta, 0.0])).max(0.0),
        };
        let radius = if radius.is_nan() { 0.0 } else { radius };
        let side = d.length() - radius;
        if self.closed {
            return (side, n.chord);
        }
        let at_start = n.s == self.onto_curve(self.s0) && d.dot(t) * self.direction() < 0.0;
        let at_end = n.s == self.onto_curve(self.s1) && d.dot(t) * self.direction() > 0.0;
        if at_start || at_end {
            // Beyond an end: the distance to the flat cap.
            let axial = d.dot(t).abs();
            let across = (d - t * d.dot(t)).length();
            return (cap(across - radius, axial), n.chord);
        }
        // Near an end, inside, the cap's plane may be nearer than the side.
        let mut v = side;
        for (end, outward) in self.caps {
            if n.point.distance(end) <= self.cap_zone {
                v = v.max((p - end).dot(outward));
            }
        }
        (v, n.chord)
    }

    /// Sets the ends of an open curve with their caps' outward normals.
    fn with_caps(mut self) -> TubeField {
        let dir = self.direction();
        let (a, da) = self.curve.with_derivative(self.s0);
        let (b, db) = self.curve.with_derivative(self.s1);
        let ta = normalize(da).unwrap_or(DVec3::Z);
        let tb = normalize(db).unwrap_or(DVec3::Z);
        self.caps = [(a, -ta * dir), (b, tb * dir)];
        self
    }

    /// +1 when s runs upwards, −1 when downwards.
    fn direction(&self) -> f64 {
        if self.s1 > self.s0 { 1.0 } else { -1.0 }
    }

    /// The hull of the parameters of chords whose boxes come within `reach` of `p`, and
    /// whether an end of an open curve is among them.
    fn parameters_within(&self, p: DVec3, reach: f64) -> (f64, f64, bool) {
        let (mut lo, mut hi) = (usize::MAX, 0usize);
        let mut stack = vec![0usize];
        while let Some(n) = stack.pop() {
            let node = &self.nodes[n];
            if node.distance(p) > reach {
                continue;
            }
            match node.kids {
                Some((a, b)) => {
                    stack.push(a);
                    stack.push(b);
                }
                None => {
                    lo = lo.min(node.lo);
                    hi = hi.max(node.hi);
                }
            }
        }
        if lo > hi {
            return (self.s0, self.s0, false);
        }
        let ends = !self.closed && (lo == 0 || hi == SEGMENTS);
        let (a, b) = (self.params[lo], self.params[hi]);
        (a.min(b), a.max(b), ends)
    }
}

/// The exact distance to a flat disc end: `across` from the rim's cylinder, `axial`
/// beyond the end plane.
fn cap(across: f64, axial: f64) -> f64 {
    let outside = (across.max(0.0).powi(2) + axial.max(0.0).powi(2)).sqrt();
    outside + across.max(axial).min(0.0)
}

/// The point of segment a–b nearest q.
fn segment_point(q: DVec3, a: DVec3, b: DVec3) -> DVec3 {
    let ab = b - a;
    let len2 = ab.length_squared();
    if len2 == 0.0 {
        return a;
    }
    a + ab * ((q - a).dot(ab) / len2).clamp(0.0, 1.0)
}

fn chord_distance(q: DVec3, a: DVec3, b: DVec3) -> f64 {
    segment_point(q, a, b).distance(q)
}

/// Builds the hierarchy over chords `lo..hi`; returns the node's index.
fn build(nodes: &mut Vec<Node>, points: &[DVec3], sags: &[f64], lo: usize, hi: usize) -> usize {
    let index = nodes.len();
    let mut min = DVec3::splat(f64::INFINITY);
    let mut max = DVec3::splat(f64::NEG_INFINITY);
    for i in lo..hi {
        let grow = DVec3::splat(2.0 * sags[i]);
        min = min.min(points[i].min(points[i + 1]) - grow);
        max = max.max(points[i].max(points[i + 1]) + grow);
    }
    nodes.push(Node {
        lo,
        hi,
        min,
        max,
        kids: None,
    });
    if hi - lo > LEAF {
        let mid = (lo + hi) / 2;
        let a = build(nodes, points, sags, lo, mid);
        let b = build(nodes, points, sags, mid, hi);
        nodes[index].kids = Some((a, b));
    }
    index
}

impl CustomField for TubeField {
    fn name(&self) -> &str {
        "curve_tube"
    }

    fn value(&self, p: [f64; 3]) -> f64 {
        self.value_at(DVec3::from(p), None).0
    }

    fn values(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        // Neighbouring points have neighbouring nearest chords.
        let mut last = None;
        for (i, o) in out.iter_mut().enumerate() {
            let (v, chord) = self.value_at(DVec3::new(xs[i], ys[i], zs[i]), last);
            *o = v;
            last = Some(chord);
        }
    }

    fn interval(&self, b: [Interval; 3]) -> Interval {
        let (lo, hi) = (
            DVec3::new(b[0].inf(), b[1].inf(), b[2].inf()),
            DVec3::new(b[0].sup(), b[1].sup(), b[2].sup()),
        );
        if !(lo.is_finite() && hi.is_finite()) {
            return Interval::ENTIRE;
        }
        let c = (lo + hi) * 0.5;
        let r = (hi - lo).length() * 0.5 * (1.0 + 1e-12);
        let n = self.nearest(c, None);
        // The true distance at c lies between the chords' less their sag and the curve
        // point found.
        let near = (n.chord_distance - self.sag).max(0.0);
        let far = c.distance(n.point);
        let reach = far + 2.0 * r + 2.0 * self.sag;
        let (sa, sb, ends) = self.parameters_within(c, reach);
        let (rlo, rhi) = match self.constant {
            Some(k) => (k.max(0.0), k.max(0.0)),
            None => {
                let s = Interval::try_from((sa, sb)).unwrap_or(Interval::ENTIRE);
                let angle =
                    Interval::try_from((-PI.next_up(), PI.next_up())).unwrap_or(Interval::ENTIRE);
                let zero = Interval::try_from((0.0, 0.0)).unwrap_or(Interval::ENTIRE);
                let i = with_evals(|e| e.interval.eval(&self.radius, [s, angle, zero]));
                if i.is_empty() || !i.inf().is_finite() && !i.sup().is_finite() {
                    (0.0, f64::INFINITY)
                } else {
                    (i.inf().max(0.0), i.sup().max(0.0))
                }
            }
        };
        let margin = 1e-9 * self.scale;
        let lower = near - r - rhi - margin;
        // Near an end the value is at most the distance to the end, which is at most the
        // distance to the curve plus the cap zone.
        let upper = far + r + 2.0 * self.sag + margin + if ends { self.cap_zone } else { -rlo };
        Interval::try_from((lower, upper)).unwrap_or(Interval::ENTIRE)
    }

    /// Central differences (the radius may vary with s and θ).
    fn gradient(&self, p: [f64; 3]) -> [f64; 4] {
        let v = self.value(p);
        let h = 1e-7 * self.scale;
        let mut g = [v, 0.0, 0.0, 0.0];
        for k in 0..3 {
            let (mut a, mut b) = (p, p);
            a[k] += h;
            b[k] -= h;
            g[k + 1] = (self.value(a) - self.value(b)) / (2.0 * h);
        }
        g
    }

    fn interval_gradient(&self, _: [Interval; 3]) -> [Interval; 3] {
        match self.constant {
            // The distance to a tube is 1-Lipschitz.
            Some(_) => [Interval::try_from((-1.0, 1.0)).unwrap_or(Interval::ENTIRE); 3],
            None => [Interval::ENTIRE; 3],
        }
    }
}

/// The tube's field as a shape, and whether it is an exact distance (constant radius).
pub fn curve_tube(
    curve: [Shape; 3],
    radius: &Shape,
    s0: f64,
    s1: f64,
) -> Result<(Shape, bool), TubeError> {
    let tube = TubeField::new(curve, radius, s0, s1)?;
    let exact = tube.is_distance();
    Ok((Shape::custom(Arc::new(tube)), exact))
}

#[cfg(test)]
mod tests;
