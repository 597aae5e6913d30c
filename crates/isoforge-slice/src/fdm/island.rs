//! One island of one layer, from its outline to its extrusions in print order: walls
//! (inner loops, then the outer loop with its overhanging stretches marked), thin walls
//! and gap fill, then sparse infill, skin, bridges, the top surface and ironing.

use crate::clip::{difference, opening};
use crate::geom::{Point, Region, polyline_length, region_area};
use crate::infill::{Lay, gyroid, gyroid_period, hatch_rows, lay_rows};
use crate::overhangs::{SteepIndex, split_wall};
use crate::paths::{Extrusion, Flow, Role, loop_from_seam, order_nearest};
use crate::profile::{FdmSettings, InfillPattern, TopFillPattern};
use crate::surfaces::Surfaces;
use crate::walls::{Bead, WallSpec, Walls, thin_beads};

/// Ironing lines are this far apart, mm (PrusaSlicer's default ironing spacing).
const IRONING_SPACING: f64 = 0.1;

/// Ironing pushes this share of the volume that would fill its spacing at full flow
/// (PrusaSlicer's default ironing flow rate, 15%).
const IRONING_FLOW: f64 = 0.15;

/// Sparse infill is laid again with corrected spacing when its joins put it off the
/// asked density by more than this share.
const DENSITY_TOLERANCE: f64 = 0.02;

/// One island: its outline, walls and surfaces.
#[derive(Clone, Debug, Default)]
pub struct Island {
    /// The island's region (one outer contour and its holes).
    pub shape: Region,
    /// Its walls.
    pub walls: Walls,
    /// Its inside, classified.
    pub surfaces: Surfaces,
}

/// What an island's layer needs to know to lay its lines.
pub struct LayerContext<'a> {
    /// The settings.
    pub s: &'a FdmSettings,
    /// The layer's index among the model's layers.
    pub index: usize,
    /// The middle of the layer above the bed, mm (gyroid phase).
    pub mid_z: f64,
    /// The layer below grown by half a nozzle (`None` on the bed or a raft).
    pub supported: Option<&'a Region>,
    /// Steep outline points of this layer.
    pub steep: &'a SteepIndex,
}

impl LayerContext<'_> {
    /// The angle of this layer's lines: 45° and 135° alternate so each layer crosses the
    /// one below.
    pub fn angle(&self) -> f64 {
        if self.index.is_multiple_of(2) {
            std::f64::consts::FRAC_PI_4
        } else {
            3.0 * std::f64::consts::FRAC_PI_4
        }
    }

    /// A bridge strand's diameter: a nozzle-wide strand at the bridge flow ratio.
    pub fn bridge_width(&self) -> f64 {
        self.s.nozzle_diameter * self.s.bridge_flow.sqrt()
    }

    fn wall_spec(&self) -> WallSpec {
        WallSpec {
            count: self.s.perimeters,
            width: self.s.line_width,
            nozzle: self.s.nozzle_diameter,
            thin_walls: self.s.thin_walls,
            gap_fill: self.s.gap_fill,
        }
    }
}

/// An island's walls (the first, parallel stage: no neighbour needed).
pub fn island_walls(shape: Region, ctx_spec: &WallSpec) -> Island {
    let walls = crate::walls::walls(&shape, ctx_spec);
    Island {
        shape,
        walls,
        surfaces: Surfaces::default(),
    }
}

/// The wall spec of a layer.
pub fn wall_spec(s: &FdmSettings) -> WallSpec {
    WallSpec {
        count: s.perimeters,
        width: s.line_width,
        nozzle: s.nozzle_diameter,
        thin_walls: s.thin_walls,
        gap_fill: s.gap_fill,
    }
}

fn bead(role: Role, b: Bead) -> Extrusion {
    Extrusion {
        role,
        points: b.points,
        widths: b.widths,
        flow: Flow::Layer,
    }
}

/// The island's extrusions in print order, starting from `pos` (moved to the end).
pub fn island_paths(isl: &Island, ctx: &LayerContext, pos: &mut Point) -> Vec<Extrusion> {
    let s = ctx.s;
    let w = s.line_width;
    let mut out = Vec::new();
    // Walls from the inside out: the outer wall last, so it is laid against the inner one.
    let max_depth = isl.walls.loops.iter().map(|l| l.depth).max();
    if let Some(max_depth) = max_depth {
        for depth in (0..=max_depth).rev() {
            let mut loops: Vec<Extrusion> = isl
                .walls
                .loops
                .iter()
                .filter(|l| l.depth == depth)
                .map(|l| {
                    let role = if depth == 0 {
                        Role::OuterWall
                    } else {
                        Role::InnerWall
                    };
                    Extrusion::new(role, loop_from_seam(&l.contour), w, Flow::Layer)
                })
                .collect();
            let mut ordered = Vec::new();
            order_nearest(std::mem::take(&mut loops), pos, &mut ordered);
            for e in ordered {
                if depth == 0 && ctx.index > 0 {
                    out.extend(split_outer(e, ctx));
                } else {
                    out.push(e);
                }
            }
        }
    }
    let beads: Vec<Extrusion> = isl
        .walls
        .thin
        .iter()
        .map(|b| bead(Role::ThinWall, b.clone()))
        .chain(
            isl.walls
                .gaps
                .iter()
                .map(|b| bead(Role::GapFill, b.clone())),
        )
        .collect();
    order_nearest(beads, pos, &mut out);

    let sf = &isl.surfaces;
    let angle = ctx.angle();
    // Sparse infill.
    let fill = sparse_lines(&sf.sparse, ctx, *pos);
    order_nearest(fill, pos, &mut out);
    // Solid skin: thin stretches along their centre, the rest in joined lines.
    let skin = solid_lines(&sf.skin, Role::Skin, w, angle, Lay::Connected, ctx, *pos);
    order_nearest(skin, pos, &mut out);
    // Bridges: round strands across the gap, anchored at both ends.
    let bw = ctx.bridge_width();
    if !sf.internal_bridge.is_empty() {
        let rows = hatch_rows(&sf.internal_bridge, angle, bw);
        let lines = lay(
            Role::InternalBridge,
            lay_rows(&rows, &sf.internal_bridge, Lay::Connected, *pos),
            bw,
            Flow::Round,
        );
        order_nearest(lines, pos, &mut out);
    }
    for (area, bangle) in &sf.bridges {
        let rows = hatch_rows(area, *bangle, bw);
        let lines = lay(
            Role::Bridge,
            lay_rows(&rows, area, Lay::Connected, *pos),
            bw,
            Flow::Round,
        );
        order_nearest(lines, pos, &mut out);
    }
    // The top surface, narrower and slower, and monotonic if asked.
    let lay_top = match s.top_fill_pattern {
        TopFillPattern::Monotonic => Lay::Monotonic,
        TopFillPattern::Rectilinear => Lay::Connected,
    };
    let tw = s.top_infill_extrusion_width;
    let top = solid_lines(&sf.top, Role::TopSkin, tw, angle, lay_top, ctx, *pos);
    // Monotonic lines keep their order: only whole paths are reordered.
    if lay_top == Lay::Monotonic {
        for e in top {
            if let Some(end) = e.end() {
                *pos = end;
            }
            out.push(e);
        }
    } else {
        order_nearest(top, pos, &mut out);
    }
    if s.ironing && !sf.top.is_empty() {
        let area = crate::clip::offset(&sf.top, -0.5 * tw);
        let rows = hatch_rows(&area, angle + std::f64::consts::FRAC_PI_4, IRONING_SPACING);
        let lines = lay(
            Role::Ironing,
            lay_rows(&rows, &area, Lay::Connected, *pos),
            IRONING_SPACING,
            Flow::Scaled(IRONING_FLOW),
        );
        order_nearest(lines, pos, &mut out);
    }
    out
}

/// Lines of one role, width and flow.
fn lay(role: Role, lines: Vec<Vec<Point>>, width: f64, flow: Flow) -> Vec<Extrusion> {
    lines
        .into_iter()
        .filter(|l| l.len() >= 2)
        .map(|l| Extrusion::new(role, l, width, flow))
        .collect()
}

/// The outer wall split into its overhanging and supported stretches.
fn split_outer(e: Extrusion, ctx: &LayerContext) -> Vec<Extrusion> {
    let width = e.widths.first().copied().unwrap_or(ctx.s.line_width);
    split_wall(&e.points, ctx.supported, ctx.steep)
        .into_iter()
        .map(|(hangs, pts)| {
            let role = if hangs {
                Role::Overhang
            } else {
                Role::OuterWall
            };
            Extrusion::new(role, pts, width, Flow::Layer)
        })
        .collect()
}

/// Solid lines over `region`: parts narrower than two lines along their centre at their
/// width (no dabs on sloped surfaces, no crescents against round walls), the rest hatched
/// `width` apart and joined.
fn solid_lines(
    region: &Region,
    role: Role,
    width: f64,
    angle: f64,
    how: Lay,
    ctx: &LayerContext,
    pos: Point,
) -> Vec<Extrusion> {
    if region.is_empty() {
        return Vec::new();
    }
    let thick = opening(region, width);
    let mut out = Vec::new();
    if ctx.s.gap_fill && region_area(region) - region_area(&thick) > 1e-6 {
        let thin = difference(region, &thick);
        let spec = WallSpec {
            width,
            ..ctx.wall_spec()
        };
        out.extend(thin_beads(&thin, &spec).into_iter().map(|b| bead(role, b)));
    }
    let rows = hatch_rows(&thick, angle, width);
    out.extend(lay(
        role,
        lay_rows(&rows, &thick, how, pos),
        width,
        Flow::Layer,
    ));
    out
}

/// Sparse infill lines at the profile's density and pattern.
fn sparse_lines(region: &Region, ctx: &LayerContext, pos: Point) -> Vec<Extrusion> {
    let s = ctx.s;
    let w = s.line_width;
    if region.is_empty() || s.infill_density <= 0.0 {
        return Vec::new();
    }
    let angle = ctx.angle();
    if s.infill_density >= 1.0 {
        let rows = hatch_rows(region, angle, w);
        return lay(
            Role::Fill,
            lay_rows(&rows, region, Lay::Connected, pos),
            w,
            Flow::Layer,
        );
    }
    let lines = match s.infill_pattern {
        InfillPattern::Gyroid => gyroid(region, ctx.mid_z, gyroid_period(s.infill_density, w)),
        pattern => {
            let angles: &[f64] = match pattern {
                InfillPattern::Grid => &[
                    std::f64::consts::FRAC_PI_4,
                    3.0 * std::f64::consts::FRAC_PI_4,
                ],
                _ => std::slice::from_ref(&angle),
            };
            let per_direction = s.infill_density / angles.len() as f64;
            let target = per_direction * region_area(region) / w;
            let mut lines = Vec::new();
            for &a in angles {
                let mut spacing = w / per_direction;
                let mut laid =
                    lay_rows(&hatch_rows(region, a, spacing), region, Lay::Connected, pos);
                // Joins add length: space the lines out so the total keeps the density.
                let got: f64 = laid.iter().map(|l| polyline_length(l)).sum();
                if target > 0.0 && (got / target - 1.0).abs() > DENSITY_TOLERANCE {
                    spacing *= got / target;
                    laid = lay_rows(&hatch_rows(region, a, spacing), region, Lay::Connected, pos);
                }
                lines.extend(laid);
            }
            lines
        }
    };
    lay(Role::Fill, lines, w, Flow::Layer)
}
