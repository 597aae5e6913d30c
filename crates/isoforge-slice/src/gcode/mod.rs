//! Marlin-flavour G-code from ordered layer paths.
//!
//! Extrusion is computed from volume: a line `w` wide on a layer `h` high and `L` long
//! needs E = w·h·L / (π·(d/2)²) mm of filament of diameter d (a bridge's round strand
//! π/4·w² per mm). E is absolute (`M82`) and reset with `G92 E0` at each layer. Each layer
//! opens with `;LAYER:n`, `;Z:z` and an `M73` progress line, and ends retracted (before Z
//! moves). The header gives the filament used (mm, g) and the time Marlin's planner would
//! take (acceleration and junction deviation included).

mod cooling;
mod moves;
mod planner;
mod travel;

use std::fmt::Write as _;

use rayon::prelude::*;

use crate::geom::{Contour, Region};
use crate::paths::Extrusion;
use crate::profile::{FdmSettings, fill_template};

pub use moves::{Kind, Op};

/// One layer, ready to emit.
#[derive(Clone, Debug, Default)]
pub struct LayerPlan {
    /// Top of the layer above the bed, mm.
    pub top: f64,
    /// Thickness, mm.
    pub height: f64,
    /// Extrusions in print order.
    pub paths: Vec<Extrusion>,
    /// Travel inside this region needs no retraction (combing).
    pub comb: Region,
    /// The layer's outline contours: a travel across one retracts (it would string over
    /// a visible surface).
    pub barriers: Vec<Contour>,
    /// A vase layer: Z rises along the paths from the layer's bottom to its top.
    pub spiral: bool,
}

/// Totals of a G-code file.
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct GcodeStats {
    /// Layers.
    pub layers: usize,
    /// Filament pushed, mm.
    pub filament_mm: f64,
    /// Filament mass, g.
    pub filament_g: f64,
    /// Estimated print time, s: Marlin's planner with the profile's acceleration and
    /// junction deviation, cooling waits included (heating not counted).
    pub seconds: f64,
    /// Retractions.
    pub retractions: usize,
    /// The shortest layer time, s (the minimum layer time holds it up).
    pub shortest_layer: f64,
}

/// Writes the whole file: header, start template, layers, end template.
pub fn write_gcode(plans: &[LayerPlan], s: &FdmSettings) -> (String, GcodeStats) {
    // Moves, layer by layer (the head's state carries over).
    let mut head = moves::Head {
        at: [0.0, 0.0, 0.0],
        retracted: false,
    };
    let mut layers: Vec<(Vec<Op>, [f64; 3])> = Vec::with_capacity(plans.len());
    for (n, plan) in plans.iter().enumerate() {
        let from = head.at;
        let ops = moves::layer_ops(plan, n, s, &mut head);
        layers.push((ops, from));
    }
    // Cooling and time, each layer on its own.
    let times: Vec<f64> = layers
        .par_iter_mut()
        .enumerate()
        .map(|(n, (ops, from))| cooling::cool_layer(ops, *from, n, s))
        .collect();
    let total: f64 = times.iter().sum();
    let filament: f64 = layers
        .iter()
        .flat_map(|(ops, _)| ops.iter())
        .map(|op| match op {
            Op::Move {
                de,
                kind: Kind::Extrude(..),
                ..
            } => *de,
            _ => 0.0,
        })
        .sum();
    let retractions = layers
        .iter()
        .flat_map(|(ops, _)| ops.iter())
        .filter(|op| {
            matches!(
                op,
                Op::Move {
                    kind: Kind::Retract,
                    ..
                }
            )
        })
        .count()
        + layers
            .iter()
            .map(|(ops, _)| {
                // A wipe retracts over several moves: one retraction.
                ops.windows(2)
                    .filter(|w| {
                        matches!(
                            w[1],
                            Op::Move {
                                kind: Kind::Wipe,
                                ..
                            }
                        ) && !matches!(
                            w[0],
                            Op::Move {
                                kind: Kind::Wipe,
                                ..
                            }
                        )
                    })
                    .count()
            })
            .sum::<usize>();
    let stats = GcodeStats {
        layers: plans.len(),
        filament_mm: filament,
        filament_g: filament * s.filament_area() * s.filament_density / 1000.0,
        seconds: total,
        retractions,
        shortest_layer: times.iter().copied().fold(f64::INFINITY, f64::min),
    };
    // Text, each layer on its own (E restarts at every layer; the fan is tracked across).
    let mut started = Vec::with_capacity(times.len());
    let mut t = 0.0;
    for &lt in &times {
        started.push(t);
        t += lt;
    }
    let fans: Vec<f64> = {
        let mut fan = 0.0;
        layers
            .iter()
            .map(|(ops, _)| {
                let before = fan;
                for op in ops {
                    if let Op::Fan(f) = op {
                        fan = *f;
                    }
                }
                before
            })
            .collect()
    };
    let bodies: Vec<String> = layers
        .par_iter()
        .enumerate()
        .map(|(n, (ops, _))| layer_text(n, &plans[n], ops, fans[n], started[n], total, s))
        .collect();

    let mut out = String::with_capacity(bodies.iter().map(|b| b.len()).sum::<usize>() + 4096);
    let _ = writeln!(out, "; generated by isoforge {}", env!("CARGO_PKG_VERSION"));
    let _ = writeln!(out, ";FLAVOR:Marlin");
    let _ = writeln!(out, ";TIME:{:.0}", total);
    let _ = writeln!(out, ";Filament used: {:.5}m", stats.filament_mm / 1000.0);
    let _ = writeln!(out, ";Layer height: {}", s.layer_height);
    let _ = writeln!(out, "; filament used [mm] = {:.2}", stats.filament_mm);
    let _ = writeln!(out, "; filament used [g] = {:.2}", stats.filament_g);
    let _ = writeln!(
        out,
        "; estimated printing time (normal mode) = {}",
        hms(total)
    );
    let _ = writeln!(
        out,
        "; layer_height = {}, first_layer_height = {}, line_width = {}, perimeters = {}, infill = {} {:?}, supports = {:?}",
        s.layer_height,
        s.first_layer_height,
        s.line_width,
        s.perimeters,
        s.infill_density,
        s.infill_pattern,
        s.supports
    );
    let start = fill_template(&s.start_gcode, s);
    // Temperatures must be set before anything extrudes, whatever the template holds.
    if !start.contains("M109") {
        let _ = writeln!(out, "M104 S{:.0}", s.nozzle_temperature);
        let _ = writeln!(out, "M140 S{:.0}", s.bed_temperature);
        let _ = writeln!(out, "M190 S{:.0}", s.bed_temperature);
        let _ = writeln!(out, "M109 S{:.0}", s.nozzle_temperature);
    }
    out.push_str(start.trim_end());
    out.push('\n');
    let _ = writeln!(
        out,
        "G21 ; millimetres\nG90 ; absolute positions\nM82 ; absolute extrusion\nG92 E0"
    );
    // The accelerations the time estimate assumes.
    let _ = writeln!(
        out,
        "M204 P{:.0} R{:.0} T{:.0} ; print, retract, travel acceleration",
        s.machine_max_acceleration_extruding,
        s.machine_max_acceleration_extruding,
        s.machine_max_acceleration_travel
    );
    let _ = writeln!(out, ";LAYER_COUNT:{}", plans.len());
    for body in &bodies {
        out.push_str(body);
    }
    let _ = writeln!(out, "M107");
    let _ = writeln!(out, "M73 P100 R0");
    out.push_str(fill_template(&s.end_gcode, s).trim_end());
    out.push('\n');
    (out, stats)
}

/// One layer's text: its markers, then its moves with absolute E from 0.
fn layer_text(
    n: usize,
    plan: &LayerPlan,
    ops: &[Op],
    fan_before: f64,
    started: f64,
    total: f64,
    s: &FdmSettings,
) -> String {
    let mut out = String::with_capacity(ops.len() * 32 + 128);
    let done = if total > 0.0 { started / total } else { 0.0 };
    let _ = writeln!(out, ";LAYER:{n}");
    let _ = writeln!(out, ";Z:{:.3}", plan.top);
    let _ = writeln!(
        out,
        "M73 P{:.0} R{:.0}",
        (done * 100.0).floor(),
        ((total - started) / 60.0).ceil()
    );
    let _ = writeln!(out, "G92 E0");
    let mut e = 0.0;
    let mut feed = f64::NAN;
    let mut fan = fan_before;
    let mut z = f64::NAN;
    let _ = s;
    for op in ops {
        match op {
            Op::Feature(role) => {
                let _ = writeln!(out, ";TYPE:{}", role.name());
            }
            Op::Fan(f) => {
                if (f - fan).abs() > 1e-9 {
                    if *f <= 0.0 {
                        let _ = writeln!(out, "M107");
                    } else {
                        let _ = writeln!(out, "M106 S{:.0}", f * 255.0);
                    }
                    fan = *f;
                }
            }
            Op::Dwell(t) => {
                let _ = writeln!(out, "G4 P{:.0} ; wait for the layer to cool", t * 1000.0);
            }
            Op::Move {
                to,
                de,
                feed: f,
                kind,
            } => {
                let fword = if feed.is_nan() || (*f - feed).abs() > 1e-9 {
                    feed = *f;
                    format!(" F{:.0}", f * 60.0)
                } else {
                    String::new()
                };
                match kind {
                    Kind::Travel => {
                        let zword = if (to[2] - z).abs() > 1e-9 {
                            z = to[2];
                            format!(" Z{:.3}", to[2])
                        } else {
                            String::new()
                        };
                        let _ = writeln!(out, "G0 X{:.3} Y{:.3}{zword}{fword}", to[0], to[1]);
                    }
                    Kind::Z => {
                        z = to[2];
                        let _ = writeln!(out, "G1 Z{:.3}{fword}", to[2]);
                    }
                    Kind::Retract | Kind::Unretract => {
                        e += de;
                        let _ = writeln!(out, "G1 E{e:.5}{fword}");
                    }
                    Kind::Wipe | Kind::Extrude(..) => {
                        e += de;
                        let zword = if (to[2] - z).abs() > 1e-9 {
                            z = to[2];
                            format!(" Z{:.3}", to[2])
                        } else {
                            String::new()
                        };
                        let _ =
                            writeln!(out, "G1 X{:.3} Y{:.3}{zword} E{e:.5}{fword}", to[0], to[1]);
                    }
                }
            }
        }
    }
    out
}

fn hms(seconds: f64) -> String {
    let t = seconds.max(0.0).round() as u64;
    let (h, m, s) = (t / 3600, t / 60 % 60, t % 60);
    if h > 0 {
        format!("{h}h {m}m {s}s")
    } else {
        format!("{m}m {s}s")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::paths::{Flow, Role};
    use crate::profile::Profile;

    fn plan(paths: Vec<Extrusion>) -> LayerPlan {
        LayerPlan {
            top: 0.2,
            height: 0.2,
            paths,
            comb: Vec::new(),
            barriers: vec![],
            spiral: false,
        }
    }

    #[test]
    fn extrusion_follows_the_volume_formula() {
        let s = Profile::default_fdm().fdm().unwrap();
        let p = plan(vec![Extrusion::new(
            Role::Fill,
            vec![[10.0, 10.0], [110.0, 10.0]],
            s.line_width,
            Flow::Layer,
        )]);
        let (text, stats) = write_gcode(&[p], &s);
        let want = s.line_width * 0.2 * 100.0
            / (std::f64::consts::PI * (s.filament_diameter / 2.0).powi(2));
        assert!((stats.filament_mm - want).abs() < 1e-9);
        assert!(text.contains(&format!("E{want:.5}")), "{text}");
        assert!(text.contains(";LAYER:0") && text.contains(";Z:0.200") && text.contains("M73 P0"));
        assert!(text.contains("M109 S205"));
    }

    #[test]
    fn long_travel_retracts_and_short_one_does_not() {
        let mut s = Profile::default_fdm().fdm().unwrap();
        s.combing = false;
        let line = |a, b| Extrusion::new(Role::Fill, vec![a, b], 0.45, Flow::Layer);
        let p = plan(vec![
            line([0.0, 0.0], [10.0, 0.0]),
            line([10.0, 0.5], [0.0, 0.5]),
            line([50.0, 50.0], [60.0, 50.0]),
        ]);
        let (_, stats) = write_gcode(&[p], &s);
        // One before the long travel, one at the end of the layer.
        assert_eq!(stats.retractions, 2);
    }

    #[test]
    fn the_layer_ends_retracted_before_the_next_z_move() {
        let s = Profile::default_fdm().fdm().unwrap();
        let line = |y| Extrusion::new(Role::Fill, vec![[0.0, y], [10.0, y]], 0.45, Flow::Layer);
        let mut second = plan(vec![line(1.0)]);
        second.top = 0.4;
        let (text, _) = write_gcode(&[plan(vec![line(0.0)]), second], &s);
        let e_only = |l: &str| l.starts_with("G1 E");
        let lines: Vec<&str> = text.lines().collect();
        let layer1 = lines.iter().position(|l| *l == ";LAYER:1").unwrap();
        let z = lines
            .iter()
            .position(|l| l.starts_with("G1 Z0.400"))
            .unwrap();
        let extrusion = |l: &&str| l.starts_with("G1 X") && l.contains(" E");
        let last_extrusion = lines[..layer1].iter().rposition(extrusion).unwrap();
        assert!(
            lines[last_extrusion..layer1].iter().any(|l| e_only(l)),
            "{text}"
        );
        assert!(layer1 < z);
        // The end retracts before the end template lifts.
        let lift = lines.iter().rposition(|l| l.starts_with("G1 Z10")).unwrap();
        let last_extrusion = lines.iter().rposition(extrusion).unwrap();
        assert!(
            lines[last_extrusion..lift].iter().any(|l| e_only(l)),
            "{text}"
        );
    }
}
