//! The filament pipeline: objects sliced into outlines and arranged on the bed, then per
//! layer: islands and their walls, solid and sparse parts, bridges, supports, the lines
//! of each part in print order, and G-code (travel, retraction, cooling, time).
//!
//! Layers are independent except where a stage compares neighbours (skins, bridges,
//! supports, overhangs); everything else runs in parallel.

mod island;
mod plate;

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

use rayon::prelude::*;

use crate::SliceError;
use crate::adhesion::{RAFT_BASE_SPACING_PER_LINE, brim, raft_area, skirt};
use crate::clip::{offset, region_from_contours, union, union_all};
use crate::gcode::{GcodeStats, LayerPlan, write_gcode};
use crate::geom::{Contour, Point, Region, bbox, region_area};
use crate::infill::{Lay, hatch_rows, lay_rows};
use crate::overhangs::SteepIndex;
use crate::paths::{Extrusion, Flow, Role, SEAM_TARGET, loop_from_seam, order_nearest};
use crate::profile::{FdmSettings, SupportStyle};
use crate::source::{Layer, Source};
use crate::supports::{SupportLayer, supports};
use crate::surfaces::{Neighbours, classify, split_solid};

use island::{Island, LayerContext, island_paths, island_walls, wall_spec};
use plate::{ARRANGE_GAP, LayerSpec, Plate, arrange, merge, slice_object};

/// Finest outline cell as a fraction of the line width: crossings are refined on the field,
/// so the cell only has to resolve features, and 1/8 of a line is far below what prints.
const CELL_PER_LINE_WIDTH: f64 = 1.0 / 8.0;

/// Support lines are this far apart, mm (PrusaSlicer's support pattern spacing, 2.5).
const SUPPORT_SPACING: f64 = 2.5;

/// The support interface's lines are this many line widths apart (dense enough to print
/// the part on, open enough to peel).
const INTERFACE_SPACING_PER_LINE: f64 = 1.5;

/// A sliced G-code job.
#[derive(Clone, Debug)]
pub struct GcodeJob {
    /// The G-code text.
    pub gcode: String,
    /// Totals.
    pub stats: GcodeStats,
    /// The first object's model-to-bed translation (x, y, z), mm.
    pub offset: [f64; 3],
    /// The layers, bed coordinates (raft layers first; `model_z` is the first object's).
    pub layers: Vec<Layer>,
    /// Raft layers at the bottom of `layers`.
    pub raft_layers: usize,
    /// Things the user should know: the print may fail as sliced.
    pub warnings: Vec<SliceWarning>,
}

/// A reason the print may fail as sliced.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SliceWarning {
    /// A part starts in mid-air: nothing printed under it.
    #[error(
        "part of the model starts in mid-air at z = {z:.2} mm (layer {layer}): nothing is \
         printed under it; turn supports on (supports = \"grid\" or \"tree\") or turn the model"
    )]
    StartsInAir {
        /// The height of the layer it starts on, mm.
        z: f64,
        /// That layer's index.
        layer: usize,
    },
}

/// Progress callback: (steps done, steps in all).
pub type Progress<'a> = &'a (dyn Fn(usize, usize) + Sync);

/// How a caller follows and stops the work: progress reports and a cancel flag.
#[derive(Clone, Copy)]
pub struct Control<'a> {
    /// Hears (steps done, steps in all) as outlines are found.
    pub progress: Progress<'a>,
    /// When set, the work stops with [`SliceError::Cancelled`].
    pub cancel: Option<&'a AtomicBool>,
}

impl<'a> Control<'a> {
    /// Progress only, never cancelled.
    pub fn new(progress: Progress<'a>) -> Control<'a> {
        Control {
            progress,
            cancel: None,
        }
    }

    /// True once the cancel flag is set.
    pub fn cancelled(&self) -> bool {
        self.cancel.is_some_and(|c| c.load(Ordering::Relaxed))
    }

    fn progress(&self, done: usize, total: usize) {
        (self.progress)(done, total);
    }

    fn check(&self) -> Result<(), SliceError> {
        if self.cancelled() {
            Err(SliceError::Cancelled)
        } else {
            Ok(())
        }
    }
}

/// Slices a model to G-code with the given settings. `progress` hears about outlines.
pub fn slice_gcode(
    source: &Source,
    s: &FdmSettings,
    progress: Progress,
) -> Result<GcodeJob, SliceError> {
    slice_plate(std::slice::from_ref(source), s, &Control::new(progress))
}

/// Slices several models (each `copies` times, arranged on the bed) into one G-code job.
pub fn slice_plate(
    sources: &[Source],
    s: &FdmSettings,
    control: &Control,
) -> Result<GcodeJob, SliceError> {
    let mut s = s.clone();
    if s.vase_mode {
        // A vase is one wall: no infill, no top, no supports.
        s.perimeters = 1;
        s.infill_density = 0.0;
        s.top_layers = 0;
        s.supports = SupportStyle::None;
    }
    let s = &s;
    let w = s.line_width;
    let spec = LayerSpec {
        first: s.first_layer_height,
        height: s.layer_height,
        cell: w * CELL_PER_LINE_WIDTH,
        steep_below: s.support_overhang_angle.to_radians().sin() as f32,
    };
    let done = AtomicUsize::new(0);
    let objects = sources
        .iter()
        .map(|src| slice_object(src, &spec, control, &done, 0))
        .collect::<Result<Vec<_>, _>>()?;
    let margin = adhesion_margin(s);
    let placements = arrange(
        &objects,
        s.copies,
        s.bed_size,
        ARRANGE_GAP + 2.0 * s.brim_width,
        margin,
    )?;
    let plate = merge(&objects, placements);
    drop(objects);
    control.check()?;
    if plate.layers.is_empty() {
        return Err(SliceError::NoLayers);
    }
    let height = plate.layers.last().map_or(0.0, |l| l.top);
    let raft_height = raft_thickness(s);
    if height + raft_height > s.max_height {
        return Err(SliceError::TallerThanPrinter {
            height: height + raft_height,
            max_height: s.max_height,
        });
    }
    let sliced = slice_layers(&plate, s, control)?;
    let (plans, warnings) = plan_layers(&plate, sliced, s, control)?;
    control.check()?;
    let raft_layers = if s.raft_layers > 0 { s.raft_layers } else { 0 };
    let (gcode, stats) = write_gcode(&plans, s);
    let mut layers: Vec<Layer> = plans
        .iter()
        .map(|p| Layer {
            top: p.top,
            height: p.height,
            model_z: f64::NAN,
        })
        .collect();
    for (l, m) in layers.iter_mut().skip(raft_layers).zip(&plate.layers) {
        l.model_z = m.model_z;
    }
    let mut offset = plate.offset;
    offset[2] += raft_height;
    Ok(GcodeJob {
        gcode,
        stats,
        offset,
        layers,
        raft_layers,
        warnings,
    })
}

/// Room kept around the arrangement for the skirt and brim, mm.
fn adhesion_margin(s: &FdmSettings) -> f64 {
    let skirt = if s.skirt_loops > 0 {
        s.skirt_distance + s.skirt_loops as f64 * s.line_width
    } else {
        0.0
    };
    let raft = if s.raft_layers > 0 {
        crate::adhesion::RAFT_MARGIN
    } else {
        0.0
    };
    s.brim_width.max(raft) + skirt
}

/// The height the raft lifts the part by, mm: its layers and the gap above them.
fn raft_thickness(s: &FdmSettings) -> f64 {
    if s.raft_layers == 0 {
        return 0.0;
    }
    s.first_layer_height + (s.raft_layers - 1) as f64 * s.layer_height + s.support_z_gap
}

/// Every layer's islands, classified, and the supports.
struct Sliced {
    regions: Vec<Region>,
    islands: Vec<Vec<Island>>,
    supports: Vec<SupportLayer>,
}

fn slice_layers(plate: &Plate, s: &FdmSettings, control: &Control) -> Result<Sliced, SliceError> {
    let n = plate.layers.len();
    let regions: Vec<Region> = plate
        .outlines
        .par_iter()
        .map(|o| region_from_contours(o))
        .collect();
    control.check()?;
    let spec = wall_spec(s);
    let mut islands: Vec<Vec<Island>> = regions
        .par_iter()
        .map(|r| {
            r.iter()
                .map(|shape| island_walls(vec![shape.clone()], &spec))
                .collect()
        })
        .collect();
    control.check()?;
    let on_bed = |l: usize| l == 0;
    let neighbours = |l: usize| Neighbours {
        above: (1..=s.top_layers.max(1))
            .map_while(|k| regions.get(l + k))
            .collect(),
        below: (1..=s.bottom_layers.max(1))
            .map_while(|k| l.checked_sub(k).and_then(|b| regions.get(b)))
            .collect(),
        on_bed: on_bed(l),
    };
    // Solid and sparse first (the layer above's classification needs the sparse below).
    let split: Vec<Vec<(Region, Region)>> = islands
        .par_iter()
        .enumerate()
        .map(|(l, isl)| {
            let nb = neighbours(l);
            isl.iter()
                .map(|i| split_solid(&i.walls.inner, &nb, s.top_layers, s.bottom_layers))
                .collect()
        })
        .collect();
    let sparse_of: Vec<Region> = split
        .par_iter()
        .map(|l| union_all(l.iter().map(|(_, sp)| sp)))
        .collect();
    control.check()?;
    islands
        .par_iter_mut()
        .zip(split)
        .enumerate()
        .for_each(|(l, (isl, sp))| {
            let nb = neighbours(l);
            let below = l.checked_sub(1).map(|b| &sparse_of[b]);
            for (i, (solid, sparse)) in isl.iter_mut().zip(sp) {
                i.surfaces = classify(&i.walls.inner, solid, sparse, &nb, below, s.line_width);
            }
        });
    control.check()?;
    let heights: Vec<f64> = plate.layers.iter().map(|l| l.height).collect();
    // Where something is printed: islands too thin for any line hold nothing up.
    let printed: Vec<Region> = islands
        .par_iter()
        .map(|isl| {
            let shapes: Vec<&Region> = isl
                .iter()
                .filter(|i| {
                    !(i.walls.loops.is_empty()
                        && i.walls.thin.is_empty()
                        && i.walls.gaps.is_empty())
                })
                .map(|i| &i.shape)
                .collect();
            union_all(shapes)
        })
        .collect();
    let supports = supports(&regions, &printed, &heights, s);
    let _ = n;
    Ok(Sliced {
        regions,
        islands,
        supports,
    })
}

/// Every layer's extrusions in print order, with what travel needs to know; and the
/// warnings found on the way.
fn plan_layers(
    plate: &Plate,
    sliced: Sliced,
    s: &FdmSettings,
    control: &Control,
) -> Result<(Vec<LayerPlan>, Vec<SliceWarning>), SliceError> {
    let w = s.line_width;
    let n = plate.layers.len();
    let raft_z = raft_thickness(s);
    let first_all = union(&sliced.regions[0], &sliced.supports[0].all());
    let raft = if s.raft_layers > 0 {
        raft_area(&first_all)
    } else {
        Vec::new()
    };
    let supported: Vec<Region> = sliced
        .regions
        .par_iter()
        .map(|r| offset(r, 0.5 * s.nozzle_diameter))
        .collect();
    let vase_from = if s.vase_mode {
        s.bottom_layers.max(1)
    } else {
        usize::MAX
    };
    let mut plans: Vec<LayerPlan> = (0..n)
        .into_par_iter()
        .map(|l| {
            let layer = &plate.layers[l];
            let steep = SteepIndex::new(&plate.steep[l], w);
            let ctx = LayerContext {
                s,
                index: l,
                mid_z: layer.top - 0.5 * layer.height,
                supported: if l == 0 {
                    None
                } else {
                    Some(&supported[l - 1])
                },
                steep: &steep,
            };
            let mut pos: Point = SEAM_TARGET;
            let mut paths = Vec::new();
            if l == 0 && s.raft_layers == 0 {
                let brim_loops = brim(&sliced.regions[0], s.brim_width, w);
                let around = if brim_loops.is_empty() {
                    first_all.clone()
                } else {
                    union(&first_all, &region_from_contours(&brim_loops))
                };
                for c in skirt(&around, s.skirt_loops, s.skirt_distance, w) {
                    paths.push(Extrusion::new(
                        Role::Skirt,
                        loop_from_seam(&c),
                        w,
                        Flow::Layer,
                    ));
                }
                for c in brim_loops {
                    paths.push(Extrusion::new(
                        Role::Brim,
                        loop_from_seam(&c),
                        w,
                        Flow::Layer,
                    ));
                }
                if let Some(end) = paths.last().and_then(Extrusion::end) {
                    pos = end;
                }
            }
            paths.extend(support_paths(&sliced.supports[l], l, s, &mut pos));
            if l >= vase_from {
                paths.extend(vase_paths(&sliced.islands[l], w));
            } else {
                let mut left: Vec<&Island> = sliced.islands[l].iter().collect();
                while !left.is_empty() {
                    let k = (0..left.len())
                        .min_by(|&a, &b| {
                            entry_distance(left[a], pos).total_cmp(&entry_distance(left[b], pos))
                        })
                        .unwrap_or(0);
                    let isl = left.swap_remove(k);
                    paths.extend(island_paths(isl, &ctx, &mut pos));
                }
            }
            let comb = comb_region(&sliced.regions[l], &sliced.supports[l], w);
            LayerPlan {
                top: layer.top + raft_z,
                height: layer.height,
                paths,
                comb,
                barriers: plate.outlines[l].clone(),
                spiral: l >= vase_from,
            }
        })
        .collect();
    control.check()?;
    let warnings = if s.supports == SupportStyle::None && s.raft_layers == 0 {
        // Lines over sparse infill are held by it across its spacing.
        let reach = if s.infill_density > 0.0 {
            (w / s.infill_density).min(AIR_REACH_MAX)
        } else {
            w
        };
        air_starts(&plans, w, reach.max(w))
    } else {
        Vec::new()
    };
    if s.raft_layers > 0 {
        let mut raft_plans = raft_layers(&raft, s);
        raft_plans.append(&mut plans);
        plans = raft_plans;
    }
    Ok((plans, warnings))
}

/// Where the island is entered: its first loop's seam, or its first line.
fn entry_distance(isl: &Island, pos: Point) -> f64 {
    let p = isl
        .walls
        .loops
        .iter()
        .max_by_key(|l| l.depth)
        .and_then(|l| loop_from_seam(&l.contour).first().copied())
        .or_else(|| {
            isl.shape
                .first()
                .and_then(|s| s.first())
                .and_then(|c| c.first().copied())
        })
        .unwrap_or(pos);
    crate::geom::dist(p, pos)
}

/// Travel needs no retraction inside this: every island shrunk by a quarter line (the
/// travel stays over printed walls) and the supports.
fn comb_region(region: &Region, support: &SupportLayer, w: f64) -> Region {
    union(&offset(region, -0.25 * w), &support.all())
}

/// A support layer's lines: the body in a grid (or lines alternating for trees), the
/// interface dense.
fn support_paths(sup: &SupportLayer, l: usize, s: &FdmSettings, pos: &mut Point) -> Vec<Extrusion> {
    let w = s.line_width;
    let mut out = Vec::new();
    if !sup.body.is_empty() {
        let angles: Vec<f64> = match s.supports {
            SupportStyle::Grid => vec![0.0, std::f64::consts::FRAC_PI_2],
            _ => vec![if l.is_multiple_of(2) {
                0.0
            } else {
                std::f64::consts::FRAC_PI_2
            }],
        };
        let mut lines = Vec::new();
        for a in angles {
            let rows = hatch_rows(&sup.body, a, SUPPORT_SPACING);
            lines.extend(
                lay_rows(&rows, &sup.body, Lay::Connected, *pos)
                    .into_iter()
                    .map(|p| Extrusion::new(Role::Support, p, w, Flow::Layer)),
            );
        }
        order_nearest(lines, pos, &mut out);
    }
    if !sup.interface.is_empty() {
        let a = if l.is_multiple_of(2) {
            std::f64::consts::FRAC_PI_4
        } else {
            3.0 * std::f64::consts::FRAC_PI_4
        };
        let rows = hatch_rows(&sup.interface, a, INTERFACE_SPACING_PER_LINE * w);
        let lines = lay_rows(&rows, &sup.interface, Lay::Connected, *pos)
            .into_iter()
            .map(|p| Extrusion::new(Role::SupportInterface, p, w, Flow::Layer))
            .collect();
        order_nearest(lines, pos, &mut out);
    }
    out
}

/// A vase layer: the outer loop of the largest island only.
fn vase_paths(islands: &[Island], w: f64) -> Vec<Extrusion> {
    islands
        .iter()
        .max_by(|a, b| region_area(&a.shape).total_cmp(&region_area(&b.shape)))
        .and_then(|isl| {
            isl.walls
                .loops
                .iter()
                .filter(|l| l.depth == 0)
                .max_by(|a, b| {
                    crate::geom::signed_area(&a.contour)
                        .total_cmp(&crate::geom::signed_area(&b.contour))
                })
        })
        .map(|l| {
            vec![Extrusion::new(
                Role::OuterWall,
                loop_from_seam(&l.contour),
                w,
                Flow::Layer,
            )]
        })
        .unwrap_or_default()
}

/// The raft's layers: a coarse base on the bed, then solid layers crossing each other.
fn raft_layers(area: &Region, s: &FdmSettings) -> Vec<LayerPlan> {
    let w = s.line_width;
    let mut out = Vec::new();
    let mut top = 0.0;
    let mut pos = SEAM_TARGET;
    for k in 0..s.raft_layers {
        let h = if k == 0 {
            s.first_layer_height
        } else {
            s.layer_height
        };
        top += h;
        let spacing = if k == 0 && s.raft_layers > 1 {
            RAFT_BASE_SPACING_PER_LINE * w
        } else {
            w
        };
        let angle = if k % 2 == 0 {
            0.0
        } else {
            std::f64::consts::FRAC_PI_2
        };
        let mut paths = Vec::new();
        if k == 0 {
            for c in skirt(area, s.skirt_loops, s.skirt_distance, w) {
                paths.push(Extrusion::new(
                    Role::Skirt,
                    loop_from_seam(&c),
                    w,
                    Flow::Layer,
                ));
            }
            if let Some(end) = paths.last().and_then(Extrusion::end) {
                pos = end;
            }
        }
        let rows = hatch_rows(area, angle, spacing);
        let lines = lay_rows(&rows, area, Lay::Connected, pos)
            .into_iter()
            .map(|p| Extrusion::new(Role::Raft, p, w, Flow::Layer))
            .collect();
        order_nearest(lines, &mut pos, &mut paths);
        out.push(LayerPlan {
            top,
            height: h,
            paths,
            comb: area.clone(),
            barriers: area.iter().flatten().cloned().collect::<Vec<Contour>>(),
            spiral: false,
        });
    }
    out
}

/// Lines are held by material this far to the side on the layer below at most, mm: sparse
/// infill leaves gaps of its spacing that the layer above bridges.
const AIR_REACH_MAX: f64 = 5.0;

/// Islands of printed lines that have nothing printed under them: each layer's lines are
/// marked on a grid of half-line cells, and a group of touching cells on layer l with no
/// marked cell within `reach` on layer l − 1 starts in mid-air.
fn air_starts(plans: &[LayerPlan], w: f64, reach: f64) -> Vec<SliceWarning> {
    let cell = 0.5 * w;
    let Some((lo, hi)) = bbox(
        plans
            .iter()
            .flat_map(|p| p.paths.iter().flat_map(|e| e.points.iter())),
    ) else {
        return Vec::new();
    };
    let nx = ((hi[0] - lo[0]) / cell) as usize + 3;
    let ny = ((hi[1] - lo[1]) / cell) as usize + 3;
    if nx.saturating_mul(ny) > 50_000_000 {
        return Vec::new();
    }
    let mark = |plan: &LayerPlan| -> Vec<bool> {
        let mut g = vec![false; nx * ny];
        for e in &plan.paths {
            if matches!(e.role, Role::Skirt) {
                continue;
            }
            for seg in e.points.windows(2) {
                let len = crate::geom::dist(seg[0], seg[1]);
                let steps = (len / (0.5 * cell)).ceil().max(1.0) as usize;
                for k in 0..=steps {
                    let t = k as f64 / steps as f64;
                    let p = [
                        seg[0][0] + t * (seg[1][0] - seg[0][0]),
                        seg[0][1] + t * (seg[1][1] - seg[0][1]),
                    ];
                    let i = ((p[0] - lo[0]) / cell) as usize + 1;
                    let j = ((p[1] - lo[1]) / cell) as usize + 1;
                    g[j * nx + i] = true;
                }
            }
        }
        g
    };
    let grids: Vec<Vec<bool>> = plans.par_iter().map(mark).collect();
    let r = (reach / cell).ceil() as usize;
    let mut out: Vec<SliceWarning> = Vec::new();
    for l in 1..grids.len() {
        let here = &grids[l];
        if !here.iter().any(|&v| v) {
            continue;
        }
        let below = dilate(&grids[l - 1], nx, ny, r);
        // Groups of touching marked cells on this layer.
        let mut seen = vec![false; nx * ny];
        for start in 0..here.len() {
            if !here[start] || seen[start] {
                continue;
            }
            let mut stack = vec![start];
            seen[start] = true;
            let mut held = false;
            while let Some(k) = stack.pop() {
                held |= below[k];
                let (i, j) = (k % nx, k / nx);
                for (di, dj) in [
                    (-1i64, -1i64),
                    (0, -1),
                    (1, -1),
                    (-1, 0),
                    (1, 0),
                    (-1, 1),
                    (0, 1),
                    (1, 1),
                ] {
                    let (a, b) = (i as i64 + di, j as i64 + dj);
                    if a < 0 || b < 0 || a as usize >= nx || b as usize >= ny {
                        continue;
                    }
                    let q = b as usize * nx + a as usize;
                    if here[q] && !seen[q] {
                        seen[q] = true;
                        stack.push(q);
                    }
                }
            }
            if !held {
                let z = plans[l].top;
                if !out
                    .iter()
                    .any(|wn| matches!(wn, SliceWarning::StartsInAir { layer, .. } if *layer == l))
                {
                    out.push(SliceWarning::StartsInAir { z, layer: l });
                }
            }
        }
    }
    out
}

/// Every cell within `r` cells (a square) of a marked one.
fn dilate(g: &[bool], nx: usize, ny: usize, r: usize) -> Vec<bool> {
    let pass = |src: &[bool], len: usize, lines: usize, at: &dyn Fn(usize, usize) -> usize| {
        let mut dst = vec![false; src.len()];
        for line in 0..lines {
            // A running count of marked cells in the window [i - r, i + r].
            let mut count = 0usize;
            for i in 0..len.min(r) {
                count += usize::from(src[at(line, i)]);
            }
            for i in 0..len {
                if i + r < len {
                    count += usize::from(src[at(line, i + r)]);
                }
                if i > r {
                    count -= usize::from(src[at(line, i - r - 1)]);
                }
                dst[at(line, i)] = count > 0;
            }
        }
        dst
    };
    let rows = pass(g, nx, ny, &|j, i| j * nx + i);
    pass(&rows, ny, nx, &|i, j| j * nx + i)
}
