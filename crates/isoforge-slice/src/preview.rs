//! Pictures of printed layers, drawn from G-code as any printer would read it (ours or
//! another slicer's): every extrusion as a line as wide as the filament it pushes makes
//! it (volume over length and layer height), coloured by its `;TYPE:`, travel as thin
//! grey lines. The colours know our feature names, PrusaSlicer's and Cura's.
//!
//! ```no_run
//! use isoforge_slice::check::parse;
//! use isoforge_slice::preview::{View, draw_layer};
//! let report = parse(&std::fs::read_to_string("cube.gcode")?)?;
//! let png = draw_layer(&report, 10, &View::fit(&report, 800), 1.75)?;
//! std::fs::write("layer-10.png", png)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use tiny_skia::{Color, LineCap, Paint, PathBuilder, Pixmap, Stroke, Transform};

use crate::SliceError;
use crate::check::GcodeReport;

/// The colour of a feature, by the names isoforge, PrusaSlicer and Cura write.
pub fn colour(feature: &str) -> [u8; 3] {
    let f = feature.to_ascii_lowercase();
    let has = |s: &str| f.contains(s);
    if has("overhang") {
        [60, 110, 255]
    } else if has("internal-bridge") || has("internal bridge") {
        [40, 180, 170]
    } else if has("bridge") {
        [120, 190, 255]
    } else if has("interface") {
        [20, 120, 60]
    } else if has("support") {
        [60, 200, 90]
    } else if has("thin") || has("gap") {
        // Before the walls: THIN-WALL is a wall of its own kind.
        [240, 240, 240]
    } else if has("outer") || has("external") {
        [255, 140, 20]
    } else if has("inner") || f == "perimeter" || has("wall") {
        [250, 220, 60]
    } else if has("top") {
        [230, 40, 40]
    } else if has("skin") || has("solid") || has("bottom") {
        [170, 70, 200]
    } else if has("fill") {
        [150, 40, 40]
    } else if has("iron") {
        [255, 150, 200]
    } else if has("skirt") || has("brim") || has("raft") {
        [120, 150, 120]
    } else {
        [160, 160, 160]
    }
}

/// The part of the bed a picture shows, and its size.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct View {
    /// Lower-left corner, mm.
    pub lo: [f64; 2],
    /// Upper-right corner, mm.
    pub hi: [f64; 2],
    /// Pixels along the longer side.
    pub size: u32,
}

impl View {
    /// A view of every extrusion in the file (so all layers share one scale), with a
    /// margin of 2 mm.
    pub fn fit(r: &GcodeReport, size: u32) -> View {
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        for x in &r.extrusions {
            for p in [x.from, x.to] {
                lo = [lo[0].min(p[0]), lo[1].min(p[1])];
                hi = [hi[0].max(p[0]), hi[1].max(p[1])];
            }
        }
        if !lo[0].is_finite() {
            lo = [0.0; 2];
            hi = [10.0; 2];
        }
        View {
            lo: [lo[0] - 2.0, lo[1] - 2.0],
            hi: [hi[0] + 2.0, hi[1] + 2.0],
            size,
        }
    }

    fn pixels(&self) -> (u32, u32, f64) {
        let (w, h) = (self.hi[0] - self.lo[0], self.hi[1] - self.lo[1]);
        let scale = self.size.max(16) as f64 / w.max(h).max(1e-6);
        (
            ((w * scale).ceil() as u32).max(1),
            ((h * scale).ceil() as u32).max(1),
            scale,
        )
    }
}

/// One layer drawn as a PNG. `filament` is the filament diameter, mm.
pub fn draw_layer(
    r: &GcodeReport,
    layer: usize,
    view: &View,
    filament: f64,
) -> Result<Vec<u8>, SliceError> {
    let (w, h, scale) = view.pixels();
    let mut pix = Pixmap::new(w, h).ok_or(SliceError::Encode {
        what: "layer picture",
        message: format!("a {w} x {h} picture cannot be made"),
    })?;
    pix.fill(Color::from_rgba8(24, 24, 28, 255));
    let to_px = |p: [f64; 3]| {
        (
            ((p[0] - view.lo[0]) * scale) as f32,
            ((view.hi[1] - p[1]) * scale) as f32,
        )
    };
    let z_of = |n: usize| r.layers.iter().find(|l| l.0 == n).and_then(|l| l.1);
    let thickness = match (z_of(layer), layer.checked_sub(1).and_then(z_of)) {
        (Some(z), Some(zb)) if z > zb => z - zb,
        (Some(z), _) if z > 0.0 => z,
        _ => 0.2,
    };
    let area_f = std::f64::consts::PI * (filament / 2.0).powi(2);
    // Travel first, under the lines.
    let mut travel = PathBuilder::new();
    for m in r
        .moves
        .iter()
        .filter(|m| m.layer == Some(layer) && m.e <= 0.0)
    {
        if (m.to[0] - m.from[0]).hypot(m.to[1] - m.from[1]) > 1e-6 {
            let (a, b) = (to_px(m.from), to_px(m.to));
            travel.move_to(a.0, a.1);
            travel.line_to(b.0, b.1);
        }
    }
    if let Some(path) = travel.finish() {
        let mut paint = Paint::default();
        paint.set_color_rgba8(110, 110, 120, 160);
        paint.anti_alias = true;
        let stroke = Stroke {
            width: 1.0,
            ..Stroke::default()
        };
        pix.stroke_path(&path, &paint, &stroke, Transform::identity(), None);
    }
    for x in r.extrusions.iter().filter(|x| x.layer == Some(layer)) {
        let len = (x.to[0] - x.from[0]).hypot(x.to[1] - x.from[1]);
        if len < 1e-6 {
            continue;
        }
        let width = x.e * area_f / (len * thickness);
        let [cr, cg, cb] = colour(&x.feature);
        let mut paint = Paint::default();
        paint.set_color_rgba8(cr, cg, cb, 255);
        paint.anti_alias = true;
        let stroke = Stroke {
            width: ((width * scale) as f32).max(1.0),
            line_cap: LineCap::Round,
            ..Stroke::default()
        };
        let mut pb = PathBuilder::new();
        let (a, b) = (to_px(x.from), to_px(x.to));
        pb.move_to(a.0, a.1);
        pb.line_to(b.0, b.1);
        if let Some(path) = pb.finish() {
            pix.stroke_path(&path, &paint, &stroke, Transform::identity(), None);
        }
    }
    encode_rgba(pix.data(), w, h)
}

fn encode_rgba(data: &[u8], w: u32, h: u32) -> Result<Vec<u8>, SliceError> {
    let err = |e: png::EncodingError| SliceError::Encode {
        what: "layer picture",
        message: e.to_string(),
    };
    let mut buf = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut buf, w, h);
        enc.set_color(png::ColorType::Rgba);
        enc.set_depth(png::BitDepth::Eight);
        let mut wr = enc.write_header().map_err(err)?;
        wr.write_image_data(data).map_err(err)?;
        wr.finish().map_err(err)?;
    }
    Ok(buf)
}

/// Layers worth a picture when none are named: the first, a quarter, the middle, three
/// quarters and the last, and the first layer with a bridge, an overhang or support.
pub fn default_layers(r: &GcodeReport) -> Vec<usize> {
    let n = r.layers.len();
    if n == 0 {
        return Vec::new();
    }
    let mut out: Vec<usize> = [0, n / 4, n / 2, 3 * n / 4, n - 1].to_vec();
    for want in ["BRIDGE", "OVERHANG", "SUPPORT"] {
        if let Some(l) = r
            .extrusions
            .iter()
            .find(|x| x.feature.to_ascii_uppercase().contains(want))
            .and_then(|x| x.layer)
        {
            out.push(l);
        }
    }
    out.sort_unstable();
    out.dedup();
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::check::parse;

    #[test]
    fn a_layer_is_drawn_with_its_features_coloured() {
        let g = ";LAYER:0\n;Z:0.2\nG92 E0\n;TYPE:WALL-OUTER\nG1 X0 Y0 F600\nG1 X10 Y0 E0.5\n;TYPE:FILL\nG1 X10 Y10 E1.0\n";
        let r = parse(g).unwrap();
        let png = draw_layer(&r, 0, &View::fit(&r, 100), 1.75).unwrap();
        assert_eq!(&png[1..4], b"PNG");
        assert_ne!(colour("WALL-OUTER"), colour("FILL"));
        assert_ne!(colour("THIN-WALL"), colour("WALL-INNER"));
        assert_eq!(colour("External perimeter"), colour("WALL-OUTER"));
        assert_eq!(colour("Bridge infill"), colour("BRIDGE"));
        assert_eq!(default_layers(&r), vec![0]);
    }
}
