//! The filament pipeline: outlines per layer, placed on the bed, then perimeters, skins,
//! infill, ordered paths and G-code. Layers are independent until skins compare
//! neighbours and paths chain one layer's end to the next one's start; everything else
//! runs in parallel.

use rayon::prelude::*;

use crate::SliceError;
use crate::gcode::{GcodeStats, LayerPlan, write_gcode};
use crate::geom::{Contour, Point, Region};
use crate::infill::{gyroid, gyroid_period, hatch};
use crate::paths::{islands, order_layer};
use crate::perimeters::{offset, perimeters, region_from_contours};
use crate::profile::{FdmSettings, InfillPattern};
use crate::skins::split_skins;
use crate::source::{Layer, Source, layer_stack, outlines_bbox};

/// Finest outline cell as a fraction of the line width: crossings are refined on the field,
/// so the cell only has to resolve features, and 1/8 of a line is far below what prints.
const CELL_PER_LINE_WIDTH: f64 = 1.0 / 8.0;

/// Outline simplification tolerance, mm: well under a line width, and enough to keep
/// dense contours from slowing polygon offsetting (docs/constants.md).
pub const OUTLINE_TOLERANCE: f64 = 0.005;

/// A layer's region with its skin and infill lines.
type LayerFill = (Region, Vec<Vec<Point>>, Vec<Vec<Point>>);

/// A sliced G-code job.
#[derive(Clone, Debug)]
pub struct GcodeJob {
    /// The G-code text.
    pub gcode: String,
    /// Totals.
    pub stats: GcodeStats,
    /// Model-to-bed translation applied (x, y, z), mm.
    pub offset: [f64; 3],
    /// The layers, bed coordinates.
    pub layers: Vec<Layer>,
}

/// Progress callback: (layers done, layers in all).
pub type Progress<'a> = &'a (dyn Fn(usize, usize) + Sync);

/// Layer outlines, placed on the bed: the model centred in x and y, its bottom at z = 0.
pub struct PlacedLayers {
    /// The layers (bed coordinates; `model_z` keeps the model height).
    pub layers: Vec<Layer>,
    /// Outline contours per layer, bed coordinates.
    pub outlines: Vec<Vec<Contour>>,
    /// The translation applied, model to bed.
    pub offset: [f64; 3],
    /// The model's footprint, bed coordinates: `(min, max)`.
    pub footprint: ([f64; 2], [f64; 2]),
}

/// Slices a model into layer outlines centred on a bed of `bed` mm.
pub fn place_layers(
    source: &Source,
    first: f64,
    height: f64,
    cell: f64,
    bed: [f64; 2],
    progress: Progress,
) -> Result<PlacedLayers, SliceError> {
    let model = source.prepare(cell, OUTLINE_TOLERANCE)?;
    let layers = layer_stack(model.z_range, first, height);
    let done = std::sync::atomic::AtomicUsize::new(0);
    let n = layers.len();
    let mut outlines: Vec<Vec<Contour>> = layers
        .par_iter()
        .map(|l| {
            let o = model.outline(
                l.model_z,
                (l.model_z - l.height * 0.5, l.model_z + l.height * 0.5),
            );
            progress(
                done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1,
                n,
            );
            o
        })
        .collect();
    let (lo, hi) = outlines_bbox(&outlines).ok_or(SliceError::NoLayers)?;
    let offset = [
        bed[0] * 0.5 - (lo[0] + hi[0]) * 0.5,
        bed[1] * 0.5 - (lo[1] + hi[1]) * 0.5,
        -model.z_range.0,
    ];
    for c in outlines.iter_mut().flatten().flatten() {
        c[0] += offset[0];
        c[1] += offset[1];
    }
    let footprint = (
        [lo[0] + offset[0], lo[1] + offset[1]],
        [hi[0] + offset[0], hi[1] + offset[1]],
    );
    Ok(PlacedLayers {
        layers,
        outlines,
        offset,
        footprint,
    })
}

/// Slices a model to G-code with the given settings. `progress` hears about outlines.
pub fn slice_gcode(
    source: &Source,
    s: &FdmSettings,
    progress: Progress,
) -> Result<GcodeJob, SliceError> {
    let cell = s.line_width * CELL_PER_LINE_WIDTH;
    let placed = place_layers(
        source,
        s.first_layer_height,
        s.layer_height,
        cell,
        s.bed_size,
        progress,
    )?;
    check_fits(&placed, s)?;
    let w = s.line_width;

    let regions: Vec<Region> = placed
        .outlines
        .par_iter()
        .map(|o| region_from_contours(o))
        .collect();
    let walls: Vec<_> = regions
        .par_iter()
        .map(|r| perimeters(r, s.perimeters, w))
        .collect();
    let skirt: Vec<Contour> = match regions.first() {
        Some(r0) if s.skirt_loops > 0 => (0..s.skirt_loops)
            .rev()
            .flat_map(|k| {
                offset(r0, s.skirt_distance + w * (0.5 + k as f64))
                    .into_iter()
                    .filter_map(|shape| shape.into_iter().next())
            })
            .collect(),
        _ => Vec::new(),
    };

    let plans_unordered: Vec<LayerFill> = (0..regions.len())
        .into_par_iter()
        .map(|i| {
            let split = split_skins(i, &walls[i].inner, &regions, s.top_layers, s.bottom_layers);
            // Alternate 45° and 135° so each skin layer crosses the one below.
            let angle = if i % 2 == 0 {
                std::f64::consts::FRAC_PI_4
            } else {
                3.0 * std::f64::consts::FRAC_PI_4
            };
            let skin = hatch(&split.solid, angle, w);
            let fill = if s.infill_density <= 0.0 {
                Vec::new()
            } else if s.infill_density >= 1.0 {
                hatch(&split.sparse, angle, w)
            } else {
                match s.infill_pattern {
                    InfillPattern::Rectilinear => hatch(&split.sparse, angle, w / s.infill_density),
                    InfillPattern::Grid => {
                        let sp = 2.0 * w / s.infill_density;
                        let mut l = hatch(&split.sparse, std::f64::consts::FRAC_PI_4, sp);
                        l.extend(hatch(&split.sparse, 3.0 * std::f64::consts::FRAC_PI_4, sp));
                        l
                    }
                    InfillPattern::Gyroid => gyroid(
                        &split.sparse,
                        placed.layers[i].top - placed.layers[i].height * 0.5,
                        gyroid_period(s.infill_density, w),
                    ),
                }
            };
            (regions[i].clone(), skin, fill)
        })
        .collect();

    let mut pos: Point = [0.0, 0.0];
    let mut plans = Vec::with_capacity(regions.len());
    for (i, ((region, skin, fill), wall)) in plans_unordered.into_iter().zip(walls).enumerate() {
        let isl = islands(&region, wall.loops, skin, fill);
        let skirt_here: &[Contour] = if i == 0 { &skirt } else { &[] };
        let paths = order_layer(skirt_here, isl, &mut pos);
        plans.push(LayerPlan {
            top: placed.layers[i].top,
            height: placed.layers[i].height,
            paths,
            barriers: placed.outlines[i].clone(),
        });
    }
    let (gcode, stats) = write_gcode(&plans, s);
    Ok(GcodeJob {
        gcode,
        stats,
        offset: placed.offset,
        layers: placed.layers,
    })
}

/// The model (with its skirt) must fit the bed and the printable height.
fn check_fits(placed: &PlacedLayers, s: &FdmSettings) -> Result<(), SliceError> {
    let (lo, hi) = placed.footprint;
    let size = [hi[0] - lo[0], hi[1] - lo[1]];
    let margin = if s.skirt_loops > 0 {
        2.0 * (s.skirt_distance + s.skirt_loops as f64 * s.line_width)
    } else {
        0.0
    };
    let height = placed.layers.last().map_or(0.0, |l| l.top);
    if size[0] + margin > s.bed_size[0] || size[1] + margin > s.bed_size[1] {
        return Err(SliceError::LargerThanBed {
            size,
            with_skirt: [size[0] + margin, size[1] + margin],
            bed: s.bed_size,
        });
    }
    if height > s.max_height {
        return Err(SliceError::TallerThanPrinter {
            height,
            max_height: s.max_height,
        });
    }
    Ok(())
}
