//! Layer images: one 8-bit grayscale picture per layer at the printer's pixel grid, white
//! where there is material, with anti-aliased edges.
//!
//! From a field, each pixel is the field clipped to the region (`ClippedField`) at its
//! centre: blocks of pixels are pruned with interval arithmetic (full and empty blocks are
//! filled without evaluating a pixel, and each block's children use the tape simplified
//! for it); in the blocks that hold the surface, a pixel's coverage is read off the field
//! and its gradient, 0.5 − F / (|∇F|·p), which sums to the exact area along a straight
//! edge (the region's faces included: there F is the distance to the face). From a mesh, the layer's outline is
//! filled with tiny-skia's anti-aliased `Mask`. Layers run in parallel and are encoded to
//! PNG as they finish, so only a few raw images are ever in memory.

use std::sync::atomic::{AtomicUsize, Ordering};

use isoforge_field::{ClippedField, GradEval, Interval, IntervalEval};
use rayon::prelude::*;

use crate::SliceError;
use crate::display::DisplayFrame;
use crate::outline::FieldSlicer;
use crate::outline::mesh::mesh_bounds;
use crate::source::{Layer, Sliceable, Source, layer_stack};

/// Root blocks are this many pixels on a side; blocks of `LEAF` pixels that may hold the
/// surface are evaluated pixel by pixel.
const ROOT: u32 = 64;
const LEAF: u32 = 4;

/// The pixel grid of a layer image.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct PixelGrid {
    /// Pixels across.
    pub width: u32,
    /// Pixels down.
    pub height: u32,
    /// Pixel size, mm.
    pub pixel: f64,
    /// Model coordinates of the grid's lower-left corner (row `height - 1`, column 0).
    pub origin: [f64; 2],
}

impl PixelGrid {
    /// The centre of pixel (column, row); row 0 is the top of the image (largest y).
    pub fn center(&self, col: u32, row: u32) -> [f64; 2] {
        [
            self.origin[0] + (col as f64 + 0.5) * self.pixel,
            self.origin[1] + ((self.height - 1 - row) as f64 + 0.5) * self.pixel,
        ]
    }
}

/// A layer as PNG, its white area and whether it touches the image border.
type RenderedLayer = (Vec<u8>, f64, bool);

/// Where layer images go.
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum GridSpec {
    /// A printer's display of fixed size, centred on the model; a model that does not fit
    /// is an error.
    Display {
        /// The image's pixels across.
        width: u32,
        /// The image's pixels down.
        height: u32,
        /// Pixel size, mm.
        pixel: f64,
        /// How the display turns and mirrors the bed's picture.
        frame: DisplayFrame,
    },
    /// A grid just large enough for the model (voxel output), one empty pixel around it.
    Fit {
        /// Pixel size, mm.
        pixel: f64,
    },
}

/// Layer images, PNG-encoded.
pub struct LayerImages {
    /// The layers (bed coordinates, `model_z` the model height).
    pub layers: Vec<Layer>,
    /// The bed's grid every layer is drawn on (columns along x, row 0 at the largest y).
    pub grid: PixelGrid,
    /// How the images turn and mirror the bed's grid.
    pub frame: DisplayFrame,
    /// One PNG per layer.
    pub pngs: Vec<Vec<u8>>,
    /// White area of each layer, mm² (sum of pixel coverage times pixel area).
    pub areas: Vec<f64>,
    /// The model seen from above: the brightest value over all layers, at 1/`SILHOUETTE`
    /// of the grid's resolution (for thumbnails).
    pub silhouette: Vec<u8>,
    /// The silhouette's width and height.
    pub silhouette_size: (u32, u32),
}

impl LayerImages {
    /// The images' size (width, height), pixels.
    pub fn image_size(&self) -> [u32; 2] {
        self.frame.image_size([self.grid.width, self.grid.height])
    }
}

/// The silhouette is kept at this fraction of the layer resolution.
pub const SILHOUETTE: u32 = 4;

/// Renders every layer of a model at `layer_height` onto a pixel grid.
pub fn render_layers(
    source: &Source,
    layer_height: f64,
    spec: GridSpec,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<LayerImages, SliceError> {
    render_layers_from(source, layer_height, layer_height, spec, progress)
}

/// Renders every layer of a model onto a pixel grid: the first `first_layer_height` thick
/// (PrusaSlicer's `initial_layer_height`), the rest `layer_height`.
pub fn render_layers_from(
    source: &Source,
    first_layer_height: f64,
    layer_height: f64,
    spec: GridSpec,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<LayerImages, SliceError> {
    let pixel = match spec {
        GridSpec::Display { pixel, .. } | GridSpec::Fit { pixel } => pixel,
    };
    let bad_grid = |width: u64, height: u64| SliceError::BadGrid {
        width,
        height,
        pixel,
        layer_height,
    };
    let positive = |v: f64| v > 0.0 && v.is_finite();
    if !(positive(pixel) && positive(layer_height) && positive(first_layer_height)) {
        return Err(bad_grid(0, 0));
    }
    // Outlines (used for meshes) at a quarter-pixel resolution.
    let model = source.prepare(pixel * 0.5, pixel * 0.1)?;
    let layers = layer_stack(model.z_range, first_layer_height, layer_height);
    let (lo, hi) = xy_extent(source);
    let center = [(lo[0] + hi[0]) * 0.5, (lo[1] + hi[1]) * 0.5];
    let frame = match spec {
        GridSpec::Display { frame, .. } => frame,
        GridSpec::Fit { .. } => DisplayFrame::default(),
    };
    let (width, height) = match spec {
        GridSpec::Display { width, height, .. } => {
            let [w, h] = frame.bed_size([width, height]);
            (w, h)
        }
        GridSpec::Fit { .. } => (
            ((hi[0] - lo[0]) / pixel).ceil() as u32 + 2,
            ((hi[1] - lo[1]) / pixel).ceil() as u32 + 2,
        ),
    };
    if width == 0 || height == 0 || width as u64 * height as u64 > 1 << 31 {
        return Err(bad_grid(width.into(), height.into()));
    }
    let grid = PixelGrid {
        width,
        height,
        pixel,
        origin: [
            center[0] - width as f64 * pixel * 0.5,
            center[1] - height as f64 * pixel * 0.5,
        ],
    };
    let done = AtomicUsize::new(0);
    let sil_size = (width.div_ceil(SILHOUETTE), height.div_ceil(SILHOUETTE));
    let silhouette = std::sync::Mutex::new(vec![0u8; sil_size.0 as usize * sil_size.1 as usize]);
    let results: Vec<Result<RenderedLayer, SliceError>> = layers
        .par_iter()
        .map(|l| {
            let img = render_one(&model, &grid, l);
            let area = img.iter().map(|&v| v as f64).sum::<f64>() / 255.0 * pixel * pixel;
            let touches = touches_border(&img, width, height);
            if let Ok(mut sil) = silhouette.lock() {
                accumulate(&mut sil, sil_size.0, &img, width, height);
            }
            let [iw, ih] = frame.image_size([width, height]);
            let png = encode_png(&frame.apply(&img, width, height), iw, ih)?;
            progress(done.fetch_add(1, Ordering::Relaxed) + 1, layers.len());
            Ok((png, area, touches))
        })
        .collect();
    let mut pngs = Vec::with_capacity(layers.len());
    let mut areas = Vec::with_capacity(layers.len());
    for (k, r) in results.into_iter().enumerate() {
        let (png, area, touches) = r?;
        if touches && matches!(spec, GridSpec::Display { .. }) {
            return Err(SliceError::LargerThanDisplay {
                display: [width as f64 * pixel, height as f64 * pixel],
                layer: k,
            });
        }
        pngs.push(png);
        areas.push(area);
    }
    Ok(LayerImages {
        layers,
        grid,
        frame,
        pngs,
        areas,
        silhouette: silhouette.into_inner().unwrap_or_default(),
        silhouette_size: sil_size,
    })
}

fn accumulate(sil: &mut [u8], sw: u32, img: &[u8], w: u32, h: u32) {
    for r in 0..h {
        let row = &img[(r * w) as usize..((r + 1) * w) as usize];
        let srow = (r / SILHOUETTE * sw) as usize;
        for (c, &v) in row.iter().enumerate() {
            if v > 0 {
                let s = &mut sil[srow + c / SILHOUETTE as usize];
                *s = (*s).max(v);
            }
        }
    }
}

/// The model's extent in x and y: the region for a field, the vertex box for a mesh.
fn xy_extent(source: &Source) -> ([f64; 2], [f64; 2]) {
    match source {
        Source::Field(_, b) => ([b.min[0], b.min[1]], [b.max[0], b.max[1]]),
        Source::Mesh(m) => mesh_bounds(m)
            .map(|(lo, hi)| ([lo[0], lo[1]], [hi[0], hi[1]]))
            .unwrap_or(([0.0; 2], [0.0; 2])),
    }
}

fn touches_border(img: &[u8], w: u32, h: u32) -> bool {
    let (w, h) = (w as usize, h as usize);
    img[..w].iter().any(|&v| v > 0)
        || img[(h - 1) * w..].iter().any(|&v| v > 0)
        || (0..h).any(|r| img[r * w] > 0 || img[r * w + w - 1] > 0)
}

/// One layer's raw pixels, row 0 at the top.
pub fn render_one(model: &Sliceable, grid: &PixelGrid, layer: &Layer) -> Vec<u8> {
    match model.field() {
        Some(f) => render_field(f, grid, layer),
        None => {
            let slab = (
                layer.model_z - layer.height * 0.5,
                layer.model_z + layer.height * 0.5,
            );
            render_outline(&model.outline(layer.model_z, slab), grid)
        }
    }
}

/// Fills oriented contours (non-zero winding) with anti-aliasing.
pub fn render_outline(contours: &[crate::geom::Contour], grid: &PixelGrid) -> Vec<u8> {
    let mut mask = match tiny_skia::Mask::new(grid.width, grid.height) {
        Some(m) => m,
        None => return vec![0; grid.width as usize * grid.height as usize],
    };
    let mut pb = tiny_skia::PathBuilder::new();
    let to_px = |p: &[f64; 2]| {
        (
            ((p[0] - grid.origin[0]) / grid.pixel) as f32,
            (grid.height as f64 - (p[1] - grid.origin[1]) / grid.pixel) as f32,
        )
    };
    for c in contours {
        let mut it = c.iter();
        if let Some(p) = it.next() {
            let (x, y) = to_px(p);
            pb.move_to(x, y);
            for p in it {
                let (x, y) = to_px(p);
                pb.line_to(x, y);
            }
            pb.close();
        }
    }
    if let Some(path) = pb.finish() {
        mask.fill_path(
            &path,
            tiny_skia::FillRule::Winding,
            true,
            tiny_skia::Transform::identity(),
        );
    }
    mask.data().to_vec()
}

struct FieldRaster<'a> {
    grid: &'a PixelGrid,
    z: f64,
    zi: Interval,
    iev: IntervalEval,
    gev: GradEval,
    img: Vec<u8>,
}

/// Renders a field layer: interval-pruned blocks, gradient coverage at the surface.
fn render_field(f: &FieldSlicer, grid: &PixelGrid, layer: &Layer) -> Vec<u8> {
    let z = layer.model_z;
    let b = f.bounds();
    let mut r = FieldRaster {
        grid,
        z,
        zi: Interval::try_from((z, z)).unwrap_or(Interval::ENTIRE),
        iev: IntervalEval::new(),
        gev: GradEval::new(),
        img: vec![0; grid.width as usize * grid.height as usize],
    };
    if z < b.min[2] || z > b.max[2] {
        return r.img;
    }
    let field = f.field().clone();
    for row in (0..grid.height).step_by(ROOT as usize) {
        for col in (0..grid.width).step_by(ROOT as usize) {
            r.block(&field, col, row, ROOT);
        }
    }
    r.img
}

impl FieldRaster<'_> {
    fn block(&mut self, field: &ClippedField, col: u32, row: u32, n: u32) {
        let g = self.grid;
        let (c1, r1) = ((col + n).min(g.width), (row + n).min(g.height));
        if col >= c1 || row >= r1 {
            return;
        }
        // The box the block's pixels cover (not just their centres: an edge pixel whose
        // centre is outside still gets partial coverage).
        let half = g.pixel * 0.5;
        let lo = g.center(col, r1 - 1).map(|v| v - half);
        let hi = g.center(c1 - 1, row).map(|v| v + half);
        let (Ok(xi), Ok(yi)) = (
            Interval::try_from((lo[0], hi[0])),
            Interval::try_from((lo[1], hi[1])),
        ) else {
            return;
        };
        let v = field.interval(&mut self.iev, [xi, yi, self.zi]);
        if v.inf() >= 0.0 {
            return;
        }
        if v.sup() < 0.0 {
            self.fill(col, row, c1, r1);
            return;
        }
        if n <= LEAF {
            self.pixels(field, col, row, c1, r1);
            return;
        }
        let child = field.narrow(&self.iev);
        let h = n / 2;
        for (dc, dr) in [(0, 0), (h, 0), (0, h), (h, h)] {
            self.block(&child, col + dc, row + dr, h);
        }
    }

    fn fill(&mut self, c0: u32, r0: u32, c1: u32, r1: u32) {
        let w = self.grid.width as usize;
        for r in r0..r1 {
            self.img[r as usize * w + c0 as usize..r as usize * w + c1 as usize].fill(255);
        }
    }

    fn pixels(&mut self, field: &ClippedField, c0: u32, r0: u32, c1: u32, r1: u32) {
        let w = self.grid.width as usize;
        let p = self.grid.pixel;
        for r in r0..r1 {
            for c in c0..c1 {
                let q = self.grid.center(c, r);
                let g = field.grad(&mut self.gev, [q[0], q[1], self.z]);
                let slope = g.d[0].hypot(g.d[1]);
                // F is never NaN (NaN counts as outside: +inf, no coverage).
                let cov = if slope.is_finite() && slope > 0.0 {
                    (0.5 - g.v / (slope * p)).clamp(0.0, 1.0)
                } else if g.v < 0.0 {
                    1.0
                } else {
                    0.0
                };
                self.img[r as usize * w + c as usize] = (cov * 255.0).round() as u8;
            }
        }
    }
}

/// Encodes an 8-bit grayscale image as PNG (fast compression: layer images are mostly
/// flat, and PNG's filters do most of the work).
pub fn encode_png(img: &[u8], width: u32, height: u32) -> Result<Vec<u8>, SliceError> {
    let mut buf = Vec::new();
    let err = |e: png::EncodingError| SliceError::Encode {
        what: "PNG",
        message: e.to_string(),
    };
    {
        let mut enc = png::Encoder::new(&mut buf, width, height);
        enc.set_color(png::ColorType::Grayscale);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_compression(png::Compression::Fast);
        let mut w = enc.write_header().map_err(err)?;
        w.write_image_data(img).map_err(err)?;
        w.finish().map_err(err)?;
    }
    Ok(buf)
}
