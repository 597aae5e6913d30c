//! What the nozzle lays down: extrusions (polylines with a width per segment) and their
//! roles, which decide speed, fan and the `;TYPE:` a G-code reader sees.

use crate::geom::{Point, dist};

/// What an extrusion is for.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub enum Role {
    /// Loops around the first layer, to prime the nozzle.
    Skirt,
    /// Loops around the first layer's outline, touching it, for adhesion.
    Brim,
    /// The layers of a raft under the part.
    Raft,
    /// Support columns.
    Support,
    /// The dense top of a support, under the part.
    SupportInterface,
    /// The outermost loop.
    OuterWall,
    /// Loops inside the outer one.
    InnerWall,
    /// Outer wall over air, or on a surface leaning past the support angle.
    Overhang,
    /// A wall too thin for a loop, printed along its centre at its width.
    ThinWall,
    /// A gap between loops, filled along its centre at its width.
    GapFill,
    /// Lines across air, anchored on both sides.
    Bridge,
    /// The first solid layer over sparse infill, laid like a bridge.
    InternalBridge,
    /// Solid infill under a top or over a bottom.
    Skin,
    /// The visible top surface.
    TopSkin,
    /// Sparse infill.
    Fill,
    /// A nearly dry pass over the top surface that smooths it.
    Ironing,
}

impl Role {
    /// The `;TYPE:` name.
    pub fn name(self) -> &'static str {
        match self {
            Role::Skirt => "SKIRT",
            Role::Brim => "BRIM",
            Role::Raft => "RAFT",
            Role::Support => "SUPPORT",
            Role::SupportInterface => "SUPPORT-INTERFACE",
            Role::OuterWall => "WALL-OUTER",
            Role::InnerWall => "WALL-INNER",
            Role::Overhang => "OVERHANG",
            Role::ThinWall => "THIN-WALL",
            Role::GapFill => "GAP-FILL",
            Role::Bridge => "BRIDGE",
            Role::InternalBridge => "INTERNAL-BRIDGE",
            Role::Skin => "SKIN",
            Role::TopSkin => "TOP-SKIN",
            Role::Fill => "FILL",
            Role::Ironing => "IRONING",
        }
    }

    /// Every role, for tables and legends.
    pub const ALL: [Role; 16] = [
        Role::Skirt,
        Role::Brim,
        Role::Raft,
        Role::Support,
        Role::SupportInterface,
        Role::OuterWall,
        Role::InnerWall,
        Role::Overhang,
        Role::ThinWall,
        Role::GapFill,
        Role::Bridge,
        Role::InternalBridge,
        Role::Skin,
        Role::TopSkin,
        Role::Fill,
        Role::Ironing,
    ];

    /// Printed over air: bridge speed and the bridge fan.
    pub fn over_air(self) -> bool {
        matches!(self, Role::Bridge | Role::InternalBridge | Role::Overhang)
    }
}

/// The shape of a line's cross-section, which sets the filament it takes per mm.
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum Flow {
    /// A flat bead as thick as the layer: width × layer height.
    Layer,
    /// A round strand as wide as its width (bridges hang in air): π/4 × width².
    Round,
    /// A flat bead at a fraction of the full flow (ironing).
    Scaled(f64),
}

/// One extrusion: a polyline (closed loops repeat their first point at the end) with the
/// width of each segment.
#[derive(Clone, Debug, PartialEq)]
pub struct Extrusion {
    /// Its role.
    pub role: Role,
    /// The points in print order.
    pub points: Vec<Point>,
    /// The width of each segment, mm (one fewer than the points).
    pub widths: Vec<f64>,
    /// Its cross-section.
    pub flow: Flow,
}

impl Extrusion {
    /// A line of one width.
    pub fn new(role: Role, points: Vec<Point>, width: f64, flow: Flow) -> Extrusion {
        let widths = vec![width; points.len().saturating_sub(1)];
        Extrusion {
            role,
            points,
            widths,
            flow,
        }
    }

    /// True when it ends where it starts.
    pub fn closed(&self) -> bool {
        self.points.len() > 2 && self.points.first() == self.points.last()
    }

    /// The same line printed the other way.
    pub fn reverse(&mut self) {
        self.points.reverse();
        self.widths.reverse();
    }

    /// Its length, mm.
    pub fn length(&self) -> f64 {
        self.points.windows(2).map(|w| dist(w[0], w[1])).sum()
    }

    /// Its first point.
    pub fn start(&self) -> Option<Point> {
        self.points.first().copied()
    }

    /// Its last point.
    pub fn end(&self) -> Option<Point> {
        self.points.last().copied()
    }
}

/// The seam target: far behind the bed's back edge, so the rear-most point of each loop wins.
pub const SEAM_TARGET: Point = [0.0, 1.0e6];

/// A closed contour as a path starting at its seam (the vertex nearest `SEAM_TARGET`,
/// ties to the left), repeating its first point at the end.
pub fn loop_from_seam(c: &[Point]) -> Vec<Point> {
    let Some(start) = (0..c.len()).min_by(|&a, &b| {
        dist(c[a], SEAM_TARGET)
            .total_cmp(&dist(c[b], SEAM_TARGET))
            .then(c[a][0].total_cmp(&c[b][0]))
    }) else {
        return Vec::new();
    };
    let mut p: Vec<Point> = c[start..].iter().chain(&c[..start]).copied().collect();
    p.push(c[start]);
    p
}

/// Orders extrusions greedily from `pos`: each next one is the one that starts (or, when
/// it may be reversed, ends) nearest; closed ones are entered at their start. `pos` ends
/// where the last one ends.
pub fn order_nearest(mut items: Vec<Extrusion>, pos: &mut Point, out: &mut Vec<Extrusion>) {
    while !items.is_empty() {
        let mut best = (f64::INFINITY, 0, false);
        for (k, e) in items.iter().enumerate() {
            let (Some(a), Some(b)) = (e.start(), e.end()) else {
                continue;
            };
            let da = dist(*pos, a);
            if da < best.0 {
                best = (da, k, false);
            }
            if !e.closed() {
                let db = dist(*pos, b);
                if db < best.0 {
                    best = (db, k, true);
                }
            }
        }
        let mut e = items.swap_remove(best.1);
        if best.2 {
            e.reverse();
        }
        if let Some(end) = e.end() {
            *pos = end;
        }
        out.push(e);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seam_is_the_rear_most_point() {
        let c = vec![
            [0.0, 0.0],
            [10.0, 0.0],
            [10.0, 10.0],
            [5.0, 12.0],
            [0.0, 10.0],
        ];
        let p = loop_from_seam(&c);
        assert_eq!(p[0], [5.0, 12.0]);
        assert_eq!(p.last(), Some(&[5.0, 12.0]));
        assert_eq!(p.len(), 6);
    }

    #[test]
    fn lines_are_ordered_nearest_first_and_flipped() {
        let lines = vec![
            Extrusion::new(Role::Fill, vec![[10.0, 0.0], [20.0, 0.0]], 0.4, Flow::Layer),
            Extrusion::new(Role::Fill, vec![[0.0, 1.0], [9.0, 1.0]], 0.4, Flow::Layer),
        ];
        let mut pos = [0.0, 0.0];
        let mut out = Vec::new();
        order_nearest(lines, &mut pos, &mut out);
        assert_eq!(out[0].points[0], [0.0, 1.0]);
        assert_eq!(out[1].points[0], [10.0, 0.0]);
        assert_eq!(pos, [20.0, 0.0]);
    }
}
