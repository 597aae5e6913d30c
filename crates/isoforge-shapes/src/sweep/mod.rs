//! Sweeps: solids made by moving a 2D profile through space (BOSL2's `skin.scad`).
//!
//! Where the motion has a closed-form inverse the sweep is exact by substitution: a point
//! is moved back to the profile's plane and the profile's field is read there.
//! [`linear_sweep`] (twist, scale, shift), [`revolve`] and [`spiral_sweep`] are such
//! expressions, so the kernel's interval arithmetic prunes them like any formula. A sweep
//! along an arbitrary 3D path ([`path::path_sweep`]) and a loft between different profiles
//! ([`skin::skin`]) are custom nodes that search for the cross-section a point lies in.

pub mod frames;
pub mod matching;
pub mod path;
pub mod skin;

use std::f64::consts::TAU;

use glam::DVec2;
use isoforge_field::Shape;

use crate::profile::{Profile, ProfileError};

pub use path::{PathMethod, PathSweep, path_sweep};
pub use skin::{Sampling, SkinMethod, SkinOptions, skin};

/// Why a sweep could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SweepError {
    /// The profile was not usable.
    #[error(transparent)]
    Profile(#[from] ProfileError),
    /// A number that must be positive was not.
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
    /// A number out of its allowed range.
    #[error("{what} must be {range}, not {value}")]
    OutOfRange {
        /// What it was.
        what: &'static str,
        /// The range, in words.
        range: &'static str,
        /// The value given.
        value: f64,
    },
    /// A revolved profile reaches across the axis.
    #[error(
        "revolve reads the profile's points as [r, z] with r >= 0, but the profile reaches r = {min_x}; move it to the right of the axis"
    )]
    CrossesAxis {
        /// The smallest x of the profile.
        min_x: f64,
    },
    /// Something about a path.
    #[error("{0}")]
    Path(String),
    /// Something about a skin.
    #[error("{0}")]
    Skin(String),
}

fn finite(what: &'static str, value: f64) -> Result<f64, SweepError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(SweepError::NotFinite { what, value })
    }
}

fn positive(what: &'static str, value: f64) -> Result<f64, SweepError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(SweepError::NotPositive { what, value })
    }
}

/// The options of [`linear_sweep`] (BOSL2's names and defaults).
#[derive(Clone, Debug, PartialEq)]
pub struct LinearSweep {
    /// Height, mm.
    pub height: f64,
    /// Degrees the top is turned against the bottom; positive turns clockwise seen from
    /// above, as OpenSCAD's `linear_extrude` and BOSL2's `linear_sweep` do.
    pub twist: f64,
    /// The top's size against the bottom's, per axis (1 keeps it).
    pub scale: [f64; 2],
    /// How far the top is moved against the bottom, mm.
    pub shift: [f64; 2],
    /// Centre the sweep on z = 0 instead of standing it on z = 0.
    pub center: bool,
}

impl LinearSweep {
    /// A straight sweep of the given height, standing on z = 0.
    pub fn new(height: f64) -> Self {
        LinearSweep {
            height,
            twist: 0.0,
            scale: [1.0, 1.0],
            shift: [0.0, 0.0],
            center: false,
        }
    }

    /// The bottom's z.
    pub fn bottom(&self) -> f64 {
        if self.center { -0.5 * self.height } else { 0.0 }
    }

    /// `shape` (this sweep of a profile reaching `reach` from its origin, or something
    /// within `reach` of such a sweep) cut by a cylinder about z that holds it: the same
    /// surface, and a region the interval search can find. A twist turns x and y by an
    /// angle that depends on z, and a scale divides by a factor that does, so over a box
    /// reaching far in z their intervals say nothing, and `linear_sweep(square(10), 20,
    /// #{twist: 90})` had no region unless the script gave one; the distance from the axis
    /// does not depend on the turn at all.
    pub fn bounded(&self, shape: Shape, reach: f64) -> Shape {
        if self.twist == 0.0 && self.scale == [1.0, 1.0] && self.shift == [0.0, 0.0] {
            return shape;
        }
        let grow = self.scale.iter().fold(1.0f64, |m, k| m.max(k.abs()));
        let radius = DVec2::from(self.shift).length() + grow * reach;
        // A millimetre and a thousandth beyond: the cylinder never touches the surface.
        shape.max(&(radial() - (radius * 1.001 + 1.0)))
    }

    fn check(&self) -> Result<(), SweepError> {
        positive("the height", self.height)?;
        finite("the twist", self.twist)?;
        for k in self.scale {
            finite("the scale", k)?;
            if k < 0.0 {
                return Err(SweepError::OutOfRange {
                    what: "the scale",
                    range: "0 or more",
                    value: k,
                });
            }
        }
        finite("the shift", self.shift[0])?;
        finite("the shift", self.shift[1])?;
        Ok(())
    }
}

/// The substitution of a linear sweep: where each point of space is in the profile's
/// plane, and the factor that keeps the profile's field a distance.
pub struct LinearCoords {
    /// Profile x at each point.
    pub u: Shape,
    /// Profile y at each point.
    pub v: Shape,
    /// The profile's scale at each height (the smaller axis), which multiplies its field.
    pub k: Shape,
    /// The height fraction, 0 at the bottom and 1 at the top.
    pub t: Shape,
    /// The slab between bottom and top: negative between them.
    pub slab: Shape,
}

/// The coordinates [`linear_sweep`] reads its profile at.
pub fn linear_coords(opts: &LinearSweep) -> Result<LinearCoords, SweepError> {
    opts.check()?;
    let (x, y, z) = (Shape::x(), Shape::y(), Shape::z());
    let z0 = opts.bottom();
    let t = (&z - z0) / opts.height;
    // Back to the bottom's frame: undo the shift, then the clockwise turn (a
    // counter-clockwise turn of the point), then the scale.
    let px = &x - &t * opts.shift[0];
    let py = &y - &t * opts.shift[1];
    let (px, py) = if opts.twist != 0.0 {
        let angle = &t * opts.twist.to_radians();
        let (c, s) = (angle.cos(), angle.sin());
        (&px * &c - &py * &s, &px * &s + &py * &c)
    } else {
        (px, py)
    };
    // The scale's t is held to the sweep's own heights: beyond them the slab decides,
    // and a factor that passes through 0 there made every interval of the sweep say
    // nothing (no region could be found).
    let held = t.max(&Shape::constant(0.0)).min(&Shape::constant(1.0));
    let kx = 1.0 + &held * (opts.scale[0] - 1.0);
    let ky = 1.0 + &held * (opts.scale[1] - 1.0);
    let k = if opts.scale[0] == opts.scale[1] {
        kx.clone()
    } else {
        kx.min(&ky)
    };
    let (u, v) = if opts.scale == [1.0, 1.0] {
        (px, py)
    } else {
        (px / &kx, py / &ky)
    };
    let slab = (z0 - &z).max(&(&z - (z0 + opts.height)));
    Ok(LinearCoords { u, v, k, t, slab })
}

/// `linear_sweep(profile, h, #{twist, scale, shift, center})`: the profile extruded along
/// z. Twist, scale and shift are exact: a twisted square is a twisted square.
pub fn linear_sweep(profile: &Profile, opts: &LinearSweep) -> Result<Shape, SweepError> {
    let c = linear_coords(opts)?;
    let side = if opts.scale == [1.0, 1.0] {
        profile.at(&c.u, &c.v)
    } else {
        profile.at(&c.u, &c.v) * &c.k
    };
    Ok(opts.bounded(side.max(&c.slab), profile.reach()))
}

/// The wedge of angles `0..angle` (degrees) about z, as a field: the intersection of two
/// half-spaces up to 180 degrees, their union beyond.
pub fn wedge(angle: f64) -> Shape {
    let (x, y) = (Shape::x(), Shape::y());
    let a = angle.to_radians();
    // Inside the start ray's side: y >= 0. Before the end ray: cross(e, p) <= 0.
    let start = -&y;
    let end = &y * a.cos() - &x * a.sin();
    if angle <= 180.0 {
        start.max(&end)
    } else {
        start.min(&end)
    }
}

/// The coordinates of [`revolve`]: the distance from the axis, and z.
pub fn radial() -> Shape {
    (Shape::x().square() + Shape::y().square()).sqrt()
}

/// Checks that a profile to be revolved stays on the +x side of the axis.
pub(crate) fn check_revolvable(profile: &Profile) -> Result<(), SweepError> {
    let min_x = match profile.outline() {
        Some(o) => o
            .rings()
            .iter()
            .flatten()
            .map(|p| p.x)
            .fold(f64::INFINITY, f64::min),
        None => profile.bounds().min.x,
    };
    // A hair below zero is a point on the axis written with rounding.
    if min_x < -1e-9 * (1.0 + profile.reach()) {
        return Err(SweepError::CrossesAxis { min_x });
    }
    Ok(())
}

/// Checks a revolve angle: more than 0, at most 360 degrees.
pub fn check_angle(angle: f64) -> Result<f64, SweepError> {
    if angle.is_finite() && angle > 0.0 && angle <= 360.0 {
        Ok(angle)
    } else {
        Err(SweepError::OutOfRange {
            what: "the angle",
            range: "more than 0 and at most 360 degrees",
            value: angle,
        })
    }
}

/// `revolve(profile, #{angle})` (BOSL2's `rotate_sweep`): the profile, read as `[r, z]`,
/// turned about z from the +x axis counter-clockwise through `angle` degrees; a partial
/// turn is capped by the two flat ends.
pub fn revolve(profile: &Profile, angle: f64) -> Result<Shape, SweepError> {
    let angle = check_angle(angle)?;
    check_revolvable(profile)?;
    let body = profile.at(&radial(), &Shape::z());
    Ok(if angle >= 360.0 {
        body
    } else {
        body.max(&wedge(angle))
    })
}

/// The options of [`spiral_sweep`].
#[derive(Clone, Debug, PartialEq)]
pub struct SpiralSweep {
    /// The height of the helix the profile's origin follows (centred on z = 0).
    pub height: f64,
    /// Its radius.
    pub radius: f64,
    /// Turns; positive is right-handed, negative left-handed.
    pub turns: f64,
    /// BOSL2's taper (lead-in): the length, mm along the helix, over which each end
    /// shrinks to a sliver. Positive adds it beyond the turns, negative takes it from them.
    pub taper: f64,
    /// Shrink the tapered ends towards the outside (internal threads) instead of inward.
    pub internal: bool,
}

/// BOSL2's smallest scale at a tapered end (its "sqrt" lead-in shape).
const TAPER_END: f64 = 0.05;

/// `spiral_sweep(profile, h, r, turns, #{taper})`: a thread. The profile's x is radial
/// and its y along the axis; its origin follows the helix of radius `r` from angle 0 on
/// +x, rising `h` over `turns` turns, centred on z = 0 as BOSL2 centres it.
///
/// Exact by substitution: for a point at angle φ and height z, the turns whose profile
/// could hold it are found with `floor`, and the profile is read in each.
pub fn spiral_sweep(profile: &Profile, opts: &SpiralSweep) -> Result<Shape, SweepError> {
    let h = positive("the height", opts.height)?;
    let r = positive("the radius", opts.radius)?;
    let turns = finite("the number of turns", opts.turns)?;
    if turns == 0.0 {
        return Err(SweepError::OutOfRange {
            what: "the number of turns",
            range: "a number other than 0",
            value: turns,
        });
    }
    let taper = finite("the taper", opts.taper)?;
    let dir = turns.signum();
    let total = TAU * turns.abs();
    let pitch = h / turns.abs();
    let taper_angle = taper.abs() / r;
    let extra = if taper > 0.0 { taper_angle } else { 0.0 };
    let (theta_a, theta_b) = (-extra, total + extra);
    if taper_angle > 0.0 && 2.0 * taper_angle > theta_b - theta_a {
        return Err(SweepError::OutOfRange {
            what: "the taper",
            range: "short enough that both tapered ends fit in the sweep",
            value: taper,
        });
    }
    let b = profile.bounds();
    let (ymin, ymax) = (b.min.y, b.max.y);
    let candidates = ((ymax - ymin) / pitch).ceil().max(0.0) as usize;
    if candidates > 64 {
        return Err(SweepError::OutOfRange {
            what: "the profile's height",
            range: "at most 64 pitches",
            value: ymax - ymin,
        });
    }
    let (x, y, z) = (Shape::x(), Shape::y(), Shape::z());
    let rho = (x.square() + y.square()).sqrt();
    let phi = (&y * dir).atan2(&x);
    // Height of the helix at angle φ: −h/2 + p·φ/2π; w is z measured from it.
    let w = &z + 0.5 * h - &phi * (pitch / TAU);
    let k0 = ((&w - ymin) / pitch).floor();
    let radial_offset = &rho - r;
    let mut best: Option<Shape> = None;
    for j in 0..=candidates {
        let k = &k0 - j as f64;
        let local_y = &w - &k * pitch;
        let theta = &phi + &k * TAU;
        let beyond = (theta_a - &theta).max(&(&theta - theta_b));
        let cap = &rho * &beyond;
        let body = if taper_angle > 0.0 {
            let from_end = (&theta - theta_a).min(&(theta_b - &theta)) / taper_angle;
            let x = from_end
                .max(&Shape::constant(0.0))
                .min(&Shape::constant(1.0));
            let e2 = TAPER_END * TAPER_END;
            let s = (&x * (1.0 - e2) + e2).sqrt();
            let sy = &s * 0.75 + 0.25;
            let cx = if opts.internal { b.max.x } else { b.min.x };
            let cy = 0.5 * (b.min.y + b.max.y);
            let u = (&radial_offset - cx) / &s + cx;
            let v = (&local_y - cy) / &sy + cy;
            profile.at(&u, &v) * &s
        } else {
            profile.at(&radial_offset, &local_y)
        };
        let piece = body.max(&cap);
        best = Some(match best {
            None => piece,
            Some(b) => b.min(&piece),
        });
    }
    // `candidates + 1 >= 1`, so there is at least one piece.
    let helix = best.unwrap_or_else(|| Shape::constant(f64::INFINITY));
    // A can around it, a millimetre and a thousandth beyond (see `LinearSweep::bounded`:
    // the angle's intervals say nothing far away, so without it a thread had no region).
    // The profile's x is radial: ρ is within r + its x range; z is within the helix's
    // height, the profile's y range and the tapers' extra turn.
    let radius = r + b.max.x.abs().max(b.min.x.abs());
    let half = 0.5 * h + ymax.abs().max(ymin.abs()) + extra * pitch / TAU;
    let can = (&rho - (radius * 1.001 + 1.0)).max(&(z.abs() - (half * 1.001 + 1.0)));
    Ok(helix.max(&can))
}

#[cfg(test)]
mod tests;
