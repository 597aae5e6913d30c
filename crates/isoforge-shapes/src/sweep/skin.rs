//! `skin`: a loft through profiles at given heights, as one custom field node.
//!
//! Consecutive profiles are first made to correspond point for point ([`super::matching`],
//! BOSL2's methods). Between heights z_i and z_i+1 the cross-section at fraction u is the
//! ring whose points are the matched points blended by u, and the field at (x, y, z) is
//! the exact 2D signed distance to that ring, cut by the first and last heights. The side
//! walls are the ruled surfaces BOSL2 approximates with `slices`: here they are exact, so
//! `slices` changes nothing.
//!
//! Interval bounds: the ring at height z moves at most `v = max |b_k − a_k| / Δz` per mm
//! of height, so the field changes by at most 1 per mm across and `v` per mm up; over a
//! box that is `f(centre) ± (r_xy + v·r_z)`, rigorous and tight.

use std::sync::Arc;

use glam::{DVec2, DVec3};
use isoforge_field::{CustomField, Interval, Shape};

use super::SweepError;
use super::matching::{self, TangentFailure};
use crate::bound::{around, finite_box};
use crate::bvh::{Box3, Bvh};
use crate::profile::Profile;

pub use super::matching::Sampling;

/// How consecutive profiles are matched (BOSL2's `method`).
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum SkinMethod {
    /// Point i to point i, after resampling to equal counts (BOSL2's default).
    Direct,
    /// As `Direct`, with the second ring turned to the shortest connecting edges.
    Reindex,
    /// Vertices duplicated so the connecting edges are shortest overall.
    Distance,
    /// As `Distance`, keeping point 0 on point 0.
    FastDistance,
    /// A polygon's edges meet a convex curve where it runs parallel to them.
    Tangent,
}

/// The options of [`skin`].
#[derive(Clone, Debug, PartialEq)]
pub struct SkinOptions {
    /// The matching method.
    pub method: SkinMethod,
    /// How `Direct` and `Reindex` add points (BOSL2's default: by length).
    pub sampling: Sampling,
    /// Points added per edge before matching (BOSL2's `refine`), at least 1.
    pub refine: usize,
}

impl Default for SkinOptions {
    fn default() -> Self {
        SkinOptions {
            method: SkinMethod::Direct,
            sampling: Sampling::Length,
            refine: 1,
        }
    }
}

fn fail(msg: impl Into<String>) -> SweepError {
    SweepError::Skin(msg.into())
}

/// One pair of matched rings between two heights.
#[derive(Clone, Debug)]
struct Band {
    z0: f64,
    z1: f64,
    a: Vec<DVec2>,
    b: Vec<DVec2>,
    /// How fast the section moves sideways per mm of height.
    speed: f64,
    /// Hierarchy over the ruled quads (edge k of `a` to edge k of `b`).
    bvh: Bvh,
}

/// The skin's field.
pub struct LoftField {
    bands: Vec<Band>,
}

/// The largest count of matched points per band: the field's cost per point grows with it
/// only logarithmically, but matching and memory do not.
const MAX_BAND_POINTS: usize = 200_000;

/// `skin(profiles, z_list, #{method, sampling, refine})`: a loft through the profiles'
/// outer rings at the given heights (strictly increasing).
pub fn skin(
    profiles: &[Profile],
    heights: &[f64],
    opts: &SkinOptions,
) -> Result<Shape, SweepError> {
    if profiles.len() < 2 {
        return Err(fail(format!(
            "skin needs at least 2 profiles, it has {}",
            profiles.len()
        )));
    }
    if heights.len() != profiles.len() {
        return Err(fail(format!(
            "skin has {} profiles but {} heights; give one height per profile",
            profiles.len(),
            heights.len()
        )));
    }
    for (i, w) in heights.windows(2).enumerate() {
        if !w[0].is_finite() || !w[1].is_finite() || w[1] <= w[0] {
            return Err(fail(format!(
                "the heights must be finite and increasing, but height {} is {} and height {} is {}",
                i,
                w[0],
                i + 1,
                w[1]
            )));
        }
    }
    if opts.refine == 0 || opts.refine > 1000 {
        return Err(SweepError::OutOfRange {
            what: "refine",
            range: "a whole number from 1 to 1000",
            value: opts.refine as f64,
        });
    }
    let mut rings = Vec::with_capacity(profiles.len());
    for (i, p) in profiles.iter().enumerate() {
        let outline = p.require_outline("skin")?;
        if outline.rings().len() > 1 {
            return Err(fail(format!(
                "profile {i} has holes; skin joins single rings (skin the holes separately and subtract them)"
            )));
        }
        rings.push(outline.outer().to_vec());
    }
    let mut bands = Vec::with_capacity(rings.len() - 1);
    for i in 0..rings.len() - 1 {
        let (a, b) = match_pair(&rings[i], &rings[i + 1], opts)
            .map_err(|TangentFailure| {
                fail(format!(
                    "method \"tangent\" could not match profiles {i} and {}: the one with more points must be a convex curve with enough points",
                    i + 1
                ))
            })?;
        if a.len() > MAX_BAND_POINTS {
            return Err(fail(format!(
                "profiles {i} and {} match into {} points; at most {MAX_BAND_POINTS}",
                i + 1,
                a.len()
            )));
        }
        bands.push(Band::new(heights[i], heights[i + 1], a, b));
    }
    Ok(Shape::custom(Arc::new(LoftField { bands })))
}

fn match_pair(
    a: &[DVec2],
    b: &[DVec2],
    opts: &SkinOptions,
) -> Result<(Vec<DVec2>, Vec<DVec2>), TangentFailure> {
    match opts.method {
        SkinMethod::Direct | SkinMethod::Reindex => {
            let n = a.len().max(b.len()) * opts.refine;
            let ra = matching::resample(a, n, opts.sampling);
            let rb = matching::resample(b, n, opts.sampling);
            let rb = if opts.method == SkinMethod::Reindex {
                matching::reindex(&ra, &rb)
            } else {
                rb
            };
            Ok((ra, rb))
        }
        SkinMethod::Distance | SkinMethod::FastDistance => {
            let (ra, rb) = (
                matching::refine(a, opts.refine),
                matching::refine(b, opts.refine),
            );
            Ok(matching::distance_match(
                &ra,
                &rb,
                opts.method == SkinMethod::Distance,
            ))
        }
        SkinMethod::Tangent => {
            let (ra, rb) = (
                matching::refine(a, opts.refine),
                matching::refine(b, opts.refine),
            );
            matching::tangent_match(&ra, &rb)
        }
    }
}

impl Band {
    fn new(z0: f64, z1: f64, a: Vec<DVec2>, b: Vec<DVec2>) -> Band {
        let n = a.len();
        let speed = a
            .iter()
            .zip(&b)
            .map(|(p, q)| p.distance(*q))
            .fold(0.0, f64::max)
            / (z1 - z0);
        let boxes = (0..n)
            .map(|k| {
                let j = (k + 1) % n;
                Box3::around([
                    a[k].extend(z0),
                    a[j].extend(z0),
                    b[k].extend(z1),
                    b[j].extend(z1),
                ])
            })
            .collect();
        Band {
            z0,
            z1,
            a,
            b,
            speed,
            bvh: Bvh::new(boxes),
        }
    }

    fn point(&self, k: usize, u: f64) -> DVec2 {
        self.a[k].lerp(self.b[k], u)
    }

    /// The signed distance, in the plane at height z, to this band's section there.
    fn section_distance(&self, p: DVec3) -> f64 {
        let u = ((p.z - self.z0) / (self.z1 - self.z0)).clamp(0.0, 1.0);
        let n = self.a.len();
        let q = p.truncate();
        // Search with p lifted onto the band's height range, so box distances bound the
        // in-plane distances from below.
        let lifted = DVec3::new(q.x, q.y, p.z.clamp(self.z0, self.z1));
        let d = self.bvh.min_search(lifted, &mut |k| {
            let (s0, s1) = (self.point(k, u), self.point((k + 1) % n, u));
            segment_distance(q, s0, s1)
        });
        let mut odd = false;
        self.bvh.visit(
            &mut |b| {
                b.min.y <= q.y
                    && q.y <= b.max.y
                    && b.max.x >= q.x
                    && b.min.z <= lifted.z
                    && lifted.z <= b.max.z
            },
            &mut |k| {
                let (s0, s1) = (self.point(k, u), self.point((k + 1) % n, u));
                if (s0.y > q.y) != (s1.y > q.y) {
                    let x = s0.x + (q.y - s0.y) * (s1.x - s0.x) / (s1.y - s0.y);
                    if x > q.x {
                        odd = !odd;
                    }
                }
            },
        );
        if odd { -d } else { d }
    }
}

fn segment_distance(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let d = b - a;
    let len2 = d.length_squared();
    let t = if len2 > 0.0 {
        ((p - a).dot(d) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (a + d * t).distance(p)
}

impl LoftField {
    fn band_at(&self, z: f64) -> &Band {
        let i = self.bands.partition_point(|b| b.z1 < z);
        &self.bands[i.min(self.bands.len() - 1)]
    }

    fn evaluate(&self, p: DVec3) -> f64 {
        let band = self.band_at(p.z);
        let first = self.bands[0].z0;
        let last = self.bands[self.bands.len() - 1].z1;
        let cap = (first - p.z).max(p.z - last);
        band.section_distance(p).max(cap)
    }
}

impl CustomField for LoftField {
    fn name(&self) -> &str {
        "skin"
    }

    fn value(&self, p: [f64; 3]) -> f64 {
        self.evaluate(DVec3::from(p))
    }

    fn interval(&self, b: [Interval; 3]) -> Interval {
        let Some((c, h)) = finite_box(b) else {
            return Interval::ENTIRE;
        };
        let (zlo, zhi) = (c.z - h.z, c.z + h.z);
        let speed = self
            .bands
            .iter()
            .filter(|band| band.z1 >= zlo && band.z0 <= zhi)
            .map(|band| band.speed)
            .fold(0.0, f64::max);
        let radius = DVec2::new(h.x, h.y).length() + speed.max(1.0) * h.z;
        around(self.evaluate(c), 1.0, radius)
    }

    fn gradient(&self, p: [f64; 3]) -> [f64; 4] {
        let p = DVec3::from(p);
        let v = self.evaluate(p);
        let scale = 1.0 + p.abs().max_element();
        let h = 1e-7 * scale;
        let d = |e: DVec3| (self.evaluate(p + e * h) - self.evaluate(p - e * h)) / (2.0 * h);
        [v, d(DVec3::X), d(DVec3::Y), d(DVec3::Z)]
    }
}
