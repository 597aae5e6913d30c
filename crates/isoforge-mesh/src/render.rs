//! A shaded preview picture of a field: for each pixel, the first surface point along the
//! view ray, found by interval pruning; shaded from the gradient.
//!
//! The shape is first clipped to its region (outside the box counts as outside, as when
//! meshing) and remapped into view coordinates `(u, v, w)`: u to the right, v up, w toward
//! the viewer. Every view, the isometric one included, then looks straight down -w. The
//! image is cut into tiles (rayon spreads them over cores); each tile's column of space is
//! searched front to back by boxes (pixel rectangle x depth range): an interval pass
//! drops boxes that are empty, stops at boxes that are full (the surface is at their front
//! face), and splits the rest, largest side first, with the tape simplified by the pass's
//! min/max choices. At one pixel and the finest depth step the ray is sampled and the
//! crossing refined by bisection. The gradient there gives a normal for Lambert shading.

use isoforge_field::{Bounds, GradEval, Interval, IntervalEval, PointEval, Shape, Tape};
use rayon::prelude::*;

/// Where the picture is taken from.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Default)]
pub enum View {
    /// From the front, right and above (x right-ish, z up).
    #[default]
    Iso,
    /// From above, looking down -z (x right, y up).
    Top,
    /// From the front, looking along +y (x right, z up).
    Front,
    /// From the right, looking along -x (y right, z up).
    Right,
}

impl View {
    /// The view for a command-line name: `iso`, `top`, `front`, `right`.
    pub fn from_name(name: &str) -> Option<View> {
        match name.to_ascii_lowercase().as_str() {
            "iso" => Some(View::Iso),
            "top" => Some(View::Top),
            "front" => Some(View::Front),
            "right" => Some(View::Right),
            _ => None,
        }
    }

    /// The rows of the rotation from world to view coordinates: `u`, `v`, `w`.
    fn frame(self) -> [[f64; 3]; 3] {
        let (w, up) = match self {
            View::Top => ([0.0, 0.0, 1.0], [0.0, 1.0, 0.0]),
            View::Front => ([0.0, -1.0, 0.0], [0.0, 0.0, 1.0]),
            View::Right => ([1.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
            View::Iso => {
                let s = 1.0 / 3f64.sqrt();
                ([s, -s, s], [0.0, 0.0, 1.0])
            }
        };
        let u = normalize(cross(up, w));
        let v = cross(w, u);
        [u, v, w]
    }
}

/// An RGB picture, 8 bits a channel, rows from the top.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width * height * 3` bytes, row by row, red green blue.
    pub pixels: Vec<u8>,
}

impl Image {
    /// The colour at a pixel.
    pub fn pixel(&self, x: u32, y: u32) -> [u8; 3] {
        let i = (y as usize * self.width as usize + x as usize) * 3;
        [self.pixels[i], self.pixels[i + 1], self.pixels[i + 2]]
    }

    /// Encodes the picture as a PNG.
    pub fn write_png(&self, w: &mut dyn std::io::Write) -> std::io::Result<()> {
        let mut enc = png::Encoder::new(w, self.width, self.height);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut writer = enc.write_header().map_err(std::io::Error::other)?;
        writer
            .write_image_data(&self.pixels)
            .map_err(std::io::Error::other)?;
        writer.finish().map_err(std::io::Error::other)
    }
}

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
    /// An iso view at a size.
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

/// Background colour (a light gray with a hint of blue).
const BACKGROUND: [f64; 3] = [0.95, 0.96, 0.98];
/// The model's colour: a calm gray-blue.
const BASE: [f64; 3] = [0.52, 0.62, 0.78];
/// Ambient light share; the key light gives the rest.
const AMBIENT: f64 = 0.28;
/// Pixels per tile side: large enough that a tile's interval passes prune well, small
/// enough that 2 cores get a fair share of a 256-pixel image.
const TILE: u32 = 32;
/// Ray samples in a finest box before bisection: catches a sign change inside a box the
/// interval pass could not decide.
const SAMPLES: usize = 4;
/// Bisection steps: 2^-12 of a sample step (a quarter of a finest depth step, about a
/// pixel), far below what shading can show. Point evaluations here were half of a heart
/// render's time with 20 steps (perf, 400 x 300).
const BISECT: usize = 12;

/// The mapping from pixels to view space.
struct Camera {
    /// View-space u, v of the top-left pixel's corner.
    u0: f64,
    v0: f64,
    /// Size of a pixel in mm.
    px: f64,
    /// Depth range (w) of the region.
    w_lo: f64,
    w_hi: f64,
    /// The finest depth step.
    dw: f64,
}

impl Camera {
    fn u(&self, x: f64) -> f64 {
        self.u0 + x * self.px
    }
    fn v(&self, y: f64) -> f64 {
        self.v0 - y * self.px
    }
}

impl Camera {
    /// A camera showing `u` x `v` (view-space ranges) in a `width` x `height` image with
    /// a 4 % margin, keeping the aspect; the depth range is `w`.
    fn fit(u: [f64; 2], v: [f64; 2], w: [f64; 2], size: (u32, u32), depth: Option<u8>) -> Self {
        let (width, height) = (f64::from(size.0), f64::from(size.1));
        let px = ((u[1] - u[0]) / width).max((v[1] - v[0]) / height) * 1.08;
        let px = if px > 0.0 { px } else { f64::MIN_POSITIVE };
        let depth_bits = depth.map_or_else(
            || ((w[1] - w[0]) / px).log2().ceil().clamp(4.0, 16.0) as i32,
            |d| i32::from(d.clamp(1, 24)),
        );
        Camera {
            u0: 0.5 * (u[0] + u[1]) - px * width * 0.5,
            v0: 0.5 * (v[0] + v[1]) + px * height * 0.5,
            px,
            w_lo: w[0],
            w_hi: w[1],
            dw: (w[1] - w[0]) / f64::from(2u32.pow(depth_bits as u32)),
        }
    }
}

/// Side of the first, coarse pass that finds where the model is, to frame it.
const FIT_PASS: u32 = 96;
/// Coarse pixels added around the outline the first pass found.
const FIT_PAD: f64 = 3.0;

/// Renders a shaded picture of `shape` over the region `bounds`.
pub fn render(shape: &Shape, bounds: &Bounds, settings: &RenderSettings) -> Image {
    let width = settings.width.max(1);
    let height = settings.height.max(1);
    let frame = settings.view.frame();
    let centre: [f64; 3] = [0, 1, 2].map(|i| (bounds.min[i] + bounds.max[i]) * 0.5);
    let half: [f64; 3] = [0, 1, 2].map(|i| (bounds.max[i] - bounds.min[i]) * 0.5);

    // The region's extent in view space, from its eight corners.
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for k in 0..8 {
        let p: [f64; 3] = [0, 1, 2].map(|a| if k >> a & 1 == 1 { half[a] } else { -half[a] });
        for (r, row) in frame.iter().enumerate() {
            let c = dot(*row, p);
            lo[r] = lo[r].min(c);
            hi[r] = hi[r].max(c);
        }
    }

    // Clip to the region, then substitute world coordinates by view ones:
    // p = centre + u * frame[0] + v * frame[1] + w * frame[2].
    let (x, y, z) = (Shape::x(), Shape::y(), Shape::z());
    let mut clip: Option<Shape> = None;
    for (a, axis) in [&x, &y, &z].into_iter().enumerate() {
        let slab = (axis - centre[a]).abs() - half[a];
        clip = Some(match clip {
            None => slab,
            Some(c) => c.max(&slab),
        });
    }
    let clipped = match clip {
        Some(c) => shape.max(&c),
        None => shape.clone(),
    };
    let world =
        [0, 1, 2].map(|a| &x * frame[0][a] + &y * frame[1][a] + &z * frame[2][a] + centre[a]);
    let tape = Tape::new(&clipped.remap(&world[0], &world[1], &world[2]));

    let (u, v, w) = ([lo[0], hi[0]], [lo[1], hi[1]], [lo[2], hi[2]]);
    let mut cam = Camera::fit(u, v, w, (width, height), settings.depth);
    if settings.fit {
        // A coarse pass over the whole region finds the model's outline; the picture is
        // then framed on it (grown by a coarse pixel each way, so nothing is cut off).
        let scale = f64::from(FIT_PASS) / f64::from(width.max(height));
        let (cw, ch) = (
            ((f64::from(width) * scale).ceil() as u32).clamp(1, FIT_PASS),
            ((f64::from(height) * scale).ceil() as u32).clamp(1, FIT_PASS),
        );
        let coarse = Camera::fit(u, v, w, (cw, ch), None);
        let hits = trace(&tape, &coarse, (cw, ch), |_, rect, hits| {
            (rect, hits.to_vec())
        });
        let mut seen = [u32::MAX, u32::MAX, 0, 0];
        for (rect, hits) in hits {
            for (i, h) in hits.iter().enumerate() {
                if !h.is_nan() {
                    let (px, py) = (rect.x0 + i as u32 % rect.w(), rect.y0 + i as u32 / rect.w());
                    seen = [
                        seen[0].min(px),
                        seen[1].min(py),
                        seen[2].max(px + 1),
                        seen[3].max(py + 1),
                    ];
                }
            }
        }
        if seen[0] < seen[2] {
            // Thin parts (a cone's tip) can slip between coarse samples: grow the outline
            // by a few coarse pixels, but never past the region.
            let pad = FIT_PAD;
            let fu = [
                coarse.u(f64::from(seen[0]) - pad).max(u[0]),
                coarse.u(f64::from(seen[2]) + pad).min(u[1]),
            ];
            let fv = [
                coarse.v(f64::from(seen[3]) + pad).max(v[0]),
                coarse.v(f64::from(seen[1]) - pad).min(v[1]),
            ];
            cam = Camera::fit(fu, fv, w, (width, height), settings.depth);
        }
    }

    let light = normalize([-0.45, 0.55, 0.7]);
    let tiles = trace(&tape, &cam, (width, height), |ev, rect, hits| {
        let mut rgb = Vec::with_capacity(hits.len() * 3);
        for (i, &w) in hits.iter().enumerate() {
            let colour = if w.is_nan() {
                BACKGROUND
            } else {
                let px_x = rect.x0 + i as u32 % rect.w();
                let px_y = rect.y0 + i as u32 / rect.w();
                let p = [
                    cam.u(f64::from(px_x) + 0.5),
                    cam.v(f64::from(px_y) + 0.5),
                    w,
                ];
                let g = ev.grad.eval(&tape, p);
                let n = normalize(g.d);
                // A NaN or zero gradient (a crease, a singular point): face the viewer.
                let n = if n.iter().all(|c| c.is_finite()) {
                    n
                } else {
                    [0.0, 0.0, 1.0]
                };
                let lambert = dot(n, light).max(0.0);
                BASE.map(|c| c * (AMBIENT + (1.0 - AMBIENT) * lambert))
            };
            rgb.extend(colour.map(|c| (c.clamp(0.0, 1.0) * 255.0).round() as u8));
        }
        (rect, rgb)
    });

    let mut pixels = vec![0u8; width as usize * height as usize * 3];
    for (rect, rgb) in tiles {
        for (row, chunk) in rgb.chunks_exact(rect.w() as usize * 3).enumerate() {
            let y = rect.y0 as usize + row;
            let start = (y * width as usize + rect.x0 as usize) * 3;
            pixels[start..start + chunk.len()].copy_from_slice(chunk);
        }
    }
    Image {
        width,
        height,
        pixels,
    }
}

/// Finds every pixel's first hit, tile by tile over rayon, and hands each tile's hit
/// depths (NaN: background) to `finish` on the same thread.
fn trace<T: Send>(
    tape: &Tape,
    cam: &Camera,
    (width, height): (u32, u32),
    finish: impl Fn(&mut Evals, Rect, &[f64]) -> T + Sync,
) -> Vec<T> {
    let tiles_x = width.div_ceil(TILE);
    let tiles_y = height.div_ceil(TILE);
    (0..tiles_x * tiles_y)
        .into_par_iter()
        .map_init(Evals::new, |ev, t| {
            let (tx, ty) = (t % tiles_x * TILE, t / tiles_x * TILE);
            let rect = Rect {
                x0: tx,
                y0: ty,
                x1: (tx + TILE).min(width),
                y1: (ty + TILE).min(height),
            };
            let mut hits = vec![f64::NAN; (rect.w() * rect.h()) as usize];
            let mut tile = Tile {
                cam,
                rect,
                hits: &mut hits,
                ev,
            };
            tile.visit(tape, rect, cam.w_lo, cam.w_hi);
            finish(ev, rect, &hits)
        })
        .collect()
}

/// Per-thread evaluators.
struct Evals {
    interval: IntervalEval,
    point: PointEval,
    grad: GradEval,
}

impl Evals {
    fn new() -> Self {
        Evals {
            interval: IntervalEval::new(),
            point: PointEval::new(),
            grad: GradEval::new(),
        }
    }
}

/// A rectangle of pixels, `x0..x1` by `y0..y1`.
#[derive(Copy, Clone, Debug)]
struct Rect {
    x0: u32,
    y0: u32,
    x1: u32,
    y1: u32,
}

impl Rect {
    fn w(&self) -> u32 {
        self.x1 - self.x0
    }
    fn h(&self) -> u32 {
        self.y1 - self.y0
    }
}

/// One tile's search state: the depth of the first hit per pixel (NaN: none yet).
struct Tile<'a> {
    cam: &'a Camera,
    rect: Rect,
    hits: &'a mut [f64],
    ev: &'a mut Evals,
}

impl Tile<'_> {
    fn hit(&mut self, x: u32, y: u32) -> &mut f64 {
        let i = (y - self.rect.y0) * self.rect.w() + (x - self.rect.x0);
        &mut self.hits[i as usize]
    }

    /// Searches the box `r` x `[a, b]` of view space; boxes nearer the viewer (higher w)
    /// are searched first, so a pixel's first hit is its nearest.
    fn visit(&mut self, tape: &Tape, r: Rect, a: f64, b: f64) {
        // Every pixel already hit? (Hits are nearer than anything left.)
        let mut open = false;
        for y in r.y0..r.y1 {
            for x in r.x0..r.x1 {
                open |= self.hit(x, y).is_nan();
            }
        }
        if !open {
            return;
        }
        let cam = self.cam;
        let iv = |lo: f64, hi: f64| {
            Interval::try_from((lo.min(hi), lo.max(hi))).unwrap_or(Interval::ENTIRE)
        };
        let bx = [
            iv(cam.u(f64::from(r.x0)), cam.u(f64::from(r.x1))),
            iv(cam.v(f64::from(r.y0)), cam.v(f64::from(r.y1))),
            iv(a, b),
        ];
        // NaN counts as outside (nothing to show there), as in `march`: a box whose
        // defined values are all positive is empty even if some points are NaN, and only
        // a box without NaN can be full. Without this, a model undefined on part of the
        // region would leave every box there undecided down to the finest level.
        let (f, nan) = self.ev.interval.eval_nan(tape, bx);
        if f.is_empty() || f.inf() > 0.0 {
            return; // empty
        }
        if !nan && f.sup() < 0.0 {
            // Full: every open pixel meets the surface at this box's front face.
            for y in r.y0..r.y1 {
                for x in r.x0..r.x1 {
                    let h = self.hit(x, y);
                    if h.is_nan() {
                        *h = b;
                    }
                }
            }
            return;
        }
        let deep = b - a;
        if r.w() == 1 && r.h() == 1 && deep <= cam.dw * 1.0001 {
            self.march(tape, r.x0, r.y0, a, b);
            return;
        }
        let sub = if self.ev.interval.choices().is_empty() {
            tape.clone()
        } else {
            tape.simplify(self.ev.interval.choices())
        };
        // Split the longest side (in mm), depth first toward the viewer.
        let across = f64::from(r.w().max(r.h())) * cam.px;
        if deep > across || (r.w() == 1 && r.h() == 1) {
            let mid = 0.5 * (a + b);
            self.visit(&sub, r, mid, b);
            self.visit(&sub, r, a, mid);
        } else if r.w() >= r.h() {
            let xm = r.x0 + r.w() / 2;
            self.visit(&sub, Rect { x1: xm, ..r }, a, b);
            self.visit(&sub, Rect { x0: xm, ..r }, a, b);
        } else {
            let ym = r.y0 + r.h() / 2;
            self.visit(&sub, Rect { y1: ym, ..r }, a, b);
            self.visit(&sub, Rect { y0: ym, ..r }, a, b);
        }
    }

    /// Samples one pixel's ray from `b` down to `a`; at the first point inside, bisects
    /// back to the crossing.
    fn march(&mut self, tape: &Tape, x: u32, y: u32, a: f64, b: f64) {
        let (u, v) = (
            self.cam.u(f64::from(x) + 0.5),
            self.cam.v(f64::from(y) + 0.5),
        );
        let step = (b - a) / SAMPLES as f64;
        let mut outside = b;
        for k in 0..=SAMPLES {
            let w = b - step * k as f64;
            let f = self.ev.point.eval(tape, [u, v, w]);
            if f < 0.0 {
                let (mut lo, mut hi) = (w, outside);
                if k > 0 {
                    for _ in 0..BISECT {
                        let mid = 0.5 * (lo + hi);
                        if self.ev.point.eval(tape, [u, v, mid]) < 0.0 {
                            lo = mid;
                        } else {
                            hi = mid;
                        }
                    }
                }
                *self.hit(x, y) = lo;
                return;
            }
            // NaN counts as outside: nothing to show there.
            outside = w;
        }
    }
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn normalize(a: [f64; 3]) -> [f64; 3] {
    let l = dot(a, a).sqrt();
    a.map(|c| c / l)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sphere(r: f64) -> Shape {
        let (x, y, z) = (Shape::x(), Shape::y(), Shape::z());
        x.square() + y.square() + z.square() - r * r
    }

    fn region(h: f64) -> Bounds {
        Bounds::new([-h; 3], [h; 3]).unwrap()
    }

    fn is_background(p: [u8; 3]) -> bool {
        p == BACKGROUND.map(|c| (c * 255.0).round() as u8)
    }

    #[test]
    fn views_are_right_handed_frames() {
        for view in [View::Iso, View::Top, View::Front, View::Right] {
            let [u, v, w] = view.frame();
            let c = cross(u, v);
            for i in 0..3 {
                assert!((c[i] - w[i]).abs() < 1e-12, "{view:?}");
            }
            assert!(v[2] >= 0.0, "{view:?}: up is up");
        }
    }

    #[test]
    fn sphere_fills_a_disc_of_the_right_size() {
        for view in [View::Iso, View::Top, View::Front, View::Right] {
            let s = RenderSettings {
                view,
                ..RenderSettings::new(64, 64)
            };
            let img = render(&sphere(1.0), &region(1.0), &s);
            assert_eq!(img.pixels.len(), 64 * 64 * 3);
            // The region's projection spans the image width / 1.08 (iso is wider).
            let filled = (0..64 * 64)
                .filter(|i| !is_background(img.pixel(i % 64, i / 64)))
                .count() as f64;
            assert!(
                !is_background(img.pixel(32, 32)),
                "{view:?}: centre is surface"
            );
            assert!(
                is_background(img.pixel(0, 0)),
                "{view:?}: corner is background"
            );
            if view != View::Iso {
                // Disc of radius 64 / 2 / 1.08 pixels.
                let r = 32.0 / 1.08;
                let want = std::f64::consts::PI * r * r;
                assert!(
                    (filled - want).abs() / want < 0.05,
                    "{view:?}: {filled} vs {want}"
                );
            }
        }
    }

    #[test]
    fn lit_side_is_brighter_than_the_shadow_side() {
        let img = render(&sphere(1.0), &region(1.0), &RenderSettings::new(64, 64));
        let lum = |p: [u8; 3]| u32::from(p[0]) + u32::from(p[1]) + u32::from(p[2]);
        // The key light comes from the upper left.
        assert!(lum(img.pixel(22, 22)) > lum(img.pixel(42, 42)) + 60);
    }

    #[test]
    fn clipped_half_space_shows_its_cut_face() {
        // z < 0 everywhere below: clipped to the box it is a slab whose top is flat.
        let img = render(
            &Shape::z(),
            &region(1.0),
            &RenderSettings {
                view: View::Top,
                ..RenderSettings::new(16, 16)
            },
        );
        let centre = img.pixel(8, 8);
        for (x, y) in [(4, 4), (12, 5), (6, 11)] {
            assert_eq!(img.pixel(x, y), centre, "a flat face shades evenly");
        }
    }

    #[test]
    fn undefined_parts_show_as_background() {
        // sqrt(x) is NaN for x < 0: the left half of a top view shows nothing, the right
        // half the slab x > 0.25 of the (clipped) half space.
        let (x, y) = (Shape::x(), Shape::y());
        let f = 0.5 - x.sqrt() + y * 0.0;
        let img = render(
            &f,
            &region(1.0),
            &RenderSettings {
                view: View::Top,
                fit: false,
                ..RenderSettings::new(40, 40)
            },
        );
        assert!(is_background(img.pixel(8, 20)));
        assert!(is_background(img.pixel(22, 20)));
        assert!(!is_background(img.pixel(34, 20)));
    }

    #[test]
    fn empty_region_is_all_background_and_png_decodes() {
        let img = render(
            &sphere(0.5),
            &Bounds::new([3.0; 3], [4.0; 3]).unwrap(),
            &RenderSettings::new(20, 10),
        );
        assert!((0..200).all(|i| is_background(img.pixel(i % 20, i / 20))));
        let mut png_bytes = Vec::new();
        img.write_png(&mut png_bytes).unwrap();
        let dec = png::Decoder::new(std::io::Cursor::new(png_bytes));
        let reader = dec.read_info().unwrap();
        assert_eq!((reader.info().width, reader.info().height), (20, 10));
    }
}
