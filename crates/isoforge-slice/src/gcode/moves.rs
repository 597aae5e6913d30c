//! A layer's extrusions turned into machine moves: travel (combed inside the part, or
//! retracted, wiped and lifted), extrusion at each role's speed and flow, a spiral rise
//! for vase layers, and the retraction that ends every layer before Z moves.

use crate::geom::{Point, dist, segments_cross};
use crate::paths::{Extrusion, Flow, Role};
use crate::profile::FdmSettings;

use super::LayerPlan;
use super::planner::Block;
use super::travel::Comb;

/// The nozzle wipes back along the path it just printed for this far while it retracts, mm.
const WIPE_DISTANCE: f64 = 1.0;

/// Combed routes are simplified within this, mm (they run a quarter line inside the part).
const ROUTE_TOLERANCE: f64 = 0.05;

/// What a machine move does.
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum Kind {
    /// Travel in x and y.
    Travel,
    /// Extrusion of a role at a width (for the reader's benefit).
    Extrude(Role, f64),
    /// Filament pulled back, without motion.
    Retract,
    /// Filament pushed again, without motion.
    Unretract,
    /// Moving back along the path while retracting.
    Wipe,
    /// A Z move: layer change, lift or lower.
    Z,
}

/// One step of a layer's G-code.
#[derive(Clone, Debug, PartialEq)]
pub enum Op {
    /// A move to (x, y, z) pushing `de` mm of filament (negative: pulling), at `feed` mm/s.
    Move {
        /// Where to.
        to: [f64; 3],
        /// Filament, mm.
        de: f64,
        /// Speed, mm/s.
        feed: f64,
        /// What it is.
        kind: Kind,
    },
    /// The feature that follows (`;TYPE:`).
    Feature(Role),
    /// The part fan, 0 to 1.
    Fan(f64),
    /// A wait, s.
    Dwell(f64),
}

/// The state moves carry from one to the next.
pub struct Head {
    /// Where the nozzle is.
    pub at: [f64; 3],
    /// True while the filament is pulled back.
    pub retracted: bool,
}

/// Builds one layer's moves from where the head is; the layer ends retracted.
pub fn layer_ops(plan: &LayerPlan, index: usize, s: &FdmSettings, head: &mut Head) -> Vec<Op> {
    let mut b = Builder {
        s,
        ops: Vec::with_capacity(plan.paths.iter().map(|p| p.points.len() + 4).sum()),
        head,
        comb: if s.combing {
            Some(Comb::new(&plan.comb))
        } else {
            None
        },
        plan,
        first_layer: index == 0,
        last: None,
        role: None,
    };
    if !plan.spiral {
        let z = plan.top;
        b.z_move(z);
    }
    let mut along = 0.0;
    let total: f64 = plan.paths.iter().map(Extrusion::length).sum();
    for (k, path) in plan.paths.iter().enumerate() {
        b.extrude(path, &mut along, total);
        b.last = Some(k);
    }
    b.retract(true);
    b.ops
}

struct Builder<'a> {
    s: &'a FdmSettings,
    ops: Vec<Op>,
    head: &'a mut Head,
    comb: Option<Comb<'a>>,
    plan: &'a LayerPlan,
    first_layer: bool,
    /// The last path extruded (wipes go back along it).
    last: Option<usize>,
    role: Option<Role>,
}

impl Builder<'_> {
    fn push_move(&mut self, to: [f64; 3], de: f64, feed: f64, kind: Kind) {
        self.ops.push(Op::Move { to, de, feed, kind });
        self.head.at = to;
    }

    fn z_move(&mut self, z: f64) {
        let at = self.head.at;
        if (at[2] - z).abs() > 1e-9 {
            let feed = self.s.machine_max_feedrate_z.min(self.s.travel_speed);
            self.push_move([at[0], at[1], z], 0.0, feed, Kind::Z);
        }
    }

    /// Pulls the filament back (wiping back along the last path if asked and possible).
    fn retract(&mut self, wipe: bool) {
        let s = self.s;
        if self.head.retracted || s.retract_length <= 0.0 {
            return;
        }
        self.head.retracted = true;
        let mut left = s.retract_length;
        if wipe
            && s.wipe
            && let Some(path) = self.last.and_then(|k| self.plan.paths.get(k))
        {
            let pts: Vec<Point> = path.points.iter().rev().copied().collect();
            let mut walked = 0.0;
            let z = self.head.at[2];
            let mut from = [self.head.at[0], self.head.at[1]];
            for &p in pts.iter().skip(1) {
                if walked >= WIPE_DISTANCE {
                    break;
                }
                let d = dist(from, p);
                if d < 1e-9 {
                    continue;
                }
                let take = d.min(WIPE_DISTANCE - walked);
                let to = [
                    from[0] + (p[0] - from[0]) * take / d,
                    from[1] + (p[1] - from[1]) * take / d,
                ];
                let de = s.retract_length * take / WIPE_DISTANCE;
                // Keep the extruder within its retraction speed.
                let feed = s.travel_speed.min(s.retract_speed * take / de.max(1e-9));
                self.push_move([to[0], to[1], z], -de, feed, Kind::Wipe);
                left -= de;
                walked += take;
                from = to;
            }
        }
        if left > 1e-9 {
            let at = self.head.at;
            self.push_move(at, -left, s.retract_speed, Kind::Retract);
        }
    }

    fn unretract(&mut self) {
        if !self.head.retracted {
            return;
        }
        self.head.retracted = false;
        let at = self.head.at;
        self.push_move(
            at,
            self.s.retract_length,
            self.s.retract_speed,
            Kind::Unretract,
        );
    }

    /// Travels to `to`: along a combed route without retracting when one exists, else
    /// retracted (and lifted by z_hop) on a straight line.
    fn travel(&mut self, to: Point, z: f64) {
        let from = [self.head.at[0], self.head.at[1]];
        let d = dist(from, to);
        if d < 1e-9 && (self.head.at[2] - z).abs() < 1e-9 {
            return;
        }
        let s = self.s;
        let v = s.travel_speed;
        if !self.head.retracted {
            let route = self.comb.as_ref().and_then(|c| c.route(from, to));
            if let Some(route) = route {
                // The route hugs contours that offsets made dense: keep its shape to a
                // twentieth of a millimetre (it runs a quarter line inside the part).
                let mut full = vec![from];
                full.extend(route);
                let keep = crate::geom::simplify_open(&full, ROUTE_TOLERANCE);
                for &i in keep.iter().skip(1) {
                    let p = full[i];
                    if dist(p, [self.head.at[0], self.head.at[1]]) > 1e-6
                        || (self.head.at[2] - z).abs() > 1e-9
                    {
                        self.push_move([p[0], p[1], z], 0.0, v, Kind::Travel);
                    }
                }
                return;
            }
            let short = d <= s.retract_min_travel && !crosses(from, to, &self.plan.barriers);
            if short {
                self.push_move([to[0], to[1], z], 0.0, v, Kind::Travel);
                return;
            }
            self.retract(true);
        }
        if s.z_hop > 0.0 && d > 1e-9 {
            let at = self.head.at;
            self.push_move(
                [at[0], at[1], at[2] + s.z_hop],
                0.0,
                s.machine_max_feedrate_z.min(v),
                Kind::Z,
            );
            let at = self.head.at;
            self.push_move([to[0], to[1], at[2]], 0.0, v, Kind::Travel);
            self.z_move(z);
        } else {
            self.push_move([to[0], to[1], z], 0.0, v, Kind::Travel);
        }
    }

    fn extrude(&mut self, path: &Extrusion, along: &mut f64, total: f64) {
        let Some(&first) = path.points.first() else {
            return;
        };
        let s = self.s;
        let plan = self.plan;
        // A vase layer rises by its height over the whole layer.
        let z_at = |along: f64| {
            if plan.spiral && total > 0.0 {
                plan.top - plan.height + plan.height * (along / total).min(1.0)
            } else {
                plan.top
            }
        };
        self.travel(first, z_at(*along));
        if self.role != Some(path.role) {
            self.ops.push(Op::Feature(path.role));
            self.role = Some(path.role);
        }
        self.unretract();
        let feed = speed(path.role, s, self.first_layer);
        let area_per_width = |w: f64| match path.flow {
            Flow::Layer => w * plan.height,
            Flow::Round => std::f64::consts::FRAC_PI_4 * w * w,
            Flow::Scaled(f) => f * w * plan.height,
        };
        let filament = s.filament_area();
        for (seg, &width) in path.points.windows(2).zip(&path.widths) {
            let d = dist(seg[0], seg[1]);
            if d < 1e-6 {
                continue;
            }
            *along += d;
            let de = d * area_per_width(width) / filament;
            self.push_move(
                [seg[1][0], seg[1][1], z_at(*along)],
                de,
                feed,
                Kind::Extrude(path.role, width),
            );
        }
    }
}

/// The speed of a role, mm/s (the first layer at most at the first layer speed).
pub fn speed(role: Role, s: &FdmSettings, first_layer: bool) -> f64 {
    let v = match role {
        Role::Skirt | Role::Brim | Role::Raft => s.first_layer_speed,
        Role::OuterWall => s.external_perimeter_speed,
        Role::InnerWall | Role::Fill | Role::Skin => s.print_speed,
        Role::Overhang | Role::Bridge | Role::InternalBridge => s.bridge_speed,
        Role::ThinWall | Role::GapFill => s.gap_fill_speed,
        Role::TopSkin => s.top_solid_infill_speed,
        Role::Support | Role::SupportInterface => s.support_material_speed,
        Role::Ironing => s.ironing_speed,
    };
    if first_layer {
        v.min(s.first_layer_speed)
    } else {
        v
    }
}

/// True when the travel `a`-`b` crosses an edge of any contour.
fn crosses(a: Point, b: Point, barriers: &[crate::geom::Contour]) -> bool {
    let (lo, hi) = (
        [a[0].min(b[0]), a[1].min(b[1])],
        [a[0].max(b[0]), a[1].max(b[1])],
    );
    barriers.iter().any(|c| {
        let n = c.len();
        (0..n).any(|i| {
            let (p, q) = (c[i], c[(i + 1) % n]);
            if p[0].max(q[0]) < lo[0]
                || p[0].min(q[0]) > hi[0]
                || p[1].max(q[1]) < lo[1]
                || p[1].min(q[1]) > hi[1]
            {
                return false;
            }
            segments_cross(a, b, p, q)
        })
    })
}

/// The planner's blocks for a run of ops starting at `from` (markers and fan changes take
/// no time and are left out), each with whether it extrudes.
pub fn blocks(ops: &[Op], from: [f64; 3], s: &FdmSettings) -> Vec<(Block, bool)> {
    let mut at = from;
    let mut out = Vec::with_capacity(ops.len());
    for op in ops {
        match op {
            Op::Move { to, de, feed, kind } => {
                let d = [to[0] - at[0], to[1] - at[1], to[2] - at[2]];
                let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                at = *to;
                let accel = match kind {
                    Kind::Travel | Kind::Z => s.machine_max_acceleration_travel,
                    _ => s.machine_max_acceleration_extruding,
                };
                let (length, dir) = if len < 1e-9 {
                    (de.abs(), None)
                } else {
                    (len, Some([d[0] / len, d[1] / len, d[2] / len]))
                };
                let block = Block {
                    length,
                    speed: *feed,
                    accel,
                    dir,
                    pause: 0.0,
                };
                out.push((block, matches!(kind, Kind::Extrude(..))));
            }
            Op::Dwell(t) => out.push((
                Block {
                    length: 0.0,
                    speed: 1.0,
                    accel: 1.0,
                    dir: None,
                    pause: *t,
                },
                false,
            )),
            Op::Feature(_) | Op::Fan(_) => {}
        }
    }
    out
}
