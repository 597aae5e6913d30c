//! Textures: height patterns laid over the side of a sweep as a displacement of its field
//! (BOSL2's `texture=` on `linear_sweep`, `rotate_sweep` and `cyl`).
//!
//! A texture is a height `T(u, v)` between 0 and 1, repeating with period 1 in both u and
//! v. A textured sweep reads it at surface coordinates (u around or along the profile,
//! v up the sweep, both in tiles) and moves its surface outward by `depth · T − inset`.
//! Nothing is triangulated: the pattern costs no triangles until the mesher meets it, and
//! the result meshes closed like any field.
//!
//! The named textures are formulas in u and v (so the kernel's interval arithmetic prunes
//! them); a height array or a grayscale image is a custom node that interpolates between
//! its samples ([`heightfield::HeightField`]).

pub mod heightfield;
pub mod textured;

use std::f64::consts::TAU;
use std::sync::Arc;

use isoforge_field::Shape;

pub use heightfield::HeightField;
pub use textured::{
    TextureOptions, Tile, textured_cylinder, textured_linear_sweep, textured_revolution,
};

/// Why a texture could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TextureError {
    /// The name is not a known texture.
    #[error("unknown texture \"{name}\"; the named textures are: {}", NAMES.join(", "))]
    UnknownName {
        /// The name given.
        name: String,
    },
    /// A height array that is empty, ragged, or holds values outside 0..1.
    #[error("{0}")]
    BadHeights(String),
}

/// The named textures, BOSL2's names.
pub const NAMES: [&str; 11] = [
    "ribs",
    "trunc_ribs",
    "wave_ribs",
    "diamonds",
    "pyramids",
    "trunc_pyramids",
    "dimpled_pyramids",
    "hills",
    "waves",
    "dots",
    "cones",
];

/// A texture: a height between 0 and 1 over the unit tile, repeating.
#[derive(Clone)]
pub enum Texture {
    /// One of [`NAMES`].
    Named(&'static str),
    /// Samples interpolated bilinearly.
    Heights(Arc<HeightField>),
}

impl std::fmt::Debug for Texture {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Texture::Named(n) => write!(f, "Texture({n})"),
            Texture::Heights(h) => write!(f, "Texture({}x{} heights)", h.cols(), h.rows()),
        }
    }
}

/// The named texture `name`.
pub fn named(name: &str) -> Result<Texture, TextureError> {
    NAMES
        .iter()
        .find(|n| **n == name)
        .map(|n| Texture::Named(n))
        .ok_or_else(|| TextureError::UnknownName {
            name: name.to_string(),
        })
}

/// A texture from rows of heights in 0..1, the first row at the top of a tile (so an
/// image reads upright on an upright sweep), columns left to right.
pub fn heights(rows: Vec<Vec<f64>>) -> Result<Texture, TextureError> {
    Ok(Texture::Heights(Arc::new(HeightField::new(rows)?)))
}

/// The fractional part, in [0, 1).
fn frac(a: &Shape) -> Shape {
    a - a.floor()
}

/// The triangle wave: 0 at whole numbers, 1 halfway between.
fn tri(a: &Shape) -> Shape {
    1.0 - (1.0 - frac(a) * 2.0).abs()
}

fn clamp01(a: &Shape) -> Shape {
    a.max(&Shape::constant(0.0)).min(&Shape::constant(1.0))
}

impl Texture {
    /// The height at tile coordinates (u, v) (any real numbers: the texture repeats).
    pub fn at(&self, u: &Shape, v: &Shape) -> Shape {
        let name = match self {
            Texture::Heights(h) => return h.at(u, v),
            Texture::Named(n) => *n,
        };
        let (fu, fv) = (frac(u), frac(v));
        // Distance from the tile's centre, as `|2f − 1|` per axis (0 there, 1 at edges).
        let (cu, cv) = ((&fu * 2.0 - 1.0).abs(), (&fv * 2.0 - 1.0).abs());
        let pyramid = 1.0 - cu.max(&cv);
        let round = || ((&fu - 0.5).square() + (&fv - 0.5).square()).sqrt();
        match name {
            // Vertical ridges: high at the tile's edges, a V down to 0 in its middle.
            "ribs" => cu,
            // Ridges with flat tops and bottoms: 0 for the first quarter, a ramp up to 1,
            // flat for a quarter, a ramp down.
            "trunc_ribs" => clamp01(&((0.375 - (&fu - 0.625).abs()) / 0.25)),
            "wave_ribs" => ((u * TAU).cos() + 1.0) * 0.5,
            // Diamonds: peaks at the middles of the tile's edges, valleys at its corners
            // and centre, so the tiles join into a diagonal lattice.
            "diamonds" => tri(&(u + v)).min(&tri(&(u - v))),
            "pyramids" => pyramid,
            "trunc_pyramids" => (1.0 - cu.max(&cv).max(&Shape::constant(1.0 / 3.0))) * 1.5,
            // Pyramids with a pyramid-shaped dent in the top: highest on a ring two thirds
            // up, half height at the centre.
            "dimpled_pyramids" => pyramid.min(&(4.0 / 3.0 - &pyramid)) * 1.5,
            "hills" => ((u * TAU).cos() * (v * TAU).cos() + 1.0) * 0.5,
            // Ribs that meander: crests along v swinging a quarter tile each way.
            "waves" => (((u - (v * TAU).sin() * 0.25) * TAU).cos() + 1.0) * 0.5,
            // A spherical dome on a flat tile, as BOSL2's "dots": a cap of a sphere of
            // radius 0.45·√2 cut at 45 degrees, 0.9 tiles across, scaled to height 1.
            "dots" => {
                let r = 0.45 * std::f64::consts::SQRT_2;
                let rise = 1.0 / (r - 0.45);
                let dome =
                    ((r * r - round().square()).max(&Shape::constant(0.0)).sqrt() - 0.45) * rise;
                dome.max(&Shape::constant(0.0))
            }
            // A cone whose base fills the tile's inscribed circle.
            "cones" => (1.0 - round() * 2.0).max(&Shape::constant(0.0)),
            _ => Shape::constant(0.0),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::at;

    fn sample(t: &Texture, u: f64, v: f64) -> f64 {
        at(&t.at(&Shape::x(), &Shape::y()), [u, v, 0.0])
    }

    #[test]
    fn every_named_texture_stays_in_0_1_and_repeats() {
        for name in NAMES {
            let t = named(name).unwrap();
            let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
            for i in 0..=40 {
                for j in 0..=40 {
                    let (u, v) = (i as f64 / 40.0, j as f64 / 40.0);
                    let h = sample(&t, u, v);
                    assert!(
                        (-1e-12..=1.0 + 1e-12).contains(&h),
                        "{name} at ({u}, {v}): {h}"
                    );
                    let again = sample(&t, u + 3.0, v - 2.0);
                    assert!((h - again).abs() < 1e-9, "{name} does not repeat");
                    lo = lo.min(h);
                    hi = hi.max(h);
                }
            }
            assert!(lo < 0.05 && hi > 0.95, "{name} spans {lo}..{hi}");
        }
        assert!(named("knurl").is_err());
    }

    #[test]
    fn shapes_of_some_textures() {
        let p = named("pyramids").unwrap();
        assert!((sample(&p, 0.5, 0.5) - 1.0).abs() < 1e-12);
        assert!(sample(&p, 0.0, 0.3).abs() < 1e-12);
        let r = named("ribs").unwrap();
        assert!((sample(&r, 0.0, 0.7) - 1.0).abs() < 1e-12);
        assert!(sample(&r, 0.5, 0.1).abs() < 1e-12);
        let d = named("diamonds").unwrap();
        assert!((sample(&d, 0.5, 0.0) - 1.0).abs() < 1e-12);
        assert!(sample(&d, 0.5, 0.5).abs() < 1e-12);
        let dots = named("dots").unwrap();
        assert!((sample(&dots, 0.5, 0.5) - 1.0).abs() < 1e-9);
        assert!(sample(&dots, 0.02, 0.02).abs() < 1e-12);
    }
}
