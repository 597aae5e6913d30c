//! Convex bodies given by their support mapping: for a direction u, a point of the body
//! that lies farthest along u. That is all GJK needs to measure distances to a body, and
//! the support of a convex hull is the farthest of its parts' supports, so hulls of
//! spheres, boxes, cylinders, cones and capsules come out exact.

use std::sync::Arc;

use glam::{DMat3, DVec3};

/// A primitive body in its own frame.
#[derive(Clone, Debug, PartialEq)]
pub enum Body {
    /// A point (a ball of radius 0 at the origin); radii come from `Convex::inflate`.
    Point,
    /// A box with these half-sides, centred at the origin.
    Box(DVec3),
    /// A cylinder of radius `r` about the z axis, from z = −half to z = half.
    Cylinder {
        /// The radius.
        r: f64,
        /// Half the height.
        half: f64,
    },
    /// A cone: base of radius `r` on z = 0, apex at (0, 0, h).
    Cone {
        /// The base radius.
        r: f64,
        /// The height.
        h: f64,
    },
    /// An ellipsoid with these semi-axes.
    Ellipsoid(DVec3),
    /// The segment between two points.
    Segment(DVec3, DVec3),
    /// A finite set of points (their convex hull).
    Points(Arc<[DVec3]>),
    /// The convex hull of several bodies.
    Hull(Arc<[Convex]>),
}

/// A body placed in space: `p ↦ m·p + t`, then grown by a ball of radius `inflate`
/// (a Minkowski sum, which keeps it convex and its support exact).
#[derive(Clone, Debug, PartialEq)]
pub struct Convex {
    body: Body,
    m: DMat3,
    t: DVec3,
    inflate: f64,
}

fn unit(u: DVec3) -> DVec3 {
    let len = u.length();
    if len > 0.0 && len.is_finite() {
        u / len
    } else {
        DVec3::Z
    }
}

/// `s` if `s` is not 0, else 1 (a support point on a face may be any point of it).
fn sign(s: f64) -> f64 {
    if s < 0.0 { -1.0 } else { 1.0 }
}

impl Body {
    /// A farthest point of the body along `u` (any length; zero picks some point).
    pub fn support(&self, u: DVec3) -> DVec3 {
        match self {
            Body::Point => DVec3::ZERO,
            Body::Box(h) => DVec3::new(sign(u.x) * h.x, sign(u.y) * h.y, sign(u.z) * h.z),
            Body::Cylinder { r, half } => {
                let radial = DVec3::new(u.x, u.y, 0.0);
                let rim = if radial.length_squared() > 0.0 {
                    unit(radial) * *r
                } else {
                    DVec3::ZERO
                };
                rim + DVec3::new(0.0, 0.0, sign(u.z) * half)
            }
            Body::Cone { r, h } => {
                let radial = DVec3::new(u.x, u.y, 0.0);
                let rim = if radial.length_squared() > 0.0 {
                    unit(radial) * *r
                } else {
                    DVec3::ZERO
                };
                let apex = DVec3::new(0.0, 0.0, *h);
                if apex.dot(u) > rim.dot(u) { apex } else { rim }
            }
            Body::Ellipsoid(a) => {
                // The normal at x is (x/a²); the point whose normal is u is a²u / |a u|.
                let au = *a * u;
                let len = au.length();
                if len > 0.0 {
                    *a * *a * u / len
                } else {
                    DVec3::new(a.x, 0.0, 0.0)
                }
            }
            Body::Segment(a, b) => {
                if b.dot(u) > a.dot(u) {
                    *b
                } else {
                    *a
                }
            }
            Body::Points(ps) => farthest(ps.iter().copied(), u),
            Body::Hull(parts) => farthest(parts.iter().map(|c| c.support(u)), u),
        }
    }
}

/// True for an orthogonal matrix (a rotation or reflection): balls stay balls under it.
fn is_rotation(m: &DMat3) -> bool {
    let p = *m * m.transpose();
    (p - DMat3::IDENTITY)
        .to_cols_array()
        .iter()
        .all(|e| e.abs() < 1e-12)
}

fn farthest(points: impl Iterator<Item = DVec3>, u: DVec3) -> DVec3 {
    let mut best = (f64::NEG_INFINITY, DVec3::ZERO);
    for p in points {
        let d = p.dot(u);
        if d > best.0 {
            best = (d, p);
        }
    }
    best.1
}

impl Convex {
    /// A body at the origin in its own orientation.
    pub fn new(body: Body) -> Convex {
        Convex {
            body,
            m: DMat3::IDENTITY,
            t: DVec3::ZERO,
            inflate: 0.0,
        }
    }

    /// A ball of radius `r` at `c`.
    pub fn ball(c: DVec3, r: f64) -> Convex {
        Convex::new(Body::Point).inflated(r).moved(c)
    }

    /// The convex hull of these bodies.
    pub fn hull(parts: Vec<Convex>) -> Convex {
        Convex::new(Body::Hull(parts.into()))
    }

    /// A farthest point along `u`.
    pub fn support(&self, u: DVec3) -> DVec3 {
        let local = self.body.support(self.m.transpose() * u);
        let p = self.m * local + self.t;
        if self.inflate > 0.0 {
            p + unit(u) * self.inflate
        } else {
            p
        }
    }

    /// Moved by `v`.
    pub fn moved(mut self, v: DVec3) -> Convex {
        self.t += v;
        self
    }

    /// Turned (or mirrored) by the orthogonal matrix `r` about the origin.
    pub fn turned(mut self, r: DMat3) -> Convex {
        self.m = r * self.m;
        self.t = r * self.t;
        self
    }

    /// Scaled about the origin by a factor per axis; `None` when a grown body would be
    /// scaled unevenly (a ball stretched is no longer a ball).
    pub fn scaled(mut self, k: DVec3) -> Option<Convex> {
        let even = k.x.abs() == k.y.abs() && k.y.abs() == k.z.abs();
        if self.inflate > 0.0 && !even {
            return None;
        }
        let d = DMat3::from_diagonal(k);
        self.m = d * self.m;
        self.t = d * self.t;
        self.inflate *= k.x.abs();
        Some(self)
    }

    /// Grown by `r >= 0` in every direction (the offset of a convex body).
    pub fn inflated(mut self, r: f64) -> Convex {
        self.inflate += r.max(0.0);
        self
    }

    /// The body without the ball it is grown by, and that ball's radius. For a hull the
    /// ball all parts share comes out too: the hull of balls of radius 4 is the hull of
    /// their centres grown by 4, a polytope on which GJK ends in a few exact steps instead
    /// of creeping round a sphere.
    pub fn core(&self) -> (Convex, f64) {
        let mut inner = self.clone();
        let mut grown = inner.inflate;
        inner.inflate = 0.0;
        if let Body::Hull(parts) = &inner.body {
            let common = parts
                .iter()
                .map(|p| p.inflate)
                .fold(f64::INFINITY, f64::min);
            if common > 0.0 && common.is_finite() {
                let shrunk: Vec<Convex> = parts
                    .iter()
                    .map(|p| {
                        let mut p = p.clone();
                        p.inflate -= common;
                        p
                    })
                    .collect();
                // Scaling by m keeps inflation as is: only its translation and frame change,
                // so the shared ball's radius is the same in the hull's own frame when m
                // is a rotation; a scaled hull keeps its inflation in the parts.
                if is_rotation(&inner.m) {
                    inner.body = Body::Hull(shrunk.into());
                    grown += common;
                }
            }
        }
        (inner, grown)
    }

    /// The corners of the body when it is a polytope (points, segments, boxes, and hulls
    /// and linear images of those, not grown), in world coordinates.
    pub fn polytope_points(&self) -> Option<Vec<DVec3>> {
        if self.inflate != 0.0 {
            return None;
        }
        let local: Vec<DVec3> = match &self.body {
            Body::Point => vec![DVec3::ZERO],
            Body::Box(h) => (0..8)
                .map(|i| {
                    DVec3::new(
                        if i & 1 == 0 { -h.x } else { h.x },
                        if i & 2 == 0 { -h.y } else { h.y },
                        if i & 4 == 0 { -h.z } else { h.z },
                    )
                })
                .collect(),
            Body::Segment(a, b) => vec![*a, *b],
            Body::Points(ps) => ps.to_vec(),
            Body::Hull(parts) => {
                let mut all = Vec::new();
                for p in parts.iter() {
                    all.extend(p.polytope_points()?);
                }
                all
            }
            Body::Cylinder { .. } | Body::Cone { .. } | Body::Ellipsoid(_) => return None,
        };
        Some(local.into_iter().map(|p| self.m * p + self.t).collect())
    }

    /// The axis-aligned box around the body, from six supports.
    pub fn bounds(&self) -> (DVec3, DVec3) {
        let lo = DVec3::new(
            self.support(-DVec3::X).x,
            self.support(-DVec3::Y).y,
            self.support(-DVec3::Z).z,
        );
        let hi = DVec3::new(
            self.support(DVec3::X).x,
            self.support(DVec3::Y).y,
            self.support(DVec3::Z).z,
        );
        (lo, hi)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn supports_of_primitives() {
        let b = Convex::new(Body::Box(DVec3::new(1.0, 2.0, 3.0)));
        assert_eq!(
            b.support(DVec3::new(1.0, -1.0, 0.5)),
            DVec3::new(1.0, -2.0, 3.0)
        );
        let c = Convex::new(Body::Cylinder { r: 2.0, half: 1.0 });
        let s = c.support(DVec3::new(3.0, 4.0, -1.0));
        assert!((s - DVec3::new(1.2, 1.6, -1.0)).length() < 1e-12);
        let ball = Convex::ball(DVec3::new(1.0, 0.0, 0.0), 2.0);
        assert!((ball.support(DVec3::Y) - DVec3::new(1.0, 2.0, 0.0)).length() < 1e-12);
        let e = Convex::new(Body::Ellipsoid(DVec3::new(1.0, 2.0, 3.0)));
        assert!((e.support(DVec3::Z) - DVec3::new(0.0, 0.0, 3.0)).length() < 1e-12);
        let cone = Convex::new(Body::Cone { r: 1.0, h: 5.0 });
        assert_eq!(cone.support(DVec3::Z), DVec3::new(0.0, 0.0, 5.0));
        assert!((cone.support(DVec3::X) - DVec3::X).length() < 1e-12);
    }

    #[test]
    fn placing_a_body_places_its_support() {
        // A box long in x, turned a quarter about z: long in y.
        let quarter = DMat3::from_cols(DVec3::Y, -DVec3::X, DVec3::Z);
        let b = Convex::new(Body::Box(DVec3::new(3.0, 1.0, 1.0)))
            .turned(quarter)
            .moved(DVec3::new(10.0, 0.0, 0.0));
        let (lo, hi) = b.bounds();
        assert_eq!(lo, DVec3::new(9.0, -3.0, -1.0));
        assert_eq!(hi, DVec3::new(11.0, 3.0, 1.0));
        let h = Convex::hull(vec![b, Convex::ball(DVec3::ZERO, 1.0)]);
        assert_eq!(h.bounds().0.x, -1.0);
        assert!(
            Convex::ball(DVec3::ZERO, 1.0)
                .scaled(DVec3::new(1.0, 2.0, 1.0))
                .is_none()
        );
    }
}
