//! `hull([shapes])`: the convex hull of any shapes, as OpenSCAD's `hull()`.
//!
//! Parts known to be convex bodies (spheres, boxes, cylinders, cones, capsules,
//! ellipsoids, and these moved, turned, mirrored, scaled, grown or hulled again) enter by
//! their support mapping ([`convex`]), so their hull is exact. Any other field is sampled:
//! its surface is found on a grid of [`SAMPLES`] cells along its longest side (sign
//! changes refined by bisection) and the hull of the farthest of those surface points in
//! 642 directions stands for it, so such a part's hull is within one grid cell plus
//! 0.3% of the part's size of the true one.
//!
//! The ball all parts are grown by (the radius of equal spheres) is taken out first: the
//! hull is its core grown by that ball, and distances to it are the core's minus the
//! radius ([`Convex::core`]). The field of the hull, per point:
//! - outside the core, the exact distance, by GJK ([`gjk`]);
//! - when the core is a polytope (hulls of points, boxes, equal spheres, capsules), inside
//!   it the largest distance to its facets: exact everywhere;
//! - otherwise, inside the core, the largest signed distance to a set of supporting
//!   planes of the hull, one per facet of the polytope spanned by the hull's support
//!   points in 162 directions. Each such plane bounds the hull, so the value is negative
//!   exactly inside and never above the true (negative) distance; it equals it near flat
//!   faces and is within the sagitta of those directions (about 0.4% of a curved part's
//!   radius) elsewhere.
//!
//! Enclosure over a box with centre c and half-diagonal R: an exact distance is
//! 1-Lipschitz, `v(c) ± R`. Otherwise the plane part is 1-Lipschitz
//! and below the distance everywhere, so every value is at least `planes(c) − R`; every
//! value is at most the true distance, which is at most `d(c) + R`, where d(c) is the GJK
//! distance outside, and inside minus the depth of c in the polytope spanned by support
//! points (that polytope lies in the hull, so its depth is a lower bound of the hull's).

pub mod convex;
pub mod gjk;
pub mod polytope;
mod sample;

use std::sync::Arc;

use glam::DVec3;
use isoforge_field::{CustomField, Interval, Shape};

pub use convex::{Body, Convex};
use polytope::{Facet, hull_facets, hull_triangles, sphere_directions};
pub use sample::{SAMPLES, sampled_part};

/// Why a hull could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum HullError {
    /// No shapes were given.
    #[error("the hull of nothing: give at least one shape")]
    Empty,
    /// A part is not bounded (a half-space, a gyroid), so it has no hull.
    #[error("shape {index} of the hull is not bounded: {why}")]
    Unbounded {
        /// Its 1-based position in the list.
        index: usize,
        /// What the region search said.
        why: String,
    },
    /// A part has nothing inside.
    #[error("shape {index} of the hull has nothing inside it")]
    NothingInside {
        /// Its 1-based position in the list.
        index: usize,
    },
}

/// Directions whose support points span the inner polytope: level 2 of the icosphere,
/// 162 directions, about 320 facets. Level 3 (642, about 1280 facets) made the inside
/// value four times as slow to evaluate for a sagitta 4x smaller; 0.4% of a rounded
/// part's radius is below what a printer resolves.
const DIRECTION_LEVEL: u32 = 2;

/// The hull's field: GJK outside, supporting planes inside.
pub struct HullField {
    /// The hull without the ball all its parts are grown by (see [`Convex::core`]); a
    /// point set when the core is a polytope.
    core: Convex,
    /// That ball's radius.
    grown: f64,
    /// The core is a polytope and the planes are its facets (moved out by `grown`): then
    /// the field is the exact signed distance everywhere.
    exact: bool,
    /// Supporting planes (normal, support value), struct-of-arrays for a fast max.
    nx: Vec<f64>,
    ny: Vec<f64>,
    nz: Vec<f64>,
    h: Vec<f64>,
    /// Facets of the polytope spanned by support points (inside the hull).
    inner: Option<Vec<Facet>>,
    /// In exact mode, the core polytope's facets as triangles (plane offset, corners):
    /// outside it the nearest point is on a facet the point lies beyond.
    triangles: Vec<(f64, [DVec3; 3])>,
    /// GJK's accuracy, and the margin added to enclosures for it.
    tolerance: f64,
}

impl HullField {
    /// The field of a convex body's surface.
    pub fn new(body: Convex) -> HullField {
        let (lo, hi) = body.bounds();
        let scale = (hi - lo).length().max(1e-9);
        let (core, grown) = body.core();
        if let Some(points) = core.polytope_points() {
            // A polytope grown by a ball: its facets give the exact distance inside and
            // out (outside, the nearest point lies on a facet the point is beyond).
            if let Some(tris) = hull_triangles(&points) {
                let planes: Vec<(DVec3, f64)> = tris
                    .iter()
                    .map(|(f, _)| (f.normal, f.offset + grown))
                    .collect();
                let mut field = HullField::with_planes(core, grown, true, &planes, None, scale);
                field.triangles = tris.iter().map(|(f, c)| (f.offset, *c)).collect();
                return field;
            }
            // A flat core (a point, a segment, a triangle): GJK on its few corners.
            let corners = Convex::new(Body::Points(points.into()));
            return HullField::with_planes(corners, grown, true, &[], None, scale);
        }
        let dirs = sphere_directions(DIRECTION_LEVEL);
        let points: Vec<DVec3> = dirs.iter().map(|&n| body.support(n)).collect();
        let inner = hull_facets(&points);
        let normals: Vec<DVec3> = match &inner {
            Some(f) => f.iter().map(|f| f.normal).collect(),
            None => dirs,
        };
        let planes: Vec<(DVec3, f64)> = normals
            .iter()
            .map(|&n| (n, body.support(n).dot(n)))
            .collect();
        HullField::with_planes(core, grown, false, &planes, inner, scale)
    }

    fn with_planes(
        core: Convex,
        grown: f64,
        exact: bool,
        planes: &[(DVec3, f64)],
        inner: Option<Vec<Facet>>,
        scale: f64,
    ) -> HullField {
        HullField {
            core,
            grown,
            exact,
            nx: planes.iter().map(|(n, _)| n.x).collect(),
            ny: planes.iter().map(|(n, _)| n.y).collect(),
            nz: planes.iter().map(|(n, _)| n.z).collect(),
            h: planes.iter().map(|(_, h)| *h).collect(),
            inner,
            triangles: Vec::new(),
            tolerance: 1e-9 * scale,
        }
    }

    /// The largest signed distance to a supporting plane, and that plane's index
    /// (`-inf` when there are none: a flat core, whose inside has no volume).
    fn planes(&self, p: DVec3) -> (f64, usize) {
        let mut best = (f64::NEG_INFINITY, 0);
        for i in 0..self.h.len() {
            let d = self.nx[i] * p.x + self.ny[i] * p.y + self.nz[i] * p.z - self.h[i];
            if d > best.0 {
                best = (d, i);
            }
        }
        best
    }

    /// The depth of `p` in the inner polytope (0 outside it or without one).
    fn inner_depth(&self, p: DVec3) -> f64 {
        match &self.inner {
            Some(facets) => facets
                .iter()
                .map(|f| f.offset - f.normal.dot(p))
                .fold(f64::INFINITY, f64::min)
                .max(0.0),
            None => 0.0,
        }
    }

    /// GJK on the core: `Some((signed distance, unit direction from the hull to p,
    /// direction from p to the core's nearest point))` outside the core, `None` inside
    /// it. Outside the core but within `grown` of it the point is inside the hull, at
    /// exactly that (negative) distance.
    fn outside_core(&self, p: DVec3, hint: DVec3) -> Option<(f64, DVec3, DVec3)> {
        let c = gjk::closest(&self.core, p, hint, self.tolerance);
        if c.inside {
            return None;
        }
        let d = c.point - p;
        Some((c.distance - self.grown, -d / c.distance, d))
    }

    /// The exact value and gradient for a polytope core with triangles.
    fn at_polytope(&self, p: DVec3) -> (f64, DVec3) {
        let (v, i) = self.planes(p);
        if v + self.grown <= 0.0 {
            return (v, DVec3::new(self.nx[i], self.ny[i], self.nz[i]));
        }
        let mut best = (f64::INFINITY, DVec3::Z);
        for (k, (offset, [a, b, c])) in self.triangles.iter().enumerate() {
            let beyond = self.nx[k] * p.x + self.ny[k] * p.y + self.nz[k] * p.z - offset;
            if beyond <= 0.0 || beyond >= best.0 {
                continue; // not beyond this facet, or farther than the best already
            }
            let q = gjk::closest_on_triangle(p, *a, *b, *c);
            let d = (p - q).length();
            if d < best.0 {
                // Nearest a point inside the facet (the distance is the plane's), the
                // gradient is the facet's normal; as `(p − q) / d` it is rounding error
                // where `p` is on the surface, as a crossing interpolated on a plane is
                // (the same fault as `import_stl`'s, mesh_field.rs).
                let on_facet = d - beyond <= self.tolerance;
                best = (
                    d,
                    if on_facet || d == 0.0 {
                        DVec3::new(self.nx[k], self.ny[k], self.nz[k])
                    } else {
                        (p - q) / d
                    },
                );
            }
        }
        (best.0 - self.grown, best.1)
    }

    /// The value and gradient at `p`; `hint` carries GJK's start between neighbours.
    fn at(&self, p: DVec3, hint: &mut DVec3) -> (f64, DVec3) {
        if !self.triangles.is_empty() {
            return self.at_polytope(p);
        }
        match self.outside_core(p, *hint) {
            // Outside the hull the GJK distance is exact; inside it (within the grown
            // ball of the core) exact too.
            Some((v, normal, towards)) if v > 0.0 || self.grown > 0.0 => {
                *hint = towards;
                (v, normal)
            }
            _ => {
                if self.h.is_empty() {
                    // On a flat core (a segment, a triangle): as deep as the ball.
                    return (-self.grown, DVec3::Z);
                }
                let (v, i) = self.planes(p);
                (v, DVec3::new(self.nx[i], self.ny[i], self.nz[i]))
            }
        }
    }
}

impl CustomField for HullField {
    fn name(&self) -> &str {
        "hull"
    }

    fn value(&self, p: [f64; 3]) -> f64 {
        self.at(DVec3::from(p), &mut DVec3::default()).0
    }

    fn values(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        // Neighbouring points have neighbouring nearest points: start each GJK there.
        let mut hint = DVec3::ZERO;
        for (i, o) in out.iter_mut().enumerate() {
            *o = self.at(DVec3::new(xs[i], ys[i], zs[i]), &mut hint).0;
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
        // Rounded up so the ball around c covers the box.
        let r = (hi - lo).length() * 0.5 * (1.0 + 1e-12);
        let margin = 2.0 * self.tolerance + 1e-12 * c.length();
        if self.exact {
            // The exact signed distance is 1-Lipschitz.
            let v = self.at(c, &mut DVec3::default()).0;
            return Interval::try_from((v - r - margin, v + r + margin))
                .unwrap_or(Interval::ENTIRE);
        }
        let lower = self.planes(c).0 - r - margin;
        // Outside the core GJK's distance is exact; inside it, the inner polytope's depth
        // is at most the hull's.
        let upper = match self.outside_core(c, DVec3::ZERO) {
            Some((distance, _, _)) => distance + r + margin,
            None => -self.inner_depth(c) + r + margin,
        };
        Interval::try_from((lower, upper)).unwrap_or(Interval::ENTIRE)
    }

    fn gradient(&self, p: [f64; 3]) -> [f64; 4] {
        let (v, n) = self.at(DVec3::from(p), &mut DVec3::default());
        [v, n.x, n.y, n.z]
    }

    fn interval_gradient(&self, _: [Interval; 3]) -> [Interval; 3] {
        // Every gradient is a unit vector.
        [Interval::try_from((-1.0, 1.0)).unwrap_or(Interval::ENTIRE); 3]
    }
}

/// One part of a hull.
pub enum HullPart {
    /// A convex body known exactly.
    Convex(Convex),
    /// Any other field: sampled (see [`sampled_part`]).
    Field(Shape),
}

/// The convex hull of the parts, as a field and as a convex body (for hulls of hulls).
pub fn hull(parts: Vec<HullPart>) -> Result<(Shape, Convex), HullError> {
    if parts.is_empty() {
        return Err(HullError::Empty);
    }
    let mut bodies = Vec::with_capacity(parts.len());
    for (i, part) in parts.into_iter().enumerate() {
        bodies.push(match part {
            HullPart::Convex(c) => c,
            HullPart::Field(s) => sampled_part(&s, i + 1)?,
        });
    }
    let body = if bodies.len() == 1 {
        bodies.pop().unwrap_or_else(|| Convex::new(Body::Point))
    } else {
        Convex::hull(bodies)
    };
    let field = HullField::new(body.clone());
    Ok((Shape::custom(Arc::new(field)), body))
}

#[cfg(test)]
mod tests;
