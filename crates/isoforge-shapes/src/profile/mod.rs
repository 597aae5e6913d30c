//! 2D profiles: the cross-sections that sweeps, skins and textured sweeps are made from.
//!
//! A [`Profile`] is an exact 2D signed distance field in the plane (x, y) — the sweeps put
//! their own coordinates in place of x and y by substitution — together with its outline
//! (the boundary as rings of points, which `skin` matches vertex by vertex and textures
//! are laid out along) and a box that holds it.
//!
//! `circle(r)` and `rect([w, h], rounding)` are closed-form expressions; `polygon(rings)` is
//! one custom node over a hierarchy of its edges ([`polygon::PolygonField`]), so a profile
//! of ten thousand points meshes as fast as a square.

pub mod edges;
pub mod polygon;

use std::sync::Arc;

use glam::{DMat2, DVec2};
use isoforge_field::Shape;

use edges::{Box2, EdgeTree};
use polygon::{OutlineParam, PolygonField};

/// Points on the outline of a round profile when no count is given: the outline is only
/// used where points are needed (skin, texture layout); at 256 a skinned circle's area is
/// within 0.01 % of the true circle's.
pub const ROUND_SEGMENTS: usize = 256;

/// Points per quarter circle on the outline of a rounded rectangle's corner.
const CORNER_SEGMENTS: usize = 32;

/// The most points a profile's outline may have: enough for any traced logo, few enough
/// that a skin's matching (cubic in the count) stays under a second.
pub const MAX_POINTS: usize = 100_000;

/// Why a profile could not be made or used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ProfileError {
    /// A size that must be a positive finite number was not.
    #[error("{what} must be a positive number, not {value}")]
    NotPositive {
        /// What it was.
        what: &'static str,
        /// The value given.
        value: f64,
    },
    /// A number that must be finite was not.
    #[error("{what} must be a finite number, not {value}")]
    NotFinite {
        /// What it was.
        what: &'static str,
        /// The value given.
        value: f64,
    },
    /// A ring of a polygon had fewer than three distinct points.
    #[error("ring {ring} of the polygon has {points} distinct points; a ring needs at least 3")]
    TooFewPoints {
        /// The ring (0 is the outer one).
        ring: usize,
        /// Its distinct points.
        points: usize,
    },
    /// A ring has (nearly) no area.
    #[error("ring {ring} of the polygon has no area (its points lie on a line)")]
    NoArea {
        /// The ring.
        ring: usize,
    },
    /// Too many points.
    #[error("the profile has {points} points; at most {MAX_POINTS} are allowed")]
    TooManyPoints {
        /// How many there were.
        points: usize,
    },
    /// The rounding does not fit the rectangle.
    #[error("the rounding {rounding} is more than half the rectangle's shorter side ({half})")]
    RoundingTooLarge {
        /// The rounding asked for.
        rounding: f64,
        /// Half the shorter side.
        half: f64,
    },
    /// An operation needs the profile's points, which this one no longer has.
    #[error(
        "{operation} needs a profile with an outline (circle, rect, polygon, or one of those moved, turned or scaled); an offset profile has none"
    )]
    NoOutline {
        /// The operation.
        operation: &'static str,
    },
}

/// How the outline relates to the field.
#[derive(Clone, Debug, PartialEq)]
enum Kind {
    /// A circle: the outline is sampled, the field exact.
    Circle { centre: DVec2, radius: f64 },
    /// The outline is the field's boundary exactly.
    Polygon,
}

/// The boundary of a profile as closed rings: the first counter-clockwise (the outer
/// boundary), any others clockwise (holes).
#[derive(Clone, Debug)]
pub struct Outline {
    rings: Vec<Vec<DVec2>>,
    kind: Kind,
}

impl Outline {
    /// The rings.
    pub fn rings(&self) -> &[Vec<DVec2>] {
        &self.rings
    }
    /// The outer ring.
    pub fn outer(&self) -> &[DVec2] {
        &self.rings[0]
    }
    /// The enclosed area (holes subtracted).
    pub fn area(&self) -> f64 {
        self.rings.iter().map(|r| signed_area(r)).sum()
    }
    /// The length of the outer ring (a circle's exact circumference, not its sampled
    /// outline's).
    pub fn perimeter(&self) -> f64 {
        match self.kind {
            Kind::Circle { radius, .. } => std::f64::consts::TAU * radius,
            Kind::Polygon => ring_length(self.outer()),
        }
    }
    /// The centre and radius when the profile is an exact circle.
    pub fn circle(&self) -> Option<(DVec2, f64)> {
        match self.kind {
            Kind::Circle { centre, radius } => Some((centre, radius)),
            Kind::Polygon => None,
        }
    }
    fn map(&self, f: impl Fn(DVec2) -> DVec2, flips: bool) -> Outline {
        let rings = self
            .rings
            .iter()
            .map(|r| {
                let mut r: Vec<DVec2> = r.iter().map(|&p| f(p)).collect();
                if flips {
                    r.reverse();
                }
                r
            })
            .collect();
        Outline {
            rings,
            kind: Kind::Polygon,
        }
    }
}

/// A 2D profile: a field in the plane (x, y), negative inside, its outline and its box.
#[derive(Clone, Debug)]
pub struct Profile {
    shape: Shape,
    outline: Option<Outline>,
    bounds: Box2,
    lipschitz: f64,
}

impl Profile {
    /// The field, in x and y (z is ignored).
    pub fn shape(&self) -> &Shape {
        &self.shape
    }
    /// The outline, if the profile still has one.
    pub fn outline(&self) -> Option<&Outline> {
        self.outline.as_ref()
    }
    /// The outline, or an error naming the operation that needed it.
    pub fn require_outline(&self, operation: &'static str) -> Result<&Outline, ProfileError> {
        self.outline
            .as_ref()
            .ok_or(ProfileError::NoOutline { operation })
    }
    /// A box that holds the whole profile.
    pub fn bounds(&self) -> Box2 {
        self.bounds
    }
    /// How fast the field can change per millimetre in the plane (1 for an exact distance).
    pub fn lipschitz(&self) -> f64 {
        self.lipschitz
    }
    /// The farthest the profile reaches from the origin.
    pub fn reach(&self) -> f64 {
        self.bounds
            .corners()
            .iter()
            .map(|c| c.length())
            .fold(0.0, f64::max)
    }

    /// The field with (x, y) replaced by `u` and `v`.
    pub fn at(&self, u: &Shape, v: &Shape) -> Shape {
        self.shape.remap(u, v, &Shape::z())
    }

    /// The arc length of the nearest outline point along its ring, at (u, v): the first
    /// coordinate textures are laid out by. A circle uses its angle (exact); any other
    /// outline a custom node over its edges.
    pub fn outline_param(&self, u: &Shape, v: &Shape) -> Result<Shape, ProfileError> {
        let outline = self.require_outline("a texture")?;
        if let Some((c, r)) = outline.circle() {
            let (du, dv) = (u - c.x, v - c.y);
            // atan2 is in (-pi, pi]; shifted to [0, 2 pi) so the seam is at angle 0, where
            // the sampled outline starts too.
            let angle = dv.atan2(&du);
            let turn = angle.modulo(&Shape::constant(std::f64::consts::TAU));
            return Ok(turn * r);
        }
        let tree = Arc::new(EdgeTree::new(&outline.rings));
        let field = Shape::custom(Arc::new(OutlineParam::new(tree)));
        Ok(field.remap(u, v, &Shape::z()))
    }

    /// The profile moved by `v`.
    pub fn translate(&self, v: [f64; 2]) -> Result<Profile, ProfileError> {
        finite("the offset", v[0])?;
        finite("the offset", v[1])?;
        let d = DVec2::from(v);
        let shape = self.at(&(Shape::x() - d.x), &(Shape::y() - d.y));
        let outline = self.outline.as_ref().map(|o| {
            let mut m = o.map(|p| p + d, false);
            if let Kind::Circle { centre, radius } = o.kind {
                m.kind = Kind::Circle {
                    centre: centre + d,
                    radius,
                };
            }
            m
        });
        Ok(Profile {
            shape,
            outline,
            bounds: Box2 {
                min: self.bounds.min + d,
                max: self.bounds.max + d,
            },
            lipschitz: self.lipschitz,
        })
    }

    /// The profile turned counter-clockwise by `degrees` about the origin.
    pub fn rotate(&self, degrees: f64) -> Result<Profile, ProfileError> {
        finite("the angle", degrees)?;
        let m = DMat2::from_angle(degrees.to_radians());
        let inv = m.transpose();
        let (x, y) = (Shape::x(), Shape::y());
        let u = &x * inv.x_axis.x + &y * inv.y_axis.x;
        let v = &x * inv.x_axis.y + &y * inv.y_axis.y;
        let shape = self.at(&u, &v);
        let outline = self.outline.as_ref().map(|o| {
            let mut out = o.map(|p| m * p, false);
            if let Kind::Circle { centre, radius } = o.kind {
                out.kind = Kind::Circle {
                    centre: m * centre,
                    radius,
                };
            }
            out
        });
        let bounds = self
            .bounds
            .corners()
            .iter()
            .fold(Box2::EMPTY, |b, &c| b.union(Box2::of(m * c, m * c)));
        Ok(Profile {
            shape,
            outline,
            bounds,
            lipschitz: self.lipschitz,
        })
    }

    /// The profile scaled by `[kx, ky]` about the origin (negative factors mirror).
    pub fn scale(&self, k: [f64; 2]) -> Result<Profile, ProfileError> {
        for &c in &k {
            finite("the scale", c)?;
            if c == 0.0 {
                return Err(ProfileError::NotPositive {
                    what: "the size of a scale factor",
                    value: c,
                });
            }
        }
        let (kx, ky) = (k[0], k[1]);
        let small = kx.abs().min(ky.abs());
        let big = kx.abs().max(ky.abs());
        // f(x/kx, y/ky)·min|k| stays a distance for a uniform scale, and a field whose
        // slope is at most max/min for an uneven one.
        let shape = self.at(&(Shape::x() / kx), &(Shape::y() / ky)) * small;
        let flips = (kx < 0.0) != (ky < 0.0);
        let outline = self.outline.as_ref().map(|o| {
            let mut out = o.map(|p| p * DVec2::new(kx, ky), flips);
            if let (Kind::Circle { centre, radius }, true) = (&o.kind, kx.abs() == ky.abs()) {
                out.kind = Kind::Circle {
                    centre: *centre * DVec2::new(kx, ky),
                    radius: radius * kx.abs(),
                };
            }
            out
        });
        let bounds = self.bounds.corners().iter().fold(Box2::EMPTY, |b, &c| {
            let q = c * DVec2::new(kx, ky);
            b.union(Box2::of(q, q))
        });
        Ok(Profile {
            shape,
            outline,
            bounds,
            lipschitz: self.lipschitz * big / small,
        })
    }

    /// The profile grown by `d` (shrunk for negative `d`): exact for a distance field.
    /// The outline is kept for a circle and dropped otherwise.
    pub fn offset(&self, d: f64) -> Result<Profile, ProfileError> {
        finite("the offset distance", d)?;
        if let Some((c, r)) = self.outline.as_ref().and_then(|o| o.circle()) {
            let grown = circle(r + d)?;
            return grown.translate(c.to_array());
        }
        let pad = DVec2::splat(d.max(0.0));
        Ok(Profile {
            shape: &self.shape - d,
            outline: None,
            bounds: Box2 {
                min: self.bounds.min - pad,
                max: self.bounds.max + pad,
            },
            lipschitz: self.lipschitz,
        })
    }
}

fn finite(what: &'static str, value: f64) -> Result<f64, ProfileError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(ProfileError::NotFinite { what, value })
    }
}

fn positive(what: &'static str, value: f64) -> Result<f64, ProfileError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(ProfileError::NotPositive { what, value })
    }
}

/// Twice the signed area of a ring, halved: positive when counter-clockwise.
pub fn signed_area(ring: &[DVec2]) -> f64 {
    let n = ring.len();
    (0..n)
        .map(|i| ring[i].perp_dot(ring[(i + 1) % n]))
        .sum::<f64>()
        * 0.5
}

/// The length of a closed ring.
pub fn ring_length(ring: &[DVec2]) -> f64 {
    let n = ring.len();
    (0..n).map(|i| ring[i].distance(ring[(i + 1) % n])).sum()
}

/// `circle(r)`: the disc of radius `r` about the origin, exact (`sqrt(x² + y²) − r`).
pub fn circle(r: f64) -> Result<Profile, ProfileError> {
    let r = positive("the radius", r)?;
    let (x, y) = (Shape::x(), Shape::y());
    let shape = (x.square() + y.square()).sqrt() - r;
    let ring = regular_ring(r, ROUND_SEGMENTS);
    Ok(Profile {
        shape,
        outline: Some(Outline {
            rings: vec![ring],
            kind: Kind::Circle {
                centre: DVec2::ZERO,
                radius: r,
            },
        }),
        bounds: Box2 {
            min: DVec2::splat(-r),
            max: DVec2::splat(r),
        },
        lipschitz: 1.0,
    })
}

/// `circle(r, #{segments: n})`: the regular n-gon inscribed in the circle of radius `r`,
/// its first vertex on +x (as OpenSCAD's `circle(r, $fn = n)`).
pub fn regular_polygon(r: f64, n: usize) -> Result<Profile, ProfileError> {
    let r = positive("the radius", r)?;
    if n < 3 {
        return Err(ProfileError::TooFewPoints { ring: 0, points: n });
    }
    polygon(&[regular_ring(r, n).iter().map(|p| p.to_array()).collect()])
}

fn regular_ring(r: f64, n: usize) -> Vec<DVec2> {
    (0..n)
        .map(|i| {
            let a = i as f64 * std::f64::consts::TAU / n as f64;
            DVec2::new(r * a.cos(), r * a.sin())
        })
        .collect()
}

/// `rect([w, h])`, centred on the origin, with corners rounded by `rounding` (0 for sharp).
pub fn rect(size: [f64; 2], rounding: f64) -> Result<Profile, ProfileError> {
    let w = positive("the width", size[0])?;
    let h = positive("the height", size[1])?;
    let half = 0.5 * w.min(h);
    let rounding = finite("the rounding", rounding)?;
    if rounding < 0.0 {
        return Err(ProfileError::NotPositive {
            what: "the rounding",
            value: rounding,
        });
    }
    if rounding > half * (1.0 + 1e-12) {
        return Err(ProfileError::RoundingTooLarge { rounding, half });
    }
    let rounding = rounding.min(half);
    let (x, y) = (Shape::x(), Shape::y());
    // The rounded box's distance: q = |p| − (b − r); |max(q, 0)| + min(max(qx, qy), 0) − r.
    let qx = x.abs() - (0.5 * w - rounding);
    let qy = y.abs() - (0.5 * h - rounding);
    let zero = Shape::constant(0.0);
    let outside = (qx.max(&zero).square() + qy.max(&zero).square()).sqrt();
    let shape = outside + qx.max(&qy).min(&zero) - rounding;
    let mut ring = Vec::new();
    let corners = [
        (DVec2::new(1.0, -1.0), -90.0),
        (DVec2::new(1.0, 1.0), 0.0),
        (DVec2::new(-1.0, 1.0), 90.0),
        (DVec2::new(-1.0, -1.0), 180.0),
    ];
    for (sign, start) in corners {
        let c = sign * DVec2::new(0.5 * w - rounding, 0.5 * h - rounding);
        if rounding > 0.0 {
            for k in 0..=CORNER_SEGMENTS {
                let a = (start + 90.0 * k as f64 / CORNER_SEGMENTS as f64).to_radians();
                ring.push(c + rounding * DVec2::new(a.cos(), a.sin()));
            }
        } else {
            ring.push(c);
        }
    }
    dedupe(&mut ring);
    Ok(Profile {
        shape,
        outline: Some(Outline {
            rings: vec![ring],
            kind: Kind::Polygon,
        }),
        bounds: Box2 {
            min: DVec2::new(-0.5 * w, -0.5 * h),
            max: DVec2::new(0.5 * w, 0.5 * h),
        },
        lipschitz: 1.0,
    })
}

/// Drops repeated consecutive points (and a last point equal to the first).
fn dedupe(ring: &mut Vec<DVec2>) {
    ring.dedup_by(|a, b| a.distance_squared(*b) <= 1e-24 * (1.0 + b.length_squared()));
    while ring.len() > 1 {
        let (first, last) = (ring[0], ring[ring.len() - 1]);
        if first.distance_squared(last) <= 1e-24 * (1.0 + first.length_squared()) {
            ring.pop();
        } else {
            break;
        }
    }
}

/// `polygon([outer, hole, ..])`: rings of `[x, y]` points, the first the outer boundary,
/// the others holes; in any orientation (they are reoriented: outer counter-clockwise,
/// holes clockwise). Inside is decided by the even-odd rule.
pub fn polygon(rings: &[Vec<[f64; 2]>]) -> Result<Profile, ProfileError> {
    let total: usize = rings.iter().map(Vec::len).sum();
    if total > MAX_POINTS {
        return Err(ProfileError::TooManyPoints { points: total });
    }
    if rings.is_empty() {
        return Err(ProfileError::TooFewPoints { ring: 0, points: 0 });
    }
    let mut out = Vec::with_capacity(rings.len());
    let mut bounds = Box2::EMPTY;
    for (i, ring) in rings.iter().enumerate() {
        let mut pts = Vec::with_capacity(ring.len());
        for p in ring {
            finite("a polygon coordinate", p[0])?;
            finite("a polygon coordinate", p[1])?;
            pts.push(DVec2::from(*p));
        }
        dedupe(&mut pts);
        if pts.len() < 3 {
            return Err(ProfileError::TooFewPoints {
                ring: i,
                points: pts.len(),
            });
        }
        let area = signed_area(&pts);
        let extent = pts
            .iter()
            .fold(Box2::EMPTY, |b, &p| b.union(Box2::of(p, p)));
        let size = (extent.max - extent.min).max_element();
        if area.abs() <= 1e-12 * size * size {
            return Err(ProfileError::NoArea { ring: i });
        }
        let want_ccw = i == 0;
        if (area > 0.0) != want_ccw {
            pts.reverse();
        }
        bounds = bounds.union(extent);
        out.push(pts);
    }
    let tree = Arc::new(EdgeTree::new(&out));
    Ok(Profile {
        shape: Shape::custom(Arc::new(PolygonField::new(tree))),
        outline: Some(Outline {
            rings: out,
            kind: Kind::Polygon,
        }),
        bounds,
        lipschitz: 1.0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::at;

    fn f(p: &Profile, x: f64, y: f64) -> f64 {
        at(p.shape(), [x, y, 0.0])
    }

    #[test]
    fn circle_and_rect_are_distances() {
        let c = circle(2.0).unwrap();
        assert!((f(&c, 3.0, 0.0) - 1.0).abs() < 1e-12);
        assert!((f(&c, 0.0, 0.0) + 2.0).abs() < 1e-12);
        let r = rect([4.0, 2.0], 0.0).unwrap();
        assert!((f(&r, 3.0, 0.0) - 1.0).abs() < 1e-12);
        assert!((f(&r, 0.0, 0.0) + 1.0).abs() < 1e-12);
        assert!((f(&r, 3.0, 2.0) - 2f64.sqrt()).abs() < 1e-12);
        let rr = rect([4.0, 2.0], 0.5).unwrap();
        // The corner's arc is centred at (1.5, 0.5) with radius 0.5.
        let d = DVec2::new(2.5, 1.5).distance(DVec2::new(1.5, 0.5)) - 0.5;
        assert!((f(&rr, 2.5, 1.5) - d).abs() < 1e-12);
        let area = rr.outline().unwrap().area();
        let exact = 8.0 - (4.0 - std::f64::consts::PI) * 0.25;
        assert!((area - exact).abs() < 1e-3, "{area} vs {exact}");
        assert!(matches!(
            rect([1.0, 1.0], 0.6),
            Err(ProfileError::RoundingTooLarge { .. })
        ));
    }

    #[test]
    fn polygons_are_reoriented_and_checked() {
        let cw = polygon(&[vec![[0.0, 0.0], [0.0, 1.0], [1.0, 1.0], [1.0, 0.0]]]).unwrap();
        assert!(cw.outline().unwrap().area() > 0.0);
        assert!(f(&cw, 0.5, 0.5) < 0.0);
        assert!(matches!(
            polygon(&[vec![[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]]]),
            Err(ProfileError::NoArea { ring: 0 })
        ));
        assert!(matches!(
            polygon(&[vec![[0.0, 0.0], [1.0, 1.0], [0.0, 0.0]]]),
            Err(ProfileError::TooFewPoints { .. })
        ));
        assert!(polygon(&[vec![[0.0, f64::NAN], [1.0, 0.0], [0.0, 1.0]]]).is_err());
    }

    #[test]
    fn transforms_move_field_and_outline_together() {
        let sq = rect([2.0, 2.0], 0.0).unwrap();
        let moved = sq.translate([5.0, 0.0]).unwrap().rotate(90.0).unwrap();
        // (5, 0) turned a quarter is (0, 5).
        assert!((f(&moved, 0.0, 5.0) + 1.0).abs() < 1e-12);
        for p in moved.outline().unwrap().outer() {
            assert!(f(&moved, p.x, p.y).abs() < 1e-9);
        }
        let wide = sq.scale([3.0, 1.0]).unwrap();
        assert!(f(&wide, 2.9, 0.0) < 0.0 && f(&wide, 0.0, 1.1) > 0.0);
        assert!((wide.outline().unwrap().area() - 12.0).abs() < 1e-9);
        let mirrored = sq.scale([-1.0, 1.0]).unwrap();
        assert!(
            mirrored.outline().unwrap().area() > 0.0,
            "stays counter-clockwise"
        );
        let grown = circle(1.0)
            .unwrap()
            .translate([1.0, 0.0])
            .unwrap()
            .offset(0.5)
            .unwrap();
        assert_eq!(
            grown.outline().unwrap().circle(),
            Some((DVec2::new(1.0, 0.0), 1.5))
        );
    }
}
