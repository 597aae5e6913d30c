//! The isoforge preview renderer: a shaded picture of a field, found by interval pruning
//! along view rays, with no mesh in between (as fidget keeps fidget-raster apart from its
//! mesher).
//!
//! The data flow, one file a step:
//! model → [`isoforge_field::ClippedField`] (the model clipped to its region, outside and
//! NaN counted as outside, as when meshing) → `view.rs` (the field in view coordinates for
//! a [`View`]) → `camera.rs` (pixels to view space; framed on the model by a coarse first
//! pass) → `trace.rs` (per pixel, the depth of the first surface point) → `shade.rs`
//! (Lambert shading from the gradient) → [`Image`] (`image.rs`, PNG).
//!
//! ```
//! use isoforge_field::{Bounds, Shape};
//! use isoforge_render::{RenderSettings, render};
//! let (x, y, z) = (Shape::x(), Shape::y(), Shape::z());
//! let ball = x.square() + y.square() + z.square() - 1.0;
//! let region = Bounds::new([-1.2; 3], [1.2; 3]).unwrap();
//! let image = render(&ball, &region, &RenderSettings::new(64, 48));
//! assert_eq!((image.width, image.height), (64, 48));
//! let mut png = Vec::new();
//! image.write_png(&mut png)?;
//! # Ok::<(), std::io::Error>(())
//! ```

mod animation;
mod camera;
mod image;
mod shade;
mod trace;
mod view;

use isoforge_field::{Bounds, ClippedField, Shape};

use crate::camera::Camera;
use crate::trace::{Rect, trace};
use crate::view::ViewField;

pub use crate::animation::{GifWriter, write_gif};
pub use crate::image::Image;
pub use crate::view::View;

/// How to render.
#[derive(Copy, Clone, Debug)]
pub struct RenderSettings {
    /// The viewpoint.
    pub view: View,
    /// Width in pixels (at least 1).
    pub width: u32,
    /// Height in pixels (at least 1).
    pub height: u32,
    /// The finest depth step is the depth range / 2^depth. `None` picks one about a
    /// pixel deep.
    pub depth: Option<u8>,
    /// Frame the picture on the model (found by a coarse first pass) rather than on the
    /// whole region.
    pub fit: bool,
}

impl RenderSettings {
    /// An iso view at a size, framed on the model.
    pub fn new(width: u32, height: u32) -> Self {
        RenderSettings {
            view: View::Iso,
            width,
            height,
            depth: None,
            fit: true,
        }
    }
}

/// Side of the first, coarse pass that finds where the model is, to frame it.
const FIT_PASS: u32 = 96;
/// Coarse pixels added around the outline the first pass found: thin parts (a cone's
/// tip) can slip between coarse samples.
const FIT_PAD: f64 = 3.0;

/// Renders a shaded picture of `shape` over the region `bounds`.
pub fn render(shape: &Shape, bounds: &Bounds, settings: &RenderSettings) -> Image {
    let size = (settings.width.max(1), settings.height.max(1));
    let field = ViewField::new(ClippedField::new(shape, *bounds), settings.view);
    let cam = camera(&field, size, settings);
    let tiles = trace(&field, &cam, size, |ev, rect, hits| {
        let mut rgb = Vec::with_capacity(hits.len() * 3);
        for (i, &w) in hits.iter().enumerate() {
            let colour = if w.is_nan() {
                shade::BACKGROUND
            } else {
                let (x, y) = rect.pixel(i);
                let p = [cam.u(f64::from(x) + 0.5), cam.v(f64::from(y) + 0.5), w];
                shade::shade(field.grad(&mut ev.grad, p).1)
            };
            rgb.extend(shade::to_rgb(colour));
        }
        (rect, rgb)
    });
    let mut image = Image::filled(size.0, size.1, shade::to_rgb(shade::BACKGROUND));
    for (rect, rgb) in tiles {
        image.paste(rect.x0, rect.y0, rect.w(), &rgb);
    }
    image
}

/// The camera for the picture: on the whole region, or (with `fit`) on the part of it
/// where a coarse first pass saw the model.
fn camera(field: &ViewField, size: (u32, u32), settings: &RenderSettings) -> Camera {
    let [u, v, w] = field.extent();
    let whole = Camera::fit(u, v, w, size, settings.depth);
    if !settings.fit {
        return whole;
    }
    let scale = f64::from(FIT_PASS) / f64::from(size.0.max(size.1));
    let coarse_size = (
        ((f64::from(size.0) * scale).ceil() as u32).clamp(1, FIT_PASS),
        ((f64::from(size.1) * scale).ceil() as u32).clamp(1, FIT_PASS),
    );
    let coarse = Camera::fit(u, v, w, coarse_size, None);
    let Some(seen) = outline(field, &coarse, coarse_size) else {
        return whole;
    };
    // Grow the outline by a few coarse pixels, but never past the region.
    let fu = [
        coarse.u(f64::from(seen.x0) - FIT_PAD).max(u[0]),
        coarse.u(f64::from(seen.x1) + FIT_PAD).min(u[1]),
    ];
    let fv = [
        coarse.v(f64::from(seen.y1) + FIT_PAD).max(v[0]),
        coarse.v(f64::from(seen.y0) - FIT_PAD).min(v[1]),
    ];
    Camera::fit(fu, fv, w, size, settings.depth)
}

/// The pixels of `cam`'s picture where the model shows, as one rectangle; `None` when it
/// shows nowhere.
fn outline(field: &ViewField, cam: &Camera, size: (u32, u32)) -> Option<Rect> {
    let tiles = trace(field, cam, size, |_, rect, hits| {
        let mut seen: Option<Rect> = None;
        for (i, h) in hits.iter().enumerate() {
            if h.is_nan() {
                continue;
            }
            let (x, y) = rect.pixel(i);
            let px = Rect {
                x0: x,
                y0: y,
                x1: x + 1,
                y1: y + 1,
            };
            seen = Some(seen.map_or(px, |s| union(s, px)));
        }
        seen
    });
    tiles.into_iter().flatten().reduce(union)
}

fn union(a: Rect, b: Rect) -> Rect {
    Rect {
        x0: a.x0.min(b.x0),
        y0: a.y0.min(b.y0),
        x1: a.x1.max(b.x1),
        y1: a.y1.max(b.y1),
    }
}

#[cfg(test)]
mod tests;
