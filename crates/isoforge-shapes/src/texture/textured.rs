//! Textured sweeps: `textured_linear_sweep`, `textured_revolution`, `textured_cylinder`.
//!
//! Each is its plain sweep with the side's field lowered by the texture's height:
//! `side − (depth · T(u, v) − inset)`, so the surface moves out by up to `depth` mm where
//! the texture is high. The side's own coordinates give (u, v): for a linear sweep, u runs
//! along the profile's outline (its arc length) and v up the height; for a revolution, u
//! runs around the axis and v along the profile. Tiles are stretched a little so a whole
//! number of them fits each way (BOSL2's rule), so a closed outline has no seam.

use std::f64::consts::TAU;

use isoforge_field::Shape;

use super::Texture;
use crate::profile::{self, Profile};
use crate::sweep::{self, LinearSweep, SweepError};

/// How big the tiles are.
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum Tile {
    /// A target size `[along, up]` in mm, adjusted to fit a whole number of tiles
    /// (BOSL2's `tex_size`, default `[5, 5]`).
    Size([f64; 2]),
    /// Exactly this many tiles `[along, up]` (BOSL2's `tex_reps` / `tex_counts`).
    Counts([u32; 2]),
}

/// The texture options shared by every textured sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct TextureOptions {
    /// Tile size or count.
    pub tile: Tile,
    /// How far the texture stands out at its highest, mm (negative inverts it).
    pub depth: f64,
    /// How far the texture is sunk into the surface, mm (`depth` sinks it entirely).
    pub inset: f64,
    /// Turn the texture a quarter turn (its u axis up the sweep).
    pub rotate: bool,
}

impl Default for TextureOptions {
    fn default() -> Self {
        TextureOptions {
            tile: Tile::Size([5.0, 5.0]),
            depth: 1.0,
            inset: 0.0,
            rotate: false,
        }
    }
}

/// The most tiles along either direction.
const MAX_TILES: f64 = 100_000.0;

impl TextureOptions {
    fn check(&self) -> Result<(), SweepError> {
        if !self.depth.is_finite() {
            return Err(SweepError::NotFinite {
                what: "tex_depth",
                value: self.depth,
            });
        }
        if !self.inset.is_finite() {
            return Err(SweepError::NotFinite {
                what: "tex_inset",
                value: self.inset,
            });
        }
        match self.tile {
            Tile::Size(s) => {
                for v in s {
                    if !(v.is_finite() && v > 0.0) {
                        return Err(SweepError::NotPositive {
                            what: "tex_size",
                            value: v,
                        });
                    }
                }
            }
            Tile::Counts(c) => {
                for v in c {
                    if v == 0 || f64::from(v) > MAX_TILES {
                        return Err(SweepError::OutOfRange {
                            what: "counts",
                            range: "whole numbers from 1 to 100000",
                            value: f64::from(v),
                        });
                    }
                }
            }
        }
        Ok(())
    }

    /// Tiles along the two surface directions of lengths `along` and `up` (mm).
    fn counts(&self, along: f64, up: f64) -> Result<[f64; 2], SweepError> {
        let c = match self.tile {
            Tile::Counts([a, b]) => [f64::from(a), f64::from(b)],
            Tile::Size([w, h]) => {
                // A quarter-turned tile lies with its width up the sweep.
                let (w, h) = if self.rotate { (h, w) } else { (w, h) };
                [(along / w).round().max(1.0), (up / h).round().max(1.0)]
            }
        };
        if c.iter().any(|&n| n > MAX_TILES) {
            return Err(SweepError::OutOfRange {
                what: "the number of texture tiles",
                range: "at most 100000 each way (make tex_size larger)",
                value: c[0].max(c[1]),
            });
        }
        Ok(c)
    }

    /// The displacement at surface coordinates (tiles along, tiles up).
    fn displacement(&self, texture: &Texture, a: &Shape, b: &Shape) -> Shape {
        let height = if self.rotate {
            // A quarter turn: the tile's u runs up, its v against the outline.
            texture.at(b, &(-a))
        } else {
            texture.at(a, b)
        };
        height * self.depth - self.inset
    }
}

/// `textured_linear_sweep(profile, texture, h, #{..})`: a linear sweep whose side carries
/// the texture, u along the profile's outline from its first point, v up.
pub fn textured_linear_sweep(
    profile: &Profile,
    texture: &Texture,
    sweep: &LinearSweep,
    tex: &TextureOptions,
) -> Result<Shape, SweepError> {
    tex.check()?;
    let c = sweep::linear_coords(sweep)?;
    let outline = profile.require_outline("a texture")?;
    let perimeter = outline.perimeter();
    let [na, nb] = tex.counts(perimeter, sweep.height)?;
    let along = profile.outline_param(&c.u, &c.v)? * (na / perimeter);
    let up = &c.t * nb;
    let side = if sweep.scale == [1.0, 1.0] {
        profile.at(&c.u, &c.v)
    } else {
        profile.at(&c.u, &c.v) * &c.k
    };
    let textured = side - tex.displacement(texture, &along, &up);
    // The texture moves the side out by at most its depth and inset, in the scaled frame.
    let grow = sweep.scale.iter().fold(1.0f64, |m, k| m.max(k.abs()));
    let reach = profile.reach() + grow * (tex.depth.abs() + tex.inset.abs());
    Ok(sweep.bounded(textured.max(&c.slab), reach))
}

/// `textured_cylinder(r, h, texture, #{..})`: a textured linear sweep of a circle,
/// centred on z = 0 unless `center: false` is given.
pub fn textured_cylinder(
    r: f64,
    texture: &Texture,
    sweep: &LinearSweep,
    tex: &TextureOptions,
) -> Result<Shape, SweepError> {
    let c = profile::circle(r)?;
    textured_linear_sweep(&c, texture, sweep, tex)
}

/// `textured_revolution(profile, texture, #{angle, ..})`: a revolution whose surface
/// carries the texture, u around the axis (from +x, counter-clockwise), v along the
/// profile's outline. Tiles around are sized at the profile's largest radius.
pub fn textured_revolution(
    profile: &Profile,
    texture: &Texture,
    angle: f64,
    tex: &TextureOptions,
) -> Result<Shape, SweepError> {
    tex.check()?;
    let angle = sweep::check_angle(angle)?;
    sweep::check_revolvable(profile)?;
    let outline = profile.require_outline("a texture")?;
    let perimeter = outline.perimeter();
    let radius = profile.bounds().max.x.max(1e-9);
    let turn = angle.to_radians();
    let [na, nb] = tex.counts(radius * turn, perimeter)?;
    let (x, y, z) = (Shape::x(), Shape::y(), Shape::z());
    let rho = sweep::radial();
    let around = y.atan2(&x).modulo(&Shape::constant(TAU)) * (na / turn);
    let along = profile.outline_param(&rho, &z)? * (nb / perimeter);
    let side = profile.at(&rho, &z) - tex.displacement(texture, &around, &along);
    Ok(if angle >= 360.0 {
        side
    } else {
        side.max(&sweep::wedge(angle))
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::profile::{circle, rect};
    use crate::reference::at;
    use crate::texture::named;

    #[test]
    fn a_ribbed_cylinder_stands_out_by_the_depth() {
        let t = named("ribs").unwrap();
        let opts = TextureOptions {
            tile: Tile::Counts([12, 1]),
            depth: 1.0,
            ..TextureOptions::default()
        };
        let sweep = LinearSweep {
            center: true,
            ..LinearSweep::new(10.0)
        };
        let s = textured_cylinder(5.0, &t, &sweep, &opts).unwrap();
        // Ribs are high at u = 0 (angle 0) and low half a tile on (angle 15 degrees).
        let peak = at(&s, [5.9, 0.0, 0.0]);
        assert!((peak + 0.1).abs() < 1e-9, "{peak}");
        let a = (15.0f64).to_radians();
        assert!((at(&s, [5.1 * a.cos(), 5.1 * a.sin(), 0.0]) - 0.1).abs() < 1e-9);
        // Inset by the full depth: the peaks are on the cylinder, the valleys below it.
        let inset = TextureOptions {
            inset: 1.0,
            ..opts.clone()
        };
        let s = textured_cylinder(5.0, &t, &sweep, &inset).unwrap();
        assert!(at(&s, [5.01, 0.0, 0.0]) > 0.0);
        assert!(at(&s, [4.9 * a.cos(), 4.9 * a.sin(), 0.0]) > 0.0);
        assert!(
            at(&s, [4.1 * a.cos(), 4.1 * a.sin(), 0.0]) > 0.0,
            "in the groove"
        );
        assert!(
            at(&s, [3.9 * a.cos(), 3.9 * a.sin(), 0.0]) < 0.0,
            "below the groove"
        );
    }

    #[test]
    fn tile_counts_fit_the_surface() {
        let o = TextureOptions::default();
        assert_eq!(o.counts(31.4, 10.0).unwrap(), [6.0, 2.0]);
        let turned = TextureOptions {
            tile: Tile::Size([2.0, 10.0]),
            rotate: true,
            ..o
        };
        assert_eq!(turned.counts(20.0, 4.0).unwrap(), [2.0, 2.0]);
        let bad = TextureOptions {
            tile: Tile::Size([0.0, 1.0]),
            ..TextureOptions::default()
        };
        assert!(bad.check().is_err());
    }

    #[test]
    fn textures_on_a_polygon_and_a_revolution() {
        let t = named("pyramids").unwrap();
        let sq = rect([10.0, 10.0], 0.0).unwrap();
        let s = textured_linear_sweep(&sq, &t, &LinearSweep::new(10.0), &TextureOptions::default())
            .unwrap();
        // Tiles of 5 mm: the first runs from the square's first corner (5, -5) up its
        // right side; its peak is 2.5 mm along and 2.5 mm up, 1 mm out.
        assert!(at(&s, [5.9, -2.5, 2.5]) < 0.0);
        assert!(at(&s, [6.1, -2.5, 2.5]) > 0.0);
        assert!(
            at(&s, [5.1, -5.0 + 0.01, 0.01]) > 0.0,
            "a valley at the corner"
        );
        let ring = rect([2.0, 6.0], 0.0)
            .unwrap()
            .translate([6.0, 0.0])
            .unwrap();
        let r = textured_revolution(&ring, &t, 360.0, &TextureOptions::default()).unwrap();
        assert!(at(&r, [6.0, 0.0, 0.0]) < 0.0);
        assert!(at(&r, [0.0, 0.0, 0.0]) > 0.0);
        let _ = circle(1.0);
    }
}
