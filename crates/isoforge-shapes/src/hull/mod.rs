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
mod planes;
pub mod polytope;
mod sample;

use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

use glam::DVec3;
use isoforge_field::{CustomField, Interval, Shape};

pub use convex::{Body, Convex};
use planes::PlaneSet;
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

/// Where a point's value was found, as a start for its neighbour's: GJK's direction to the
/// core, or the nearest facet of a polytope.
#[derive(Default)]
struct Hint {
    towards: DVec3,
    facet: usize,
}

/// The nearest facet of a polytope found so far.
struct Nearest {
    distance: f64,
    facet: usize,
    gradient: DVec3,
}

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
    /// Supporting planes (normal, support value), grouped by direction for a fast max.
    planes: PlaneSet,
    /// Facets of the polytope spanned by support points (inside the hull).
    inner: Option<Vec<Facet>>,
    /// In exact mode, the core polytope's facets as triangles (plane offset, corners), in
    /// the order of `planes`: outside it the nearest point is on a facet the point lies
    /// beyond.
    triangles: Vec<(f64, [DVec3; 3])>,
    /// The facet nearest the last single point (see `shared_hint`).
    last_facet: AtomicUsize,
    /// A disc around each triangle in its plane (centre, radius).
    triangle_discs: Vec<(DVec3, f64)>,
    /// A ball around each plane group's triangles (centre, radius): a group whose ball
    /// is farther than the nearest facet found so far is passed over.
    group_balls: Vec<(DVec3, f64)>,
    /// GJK's accuracy, and the margin added to enclosures for it.
    tolerance: f64,
}

impl HullField {
    /// The field of a convex body's surface.
    pub fn new(body: Convex) -> HullField {
        let body = &body;
        let (core, grown) = body.core();
        if let Some(points) = core.polytope_points() {
            // A polytope grown by a ball: its facets give the exact distance inside and
            // out (outside, the nearest point lies on a facet the point is beyond).
            if let Some(tris) = hull_triangles(&points) {
                let planes: Vec<(DVec3, f64)> = tris
                    .iter()
                    .map(|(f, _)| (f.normal, f.offset + grown))
                    .collect();
                let triangles = tris.iter().map(|(f, c)| (f.offset, *c)).collect();
                return HullField::with_planes(core, grown, true, &planes, None, triangles, body);
            }
            // A flat core (a point, a segment, a triangle): GJK on its few corners.
            let corners = Convex::new(Body::Points(points.into()));
            return HullField::with_planes(corners, grown, true, &[], None, Vec::new(), body);
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
        HullField::with_planes(core, grown, false, &planes, inner, Vec::new(), body)
    }

    /// `triangles`, when given, are the planes' facets in the same order.
    fn with_planes(
        core: Convex,
        grown: f64,
        exact: bool,
        planes: &[(DVec3, f64)],
        inner: Option<Vec<Facet>>,
        triangles: Vec<(f64, [DVec3; 3])>,
        body: &Convex,
    ) -> HullField {
        let (lo, hi) = body.bounds();
        let (planes, order) = PlaneSet::new(planes, (lo + hi) * 0.5);
        let triangles: Vec<(f64, [DVec3; 3])> = if triangles.is_empty() {
            triangles
        } else {
            order.iter().map(|&i| triangles[i]).collect()
        };
        let group_balls = if triangles.is_empty() {
            Vec::new()
        } else {
            planes
                .groups()
                .map(|(_, members)| {
                    let corners = || members.clone().flat_map(|k| triangles[k].1);
                    let centre = corners().sum::<DVec3>() / (3 * members.len()) as f64;
                    let radius = corners().map(|c| (c - centre).length()).fold(0.0, f64::max);
                    // A little larger, for rounding.
                    (centre, radius * (1.0 + 1e-9) + 1e-12)
                })
                .collect()
        };
        let triangle_discs = triangles
            .iter()
            .map(|(_, corners)| {
                let centre = (corners[0] + corners[1] + corners[2]) / 3.0;
                let radius = corners
                    .iter()
                    .map(|&c| (c - centre).length())
                    .fold(0.0, f64::max);
                (centre, radius * (1.0 + 1e-9) + 1e-12)
            })
            .collect();
        HullField {
            last_facet: AtomicUsize::new(0),
            triangle_discs,
            group_balls,
            core,
            grown,
            exact,
            planes,
            inner,
            triangles,
            tolerance: 1e-9 * (hi - lo).length().max(1e-9),
        }
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

    /// The exact value and gradient for a polytope core with triangles. `facet` carries
    /// the facet nearest the last point between neighbours.
    fn at_polytope(&self, p: DVec3, facet: &mut usize) -> (f64, DVec3) {
        let mut first = *facet;
        if self.planes.value(first, p) + self.grown <= 0.0 {
            // Not beyond the last point's facet: inside, or beyond another.
            let (v, i) = self.planes.max(p);
            if v + self.grown <= 0.0 {
                *facet = i;
                return (v, self.planes.normal(i));
            }
            // The facet the point is farthest beyond: near the surface its triangle
            // mostly holds the nearest point.
            first = i;
        }
        // Outside. The first facet's distance lets every group whose triangles are all
        // farther, or whose planes the point is not beyond, be passed over.
        let mut best = Nearest {
            distance: f64::INFINITY,
            facet: usize::MAX,
            gradient: DVec3::Z,
        };
        self.nearer_on_facet(first, p, &mut best);
        let seen = self.planes.seen_from_origin(p);
        for (g, range) in self.planes.groups() {
            let (centre, radius) = self.group_balls[g];
            if (p - centre).length() - radius > best.distance
                || !self.planes.may_exceed(g, &seen, -self.grown)
            {
                continue;
            }
            for k in range {
                if k != first {
                    self.nearer_on_facet(k, p, &mut best);
                }
            }
        }
        *facet = best.facet.min(self.triangles.len() - 1);
        (best.distance - self.grown, best.gradient)
    }

    /// Facet `k`'s nearest point to `p`, kept in `best` when nearer (or as near, with a
    /// lower index: the answer does not depend on the order facets are read in, which
    /// the hint changes).
    fn nearer_on_facet(&self, k: usize, p: DVec3, best: &mut Nearest) {
        let (offset, [a, b, c]) = &self.triangles[k];
        let beyond = self.planes.normal(k).dot(p) - offset;
        if beyond <= 0.0 || beyond > best.distance {
            return; // not beyond this facet, or farther than the best already
        }
        // Nor nearer than the plane's distance and, across the plane, the way from p's
        // foot to the disc around the triangle (many facets of a curved part lie nearly
        // in one plane, and the plane's distance alone passes them all).
        let (centre, radius) = self.triangle_discs[k];
        let across = ((p - centre).length_squared() - beyond * beyond)
            .max(0.0)
            .sqrt();
        let outside_disc = (across - radius).max(0.0);
        if beyond * beyond + outside_disc * outside_disc > best.distance * best.distance {
            return;
        }
        let q = gjk::closest_on_triangle(p, *a, *b, *c);
        let d = (p - q).length();
        if d > best.distance || d == best.distance && k > best.facet {
            return;
        }
        // Nearest a point inside the facet (the distance is the plane's), the gradient is
        // the facet's normal; as `(p − q) / d` it is rounding error where `p` is on the
        // surface, as a crossing interpolated on a plane is (the same fault as
        // `import_stl`'s, mesh_field.rs).
        let on_facet = d - beyond <= self.tolerance;
        *best = Nearest {
            distance: d,
            facet: k,
            gradient: if on_facet || d == 0.0 {
                self.planes.normal(k)
            } else {
                (p - q) / d
            },
        };
    }

    /// Single points come one by one (the collapses, the refiner), mostly near the last
    /// one: the last facet found is their hint. A polytope's answer does not depend on
    /// it, so threads may share it; GJK's start is not shared (its answer varies within
    /// its accuracy with the start).
    fn shared_hint(&self) -> Hint {
        Hint {
            towards: DVec3::ZERO,
            facet: self.last_facet.load(Ordering::Relaxed),
        }
    }

    fn at_shared(&self, p: DVec3) -> (f64, DVec3) {
        let mut hint = self.shared_hint();
        let answer = self.at(p, &mut hint);
        self.last_facet.store(hint.facet, Ordering::Relaxed);
        answer
    }

    /// The value and gradient at `p`; `hint` carries where the last point's answer was
    /// found, for its neighbour.
    fn at(&self, p: DVec3, hint: &mut Hint) -> (f64, DVec3) {
        if !self.triangles.is_empty() {
            return self.at_polytope(p, &mut hint.facet);
        }
        match self.outside_core(p, hint.towards) {
            // Outside the hull the GJK distance is exact; inside it (within the grown
            // ball of the core) exact too.
            Some((v, normal, towards)) if v > 0.0 || self.grown > 0.0 => {
                hint.towards = towards;
                (v, normal)
            }
            _ => {
                if self.planes.is_empty() {
                    // On a flat core (a segment, a triangle): as deep as the ball.
                    return (-self.grown, DVec3::Z);
                }
                let (v, i) = self.planes.max(p);
                (v, self.planes.normal(i))
            }
        }
    }
}

impl CustomField for HullField {
    fn name(&self) -> &str {
        "hull"
    }

    fn value(&self, p: [f64; 3]) -> f64 {
        self.at_shared(DVec3::from(p)).0
    }

    fn values(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        // Neighbouring points have neighbouring nearest points: start each GJK there.
        let mut hint = self.shared_hint();
        for (i, o) in out.iter_mut().enumerate() {
            *o = self.at(DVec3::new(xs[i], ys[i], zs[i]), &mut hint).0;
        }
        self.last_facet.store(hint.facet, Ordering::Relaxed);
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
            let v = self.at(c, &mut Hint::default()).0;
            return Interval::try_from((v - r - margin, v + r + margin))
                .unwrap_or(Interval::ENTIRE);
        }
        let lower = self.planes.max(c).0 - r - margin;
        // Outside the core GJK's distance is exact; inside it, the inner polytope's depth
        // is at most the hull's.
        let upper = match self.outside_core(c, DVec3::ZERO) {
            Some((distance, _, _)) => distance + r + margin,
            None => -self.inner_depth(c) + r + margin,
        };
        Interval::try_from((lower, upper)).unwrap_or(Interval::ENTIRE)
    }

    fn gradient(&self, p: [f64; 3]) -> [f64; 4] {
        let (v, n) = self.at_shared(DVec3::from(p));
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
