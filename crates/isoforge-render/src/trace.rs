//! The ray search: for every pixel, the depth of the first surface point along its ray.
//!
//! The image is cut into tiles (rayon spreads them over cores); each tile's column of
//! space is searched front to back by boxes (pixel rectangle x depth range): an interval
//! pass drops boxes that are empty, stops at boxes that are full (the surface is at their
//! front face), and splits the rest, largest side first, with the field simplified by the
//! pass's min/max choices. At one pixel and the finest depth step the ray is sampled and
//! the crossing refined by bisection.

use isoforge_field::{GradEval, Interval, IntervalEval, PointEval};
use rayon::prelude::*;

use crate::camera::Camera;
use crate::view::ViewField;

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

/// A rectangle of pixels, `x0..x1` by `y0..y1`.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub(crate) struct Rect {
    pub(crate) x0: u32,
    pub(crate) y0: u32,
    pub(crate) x1: u32,
    pub(crate) y1: u32,
}

impl Rect {
    pub(crate) fn w(&self) -> u32 {
        self.x1 - self.x0
    }
    pub(crate) fn h(&self) -> u32 {
        self.y1 - self.y0
    }
    /// The pixel at index `i` of the rectangle's row-major list.
    pub(crate) fn pixel(&self, i: usize) -> (u32, u32) {
        let i = i as u32;
        (self.x0 + i % self.w(), self.y0 + i / self.w())
    }
}

/// Per-thread evaluators.
pub(crate) struct Evals {
    interval: IntervalEval,
    point: PointEval,
    /// For shading, done on the thread that traced the tile.
    pub(crate) grad: GradEval,
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

/// Finds every pixel's first hit, tile by tile over rayon, and hands each tile's hit
/// depths (w, NaN: background) to `finish` on the same thread.
pub(crate) fn trace<T: Send>(
    field: &ViewField,
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
            tile.visit(field, rect, cam.w_lo, cam.w_hi);
            finish(ev, rect, &hits)
        })
        .collect()
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

    /// True while some pixel of `r` has no hit yet (hits are nearer than anything left).
    fn open(&mut self, r: Rect) -> bool {
        (r.y0..r.y1).any(|y| (r.x0..r.x1).any(|x| self.hit(x, y).is_nan()))
    }

    /// Searches the box `r` x `[a, b]` of view space; boxes nearer the viewer (higher w)
    /// are searched first, so a pixel's first hit is its nearest.
    fn visit(&mut self, field: &ViewField, r: Rect, a: f64, b: f64) {
        if !self.open(r) {
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
        // The clipped field counts NaN as outside: a box where the model may be undefined
        // is never full, but one wholly outside the region is empty whatever the model.
        let f = field.interval(&mut self.ev.interval, bx);
        if f.inf() >= 0.0 {
            return; // empty
        }
        if f.sup() < 0.0 {
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
            self.march(field, r.x0, r.y0, a, b);
            return;
        }
        let sub = field.narrow(&self.ev.interval);
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
    fn march(&mut self, field: &ViewField, x: u32, y: u32, a: f64, b: f64) {
        let (u, v) = (
            self.cam.u(f64::from(x) + 0.5),
            self.cam.v(f64::from(y) + 0.5),
        );
        let step = (b - a) / SAMPLES as f64;
        let mut outside = b;
        for k in 0..=SAMPLES {
            let w = b - step * k as f64;
            if field.point(&mut self.ev.point, [u, v, w]) < 0.0 {
                let (mut lo, mut hi) = (w, outside);
                if k > 0 {
                    for _ in 0..BISECT {
                        let mid = 0.5 * (lo + hi);
                        if field.point(&mut self.ev.point, [u, v, mid]) < 0.0 {
                            lo = mid;
                        } else {
                            hi = mid;
                        }
                    }
                }
                *self.hit(x, y) = lo;
                return;
            }
            outside = w;
        }
    }
}
