//! The distance from a point to a convex body by GJK (Gilbert, Johnson, Keerthi 1988, in
//! van den Bergen's formulation): a simplex of support points is grown towards the point
//! and reduced to the face, edge or vertex nearest it, until the support along the
//! current direction brings the estimate no closer. Simplex reduction follows the
//! Voronoi-region tests of Ericson, "Real-Time Collision Detection", §5.1.
//!
//! All work is in coordinates relative to the query point, so the question is always
//! "how far is the origin from the body K − p".

use glam::DVec3;

use super::convex::Convex;

/// At most this many support queries per distance; GJK on the bodies here converges
/// in a handful (polytopes) to a few dozen (round parts at 1e-9 relative).
const MAX_ITERATIONS: usize = 96;

/// The answer for one point.
#[derive(Copy, Clone, Debug)]
pub struct Closest {
    /// The point lies in the body (or within the tolerance of its surface).
    pub inside: bool,
    /// The distance to the body (0 inside); an upper bound within the tolerance.
    pub distance: f64,
    /// The body's point nearest the query point (the query point itself inside).
    pub point: DVec3,
}

/// Up to four support points (relative to the query point).
#[derive(Copy, Clone)]
struct Simplex {
    pts: [DVec3; 4],
    n: usize,
}

impl Simplex {
    fn push(&mut self, w: DVec3) {
        self.pts[self.n] = w;
        self.n += 1;
    }
    fn set(&mut self, pts: &[DVec3]) {
        self.n = pts.len();
        self.pts[..pts.len()].copy_from_slice(pts);
    }
}

/// The closest point to the origin on segment a–b, and the vertices that span it.
fn segment(a: DVec3, b: DVec3, out: &mut Simplex) -> DVec3 {
    let ab = b - a;
    let den = ab.length_squared();
    let t = if den > 0.0 { -a.dot(ab) / den } else { 0.0 };
    if t <= 0.0 {
        out.set(&[a]);
        a
    } else if t >= 1.0 {
        out.set(&[b]);
        b
    } else {
        out.set(&[a, b]);
        a + ab * t
    }
}

/// The closest point to the origin on triangle a, b, c (Ericson's region tests).
fn triangle(a: DVec3, b: DVec3, c: DVec3, out: &mut Simplex) -> DVec3 {
    let ab = b - a;
    let ac = c - a;
    let ap = -a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        out.set(&[a]);
        return a;
    }
    let bp = -b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        out.set(&[b]);
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        out.set(&[a, b]);
        return a + ab * v;
    }
    let cp = -c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        out.set(&[c]);
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        out.set(&[a, c]);
        return a + ac * w;
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        out.set(&[b, c]);
        return b + (c - b) * w;
    }
    let den = va + vb + vc;
    if den == 0.0 || den.is_nan() {
        // A degenerate (zero-area) triangle: its nearest edge.
        return segment(a, b, out);
    }
    let (v, w) = (vb / den, vc / den);
    out.set(&[a, b, c]);
    a + ab * v + ac * w
}

/// The point of triangle a, b, c nearest `p`.
pub fn closest_on_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    let mut s = Simplex {
        pts: [DVec3::ZERO; 4],
        n: 0,
    };
    p + triangle(a - p, b - p, c - p, &mut s)
}

/// The closest point to the origin on tetrahedron a, b, c, d; `None` when the origin is
/// inside it.
fn tetrahedron(p: [DVec3; 4], out: &mut Simplex) -> Option<DVec3> {
    let [a, b, c, d] = p;
    let faces = [(a, b, c, d), (a, c, d, b), (a, d, b, c), (b, d, c, a)];
    let volume = (b - a).cross(c - a).dot(d - a);
    let scale = [b - a, c - a, d - a]
        .iter()
        .map(|e| e.length())
        .fold(0.0f64, f64::max);
    let flat = volume.abs() <= 1e-12 * scale * scale * scale;
    let mut best: Option<(f64, DVec3, Simplex)> = None;
    for (u, v, w, opposite) in faces {
        let n = (v - u).cross(w - u);
        // The origin is beyond this face when it and the opposite vertex are on
        // different sides of the face's plane (every face counts on a flat tetrahedron).
        let outside = flat || n.dot(-u) * n.dot(opposite - u) < 0.0;
        if outside {
            let mut s = Simplex {
                pts: [DVec3::ZERO; 4],
                n: 0,
            };
            let q = triangle(u, v, w, &mut s);
            let dist = q.length_squared();
            if best.as_ref().is_none_or(|(bd, _, _)| dist < *bd) {
                best = Some((dist, q, s));
            }
        }
    }
    let (_, q, s) = best?;
    *out = s;
    Some(q)
}

/// The distance from `p` to `body`. `hint` is a guess of the direction from `p` to the
/// body's nearest point (the answer for a neighbouring point makes GJK converge in a
/// few steps); `tolerance` is the absolute accuracy wanted, in mm.
pub fn closest(body: &Convex, p: DVec3, hint: DVec3, tolerance: f64) -> Closest {
    // The nearest point's outward normal is −hint, and along it the support is that
    // point itself (for a smooth body): start there.
    let start = if hint.length_squared() > 0.0 {
        -hint
    } else {
        DVec3::X
    };
    let mut v = body.support(start) - p;
    let mut simplex = Simplex {
        pts: [DVec3::ZERO; 4],
        n: 0,
    };
    simplex.push(v);
    let touching = tolerance * tolerance;
    for _ in 0..MAX_ITERATIONS {
        let vv = v.length_squared();
        if vv <= touching {
            return Closest {
                inside: true,
                distance: 0.0,
                point: p,
            };
        }
        let w = body.support(-v) - p;
        // |v| - v·w/|v| bounds how much closer the body can be than |v|.
        let gap = vv - v.dot(w);
        if gap <= tolerance * vv.sqrt() || simplex.pts[..simplex.n].contains(&w) {
            break;
        }
        simplex.push(w);
        let pts = simplex.pts;
        v = match simplex.n {
            2 => segment(pts[0], pts[1], &mut simplex),
            3 => triangle(pts[0], pts[1], pts[2], &mut simplex),
            _ => match tetrahedron(pts, &mut simplex) {
                Some(q) => q,
                None => {
                    return Closest {
                        inside: true,
                        distance: 0.0,
                        point: p,
                    };
                }
            },
        };
    }
    Closest {
        inside: false,
        distance: v.length(),
        point: p + v,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hull::convex::Body;

    fn dist(body: &Convex, p: [f64; 3]) -> Closest {
        closest(body, DVec3::from(p), DVec3::ZERO, 1e-10)
    }

    #[test]
    fn distance_to_a_ball_and_a_box() {
        let ball = Convex::ball(DVec3::new(1.0, 2.0, 3.0), 2.0);
        let c = dist(&ball, [1.0, 2.0, 8.0]);
        assert!(!c.inside && (c.distance - 3.0).abs() < 1e-8, "{c:?}");
        assert!(dist(&ball, [1.5, 2.0, 3.0]).inside);
        let b = Convex::new(Body::Box(DVec3::new(1.0, 1.0, 1.0)));
        let c = dist(&b, [3.0, 3.0, 0.5]);
        assert!((c.distance - 8f64.sqrt()).abs() < 1e-9, "{c:?}");
        assert!((c.point - DVec3::new(1.0, 1.0, 0.5)).length() < 1e-9);
        assert!(dist(&b, [0.9, -0.9, 0.2]).inside);
        assert!((dist(&b, [0.0, 0.0, 4.0]).distance - 3.0).abs() < 1e-12);
    }

    #[test]
    fn hull_of_two_balls_is_a_capsule() {
        let h = Convex::hull(vec![
            Convex::ball(DVec3::ZERO, 1.0),
            Convex::ball(DVec3::new(10.0, 0.0, 0.0), 1.0),
        ]);
        for (p, want) in [
            ([5.0, 3.0, 0.0], 2.0),
            ([5.0, 0.0, -4.0], 3.0),
            ([-3.0, 0.0, 0.0], 2.0),
            ([13.0, 4.0, 0.0], 4.0),
        ] {
            let c = dist(&h, p);
            assert!(
                !c.inside && (c.distance - want).abs() < 1e-7,
                "{p:?}: {c:?}"
            );
        }
        assert!(dist(&h, [5.0, 0.9, 0.0]).inside);
        assert!(!dist(&h, [5.0, 1.1, 0.0]).inside);
    }

    #[test]
    fn hull_of_unequal_balls_is_a_cone_frustum() {
        // Balls of radius 1 and 3 with centres 10 apart: the tangent cone's side.
        let h = Convex::hull(vec![
            Convex::ball(DVec3::ZERO, 1.0),
            Convex::ball(DVec3::new(10.0, 0.0, 0.0), 3.0),
        ]);
        // The side line touches the balls where the normal makes sin a = 0.2 with y.
        let (s, c) = (0.2f64, (1.0f64 - 0.04).sqrt());
        let n = DVec3::new(-s, c, 0.0);
        // The tangent points are at r·n on each ball; a point 2.5 out from that line.
        let on = n * 1.0;
        let along = (DVec3::new(10.0, 0.0, 0.0) + n * 3.0 - on).normalize();
        let q = on + along * 4.0 + n * 2.5;
        let got = dist(&h, q.to_array());
        assert!((got.distance - 2.5).abs() < 1e-7, "{got:?}");
    }
}
