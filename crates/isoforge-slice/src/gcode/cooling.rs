//! Cooling: a layer that would print faster than the minimum layer time is slowed down
//! (never below the slowest speed allowed), and when that is not enough the head lifts
//! off the part and waits; the part fan runs by layer time (full on short layers, the
//! minimum on long ones), ramps up over the first layers, and runs at the bridge fan
//! speed while bridges and overhangs print.

use crate::paths::Role;
use crate::profile::FdmSettings;

use super::moves::{Kind, Op, blocks};
use super::planner::{Limits, block_times};

/// Cooling aims this share above the minimum layer time, so rounding in the file (feed
/// rates in whole mm/min, waits in whole ms) cannot take a layer under it.
const COOLING_MARGIN: f64 = 0.01;

/// The head lifts this far off the part while it waits for a layer to cool, mm.
const DWELL_LIFT: f64 = 2.0;

/// The time a layer's moves take, and the part of it spent extruding, s.
pub fn layer_time(ops: &[Op], from: [f64; 3], s: &FdmSettings) -> (f64, f64) {
    let bl = blocks(ops, from, s);
    let limits = Limits {
        junction_deviation: s.junction_deviation,
    };
    let times = block_times(&bl.iter().map(|b| b.0).collect::<Vec<_>>(), limits);
    let total = times.iter().sum();
    let extruding = times
        .iter()
        .zip(&bl)
        .filter(|(_, b)| b.1)
        .map(|(t, _)| t)
        .sum();
    (total, extruding)
}

/// The time a layer's moves take at the speeds asked, as if the head accelerated at once,
/// and the part of it spent extruding, s. A printer can only take longer, so a layer held
/// to the minimum layer time by this clock is held to it on every printer and by every
/// reader of the file.
pub fn feed_time(ops: &[Op], from: [f64; 3]) -> (f64, f64) {
    let mut at = from;
    let (mut total, mut extruding) = (0.0, 0.0);
    for op in ops {
        match op {
            Op::Move { to, de, feed, kind } => {
                let d =
                    ((to[0] - at[0]).powi(2) + (to[1] - at[1]).powi(2) + (to[2] - at[2]).powi(2))
                        .sqrt();
                at = *to;
                if *feed > 0.0 {
                    let t = d.max(de.abs()) / feed;
                    total += t;
                    if matches!(kind, Kind::Extrude(..)) {
                        extruding += t;
                    }
                }
            }
            Op::Dwell(t) => total += t,
            Op::Feature(_) | Op::Fan(_) => {}
        }
    }
    (total, extruding)
}

/// Slows the layer down to the minimum layer time, adds a lifted wait if slowing is not
/// enough, and sets the fan. Returns the layer's time as Marlin's planner takes it, s.
pub fn cool_layer(ops: &mut Vec<Op>, from: [f64; 3], index: usize, s: &FdmSettings) -> f64 {
    let (t0, _) = feed_time(ops, from);
    // Aim a little above the minimum: the file rounds feed rates to mm/min and waits to ms.
    let target = s.min_layer_time * (1.0 + COOLING_MARGIN);
    if s.min_layer_time > 0.0 && t0 < target {
        for _ in 0..4 {
            let (total, extruding) = feed_time(ops, from);
            let other = total - extruding;
            let want = target - other;
            if total >= target || extruding <= 0.0 || want <= extruding {
                break;
            }
            let factor = extruding / want;
            let mut changed = false;
            for op in ops.iter_mut() {
                if let Op::Move {
                    feed,
                    kind: Kind::Extrude(..),
                    ..
                } = op
                {
                    let slower = (*feed * factor).max(s.slowdown_min_speed).min(*feed);
                    if slower < *feed - 1e-9 {
                        *feed = slower;
                        changed = true;
                    }
                }
            }
            if !changed {
                break;
            }
        }
        let t = feed_time(ops, from).0;
        if t < target {
            let at = last_position(ops).unwrap_or(from);
            let lift = (at[2] + DWELL_LIFT).min(s.max_height);
            let z_feed = s.machine_max_feedrate_z.min(s.travel_speed);
            if lift > at[2] {
                ops.push(Op::Move {
                    to: [at[0], at[1], lift],
                    de: 0.0,
                    feed: z_feed,
                    kind: Kind::Z,
                });
            }
            let lifted = feed_time(ops, from).0;
            ops.push(Op::Dwell((target - lifted).max(0.0)));
        }
    }
    set_fan(ops, t0, index, s);
    layer_time(ops, from, s).0
}

/// Where the last move of `ops` ends.
fn last_position(ops: &[Op]) -> Option<[f64; 3]> {
    ops.iter().rev().find_map(|op| match op {
        Op::Move { to, .. } => Some(*to),
        _ => None,
    })
}

/// The fan for a layer that takes `t` s, before the ramp of the first layers.
fn fan_for_time(t: f64, s: &FdmSettings) -> f64 {
    let (full, least) = (s.fan_speed, s.min_fan_speed.min(s.fan_speed));
    if t <= s.min_layer_time || s.fan_below_layer_time <= s.min_layer_time {
        if t < s.fan_below_layer_time {
            full
        } else {
            least
        }
    } else if t < s.fan_below_layer_time {
        let k = (t - s.min_layer_time) / (s.fan_below_layer_time - s.min_layer_time);
        full + (least - full) * k
    } else {
        least
    }
}

/// The fan over the first layers: off on the first, rising to full over
/// `fan_first_layers`.
fn ramp(index: usize, s: &FdmSettings) -> f64 {
    if s.fan_first_layers == 0 || index >= s.fan_first_layers {
        1.0
    } else {
        index as f64 / s.fan_first_layers as f64
    }
}

/// Inserts fan changes: the layer's fan at its start, the bridge fan around bridges and
/// overhangs.
fn set_fan(ops: &mut Vec<Op>, t: f64, index: usize, s: &FdmSettings) {
    let base = fan_for_time(t, s) * ramp(index, s);
    let bridge = if index == 0 {
        base
    } else {
        base.max(s.bridge_fan_speed)
    };
    let mut out = Vec::with_capacity(ops.len() + 8);
    out.push(Op::Fan(base));
    let mut current = base;
    for op in ops.drain(..) {
        if let Op::Feature(role) = op {
            let want = if role_over_air(role) { bridge } else { base };
            if (want - current).abs() > 1e-9 {
                out.push(Op::Fan(want));
                current = want;
            }
        }
        out.push(op);
    }
    *ops = out;
}

fn role_over_air(role: Role) -> bool {
    role.over_air()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::profile::Profile;

    fn s() -> FdmSettings {
        Profile::default_fdm().fdm().unwrap()
    }

    /// A small square, 4 mm a side, at 50 mm/s: well under a second.
    fn square() -> Vec<Op> {
        let pts = [[4.0, 0.0], [4.0, 4.0], [0.0, 4.0], [0.0, 0.0]];
        let mut ops = vec![Op::Feature(Role::OuterWall)];
        for p in pts {
            ops.push(Op::Move {
                to: [p[0], p[1], 0.4],
                de: 0.1,
                feed: 50.0,
                kind: Kind::Extrude(Role::OuterWall, 0.45),
            });
        }
        ops
    }

    #[test]
    fn a_short_layer_is_slowed_then_waits_out_the_minimum() {
        let s = s();
        let mut ops = square();
        let t = cool_layer(&mut ops, [0.0, 0.0, 0.4], 5, &s);
        assert!(t >= s.min_layer_time - 1e-3, "{t}");
        let slowest = ops
            .iter()
            .filter_map(|o| match o {
                Op::Move {
                    feed,
                    kind: Kind::Extrude(..),
                    ..
                } => Some(*feed),
                _ => None,
            })
            .fold(f64::INFINITY, f64::min);
        assert!((slowest - s.slowdown_min_speed).abs() < 1e-9, "{slowest}");
        assert!(ops.iter().any(|o| matches!(o, Op::Dwell(_))));
        // Short layers get the full fan.
        assert_eq!(ops.first(), Some(&Op::Fan(s.fan_speed)));
    }

    #[test]
    fn the_fan_ramps_over_the_first_layers() {
        let mut s = s();
        s.fan_first_layers = 2;
        let mut ops = square();
        cool_layer(&mut ops, [0.0; 3], 0, &s);
        assert_eq!(ops.first(), Some(&Op::Fan(0.0)));
        let mut ops = square();
        cool_layer(&mut ops, [0.0; 3], 1, &s);
        assert_eq!(ops.first(), Some(&Op::Fan(0.5 * s.fan_speed)));
    }
}
